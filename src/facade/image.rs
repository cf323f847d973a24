//! Host images in and out: PNG (8- and 16-bit) and OpenEXR (32-bit float).

use std::path::Path;

use crate::imaging::Raster;
use crate::Result;

impl Raster {
    /// Reads a PNG (8- or 16-bit; grey, grey+alpha, RGB, RGBA) or OpenEXR image; errors
    /// name the file.
    pub fn load(path: impl AsRef<Path>) -> Result<Raster> {
        crate::imaging::file::load(path.as_ref())
    }

    /// Writes a `.png` (keeping 8 or 16 bits) or `.exr` (32-bit float) image, atomically: a
    /// failure leaves no partial file behind.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        crate::imaging::file::save(self, path.as_ref())
    }
}

/// The samples of a borrowed host image, interleaved, row-major, tightly packed.
#[derive(Debug, Clone, Copy)]
pub enum HostPixels<'a> {
    /// 8-bit samples (0..255 is 0..1).
    U8(&'a [u8]),
    /// 16-bit samples (0..65535 is 0..1).
    U16(&'a [u16]),
    /// Float samples.
    F32(&'a [f32]),
}

/// Where a warp writes a host image: the same shapes as [`HostPixels`].
#[derive(Debug)]
pub enum HostPixelsMut<'a> {
    /// 8-bit samples.
    U8(&'a mut [u8]),
    /// 16-bit samples (rounded to the nearest step).
    U16(&'a mut [u16]),
    /// Float samples.
    F32(&'a mut [f32]),
}

/// A host image borrowed from the caller (a numpy array, a C buffer): `width × height`
/// pixels of `channels` samples each (1 grey, 3 RGB, 4 RGBA).
#[derive(Debug, Clone, Copy)]
pub struct HostImage<'a> {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Samples per pixel: 1, 3 or 4.
    pub channels: u32,
    /// The samples.
    pub pixels: HostPixels<'a>,
}

/// A host image the caller lends for writing, laid out as [`HostImage`].
#[derive(Debug)]
pub struct HostImageMut<'a> {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Samples per pixel: 1, 3 or 4.
    pub channels: u32,
    /// The samples.
    pub pixels: HostPixelsMut<'a>,
}

impl HostPixels<'_> {
    pub(crate) fn len(&self) -> usize {
        match self {
            HostPixels::U8(p) => p.len(),
            HostPixels::U16(p) => p.len(),
            HostPixels::F32(p) => p.len(),
        }
    }
    pub(crate) fn kind(&self) -> &'static str {
        match self {
            HostPixels::U8(_) => "uint8",
            HostPixels::U16(_) => "uint16",
            HostPixels::F32(_) => "float32",
        }
    }
}

impl HostPixelsMut<'_> {
    pub(crate) fn len(&self) -> usize {
        match self {
            HostPixelsMut::U8(p) => p.len(),
            HostPixelsMut::U16(p) => p.len(),
            HostPixelsMut::F32(p) => p.len(),
        }
    }
    pub(crate) fn kind(&self) -> &'static str {
        match self {
            HostPixelsMut::U8(_) => "uint8",
            HostPixelsMut::U16(_) => "uint16",
            HostPixelsMut::F32(_) => "float32",
        }
    }
}

/// Checks that `len` samples make a `width × height × channels` image; `what` names it.
pub(crate) fn check_host_shape(
    what: &str,
    (width, height, channels): (u32, u32, u32),
    len: usize,
    want: (u32, u32),
) -> Result<()> {
    if ![1, 3, 4].contains(&channels) {
        return Err(crate::Error::input(format!(
            "{what}: {channels} channels; expected 1 (grey), 3 (RGB) or 4 (RGBA)"
        )));
    }
    if (width, height) != want {
        return Err(crate::Error::input(format!(
            "{what}: the image is {width}×{height} but the warp expects {}×{}",
            want.0, want.1
        )));
    }
    let need = width as usize * height as usize * channels as usize;
    if len != need {
        return Err(crate::Error::input(format!(
            "{what}: {len} samples, but {width}×{height}×{channels} needs {need}"
        )));
    }
    Ok(())
}

