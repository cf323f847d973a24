//! GPU passes. Each is built once from a [`crate::gpu::Gpu`] (`new`) and then *records* into a
//! command buffer the caller owns; no pass submits work by itself. What submits (upload,
//! record, wait, read back on the headless [`crate::host::Context`]) is in [`crate::host`].

pub mod camera_params;
pub mod copy;
pub mod cube_stage;
pub mod environment;
pub mod film;
pub mod geometry;
pub mod grid_demo;
pub mod lens_render;
pub mod mesh_warp;
pub mod points;
pub mod spec;
pub mod sphere_warp;
#[cfg(test)]
mod tests;
pub mod warp;
pub mod warp_raster;
pub mod warp_stage;

pub use camera_params::{CameraParams, CameraParams64};
pub use points::{PointsMode, PointsPass, Precision};
