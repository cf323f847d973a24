//! Mei and Rives' unified omnidirectional model with radial-tangential distortion, "Single
//! View Point Omnidirectional Camera Calibration from Planar Grids" (ICRA 2007): Kalibr's
//! `omni-radtan`, camodocal's `MEI`, OpenCV contrib's `cv2.omnidir`.
//!
//! ```text
//!   d = |p|,  m = (x, y) / (z + ξ d)               the point on the unit sphere, seen from −ξ
//!   m' = radtan(m; k1, k2, p1, p2)                 OpenCV's k1 k2 p1 p2 terms
//!   u = γ1 m'x + cx,  v = γ2 m'y + cy              γ: Mei's generalized focal lengths (fx fy)
//!   valid while z > −w d, w = ξ for ξ ≤ 1, else 1/ξ (Kalibr's test), and m inside the
//!   radial-tangential part's own valid domain (where it folds, no inverse can be right)
//! ```
//!
//! The inverse undoes the radial-tangential part by the standard model's Newton (the same
//! code and domain as OpenCV's model) and lifts m onto the sphere in closed form:
//! ray ∝ (f m, f − ξ), f = (ξ + √(1 + (1 − ξ²)|m|²)) / (1 + |m|²).

use glam::{DVec2, DVec3};

use super::domain::ValidDomain;
use super::jet::Scalar;
use super::opencv::{Intrinsics, OpenCvDistortion};
use super::table::{norm3, unit, RayModel};
use super::Camera;
use super::{check_finite, InverseMethod, ModelError, ABSURD_MAGNITUDE};

/// Mei's model: ξ and the radial-tangential k1 k2 p1 p2.
#[derive(Debug, Clone)]
pub struct Omni {
    /// ξ ≥ 0: the sphere's offset (0 is a pinhole, 1 a parabolic mirror).
    pub xi: f64,
    /// The radial-tangential part as a standard-model camera on the plane of m (fx = fy = 1,
    /// cx = cy = 0), which carries its valid domain and its inverse.
    radtan: Box<Camera>,
}

impl PartialEq for Omni {
    fn eq(&self, other: &Self) -> bool {
        self.xi == other.xi && self.dist_coeffs() == other.dist_coeffs()
    }
}

impl Omni {
    /// Validates ξ ≥ 0 and k1 k2 p1 p2, and finds the radial-tangential part's domain.
    pub fn new(xi: f64, dist_coeffs: [f64; 4]) -> Result<Self, ModelError> {
        check_finite("xi", xi, ABSURD_MAGNITUDE)?;
        if !(xi >= 0.0) {
            return Err(ModelError::Other(format!(
                "parameter `xi` = {xi} must be ≥ 0"
            )));
        }
        let unit_k = Intrinsics {
            fx: 1.0,
            fy: 1.0,
            cx: 0.0,
            cy: 0.0,
        };
        let radtan = Camera::new(1, 1, unit_k, OpenCvDistortion::from_coeffs(&dist_coeffs)?)?
            .with_radius_cap(Self::plane_radius_cap(xi));
        Ok(Omni {
            xi,
            radtan: Box::new(radtan),
        })
    }

    /// How far out Mei's plane point m reaches inside the domain. At its edge, z = −w·|P|,
    /// |m| = sin θ / (cos θ + ξ) is 1/√(ξ² − 1) for ξ > 1, and unbounded for ξ ≤ 1 (the edge
    /// ray meets the plane at infinity). There the table stops at 1e6, which gives up the
    /// last 1e-6 rad before the edge (|m| ≈ 1/Δθ there), far below what a pixel resolves.
    fn plane_radius_cap(xi: f64) -> f64 {
        const FAR: f64 = 1e6;
        let edge = if xi > 1.0 {
            1.0 / (xi * xi - 1.0).sqrt()
        } else {
            f64::INFINITY
        };
        (edge * 1.01).clamp(ValidDomain::RADIUS_CAP, FAR)
    }

    /// The radial-tangential part as a standard-model camera (fx = fy = 1, cx = cy = 0): the
    /// shaders evaluate it with the standard model's code and its domain table.
    pub fn radtan(&self) -> &Camera {
        &self.radtan
    }

    /// k1 k2 p1 p2.
    pub fn dist_coeffs(&self) -> [f64; 4] {
        let d = self.radtan.distortion();
        [d.k1, d.k2, d.p1, d.p2]
    }

    /// Kalibr's w: the domain is z > −w |p|.
    fn w(&self) -> f64 {
        if self.xi <= 1.0 {
            self.xi
        } else {
            1.0 / self.xi
        }
    }

    /// The undistorted point m on the unit sphere's plane (before radial-tangential).
    fn sphere_point(&self, p: DVec3) -> DVec2 {
        let k = p.z + self.xi * p.length();
        DVec2::new(p.x / k, p.y / k)
    }
}

impl RayModel for Omni {
    fn param_names(&self) -> Vec<&'static str> {
        vec!["xi", "k1", "k2", "p1", "p2"]
    }

    fn params(&self) -> Vec<f64> {
        let [k1, k2, p1, p2] = self.dist_coeffs();
        vec![self.xi, k1, k2, p1, p2]
    }

    fn project_generic<T: Scalar>(&self, p: [T; 3]) -> Option<[T; 2]> {
        let d = norm3(p);
        let k = p[2] + d * self.xi;
        if k.value() == 0.0 {
            return None;
        }
        let (mx, my) = (p[0] / k, p[1] / k);
        let [k1, k2, p1, p2] = self.dist_coeffs();
        let r2 = mx * mx + my * my;
        let radial = r2 * (r2 * k2 + k1) + 1.0;
        let two_xy = mx * my * 2.0;
        Some([
            mx * radial + two_xy * p1 + (r2 + mx * mx * 2.0) * p2,
            my * radial + (r2 + my * my * 2.0) * p1 + two_xy * p2,
        ])
    }

    fn contains_ray(&self, p: DVec3) -> bool {
        if !p.is_finite() || p == DVec3::ZERO || !(p.z > -self.w() * p.length()) {
            return false;
        }
        let m = self.sphere_point(p);
        m.is_finite() && self.radtan.domain().contains_ideal(m)
    }

    fn unproject(&self, m: DVec2) -> Option<DVec3> {
        if !m.is_finite() {
            return None;
        }
        let m = self.radtan.undistort_normalized(m, InverseMethod::Newton)?;
        let xi = self.xi;
        let r2 = m.length_squared();
        let root = 1.0 + (1.0 - xi * xi) * r2;
        if !(root >= 0.0) {
            return None;
        }
        let f = (xi + root.sqrt()) / (1.0 + r2);
        let ray = unit(DVec3::new(f * m.x, f * m.y, f - xi))?;
        self.contains_ray(ray).then_some(ray)
    }

    fn max_angle(&self) -> f64 {
        (-self.w()).acos()
    }

    /// `glsl/include/models/omni.glsl`: ξ and Kalibr's w (k1 k2 p1 p2 go where the standard
    /// model's are, with the radial-tangential part's domain table).
    fn gpu_params(&self) -> Vec<f64> {
        vec![self.xi, self.w()]
    }
}
