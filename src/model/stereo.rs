//! Stereo rectification of a calibrated pair, as OpenCV computes it, so that a pipeline built
//! on `cv2.stereoRectify` gets the same rectified cameras from vklens:
//!
//! * The rotations (OpenCV, `modules/calib3d`, `stereoRectify`; Bouguet's method): the
//!   rotation R between the cameras is split in half, each camera turned by one half (R1 =
//!   w·r_rᵀ, R2 = w·r_r with r_r the half turn back, so that both look the same way), then both
//!   by the one rotation w that lays the baseline along the image rows (or, where the baseline
//!   is more vertical than horizontal, `|T_y| > |T_x|` after the half turn, along the columns).
//!   X2 = R·X1 + T, as `cv2.stereoCalibrate` reports R and T.
//! * [`stereo_rectify`] on OpenCV's standard model is `cv2.stereoRectify`: one focal length
//!   for both (the mean of the two fy, fx for a vertical pair, scaled to the new image), each
//!   principal point the one that centres the four undistorted, rectified image corners, and
//!   with `CALIB_ZERO_DISPARITY` (`zero_disparity`) one principal point for both; otherwise
//!   they share the coordinate across the baseline. `alpha` then scales the focal length
//!   between the largest that keeps only pixels with a source in both images (0) and the
//!   smallest that keeps every source pixel of both (1), from `getUndistortRectangles`' 9 × 9
//!   grid as [`super::new_camera::optimal_new_camera`] uses it, turned by R1 and R2; `None`
//!   (OpenCV's −1) keeps the first focal length. The valid ROIs are OpenCV's.
//! * On OpenCV's fisheye model it is `cv2.fisheye.stereoRectify`: each camera's new camera by
//!   the rule of [`super::new_camera::fisheye_new_camera`] with R1 or R2 (`balance`,
//!   `fov_scale`), then the smaller fy of the two as both focal lengths, and the principal
//!   points as above. OpenCV's fisheye rectification always puts the baseline along the rows:
//!   a vertical pair's rectified images are turned a quarter turn. It gives no ROI; vklens
//!   gives the whole new image.
//!
//! Where vklens departs from OpenCV's numbers, and why:
//!
//! * The standard model's corners and grid are undistorted by vklens's converged inverse,
//!   where OpenCV's `undistortPoints` stops after 5 iterations (see
//!   [`super::new_camera`]): on a strong lens the cameras differ slightly near the corners,
//!   vklens's being the one the rule means.
//! * OpenCV holds the four corners as `float` (`Point2f`) through `undistortPoints` and
//!   `projectPoints`: vklens rounds them to f32 at the same two steps, so that where the
//!   inverses agree the principal points agree to the last bit rather than to 1e-9.
//! * A 3×3 R is taken to its Rodrigues vector as `cv::Rodrigues` does it (the nearest
//!   rotation first, a turn below about 1e-5 rad read as none, OpenCV's choice of axis sign
//!   at a half turn); a Rodrigues vector is used as given, as OpenCV uses it.
//!
//! Pixel-centre convention: OpenCV's, as everywhere in vklens ([`super`]).

use glam::{DMat3, DVec2, DVec3};

use super::new_camera::{
    checked_size, fisheye_rule, pinhole, scaled_roi, side_scales, undistort_rectangles, Rect, Roi,
    Unmapped,
};
use super::{Camera, Intrinsics, InverseMethod, ModelKind};
use crate::{Error, Result};

/// The rotation R between the cameras of a pair (X2 = R·X1 + T), as `cv2.stereoRectify` takes
/// it: a 3×3 matrix (row-major) or a Rodrigues vector (axis × angle in radians).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PairRotation {
    /// A rotation matrix, row-major; it must be a rotation (RᵀR = I within
    /// [`PairRotation::TOLERANCE`], det R = +1).
    Matrix([[f64; 3]; 3]),
    /// A Rodrigues vector: the axis scaled by the angle, in radians.
    Rodrigues([f64; 3]),
}

impl PairRotation {
    /// How far RᵀR may be from the identity (largest entry) for a matrix to be taken as a
    /// rotation: a matrix printed to six decimals is that far off, and OpenCV takes the nearest
    /// rotation of what it is given.
    pub const TOLERANCE: f64 = 1e-5;
}

