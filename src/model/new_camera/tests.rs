//! The two rules' refusals, and what the rules promise: at `alpha` 0 every pixel of the new
//! image has a source, at `alpha` 1 every source pixel lands in the new image, the ROI holds
//! only pixels with a source, and the fisheye rule's `balance` and `fov_scale` move the edges
//! as OpenCV documents.

use glam::DVec2;

use super::*;
use crate::model::{CameraModel, Fisheye, Lens};

/// A standard-model camera of `width`×`height`, principal point off the centre.
fn standard(coeffs: &[f64], width: u32, height: u32) -> Camera {
    let k = Intrinsics {
        fx: 0.8 * width as f64,
        fy: 0.82 * width as f64,
        cx: width as f64 / 2.0 - 3.25,
        cy: height as f64 / 2.0 + 2.5,
    };
    Camera::from_coeffs(width, height, k, coeffs).unwrap()
}

fn fisheye(k: [f64; 4]) -> Camera {
    let intrinsics = Intrinsics {
        fx: 420.0,
        fy: 410.0,
        cx: 638.0,
        cy: 402.5,
    };
    Camera::fisheye(1280, 800, intrinsics, Fisheye::new(k, 0.0, None).unwrap()).unwrap()
}

/// Lenses the rules are meant for: barrel, barrel with tangential terms, pincushion, and a
/// rational lens, each at a small size so that every pixel can be checked.
fn lenses() -> Vec<Camera> {
    vec![
        standard(&[-0.28, 0.07, 0.0, 0.0, 0.0], 160, 120),
        standard(&[-0.2, 0.05, 0.004, -0.003, -0.01], 200, 130),
        standard(&[0.12, 0.02, 0.0, 0.0], 150, 150),
        standard(&[0.3, -0.05, 0.001, 0.002, 0.0, 0.45, -0.02, 0.0], 170, 110),
    ]
}

/// Half a pixel past the pixel centres at the edges: the image's extent.
fn inside(p: DVec2, width: u32, height: u32) -> bool {
    let slack = 0.5 + 1e-9;
    p.x >= -slack
        && p.y >= -slack
        && p.x <= width as f64 - 1.0 + slack
        && p.y <= height as f64 - 1.0 + slack
}

fn pixels(width: u32, height: u32) -> impl Iterator<Item = DVec2> {
    (0..height).flat_map(move |y| (0..width).map(move |x| DVec2::new(x as f64, y as f64)))
}

/// Where a pixel of the new (pinhole) image takes its light from in the lens image.
fn source_of(lens: &Camera, new: &Camera, p: DVec2) -> Option<DVec2> {
    let x = new.intrinsics.to_normalized(p);
    lens.distort_normalized(x)
        .map(|y| lens.intrinsics.to_pixel(y))
}

/// Where a lens pixel lands in the new image.
fn lands_at(lens: &Camera, new: &Camera, p: DVec2) -> Option<DVec2> {
    lens.undistort_pixel(p, InverseMethod::Newton).map(|ideal| {
        new.intrinsics
            .to_pixel(lens.intrinsics.to_normalized(ideal))
    })
}

#[test]
fn alpha_zero_leaves_no_pixel_without_a_source() {
    for lens in lenses() {
        for (new_size, centred) in [
            (None, false),
            (Some((lens.width + 40, lens.height - 10)), false),
            (None, true),
        ] {
            let (new, roi) = optimal_new_camera(&lens, 0.0, new_size, centred).unwrap();
            assert!(new.is_pinhole());
            let (w, h) = new_size.unwrap_or((lens.width, lens.height));
            assert_eq!((new.width, new.height), (w, h));
            for p in pixels(w, h) {
                let s = source_of(&lens, &new, p);
                assert!(
                    s.is_some_and(|s| inside(s, lens.width, lens.height)),
                    "{:?} centred={centred}: new pixel {p} samples {s:?}, outside {}×{}",
                    lens.dist_coeffs(),
                    lens.width,
                    lens.height
                );
            }
            // Nothing is filled at alpha 0: the ROI is (nearly) the whole image.
            assert!(roi.2 + 2 >= w && roi.3 + 2 >= h, "{roi:?} of {w}×{h}");
        }
    }
}

