//! The pinhole camera an undistorted image is drawn into, chosen by OpenCV's two rules, so
//! that a script built on them gets the same camera from vklens:
//!
//! * [`optimal_new_camera`] is `cv2.getOptimalNewCameraMatrix` (OpenCV, `modules/calib3d`,
//!   `getOptimalNewCameraMatrix` and `getUndistortRectangles`) for OpenCV's standard model. A
//!   9 × 9 grid of pixels spanning the image is undistorted; the rectangle inside the left,
//!   right, top and bottom columns and rows (*inner*: every pixel of it has a source) and the
//!   one around all of them (*outer*: no source pixel is lost) each give a camera that maps
//!   it onto the new image, and `alpha` blends the two (0: inner, 1: outer). With
//!   `center_principal_point` the principal point is the new image's centre and one scale,
//!   between the largest that keeps the inner rectangle's four sides and the smallest that
//!   keeps the outer's, is blended instead.
//! * [`fisheye_new_camera`] is `cv2.fisheye.estimateNewCameraMatrixForUndistortRectify`
//!   (OpenCV, `fisheye.cpp`) for OpenCV's fisheye model, with `R` the identity. The midpoints
//!   of the four image edges (OpenCV's: `(w/2, 0)`, `(w, h/2)`, `(w/2, h)`, `(0, h/2)`, in
//!   whole pixels) are undistorted; their mean is the new principal point, each edge's distance
//!   from it gives a focal length that puts that edge on the new image's edge, and `balance`
//!   blends the largest (0) and the smallest (1), divided by `fov_scale`. The search runs on
//!   y scaled by fx / fy, and the new principal point is divided by that ratio again: so the
//!   midpoints' centre lands on the image centre, and the chosen edge on its image edge, only
//!   for square pixels (fx = fy). vklens keeps the rule as OpenCV computes it, for the cameras
//!   to agree.
//!
//! Both undistort with vklens's converged inverse (Newton, [`InverseMethod::Newton`]).
//! OpenCV's `undistortPoints` stops the standard model's fixed-point iteration after 5 steps
//! (its default criteria), which has not converged on a strong lens near the image corners:
//! there the two cameras differ slightly, vklens's being the one the rule means. OpenCV's
//! fisheye `undistortPoints` runs Newton to 1e-8 and agrees. It also clips the distorted radius
//! θ_d at π/2 (and then scales the point by θ_d / (π/2) again), which decides the camera of a
//! lens past 180° whose edge midpoints lie outside its image circle; vklens clips as it does,
//! so that such a lens gets OpenCV's camera too.
//! One difference remains, where OpenCV's answer is not the lens's: `fisheye::undistortPoints`
//! ignores the skew `K[0][1]`, which vklens removes.
//!
//! The valid ROI is OpenCV's: the inner rectangle in the new camera's pixels, rounded and cut
//! to the new image. OpenCV's fisheye rule has none; vklens gives it the same one, where border
//! pixels that see at or past 90° off the axis (which no pinhole image holds) bound nothing.
//!
//! Pixel-centre convention: OpenCV's, as everywhere in vklens ([`super`]).

use std::f64::consts::FRAC_PI_2;

use glam::{DMat3, DVec2};

use super::{
    check_size, Camera, Intrinsics, InverseMethod, ModelKind, OpenCvDistortion, ValidDomain,
};
use crate::{Error, Result};

/// Points per side of the grid `getUndistortRectangles` undistorts (OpenCV's `N`).
const GRID: usize = 9;

/// A valid-pixel rectangle `(x, y, width, height)` in the new image, as OpenCV's `cv::Rect`
/// (all zero where nothing is valid).
pub type Roi = (u32, u32, u32, u32);

/// An axis-aligned rectangle in f64, OpenCV's `Rect_<double>`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Rect {
    pub(super) x: f64,
    pub(super) y: f64,
    pub(super) width: f64,
    pub(super) height: f64,
}

/// What to do with a grid pixel the inverse has no answer for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Unmapped {
    /// Refuse: OpenCV's rule needs every grid pixel.
    Refuse,
    /// Skip it: it sees at or past 90° off the axis, where the pinhole plane reaches without
    /// end, so it bounds no rectangle on that side.
    Skip,
}