impl From<[[f64; 3]; 3]> for PairRotation {
    fn from(m: [[f64; 3]; 3]) -> Self {
        PairRotation::Matrix(m)
    }
}

impl From<[f64; 3]> for PairRotation {
    fn from(v: [f64; 3]) -> Self {
        PairRotation::Rodrigues(v)
    }
}

/// How [`stereo_rectify`] chooses the rectified cameras: OpenCV's arguments of the same names.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StereoOptions {
    /// The standard model's free scaling (`cv2.stereoRectify`'s `alpha`): 0 keeps only pixels
    /// that have a source in both images, 1 every source pixel of both; `None` is OpenCV's −1
    /// (no scaling: the mean focal length). A fisheye pair takes none.
    pub alpha: Option<f64>,
    /// The rectified images' size; `None`: the cameras' own.
    pub new_size: Option<(u32, u32)>,
    /// `CALIB_ZERO_DISPARITY`: one principal point for both rectified cameras (points at
    /// infinity have zero disparity). Off: they share only the coordinate across the baseline.
    /// OpenCV's default is on.
    pub zero_disparity: bool,
    /// The fisheye model's `balance` (0: the largest focal length the edge midpoints allow, 1:
    /// the smallest); must stay 0 for a standard-model pair.
    pub balance: f64,
    /// The fisheye model's `fov_scale` (the new focal length is divided by it); must stay 1
    /// for a standard-model pair.
    pub fov_scale: f64,
}

impl Default for StereoOptions {
    fn default() -> Self {
        StereoOptions {
            alpha: None,
            new_size: None,
            zero_disparity: true,
            balance: 0.0,
            fov_scale: 1.0,
        }
    }
}

/// What `cv2.stereoRectify` (or `cv2.fisheye.stereoRectify`) returns, and the two rectified
/// pinhole cameras (P1's and P2's 3×3 part at the new size), which an undistort warp with R1
/// (R2) draws each image into.
#[derive(Debug, Clone)]
pub struct StereoRectification {
    /// The rotation from the first camera's frame to its rectified frame (row-major).
    pub r1: [[f64; 3]; 3],
    /// The same for the second camera.
    pub r2: [[f64; 3]; 3],
    /// The first rectified camera's projection `[f 0 cx1 0; 0 f cy 0; 0 0 1 0]`.
    pub p1: [[f64; 4]; 3],
    /// The second's: `[f 0 cx2 Tx·f; 0 f cy 0; 0 0 1 0]` (`Ty·f` in row 1 for a vertical
    /// pair), T the baseline in the rectified frame.
    pub p2: [[f64; 4]; 3],
    /// The disparity-to-depth matrix (`cv2.reprojectImageTo3D`'s Q).
    pub q: [[f64; 4]; 4],
    /// The first rectified image's valid pixels (OpenCV's `validPixROI1`; the whole image for
    /// a fisheye pair).
    pub roi1: Roi,
    /// The second's.
    pub roi2: Roi,
    /// The first rectified camera (pinhole, at the new size).
    pub left: Camera,
    /// The second.
    pub right: Camera,
    /// Whether the baseline runs along the image columns (OpenCV's vertical stereo, `|T_y| >
    /// |T_x|`): then the second camera's baseline is in P2's row 1, and rectified points share
    /// their column instead of their row.
    pub vertical: bool,
}

impl StereoRectification {
    /// The distance between the two camera centres, in the units of T.
    pub fn baseline(&self) -> f64 {
        let row = usize::from(self.vertical);
        (self.p2[row][3] / self.p2[0][0]).abs()
    }

    /// How far rectifying turns each camera, in degrees (R1's angle, R2's).
    pub fn turn_degrees(&self) -> [f64; 2] {
        [turn_degrees(mat3(self.r1)), turn_degrees(mat3(self.r2))]
    }
}

