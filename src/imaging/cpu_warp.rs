//! The reference warp in f64: the same coordinates ([`WarpGeometry::source_coordinate`]) and
//! the same sampling as `glsl/warp.comp`, so the GPU can be checked pixel by pixel.

use glam::DVec2;

use super::{BitDepth, Pixels, Raster};
use crate::model::warp::WarpGeometry;

/// How the source is interpolated between its pixels (OpenCV's `INTER_*`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sampling {
    /// Bilinear: for colour (OpenCV's `INTER_LINEAR`).
    Bilinear,
    /// Nearest: for data that must not be interpolated (object IDs, flow). Exact values, but
    /// positions rounded to the nearest source pixel (`INTER_NEAREST`).
    Nearest,
    /// Bicubic over 4×4 pixels with OpenCV's kernel (`INTER_CUBIC`, Keys' cubic convolution
    /// with a = −0.75): sharper than bilinear at 16 fetches instead of 4; it overshoots at
    /// edges as OpenCV's does (8-bit images clamp, float images keep the overshoot).
    Bicubic,
}

impl Sampling {
    /// The name the command line, Python and C take.
    pub fn name(self) -> &'static str {
        match self {
            Sampling::Bilinear => "bilinear",
            Sampling::Nearest => "nearest",
            Sampling::Bicubic => "bicubic",
        }
    }
}

impl std::str::FromStr for Sampling {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        match s {
            "bilinear" | "linear" => Ok(Sampling::Bilinear),
            "nearest" => Ok(Sampling::Nearest),
            "bicubic" | "cubic" => Ok(Sampling::Bicubic),
            _ => Err(crate::Error::input(format!(
                "unknown interpolation `{s}` (expected nearest, bilinear or bicubic)"
            ))),
        }
    }
}

/// What a source position off the source image reads (OpenCV's `BORDER_*` of `remap`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Border {
    /// The pixel gets the fill value and mask 0 when its source position lies off the source
    /// frame [−0.5, size − 0.5]² (interpolation taps at the edge repeat the edge pixel, so no
    /// fill colour bleeds into the image's own border).
    #[default]
    Constant,
    /// Off-frame positions and taps repeat the edge pixel (`BORDER_REPLICATE`: aaa|abcd|ddd).
    Replicate,
    /// Off-frame positions and taps mirror the image, edge pixel included
    /// (`BORDER_REFLECT`: cba|abcd|dcb).
    Reflect,
}

impl Border {
    /// The name the command line, Python and C take.
    pub fn name(self) -> &'static str {
        match self {
            Border::Constant => "constant",
            Border::Replicate => "replicate",
            Border::Reflect => "reflect",
        }
    }

    /// The GPU's `BORDER` specialization constant.
    pub fn gpu_id(self) -> u32 {
        match self {
            Border::Constant => 0,
            Border::Replicate => 1,
            Border::Reflect => 2,
        }
    }

    /// Whether the source position `s` of `geometry`'s warp gives the pixel a value.
    pub fn reads(self, geometry: &WarpGeometry, s: DVec2) -> bool {
        match self {
            Border::Constant => geometry.on_source_frame(s),
            Border::Replicate | Border::Reflect => s.x.is_finite() && s.y.is_finite(),
        }
    }

    /// The source index that tap `i` of a side of `n` pixels reads.
    fn index(self, i: i64, n: i64) -> i64 {
        match self {
            Border::Constant | Border::Replicate => i.clamp(0, n - 1),
            Border::Reflect => {
                // Period 2n: the image, then its mirror image (edge pixel repeated).
                let m = i.rem_euclid(2 * n);
                if m < n {
                    m
                } else {
                    2 * n - 1 - m
                }
            }
        }
    }

    /// `s` moved to where it reads the same value, within a few pixels of the frame, so that
    /// far-off positions neither overflow an integer nor lose precision; exact because the
    /// interpolation kernels are symmetric.
    fn fold(self, s: f64, n: u32) -> f64 {
        let n = n as f64;
        match self {
            Border::Constant | Border::Replicate => s.clamp(-3.0, n + 2.0),
            Border::Reflect => {
                // Mirror images about −0.5 and n − 0.5: period 2n from −0.5.
                let m = (s + 0.5).rem_euclid(2.0 * n) - 0.5;
                if m > n - 0.5 {
                    2.0 * n - 1.0 - m
                } else {
                    m
                }
            }
        }
    }
}

impl std::str::FromStr for Border {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        match s {
            "constant" => Ok(Border::Constant),
            "replicate" => Ok(Border::Replicate),
            "reflect" => Ok(Border::Reflect),
            _ => Err(crate::Error::input(format!(
                "unknown border `{s}` (expected constant, replicate or reflect)"
            ))),
        }
    }
}

