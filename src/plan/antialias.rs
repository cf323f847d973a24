//! Anti-aliasing of colour (Lambers et al. render one sample per pixel; calibration needs
//! corners to a fraction of a pixel): `supersample` renders at `s×` the resolution with the
//! scaled camera (the lens is the same: distortion acts on normalized coordinates) and
//! box-filters down; `jitter` repeats that with the sample grid shifted by sub-sample offsets
//! (Halton 2, 3) and averages. IDs, flow and depth are never averaged.

use glam::DVec2;

use crate::imaging::{Pixels, Raster};
use crate::model::{Camera, Intrinsics};
use crate::{Error, Result};

/// Largest colour supersampling factor per axis (`--supersample`, `[render] supersample`):
/// at 8× an 800×600 frame is already rendered at 6400×4800.
pub const MAX_SUPERSAMPLE: u32 = 8;
/// Most jittered passes averaged (`--jitter`, `[render] jitter`).
pub const MAX_JITTER: u32 = 64;
/// The background a render clears to unless told otherwise: transparent black, so that what
/// the scene does not cover can be told apart (the same on the command line and in scene
/// files).
pub const DEFAULT_BACKGROUND: [f32; 4] = [0.0; 4];

/// The camera rendering `camera`'s image at `s×` its resolution.
pub fn scaled_camera(camera: &Camera, s: u32) -> Result<Camera> {
    let k = camera.intrinsics;
    let f = s as f64;
    camera
        .with_intrinsics(
            camera.width * s,
            camera.height * s,
            Intrinsics {
                fx: k.fx * f,
                fy: k.fy * f,
                // Pixel edges scale, not centres: pixel i spans [i − 0.5, i + 0.5].
                cx: (k.cx + 0.5) * f - 0.5,
                cy: (k.cy + 0.5) * f - 0.5,
            },
        )
        .map_err(Error::from)
}

/// The camera whose image is `camera`'s translated by `-shift` px (principal point moved).
pub(crate) fn shifted(camera: &Camera, shift: DVec2) -> Result<Camera> {
    let mut k = camera.intrinsics;
    k.cx -= shift.x;
    k.cy -= shift.y;
    camera
        .with_intrinsics(camera.width, camera.height, k)
        .map_err(Error::from)
}

/// Radical inverse of `i` in `base` (Halton sequence), in [0, 1).
fn radical_inverse(mut i: u32, base: u32) -> f64 {
    let (mut f, mut r) = (1.0, 0.0);
    while i > 0 {
        f /= base as f64;
        r += f * (i % base) as f64;
        i /= base;
    }
    r
}

/// Sub-sample offsets of `passes` jittered passes, in units of one sample (centred on 0).
pub fn jitter_offsets(passes: u32) -> Vec<DVec2> {
    if passes <= 1 {
        return vec![DVec2::ZERO];
    }
    let raw: Vec<DVec2> = (0..passes)
        .map(|i| DVec2::new(radical_inverse(i, 2), radical_inverse(i, 3)))
        .collect();
    // Centre exactly (the mean offset would shift the whole image).
    let mean = raw.iter().sum::<DVec2>() / passes as f64;
    raw.into_iter().map(|o| o - mean).collect()
}

/// The mean of equally sized images (8-bit results rounded).
pub(crate) fn average(images: &[Raster]) -> Raster {
    let n = images.len().max(1) as f32;
    let first = &images[0];
    let mut sums = vec![[0f32; 4]; first.len()];
    for img in images {
        for (i, o) in sums.iter_mut().enumerate() {
            let v = img.rgba_f32(i);
            for c in 0..4 {
                o[c] += v[c] / n;
            }
        }
    }
    let pixels = match first.pixels {
        Pixels::Rgba8(_) => Pixels::Rgba8(
            sums.iter()
                .map(|p| p.map(|c| (c * 255.0).round().clamp(0.0, 255.0) as u8))
                .collect(),
        ),
        _ => Pixels::Rgba32F(sums),
    };
    Raster {
        width: first.width,
        height: first.height,
        pixels,
        bit_depth: first.bit_depth,
    }
}

/// Box-filters an image by `s` per axis (its size must be a multiple of `s`).
pub fn downsample(image: &Raster, s: u32) -> Raster {
    if s == 1 {
        return image.clone();
    }
    let (w, h) = (image.width / s, image.height / s);
    let (s, iw) = (s as usize, image.width as usize);
    let pixels = match &image.pixels {
        // Integer sums, row by row: this runs on every supersampled pass.
        Pixels::Rgba8(p) => {
            let n = (s * s) as u32;
            let mut out = Vec::with_capacity(w as usize * h as usize);
            let mut sums = vec![[0u32; 4]; w as usize];
            for y in 0..h as usize {
                sums.iter_mut().for_each(|v| *v = [0; 4]);
                for row in p[y * s * iw..(y + 1) * s * iw].chunks_exact(iw) {
                    for (x, block) in row.chunks_exact(s).enumerate() {
                        for px in block {
                            for c in 0..4 {
                                sums[x][c] += px[c] as u32;
                            }
                        }
                    }
                }
                out.extend(sums.iter().map(|v| v.map(|c| ((c + n / 2) / n) as u8)));
            }
            Pixels::Rgba8(out)
        }
        _ => {
            let n = (s * s) as f32;
            let mut out = vec![[0f32; 4]; w as usize * h as usize];
            for y in 0..image.height as usize {
                for x in 0..iw {
                    let v = image.rgba_f32(y * iw + x);
                    let o = &mut out[(y / s) * w as usize + x / s];
                    for c in 0..4 {
                        o[c] += v[c] / n;
                    }
                }
            }
            Pixels::Rgba32F(out)
        }
    };
    Raster {
        width: w,
        height: h,
        pixels,
        bit_depth: image.bit_depth,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imaging::BitDepth;

    #[test]
    fn scaled_camera_keeps_pixel_edges() {
        let cam = Camera::from_coeffs(
            800,
            600,
            Intrinsics {
                fx: 400.0,
                fy: 400.0,
                cx: 399.5,
                cy: 299.5,
            },
            &[-0.05, 0.01, 0.03, -0.01],
        )
        .unwrap();
        let big = scaled_camera(&cam, 4).unwrap();
        // The image's left edge (pixel −0.5) is at the same normalized x in both.
        let edge = |c: &Camera| (-0.5 - c.intrinsics.cx) / c.intrinsics.fx;
        assert!((edge(&cam) - edge(&big)).abs() < 1e-15);
        assert_eq!((big.width, big.height), (3200, 2400));
        let img = Raster {
            width: 4,
            height: 2,
            pixels: Pixels::Rgba8(vec![
                [0; 4], [255; 4], [10; 4], [10; 4], [255; 4], [0; 4], [10; 4], [10; 4],
            ]),
            bit_depth: BitDepth::U8,
        };
        let small = downsample(&img, 2);
        assert_eq!(small.pixels, Pixels::Rgba8(vec![[128; 4], [10; 4]]));
    }
}
