//! vklens: realistic, calibrated camera-lens effects with raw Vulkan.
//!
//! A [`Camera`] is a calibrated lens: OpenCV's standard model with all 14 coefficients,
//! applied exactly as `cv2.projectPoints` does, with a safe inverse that says explicitly where
//! no inverse can be right (see [`Camera::undistort_points`]). Three things put it into
//! images:
//!
//! * a [`Warper`]: the post-processing warp (distort, undistort, headset pre-correction),
//!   built once and run on host images ([`Warper::run`]) or recorded into your own command
//!   buffer with your own images ([`Warper::record`]);
//! * a [`SceneRenderer`]: a scene file through the lens, planned to the cheapest pipeline for
//!   what it asks (per vertex with Lambers et al.'s Alg. 1 for IDs, flow and depth; the warp;
//!   or Heidrich et al.'s image-based model for a real lens prescription);
//! * [`overscan`]: the pinhole source camera that covers every valid pixel of a lens;
//!   [`optimal_new_camera`] and [`fisheye_new_camera`]: the pinhole camera to undistort into,
//!   chosen as OpenCV's `getOptimalNewCameraMatrix` and
//!   `fisheye.estimateNewCameraMatrixForUndistortRectify` choose it; [`stereo_rectify`]: the
//!   rectification of a calibrated pair, as `cv2.stereoRectify` and
//!   `cv2.fisheye.stereoRectify` compute it.
//!
//! ```
//! use vklens::{Camera, InverseMethod};
//! let k = [[400.0, 0.0, 399.5], [0.0, 400.0, 299.5], [0.0, 0.0, 1.0]];
//! let camera = Camera::from_opencv(k, &[-0.05, 0.01, 0.03, -0.01], (800, 600))?;
//! let uv = camera.distort_points(&[[0.1, -0.2]]);
//! let xy = camera.undistort_points(&[uv[0].unwrap()], InverseMethod::Newton);
//! let [x, y] = xy[0].unwrap();
//! assert!((x - 0.1).abs() < 1e-12 && (y + 0.2).abs() < 1e-12);
//! # Ok::<(), vklens::Error>(())
//! ```
//!
//! Every fallible call returns [`Result`]; an [`Error`]'s [`ErrorKind`] says what the caller
//! can do about it.
//!
//! Beneath this surface are the layers it is built from, bottom first: [`model`] (camera
//! models as f64 maths), [`lens`], [`io`], [`imaging`] and [`scene`] (no Vulkan), [`gpu`] (one
//! owning type per Vulkan object), [`pass`] (record-only GPU passes), [`host`] (the headless
//! submit path) and [`plan`] (the planner and its recorder). The command line is built on
//! them; they are public for it and for callers who need a layer itself, but unlike the items
//! re-exported here they are not kept stable between minor versions.

// `!(x > 0.0)` is how this crate says "x is positive and not NaN": a NaN must fail every
// check (the answer is an explicit invalid, never silent garbage). `partial_cmp` would hide that.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
#![warn(missing_docs)]
// An `unsafe fn` states its contract; the operations inside still each need a block that says
// why they are sound.
#![deny(unsafe_op_in_unsafe_fn)]

mod error;
mod facade;
#[cfg(test)]
mod testing;

pub use error::{Error, ErrorKind, Result};
pub use facade::{
    overscan, Device, Frame, HostImage, HostImageMut, HostPixels, HostPixelsMut, ImageRef,
    Rendered, SceneRenderer, WarpDirection, WarpMethod, WarpOptions, Warped, Warper,
};
pub use gpu::{EnabledFeatures, Gpu};
/// How [`Device::with_options`] opens a device: which one, the validation layer, the
/// geometry-shader feature.
pub use host::ContextOptions as DeviceOptions;
pub use imaging::cpu_warp::{Border, Sampling};
pub use imaging::{BitDepth, Pixels, Raster};
pub use io::catalog::{Found, Listing, LoadOptions};
pub use io::writers::Format as CameraFormat;
pub use model::new_camera::{fisheye_new_camera, optimal_new_camera, Roi};
pub use model::stereo::{stereo_rectify, PairRotation, StereoOptions, StereoRectification};
/// The types [`Camera`]'s own methods name, public by design and kept stable with it: the
/// lens it holds ([`Lens`], whose variants are the model types of [`model`]), which model
/// that is ([`ModelKind`]), the standard model's coefficients and terms ([`OpenCvDistortion`],
/// [`Terms`]), OpenCV's fisheye ([`Fisheye`]), a Brown headset lens ([`BrownRadial`]), the
/// region where its inverse is right ([`ValidDomain`]), and the error its constructors return
/// ([`ModelError`], which `?` turns into an [`Error`] of kind [`ErrorKind::Input`]).
pub use model::{
    BrownRadial, Fisheye, Lens, ModelError, ModelKind, OpenCvDistortion, Terms, ValidDomain,
};
pub use model::{Camera, Intrinsics, InverseMethod};
pub use pass::warp::PixelFormat;

