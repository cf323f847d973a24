//! The cost model: per-pixel, per-triangle and per-vertex times on lavapipe (2 cores), read
//! off the benches (`bench vertex`, `bench warp`, `bench inverse`, `bench wide`,
//! docs/benchmarks.md), and the frame time they estimate. Only their ratios matter to the
//! choice; `--explain` prints the times measured on the frame itself.

use crate::model::InverseMethod;

/// Inverse methods the planner chooses between, cheapest first for `terms`, with a per-pixel
/// GPU cost (ns, f32, lavapipe), read off the README's `bench inverse` table: Heikkilä ~25;
/// fixed-point ~22 + N × (1.2 for radial lenses, 6 with rational, prism or tilt terms, e.g.
/// 36 → 129 ns from 5 to 20 iterations on `prism_tilt`); Newton ~70 (radial) to ~100.
pub fn inverse_candidates_for(terms: crate::model::Terms) -> Vec<(InverseMethod, f64)> {
    if terms.is_ray_model() {
        // One inverse for the ray models: their own (closed form, or Newton).
        return vec![(InverseMethod::Newton, ray_model_inverse_ns(terms.model))];
    }
    let complex = terms.rational || terms.prism || terms.tilt;
    let per_iteration = if complex { 6.0 } else { 1.2 };
    let mut v = vec![(InverseMethod::Heikkila, 25.0)];
    for n in [1, 2, 3, 5, 10, 20, 50] {
        v.push((
            InverseMethod::FixedPoint(n),
            22.0 + per_iteration * n as f64,
        ));
    }
    v.push((InverseMethod::Newton, if complex { 100.0 } else { 70.0 }));
    v.sort_by(|a, b| a.1.total_cmp(&b.1));
    v
}

/// GPU cost per pixel (ns, f32, lavapipe) of a ray model's inverse: the fisheye's 70 (Newton
/// on θ, as `bench inverse` measured it) scaled by the model's `inverse_cost` in
/// `src/model/list.rs` (closed forms about 0.6–0.8 of it, the omni model and the thin-prism
/// fisheyes, Newton on their plane, about 2.6× and 3×).
pub fn ray_model_inverse_ns(model: crate::model::ModelKind) -> f64 {
    const FISHEYE_NS: f64 = 70.0;
    FISHEYE_NS * model.inverse_cost()
}

/// [`inverse_candidates_for`] a lens with every term.
pub fn inverse_candidates() -> Vec<(InverseMethod, f64)> {
    inverse_candidates_for(crate::model::Terms {
        radial: true,
        rational: true,
        tangential: true,
        prism: true,
        tilt: true,
        model: crate::model::ModelKind::Standard,
    })
}

// The cost model: frame times on lavapipe (2 cores), from `vklens bench vertex` and
// `vklens bench warp` at 800×600 (docs/benchmarks.md). Only their ratios matter to the choice.

/// A pinhole render, per output pixel (ns): clear, raster and store (`bench vertex`, plain).
pub(super) const RENDER_NS_PER_PIXEL: f64 = 12.0;
/// A pinhole render, per triangle (ns) (`bench vertex`, plain render at 128² and 512² quads).
pub(super) const RENDER_NS_PER_TRIANGLE: f64 = 230.0;
/// Alg. 1 with its compute discard (the default), per vertex, beyond the plain render of the
/// same triangles (ns): the per-vertex pass (the model once per vertex, the discard's
/// bookkeeping); the draw that follows costs what the plain render does. `bench vertex`,
/// 2026-12-02, 512² quads (263,169 vertices), the 14-term lens: 112.3 against 92.2 ms at
/// 800×600 (76 ns a vertex), 140.6 against 113.2 ms at 1920×1080 (104 ns). The geometry-shader
/// discard costs 2.2× and 1.9× the plain render there.
pub(super) const DISCARD_NS_PER_VERTEX: f64 = 90.0;
/// The overscanned source a warp renders, in source pixels per output pixel (density 1 on
/// the shipped barrel and prism cameras).
pub(super) const OVERSCAN_AREA: f64 = 1.3;
/// Sampling a precomputed map in the warp, per output pixel (ns): `bench warp` "warp map",
/// 6.0 ms at 800×600.
pub(super) const MAP_WARP_NS: f64 = 12.5;
/// The same with three maps, one per channel: "warp map chromatic", 10.6 ms at 800×600.
pub(super) const MAP_WARP_CHROMATIC_NS: f64 = 22.0;
/// Building a coarse map (every 8th pixel solved, cubic between), per output pixel and
/// channel (ns): "inverse map build: coarse8+cubic", 3.2 ms at 800×600.
pub(super) const MAP_BUILD_NS: f64 = 6.7;
/// The sphere warp from a cube map, per output pixel and fetch (ns): each pixel's ray (the
/// lens's inverse) and a bilinear cube fetch into an RGBA8 target. `bench wide`, 2026-12-02,
/// GPU time of the warp pass at 1920×1080: 24 and 23 ns a pixel on the 180° and 200°
/// fisheyes, 30 on the GoPro-like lens (its inverse is a Newton solve).
pub(super) const SPHERE_WARP_NS: f64 = 25.0;
/// The cube path's geometric error (px): the pixel each output pixel's f32 ray reprojects
/// to, against the f64 model, the largest over `bench wide`'s three lenses (2.2e-4 px on the
/// GoPro-like lens, 1.1e-4 and 8.5e-5 on the 180° and 200° fisheyes).
pub(super) const CUBE_RAY_ERROR_PX: f64 = 2.5e-4;
/// The largest face the planner asks for: the smallest `maxImageDimensionCube` Vulkan allows
/// (the recorder clamps to the device's own limit and the cube budget again).
pub(super) const PLANNED_CUBE_MAX_SIDE: u32 = 4096;