/// `cv2.getOptimalNewCameraMatrix(K, D, size, alpha, new_size, center_principal_point)`: the
/// new pinhole camera (of size `new_size`, the camera's own when `None`) and the valid ROI, for
/// a camera of OpenCV's standard model (a Brown lens included). See the [module](self) docs for
/// the rule and where the camera may differ slightly from OpenCV's.
///
/// Refuses `alpha` outside `0..=1` (and NaN), a zero or oversized `new_size`, a camera of
/// another model, and a lens that folds inside the image (a grid pixel with no undistorted
/// position: OpenCV's rectangles are meaningless there).
pub fn optimal_new_camera(
    camera: &Camera,
    alpha: f64,
    new_size: Option<(u32, u32)>,
    center_principal_point: bool,
) -> Result<(Camera, Roi)> {
    if !(0.0..=1.0).contains(&alpha) {
        return Err(Error::argument(
            "alpha",
            format!(
                "must be in 0..=1 (0: every pixel valid, 1: every source pixel kept), got {alpha}"
            ),
        ));
    }
    if camera.model() != ModelKind::Standard {
        let hint = if camera.model() == ModelKind::Fisheye {
            ": a fisheye takes `balance` (cv2.fisheye.estimateNewCameraMatrixForUndistortRectify) instead"
        } else {
            ""
        };
        return Err(Error::argument(
            "alpha",
            format!(
                "cv2.getOptimalNewCameraMatrix's rule is for OpenCV's standard model (opencv, brown), and this camera is `{}`{hint}",
                camera.model_name()
            ),
        ));
    }
    let (new_w, new_h) = checked_size(camera, new_size)?;
    if center_principal_point {
        return centred(camera, alpha, new_w, new_h);
    }
    // The rectangles in normalized coordinates (OpenCV passes no new matrix).
    let (inner, outer) = undistort_rectangles(camera, Unmapped::Refuse, Some)?;
    if !(inner.width > 0.0 && inner.height > 0.0) {
        return Err(Error::argument(
            "camera",
            "the lens bends the image's opposite sides past each other when undistorted: no rectangle has a source in every pixel",
        ));
    }
    // The camera mapping a rectangle onto the new image's pixel centres 0..=w-1.
    let fit = |r: Rect| {
        let fx = (new_w as f64 - 1.0) / r.width;
        let fy = (new_h as f64 - 1.0) / r.height;
        [fx, fy, -fx * r.x, -fy * r.y]
    };
    let (a, b) = (fit(inner), fit(outer));
    let mix = |i: usize| a[i] * (1.0 - alpha) + b[i] * alpha;
    let intrinsics = Intrinsics {
        fx: mix(0),
        fy: mix(1),
        cx: mix(2),
        cy: mix(3),
    };
    let new_camera = pinhole(new_w, new_h, intrinsics)?;
    // OpenCV undistorts the grid again straight into the new camera for its ROI.
    let (inner, _) = undistort_rectangles(camera, Unmapped::Refuse, |x| {
        Some(new_camera.intrinsics.to_pixel(x))
    })?;
    Ok((new_camera, rounded_roi(inner, new_w, new_h)))
}

