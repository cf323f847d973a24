//! OpenCV's fisheye model (`cv2.fisheye`, Kannala–Brandt with k1..k4): ROS `equidistant`,
//! Kalibr `pinhole-equi`, COLMAP `OPENCV_FISHEYE`.
//!
//! For a camera-frame point (X, Y, Z), r = √(X² + Y²):
//!
//! ```text
//!   θ    = atan2(r, Z)                                   angle off the optical axis, 0..π
//!   θ_d  = θ (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸)
//!   x'   = θ_d X / r,  y' = θ_d Y / r
//!   u    = fx (x' + α y') + cx,  v = fy y' + cy          α: OpenCV's skew
//! ```
//!
//! OpenCV's `projectPoints` computes θ = atan(r / Z), which mirrors a point behind the image
//! plane into the front hemisphere; `atan2` is the same wherever OpenCV is right (θ < 90°) and
//! stays right past it, which is what lenses of 180° and more need.
//!
//! The skew is applied after the radial map, as OpenCV does: so the *distorted normalized*
//! point of this model is (x' + α y', y'), and the pixel follows from it by the same
//! `fx fy cx cy` as every other model ([`super::Intrinsics::to_pixel`]).
//!
//! # Valid domain
//!
//! The map is radial, so its domain is a cone: θ ≤ θ_max, where θ_max is the first angle at
//! which θ_d stops growing (dθ_d/dθ ≤ 0, the fold), the camera's `max_fov_deg / 2` when it is
//! given, and at most π. Past the fold two directions share a pixel; past the field of view
//! the lens sees nothing. Both are "invalid", as for the standard model.

use std::f64::consts::PI;

use glam::{DMat2, DVec2, DVec3};

use super::jet::Scalar;
use super::solve::solve_increasing;
use super::table::RayModel;
use super::{check_finite, ModelError, ABSURD_MAGNITUDE};

/// Names of the four coefficients, as `cv2.fisheye` orders them.
pub const COEFFICIENT_NAMES: [&str; 4] = ["k1", "k2", "k3", "k4"];

/// Step of the march that finds the fold (radians); bisection refines it.
const FOLD_MARCH_STEP: f64 = 1e-3;
/// The found fold is pulled inward by this (radians) so that dθ_d/dθ stays clearly positive
/// inside the domain (where the inverse is well conditioned enough to converge).
const FOLD_MARGIN: f64 = 1e-9;
/// Below this r / |Z| the ratio θ_d / r is evaluated by its series (1 + O(r²)), where the
/// direct quotient loses digits.
const SMALL_ANGLE: f64 = 1e-8;
/// The inverse accepts θ when θ_d(θ) reproduces the distorted radius to this (relative).
const INVERSE_ACCEPT: f64 = 1e-12;

/// The fisheye lens: k1..k4, the skew α and the half-angle where its domain ends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fisheye {
    /// k1 k2 k3 k4.
    pub k: [f64; 4],
    /// OpenCV's skew α (`K[0][1] = α fx`).
    pub alpha: f64,
    /// The field of view the camera file gave (`max_fov_deg`), full angle in degrees.
    max_fov_deg: Option<f64>,
    /// Largest angle off the axis in the domain (radians, ≤ π).
    theta_max: f64,
    /// Whether θ_max is a fold of θ_d (rather than the field of view or π).
    folds: bool,
}

impl Fisheye {
    /// Largest skew accepted: |α| ≥ 1 shears a pixel by more than its width, which no sensor
    /// means (and OpenCV's calibration keeps α at 0 unless asked).
    pub const MAX_ALPHA: f64 = 1.0;

    /// Validates the parameters and finds the domain.
    pub fn new(k: [f64; 4], alpha: f64, max_fov_deg: Option<f64>) -> Result<Self, ModelError> {
        for (name, &v) in COEFFICIENT_NAMES.iter().zip(k.iter()) {
            check_finite(name, v, ABSURD_MAGNITUDE)?;
        }
        if !alpha.is_finite() {
            return Err(ModelError::NotFinite {
                name: "alpha",
                value: alpha,
            });
        }
        if alpha.abs() >= Self::MAX_ALPHA {
            return Err(ModelError::Other(format!(
                "parameter `alpha` = {alpha}: the skew must be below {} in magnitude",
                Self::MAX_ALPHA
            )));
        }
        if let Some(fov) = max_fov_deg {
            if !fov.is_finite() {
                return Err(ModelError::NotFinite {
                    name: "max_fov_deg",
                    value: fov,
                });
            }
            if !(fov > 0.0 && fov <= 360.0) {
                return Err(ModelError::Other(format!(
                    "parameter `max_fov_deg` must be in (0, 360] degrees, got {fov}"
                )));
            }
        }
        let mut lens = Fisheye {
            k,
            alpha,
            max_fov_deg,
            theta_max: PI,
            folds: false,
        };
        let fold = lens.find_fold();
        let fov = max_fov_deg.map_or(PI, |f| (f / 2.0).to_radians()).min(PI);
        lens.folds = fold.is_some_and(|f| f <= fov);
        lens.theta_max = fold.map_or(fov, |f| f.min(fov));
        Ok(lens)
    }

