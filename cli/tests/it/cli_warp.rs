//! `vklens distort | undistort | precorrect | overscan` as scripts use them.

use std::path::{Path, PathBuf};

use crate::common;

use common::{shared_dir, vklens, write_png};
use image::ColorType;

fn tmp(name: &str) -> PathBuf {
    common::scratch("cliwarp", name)
}

fn cam(name: &str) -> String {
    shared_dir()
        .join("reference/calibration-files")
        .join(name)
        .display()
        .to_string()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn every_direction_writes_the_right_size_and_depth() {
    let fig2 = cam("seed_fig2.opencv4.yml");
    let three = format!(
        "{},{},{}",
        cam("seed_fig2.opencv.json"),
        fig2,
        cam("seed_fig2.opencv.xml")
    );
    let input8 = tmp("in8.png");
    let input16 = tmp("in16.png");
    write_png(&input8, 800, 600, false);
    write_png(&input16, 800, 600, true);
    for (cmd, extra) in [
        (
            "distort",
            vec!["--method", "lut", "--chromatic", "1.01,1,0.99"],
        ),
        (
            "distort",
            vec!["--method", "fixed-point:5", "--backend", "cpu"],
        ),
        ("undistort", vec![]),
        ("precorrect", vec!["--chromatic", "1.005,1,0.995"]),
        (
            "distort",
            vec!["--method", "lut", "--channel-cameras", &three],
        ),
    ] {
        for (input, depth) in [
            (&input8, image::ColorType::Rgba8),
            (&input16, image::ColorType::Rgba16),
        ] {
            let out = tmp(&format!("{cmd}.png"));
            let mask = tmp(&format!("{cmd}.mask.png"));
            let mut args = vec![
                cmd,
                "--camera",
                &fig2,
                "--input",
                s(input),
                "--output",
                s(&out),
                "--mask",
                s(&mask),
            ];
            args.extend(extra.iter());
            let r = vklens(&args);
            assert!(
                r.status.success(),
                "{args:?}: {}",
                String::from_utf8_lossy(&r.stderr)
            );
            let img = image::open(&out).unwrap();
            assert_eq!(
                (img.width(), img.height(), img.color()),
                (800, 600, depth),
                "{args:?}"
            );
            assert_eq!(image::open(&mask).unwrap().width(), 800);
        }
    }
    // EXR out.
    let exr = tmp("out.exr");
    let r = vklens(&[
        "undistort",
        "--camera",
        &fig2,
        "--input",
        s(&input16),
        "--output",
        s(&exr),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(matches!(
        image::open(&exr).unwrap().color(),
        ColorType::Rgb32F | ColorType::Rgba32F
    ));
}

#[test]
fn overscan_prints_a_camera_that_distort_accepts_as_source() {
    let fig1 = shared_dir().join("reference/calibration-files/seed_fig2.opencv.json");
    let r = vklens(&["overscan", "--camera", s(&fig1), "--density", "1.0"]);
    assert!(r.status.success());
    let json: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    let (w, h) = (
        json["width"].as_u64().unwrap() as u32,
        json["height"].as_u64().unwrap() as u32,
    );
    assert!(w > 800 && h > 600, "{json}");
    let src = tmp("src.json");
    std::fs::write(&src, r.stdout).unwrap();
    let input = tmp("over.png");
    write_png(&input, w, h, false);
    let (out, mask) = (tmp("over_out.png"), tmp("over_mask.png"));
    let r = vklens(&[
        "distort",
        "--camera",
        s(&fig1),
        "--source-camera",
        s(&src),
        "--input",
        s(&input),
        "--output",
        s(&out),
        "--mask",
        s(&mask),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    // With the overscanned source, no pixel of this fold-free lens is left unfilled.
    let m = image::open(&mask).unwrap().to_luma8();
    assert!(m.pixels().all(|p| p[0] == 255));
    // The pinhole image of CAM's own size is now the wrong size: said so, exit 2.
    let small = tmp("small.png");
    write_png(&small, 800, 600, false);
    let r = vklens(&[
        "distort",
        "--camera",
        s(&fig1),
        "--source-camera",
        s(&src),
        "--input",
        s(&small),
        "--output",
        s(&tmp("never.png")),
    ]);
    assert_eq!(r.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&r.stderr).contains("800×600"));
}

#[test]
fn bad_input_is_one_line_exit_2_and_leaves_no_file() {
    let fig2 = cam("seed_fig2.ros.yaml");
    let input = tmp("ok.png");
    write_png(&input, 800, 600, false);
    let jpeg = tmp("photo.jpg");
    std::fs::write(&jpeg, b"\xff\xd8\xff\xe0 not really a jpeg").unwrap();
    let nan_cam = tmp("nan.yml");
    std::fs::write(&nan_cam, "image_width: 800\nimage_height: 600\ncamera_matrix:\n  data: [400, 0, 399.5, 0, .Nan, 299.5, 0, 0, 1]\n").unwrap();
    let distorted_src = cam("seed_fig2.opencv.yml");
    let wide = cam("rational_wide.ros.yaml");
    let three_bad = format!("{fig2},{fig2},{fig2}");
    let out = tmp("must_not_exist.png");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec![
                "distort",
                "--camera",
                &fig2,
                "--input",
                "/no/such.png",
                "--output",
                s(&out),
            ],
            "/no/such.png",
        ),
        (
            vec![
                "distort",
                "--camera",
                &wide,
                "--input",
                s(&input),
                "--output",
                s(&out),
            ],
            "1920×1080",
        ),
        (
            vec![
                "distort",
                "--camera",
                &fig2,
                "--input",
                s(&jpeg),
                "--output",
                s(&out),
            ],
            "photo.jpg",
        ),
        (
            vec![
                "distort",
                "--camera",
                &fig2,
                "--input",
                s(&input),
                "--output",
                "/tmp/x.bmp",
            ],
            ".png or .exr",
        ),
        (
            vec![
                "distort",
                "--camera",
                &fig2,
                "--input",
                s(&input),
                "--output",
                "/no/such/dir/x.png",
            ],
            "does not exist",
        ),
        (
            vec![
                "distort",
                "--camera",
                s(&nan_cam),
                "--input",
                s(&input),
                "--output",
                s(&out),
            ],
            "NaN",
        ),
        (
            vec![
                "distort",
                "--camera",
                &fig2,
                "--source-camera",
                &distorted_src,
                "--input",
                s(&input),
                "--output",
                s(&out),
            ],
            "no distortion",
        ),
        (
            vec![
                "distort",
                "--camera",
                &fig2,
                "--input",
                s(&input),
                "--output",
                s(&out),
                "--chromatic",
                "1,1",
            ],
            "3 comma-separated",
        ),
        (
            vec![
                "distort",
                "--camera",
                &fig2,
                "--input",
                s(&input),
                "--output",
                s(&out),
                "--fill",
                "0,0,x,1",
            ],
            "not a number",
        ),
        (
            vec![
                "distort",
                "--camera",
                &fig2,
                "--input",
                s(&input),
                "--output",
                s(&out),
                "--method",
                "bogus",
            ],
            "bogus",
        ),
        (
            vec![
                "undistort",
                "--camera",
                &fig2,
                "--input",
                s(&input),
                "--output",
                s(&out),
                "--method",
                "heikkila",
            ],
            "forward model",
        ),
        (
            vec!["overscan", "--camera", &fig2, "--density", "0"],
            "density",
        ),
        (
            vec![
                "distort",
                "--camera",
                &fig2,
                "--input",
                s(&input),
                "--output",
                s(&out),
                "--channel-cameras",
                &fig2,
            ],
            "three camera files",
        ),
        (
            vec![
                "distort",
                "--camera",
                &fig2,
                "--input",
                s(&input),
                "--output",
                s(&out),
                "--channel-cameras",
                &three_bad,
            ],
            "the method must be lut (--method)",
        ),
    ];
    for (args, needle) in cases {
        let r = vklens(&args);
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!out.exists(), "{args:?} left an output behind");
    }
    // This test's own temporary files: the folder is shared with the module's other tests,
    // whose outputs are staged there while they run.
    let staged = format!(".{}.", out.file_name().unwrap().to_string_lossy());
    let leftovers: Vec<_> = std::fs::read_dir(out.parent().unwrap())
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(&staged) && n.contains("vklens-tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

/// The models of the table through the pinhole warp: a FOV lens distorted from its overscanned
/// pinhole source on the GPU agrees with the f64 reference warp within a grey level, and a
/// model without a pinhole focal length asks for the source camera.
#[test]
fn a_fov_lens_warps_on_the_gpu_as_the_f64_reference_and_ftheta_asks_for_a_source() {
    let lens = tmp("fov.json");
    std::fs::write(
        &lens,
        r#"{"model": "fov", "width": 320, "height": 240, "fx": 150, "fy": 151, "cx": 160.5, "cy": 120.2, "omega": 0.93}"#,
    )
    .unwrap();
    let r = vklens(&["overscan", "--camera", s(&lens)]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let json: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    let (w, h) = (
        json["width"].as_u64().unwrap() as u32,
        json["height"].as_u64().unwrap() as u32,
    );
    let src = tmp("fov_src.json");
    std::fs::write(&src, &r.stdout).unwrap();
    let input = tmp("fov_in.png");
    write_png(&input, w, h, false);
    let mut outs = Vec::new();
    for backend in ["gpu", "cpu"] {
        let out = tmp(&format!("fov_{backend}.png"));
        let r = vklens(&[
            "distort",
            "--camera",
            s(&lens),
            "--source-camera",
            s(&src),
            "--input",
            s(&input),
            "--output",
            s(&out),
            "--backend",
            backend,
        ]);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        outs.push(image::open(&out).unwrap().to_rgba8());
    }
    let worst = outs[0]
        .pixels()
        .zip(outs[1].pixels())
        .flat_map(|(a, b)| (0..4).map(move |c| (a[c] as i32 - b[c] as i32).abs()))
        .max()
        .unwrap();
    assert!(
        worst <= 1,
        "GPU and f64 warps differ by {worst} grey levels"
    );
    let ftheta = tmp("ftheta.json");
    std::fs::write(
        &ftheta,
        r#"{"model": "ftheta", "width": 320, "height": 240, "cx": 160, "cy": 120, "reference_poly": "ANGLE_TO_PIXELDIST", "angle_to_pixeldist_poly": [0, 150], "max_angle": 1.2}"#,
    )
    .unwrap();
    let r = vklens(&[
        "undistort",
        "--camera",
        s(&ftheta),
        "--input",
        s(&tmp("fov_cpu.png")),
        "--output",
        s(&tmp("never_ft.png")),
    ]);
    assert_eq!(r.status.code(), Some(2));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("ftheta") && err.contains("--source-camera"),
        "{err}"
    );
    assert!(!tmp("never_ft.png").exists());
}

#[test]
fn interpolation_and_border_run_alike_on_both_backends() {
    let fig2 = cam("seed_fig2.opencv4.yml");
    let input = tmp("filter_in.png");
    write_png(&input, 800, 600, false);
    let out = tmp("filter_out.png");
    let distort = |extra: &[&str]| {
        let mut args = vec![
            "distort",
            "--camera",
            &fig2,
            "--input",
            s(&input),
            "--output",
            s(&out),
        ];
        args.extend(extra);
        vklens(&args)
    };
    let run = |backend: &str, interpolation: &str, border: &str| {
        let mask = tmp("filter_out.mask.png");
        let r = distort(&[
            "--mask",
            s(&mask),
            "--backend",
            backend,
            "--interpolation",
            interpolation,
            "--border",
            border,
        ]);
        assert!(r.status.success(), "{}", common::stderr(&r));
        (
            image::open(&out).unwrap().to_rgba8(),
            image::open(&mask).unwrap().to_luma8(),
        )
    };
    for (interpolation, border) in [("bicubic", "reflect"), ("nearest", "replicate")] {
        let (gpu, gpu_mask) = run("gpu", interpolation, border);
        let (cpu, cpu_mask) = run("cpu", interpolation, border);
        // Every pixel of this barrel lens has a source position: off-frame ones read the border.
        assert!(gpu_mask.pixels().all(|m| m.0[0] == 255));
        assert!(cpu_mask.pixels().all(|m| m.0[0] == 255));
        let differ = gpu
            .pixels()
            .zip(cpu.pixels())
            .filter(|(a, b)| (0..4).any(|c| a.0[c].abs_diff(b.0[c]) > 1))
            .count();
        // Nearest may pick the other neighbour where f32 and f64 positions straddle a
        // half-pixel.
        assert!(
            differ < 800 * 600 / 1000,
            "{interpolation} {border}: {differ} px"
        );
    }
    // The constant border leaves the corners that see past the source unfilled.
    let (_, constant_mask) = run("gpu", "bicubic", "constant");
    assert!(constant_mask.pixels().filter(|m| m.0[0] == 0).count() > 800 * 600 / 100);
    // The older flag name still works; unknown values are named.
    let r = distort(&["--sampling", "nearest"]);
    assert!(r.status.success(), "{}", common::stderr(&r));
    for (flag, value, word) in [
        ("--border", "wrap", "unknown border `wrap`"),
        (
            "--interpolation",
            "lanczos",
            "unknown interpolation `lanczos`",
        ),
    ] {
        let r = distort(&[flag, value]);
        assert_eq!(r.status.code(), Some(2));
        assert!(common::stderr(&r).contains(word), "{}", common::stderr(&r));
    }
}
