//! `vklens new-camera` and `vklens undistort --alpha | --balance` as scripts use them: the
//! camera the library's OpenCV rules choose, printed as vklens JSON with its ROI, and used as
//! the undistorted image's camera; refusals exit 2 naming the flag.

use std::path::{Path, PathBuf};
use std::process::Output;

use crate::common;

use common::{shared_dir, stderr, vklens};
use vklens::{fisheye_new_camera, optimal_new_camera, Camera};

fn tmp(name: &str) -> PathBuf {
    common::scratch("newcam", name)
}

fn write_png(path: &Path, w: u32, h: u32) {
    common::write_png(path, w, h, false);
}

fn reference(path: &str) -> String {
    shared_dir()
        .join("reference")
        .join(path)
        .display()
        .to_string()
}

/// The printed `{"camera", "roi"}`, the camera read back through vklens's own camera reader.
fn printed(r: &Output) -> (Camera, [u32; 4]) {
    assert!(r.status.success(), "{}", stderr(r));
    let json: serde_json::Value = serde_json::from_slice(&r.stdout).expect("stdout is JSON");
    let camera = Camera::parse(&json["camera"].to_string(), "new-camera output").unwrap();
    let roi: [u32; 4] = serde_json::from_value(json["roi"].clone()).unwrap();
    (camera, roi)
}

fn same_camera(a: &Camera, b: &Camera) {
    assert!(a.is_pinhole() && b.is_pinhole());
    assert_eq!((a.width, a.height), (b.width, b.height));
    let (p, q) = (a.intrinsics, b.intrinsics);
    for (x, y) in [(p.fx, q.fx), (p.fy, q.fy), (p.cx, q.cx), (p.cy, q.cy)] {
        // JSON carries f64 exactly (shortest round-trip text).
        assert_eq!(x, y, "{p:?} vs {q:?}");
    }
}

#[test]
fn new_camera_prints_the_rules_camera_and_roi() {
    let cam = reference("calibration-files/seed_fig2.opencv4.yml");
    let lens = Camera::load(&cam).unwrap();
    for alpha in ["0", "0.5", "1"] {
        for (size, centred) in [(None, false), (Some("1024x512"), false), (None, true)] {
            let mut args = vec!["new-camera", "--camera", &cam, "--alpha", alpha];
            if let Some(s) = size {
                args.extend(["--new-size", s]);
            }
            if centred {
                args.push("--center-principal-point");
            }
            let (got, roi) = printed(&vklens(&args));
            let (want, want_roi) = optimal_new_camera(
                &lens,
                alpha.parse().unwrap(),
                size.map(|_| (1024, 512)),
                centred,
            )
            .unwrap();
            same_camera(&got, &want);
            assert_eq!(
                roi,
                [want_roi.0, want_roi.1, want_roi.2, want_roi.3],
                "{args:?}"
            );
        }
    }
    let fish = reference("fisheye/fish_wide160.json");
    let lens = Camera::load(&fish).unwrap();
    for (balance, fov_scale, size) in [
        ("0", None, None),
        ("1", Some("1.5"), None),
        ("0.25", None, Some("800x600")),
    ] {
        let mut args = vec!["new-camera", "--camera", &fish, "--balance", balance];
        if let Some(f) = fov_scale {
            args.extend(["--fov-scale", f]);
        }
        if let Some(s) = size {
            args.extend(["--new-size", s]);
        }
        let (got, roi) = printed(&vklens(&args));
        let (want, want_roi) = fisheye_new_camera(
            &lens,
            balance.parse().unwrap(),
            fov_scale.map_or(1.0, |f| f.parse().unwrap()),
            size.map(|_| (800, 600)),
        )
        .unwrap();
        same_camera(&got, &want);
        assert_eq!(
            roi,
            [want_roi.0, want_roi.1, want_roi.2, want_roi.3],
            "{args:?}"
        );
    }
}

#[test]
fn undistort_draws_into_the_chosen_camera_and_says_so() {
    let cam = reference("calibration-files/seed_fig2.opencv4.yml");
    let input = tmp("fig2.png");
    write_png(&input, 800, 600);
    let (out, mask) = (tmp("alpha.png"), tmp("alpha_mask.png"));
    let r = vklens(&[
        "undistort",
        "--camera",
        &cam,
        "--input",
        input.to_str().unwrap(),
        "--output",
        out.to_str().unwrap(),
        "--mask",
        mask.to_str().unwrap(),
        "--backend",
        "cpu",
        "--alpha",
        "1",
        "--new-size",
        "400x300",
    ]);
    assert!(r.status.success(), "{}", stderr(&r));
    let err = stderr(&r);
    assert!(
        err.contains("getOptimalNewCameraMatrix") && err.contains("400×300"),
        "{err}"
    );
    let img = image::open(&out).unwrap();
    assert_eq!((img.width(), img.height()), (400, 300));
    // The camera new-camera prints for the same flags has a source in every pixel of its ROI
    // but the outermost ring (OpenCV rounds the ROI's edges to the nearest pixel, and the warp
    // needs both bilinear taps inside the image).
    let (_, [x, y, w, h]) = printed(&vklens(&[
        "new-camera",
        "--camera",
        &cam,
        "--alpha",
        "1",
        "--new-size",
        "400x300",
    ]));
    assert!(w > 300 && h > 200, "{:?}", [x, y, w, h]);
    let m = image::open(&mask).unwrap().to_luma8();
    for py in y + 1..y + h - 1 {
        for px in x + 1..x + w - 1 {
            assert_eq!(
                m.get_pixel(px, py)[0],
                255,
                "ROI pixel ({px}, {py}) has no source"
            );
        }
    }
    // alpha 1 keeps every source pixel: the corners of the new image have none.
    assert_eq!(m.get_pixel(0, 0)[0], 0);
    // Without a rule the output camera is said too.
    let r = vklens(&[
        "undistort",
        "--camera",
        &cam,
        "--input",
        input.to_str().unwrap(),
        "--output",
        out.to_str().unwrap(),
        "--backend",
        "cpu",
    ]);
    assert!(r.status.success(), "{}", stderr(&r));
    assert!(stderr(&r).contains("output camera"), "{}", stderr(&r));
}

