//! NVIDIA's f-theta model as NCore defines it (`FThetaCameraModel`): the pixel distance from
//! the principal point is a polynomial of the angle off the axis, or the angle a polynomial of
//! the pixel distance, then a linear term:
//!
//! ```text
//!   θ = atan2(ρ, z),  ρ = √(x² + y²)             any hemisphere
//!   δ = fw(θ)          (reference ANGLE_TO_PIXELDIST), or the δ with bw(δ) = θ
//!                      (reference PIXELDIST_TO_ANGLE), solved exactly on bw's increasing branch
//!   m = [[c, d], [e, 1]] · δ (x, y) / ρ        the file's linear_cde
//!   u = m.x + cx,  v = m.y + cy                 cx, cy = NCore's principal_point
//!   valid while θ < max_angle and the reference polynomial increases
//! ```
//!
//! NCore's principal point puts pixel centres on integers, as OpenCV does, so it is `cx, cy`
//! unchanged. The reference polynomial is the definition; the file's other polynomial (a fit
//! of the inverse) is what NCore itself evaluates, with three Newton steps: vklens solves
//! exactly instead, and [`FTheta::approximate_angle`] / [`FTheta::approximate_distance`] give
//! the fit's answer, whose error `vklens bench models` measures.

use glam::{DMat2, DVec2, DVec3};

use super::jet::Scalar;
use super::poly;
use super::table::{unit, RayModel};
use super::{check_finite, ModelError, ABSURD_MAGNITUDE};

/// Which of the two polynomials defines the model (NCore's `reference_poly`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reference {
    /// θ = bw(pixel distance) is the definition.
    PixeldistToAngle,
    /// pixel distance = fw(θ) is the definition.
    AngleToPixeldist,
}

impl Reference {
    /// NCore's spelling.
    pub fn name(self) -> &'static str {
        match self {
            Reference::PixeldistToAngle => "PIXELDIST_TO_ANGLE",
            Reference::AngleToPixeldist => "ANGLE_TO_PIXELDIST",
        }
    }

    /// From NCore's spelling.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "PIXELDIST_TO_ANGLE" => Some(Reference::PixeldistToAngle),
            "ANGLE_TO_PIXELDIST" => Some(Reference::AngleToPixeldist),
            _ => None,
        }
    }
}

/// Most coefficients per polynomial (the shaders hold 8).
pub const MAX_COEFFICIENTS: usize = 8;

/// Steps of the march that finds where the reference polynomial stops increasing.
const FOLD_STEPS: usize = 4096;

/// The f-theta model.
#[derive(Debug, Clone, PartialEq)]
pub struct FTheta {
    /// Which polynomial is the definition.
    pub reference: Reference,
    /// bw: pixel distance → angle, ascending (c0 first).
    pub pixeldist_to_angle: Vec<f64>,
    /// fw: angle → pixel distance, ascending.
    pub angle_to_pixeldist: Vec<f64>,
    /// [c, d, e] of the linear term [[c, d], [e, 1]].
    pub linear_cde: [f64; 3],
    /// The largest angle off the axis the file allows (radians).
    pub max_angle: f64,
    /// NCore's `shutter_type` (how the sensor reads its lines), kept as the file wrote it.
    pub shutter_type: Option<String>,
    /// Evaluate the direction the reference does not define with the file's other polynomial
    /// (what NCore evaluates before its Newton steps: cheaper, off by its fit's error) instead
    /// of solving the reference exactly ([`FTheta::with_fitted_inverse`]).
    fitted_inverse: bool,
    /// Largest angle in the domain: max_angle, or less where the reference polynomial folds.
    theta_max: f64,
    /// The reference polynomial's increasing branch ends here (its own argument).
    branch_end: f64,
}

