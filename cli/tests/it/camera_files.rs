//! Every calibration file in `../shared/reference/calibration-files/` loads and equals the
//! camera `index.json` says it holds; bad files give one clear error naming the problem.

use crate::common;

use common::shared_dir;
use vklens::Camera;

#[test]
fn every_shared_calibration_file_loads_with_the_true_parameters() {
    let dir = shared_dir().join("reference").join("calibration-files");
    let index: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("index.json")).expect("index.json"))
            .expect("valid JSON");
    let mut loaded = 0;
    for cam in index["cameras"].as_array().expect("cameras") {
        let truth: Vec<f64> = cam["dist_coeffs"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        for file in cam["files"].as_array().expect("files") {
            let path = dir.join(file.as_str().unwrap());
            let got = Camera::load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(
                got.width as u64,
                cam["width"].as_u64().unwrap(),
                "{}",
                path.display()
            );
            assert_eq!(got.height as u64, cam["height"].as_u64().unwrap());
            for (name, v) in [
                ("fx", got.intrinsics.fx),
                ("fy", got.intrinsics.fy),
                ("cx", got.intrinsics.cx),
                ("cy", got.intrinsics.cy),
            ] {
                assert_eq!(v, cam[name].as_f64().unwrap(), "{} {name}", path.display());
            }
            let coeffs = got.distortion().to_coeffs();
            for (i, t) in truth.iter().enumerate() {
                assert!(
                    (coeffs[i] - t).abs() <= 1e-15,
                    "{} coefficient {i}: {} vs {t}",
                    path.display(),
                    coeffs[i]
                );
            }
            assert!(coeffs[truth.len()..].iter().all(|&c| c == 0.0));
            loaded += 1;
        }
    }
    assert_eq!(loaded, 14);
}

#[test]
fn reference_cases_are_camera_files_as_they_stand() {
    let text = std::fs::read_to_string(common::reference_path()).expect("reference");
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    for case in v["cases"].as_array().unwrap() {
        let cam = Camera::parse(&case.to_string(), "opencv_standard_model.json")
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(cam.distortion().to_coeffs().len(), 14);
    }
}

fn err(text: &str) -> String {
    Camera::parse(text, "cam.json")
        .expect_err("must be refused")
        .to_string()
}

