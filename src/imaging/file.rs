//! PNG (8- and 16-bit; grey, grey+alpha, RGB, RGBA) and OpenEXR (32-bit float) in and out.
//! Writes go to a temporary file beside the target and are renamed over it, so a failure
//! never leaves a half-written file.

use std::path::Path;

use image::{DynamicImage, ImageBuffer, Rgba};

use super::{BitDepth, Pixels, Raster};
use crate::{Error, Result};

/// Largest image vklens decodes, in MiB of its float RGBA form (16 bytes a pixel), unless
/// `VKLENS_MAX_IMAGE_MB` says otherwise: checked from the header, before anything is decoded
/// (a 20000 × 20000 PNG would take 6 GiB).
pub const DEFAULT_MAX_IMAGE_MB: u64 = 2048;

/// The image budget in force, in bytes.
pub fn max_image_bytes() -> u64 {
    std::env::var("VKLENS_MAX_IMAGE_MB")
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok())
        .unwrap_or(DEFAULT_MAX_IMAGE_MB)
        .saturating_mul(1 << 20)
}

/// More than any PNG or EXR compression packs into one byte (deflate's limit is 1032).
const MAX_COMPRESSION: u64 = 1100;

/// Refuses an image of `width × height` that exceeds the image budget, naming the limit and
/// how to raise it; `what` names the image.
pub fn check_budget(what: &str, width: u32, height: u32) -> Result<()> {
    let bytes = width as u64 * height as u64 * 16;
    let limit = max_image_bytes();
    if bytes > limit {
        return Err(Error::input(format!(
            "{what} is {width}×{height} ({} MiB as float RGBA), more than the {} MiB image budget (set VKLENS_MAX_IMAGE_MB to raise it)",
            bytes >> 20,
            limit >> 20
        )));
    }
    Ok(())
}

/// The colour channels an image file holds (1 grey, 2 grey + alpha, 3 RGB, 4 RGBA), so that an
/// output can keep them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Channels(pub u8);

impl Channels {
    /// Whether the file has an alpha channel.
    pub fn has_alpha(self) -> bool {
        self.0 == 2 || self.0 == 4
    }
}

/// Reads an image; errors are one line naming the file.
pub fn load(path: &Path) -> Result<Raster> {
    load_with_channels(path).map(|(r, _)| r)
}

/// Whether [`load_with_channels`] would give `path` 8-bit RGBA pixels, from its header alone
/// (nothing decoded); `None` where the header cannot say (not an image, unreadable). Lets a
/// caller build what depends on the pixel format while the pixels decode.
pub fn is_eight_bit(path: &Path) -> Option<bool> {
    use image::ImageDecoder;
    let decoder = image::ImageReader::open(path)
        .ok()?
        .with_guessed_format()
        .ok()?
        .into_decoder()
        .ok()?;
    Some(matches!(
        decoder.color_type(),
        image::ColorType::L8
            | image::ColorType::La8
            | image::ColorType::Rgb8
            | image::ColorType::Rgba8
    ))
}

