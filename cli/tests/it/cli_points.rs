//! `vklens points project`: world points through a pose and a global or rolling shutter,
//! against an independent solve written here (Rodrigues and Shoemake's slerp by hand, the
//! line time written out, g scanned on a fine grid and bisected), using the camera's own
//! forward projection of camera-frame points from the public API.

use crate::common;

use glam::{DMat3, DQuat, DVec3};

use common::{scratch, stderr, vklens_with_stdin};

fn example_camera(name: &str) -> String {
    crate::common::root()
        .join("examples/cameras")
        .join(name)
        .display()
        .to_string()
}

/// OpenCV's Rodrigues formula, R = cos θ I + (1 − cos θ) k kᵀ + sin θ [k]×.
fn rodrigues(r: [f64; 3]) -> DMat3 {
    let v = DVec3::from_array(r);
    let theta = v.length();
    if theta == 0.0 {
        return DMat3::IDENTITY;
    }
    let k = v / theta;
    let cross = DMat3::from_cols(
        DVec3::new(0.0, k.z, -k.y),
        DVec3::new(-k.z, 0.0, k.x),
        DVec3::new(k.y, -k.x, 0.0),
    );
    let outer = DMat3::from_cols(k * k.x, k * k.y, k * k.z);
    DMat3::IDENTITY * theta.cos() + outer * (1.0 - theta.cos()) + cross * theta.sin()
}

/// A pose as the command line takes it, and as world → camera rotation and translation.
#[derive(Clone, Copy)]
struct Pose {
    r: [f64; 3],
    t: [f64; 3],
}

impl Pose {
    fn arg(&self) -> String {
        let v = [self.r, self.t].concat();
        v.iter()
            .map(|x| x.to_string())
            .collect::<Vec<_>>()
            .join(",")
    }
    fn rotation(&self) -> DMat3 {
        rodrigues(self.r)
    }
    fn centre(&self) -> DVec3 {
        -(self.rotation().transpose() * DVec3::from_array(self.t))
    }
}

fn slerp(q0: DQuat, q1: DQuat, s: f64) -> DQuat {
    let q1 = if q0.dot(q1) < 0.0 { -q1 } else { q1 };
    let omega = q0.dot(q1).min(1.0).acos();
    if omega < 1e-12 {
        return q0;
    }
    (q0 * (((1.0 - s) * omega).sin() / omega.sin()) + q1 * ((s * omega).sin() / omega.sin()))
        .normalize()
}

