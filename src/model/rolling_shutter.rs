//! Rolling shutter: when each line of the sensor is read, the camera's pose at that time, and
//! where a world point appears when every line sees the world from its own pose.
//!
//! A rolling-shutter sensor reads its lines one after another, so a camera that moves during
//! the readout sees each line from another pose (Meingast, Geyer and Sastry, "Geometric models
//! of rolling-shutter cameras", 2005). The motion over one frame is given by two poses: the
//! pose when the first line is read (readout time s = 0) and the pose when the last line is
//! read (s = 1). Between them the camera-to-world rotation is interpolated by slerp on SO(3)
//! and the camera centre linearly, as Hedborg et al. interpolate poses between the lines of a
//! frame ("Rolling shutter bundle adjustment", 2012):
//!
//! ```text
//! R_wc(s) = R_wc0 · exp(s · log(R_wc0ᵀ R_wc1)),   C(s) = (1 − s) C0 + s C1
//! ```
//!
//! A world point X appears at the pixel p whose own line time agrees with the pose it was
//! seen from: p = π(R_cw(s) (X − C(s))) with s = line_time(p), π the camera's full model.
//! That is a scalar root find on the readout interval,
//!
//! ```text
//! g(s) = s − line_time(π(X at pose(s))) = 0,   s ∈ [0, 1],
//! ```
//!
//! solved here by scanning [0, 1] in [`SCAN_CELLS`] cells for the first sign change (so the
//! root returned is the first in readout order where the motion is fast enough to give
//! several) and refining it by Illinois false position, safeguarded by bisection, until the
//! pixels at the two ends of the bracket agree to [`PIXEL_TOLERANCE`]. Every loop is bounded
//! and nothing is allocated, so the same iteration can run per vertex in a shader.
//!
//! A single step of that iteration from mid-frame (the pose at s = ½ gives a row, the row a
//! time, the time a pose) is what warps built on a gyroscope's rotations use; it is exact only
//! when the point's line does not move during the readout, and `docs/rolling-shutter.md`
//! measures what it leaves.
//!
//! Points no line reads (their line time stays before the first line, or after the last,
//! during the whole readout: outside the image along the readout direction) keep a defined
//! position: the one they have when the first line is read, or when the last one is. A point
//! that leaves the lens's domain or passes behind the camera during the readout, without a
//! root where it is seen, has none (`None`).

use std::fmt;
use std::str::FromStr;

use glam::{DMat3, DQuat, DVec2, DVec3};

use super::lens::Lens;
use super::{Camera, ModelError};

/// Cells the readout interval [0, 1] is scanned in for the first sign change of g. Two roots
/// closer than one cell (a point whose line moves faster than the readout, back and forth
/// within 1/16 of a frame) can hide from the scan; one root cannot.
pub const SCAN_CELLS: usize = 16;
/// Most refinement steps on one bracketing cell. Illinois false position converges
/// superlinearly (6 to 10 steps to [`PIXEL_TOLERANCE`] on smooth motion); a bisection step
/// whenever the bracket shrinks by less than half twice in a row bounds the rest.
pub const MAX_REFINE_STEPS: usize = 64;
/// A root is refined until the pixels at the two ends of its bracket are this close (pixels).
pub const PIXEL_TOLERANCE: f64 = 1e-9;
/// What the solve promises (pixels). Where f64 rounding stops the bracket before
/// [`PIXEL_TOLERANCE`] (a bracket one unit in the last place wide), the root is kept when the
/// two ends are this close; further apart they straddle a jump of the lens map (the seam of an
/// equirectangular panorama), which is no root, and the scan moves on.
pub const MAX_ERROR_PX: f64 = 1e-4;

/// The order in which a rolling-shutter sensor reads its lines (rows, or columns for the
/// horizontal readouts).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Readout {
    /// Row 0 first, row H − 1 last.
    TopToBottom,
    /// Row H − 1 first, row 0 last.
    BottomToTop,
    /// Column 0 first, column W − 1 last.
    LeftToRight,
    /// Column W − 1 first, column 0 last.
    RightToLeft,
}

