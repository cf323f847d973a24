//! What stereo rectification promises, whatever the numbers: rectified points of a pair share
//! their row (their column for a vertical pair), Q takes a pixel and its disparity back to the
//! point, R1 and R2 turn both cameras parallel, alpha 0 and 1 keep what OpenCV documents, the
//! options do what their names say; and every refusal names its argument. The numbers
//! themselves are checked against OpenCV in `python/tests/test_stereo.py`.

use glam::{DMat3, DVec2, DVec3};

use super::*;
use crate::model::{Fisheye, Lens};
use crate::ErrorKind;

fn intrinsics(fx: f64, fy: f64, cx: f64, cy: f64) -> Intrinsics {
    Intrinsics { fx, fy, cx, cy }
}

fn left() -> Camera {
    let k = intrinsics(600.0, 610.0, 330.2, 236.9);
    Camera::from_coeffs(640, 480, k, &[-0.05, 0.01, 0.001, -0.0015, 0.0]).unwrap()
}

fn right() -> Camera {
    let k = intrinsics(605.0, 603.0, 322.2, 240.1);
    Camera::from_coeffs(640, 480, k, &[-0.06, 0.012, -0.0005, 0.001, 0.0]).unwrap()
}

fn fisheye(fx: f64, fy: f64, cx: f64, cy: f64, k: [f64; 4]) -> Camera {
    let lens = Fisheye::new(k, 0.0, None).unwrap();
    Camera::fisheye(1280, 800, intrinsics(fx, fy, cx, cy), lens).unwrap()
}

/// A fisheye pair whose frames stay well inside 90° off the axis, turned as a vertical pair
/// turns them too.
fn fisheye_pair_cameras() -> (Camera, Camera) {
    (
        fisheye(700.0, 698.0, 638.0, 402.5, [0.02, -0.004, 0.001, -0.0002]),
        fisheye(702.0, 705.0, 641.0, 399.5, [0.018, -0.003, 0.0012, -0.0001]),
    )
}

/// A horizontal pair: the second camera 12 cm to the right (X2 = R X1 + T, T = -C2).
const HORIZONTAL: ([f64; 3], [f64; 3]) = ([0.01, -0.02, 0.005], [-0.12, 0.003, 0.001]);
/// A vertical pair: the second camera 10 cm below.
const VERTICAL: ([f64; 3], [f64; 3]) = ([0.01, 0.02, -0.01], [0.002, -0.1, 0.004]);

fn rect(
    a: &Camera,
    b: &Camera,
    (r, t): ([f64; 3], [f64; 3]),
    options: StereoOptions,
) -> StereoRectification {
    stereo_rectify(a, b, r, t, &options).unwrap()
}

/// Points in the first camera's frame that both cameras see.
fn scene_points() -> Vec<DVec3> {
    let mut points = Vec::new();
    for z in [0.8, 2.0, 7.5] {
        for (x, y) in [(0.0, 0.0), (-0.2, 0.15), (0.25, -0.1), (0.1, 0.2)] {
            points.push(DVec3::new(x * z, y * z, z));
        }
    }
    points
}

fn apply(m: [[f64; 4]; 3], x: DVec3) -> DVec2 {
    let v: [f64; 3] =
        std::array::from_fn(|i| m[i][0] * x.x + m[i][1] * x.y + m[i][2] * x.z + m[i][3]);
    DVec2::new(v[0] / v[2], v[1] / v[2])
}

fn apply4(q: [[f64; 4]; 4], v: [f64; 4]) -> DVec3 {
    let h: [f64; 4] = std::array::from_fn(|i| (0..4).map(|j| q[i][j] * v[j]).sum());
    DVec3::new(h[0] / h[3], h[1] / h[3], h[2] / h[3])
}

