//! The OpenCV "standard" camera model with all 14 distortion coefficients.
//!
//! Forward model, exactly as `cv2.projectPoints` computes it (Lambers et al. Eq. 1 extended to
//! OpenCV's full model). For an ideal normalized point x = (x, y) = (X/Z, Y/Z), s = r² = x² + y²:
//!
//! ```text
//!   R(s)  = (1 + k1 s + k2 s² + k3 s³) / (1 + k4 s + k5 s² + k6 s³)      radial, rational
//!   x'    = x R + 2 p1 x y + p2 (s + 2x²) + s1 s + s2 s²                tangential, thin prism
//!   y'    = y R + p1 (s + 2y²) + 2 p2 x y + s3 s + s4 s²
//!   (x'', y'') = tilt(x', y')                                          tilted sensor (τx, τy)
//!   u = fx x'' + cx,  v = fy y'' + cy
//! ```
//!
//! The tilt is OpenCV's `computeTiltProjectionMatrix`: a homography that maps the origin to
//! itself. Every inverse first removes it exactly (it is a homography), then inverts the
//! pre-tilt distortion.
//!
//! Pixel-centre convention: OpenCV's, pixel (0, 0) has its centre at (0, 0) (see [`super`]).

use glam::{DMat2, DMat3, DVec2};

use super::lens::ModelKind;
use super::{check_finite, ModelError, ABSURD_MAGNITUDE};

/// Names of the 14 coefficients in OpenCV's order (`distCoeffs`).
pub const COEFFICIENT_NAMES: [&str; 14] = [
    "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6", "s1", "s2", "s3", "s4", "tau_x", "tau_y",
];

/// The constants of the 2D Newton every plane distortion shares (`super::solve::invert_2d`).
pub use super::solve::{
    CONTINUATION_STEPS, NEWTON_ACCEPT_RESIDUAL, NEWTON_MAX_HALVINGS, NEWTON_MAX_ITERATIONS,
};

/// Pinhole intrinsics in pixels (no skew).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intrinsics {
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
}

impl Intrinsics {
    /// Ideal normalized point → ideal (pinhole) pixel.
    pub fn to_pixel(&self, x: DVec2) -> DVec2 {
        DVec2::new(self.fx * x.x + self.cx, self.fy * x.y + self.cy)
    }
    /// Pixel → normalized point.
    pub fn to_normalized(&self, p: DVec2) -> DVec2 {
        DVec2::new((p.x - self.cx) / self.fx, (p.y - self.cy) / self.fy)
    }
}

/// OpenCV's 14 distortion coefficients, by name. Missing ones (shorter vectors) are zero.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OpenCvDistortion {
    pub k1: f64,
    pub k2: f64,
    pub p1: f64,
    pub p2: f64,
    pub k3: f64,
    pub k4: f64,
    pub k5: f64,
    pub k6: f64,
    pub s1: f64,
    pub s2: f64,
    pub s3: f64,
    pub s4: f64,
    pub tau_x: f64,
    pub tau_y: f64,
}

/// Which groups of terms a distortion uses; zero groups are compiled out of the shaders
/// (specialization constants) and skipped by the planner.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Terms {
    /// k1 k2 k3 (numerator of R).
    pub radial: bool,
    /// k4 k5 k6 (denominator of R).
    pub rational: bool,
    /// p1 p2.
    pub tangential: bool,
    /// s1..s4.
    pub prism: bool,
    /// tau_x tau_y.
    pub tilt: bool,
    /// Which model the shaders evaluate (for OpenCV's fisheye, `radial` says whether any of
    /// its k1..k4 is non-zero; the other models of the table compile in whole).
    pub model: ModelKind,
}

impl Terms {
    /// The groups used by either (one shader serving several cameras).
    pub fn union(self, other: Terms) -> Terms {
        Terms {
            radial: self.radial || other.radial,
            rational: self.rational || other.rational,
            tangential: self.tangential || other.tangential,
            prism: self.prism || other.prism,
            tilt: self.tilt || other.tilt,
            // One shader evaluates one model, and callers share a shader only between
            // cameras of one model: the union keeps the model that is not the default
            // (a fold starts from `Terms::default()`).
            model: if self.model == ModelKind::Standard {
                other.model
            } else {
                self.model
            },
        }
    }

    /// Whether the model maps camera-frame rays (every model but the standard one).
    pub fn is_ray_model(self) -> bool {
        self.model.is_ray_model()
    }
}