/// [`optimal_new_camera`] with the principal point at the new image's centre: one scale of
/// the camera's focal lengths, blended by `alpha` between the largest that keeps each side of
/// the inner rectangle and the smallest that keeps each side of the outer one.
fn centred(camera: &Camera, alpha: f64, new_w: u32, new_h: u32) -> Result<(Camera, Roi)> {
    let k = camera.intrinsics;
    // The rectangles in the camera's own pixels (OpenCV passes K as the new matrix).
    let (inner, outer) = undistort_rectangles(camera, Unmapped::Refuse, |x| Some(k.to_pixel(x)))?;
    let cx = (new_w as f64 - 1.0) * 0.5;
    let cy = (new_h as f64 - 1.0) * 0.5;
    let (cx0, cy0) = (k.cx, k.cy);
    let (from, to) = (DVec2::new(cx0, cy0), DVec2::new(cx, cy));
    let ratios = |r: Rect| side_scales(r, from, to, new_w, new_h);
    let s0 = ratios(inner).into_iter().fold(f64::NEG_INFINITY, f64::max);
    let s1 = ratios(outer).into_iter().fold(f64::INFINITY, f64::min);
    let s = s0 * (1.0 - alpha) + s1 * alpha;
    if !(s > 0.0 && s.is_finite()) {
        return Err(Error::argument(
            "center_principal_point",
            format!(
                "the principal point ({cx0}, {cy0}) is not inside the undistorted image, so no scale about it keeps the image's sides"
            ),
        ));
    }
    let new = Intrinsics {
        fx: k.fx * s,
        fy: k.fy * s,
        cx,
        cy,
    };
    let new_camera = pinhole(new_w, new_h, new)?;
    Ok((new_camera, scaled_roi(inner, from, to, s, new_w, new_h)))
}

/// For each side of rectangle `r` (left, top, right, bottom; in pixels of a camera whose
/// principal point is `from`), the scale about the principal point that puts it on that edge
/// of a `width`×`height` image whose principal point is `to`: OpenCV's scales of
/// `getOptimalNewCameraMatrix`'s centred camera and of `stereoRectify`'s alpha.
pub(super) fn side_scales(r: Rect, from: DVec2, to: DVec2, width: u32, height: u32) -> [f64; 4] {
    [
        to.x / (from.x - r.x),
        to.y / (from.y - r.y),
        (width as f64 - 1.0 - to.x) / (r.x + r.width - from.x),
        (height as f64 - 1.0 - to.y) / (r.y + r.height - from.y),
    ]
}

/// OpenCV's ROI of a camera scaled by `s` about its principal point (`from`, moved to `to` in a
/// `width`×`height` image): the inner rectangle scaled so, its corner rounded up and its size
/// down, cut to the image.
pub(super) fn scaled_roi(
    inner: Rect,
    from: DVec2,
    to: DVec2,
    s: f64,
    width: u32,
    height: u32,
) -> Roi {
    intersect(
        [
            saturate(((inner.x - from.x) * s + to.x).ceil()),
            saturate(((inner.y - from.y) * s + to.y).ceil()),
            saturate((inner.width * s).floor()),
            saturate((inner.height * s).floor()),
        ],
        width,
        height,
    )
}

/// `cv2.fisheye.estimateNewCameraMatrixForUndistortRectify(K, D, size, R = I, balance,
/// new_size, fov_scale)`: the new pinhole camera (of size `new_size`, the camera's own when
/// `None`) for a camera of OpenCV's fisheye model, with a valid ROI as
/// [`optimal_new_camera`] finds one. See the [module](self) docs for the rule.
///
/// Refuses `balance` outside `0..=1` (OpenCV clamps it), `fov_scale` that is not a positive
/// number (OpenCV ignores it then), a zero or oversized `new_size`, a camera of another model,
/// and an edge midpoint that sees (θ_d clipped at π/2 as OpenCV clips it) past what a pinhole
/// image holds, or lies past the lens's fold or field of view: OpenCV's answer there is not a
/// camera (a focal length near zero).
pub fn fisheye_new_camera(
    camera: &Camera,
    balance: f64,
    fov_scale: f64,
    new_size: Option<(u32, u32)>,
) -> Result<(Camera, Roi)> {
    let new_camera = fisheye_rule(camera, DMat3::IDENTITY, balance, fov_scale, new_size)?;
    let (new_w, new_h) = (new_camera.width, new_camera.height);
    let (inner, _) = undistort_rectangles(camera, Unmapped::Skip, |x| {
        Some(new_camera.intrinsics.to_pixel(x))
    })?;
    // A side whose grid pixels all see past 90° bounds nothing and stays at ±FLT_MAX: cut to
    // just outside the image first, so that rounding to whole pixels cannot overflow.
    let (x0, y0) = (inner.x.max(-1.0), inner.y.max(-1.0));
    let x1 = (inner.x + inner.width).min(new_w as f64 + 1.0);
    let y1 = (inner.y + inner.height).min(new_h as f64 + 1.0);
    let inner = Rect {
        x: x0,
        y: y0,
        width: x1 - x0,
        height: y1 - y0,
    };
    Ok((new_camera, rounded_roi(inner, new_w, new_h)))
}

