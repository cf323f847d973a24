//! The lens a [`super::Camera`] holds: one value of an enum over the models of the table.
//!
//! OpenCV's standard model (and Brown's, its exact twin) is evaluated on the pinhole-normalized
//! point with its own inverses ([`super::opencv`]); every other model maps camera-frame rays
//! ([`super::table::RayModel`]), past 90° off the axis where it sees there. Adding a model is
//! one file with its `RayModel` implementation, one variant here, one arm in each `match` of
//! `for_each_ray_model!`, and its GLSL include (see `docs/how-it-works.md`).

use glam::{DMat2, DVec2, DVec3};

use super::division::Division;
use super::double_sphere::DoubleSphere;
use super::equirect::Equirectangular;
use super::eucm::Eucm;
use super::fisheye::Fisheye;
use super::fov::Fov;
use super::ftheta::FTheta;
use super::ocam::Ocam;
use super::omni::Omni;
use super::opencv::OpenCvDistortion;
use super::table::{self, RayModel};
use super::thin_prism::ThinPrismFisheye;
use super::ucm::Ucm;

/// Which model a lens is: the shaders' `VKL_MODEL` specialization constant is
/// [`ModelKind::gpu_id`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum ModelKind {
    /// OpenCV's standard model (k1..k6, p1 p2, s1..s4, τx τy), and Brown's radial model.
    #[default]
    Standard,
    /// OpenCV's fisheye model (Kannala–Brandt k1..k4).
    Fisheye,
    /// Mei's unified model with radial-tangential distortion.
    Omni,
    /// Basalt's unified camera model.
    Ucm,
    /// The enhanced unified camera model.
    Eucm,
    /// The double sphere model.
    DoubleSphere,
    /// Devernay and Faugeras' field-of-view model.
    Fov,
    /// The equirectangular panorama.
    Equirectangular,
    /// NVIDIA's f-theta model.
    FTheta,
    /// Scaramuzza's OCamCalib model.
    Ocam,
    /// Fitzgibbon's division model (COLMAP's).
    Division,
    /// COLMAP's thin-prism fisheyes (THIN_PRISM_FISHEYE, RAD_TAN_THIN_PRISM_FISHEYE).
    ThinPrismFisheye,
}

impl ModelKind {
    /// Every model, in `gpu_id` order.
    pub const ALL: [ModelKind; 12] = [
        ModelKind::Standard,
        ModelKind::Fisheye,
        ModelKind::Omni,
        ModelKind::Ucm,
        ModelKind::Eucm,
        ModelKind::DoubleSphere,
        ModelKind::Fov,
        ModelKind::Equirectangular,
        ModelKind::FTheta,
        ModelKind::Ocam,
        ModelKind::Division,
        ModelKind::ThinPrismFisheye,
    ];

    /// The value of the shaders' `VKL_MODEL` constant (`glsl/include/camera_model.glsl`).
    pub fn gpu_id(self) -> u32 {
        self as u32
    }

    /// The model's name in vklens camera files.
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Standard => "opencv",
            ModelKind::Fisheye => "opencv_fisheye",
            ModelKind::Omni => Omni::NAME,
            ModelKind::Ucm => Ucm::NAME,
            ModelKind::Eucm => Eucm::NAME,
            ModelKind::DoubleSphere => DoubleSphere::NAME,
            ModelKind::Fov => Fov::NAME,
            ModelKind::Equirectangular => Equirectangular::NAME,
            ModelKind::FTheta => FTheta::NAME,
            ModelKind::Ocam => Ocam::NAME,
            ModelKind::Division => Division::NAME,
            ModelKind::ThinPrismFisheye => ThinPrismFisheye::NAME,
        }
    }

    /// Whether the camera's fx fy are a focal length a pinhole image can share (the
    /// undistorted image's default): not for f-theta and OCamCalib (their polynomials carry
    /// the scale) nor for the equirectangular panorama (fx fy are pixels per radian).
    pub fn has_focal_length(self) -> bool {
        !matches!(
            self,
            ModelKind::FTheta | ModelKind::Ocam | ModelKind::Equirectangular
        )
    }

    /// Whether the model maps camera-frame rays (every model but the standard one): its
    /// inverse gives rays, and it may see past 90° off the axis.
    pub fn is_ray_model(self) -> bool {
        self != ModelKind::Standard
    }
}