/// Reads an image and says which channels the file held.
/// An object-ID image a renderer wrote: a grey 8- or 16-bit PNG, or an OpenEXR whose first
/// channel holds whole numbers (0 is nothing). Never filtered or scaled: the IDs as written.
/// Colour PNGs are refused (an ID image with colour or alpha is not one ID per pixel).
pub fn load_ids(path: &Path) -> Result<(u32, u32, Vec<u32>)> {
    let shown = path.display();
    let (raster, channels) = load_with_channels(path)?;
    let w = raster.width;
    let whole = |i: usize, v: f32| {
        if v >= 0.0 && v.fract() == 0.0 && v <= u32::MAX as f32 {
            Ok(v as u32)
        } else {
            Err(Error::input(format!(
                "{shown}: pixel ({}, {}) holds {v}, not an object ID (a whole number ≥ 0)",
                i as u32 % w,
                i as u32 / w
            )))
        }
    };
    let ids: Vec<u32> = match (&raster.pixels, raster.bit_depth) {
        // A PNG: one grey channel (load_with_channels keeps 8-bit as it is and scales 16-bit
        // to 0..1, which f32 holds exactly enough to round back).
        (_, BitDepth::U8 | BitDepth::U16) if channels.0 != 1 => {
            return Err(Error::input(format!(
                "{shown}: IDs are one grey channel (an 8- or 16-bit grey PNG, or an EXR), this PNG has {} channels",
                channels.0
            )))
        }
        (Pixels::Rgba8(p), _) => p.iter().map(|p| p[0] as u32).collect(),
        (Pixels::Rgba32F(p), BitDepth::U16) => {
            p.iter().map(|p| (p[0] * 65535.0).round() as u32).collect()
        }
        (Pixels::Rgba32F(p), _) => p
            .iter()
            .enumerate()
            .map(|(i, p)| whole(i, p[0]))
            .collect::<Result<_>>()?,
        (Pixels::R32Uint(p), _) => p.clone(),
    };
    Ok((w, raster.height, ids))
}

/// A depth image a renderer wrote: an OpenEXR's first channel, metres; +inf where nothing was
/// drawn. NaN or a negative depth is refused, naming the pixel.
pub fn load_depth(path: &Path) -> Result<(u32, u32, Vec<f32>)> {
    let shown = path.display();
    let (raster, _) = load_with_channels(path)?;
    let Pixels::Rgba32F(p) = &raster.pixels else {
        return Err(Error::input(format!(
            "{shown}: depth is a 32-bit float OpenEXR (metres), not an integer image"
        )));
    };
    if raster.bit_depth != BitDepth::F32 {
        return Err(Error::input(format!(
            "{shown}: depth is a 32-bit float OpenEXR (metres), not a {}-bit PNG",
            if raster.bit_depth == BitDepth::U16 {
                16
            } else {
                8
            }
        )));
    }
    let w = raster.width;
    let mut depth = Vec::with_capacity(p.len());
    for (i, px) in p.iter().enumerate() {
        let d = px[0];
        if d.is_nan() || d < 0.0 {
            return Err(Error::input(format!(
                "{shown}: pixel ({}, {}) has depth {d}: expected metres ≥ 0 (+inf where nothing is drawn)",
                i as u32 % w,
                i as u32 / w
            )));
        }
        depth.push(d);
    }
    Ok((w, raster.height, depth))
}

