//! OpenCV's fisheye model on the CPU, against `../shared/reference/fisheye/`: every camera file
//! form loads to the exact parameters, the forward model matches `cv2.fisheye.projectPoints`
//! below 90° and the atan2 formula past it, the inverse recovers every direction of the
//! domain and answers "invalid" exactly outside it.

use crate::io::camera::{load_camera_at, parse_camera};
use crate::io::load_camera;
use crate::io::reference::shared_dir;
use crate::model::{Camera, CameraModel, InverseMethod};
use glam::{DVec2, DVec3};
use serde_json::Value;

fn dir() -> std::path::PathBuf {
    shared_dir().join("reference").join("fisheye")
}

fn index() -> Value {
    let text = std::fs::read_to_string(dir().join("index.json")).expect("fisheye/index.json");
    serde_json::from_str(&text).expect("valid JSON")
}

fn points(cam: &Value) -> Value {
    let path = dir().join(cam["points"].as_str().expect("points"));
    serde_json::from_str(&std::fs::read_to_string(path).expect("points file")).expect("JSON")
}

fn rows<const N: usize>(v: &Value) -> Vec<[f64; N]> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|r| {
            let r: Vec<f64> = r
                .as_array()
                .expect("row")
                .iter()
                .map(|x| x.as_f64().expect("number"))
                .collect();
            r.try_into().expect("row length")
        })
        .collect()
}

