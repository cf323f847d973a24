//! SPIR-V compiled from `glsl/` by `build.rs`.

/// `glsl/points.comp`: the camera model on a list of points (forward or inverse).
pub const POINTS_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/points.comp.spv"));
/// `glsl/points.comp` compiled with `VKL_F64`: the same model in f64 (needs `shaderFloat64`).
pub const POINTS_COMP_F64: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/points.comp.f64.spv"));
/// `glsl/grid_demo.comp`: a procedural grid seen through a lens (analytic inverse per pixel).
pub const GRID_DEMO_COMP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/grid_demo.comp.spv"));
