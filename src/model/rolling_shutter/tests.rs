//! The rolling-shutter projection against an independent solve written here: the poses by
//! Shoemake's slerp formula on quaternions (not the exp/log of the module), the line time
//! written out again, g scanned on a fine grid and its first sign change bisected to the last
//! bit of f64.

use std::cell::Cell;

use glam::{DMat3, DQuat, DVec2, DVec3};

use super::*;
use crate::model::double_sphere::DoubleSphere;
use crate::model::{Fisheye, Intrinsics};

/// Cells of the reference's scan: 256 times finer than the module's.
const REFERENCE_CELLS: usize = 4096;

fn pose(rvec: [f64; 3], tvec: [f64; 3]) -> WorldToCamera {
    let r = DVec3::from_array(rvec);
    let angle = r.length();
    let rotation = if angle == 0.0 {
        DMat3::IDENTITY
    } else {
        DMat3::from_axis_angle(r / angle, angle)
    };
    WorldToCamera {
        rotation,
        translation: DVec3::from_array(tvec),
    }
}

fn standard() -> Camera {
    let k = Intrinsics {
        fx: 1100.0,
        fy: 1090.0,
        cx: 959.5,
        cy: 539.5,
    };
    Camera::from_coeffs(1920, 1080, k, &[-0.12, 0.05, 0.0008, -0.0005, -0.01]).unwrap()
}

fn fisheye() -> Camera {
    let k = Intrinsics {
        fx: 230.0,
        fy: 230.0,
        cx: 399.5,
        cy: 399.5,
    };
    let lens = Fisheye::new([0.02, -0.004, 0.0005, 0.0], 0.0, Some(200.0)).unwrap();
    Camera::fisheye(800, 800, k, lens).unwrap()
}

fn double_sphere() -> Camera {
    let k = Intrinsics {
        fx: 349.7,
        fy: 348.9,
        cx: 365.8,
        cy: 249.9,
    };
    let lens = Lens::DoubleSphere(DoubleSphere::new(-0.2, 0.57).unwrap());
    Camera::with_lens(752, 480, k, lens).unwrap()
}

/// Shoemake's slerp between unit quaternions (the shorter way round).
fn slerp(q0: DQuat, q1: DQuat, s: f64) -> DQuat {
    let (q1, dot) = if q0.dot(q1) < 0.0 {
        (-q1, -q0.dot(q1))
    } else {
        (q1, q0.dot(q1))
    };
    let omega = dot.min(1.0).acos();
    if omega < 1e-12 {
        return q0;
    }
    let (a, b) = (
        ((1.0 - s) * omega).sin() / omega.sin(),
        (s * omega).sin() / omega.sin(),
    );
    (q0 * a + q1 * b).normalize()
}

/// The reference's camera-frame point at readout time `s`.
fn reference_camera_point(start: &WorldToCamera, end: &WorldToCamera, s: f64, x: DVec3) -> DVec3 {
    let (q0, q1) = (
        DQuat::from_mat3(&start.rotation.transpose()),
        DQuat::from_mat3(&end.rotation.transpose()),
    );
    let centre = |p: &WorldToCamera| -(p.rotation.transpose() * p.translation);
    let c = centre(start) * (1.0 - s) + centre(end) * s;
    let r_wc = DMat3::from_quat(slerp(q0, q1, s));
    r_wc.transpose() * (x - c)
}

fn reference_line_time(camera: &Camera, readout: Readout, p: DVec2) -> f64 {
    let (w, h) = (camera.width as f64 - 1.0, camera.height as f64 - 1.0);
    match readout {
        Readout::TopToBottom => p.y / h,
        Readout::BottomToTop => (h - p.y) / h,
        Readout::LeftToRight => p.x / w,
        Readout::RightToLeft => (w - p.x) / w,
    }
}

