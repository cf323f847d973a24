//! The bands approximation of a rolling shutter: what a route that draws each image from one
//! pose (a pinhole render and a warp) can do for a camera that moves during the readout.
//!
//! The readout's lines (rows for the vertical readouts, columns for the horizontal ones) are
//! split into K bands of equal size; band k is drawn from the pose of its middle line's
//! readout time, so each pixel is drawn from a pose at most half a band's readout time away
//! from its own line's. That is the piecewise-constant approximation of the camera's motion
//! over the lines that rolling-shutter rectification by scanline bands uses (Ringaby and
//! Forssén, "Efficient video rectification and stabilisation for cell-phones", 2012, who
//! interpolate the rotation per scanline instead); its error falls as 1/K: the pose a pixel
//! is drawn from is off by at most 1/(2K) of the frame's motion.
//!
//! [`band_error_px`] measures it in f64 against the exact projection
//! ([`FrameMotion::project`]): a world point drawn at a pixel by its band's pose is projected
//! through the motion, where the sensor would really have recorded it, and the distance
//! between the two pixels is the error.

use glam::{DVec2, DVec3};

use super::{FrameMotion, Readout};
use crate::model::Camera;

/// The band counts a planner tries, fewest first: each doubling halves the error.
pub const BAND_COUNTS: [u32; 5] = [4, 8, 16, 32, 64];

/// One band of a rolling shutter's lines.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Band {
    /// The band's place in readout order (0 is read first).
    pub index: u32,
    /// The output pixels it covers: columns `x0..x1`, rows `y0..y1` (`[x0, y0, x1, y1]`).
    pub rect: [u32; 4],
    /// The readout time of its middle line (0 the first line, 1 the last), whose pose draws it.
    pub s: f64,
}

/// The lines along the readout direction of a `width` × `height` sensor.
fn line_count(readout: Readout, width: u32, height: u32) -> u32 {
    if readout.is_vertical() {
        height
    } else {
        width
    }
}

/// The first line (in readout order) of band `k` of `count` over `lines` lines: the bands are
/// as equal as whole lines allow, band k holding the lines ℓ with k ≤ ℓ·count/lines < k + 1.
fn first_line(k: u32, count: u32, lines: u32) -> u32 {
    let (k, count, lines) = (u64::from(k), u64::from(count.max(1)), u64::from(lines));
    ((k * lines).div_ceil(count)) as u32
}

/// The `count` bands of a `width` × `height` image read out in `readout` order, in readout
/// order; bands without a line (more bands than lines) are left out.
pub fn bands(readout: Readout, width: u32, height: u32, count: u32) -> Vec<Band> {
    let lines = line_count(readout, width, height);
    let last = f64::from(lines.saturating_sub(1));
    (0..count.max(1))
        .filter_map(|k| {
            let (a, b) = (first_line(k, count, lines), first_line(k + 1, count, lines));
            if a >= b {
                return None;
            }
            // The middle of lines a..=b−1, as a readout time (a one-line sensor reads at 0).
            let middle = 0.5 * f64::from(a + b - 1);
            let s = if last > 0.0 { middle / last } else { 0.0 };
            let rect = match readout {
                Readout::TopToBottom => [0, a, width, b],
                Readout::BottomToTop => [0, height - b, width, height - a],
                Readout::LeftToRight => [a, 0, b, height],
                Readout::RightToLeft => [width - b, 0, width - a, height],
            };
            Some(Band { index: k, rect, s })
        })
        .collect()
}

/// Lines of a band the error is measured on: its first and its last (where the pose it is
/// drawn from is furthest from the line's own) and its middle.
const LINES_PER_BAND: usize = 3;
/// Pixels measured along each of those lines, evenly from one edge of the image to the other.
const PIXELS_PER_LINE: usize = 9;
/// Distances measured behind each pixel, evenly in inverse distance (the parallax of a
/// translation is linear in it) from the nearest to the farthest.
const DISTANCES: usize = 3;