/// `cv2.stereoRectify(K1, D1, K2, D2, size, R, T, flags, alpha, new_size)` for a pair of
/// OpenCV's standard model (Brown lenses included), `cv2.fisheye.stereoRectify(K1, D1, K2, D2,
/// size, R, T, flags, new_size, balance, fov_scale)` for a pair of its fisheye model. `left` is
/// the first camera, `right` the second: X2 = R·X1 + T. See the [module](self) docs for the
/// rule and where the numbers may differ slightly from OpenCV's.
///
/// Refuses, as an argument error naming it: a camera of another model, or a pair of two models
/// or two image sizes (`left`, `right`); an R that is not a rotation or has a non-finite entry
/// (`R`); a zero or non-finite T (`T`); `alpha` outside 0..=1 or on a fisheye pair, `balance`
/// or `fov_scale` on a standard pair, or out of range (their names); a zero or oversized
/// `new_size`; and a lens or a baseline for which OpenCV's rule has no camera to give (a lens
/// that folds inside the image, a rectification that turns a corner of the image behind the
/// rectified image plane), naming the camera.
pub fn stereo_rectify(
    left: &Camera,
    right: &Camera,
    rotation: impl Into<PairRotation>,
    translation: [f64; 3],
    options: &StereoOptions,
) -> Result<StereoRectification> {
    let model = pair_model(left, right)?;
    check_options(model, options)?;
    let om = rotation_vector(rotation.into())?;
    let t = translation_vector(translation)?;
    let new_size = checked_size(left, options.new_size)?;
    let turns = rectifying_rotations(om, t, model == ModelKind::Fisheye);
    if model == ModelKind::Fisheye {
        fisheye_pair(left, right, &turns, new_size, options)
    } else {
        standard_pair(left, right, &turns, new_size, options)
    }
}

/// R1, R2 and what they make of T.
struct Turns {
    r1: DMat3,
    r2: DMat3,
    /// T in the rectified frame (R2·T): along one axis, up to rounding.
    t: DVec3,
    /// OpenCV's `idx`: 0 for a baseline along the rows, 1 along the columns.
    idx: usize,
}

/// The model both cameras share, refusing another model, two models or two sizes.
fn pair_model(left: &Camera, right: &Camera) -> Result<ModelKind> {
    for (side, camera) in [("left", left), ("right", right)] {
        if !matches!(camera.model(), ModelKind::Standard | ModelKind::Fisheye) {
            return Err(Error::argument(
                side,
                format!(
                    "cv2.stereoRectify rectifies OpenCV's standard model (opencv, brown) and cv2.fisheye.stereoRectify its fisheye model (opencv_fisheye); this camera is `{}`",
                    camera.model_name()
                ),
            ));
        }
    }
    if left.model() != right.model() {
        return Err(Error::argument(
            "right",
            format!(
                "the left camera is `{}` and the right `{}`: OpenCV rectifies a pair of one model (cv2.stereoRectify for opencv, cv2.fisheye.stereoRectify for opencv_fisheye)",
                left.model_name(),
                right.model_name()
            ),
        ));
    }
    if (left.width, left.height) != (right.width, right.height) {
        return Err(Error::argument(
            "right",
            format!(
                "the right camera's images are {}×{} and the left's {}×{}: OpenCV rectifies a pair of one image size",
                right.width, right.height, left.width, left.height
            ),
        ));
    }
    Ok(left.model())
}

/// Refuses the options the pair's rule does not take.
fn check_options(model: ModelKind, options: &StereoOptions) -> Result<()> {
    if model == ModelKind::Fisheye {
        if let Some(alpha) = options.alpha {
            return Err(Error::argument(
                "alpha",
                format!(
                    "cv2.fisheye.stereoRectify has no alpha (got {alpha}): a fisheye pair takes balance (0..=1) and fov_scale"
                ),
            ));
        }
        // balance and fov_scale are checked by the fisheye rule itself.
        return Ok(());
    }
    if let Some(alpha) = options.alpha {
        if !(0.0..=1.0).contains(&alpha) {
            return Err(Error::argument(
                "alpha",
                format!(
                    "must be in 0..=1 (0: only pixels with a source in both images, 1: every source pixel of both), or none for OpenCV's -1; got {alpha}"
                ),
            ));
        }
    }
    for (name, value, default) in [
        ("balance", options.balance, 0.0),
        ("fov_scale", options.fov_scale, 1.0),
    ] {
        if value != default {
            return Err(Error::argument(
                name,
                format!(
                    "cv2.fisheye.stereoRectify's {name} (got {value}) is for a fisheye pair; this pair is OpenCV's standard model, whose cv2.stereoRectify takes alpha instead"
                ),
            ));
        }
    }
    Ok(())
}