    /// θ_d(θ) and its derivative.
    #[inline]
    pub fn theta_d(&self, theta: f64) -> (f64, f64) {
        let [k1, k2, k3, k4] = self.k;
        let t2 = theta * theta;
        let poly = 1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4)));
        let dpoly = 1.0 + t2 * (3.0 * k1 + t2 * (5.0 * k2 + t2 * (7.0 * k3 + t2 * 9.0 * k4)));
        (theta * poly, dpoly)
    }

    /// The first θ in (0, π] where θ_d stops growing (or stops being positive), if any.
    fn find_fold(&self) -> Option<f64> {
        let bad = |t: f64| {
            let (v, d) = self.theta_d(t);
            !(d > 0.0 && v > 0.0)
        };
        let mut lo = 0.0;
        let steps = (PI / FOLD_MARCH_STEP).ceil() as usize;
        for i in 1..=steps {
            let t = (i as f64 * FOLD_MARCH_STEP).min(PI);
            if bad(t) {
                let mut hi = t;
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if bad(mid) {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                return Some((lo - FOLD_MARGIN).max(0.0));
            }
            lo = t;
        }
        None
    }

    /// Largest angle off the optical axis in the domain (radians).
    pub fn theta_max(&self) -> f64 {
        self.theta_max
    }

    /// The distorted radius at the edge of the domain (normalized units, before the skew).
    pub fn theta_d_max(&self) -> f64 {
        self.theta_d(self.theta_max).0
    }

    /// Whether the domain ends at a fold of θ_d.
    pub fn folds(&self) -> bool {
        self.folds
    }

    /// The field of view the camera file gave, full angle in degrees.
    pub fn max_fov_deg(&self) -> Option<f64> {
        self.max_fov_deg
    }

    /// Applies the skew: (x', y') → (x' + α y', y').
    fn skew(&self, p: DVec2) -> DVec2 {
        DVec2::new(p.x + self.alpha * p.y, p.y)
    }

    /// Removes the skew exactly.
    pub fn unskew(&self, y: DVec2) -> DVec2 {
        DVec2::new(y.x - self.alpha * y.y, y.y)
    }

    /// Forward model on a camera-frame direction (any length, any hemisphere): the distorted
    /// normalized point, skew included. `None` for the zero or a non-finite vector and for the
    /// one direction straight behind the lens (θ = π, where x'/r has no limit). Whether the
    /// direction is in the domain is [`Fisheye::contains_ray`]'s to say.
    pub fn distort_ray(&self, p: DVec3) -> Option<DVec2> {
        let p = super::table::scaled(p)?;
        let [x, y] = self.project_generic([p.x, p.y, p.z])?;
        let out = DVec2::new(x, y);
        out.is_finite().then_some(out)
    }

    /// Whether a camera-frame direction is inside the domain (θ ≤ θ_max).
    pub fn contains_ray(&self, p: DVec3) -> bool {
        if !p.is_finite() || p == DVec3::ZERO {
            return false;
        }
        let r = p.x.hypot(p.y);
        if r == 0.0 {
            return p.z > 0.0 || self.theta_max >= PI;
        }
        r.atan2(p.z) <= self.theta_max
    }

    /// Forward model on pinhole-normalized coordinates (X/Z, Y/Z), Z > 0, with the Jacobian
    /// ∂(distorted normalized)/∂(x, y). With ρ = |x| and g(ρ) = θ_d(atan ρ) / ρ the map is
    /// x ↦ g x, so J = g I + (g'(ρ)/ρ) x xᵀ, then the skew.
    pub fn distort_normalized(&self, x: DVec2) -> Option<(DVec2, DMat2)> {
        if !x.is_finite() {
            return None;
        }
        // hypot: |x| of a huge finite point must not overflow to ∞ (and g to 0).
        let rho = x.x.hypot(x.y);
        // J = g I + (g'(ρ) ρ) x̂ x̂ᵀ with x̂ = x / ρ: every factor stays finite for huge ρ.
        let (g, dg_rho) = if rho < SMALL_ANGLE {
            // θ = ρ − ρ³/3 + …, θ_d = θ (1 + k1 θ² + …): g = 1 + (k1 − 1/3) ρ² + O(ρ⁴).
            let c = self.k[0] - 1.0 / 3.0;
            (1.0 + c * rho * rho, 2.0 * c * rho * rho)
        } else {
            let theta = rho.atan();
            let (td, dtd) = self.theta_d(theta);
            let g = td / rho;
            (g, dtd / (1.0 + rho * rho) - g)
        };
        let pre = x * g;
        let dir = if rho > 0.0 { x / rho } else { DVec2::ZERO };
        let jac = DMat2::from_diagonal(DVec2::splat(g))
            + DMat2::from_cols(dir * dir.x, dir * dir.y) * dg_rho;
        let shear = DMat2::from_cols(DVec2::new(1.0, 0.0), DVec2::new(self.alpha, 1.0));
        let out = self.skew(pre);
        let jac = shear * jac;
        (out.is_finite() && jac.is_finite()).then_some((out, jac))
    }

    /// Inverse model: distorted normalized point (skew included) → unit camera-frame ray, by
    /// Newton on θ from θ_d (safeguarded by bisection on [0, θ_max], where θ_d increases).
    /// `None` outside the domain.
    pub fn undistort_ray(&self, y: DVec2) -> Option<DVec3> {
        if !y.is_finite() {
            return None;
        }
        let pre = self.unskew(y);
        let rho = pre.x.hypot(pre.y);
        if rho == 0.0 {
            return Some(DVec3::Z);
        }
        if rho > self.theta_d_max() {
            return None;
        }
        let theta = solve_increasing(|t| self.theta_d(t), rho, self.theta_max);
        let (td, _) = self.theta_d(theta);
        if !((td - rho).abs() <= INVERSE_ACCEPT * (1.0 + rho)) || theta > self.theta_max {
            return None;
        }
        let dir = pre / rho;
        let (s, c) = theta.sin_cos();
        Some(DVec3::new(dir.x * s, dir.y * s, c))
    }
}

