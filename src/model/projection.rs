//! Lambers et al. Sec. 3.1: the pinhole frustum from intrinsics, as a Vulkan projection matrix.
//!
//! With OpenCV's pixel-centre convention the image spans `u ∈ [-0.5, w − 0.5]`, so at unit
//! depth the frustum's side planes are
//! `left = −(cx + 0.5)/fx`, `right = w/fx + left`, `top = −(cy + 0.5)/fy`, `bottom = h/fy + top`
//! — exactly Lambers et al.'s l, r, b, t (their y axis points up, ours, like OpenCV's and
//! Vulkan's, points down, so its "b" is our "top").
//!
//! The matrix takes points in the OpenCV camera frame (x right, y down, z forward) to Vulkan
//! clip space (NDC y down, depth 0 at `near`, 1 at `far`). The viewport transform
//! `x_window = (ndc_x + 1) w / 2` then puts a point at window x = u + 0.5, which is OpenCV's
//! pixel u under Vulkan's pixel-centre-at-half-integer convention.

use glam::{DMat4, DVec4};

use super::opencv::Intrinsics;

/// Frustum side planes at unit depth (normalized coordinates, y down).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frustum {
    pub left: f64,
    pub right: f64,
    pub top: f64,
    pub bottom: f64,
}

impl Frustum {
    /// Lambers et al. Sec. 3.1, in OpenCV's pixel-centre convention.
    pub fn from_intrinsics(k: &Intrinsics, width: u32, height: u32) -> Self {
        let left = -(k.cx + 0.5) / k.fx;
        let top = -(k.cy + 0.5) / k.fy;
        Frustum {
            left,
            right: width as f64 / k.fx + left,
            top,
            bottom: height as f64 / k.fy + top,
        }
    }
}

/// The Vulkan projection matrix of an off-centre frustum (x right, y down, z forward; depth
/// 0..1 between `near` and `far`).
pub fn vulkan_projection(f: &Frustum, near: f64, far: f64) -> DMat4 {
    let sx = 2.0 / (f.right - f.left);
    let sy = 2.0 / (f.bottom - f.top);
    let ox = -(f.right + f.left) / (f.right - f.left);
    let oy = -(f.bottom + f.top) / (f.bottom - f.top);
    let a = far / (far - near);
    let b = -far * near / (far - near);
    // Rows: x_c = sx X + ox Z; y_c = sy Y + oy Z; z_c = a Z + b; w_c = Z.
    DMat4::from_cols(
        DVec4::new(sx, 0.0, 0.0, 0.0),
        DVec4::new(0.0, sy, 0.0, 0.0),
        DVec4::new(ox, oy, a, 1.0),
        DVec4::new(0.0, 0.0, b, 0.0),
    )
}