fn tap(source: &Raster, border: Border, x: i64, y: i64) -> [f64; 4] {
    let x = border.index(x, source.width as i64) as usize;
    let y = border.index(y, source.height as i64) as usize;
    source
        .rgba_f32(y * source.width as usize + x)
        .map(f64::from)
}

/// OpenCV's cubic convolution weights (`INTER_CUBIC`, a = −0.75) of the taps at −1, 0, 1, 2
/// for a position `t` in [0, 1) past tap 0.
pub fn cubic_weights(t: f64) -> [f64; 4] {
    const A: f64 = -0.75;
    let near = |x: f64| ((A + 2.0) * x - (A + 3.0)) * x * x + 1.0;
    let far = |x: f64| ((A * x - 5.0 * A) * x + 8.0 * A) * x - 4.0 * A;
    let w0 = far(t + 1.0);
    let w1 = near(t);
    let w2 = near(1.0 - t);
    [w0, w1, w2, 1.0 - w0 - w1 - w2]
}

/// Samples `source` at `s` (OpenCV convention: texel centres at integers), taps off the
/// image read as `border` says (clamped to the edge for [`Border::Constant`]).
pub fn sample(source: &Raster, s: DVec2, sampling: Sampling, border: Border) -> [f64; 4] {
    let s = DVec2::new(
        border.fold(s.x, source.width),
        border.fold(s.y, source.height),
    );
    let tap = |x: i64, y: i64| tap(source, border, x, y);
    if sampling == Sampling::Nearest || matches!(source.pixels, Pixels::R32Uint(_)) {
        return tap((s.x + 0.5).floor() as i64, (s.y + 0.5).floor() as i64);
    }
    let (x0, y0) = (s.x.floor(), s.y.floor());
    let (fx, fy) = (s.x - x0, s.y - y0);
    let (x0, y0) = (x0 as i64, y0 as i64);
    if sampling == Sampling::Bicubic {
        let (wx, wy) = (cubic_weights(fx), cubic_weights(fy));
        let mut v = [0.0; 4];
        for (j, wy) in wy.iter().enumerate() {
            for (i, wx) in wx.iter().enumerate() {
                let t = tap(x0 - 1 + i as i64, y0 - 1 + j as i64);
                for c in 0..4 {
                    v[c] += wx * wy * t[c];
                }
            }
        }
        return v;
    }
    let lerp = |a: [f64; 4], b: [f64; 4], t: f64| [0, 1, 2, 3].map(|i| a[i] + (b[i] - a[i]) * t);
    let top = lerp(tap(x0, y0), tap(x0 + 1, y0), fx);
    let bottom = lerp(tap(x0, y0 + 1), tap(x0 + 1, y0 + 1), fx);
    lerp(top, bottom, fy)
}

/// Warps `source` (of `geometry.source_size`) into an image of `geometry.output_size`.
/// Returns float RGBA (IDs stay integers) and the validity mask (255 valid, 0 filled).
pub fn warp(
    geometry: &WarpGeometry,
    source: &Raster,
    sampling: Sampling,
    border: Border,
    fill: [f32; 4],
) -> (Raster, Vec<u8>) {
    let (w, h) = geometry.output_size;
    let ids = matches!(source.pixels, Pixels::R32Uint(_));
    let mut out = Vec::with_capacity(w as usize * h as usize);
    let mut mask = Vec::with_capacity(out.capacity());
    for y in 0..h {
        for x in 0..w {
            let p = DVec2::new(x as f64, y as f64);
            let source_of = |c| {
                geometry
                    .model_coordinate(p, c)
                    .filter(|&s| border.reads(geometry, s))
            };
            let g = source_of(1);
            let value = if geometry.is_chromatic() && !ids {
                match (source_of(0), g, source_of(2)) {
                    (Some(r), Some(g), Some(b)) => {
                        let mut v = sample(source, g, sampling, border);
                        v[0] = sample(source, r, sampling, border)[0];
                        v[2] = sample(source, b, sampling, border)[2];
                        Some(v)
                    }
                    _ => None,
                }
            } else {
                g.map(|g| sample(source, g, sampling, border))
            };
            mask.push(if value.is_some() { 255 } else { 0 });
            out.push(value.map(|v| v.map(|c| c as f32)).unwrap_or(fill));
        }
    }
    let pixels = if ids {
        Pixels::R32Uint(out.iter().map(|v| v[0] as u32).collect())
    } else {
        Pixels::Rgba32F(out)
    };
    let depth = if source.bit_depth == BitDepth::U8 {
        BitDepth::U8
    } else {
        source.bit_depth
    };
    (
        Raster {
            width: w,
            height: h,
            pixels,
            bit_depth: depth,
        },
        mask,
    )
}
