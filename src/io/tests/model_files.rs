//! The models of the table from the tools' own files: each layout loads to exactly the camera
//! its vklens JSON twin describes (same model, same pixels), and malformed files are refused
//! naming the file and the key. The files are small ones written here, in each tool's layout.

use crate::io::camera::parse_camera_at;
use crate::model::Camera;
use glam::DVec3;

fn load(text: &str, origin: &str, index: Option<usize>) -> Camera {
    parse_camera_at(text, origin, index).unwrap_or_else(|e| panic!("{origin}: {e}"))
}

fn refused(text: &str, origin: &str) -> String {
    parse_camera_at(text, origin, None)
        .map(|c| panic!("{origin} loaded as {}", c.model_name()))
        .unwrap_err()
        .to_string()
}

/// Same model and the same pixel for points all around, past 90° too.
fn same(a: &Camera, b: &Camera, what: &str) {
    assert_eq!(a.model_name(), b.model_name(), "{what}");
    assert_eq!((a.width, a.height), (b.width, b.height), "{what}");
    for p in [
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(0.3, -0.2, 1.0),
        DVec3::new(-1.0, 0.4, 0.3),
        DVec3::new(0.8, 0.7, -0.2),
    ] {
        assert_eq!(a.project(p), b.project(p), "{what} at {p:?}");
    }
}

#[test]
fn kalibr_omni_eucm_ds_and_fov_cameras_load_as_their_twins() {
    let omni = load(
        r#"{"model": "omni", "width": 1024, "height": 768, "fx": 820, "fy": 816, "cx": 514.5, "cy": 381.5, "xi": 0.95, "dist_coeffs": [-0.05, 0.02, 0.0006, -0.0004]}"#,
        "omni.json",
        None,
    );
    let chain = "cam0:\n  camera_model: pinhole\n  intrinsics: [400, 400, 320, 240]\n  distortion_model: radtan\n  distortion_coeffs: [0, 0, 0, 0]\n  resolution: [640, 480]\ncam1:\n  camera_model: omni\n  intrinsics: [0.95, 820.0, 816.0, 514.5, 381.5]\n  distortion_model: radtan\n  distortion_coeffs: [-0.05, 0.02, 0.0006, -0.0004]\n  resolution: [1024, 768]\ncam2:\n  camera_model: eucm\n  intrinsics: [0.63, 1.04, 460.8, 459.7, 365.9, 249.8]\n  distortion_model: none\n  distortion_coeffs: []\n  resolution: [752, 480]\ncam3:\n  camera_model: ds\n  intrinsics: [-0.2, 0.57, 349.7, 348.9, 365.8, 249.9]\n  distortion_model: none\n  resolution: [752, 480]\ncam4:\n  camera_model: pinhole\n  intrinsics: [300, 302, 370.5, 240.2]\n  distortion_model: fov\n  distortion_coeffs: [0.93]\n  resolution: [752, 480]\n";
    same(
        &load(chain, "camchain.yaml", Some(1)),
        &omni,
        "Kalibr omni-radtan",
    );
    same(
        &load(chain, "camchain.yaml", Some(2)),
        &load(
            r#"{"model": "eucm", "width": 752, "height": 480, "fx": 460.8, "fy": 459.7, "cx": 365.9, "cy": 249.8, "alpha": 0.63, "beta": 1.04}"#,
            "eucm.json",
            None,
        ),
        "Kalibr eucm",
    );
    same(
        &load(chain, "camchain.yaml", Some(3)),
        &load(
            r#"{"model": "double_sphere", "width": 752, "height": 480, "fx": 349.7, "fy": 348.9, "cx": 365.8, "cy": 249.9, "xi": -0.2, "alpha": 0.57}"#,
            "ds.json",
            None,
        ),
        "Kalibr ds",
    );
    same(
        &load(chain, "camchain.yaml", Some(4)),
        &load(
            r#"{"model": "fov", "width": 752, "height": 480, "fx": 300, "fy": 302, "cx": 370.5, "cy": 240.2, "omega": 0.93}"#,
            "fov.json",
            None,
        ),
        "Kalibr pinhole-fov",
    );
    // A pair Kalibr does not have is refused, naming both keys.
    let e = refused(
        "cam0:\n  camera_model: ds\n  intrinsics: [-0.2, 0.57, 349.7, 348.9, 365.8, 249.9]\n  distortion_model: radtan\n  distortion_coeffs: [0, 0, 0, 0]\n  resolution: [752, 480]\n",
        "camchain.yaml",
    );
    assert!(
        e.contains("camchain.yaml") && e.contains("cam0.distortion_model") && e.contains("ds"),
        "{e}"
    );
}

