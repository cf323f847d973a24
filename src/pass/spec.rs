//! Specialization-constant ids, named once. Each is `(GLSL name, constant_id)`; the host sets
//! constants only through these, and `src/pass/tests/layout.rs` checks every one against the compiled
//! SPIR-V of each shader that declares it.

use crate::gpu::SpecId;

// glsl/include/camera_model.glsl: which term groups are compiled in.
/// k1 k2 k3.
pub const RADIAL: SpecId = SpecId::new("VKL_RADIAL", 0);
/// k4 k5 k6.
pub const RATIONAL: SpecId = SpecId::new("VKL_RATIONAL", 1);
/// p1 p2.
pub const TANGENTIAL: SpecId = SpecId::new("VKL_TANGENTIAL", 2);
/// s1 s2 s3 s4.
pub const PRISM: SpecId = SpecId::new("VKL_PRISM", 3);
/// τx τy.
pub const TILT: SpecId = SpecId::new("VKL_TILT", 4);
/// Newton iterations of the GPU inverse.
pub const NEWTON_ITERATIONS: SpecId = SpecId::new("VKL_NEWTON_ITERATIONS", 5);
/// Which camera model the shader evaluates: `model::ModelKind::gpu_id` (0 OpenCV's standard
/// model and Brown's, 1 OpenCV's fisheye, 2.. the other models of the table).
pub const MODEL: SpecId = SpecId::new("VKL_MODEL", 6);
/// Whether the valid-domain test may look up its table (false: the smallest boundary radius
/// alone decides, where that is all a pass can need; see `glsl/include/camera_model.glsl`).
pub const DOMAIN_TABLE: SpecId = SpecId::new("VKL_DOMAIN_TABLE", 7);
/// Every camera-model constant: the term groups in the order of [`crate::model::Terms`]'s
/// fields, the Newton iterations, the model, the domain table.
pub const CAMERA: [SpecId; 8] = [
    RADIAL,
    RATIONAL,
    TANGENTIAL,
    PRISM,
    TILT,
    NEWTON_ITERATIONS,
    MODEL,
    DOMAIN_TABLE,
];

// glsl/include/warp_coords.glsl and glsl/points.comp: what a coordinate pass computes.
/// Direction: 0 distort (inverse per pixel), 1 undistort (forward per pixel).
pub const MODE: SpecId = SpecId::new("MODE", 8);
/// Inverse method: 0 Newton, 1 Heikkilä, 2 fixed point.
pub const METHOD: SpecId = SpecId::new("METHOD", 9);
/// Iterations of the fixed-point inverse.
pub const FIXED_POINT_ITERATIONS: SpecId = SpecId::new("FIXED_POINT_ITERATIONS", 10);
/// Undistort into a rotated (rectified) frame: the output pixel's ray through a homography.
pub const RECTIFY: SpecId = SpecId::new("RECTIFY", 16);

// glsl/warp.comp, glsl/warp_raster.frag, glsl/include/warp_sample.glsl.
/// Three fetches, one per channel's lens (lateral chromatic aberration).
pub const CHROMATIC: SpecId = SpecId::new("CHROMATIC", 11);
/// Sample precomputed maps instead of solving per pixel.
pub const USE_MAP: SpecId = SpecId::new("USE_MAP", 12);
/// Nearest sampling (IDs, depth) instead of bilinear.
pub const NEAREST: SpecId = SpecId::new("NEAREST", 13);
/// Bicubic sampling (OpenCV's `INTER_CUBIC`) instead of bilinear.
pub const BICUBIC: SpecId = SpecId::new("BICUBIC", 17);
/// What positions off the source read: `Border::gpu_id` (0 constant, 1 replicate, 2 reflect).
pub const BORDER: SpecId = SpecId::new("BORDER", 18);
/// Write the validity mask.
pub const WRITE_MASK: SpecId = SpecId::new("WRITE_MASK", 14);

// glsl/inverse_map.comp and glsl/upsample_map.comp: coarse maps.
/// Pixels between solved samples.
pub const STRIDE: SpecId = SpecId::new("STRIDE", 11);
/// Newton steps after interpolation.
pub const REFINE: SpecId = SpecId::new("REFINE", 12);
/// Largest forward residual an interpolated pixel may keep (px).
pub const MAX_RESIDUAL_PX: SpecId = SpecId::new("MAX_RESIDUAL_PX", 13);
/// Whether the per-pixel forward check is compiled in.
pub const CHECK_RESIDUAL: SpecId = SpecId::new("CHECK_RESIDUAL", 14);
/// Cubic (Lagrange) instead of bilinear interpolation.
pub const CUBIC: SpecId = SpecId::new("CUBIC", 15);

// glsl/geometry.vert and glsl/geometry.frag.
/// Alg. 1 (the lens per vertex) instead of the pinhole projection.
pub const DISTORT: SpecId = SpecId::new("DISTORT", 8);
/// Outputs written by the fragment shader.
pub const WRITE_COLOR: SpecId = SpecId::new("WRITE_COLOR", 20);
/// Object IDs.
pub const WRITE_IDS: SpecId = SpecId::new("WRITE_IDS", 21);
/// Flow.
pub const WRITE_FLOW: SpecId = SpecId::new("WRITE_FLOW", 22);
/// Camera depth.
pub const WRITE_DEPTH: SpecId = SpecId::new("WRITE_DEPTH", 23);
/// Range: the distance along the pixel's ray.
pub const WRITE_RANGE: SpecId = SpecId::new("WRITE_RANGE", 25);

// glsl/include/wraps_behind.glsl (glsl/geometry.geom, glsl/discard.comp through alg1.glsl).
/// The camera's image is cut along the half-plane x = 0 behind it (a panorama,
/// `Camera::has_seam`): triangles through it are dropped.
pub const SEAM_BEHIND: SpecId = SpecId::new("VKL_SEAM_BEHIND", 27);

// glsl/include/rolling_shutter.glsl (glsl/geometry.vert, glsl/discard.comp).
/// A moving rolling shutter's readout, `Readout::gpu_id` (0: a global shutter or a still
/// camera, and none of the per-vertex solve is compiled in).
pub const READOUT: SpecId = SpecId::new("VKL_READOUT", 24);

// glsl/discard.comp (also DISTORT).
/// 0: one flag per vertex; 1: one index triple per triangle.
pub const DISCARD_STAGE: SpecId = SpecId::new("STAGE", 9);

// glsl/grid_demo.comp.
/// Grid cells across the image.
pub const GRID: SpecId = SpecId::new("GRID", 8);

// glsl/mesh_warp.frag.
/// Write source coordinates instead of colour.
pub const WRITE_COORDINATES: SpecId = SpecId::new("WRITE_COORDINATES", 0);