/// The lens model of a camera and its parameters.
#[derive(Debug, Clone, PartialEq)]
pub enum Lens {
    /// OpenCV's standard model.
    Standard {
        /// The 14 coefficients.
        distortion: OpenCvDistortion,
        /// How many coefficients the camera was given (4, 5, 8, 12 or 14).
        coeff_count: usize,
        /// `Some((c1, c2))` for a Brown radial lens (the Durham radial-correction paper).
        brown: Option<(f64, f64)>,
        /// A bound on the ideal normalized radius the file gives (Basalt's `rpmax`): the
        /// valid domain ends there, or earlier where the lens folds.
        max_radius: Option<f64>,
    },
    /// OpenCV's fisheye model.
    Fisheye(Fisheye),
    /// Mei's unified model with radial-tangential distortion.
    Omni(Omni),
    /// Basalt's unified camera model.
    Ucm(Ucm),
    /// The enhanced unified camera model.
    Eucm(Eucm),
    /// The double sphere model.
    DoubleSphere(DoubleSphere),
    /// The field-of-view model.
    Fov(Fov),
    /// The equirectangular panorama.
    Equirectangular(Equirectangular),
    /// NVIDIA's f-theta model.
    FTheta(FTheta),
    /// Scaramuzza's OCamCalib model.
    Ocam(Ocam),
    /// Fitzgibbon's division model.
    Division(Division),
    /// COLMAP's thin-prism fisheyes.
    ThinPrismFisheye(ThinPrismFisheye),
}

/// Runs `$body` with `$m` bound to the ray model inside `$lens`, or `$standard` for the
/// standard model: the one place that lists the ray models' variants.
macro_rules! for_each_ray_model {
    ($lens:expr, $m:ident => $body:expr, standard => $standard:expr) => {
        match $lens {
            Lens::Standard { .. } => $standard,
            Lens::Fisheye($m) => $body,
            Lens::Omni($m) => $body,
            Lens::Ucm($m) => $body,
            Lens::Eucm($m) => $body,
            Lens::DoubleSphere($m) => $body,
            Lens::Fov($m) => $body,
            Lens::Equirectangular($m) => $body,
            Lens::FTheta($m) => $body,
            Lens::Ocam($m) => $body,
            Lens::Division($m) => $body,
            Lens::ThinPrismFisheye($m) => $body,
        }
    };
}

impl Lens {
    /// Which model this is.
    pub fn kind(&self) -> ModelKind {
        match self {
            Lens::Standard { .. } => ModelKind::Standard,
            Lens::Fisheye(_) => ModelKind::Fisheye,
            Lens::Omni(_) => ModelKind::Omni,
            Lens::Ucm(_) => ModelKind::Ucm,
            Lens::Eucm(_) => ModelKind::Eucm,
            Lens::DoubleSphere(_) => ModelKind::DoubleSphere,
            Lens::Fov(_) => ModelKind::Fov,
            Lens::Equirectangular(_) => ModelKind::Equirectangular,
            Lens::FTheta(_) => ModelKind::FTheta,
            Lens::Ocam(_) => ModelKind::Ocam,
            Lens::Division(_) => ModelKind::Division,
            Lens::ThinPrismFisheye(_) => ModelKind::ThinPrismFisheye,
        }
    }

