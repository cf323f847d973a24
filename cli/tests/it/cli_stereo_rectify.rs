//! `vklens stereo-rectify` as scripts use it: each way of giving the pair (a stereo file, a
//! Kalibr camchain, two camera files with R and T, an extrinsics file), the camera_info files
//! it writes holding the library's R and P beside the lens's K and D, the rectified pair equal
//! to what `vklens undistort` draws from those files, and refusals that exit 2 naming the
//! file, key or flag and leave nothing written.

use std::path::{Path, PathBuf};

use crate::common;

use common::{stderr, vklens};
use vklens::{stereo_rectify, Camera, StereoOptions, StereoRectification};

fn tmp(name: &str) -> PathBuf {
    common::scratch("stereo", name)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A fresh, empty output folder (not made: the command makes it).
fn out_dir(name: &str) -> PathBuf {
    let dir = tmp(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

const LEFT: &str = r#"{"width": 640, "height": 480, "fx": 600.0, "fy": 610.0, "cx": 330.25,
    "cy": 236.5, "dist_coeffs": [-0.05, 0.01, 0.001, -0.0015, 0.0]}"#;
const RIGHT: &str = r#"{"width": 640, "height": 480, "fx": 605.0, "fy": 603.0, "cx": 322.25,
    "cy": 240.125, "dist_coeffs": [-0.06, 0.012, -0.0005, 0.001, 0.0]}"#;

/// X2 = R X1 + T: R as a Rodrigues vector, and its matrix row by row.
const RVEC: [f64; 3] = [0.01, -0.02, 0.005];
const T: [f64; 3] = [-0.12, 0.003, 0.001];

fn rotation_matrix(v: [f64; 3]) -> [[f64; 3]; 3] {
    let theta = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let k = v.map(|x| x / theta);
    let (s, c) = theta.sin_cos();
    let cross = [[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]];
    std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let id = if i == j { 1.0 } else { 0.0 };
            c * id + (1.0 - c) * k[i] * k[j] + s * cross[i][j]
        })
    })
}