#[test]
fn refusals_exit_2_naming_the_flag() {
    let cam = reference("calibration-files/seed_fig2.opencv4.yml");
    let fish = reference("fisheye/fish_wide160.json");
    let input = tmp("refuse.png");
    write_png(&input, 800, 600);
    let out = tmp("never.png");
    let (i, o) = (input.to_str().unwrap(), out.to_str().unwrap());
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["new-camera", "--camera", &cam, "--alpha", "1.5"],
            "--alpha",
        ),
        (
            vec!["new-camera", "--camera", &cam, "--alpha", "NaN"],
            "--alpha",
        ),
        (
            vec!["new-camera", "--camera", &cam, "--balance", "0.5"],
            "--balance",
        ),
        (
            vec!["new-camera", "--camera", &fish, "--alpha", "0.5"],
            "--alpha",
        ),
        (
            vec![
                "new-camera",
                "--camera",
                &fish,
                "--balance",
                "0.5",
                "--fov-scale",
                "0",
            ],
            "--fov-scale",
        ),
        (
            vec![
                "new-camera",
                "--camera",
                &cam,
                "--alpha",
                "0",
                "--balance",
                "0",
            ],
            "--balance",
        ),
        (
            vec!["new-camera", "--camera", &cam, "--fov-scale", "2"],
            "--balance",
        ),
        (
            vec![
                "new-camera",
                "--camera",
                &fish,
                "--balance",
                "0",
                "--center-principal-point",
            ],
            "--center-principal-point",
        ),
        (
            vec![
                "new-camera",
                "--camera",
                &cam,
                "--alpha",
                "0",
                "--new-size",
                "0x10",
            ],
            "--new-size",
        ),
        (vec!["new-camera", "--camera", &cam], "--alpha"),
        (
            vec![
                "undistort",
                "--camera",
                &cam,
                "--input",
                i,
                "--output",
                o,
                "--alpha",
                "0",
                "--source-camera",
                &cam,
            ],
            "--source-camera",
        ),
        (
            vec![
                "distort", "--camera", &cam, "--input", i, "--output", o, "--alpha", "0",
            ],
            "--alpha",
        ),
        (
            vec![
                "undistort",
                "--camera",
                &cam,
                "--input",
                i,
                "--output",
                o,
                "--new-size",
                "10x10",
            ],
            "--new-size",
        ),
    ];
    for (args, flag) in cases {
        let r = vklens(&args);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {}", stderr(&r));
        assert!(stderr(&r).contains(flag), "{args:?}: {}", stderr(&r));
        assert!(r.stdout.is_empty(), "{args:?}");
    }
    assert!(!out.exists());
}

#[test]
fn help_teaches_both_rules() {
    let r = vklens(&["new-camera", "--help"]);
    assert!(r.status.success());
    let text = String::from_utf8_lossy(&r.stdout);
    for word in [
        "getOptimalNewCameraMatrix",
        "estimateNewCameraMatrixForUndistortRectify",
        "--alpha",
        "--balance",
        "--fov-scale",
        "--new-size",
        "--center-principal-point",
        "roi",
    ] {
        assert!(
            text.contains(word),
            "new-camera --help lacks {word}:\n{text}"
        );
    }
    let r = vklens(&["undistort", "--help"]);
    let text = String::from_utf8_lossy(&r.stdout);
    assert!(
        text.contains("--alpha") && text.contains("--balance"),
        "{text}"
    );
}

#[test]
fn a_camera_info_that_rectifies_needs_no_rectification_with_a_rule() {
    // OpenCV's rules choose the camera for R = identity: a camera_info with a rotation R (a
    // stereo pair's) is refused with them unless --no-rectification says to undistort with K
    // alone.
    let ros = std::fs::read_to_string(reference("calibration-files/seed_fig2.ros.yaml")).unwrap();
    let (c, s) = (0.05f64.cos(), 0.05f64.sin());
    let rotated = ros.replace(
        "data: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]",
        &format!("data: [{c}, 0.0, {s}, 0.0, 1.0, 0.0, {}, 0.0, {c}]", -s),
    );
    assert_ne!(ros, rotated);
    let cam = tmp("stereo_left.yaml");
    std::fs::write(&cam, rotated).unwrap();
    let input = tmp("stereo.png");
    write_png(&input, 800, 600);
    let out = tmp("stereo_out.png");
    let mut args = vec![
        "undistort",
        "--camera",
        cam.to_str().unwrap(),
        "--input",
        input.to_str().unwrap(),
        "--output",
        out.to_str().unwrap(),
        "--backend",
        "cpu",
        "--alpha",
        "0",
    ];
    let r = vklens(&args);
    assert_eq!(r.status.code(), Some(2), "{}", stderr(&r));
    assert!(stderr(&r).contains("--no-rectification"), "{}", stderr(&r));
    assert!(!out.exists());
    args.push("--no-rectification");
    let r = vklens(&args);
    assert!(r.status.success(), "{}", stderr(&r));
    assert!(
        stderr(&r).contains("getOptimalNewCameraMatrix"),
        "{}",
        stderr(&r)
    );
}