/// The camera of [`fisheye_new_camera`]'s rule with OpenCV's `R` argument: the undistorted
/// edge midpoints are turned by `rotation` (a rectification) before the search, as
/// `cv2.fisheye.stereoRectify` asks for each camera of a pair. Refuses what
/// [`fisheye_new_camera`] refuses, and a midpoint the rotation turns to or behind the new
/// image plane.
pub(super) fn fisheye_rule(
    camera: &Camera,
    rotation: DMat3,
    balance: f64,
    fov_scale: f64,
    new_size: Option<(u32, u32)>,
) -> Result<Camera> {
    if !(0.0..=1.0).contains(&balance) {
        return Err(Error::argument(
            "balance",
            format!(
                "must be in 0..=1 (0: the largest focal length, 1: the smallest), got {balance}"
            ),
        ));
    }
    if !(fov_scale > 0.0 && fov_scale.is_finite()) {
        return Err(Error::argument(
            "fov_scale",
            format!("must be a positive number (the new focal length is divided by it), got {fov_scale}"),
        ));
    }
    if camera.model() != ModelKind::Fisheye {
        let hint = if camera.model() == ModelKind::Standard {
            ": OpenCV's standard model takes `alpha` (cv2.getOptimalNewCameraMatrix) instead"
        } else {
            ""
        };
        return Err(Error::argument(
            "balance",
            format!(
                "cv2.fisheye.estimateNewCameraMatrixForUndistortRectify's rule is for OpenCV's fisheye model (opencv_fisheye), and this camera is `{}`{hint}",
                camera.model_name()
            ),
        ));
    }
    let (new_w, new_h) = checked_size(camera, new_size)?;
    let (w, h) = (camera.width, camera.height);
    // OpenCV's integer halves.
    let midpoints = [
        ("top", DVec2::new((w / 2) as f64, 0.0)),
        ("right", DVec2::new(w as f64, (h / 2) as f64)),
        ("bottom", DVec2::new((w / 2) as f64, h as f64)),
        ("left", DVec2::new(0.0, (h / 2) as f64)),
    ];
    let mut points = [DVec2::ZERO; 4];
    for (slot, (edge, p)) in points.iter_mut().zip(midpoints) {
        let x = clipped_pinhole_point(camera, p).ok_or_else(|| {
            Error::argument(
                "camera",
                format!(
                    "the midpoint of the image's {edge} edge, pixel ({}, {}), sees {:.1}° or more off the axis even with its distorted radius clipped at π/2 as OpenCV clips it (or lies past the lens's field of view): no pinhole image holds it, so the fisheye rule has no camera to give",
                    p.x,
                    p.y,
                    ValidDomain::RADIUS_CAP.atan().to_degrees()
                ),
            )
        })?;
        // OpenCV turns the point on the plane z = 1 by R and projects it again.
        let turned = rotation * x.extend(1.0);
        if !(turned.z > 0.0) {
            return Err(Error::argument(
                "camera",
                format!(
                    "the midpoint of the image's {edge} edge, pixel ({}, {}), is turned to or behind the rectified image plane by the rectification: no pinhole image holds it, so the fisheye rule has no camera to give",
                    p.x, p.y
                ),
            ));
        }
        *slot = DVec2::new(turned.x / turned.z, turned.y / turned.z);
    }
    let k = camera.intrinsics;
    let aspect = k.fx / k.fy;
    // Square pixels for the search, as OpenCV: y scaled by fx / fy, undone at the end.
    for p in &mut points {
        p.y *= aspect;
    }
    let centre = points.iter().copied().sum::<DVec2>() / 4.0;
    let min = points.iter().fold(DVec2::splat(f64::MAX), |a, &p| a.min(p));
    let max = points
        .iter()
        .fold(DVec2::splat(-f64::MAX), |a, &p| a.max(p));
    let focals = [
        w as f64 * 0.5 / (centre.x - min.x),
        w as f64 * 0.5 / (max.x - centre.x),
        h as f64 * 0.5 * aspect / (centre.y - min.y),
        h as f64 * 0.5 * aspect / (max.y - centre.y),
    ];
    let fmin = focals.into_iter().fold(f64::INFINITY, f64::min);
    let fmax = focals.into_iter().fold(f64::NEG_INFINITY, f64::max);
    if !(fmin > 0.0 && fmax.is_finite()) {
        return Err(Error::argument(
            "camera",
            "the undistorted edge midpoints do not surround their centre (the lens maps opposite edges past each other): the fisheye rule has no focal length to give",
        ));
    }
    let f = (balance * fmin + (1.0 - balance) * fmax) / fov_scale;
    let c = DVec2::new(w as f64, h as f64 * aspect) * 0.5 - centre * f;
    let (rx, ry) = match new_size {
        Some((nw, nh)) => (nw as f64 / w as f64, nh as f64 / h as f64),
        None => (1.0, 1.0),
    };
    let intrinsics = Intrinsics {
        fx: f * rx,
        fy: f / aspect * ry,
        cx: c.x * rx,
        cy: c.y / aspect * ry,
    };
    pinhole(new_w, new_h, intrinsics)
}

