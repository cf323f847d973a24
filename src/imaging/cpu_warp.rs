//! The reference warp in f64: the same coordinates ([`WarpGeometry::source_coordinate`]) and
//! the same sampling as `glsl/warp.comp`, so the GPU can be checked pixel by pixel.

use glam::DVec2;

use super::{BitDepth, Pixels, Raster};
use crate::model::warp::WarpGeometry;

/// How the source is sampled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sampling {
    /// Bilinear: for colour.
    Bilinear,
    /// Nearest: for data that must not be interpolated (object IDs, flow). Exact values, but
    /// positions rounded to the nearest source pixel.
    Nearest,
}

impl std::str::FromStr for Sampling {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        match s {
            "bilinear" => Ok(Sampling::Bilinear),
            "nearest" => Ok(Sampling::Nearest),
            _ => Err(crate::Error::input(format!(
                "unknown sampling `{s}` (expected bilinear or nearest)"
            ))),
        }
    }
}

fn tap(source: &Raster, x: i64, y: i64) -> [f64; 4] {
    let x = x.clamp(0, source.width as i64 - 1) as usize;
    let y = y.clamp(0, source.height as i64 - 1) as usize;
    source
        .rgba_f32(y * source.width as usize + x)
        .map(f64::from)
}

/// Samples `source` at `s` (OpenCV convention: texel centres at integers), edge taps clamped.
pub fn sample(source: &Raster, s: DVec2, sampling: Sampling) -> [f64; 4] {
    if sampling == Sampling::Nearest || matches!(source.pixels, Pixels::R32Uint(_)) {
        return tap(
            source,
            (s.x + 0.5).floor() as i64,
            (s.y + 0.5).floor() as i64,
        );
    }
    let (x0, y0) = (s.x.floor(), s.y.floor());
    let (fx, fy) = (s.x - x0, s.y - y0);
    let (x0, y0) = (x0 as i64, y0 as i64);
    let lerp = |a: [f64; 4], b: [f64; 4], t: f64| [0, 1, 2, 3].map(|i| a[i] + (b[i] - a[i]) * t);
    let top = lerp(tap(source, x0, y0), tap(source, x0 + 1, y0), fx);
    let bottom = lerp(tap(source, x0, y0 + 1), tap(source, x0 + 1, y0 + 1), fx);
    lerp(top, bottom, fy)
}

/// Warps `source` (of `geometry.source_size`) into an image of `geometry.output_size`.
/// Returns float RGBA (IDs stay integers) and the validity mask (255 valid, 0 filled).
pub fn warp(
    geometry: &WarpGeometry,
    source: &Raster,
    sampling: Sampling,
    fill: [f32; 4],
) -> (Raster, Vec<u8>) {
    let (w, h) = geometry.output_size;
    let ids = matches!(source.pixels, Pixels::R32Uint(_));
    let mut out = Vec::with_capacity(w as usize * h as usize);
    let mut mask = Vec::with_capacity(out.capacity());
    for y in 0..h {
        for x in 0..w {
            let p = DVec2::new(x as f64, y as f64);
            let g = geometry.source_coordinate(p, 1);
            let value = if geometry.is_chromatic() && !ids {
                match (
                    geometry.source_coordinate(p, 0),
                    g,
                    geometry.source_coordinate(p, 2),
                ) {
                    (Some(r), Some(g), Some(b)) => {
                        let mut v = sample(source, g, sampling);
                        v[0] = sample(source, r, sampling)[0];
                        v[2] = sample(source, b, sampling)[2];
                        Some(v)
                    }
                    _ => None,
                }
            } else {
                g.map(|g| sample(source, g, sampling))
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