/// The f32 floor of a coarse cubic map's coordinates (px): its measured error at 1080p on
/// `prism_tilt` ("map max error px" in `bench warp`), where the f64 estimate is 3e-6 px.
pub(super) const MAP_F32_FLOOR_PX: f64 = 5.3e-4;

/// The rolling-shutter solve per vertex (ns), beyond Alg. 1's for a still camera: each
/// vertex scans 17 readout times through the lens before it refines. `bench rolling-shutter`,
/// 2026-12-03, 800×600: 29.3 against 17.3 ms at 128² quads (16,641 vertices, 721 ns a vertex),
/// 295.1 against 115.5 ms at 512² (263,169 vertices, 682 ns).
pub(super) const ROLLING_SHUTTER_NS_PER_VERTEX: f64 = 700.0;

/// The warp's pinhole source alone, one render (ms): what each further band of a moving
/// rolling shutter adds to the warp route's frame.
pub(super) fn source_render_ms(pixels: f64, triangles: f64) -> f64 {
    (RENDER_NS_PER_PIXEL * OVERSCAN_AREA * pixels + RENDER_NS_PER_TRIANGLE * triangles) * 1e-6
}

/// One pinhole render of `pixels` pixels (ms): a cube face, which each further band of a
/// moving rolling shutter renders six times.
pub(super) fn face_render_ms(pixels: f64, triangles: f64) -> f64 {
    (RENDER_NS_PER_PIXEL * pixels + RENDER_NS_PER_TRIANGLE * triangles) * 1e-6
}

/// What a frame costs, by route.
#[derive(Debug, Clone, Copy)]
pub(super) enum Cost {
    /// A pinhole render of the camera.
    Pinhole,
    /// Alg. 1 on a mesh of this many vertices.
    Vertex { vertices: f64 },
    /// The overscanned pinhole render, then a warp spending `coordinate_ns` per output pixel
    /// on its coordinates and samples.
    Warp { coordinate_ns: f64 },
    /// Six pinhole faces of `side` pixels, each drawing every triangle, then the sphere warp
    /// with `fetches` per output pixel.
    Cube { side: u32, fetches: f64 },
}

/// Estimated frame time (ms) of `pixels` output pixels and `triangles` triangles.
pub(super) fn estimate_ms(pixels: f64, triangles: f64, cost: Cost) -> f64 {
    let ns = match cost {
        Cost::Pinhole => RENDER_NS_PER_PIXEL * pixels + RENDER_NS_PER_TRIANGLE * triangles,
        Cost::Vertex { vertices } => {
            RENDER_NS_PER_PIXEL * pixels
                + RENDER_NS_PER_TRIANGLE * triangles
                + DISCARD_NS_PER_VERTEX * vertices
        }
        Cost::Cube { side, fetches } => {
            6.0 * (RENDER_NS_PER_PIXEL * side as f64 * side as f64
                + RENDER_NS_PER_TRIANGLE * triangles)
                + SPHERE_WARP_NS * fetches * pixels
        }
        Cost::Warp { coordinate_ns } => {
            RENDER_NS_PER_PIXEL * OVERSCAN_AREA * pixels
                + RENDER_NS_PER_TRIANGLE * triangles
                + coordinate_ns * pixels
        }
    };
    ns * 1e-6
}