/// The independent solve: `(pixel, s)` at the first root of g on the fine scan, bisected; for
/// a point no line reads, its position at the nearer end of the readout.
fn reference(
    camera: &Camera,
    start: &WorldToCamera,
    end: &WorldToCamera,
    readout: Readout,
    x: DVec3,
) -> Option<(DVec2, f64)> {
    let g = |s: f64| {
        let p = camera.project(reference_camera_point(start, end, s, x))?;
        Some((s - reference_line_time(camera, readout, p), p))
    };
    let mut prev = g(0.0)?;
    if prev.0 == 0.0 {
        return Some((prev.1, 0.0));
    }
    let first = prev;
    for k in 1..=REFERENCE_CELLS {
        let s = k as f64 / REFERENCE_CELLS as f64;
        let cur = g(s)?;
        if (cur.0 < 0.0) != (prev.0 < 0.0) || cur.0 == 0.0 {
            let (mut lo, mut hi) = ((k - 1) as f64 / REFERENCE_CELLS as f64, s);
            let below = prev.0 < 0.0;
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if mid <= lo || mid >= hi {
                    break;
                }
                let (gm, _) = g(mid)?;
                if (gm < 0.0) == below {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let s = 0.5 * (lo + hi);
            return Some((g(s)?.1, s));
        }
        prev = cur;
    }
    Some(if first.0 > 0.0 {
        (first.1, 0.0)
    } else {
        (prev.1, 1.0)
    })
}

/// A deterministic stream of numbers in [0, 1).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// World points seen across the image from `start`, at 1.5 to 20 m.
fn world_points(camera: &Camera, start: &WorldToCamera, n: usize, seed: u64) -> Vec<DVec3> {
    let mut rng = Lcg(seed);
    let mut out = Vec::new();
    while out.len() < n {
        let px = DVec2::new(
            rng.next() * (camera.width - 1) as f64,
            rng.next() * (camera.height - 1) as f64,
        );
        let Some(ray) = camera.unproject(px) else {
            continue;
        };
        let depth = 1.5 + 18.5 * rng.next();
        out.push(start.rotation.transpose() * (ray * depth - start.translation));
    }
    out
}

/// A handheld-like move during one readout: a few degrees about a tilted axis, 30 cm sideways.
fn moving() -> (WorldToCamera, WorldToCamera) {
    (
        pose([0.02, -0.01, 0.005], [0.1, -0.05, 0.2]),
        pose([0.05, 0.03, -0.01], [-0.2, 0.1, 0.25]),
    )
}

#[test]
fn readout_names_parse_and_line_times_run_from_the_first_line_to_the_last() {
    for r in Readout::ALL {
        assert_eq!(r.name().parse::<Readout>().unwrap(), r);
        assert_eq!(Readout::from_ncore(r.ncore_name()).unwrap(), Some(r));
        assert_eq!(r.to_string(), r.name());
    }
    assert_eq!(Readout::from_ncore("GLOBAL").unwrap(), None);
    let e = "diagonal".parse::<Readout>().unwrap_err().to_string();
    assert!(
        e.contains("\"diagonal\"") && e.contains("top_to_bottom"),
        "{e}"
    );
    assert!(Readout::from_ncore("ROLLING").is_err());
    let (w, h) = (640, 480);
    let corners = [(0.0, 0.0), (639.0, 479.0)];
    let at = |r, (u, v): (f64, f64)| line_time(r, u, v, w, h);
    assert_eq!(at(Readout::TopToBottom, corners[0]), 0.0);
    assert_eq!(at(Readout::TopToBottom, corners[1]), 1.0);
    assert_eq!(at(Readout::BottomToTop, corners[0]), 1.0);
    assert_eq!(at(Readout::BottomToTop, corners[1]), 0.0);
    assert_eq!(at(Readout::LeftToRight, corners[0]), 0.0);
    assert_eq!(at(Readout::LeftToRight, corners[1]), 1.0);
    assert_eq!(at(Readout::RightToLeft, corners[0]), 1.0);
    assert_eq!(at(Readout::RightToLeft, corners[1]), 0.0);
    // A column's time does not depend on the row for a horizontal readout, and vice versa.
    assert_eq!(
        line_time(Readout::LeftToRight, 100.0, 7.0, w, h),
        line_time(Readout::LeftToRight, 100.0, 400.0, w, h)
    );
    assert_eq!(line_time(Readout::TopToBottom, 3.0, 5.0, w, 1), 0.0);
    assert_eq!(line_time(Readout::RightToLeft, 3.0, 5.0, 1, h), 0.0);
}

#[test]
fn the_pose_follows_slerp_and_a_straight_centre_line() {
    let (start, end) = moving();
    let m = FrameMotion::new(start, end);
    assert_eq!(m.at(0.0), start);
    assert_eq!(m.at(1.0), end);
    for s in [0.1, 0.37, 0.5, 0.93] {
        let p = m.at(s);
        let x = DVec3::new(0.3, -1.2, 4.0);
        let want = reference_camera_point(&start, &end, s, x);
        assert!((p.apply(x) - want).length() < 1e-13, "s = {s}");
        assert!((m.to_camera(s, x) - want).length() < 1e-13, "s = {s}");
        // The angle turned so far is s times the whole.
        let turned = DQuat::from_mat3(&(start.rotation * p.rotation.transpose()))
            .angle_between(DQuat::IDENTITY);
        assert!((turned - s * m.angle()).abs() < 1e-12, "s = {s}: {turned}");
    }
    // A small turn keeps its digits (2·acos(w) would lose half of them).
    let first = pose([0.0; 3], [0.1, -0.05, 0.2]);
    let tiny = FrameMotion::new(first, pose([0.0, 1e-9, 0.0], [0.1, -0.05, 0.2]));
    assert!(
        (tiny.angle() / 1e-9 - 1.0).abs() < 1e-12,
        "{}",
        tiny.angle()
    );
    // Still poses: one pose for every line, bit for bit.
    let still = FrameMotion::still(start);
    assert!(still.is_still());
    assert_eq!(still.at(0.6), start);
}

#[test]
fn the_solve_matches_an_independent_bisection_for_every_model_and_readout() {
    let (start, end) = moving();
    let mut worst_of_all = 0.0f64;
    for (name, camera) in [
        ("standard", standard()),
        ("fisheye", fisheye()),
        ("double sphere", double_sphere()),
    ] {
        let points = world_points(&camera, &start, 300, 7);
        for readout in Readout::ALL {
            let (mut worst, mut seen) = (0.0f64, 0);
            let mut moved = 0.0f64;
            for &x in &points {
                let got = project_rolling(&camera, &start, &end, readout, x);
                let want = reference(&camera, &start, &end, readout, x);
                let (Some(got), Some((pixel, s))) = (got, want) else {
                    assert_eq!(
                        got.is_some(),
                        want.is_some(),
                        "{name} {readout} {x}: {got:?} vs {want:?}"
                    );
                    continue;
                };
                seen += 1;
                worst = worst.max((got.pixel - pixel).abs().max_element());
                assert!(
                    (got.s - s).abs() < 1e-6,
                    "{name} {readout}: s {} vs {s}",
                    got.s
                );
                let depth = reference_camera_point(&start, &end, s, x).z;
                assert!((got.depth - depth).abs() < 1e-9 * depth.abs().max(1.0));
                let global = camera.project(start.apply(x)).unwrap_or(got.pixel);
                moved = moved.max((got.pixel - global).length());
            }
            assert!(seen >= 250, "{name} {readout}: {seen} of 300 seen");
            assert!(worst <= 1e-6, "{name} {readout}: {worst:e} px");
            worst_of_all = worst_of_all.max(worst);
            // The motion is real: the rolling image is far from the first line's.
            assert!(moved > 5.0, "{name} {readout}: moved {moved} px");
        }
    }
    eprintln!("three models, four readouts: the solve is off by {worst_of_all:.1e} px at most");
}

#[test]
fn a_camera_that_does_not_move_is_the_global_shutter_bit_for_bit() {
    let (start, _) = moving();
    for camera in [standard(), fisheye(), double_sphere()] {
        let mut points = world_points(&camera, &start, 200, 3);
        // Outside the image on every side too.
        points.extend([
            DVec3::new(-30.0, 0.0, 5.0),
            DVec3::new(30.0, 0.0, 5.0),
            DVec3::new(0.0, -30.0, 5.0),
            DVec3::new(0.0, 30.0, 5.0),
        ]);
        for readout in Readout::ALL {
            for &x in &points {
                let global = camera.project(start.apply(x));
                let same_pose = project_rolling(&camera, &start, &start, readout, x);
                let still = FrameMotion::still(start).project(&camera, readout, x);
                assert_eq!(same_pose, still);
                match (global, same_pose) {
                    (Some(g), Some(r)) => {
                        assert_eq!(g.to_array(), r.pixel.to_array(), "{readout} {x}");
                        assert_eq!(r.depth, start.apply(x).z);
                        let s = line_time(readout, g.x, g.y, camera.width, camera.height);
                        assert_eq!(r.s, s.clamp(0.0, 1.0));
                    }
                    (None, None) => {}
                    other => panic!("{readout} {x}: {other:?}"),
                }
            }
        }
    }
}

/// One fixed-point step from mid-frame, as warps built on a gyroscope's rotations take a
/// point's time: the pose at s = ½ gives a line, the line a time, the time a pose.
fn one_step(camera: &Camera, m: &FrameMotion, readout: Readout, x: DVec3) -> Option<DVec2> {
    let p = camera.project(m.to_camera(0.5, x))?;
    let s = line_time(readout, p.x, p.y, camera.width, camera.height);
    camera.project(m.to_camera(s, x))
}

/// The largest error of one step and of the solve, against the reference, over points across
/// the image; `turn_deg` about the image's vertical (pan) or horizontal (tilt) axis during the
/// readout.
fn one_step_error(camera: &Camera, readout: Readout, turn_deg: f64, tilt: bool) -> (f64, f64) {
    let start = pose([0.0; 3], [0.0; 3]);
    let angle = turn_deg.to_radians();
    let end = if tilt {
        pose([angle, 0.0, 0.0], [0.0; 3])
    } else {
        pose([0.0, angle, 0.0], [0.0; 3])
    };
    let m = FrameMotion::new(start, end);
    let (mut step, mut solve) = (0.0f64, 0.0f64);
    for x in world_points(camera, &start, 400, 11) {
        let (Some(got), Some((want, s))) = (
            m.project(camera, readout, x),
            reference(camera, &start, &end, readout, x),
        ) else {
            continue;
        };
        // Only points a line reads (inside the image at their own time).
        if !(0.0..=1.0).contains(&s) || s == 0.0 || s == 1.0 {
            continue;
        }
        solve = solve.max((got.pixel - want).length());
        if let Some(p) = one_step(camera, &m, readout, x) {
            step = step.max((p - want).length());
        }
    }
    (step, solve)
}

#[test]
fn one_step_from_mid_frame_is_not_enough_on_a_fast_pan_and_the_solve_is() {
    // 1920×1080 at a 82° horizontal field of view, read top to bottom in 30 ms.
    let camera = standard();
    let readout_ms = 30.0;
    let mut rows = Vec::new();
    for (what, deg_per_s, tilt, readout) in [
        (
            "handheld pan, rows read down",
            30.0,
            false,
            Readout::TopToBottom,
        ),
        (
            "handheld tilt, rows read down",
            30.0,
            true,
            Readout::TopToBottom,
        ),
        (
            "fast pan, columns read across",
            180.0,
            false,
            Readout::LeftToRight,
        ),
        (
            "fast tilt, rows read down",
            180.0,
            true,
            Readout::TopToBottom,
        ),
    ] {
        let (step, solve) = one_step_error(&camera, readout, deg_per_s * readout_ms / 1000.0, tilt);
        rows.push((what, deg_per_s, step, solve));
        assert!(solve <= 1e-6, "{what}: the solve is off by {solve:e} px");
    }
    for (what, speed, step, solve) in &rows {
        eprintln!("{what}, {speed}°/s: one step off by {step:.3} px, the solve by {solve:.1e} px");
    }
    // A fast move along the readout: one step is off by more than half a pixel.
    assert!(rows[2].2 > 0.5 && rows[3].2 > 0.5, "{rows:?}");
    // A handheld pan across the rows moves a point's row little: one step is nearly right.
    assert!(rows[0].2 < rows[1].2, "{rows:?}");
}

#[test]
fn the_first_root_in_readout_order_is_taken_where_motion_gives_several() {
    // A pinhole rushing at a point below the axis: its row runs away faster than the readout
    // late in the frame, so g(s) = s − v(s)/(H − 1) has two roots, near 0.62 and 0.93.
    let k = Intrinsics {
        fx: 400.0,
        fy: 400.0,
        cx: 319.5,
        cy: 239.5,
    };
    let camera = Camera::from_coeffs(640, 480, k, &[0.0; 5]).unwrap();
    let start = pose([0.0; 3], [0.0; 3]);
    let end = pose([0.0; 3], [0.0, 0.0, -0.95]);
    let x = DVec3::new(0.0, 0.05 * 479.0 / 400.0, 1.0);
    let got = project_rolling(&camera, &start, &end, Readout::TopToBottom, x).unwrap();
    let (pixel, s) = reference(&camera, &start, &end, Readout::TopToBottom, x).unwrap();
    assert!((0.55..0.7).contains(&got.s), "{got:?}");
    assert!((got.s - s).abs() < 1e-9 && (got.pixel - pixel).length() < 1e-6);
    // The second root exists: g changes sign again before the end of the readout.
    let m = FrameMotion::new(start, end);
    let g = |s: f64| {
        let p = camera.project(m.to_camera(s, x)).unwrap();
        s - line_time(Readout::TopToBottom, p.x, p.y, 640, 480)
    };
    assert!(g(0.8) > 0.0 && g(1.0) < 0.0);
}

#[test]
fn points_no_line_reads_keep_the_position_of_the_nearer_end_of_the_readout() {
    let camera = standard();
    let (start, end) = moving();
    let m = FrameMotion::new(start, end);
    // Far above the image (before the first line) and far below it (after the last).
    let above = start.rotation.transpose() * (DVec3::new(0.0, -4.0, 5.0) - start.translation);
    let below = start.rotation.transpose() * (DVec3::new(0.0, 4.0, 5.0) - start.translation);
    let a = m.project(&camera, Readout::TopToBottom, above).unwrap();
    assert_eq!(a.s, 0.0);
    assert_eq!(a.pixel, camera.project(start.apply(above)).unwrap());
    assert!(a.pixel.y < 0.0);
    let b = m.project(&camera, Readout::TopToBottom, below).unwrap();
    assert_eq!(b.s, 1.0);
    assert_eq!(b.pixel, camera.project(end.apply(below)).unwrap());
    assert!(b.pixel.y > 1079.0);
    // Read the other way round, the ends swap.
    assert_eq!(
        m.project(&camera, Readout::BottomToTop, above).unwrap().s,
        1.0
    );
}

#[test]
fn points_the_lens_does_not_see_are_none_never_garbage() {
    let (start, end) = moving();
    let camera = standard();
    let behind = start.rotation.transpose() * (DVec3::new(0.0, 0.0, -3.0) - start.translation);
    for readout in Readout::ALL {
        assert_eq!(
            project_rolling(&camera, &start, &end, readout, behind),
            None
        );
        for bad in [
            DVec3::new(f64::NAN, 0.0, 1.0),
            DVec3::new(0.0, f64::INFINITY, 1.0),
            DVec3::new(1e300, 1e300, -1e300),
        ] {
            assert_eq!(
                project_rolling(&camera, &start, &end, readout, bad),
                None,
                "{bad}"
            );
            assert_eq!(
                FrameMotion::still(start).project(&camera, readout, bad),
                None
            );
        }
        // A non-finite pose sees nothing.
        let nan = WorldToCamera {
            translation: DVec3::new(f64::NAN, 0.0, 0.0),
            ..end
        };
        let x = DVec3::new(0.0, 0.0, 5.0);
        assert_eq!(project_rolling(&camera, &start, &nan, readout, x), None);
    }
    // A fisheye sees behind its image plane, up to its 200° field: the point straight
    // behind it is outside that, before and after the move.
    let camera = fisheye();
    assert_eq!(
        project_rolling(&camera, &start, &end, Readout::TopToBottom, behind),
        None
    );
}

#[test]
fn refinement_converges_in_a_few_steps() {
    // The handheld move, and a 180°/s tilt read out in 30 ms.
    let fast = (pose([0.0; 3], [0.0; 3]), pose([0.0942, 0.0, 0.0], [0.0; 3]));
    let (mut most, mut total, mut scanned, mut roots) = (0, 0, 0, 0);
    for (start, end) in [moving(), fast] {
        let m = FrameMotion::new(start, end);
        for camera in [standard(), fisheye(), double_sphere()] {
            for x in world_points(&camera, &start, 200, 5) {
                let eval = |s| Sample::at(&m, &camera, Readout::TopToBottom, x, s);
                // The scan's bracketing cell.
                let cells: Vec<Option<Sample>> = (0..=SCAN_CELLS)
                    .map(|k| eval(k as f64 / SCAN_CELLS as f64))
                    .collect();
                let Some((k, a, b)) =
                    cells
                        .windows(2)
                        .enumerate()
                        .find_map(|(k, w)| match (w[0], w[1]) {
                            (Some(a), Some(b)) if (a.g < 0.0) != (b.g < 0.0) => Some((k, a, b)),
                            _ => None,
                        })
                else {
                    continue;
                };
                let count = Cell::new(0);
                let root = refine(a, b, |s| {
                    count.set(count.get() + 1);
                    eval(s)
                });
                assert!(root.is_some());
                most = most.max(count.get());
                total += count.get();
                scanned += k + 2;
                roots += 1;
            }
        }
    }
    eprintln!(
        "{roots} roots: the scan evaluated {:.1} poses on average, the refinement {:.1} ({most} at most)",
        scanned as f64 / roots as f64,
        total as f64 / roots as f64
    );
    assert!(roots > 1000 && most <= 12, "{most}");
}

#[test]
fn an_ncore_camera_file_states_its_readout() {
    let text = r#"{"camera_model_type": "ftheta", "camera_model_parameters": {
        "resolution": [1920, 1080], "principal_point": [959.3, 541.8],
        "reference_poly": "PIXELDIST_TO_ANGLE",
        "pixeldist_to_angle_poly": [0.0, 1.02e-3, 3.1e-10, -2.4e-13, 0.0, 0.0],
        "angle_to_pixeldist_poly": [0.0, 980.392, -0.2921, 0.2219, -3.3e-4, 1.5e-4],
        "linear_cde": [1.0, 0.0, 0.0], "max_angle": 1.1, "shutter_type": "SHUTTER"}}"#;
    for (name, want) in [
        ("ROLLING_BOTTOM_TO_TOP", Some(Readout::BottomToTop)),
        ("ROLLING_LEFT_TO_RIGHT", Some(Readout::LeftToRight)),
        ("GLOBAL", None),
    ] {
        let camera =
            crate::io::camera::parse_camera(&text.replace("SHUTTER", name), "ncore.json").unwrap();
        assert_eq!(camera.readout(), want, "{name}");
    }
    assert_eq!(standard().readout(), None);
}

