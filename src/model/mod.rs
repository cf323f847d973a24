//! Camera models as plain f64 math: no Vulkan in this module.
//!
//! # Pixel-centre convention
//!
//! vklens uses OpenCV's convention everywhere: **pixel (0, 0) has its centre at (0, 0)**, so an
//! image of width `w` covers `x ∈ [-0.5, w - 0.5]`. A pinhole camera maps a point (X, Y, Z) in
//! the OpenCV camera frame (x right, y down, z forward) to `u = fx·X/Z + cx`, `v = fy·Y/Z + cy`.
//! `glsl/include/camera_model.glsl` states the same convention word for word.
//!
//! # Layout (after COLMAP's `sensor/models.h`)
//!
//! * [`opencv`] — the OpenCV "standard" model with all 14 coefficients (Lambers et al., Eq. 1, and
//!   OpenCV's own `projectPoints`), its analytic Jacobian and three inverse methods.
//! * [`table`] — the table every other model slots into ([`table::RayModel`]: name and
//!   parameters, forward map written once for values and exact Jacobians, domain, inverse),
//!   and [`lens`], the enum over its models that a [`Camera`] holds: [`fisheye`], [`omni`],
//!   [`ucm`], [`eucm`], [`double_sphere`], [`fov`], [`equirect`], [`ftheta`], [`ocam`].
//! * [`fisheye`] — OpenCV's fisheye model (Kannala–Brandt k1..k4 and skew), defined past 90°
//!   off the axis, with its Jacobian, its inverse by Newton on θ and its cone-shaped domain.
//! * [`brown`] — the Durham radial-correction paper's Brown radial model for headset lenses (Eq. 1, Eq. 2).
//! * [`domain`] — the valid (invertible) domain of a distortion, computed once per camera.
//! * [`new_camera`] — the pinhole camera an undistorted image is drawn into, by OpenCV's
//!   `getOptimalNewCameraMatrix` and `fisheye.estimateNewCameraMatrixForUndistortRectify`.
//! * [`stereo`] — stereo rectification of a calibrated pair, by OpenCV's `stereoRectify` and
//!   `fisheye.stereoRectify`.
//! * [`projection`] — the Sec. 3.1 frustum as a Vulkan projection matrix.
//! * [`solve`] — the safeguarded 1D Newton both models' inverses start from.
//! * [`rolling_shutter`] — a rolling-shutter sensor's line times, the pose during its readout
//!   and the self-consistent projection of a world point through any of the models.
//! * [`CameraModel`] — the interface both models share: maps between the ideal (pinhole)
//!   pixel and the distorted pixel, in both directions, with an explicit "invalid".

pub mod brown;
pub mod camera;
pub mod division;
pub mod domain;
pub mod double_sphere;
pub mod equirect;
pub mod eucm;
pub mod fisheye;
pub mod fov;
pub mod ftheta;
pub mod jet;
pub mod lens;
pub mod new_camera;
pub mod ocam;
pub mod omni;
pub mod opencv;
pub mod overscan;
pub mod poly;
pub mod projection;
pub mod rolling_shutter;
pub mod samples;
pub mod solve;
pub mod stereo;
#[cfg(test)]
mod suite;
pub mod table;
#[cfg(test)]
mod tests;
pub mod thin_prism;
pub mod ucm;
pub mod warp;

use std::fmt;
use std::str::FromStr;

use glam::{DMat2, DVec2};

pub use brown::BrownRadial;
pub use camera::Camera;
pub use domain::ValidDomain;
pub use fisheye::Fisheye;
pub use lens::{Lens, ModelKind};
pub use opencv::{Intrinsics, OpenCvDistortion, Terms};
pub use projection::{vulkan_projection, Frustum};

/// Largest magnitude accepted for any parameter; beyond it a model is certainly a unit or
/// parsing mistake (and f32 on the GPU would lose all precision).
pub const ABSURD_MAGNITUDE: f64 = 1e7;
/// Smallest focal length accepted (pixels): below it one pixel spans more than a thousand
/// radians' worth of normalized coordinates, which no lens means (and f32 on the GPU cannot
/// hold the normalized coordinates).
pub const MIN_FOCAL_PX: f64 = 1e-3;
/// Largest image side accepted (pixels).
pub const MAX_IMAGE_SIDE: u32 = 1 << 16;