/// The reference: the pixel at the first self-consistent readout time on a 4096-cell scan,
/// bisected; the nearer end of the readout for a point no line reads.
fn reference(
    camera: &vklens::Camera,
    start: Pose,
    end: Pose,
    readout: &str,
    x: DVec3,
) -> Option<[f64; 2]> {
    let q0 = DQuat::from_mat3(&start.rotation().transpose());
    let q1 = DQuat::from_mat3(&end.rotation().transpose());
    let (w, h) = (camera.width as f64 - 1.0, camera.height as f64 - 1.0);
    let g = |s: f64| -> Option<(f64, [f64; 2])> {
        let c = start.centre() * (1.0 - s) + end.centre() * s;
        let p = DMat3::from_quat(slerp(q0, q1, s)).transpose() * (x - c);
        let px = camera.project_points(&[p.to_array()])[0]?;
        let time = match readout {
            "top_to_bottom" => px[1] / h,
            "bottom_to_top" => (h - px[1]) / h,
            "left_to_right" => px[0] / w,
            _ => (w - px[0]) / w,
        };
        Some((s - time, px))
    };
    const CELLS: usize = 4096;
    let first = g(0.0)?;
    let mut prev = first;
    for k in 1..=CELLS {
        let s = k as f64 / CELLS as f64;
        let cur = g(s)?;
        if (cur.0 < 0.0) != (prev.0 < 0.0) {
            let (mut lo, mut hi) = ((k - 1) as f64 / CELLS as f64, s);
            while 0.5 * (lo + hi) > lo && 0.5 * (lo + hi) < hi {
                let mid = 0.5 * (lo + hi);
                if (g(mid)?.0 < 0.0) == (prev.0 < 0.0) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            return Some(g(0.5 * (lo + hi))?.1);
        }
        prev = cur;
    }
    Some(if first.0 > 0.0 { first.1 } else { prev.1 })
}

/// World points seen across the image from `pose`, at 1.5 to 12 m.
fn world_points(camera: &vklens::Camera, pose: Pose, n: usize) -> Vec<[f64; 3]> {
    let mut seed = 0x9e3779b97f4a7c15u64;
    let mut next = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut out = Vec::new();
    while out.len() < n {
        let uv = [
            next() * (camera.width - 1) as f64,
            next() * (camera.height - 1) as f64,
        ];
        let depth = 1.5 + 10.5 * next();
        let Some(ray) = camera.unproject_points(&[uv])[0] else {
            continue;
        };
        let p = DVec3::from_array(ray) * depth - DVec3::from_array(pose.t);
        out.push((pose.rotation().transpose() * p).to_array());
    }
    out
}

/// Runs `points project` and reads its rows.
fn project(camera: &str, extra: &[&str], points: &[[f64; 3]]) -> Vec<Option<[f64; 2]>> {
    let mut args = vec!["points", "project", "--camera", camera];
    args.extend_from_slice(extra);
    let out = vklens_with_stdin(&args, &serde_json::to_string(points).unwrap());
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    serde_json::from_slice(&out.stdout).expect("JSON rows")
}

const READOUTS: [&str; 4] = [
    "top_to_bottom",
    "bottom_to_top",
    "left_to_right",
    "right_to_left",
];

#[test]
fn rolling_shutter_points_match_an_independent_solve_for_three_models_and_every_readout() {
    let start = Pose {
        r: [0.02, -0.01, 0.005],
        t: [0.1, -0.05, 0.2],
    };
    let end = Pose {
        r: [0.06, 0.04, -0.01],
        t: [-0.2, 0.1, 0.25],
    };
    for name in ["barrel_k1k2.json", "fisheye_200.json", "double_sphere.json"] {
        let path = example_camera(name);
        let camera = vklens::Camera::load(&path).unwrap();
        let points = world_points(&camera, start, 120);
        for readout in READOUTS {
            let got = project(
                &path,
                &[
                    "--pose",
                    &start.arg(),
                    "--end-pose",
                    &end.arg(),
                    "--rolling-shutter",
                    readout,
                ],
                &points,
            );
            let (mut worst, mut seen, mut moved) = (0.0f64, 0, 0.0f64);
            for (i, &x) in points.iter().enumerate() {
                let want = reference(&camera, start, end, readout, DVec3::from_array(x));
                let (Some(g), Some(w)) = (got[i], want) else {
                    assert_eq!(got[i].is_some(), want.is_some(), "{name} {readout} {x:?}");
                    continue;
                };
                seen += 1;
                worst = worst.max((g[0] - w[0]).abs().max((g[1] - w[1]).abs()));
                let first = start.rotation() * DVec3::from_array(x) + DVec3::from_array(start.t);
                if let Some(f) = camera.project_points(&[first.to_array()])[0] {
                    moved = moved.max((g[0] - f[0]).hypot(g[1] - f[1]));
                }
            }
            assert!(seen >= 100, "{name} {readout}: {seen} of 120 seen");
            assert!(worst <= 1e-6, "{name} {readout}: off by {worst:e} px");
            assert!(moved > 3.0, "{name} {readout}: the motion moved {moved} px");
        }
    }
}

#[test]
fn a_camera_that_does_not_move_gives_the_global_shutters_pixels_bit_for_bit() {
    let pose = Pose {
        r: [0.1, -0.2, 0.05],
        t: [0.3, 0.1, 1.0],
    };
    for name in ["barrel_k1k2.json", "fisheye_200.json", "double_sphere.json"] {
        let path = example_camera(name);
        let camera = vklens::Camera::load(&path).unwrap();
        let mut points = world_points(&camera, pose, 60);
        // Behind the camera (null for the standard model) and outside the image.
        points.push((pose.rotation().transpose() * DVec3::new(-0.3, -0.1, -4.0)).to_array());
        points.push((pose.rotation().transpose() * DVec3::new(5.0, 5.0, 2.0)).to_array());
        let global = project(&path, &["--pose", &pose.arg()], &points);
        // As cv2.projectPoints: the camera's projection of R X + t (R by Rodrigues' formula
        // here, by the library's own rotation there: the same to rounding).
        for (i, x) in points.iter().enumerate() {
            let p = pose.rotation() * DVec3::from_array(*x) + DVec3::from_array(pose.t);
            let want = camera.project_points(&[p.to_array()])[0];
            match (global[i], want) {
                (Some(g), Some(w)) => {
                    assert!((g[0] - w[0]).abs() < 1e-9 && (g[1] - w[1]).abs() < 1e-9)
                }
                (None, None) => {}
                other => panic!("{name} {x:?}: {other:?}"),
            }
        }
        for readout in READOUTS {
            let still = project(
                &path,
                &["--pose", &pose.arg(), "--rolling-shutter", readout],
                &points,
            );
            let same_end = project(
                &path,
                &[
                    "--pose",
                    &pose.arg(),
                    "--end-pose",
                    &pose.arg(),
                    "--rolling-shutter",
                    readout,
                ],
                &points,
            );
            assert_eq!(still, global, "{name} {readout}");
            assert_eq!(same_end, global, "{name} {readout}");
        }
    }
    // The identity pose: `points distort`'s camera-frame points, bit for bit.
    let path = example_camera("barrel_k1k2.json");
    let points = [[0.5, 0.4, 4.0], [-1.0, 0.3, 2.0], [0.0, 0.0, -1.0]];
    let distorted = vklens_with_stdin(
        &["points", "distort", "--camera", &path],
        &serde_json::to_string(&points).unwrap(),
    );
    let distorted: Vec<Option<[f64; 2]>> = serde_json::from_slice(&distorted.stdout).unwrap();
    assert_eq!(
        project(&path, &["--pose", "0,0,0,0,0,0"], &points),
        distorted
    );
    assert_eq!(distorted[2], None, "behind the camera");
}

#[test]
fn a_fast_pan_moves_points_by_pixels_and_the_solve_follows_it() {
    // 180°/s for a 30 ms readout, columns read left to right.
    let path = example_camera("barrel_k1k2.json");
    let camera = vklens::Camera::load(&path).unwrap();
    let start = Pose {
        r: [0.0; 3],
        t: [0.0; 3],
    };
    let end = Pose {
        r: [0.0, 0.0942, 0.0],
        t: [0.0; 3],
    };
    let points = world_points(&camera, start, 40);
    let args = [
        "--pose",
        &start.arg(),
        "--end-pose",
        &end.arg(),
        "--rolling-shutter",
        "left_to_right",
    ];
    let got = project(&path, &args, &points);
    let global = project(&path, &["--pose", &start.arg()], &points);
    let mut most = 0.0f64;
    for (i, &x) in points.iter().enumerate() {
        let (Some(g), Some(w), Some(f)) = (
            got[i],
            reference(&camera, start, end, "left_to_right", DVec3::from_array(x)),
            global[i],
        ) else {
            continue;
        };
        assert!((g[0] - w[0]).abs() <= 1e-6 && (g[1] - w[1]).abs() <= 1e-6);
        most = most.max((g[0] - f[0]).abs());
    }
    assert!(most > 10.0, "the pan moved points by {most} px at most");
}

#[test]
fn the_camera_files_readout_is_the_default_and_the_flag_overrides_it() {
    let ncore = scratch("cli-points", "ncore.json");
    std::fs::write(
        &ncore,
        r#"{"camera_model_type": "ftheta", "camera_model_parameters": {
        "resolution": [1920, 1080], "principal_point": [959.3, 541.8],
        "reference_poly": "PIXELDIST_TO_ANGLE",
        "pixeldist_to_angle_poly": [0.0, 1.02e-3, 3.1e-10, -2.4e-13, 0.0, 0.0],
        "angle_to_pixeldist_poly": [0.0, 980.392, -0.2921, 0.2219, -3.3e-4, 1.5e-4],
        "linear_cde": [1.0, 0.0, 0.0], "max_angle": 1.1,
        "shutter_type": "ROLLING_LEFT_TO_RIGHT"}}"#,
    )
    .unwrap();
    let ncore = ncore.display().to_string();
    let points = [[1.0, 0.5, 5.0], [-2.0, -0.5, 6.0]];
    let moving = ["--pose", "0,0,0,0,0,0", "--end-pose", "0,0.05,0,-0.3,0,0"];
    let default = project(&ncore, &moving, &points);
    let named = project(
        &ncore,
        &[&moving[..], &["--rolling-shutter", "left_to_right"]].concat(),
        &points,
    );
    let other = project(
        &ncore,
        &[&moving[..], &["--rolling-shutter", "top_to_bottom"]].concat(),
        &points,
    );
    assert_eq!(default, named);
    assert!(default.iter().all(Option::is_some));
    assert_ne!(default, other);
}

