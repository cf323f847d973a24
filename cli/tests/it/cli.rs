//! The `vklens` command line as other tools script it: JSON in, JSON out, exit codes.

use std::io::Write;
use std::process::{Command, Output, Stdio};

use crate::common;

use common::{load_reference, shared_dir};

fn vklens(args: &[&str], stdin: &str) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_vklens"))
        .args(args)
        .env("VKLENS_VALIDATION", "1")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run vklens");
    child.stdin.take().unwrap().write_all(stdin.as_bytes()).ok();
    child.wait_with_output().unwrap()
}

fn camera_file(name: &str) -> String {
    shared_dir()
        .join("reference/calibration-files")
        .join(name)
        .display()
        .to_string()
}

fn json(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "vklens failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is JSON")
}

#[test]
fn points_distort_and_undistort_match_the_reference_on_cpu_and_gpu() {
    let reference = load_reference();
    let case = reference
        .cases
        .iter()
        .find(|c| c.name == "seed_fig2")
        .unwrap();
    let ideal: Vec<[f64; 2]> = case
        .points
        .iter()
        .map(|p| p.undistorted_normalized)
        .collect();
    let pixels: Vec<[f64; 2]> = case.points.iter().map(|p| p.distorted_pixel).collect();
    let cam = camera_file("seed_fig2.opencv4.yml");
    for (backend, tol) in [("cpu", 1e-9), ("gpu", 2e-3)] {
        let out = json(&vklens(
            &["points", "distort", "--camera", &cam, "--backend", backend],
            &serde_json::to_string(&ideal).unwrap(),
        ));
        let got: Vec<[f64; 2]> = serde_json::from_value(out).unwrap();
        for (g, e) in got.iter().zip(&pixels) {
            assert!(
                (g[0] - e[0]).hypot(g[1] - e[1]) <= tol,
                "{backend}: {g:?} vs {e:?}"
            );
        }
    }
    for (backend, tol) in [("cpu", 1e-9), ("gpu", 1e-5)] {
        let out = json(&vklens(
            &[
                "points",
                "undistort",
                "--camera",
                &cam,
                "--backend",
                backend,
            ],
            &serde_json::to_string(&pixels).unwrap(),
        ));
        let got: Vec<[f64; 2]> = serde_json::from_value(out).unwrap();
        for (g, e) in got.iter().zip(&ideal) {
            assert!(
                (g[0] - e[0]).hypot(g[1] - e[1]) <= tol,
                "{backend}: {g:?} vs {e:?}"
            );
        }
    }
}

#[test]
fn undistort_writes_null_outside_the_valid_domain() {
    let cam = camera_file("rational_wide.ros.yaml");
    for args in [
        vec!["--method", "newton"],
        vec!["--method", "fixed-point:5", "--backend", "gpu"],
        vec!["--backend", "gpu", "--precision", "f64"],
    ] {
        let mut all = vec!["points", "undistort", "--camera", cam.as_str()];
        all.extend(args.iter());
        let out = json(&vklens(&all, "[[960, 540], [0, 0], [1919, 1079]]"));
        let arr = out.as_array().unwrap();
        assert_eq!(arr[0], serde_json::json!([0.0, 0.0]), "{args:?}");
        assert!(arr[1].is_null() && arr[2].is_null(), "{args:?}: {out}");
    }
}

