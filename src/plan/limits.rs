//! What a device can hold: the largest overscanned pinhole source the warp renders and the
//! largest cube map, and why a lens needs a cube map instead of a pinhole source.

use crate::model::overscan::{beyond_a_pinhole, overscan};
use crate::model::Camera;
use crate::pass::geometry::ColorFormat;

/// Largest overscanned pinhole source the warp path renders before it turns to a cube map,
/// in bytes of RGBA32F (4 GiB: the device limit usually binds first).
pub const MAX_WARP_SOURCE_BYTES: u64 = 4 << 30;

/// Largest cube map the cube path renders, all six faces together, in bytes (512 MiB). A
/// face side beyond it is clamped.
pub const MAX_CUBE_BYTES: u64 = 512 << 20;

/// The cube faces' side for `wanted` pixels: at most `max_side` (the device's image and cube
/// limits) and within [`MAX_CUBE_BYTES`] for six faces of `texel_bytes` per pixel.
pub fn cube_side(wanted: u32, texel_bytes: u64, max_side: u32) -> u32 {
    let budget_side = ((MAX_CUBE_BYTES / (6 * texel_bytes)) as f64).sqrt() as u32;
    wanted.min(max_side).min(budget_side)
}

/// The faces this device renders for a colour output in `format` that wants faces of
/// `wanted` pixels: their format (8-bit stays 8-bit, anything else is RGBA32F, the float
/// format every device filters) and their side ([`cube_side`] within the device's image and
/// cube limits).
pub(crate) fn device_cube_faces(
    gpu: &crate::gpu::Gpu,
    format: ColorFormat,
    wanted: u32,
) -> (ColorFormat, u32) {
    let (format, texel) = match format {
        ColorFormat::Rgba8 => (ColorFormat::Rgba8, 4),
        _ => (ColorFormat::Rgba32F, 16),
    };
    let max_side = gpu.max_image_side().min(gpu.max_cube_side());
    (format, cube_side(wanted, texel, max_side))
}

/// Why the warp path cannot use an overscanned pinhole source for `camera` at `density`
/// source pixels per output pixel, on a device of `max_side` px images, if it cannot.
pub fn pinhole_source_refusal(camera: &Camera, density: f64, max_side: u32) -> Option<String> {
    if beyond_a_pinhole(camera) {
        return Some(
            "the lens sees directions 90° and more off its axis, which no pinhole source holds"
                .into(),
        );
    }
    match overscan(camera, density) {
        Err(e) => Some(format!("the overscan fails ({e})")),
        Ok(ov) if ov.width > max_side || ov.height > max_side => Some(format!(
            "the overscanned pinhole source would be {}×{}, beyond the device's {max_side} px image limit",
            ov.width, ov.height
        )),
        Ok(ov) if ov.width as u64 * ov.height as u64 * 16 > MAX_WARP_SOURCE_BYTES => Some(format!(
            "the overscanned pinhole source would be {}×{} ({} MiB), beyond the {} MiB budget",
            ov.width,
            ov.height,
            (ov.width as u64 * ov.height as u64 * 16) >> 20,
            MAX_WARP_SOURCE_BYTES >> 20
        )),
        Ok(_) => None,
    }
}