impl RayModel for Fisheye {
    fn param_names(&self) -> Vec<&'static str> {
        vec!["k1", "k2", "k3", "k4", "alpha"]
    }

    fn params(&self) -> Vec<f64> {
        let [k1, k2, k3, k4] = self.k;
        vec![k1, k2, k3, k4, self.alpha]
    }

    fn project_generic<T: Scalar>(&self, p: [T; 3]) -> Option<[T; 2]> {
        let r2 = p[0] * p[0] + p[1] * p[1];
        let z = p[2].value();
        let scale = if r2.value() == 0.0 {
            if !(z > 0.0) {
                // Straight behind the lens x'/r has no limit.
                return None;
            }
            T::cst(1.0) / p[2]
        } else if z > 0.0 && r2.value() < (SMALL_ANGLE * z) * (SMALL_ANGLE * z) {
            // θ = ρ − ρ³/3 + …, θ_d = θ (1 + k1 θ² + …): θ_d / r = (1 + (k1 − 1/3) ρ²) / z.
            let rho2 = r2 / (p[2] * p[2]);
            (rho2 * (self.k[0] - 1.0 / 3.0) + 1.0) / p[2]
        } else {
            let r = r2.sqrt();
            let theta = r.atan2(p[2]);
            let [k1, k2, k3, k4] = self.k;
            let t2 = theta * theta;
            let poly = (((t2 * k4 + k3) * t2 + k2) * t2 + k1) * t2 + 1.0;
            theta * poly / r
        };
        let (x, y) = (p[0] * scale, p[1] * scale);
        Some([x + y * self.alpha, y])
    }

    fn contains_ray(&self, p: DVec3) -> bool {
        Fisheye::contains_ray(self, p)
    }

    fn unproject(&self, m: DVec2) -> Option<DVec3> {
        self.undistort_ray(m)
    }

    fn max_angle(&self) -> f64 {
        self.theta_max
    }
}
