//! Lambers et al. Sec. 4's proof, in CI: render calibration sets through both paths for two
//! cameras, calibrate them with OpenCV (`tests/calibrate.py`), and check the lens comes back.
//!
//! Two claims per run: (1) nothing is biased — every parameter is within 3 of OpenCV's own
//! standard deviations of the truth; (2) the target, every error below 0.5 %, where
//! this detector's noise allows it (the README's table has every camera and path; for k2
//! the standard deviation itself is near 0.5 % of the value, so a miss there is noise).

use crate::common;

use std::process::Command;

fn calibrate(camera: &str, path: &str, require_target: bool) {
    let have_cv2 = Command::new("python3")
        .args(["-c", "import cv2, numpy"])
        .status()
        .map(|s| s.success())
        .unwrap_or(false);
    assert!(
        have_cv2,
        "python3 with cv2 and numpy is needed: run scripts/bootstrap"
    );
    let case = common::reference_case(camera);
    let dir = std::env::temp_dir().join(format!(
        "vklens-calib-{camera}-{path}-{}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let cam_file = dir.join("camera.json");
    let json = serde_json::json!({
        "width": case.width, "height": case.height, "fx": case.fx, "fy": case.fy,
        "cx": case.cx, "cy": case.cy, "dist_coeffs": case.dist_coeffs,
    });
    std::fs::write(&cam_file, json.to_string()).unwrap();
    let out = dir.join("set");
    let o = Command::new(env!("CARGO_BIN_EXE_vklens"))
        .args([
            "calibration-set",
            "--camera",
            cam_file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--path",
            path,
        ])
        .env("VKLENS_VALIDATION", "1")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = Command::new("python3")
        .arg(format!(
            "{}/tests/calibrate.py",
            crate::common::root().display()
        ))
        .args([out.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    let r: serde_json::Value = serde_json::from_str(text.trim())
        .unwrap_or_else(|_| panic!("calibrate.py: {text}{}", String::from_utf8_lossy(&o.stderr)));
    println!("{camera} {path}: {r}");
    assert_eq!(r["views_used"], 17, "{r}");
    for p in r["parameters"].as_array().unwrap() {
        assert!(
            p["sigmas_off"].as_f64().unwrap() < 3.0,
            "{camera} {path}: biased {p}"
        );
        if require_target {
            assert!(
                p["error_percent"].as_f64().unwrap() < 0.5,
                "{camera} {path}: {p}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn seed_fig2_vertex_path_recovers_the_lens() {
    calibrate("seed_fig2", "vertex", true);
}

#[test]
fn seed_fig2_warp_path_is_unbiased() {
    calibrate("seed_fig2", "warp", false);
}

#[test]
fn seed_fig1_barrel_vertex_path_recovers_the_lens() {
    calibrate("seed_fig1_barrel", "vertex", true);
}

#[test]
fn seed_fig1_barrel_warp_path_recovers_the_lens() {
    calibrate("seed_fig1_barrel", "warp", true);
}

/// The same proof for OpenCV's fisheye model: a calibration set through a shared fisheye
/// camera, `tests/calibrate.py` with cv2.fisheye.calibrate; fx fy cx cy within 0.5 % and
/// k1..k4 within 0.005 absolute. Returns the report.
fn calibrate_fisheye(camera: &str, path: &str) -> serde_json::Value {
    let cam_file = common::shared_dir()
        .join("reference")
        .join("fisheye")
        .join(format!("{camera}.json"));
    let r = calibrate_file(&cam_file, camera, path);
    assert_eq!(r["model"], "opencv_fisheye", "{r}");
    r
}

/// Renders a calibration set through the camera file `cam_file`, runs `tests/calibrate.py`
/// on it (its mode follows the camera's model) and checks that at least 8 views were used and
/// every parameter the script gates passes (`"gated": false` rows are reported only).
/// Returns the report.
fn calibrate_file(cam_file: &std::path::Path, camera: &str, path: &str) -> serde_json::Value {
    let dir = std::env::temp_dir().join(format!(
        "vklens-calib-{camera}-{path}-{}",
        std::process::id()
    ));
    let out = dir.join("set");
    let o = Command::new(env!("CARGO_BIN_EXE_vklens"))
        .args(["calibration-set", "--camera"])
        .arg(cam_file)
        .arg("--out")
        .arg(&out)
        .args(["--path", path])
        .env("VKLENS_VALIDATION", "1")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = Command::new("python3")
        .arg(format!(
            "{}/tests/calibrate.py",
            crate::common::root().display()
        ))
        .arg(&out)
        .arg("--json")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    let r: serde_json::Value = serde_json::from_str(text.trim())
        .unwrap_or_else(|_| panic!("calibrate.py: {text}{}", String::from_utf8_lossy(&o.stderr)));
    println!("{camera} {path}: {r}");
    assert!(r["views_used"].as_u64().unwrap() >= 8, "{r}");
    for p in r["parameters"].as_array().unwrap() {
        if p["gated"].as_bool() != Some(false) {
            assert!(p["pass"].as_bool().unwrap(), "{camera} {path}: {p}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    r
}

/// Mei's unified omnidirectional model + radtan (`examples/cameras/omni.json`, 1024×768,
/// γ 820/816, ξ 0.95), calibrated with cv2.omnidir.calibrate: fx fy cx cy within 0.5 %, ξ
/// within 1 %, p1 p2 within 0.005; k1 k2 reported only (they trade with ξ, see
/// tests/calibrate.py). About 30 s (render ~25 s on lavapipe, calibration ~2 s).
///
/// Caveat: γ and ξ lie in a flat valley of the fit (the paraxial γ/(1 + ξ) is what the views
/// pin down, within 0.01 %), so this pass depends on this exact pose set: the same camera's
/// 21- and 25-view sets miss the ξ limit (1.6 %, 4.3 %). A driver whose renders move the corners
/// by a few thousandths of a pixel can flip it; the report's fx/(1+xi) rows tell noise from bias.
#[test]
fn omni_vertex_path_recovers_the_lens() {
    let cam_file = crate::common::root()
        .join("examples")
        .join("cameras")
        .join("omni.json");
    let r = calibrate_file(&cam_file, "omni", "vertex");
    assert_eq!(r["model"], "omni", "{r}");
    let names: Vec<&str> = r["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| p["gated"] == true)
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["fx", "fy", "cx", "cy", "xi", "p1", "p2"], "{r}");
}

#[test]
fn fish_wide160_vertex_path_recovers_the_fisheye() {
    calibrate_fisheye("fish_wide160", "vertex");
}

/// The other three of the four runs take minutes each on lavapipe (the cube path
/// renders six supersampled faces per view): run by hand with `--ignored`;
/// docs/accuracy.md has their figures.
#[test]
#[ignore]
fn fish_wide160_warp_path_recovers_the_fisheye() {
    calibrate_fisheye("fish_wide160", "warp");
}

#[test]
#[ignore]
fn fish_equidistant185_vertex_path_recovers_the_fisheye() {
    calibrate_fisheye("fish_equidistant185", "vertex");
}

#[test]
#[ignore]
fn fish_equidistant185_warp_path_recovers_the_fisheye() {
    calibrate_fisheye("fish_equidistant185", "warp");
}
