//! The shared reference data (`../shared/reference/`), read by tests and by `vklens bench`.
//! It is never copied into the repository: this finds it beside the checkout.

use crate::{Error, Result};
use std::path::PathBuf;

use serde::Deserialize;

/// `opencv_standard_model.json`.
#[derive(Debug, Clone, Deserialize)]
pub struct ReferenceFile {
    pub generator: String,
    pub cases: Vec<ReferenceCase>,
}

/// One camera with its 625 points.
#[derive(Debug, Clone, Deserialize)]
pub struct ReferenceCase {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    pub dist_coeffs: Vec<f64>,
    pub points: Vec<ReferencePoint>,
}

/// A point: OpenCV's forward value and OpenCV's own inverses of it.
#[derive(Debug, Clone, Deserialize)]
pub struct ReferencePoint {
    pub undistorted_normalized: [f64; 2],
    pub distorted_pixel: [f64; 2],
    pub opencv_undistort_default: [f64; 2],
    pub opencv_undistort_200_iter: [f64; 2],
}

impl ReferenceCase {
    /// The case as a camera (it is a valid camera object as it stands).
    pub fn camera(&self) -> Result<crate::model::Camera, crate::model::ModelError> {
        crate::model::Camera::from_coeffs(
            self.width,
            self.height,
            crate::model::Intrinsics {
                fx: self.fx,
                fy: self.fy,
                cx: self.cx,
                cy: self.cy,
            },
            &self.dist_coeffs,
        )
    }
}

/// The shared folder: `$VKLENS_SHARED` if set, else `../shared` beside the repository root.
pub fn shared_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os("VKLENS_SHARED") {
        return PathBuf::from(dir);
    }
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("shared")
}

/// Path of the shared OpenCV reference file.
pub fn reference_path() -> PathBuf {
    shared_dir()
        .join("reference")
        .join("opencv_standard_model.json")
}

/// Loads the shared OpenCV reference file.
pub fn load_reference() -> Result<ReferenceFile> {
    let path = reference_path();
    let text = std::fs::read_to_string(&path)
        .map_err(|e| Error::io(&path, "cannot read the shared reference file", &e))?;
    serde_json::from_str(&text).map_err(|e| Error::input(format!("{}: {e}", path.display())))
}
