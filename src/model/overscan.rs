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

/// The side of the cube faces that give a sphere warp `density` source pixels per output pixel
/// where the faces sample most coarsely (their centres, `S / 2` pixels per unit tangent) and
/// the lens most finely (its centre, `f` pixels per radian): `S = 2 f density`.
pub fn cube_face_side(camera: &Camera, density: f64) -> u32 {
    let f = camera.intrinsics.fx.max(camera.intrinsics.fy);
    (2.0 * f * density)
        .ceil()
        .clamp(16.0, MAX_IMAGE_SIDE as f64) as u32
}

/// Whether some valid pixel of `camera`'s frame sees a direction no pinhole source can hold
/// (at or past the domain's radius cap, 89.94° off the axis): a fisheye of 180° and more, or
/// one whose frame corners reach past 90°.
pub fn beyond_a_pinhole(camera: &Camera) -> bool {
    let cap = super::ValidDomain::RADIUS_CAP.atan();
    let (w, h) = (camera.width as f64, camera.height as f64);
    let border = (0..=256).flat_map(|i| {
        let t = i as f64 / 256.0;
        [
            DVec2::new(t * (w - 1.0), 0.0),
            DVec2::new(t * (w - 1.0), h - 1.0),
            DVec2::new(0.0, t * (h - 1.0)),
            DVec2::new(w - 1.0, t * (h - 1.0)),
        ]
    });
    border
        .filter_map(|p| camera.unproject(p))
        .any(|ray| ray.z <= cap.cos())
        || camera.fisheye_lens().is_some_and(|f| {
            // The domain's edge inside the frame (an image circle).
            f.theta_max() >= cap && {
                let k = camera.intrinsics;
                let r = f.theta_d(cap).0;
                let c = DVec2::new(k.cx, k.cy);
                (0..64).any(|i| {
                    let a = TAU * i as f64 / 64.0;
                    let p = c + DVec2::new(a.cos() * r * k.fx, a.sin() * r * k.fy);
                    p.x >= -0.5 && p.y >= -0.5 && p.x <= w - 0.5 && p.y <= h - 0.5
                })
            }
        })
}