    /// The model's own parameter names and values (not fx fy cx cy), as camera files write
    /// them; the standard model's are its 14 coefficients.
    pub fn params(&self) -> Vec<(&'static str, f64)> {
        if let Lens::Standard { distortion, .. } = self {
            return super::opencv::COEFFICIENT_NAMES
                .into_iter()
                .zip(distortion.to_coeffs())
                .collect();
        }
        for_each_ray_model!(self, m => m.param_names().into_iter().zip(m.params()).collect(),
            standard => Vec::new())
    }

    /// A ray model's forward map with its domain check (`None` for the standard model).
    pub fn project_ray(&self, p: DVec3) -> Option<DVec2> {
        for_each_ray_model!(self, m => table::project(m, p), standard => None)
    }

    /// A ray model's forward map with its exact Jacobian ∂m/∂p.
    pub fn project_ray_jacobian(&self, p: DVec3) -> Option<(DVec2, [DVec3; 2])> {
        for_each_ray_model!(self, m => table::project_jacobian(m, p), standard => None)
    }

    /// A ray model's forward map on the pinhole-normalized point, with its Jacobian.
    pub fn ray_distort_normalized(&self, x: DVec2) -> Option<(DVec2, DMat2)> {
        for_each_ray_model!(self, m => table::distort_normalized(m, x), standard => None)
    }

    /// A ray model's inverse to the unit ray.
    pub fn unproject_ray(&self, m: DVec2) -> Option<DVec3> {
        for_each_ray_model!(self, l => l.unproject(m), standard => None)
    }

    /// A ray model's `model[16]` block for the shaders (all zero for the standard model).
    pub fn gpu_params(&self) -> [f64; table::GPU_PARAMS] {
        let v = for_each_ray_model!(self, m => m.gpu_params(), standard => Vec::new());
        let mut out = [0.0; table::GPU_PARAMS];
        for (slot, x) in out.iter_mut().zip(v) {
            *slot = x;
        }
        out
    }

    /// The largest angle off the axis the domain reaches (π/2 at most for the standard model).
    pub fn max_angle(&self) -> f64 {
        for_each_ray_model!(self, m => m.max_angle(), standard => std::f64::consts::FRAC_PI_2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shaders number the models as `ModelKind` does: each `#define VKL_MODEL_<NAME> <id>u`
    /// of `glsl/include/camera_model.glsl` against `gpu_id`.
    #[test]
    fn the_shaders_number_the_models_as_the_host_does() {
        let glsl = include_str!("../../glsl/include/camera_model.glsl");
        for (i, kind) in ModelKind::ALL.into_iter().enumerate() {
            assert_eq!(kind.gpu_id(), i as u32);
            let name = match kind {
                ModelKind::Standard => "OPENCV".to_string(),
                ModelKind::Fisheye => "FISHEYE".to_string(),
                k => k.name().to_ascii_uppercase(),
            };
            let define = format!("#define VKL_MODEL_{name} {i}u");
            assert!(glsl.contains(&define), "camera_model.glsl lacks `{define}`");
            // One include per model of the table (the fisheye's is the standard stages').
            if kind.is_ray_model() && kind != ModelKind::Fisheye {
                let include = format!("#include \"models/{}.glsl\"", kind.name());
                assert!(
                    glsl.contains(&include),
                    "camera_model.glsl lacks `{include}`"
                );
            }
        }
    }
}

#[cfg(test)]
mod union_tests {
    use crate::model::{ModelKind, Terms};

    /// A shader serving several cameras (a warp's channels) folds their terms from the
    /// default: the union must keep the ray model, or the shader evaluates the standard one.
    #[test]
    fn the_union_of_terms_keeps_the_ray_model() {
        let fisheye = Terms {
            radial: true,
            model: ModelKind::Fisheye,
            ..Terms::default()
        };
        assert_eq!(Terms::default().union(fisheye).model, ModelKind::Fisheye);
        assert_eq!(fisheye.union(Terms::default()).model, ModelKind::Fisheye);
    }
}
