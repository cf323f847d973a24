//! The f64 models: round trips over random realistic cameras, Jacobians against finite
//! differences, the Sec. 3.1 projection, and the hard cases (fold-over, poles, the principal
//! point, huge images, NaN/Inf) — correct value, explicit invalid, or typed error; no panic.

use crate::model::{
    vulkan_projection, BrownRadial, Camera, CameraModel, Frustum, Intrinsics, InverseMethod,
    ModelError,
};
use glam::{DVec2, DVec3, DVec4};
use proptest::prelude::*;

fn camera(w: u32, h: u32, f: f64, coeffs: &[f64]) -> Camera {
    Camera::from_coeffs(
        w,
        h,
        Intrinsics {
            fx: f,
            fy: f,
            cx: (w as f64 - 1.0) / 2.0,
            cy: (h as f64 - 1.0) / 2.0,
        },
        coeffs,
    )
    .expect("valid camera")
}

prop_compose! {
    /// Cameras in the range real calibrations produce, every term group possibly on.
    fn realistic_camera()(
        f in 300.0..2000.0f64, aspect in 0.95..1.05f64,
        dcx in -20.0..20.0f64, dcy in -20.0..20.0f64,
        k1 in -0.4..0.4f64, k2 in -0.15..0.15f64, k3 in -0.03..0.03f64,
        p1 in -0.005..0.005f64, p2 in -0.005..0.005f64,
        rational in any::<bool>(), k4 in -0.2..0.2f64, k5 in -0.05..0.05f64, k6 in -0.01..0.01f64,
        prism in any::<bool>(), s in prop::array::uniform4(-0.003..0.003f64),
        tilt in any::<bool>(), tx in -0.03..0.03f64, ty in -0.03..0.03f64,
    ) -> Camera {
        let (w, h) = (1280u32, 800u32);
        let mut c = vec![k1, k2, p1, p2, k3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        if rational { c[5] = k4; c[6] = k5; c[7] = k6; }
        if prism { c[8..12].copy_from_slice(&s); }
        if tilt { c[12] = tx; c[13] = ty; }
        Camera::from_coeffs(w, h, Intrinsics {
            fx: f, fy: f * aspect, cx: 639.5 + dcx, cy: 399.5 + dcy,
        }, &c).expect("valid camera")
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn undistort_of_distort_is_identity_inside_the_domain(
        cam in realistic_camera(),
        u in -0.5..1279.5f64, v in -0.5..799.5f64,
    ) {
        let ideal = DVec2::new(u, v);
        prop_assume!(cam.ideal_in_domain(ideal));
        let distorted = cam.distort_pixel(ideal).expect("forward defined in the domain");
        let back = cam.undistort_pixel(distorted, InverseMethod::Newton);
        prop_assert!(back.is_some(), "Newton refused an in-domain point");
        let err = (back.unwrap() - ideal).length();
        prop_assert!(err < 1e-6, "round trip off by {err} px");
    }

    #[test]
    fn jacobian_matches_central_differences(cam in realistic_camera(), u in 0.0..1279.0f64, v in 0.0..799.0f64) {
        let p = DVec2::new(u, v);
        prop_assume!(cam.ideal_in_domain(p));
        let j = cam.distort_jacobian_pixel(p).expect("defined");
        let h = 1e-4;
        for (axis, col) in [(DVec2::X, j.x_axis), (DVec2::Y, j.y_axis)] {
            let fd = (cam.distort_pixel(p + axis * h).unwrap() - cam.distort_pixel(p - axis * h).unwrap()) / (2.0 * h);
            prop_assert!((fd - col).length() < 1e-6 * (1.0 + col.length()), "J column {col} vs finite difference {fd}");
        }
    }

    #[test]
    fn brown_round_trip_and_jacobian(c1 in -0.3..0.3f64, c2 in -0.1..0.1f64, u in 0.0..499.0f64, v in 0.0..499.0f64) {
        let m = BrownRadial::new(500, 500, c1, c2).expect("valid");
        let p = DVec2::new(u, v);
        prop_assume!(m.ideal_in_domain(p));
        let d = m.distort_pixel(p).unwrap();
        let back = m.undistort_pixel(d, InverseMethod::Newton).expect("in domain");
        prop_assert!((back - p).length() < 1e-6);
        let j = m.distort_jacobian_pixel(p).unwrap();
        let h = 1e-4;
        let fd = (m.distort_pixel(p + DVec2::X * h).unwrap() - m.distort_pixel(p - DVec2::X * h).unwrap()) / (2.0 * h);
        prop_assert!((fd - j.x_axis).length() < 1e-6);
    }
}

#[test]
fn brown_eq2_is_approximate_and_worsens_with_stronger_lenses() {
    // The Durham radial-correction paper: "the greater values of c1 and c2, the more f⁻¹(f(r)), f(f⁻¹(r)) and r diverge".
    let corner = DVec2::new(0.0, 0.0);
    let mut last = 0.0;
    for (c1, c2) in [(0.02, 0.01), (0.08, 0.04), (0.15, 0.10)] {
        let m = BrownRadial::new(500, 500, c1, c2).unwrap();
        let d = m.distort_pixel(corner).unwrap();
        let approx = m.undistort_pixel(d, InverseMethod::Heikkila).unwrap();
        let err = (approx - corner).length();
        assert!(
            err > last,
            "Eq. 2 error {err} px at c1={c1} should exceed {last}"
        );
        last = err;
    }
    // The Durham paper's own values leave a visible error at the corner; Newton leaves none.
    let m = BrownRadial::new(500, 500, 0.15, 0.10).unwrap();
    let d = m.distort_pixel(corner).unwrap();
    assert!((m.undistort_pixel(d, InverseMethod::Newton).unwrap() - corner).length() < 1e-9);
}

#[test]
fn projection_lands_on_opencv_pinhole_pixels() {
    let k = Intrinsics {
        fx: 400.0,
        fy: 410.0,
        cx: 399.5,
        cy: 299.5,
    };
    let (w, h) = (800u32, 600u32);
    let f = Frustum::from_intrinsics(&k, w, h);
    // Lambers et al.'s Sec. 3.1 formulas.
    assert_eq!(f.left, -(k.cx + 0.5) / k.fx);
    assert_eq!(f.right, w as f64 / k.fx + f.left);
    let (near, far) = (0.1, 100.0);
    let m = vulkan_projection(&f, near, far);
    for p in [
        DVec3::new(0.3, -0.2, 2.0),
        DVec3::new(-1.0, 0.7, 3.5),
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(2.0, 1.5, 1.0),
    ] {
        let clip = m * DVec4::new(p.x, p.y, p.z, 1.0);
        let ndc = clip.truncate() / clip.w;
        // Vulkan viewport: window = (ndc + 1) / 2 · size; OpenCV pixel = window − 0.5.
        let u = (ndc.x + 1.0) * 0.5 * w as f64 - 0.5;
        let v = (ndc.y + 1.0) * 0.5 * h as f64 - 0.5;
        let (eu, ev) = (k.fx * p.x / p.z + k.cx, k.fy * p.y / p.z + k.cy);
        assert!(
            (u - eu).abs() < 1e-9 && (v - ev).abs() < 1e-9,
            "({u}, {v}) vs OpenCV ({eu}, {ev})"
        );
    }
    // Depth 0..1 between the planes.
    let z = |d: f64| {
        let c = m * DVec4::new(0.0, 0.0, d, 1.0);
        c.z / c.w
    };
    assert!(z(near).abs() < 1e-12 && (z(far) - 1.0).abs() < 1e-12);
    // The image corners sit on the frustum's edges: pixel −0.5 ↔ NDC −1.
    let corner = m * DVec4::new(f.left, f.top, 1.0, 1.0);
    assert!((corner.x / corner.w + 1.0).abs() < 1e-12 && (corner.y / corner.w + 1.0).abs() < 1e-12);
}

/// Two cameras the property test above once failed on (CI, then a 30 000-case run): a strong
/// barrel lens with p2 and s4, whose fold is inside the image, and a wide rational lens with
/// prism terms. Both exposed a domain table that disagreed with itself next to the fold:
/// a distorted table read off chords (in-domain points refused before the inverse ran), and an
/// ideal table whose interpolation between rays reached past the fold (Newton started where
/// the Jacobian determinant is already negative).
fn cameras_with_a_fold_in_view() -> [Camera; 2] {
    let barrel = Camera::from_coeffs(
        1280,
        800,
        Intrinsics {
            fx: 479.871,
            fy: 481.047,
            cx: 642.889,
            cy: 395.577,
        },
        &[
            -0.31816, -0.075277, 0.0, -0.0031920, -0.0033314, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
            0.0029677,
        ],
    );
    let wide = Camera::from_coeffs(
        1280,
        800,
        Intrinsics {
            fx: 300.0,
            fy: 285.0,
            cx: 639.5,
            cy: 399.5,
        },
        &[
            0.0, 0.056964, 0.0, 0.0, 0.0, 0.0, 0.047253, 0.0075791, 0.0, 0.0022273, 0.0, 0.0022413,
        ],
    );
    [barrel.expect("valid camera"), wide.expect("valid camera")]
}

#[test]
fn the_band_next_to_the_fold_round_trips() {
    // Every ideal point just inside the boundary, all the way round and at depths from 1 % of
    // the radius down to 1e-7, must come back from its distorted image: that band is where
    // every ideal point maps next to the boundary, so any slack in the tables shows there.
    for (which, cam) in cameras_with_a_fold_in_view().iter().enumerate() {
        assert!(cam.domain().folds(), "camera {which} should fold");
        let mut checked = 0;
        for k in 0..4096 {
            let angle = std::f64::consts::TAU * (k as f64 + 0.37) / 4096.0;
            let dir = DVec2::new(angle.cos(), angle.sin());
            for depth in [1e-2, 1e-3, 1e-4, 1e-5, 1e-7] {
                let x = dir * cam.domain().ideal_radius(angle) * (1.0 - depth);
                assert!(
                    cam.domain().contains_ideal(x),
                    "camera {which}: {x} not inside"
                );
                let y = cam
                    .distort_normalized(x)
                    .expect("forward defined in the domain");
                let back = cam
                    .undistort_normalized(y, InverseMethod::Newton)
                    .unwrap_or_else(|| {
                        panic!("camera {which}: Newton refused {x} (depth {depth})")
                    });
                // Near the fold the inverse is ill-conditioned (det J → 0): the residual is what
                // Newton controls, and the ideal error follows from it through J.
                let residual = (cam.distort_normalized(back).unwrap() - y).length();
                assert!(
                    residual <= 1e-12 * (1.0 + y.length()),
                    "camera {which}: residual {residual}"
                );
                // The ideal error is the residual over the smallest singular value of J, which
                // is at least det(J)/|J|_F: that vanishes at the fold, so the bound grows there.
                let jac = cam.jacobian_normalized(x).expect("defined in the domain");
                let frobenius = (jac.x_axis.length_squared() + jac.y_axis.length_squared()).sqrt();
                let bound = 2e-12 * (1.0 + y.length()) * frobenius / jac.determinant();
                assert!(
                    (back - x).length() <= bound.max(1e-12),
                    "camera {which}: {back} vs {x}, beyond {bound}"
                );
                checked += 1;
            }
        }
        assert_eq!(checked, 4096 * 5);
    }
}

#[test]
fn fold_over_is_reported_not_guessed() {
    // r_d = r (1 − 0.5 r²) peaks at r = √(2/3): beyond, two ideal radii share a distorted one.
    let cam = camera(800, 800, 400.0, &[-0.5, 0.0, 0.0, 0.0]);
    let r_fold = (2.0f64 / 3.0).sqrt();
    let boundary = cam.domain().ideal_radius(0.0);
    assert!(
        (boundary - r_fold).abs() < 1e-6,
        "fold at {boundary}, expected {r_fold}"
    );
    assert!(cam.domain().folds());
    // The pixel of an ideal point beyond the fold: the inverse gives the in-domain preimage
    // (which distorts to the same pixel), never the out-of-domain point or garbage.
    let beyond = DVec2::new(0.95, 0.0);
    let pixel = cam
        .intrinsics
        .to_pixel(cam.distort_normalized(beyond).unwrap());
    for method in [
        InverseMethod::Newton,
        InverseMethod::Heikkila,
        InverseMethod::FixedPoint(5),
    ] {
        if let Some(x) = cam.undistort_pixel(pixel, method) {
            assert!(
                cam.ideal_in_domain(x),
                "{method}: returned a point outside the domain"
            );
        }
    }
    let x = cam
        .undistort_pixel(pixel, InverseMethod::Newton)
        .expect("has an in-domain preimage");
    assert!((cam.distort_pixel(x).unwrap() - pixel).length() < 1e-9);
    // Beyond the largest distorted radius there is no preimage at all: every method says so.
    let r_max_d = r_fold * (1.0 - 0.5 * r_fold * r_fold);
    let outside = cam.intrinsics.to_pixel(DVec2::new(r_max_d * 1.01, 0.0));
    for method in [
        InverseMethod::Newton,
        InverseMethod::Heikkila,
        InverseMethod::FixedPoint(200),
    ] {
        assert_eq!(cam.undistort_pixel(outside, method), None, "{method}");
    }
}

#[test]
fn a_rational_pole_ends_the_domain() {
    // Denominator 1 − r² vanishes at r = 1: the model flips through infinity there.
    let cam = camera(800, 800, 400.0, &[0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0]);
    let b = cam.domain().ideal_radius(1.0);
    assert!(b < 1.0 && b > 0.9, "domain ends at {b}");
    assert_eq!(
        cam.distort_normalized(DVec2::new(1.0, 0.0)),
        None,
        "forward at the pole"
    );
    // Just inside the pole the map still grows monotonically (to +∞): the point is valid and
    // recovered exactly.
    let near_pole = cam.distort_normalized(DVec2::new(0.999_99, 0.0)).unwrap();
    assert!(near_pole.x > 1e4);
    let back = cam
        .undistort_normalized(near_pole, InverseMethod::Newton)
        .expect("valid");
    assert!((back.x - 0.999_99).abs() < 1e-12, "{back}");
    // Beyond the pole the model flips sign: r = 1.1 lands at x ≈ −5.24, on top of the genuine
    // preimage r ≈ −0.909. The domain excludes r = 1.1 and the inverse returns the genuine one.
    let beyond = DVec2::new(1.1, 0.0);
    assert!(!cam.domain().contains_ideal(beyond));
    let flipped = cam.distort_normalized(beyond).unwrap();
    assert!(flipped.x < -5.0);
    let x = cam
        .undistort_normalized(flipped, InverseMethod::Newton)
        .expect("has a genuine preimage");
    assert!(x.x < 0.0 && cam.domain().contains_ideal(x));
    assert!((cam.distort_normalized(x).unwrap() - flipped).length() < 1e-9);
}

#[test]
fn the_principal_point_maps_to_itself_exactly() {
    let cam = camera(
        1024,
        768,
        800.0,
        &[
            -0.12, 0.04, 0.002, -0.001, 0.0, 0.0, 0.0, 0.0, 0.003, -0.0005, -0.002, 0.0004, 0.01,
            -0.015,
        ],
    );
    let c = DVec2::new(cam.intrinsics.cx, cam.intrinsics.cy);
    assert_eq!(cam.distort_pixel(c), Some(c));
    for method in [
        InverseMethod::Newton,
        InverseMethod::Heikkila,
        InverseMethod::FixedPoint(5),
    ] {
        assert_eq!(cam.undistort_pixel(c, method), Some(c), "{method}");
    }
}

#[test]
fn huge_images_work() {
    let cam = camera(65536, 65536, 30000.0, &[-0.2, 0.05, 0.001, 0.001, 0.0]);
    let p = DVec2::new(60000.25, 100.75);
    let d = cam.distort_pixel(p).unwrap();
    let back = cam.undistort_pixel(d, InverseMethod::Newton).unwrap();
    assert!((back - p).length() < 1e-6, "{back} vs {p}");
    let too_big = Camera::from_coeffs(
        70000,
        10,
        Intrinsics {
            fx: 1.0,
            fy: 1.0,
            cx: 0.0,
            cy: 0.0,
        },
        &[0.0; 4],
    );
    assert!(matches!(too_big, Err(ModelError::BadSize { .. })));
}

#[test]
fn nan_inf_and_behind_the_camera_are_invalid_not_garbage() {
    let cam = camera(800, 600, 400.0, &[-0.05, 0.01, 0.03, -0.01]);
    for bad in [
        DVec2::new(f64::NAN, 0.0),
        DVec2::new(0.0, f64::INFINITY),
        DVec2::new(f64::NEG_INFINITY, f64::NAN),
    ] {
        assert_eq!(cam.distort_normalized(bad), None);
        for method in [
            InverseMethod::Newton,
            InverseMethod::Heikkila,
            InverseMethod::FixedPoint(5),
        ] {
            assert_eq!(cam.undistort_pixel(bad, method), None, "{method} {bad}");
        }
        assert!(!cam.ideal_in_domain(bad));
    }
    assert_eq!(
        cam.project(DVec3::new(1.0, 1.0, 0.0)),
        None,
        "on the camera plane"
    );
    assert_eq!(
        cam.project(DVec3::new(1.0, 1.0, -2.0)),
        None,
        "behind the camera"
    );
    assert_eq!(cam.project(DVec3::new(f64::NAN, 1.0, 2.0)), None);
    assert!(cam.project(DVec3::new(0.1, 0.1, 2.0)).is_some());
}

#[test]
fn bad_parameters_are_typed_errors() {
    let k = Intrinsics {
        fx: 400.0,
        fy: 400.0,
        cx: 0.0,
        cy: 0.0,
    };
    let nan = Camera::from_coeffs(10, 10, Intrinsics { fx: f64::NAN, ..k }, &[0.0; 4]);
    assert!(matches!(nan, Err(ModelError::NotFinite { name: "fx", .. })));
    let neg = Camera::from_coeffs(10, 10, Intrinsics { fy: 0.0, ..k }, &[0.0; 4]);
    assert!(matches!(
        neg,
        Err(ModelError::NotPositive { name: "fy", .. })
    ));
    let inf = Camera::from_coeffs(10, 10, k, &[0.0, f64::INFINITY, 0.0, 0.0]);
    assert!(matches!(inf, Err(ModelError::NotFinite { name: "k2", .. })));
    let absurd = Camera::from_coeffs(10, 10, k, &[1e12, 0.0, 0.0, 0.0]);
    assert!(matches!(absurd, Err(ModelError::Absurd { name: "k1", .. })));
    for n in [0, 1, 3, 6, 7, 9, 13, 15] {
        let c = vec![0.0; n];
        assert_eq!(
            Camera::from_coeffs(10, 10, k, &c).unwrap_err(),
            ModelError::CoefficientCount(n)
        );
    }
    for n in [4, 5, 8, 12, 14] {
        assert!(Camera::from_coeffs(10, 10, k, &vec![0.0; n]).is_ok());
    }
    assert!(BrownRadial::new(10, 10, f64::NAN, 0.0).is_err());
    for bad in [
        "",
        "newtons",
        "fixed-point:",
        "fixed-point:0",
        "fixed-point:-3",
        "fixed-point:99999999",
    ] {
        assert!(bad.parse::<InverseMethod>().is_err(), "{bad}");
    }
    assert_eq!(
        "fixed-point:7".parse::<InverseMethod>(),
        Ok(InverseMethod::FixedPoint(7))
    );
}