impl Readout {
    /// Every readout, in the order the names are listed in errors.
    pub const ALL: [Readout; 4] = [
        Readout::TopToBottom,
        Readout::BottomToTop,
        Readout::LeftToRight,
        Readout::RightToLeft,
    ];

    /// The name a scene file's `[sensor] rolling_shutter` and the command line use.
    pub fn name(self) -> &'static str {
        match self {
            Readout::TopToBottom => "top_to_bottom",
            Readout::BottomToTop => "bottom_to_top",
            Readout::LeftToRight => "left_to_right",
            Readout::RightToLeft => "right_to_left",
        }
    }

    /// NCore's name for the readout (a camera file's `shutter_type`).
    pub fn ncore_name(self) -> &'static str {
        match self {
            Readout::TopToBottom => "ROLLING_TOP_TO_BOTTOM",
            Readout::BottomToTop => "ROLLING_BOTTOM_TO_TOP",
            Readout::LeftToRight => "ROLLING_LEFT_TO_RIGHT",
            Readout::RightToLeft => "ROLLING_RIGHT_TO_LEFT",
        }
    }

    /// NCore's `shutter_type`: `Ok(None)` for `GLOBAL`, the readout for a `ROLLING_*` name.
    pub fn from_ncore(name: &str) -> Result<Option<Readout>, ModelError> {
        if name == "GLOBAL" {
            return Ok(None);
        }
        Readout::ALL
            .into_iter()
            .find(|r| r.ncore_name() == name)
            .map(Some)
            .ok_or_else(|| {
                ModelError::Other(format!(
                    "`{name}` is not one of NCore's shutter types ({}, GLOBAL)",
                    Readout::ALL.map(Readout::ncore_name).join(", ")
                ))
            })
    }

    /// The shaders' id of the readout (`VKL_READOUT` in `glsl/include/rolling_shutter.glsl`,
    /// where 0 is the global shutter).
    pub fn gpu_id(self) -> u32 {
        match self {
            Readout::TopToBottom => 1,
            Readout::BottomToTop => 2,
            Readout::LeftToRight => 3,
            Readout::RightToLeft => 4,
        }
    }

    /// Whether the lines are rows (the readout runs down or up the image).
    pub fn is_vertical(self) -> bool {
        matches!(self, Readout::TopToBottom | Readout::BottomToTop)
    }
}

impl fmt::Display for Readout {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Readout {
    type Err = ModelError;
    /// The scene file's and command line's names (`top_to_bottom`, ...).
    fn from_str(s: &str) -> Result<Self, ModelError> {
        Readout::ALL
            .into_iter()
            .find(|r| r.name() == s)
            .ok_or_else(|| {
                ModelError::Other(format!(
                    "unknown rolling-shutter readout {s:?}; expected one of {}",
                    Readout::ALL.map(Readout::name).join(", ")
                ))
            })
    }
}

/// When the pixel (u, v) (OpenCV pixel centres) is read, as a fraction of the readout: 0 for
/// the first line, 1 for the last; beyond [0, 1] for pixels outside the image along the
/// readout direction. A sensor of one line reads it at 0.
pub fn line_time(readout: Readout, u: f64, v: f64, width: u32, height: u32) -> f64 {
    let (x, lines) = if readout.is_vertical() {
        (v, height)
    } else {
        (u, width)
    };
    let last = f64::from(lines.saturating_sub(1));
    if last == 0.0 {
        return 0.0;
    }
    let t = x / last;
    match readout {
        Readout::TopToBottom | Readout::LeftToRight => t,
        Readout::BottomToTop | Readout::RightToLeft => 1.0 - t,
    }
}

/// A rigid world → camera transform in OpenCV's convention: p_camera = R p_world + t.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldToCamera {
    /// R (world → camera).
    pub rotation: DMat3,
    /// t (metres, camera frame).
    pub translation: DVec3,
}