/// Rectified pixels of a point seen from the first camera's frame, through each camera's own
/// rectified frame, and through P2 from the first's.
fn rectified_pixels(
    s: &StereoRectification,
    (r, t): ([f64; 3], [f64; 3]),
    x1: DVec3,
) -> [DVec2; 3] {
    let r = rodrigues(DVec3::from_array(r));
    let x2 = r * x1 + DVec3::from_array(t);
    let xr1 = mat3(s.r1) * x1;
    let xr2 = mat3(s.r2) * x2;
    let pin = |c: &Camera, x: DVec3| c.intrinsics.to_pixel(DVec2::new(x.x / x.z, x.y / x.z));
    [pin(&s.left, xr1), pin(&s.right, xr2), apply(s.p2, xr1)]
}

#[test]
fn rectified_points_share_their_row_and_q_gives_them_back() {
    for (pair, across) in [(HORIZONTAL, 1), (VERTICAL, 0)] {
        for zero_disparity in [true, false] {
            for alpha in [None, Some(0.0), Some(0.7)] {
                let options = StereoOptions {
                    alpha,
                    zero_disparity,
                    ..StereoOptions::default()
                };
                let s = rect(&left(), &right(), pair, options);
                assert_eq!(s.vertical, across == 0);
                for x1 in scene_points() {
                    let [p1, p2, via_p2] = rectified_pixels(&s, pair, x1);
                    // The shared coordinate: the row (y) of a horizontal pair.
                    assert!((p1[across] - p2[across]).abs() < 1e-9, "{p1} {p2}");
                    // P2 projects from the first camera's rectified frame.
                    assert!((p2 - via_p2).length() < 1e-9, "{p2} {via_p2}");
                    // Q: pixel and disparity back to the point, in the first rectified frame.
                    let along = 1 - across;
                    let d = p1[along] - p2[along];
                    let back = apply4(s.q, [p1.x, p1.y, d, 1.0]);
                    let want = mat3(s.r1) * x1;
                    assert!(
                        (back - want).length() < 1e-9 * want.length(),
                        "{back} {want}"
                    );
                }
            }
        }
    }
}

#[test]
fn r1_and_r2_turn_both_cameras_parallel() {
    for (r, t) in [HORIZONTAL, VERTICAL] {
        let s = rect(&left(), &right(), (r, t), StereoOptions::default());
        let (r1, r2) = (mat3(s.r1), mat3(s.r2));
        for m in [r1, r2] {
            assert!((m.transpose() * m - DMat3::IDENTITY).abs_diff_eq(DMat3::ZERO, 1e-14));
            assert!((m.determinant() - 1.0).abs() < 1e-14);
        }
        // Both rectified frames are parallel: R2 R R1ᵀ = I.
        let r = rodrigues(DVec3::from_array(r));
        assert!((r2 * r * r1.transpose()).abs_diff_eq(DMat3::IDENTITY, 1e-14));
        // The baseline lies along one axis of the rectified frame.
        let along = (r2 * DVec3::from_array(t)).abs();
        let main = if s.vertical { along.y } else { along.x };
        assert!(main > 1e6 * (along.x + along.y + along.z - main));
        assert!((s.baseline() - DVec3::from_array(t).length()).abs() < 1e-15);
    }
}

#[test]
fn zero_disparity_shares_the_principal_point() {
    for pair in [HORIZONTAL, VERTICAL] {
        let on = rect(&left(), &right(), pair, StereoOptions::default());
        let c = |s: &StereoRectification| (s.left.intrinsics, s.right.intrinsics);
        let (a, b) = c(&on);
        assert_eq!((a.cx, a.cy), (b.cx, b.cy));
        let off = rect(
            &left(),
            &right(),
            pair,
            StereoOptions {
                zero_disparity: false,
                ..StereoOptions::default()
            },
        );
        let (a, b) = c(&off);
        // Only the coordinate across the baseline is shared.
        if off.vertical {
            assert!(a.cx == b.cx && a.cy != b.cy);
        } else {
            assert!(a.cy == b.cy && a.cx != b.cx);
        }
        // The one focal length of both, in P and in the cameras.
        for s in [&on, &off] {
            let f = s.p1[0][0];
            for k in [s.left.intrinsics, s.right.intrinsics] {
                assert!(k.fx == f && k.fy == f);
            }
            assert!(s.p1[1][1] == f && s.p2[0][0] == f && s.p2[1][1] == f);
        }
    }
}

