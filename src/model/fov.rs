//! The field-of-view model of Devernay and Faugeras, "Straight lines have to be straight"
//! (2001), as COLMAP (`FOV`), Kalibr (`pinhole-fov`) and DSO write it: on the pinhole-normalized
//! point x = (X/Z, Y/Z) with r_u = |x|,
//!
//! ```text
//!   r_d = atan(2 r_u tan(ω/2)) / ω,   m = x · r_d / r_u       (ω = 0: the pinhole)
//! ```
//!
//! It sees the front hemisphere (Z > 0, as COLMAP and Kalibr), and its inverse is closed
//! form: r_u = tan(r_d ω) / (2 tan(ω/2)), defined while r_d ω < π/2.
//!
//! Near the axis the quotient is its series (a/ω)(1 − a²r²/3 + a⁴r⁴/5), a = 2 tan(ω/2), whose
//! error there is far below rounding. COLMAP uses shorter series below r² = 1e-4 and ω² =
//! 1e-4, which differ from the exact model by up to about 1e-8 of a pixel's worth near the
//! axis; vklens evaluates the exact model everywhere.

use std::f64::consts::FRAC_PI_2;

use glam::{DVec2, DVec3};

use super::jet::Scalar;
use super::table::{unit, RayModel};
use super::{check_finite, ModelError};

/// Below this r_u the series is used (its first omitted term is a⁶r⁶/7 relative).
const SERIES_RADIUS: f64 = 1e-4;

/// The field-of-view model: one parameter, ω (radians).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fov {
    /// ω ∈ [0, π): the field of view of the ideal fisheye lens the model describes.
    pub omega: f64,
}

impl Fov {
    /// Validates ω ∈ [0, π).
    pub fn new(omega: f64) -> Result<Self, ModelError> {
        check_finite("omega", omega, std::f64::consts::PI)?;
        if !(0.0..std::f64::consts::PI).contains(&omega) {
            return Err(ModelError::Other(format!(
                "parameter `omega` = {omega} must be in [0, π) radians"
            )));
        }
        Ok(Fov { omega })
    }

    /// 2 tan(ω/2).
    fn a(&self) -> f64 {
        2.0 * (self.omega / 2.0).tan()
    }
}

impl RayModel for Fov {
    fn from_params(values: &[f64]) -> Result<Self, ModelError> {
        let [omega] = super::table::exactly(values)?;
        Fov::new(omega)
    }

    fn param_names(&self) -> Vec<&'static str> {
        vec!["omega"]
    }

    fn params(&self) -> Vec<f64> {
        vec![self.omega]
    }

    fn project_generic<T: Scalar>(&self, p: [T; 3]) -> Option<[T; 2]> {
        if !(p[2].value() > 0.0) {
            return None;
        }
        let (x, y) = (p[0] / p[2], p[1] / p[2]);
        if self.omega == 0.0 {
            return Some([x, y]);
        }
        let a = self.a();
        let r2 = x * x + y * y;
        let factor = if r2.value() < SERIES_RADIUS * SERIES_RADIUS {
            let a2 = a * a;
            (r2 * (r2 * (a2 * a2 / 5.0) - a2 / 3.0) + 1.0) * (a / self.omega)
        } else {
            let r = r2.sqrt();
            (r * a).atan() / (r * self.omega)
        };
        Some([x * factor, y * factor])
    }

    fn contains_ray(&self, p: DVec3) -> bool {
        p.is_finite() && p.z > 0.0
    }

    fn unproject(&self, m: DVec2) -> Option<DVec3> {
        if !m.is_finite() {
            return None;
        }
        if self.omega == 0.0 {
            return unit(DVec3::new(m.x, m.y, 1.0));
        }
        let rd = m.length();
        if rd == 0.0 {
            return Some(DVec3::Z);
        }
        let angle = rd * self.omega;
        if !(angle < FRAC_PI_2) {
            return None;
        }
        let ru = angle.tan() / self.a();
        unit(DVec3::new(m.x / rd * ru, m.y / rd * ru, 1.0))
    }

    fn max_angle(&self) -> f64 {
        FRAC_PI_2
    }

    /// `glsl/include/models/fov.glsl`: ω and 2 tan(ω/2).
    fn gpu_params(&self) -> Vec<f64> {
        vec![self.omega, self.a()]
    }
}