/// The new image's size: `new_size`, or the camera's own.
pub(super) fn checked_size(camera: &Camera, new_size: Option<(u32, u32)>) -> Result<(u32, u32)> {
    let Some((w, h)) = new_size else {
        return Ok((camera.width, camera.height));
    };
    check_size(w, h).map_err(|e| Error::argument("new_size", e.to_string()))?;
    Ok((w, h))
}

/// The pinhole camera of the new image; a camera the rule makes absurd (a focal length of
/// 1e9 px from a lens that hardly bends its edges) is refused, saying so.
pub(super) fn pinhole(width: u32, height: u32, k: Intrinsics) -> Result<Camera> {
    Camera::new(width, height, k, OpenCvDistortion::default()).map_err(|e| {
        Error::argument(
            "camera",
            format!("the rule gives no usable pinhole camera for this lens ({e})"),
        )
    })
}

/// Where the ray of a distorted pixel meets the pinhole plane z = 1, `None` where it does not
/// (at or past 90° off the axis, outside the lens's domain).
fn pinhole_point(camera: &Camera, pixel: DVec2) -> Option<DVec2> {
    let ray = camera.unproject(pixel)?;
    (ray.z > 0.0).then(|| DVec2::new(ray.x / ray.z, ray.y / ray.z))
}

/// A fisheye edge midpoint on the pinhole plane z = 1 as OpenCV's `fisheye::undistortPoints`
/// finds it: the distorted radius θ_d clipped at π/2 first. `None` where the point sees past
/// the radius a pinhole image holds ([`ValidDomain::RADIUS_CAP`]) or the lens's domain.
fn clipped_pinhole_point(camera: &Camera, pixel: DVec2) -> Option<DVec2> {
    let lens = camera.fisheye_lens()?;
    let y = camera.intrinsics.to_normalized(pixel);
    let theta_d = lens.unskew(y).length();
    // OpenCV solves for θ at the clipped radius, then scales the unclipped point by
    // tan θ / θ_d with θ_d clipped: past π/2 the point lands θ_d / (π/2) farther out than the
    // direction at θ. The skew is linear, so scaling the point scales its radius alike.
    let (y, stretch) = if theta_d > FRAC_PI_2 {
        (y * (FRAC_PI_2 / theta_d), theta_d / FRAC_PI_2)
    } else {
        (y, 1.0)
    };
    let ray = lens.undistort_ray(y)?;
    let x = DVec2::new(ray.x / ray.z, ray.y / ray.z);
    (ray.z > 0.0 && x.length() <= ValidDomain::RADIUS_CAP).then_some(x * stretch)
}