pub fn load_with_channels(path: &Path) -> Result<(Raster, Channels)> {
    let shown = path.display();
    let reader = image::ImageReader::open(path)
        .map_err(|e| Error::io(path, "cannot read", &e))?
        .with_guessed_format()
        .map_err(|e| Error::io(path, "cannot read", &e))?;
    match reader.format() {
        Some(image::ImageFormat::Png) | Some(image::ImageFormat::OpenExr) => {}
        Some(f) => {
            return Err(Error::input(format!(
                "{shown}: {f:?} images are not supported (vklens reads PNG and OpenEXR)"
            )))
        }
        None => {
            return Err(Error::input(format!(
                "{shown}: not an image vklens can read (PNG or OpenEXR)"
            )))
        }
    }
    // The size from the header first: nothing is decoded past the budget.
    let (hw, hh) = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| Error::io(path, "cannot read", &e))?
        .into_dimensions()
        .map_err(|e| Error::input(format!("{shown}: cannot read the image header: {e}")))?;
    check_budget(&shown.to_string(), hw, hh)?;
    // A header can claim more than its file could ever hold: PNG's deflate and EXR's
    // compressions pack at most ~1032 bytes into one, and no pixel takes less than one bit.
    // Such a file is corrupt or truncated; decoding would allocate the claimed size first.
    let file_len = std::fs::metadata(path).map(|m| m.len()).unwrap_or(u64::MAX);
    let least_raw = hw as u64 * hh as u64 / 8;
    if least_raw > file_len.saturating_mul(MAX_COMPRESSION) {
        return Err(Error::input(format!(
            "{shown}: the header says {hw}×{hh}, which {file_len} bytes cannot hold: the file is truncated or corrupt"
        )));
    }
    // The decoder's own allocation limit follows the budget (its default, 512 MiB, would
    // refuse what the budget allows, with a message VKLENS_MAX_IMAGE_MB could not help).
    let mut reader = reader;
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(max_image_bytes());
    reader.limits(limits);
    let img = reader
        .decode()
        .map_err(|e| Error::input(format!("{shown}: cannot decode: {e}")))?;
    let (width, height) = (img.width(), img.height());
    let channels = Channels(img.color().channel_count());
    let raster = match img {
        // A photo's common layouts straight into RGBA8: one pass, no intermediate image.
        DynamicImage::ImageRgb8(rgb) => Raster {
            width,
            height,
            pixels: Pixels::Rgba8(rgb.pixels().map(|p| [p[0], p[1], p[2], 255]).collect()),
            bit_depth: BitDepth::U8,
        },
        DynamicImage::ImageRgba8(rgba) => Raster {
            width,
            height,
            pixels: Pixels::Rgba8(rgba.pixels().map(|p| p.0).collect()),
            bit_depth: BitDepth::U8,
        },
        DynamicImage::ImageLuma8(_) | DynamicImage::ImageLumaA8(_) => {
            let rgba = img.to_rgba8();
            Raster {
                width,
                height,
                pixels: Pixels::Rgba8(rgba.pixels().map(|p| p.0).collect()),
                bit_depth: BitDepth::U8,
            }
        }
        DynamicImage::ImageLuma16(_)
        | DynamicImage::ImageLumaA16(_)
        | DynamicImage::ImageRgb16(_)
        | DynamicImage::ImageRgba16(_) => {
            let rgba = img.to_rgba16();
            Raster {
                width,
                height,
                pixels: Pixels::Rgba32F(
                    rgba.pixels()
                        .map(|p| p.0.map(|c| c as f32 / 65535.0))
                        .collect(),
                ),
                bit_depth: BitDepth::U16,
            }
        }
        other => {
            let rgba = other.to_rgba32f();
            Raster {
                width,
                height,
                pixels: Pixels::Rgba32F(rgba.pixels().map(|p| p.0).collect()),
                bit_depth: BitDepth::F32,
            }
        }
    };
    Ok((raster, channels))
}

/// Writes `raster` to `path` (`.png` or `.exr`), keeping its depth where the format allows
/// (8-bit or 16-bit PNG; float data becomes 16-bit PNG or float EXR), as RGBA.
pub fn save(raster: &Raster, path: &Path) -> Result<()> {
    save_as(raster, path, Channels(4))
}

/// [`save`] with the colour channels of `channels` (grey, grey + alpha, RGB or RGBA): an
/// input's layout kept through a warp. Object IDs stay 16-bit grey.
pub fn save_as(raster: &Raster, path: &Path, channels: Channels) -> Result<()> {
    save_staged(raster, path, channels)?.commit()
}

