//! Overscan (Lambers et al. Sec. 3.3's unfilled areas): the pinhole camera a post-processing warp
//! needs as its source so that *every* valid distorted pixel has something to sample.
//!
//! The seed suggests undistorting the four image corners. That is not enough: for barrel,
//! pincushion and mustache lenses the extreme ideal coordinates lie at different places on the
//! border, and where the lens folds over inside the image the fold boundary bounds the valid
//! region instead. The warp is a homeomorphism on the valid region, so its bounding box is the
//! bounding box of the image of the region's boundary: the image border (every pixel) where it
//! is valid, plus the domain boundary where it lies inside the image.

use std::f64::consts::TAU;

use glam::DVec2;

use super::{Camera, Intrinsics, InverseMethod, ModelError, MAX_IMAGE_SIDE};

/// The pinhole source camera for a distort warp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Overscan {
    pub intrinsics: Intrinsics,
    pub width: u32,
    pub height: u32,
}

/// Ideal normalized points on the boundary of `camera`'s valid region (see module docs).
pub fn valid_region_boundary(camera: &Camera) -> Vec<DVec2> {
    let (w, h) = (camera.width as f64, camera.height as f64);
    let mut pixels = Vec::new();
    for x in 0..camera.width {
        pixels.push(DVec2::new(x as f64, 0.0));
        pixels.push(DVec2::new(x as f64, h - 1.0));
    }
    for y in 0..camera.height {
        pixels.push(DVec2::new(0.0, y as f64));
        pixels.push(DVec2::new(w - 1.0, y as f64));
    }
    let mut points: Vec<DVec2> = pixels
        .iter()
        .filter_map(|&p| {
            camera.undistort_normalized(camera.intrinsics.to_normalized(p), InverseMethod::Newton)
        })
        .collect();
    // The fold boundary, finely sampled, where its image lies on the image.
    let domain = camera.domain();
    for i in 0..4096 {
        let angle = TAU * i as f64 / 4096.0;
        let x = DVec2::new(angle.cos(), angle.sin()) * domain.ideal_radius(angle);
        if let Some(p) = camera
            .distort_normalized(x)
            .map(|y| camera.intrinsics.to_pixel(y))
        {
            if p.x >= 0.0 && p.y >= 0.0 && p.x <= w - 1.0 && p.y <= h - 1.0 {
                points.push(x);
            }
        }
    }
    points
}

/// The overscanned pinhole camera covering every valid pixel of `camera`, with `density`
/// source pixels per output pixel at the principal point (1.0: the same focal length), and a
/// one-pixel margin for bilinear taps.
pub fn overscan(camera: &Camera, density: f64) -> Result<Overscan, ModelError> {
    if !(density.is_finite() && density > 0.0 && density <= 16.0) {
        return Err(ModelError::Other(format!(
            "density must be in (0, 16], got {density}"
        )));
    }
    let points = valid_region_boundary(camera);
    if points.is_empty() {
        return Err(ModelError::Other(
            "no pixel of the image is in the lens's valid domain".into(),
        ));
    }
    let min = points
        .iter()
        .fold(DVec2::splat(f64::INFINITY), |a, &p| a.min(p));
    let max = points
        .iter()
        .fold(DVec2::splat(f64::NEG_INFINITY), |a, &p| a.max(p));
    let fx = camera.intrinsics.fx * density;
    let fy = camera.intrinsics.fy * density;
    let width = (fx * (max.x - min.x)).ceil() + 2.0;
    let height = (fy * (max.y - min.y)).ceil() + 2.0;
    if width > MAX_IMAGE_SIDE as f64 || height > MAX_IMAGE_SIDE as f64 {
        return Err(ModelError::Other(format!(
            "the overscanned source would be {width}×{height} px (over {MAX_IMAGE_SIDE}): lower the density"
        )));
    }
    Ok(Overscan {
        // The extreme point lands half a pixel inside the frame's first pixel centre.
        intrinsics: Intrinsics {
            fx,
            fy,
            cx: 0.5 - fx * min.x,
            cy: 0.5 - fy * min.y,
        },
        width: width as u32,
        height: height as u32,
    })
}
