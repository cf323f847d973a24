//! Reading what users bring: camera files, the shared reference data.

pub mod camera;
pub mod reference;

pub use camera::{load_camera, load_lens, parse_camera, parse_lens, CameraFileError, Lens};
