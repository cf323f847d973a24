//! The f64 models against OpenCV's own numbers, random realistic cameras, the fisheye model's
//! references and the overscan source camera.

mod fisheye;
mod model_properties;
mod overscan;
mod reference_cpu;
