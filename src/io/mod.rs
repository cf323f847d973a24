//! Reading what users bring: camera files, the shared reference data.

pub mod camera;
pub mod reference;

pub use camera::{load_camera, parse_camera};
