//! Scaramuzza's omnidirectional model as OCamCalib calibrates it (Scaramuzza, Martinelli and
//! Siegwart, "A Toolbox for Easily Calibrating Omnidirectional Cameras", IROS 2006), after
//! `ocam_functions.cpp`'s `cam2world` and `world2cam`.
//!
//! OCamCalib's frame puts rows first: its image point is (row, column) and its camera frame
//! (x along the rows, y along the columns, z out of the back of the lens). In OpenCV's frame
//! (x right, y down, z ahead) a ray (X, Y, Z) is OCamCalib's (Y, X, −Z). Its `cam2world` is the
//! definition (`poly` = its `pol`, ascending):
//!
//! ```text
//!   (x, y) = A⁻¹ (row − xc, col − yc),  A = [[c, d], [e, 1]]
//!   ray_ocam ∝ (x, y, poly(√(x² + y²)))
//! ```
//!
//! vklens's `cx` is OCamCalib's column centre `yc` and `cy` its row centre `xc`, so with fx =
//! fy = 1 the model's distorted point is m = (col − cx, row − cy). The forward map (`world2cam`)
//! finds the radius whose ray makes the point's angle exactly: the first radius (the smallest
//! positive root), on the branch where the angle still grows. OCamCalib's own `world2cam`
//! evaluates `inverse_poly`, a fit of that inverse a few hundredths of a pixel off
//! ([`Ocam::approximate_radius`]); `vklens bench models` measures it.
//!
//! The valid domain ends where the angle stops growing with the radius, and at the largest
//! radius any pixel of the calibrated image reaches (past it `poly` is an extrapolation).

use glam::{DMat2, DVec2, DVec3};

use super::jet::Scalar;
use super::poly;
use super::table::{off_axis, unit, RayModel};
use super::{check_finite, ModelError, ABSURD_MAGNITUDE};

/// Most coefficients of `poly` (the shaders hold 24; OCamCalib fits 5 by default).
pub const MAX_POLY: usize = 24;

/// Most coefficients of `inverse_poly` the shaders hold, for [`Ocam::with_fitted_inverse`]
/// (OCamCalib's fits have about 10 to 20).
pub const MAX_INVERSE_POLY: usize = 32;

/// Steps of the march that finds where the angle stops growing.
const FOLD_STEPS: usize = 4096;

/// Scaramuzza's model (OCamCalib).
#[derive(Debug, Clone, PartialEq)]
pub struct Ocam {
    /// `pol`: the radius → z polynomial of `cam2world`, ascending.
    pub poly: Vec<f64>,
    /// `invpol`: OCamCalib's fit of the inverse (angle → radius), ascending.
    pub inverse_poly: Vec<f64>,
    /// [c, d, e] of the affine term [[c, d], [e, 1]].
    pub cde: [f64; 3],
    /// Largest radius in the domain.
    r_max: f64,
    /// The angle off the axis of `r_max`'s ray: the domain's edge.
    angle_max: f64,
    /// `world2cam` by `inverse_poly`, as OCamCalib does, instead of the exact root
    /// ([`Ocam::with_fitted_inverse`]).
    fitted_inverse: bool,
}

impl Ocam {
    /// Validates the parameters; `max_radius` is the largest radius a pixel of the image
    /// reaches (the domain ends there, or earlier where the model folds).
    pub fn new(
        poly: Vec<f64>,
        inverse_poly: Vec<f64>,
        cde: [f64; 3],
        max_radius: f64,
    ) -> Result<Self, ModelError> {
        for (name, p, most) in [
            ("poly", &poly, MAX_POLY),
            ("inverse_poly", &inverse_poly, 64),
        ] {
            if p.len() > most {
                return Err(ModelError::Other(format!(
                    "`{name}` has {} coefficients; vklens reads at most {most}",
                    p.len()
                )));
            }
            for &c in p.iter() {
                check_finite(name, c, 1e300)?;
            }
        }
        for (name, v) in ["c", "d", "e"].into_iter().zip(cde) {
            check_finite(name, v, ABSURD_MAGNITUDE)?;
        }
        let [c, d, e] = cde;
        if !((c - d * e).abs() > 1e-12) {
            return Err(ModelError::Other(format!(
                "the affine term c, d, e = {c}, {d}, {e} is singular (c − d·e = 0)"
            )));
        }
        if !(poly.first().is_some_and(|&a0| a0 < 0.0)) {
            return Err(ModelError::Other(
                "`poly`'s first coefficient must be negative (OCamCalib's z points out of the back of the lens; its a0 is −focal length)".into(),
            ));
        }
        let mut lens = Ocam {
            poly,
            inverse_poly,
            cde,
            r_max: 0.0,
            angle_max: 0.0,
            fitted_inverse: false,
        };
        let hi = max_radius.max(1.0);
        lens.r_max = poly::increasing_until(|r| lens.angle_with_slope(r), hi, FOLD_STEPS);
        lens.angle_max = lens.angle_with_slope(lens.r_max).0;
        Ok(lens)
    }

    /// The angle off the optical axis of radius r's ray, atan2(r, −poly(r)), and its slope.
    fn angle_with_slope(&self, r: f64) -> (f64, f64) {
        let (z, dz) = poly::eval_with_slope(&self.poly, r);
        let q = r * r + z * z;
        // d/dr atan2(r, −z) = (−z + r z') / (r² + z²).
        (r.atan2(-z), (-z + r * dz) / q)
    }