impl WorldToCamera {
    /// From R given row by row (as numpy and OpenCV write it) and t.
    pub fn from_rows(rows: [[f64; 3]; 3], translation: [f64; 3]) -> Self {
        WorldToCamera {
            rotation: DMat3::from_cols_array_2d(&rows).transpose(),
            translation: DVec3::from_array(translation),
        }
    }

    /// World point → camera frame.
    pub fn apply(&self, x: DVec3) -> DVec3 {
        self.rotation * x + self.translation
    }

    /// The camera centre in world coordinates, C = −Rᵀ t.
    pub fn centre(&self) -> DVec3 {
        -(self.rotation.transpose() * self.translation)
    }

    /// Whether every entry is a finite number.
    pub fn is_finite(&self) -> bool {
        self.rotation.is_finite() && self.translation.is_finite()
    }
}

/// Where a world point appears through a rolling shutter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    /// The distorted pixel (OpenCV pixel centres).
    pub pixel: DVec2,
    /// The readout time the point was seen at: 0 the first line, 1 the last.
    pub s: f64,
    /// The point's camera-frame z at that time (metres; negative behind a wide lens).
    pub depth: f64,
}

/// The camera's motion during one frame's readout: the pose when the first line is read and
/// the pose when the last is, and what interpolating between them needs, computed once.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameMotion {
    start: WorldToCamera,
    end: WorldToCamera,
    /// The unit axis and angle of log(R_wc0ᵀ R_wc1), the rotation from the first line's camera
    /// frame to the last line's, the shorter way round.
    axis: DVec3,
    angle: f64,
    /// The camera centres C0 and C1.
    centres: [DVec3; 2],
    /// The two poses are the same: every line sees the world from the first.
    still: bool,
}

impl FrameMotion {
    /// The motion from `start` (first line) to `end` (last line).
    pub fn new(start: WorldToCamera, end: WorldToCamera) -> Self {
        let still = start == end;
        // R_wc0ᵀ R_wc1 = R_cw0 R_cw1ᵀ.
        let relative = start.rotation * end.rotation.transpose();
        let mut q = DQuat::from_mat3(&relative);
        if q.w < 0.0 {
            q = -q;
        }
        let v = q.xyz();
        let n = v.length();
        // 2·atan2(|v|, w) keeps small angles exact, where 2·acos(w) loses half the digits.
        let angle = 2.0 * n.atan2(q.w);
        let (axis, angle) = if n > 0.0 && angle.is_finite() {
            (v / n, angle)
        } else {
            (DVec3::X, 0.0)
        };
        FrameMotion {
            start,
            end,
            axis,
            angle,
            centres: [start.centre(), end.centre()],
            still,
        }
    }

    /// A camera that does not move during the frame.
    pub fn still(pose: WorldToCamera) -> Self {
        Self::new(pose, pose)
    }

    /// Whether the two poses are the same (a global shutter's result, whatever the readout).
    pub fn is_still(&self) -> bool {
        self.still
    }

    /// The pose when the first line is read.
    pub fn start(&self) -> WorldToCamera {
        self.start
    }

    /// The pose when the last line is read.
    pub fn end(&self) -> WorldToCamera {
        self.end
    }

    /// The unit axis of the turn from the first line's camera frame to the last line's
    /// (log(R_wc0ᵀ R_wc1) = angle · axis; any unit vector where the angle is 0).
    pub fn axis(&self) -> DVec3 {
        self.axis
    }

    /// The camera centres when the first and the last line are read.
    pub fn centres(&self) -> [DVec3; 2] {
        self.centres
    }

    /// The angle the camera turns through during the readout (radians).
    pub fn angle(&self) -> f64 {
        self.angle
    }

