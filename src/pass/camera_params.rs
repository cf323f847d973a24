//! The camera as the shaders see it: one `#[repr(C)]` struct mirroring the `CameraParams`
//! block of `glsl/include/camera_model.glsl`, plus the specialization constants that compile
//! out the terms a camera does not use.

use bytemuck::{Pod, Zeroable};

use super::spec;
use crate::gpu::SpecConstants;
use crate::model::{Camera, Terms, ValidDomain};

/// Entries of the valid-domain table (same as the CPU table).
pub const DOMAIN_SAMPLES: usize = ValidDomain::SAMPLES;

/// Newton iterations on the GPU (f32 converges in 3-6 from the radial start).
pub const GPU_NEWTON_ITERATIONS: u32 = 20;

macro_rules! camera_params {
    ($(#[$doc:meta])* $name:ident, $t:ty) => {
        $(#[$doc])*
        #[repr(C)]
        #[derive(Clone, Copy, Pod, Zeroable)]
        pub struct $name {
            /// fx fy cx cy
            pub intrinsics: [$t; 4],
            /// k1 k2 k3 - (fisheye: k1 k2 k3 k4)
            pub radial: [$t; 4],
            /// k4 k5 k6 - (fisheye: α, θ_max, θ_d(θ_max), -)
            pub rational: [$t; 4],
            /// p1 p2 s1 s2
            pub tangential_prism: [$t; 4],
            /// s3 s4 - -
            pub prism: [$t; 4],
            /// Rows of OpenCV's tilt matrix.
            pub tilt: [[$t; 4]; 3],
            /// Rows of its inverse.
            pub untilt: [[$t; 4]; 3],
            /// x: smallest ideal boundary radius, y: smallest distorted boundary radius, z:
            /// the cosine of Alg. 1's vertex limit for a ray model (-2 where the domain decides).
            pub domain_info: [$t; 4],
            /// The ray model's own parameters (`model::table::RayModel::gpu_params`).
            pub model: [[$t; 4]; 16],
            /// x: ideal boundary radius, y: distorted boundary radius, at angle TAU·i/N.
            pub domain: [[$t; 4]; DOMAIN_SAMPLES],
        }

        impl $name {
            /// The camera's parameters for the shaders.
            pub fn from_camera(camera: &Camera) -> Self {
                let k = camera.intrinsics;
                let d = camera.shader_coefficients();
                let f = |v: f64| v as $t;
                let rows = |m: glam::DMat3| -> [[$t; 4]; 3] {
                    let t = m.transpose(); // columns of the transpose are the rows
                    [0, 1, 2].map(|i| {
                        let r = t.col(i);
                        [f(r.x), f(r.y), f(r.z), f(0.0)]
                    })
                };
                let (tilt, untilt) = camera
                    .tilt_matrices()
                    .map(|(m, inv)| (rows(m), rows(inv)))
                    .unwrap_or_else(|| (rows(glam::DMat3::IDENTITY), rows(glam::DMat3::IDENTITY)));
                let domain = camera.shader_domain();
                let mut table = [[f(0.0); 4]; DOMAIN_SAMPLES];
                for (slot, [ideal, distorted]) in table.iter_mut().zip(domain.table()) {
                    *slot = [f(ideal), f(distorted), f(0.0), f(0.0)];
                }
                // The fisheye's k1..k4 fill `radial`; α, θ_max and θ_d(θ_max) `rational`.
                let (radial, rational) = match camera.fisheye_lens() {
                    Some(l) => (
                        l.k.map(f),
                        [f(l.alpha), f(l.theta_max()), f(l.theta_d_max()), f(0.0)],
                    ),
                    None => (
                        [f(d.k1), f(d.k2), f(d.k3), f(0.0)],
                        [f(d.k4), f(d.k5), f(d.k6), f(0.0)],
                    ),
                };
                $name {
                    intrinsics: [f(k.fx), f(k.fy), f(k.cx), f(k.cy)],
                    radial,
                    rational,
                    tangential_prism: [f(d.p1), f(d.p2), f(d.s1), f(d.s2)],
                    prism: [f(d.s3), f(d.s4), f(0.0), f(0.0)],
                    tilt,
                    untilt,
                    domain_info: [
                        f(domain.min_ideal_radius()),
                        f(domain.min_distorted_radius()),
                        // cos of Alg. 1's vertex limit; -2 where the domain decides.
                        f(camera.fisheye_vertex_limit().map_or(-2.0, f64::cos)),
                        f(0.0),
                    ],
                    model: {
                        let p = camera.lens().gpu_params();
                        std::array::from_fn(|i| [0, 1, 2, 3].map(|j| f(p[4 * i + j])))
                    },
                    domain: table,
                }
            }
        }
    };
}

camera_params!(
    /// `uniform CameraParams` (std140), the f32 model. Every member is a vec4 (or an array of
    /// them), so std140 and `repr(C)` agree without hidden padding.
    CameraParams,
    f32
);
camera_params!(
    /// `uniform CameraParams64` (std140), the f64 model of shaders compiled with `VKL_F64`:
    /// the same members as dvec4.
    CameraParams64,
    f64
);

const _: () = assert!(std::mem::size_of::<CameraParams>() == 448 + 16 * DOMAIN_SAMPLES);
const _: () = assert!(std::mem::size_of::<CameraParams64>() == 896 + 32 * DOMAIN_SAMPLES);

impl CameraParams {
    /// Specialization constants that compile out every term group the camera does not use.
    pub fn spec_constants(terms: Terms) -> SpecConstants {
        SpecConstants::new()
            .bool(spec::RADIAL, terms.radial)
            .bool(spec::RATIONAL, terms.rational)
            .bool(spec::TANGENTIAL, terms.tangential)
            .bool(spec::PRISM, terms.prism)
            .bool(spec::TILT, terms.tilt)
            .u32(spec::NEWTON_ITERATIONS, GPU_NEWTON_ITERATIONS)
            .u32(spec::MODEL, terms.model.gpu_id())
            .bool(spec::DOMAIN_TABLE, true)
    }
}