/// The largest |d line_time / ds| of `x`'s own pixel over the frame, by central differences on
/// 400 cells of the readout (`None` where the lens loses the point somewhere).
fn measured_line_rate(camera: &Camera, m: &FrameMotion, readout: Readout, x: DVec3) -> Option<f64> {
    const CELLS: usize = 400;
    const H: f64 = 1e-6;
    let t = |s: f64| {
        let p = camera.project(m.to_camera(s, x))?;
        Some(line_time(readout, p.x, p.y, camera.width, camera.height))
    };
    let mut worst: f64 = 0.0;
    for k in 0..=CELLS {
        let s = (k as f64 / CELLS as f64).clamp(H, 1.0 - H);
        worst = worst.max(((t(s + H)? - t(s - H)?) / (2.0 * H)).abs());
    }
    Some(worst)
}

#[test]
fn a_still_camera_has_a_zero_line_rate_bound() {
    let camera = standard();
    let rate = LineRate::measure(&camera, Readout::TopToBottom).expect("a rate");
    let pose = moving().0;
    let m = FrameMotion::still(pose);
    for x in world_points(&camera, &pose, 50, 3) {
        assert_eq!(m.angular_speed_bound(x), 0.0);
        assert_eq!(m.line_rate_bound(&rate, x), Some(0.0));
    }
    assert_eq!(m.angular_speed_bound_beyond(0.0), 0.0);
}