/// A row-major 3×3 matrix as glam's.
fn mat3(m: [[f64; 3]; 3]) -> DMat3 {
    DMat3::from_cols_array_2d(&m).transpose()
}

/// A glam matrix row-major.
fn rows3(m: DMat3) -> [[f64; 3]; 3] {
    m.transpose().to_cols_array_2d()
}

/// The Rodrigues vector OpenCV rectifies with: a vector as given, a matrix through
/// `cv::Rodrigues` (after checking that it is a rotation).
fn rotation_vector(rotation: PairRotation) -> Result<DVec3> {
    match rotation {
        PairRotation::Rodrigues(v) => {
            if !v.iter().all(|x| x.is_finite()) {
                return Err(Error::argument(
                    "R",
                    format!("the Rodrigues vector {v:?} must have finite entries"),
                ));
            }
            Ok(DVec3::from_array(v))
        }
        PairRotation::Matrix(m) => {
            if !m.iter().flatten().all(|x| x.is_finite()) {
                return Err(Error::argument(
                    "R",
                    format!("the rotation {m:?} must have finite entries"),
                ));
            }
            let r = mat3(m);
            let off = (r.transpose() * r - DMat3::IDENTITY)
                .to_cols_array()
                .into_iter()
                .fold(0.0f64, |a, x| a.max(x.abs()));
            let det = r.determinant();
            let mut why = Vec::new();
            if !(off <= PairRotation::TOLERANCE) {
                why.push(format!(
                    "RᵀR differs from the identity by up to {off:.1e} (at most {:.0e} is taken as rounding)",
                    PairRotation::TOLERANCE
                ));
            }
            if !(det > 0.0) {
                why.push(format!(
                    "det R is {det:.6} (a rotation's is +1; this one mirrors)"
                ));
            }
            if !why.is_empty() {
                return Err(Error::argument(
                    "R",
                    format!("{m:?} is not a rotation: {}", why.join("; ")),
                ));
            }
            Ok(rodrigues_of(nearest_rotation(r)))
        }
    }
}

/// The rotation nearest to an almost-orthogonal matrix (its polar factor, what OpenCV takes as
/// U·Vᵀ of the SVD), by Newton's iteration X ← (X + X⁻ᵀ) / 2.
fn nearest_rotation(r: DMat3) -> DMat3 {
    let mut x = r;
    for _ in 0..20 {
        let next = (x + x.inverse().transpose()) * 0.5;
        let change = (next - x)
            .to_cols_array()
            .into_iter()
            .fold(0.0f64, |a, v| a.max(v.abs()));
        x = next;
        if change <= 1e-16 {
            break;
        }
    }
    x
}

/// `cv::Rodrigues` of a rotation matrix: its axis × angle, read as OpenCV reads it (no turn
/// below the threshold on sin θ, and its choice of sign at a half turn).
fn rodrigues_of(r: DMat3) -> DVec3 {
    let m = rows3(r);
    let v = DVec3::new(m[2][1] - m[1][2], m[0][2] - m[2][0], m[1][0] - m[0][1]);
    let s = (v.length_squared() * 0.25).sqrt();
    let c = ((m[0][0] + m[1][1] + m[2][2] - 1.0) * 0.5).clamp(-1.0, 1.0);
    let theta = c.acos();
    if s >= 1e-5 {
        return v * (theta / (2.0 * s));
    }
    if c > 0.0 {
        return DVec3::ZERO;
    }
    // A half turn: the axis from the diagonal, its signs from the off-diagonal entries.
    let half = |d: f64| ((d + 1.0) * 0.5).max(0.0).sqrt();
    let x = half(m[0][0]);
    let y = half(m[1][1]) * if m[0][1] < 0.0 { -1.0 } else { 1.0 };
    let mut z = half(m[2][2]) * if m[0][2] < 0.0 { -1.0 } else { 1.0 };
    if x.abs() < y.abs() && x.abs() < z.abs() && (m[1][2] > 0.0) != (y * z > 0.0) {
        z = -z;
    }
    let axis = DVec3::new(x, y, z);
    axis * (theta / axis.length())
}