impl OpenCvDistortion {
    /// From an OpenCV coefficient vector of length 4, 5, 8, 12 or 14 (OpenCV's own rule).
    pub fn from_coeffs(c: &[f64]) -> Result<Self, ModelError> {
        if ![4, 5, 8, 12, 14].contains(&c.len()) {
            return Err(ModelError::CoefficientCount(c.len()));
        }
        let mut all = [0.0; 14];
        all[..c.len()].copy_from_slice(c);
        for (name, &v) in COEFFICIENT_NAMES.iter().zip(all.iter()) {
            check_finite(name, v, ABSURD_MAGNITUDE)?;
        }
        // A tilt of ±90° puts the sensor edge-on; OpenCV's matrix degenerates there.
        for (name, v) in [("tau_x", all[12]), ("tau_y", all[13])] {
            if v.abs() >= 1.5 {
                return Err(ModelError::Absurd {
                    name,
                    value: v,
                    limit: 1.5,
                });
            }
        }
        Ok(Self::from_array(all))
    }

    fn from_array(a: [f64; 14]) -> Self {
        OpenCvDistortion {
            k1: a[0],
            k2: a[1],
            p1: a[2],
            p2: a[3],
            k3: a[4],
            k4: a[5],
            k5: a[6],
            k6: a[7],
            s1: a[8],
            s2: a[9],
            s3: a[10],
            s4: a[11],
            tau_x: a[12],
            tau_y: a[13],
        }
    }

    /// All 14 coefficients in OpenCV's order.
    pub fn to_coeffs(&self) -> [f64; 14] {
        [
            self.k1, self.k2, self.p1, self.p2, self.k3, self.k4, self.k5, self.k6, self.s1,
            self.s2, self.s3, self.s4, self.tau_x, self.tau_y,
        ]
    }

    /// Which term groups are non-zero.
    pub fn terms(&self) -> Terms {
        Terms {
            radial: self.k1 != 0.0 || self.k2 != 0.0 || self.k3 != 0.0,
            rational: self.k4 != 0.0 || self.k5 != 0.0 || self.k6 != 0.0,
            tangential: self.p1 != 0.0 || self.p2 != 0.0,
            prism: self.s1 != 0.0 || self.s2 != 0.0 || self.s3 != 0.0 || self.s4 != 0.0,
            tilt: self.tau_x != 0.0 || self.tau_y != 0.0,
            model: ModelKind::Standard,
        }
    }

    /// OpenCV's `computeTiltProjectionMatrix(tauX, tauY)`.
    pub fn tilt_matrix(&self) -> DMat3 {
        let (stx, ctx) = self.tau_x.sin_cos();
        let (sty, cty) = self.tau_y.sin_cos();
        // Row-major as in OpenCV, then transposed into glam's column-major.
        let rot_x =
            DMat3::from_cols_array(&[1.0, 0.0, 0.0, 0.0, ctx, stx, 0.0, -stx, ctx]).transpose();
        let rot_y =
            DMat3::from_cols_array(&[cty, 0.0, -sty, 0.0, 1.0, 0.0, sty, 0.0, cty]).transpose();
        let rot_xy = rot_y * rot_x;
        let r22 = rot_xy.col(2).z;
        let r02 = rot_xy.col(2).x;
        let r12 = rot_xy.col(2).y;
        let proj_z =
            DMat3::from_cols_array(&[r22, 0.0, -r02, 0.0, r22, -r12, 0.0, 0.0, 1.0]).transpose();
        proj_z * rot_xy
    }

    /// Radial numerator and denominator and their derivatives in s = r².
    #[inline]
    pub(super) fn radial(&self, s: f64) -> (f64, f64, f64, f64) {
        let num = 1.0 + s * (self.k1 + s * (self.k2 + s * self.k3));
        let den = 1.0 + s * (self.k4 + s * (self.k5 + s * self.k6));
        let dnum = self.k1 + s * (2.0 * self.k2 + 3.0 * s * self.k3);
        let dden = self.k4 + s * (2.0 * self.k5 + 3.0 * s * self.k6);
        (num, den, dnum, dden)
    }