#[test]
fn the_line_rate_bound_is_never_below_the_rate_the_motion_gives() {
    // A pan with a step sideways for every model and readout: the bound L of each point against
    // the largest rate of its own line time over the frame, measured by finite differences.
    let pan = (
        pose([0.0, 0.0, 0.0], [0.0, 0.0, 0.0]),
        pose([0.01, 0.06, 0.0], [-0.08, 0.01, 0.0]),
    );
    let m = FrameMotion::new(pan.0, pan.1);
    let mut contracting = 0;
    for camera in [standard(), fisheye(), double_sphere()] {
        for readout in Readout::ALL {
            let rate = LineRate::measure(&camera, readout).expect("a rate");
            assert!(rate.per_radian[0] > 0.0 && rate.cone > 0.0, "{rate:?}");
            assert!(
                rate.per_radian.windows(2).all(|w| w[0] <= w[1]),
                "a wider cone has no slower rate: {rate:?}"
            );
            assert_eq!(
                rate.within(rate.cone),
                Some(rate.per_radian[RATE_TABLE - 1])
            );
            assert_eq!(rate.within(rate.cone * 1.01), None);
            assert_eq!(rate.within(f64::NAN), None);
            let (mut checked, mut tightest) = (0, f64::INFINITY);
            for x in world_points(&camera, &pan.0, 300, 5) {
                let Some(bound) = m.line_rate_bound(&rate, x) else {
                    continue;
                };
                let measured = measured_line_rate(&camera, &m, readout, x)
                    .expect("a bounded point stays in the lens's domain");
                assert!(
                    measured <= bound,
                    "{} {readout}: {x}: the line time moves at {measured}, bound {bound}",
                    camera.model_name()
                );
                if bound <= MAX_CONTRACTION {
                    contracting += 1;
                }
                tightest = tightest.min(bound / measured.max(1e-12));
                checked += 1;
            }
            assert!(
                checked > 200,
                "{} {readout}: {checked} points bounded",
                camera.model_name()
            );
            println!(
                "{} {readout}: {checked} points, bound/measured ≥ {tightest:.2}, cone {:.3}, rates {:.3} .. {:.3}",
                camera.model_name(),
                rate.cone,
                rate.per_radian[0],
                rate.per_radian[RATE_TABLE - 1]
            );
        }
    }
    assert!(
        contracting > 1000,
        "the scan is skipped for most points ({contracting})"
    );
}

#[test]
fn a_frame_bound_over_a_distance_covers_every_point_beyond_it() {
    let (start, end) = moving();
    let m = FrameMotion::new(start, end);
    let camera = standard();
    let points = world_points(&camera, &start, 200, 9);
    let nearest = points
        .iter()
        .map(|&x| m.distance_to_path(x))
        .fold(f64::INFINITY, f64::min);
    assert!(nearest > 1.0);
    let frame = m.angular_speed_bound_beyond(nearest);
    for &x in &points {
        assert!(m.angular_speed_bound(x) <= frame);
    }
    // A box that touches the centres' path: no bound.
    assert_eq!(m.angular_speed_bound_beyond(0.0), f64::INFINITY);
    // The distance to the segment, not to its line: past C1 the point is nearer C1.
    let [_, c1] = m.centres();
    let beyond = c1 + (c1 - m.centres()[0]).normalize() * 2.0;
    assert!((m.distance_to_path(beyond) - 2.0).abs() < 1e-12);
}
