//! Board poses for a calibration set (Lambers et al. Sec. 4): varied 3D orientations, each placed as
//! close to the camera as it can be while the whole board — every inner corner and the white
//! frame around them — stays inside the *distorted* image, so the views fill the image and
//! reach its borders, where the distortion is strongest and best measured.
//!
//! Deterministic: view i's tilt and aim come from low-discrepancy sequences, so the same
//! count gives the same set everywhere.

use crate::{Error, Result};
use glam::{DMat3, DVec2, DVec3};

use super::builtin::Board;
use super::Pose;
use crate::model::Camera;

/// Fractional part of `i · alpha` (additive recurrence: evenly spread, never repeating).
fn sequence(i: u32, alpha: f64) -> f64 {
    (i as f64 * alpha).fract()
}

/// Points on the outline that must stay in the image: the squares plus `QUIET` squares of the
/// white frame around them (the detector needs some quiet zone, not all of the frame), in
/// board coordinates.
fn outline(board: &Board) -> Vec<DVec3> {
    const QUIET: f64 = 0.4;
    let s = board.square;
    let (x0, y0) = (-(1.0 + QUIET) * s, -(1.0 + QUIET) * s);
    let (x1, y1) = (
        (board.columns as f64 + QUIET) * s,
        (board.rows as f64 + QUIET) * s,
    );
    let mut points = Vec::new();
    let n = 32;
    for k in 0..=n {
        let t = k as f64 / n as f64;
        points.push(DVec3::new(x0 + t * (x1 - x0), y0, 0.0));
        points.push(DVec3::new(x0 + t * (x1 - x0), y1, 0.0));
        points.push(DVec3::new(x0, y0 + t * (y1 - y0), 0.0));
        points.push(DVec3::new(x1, y0 + t * (y1 - y0), 0.0));
    }
    points
}

/// Whether every point projects through the lens inside the image, `margin` px from the edge.
fn fits(camera: &Camera, pose: &Pose, points: &[DVec3], margin: f64) -> bool {
    let (w, h) = (camera.width as f64, camera.height as f64);
    points.iter().all(|&p| {
        let q = pose.apply(p);
        q.z > 0.0
            && camera.project(q).is_some_and(|px: DVec2| {
                px.x >= margin - 0.5
                    && px.y >= margin - 0.5
                    && px.x <= w - 0.5 - margin
                    && px.y <= h - 0.5 - margin
            })
    })
}

/// `count` board poses for `camera`; errors when a view cannot keep the board in the image.
pub fn board_poses(camera: &Camera, board: &Board, count: u32) -> Result<Vec<Pose>> {
    let points = outline(board);
    let centre = DVec3::new(
        (board.columns as f64 - 1.0) * board.square / 2.0,
        (board.rows as f64 - 1.0) * board.square / 2.0,
        0.0,
    );
    let k = camera.intrinsics;
    let mut poses = Vec::with_capacity(count as usize);
    for i in 0..count {
        // Tilt up to 45° in a direction that turns round the circle; a little roll.
        let direction = std::f64::consts::TAU * sequence(i, 0.618_033_988_749_895);
        let tilt = (10.0 + 35.0 * sequence(i + 1, 0.754_877_666_246_693)).to_radians();
        let roll = (30.0 * (sequence(i, 0.569_840_290_998_053) - 0.5)).to_radians();
        let rotation = DMat3::from_rotation_z(roll)
            * DMat3::from_axis_angle(
                DVec3::new(direction.cos(), direction.sin(), 0.0),
                if i == 0 { 0.0 } else { tilt },
            );
        // The pose whose board centre is seen at pixel offset `aim` (fractions of the image
        // size from the principal point) at `distance`.
        let at = |aim: DVec2, distance: f64| {
            let pixel = DVec2::new(
                k.cx + aim.x * camera.width as f64,
                k.cy + aim.y * camera.height as f64,
            );
            let n = k.to_normalized(pixel);
            let ray = camera
                .undistort_normalized(n, crate::model::InverseMethod::Newton)
                .unwrap_or(n)
                .extend(1.0);
            Pose {
                rotation,
                translation: ray * distance - rotation * centre,
            }
        };
        // Closest distance at which the centred board fits: far enough, then bisection.
        let columns = (board.columns + 3) as f64;
        let rows = (board.rows + 3) as f64;
        let mut far = board.square * (columns * columns + rows * rows).sqrt();
        let mut tries = 0;
        while !fits(camera, &at(DVec2::ZERO, far), &points, 2.0) {
            far *= 1.5;
            tries += 1;
            if tries > 40 {
                return Err(Error::input(format!(
                    "view {i}: no distance keeps the whole board inside the image"
                )));
            }
        }
        let mut near = 0.0;
        for _ in 0..50 {
            let mid = 0.5 * (near + far);
            if fits(camera, &at(DVec2::ZERO, mid), &points, 2.0) {
                far = mid;
            } else {
                near = mid;
            }
        }
        if i % 3 == 0 {
            // Every third view: as large as it gets, centred.
            poses.push(at(DVec2::ZERO, far));
            continue;
        }
        // The others: somewhat smaller, pushed towards a corner until they touch the border,
        // so the image's edges and corners are covered.
        let distance = far * (1.2 + 0.3 * sequence(i, 0.324_717_957_244_746));
        // Towards the image corners (where the radius, and so the distortion, is largest),
        // turning round them, with a little spread.
        let a = std::f64::consts::FRAC_PI_4
            + std::f64::consts::FRAC_PI_2 * (i % 4) as f64
            + 0.3 * (sequence(i, 0.414_213_562_373_095) - 0.5);
        let direction = DVec2::new(a.cos(), a.sin());
        let (mut inside, mut outside) = (0.0, 0.6);
        for _ in 0..40 {
            let mid = 0.5 * (inside + outside);
            if fits(camera, &at(direction * mid, distance), &points, 2.0) {
                inside = mid;
            } else {
                outside = mid;
            }
        }
        poses.push(at(direction * inside, distance));
    }
    Ok(poses)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Intrinsics;

    #[test]
    fn every_inner_corner_is_in_the_image() {
        let camera = Camera::from_coeffs(
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
        let board = Board {
            columns: 9,
            rows: 6,
            square: 0.04,
        };
        let poses = board_poses(&camera, &board, 17).unwrap();
        assert_eq!(poses.len(), 17);
        let mut spans = Vec::new();
        for pose in &poses {
            let px: Vec<DVec2> = (0..9)
                .flat_map(|i| (0..6).map(move |j| (i, j)))
                .map(|(i, j)| camera.project(pose.apply(board.corner(i, j))).unwrap())
                .collect();
            assert!(px
                .iter()
                .all(|p| p.x > 0.0 && p.y > 0.0 && p.x < 799.0 && p.y < 599.0));
            let lo = px.iter().fold(DVec2::splat(f64::MAX), |a, &p| a.min(p));
            let hi = px.iter().fold(DVec2::splat(f64::MIN), |a, &p| a.max(p));
            spans.push((hi - lo).x / 800.0);
        }
        // The boards fill the image: inner corners span a good part of its width.
        let mean = spans.iter().sum::<f64>() / spans.len() as f64;
        assert!(mean > 0.45, "mean span {mean}");
    }
}