/// Converts host samples into the warp's texels, in place in the upload buffer: 8-bit
/// samples to RGBA8, 16-bit and float samples to RGBA32F; grey fills R, G and B, and a
/// missing alpha is opaque.
pub(crate) fn host_to_texels(input: &HostImage<'_>, texels: &mut [u8]) -> Result<()> {
    let c = input.channels as usize;
    let internal = |m: &str| crate::Error::internal(format!("host upload: {m}"));
    match input.pixels {
        HostPixels::U8(src) => {
            if texels.len() != src.len() / c * 4 {
                return Err(internal("8-bit texel count"));
            }
            match c {
                4 => texels.copy_from_slice(src),
                _ => {
                    for (t, s) in texels.chunks_exact_mut(4).zip(src.chunks_exact(c)) {
                        let (r, g, b) = if c == 3 {
                            (s[0], s[1], s[2])
                        } else {
                            (s[0], s[0], s[0])
                        };
                        t.copy_from_slice(&[r, g, b, 255]);
                    }
                }
            }
        }
        HostPixels::U16(src) => widen(src, c, texels, |v| v as f32 / 65535.0)?,
        HostPixels::F32(src) => widen(src, c, texels, |v| v)?,
    }
    Ok(())
}

/// `src` (`c` samples a pixel) into RGBA32F texels through `f`.
fn widen<T: Copy>(src: &[T], c: usize, texels: &mut [u8], f: impl Fn(T) -> f32) -> Result<()> {
    let internal = |m: String| crate::Error::internal(format!("host upload: {m}"));
    let texels: &mut [[f32; 4]] =
        bytemuck::try_cast_slice_mut(texels).map_err(|e| internal(e.to_string()))?;
    if texels.len() * c != src.len() {
        return Err(internal("float texel count".into()));
    }
    for (t, s) in texels.iter_mut().zip(src.chunks_exact(c)) {
        *t = match c {
            4 => [f(s[0]), f(s[1]), f(s[2]), f(s[3])],
            3 => [f(s[0]), f(s[1]), f(s[2]), 1.0],
            _ => {
                let g = f(s[0]);
                [g, g, g, 1.0]
            }
        };
    }
    Ok(())
}

/// The warp's texels (RGBA8 or RGBA32F) out into the caller's samples, `channels` a pixel:
/// grey takes G (the geometric channel when lateral colour splits R and B off it).
pub(crate) fn texels_to_host(texels: &[u8], output: &mut HostImageMut<'_>) -> Result<()> {
    let c = output.channels as usize;
    let internal = |m: String| crate::Error::internal(format!("host download: {m}"));
    let pick = |i: usize| match (c, i) {
        (1, _) => 1,
        (_, i) => i,
    };
    match &mut output.pixels {
        HostPixelsMut::U8(dst) => {
            if texels.len() / 4 * c != dst.len() {
                return Err(internal("8-bit texel count".into()));
            }
            if c == 4 {
                dst.copy_from_slice(texels);
            } else {
                for (d, t) in dst.chunks_exact_mut(c).zip(texels.chunks_exact(4)) {
                    for (i, v) in d.iter_mut().enumerate() {
                        *v = t[pick(i)];
                    }
                }
            }
        }
        HostPixelsMut::U16(dst) => narrow(texels, c, dst, |v| {
            (v * 65535.0).round().clamp(0.0, 65535.0) as u16
        })?,
        HostPixelsMut::F32(dst) => narrow(texels, c, dst, |v| v)?,
    }
    Ok(())
}

/// RGBA32F texels into `c` samples a pixel through `f` (grey takes G).
fn narrow<T>(texels: &[u8], c: usize, dst: &mut [T], f: impl Fn(f32) -> T) -> Result<()> {
    let texels: &[[f32; 4]] = bytemuck::try_cast_slice(texels)
        .map_err(|e| crate::Error::internal(format!("float texels: {e}")))?;
    if texels.len() * c != dst.len() {
        return Err(crate::Error::internal("float texel count"));
    }
    for (d, t) in dst.chunks_exact_mut(c).zip(texels) {
        if c == 1 {
            d[0] = f(t[1]);
        } else {
            for (i, v) in d.iter_mut().enumerate() {
                *v = f(t[i]);
            }
        }
    }
    Ok(())
}
