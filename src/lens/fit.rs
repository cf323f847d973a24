//! The bridge from a real lens to the fast paths: the OpenCV standard model
//! fitted to the traced lens, so that Alg. 1, the warp and everything else can render it.
//!
//! A centred, rotationally symmetric lens focused at infinity maps the object direction θ to
//! the image height r(θ) on the film (the chief ray through the stop centre). OpenCV's model
//! with square pixels, the principal point at the sensor centre and no tangential terms maps
//! it to `f·t·(1 + k1 t² + k2 t⁴ + k3 t⁶)` pixels with t = tan θ — linear in
//! (f, f·k1, f·k2, f·k3), so the fit is an exact linear least-squares problem.

use crate::{Error, Result};
use glam::DMat4;
use glam::DVec4;

use super::{analyse, trace, Prescription};

/// A fitted camera and how well it fits.
#[derive(Debug, Clone, PartialEq)]
pub struct OpenCvFit {
    pub width: u32,
    pub height: u32,
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    /// k1 k2 p1 p2 k3.
    pub dist_coeffs: [f64; 5],
    /// Residual over the fitted field (pixels).
    pub max_residual_px: f64,
    pub rms_residual_px: f64,
    /// Field angle up to which chief rays were fitted (degrees): the sensor corner, or less
    /// where the lens vignettes the chief ray.
    pub max_field_deg: f64,
    pub samples: usize,
}

/// Fits the model for a sensor of `sensor_mm` (width, height) with `pixels` (width, height),
/// the film at the paraxial focus for an object `focus_m` metres in front of the front vertex
/// (infinite: focused at infinity), at `lambda_um`.
///
/// The chief ray of field angle θ passes the centre of the stop, so in object space it comes
/// from the centre of the entrance pupil: that is the camera centre, and OpenCV's normalized
/// coordinate is tan θ whatever the focus. Focusing only moves the film, which scales and
/// reshapes r(θ); the fit is the same linear problem.
pub fn fit_opencv(
    p: &Prescription,
    sensor_mm: (f64, f64),
    pixels: (u32, u32),
    focus_m: f64,
    lambda_um: f64,
) -> Result<OpenCvFit> {
    let pitch_x = sensor_mm.0 / pixels.0 as f64;
    let pitch_y = sensor_mm.1 / pixels.1 as f64;
    if !(pitch_x > 0.0 && pitch_y > 0.0) || ((pitch_x - pitch_y) / pitch_x).abs() > 1e-3 {
        return Err(Error::input(format!(
            "pixels must be square: {pitch_x:.6} × {pitch_y:.6} mm (sensor / pixels)"
        )));
    }
    let par = analyse(p, lambda_um);
    let (Some(efl), Some(bfl)) = (par.efl, par.bfl) else {
        return Err(Error::input(
            "the lens is afocal: it has no focal length to fit",
        ));
    };
    if efl <= 0.0 {
        return Err(Error::input(format!(
            "the lens diverges (EFL {efl:.3} mm): no real image to fit"
        )));
    }
    let image = if focus_m.is_infinite() {
        Some(bfl)
    } else if focus_m > 0.0 {
        super::focus(p, focus_m * 1000.0, lambda_um)
    } else {
        None
    };
    let Some(image) = image.filter(|d| d.is_finite() && *d > 0.0) else {
        return Err(Error::input(format!(
            "cannot focus at {focus_m} m: the image would not be behind the lens"
        )));
    };
    let film_z = par.rear_vertex_z + image;
    let half_diagonal = 0.5 * (sensor_mm.0.hypot(sensor_mm.1));
    // Sample field angles until the image height passes the sensor corner (or rays stop).
    let mut samples = Vec::new();
    let max_theta = (half_diagonal / efl).atan() * 1.6;
    let steps = 200;
    for k in 1..=steps {
        let theta = max_theta * k as f64 / steps as f64;
        let Some(ray) = trace::chief_ray(p, theta, lambda_um) else {
            break;
        };
        let Ok(exit) = trace::trace(p, ray, lambda_um) else {
            break;
        };
        let r_mm = trace::height_at(&exit, film_z).abs();
        samples.push((theta.tan(), r_mm / pitch_x));
        if r_mm > half_diagonal {
            break;
        }
    }
    if samples.len() < 8 {
        return Err(Error::input(format!(
            "only {} chief rays reach the film: the lens vignettes the field",
            samples.len()
        )));
    }
    // Normal equations of r = a t + b t³ + c t⁵ + d t⁷.
    let mut ata = DMat4::ZERO;
    let mut atb = DVec4::ZERO;
    for &(t, r) in &samples {
        let row = DVec4::new(t, t.powi(3), t.powi(5), t.powi(7));
        ata += DMat4::from_cols(row * row.x, row * row.y, row * row.z, row * row.w);
        atb += row * r;
    }
    if ata.determinant().abs() < 1e-300 {
        return Err(Error::input("the fit is singular"));
    }
    let c = ata.inverse() * atb;
    let f = c.x;
    let model = |t: f64| c.x * t + c.y * t.powi(3) + c.z * t.powi(5) + c.w * t.powi(7);
    let residuals: Vec<f64> = samples.iter().map(|&(t, r)| (model(t) - r).abs()).collect();
    let rms = (residuals.iter().map(|r| r * r).sum::<f64>() / residuals.len() as f64).sqrt();
    let max_t = samples.last().map(|s| s.0).unwrap_or(0.0);
    Ok(OpenCvFit {
        width: pixels.0,
        height: pixels.1,
        fx: f,
        fy: f,
        cx: (pixels.0 as f64 - 1.0) / 2.0,
        cy: (pixels.1 as f64 - 1.0) / 2.0,
        dist_coeffs: [c.y / f, c.z / f, 0.0, 0.0, c.w / f],
        max_residual_px: residuals.iter().copied().fold(0.0, f64::max),
        rms_residual_px: rms,
        max_field_deg: max_t.atan().to_degrees(),
        samples: samples.len(),
    })
}