/// The largest error (pixels) of drawing `camera`'s image in `count` bands (see [`bands`])
/// of `readout` while the camera moves as `motion` says, for scene points `distances` (near,
/// far; metres from the camera centre, far may be infinite) away: at the first, middle and
/// last line of every band, [`PIXELS_PER_LINE`] pixels across, the world point at each
/// distance behind the pixel as the band's pose sees it, projected exactly through the
/// moving camera. 0 for a camera that does not move; pixels the lens does not see, and
/// points the sensor does not record, are left out.
pub fn band_error_px(
    camera: &Camera,
    motion: &FrameMotion,
    readout: Readout,
    count: u32,
    distances: (f64, f64),
) -> f64 {
    if motion.is_still() {
        return 0.0;
    }
    let (w, h) = (camera.width, camera.height);
    let across = if readout.is_vertical() { w } else { h };
    let (near, far) = distances;
    let inverse = |i: usize| {
        let t = i as f64 / (DISTANCES - 1) as f64;
        (1.0 - t) / near + t / far
    };
    let mut worst = 0f64;
    for band in bands(readout, w, h, count) {
        let pose = motion.at(band.s);
        let rotation_t = pose.rotation.transpose();
        let centre = pose.centre();
        let (a, b) = if readout.is_vertical() {
            (band.rect[1], band.rect[3])
        } else {
            (band.rect[0], band.rect[2])
        };
        let ends = [a, (a + b - 1) / 2, b - 1];
        for &line in ends.iter().take(LINES_PER_BAND) {
            for j in 0..PIXELS_PER_LINE {
                let along = j as f64 / (PIXELS_PER_LINE - 1) as f64 * f64::from(across - 1);
                let pixel = if readout.is_vertical() {
                    DVec2::new(along, f64::from(line))
                } else {
                    DVec2::new(f64::from(line), along)
                };
                let Some(ray) = camera.unproject(pixel) else {
                    continue;
                };
                for i in 0..DISTANCES {
                    let d = 1.0 / inverse(i);
                    if !d.is_finite() || d <= 0.0 {
                        continue;
                    }
                    let x: DVec3 = centre + rotation_t * (ray * d);
                    if let Some(p) = motion.project(camera, readout, x) {
                        let e = (p.pixel - pixel).length();
                        if e.is_finite() {
                            worst = worst.max(e);
                        }
                    }
                }
            }
        }
    }
    worst
}