impl FTheta {
    /// Validates the parameters and finds the reference polynomial's increasing branch.
    pub fn new(
        reference: Reference,
        pixeldist_to_angle: Vec<f64>,
        angle_to_pixeldist: Vec<f64>,
        linear_cde: [f64; 3],
        max_angle: f64,
    ) -> Result<Self, ModelError> {
        for (name, poly) in [
            ("pixeldist_to_angle_poly", &pixeldist_to_angle),
            ("angle_to_pixeldist_poly", &angle_to_pixeldist),
        ] {
            if poly.len() > MAX_COEFFICIENTS {
                return Err(ModelError::Other(format!(
                    "`{name}` has {} coefficients; vklens evaluates f-theta polynomials of at most 8 (NCore writes 6)",
                    poly.len()
                )));
            }
            for &c in poly.iter() {
                check_finite(name, c, ABSURD_MAGNITUDE)?;
            }
        }
        for (name, v) in ["c", "d", "e"].into_iter().zip(linear_cde) {
            check_finite(name, v, ABSURD_MAGNITUDE)?;
        }
        check_finite("max_angle", max_angle, std::f64::consts::PI)?;
        if !(max_angle > 0.0) {
            return Err(ModelError::NotPositive {
                name: "max_angle",
                value: max_angle,
            });
        }
        // NCore: a linear term of all zeros means none.
        let linear_cde = if linear_cde == [0.0; 3] {
            [1.0, 0.0, 0.0]
        } else {
            linear_cde
        };
        let [c, d, e] = linear_cde;
        if !((c - d * e).abs() > 1e-12) {
            return Err(ModelError::Other(format!(
                "`linear_cde` = [{c}, {d}, {e}] is singular (c − d·e = 0)"
            )));
        }
        let defining = match reference {
            Reference::PixeldistToAngle => &pixeldist_to_angle,
            Reference::AngleToPixeldist => &angle_to_pixeldist,
        };
        if defining.iter().all(|&c| c == 0.0) {
            return Err(ModelError::Other(format!(
                "the reference polynomial ({}) is all zeros",
                reference.name()
            )));
        }
        let mut lens = FTheta {
            reference,
            pixeldist_to_angle,
            angle_to_pixeldist,
            linear_cde,
            max_angle,
            shutter_type: None,
            fitted_inverse: false,
            theta_max: max_angle,
            branch_end: 0.0,
        };
        match reference {
            Reference::AngleToPixeldist => {
                let end = poly::increasing_until(
                    |t| poly::eval_with_slope(&lens.angle_to_pixeldist, t),
                    max_angle,
                    FOLD_STEPS,
                );
                lens.branch_end = end;
                lens.theta_max = end;
            }
            Reference::PixeldistToAngle => {
                // The pixel distance that reaches max_angle bounds the search: bw's slope is
                // about 1/focal length, so 1e7 px reaches any angle a lens has.
                let bw = |r: f64| poly::eval_with_slope(&lens.pixeldist_to_angle, r);
                let mut hi = 1.0;
                while bw(hi).0 < max_angle && hi < 1e7 {
                    hi *= 2.0;
                }
                let end = poly::increasing_until(bw, hi, FOLD_STEPS);
                lens.branch_end = end;
                lens.theta_max = bw(end).0.min(max_angle);
            }
        }
        if !(lens.theta_max > 0.0) {
            return Err(ModelError::Other(format!(
                "the reference polynomial ({}) does not increase from the axis: no angle has a pixel",
                reference.name()
            )));
        }
        Ok(lens)
    }

    /// The same lens evaluating the direction its reference does not define with the file's
    /// other polynomial (`true`), or solving the reference exactly (`false`, the default).
    /// `vklens bench models` measures what the fit costs in pixels and saves in time.
    pub fn with_fitted_inverse(mut self, fitted: bool) -> Result<Self, ModelError> {
        let (name, fit) = match self.reference {
            Reference::PixeldistToAngle => ("angle_to_pixeldist_poly", &self.angle_to_pixeldist),
            Reference::AngleToPixeldist => ("pixeldist_to_angle_poly", &self.pixeldist_to_angle),
        };
        if fitted && fit.iter().all(|&c| c == 0.0) {
            return Err(ModelError::Other(format!(
                "`fitted_inverse` needs the file's fit of the inverse, but `{name}` is empty or all zeros"
            )));
        }
        self.fitted_inverse = fitted;
        Ok(self)
    }

    /// Whether the non-reference direction is the file's fit ([`FTheta::with_fitted_inverse`]).
    pub fn fitted_inverse(&self) -> bool {
        self.fitted_inverse
    }

    fn linear(&self) -> DMat2 {
        let [c, d, e] = self.linear_cde;
        DMat2::from_cols(DVec2::new(c, e), DVec2::new(d, 1.0))
    }

    /// Pixel distance (before the linear term) of the angle θ, exactly (inside the domain).
    pub fn distance(&self, theta: f64) -> Option<f64> {
        match self.reference {
            Reference::AngleToPixeldist => Some(poly::eval(&self.angle_to_pixeldist, theta)),
            Reference::PixeldistToAngle => poly::solve_monotone(
                |r| poly::eval_with_slope(&self.pixeldist_to_angle, r),
                theta,
                self.branch_end,
            ),
        }
    }

