//! The passes on a device with the Khronos validation layer on, against exact oracles: the
//! shaders' camera models against the f64 model and OpenCV's numbers, the warps against the
//! f64 reference warp, the geometry path against a ray cast, the image-based lens model
//! against the reference ray tracer, the host structs against the compiled SPIR-V, and a pass
//! recorded into a caller's own device and command buffer.

mod embedding;
mod fisheye_gpu;
mod fisheye_render;
mod geometry;
mod ground_truth;
mod layout;
mod lens_render;
mod mesh_warp;
mod models_gpu;
mod reference_gpu;
mod rolling_shutter;
mod sphere_warp;
mod warp_gpu;
mod warp_hard_cases;