#[test]
fn basalt_and_camodocal_files_load_as_their_twins() {
    let basalt = r#"{"value0": {"T_imu_cam": [], "intrinsics": [
        {"camera_type": "ds", "intrinsics": {"fx": 349.7, "fy": 348.9, "cx": 365.8, "cy": 249.9, "xi": -0.2, "alpha": 0.57}},
        {"camera_type": "eucm", "intrinsics": {"fx": 460.8, "fy": 459.7, "cx": 365.9, "cy": 249.8, "alpha": 0.63, "beta": 1.04}},
        {"camera_type": "ucm", "intrinsics": {"fx": 349.0, "fy": 348.5, "cx": 365.0, "cy": 249.0, "alpha": 0.62}},
        {"camera_type": "kb4", "intrinsics": {"fx": 190.9, "fy": 190.9, "cx": 254.9, "cy": 256.9, "k1": -0.013, "k2": 0.017, "k3": -0.012, "k4": 0.003}}],
        "resolution": [[752, 480], [752, 480], [752, 480], [512, 512]]}}"#;
    same(
        &load(basalt, "calib.json", None),
        &load(
            r#"{"model": "double_sphere", "width": 752, "height": 480, "fx": 349.7, "fy": 348.9, "cx": 365.8, "cy": 249.9, "xi": -0.2, "alpha": 0.57}"#,
            "ds.json",
            None,
        ),
        "Basalt ds",
    );
    same(
        &load(basalt, "calib.json", Some(2)),
        &load(
            r#"{"model": "ucm", "width": 752, "height": 480, "fx": 349.0, "fy": 348.5, "cx": 365.0, "cy": 249.0, "alpha": 0.62}"#,
            "ucm.json",
            None,
        ),
        "Basalt ucm",
    );
    let kb4 = load(basalt, "calib.json", Some(3));
    assert_eq!(kb4.model_name(), "opencv_fisheye");
    assert_eq!(kb4.dist_coeffs(), vec![-0.013, 0.017, -0.012, 0.003]);
    let e = parse_camera_at(basalt, "calib.json", Some(7))
        .unwrap_err()
        .to_string();
    assert!(e.contains("calib.json") && e.contains("4 camera"), "{e}");

    let mei = "%YAML:1.0\n---\nmodel_type: MEI\ncamera_name: camera\nimage_width: 1024\nimage_height: 768\nmirror_parameters:\n   xi: 0.95\ndistortion_parameters:\n   k1: -0.05\n   k2: 0.02\n   p1: 0.0006\n   p2: -0.0004\nprojection_parameters:\n   gamma1: 820.0\n   gamma2: 816.0\n   u0: 514.5\n   v0: 381.5\n";
    same(
        &load(mei, "cam.yaml", None),
        &load(
            r#"{"model": "omni", "width": 1024, "height": 768, "fx": 820, "fy": 816, "cx": 514.5, "cy": 381.5, "xi": 0.95, "dist_coeffs": [-0.05, 0.02, 0.0006, -0.0004]}"#,
            "omni.json",
            None,
        ),
        "camodocal MEI",
    );
    let e = refused(
        "%YAML:1.0\n---\nmodel_type: SCARAMUZZA\nimage_width: 640\nimage_height: 480\n",
        "cam.yaml",
    );
    // SCARAMUZZA (camodocal's OCamCalib) is read; without its parameters the error names the
    // format it was read as and the missing mapping.
    assert!(
        e.contains("cam.yaml") && e.contains("camodocal") && e.contains("_parameters"),
        "{e}"
    );
    let e = refused(
        "%YAML:1.0\n---\nmodel_type: MEI\nimage_width: 1024\nimage_height: 768\nmirror_parameters:\n   xi: 0.95\n",
        "cam.yaml",
    );
    assert!(
        e.contains("distortion_parameters") || e.contains("projection_parameters"),
        "{e}"
    );
}