    /// Pre-tilt distortion (x', y') of an ideal normalized point, with its Jacobian.
    /// `None` where the rational denominator is zero or the result is not finite.
    pub fn distort_pre_tilt(&self, x: DVec2) -> Option<(DVec2, DMat2)> {
        let s = x.length_squared();
        let (num, den, dnum, dden) = self.radial(s);
        if den == 0.0 {
            return None;
        }
        let r = num / den;
        let dr_ds = (dnum * den - num * dden) / (den * den);
        let (px, py) = (x.x, x.y);
        let out = DVec2::new(
            px * r
                + 2.0 * self.p1 * px * py
                + self.p2 * (s + 2.0 * px * px)
                + self.s1 * s
                + self.s2 * s * s,
            py * r
                + self.p1 * (s + 2.0 * py * py)
                + 2.0 * self.p2 * px * py
                + self.s3 * s
                + self.s4 * s * s,
        );
        // ∂/∂x of x R(s) is R + x · R'(s) · 2x, and so on; prism terms are c·s + d·s².
        let prism_x = self.s1 + 2.0 * self.s2 * s;
        let prism_y = self.s3 + 2.0 * self.s4 * s;
        let j00 = r
            + 2.0 * px * px * dr_ds
            + 2.0 * self.p1 * py
            + 6.0 * self.p2 * px
            + 2.0 * px * prism_x;
        let j01 =
            2.0 * px * py * dr_ds + 2.0 * self.p1 * px + 2.0 * self.p2 * py + 2.0 * py * prism_x;
        let j10 =
            2.0 * px * py * dr_ds + 2.0 * self.p1 * px + 2.0 * self.p2 * py + 2.0 * px * prism_y;
        let j11 = r
            + 2.0 * py * py * dr_ds
            + 6.0 * self.p1 * py
            + 2.0 * self.p2 * px
            + 2.0 * py * prism_y;
        let jac = DMat2::from_cols(DVec2::new(j00, j10), DVec2::new(j01, j11));
        (out.is_finite() && jac.is_finite()).then_some((out, jac))
    }
}

/// Lambers et al. Eq. 2: Heikkilä's closed-form approximate inverse, k1 k2 p1 p2 only, applied
/// to the pre-tilt distorted point. `None` where its denominator vanishes.
pub fn heikkila(d: &OpenCvDistortion, y: DVec2) -> Option<DVec2> {
    let (s, t) = (y.x, y.y);
    let r2 = s * s + t * t;
    let d1 = d.k1 * r2 + d.k2 * r2 * r2;
    let denom = 4.0 * d.k1 * r2 + 6.0 * d.k2 * r2 * r2 + 8.0 * d.p1 * t + 8.0 * d.p2 * s + 1.0;
    if !(denom.abs() > 1e-12) {
        return None;
    }
    let d2 = 1.0 / denom;
    let x = s - d2 * (d1 * s + 2.0 * d.p1 * s * t + d.p2 * (r2 + 2.0 * s * s));
    let yy = t - d2 * (d1 * t + d.p1 * (r2 + 2.0 * t * t) + 2.0 * d.p2 * s * t);
    Some(DVec2::new(x, yy))
}

/// OpenCV's `undistortPoints` iteration (cvUndistortPointsInternal, COUNT criterion), on the
/// pre-tilt distorted point: x ← (x₀ − Δ(x)) / R(x). Gives up (None) where OpenCV would bail
/// out on a negative radial factor.
pub fn fixed_point(d: &OpenCvDistortion, y0: DVec2, iterations: u32) -> Option<DVec2> {
    let mut x = y0;
    for _ in 0..iterations {
        let r2 = x.length_squared();
        let icdist = (1.0 + ((d.k6 * r2 + d.k5) * r2 + d.k4) * r2)
            / (1.0 + ((d.k3 * r2 + d.k2) * r2 + d.k1) * r2);
        if !(icdist >= 0.0) {
            return None;
        }
        let dx =
            2.0 * d.p1 * x.x * x.y + d.p2 * (r2 + 2.0 * x.x * x.x) + d.s1 * r2 + d.s2 * r2 * r2;
        let dy =
            d.p1 * (r2 + 2.0 * x.y * x.y) + 2.0 * d.p2 * x.x * x.y + d.s3 * r2 + d.s4 * r2 * r2;
        x = DVec2::new((y0.x - dx) * icdist, (y0.y - dy) * icdist);
    }
    Some(x)
}

/// Local invertibility when walking outward along `dir` at `x`: the rational denominator and
/// the radial factor stay positive, the Jacobian determinant is positive, and the distorted
/// point still moves away from the centre (the distorted radius keeps growing).
pub(super) fn locally_invertible(d: &OpenCvDistortion, x: DVec2, dir: DVec2) -> bool {
    let s = x.length_squared();
    let (num, den, _, _) = d.radial(s);
    if !(den > 0.0 && num > 0.0) {
        return false;
    }
    let Some((y, jac)) = d.distort_pre_tilt(x) else {
        return false;
    };
    jac.determinant() > 0.0 && y.dot(jac * dir) > 0.0
}