    /// Angle of the pixel distance r, exactly (inside the domain).
    fn angle(&self, r: f64) -> Option<f64> {
        match self.reference {
            Reference::PixeldistToAngle => {
                (r <= self.branch_end).then(|| poly::eval(&self.pixeldist_to_angle, r))
            }
            Reference::AngleToPixeldist => poly::solve_monotone(
                |t| poly::eval_with_slope(&self.angle_to_pixeldist, t),
                r,
                self.branch_end,
            ),
        }
    }

    /// The file's non-reference polynomial's answer for the angle of pixel distance r (the
    /// cheaper method NCore's fit offers); exact where bw is the reference.
    pub fn approximate_angle(&self, r: f64) -> f64 {
        poly::eval(&self.pixeldist_to_angle, r)
    }

    /// The file's fit for the pixel distance of angle θ; exact where fw is the reference.
    pub fn approximate_distance(&self, theta: f64) -> f64 {
        poly::eval(&self.angle_to_pixeldist, theta)
    }
}

impl RayModel for FTheta {
    fn param_names(&self) -> Vec<&'static str> {
        vec!["max_angle", "c", "d", "e"]
    }

    fn params(&self) -> Vec<f64> {
        let [c, d, e] = self.linear_cde;
        vec![self.max_angle, c, d, e]
    }

    fn project_generic<T: Scalar>(&self, p: [T; 3]) -> Option<[T; 2]> {
        let r2 = p[0] * p[0] + p[1] * p[1];
        if r2.value() == 0.0 {
            return (p[2].value() > 0.0).then(|| [T::cst(0.0), T::cst(0.0)]);
        }
        let rho = r2.sqrt();
        let theta = rho.atan2(p[2]);
        let delta = match self.reference {
            Reference::AngleToPixeldist => poly::eval(&self.angle_to_pixeldist, theta),
            Reference::PixeldistToAngle if self.fitted_inverse => {
                if !(theta.value() < self.theta_max) {
                    return None;
                }
                poly::eval(&self.angle_to_pixeldist, theta)
            }
            Reference::PixeldistToAngle => {
                // δ solves bw(δ) = θ: its value by the solver, its derivatives by the implicit
                // function theorem (dδ = dθ / bw'(δ)).
                let d = self.distance(theta.value())?;
                let (_, slope) = poly::eval_with_slope(&self.pixeldist_to_angle, d);
                (theta - theta.value()) / slope + d
            }
        };
        let s = delta / rho;
        let (x, y) = (p[0] * s, p[1] * s);
        let [c, d, e] = self.linear_cde;
        Some([x * c + y * d, x * e + y])
    }

    fn contains_ray(&self, p: DVec3) -> bool {
        p.is_finite() && p != DVec3::ZERO && p.x.hypot(p.y).atan2(p.z) < self.theta_max
    }

    fn unproject(&self, m: DVec2) -> Option<DVec3> {
        if !m.is_finite() {
            return None;
        }
        let q = self.linear().inverse() * m;
        let r = q.length();
        if r == 0.0 {
            return Some(DVec3::Z);
        }
        let theta = if self.fitted_inverse && self.reference == Reference::AngleToPixeldist {
            poly::eval(&self.pixeldist_to_angle, r)
        } else {
            self.angle(r)?
        };
        if !(theta >= 0.0 && theta < self.theta_max) {
            return None;
        }
        let (s, c) = theta.sin_cos();
        unit(DVec3::new(q.x / r * s, q.y / r * s, c))
    }

    // The domain's edge: the file's max_angle, or earlier where the reference polynomial
    // folds.
    #[allow(clippy::misnamed_getters)]
    fn max_angle(&self) -> f64 {
        self.theta_max
    }

    /// `glsl/include/models/ftheta.glsl`: (reference, θ_max, branch end, fitted inverse),
    /// (c, d, e, −), then fw's and bw's 8 coefficients each.
    fn gpu_params(&self) -> Vec<f64> {
        let reference = match self.reference {
            Reference::PixeldistToAngle => 0.0,
            Reference::AngleToPixeldist => 1.0,
        };
        let [c, d, e] = self.linear_cde;
        let mut v = vec![
            reference,
            self.theta_max,
            self.branch_end,
            if self.fitted_inverse { 1.0 } else { 0.0 },
            c,
            d,
            e,
            0.0,
        ];
        for poly in [&self.angle_to_pixeldist, &self.pixeldist_to_angle] {
            let mut padded = [0.0; MAX_COEFFICIENTS];
            padded[..poly.len()].copy_from_slice(poly);
            v.extend(padded);
        }
        v
    }
}