/// [`save_as`] without putting the file in place ([`Staged::commit`]).
pub fn save_staged(raster: &Raster, path: &Path, channels: Channels) -> Result<Staged> {
    // 8-bit RGBA written as RGB (a photo warped): straight to RGB, no RGBA copy first.
    if let (3, Pixels::Rgba8(p), true) = (channels.0, &raster.pixels, has_extension(path, "png")) {
        let rgb: Vec<u8> = p.iter().flat_map(|c| [c[0], c[1], c[2]]).collect();
        let image =
            ImageBuffer::from_raw(raster.width, raster.height, rgb).ok_or_else(size_mismatch)?;
        return write_image(&DynamicImage::ImageRgb8(image), path);
    }
    let image = encode(raster, path)?;
    let image = match (channels.0, &raster.pixels) {
        (_, Pixels::R32Uint(_)) | (4, _) => image,
        (1, _) => match image {
            DynamicImage::ImageRgba8(_) => DynamicImage::ImageLuma8(image.to_luma8()),
            DynamicImage::ImageRgba32F(_) => DynamicImage::ImageRgb32F(image.to_rgb32f()),
            other => DynamicImage::ImageLuma16(other.to_luma16()),
        },
        (2, _) => match image {
            DynamicImage::ImageRgba8(_) => DynamicImage::ImageLumaA8(image.to_luma_alpha8()),
            DynamicImage::ImageRgba32F(_) => image,
            other => DynamicImage::ImageLumaA16(other.to_luma_alpha16()),
        },
        (3, _) => match image {
            DynamicImage::ImageRgba8(_) => DynamicImage::ImageRgb8(image.to_rgb8()),
            DynamicImage::ImageRgba32F(_) => DynamicImage::ImageRgb32F(image.to_rgb32f()),
            other => DynamicImage::ImageRgb16(other.to_rgb16()),
        },
        _ => image,
    };
    write_image(&image, path)
}

/// Whether `path`'s extension is `ext`, in any case.
fn has_extension(path: &Path, ext: &str) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case(ext))
}

fn write_image(image: &DynamicImage, path: &Path) -> Result<Staged> {
    let exr = has_extension(path, "exr");
    stage(path, |tmp| {
        let format = if exr {
            image::ImageFormat::OpenExr
        } else {
            image::ImageFormat::Png
        };
        image.save_with_format(tmp, format).map_err(|e| match e {
            image::ImageError::IoError(e) => e,
            other => std::io::Error::other(other),
        })
    })
}

/// The image as the `image` crate writes it: RGBA (8/16-bit PNG, float EXR), IDs as 16-bit grey.
fn encode(raster: &Raster, path: &Path) -> Result<DynamicImage> {
    let shown = path.display();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    let exr = match ext.as_deref() {
        Some("png") => false,
        Some("exr") => true,
        _ => {
            return Err(Error::input(format!(
                "{shown}: the output must be a .png or .exr file"
            )))
        }
    };
    let (w, h) = (raster.width, raster.height);
    let image: DynamicImage = match (&raster.pixels, exr) {
        (Pixels::Rgba8(p), false) => DynamicImage::ImageRgba8(
            ImageBuffer::from_raw(w, h, p.iter().flatten().copied().collect())
                .ok_or_else(size_mismatch)?,
        ),
        (Pixels::R32Uint(p), false) => {
            let v: Vec<u16> = p.iter().map(|&id| id.min(u16::MAX as u32) as u16).collect();
            DynamicImage::ImageLuma16(ImageBuffer::from_raw(w, h, v).ok_or_else(size_mismatch)?)
        }
        (Pixels::Rgba32F(p), false) if raster.bit_depth == BitDepth::U8 => {
            let v: Vec<u8> = p
                .iter()
                .flatten()
                .map(|&c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
                .collect();
            DynamicImage::ImageRgba8(ImageBuffer::from_raw(w, h, v).ok_or_else(size_mismatch)?)
        }
        (Pixels::Rgba32F(p), false) => {
            let v: Vec<u16> = p
                .iter()
                .flatten()
                .map(|&c| (c.clamp(0.0, 1.0) * 65535.0).round() as u16)
                .collect();
            DynamicImage::ImageRgba16(
                ImageBuffer::<Rgba<u16>, _>::from_raw(w, h, v).ok_or_else(size_mismatch)?,
            )
        }
        (_, true) => {
            let v: Vec<f32> = (0..raster.len()).flat_map(|i| raster.rgba_f32(i)).collect();
            DynamicImage::ImageRgba32F(ImageBuffer::from_raw(w, h, v).ok_or_else(size_mismatch)?)
        }
    };
    Ok(image)
}

fn size_mismatch() -> Error {
    Error::internal("the pixel count does not match the image size")
}

/// Writes an output the way every command and `save` function does: `write` fills a temporary
/// file beside the target, which is flushed to disk and renamed over it, so a failure (or a
/// concurrent writer) never leaves a half-written or mixed file. The temporary name is unique
/// per process and call. A symlink at `path` is followed (its target is replaced, the link
/// kept); a device or FIFO there is written through, never replaced; a folder is refused.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> std::io::Result<()>,
) -> Result<()> {
    stage(path, write)?.commit()
}