/// Half a pixel past the pixel centres at the edges: the image's extent.
fn inside(p: DVec2, width: u32, height: u32) -> bool {
    let slack = 0.5 + 1e-6;
    p.x >= -slack
        && p.y >= -slack
        && p.x <= width as f64 - 1.0 + slack
        && p.y <= height as f64 - 1.0 + slack
}

/// Where a rectified pixel takes its light from in the lens image.
fn source_of(lens: &Camera, r: [[f64; 3]; 3], new: &Camera, p: DVec2) -> Option<DVec2> {
    let ray = mat3(r).transpose() * new.intrinsics.to_normalized(p).extend(1.0);
    lens.project(ray)
}

/// Where a lens pixel lands in the rectified image.
fn lands_at(lens: &Camera, r: [[f64; 3]; 3], new: &Camera, p: DVec2) -> Option<DVec2> {
    let ray = mat3(r) * lens.unproject(p)?;
    (ray.z > 0.0).then(|| {
        new.intrinsics
            .to_pixel(DVec2::new(ray.x / ray.z, ray.y / ray.z))
    })
}

fn pixels(x0: u32, y0: u32, w: u32, h: u32, step: usize) -> impl Iterator<Item = DVec2> {
    (y0..y0 + h)
        .step_by(step)
        .chain([y0 + h - 1])
        .flat_map(move |y| {
            (x0..x0 + w)
                .step_by(step)
                .chain([x0 + w - 1])
                .map(move |x| DVec2::new(x as f64, y as f64))
        })
}