    /// The pose at readout time `s`: slerp of the rotation, the centre linear. At s = 0 and
    /// s = 1 exactly the two poses given.
    pub fn at(&self, s: f64) -> WorldToCamera {
        if self.still || s == 0.0 {
            return self.start;
        }
        if s == 1.0 {
            return self.end;
        }
        // R_wc(s) = R_wc0 · exp(s ω), so R_cw(s) = exp(s ω)ᵀ R_cw0.
        let turn = DMat3::from_axis_angle(self.axis, s * self.angle);
        let rotation = turn.transpose() * self.start.rotation;
        let centre = (1.0 - s) * self.centres[0] + s * self.centres[1];
        WorldToCamera {
            rotation,
            translation: -(rotation * centre),
        }
    }

    /// The world point `x` in the camera frame at readout time `s`.
    pub fn to_camera(&self, s: f64, x: DVec3) -> DVec3 {
        if self.still || s == 0.0 {
            return self.start.apply(x);
        }
        if s == 1.0 {
            return self.end.apply(x);
        }
        let pose = self.at(s);
        // R(s) (X − C(s)): the difference first, exact for points near the camera.
        let centre = (1.0 - s) * self.centres[0] + s * self.centres[1];
        pose.rotation * (x - centre)
    }

    /// Where the world point `x` appears through `camera` read out in `readout` order: the
    /// first self-consistent readout time, or `None` where the lens does not see the point.
    pub fn project(&self, camera: &Camera, readout: Readout, x: DVec3) -> Option<Projection> {
        if !x.is_finite() || !self.start.is_finite() || !self.end.is_finite() {
            return None;
        }
        if self.still {
            // One pose for every line: the global shutter's projection, and the line that
            // reads it (the nearest end for a point outside the image).
            let p = self.start.apply(x);
            let pixel = camera.project(p)?;
            let s = line_time(readout, pixel.x, pixel.y, camera.width, camera.height);
            return (s.is_finite() && p.z.is_finite()).then(|| Projection {
                pixel,
                s: s.clamp(0.0, 1.0),
                depth: p.z,
            });
        }
        let eval = |s: f64| Sample::at(self, camera, readout, x, s);
        let mut previous: Option<Sample> = None;
        let (mut first, mut last) = (None, None);
        let mut seen_everywhere = true;
        let mut crossed = false;
        for k in 0..=SCAN_CELLS {
            let s = k as f64 / SCAN_CELLS as f64;
            let current = eval(s);
            if let Some(c) = current {
                if c.g == 0.0 {
                    return Some(c.projection());
                }
                if let Some(p) = previous {
                    if (p.g < 0.0) != (c.g < 0.0) {
                        crossed = true;
                        if let Some(root) = refine(p, c, eval) {
                            return Some(root.projection());
                        }
                    }
                }
            } else {
                seen_everywhere = false;
            }
            if k == 0 {
                first = current;
            }
            last = current;
            previous = current;
        }
        if crossed || !seen_everywhere {
            return None;
        }
        // No line reads the point: it stays before the first line (g > 0) or after the last
        // (g < 0) through the whole readout. It keeps the position it has when the nearest
        // end of the readout happens, so that positions stay continuous across the image's
        // edge (what a triangle with a vertex outside the image needs).
        let (first, last) = (first?, last?);
        Some(if first.g > 0.0 { first } else { last }.projection())
    }
}

/// [`FrameMotion::project`] for one point: `start` the pose when the first line is read, `end`
/// when the last is.
pub fn project_rolling(
    camera: &Camera,
    start: &WorldToCamera,
    end: &WorldToCamera,
    readout: Readout,
    x: DVec3,
) -> Option<Projection> {
    FrameMotion::new(*start, *end).project(camera, readout, x)
}

/// One evaluation of g: the point seen from the pose at `s`.
#[derive(Debug, Clone, Copy)]
struct Sample {
    s: f64,
    /// g(s) = s − line_time(pixel).
    g: f64,
    pixel: DVec2,
    depth: f64,
}