/// `cv::Rodrigues` of a vector: the rotation by |v| about v.
fn rodrigues(v: DVec3) -> DMat3 {
    let theta = v.length();
    if theta < f64::EPSILON {
        return DMat3::IDENTITY;
    }
    let (s, c) = theta.sin_cos();
    let k = v * (1.0 / theta);
    let cross = DMat3::from_cols(
        DVec3::new(0.0, k.z, -k.y),
        DVec3::new(-k.z, 0.0, k.x),
        DVec3::new(k.y, -k.x, 0.0),
    );
    let outer = DMat3::from_cols(k * k.x, k * k.y, k * k.z);
    DMat3::IDENTITY * c + outer * (1.0 - c) + cross * s
}

fn translation_vector(t: [f64; 3]) -> Result<DVec3> {
    let v = DVec3::from_array(t);
    if !v.is_finite() || v == DVec3::ZERO {
        return Err(Error::argument(
            "T",
            format!(
                "the translation {t:?} between the cameras must be finite and not zero (two cameras at one place have no baseline to rectify along)"
            ),
        ));
    }
    Ok(v)
}

/// R1 and R2: each camera turned half of R towards the other, then both so that the baseline
/// lies along the rows (or the columns where it is more vertical, unless `rows_only`, as
/// OpenCV's fisheye rule always takes the rows).
fn rectifying_rotations(om: DVec3, translation: DVec3, rows_only: bool) -> Turns {
    let half = rodrigues(om * -0.5);
    let t = half * translation;
    let idx = if rows_only || t.x.abs() > t.y.abs() {
        0
    } else {
        1
    };
    let c = t[idx];
    let mut axis = DVec3::ZERO;
    axis[idx] = if c > 0.0 { 1.0 } else { -1.0 };
    let mut w = t.cross(axis);
    let nw = w.length();
    if nw > 0.0 {
        // |c| ≤ |t| up to rounding, which must not make acos NaN.
        w *= (c.abs() / t.length()).min(1.0).acos() / nw;
    }
    let turn = rodrigues(w);
    let r1 = turn * half.transpose();
    let r2 = turn * half;
    Turns {
        r1,
        r2,
        t: r2 * translation,
        idx,
    }
}

/// An error of one camera's rule ("camera") as the argument of that side.
fn of_side(side: &'static str) -> impl Fn(Error) -> Error {
    move |e| match e.argument_name() {
        Some("camera") => Error::argument(side, e.message_only()),
        _ => e,
    }
}

/// The angle, in degrees, a rotation turns by.
fn turn_degrees(r: DMat3) -> f64 {
    ((r.x_axis.x + r.y_axis.y + r.z_axis.z - 1.0) * 0.5)
        .clamp(-1.0, 1.0)
        .acos()
        .to_degrees()
}

/// OpenCV's principal point for one camera before alpha: the one that puts the centre of the
/// four image corners, undistorted, turned by `r` and projected with focal length `fc`, at
/// the image centre. The corners are rounded to f32 where OpenCV holds them in `float`.
fn corner_centre(
    camera: &Camera,
    r: DMat3,
    fc: f64,
    idx: usize,
    side: &'static str,
) -> Result<DVec2> {
    let (w, h) = (camera.width as f64, camera.height as f64);
    let f32_round = |p: DVec2| DVec2::new(p.x as f32 as f64, p.y as f32 as f64);
    let mut sum = DVec2::ZERO;
    for corner in [
        DVec2::new(0.0, 0.0),
        DVec2::new(w - 1.0, 0.0),
        DVec2::new(0.0, h - 1.0),
        DVec2::new(w - 1.0, h - 1.0),
    ] {
        let ideal = camera
            .undistort_normalized(camera.intrinsics.to_normalized(corner), InverseMethod::Newton)
            .ok_or_else(|| {
                Error::argument(
                    side,
                    format!(
                        "corner pixel ({}, {}) of the image has no undistorted position (the lens folds over before it): OpenCV's rule centres the undistorted corners",
                        corner.x, corner.y
                    ),
                )
            })?;
        let turned = r * f32_round(ideal).extend(1.0);
        if !(turned.z > 0.0) {
            return Err(Error::argument(
                side,
                format!(
                    "corner pixel ({}, {}) of the image is turned to or behind the rectified image plane: rectifying turns this camera by {:.1}° to lay the baseline T along the image {}, and no pinhole image holds what it saw (T is mostly along the viewing direction)",
                    corner.x,
                    corner.y,
                    turn_degrees(r),
                    if idx == 0 { "rows" } else { "columns" }
                ),
            ));
        }
        let iz = 1.0 / turned.z;
        sum += f32_round(DVec2::new(fc * (turned.x * iz), fc * (turned.y * iz)));
    }
    let mean = sum * 0.25;
    Ok(DVec2::new(
        (w - 1.0) / 2.0 - mean.x,
        (h - 1.0) / 2.0 - mean.y,
    ))
}

