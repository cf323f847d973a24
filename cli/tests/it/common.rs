//! Shared helpers of the integration tests: the shared reference data (`../shared`), which is
//! never copied into the repository, found where vklens finds it, and read as a test reads
//! any data file; running the binary, and the scratch files a command-line test writes.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde::Deserialize;

/// The repository's root (these tests belong to `cli/`): the examples, lenses and scripts.
pub fn root() -> PathBuf {
    let cli = Path::new(env!("CARGO_MANIFEST_DIR"));
    cli.parent().unwrap_or(cli).to_path_buf()
}

/// The shared folder: `$VKLENS_SHARED` if set, else `../shared` beside the repository root.
pub fn shared_dir() -> PathBuf {
    match std::env::var_os("VKLENS_SHARED") {
        Some(dir) => PathBuf::from(dir),
        None => root().join("..").join("shared"),
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

/// Runs the release binary with `args`, the validation layer on.
pub fn vklens(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vklens"))
        .args(args)
        .env("VKLENS_VALIDATION", "1")
        .output()
        .unwrap()
}

/// What a run said on stderr.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `name` in this process's scratch folder for the test file `tag` (made if missing).
pub fn scratch(tag: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vklens-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// A `w × h` RGBA gradient PNG (red across, green down), 16-bit or 8-bit.
pub fn write_png(path: &Path, w: u32, h: u32, sixteen: bool) {
    use image::{ImageBuffer, Rgba};
    let pixel = |x: u32, y: u32| [x as f32 / w as f32, y as f32 / h as f32, 0.5, 1.0];
    if sixteen {
        ImageBuffer::from_fn(w, h, |x, y| {
            Rgba(pixel(x, y).map(|c| (c * 65535.0).round() as u16))
        })
        .save(path)
        .unwrap();
    } else {
        ImageBuffer::from_fn(w, h, |x, y| {
            Rgba(pixel(x, y).map(|c| (c * 255.0).round() as u8))
        })
        .save(path)
        .unwrap();
    }
}

/// Runs the release binary with `args` and `stdin` piped in, the validation layer on.
pub fn vklens_with_stdin(args: &[&str], stdin: &str) -> Output {
    use std::io::Write;
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_vklens"))
        .args(args)
        .env("VKLENS_VALIDATION", "1")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(stdin.as_bytes()).ok();
    child.wait_with_output().unwrap()
}
