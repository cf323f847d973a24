//! Fitzgibbon's one-parameter division model, "Simultaneous linear estimation of multiple view
//! geometry and lens distortion" (CVPR 2001), as COLMAP (`SIMPLE_DIVISION`, `DIVISION`) writes
//! it: the undistorted normalized point is the distorted one divided by 1 + k r_d²,
//!
//! ```text
//!   x_u = m / (1 + k |m|²)          (the inverse, closed form)
//!   m = 2 (x, y) / (z + √(z² − 4 k (x² + y²)))      (the forward map, COLMAP's)
//! ```
//!
//! The forward map takes the root with r_d ≤ 1/√k (k > 0), where r_u(r_d) still grows, so it
//! is invertible on its domain: z > 0 and z² ≥ 4k(x² + y²). COLMAP does not check the depth
//! and returns the mirror image of a point behind the camera; vklens calls it invalid.

use glam::{DVec2, DVec3};

use super::jet::Scalar;
use super::table::{unit, RayModel};
use super::{check_finite, ModelError, ABSURD_MAGNITUDE};

/// The division model: one parameter, k.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Division {
    /// k (negative: barrel).
    pub k: f64,
}

impl Division {
    /// Validates k.
    pub fn new(k: f64) -> Result<Self, ModelError> {
        check_finite("k", k, ABSURD_MAGNITUDE)?;
        Ok(Division { k })
    }
}

impl RayModel for Division {
    fn from_params(values: &[f64]) -> Result<Self, ModelError> {
        let [k] = super::table::exactly(values)?;
        Division::new(k)
    }

    fn param_names(&self) -> Vec<&'static str> {
        vec!["k"]
    }

    fn params(&self) -> Vec<f64> {
        vec![self.k]
    }

    fn project_generic<T: Scalar>(&self, p: [T; 3]) -> Option<[T; 2]> {
        let rho2 = p[0] * p[0] + p[1] * p[1];
        let disc = p[2] * p[2] - rho2 * (4.0 * self.k);
        if !(disc.value() >= 0.0) {
            return None;
        }
        let den = p[2] + disc.sqrt();
        (den.value() > 0.0).then(|| {
            let s = T::cst(2.0) / den;
            [p[0] * s, p[1] * s]
        })
    }

    fn contains_ray(&self, p: DVec3) -> bool {
        p.is_finite() && p.z > 0.0 && p.z * p.z >= 4.0 * self.k * (p.x * p.x + p.y * p.y)
    }

    fn unproject(&self, m: DVec2) -> Option<DVec3> {
        if !m.is_finite() {
            return None;
        }
        let r2 = m.length_squared();
        // Past r_d = 1/√k the forward map never lands (its other root).
        if self.k > 0.0 && r2 * self.k > 1.0 {
            return None;
        }
        let d = 1.0 + self.k * r2;
        if !(d > 0.0) {
            return None;
        }
        unit(DVec3::new(m.x / d, m.y / d, 1.0))
    }

    fn max_angle(&self) -> f64 {
        if self.k > 0.0 {
            // r_u ≤ 1/(2√k).
            (0.5 / self.k.sqrt()).atan()
        } else {
            std::f64::consts::FRAC_PI_2
        }
    }
}
