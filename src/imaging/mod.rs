//! Host-side images: loading and saving (PNG 8/16-bit, OpenEXR 32-bit float) and the f64
//! reference warp the GPU is tested against. No Vulkan here.
//!
//! Pixel values are kept as stored: interpolation happens on the encoded values (sRGB or
//! linear alike), as `cv2.remap` does; vklens converts nothing behind the user's back.

pub mod cpu_warp;
pub mod file;

/// Pixels of a host image, row-major.
#[derive(Debug, Clone, PartialEq)]
pub enum Pixels {
    /// 8-bit RGBA (from 8-bit PNG).
    Rgba8(Vec<[u8; 4]>),
    /// Float RGBA (from 16-bit PNG, scaled to 0..1, or from EXR).
    Rgba32F(Vec<[f32; 4]>),
    /// Unsigned integers (object IDs): never interpolated.
    R32Uint(Vec<u32>),
}

/// What the image was read from, so that it is written back the same way.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BitDepth {
    U8,
    U16,
    F32,
}

/// A host image.
#[derive(Debug, Clone, PartialEq)]
pub struct Raster {
    pub width: u32,
    pub height: u32,
    pub pixels: Pixels,
    pub bit_depth: BitDepth,
}

impl Raster {
    /// The image as 8-bit RGBA: each channel clamped to [0, 1], scaled by 255 and rounded
    /// to the nearest (what a UNORM store would give, computed on the host).
    pub fn to_rgba8_rounded(&self) -> Raster {
        let byte = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
        Raster {
            width: self.width,
            height: self.height,
            pixels: Pixels::Rgba8(
                (0..self.len())
                    .map(|i| self.rgba_f32(i).map(byte))
                    .collect(),
            ),
            bit_depth: BitDepth::U8,
        }
    }

    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.width as usize * self.height as usize
    }
    /// Checks that the pixel vector holds exactly `width × height` pixels (the fields are
    /// public, and every upload copies the whole image).
    pub fn check(&self) -> crate::Result<()> {
        let n = match &self.pixels {
            Pixels::Rgba8(p) => p.len(),
            Pixels::Rgba32F(p) => p.len(),
            Pixels::R32Uint(p) => p.len(),
        };
        if n != self.len() {
            return Err(crate::Error::input(format!(
                "the image is {}×{} but holds {n} pixels",
                self.width, self.height
            )));
        }
        Ok(())
    }

    /// Whether it has no pixels.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The `w × h` block whose top-left pixel is `(x, y)` (clipped to the image).
    pub fn crop(&self, x: u32, y: u32, w: u32, h: u32) -> Raster {
        let w = w.min(self.width.saturating_sub(x));
        let h = h.min(self.height.saturating_sub(y));
        fn block<T: Copy>(p: &[T], stride: u32, (x, y, w, h): (u32, u32, u32, u32)) -> Vec<T> {
            (y..y + h)
                .flat_map(|row| {
                    let start = (row * stride + x) as usize;
                    p[start..start + w as usize].iter().copied()
                })
                .collect()
        }
        let r = (x, y, w, h);
        let pixels = match &self.pixels {
            Pixels::Rgba8(p) => Pixels::Rgba8(block(p, self.width, r)),
            Pixels::Rgba32F(p) => Pixels::Rgba32F(block(p, self.width, r)),
            Pixels::R32Uint(p) => Pixels::R32Uint(block(p, self.width, r)),
        };
        Raster {
            width: w,
            height: h,
            pixels,
            bit_depth: self.bit_depth,
        }
    }

    /// Pixel `i` as float RGBA (8-bit scaled to 0..1; IDs as numbers in .r).
    pub fn rgba_f32(&self, i: usize) -> [f32; 4] {
        match &self.pixels {
            Pixels::Rgba8(p) => p[i].map(|c| c as f32 / 255.0),
            Pixels::Rgba32F(p) => p[i],
            Pixels::R32Uint(p) => [p[i] as f32, 0.0, 0.0, 1.0],
        }
    }
}

/// The images of one rendered frame, on the host: colour, object IDs, flow and depth, each
/// when asked for (row-major, `width × height`).
#[derive(Debug, Clone, Default)]
pub struct Rendered {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Colour (8-bit, or float for EXR output).
    pub color: Option<Raster>,
    /// Object IDs, 0 = background.
    pub ids: Option<Vec<u32>>,
    /// Pixel motion since the previous pose; NaN where unknown or background.
    pub flow: Option<Vec<[f32; 2]>>,
    /// Camera-frame z in metres; +inf where nothing was drawn.
    pub depth: Option<Vec<f32>>,
    /// Distance from the projection centre along the pixel's ray, in metres; +inf where
    /// nothing was drawn.
    pub range: Option<Vec<f32>>,
    /// 255 where the pixel has a source, 0 where it was filled (outside the lens's valid
    /// domain): a 360° source's sphere warp gives it.
    pub mask: Option<Vec<u8>>,
}
