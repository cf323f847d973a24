//! The equirectangular panorama: 360° of longitude across the image, 180° of latitude down
//! it. COLMAP's `EQUIRECTANGULAR`, and what `distort --input-equirect` reads.
//!
//! ```text
//!   lon = atan2(x, z)          0 straight ahead, +90° to the right (+x)
//!   lat = atan2(y, √(x² + z²)) +90° straight down (+y, OpenCV's frame)
//!   m = (lon, lat),  u = fx lon + cx,  v = fy lat + cy
//! ```
//!
//! With fx = W/2π, fy = H/π, cx = W/2 − 0.5, cy = H/2 − 0.5 (the defaults) the image covers the
//! whole sphere, pixel centres in OpenCV's convention (COLMAP's frame is the same, shifted by
//! its +0.5 pixel centre). Every direction has a pixel: the domain is the whole sphere.

use std::f64::consts::{FRAC_PI_2, PI};

use glam::{DVec2, DVec3};

use super::jet::Scalar;
use super::table::RayModel;

/// The equirectangular panorama (no parameters of its own).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Equirectangular;

impl Equirectangular {
    /// The intrinsics that map the whole sphere onto a `width` × `height` image.
    pub fn full_sphere(width: u32, height: u32) -> [f64; 4] {
        let (w, h) = (width as f64, height as f64);
        [w / (2.0 * PI), h / PI, w / 2.0 - 0.5, h / 2.0 - 0.5]
    }
}

impl RayModel for Equirectangular {
    fn param_names(&self) -> Vec<&'static str> {
        Vec::new()
    }

    fn params(&self) -> Vec<f64> {
        Vec::new()
    }

    fn project_generic<T: Scalar>(&self, p: [T; 3]) -> Option<[T; 2]> {
        let horizontal = (p[0] * p[0] + p[2] * p[2]).sqrt();
        if horizontal.value() == 0.0 {
            // Straight up or down: the pole row's centre column (longitude 0).
            let lat = if p[1].value() > 0.0 {
                FRAC_PI_2
            } else {
                -FRAC_PI_2
            };
            return Some([T::cst(0.0), T::cst(lat)]);
        }
        Some([p[0].atan2(p[2]), p[1].atan2(horizontal)])
    }

    fn contains_ray(&self, p: DVec3) -> bool {
        p.is_finite() && p != DVec3::ZERO
    }

    fn unproject(&self, m: DVec2) -> Option<DVec3> {
        if !m.is_finite() || m.x.abs() > PI || m.y.abs() > FRAC_PI_2 {
            return None;
        }
        let (sl, cl) = m.y.sin_cos();
        let (so, co) = m.x.sin_cos();
        Some(DVec3::new(cl * so, sl, cl * co))
    }

    fn max_angle(&self) -> f64 {
        PI
    }
}