fn list(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x:?}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The pair as cv2.stereoCalibrate scripts write it (FileStorage YAML, K1 D1 K2 D2 R T).
fn stereo_file(name: &str, r: Option<[[f64; 3]; 3]>, t: Option<[f64; 3]>) -> PathBuf {
    let mut text = "%YAML:1.0\n---\nimageSize: [ 640, 480 ]\n\
        K1: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [ 600., 0., 330.25, 0., 610., 236.5, 0., 0., 1. ]\n\
        D1: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   data: [ -0.05, 0.01, 0.001, -0.0015, 0. ]\n\
        K2: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [ 605., 0., 322.25, 0., 603., 240.125, 0., 0., 1. ]\n\
        D2: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   data: [ -0.06, 0.012, -0.0005, 0.001, 0. ]\n"
        .to_string();
    if let Some(r) = r {
        text += &format!(
            "R: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [ {} ]\n",
            list(r.as_flattened())
        );
    }
    if let Some(t) = t {
        text += &format!(
            "T: !!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n   data: [ {} ]\n",
            list(&t)
        );
    }
    let path = tmp(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// The same pair as a Kalibr camchain: cam1's T_cn_cnm1 is [R T; 0 0 0 1].
fn camchain(name: &str) -> PathBuf {
    let r = rotation_matrix(RVEC);
    let rows: Vec<String> = (0..3)
        .map(|i| format!("  - [{}, {:?}]", list(&r[i]), T[i]))
        .collect();
    let text = format!(
        "cam0:\n  camera_model: pinhole\n  intrinsics: [600.0, 610.0, 330.25, 236.5]\n  distortion_model: radtan\n  distortion_coeffs: [-0.05, 0.01, 0.001, -0.0015]\n  resolution: [640, 480]\n\
         cam1:\n  T_cn_cnm1:\n{}\n  - [0.0, 0.0, 0.0, 1.0]\n  camera_model: pinhole\n  intrinsics: [605.0, 603.0, 322.25, 240.125]\n  distortion_model: radtan\n  distortion_coeffs: [-0.06, 0.012, -0.0005, 0.001]\n  resolution: [640, 480]\n",
        rows.join("\n")
    );
    let path = tmp(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// The pair's camera files, named for the test that writes them: the tests run in parallel
/// threads of one process, and one rewriting a file another's command is reading hands it an
/// empty file.
fn cameras(test: &str) -> (PathBuf, PathBuf) {
    let (l, r) = (
        tmp(&format!("{test}_left.json")),
        tmp(&format!("{test}_right.json")),
    );
    std::fs::write(&l, LEFT).unwrap();
    std::fs::write(&r, RIGHT).unwrap();
    (l, r)
}

/// What the library computes for the pair.
fn library(options: &StereoOptions) -> StereoRectification {
    let left = Camera::parse(LEFT, "left.json").unwrap();
    let right = Camera::parse(RIGHT, "right.json").unwrap();
    stereo_rectify(&left, &right, RVEC, T, options).unwrap()
}

/// A camera_info matrix's data, read with a YAML parser.
fn matrix(text: &str, key: &str) -> Vec<f64> {
    let docs = yaml_rust2::YamlLoader::load_from_str(text).expect("camera_info is YAML");
    docs[0][key]["data"]
        .as_vec()
        .unwrap_or_else(|| panic!("{key}.data in {text}"))
        .iter()
        .map(|v| v.as_f64().or_else(|| v.as_i64().map(|i| i as f64)).unwrap())
        .collect()
}

/// The written camera_info files hold the library's R and P, every bit, and the lens's K and D.
fn check_infos(dir: &Path, want: &StereoRectification) {
    let lenses = [LEFT, RIGHT].map(|t| Camera::parse(t, "lens").unwrap());
    for (side, lens, r, p) in [
        ("left", &lenses[0], want.r1, want.p1),
        ("right", &lenses[1], want.r2, want.p2),
    ] {
        let path = dir.join(format!("{side}.yaml"));
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(matrix(&text, "rectification_matrix"), r.as_flattened());
        assert_eq!(matrix(&text, "projection_matrix"), p.as_flattened());
        let back = Camera::load(&path).unwrap();
        assert_eq!(back.intrinsics, lens.intrinsics);
        assert_eq!(&back.dist_coeffs()[..4], &lens.dist_coeffs()[..4]);
    }
}

#[test]
fn every_way_of_giving_the_pair_writes_the_librarys_rectification() {
    let (l, r) = cameras("ways");
    let matrix9 = list(rotation_matrix(RVEC).as_flattened()).replace(' ', "");
    let rvec = list(&RVEC).replace(' ', "");
    let t = list(&T).replace(' ', "");
    let stereo = stereo_file("stereo.yml", Some(rotation_matrix(RVEC)), Some(T));
    let intrinsics = stereo_file("intrinsics.yml", None, None);
    let extrinsics = tmp("extrinsics.yml");
    std::fs::write(
        &extrinsics,
        format!("%YAML:1.0\nR: [{}]\nT: [{}]\n", list(&RVEC), list(&T)),
    )
    .unwrap();
    let chain = camchain("camchain.yaml");
    let want = library(&StereoOptions {
        alpha: Some(0.0),
        ..StereoOptions::default()
    });
    let ways: Vec<Vec<&str>> = vec![
        vec![
            "--camera",
            s(&l),
            "--camera",
            s(&r),
            "--rotation",
            &rvec,
            "--translation",
            &t,
        ],
        vec![
            "--camera",
            s(&l),
            "--camera",
            s(&r),
            "--rotation",
            &matrix9,
            "--translation",
            &t,
        ],
        vec![
            "--camera",
            s(&l),
            "--camera",
            s(&r),
            "--extrinsics",
            s(&extrinsics),
        ],
        vec![s(&stereo)],
        vec![s(&intrinsics), "--extrinsics", s(&extrinsics)],
        vec![s(&chain)],
    ];
    for (i, way) in ways.iter().enumerate() {
        let dir = out_dir(&format!("way{i}"));
        let mut args = vec!["stereo-rectify", "--alpha", "0", "--out", s(&dir)];
        args.extend(way);
        let run = vklens(&args);
        assert!(run.status.success(), "{args:?}: {}", stderr(&run));
        let err = stderr(&run);
        assert!(
            err.contains("baseline 0.120")
                && err.contains("along the rows")
                && err.contains("valid ROI"),
            "{err}"
        );
        // A matrix and its Rodrigues vector, and a matrix read from a file, are one rotation
        // to rounding; the vector given as is rectifies to the bit.
        if way.contains(&rvec.as_str()) || way.contains(&s(&extrinsics)) {
            check_infos(&dir, &want);
        } else {
            let text = std::fs::read_to_string(dir.join("right.yaml")).unwrap();
            let p = matrix(&text, "projection_matrix");
            for (x, y) in p.iter().zip(want.p2.as_flattened()) {
                assert!((x - y).abs() <= 1e-9 * y.abs().max(1.0), "{args:?}: {p:?}");
            }
        }
    }
}

#[test]
fn the_rectified_pair_is_what_undistort_draws_from_the_written_files() {
    let (l, r) = cameras("undistort");
    let (li, ri) = (tmp("left_in.png"), tmp("right_in.png"));
    common::write_png(&li, 640, 480, false);
    common::write_png(&ri, 640, 480, true);
    let dir = out_dir("images");
    let (rvec, t) = (list(&RVEC).replace(' ', ""), list(&T).replace(' ', ""));
    let run = vklens(&[
        "stereo-rectify",
        "--camera",
        s(&l),
        "--camera",
        s(&r),
        "--rotation",
        &rvec,
        "--translation",
        &t,
        "--alpha",
        "0.5",
        "--no-zero-disparity",
        "--out",
        s(&dir),
        "--left",
        s(&li),
        "--right",
        s(&ri),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    check_infos(
        &dir,
        &library(&StereoOptions {
            alpha: Some(0.5),
            zero_disparity: false,
            ..StereoOptions::default()
        }),
    );
    for (side, input, sixteen) in [("left", &li, false), ("right", &ri, true)] {
        let again = tmp(&format!("{side}_undistorted.png"));
        let u = vklens(&[
            "undistort",
            "--camera",
            s(&dir.join(format!("{side}.yaml"))),
            "--input",
            s(input),
            "--output",
            s(&again),
        ]);
        assert!(u.status.success(), "{}", stderr(&u));
        assert!(
            stderr(&u).contains("rectifying as image_proc does"),
            "{}",
            stderr(&u)
        );
        let ours = image::open(dir.join(format!("{side}.png"))).unwrap();
        let theirs = image::open(&again).unwrap();
        // The input's bit depth, and an alpha channel for the pixels without a source.
        assert_eq!(ours.color(), theirs.color());
        assert_eq!(
            matches!(ours.color(), image::ColorType::Rgba16),
            sixteen,
            "{:?}",
            ours.color()
        );
        assert_eq!(ours.as_bytes(), theirs.as_bytes(), "{side}");
    }
}

#[test]
fn a_vertical_pair_shares_its_columns_and_a_new_size_is_said_in_the_files() {
    let (l, r) = cameras("vertical");
    let dir = out_dir("vertical");
    let run = vklens(&[
        "stereo-rectify",
        "--camera",
        s(&l),
        "--camera",
        s(&r),
        "--rotation",
        "0.01,0.02,-0.01",
        "--translation",
        "0.002,-0.1,0.004",
        "--new-size",
        "800x500",
        "--out",
        s(&dir),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(
        stderr(&run).contains("columns (a vertical pair)"),
        "{}",
        stderr(&run)
    );
    let text = std::fs::read_to_string(dir.join("right.yaml")).unwrap();
    assert!(
        text.starts_with("# rectified image size: 800x500"),
        "{text}"
    );
    // The baseline times the focal length in P2's second row, as OpenCV puts it.
    let p = matrix(&text, "projection_matrix");
    assert!(p[3] == 0.0 && p[7] < 0.0, "{p:?}");
}

#[test]
fn refusals_exit_2_naming_the_file_key_or_flag_and_write_nothing() {
    let (l, r) = cameras("refusals");
    let no_t = stereo_file("no_t.yml", Some(rotation_matrix(RVEC)), None);
    let bad_r = stereo_file(
        "bad_r.yml",
        Some([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]]),
        Some(T),
    );
    let fish = tmp("fish.json");
    std::fs::write(
        &fish,
        r#"{"model": "opencv_fisheye", "width": 640, "height": 480, "fx": 300.0, "fy": 300.0,
            "cx": 320.0, "cy": 240.0, "dist_coeffs": [0.01, 0.0, 0.0, 0.0]}"#,
    )
    .unwrap();
    let small = tmp("small.png");
    common::write_png(&small, 320, 240, false);
    let a_file = tmp("a_file.txt");
    std::fs::write(&a_file, "not a folder").unwrap();
    let dir = out_dir("refused");
    let (rt, tt) = ("0.01,-0.02,0.005", "-0.12,0.003,0.001");
    let two = |extra: &[&'static str]| -> Vec<String> {
        let mut v: Vec<String> = ["--camera", s(&l), "--camera", s(&r)]
            .map(String::from)
            .to_vec();
        v.extend(extra.iter().map(|x| x.to_string()));
        v
    };
    let cases: Vec<(Vec<String>, Vec<&str>)> = vec![
        (vec![s(&no_t).into()], vec!["no_t.yml", "missing `T`"]),
        (
            vec![s(&bad_r).into()],
            vec!["bad_r.yml", "`R`", "not a rotation"],
        ),
        (
            two(&["--rotation", "1,2", "--translation", tt]),
            vec!["--rotation", "2 numbers"],
        ),
        (
            two(&["--rotation", "0,0,0", "--translation", "0,0,0"]),
            vec!["--translation", "not zero"],
        ),
        (
            two(&["--rotation", "1,0,0,0,1,0,0,0,-1", "--translation", tt]),
            vec!["--rotation", "not a rotation"],
        ),
        (two(&["--rotation", rt]), vec!["--translation"]),
        (
            two(&["--rotation", rt, "--translation", tt, "--balance", "0.5"]),
            vec!["--balance", "alpha"],
        ),
        (
            two(&["--rotation", rt, "--translation", tt, "--alpha", "2"]),
            vec!["--alpha", "0..=1"],
        ),
        (
            vec![
                "--camera".into(),
                s(&l).into(),
                "--camera".into(),
                s(&fish).into(),
                "--rotation".into(),
                rt.into(),
                "--translation".into(),
                tt.into(),
            ],
            vec!["fish.json", "opencv_fisheye"],
        ),
        (
            vec!["--camera".into(), s(&l).into()],
            vec!["--camera LEFT --camera RIGHT"],
        ),
        (
            vec![s(&no_t).into(), "--rotation".into(), rt.into()],
            vec!["no_t.yml", "--rotation"],
        ),
        (
            two(&["--rotation", rt, "--translation", tt, "--left"])
                .into_iter()
                .chain([
                    s(&small).to_string(),
                    "--right".into(),
                    s(&small).to_string(),
                ])
                .collect(),
            vec!["small.png", "320×240"],
        ),
    ];
    for (extra, words) in cases {
        let mut args: Vec<String> = vec!["stereo-rectify".into(), "--out".into(), s(&dir).into()];
        args.extend(extra);
        let argv: Vec<&str> = args.iter().map(String::as_str).collect();
        let run = vklens(&argv);
        let err = stderr(&run);
        assert_eq!(run.status.code(), Some(2), "{argv:?}: {err}");
        for w in words {
            assert!(err.contains(w), "{argv:?}: `{w}` not in {err}");
        }
        assert!(!dir.exists(), "{argv:?} wrote {}", dir.display());
    }
    // --out must be a folder.
    let run = vklens(&["stereo-rectify", "--out", s(&a_file), s(&no_t)]);
    assert_eq!(run.status.code(), Some(2));
    assert!(stderr(&run).contains("folder"), "{}", stderr(&run));
}
