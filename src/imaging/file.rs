//! PNG (8- and 16-bit; grey, grey+alpha, RGB, RGBA) and OpenEXR (32-bit float) in and out.
//! Writes go to a temporary file beside the target and are renamed over it, so a failure
//! never leaves a half-written file.

use std::path::Path;

use image::{DynamicImage, ImageBuffer, Rgba};

use super::{BitDepth, Pixels, Raster};
use crate::{Error, Result};

/// Reads an image; errors are one line naming the file.
pub fn load(path: &Path) -> Result<Raster> {
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
    let img = reader
        .decode()
        .map_err(|e| Error::input(format!("{shown}: cannot decode: {e}")))?;
    let (width, height) = (img.width(), img.height());
    let raster = match img {
        DynamicImage::ImageLuma8(_)
        | DynamicImage::ImageLumaA8(_)
        | DynamicImage::ImageRgb8(_)
        | DynamicImage::ImageRgba8(_) => {
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
    Ok(raster)
}

/// Writes `raster` to `path` (`.png` or `.exr`), keeping its depth where the format allows
/// (8-bit or 16-bit PNG; float data becomes 16-bit PNG or float EXR).
pub fn save(raster: &Raster, path: &Path) -> Result<()> {
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
    write_atomically(path, |tmp| {
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
            return write(&target).map_err(|e| Error::io(path, "cannot write", &e));
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
    let result = write(&tmp)
        .and_then(|_| std::fs::File::open(&tmp)?.sync_all())
        .and_then(|_| std::fs::rename(&tmp, &target))
        .map_err(|e| Error::io(path, "cannot write", &e));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}
