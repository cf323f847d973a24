//! Shared helpers of the integration tests: the shared reference data (`../shared`), which is
//! never copied into the repository, found where vklens finds it, and read as a test reads
//! any data file.
#![allow(dead_code)]

use std::path::PathBuf;

use serde::Deserialize;

/// The shared folder: `$VKLENS_SHARED` if set, else `../shared` beside the repository root.
pub fn shared_dir() -> PathBuf {
    match std::env::var_os("VKLENS_SHARED") {
        Some(dir) => PathBuf::from(dir),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join("shared"),
    }
}

/// The shared OpenCV reference file: cameras and OpenCV's own numbers for their points.
pub fn reference_path() -> PathBuf {
    shared_dir()
        .join("reference")
        .join("opencv_standard_model.json")
}

/// `opencv_standard_model.json`, the fields the tests read.
#[derive(Deserialize)]
pub struct Reference {
    pub cases: Vec<ReferenceCase>,
}

/// One camera of the reference file with its points.
#[derive(Deserialize)]
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

/// A point: the ideal normalized coordinates and OpenCV's `projectPoints` pixel for them.
#[derive(Deserialize)]
pub struct ReferencePoint {
    pub undistorted_normalized: [f64; 2],
    pub distorted_pixel: [f64; 2],
}

/// Reads the shared reference file.
pub fn load_reference() -> Reference {
    let path = reference_path();
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (the shared reference data)", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The reference case named `name`.
pub fn reference_case(name: &str) -> ReferenceCase {
    load_reference()
        .cases
        .into_iter()
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("no reference case {name}"))
}

/// The reference case named `name`, as a camera built from its `K` and `D` as OpenCV's are.
pub fn reference_camera(name: &str) -> vklens::Camera {
    let c = reference_case(name);
    let k = [[c.fx, 0.0, c.cx], [0.0, c.fy, c.cy], [0.0, 0.0, 1.0]];
    vklens::Camera::from_opencv(k, &c.dist_coeffs, (c.width, c.height))
        .expect("reference cases are valid cameras")
}