/// OpenCV's `getUndistortRectangles`: the inner and outer rectangles of a 9 × 9 grid of pixels
/// spanning the image (centres 0..=w-1, 0..=h-1), undistorted and mapped by `to` (`None`
/// where the mapped point has no place in the new image, which `unmapped` decides on as for
/// a pixel without an undistorted position).
pub(super) fn undistort_rectangles(
    camera: &Camera,
    unmapped: Unmapped,
    to: impl Fn(DVec2) -> Option<DVec2>,
) -> Result<(Rect, Rect)> {
    let step_x = (camera.width as f64 - 1.0) / (GRID - 1) as f64;
    let step_y = (camera.height as f64 - 1.0) / (GRID - 1) as f64;
    // OpenCV starts the inner bounds at ±FLT_MAX.
    let big = f32::MAX as f64;
    let (mut ix0, mut ix1, mut iy0, mut iy1) = (-big, big, -big, big);
    let (mut ox0, mut ox1, mut oy0, mut oy1) = (big, -big, big, -big);
    for gy in 0..GRID {
        for gx in 0..GRID {
            let pixel = DVec2::new(gx as f64 * step_x, gy as f64 * step_y);
            let ideal = if camera.model() == ModelKind::Standard {
                camera.undistort_normalized(
                    camera.intrinsics.to_normalized(pixel),
                    InverseMethod::Newton,
                )
            } else {
                pinhole_point(camera, pixel)
            };
            let Some(p) = ideal.and_then(&to) else {
                match unmapped {
                    Unmapped::Skip => continue,
                    Unmapped::Refuse => {
                        return Err(Error::argument(
                            "camera",
                            format!(
                                "pixel ({}, {}) of the image has no undistorted position (the lens folds over before it, or the rectification turns it behind the image plane): OpenCV's rule needs every pixel of its 9 × 9 grid; `vklens overscan` gives a camera for the valid region instead",
                                pixel.x, pixel.y
                            ),
                        ))
                    }
                }
            };
            ox0 = ox0.min(p.x);
            ox1 = ox1.max(p.x);
            oy0 = oy0.min(p.y);
            oy1 = oy1.max(p.y);
            if gx == 0 {
                ix0 = ix0.max(p.x);
            }
            if gx == GRID - 1 {
                ix1 = ix1.min(p.x);
            }
            if gy == 0 {
                iy0 = iy0.max(p.y);
            }
            if gy == GRID - 1 {
                iy1 = iy1.min(p.y);
            }
        }
    }
    let rect = |x0: f64, y0: f64, x1: f64, y1: f64| Rect {
        x: x0,
        y: y0,
        width: x1 - x0,
        height: y1 - y0,
    };
    Ok((rect(ix0, iy0, ix1, iy1), rect(ox0, oy0, ox1, oy1)))
}

/// `saturate_cast<int>` of a whole or rounded number: clamped to `int`'s range (NaN to 0).
fn saturate(v: f64) -> i64 {
    v.clamp(i32::MIN as f64, i32::MAX as f64) as i64
}

/// OpenCV's `Rect r = inner` (each of x, y, width, height rounded to the nearest, ties to even
/// as `cvRound` does) cut to the new image.
fn rounded_roi(r: Rect, width: u32, height: u32) -> Roi {
    intersect(
        [r.x, r.y, r.width, r.height].map(|v| saturate(v.round_ties_even())),
        width,
        height,
    )
}

/// OpenCV's `r &= Rect(0, 0, width, height)`: the overlap, or all zero where there is none.
fn intersect([x, y, w, h]: [i64; 4], width: u32, height: u32) -> Roi {
    if w <= 0 || h <= 0 {
        return (0, 0, 0, 0);
    }
    let x1 = x.max(0);
    let y1 = y.max(0);
    let w1 = (x + w).min(width as i64) - x1;
    let h1 = (y + h).min(height as i64) - y1;
    if w1 <= 0 || h1 <= 0 {
        return (0, 0, 0, 0);
    }
    // Inside 0..=width and 0..=height, both u32.
    (x1 as u32, y1 as u32, w1 as u32, h1 as u32)
}

#[cfg(test)]
mod tests;