impl Sample {
    fn at(
        motion: &FrameMotion,
        camera: &Camera,
        readout: Readout,
        x: DVec3,
        s: f64,
    ) -> Option<Sample> {
        let p = motion.to_camera(s, x);
        let pixel = camera.project(p)?;
        let g = s - line_time(readout, pixel.x, pixel.y, camera.width, camera.height);
        (g.is_finite() && p.z.is_finite()).then_some(Sample {
            s,
            g,
            pixel,
            depth: p.z,
        })
    }

    fn projection(self) -> Projection {
        Projection {
            pixel: self.pixel,
            s: self.s,
            depth: self.depth,
        }
    }
}

/// The root of g between `a` and `b` (g of opposite signs, a.s < b.s): Illinois false
/// position (the end kept twice in a row has its g halved, so both ends converge), with
/// Dekker's guard against steps too small to count: a step that would land within half the
/// tolerance of an end lands at that distance from it instead, so that an end that has
/// converged is confirmed by a sign change next to it instead of approached from one side. A bisection step where the bracket shrank by less than half twice in a row.
/// `None` where the lens does not see the point somewhere inside the bracket, or where the
/// bracket closes on a jump of the lens map rather than a root.
fn refine(mut a: Sample, mut b: Sample, eval: impl Fn(f64) -> Option<Sample>) -> Option<Sample> {
    // The g values false position weighs the ends with (halved by the Illinois rule).
    let (mut ga, mut gb) = (a.g, b.g);
    // Which end the last step replaced: -1 a, 1 b, 0 neither yet.
    let mut replaced = 0i8;
    let mut slow_steps = 0;
    let spread = |a: &Sample, b: &Sample| (b.pixel - a.pixel).abs().max_element();
    let closest = |a: Sample, b: Sample| if a.g.abs() <= b.g.abs() { a } else { b };
    for _ in 0..MAX_REFINE_STEPS {
        let width = b.s - a.s;
        let gap = spread(&a, &b);
        if gap <= PIXEL_TOLERANCE {
            return Some(closest(a, b));
        }
        let mut s = if slow_steps >= 2 {
            slow_steps = 0;
            0.5 * (a.s + b.s)
        } else {
            (a.s * gb - b.s * ga) / (gb - ga)
        };
        // Half the tolerance in readout time, at the bracket's mean pixel speed: no step
        // lands closer than that to either end.
        let step = 0.5 * PIXEL_TOLERANCE * width / gap;
        s = if s.is_finite() && step < 0.5 * width {
            s.clamp(a.s + step, b.s - step)
        } else {
            0.5 * (a.s + b.s)
        };
        if !(s > a.s && s < b.s) {
            // The bracket is as narrow as f64 makes it.
            break;
        }
        let c = eval(s)?;
        if c.g == 0.0 {
            return Some(c);
        }
        if (c.g < 0.0) == (a.g < 0.0) {
            a = c;
            ga = c.g;
            if replaced == -1 {
                gb *= 0.5;
            }
            replaced = -1;
        } else {
            b = c;
            gb = c.g;
            if replaced == 1 {
                ga *= 0.5;
            }
            replaced = 1;
        }
        if b.s - a.s > 0.5 * width {
            slow_steps += 1;
        } else {
            slow_steps = 0;
        }
    }
    (spread(&a, &b) <= MAX_ERROR_PX).then(|| closest(a, b))
}

impl Camera {
    /// The readout the camera file states (NCore's `shutter_type`); `None` for a global
    /// shutter, or where the file says nothing about its shutter.
    pub fn readout(&self) -> Option<Readout> {
        match self.lens() {
            Lens::FTheta(f) => f
                .shutter_type
                .as_deref()
                .and_then(|name| Readout::from_ncore(name).ok().flatten()),
            _ => None,
        }
    }
}

pub mod bands;

#[cfg(test)]
mod tests;
