//! Everything that submits: the headless path of each pass (upload, record, submit, wait, read
//! back) for the command line, the tests, the benches and the facade's `Warper::run`. The
//! passes themselves (`pass/`) only record into a command buffer the caller owns.

pub mod bands_study;
mod context;
pub mod geometry;
pub mod grid_demo;
pub mod lens_render;
pub mod mesh_warp;
pub mod plan;
pub mod points;
pub mod readback;
pub mod sphere_warp;
pub mod warp;
pub mod warp_images;
pub mod warp_raster;

pub use context::{
    geometry_shader_discard_from_env, geometry_shader_from_env, Context, ContextOptions,
};
