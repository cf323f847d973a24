//! The f64 model against OpenCV 5.0.0's own numbers (`../shared/reference/`).

use crate::io::reference::load_reference;
use crate::model::{CameraModel, InverseMethod};
use glam::DVec2;

/// An inverse counts as "wrong" when it is off by more than this (pixels).
const WRONG_PX: f64 = 1e-3;

#[test]
fn forward_matches_project_points_to_1e9_px() {
    let reference = load_reference().expect("shared reference file");
    for case in &reference.cases {
        let cam = case.camera().expect("reference case is a valid camera");
        let mut worst = 0.0_f64;
        for p in &case.points {
            let x = DVec2::from(p.undistorted_normalized);
            let got = cam
                .distort_normalized(x)
                .map(|y| cam.intrinsics.to_pixel(y))
                .expect("forward defined on every reference point");
            worst = worst.max((got - DVec2::from(p.distorted_pixel)).length());
        }
        println!("{}: forward max error {worst:.3e} px", case.name);
        assert!(worst <= 1e-9, "{}: forward off by {worst} px", case.name);
    }
}

#[test]
fn newton_inverse_within_1e6_px_inside_the_domain_and_exclusions_are_justified() {
    let reference = load_reference().expect("shared reference file");
    for case in &reference.cases {
        let cam = case.camera().expect("valid camera");
        let (mut worst, mut inside, mut excluded) = (0.0_f64, 0, 0);
        for p in &case.points {
            let truth = DVec2::from(p.undistorted_normalized);
            let pixel = DVec2::from(p.distorted_pixel);
            let true_ideal_px = cam.intrinsics.to_pixel(truth);
            if cam.ideal_in_domain(true_ideal_px) {
                inside += 1;
                let got = cam
                    .undistort_pixel(pixel, InverseMethod::Newton)
                    .unwrap_or_else(|| {
                        panic!("{}: Newton refused an in-domain point {truth}", case.name)
                    });
                let err = (got - true_ideal_px).length();
                worst = worst.max(err);
            } else {
                excluded += 1;
                // No valid point is thrown away needlessly: OpenCV's 200-iteration inverse
                // must get this one wrong too.
                let opencv = cam
                    .intrinsics
                    .to_pixel(DVec2::from(p.opencv_undistort_200_iter));
                let opencv_err = (opencv - true_ideal_px).length();
                assert!(
                    opencv_err > WRONG_PX,
                    "{}: the domain excludes {truth}, yet OpenCV (200 it.) recovers it to {opencv_err} px",
                    case.name
                );
                // And whatever our inverse returns for its pixel is not this point.
                if let Some(got) = cam.undistort_pixel(pixel, InverseMethod::Newton) {
                    assert!(
                        cam.ideal_in_domain(got),
                        "{}: returned a point outside the domain",
                        case.name
                    );
                    let back = cam.distort_pixel(got).expect("forward");
                    assert!(
                        (back - pixel).length() < 1e-6,
                        "{}: returned a non-preimage",
                        case.name
                    );
                }
            }
        }
        println!(
            "{}: {inside} points inside the domain (Newton max error {worst:.3e} px), {excluded} excluded",
            case.name
        );
        assert!(worst <= 1e-6, "{}: Newton off by {worst} px", case.name);
        assert!(inside > 0);
    }
}

#[test]
fn fixed_point_5_reproduces_opencv_default_undistort_points() {
    // OpenCV's default criteria are 5 iterations of this very iteration; on points where
    // OpenCV did not bail out, we must land on its numbers (to rounding).
    let reference = load_reference().expect("shared reference file");
    for case in &reference.cases {
        let cam = case.camera().expect("valid camera");
        let mut worst = 0.0_f64;
        let mut compared = 0;
        for p in &case.points {
            let y = cam.intrinsics.to_normalized(DVec2::from(p.distorted_pixel));
            let pre = cam.remove_tilt(y).expect("untilt");
            if let Some(x) = crate::model::opencv::fixed_point(&cam.distortion(), pre, 5) {
                let opencv = DVec2::from(p.opencv_undistort_default);
                worst = worst.max((x - opencv).length() * cam.intrinsics.fx);
                compared += 1;
            }
        }
        println!(
            "{}: fixed-point:5 vs OpenCV default: max {worst:.3e} px over {compared} points",
            case.name
        );
        assert!(compared > 500);
        assert!(worst < 1e-6, "{}: {worst}", case.name);
    }
}
