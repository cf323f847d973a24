//! Everything that submits: the headless path of each pass (upload, record, submit, wait, read
//! back) for the command line, the tests, the benches and the facade's `Warper::run`. The
//! passes themselves (`pass/`) only record into a command buffer the caller owns.

pub mod geometry;
pub mod grid_demo;
pub mod lens_render;
pub mod mesh_warp;
pub mod points;
pub mod sphere_warp;
pub mod warp;
pub mod warp_raster;
