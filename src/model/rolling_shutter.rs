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
//! Where the motion is slow enough, the scan finds nothing: [`FrameMotion::line_rate_bound`]
//! bounds |d line_time / ds| of a point's own pixel by L (how fast its ray turns, times the
//! lens's [`LineRate`]), and below 1 g′ ≥ 1 − L > 0, so g has one root at most. The renderer's
//! per-vertex solve skips the scan there (`glsl/include/rolling_shutter.glsl`); this one, the
//! reference, always scans.
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

    /// The camera centre at readout time `s`: C(s) = (1 − s) C0 + s C1.
    pub fn centre_at(&self, s: f64) -> DVec3 {
        (1.0 - s) * self.centres[0] + s * self.centres[1]
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
        let centre = self.centre_at(s);
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
        let centre = self.centre_at(s);
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

/// The largest bound on |d line_time / ds| for which the shaders skip the scan: below 1 the
/// function g(s) = s − line_time(s) has g′ ≥ 1 − L > 0, so it is strictly increasing and has at
/// most one root; at ½ a lens rate measured a factor 2 too low would still leave g increasing.
pub const MAX_CONTRACTION: f64 = 0.5;

/// Directions per side of the grid [`LineRate::measure`] samples the cone on (off-axis angle
/// × azimuth).
const RATE_GRID: usize = 192;
/// Entries of [`LineRate::per_radian`]: the rate of cones of growing half angle, so that a
/// point near the axis, where a lens moves its rays' pixels slowest, is bounded by the rate
/// near the axis, not by the rate at the image's corners.
pub const RATE_TABLE: usize = 32;
/// How far past the image's widest ray the measured cone reaches (radians): a vertex at the
/// image's edge keeps the bounded solve while its ray turns by up to twice this over a frame.
const RATE_CONE_MARGIN: f64 = 0.25;
/// The measured sup is multiplied by this. The rate is an analytic function of the direction
/// inside the lens's domain, and the grid's cells are a few milliradians wide: between grid
/// points it exceeds the sampled largest value by the change of the rate across half a cell,
/// a fraction of a percent for any calibrated lens (the finite differences themselves are
/// accurate to O(h²), h = 1e-6 rad). A quarter on top covers what sampling can miss and the
/// shaders' f32 arithmetic; with [`MAX_CONTRACTION`] at ½ the bound could be 2.5 times too low
/// before a skipped scan could miss a root.
const RATE_MARGIN: f64 = 1.25;

/// How fast a lens moves a point across the readout's lines as the point's ray direction turns:
/// the largest |∇ line_time| per radian of ray direction over cones of directions about the
/// optical axis, measured once per camera. With a frame's motion it bounds how fast a point's
/// own line time can change with the readout time ([`FrameMotion::line_rate_bound`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineRate {
    /// Entry i: readout time per radian of ray direction (the lens's largest pixels per radian
    /// along the readout's axis, over lines − 1, with a quarter's margin for what the grid of
    /// directions can miss) over the rays at most `cone · i / (RATE_TABLE − 1)` off the axis.
    /// Non-decreasing.
    pub per_radian: [f64; RATE_TABLE],
    /// The half angle of the largest cone (radians off the optical axis); every direction
    /// sampled in it is in the lens's valid domain.
    pub cone: f64,
}

impl LineRate {
    /// Measures the rate of `camera` read out in `readout` order on a fine grid of directions
    /// in the cone that holds the image's rays (plus a margin), through the camera's one
    /// projection ([`Camera::project`]), so that every model of the table is measured alike.
    /// The cone stops short of the first direction the lens does not see. `None` for a sensor
    /// of one line, or a lens whose rate is not finite there.
    pub fn measure(camera: &Camera, readout: Readout) -> Option<LineRate> {
        let lines = if readout.is_vertical() {
            camera.height
        } else {
            camera.width
        };
        let last = f64::from(lines.saturating_sub(1));
        if last == 0.0 {
            return None;
        }
        // Alg. 1 drops a fisheye's vertices past its vertex limit, as if the lens did not see
        // them: the cone stays inside it.
        let max_angle = camera
            .fisheye_vertex_limit()
            .unwrap_or(f64::INFINITY)
            .min(camera.lens().max_angle())
            .min(std::f64::consts::PI);
        let cone = (image_cone(camera)? + RATE_CONE_MARGIN).min(max_angle);
        // The line coordinate (pixels) along the readout's axis.
        let line = |d: DVec3| {
            camera
                .project(d)
                .map(|p| if readout.is_vertical() { p.y } else { p.x })
        };
        const H: f64 = 1e-6;
        let ring_angle = |i: usize| cone * i as f64 / RATE_GRID as f64;
        // The largest rate on each ring of directions the lens sees whole.
        let mut rings = Vec::with_capacity(RATE_GRID + 1);
        'rings: for i in 0..=RATE_GRID {
            let theta = ring_angle(i);
            let azimuths = if i == 0 { 1 } else { RATE_GRID };
            let mut ring: f64 = 0.0;
            for j in 0..azimuths {
                let phi = std::f64::consts::TAU * j as f64 / azimuths as f64;
                let d = DVec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                );
                // Any orthonormal pair of tangents gives the gradient's norm on the sphere.
                let (t1, t2) = d.any_orthonormal_pair();
                let mut g = [0.0; 2];
                for (k, t) in [t1, t2].into_iter().enumerate() {
                    let (Some(a), Some(b)) = (
                        line(H.cos() * d + H.sin() * t),
                        line(H.cos() * d - H.sin() * t),
                    ) else {
                        // The lens does not see this ring everywhere: the cone ends at the
                        // last ring it does.
                        break 'rings;
                    };
                    g[k] = (a - b) / (2.0 * H);
                }
                ring = ring.max(g[0].hypot(g[1]));
            }
            rings.push(ring);
        }
        let reach = ring_angle(rings.len().checked_sub(1)?);
        // Cone i holds the rings up to its half angle and the next one: between two rings the
        // rate is within RATE_MARGIN of the larger of them.
        let mut per_radian = [0.0; RATE_TABLE];
        for (i, entry) in per_radian.iter_mut().enumerate() {
            let theta = reach * i as f64 / (RATE_TABLE - 1) as f64;
            let outer = ((theta / cone * RATE_GRID as f64).ceil() as usize + 1).min(rings.len());
            let worst = rings[..outer].iter().copied().fold(0.0, f64::max);
            *entry = RATE_MARGIN * worst / last;
        }
        (per_radian.iter().all(|r| r.is_finite()) && reach > 0.0).then_some(LineRate {
            per_radian,
            cone: reach,
        })
    }

    /// The rate over the rays at most `theta` off the axis; `None` past the cone.
    pub fn within(&self, theta: f64) -> Option<f64> {
        let i = (theta.max(0.0) / self.cone * (RATE_TABLE - 1) as f64).ceil();
        (theta.is_finite() && i <= (RATE_TABLE - 1) as f64).then(|| self.per_radian[i as usize])
    }
}

