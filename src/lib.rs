//! vklens: realistic, calibrated camera-lens effects with raw Vulkan.
//!
//! * [`model`] — camera models in plain f64 (OpenCV's 14-coefficient standard model, Brown
//!   radial), their Jacobians, inverses and valid domains. No Vulkan.
//! * [`io`] — camera files (JSON, OpenCV FileStorage YAML/XML/JSON, ROS camera_info).
//! * [`imaging`] — host images (PNG, EXR) and the f64 reference warp.
//! * [`gpu`] — Vulkan plumbing: a [`gpu::Gpu`] built from the caller's device, queue and
//!   allocator, the headless [`gpu::Context`] that tests and the CLI use, owned resources.
//! * [`pass`] — GPU passes that record into a command buffer the caller owns.
//! * [`lens`] — real lens systems (Heidrich et al.): prescriptions, exact tracing, the image-based
//!   model and its reference ray tracer. No Vulkan.
//! * [`plan`] — scene files and the planner: the cheapest pipeline for what a scene asks.
//! * [`bench`] — the accuracy-versus-time measurements behind `vklens bench`.

// `!(x > 0.0)` is how this crate says "x is positive and not NaN": a NaN must fail every
// check (the answer is an explicit invalid, never silent garbage). `partial_cmp` would hide that.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod bench;
mod error;
pub use error::{Error, ErrorKind, Result};
pub mod cli;
pub mod gpu;
pub mod imaging;
pub mod io;
pub mod lens;
pub mod model;
pub mod pass;
pub mod plan;
pub mod render;
pub mod scene;