/// An output written to its temporary file and flushed, not yet in place: [`Staged::commit`]
/// renames it over the target; dropping it uncommitted removes it. A command with several
/// outputs stages them all, then commits them all, so a failure leaves none of them written.
pub struct Staged {
    path: std::path::PathBuf,
    /// `None`: written through already (a device or FIFO), nothing to rename.
    tmp: Option<(std::path::PathBuf, std::path::PathBuf, PendingTemp)>,
}

impl Staged {
    /// Puts the output in place.
    pub fn commit(mut self) -> Result<()> {
        if let Some((tmp, target, _pending)) = self.tmp.take() {
            std::fs::rename(&tmp, &target).map_err(|e| {
                let _ = std::fs::remove_file(&tmp);
                Error::io(&self.path, "cannot write", &e)
            })?;
        }
        Ok(())
    }
}

impl Staged {
    /// Puts the output in place and lists it among `outputs`, in one step as the interrupt
    /// handler sees it: the rename and the listing happen under the lock
    /// [`remove_pending_and_exit`] takes, so an interrupt removes either the temporary file or
    /// the output, never leaves the output unlisted.
    pub fn commit_into(mut self, outputs: &mut RunOutputs) -> Result<()> {
        let Some((tmp, target, pending)) = self.tmp.take() else {
            return Ok(());
        };
        let renamed = {
            let mut list = PENDING.lock().ok();
            let renamed = std::fs::rename(&tmp, &target);
            if let (Ok(()), Some(list)) = (&renamed, list.as_mut()) {
                list.retain(|t| t != &tmp);
                list.push(target.clone());
            }
            renamed
        };
        // After the lock is released: `PendingTemp`'s drop takes it.
        drop(pending);
        renamed.map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            Error::io(&self.path, "cannot write", &e)
        })?;
        outputs.files.push(target);
        Ok(())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if let Some((tmp, _, _)) = self.tmp.take() {
            let _ = std::fs::remove_file(tmp);
        }
    }
}

/// Writes `path`'s temporary file (see [`write_atomically`]) without putting it in place.
pub fn stage(path: &Path, write: impl FnOnce(&Path) -> std::io::Result<()>) -> Result<Staged> {
    use std::sync::atomic::{AtomicU64, Ordering};
    static CALLS: AtomicU64 = AtomicU64::new(0);
    let shown = path.display();
    // Follow a symlink to what it names (relative links are relative to their folder).
    let mut target = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&target) {
            Ok(m) if m.file_type().is_symlink() => {
                let link = std::fs::read_link(&target)
                    .map_err(|e| Error::io(path, "cannot follow the symlink", &e))?;
                target = match target.parent() {
                    Some(dir) if link.is_relative() => dir.join(link),
                    _ => link,
                };
            }
            _ => break,
        }
    }
    if let Ok(m) = std::fs::metadata(&target) {
        if m.is_dir() {
            return Err(Error::input(format!("{shown}: is a folder, not a file")));
        }
        if !m.is_file() {
            // A device or FIFO: write through it; renaming over it would replace it.
            write(&target).map_err(|e| Error::io(path, "cannot write", &e))?;
            return Ok(Staged {
                path: path.to_path_buf(),
                tmp: None,
            });
        }
    }
    let dir = target
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if !dir.is_dir() {
        return Err(Error::input(format!(
            "{shown}: folder {} does not exist",
            dir.display()
        )));
    }
    let name = target
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or("output");
    let tmp = dir.join(format!(
        ".{name}.{}.{}.vklens-tmp",
        std::process::id(),
        CALLS.fetch_add(1, Ordering::Relaxed)
    ));
    let pending = PendingTemp::register(&tmp);
    let staged = Staged {
        path: path.to_path_buf(),
        tmp: Some((tmp.clone(), target.clone(), pending)),
    };
    write(&tmp)
        .and_then(|_| std::fs::File::open(&tmp)?.sync_all())
        .map_err(|e| Error::io(path, "cannot write", &e))?;
    Ok(staged)
}

