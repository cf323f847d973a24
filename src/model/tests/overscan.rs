//! Overscan: the computed source covers every valid distorted pixel — for barrel, pincushion,
//! mustache and folding lenses — where Lambers et al.'s four-corner rule does not.

use crate::io::reference::load_reference;
use crate::model::overscan::overscan;
use crate::model::warp::WarpGeometry;
use crate::model::{Camera, Intrinsics, InverseMethod};
use glam::DVec2;

/// Valid output pixels (inverse defined) whose source falls off the frame.
fn uncovered(cam: &Camera, geometry: &WarpGeometry) -> usize {
    let mut n = 0;
    for y in 0..cam.height {
        for x in 0..cam.width {
            let p = DVec2::new(x as f64, y as f64);
            if cam.undistort_pixel_valid(p) && geometry.source_coordinate(p, 1).is_none() {
                n += 1;
            }
        }
    }
    n
}

trait Valid {
    fn undistort_pixel_valid(&self, p: DVec2) -> bool;
}
impl Valid for Camera {
    fn undistort_pixel_valid(&self, p: DVec2) -> bool {
        self.undistort_normalized(self.intrinsics.to_normalized(p), InverseMethod::Newton)
            .is_some()
    }
}

#[test]
fn overscan_covers_every_valid_pixel_on_every_shared_camera() {
    let reference = load_reference().unwrap();
    for case in &reference.cases {
        let cam = case.camera().unwrap();
        let plain = WarpGeometry::distort(cam.clone(), InverseMethod::Newton);
        let before = uncovered(&cam, &plain);
        let o = overscan(&cam, 1.0).unwrap();
        let g = plain
            .clone()
            .with_ideal(o.intrinsics, (o.width, o.height))
            .unwrap();
        let after = uncovered(&cam, &g);
        println!(
            "{}: {before} valid px uncovered by the plain pinhole; overscan {}×{} leaves {after}",
            case.name, o.width, o.height
        );
        assert_eq!(after, 0, "{}", case.name);
    }
}

#[test]
fn the_four_corner_rule_misses_a_mustache_lens() {
    // Barrel near the centre turning pincushion outside: the border's extreme ideal points are
    // not at the corners.
    let cam = Camera::from_coeffs(
        800,
        600,
        Intrinsics {
            fx: 400.0,
            fy: 400.0,
            cx: 399.5,
            cy: 299.5,
        },
        &[-0.25, 0.12, 0.0, 0.0, -0.01],
    )
    .unwrap();
    let corners: Vec<DVec2> = [(0.0, 0.0), (799.0, 0.0), (0.0, 599.0), (799.0, 599.0)]
        .iter()
        .map(|&(x, y)| {
            cam.undistort_normalized(
                cam.intrinsics.to_normalized(DVec2::new(x, y)),
                InverseMethod::Newton,
            )
            .unwrap()
        })
        .collect();
    let cmin = corners.iter().fold(DVec2::INFINITY, |a, &p| a.min(p));
    let cmax = corners.iter().fold(DVec2::NEG_INFINITY, |a, &p| a.max(p));
    let fx = cam.intrinsics.fx;
    let corner_cam = Intrinsics {
        fx,
        fy: fx,
        cx: 0.5 - fx * cmin.x,
        cy: 0.5 - fx * cmin.y,
    };
    let size = (
        ((cmax.x - cmin.x) * fx).ceil() as u32 + 2,
        ((cmax.y - cmin.y) * fx).ceil() as u32 + 2,
    );
    let by_corners = WarpGeometry::distort(cam.clone(), InverseMethod::Newton)
        .with_ideal(corner_cam, size)
        .unwrap();
    let o = overscan(&cam, 1.0).unwrap();
    let by_border = WarpGeometry::distort(cam.clone(), InverseMethod::Newton)
        .with_ideal(o.intrinsics, (o.width, o.height))
        .unwrap();
    let (missed, ours) = (uncovered(&cam, &by_corners), uncovered(&cam, &by_border));
    println!("four corners leave {missed} valid px uncovered; the whole border leaves {ours}");
    assert!(missed > 0);
    assert_eq!(ours, 0);
}

#[test]
fn density_scales_the_source() {
    let cam = Camera::from_coeffs(
        800,
        600,
        Intrinsics {
            fx: 400.0,
            fy: 400.0,
            cx: 399.5,
            cy: 299.5,
        },
        &[-0.11, 0.0, 0.0, 0.0],
    )
    .unwrap();
    let a = overscan(&cam, 1.0).unwrap();
    let b = overscan(&cam, 2.0).unwrap();
    assert!(
        a.width > 800 && a.height > 600,
        "barrel needs a larger source: {a:?}"
    );
    assert!((b.width as f64 - 2.0 * a.width as f64).abs() <= 3.0);
    assert_eq!(b.intrinsics.fx, 800.0);
    assert!(
        overscan(&cam, 0.0).is_err()
            && overscan(&cam, f64::NAN).is_err()
            && overscan(&cam, 1e3).is_err()
    );
}