#[test]
fn alpha_one_keeps_every_source_pixel() {
    for lens in lenses() {
        for (new_size, centred) in [
            (None, false),
            (Some((lens.width / 2, lens.height + 30)), false),
            (None, true),
        ] {
            let (new, _) = optimal_new_camera(&lens, 1.0, new_size, centred).unwrap();
            for p in pixels(lens.width, lens.height) {
                let at = lands_at(&lens, &new, p);
                assert!(
                    at.is_some_and(|q| inside(q, new.width, new.height)),
                    "{:?} centred={centred}: lens pixel {p} lands at {at:?}, outside {}×{}",
                    lens.dist_coeffs(),
                    new.width,
                    new.height
                );
            }
        }
    }
}

#[test]
fn the_roi_holds_only_pixels_with_a_source() {
    for lens in lenses() {
        for alpha in [0.0, 0.5, 1.0] {
            for centred in [false, true] {
                let (new, (x, y, w, h)) = optimal_new_camera(&lens, alpha, None, centred).unwrap();
                assert!(w > 0 && h > 0 && x + w <= new.width && y + h <= new.height);
                for p in pixels(w, h) {
                    let p = p + DVec2::new(x as f64, y as f64);
                    let s = source_of(&lens, &new, p);
                    assert!(
                        s.is_some_and(|s| inside(s, lens.width, lens.height)),
                        "alpha {alpha} centred={centred}: ROI pixel {p} samples {s:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn alpha_blends_between_the_two_cameras() {
    let lens = &lenses()[0];
    let f = |a: f64| {
        optimal_new_camera(lens, a, None, false)
            .unwrap()
            .0
            .intrinsics
    };
    let (k0, k1, kh) = (f(0.0), f(1.0), f(0.5));
    // Barrel: keeping every source pixel takes a shorter focal length.
    assert!(k1.fx < k0.fx && k1.fy < k0.fy);
    for (a, b, m) in [
        (k0.fx, k1.fx, kh.fx),
        (k0.fy, k1.fy, kh.fy),
        (k0.cx, k1.cx, kh.cx),
        (k0.cy, k1.cy, kh.cy),
    ] {
        assert!((m - (a + b) / 2.0).abs() <= 1e-9 * m.abs());
    }
}

#[test]
fn a_pinhole_camera_gets_itself_back() {
    let lens = standard(&[0.0; 5], 320, 240);
    for alpha in [0.0, 1.0] {
        let (new, roi) = optimal_new_camera(&lens, alpha, None, false).unwrap();
        let (a, b) = (new.intrinsics, lens.intrinsics);
        for (x, y) in [(a.fx, b.fx), (a.fy, b.fy), (a.cx, b.cx), (a.cy, b.cy)] {
            assert!((x - y).abs() <= 1e-9 * y.abs(), "{a:?} vs {b:?}");
        }
        assert_eq!(roi, (0, 0, 319, 239));
    }
}

#[test]
fn refusals_name_the_argument() {
    let lens = &lenses()[0];
    let cases: Vec<(&str, Result<(Camera, Roi)>)> = vec![
        ("alpha", optimal_new_camera(lens, -0.1, None, false)),
        ("alpha", optimal_new_camera(lens, 1.5, None, false)),
        ("alpha", optimal_new_camera(lens, f64::NAN, None, false)),
        (
            "new_size",
            optimal_new_camera(lens, 0.5, Some((0, 100)), false),
        ),
        (
            "new_size",
            optimal_new_camera(lens, 0.5, Some((100, 0)), false),
        ),
        (
            "new_size",
            optimal_new_camera(
                lens,
                0.5,
                Some((crate::model::MAX_IMAGE_SIDE + 1, 10)),
                false,
            ),
        ),
        (
            "alpha",
            optimal_new_camera(&fisheye([0.0; 4]), 0.5, None, false),
        ),
        ("balance", fisheye_new_camera(lens, 0.5, 1.0, None)),
        (
            "balance",
            fisheye_new_camera(&fisheye([0.0; 4]), -1.0, 1.0, None),
        ),
        (
            "balance",
            fisheye_new_camera(&fisheye([0.0; 4]), f64::NAN, 1.0, None),
        ),
        (
            "fov_scale",
            fisheye_new_camera(&fisheye([0.0; 4]), 0.5, 0.0, None),
        ),
        (
            "fov_scale",
            fisheye_new_camera(&fisheye([0.0; 4]), 0.5, -2.0, None),
        ),
        (
            "fov_scale",
            fisheye_new_camera(&fisheye([0.0; 4]), 0.5, f64::INFINITY, None),
        ),
        (
            "new_size",
            fisheye_new_camera(&fisheye([0.0; 4]), 0.5, 1.0, Some((0, 0))),
        ),
    ];
    for (argument, result) in cases {
        let e = result.expect_err(argument);
        assert_eq!(e.kind(), crate::ErrorKind::Input, "{e}");
        assert_eq!(e.argument_name(), Some(argument), "{e}");
    }
    // The wrong model is named, with the rule it takes instead.
    let e = optimal_new_camera(&fisheye([0.0; 4]), 0.5, None, false).unwrap_err();
    assert!(
        e.to_string().contains("opencv_fisheye") && e.to_string().contains("balance"),
        "{e}"
    );
    let e = fisheye_new_camera(lens, 0.5, 1.0, None).unwrap_err();
    assert!(
        e.to_string().contains("`opencv`") && e.to_string().contains("alpha"),
        "{e}"
    );
    let ucm = Camera::with_lens(
        640,
        480,
        Intrinsics {
            fx: 300.0,
            fy: 300.0,
            cx: 320.0,
            cy: 240.0,
        },
        Lens::Ucm(crate::model::ucm::Ucm::new(0.6).unwrap()),
    )
    .unwrap();
    for e in [
        optimal_new_camera(&ucm, 0.5, None, false).unwrap_err(),
        fisheye_new_camera(&ucm, 0.5, 1.0, None).unwrap_err(),
    ] {
        assert!(e.to_string().contains("`ucm`"), "{e}");
    }
}

#[test]
fn a_lens_that_folds_inside_the_image_is_refused() {
    // k1 = -0.6 folds at r² = 1/(3·0.6): the corners of this image are past it.
    let lens = standard(&[-0.6, 0.0, 0.0, 0.0, 0.0], 640, 480);
    let e = optimal_new_camera(&lens, 0.0, None, false).unwrap_err();
    assert_eq!(e.argument_name(), Some("camera"), "{e}");
    assert!(e.to_string().contains("folds"), "{e}");
}

#[test]
fn a_fisheye_whose_edges_see_past_90_degrees_is_refused() {
    // θ_d = θ: the right edge, 642 px from the principal point at f = 380, is 97° off the axis;
    // clipped at θ_d = π/2 it is still 90°.
    let intrinsics = Intrinsics {
        fx: 380.0,
        fy: 380.0,
        cx: 638.0,
        cy: 402.5,
    };
    let lens = Fisheye::new([0.0; 4], 0.0, None).unwrap();
    let wide = Camera::fisheye(1280, 800, intrinsics, lens).unwrap();
    let e = fisheye_new_camera(&wide, 0.0, 1.0, None).unwrap_err();
    assert_eq!(e.argument_name(), Some("camera"), "{e}");
    assert!(e.to_string().contains("clipped"), "{e}");
}

/// A fisheye whose frame stays inside 90° off the axis, with square pixels: OpenCV's rule
/// scales y by fx / fy to find the focal length and divides the new principal point by it
/// again, which puts the edges where its documentation says only when fx = fy (vklens keeps
/// the rule as OpenCV computes it, for the cameras to agree).
fn narrow_fisheye() -> Camera {
    let intrinsics = Intrinsics {
        fx: 700.0,
        fy: 700.0,
        cx: 636.0,
        cy: 404.0,
    };
    let lens = Fisheye::new([-0.02, 0.004, -0.001, 0.0002], 0.0, None).unwrap();
    Camera::fisheye(1280, 800, intrinsics, lens).unwrap()
}

/// The four edge midpoints (OpenCV's) in the new camera's pixels.
fn midpoints_in(lens: &Camera, new: &Camera) -> [DVec2; 4] {
    let (w, h) = (lens.width, lens.height);
    [
        DVec2::new((w / 2) as f64, 0.0),
        DVec2::new(w as f64, (h / 2) as f64),
        DVec2::new((w / 2) as f64, h as f64),
        DVec2::new(0.0, (h / 2) as f64),
    ]
    .map(|p| {
        let ray = lens.unproject(p).unwrap();
        new.intrinsics
            .to_pixel(DVec2::new(ray.x / ray.z, ray.y / ray.z))
    })
}

#[test]
fn balance_puts_the_edge_midpoints_on_or_inside_the_new_edges() {
    let lens = narrow_fisheye();
    let (w, h) = (lens.width as f64, lens.height as f64);
    // The distance of each midpoint beyond its edge of the new image (OpenCV's edges: 0 and
    // the size, in whole pixels).
    let overshoot = |new: &Camera| {
        let [top, right, bottom, left] = midpoints_in(&lens, new);
        [-top.y, right.x - w, bottom.y - h, -left.x]
    };
    let (wide, _) = fisheye_new_camera(&lens, 1.0, 1.0, None).unwrap();
    let (tight, _) = fisheye_new_camera(&lens, 0.0, 1.0, None).unwrap();
    // balance 1: the smallest focal length, every midpoint on or inside its edge, one on it.
    let o = overshoot(&wide);
    assert!(o.iter().all(|&d| d <= 1e-9), "{o:?}");
    assert!(o.iter().any(|&d| d.abs() <= 1e-9), "{o:?}");
    // balance 0: the largest, every midpoint on or past its edge.
    let o = overshoot(&tight);
    assert!(o.iter().all(|&d| d >= -1e-9), "{o:?}");
    assert!(o.iter().any(|&d| d.abs() <= 1e-9), "{o:?}");
}

#[test]
fn fov_scale_divides_the_focal_length_and_new_size_scales_the_camera() {
    let lens = narrow_fisheye();
    let (base, _) = fisheye_new_camera(&lens, 0.3, 1.0, None).unwrap();
    let (half, _) = fisheye_new_camera(&lens, 0.3, 2.0, None).unwrap();
    let (b, hk) = (base.intrinsics, half.intrinsics);
    assert!((hk.fx * 2.0 - b.fx).abs() < 1e-9 && (hk.fy * 2.0 - b.fy).abs() < 1e-9);
    // The undistorted centre of the midpoints stays at the image centre.
    let centre = |new: &Camera| midpoints_in(&lens, new).iter().sum::<DVec2>() / 4.0;
    let c = DVec2::new(lens.width as f64, lens.height as f64) / 2.0;
    assert!((centre(&base) - c).length() < 1e-9);
    assert!((centre(&half) - c).length() < 1e-9);
    let (big, _) = fisheye_new_camera(&lens, 0.3, 1.0, Some((1920, 1000))).unwrap();
    let k = big.intrinsics;
    assert_eq!((big.width, big.height), (1920, 1000));
    assert!((k.fx - b.fx * 1.5).abs() < 1e-9 && (k.fy - b.fy * 1.25).abs() < 1e-9);
    assert!((k.cx - b.cx * 1.5).abs() < 1e-9 && (k.cy - b.cy * 1.25).abs() < 1e-9);
}

#[test]
fn the_fisheye_roi_holds_only_pixels_with_a_source() {
    let lens = narrow_fisheye();
    for balance in [0.0, 1.0] {
        let (new, (x, y, w, h)) = fisheye_new_camera(&lens, balance, 1.0, None).unwrap();
        assert!(w > 0 && h > 0);
        for p in pixels(w, h).step_by(7) {
            let p = p + DVec2::new(x as f64, y as f64);
            let ray = new.intrinsics.to_normalized(p).extend(1.0);
            let s = lens.project(ray);
            assert!(
                s.is_some_and(|s| inside(s, lens.width, lens.height)),
                "balance {balance}: ROI pixel {p} samples {s:?}"
            );
        }
    }
}
