//! OpenCV's fisheye model in the shaders (`glsl/include/camera_model.glsl`, f32 and f64)
//! against `cv2.fisheye.projectPoints` and the f64 model, under validation.

use crate::host::points::{run_points, run_project, run_unproject};
use crate::io::load_camera;
use crate::io::reference::shared_dir;
use crate::model::{Camera, InverseMethod};
use crate::pass::{PointsMode, Precision};
use glam::{DVec2, DVec3};
use serde_json::Value;

fn dir() -> std::path::PathBuf {
    shared_dir().join("reference").join("fisheye")
}

/// Every reference camera with its points file.
fn cases() -> Vec<(String, Camera, Value)> {
    let index: Value =
        serde_json::from_str(&std::fs::read_to_string(dir().join("index.json")).expect("index"))
            .expect("JSON");
    index["cameras"]
        .as_array()
        .expect("cameras")
        .iter()
        .map(|c| {
            let name = c["name"].as_str().expect("name").to_string();
            let camera = load_camera(&dir().join(format!("{name}.json"))).expect("camera");
            let points =
                std::fs::read_to_string(dir().join(c["points"].as_str().unwrap())).expect("points");
            (name, camera, serde_json::from_str(&points).expect("JSON"))
        })
        .collect()
}

fn rows<const N: usize>(v: &Value) -> Vec<[f64; N]> {
    serde_json::from_value::<Vec<Vec<f64>>>(v.clone())
        .expect("rows")
        .into_iter()
        .map(|r| r.try_into().expect("row length"))
        .collect()
}

fn angle(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

#[test]
fn gpu_forward_within_2e3_px_of_opencv_and_the_formula() {
    let ctx = crate::testing::validated_context();
    for (name, camera, pts) in cases() {
        let inside = &pts["inside"];
        let want = rows::<2>(&inside["pixel"]);
        let got = run_points(
            ctx,
            &camera,
            PointsMode::Distort,
            Precision::F32,
            &rows::<2>(&inside["normalized"]),
        )
        .expect("gpu run");
        let mut worst = 0.0_f64;
        for (g, w) in got.iter().zip(&want) {
            let g = g.expect("defined below 90°");
            worst = worst.max((DVec2::from(g) - DVec2::from(*w)).length());
        }
        // Camera-frame points, past 90° too.
        let mut xyz = rows::<3>(&inside["xyz"]);
        xyz.extend(rows::<3>(&pts["beyond90"]["xyz"]));
        let mut want3 = want.clone();
        want3.extend(rows::<2>(&pts["beyond90"]["pixel"]));
        let got3 = run_project(ctx, &camera, Precision::F32, &xyz).expect("gpu run");
        for (g, w) in got3.iter().zip(&want3) {
            let g = g.expect("in the domain");
            worst = worst.max((DVec2::from(g) - DVec2::from(*w)).length());
        }
        println!("{name}: GPU forward max error {worst:.2e} px");
        assert!(worst <= 2e-3, "{name}: {worst} px");
        let outside = rows::<3>(&pts["beyond_max_fov"]["xyz"]);
        let refused = run_project(ctx, &camera, Precision::F32, &outside).expect("gpu run");
        assert!(
            refused.iter().all(Option::is_none),
            "{name}: past the field of view"
        );
    }
    crate::testing::assert_no_validation_messages(ctx);
}

#[test]
fn gpu_inverse_within_1e3_px_of_the_model_and_invalid_outside_the_domain() {
    let ctx = crate::testing::validated_context();
    for (name, camera, pts) in cases() {
        let mut pixels = rows::<2>(&pts["inside"]["pixel"]);
        pixels.extend(rows::<2>(&pts["beyond90"]["pixel"]));
        // A grid over the image too: every pixel the CPU model calls valid.
        let (w, h) = (camera.width as f64, camera.height as f64);
        for j in 0..=24 {
            for i in 0..=32 {
                pixels.push([i as f64 / 32.0 * (w - 1.0), j as f64 / 24.0 * (h - 1.0)]);
            }
        }
        for precision in [Precision::F32, Precision::F64] {
            if precision == Precision::F64 && !ctx.gpu().supports_float64() {
                continue;
            }
            let rays = run_unproject(ctx, &camera, precision, &pixels).expect("gpu run");
            let mut worst = 0.0_f64;
            for (p, got) in pixels.iter().zip(&rays) {
                let want = camera.unproject(DVec2::from(*p));
                match (want, got) {
                    (Some(w), Some(g)) => {
                        // Against the forward model: the f64 pixel of the GPU's ray (next to
                        // a fold an angle error is magnified, the pixel error is not).
                        let back = camera.project(DVec3::from(*g)).expect("in the domain");
                        worst = worst.max((back - DVec2::from(*p)).length());
                        assert!(angle(w, DVec3::from(*g)) < 1e-2, "{name} {p:?}");
                    }
                    (None, None) => {}
                    (w, g) => panic!("{name} {precision} {p:?}: CPU {w:?}, GPU {g:?}"),
                }
            }
            println!("{name} {precision}: GPU inverse max error {worst:.2e} px");
            let bound = if precision == Precision::F32 {
                1e-3
            } else {
                1e-9
            };
            assert!(worst <= bound, "{name} {precision}: {worst} px");
            let fold = rows::<2>(&pts["beyond_fold_pixels"]);
            let past = run_unproject(ctx, &camera, precision, &fold).expect("gpu run");
            assert!(past.iter().all(Option::is_none), "{name}: past the fold");
        }
        // The pinhole-side inverse (normalized X/Z, Y/Z) agrees with the CPU below 90°.
        let inside = rows::<2>(&pts["inside"]["pixel"]);
        let got = run_points(
            ctx,
            &camera,
            PointsMode::Undistort(InverseMethod::Newton),
            Precision::F32,
            &inside,
        )
        .expect("gpu run");
        for (p, g) in inside.iter().zip(&got) {
            let want = camera
                .undistort_normalized(
                    camera.intrinsics.to_normalized(DVec2::from(*p)),
                    InverseMethod::Newton,
                )
                .expect("valid");
            let g = DVec2::from(g.expect("valid on the GPU"));
            // In pixels of the ideal image: normalized error × f, relative to the radius
            // (tan θ grows fast near 85°).
            let err = (g - want).length() * camera.intrinsics.fx / (1.0 + want.length_squared());
            assert!(err <= 1e-3, "{name} {p:?}: {err:e}");
        }
    }
    crate::testing::assert_no_validation_messages(ctx);
}

#[test]
fn the_standard_models_inverses_are_refused_for_a_fisheye() {
    let ctx = crate::testing::validated_context();
    let (_, camera, _) = cases().remove(0);
    for method in [InverseMethod::Heikkila, InverseMethod::FixedPoint(5)] {
        let e = run_points(
            ctx,
            &camera,
            PointsMode::Undistort(method),
            Precision::F32,
            &[[1.0, 2.0]],
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("fisheye") && e.contains("newton"), "{e}");
    }
    crate::testing::assert_no_validation_messages(ctx);
}