/// The distances (metres) from `camera` to those of `points` it sees over the readout of
/// `motion`: the nearest and the farthest of the points that land on the image from the pose
/// of its first or its last line, `None` where none does. The bands' error is measured over
/// it.
pub fn distance_range(
    camera: &Camera,
    motion: &FrameMotion,
    points: impl IntoIterator<Item = DVec3>,
) -> Option<(f64, f64)> {
    let poses = [motion.start(), motion.end()];
    let (w, h) = (f64::from(camera.width), f64::from(camera.height));
    let mut range: Option<(f64, f64)> = None;
    for x in points {
        for pose in &poses {
            let p = pose.apply(x);
            let d = p.length();
            let seen = camera
                .project(p)
                .is_some_and(|q| (-0.5..w - 0.5).contains(&q.x) && (-0.5..h - 0.5).contains(&q.y));
            if !(seen && d.is_finite() && d > 0.0) {
                continue;
            }
            range = Some(match range {
                Some((lo, hi)) => (lo.min(d), hi.max(d)),
                None => (d, d),
            });
        }
    }
    range
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::rolling_shutter::WorldToCamera;
    use crate::model::Intrinsics;
    use glam::DMat3;

    fn camera() -> Camera {
        let k = Intrinsics {
            fx: 400.0,
            fy: 400.0,
            cx: 399.5,
            cy: 299.5,
        };
        Camera::from_coeffs(800, 600, k, &[-0.11, 0.02, 0.0, 0.0]).unwrap()
    }

    /// A 7° pan with a 12 cm step, 1.6 m from the origin.
    fn pan() -> FrameMotion {
        let start = WorldToCamera {
            rotation: DMat3::IDENTITY,
            translation: DVec3::new(0.06, 0.0, 1.6),
        };
        let turn = DMat3::from_axis_angle(DVec3::Y, 7f64.to_radians());
        let end = WorldToCamera {
            rotation: turn,
            translation: turn * DVec3::new(-0.06, 0.0, 1.6),
        };
        FrameMotion::new(start, end)
    }

    #[test]
    fn the_bands_cover_every_line_once_in_readout_order() {
        for readout in Readout::ALL {
            for count in [1, 3, 4, 7, 64, 700] {
                let (w, h) = (160, 120);
                let bands = bands(readout, w, h, count);
                let mut seen = vec![0u32; (w * h) as usize];
                let mut last_s = -1.0;
                for b in &bands {
                    let [x0, y0, x1, y1] = b.rect;
                    assert!(x0 < x1 && y0 < y1 && x1 <= w && y1 <= h, "{readout} {b:?}");
                    for y in y0..y1 {
                        for x in x0..x1 {
                            seen[(y * w + x) as usize] += 1;
                        }
                    }
                    assert!(b.s > last_s && (0.0..=1.0).contains(&b.s));
                    last_s = b.s;
                    // The middle line's time: the mean of the band's first and last lines'.
                    let (a, e) = match readout {
                        Readout::TopToBottom => (y0, y1 - 1),
                        Readout::BottomToTop => (h - y1, h - 1 - y0),
                        Readout::LeftToRight => (x0, x1 - 1),
                        Readout::RightToLeft => (w - x1, w - 1 - x0),
                    };
                    let last = if readout.is_vertical() { h - 1 } else { w - 1 };
                    let expected = 0.5 * f64::from(a + e) / f64::from(last);
                    assert!((b.s - expected).abs() < 1e-12, "{readout} {b:?}");
                }
                assert!(seen.iter().all(|&n| n == 1), "{readout} ×{count}");
                let lines = if readout.is_vertical() { h } else { w };
                assert_eq!(bands.len() as u32, count.min(lines));
            }
        }
        // Equal bands of whole lines: 120 rows in 4 bands of 30, the first read first.
        let b = bands(Readout::BottomToTop, 160, 120, 4);
        assert_eq!(b[0].rect, [0, 90, 160, 120]);
        assert_eq!(b[3].rect, [0, 0, 160, 30]);
    }

    #[test]
    fn the_error_falls_as_one_over_the_band_count() {
        let (camera, motion) = (camera(), pan());
        let range = (1.2, 2.4);
        let errors: Vec<f64> = BAND_COUNTS
            .iter()
            .map(|&k| band_error_px(&camera, &motion, Readout::TopToBottom, k, range))
            .collect();
        // A 7° pan at f = 400 px sweeps ~50 px over the readout: half a band of 4 is ~6 px.
        assert!(errors[0] > 3.0 && errors[0] < 12.0, "{errors:?}");
        for pair in errors.windows(2) {
            let ratio = pair[0] / pair[1];
            assert!((1.7..2.3).contains(&ratio), "{errors:?}");
        }
        // One band per line leaves only the motion within a line's own readout time.
        let per_line = band_error_px(&camera, &motion, Readout::TopToBottom, 600, range);
        assert!(per_line < 0.1, "{per_line}");
        // A still camera has no error, whatever the bands.
        let still = FrameMotion::still(motion.start());
        assert_eq!(
            band_error_px(&camera, &still, Readout::TopToBottom, 4, range),
            0.0
        );
    }

    #[test]
    fn the_error_is_measured_where_the_exact_projection_lands() {
        let (camera, motion) = (camera(), pan());
        let e = |readout, range| band_error_px(&camera, &motion, readout, 8, range);
        // The parallax of the step grows as points come nearer; the far end is shared.
        let rows = e(Readout::TopToBottom, (1.2, 2.4));
        assert!(e(Readout::TopToBottom, (0.3, 2.4)) > 2.0 * rows, "{rows}");
        // Read column by column, the pan moves points along the readout direction, so the
        // time a point is read depends on which way the columns go: the self-consistent
        // projection gives the two horizontal readouts different errors (a band's pose
        // alone would give them the same).
        let (right, left) = (
            e(Readout::LeftToRight, (1.2, 2.4)),
            e(Readout::RightToLeft, (1.2, 2.4)),
        );
        assert!(
            right > 0.5 && left > 0.5 && (right - left).abs() > 0.05,
            "{right} {left}"
        );
        // A turn alone: no parallax, the same error at every distance.
        let turn = FrameMotion::new(
            motion.start(),
            WorldToCamera {
                rotation: motion.end().rotation,
                translation: motion.end().rotation * motion.start().centre() * -1.0,
            },
        );
        let at = |range| band_error_px(&camera, &turn, Readout::TopToBottom, 8, range);
        let (near, far) = (at((0.3, 0.6)), at((1e3, f64::INFINITY)));
        assert!(
            near > 1.0 && (near - far).abs() < 1e-6 * near,
            "{near} {far}"
        );
    }

    #[test]
    fn the_distance_range_spans_the_points_at_both_ends_of_the_readout() {
        let (camera, motion) = (camera(), pan());
        // Behind the camera, and far off to the side: not seen, not counted.
        let unseen = [DVec3::new(0.0, 0.0, -3.0), DVec3::new(40.0, 0.0, 0.5)];
        let points = [DVec3::ZERO, DVec3::new(0.0, 0.0, 1.0)];
        let (near, far) =
            distance_range(&camera, &motion, points.into_iter().chain(unseen)).unwrap();
        assert!((near - 0.06f64.hypot(1.6)).abs() < 1e-12, "{near}");
        assert!((far - 0.06f64.hypot(2.6)).abs() < 1e-12, "{far}");
        assert!(distance_range(&camera, &motion, unseen).is_none());
    }
}