/// The names of the camera models vklens knows, as camera files spell them (`"model": NAME`), in
/// the order of the library's model list (`src/model/list.rs`; it only grows at the end). A
/// Brown headset lens (`"brown"`) runs as its exact twin, `opencv`.
///
/// ```
/// let models = vklens::camera_models();
/// assert_eq!(models[0], "opencv");
/// assert!(models.contains(&"double_sphere"));
/// ```
pub fn camera_models() -> Vec<&'static str> {
    model::ModelKind::ALL
        .into_iter()
        .map(model::ModelKind::name)
        .collect()
}

/// Rolling-shutter sensors: a world point seen through a camera that moves while its lines are
/// read appears where its own line's readout time agrees with the pose it was seen from
/// (`docs/rolling-shutter.md`).
///
/// ```
/// use vklens::rolling_shutter::{project_rolling, Readout, WorldToCamera};
/// let k = [[1000.0, 0.0, 959.5], [0.0, 1000.0, 539.5], [0.0, 0.0, 1.0]];
/// let camera = vklens::Camera::from_opencv(k, &[-0.1, 0.02, 0.0, 0.0], (1920, 1080))?;
/// let start = WorldToCamera::from_rows([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], [0.0; 3]);
/// // Panning right by 1° while the rows are read, top to bottom.
/// let (s, c) = 1f64.to_radians().sin_cos();
/// let end = WorldToCamera::from_rows([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]], [0.0; 3]);
/// let x = glam::DVec3::new(0.5, 0.4, 4.0);
/// let p = project_rolling(&camera, &start, &end, Readout::TopToBottom, x).unwrap();
/// // Below the image's centre, the point is read after mid-frame, from a pose turned by more
/// // than half the pan: further left than the first line's pose shows it.
/// let first = camera.project_points(&[[0.5, 0.4, 4.0]])[0].unwrap();
/// assert!(p.s > 0.5 && p.pixel.x < first[0] - 5.0 && p.depth > 3.9);
/// # Ok::<(), vklens::Error>(())
/// ```
pub mod rolling_shutter {
    pub use crate::model::rolling_shutter::{
        line_time, project_rolling, FrameMotion, Projection, Readout, WorldToCamera, MAX_ERROR_PX,
        MAX_REFINE_STEPS, PIXEL_TOLERANCE, SCAN_CELLS,
    };
}

// The layers beneath the surface above, bottom first: `model`, `lens`, `io`, `imaging`,
// `scene` and `labels` (no Vulkan), `gpu` (one owning type per Vulkan object), `pass` (record-only GPU
// passes), `host` (the headless submit path) and `plan` (what to record for a scene, and its
// recorder). See `docs/architecture.md`. They are public for the command line (`vklens-cli`)
// and for callers who need a layer itself; unlike the items above, they are not kept stable
// between minor versions.
#[allow(missing_docs)]
pub mod gpu;
#[allow(missing_docs)]
pub mod host;
#[allow(missing_docs)]
pub mod imaging;
#[allow(missing_docs)]
pub mod io;
#[allow(missing_docs)]
pub mod labels;
#[allow(missing_docs)]
pub mod lens;
#[allow(missing_docs)]
pub mod model;
#[allow(missing_docs)]
pub mod pass;
#[allow(missing_docs)]
pub mod plan;
#[allow(missing_docs)]
pub mod scene;