#[test]
fn bad_input_gives_one_clear_line_and_exit_code_2() {
    let cam = camera_file("seed_fig2.ros.yaml");
    let cases: Vec<(Vec<&str>, &str, &str)> = vec![
        (
            vec!["points", "distort", "--camera", "/no/such/cam.json"],
            "[]",
            "/no/such/cam.json",
        ),
        (
            vec!["points", "distort", "--camera", &cam],
            "[[1, 2], [3]]",
            "element 1",
        ),
        (
            vec!["points", "distort", "--camera", &cam],
            "{\"a\": 1}",
            "JSON array",
        ),
        (
            vec!["points", "distort", "--camera", &cam],
            "[[1, 2",
            "not valid JSON",
        ),
        (
            vec![
                "points",
                "undistort",
                "--camera",
                &cam,
                "--method",
                "fixed-point:0",
            ],
            "[]",
            "fixed-point:0",
        ),
        (
            vec![
                "points",
                "undistort",
                "--camera",
                &cam,
                "--method",
                "bisection",
            ],
            "[]",
            "bisection",
        ),
    ];
    for (args, stdin, needle) in cases {
        let out = vklens(&args, stdin);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(out.stdout.is_empty());
    }
    let dir = std::env::temp_dir().join(format!("vklens-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.json");
    std::fs::write(&bad, r#"{"width": 8, "height": 8, "fx": 4, "fy": 4, "cx": 4, "cy": 4, "dist_coeffs": [0.1, 0.2, 0.3]}"#).unwrap();
    let out = vklens(
        &["points", "distort", "--camera", bad.to_str().unwrap()],
        "[]",
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2));
    assert!(err.contains("bad.json") && err.contains("has 3"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}

#[test]
fn demo_writes_a_png_of_the_camera_size_and_nothing_on_error() {
    let dir = std::env::temp_dir().join(format!("vklens-demo-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out_png = dir.join("grid.png");
    let cam = camera_file("rational_wide.opencv.xml");
    let out = vklens(
        &[
            "demo",
            "--camera",
            &cam,
            "--output",
            out_png.to_str().unwrap(),
        ],
        "",
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let img = image::open(&out_png).unwrap().to_rgba8();
    assert_eq!(img.dimensions(), (1920, 1080));
    // rational_wide folds over near the corners: those pixels are transparent, the centre not.
    assert_eq!(img.get_pixel(0, 0)[3], 0);
    assert_eq!(img.get_pixel(960, 540)[3], 255);
    let bad = dir.join("grid.jpg");
    let out = vklens(&["demo", "--output", bad.to_str().unwrap()], "");
    assert_eq!(out.status.code(), Some(2));
    assert!(!bad.exists());
    let missing_dir = dir.join("no/such/folder/grid.png");
    let out = vklens(&["demo", "--output", missing_dir.to_str().unwrap()], "");
    assert_eq!(out.status.code(), Some(2));
    assert!(std::fs::read_dir(&dir).unwrap().all(|e| !e
        .unwrap()
        .file_name()
        .to_string_lossy()
        .contains("vklens-tmp")));
}

#[test]
fn help_teaches() {
    let out = vklens(&["--help"], "");
    let text = String::from_utf8_lossy(&out.stdout);
    for needle in ["points", "bench", "demo", "VKLENS_DEVICE", "Examples"] {
        assert!(text.contains(needle), "--help lacks {needle}");
    }
    let out = vklens(&["points", "undistort", "--help"], "");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("fixed-point:N") && text.contains("null"));
}

/// The exit code follows the error's kind, in every command: 2 for what the user can fix
/// (bad input, a path that cannot be used, work the device cannot do), 1 for the rest (the
/// mapping itself, kind by kind, is a unit test of `cli::exit_code`).
#[test]
fn exit_codes_follow_the_error_kind() {
    let dir = std::env::temp_dir().join(format!("vklens-exit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let expect = |args: &[&str], code: i32, needle: &str| {
        let out = vklens(args, "");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
    };
    // A bad camera file (a key out of range): bad input.
    let cam = dir.join("negative_fx.json");
    std::fs::write(&cam, r#"{"width": 64, "height": 48, "fx": -40, "fy": 40, "cx": 32, "cy": 24, "dist_coeffs": [0, 0, 0, 0]}"#).unwrap();
    expect(&["overscan", "--camera", &s(&cam)], 2, "negative_fx.json");
    // A bad scene key.
    let scene = dir.join("bad.toml");
    std::fs::write(
        &scene,
        "[geometry]\nscene = \"boxes\"\n[optics]\ncamera = \"x.json\"\n[effects]\nwobble = true\n",
    )
    .unwrap();
    expect(
        &["render", "--scene", &s(&scene), "--out", &s(&dir)],
        2,
        "wobble",
    );
    // An output that cannot be written (its folder does not exist), in two commands.
    let good = camera_file("seed_fig2.opencv4.yml");
    let nowhere = dir.join("no/such/folder/out.png");
    expect(
        &["demo", "--camera", &good, "--output", &s(&nowhere)],
        2,
        "does not exist",
    );
    let input = dir.join("in.png");
    image::RgbaImage::new(800, 600).save(&input).unwrap();
    expect(
        &[
            "distort",
            "--camera",
            &good,
            "--input",
            &s(&input),
            "--output",
            &s(&nowhere),
        ],
        2,
        "does not exist",
    );
    // An image over the device's limit: unsupported, named before any work.
    let wide = dir.join("wide.json");
    std::fs::write(&wide, r#"{"width": 40000, "height": 8, "fx": 4000, "fy": 4000, "cx": 20000, "cy": 4, "dist_coeffs": [0.01, 0, 0, 0]}"#).unwrap();
    let wide_in = dir.join("wide.png");
    image::GrayImage::new(40000, 8).save(&wide_in).unwrap();
    expect(
        &[
            "distort",
            "--camera",
            &s(&wide),
            "--input",
            &s(&wide_in),
            "--output",
            &s(&dir.join("o.png")),
        ],
        2,
        "px per side",
    );
    assert!(!dir.join("o.png").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A stdout that cannot be written (a pipe whose reader quit, a full disk) is an I/O error,
/// exit 1, one line: never a panic. /dev/full fails every write, without the race of closing
/// a pipe before the command writes.
#[test]
fn a_closed_stdout_is_an_error_not_a_panic() {
    let cam = camera_file("seed_fig2.opencv.yml");
    let lens = crate::common::root().join("lenses/dgauss.50mm.dat");
    for args in [
        vec!["overscan", "--camera", cam.as_str()],
        vec!["lens", "info", "--lens", lens.to_str().unwrap()],
    ] {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .expect("/dev/full");
        let out = Command::new(env!("CARGO_BIN_EXE_vklens"))
            .args(&args)
            .stdout(Stdio::from(full))
            .stderr(Stdio::piped())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.contains("<stdout>") && !err.contains("panicked"),
            "{args:?}: {err}"
        );
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
    }
}