#[test]
fn bad_input_is_refused_naming_the_flag_or_the_element() {
    let path = example_camera("barrel_k1k2.json");
    let run = |args: &[&str], stdin: &str| {
        let mut all = vec!["points", "project", "--camera", path.as_str()];
        all.extend_from_slice(args);
        vklens_with_stdin(&all, stdin)
    };
    let cases: [(&[&str], &str, &str); 5] = [
        (
            &["--pose", "0,0,0,0,0,0", "--end-pose", "0,0.1,0,0,0,0"],
            "[[0, 0, 1]]",
            "--rolling-shutter",
        ),
        (&["--pose", "0,0,0,0,0"], "[[0, 0, 1]]", "--pose"),
        (
            &["--pose", "0,0,0,0,0,0", "--rolling-shutter", "diagonal"],
            "[[0, 0, 1]]",
            "top_to_bottom",
        ),
        (&["--pose", "0,0,0,0,0,0"], "[[0, 1]]", "element 0"),
        (&["--pose", "0,0,0,0,0,0"], "[[0, 1, \"z\"]]", "element 0"),
    ];
    for (args, stdin, needle) in cases {
        let out = run(args, stdin);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let e = stderr(&out);
        assert!(e.contains(needle), "{args:?}: {e}");
    }
    let e = stderr(&run(
        &["--pose", "0,0,0,0,0,0", "--end-pose", "0,0.1,0,0,0,0"],
        "[]",
    ));
    assert!(e.contains("--end-pose") && e.contains("global"), "{e}");
    // A point behind the camera is null; a huge one is the direction it lies in (the camera
    // only turns here, so distance does not matter), not an overflow.
    let out = project(
        &path,
        &[
            "--pose",
            "0,0,0,0,0,0",
            "--end-pose",
            "0,0.1,0,0,0,0",
            "--rolling-shutter",
            "top_to_bottom",
        ],
        &[[0.0, 0.0, -3.0], [1e300, 5e299, 1e300], [1.0, 0.5, 1.0]],
    );
    assert_eq!(out[0], None);
    let (huge, near) = (out[1].unwrap(), out[2].unwrap());
    assert!((huge[0] - near[0]).abs() < 1e-9 && (huge[1] - near[1]).abs() < 1e-9);
}