/// The largest angle off the optical axis among the rays of the image's border pixels (where
/// the lens sees them; its largest angle where it sees none).
fn image_cone(camera: &Camera) -> Option<f64> {
    let (w, h) = (f64::from(camera.width), f64::from(camera.height));
    const STEPS: usize = 64;
    let mut widest: Option<f64> = None;
    for k in 0..=STEPS {
        let t = k as f64 / STEPS as f64;
        for p in [
            DVec2::new(t * w - 0.5, -0.5),
            DVec2::new(t * w - 0.5, h - 0.5),
            DVec2::new(-0.5, t * h - 0.5),
            DVec2::new(w - 0.5, t * h - 0.5),
        ] {
            if let Some(ray) = camera.unproject(p) {
                let theta = ray.x.hypot(ray.y).atan2(ray.z);
                widest = Some(widest.map_or(theta, |w| w.max(theta)));
            }
        }
    }
    widest
        .or(Some(camera.lens().max_angle()))
        .filter(|t| t.is_finite())
}

impl FrameMotion {
    /// The distance from `x` to the segment C0C1 the camera centre moves along (metres).
    pub fn distance_to_path(&self, x: DVec3) -> f64 {
        let [c0, c1] = self.centres;
        let d = c1 - c0;
        let dd = d.length_squared();
        let t = if dd > 0.0 {
            ((x - c0).dot(d) / dd).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (x - (c0 + t * d)).length()
    }

    /// A bound on how fast the ray direction from the camera to `x` turns (radians per unit of
    /// readout time) anywhere in the frame: the camera turns at a constant `angle`, and the
    /// centre's step C1 − C0 turns the ray by at most |C1 − C0| / |X − C(s)| ≤ |C1 − C0| /
    /// d(X, C0C1). Infinite for a point on the centres' path.
    pub fn angular_speed_bound(&self, x: DVec3) -> f64 {
        let step = (self.centres[1] - self.centres[0]).length();
        if step == 0.0 {
            return self.angle;
        }
        self.angle + step / self.distance_to_path(x)
    }

    /// The same for every point at least `distance` from the centres' path (the distance from
    /// the segment C0C1 to a scene's bounding box): infinite where the distance is not
    /// positive and the camera's centre moves.
    pub fn angular_speed_bound_beyond(&self, distance: f64) -> f64 {
        let step = (self.centres[1] - self.centres[0]).length();
        if step == 0.0 {
            return self.angle;
        }
        if !(distance > 0.0) {
            return f64::INFINITY;
        }
        self.angle + step / distance
    }

    /// L, a bound on |d line_time / ds| of the line on which `x` appears, for every readout
    /// time s: the ray's angular speed ([`Self::angular_speed_bound`]) times the lens's rate
    /// (`rate`). `None` where the bound does not hold: `x` is not in front of the lens at
    /// mid-frame, or its ray could leave the cone the rate was measured on (its ray at s = ½
    /// is within the angular speed × ½ of every ray it has during the frame).
    ///
    /// Below 1, g(s) = s − line_time(s) is strictly increasing (g′ ≥ 1 − L): one root at
    /// most, and the scan for the first root finds nothing a local solve would not.
    pub fn line_rate_bound(&self, rate: &LineRate, x: DVec3) -> Option<f64> {
        if self.still {
            return Some(0.0);
        }
        let speed = self.angular_speed_bound(x);
        let p = self.to_camera(0.5, x);
        let theta = p.x.hypot(p.y).atan2(p.z);
        let bound = speed * rate.within(theta + 0.5 * speed)?;
        bound.is_finite().then_some(bound)
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