    /// The same lens projecting (`world2cam`) by OCamCalib's own fit `inverse_poly`
    /// (`true`), or by the exact root of `poly` (`false`, the default). The fit is cheaper and
    /// a few hundredths of a pixel off; `vklens bench models` measures both.
    pub fn with_fitted_inverse(mut self, fitted: bool) -> Result<Self, ModelError> {
        if fitted && !(1..=MAX_INVERSE_POLY).contains(&self.inverse_poly.len()) {
            return Err(ModelError::Other(format!(
                "`fitted_inverse` needs OCamCalib's `inverse_poly` with 1 to {MAX_INVERSE_POLY} coefficients, got {}",
                self.inverse_poly.len()
            )));
        }
        self.fitted_inverse = fitted;
        Ok(self)
    }

    /// Whether `world2cam` is OCamCalib's fit ([`Ocam::with_fitted_inverse`]).
    pub fn fitted_inverse(&self) -> bool {
        self.fitted_inverse
    }

    fn affine(&self) -> DMat2 {
        let [c, d, e] = self.cde;
        DMat2::from_cols(DVec2::new(c, e), DVec2::new(d, 1.0))
    }

    /// OCamCalib's `world2cam` radius from `inverse_poly`, for a ray at `angle` off the axis:
    /// its θ is measured from the image plane (θ = angle − π/2).
    pub fn approximate_radius<T: Scalar>(&self, angle: T) -> T {
        poly::eval(&self.inverse_poly, angle - std::f64::consts::FRAC_PI_2)
    }

    /// The distorted point m of OCamCalib's (x, y).
    fn to_m<T: Scalar>(&self, x: T, y: T) -> [T; 2] {
        let [c, d, e] = self.cde;
        // (row − xc, col − yc) = A (x, y); m = (col − cx, row − cy).
        [x * e + y, x * c + y * d]
    }

    /// The exact radius of a ray at `angle` off the axis (the smallest positive root), inside
    /// the domain.
    pub fn radius_of(&self, angle: f64) -> Option<f64> {
        poly::solve_monotone(|r| self.angle_with_slope(r), angle, self.r_max)
    }
}

impl RayModel for Ocam {
    fn param_names(&self) -> Vec<&'static str> {
        vec!["c", "d", "e"]
    }

    fn params(&self) -> Vec<f64> {
        self.cde.to_vec()
    }

    fn project_generic<T: Scalar>(&self, p: [T; 3]) -> Option<[T; 2]> {
        // OCamCalib's frame: x along rows (OpenCV's y), y along columns (OpenCV's x).
        let (xo, yo) = (p[1], p[0]);
        let rho2 = xo * xo + yo * yo;
        if rho2.value() == 0.0 {
            return (p[2].value() > 0.0).then(|| [T::cst(0.0), T::cst(0.0)]);
        }
        let rho = rho2.sqrt();
        let angle = rho.atan2(p[2]);
        if self.fitted_inverse {
            // OCamCalib's world2cam: its θ is measured from the image plane.
            if !(angle.value() <= self.max_angle()) {
                return None;
            }
            let r = self.approximate_radius(angle);
            let s = r / rho;
            return Some(self.to_m(xo * s, yo * s));
        }
        // The radius whose ray makes this angle: its value by the solver, its derivatives by
        // the implicit function theorem (dr = dangle / angle'(r)).
        let r0 = poly::solve_monotone(|r| self.angle_with_slope(r), angle.value(), self.r_max)?;
        let (_, slope) = self.angle_with_slope(r0);
        let r = (angle - angle.value()) / slope + r0;
        let s = r / rho;
        Some(self.to_m(xo * s, yo * s))
    }

    fn contains_ray(&self, p: DVec3) -> bool {
        p.is_finite() && p != DVec3::ZERO && off_axis(p) <= self.angle_max
    }

    fn unproject(&self, m: DVec2) -> Option<DVec3> {
        if !m.is_finite() {
            return None;
        }
        // (row − xc, col − yc) = (m.y, m.x); (x, y) = A⁻¹ of it.
        let q = self.affine().inverse() * DVec2::new(m.y, m.x);
        let r = q.length();
        if !(r <= self.r_max) {
            return None;
        }
        let z = poly::eval(&self.poly, r);
        // OpenCV's frame: (ocam y, ocam x, −ocam z).
        unit(DVec3::new(q.y, q.x, -z))
    }

    fn max_angle(&self) -> f64 {
        self.angle_max
    }

    /// `glsl/include/models/ocam.glsl`: (r_max, max angle, c, d), (e, coefficients, fitted
    /// coefficients or 0, −), then `poly` (24, zero-padded), then `inverse_poly` where it is
    /// used (32, zero-padded).
    fn gpu_params(&self) -> Vec<f64> {
        let [c, d, e] = self.cde;
        let mut v = vec![
            self.r_max,
            self.max_angle(),
            c,
            d,
            e,
            self.poly.len() as f64,
            if self.fitted_inverse {
                self.inverse_poly.len() as f64
            } else {
                0.0
            },
            0.0,
        ];
        let mut padded = [0.0; MAX_POLY];
        padded[..self.poly.len()].copy_from_slice(&self.poly);
        v.extend(padded);
        if self.fitted_inverse {
            let mut padded = [0.0; MAX_INVERSE_POLY];
            padded[..self.inverse_poly.len()].copy_from_slice(&self.inverse_poly);
            v.extend(padded);
        }
        v
    }
}