#[test]
fn alpha_zero_keeps_only_pixels_with_a_source_and_one_keeps_every_source_pixel() {
    let (a, b) = (left(), right());
    for pair in [HORIZONTAL, VERTICAL] {
        for new_size in [None, Some((800, 500))] {
            let options = |alpha| StereoOptions {
                alpha: Some(alpha),
                new_size,
                ..StereoOptions::default()
            };
            let tight = rect(&a, &b, pair, options(0.0));
            let wide = rect(&a, &b, pair, options(1.0));
            for (lens, r, new, roi) in [
                (&a, tight.r1, &tight.left, tight.roi1),
                (&b, tight.r2, &tight.right, tight.roi2),
            ] {
                let (w, h) = (new.width, new.height);
                // Nothing is left without a source at alpha 0: the ROI is (nearly) all of it.
                assert!(roi.2 + 2 >= w && roi.3 + 2 >= h, "{roi:?} of {w}×{h}");
                for p in pixels(0, 0, w, h, 9) {
                    let s = source_of(lens, r, new, p);
                    assert!(
                        s.is_some_and(|s| inside(s, lens.width, lens.height)),
                        "alpha 0: rectified pixel {p} samples {s:?}"
                    );
                }
            }
            for (lens, r, new) in [(&a, wide.r1, &wide.left), (&b, wide.r2, &wide.right)] {
                for p in pixels(0, 0, lens.width, lens.height, 9) {
                    let at = lands_at(lens, r, new, p);
                    assert!(
                        at.is_some_and(|q| inside(q, new.width, new.height)),
                        "alpha 1: lens pixel {p} lands at {at:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn the_roi_holds_only_pixels_with_a_source() {
    let (a, b) = (left(), right());
    for pair in [HORIZONTAL, VERTICAL] {
        for alpha in [None, Some(0.5), Some(1.0)] {
            let s = rect(
                &a,
                &b,
                pair,
                StereoOptions {
                    alpha,
                    ..StereoOptions::default()
                },
            );
            for (lens, r, new, (x, y, w, h)) in
                [(&a, s.r1, &s.left, s.roi1), (&b, s.r2, &s.right, s.roi2)]
            {
                assert!(w > 0 && h > 0 && x + w <= new.width && y + h <= new.height);
                for p in pixels(x, y, w, h, 7) {
                    let src = source_of(lens, r, new, p);
                    assert!(
                        src.is_some_and(|q| inside(q, lens.width, lens.height)),
                        "alpha {alpha:?}: ROI pixel {p} samples {src:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn alpha_none_keeps_the_mean_focal_length_scaled_to_the_new_size() {
    let (a, b) = (left(), right());
    let s = rect(&a, &b, HORIZONTAL, StereoOptions::default());
    let fy = (a.intrinsics.fy + b.intrinsics.fy) / 2.0;
    assert!((s.p1[0][0] - fy).abs() < 1e-12);
    let big = rect(
        &a,
        &b,
        HORIZONTAL,
        StereoOptions {
            new_size: Some((960, 720)),
            ..StereoOptions::default()
        },
    );
    assert_eq!((big.left.width, big.left.height), (960, 720));
    assert_eq!((big.right.width, big.right.height), (960, 720));
    assert!((big.p1[0][0] - fy * 1.5).abs() < 1e-12);
    // OpenCV centres the corners with the focal length already scaled, then scales that
    // centre to the new image: the corners' mean offset from the centre grows by 1.5 twice.
    for (axis, centre) in [(0, 319.5), (1, 239.5)] {
        let offset = centre - s.p1[axis][2];
        let want = 1.5 * (centre - 1.5 * offset);
        // The corners are rounded to f32 as OpenCV holds them.
        assert!(
            (big.p1[axis][2] - want).abs() < 1e-4,
            "{} {want}",
            big.p1[axis][2]
        );
    }
    // A vertical pair takes the mean fx, scaled by the new width.
    let v = rect(&a, &b, VERTICAL, StereoOptions::default());
    let fx = (a.intrinsics.fx + b.intrinsics.fx) / 2.0;
    assert!((v.p1[0][0] - fx).abs() < 1e-12);
}

#[test]
fn an_aligned_pinhole_pair_keeps_its_cameras() {
    // Two identical pinhole cameras side by side, already parallel: nothing to turn, and the
    // corners centre on the cameras' own principal point.
    let k = intrinsics(500.0, 500.0, 321.5, 241.0);
    let cam = Camera::from_coeffs(640, 480, k, &[0.0; 5]).unwrap();
    let s = stereo_rectify(
        &cam,
        &cam,
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        [-0.1, 0.0, 0.0],
        &StereoOptions::default(),
    )
    .unwrap();
    for r in [s.r1, s.r2] {
        assert!(mat3(r).abs_diff_eq(DMat3::IDENTITY, 1e-15));
    }
    for c in [&s.left, &s.right] {
        let got = c.intrinsics;
        assert!((got.fx - 500.0).abs() < 1e-12 && (got.fy - 500.0).abs() < 1e-12);
        // The corners are rounded to f32 as OpenCV holds them.
        assert!(
            (got.cx - 321.5).abs() < 1e-4 && (got.cy - 241.0).abs() < 1e-4,
            "{got:?}"
        );
    }
    assert!((s.p2[0][3] - -0.1 * 500.0).abs() < 1e-12);
    // The inner rectangle spans the pixel centres 0..=w-1, one pixel short of the image.
    assert_eq!(s.roi1, (0, 0, 639, 479));
}

#[test]
fn a_rotation_matrix_and_its_rodrigues_vector_rectify_alike() {
    let (a, b) = (left(), right());
    for (r, t) in [HORIZONTAL, VERTICAL] {
        let m = rows3(rodrigues(DVec3::from_array(r)));
        let by_vector = stereo_rectify(&a, &b, r, t, &StereoOptions::default()).unwrap();
        let by_matrix = stereo_rectify(&a, &b, m, t, &StereoOptions::default()).unwrap();
        for (x, y) in by_vector
            .p1
            .iter()
            .chain(&by_vector.p2)
            .flatten()
            .zip(by_matrix.p1.iter().chain(&by_matrix.p2).flatten())
        {
            assert!((x - y).abs() <= 1e-9 * x.abs().max(1.0), "{x} {y}");
        }
    }
    // A matrix a little off a rotation (six printed decimals) is taken as the nearest one.
    let m = rows3(rodrigues(DVec3::from_array(HORIZONTAL.0)));
    let printed = m.map(|row| row.map(|v| (v * 1e6).round() / 1e6));
    let s = stereo_rectify(&a, &b, printed, HORIZONTAL.1, &StereoOptions::default()).unwrap();
    let exact = stereo_rectify(&a, &b, m, HORIZONTAL.1, &StereoOptions::default()).unwrap();
    assert!((s.p1[0][2] - exact.p1[0][2]).abs() < 1e-2);
}

#[test]
fn rodrigues_reads_a_matrix_back_as_opencv_does() {
    // Away from a half turn the angle is exact to rounding; at one, acos near -1 leaves it
    // as close as OpenCV's, the square root of rounding (1e-8).
    for (v, tolerance) in [
        (DVec3::new(0.1, -0.2, 0.3), 1e-12),
        (DVec3::new(-1.2, 0.4, 2.0), 1e-12),
        (DVec3::new(0.0, 0.0, 3.0), 1e-12),
        (DVec3::new(0.0, std::f64::consts::PI, 0.0), 1e-7),
        (
            DVec3::new(1.0, 2.0, -2.0).normalize() * std::f64::consts::PI,
            1e-7,
        ),
    ] {
        let back = rodrigues_of(rodrigues(v));
        // The same rotation (at a half turn ±axis are one rotation), with an angle in [0, π].
        assert!(
            rodrigues(back).abs_diff_eq(rodrigues(v), tolerance),
            "{v} → {back}"
        );
        assert!(back.length() <= std::f64::consts::PI + 1e-12);
    }
    // Just short of a half turn OpenCV still takes the axis from the diagonal, which is off by
    // the square root of the distance to π.
    let v = DVec3::new(0.0, std::f64::consts::PI - 1e-7, 0.0);
    assert!(rodrigues(rodrigues_of(rodrigues(v))).abs_diff_eq(rodrigues(v), 1e-6));
    // OpenCV reads a turn this small as none.
    assert_eq!(
        rodrigues_of(rodrigues(DVec3::new(1e-6, 0.0, 0.0))),
        DVec3::ZERO
    );
    // A matrix close to orthogonal has the nearest rotation for its polar factor.
    let r = rodrigues(DVec3::new(0.3, -0.1, 0.2));
    let noisy = r + DMat3::from_cols_array(&[1e-7, -2e-7, 0.0, 3e-7, 0.0, 1e-7, 0.0, -1e-7, 2e-7]);
    let fixed = nearest_rotation(noisy);
    assert!((fixed.transpose() * fixed).abs_diff_eq(DMat3::IDENTITY, 1e-15));
    assert!(fixed.abs_diff_eq(r, 5e-7));
}

#[test]
fn a_fisheye_pair_shares_its_rows_whichever_way_it_is_stacked() {
    let (a, b) = fisheye_pair_cameras();
    for pair in [HORIZONTAL, VERTICAL] {
        for (balance, fov_scale, new_size) in [(0.0, 1.0, None), (1.0, 1.3, Some((1920, 1080)))] {
            let options = StereoOptions {
                balance,
                fov_scale,
                new_size,
                ..StereoOptions::default()
            };
            let s = rect(&a, &b, pair, options);
            // OpenCV's fisheye rule lays every baseline along the rows.
            assert!(!s.vertical);
            let size = new_size.unwrap_or((1280, 800));
            assert_eq!(
                (s.roi1, s.roi2),
                ((0, 0, size.0, size.1), (0, 0, size.0, size.1))
            );
            // The smaller of the two cameras' fy, each from the fisheye rule with R1 or R2.
            let fy = |cam: &Camera, r| {
                fisheye_rule(cam, mat3(r), balance, fov_scale, Some(size))
                    .unwrap()
                    .intrinsics
                    .fy
            };
            assert_eq!(s.p1[0][0], fy(&a, s.r1).min(fy(&b, s.r2)));
            for x1 in scene_points() {
                let [p1, p2, via_p2] = rectified_pixels(&s, pair, x1);
                assert!((p1.y - p2.y).abs() < 1e-9 && (p2 - via_p2).length() < 1e-9);
                let back = apply4(s.q, [p1.x, p1.y, p1.x - p2.x, 1.0]);
                let want = mat3(s.r1) * x1;
                assert!((back - want).length() < 1e-9 * want.length());
            }
        }
    }
}

#[test]
fn refusals_name_the_argument() {
    let (a, b) = (left(), right());
    let (fa, fb) = fisheye_pair_cameras();
    let ucm = Camera::with_lens(
        640,
        480,
        intrinsics(300.0, 300.0, 320.0, 240.0),
        Lens::Ucm(crate::model::ucm::Ucm::new(0.6).unwrap()),
    )
    .unwrap();
    let small =
        Camera::from_coeffs(320, 240, intrinsics(300.0, 300.0, 160.0, 120.0), &[0.0; 5]).unwrap();
    let (r, t) = HORIZONTAL;
    let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let mirror = [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let sheared = [[1.0, 0.01, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let d = StereoOptions::default();
    let run = |a: &Camera, b: &Camera, o: StereoOptions| stereo_rectify(a, b, r, t, &o);
    let cases: Vec<(&str, &str, Result<StereoRectification>)> = vec![
        ("left", "`ucm`", run(&ucm, &b, d)),
        ("right", "`ucm`", run(&a, &ucm, d)),
        ("right", "opencv_fisheye", run(&a, &fb, d)),
        ("right", "320×240", run(&a, &small, d)),
        ("R", "not a rotation", stereo_rectify(&a, &b, mirror, t, &d)),
        (
            "R",
            "not a rotation",
            stereo_rectify(&a, &b, sheared, t, &d),
        ),
        (
            "R",
            "finite",
            stereo_rectify(&a, &b, [f64::NAN, 0.0, 0.0], t, &d),
        ),
        (
            "T",
            "not zero",
            stereo_rectify(&a, &b, identity, [0.0; 3], &d),
        ),
        (
            "T",
            "finite",
            stereo_rectify(&a, &b, r, [f64::INFINITY, 0.0, 0.0], &d),
        ),
        (
            "alpha",
            "0..=1",
            run(
                &a,
                &b,
                StereoOptions {
                    alpha: Some(1.5),
                    ..d
                },
            ),
        ),
        (
            "alpha",
            "0..=1",
            run(
                &a,
                &b,
                StereoOptions {
                    alpha: Some(f64::NAN),
                    ..d
                },
            ),
        ),
        (
            "alpha",
            "balance",
            run(
                &fa,
                &fb,
                StereoOptions {
                    alpha: Some(0.5),
                    ..d
                },
            ),
        ),
        (
            "balance",
            "alpha",
            run(&a, &b, StereoOptions { balance: 0.5, ..d }),
        ),
        (
            "fov_scale",
            "alpha",
            run(
                &a,
                &b,
                StereoOptions {
                    fov_scale: 2.0,
                    ..d
                },
            ),
        ),
        (
            "balance",
            "0..=1",
            run(&fa, &fb, StereoOptions { balance: 2.0, ..d }),
        ),
        (
            "fov_scale",
            "positive",
            run(
                &fa,
                &fb,
                StereoOptions {
                    fov_scale: 0.0,
                    ..d
                },
            ),
        ),
        (
            "new_size",
            "",
            run(
                &a,
                &b,
                StereoOptions {
                    new_size: Some((0, 10)),
                    ..d
                },
            ),
        ),
        // A baseline along the viewing direction: rectifying turns each camera by 90°.
        (
            "left",
            "behind",
            stereo_rectify(&a, &b, identity, [0.0, 0.0, 0.2], &d),
        ),
    ];
    for (argument, words, result) in cases {
        let e = result.expect_err(argument);
        assert_eq!(e.kind(), ErrorKind::Input, "{e}");
        assert_eq!(e.argument_name(), Some(argument), "{e}");
        assert!(e.to_string().contains(words), "{argument}: {e}");
    }
}
