//! The lens a [`super::Camera`] holds: one value of an enum over the models of the table.
//!
//! OpenCV's standard model (and Brown's, its exact twin) is evaluated on the pinhole-normalized
//! point with its own inverses ([`super::opencv`]); every other model maps camera-frame rays
//! ([`super::table::RayModel`]), past 90° off the axis where it sees there. The models are the
//! rows of `list.rs`; adding one: `docs/how-it-works.md#adding-a-model`.

use glam::{DMat2, DVec2, DVec3};

use super::opencv::OpenCvDistortion;
use super::table::{self, RayModel};
use super::ModelError;

/// Builds, from the rows of `list.rs`: [`ModelKind`] and its tables, [`Lens`], and
/// `for_each_ray_model!`, the one `match` over the ray models every dispatch goes through.
macro_rules! camera_models {
    (
        standard: {
            $(#[$sdoc:meta])*
            $standard:ident = $sid:literal, name: $sname:literal, params: custom($skeys:literal),
            glsl: ($sdefine:ident),
            inverse_cost: $scost:literal, focal_length: $sfocal:literal;
        }
        rays: {$(
            $(#[$doc:meta])*
            $variant:ident = $id:literal, rust: $module:ident :: $ty:ident, name: $name:literal,
            params: $pkind:ident $pargs:tt, glsl: ($define:ident, $prefix:ident, $include:literal),
            inverse_cost: $cost:literal, focal_length: $focal:literal;
        )*}
    ) => {
        /// Which model a lens is: the shaders' `VKL_MODEL` specialization constant is
        /// [`ModelKind::gpu_id`]. One variant per row of `src/model/list.rs`.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
        pub enum ModelKind {
            $(#[$sdoc])*
            #[default]
            $standard = $sid,
            $($(#[$doc])* $variant = $id,)*
        }

        impl ModelKind {
            /// Every model, in `gpu_id` order.
            pub const ALL: [ModelKind; 1 + [$($name),*].len()] =
                [ModelKind::$standard, $(ModelKind::$variant),*];

            /// The model's name in vklens camera files (and the C API's `vkl_camera_model`).
            pub fn name(self) -> &'static str {
                match self {
                    ModelKind::$standard => $sname,
                    $(ModelKind::$variant => $name,)*
                }
            }

            /// The model of a vklens camera file's `"model"` name.
            pub fn from_name(name: &str) -> Option<ModelKind> {
                ModelKind::ALL.into_iter().find(|k| k.name() == name)
            }

            /// Whether the camera's fx fy are a focal length a pinhole image can share (the
            /// undistorted image's default): not for f-theta and OCamCalib (their polynomials
            /// carry the scale) nor for the equirectangular panorama (fx fy are pixels per
            /// radian).
            pub fn has_focal_length(self) -> bool {
                match self {
                    ModelKind::$standard => $sfocal,
                    $(ModelKind::$variant => $focal,)*
                }
            }

            /// The GPU inverse's cost per pixel relative to the fisheye's (`list.rs`).
            pub fn inverse_cost(self) -> f64 {
                match self {
                    ModelKind::$standard => $scost,
                    $(ModelKind::$variant => $cost,)*
                }
            }

            /// The keys of a vklens JSON camera of this model beside width, height and fx fy
            /// cx cy, as `vklens --help` lists them.
            pub fn file_keys(self) -> &'static str {
                match self {
                    ModelKind::$standard => $skeys,
                    $(ModelKind::$variant => camera_models!(@keys $pkind $pargs),)*
                }
            }

            /// The parameters a vklens JSON camera gives as named numbers, in the order
            /// [`Lens::from_params`] takes them; `None` for models whose files need lists or
            /// flags (read by `io::models`) and for the standard model.
            pub fn scalar_params(self) -> Option<&'static [&'static str]> {
                match self {
                    ModelKind::$standard => None,
                    $(ModelKind::$variant => camera_models!(@names $pkind $pargs),)*
                }
            }
        }

        /// The lens model of a camera and its parameters.
        #[derive(Debug, Clone, PartialEq)]
        pub enum Lens {
            $(#[$sdoc])*
            $standard {
                /// The 14 coefficients.
                distortion: OpenCvDistortion,
                /// How many coefficients the camera was given (4, 5, 8, 12 or 14).
                coeff_count: usize,
                /// `Some((c1, c2))` for a Brown radial lens (the Durham radial-correction
                /// paper).
                brown: Option<(f64, f64)>,
                /// A bound on the ideal normalized radius the file gives (Basalt's `rpmax`):
                /// the valid domain ends there, or earlier where the lens folds.
                max_radius: Option<f64>,
            },
            $($(#[$doc])* $variant(super::$module::$ty),)*
        }

        impl Lens {
            /// Which model this is.
            pub fn kind(&self) -> ModelKind {
                match self {
                    Lens::$standard { .. } => ModelKind::$standard,
                    $(Lens::$variant(_) => ModelKind::$variant,)*
                }
            }

            /// The lens of a model whose parameters are named numbers
            /// ([`ModelKind::scalar_params`]), validated by the model; `None` for the others.
            pub fn from_params(kind: ModelKind, values: &[f64]) -> Option<Result<Lens, ModelError>> {
                match kind {
                    ModelKind::$standard => None,
                    $(ModelKind::$variant => camera_models!(
                        @build $pkind $pargs, $variant, super::$module::$ty, values),)*
                }
            }
        }

        camera_models!(@dispatch ($) $($variant)*);
    };
    (@names custom $keys:tt) => { None };
    (@names named [$($n:literal),*]) => { Some(&[$($n),*]) };
    (@keys custom ($keys:literal)) => { $keys };
    (@keys named [$first:literal $(, $rest:literal)*]) => { concat!($first $(, ", ", $rest)*) };
    (@build custom $keys:tt, $variant:ident, $ty:ty, $values:ident) => { None };
    (@build named [$($n:literal),*], $variant:ident, $ty:ty, $values:ident) => {
        Some(<$ty>::from_params($values).map(Lens::$variant))
    };
    // `$d` is a `$`, so that the generated macro can have metavariables of its own.
    (@dispatch ($d:tt) $($variant:ident)*) => {
        /// Runs `$body` with `$m` bound to the ray model inside `$lens`, or `$standard` for
        /// the standard model.
        macro_rules! for_each_ray_model {
            ($d lens:expr, $d m:ident => $d body:expr, standard => $d standard:expr) => {
                match $d lens {
                    Lens::Standard { .. } => $d standard,
                    $(Lens::$variant($d m) => $d body,)*
                }
            };
        }
    };
}

include!("list.rs");

impl ModelKind {
    /// The value of the shaders' `VKL_MODEL` constant (generated by `build.rs` from the same
    /// list).
    pub fn gpu_id(self) -> u32 {
        self as u32
    }

    /// Whether the model maps camera-frame rays (every model but the standard one): its
    /// inverse gives rays, and it may see past 90° off the axis.
    pub fn is_ray_model(self) -> bool {
        self != ModelKind::Standard
    }
}

impl Lens {
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

    /// The shaders number and dispatch the models as `ModelKind` does: build.rs generates
    /// both includes from `list.rs`; this checks what it wrote against `gpu_id` and the names.
    #[test]
    fn the_shaders_number_the_models_as_the_host_does() {
        let ids = include_str!(concat!(env!("OUT_DIR"), "/glsl/model_ids.glsl"));
        let dispatch = include_str!(concat!(env!("OUT_DIR"), "/glsl/model_dispatch.glsl"));
        for (i, kind) in ModelKind::ALL.into_iter().enumerate() {
            assert_eq!(kind.gpu_id(), i as u32);
            let name = match kind {
                ModelKind::Standard => "OPENCV".to_string(),
                ModelKind::Fisheye => "FISHEYE".to_string(),
                k => k.name().to_ascii_uppercase(),
            };
            let define = format!("#define VKL_MODEL_{name} {i}u");
            assert!(ids.contains(&define), "model_ids.glsl lacks `{define}`");
            // One include per model (the fisheye's is the standard stages').
            if kind.is_ray_model() && kind != ModelKind::Fisheye {
                let include = format!("#include \"models/{}.glsl\"", kind.name());
                assert!(
                    dispatch.contains(&include),
                    "model_dispatch.glsl lacks `{include}`"
                );
                assert!(std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join("glsl/include/models")
                    .join(format!("{}.glsl", kind.name()))
                    .is_file());
            }
            if kind.is_ray_model() {
                let arm = format!("if (VKL_MODEL == VKL_MODEL_{name}) return vkl_");
                assert_eq!(dispatch.matches(&arm).count(), 2, "{}", kind.name());
            }
        }
    }

    /// Names round-trip, and every model with named-number parameters builds from them.
    #[test]
    fn every_row_names_and_builds_its_model() {
        for kind in ModelKind::ALL {
            assert_eq!(ModelKind::from_name(kind.name()), Some(kind));
            if let Some(names) = kind.scalar_params() {
                let lens = Lens::from_params(kind, &vec![0.5; names.len()])
                    .expect("a scalar-parameter model builds")
                    .expect("0.5 is valid for every such model");
                assert_eq!(lens.kind(), kind);
                let params: Vec<&str> = lens.params().into_iter().map(|(n, _)| n).collect();
                assert_eq!(params, names, "{}", kind.name());
                assert!(Lens::from_params(kind, &[]).unwrap().is_err());
            } else {
                assert!(Lens::from_params(kind, &[]).is_none());
            }
        }
        assert_eq!(ModelKind::from_name("brown"), None);
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
