//! The ground truth for the image-based model: distribution ray tracing through the same
//! prescription and the same scene (Heidrich et al. Sec. 4 compares against exactly this). Every film
//! pixel centre sends one ray through each lens sample point; each ray is traced exactly
//! through the lens, cast into the scene, shaded as the rasterizer shades, and weighted with
//! the same radiometric term `W_i(x')` (Eq. 3). Each sample's ray starts at its own place in
//! the pixel (stratified), so the reference integrates over pixel area and lens together as
//! distribution ray tracing does; the image-based model evaluates pixel centres and filters
//! by resampling. At equal samples the difference is the cost of the model's approximations
//! (perspective cells, morph interpolation, rasterization) plus the two ways of filtering.

use crate::{Error, Result};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use glam::DVec2;

use super::image_model::{radiometric_weight, Optics};
use crate::scene::raycast::{shade, Bvh};
use crate::scene::{Pose, Scene};

/// One wavelength and the channels it lights (as for the GPU renderer).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Channel {
    pub lambda_um: f64,
    pub mask: [f32; 4],
}

/// A reference film: same meaning as [`crate::pass::lens_render::LensFrame`]'s pixels.
#[derive(Debug, Clone)]
pub struct ReferenceFrame {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
    pub seconds: f64,
    /// Rays traced through the lens.
    pub rays: u64,
}

/// Renders `scene` from `pose` through `optics` with `samples` lens samples per pixel (the
/// points the image-based model uses), on all cores; `progress` gets the fraction done.
pub fn render_reference(
    optics: &Optics,
    channels: &[Channel],
    samples: u32,
    scene: &Scene,
    pose: &Pose,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<ReferenceFrame> {
    let start = Instant::now();
    let film = optics.film;
    let (w, h) = (film.width as usize, film.height as usize);
    // Per channel: the sample points and their normalized weights' scale.
    let mut lens = Vec::new();
    for c in channels {
        let s = optics.weighted_samples(samples, c.lambda_um)?;
        lens.push((c, s.points, s.scale));
    }
    let bvh = Bvh::new(&scene.mesh);
    let inverse = pose.rotation.transpose();
    let next_row = AtomicUsize::new(0);
    let rays = AtomicUsize::new(0);
    let rows_done = AtomicUsize::new(0);
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
        .min(h.max(1));
    let mut pixels = vec![[0.0f32; 4]; w * h];
    let rows: Vec<Vec<(usize, Vec<[f32; 4]>)>> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                s.spawn(|| {
                    let mut done = Vec::new();
                    let mut traced = 0usize;
                    loop {
                        let y = next_row.fetch_add(1, Ordering::Relaxed);
                        if y >= h {
                            break;
                        }
                        let mut row = vec![[0.0f32; 4]; w];
                        for (x, out) in row.iter_mut().enumerate() {
                            let mut sum = [0.0f64; 4];
                            for (channel, points, scale) in &lens {
                                for (k, p) in points.iter().enumerate() {
                                    traced += 1;
                                    let film_point = film.point(
                                        DVec2::new(x as f64, y as f64)
                                            + pixel_offset(k, points.len()),
                                    );
                                    let Some(ray) =
                                        optics.trace_from_film(film_point, *p, channel.lambda_um)
                                    else {
                                        continue;
                                    };
                                    let weight = radiometric_weight(film_point, *p) * scale;
                                    let origin = inverse * (ray.origin - pose.translation);
                                    let direction = inverse * ray.direction;
                                    let Some(hit) =
                                        bvh.intersect(origin, direction, 0.0, f64::INFINITY)
                                    else {
                                        continue;
                                    };
                                    let colour = shade(&scene.mesh, scene.texture.as_ref(), &hit);
                                    for k in 0..4 {
                                        sum[k] += colour[k] * weight * channel.mask[k] as f64;
                                    }
                                }
                            }
                            *out = sum.map(|v| v as f32);
                        }
                        done.push((y, row));
                        // Progress every 5 % (rows finish out of order across threads).
                        let finished = rows_done.fetch_add(1, Ordering::Relaxed) + 1;
                        if finished * 20 / h != (finished - 1) * 20 / h {
                            progress(finished as f64 / h as f64);
                        }
                    }
                    rays.fetch_add(traced, Ordering::Relaxed);
                    done
                })
            })
            .collect();
        workers
            .into_iter()
            .map(|t| t.join().unwrap_or_default())
            .collect()
    });
    let mut filled = 0;
    for (y, row) in rows.into_iter().flatten() {
        pixels[y * w..(y + 1) * w].copy_from_slice(&row);
        filled += 1;
    }
    if filled != h {
        return Err(Error::input("a reference worker thread failed"));
    }
    Ok(ReferenceFrame {
        width: film.width,
        height: film.height,
        pixels,
        seconds: start.elapsed().as_secs_f64(),
        rays: rays.into_inner() as u64,
    })
}

/// Where in its pixel the ray of lens sample `k` of `n` starts: stratified over the pixel
/// area (the R2 low-discrepancy sequence), so that the reference integrates over the pixel
/// as a sensor does, as distribution ray tracing samples pixel and lens together; one
/// sample sits at the pixel centre.
pub fn pixel_offset(k: usize, n: usize) -> DVec2 {
    if n == 1 {
        return DVec2::ZERO;
    }
    const A1: f64 = 0.754_877_666_246_692_8;
    const A2: f64 = 0.569_840_290_998_053_3;
    let k = k as f64;
    DVec2::new((0.5 + A1 * k).fract(), (0.5 + A2 * k).fract()) - 0.5
}

/// Relative illumination at a film pixel: Σ over samples whose ray passes of the normalized
/// weight (1 on the axis) — the vignetting a white, all-covering scene would show.
pub fn relative_illumination(optics: &Optics, samples: u32, lambda_um: f64, px: DVec2) -> f64 {
    let Ok(s) = optics.weighted_samples(samples, lambda_um) else {
        return 0.0;
    };
    let x = optics.film.point(px);
    s.points
        .iter()
        .filter(|p| optics.trace_from_film(x, **p, lambda_um).is_some())
        .map(|p| radiometric_weight(x, *p) * s.scale)
        .sum()
}

/// Peak signal-to-noise ratio (dB) of the RGB channels of two films (values in 0..1).
pub fn psnr(a: &[[f32; 4]], b: &[[f32; 4]]) -> f64 {
    let n = a.len().min(b.len()).max(1);
    let mse: f64 = a
        .iter()
        .zip(b)
        .map(|(p, q)| {
            (0..3)
                .map(|k| (p[k].clamp(0.0, 1.0) as f64 - q[k].clamp(0.0, 1.0) as f64).powi(2))
                .sum::<f64>()
        })
        .sum::<f64>()
        / (3 * n) as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (1.0 / mse).log10()
    }
}
