//! COLMAP's fisheye models with a distortion on the plane of the angle-scaled point:
//! `THIN_PRISM_FISHEYE` (Weng et al.'s thin prism on the equidistant projection) and
//! `RAD_TAN_THIN_PRISM_FISHEYE` (Meta's Project Aria "Fisheye624"). With θ = atan2(r, z) and
//! q = θ (x, y)/r the equidistant point:
//!
//! ```text
//!   THIN_PRISM_FISHEYE:          s = |q|²,  X = q (1 + k1 s + k2 s² + k3 s³ + k4 s⁴)
//!                                m = X + tangential(q) + thin prism(q)
//!   RAD_TAN_THIN_PRISM_FISHEYE:  s = |q|²,  X = q (1 + k0 s + … + k5 s⁶)
//!                                m = X + tangential(X) + thin prism(X)
//!   tangential(v) = (2 p1 v_x v_y + p2 (|v|² + 2 v_x²), p1 (|v|² + 2 v_y²) + 2 p2 v_x v_y)
//!   thin prism(v) = (s1 |v|² + s2 |v|⁴, s3 |v|² + s4 |v|⁴)          (OpenCV's p and s names)
//! ```
//!
//! COLMAP's own parameter names map to these: THIN_PRISM_FISHEYE's p1 p2, sx1 sy1 are p1 p2,
//! s1 s3; RAD_TAN_THIN_PRISM_FISHEYE's p0 p1 are p2 p1 and s0..s3 are s1..s4 (its tangential
//! x term is 2 p1 X Y + p0 (r² + 2X²)). Like COLMAP, the models see the front hemisphere
//! (z > 0). The inverse solves the plane's distortion by damped Newton inside its valid domain
//! (found once, as for OpenCV's model), then lifts q back to the ray.

use std::f64::consts::FRAC_PI_2;

use glam::{DMat2, DVec2, DVec3};

use super::domain::ValidDomain;
use super::jet::{Jet, Scalar};
use super::table::{unit, RayModel};
use super::{check_finite, ModelError, ABSURD_MAGNITUDE};

/// Below this r/z the equidistant factor θ/r is its series 1 − ρ²/3 (over z).
const SMALL: f64 = 1e-8;

/// A fisheye whose equidistant point is distorted on its plane (COLMAP's two thin-prism
/// fisheyes).
#[derive(Debug, Clone, PartialEq)]
pub struct ThinPrismFisheye {
    /// Radial coefficients of s, s², … (s = |q|²): 4 for THIN_PRISM_FISHEYE, 6 for
    /// RAD_TAN_THIN_PRISM_FISHEYE.
    pub radial: Vec<f64>,
    /// p1 p2 in OpenCV's sense.
    pub p: [f64; 2],
    /// s1 s2 s3 s4 in OpenCV's sense.
    pub s: [f64; 4],
    /// Tangential and thin prism on the radially distorted point (Fisheye624) rather than on q.
    pub radial_first: bool,
    domain: ValidDomain,
}

impl ThinPrismFisheye {
    /// Validates the coefficients and finds the plane's valid domain.
    pub fn new(
        radial: Vec<f64>,
        p: [f64; 2],
        s: [f64; 4],
        radial_first: bool,
    ) -> Result<Self, ModelError> {
        if radial.len() > 6 {
            return Err(ModelError::Other(format!(
                "{} radial coefficients; these models have at most 6",
                radial.len()
            )));
        }
        for (i, &c) in radial.iter().enumerate() {
            let name = ["k1", "k2", "k3", "k4", "k5", "k6"][i];
            check_finite(name, c, ABSURD_MAGNITUDE)?;
        }
        for (name, c) in ["p1", "p2"].into_iter().zip(p) {
            check_finite(name, c, ABSURD_MAGNITUDE)?;
        }
        for (name, c) in ["s1", "s2", "s3", "s4"].into_iter().zip(s) {
            check_finite(name, c, ABSURD_MAGNITUDE)?;
        }
        let mut lens = ThinPrismFisheye {
            radial,
            p,
            s,
            radial_first,
            domain: ValidDomain::unbounded(),
        };
        let probe = lens.clone();
        // The plane's domain, as the standard model's; θ = |q| < π/2 bounds it too.
        lens.domain = ValidDomain::compute(
            |q| probe.plane(q).map(|(m, _)| m),
            |q, dir| {
                q.length() < FRAC_PI_2
                    && probe
                        .plane(q)
                        .is_some_and(|(m, j)| j.determinant() > 0.0 && m.dot(j * dir) > 0.0)
            },
        );
        Ok(lens)
    }