fn json_camera(cam: &Value) -> Camera {
    load_camera(&dir().join(format!("{}.json", cam["name"].as_str().unwrap())))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// The angle between two directions, accurate for tiny angles too (`acos` of the dot product
/// is not: it resolves no better than 1e-8 rad).
fn angle(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

fn f(v: &Value) -> f64 {
    v.as_f64().expect("number")
}

#[test]
fn every_fisheye_file_form_loads_to_the_exact_parameters() {
    let mut loaded = 0;
    for cam in index()["cameras"].as_array().expect("cameras") {
        for file in cam["files"].as_array().expect("files") {
            let path = dir().join(file["path"].as_str().unwrap());
            let got = load_camera(&path).unwrap_or_else(|e| panic!("{e}"));
            let what = path.display().to_string();
            assert_eq!(got.model_name(), "opencv_fisheye", "{what}");
            assert_eq!(got.width as f64, f(&cam["width"]), "{what}");
            assert_eq!(got.height as f64, f(&cam["height"]), "{what}");
            let k = got.intrinsics;
            // COLMAP's cx, cy are written + 0.5: the loader's − 0.5 is one rounding.
            let tol = if file["form"] == "colmap-cameras-txt" {
                1e-12
            } else {
                0.0
            };
            for (name, v) in [("fx", k.fx), ("fy", k.fy), ("cx", k.cx), ("cy", k.cy)] {
                assert!((v - f(&cam[name])).abs() <= tol, "{what} {name}: {v}");
            }
            let lens = got.fisheye_lens().expect("a fisheye");
            for (i, c) in cam["dist_coeffs"].as_array().unwrap().iter().enumerate() {
                assert_eq!(lens.k[i], f(c), "{what} k{}", i + 1);
            }
            // ROS carries α as K[0][1] = α fx, written with 5 decimals.
            let alpha = f(&cam["alpha"]);
            assert!(
                (lens.alpha - alpha).abs() <= 1e-9,
                "{what} alpha {}",
                lens.alpha
            );
            loaded += 1;
        }
    }
    assert_eq!(loaded, 14);
}

#[test]
fn a_kalibr_camchain_gives_the_camera_asked_for() {
    let idx = index();
    let cam = &idx["cameras"][0];
    let file = &cam["files"][2];
    assert_eq!(file["form"], "kalibr-camchain");
    let path = dir().join(file["path"].as_str().unwrap());
    let other = &file["cam1_is_a_different_camera"];
    let cam1 = load_camera_at(&path, Some(1)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(cam1.intrinsics.fx, f(&other["fx"]));
    assert_eq!(cam1.intrinsics.cy, f(&other["cy"]));
    assert_eq!(cam1.fisheye_lens().unwrap().k[3], f(&other["k"][3]));
    let e = load_camera_at(&path, Some(2)).unwrap_err().to_string();
    assert!(
        e.contains("camera index 2") && e.contains("0: cam0, 1: cam1"),
        "{e}"
    );
    assert!(e.contains("camchain-imucam.yaml"), "{e}");
    // A file of one camera refuses another index.
    let json = dir().join(format!("{}.json", cam["name"].as_str().unwrap()));
    let e = load_camera_at(&json, Some(1)).unwrap_err().to_string();
    assert!(e.contains("holds one camera"), "{e}");
}

#[test]
fn forward_matches_opencv_below_90_degrees_and_the_atan2_formula_past_it() {
    for cam in index()["cameras"].as_array().unwrap() {
        let camera = json_camera(cam);
        let pts = points(cam);
        let name = cam["name"].as_str().unwrap();
        let inside = &pts["inside"];
        for (p, want) in rows::<3>(&inside["xyz"])
            .iter()
            .zip(rows::<2>(&inside["pixel"]))
        {
            let got = camera
                .project(DVec3::from_array(*p))
                .expect("in the domain");
            let err = (got - DVec2::from_array(want)).length();
            assert!(err <= 1e-9, "{name} {p:?}: {err:e} px from cv2.fisheye");
        }
        // The same points as normalized coordinates (X/Z, Y/Z) through the 2D forward.
        for (x, want) in rows::<2>(&inside["normalized"])
            .iter()
            .zip(rows::<2>(&inside["pixel"]))
        {
            let got = camera.distort_pixel(camera.intrinsics.to_pixel(DVec2::from_array(*x)));
            let err = (got.expect("defined") - DVec2::from_array(want)).length();
            assert!(err <= 1e-9, "{name} {x:?}: {err:e} px");
        }
        let beyond = &pts["beyond90"];
        let xyz = rows::<3>(&beyond["xyz"]);
        let opencv = rows::<2>(&beyond["opencv_pixel"]);
        for ((p, want), cv) in xyz.iter().zip(rows::<2>(&beyond["pixel"])).zip(&opencv) {
            let p = DVec3::from_array(*p);
            let got = camera.project(p).expect("past 90° but in the domain");
            let err = (got - DVec2::from_array(want)).length();
            assert!(err <= 1e-9, "{name} {p}: {err:e} px from the formula");
            // OpenCV's atan(r / Z) mirrors a point behind the image plane: its answer is the
            // mirror image's, nowhere near the true one.
            assert!((DVec2::from_array(*cv) - got).length() > 1.0, "{name} {p}");
            if p.z < 0.0 {
                let mirrored = camera.project(-p).expect("mirror in front");
                let err = (mirrored - DVec2::from_array(*cv)).length();
                assert!(
                    err <= 1e-6,
                    "{name} {p}: OpenCV is not the mirror ({err:e})"
                );
            }
        }
        let outside = &pts["beyond_max_fov"];
        for p in rows::<3>(&outside["xyz"]) {
            assert_eq!(camera.project(DVec3::from_array(p)), None, "{name} {p:?}");
        }
    }
}

#[test]
fn the_inverse_recovers_every_direction_and_refuses_past_the_domain() {
    for cam in index()["cameras"].as_array().unwrap() {
        let camera = json_camera(cam);
        let pts = points(cam);
        let name = cam["name"].as_str().unwrap();
        let fx = camera.intrinsics.fx;
        for part in ["inside", "beyond90"] {
            let set = &pts[part];
            for (p, px) in rows::<3>(&set["xyz"]).iter().zip(rows::<2>(&set["pixel"])) {
                let truth = DVec3::from_array(*p).normalize();
                let ray = camera
                    .unproject(DVec2::from_array(px))
                    .expect("in the domain");
                // An angle error of ε moves the pixel by about fx·ε (dθ_d/dθ ≈ 1).
                let err_px = angle(ray, truth) * fx;
                assert!(err_px <= 1e-6, "{name} {part} {p:?}: {err_px:e} px");
                assert!((ray.length() - 1.0).abs() < 1e-12);
            }
        }
        // Inside θ < 90°, the pinhole-side inverse (normalized X/Z, Y/Z) agrees.
        let inside = &pts["inside"];
        for (x, px) in rows::<2>(&inside["normalized"])
            .iter()
            .zip(rows::<2>(&inside["pixel"]))
        {
            let got = camera
                .undistort_pixel(DVec2::from_array(px), InverseMethod::Newton)
                .expect("valid");
            let err = (got - camera.intrinsics.to_pixel(DVec2::from_array(*x))).length();
            assert!(err <= 1e-6, "{name} {x:?}: {err:e} px");
        }
        for px in rows::<2>(&pts["beyond_fold_pixels"]) {
            assert_eq!(
                camera.unproject(DVec2::from_array(px)),
                None,
                "{name} past the fold"
            );
        }
        // Past max_fov_deg: invalid, or the true preimage (the reference allows both).
        let outside = &pts["beyond_max_fov"];
        for (p, px) in rows::<3>(&outside["xyz"])
            .iter()
            .zip(rows::<2>(&outside["pixel"]))
        {
            if let Some(ray) = camera.unproject(DVec2::from_array(px)) {
                assert!(angle(ray, DVec3::from_array(*p)) * fx <= 1e-6, "{name}");
            }
        }
    }
}

#[test]
fn the_domain_ends_at_the_fold_or_the_field_of_view() {
    for cam in index()["cameras"].as_array().unwrap() {
        let camera = json_camera(cam);
        let lens = camera.fisheye_lens().unwrap();
        let name = cam["name"].as_str().unwrap();
        let got = lens.theta_max().to_degrees();
        let want = match (
            cam["json_max_fov_deg"].as_f64(),
            cam["fold_theta_deg"].as_f64(),
        ) {
            (Some(fov), fold) => (fov / 2.0).min(fold.unwrap_or(180.0)),
            (None, Some(fold)) => fold,
            (None, None) => 180.0,
        };
        assert!((got - want).abs() < 1e-6, "{name}: θ_max {got}° vs {want}°");
        assert_eq!(
            lens.folds(),
            cam["json_max_fov_deg"].is_null() && !cam["fold_theta_deg"].is_null()
        );
        // θ_d increases up to θ_max and stops just past a fold.
        let (_, slope) = lens.theta_d(lens.theta_max());
        assert!(slope > 0.0, "{name}");
        if lens.folds() {
            assert!(lens.theta_d(lens.theta_max() + 1e-6).1 <= 0.0, "{name}");
        }
        // A direction just past θ_max has no pixel, one just inside has.
        let t = lens.theta_max();
        let at = |t: f64| DVec3::new(t.sin(), 0.0, t.cos());
        assert!(camera.project(at(t - 1e-6)).is_some(), "{name}");
        assert!(
            t >= std::f64::consts::PI || camera.project(at(t + 1e-6)).is_none(),
            "{name}"
        );
    }
}

#[test]
fn the_jacobian_is_the_derivative_of_the_forward_model() {
    for cam in index()["cameras"].as_array().unwrap() {
        let camera = json_camera(cam);
        for x in [
            DVec2::new(0.0, 0.0),
            DVec2::new(1e-10, -2e-10),
            DVec2::new(0.3, -0.2),
            DVec2::new(-1.5, 2.0),
            DVec2::new(4.0, 0.5),
        ] {
            let j = camera.jacobian_normalized(x).expect("defined");
            let h = 1e-6;
            for (col, e) in [(0, DVec2::X), (1, DVec2::Y)] {
                let d = (camera.distort_normalized(x + e * h).unwrap()
                    - camera.distort_normalized(x - e * h).unwrap())
                    / (2.0 * h);
                let err = (j.col(col) - d).length();
                assert!(
                    err < 1e-7,
                    "{} at {x}: column {col} off by {err:e}",
                    cam["name"]
                );
            }
        }
    }
}

#[test]
fn a_fisheye_camera_round_trips_through_vklens_json() {
    for cam in index()["cameras"].as_array().unwrap() {
        let camera = json_camera(cam);
        let text = camera.to_json().to_string();
        let again = parse_camera(&text, "round trip").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(again.to_json(), camera.to_json());
        assert_eq!(again.fisheye_lens(), camera.fisheye_lens());
    }
}

#[test]
fn a_colmap_camera_and_its_opencv_twin_see_a_point_at_the_same_pixel() {
    let twins = [
        (
            "1 OPENCV 800 600 500 510 400.5 300.5 -0.1 0.01 0.001 -0.002",
            r#"{"width": 800, "height": 600, "fx": 500, "fy": 510, "cx": 400, "cy": 300, "dist_coeffs": [-0.1, 0.01, 0.001, -0.002]}"#,
        ),
        (
            "# Camera list\n1 SIMPLE_RADIAL 640 480 400 320 240 -0.05",
            r#"{"width": 640, "height": 480, "fx": 400, "fy": 400, "cx": 319.5, "cy": 239.5, "dist_coeffs": [-0.05, 0, 0, 0]}"#,
        ),
        (
            "1 OPENCV_FISHEYE 752 480 218.62 218.84 377.31 242.57 -0.004261 0.027391 -0.018524 0.003926",
            r#"{"model": "opencv_fisheye", "width": 752, "height": 480, "fx": 218.62, "fy": 218.84, "cx": 376.81, "cy": 242.07, "dist_coeffs": [-0.004261, 0.027391, -0.018524, 0.003926]}"#,
        ),
        (
            "1 FULL_OPENCV 800 600 500 500 400 300 -0.1 0.01 0 0 0.001 0.01 0 0",
            r#"{"width": 800, "height": 600, "fx": 500, "fy": 500, "cx": 399.5, "cy": 299.5, "dist_coeffs": [-0.1, 0.01, 0, 0, 0.001, 0.01, 0, 0]}"#,
        ),
    ];
    let p = DVec3::new(0.3, -0.2, 1.0);
    for (colmap, opencv) in twins {
        let a = parse_camera(colmap, "cameras.txt").unwrap_or_else(|e| panic!("{e}"));
        let b = parse_camera(opencv, "twin.json").unwrap_or_else(|e| panic!("{e}"));
        let (pa, pb) = (a.project(p).unwrap(), b.project(p).unwrap());
        assert!((pa - pb).length() < 1e-12, "{colmap}: {pa} vs {pb}");
    }
}

#[test]
fn malformed_fisheye_files_name_the_file_and_the_key() {
    let cases: [(&str, &str, &[&str]); 10] = [
        (
            r#"{"model": "opencv_fisheye", "width": 800, "height": 600, "fx": 300, "fy": 300, "cx": 400, "cy": 300, "dist_coeffs": [0.1, 0.0, 0.0]}"#,
            "cam.json",
            &["cam.json", "dist_coeffs", "4 coefficients", "has 3"],
        ),
        (
            r#"{"model": "opencv_fisheye", "width": 800, "height": 600, "fx": 300, "fy": 300, "cx": 400, "cy": 300, "dist_coeffs": [0, 0, 0, 0], "max_fov_deg": 400}"#,
            "cam.json",
            &["cam.json", "max_fov_deg", "400"],
        ),
        (
            r#"{"model": "opencv_fisheye", "width": 800, "height": 600, "fx": 300, "fy": 300, "cx": 400, "cy": 300, "dist_coeffs": [0, "x", 0, 0]}"#,
            "cam.json",
            &["cam.json", "dist_coeffs`[1]"],
        ),
        (
            r#"{"model": "opencv_fisheye", "width": 800, "height": 600, "fx": 300, "fy": 300, "cx": 400, "cy": 300, "dist_coeffs": [0, 0, 0, 0], "alpha": 3}"#,
            "cam.json",
            &["cam.json", "alpha", "3"],
        ),
        (
            "image_width: 800\nimage_height: 600\ndistortion_model: equidistant\ncamera_matrix: {rows: 3, cols: 3, data: [300, 0, 400, 0, 300, 300, 0, 0, 1]}\ndistortion_coefficients: {rows: 1, cols: 5, data: [0, 0, 0, 0, 0]}\n",
            "ros.yaml",
            &["ros.yaml", "distortion_coefficients", "4 coefficients"],
        ),
        (
            "cam0:\n  camera_model: omni\n  distortion_model: equidistant\n  distortion_coeffs: [0, 0, 0, 0]\n  intrinsics: [1, 300, 300, 400, 300]\n  resolution: [800, 600]\n",
            "camchain.yaml",
            &["camchain.yaml", "cam0.distortion_model", "equidistant", "omni"],
        ),
        (
            "cam0:\n  camera_model: unified\n  intrinsics: [1, 300, 300, 400, 300]\n  resolution: [800, 600]\n",
            "camchain.yaml",
            &["camchain.yaml", "cam0.camera_model", "unified"],
        ),
        (
            "cam0:\n  camera_model: pinhole\n  distortion_model: equidistant\n  distortion_coeffs: [0, 0, 0]\n  intrinsics: [300, 300, 400, 300]\n  resolution: [800, 600]\n",
            "camchain.yaml",
            &["camchain.yaml", "cam0.distortion_coeffs", "4 numbers"],
        ),
        (
            "# Camera list\n1 OPENCV_FISHEYE 800 600 300 300 400 300 0 0 0\n",
            "cameras.txt",
            &["cameras.txt", "line 2", "OPENCV_FISHEYE", "k4"],
        ),
        (
            "1 THIN_PRISM_FISHEYE 800 600 300 300 400 300 0 0 0 0 0 0 0 0 0 0 0 0\n",
            "cameras.txt",
            &["cameras.txt", "line 1", "THIN_PRISM_FISHEYE"],
        ),
    ];
    for (text, origin, needles) in cases {
        let e = parse_camera(text, origin).unwrap_err().to_string();
        for n in needles {
            assert!(e.contains(n), "{origin}: `{e}` lacks `{n}`");
        }
        assert_eq!(e.lines().count(), 1, "{e}");
    }
}

#[test]
fn ros_camera_info_carries_every_camera_ros_can_describe() {
    let mut cameras: Vec<Camera> = index()["cameras"]
        .as_array()
        .unwrap()
        .iter()
        .map(json_camera)
        .collect();
    let standard = |coeffs: &[f64]| {
        parse_camera(
            &serde_json::json!({"width": 800, "height": 600, "fx": 500.5, "fy": 501.25,
                "cx": 399.5, "cy": 300.25, "dist_coeffs": coeffs})
            .to_string(),
            "std.json",
        )
        .unwrap()
    };
    cameras.push(standard(&[-0.1, 0.02, 0.001, -0.002, 0.003]));
    cameras.push(standard(&[
        -0.1, 0.02, 0.001, -0.002, 0.003, 0.01, 0.002, 0.0001,
    ]));
    for camera in &cameras {
        let text = camera.to_ros_camera_info().unwrap();
        let back =
            parse_camera(&text, "camera_info.yaml").unwrap_or_else(|e| panic!("{e}\n{text}"));
        assert_eq!(back.model_name(), camera.model_name());
        for p in [DVec3::new(0.2, -0.1, 1.0), DVec3::new(-0.7, 0.4, 0.5)] {
            let (a, b) = (camera.project(p).unwrap(), back.project(p).unwrap());
            assert!((a - b).length() < 1e-9, "{text}: {a} vs {b}");
        }
    }
    // Thin prism and tilt terms have no place in camera_info: said, not dropped.
    let prism = standard(&[
        -0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.001, 0.0, 0.0, 0.0,
    ]);
    let e = prism.to_ros_camera_info().unwrap_err().to_string();
    assert!(e.contains("thin prism"), "{e}");
}

#[test]
fn a_huge_finite_point_lands_on_the_90_degree_circle_not_the_principal_point() {
    let cam = &index()["cameras"][1];
    let camera = json_camera(cam);
    let lens = *camera.fisheye_lens().unwrap();
    let d = camera
        .distort_normalized(DVec2::new(1e200, 0.0))
        .expect("finite");
    let want = lens.theta_d(std::f64::consts::FRAC_PI_2).0;
    assert!((d.x - want).abs() < 1e-12 && d.y == 0.0, "{d}");
}
