//! The public surface of vklens: what the command line, the Python package and the C API
//! wrap, and what a Rust program or engine uses.

mod camera;
mod device;
mod image;
mod scene;
mod warper;

#[cfg(test)]
mod tests;

pub use device::Device;
pub use image::{HostImage, HostImageMut, HostPixels, HostPixelsMut};
pub use scene::{Frame, Rendered, SceneRenderer};
pub use warper::{overscan, ImageRef, WarpDirection, WarpMethod, WarpOptions, Warped, Warper};