#[test]
fn every_colmap_model_reads_from_cameras_txt_as_from_colmap_json() {
    let cases: [(&str, &str); 7] = [
        ("FOV", "300 302 371 240.7 0.93"),
        ("SIMPLE_DIVISION", "420 375.7 239.6 -0.35"),
        ("DIVISION", "420 421 375.7 239.6 0.08"),
        ("SIMPLE_FISHEYE", "240 376 240"),
        ("EUCM", "460.8 459.7 366.4 250.3 0.63 1.04"),
        ("EQUIRECTANGULAR", "752 480"),
        (
            "RAD_TAN_THIN_PRISM_FISHEYE",
            "241 241 375.6 241.1 0.025 -0.016 0.003 0.001 -5e-4 6e-5 3e-4 -1e-4 2e-4 -1e-5 1e-4 2e-5",
        ),
    ];
    for (model, params) in cases {
        let txt = load(
            &format!("# Camera list\n7 {model} 752 480 {params}\n"),
            "cameras.txt",
            None,
        );
        let list: Vec<&str> = params.split(' ').collect();
        let json = load(
            &format!(
                r#"{{"model": "colmap", "colmap_model": "{model}", "width": 752, "height": 480, "params": [{}]}}"#,
                list.join(", ")
            ),
            "colmap.json",
            None,
        );
        same(&txt, &json, model);
    }
    // The wrong number of parameters for the model is refused, never padded or cut.
    let e = refused("1 DIVISION 752 480 420 421 375.7 239.6\n", "cameras.txt");
    assert!(
        e.contains("cameras.txt") && e.contains("line 1") && e.contains("DIVISION has 5"),
        "{e}"
    );
    let e = refused(
        r#"{"model": "colmap", "colmap_model": "PINHOLE_X", "width": 752, "height": 480, "params": [1, 2, 3, 4]}"#,
        "colmap.json",
    );
    assert!(e.contains("PINHOLE_X"), "{e}");
}

/// `fitted_inverse: true` in a camera's JSON selects the file's fit of the inverse (the
/// sample cameras' fitted twins project the same), is written back, and is refused where the
/// file carries no fit or the key is not a boolean.
#[test]
fn fitted_inverse_reads_and_writes_in_vklens_json() {
    use crate::io::models::camera_to_json;
    use crate::model::samples::{fitted_inverse_cameras, sample_cameras};
    let exact: Vec<_> = sample_cameras().expect("samples");
    for (name, fitted) in fitted_inverse_cameras().expect("fitted") {
        let (_, plain) = exact
            .iter()
            .find(|(n, _)| format!("{n}_fitted") == name)
            .expect("its exact twin");
        let mut json = camera_to_json(plain).expect("json");
        assert!(
            json.get("fitted_inverse").is_none(),
            "{name}: the default is not written"
        );
        json["fitted_inverse"] = true.into();
        let text = json.to_string();
        let loaded = load(&text, "fitted.json", None);
        same(&loaded, &fitted, name);
        assert_eq!(
            camera_to_json(&loaded).expect("json")["fitted_inverse"],
            true
        );
        json["fitted_inverse"] = "yes".into();
        let err = refused(&json.to_string(), "fitted.json");
        assert!(
            err.contains("fitted_inverse") && err.contains("fitted.json"),
            "{err}"
        );
    }
    let no_fit = r#"{"model": "ocam", "width": 640, "height": 480, "cx": 320, "cy": 240,
        "poly": [-250.0, 0.0, 0.001], "c": 1, "d": 0, "e": 0, "fitted_inverse": true}"#;
    let err = refused(no_fit, "ocam.json");
    assert!(err.contains("inverse_poly"), "{err}");
}
