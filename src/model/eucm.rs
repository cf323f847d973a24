//! The enhanced unified camera model (EUCM) of Khomutenko, Garcia and Martinet, "An Enhanced
//! Unified Camera Model" (2016), as Basalt, Kalibr (`eucm`) and COLMAP (`EUCM`) write it:
//!
//! ```text
//!   ρ = √(β (x² + y²) + z²)
//!   m = (x, y) / (α ρ + (1 − α) z)
//!   valid while z > −w ρ,  w = (1 − α)/α for α > 0.5, else α/(1 − α)
//! ```
//!
//! The inverse is closed form (Basalt's): with r² = |m|²,
//! `mz = (1 − β α² r²) / (α √(1 − (2α − 1) β r²) + 1 − α)`, ray ∝ (m, mz); past
//! r² = 1/((2α − 1) β) (α > 0.5) no ray projects.

use glam::{DVec2, DVec3};

use super::jet::Scalar;
use super::table::{unit, RayModel};
use super::ucm::{check_unit_interval, unified_w};
use super::{check_finite, ModelError, ABSURD_MAGNITUDE};

/// The enhanced unified camera model: α and β.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Eucm {
    /// α ∈ [0, 1).
    pub alpha: f64,
    /// β > 0: the ellipsoid's shape (1 is Basalt's UCM).
    pub beta: f64,
}

impl Eucm {
    /// Validates α ∈ [0, 1) and β > 0.
    pub fn new(alpha: f64, beta: f64) -> Result<Self, ModelError> {
        check_unit_interval("alpha", alpha)?;
        check_finite("beta", beta, ABSURD_MAGNITUDE)?;
        if !(beta > 0.0) {
            return Err(ModelError::NotPositive {
                name: "beta",
                value: beta,
            });
        }
        Ok(Eucm { alpha, beta })
    }
}

impl RayModel for Eucm {
    fn from_params(values: &[f64]) -> Result<Self, ModelError> {
        let [alpha, beta] = super::table::exactly(values)?;
        Eucm::new(alpha, beta)
    }

    fn param_names(&self) -> Vec<&'static str> {
        vec!["alpha", "beta"]
    }

    fn params(&self) -> Vec<f64> {
        vec![self.alpha, self.beta]
    }

    fn project_generic<T: Scalar>(&self, p: [T; 3]) -> Option<[T; 2]> {
        let rho = ((p[0] * p[0] + p[1] * p[1]) * self.beta + p[2] * p[2]).sqrt();
        let den = rho * self.alpha + p[2] * (1.0 - self.alpha);
        (den.value() != 0.0).then(|| [p[0] / den, p[1] / den])
    }

    fn contains_ray(&self, p: DVec3) -> bool {
        if !p.is_finite() || p == DVec3::ZERO {
            return false;
        }
        let rho = (self.beta * (p.x * p.x + p.y * p.y) + p.z * p.z).sqrt();
        p.z > -unified_w(self.alpha) * rho
    }

    fn unproject(&self, m: DVec2) -> Option<DVec3> {
        if !m.is_finite() {
            return None;
        }
        let (a, b) = (self.alpha, self.beta);
        let r2 = m.length_squared();
        if a > 0.5 && r2 >= 1.0 / ((2.0 * a - 1.0) * b) {
            return None;
        }
        let root = 1.0 - (2.0 * a - 1.0) * b * r2;
        if !(root >= 0.0) {
            return None;
        }
        let mz = (1.0 - b * a * a * r2) / (a * root.sqrt() + 1.0 - a);
        let ray = unit(DVec3::new(m.x, m.y, mz))?;
        self.contains_ray(ray).then_some(ray)
    }

    fn max_angle(&self) -> f64 {
        // Where z + w ρ reaches zero along θ, with ρ² = β sin²θ + cos²θ on the unit sphere.
        let w = unified_w(self.alpha);
        let g = |t: f64| t.cos() + w * (self.beta * t.sin().powi(2) + t.cos().powi(2)).sqrt();
        boundary_angle(g)
    }
}

/// The first angle in (0, π] at which `g` (positive at 0, continuous) reaches zero, by
/// bisection after a march; π where it never does.
pub(crate) fn boundary_angle(g: impl Fn(f64) -> f64) -> f64 {
    const STEPS: usize = 4096;
    let pi = std::f64::consts::PI;
    let mut lo = 0.0;
    for i in 1..=STEPS {
        let t = pi * i as f64 / STEPS as f64;
        if !(g(t) > 0.0) {
            let mut hi = t;
            for _ in 0..80 {
                let mid = 0.5 * (lo + hi);
                if g(mid) > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            return lo;
        }
        lo = t;
    }
    pi
}