    /// The plane's distortion, generic.
    fn distort<T: Scalar>(&self, q: [T; 2]) -> [T; 2] {
        let s2 = q[0] * q[0] + q[1] * q[1];
        let mut factor = T::cst(0.0);
        for &c in self.radial.iter().rev() {
            factor = (factor + c) * s2;
        }
        let x = [q[0] * (factor + 1.0), q[1] * (factor + 1.0)];
        let v = if self.radial_first { x } else { q };
        let r2 = v[0] * v[0] + v[1] * v[1];
        let [p1, p2] = self.p;
        let [s1, s2c, s3, s4] = self.s;
        let two_xy = v[0] * v[1] * 2.0;
        [
            x[0] + two_xy * p1 + (r2 + v[0] * v[0] * 2.0) * p2 + r2 * s1 + r2 * r2 * s2c,
            x[1] + (r2 + v[1] * v[1] * 2.0) * p1 + two_xy * p2 + r2 * s3 + r2 * r2 * s4,
        ]
    }

    /// The plane's distortion and its Jacobian.
    fn plane(&self, q: DVec2) -> Option<(DVec2, DMat2)> {
        let [u, v] = self.distort([Jet::<2>::var(q.x, 0), Jet::var(q.y, 1)]);
        let m = DVec2::new(u.v, v.v);
        let j = DMat2::from_cols(DVec2::new(u.d[0], v.d[0]), DVec2::new(u.d[1], v.d[1]));
        (m.is_finite() && j.is_finite()).then_some((m, j))
    }

    /// The plane's valid domain (its table goes to the shaders).
    pub fn domain(&self) -> &ValidDomain {
        &self.domain
    }

    /// The plane's inverse: q with distort(q) = m inside the domain, by the 2D Newton the
    /// standard model uses (`super::solve::invert_2d`), started where the radial factor alone
    /// would put it (one fixed-point step from the target: the tangential and prism terms are
    /// small beside it).
    fn invert(&self, target: DVec2) -> Option<DVec2> {
        if target != DVec2::ZERO && !self.domain.contains_distorted(target) {
            return None;
        }
        let s = target.length_squared();
        let factor = self.radial.iter().rev().fold(0.0, |f, &c| (f + c) * s);
        let start = target / (1.0 + factor);
        let start = if start.is_finite() { start } else { target };
        super::solve::invert_2d(
            |q| self.plane(q),
            |q| self.domain.contains_ideal(q),
            start,
            target,
        )
    }
}

impl RayModel for ThinPrismFisheye {
    fn param_names(&self) -> Vec<&'static str> {
        let mut v: Vec<&'static str> =
            ["k1", "k2", "k3", "k4", "k5", "k6"][..self.radial.len()].to_vec();
        v.extend(["p1", "p2", "s1", "s2", "s3", "s4"]);
        v
    }

    fn params(&self) -> Vec<f64> {
        let mut v = self.radial.clone();
        v.extend(self.p);
        v.extend(self.s);
        v
    }

    fn project_generic<T: Scalar>(&self, p: [T; 3]) -> Option<[T; 2]> {
        let z = p[2].value();
        if !(z > 0.0) {
            return None;
        }
        let r2 = p[0] * p[0] + p[1] * p[1];
        let scale = if r2.value() < (SMALL * z) * (SMALL * z) {
            // θ/r = (1 − ρ²/3 + …)/z with ρ = r/z.
            (T::cst(1.0) - r2 / (p[2] * p[2]) / 3.0) / p[2]
        } else {
            let r = r2.sqrt();
            r.atan2(p[2]) / r
        };
        Some(self.distort([p[0] * scale, p[1] * scale]))
    }

    fn contains_ray(&self, p: DVec3) -> bool {
        if !p.is_finite() || !(p.z > 0.0) {
            return false;
        }
        let r = p.x.hypot(p.y);
        let theta = r.atan2(p.z);
        let q = if r > 0.0 {
            DVec2::new(p.x, p.y) * (theta / r)
        } else {
            DVec2::ZERO
        };
        self.domain.contains_ideal(q)
    }

    fn unproject(&self, m: DVec2) -> Option<DVec3> {
        if !m.is_finite() {
            return None;
        }
        let q = self.invert(m)?;
        let theta = q.length();
        if theta == 0.0 {
            return Some(DVec3::Z);
        }
        if !(theta < FRAC_PI_2) {
            return None;
        }
        let (s, c) = theta.sin_cos();
        let ray = unit(DVec3::new(q.x / theta * s, q.y / theta * s, c))?;
        self.contains_ray(ray).then_some(ray)
    }

    fn max_angle(&self) -> f64 {
        let reach = (0..ValidDomain::SAMPLES)
            .map(|i| {
                self.domain
                    .ideal_radius(std::f64::consts::TAU * i as f64 / ValidDomain::SAMPLES as f64)
            })
            .fold(0.0, f64::max);
        reach.min(FRAC_PI_2)
    }

    /// `glsl/include/models/thin_prism_fisheye.glsl`: (flag radial-first, count, −, −), the radial
    /// coefficients (6), p1 p2, s1..s4. The plane's domain table goes where the standard
    /// model's does.
    fn gpu_params(&self) -> Vec<f64> {
        let mut v = vec![
            f64::from(u8::from(self.radial_first)),
            self.radial.len() as f64,
            0.0,
            0.0,
        ];
        let mut r = [0.0; 6];
        r[..self.radial.len()].copy_from_slice(&self.radial);
        v.extend(r);
        v.extend(self.p);
        v.extend(self.s);
        v
    }
}