/// Whether a file can be created in `path`'s folder (probed with a temporary file, removed
/// again): checked before any work, so a read-only folder fails a command before it renders.
pub fn check_writable(path: &Path) -> Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir()) {
        // A device or FIFO is written through.
        return Ok(());
    }
    let probe = dir.join(format!(".vklens-probe.{}", std::process::id()));
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(()),
        Err(e) => Err(Error::io(
            path,
            &format!("cannot write in folder {}", dir.display()),
            &e,
        )),
    }
}

/// Temporary files being written right now, for [`remove_pending_and_exit`] (a command
/// interrupted by SIGINT or SIGTERM leaves none behind).
static PENDING: std::sync::Mutex<Vec<std::path::PathBuf>> = std::sync::Mutex::new(Vec::new());

/// A temporary file's entry in [`PENDING`], removed when the write is over.
struct PendingTemp(std::path::PathBuf);

impl PendingTemp {
    fn register(tmp: &Path) -> Self {
        if let Ok(mut p) = PENDING.lock() {
            p.push(tmp.to_path_buf());
        }
        PendingTemp(tmp.to_path_buf())
    }
}

impl Drop for PendingTemp {
    fn drop(&mut self) {
        if let Ok(mut p) = PENDING.lock() {
            p.retain(|t| t != &self.0);
        }
    }
}

/// The files a command has written so far, removed again if it fails (dropped without
/// [`RunOutputs::keep`]) or is interrupted (listed with the temporary files that
/// [`remove_pending_and_exit`] removes): a command that fails leaves no output of its own, and a
/// set of files (a calibration set, a scene's frames) is all or nothing.
#[derive(Default)]
pub struct RunOutputs {
    files: Vec<std::path::PathBuf>,
}

impl RunOutputs {
    pub fn new() -> Self {
        Self::default()
    }

    /// A file this run has just written in full.
    pub fn add(&mut self, path: &Path) {
        if let Ok(mut p) = PENDING.lock() {
            p.push(path.to_path_buf());
        }
        self.files.push(path.to_path_buf());
    }

    /// The run succeeded: its files stay.
    pub fn keep(mut self) {
        let files = std::mem::take(&mut self.files);
        if let Ok(mut p) = PENDING.lock() {
            p.retain(|t| !files.contains(t));
        }
    }
}

impl Drop for RunOutputs {
    fn drop(&mut self) {
        if self.files.is_empty() {
            return;
        }
        if let Ok(mut p) = PENDING.lock() {
            p.retain(|t| !self.files.contains(t));
        }
        for f in &self.files {
            let _ = std::fs::remove_file(f);
        }
    }
}

/// Removes every temporary file a write in progress has made and every output of an
/// unfinished run, then exits with `code`: what the command line's SIGINT/SIGTERM handler
/// runs (on its own thread, not in signal context, so taking the lock is safe; a writer
/// holding it only pushes or retains).
///
/// The lock is held until the process ends, so no write registers after the sweep; a file
/// registered just before it may still be created a moment later (a writer registers its
/// temporary file first, then creates it), which the second sweep removes.
pub fn remove_pending_and_exit(code: i32) -> ! {
    let guard = PENDING.lock();
    let sweep = || {
        if let Ok(p) = &guard {
            for t in p.iter() {
                let _ = std::fs::remove_file(t);
            }
        }
    };
    sweep();
    std::thread::sleep(std::time::Duration::from_millis(100));
    sweep();
    std::process::exit(code)
}

#[cfg(test)]
mod tests;