#[test]
fn bad_camera_files_name_the_file_the_field_and_the_value() {
    let base = r#""width": 800, "height": 600, "fx": 400, "fy": 400, "cx": 399.5, "cy": 299.5"#;
    let e = err(&format!("{{{base}, \"dist_coeffs\": [0.1, 0.2, 0.3]}}"));
    assert!(
        e.starts_with("cam.json: ") && e.contains("4, 5, 8, 12 or 14") && e.contains('3'),
        "{e}"
    );
    let e = err(r#"{"width": 800, "height": 600, "fx": -4, "fy": 400, "cx": 1, "cy": 1}"#);
    assert!(e.contains("fx") && e.contains("-4"), "{e}");
    let e = err(r#"{"width": 800, "height": 600, "fx": "abc", "fy": 400, "cx": 1, "cy": 1}"#);
    assert!(e.contains("fx") && e.contains("abc"), "{e}");
    let e = err(r#"{"width": 0, "height": 600, "fx": 4, "fy": 400, "cx": 1, "cy": 1}"#);
    assert!(e.contains("width"), "{e}");
    let e = err(r#"{"width": 800.5, "height": 600, "fx": 4, "fy": 400, "cx": 1, "cy": 1}"#);
    assert!(e.contains("width") && e.contains("800.5"), "{e}");
    let e = err(&format!("{{{base}, \"dist_coeffs\": [1e300, 0, 0, 0]}}"));
    assert!(e.contains("k1") && e.contains("absurd"), "{e}");
    let e = err(&format!(
        "{{{base}, \"dist_coeffs\": [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1.6, 0]}}"
    ));
    assert!(e.contains("tau_x"), "{e}");
    let e = err("{\"width\": 8");
    assert!(e.contains("invalid JSON"), "{e}");
    let e = err(r#"{"height": 600, "fx": 4, "fy": 400, "cx": 1, "cy": 1}"#);
    assert!(e.contains("missing") && e.contains("width"), "{e}");
    // NaN in YAML (FileStorage writes .Nan).
    let e = Camera::parse(
        "image_width: 8\nimage_height: 8\ncamera_matrix:\n  data: [.Nan, 0, 4, 0, 4, 4, 0, 0, 1]\n",
        "cam.yml",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("fx") && e.contains("NaN"), "{e}");
    // Skewed camera matrices are refused rather than silently mis-read.
    let e = Camera::parse(
        "image_width: 8\nimage_height: 8\ncamera_matrix:\n  data: [4, 0.5, 4, 0, 4, 4, 0, 0, 1]\n",
        "cam.yml",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("skew"), "{e}");
    let e = Camera::parse(
        "image_width: 8\nimage_height: 8\ndistortion_model: equidistant\ncamera_matrix:\n  data: [4, 0, 4, 0, 4, 4, 0, 0, 1]\n",
        "cam.yaml",
    )
    .unwrap_err()
    .to_string();
    assert!(e.starts_with("cam.yaml: ") && e.contains("k1..k4"), "{e}");
    let e = Camera::parse("<opencv_storage><image_width>8</image_width>", "cam.xml")
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("cam.xml: invalid XML"), "{e}");
}

#[test]
fn missing_distortion_means_a_pinhole() {
    let cam = Camera::parse(
        r#"{"width": 8, "height": 8, "fx": 4, "fy": 4, "cx": 3.5, "cy": 3.5}"#,
        "p.json",
    )
    .unwrap();
    assert_eq!(cam.distortion().to_coeffs(), [0.0; 14]);
}

/// Hostile camera files are refused quickly, naming the limit: a YAML "billion laughs" (730
/// bytes that expand to a billion nodes) and an endless file.
#[test]
fn alias_bombs_and_endless_files_are_refused_with_the_limit() {
    let dir = std::env::temp_dir().join(format!("vklens-hostile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut bomb =
        String::from("a: &a [\"x\",\"x\",\"x\",\"x\",\"x\",\"x\",\"x\",\"x\",\"x\",\"x\"]\n");
    for (prev, name) in "abcdefgh".chars().zip("bcdefghi".chars()) {
        let refs = vec![format!("*{prev}"); 10].join(",");
        bomb.push_str(&format!("{name}: &{name} [{refs}]\n"));
    }
    let path = dir.join("bomb.yaml");
    std::fs::write(&path, &bomb).unwrap();
    let start = std::time::Instant::now();
    let e = vklens::Camera::load(&path).unwrap_err();
    assert!(
        start.elapsed().as_secs_f64() < 5.0,
        "took {:?}",
        start.elapsed()
    );
    assert_eq!(e.kind(), vklens::ErrorKind::Input);
    assert!(
        e.to_string().contains("bomb.yaml") && e.to_string().contains("100000"),
        "{e}"
    );
    let e = vklens::Camera::load("/dev/zero").unwrap_err();
    assert!(e.to_string().contains("VKLENS_MAX_FILE_MB"), "{e}");
    // The command line refuses it alike, with the exit code of input the user can fix.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_vklens"))
        .args(["overscan", "--camera", "/dev/zero"])
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// 50,000 nested elements are refused with the limit, not a stack overflow.
#[test]
fn deeply_nested_xml_is_refused_not_a_crash() {
    let text = format!(
        "<opencv_storage>{}{}</opencv_storage>",
        "<a>".repeat(50_000),
        "</a>".repeat(50_000)
    );
    let e = vklens::Camera::parse(&text, "deep.xml").unwrap_err();
    assert_eq!(e.kind(), vklens::ErrorKind::Input);
    assert!(
        e.to_string().contains("deep.xml") && e.to_string().contains("64"),
        "{e}"
    );
}

/// A focal length no lens can mean (1e-308 px) is refused by every command alike, naming it.
#[test]
fn a_vanishing_focal_length_is_refused() {
    let k = [[1e-308, 0.0, 32.0], [0.0, 40.0, 24.0], [0.0, 0.0, 1.0]];
    let e = vklens::Camera::from_opencv(k, &[0.1, 0.0, 0.0, 0.0], (64, 48)).unwrap_err();
    assert_eq!(e.kind(), vklens::ErrorKind::Input);
    assert!(e.to_string().contains("`fx` = 1e-308"), "{e}");
    let e = vklens::Camera::parse(
        r#"{"width": 64, "height": 48, "fx": 40, "fy": 1e-308, "cx": 32, "cy": 24}"#,
        "tiny.json",
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("tiny.json") && e.to_string().contains("`fy`"),
        "{e}"
    );
}

/// A JSON camera that gives one key twice is refused, naming the key (a parser that keeps the
/// last would let a file say two things about one parameter).
#[test]
fn duplicate_json_keys_are_refused() {
    let e = vklens::Camera::parse(
        r#"{"width": 64, "height": 48, "fx": 40, "fx": 4000, "fy": 40, "cx": 32, "cy": 24}"#,
        "dup.json",
    )
    .unwrap_err();
    assert_eq!(e.kind(), vklens::ErrorKind::Input);
    assert!(
        e.to_string().contains("dup.json") && e.to_string().contains("`fx` appears twice"),
        "{e}"
    );
}

#[test]
fn an_unknown_camera_model_is_refused_naming_it() {
    // A model read as another would put its pixels far off (a fisheye's k1..k4 as k1 k2 p1 p2:
    // 9.5e5 px): the one vklens does not know is refused by name.
    let e = err(
        r#"{"model": "omnidirectional", "width": 640, "height": 480, "fx": 300, "fy": 300,
            "cx": 319.5, "cy": 239.5, "dist_coeffs": [0.1, 0.01, 0.0, 0.0]}"#,
    );
    assert!(
        e.contains("`model`") && e.contains("omnidirectional"),
        "{e}"
    );
    assert!(
        e.contains("opencv_fisheye"),
        "the models it reads are listed: {e}"
    );
    let e =
        err(r#"{"model": 3, "width": 640, "height": 480, "fx": 300, "fy": 300, "cx": 1, "cy": 1}"#);
    assert!(e.contains("`model` must be a string"), "{e}");
    // The standard model may say so.
    let cam = vklens::Camera::parse(
        r#"{"model": "opencv", "width": 640, "height": 480, "fx": 300, "fy": 300,
            "cx": 319.5, "cy": 239.5, "dist_coeffs": [0.1, 0.01, 0.0, 0.0]}"#,
        "camera.json",
    )
    .unwrap();
    assert_eq!(cam.dist_coeffs(), vec![0.1, 0.01, 0.0, 0.0]);
}

#[test]
fn a_broken_json_file_is_reported_as_json() {
    // Missing its opening brace: YAML would accept the first line and then complain in YAML.
    let e = Camera::parse(r#""width": 640, "height": 480, "fx": 300}"#, "camera.json")
        .expect_err("must be refused")
        .to_string();
    assert!(e.starts_with("camera.json: invalid JSON"), "{e}");
}
