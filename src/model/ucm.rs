//! The unified camera model (UCM) as Basalt writes it (Usenko et al., "The Double Sphere
//! Camera Model", Sec. 3.3): Mei's unified model without distortion, in the parametrization
//! with α ∈ [0, 1] that keeps fx fy close to a pinhole's.
//!
//! ```text
//!   d = √(x² + y² + z²)
//!   m = (x, y) / (α d + (1 − α) z)
//!   valid while z > −w d,  w = (1 − α)/α for α > 0.5, else α/(1 − α)
//! ```
//!
//! It is Mei's model with ξ = α/(1 − α) and focal lengths fx/(1 − α): the inverse lifts
//! m(1 − α) onto the unit sphere in closed form.

use glam::{DVec2, DVec3};

use super::jet::Scalar;
use super::table::{norm3, unit, RayModel};
use super::{check_finite, ModelError};

/// Basalt's unified camera model: one parameter, α.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ucm {
    /// α ∈ [0, 1): 0 is a pinhole.
    pub alpha: f64,
}

impl Ucm {
    /// Validates α (Basalt's range, [0, 1)).
    pub fn new(alpha: f64) -> Result<Self, ModelError> {
        check_unit_interval("alpha", alpha)?;
        Ok(Ucm { alpha })
    }
}

/// The domain's half-angle of the unified models: z > −w d holds up to θ = acos(−w), and w
/// = (1 − α)/α or α/(1 − α).
pub(crate) fn unified_w(alpha: f64) -> f64 {
    if alpha > 0.5 {
        (1.0 - alpha) / alpha
    } else {
        alpha / (1.0 - alpha)
    }
}

/// α (or ξ's counterpart) in [0, 1): Basalt refuses α outside it.
pub(crate) fn check_unit_interval(name: &'static str, v: f64) -> Result<(), ModelError> {
    check_finite(name, v, 1.0)?;
    if !(0.0..1.0).contains(&v) {
        return Err(ModelError::Other(format!(
            "parameter `{name}` = {v} must be in [0, 1)"
        )));
    }
    Ok(())
}

impl RayModel for Ucm {
    fn from_params(values: &[f64]) -> Result<Self, ModelError> {
        let [alpha] = super::table::exactly(values)?;
        Ucm::new(alpha)
    }

    fn param_names(&self) -> Vec<&'static str> {
        vec!["alpha"]
    }

    fn params(&self) -> Vec<f64> {
        vec![self.alpha]
    }

    fn project_generic<T: Scalar>(&self, p: [T; 3]) -> Option<[T; 2]> {
        let d = norm3(p);
        let den = d * self.alpha + p[2] * (1.0 - self.alpha);
        (den.value() != 0.0).then(|| [p[0] / den, p[1] / den])
    }

    fn contains_ray(&self, p: DVec3) -> bool {
        p.is_finite() && p != DVec3::ZERO && p.z > -unified_w(self.alpha) * p.length()
    }

    fn unproject(&self, m: DVec2) -> Option<DVec3> {
        if !m.is_finite() {
            return None;
        }
        let a = self.alpha;
        let r2 = m.length_squared();
        // Past r² = 1/(2α − 1) no ray projects (Basalt's own test).
        if a > 0.5 && r2 >= 1.0 / (2.0 * a - 1.0) {
            return None;
        }
        // Mei's lifting with ξ = α/(1 − α) on m(1 − α).
        let xi = a / (1.0 - a);
        let mm = m * (1.0 - a);
        let s2 = mm.length_squared();
        let root = 1.0 + (1.0 - xi * xi) * s2;
        if !(root >= 0.0) {
            return None;
        }
        let factor = (xi + root.sqrt()) / (1.0 + s2);
        let ray = unit(DVec3::new(factor * mm.x, factor * mm.y, factor - xi))?;
        self.contains_ray(ray).then_some(ray)
    }

    fn max_angle(&self) -> f64 {
        (-unified_w(self.alpha)).acos()
    }
}