/// One principal point for both (`zero_disparity`), or one coordinate across the baseline.
fn shared_centres(c: [DVec2; 2], zero_disparity: bool, idx: usize) -> [DVec2; 2] {
    let mean = (c[0] + c[1]) * 0.5;
    if zero_disparity {
        [mean, mean]
    } else if idx == 0 {
        [DVec2::new(c[0].x, mean.y), DVec2::new(c[1].x, mean.y)]
    } else {
        [DVec2::new(mean.x, c[0].y), DVec2::new(mean.x, c[1].y)]
    }
}

/// The rectified pinhole camera of a projection, refusing one the rule makes unusable.
fn rectified(size: (u32, u32), f: f64, c: DVec2, side: &'static str) -> Result<Camera> {
    let k = Intrinsics {
        fx: f,
        fy: f,
        cx: c.x,
        cy: c.y,
    };
    pinhole(size.0, size.1, k).map_err(of_side(side))
}

/// A 3×4 projection matrix, row-major.
type Projection = [[f64; 4]; 3];

/// P1, P2 and Q from the final focal length, principal points and baseline (`t_idx` the
/// baseline's coordinate in the rectified frame, `fc_t` its product with the focal length as
/// OpenCV rounds it).
fn projections(
    f: f64,
    c: [DVec2; 2],
    idx: usize,
    t_idx: f64,
    fc_t: f64,
) -> (Projection, Projection, [[f64; 4]; 4]) {
    let p = |c: DVec2| [[f, 0.0, c.x, 0.0], [0.0, f, c.y, 0.0], [0.0, 0.0, 1.0, 0.0]];
    let p1 = p(c[0]);
    let mut p2 = p(c[1]);
    p2[idx][3] = fc_t;
    let shift = if idx == 0 {
        c[0].x - c[1].x
    } else {
        c[0].y - c[1].y
    };
    let q = [
        [1.0, 0.0, 0.0, -c[0].x],
        [0.0, 1.0, 0.0, -c[0].y],
        [0.0, 0.0, 0.0, f],
        [0.0, 0.0, -1.0 / t_idx, shift / t_idx],
    ];
    (p1, p2, q)
}

