//! `vklens cameras` and `vklens convert` as scripts use them: every camera of a file listed
//! with its name, model and size; `--camera-name` picks one for any command; a conversion
//! reads back to the same pixels, and a format that cannot hold the camera is refused with
//! the file left as it was. The camera files are small ones written here in each tool's
//! layout.

use std::io::Write;
use std::process::{Command, Output, Stdio};

use glam::DVec3;
use vklens::{Camera, LoadOptions};

fn by_name(name: &str) -> LoadOptions {
    LoadOptions {
        name: Some(name.into()),
        ..LoadOptions::default()
    }
}

/// Points all around, past 90° too: the same pixel to 1e-9 px (a file's numbers round-trip
/// exactly; a solver's bracket may move its last bit) or the same "not seen" for both.
fn same_pixels(a: &Camera, b: &Camera, what: &str) {
    assert_eq!(a.model_name(), b.model_name(), "{what}");
    assert_eq!((a.width, a.height), (b.width, b.height), "{what}");
    for i in 0..200 {
        let t = std::f64::consts::PI * (i as f64 + 0.5) / 200.0;
        let phi = 2.399963 * i as f64;
        let p = DVec3::new(t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos());
        match (a.project(p), b.project(p)) {
            (Some(x), Some(y)) => assert!(
                (x - y).length() <= 1e-9 * (1.0 + x.length()),
                "{what} at {p:?}: {x} vs {y}"
            ),
            (x, y) => assert_eq!(x, y, "{what} at {p:?}"),
        }
    }
}

const KALIBR: &str = "cam2:
  camera_model: pinhole
  intrinsics: [461.6, 460.3, 366.3, 249.3]
  distortion_model: radtan
  distortion_coeffs: [-0.27, 0.06, 1.2e-4, 2.2e-5]
  resolution: [752, 480]
cam10:
  camera_model: pinhole
  intrinsics: [458.7, 457.3, 367.2, 248.4]
  distortion_model: equidistant
  distortion_coeffs: [-0.013, 0.017, -0.012, 0.003]
  resolution: [752, 480]
";

fn vklens(args: &[&str], stdin: &str) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_vklens"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run vklens");
    if let Some(mut s) = child.stdin.take() {
        s.write_all(stdin.as_bytes()).ok();
    }
    child.wait_with_output().expect("vklens output")
}

#[test]
fn the_command_line_lists_picks_and_converts() {
    let dir = std::env::temp_dir().join(format!("vklens-catalog-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp");
    let chain = dir.join("camchain.yaml");
    std::fs::write(&chain, KALIBR).expect("write");
    let chain = chain.to_str().expect("utf-8");

    let out = vklens(&["cameras", chain], "");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("a Kalibr camchain (2 cameras)"), "{text}");
    assert!(
        text.contains("cam10") && text.contains("opencv_fisheye") && text.contains("752x480"),
        "{text}"
    );
    let out = vklens(&["cameras", chain, "--json"], "");
    let rows: Vec<serde_json::Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("json line"))
        .collect();
    assert_eq!(rows.len(), 2);
    assert_eq!(rows[1]["name"], "cam10");
    assert_eq!(rows[1]["model"], "opencv_fisheye");
    assert_eq!(rows[0]["format"], "Kalibr camchain");

    // --camera-name picks the camera for any command.
    let out = vklens(
        &[
            "points",
            "distort",
            "--camera",
            chain,
            "--camera-name",
            "cam10",
        ],
        "[[0.1, 0.2]]",
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let got: Vec<[f64; 2]> = serde_json::from_slice(&out.stdout).expect("json");
    let want = Camera::load_with(chain, &by_name("cam10"))
        .expect("cam10")
        .project(DVec3::new(0.1, 0.2, 1.0))
        .expect("px");
    assert_eq!(got[0], want.to_array());

    // convert: to Kalibr and back; refused where the format cannot hold it, file untouched.
    let out_path = dir.join("cam10.txt");
    let out = vklens(
        &[
            "convert",
            "--camera",
            chain,
            "--camera-name",
            "cam10",
            "--to",
            "colmap",
            "--output",
            out_path.to_str().expect("utf-8"),
        ],
        "",
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let back = Camera::load(&out_path).expect("colmap back");
    let cam10 = Camera::load_with(chain, &by_name("cam10")).expect("cam10");
    same_pixels(&back, &cam10, "cam10 → colmap");
    let out = vklens(
        &[
            "convert",
            "--camera",
            chain,
            "--camera-name",
            "cam10",
            "--to",
            "opencv",
            "--output",
            out_path.to_str().expect("utf-8"),
        ],
        "",
    );
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("OpenCV FileStorage YAML cannot hold this camera"),
        "{err}"
    );
    assert!(std::fs::read_to_string(&out_path)
        .expect("kept")
        .contains("OPENCV_FISHEYE"));

    // A file without a size: exit 2 naming the missing size; --size loads it.
    let no_size = dir.join("orb.yaml");
    std::fs::write(&no_size, "%YAML:1.0\ncamera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [ 500., 0., 320., 0., 500., 240., 0., 0., 1. ]\n").expect("write");
    let path = no_size.to_str().expect("utf-8");
    let out = vklens(&["points", "distort", "--camera", path], "[[0, 0]]");
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--size"));
    let out = vklens(
        &["points", "distort", "--camera", path, "--size", "640x480"],
        "[[0, 0]]",
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::remove_dir_all(&dir).ok();
}
