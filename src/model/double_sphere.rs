//! The double sphere camera model of Usenko, Demmel and Cremers, "The Double Sphere Camera
//! Model" (3DV 2018), as Basalt and Kalibr (`ds`) write it: the point is projected onto two
//! unit spheres whose centres are ξ apart, then by the unified model with α:
//!
//! ```text
//!   d1 = |p|,  k = ξ d1 + z,  d2 = √(x² + y² + k²)
//!   m = (x, y) / (α d2 + (1 − α) k)
//!   valid while z > −w2 d1,  w1 = (1 − α)/α for α > 0.5, else α/(1 − α),
//!                            w2 = (w1 + ξ) / √(2 w1 ξ + ξ² + 1)
//! ```
//!
//! The inverse is the paper's closed form (Eq. 47–50): with r² = |m|²,
//! `mz = (1 − α² r²) / (α √(1 − (2α − 1) r²) + 1 − α)` and
//! ray = (mz ξ + √(mz² + (1 − ξ²) r²)) / (mz² + r²) · (mx, my, mz) − (0, 0, ξ).

use glam::{DVec2, DVec3};

use super::eucm::boundary_angle;
use super::jet::Scalar;
use super::table::{norm3, unit, RayModel};
use super::ucm::{check_unit_interval, unified_w};
use super::{check_finite, ModelError};

/// The double sphere model: ξ and α.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DoubleSphere {
    /// ξ ∈ [−1, 1]: the distance between the spheres' centres.
    pub xi: f64,
    /// α ∈ [0, 1).
    pub alpha: f64,
}

impl DoubleSphere {
    /// Validates ξ ∈ [−1, 1] and α ∈ [0, 1).
    pub fn new(xi: f64, alpha: f64) -> Result<Self, ModelError> {
        check_finite("xi", xi, 1.0)?;
        check_unit_interval("alpha", alpha)?;
        Ok(DoubleSphere { xi, alpha })
    }

    fn w2(&self) -> f64 {
        let w1 = unified_w(self.alpha);
        let xi = self.xi;
        (w1 + xi) / (2.0 * w1 * xi + xi * xi + 1.0).sqrt()
    }
}

impl RayModel for DoubleSphere {
    fn from_params(values: &[f64]) -> Result<Self, ModelError> {
        let [xi, alpha] = super::table::exactly(values)?;
        DoubleSphere::new(xi, alpha)
    }

    fn param_names(&self) -> Vec<&'static str> {
        vec!["xi", "alpha"]
    }

    fn params(&self) -> Vec<f64> {
        vec![self.xi, self.alpha]
    }

    fn project_generic<T: Scalar>(&self, p: [T; 3]) -> Option<[T; 2]> {
        let d1 = norm3(p);
        let k = d1 * self.xi + p[2];
        let d2 = (p[0] * p[0] + p[1] * p[1] + k * k).sqrt();
        let den = d2 * self.alpha + k * (1.0 - self.alpha);
        (den.value() != 0.0).then(|| [p[0] / den, p[1] / den])
    }

    fn contains_ray(&self, p: DVec3) -> bool {
        p.is_finite() && p != DVec3::ZERO && p.z > -self.w2() * p.length()
    }

    fn unproject(&self, m: DVec2) -> Option<DVec3> {
        if !m.is_finite() {
            return None;
        }
        let (xi, a) = (self.xi, self.alpha);
        let r2 = m.length_squared();
        if a > 0.5 && r2 >= 1.0 / (2.0 * a - 1.0) {
            return None;
        }
        let root = 1.0 - (2.0 * a - 1.0) * r2;
        if !(root >= 0.0) {
            return None;
        }
        let mz = (1.0 - a * a * r2) / (a * root.sqrt() + 1.0 - a);
        let inner = mz * mz + (1.0 - xi * xi) * r2;
        if !(inner >= 0.0) {
            return None;
        }
        let k = (mz * xi + inner.sqrt()) / (mz * mz + r2);
        let ray = unit(DVec3::new(k * m.x, k * m.y, k * mz - xi))?;
        self.contains_ray(ray).then_some(ray)
    }

    fn max_angle(&self) -> f64 {
        let w2 = self.w2();
        boundary_angle(|t| t.cos() + w2)
    }
}