/// `cv2.stereoRectify` for a standard-model pair.
fn standard_pair(
    left: &Camera,
    right: &Camera,
    turns: &Turns,
    (new_w, new_h): (u32, u32),
    options: &StereoOptions,
) -> Result<StereoRectification> {
    let (w, h) = (left.width as f64, left.height as f64);
    let (nw, nh) = (new_w as f64, new_h as f64);
    let idx = turns.idx;
    // The mean of the focal lengths across the baseline, scaled to the new image.
    let ratio = if idx == 1 { nw / w / 2.0 } else { nh / h / 2.0 };
    let (a, b) = (left.intrinsics, right.intrinsics);
    let fc = (if idx == 1 { a.fx + b.fx } else { a.fy + b.fy }) * ratio;
    let cameras = [(left, turns.r1, "left"), (right, turns.r2, "right")];
    let mut centres = [DVec2::ZERO; 2];
    for (slot, &(camera, r, side)) in centres.iter_mut().zip(&cameras) {
        *slot = corner_centre(camera, r, fc, idx, side)?;
    }
    let c0 = shared_centres(centres, options.zero_disparity, idx);
    // The rectangles in the first rectified cameras' pixels (OpenCV's P1, P2 before alpha).
    let mut rects = [(ZERO_RECT, ZERO_RECT); 2];
    for ((slot, &(camera, r, side)), c) in rects.iter_mut().zip(&cameras).zip(c0) {
        let k = Intrinsics {
            fx: fc,
            fy: fc,
            cx: c.x,
            cy: c.y,
        };
        *slot = undistort_rectangles(camera, Unmapped::Refuse, |x| {
            let v = r * x.extend(1.0);
            (v.z > 0.0).then(|| k.to_pixel(DVec2::new(v.x / v.z, v.y / v.z)))
        })
        .map_err(of_side(side))?;
    }
    // The principal points moved to the new image.
    let c = c0.map(|c| DVec2::new(nw * c.x / w, nh * c.y / h));
    let s = match options.alpha {
        None => 1.0,
        Some(alpha) => {
            // Per side of each image: the scale that puts that side of the rectangle on the
            // new image's edge.
            let ratios = |r: Rect, k: usize| side_scales(r, c0[k], c[k], new_w, new_h);
            let inner = [ratios(rects[0].0, 0), ratios(rects[1].0, 1)];
            let outer = [ratios(rects[0].1, 0), ratios(rects[1].1, 1)];
            let s0 = inner
                .iter()
                .flatten()
                .fold(f64::NEG_INFINITY, |m, &x| m.max(x));
            let s1 = outer.iter().flatten().fold(f64::INFINITY, |m, &x| m.min(x));
            s0 * (1.0 - alpha) + s1 * alpha
        }
    };
    if !(s > 0.0 && s.is_finite()) {
        return Err(Error::argument(
            "alpha",
            format!(
                "the undistorted, rectified images do not surround their principal points (scale {s}): alpha's rule has no focal length to give; leave alpha out (OpenCV's -1)"
            ),
        ));
    }
    let f = fc * s;
    let t_idx = turns.t[idx];
    let (p1, p2, q) = projections(f, c, idx, t_idx, t_idx * fc * s);
    let roi = |(inner, _): (Rect, Rect), k: usize| scaled_roi(inner, c0[k], c[k], s, new_w, new_h);
    Ok(StereoRectification {
        r1: rows3(turns.r1),
        r2: rows3(turns.r2),
        p1,
        p2,
        q,
        roi1: roi(rects[0], 0),
        roi2: roi(rects[1], 1),
        left: rectified((new_w, new_h), f, c[0], "left")?,
        right: rectified((new_w, new_h), f, c[1], "right")?,
        vertical: idx == 1,
    })
}

const ZERO_RECT: Rect = Rect {
    x: 0.0,
    y: 0.0,
    width: 0.0,
    height: 0.0,
};

/// `cv2.fisheye.stereoRectify` for a fisheye pair.
fn fisheye_pair(
    left: &Camera,
    right: &Camera,
    turns: &Turns,
    new_size: (u32, u32),
    options: &StereoOptions,
) -> Result<StereoRectification> {
    let size = Some(new_size);
    let rule = |camera: &Camera, r: DMat3, side: &'static str| {
        fisheye_rule(camera, r, options.balance, options.fov_scale, size)
            .map(|c| c.intrinsics)
            .map_err(of_side(side))
    };
    let a = rule(left, turns.r1, "left")?;
    let b = rule(right, turns.r2, "right")?;
    // The smaller vertical focal length, for both.
    let f = if b.fy < a.fy { b.fy } else { a.fy };
    let c = shared_centres(
        [DVec2::new(a.cx, a.cy), DVec2::new(b.cx, b.cy)],
        options.zero_disparity,
        0,
    );
    let t_x = turns.t.x;
    let (p1, p2, q) = projections(f, c, 0, t_x, t_x * f);
    let whole = (0, 0, new_size.0, new_size.1);
    Ok(StereoRectification {
        r1: rows3(turns.r1),
        r2: rows3(turns.r2),
        p1,
        p2,
        q,
        roi1: whole,
        roi2: whole,
        left: rectified(new_size, f, c[0], "left")?,
        right: rectified(new_size, f, c[1], "right")?,
        vertical: false,
    })
}

#[cfg(test)]
mod tests;