/// Why a set of model parameters was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ModelError {
    #[error("parameter `{name}` is {value}, which is not a finite number")]
    NotFinite { name: &'static str, value: f64 },
    #[error("parameter `{name}` must be > 0, got {value}")]
    NotPositive { name: &'static str, value: f64 },
    #[error("parameter `{name}` = {value:e} is too small to be meant (it must be at least {min})")]
    TooSmall {
        name: &'static str,
        value: f64,
        min: f64,
    },
    #[error("parameter `{name}` = {value} is absurdly large (|value| must be ≤ {limit})")]
    Absurd {
        name: &'static str,
        value: f64,
        limit: f64,
    },
    #[error("image size {width}×{height} is out of range (each side must be 1..={max})")]
    BadSize { width: u32, height: u32, max: u32 },
    #[error("OpenCV distortion vectors have 4, 5, 8, 12 or 14 coefficients, got {0}")]
    CoefficientCount(usize),
    #[error("{0}")]
    Other(String),
}

/// How to invert a distortion (distorted pixel → ideal pixel). Selectable by name:
/// `newton`, `heikkila`, `fixed-point:N`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum InverseMethod {
    /// Newton's method with the analytic Jacobian on every coefficient; converges to the
    /// machine precision of f64 inside the valid domain.
    Newton,
    /// The closed-form Taylor approximation of Lambers et al. Eq. 2 (Heikkilä), k1 k2 p1 p2 only;
    /// for the Brown model, the Durham radial-correction paper Eq. 2 (Mallon & Whelan).
    Heikkila,
    /// OpenCV's `undistortPoints` fixed-point iteration with this many iterations
    /// (OpenCV's default criteria are 5).
    FixedPoint(u32),
}

impl InverseMethod {
    /// Upper bound on fixed-point iterations accepted from users.
    pub const MAX_ITERATIONS: u32 = 10_000;
}

impl fmt::Display for InverseMethod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            InverseMethod::Newton => write!(f, "newton"),
            InverseMethod::Heikkila => write!(f, "heikkila"),
            InverseMethod::FixedPoint(n) => write!(f, "fixed-point:{n}"),
        }
    }
}

impl FromStr for InverseMethod {
    type Err = ModelError;
    fn from_str(s: &str) -> Result<Self, ModelError> {
        match s {
            "newton" => Ok(InverseMethod::Newton),
            "heikkila" => Ok(InverseMethod::Heikkila),
            _ => {
                let Some(n) = s.strip_prefix("fixed-point:") else {
                    return Err(ModelError::Other(format!(
                        "unknown inverse method `{s}` (expected newton, heikkila or fixed-point:N)"
                    )));
                };
                let n: u32 = n.parse().map_err(|_| {
                    ModelError::Other(format!(
                        "`{s}`: N in fixed-point:N must be a whole number of iterations"
                    ))
                })?;
                if n == 0 || n > Self::MAX_ITERATIONS {
                    return Err(ModelError::Other(format!(
                        "`{s}`: N must be between 1 and {}",
                        Self::MAX_ITERATIONS
                    )));
                }
                Ok(InverseMethod::FixedPoint(n))
            }
        }
    }
}

/// What every distortion model offers: maps between *ideal* pixels (the pinhole image a
/// graphics pipeline renders, same intrinsics) and *distorted* pixels (what the lens makes).
///
/// `None` always means "outside the valid domain": the map is not defined or not invertible
/// there. No method panics on any input, NaN included.
pub trait CameraModel {
    /// Short model name, e.g. `opencv` or `brown`.
    fn model_name(&self) -> &'static str;
    /// Image size in pixels.
    fn size(&self) -> (u32, u32);
    /// Forward model: ideal pixel → distorted pixel.
    fn distort_pixel(&self, ideal: DVec2) -> Option<DVec2>;
    /// Jacobian of [`CameraModel::distort_pixel`] (∂distorted/∂ideal).
    fn distort_jacobian_pixel(&self, ideal: DVec2) -> Option<DMat2>;
    /// Inverse model: distorted pixel → ideal pixel, or `None` outside the valid domain.
    fn undistort_pixel(&self, distorted: DVec2, method: InverseMethod) -> Option<DVec2>;
    /// Whether an ideal pixel lies in the valid (invertible) domain.
    fn ideal_in_domain(&self, ideal: DVec2) -> bool;
}

/// Checks a named parameter for finiteness and magnitude.
pub(crate) fn check_finite(name: &'static str, value: f64, limit: f64) -> Result<(), ModelError> {
    if !value.is_finite() {
        return Err(ModelError::NotFinite { name, value });
    }
    if value.abs() > limit {
        return Err(ModelError::Absurd { name, value, limit });
    }
    Ok(())
}

pub(crate) fn check_size(width: u32, height: u32) -> Result<(), ModelError> {
    if width == 0 || height == 0 || width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
        return Err(ModelError::BadSize {
            width,
            height,
            max: MAX_IMAGE_SIDE,
        });
    }
    Ok(())
}
