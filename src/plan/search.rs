//! The candidates' search: the coarsest tessellation, the cheapest inverse, the precomputed
//! map, the cube map, each with its error measured on this camera (and scene and pose)
//! against the budget and its frame time estimated.

use glam::{DVec2, DVec3};

use super::cost::{
    estimate_ms, face_render_ms, inverse_candidates_for, source_render_ms, Cost, CUBE_RAY_ERROR_PX,
    MAP_BUILD_NS, MAP_F32_FLOOR_PX, MAP_WARP_CHROMATIC_NS, MAP_WARP_NS, PLANNED_CUBE_MAX_SIDE,
    ROLLING_SHUTTER_NS_PER_VERTEX,
};
use super::{chromatic_scales, limits, SceneFile, MAP_COORDINATES};
use crate::model::rolling_shutter::bands::{band_error_px, distance_range, BAND_COUNTS};
use crate::model::rolling_shutter::{FrameMotion, Readout};
use crate::model::{Camera, InverseMethod};
use crate::pass::warp::Coordinates;
use crate::scene::{Pose, Scene};
use crate::Result;

/// The largest error (pixels) of `method` on `camera`: every pixel of a 48 × 36 grid over
/// the image inside the valid domain is undistorted by the method and projected back by the
/// exact forward model. `None` where the method refuses a pixel Newton accepts.
pub fn inverse_error_px(camera: &Camera, method: InverseMethod) -> Option<f64> {
    let k = &camera.intrinsics;
    let mut worst = 0f64;
    for j in 0..36 {
        for i in 0..48 {
            let p = DVec2::new(
                (i as f64 + 0.5) / 48.0 * camera.width as f64 - 0.5,
                (j as f64 + 0.5) / 36.0 * camera.height as f64 - 0.5,
            );
            let y = DVec2::new((p.x - k.cx) / k.fx, (p.y - k.cy) / k.fy);
            if camera
                .undistort_normalized(y, InverseMethod::Newton)
                .is_none()
            {
                continue; // outside the valid domain: no method may answer
            }
            let x = camera.undistort_normalized(y, method)?;
            let back = camera.project(DVec3::new(x.x, x.y, 1.0))?;
            let e = (back - p).length();
            if !e.is_finite() {
                return None;
            }
            worst = worst.max(e);
        }
    }
    Some(worst)
}

/// One way of warping, as the planner weighs it.
#[derive(Debug, Clone, Copy)]
pub(super) struct WarpChoice {
    /// The inverse solved per pixel (or the map's, Newton).
    pub(super) method: InverseMethod,
    /// Whether the coordinates come from a precomputed map.
    pub(super) map: bool,
    /// Its geometric error on the camera (px).
    pub(super) error_px: f64,
    /// Its estimated frame time (ms).
    pub(super) ms: f64,
}

/// The precomputed map's error (px) on `camera`'s warp geometry: the f64 estimate of the
/// interpolation, at least the f32 floor. `None` where a fold is in view (a map there needs a
/// per-pixel check, which the planner does not weigh).
pub(super) fn map_error_px(camera: &Camera, chromatic: Option<[f64; 3]>) -> Option<f64> {
    let (_, mut g) =
        crate::model::warp::WarpGeometry::overscanned(camera, InverseMethod::Newton, 1.0).ok()?;
    if let Some(scales) = chromatic {
        g = g.with_chromatic(scales).ok()?;
    }
    let Coordinates::CoarseMap {
        stride,
        interpolation,
        ..
    } = MAP_COORDINATES
    else {
        return None;
    };
    g.coarse_interpolation_error(stride, interpolation)
        .map(|e| e.max(MAP_F32_FLOOR_PX))
}

/// The tessellation Alg. 1 needs: the mesh as it is, or its edges split to the coarsest
/// length whose straight-edge error meets the budget.
#[derive(Debug, Clone, Copy)]
pub(super) struct TessellationChoice {
    /// Edge length in pixels (`None`: the mesh as it is).
    pub(super) edge_px: Option<f64>,
    /// Largest distance of a straight edge from the true curve (px), measured.
    pub(super) error_px: f64,
    pub(super) triangles: usize,
    pub(super) vertices: usize,
}

/// The coarsest tessellation of `scene` whose straight-line error at `pose` meets `budget`
/// (none beyond 4 million triangles). `moving`: the readout and the pose the frame's last line
/// is read from (`pose` the first's), where the camera moves during the frame; the error is
/// measured through that motion.
pub(super) fn search_tessellation(
    scene: &Scene,
    pose: &Pose,
    camera: &Camera,
    budget: f64,
    moving: Option<(Readout, Pose)>,
) -> Result<Option<TessellationChoice>> {
    let motion = moving.map(|(r, end)| (r, FrameMotion::new((*pose).into(), end.into())));
    const EDGES: [Option<f64>; 8] = [
        None,
        Some(64.0),
        Some(32.0),
        Some(16.0),
        Some(8.0),
        Some(4.0),
        Some(2.0),
        Some(1.0),
    ];
    for l in EDGES {
        let mesh = match l {
            None => scene.mesh.clone(),
            Some(l) => crate::scene::tessellate::tessellate(&scene.mesh, pose, camera, l)?,
        };
        if mesh.triangle_count() > 4_000_000 {
            break;
        }
        let err = match &motion {
            Some((readout, m)) => {
                crate::scene::tessellate::straight_line_error_moving(camera, m, *readout, &mesh)
            }
            None => crate::scene::tessellate::straight_line_error(camera, pose, &mesh),
        };
        if err <= budget {
            return Ok(Some(TessellationChoice {
                edge_px: l,
                error_px: err,
                triangles: mesh.triangle_count(),
                vertices: mesh.vertices.len(),
            }));
        }
    }
    Ok(None)
}

/// The cheapest inverse method whose error, measured on `camera`, meets `budget`, with the
/// frame time `ms` estimates from its per-pixel cost (ns).
pub(super) fn search_inverse(
    camera: &Camera,
    budget: f64,
    ms: impl Fn(f64) -> f64,
) -> Option<WarpChoice> {
    inverse_candidates_for(camera.terms())
        .into_iter()
        .find_map(|(method, ns)| {
            let err = inverse_error_px(camera, method)?;
            (err <= budget).then(|| WarpChoice {
                method,
                map: false,
                error_px: err,
                ms: ms(ns),
            })
        })
}

/// Alg. 1 as a candidate: the tessellation that meets the budget and its estimated frame time.
#[derive(Debug, Clone, Copy)]
pub(super) struct VertexCandidate {
    pub(super) tessellation: TessellationChoice,
    /// Estimated frame time (ms).
    pub(super) ms: f64,
}

/// The cube map as a candidate: its faces' side (pixels, at 1×) and estimated frame time.
#[derive(Debug, Clone, Copy)]
pub(super) struct CubeCandidate {
    pub(super) side: u32,
    /// Estimated frame time (ms).
    pub(super) ms: f64,
}

/// Every route a calibrated camera's scene could take, each measured against the budget:
/// `None` where a route cannot meet it, cannot carry the outputs, or was not searched.
#[derive(Debug, Clone)]
pub(super) struct Candidates {
    /// Alg. 1 (not searched when nothing can go that way: chromatic colour without IDs or
    /// flow, since Alg. 1 cannot give each channel its own lens).
    pub(super) vertex: Option<VertexCandidate>,
    /// The warp solved per pixel: the cheapest inverse meeting the budget.
    pub(super) per_pixel: Option<WarpChoice>,
    /// The warp from a precomputed map (not with jittered anti-aliasing, which moves the
    /// lens every pass).
    pub(super) from_map: Option<WarpChoice>,
    /// The cheaper of the two warps; none where no pinhole source holds the lens.
    pub(super) warp: Option<WarpChoice>,
    /// The cube map, where colour alone is asked for and its rays meet the budget.
    pub(super) cube: Option<CubeCandidate>,
    /// Why no overscanned pinhole source holds the lens, where none does.
    pub(super) no_pinhole_warp: Option<String>,
    /// The frames a map's build is shared over.
    pub(super) frames: usize,
}

impl Candidates {
    /// Routes with a pinhole source for one frame: `vertex`, the warp solved per pixel
    /// (`warp`, no map) and `cube`.
    pub(super) fn with_pinhole(
        vertex: Option<VertexCandidate>,
        warp: Option<WarpChoice>,
        cube: Option<CubeCandidate>,
    ) -> Candidates {
        Candidates {
            vertex,
            per_pixel: warp,
            from_map: None,
            warp,
            cube,
            no_pinhole_warp: None,
            frames: 1,
        }
    }
}

/// Searches every candidate route of `file` for `scene` through `camera` at `poses` (the
/// tessellation is measured at the first).
pub(super) fn search_candidates(
    file: &SceneFile,
    scene: &Scene,
    camera: &Camera,
    poses: &[Pose],
    moving: Option<(Readout, Pose, Pose)>,
) -> Result<Candidates> {
    let budget = file.max_error_px;
    let o = &file.outputs;
    let chromatic = chromatic_scales(file);
    let pixels = camera.width as f64 * camera.height as f64;
    let triangles = scene.mesh.triangle_count() as f64;
    let data_needs_vertex = o.renders_ids() || o.flow;
    // A frame that moves during its readout is measured through its motion.
    let (first, motion) = match moving {
        Some((readout, start, end)) => (Some(start), Some((readout, end))),
        None => (poses.first().copied(), None),
    };
    let vertex = match first {
        Some(pose) if chromatic.is_none() || data_needs_vertex => {
            search_tessellation(scene, &pose, camera, budget, motion)?
        }
        _ => None,
    }
    .map(|tessellation| {
        let vertices = tessellation.vertices as f64;
        // A moving rolling shutter solves each vertex's readout time besides.
        let solve = if motion.is_some() {
            ROLLING_SHUTTER_NS_PER_VERTEX * vertices * 1e-6
        } else {
            0.0
        };
        VertexCandidate {
            tessellation,
            ms: estimate_ms(
                pixels,
                tessellation.triangles as f64,
                Cost::Vertex { vertices },
            ) + solve,
        }
    });
    // Three fetches (and inverses, or maps) per pixel with chromatic aberration.
    let fetches = if chromatic.is_some() { 3.0 } else { 1.0 };
    let per_pixel = search_inverse(camera, budget, |ns| {
        estimate_ms(
            pixels,
            triangles,
            Cost::Warp {
                coordinate_ns: ns * fetches,
            },
        )
    });
    // A map is built once, its build shared by the frames.
    let frames = poses.len().max(1);
    let from_map = if file.antialias.is_on() {
        None
    } else {
        map_error_px(camera, chromatic)
            .filter(|&e| e <= budget)
            .map(|e| {
                let sample = if chromatic.is_some() {
                    MAP_WARP_CHROMATIC_NS
                } else {
                    MAP_WARP_NS
                };
                WarpChoice {
                    method: InverseMethod::Newton,
                    map: true,
                    error_px: e,
                    ms: estimate_ms(
                        pixels,
                        triangles,
                        Cost::Warp {
                            coordinate_ns: sample + MAP_BUILD_NS * fetches / frames as f64,
                        },
                    ),
                }
            })
    };
    // A lens no overscanned pinhole source holds (180° and more, or past the image limit):
    // the planned warp would miss pixels, so it is not a candidate; the vertex path runs the
    // lens's own model per vertex, the cube map samples six pinhole faces along each pixel's
    // ray.
    let no_pinhole_warp =
        limits::pinhole_source_refusal(camera, 1.0, crate::model::MAX_IMAGE_SIDE.min(16384));
    let warp = match (per_pixel, from_map) {
        _ if no_pinhole_warp.is_some() => None,
        (Some(a), Some(b)) => Some(if b.ms < a.ms { b } else { a }),
        (a, b) => a.or(b),
    };
    // The planner weighs the cube map for colour alone; IDs, depth and range go through it
    // (nearest, the depth carried onto each pixel's ray) only where the file asks for the
    // cube path, and flow never. Faces of one face pixel per output pixel at the centre
    // (density 1, as the warp's source).
    let asked_cube = file.path == Some(super::PathKind::Cube);
    let carried = if asked_cube {
        (o.color || o.renders_data()) && !o.flow
    } else {
        o.color && !o.renders_data()
    };
    let cube = (carried && CUBE_RAY_ERROR_PX <= budget).then(|| {
        let texel = if o.exr { 16 } else { 4 };
        let wanted = crate::model::overscan::cube_face_side(camera, 1.0);
        let side = limits::cube_side(wanted, texel, PLANNED_CUBE_MAX_SIDE);
        CubeCandidate {
            side,
            ms: estimate_ms(pixels, triangles, Cost::Cube { side, fetches }),
        }
    });
    Ok(Candidates {
        vertex,
        per_pixel,
        from_map,
        warp,
        cube,
        no_pinhole_warp,
        frames,
    })
}

/// A moving rolling shutter drawn in bands: `count` bands of the readout's lines, the warp's
/// pinhole source (or the cube map's six faces) rendered once per band from the pose of its
/// middle line, each band warped alone.
#[derive(Debug, Clone, Copy)]
pub(super) struct BandsCandidate {
    /// How many bands.
    pub(super) count: u32,
    /// The bands' own geometric error (px), measured against the exact projection.
    pub(super) bands_error_px: f64,
    /// The route that carries each band.
    pub(super) via: BandsVia,
    /// Estimated frame time (ms): the route's, and its sources rendered again per further
    /// band.
    pub(super) ms: f64,
    /// The budget the count was chosen against (px).
    pub(super) budget_px: f64,
}

/// The route that draws each band.
#[derive(Debug, Clone, Copy)]
pub(super) enum BandsVia {
    /// A pinhole source and the warp.
    Warp(WarpChoice),
    /// Six pinhole faces of a cube map and the sphere warp: a lens no pinhole source holds.
    Cube(CubeCandidate),
}

impl BandsVia {
    /// The route's own geometric error (px).
    pub(super) fn error_px(&self) -> f64 {
        match self {
            BandsVia::Warp(w) => w.error_px,
            BandsVia::Cube(_) => CUBE_RAY_ERROR_PX,
        }
    }
}

impl BandsCandidate {
    /// The route's error: the bands' and the warp's, which add along the chain.
    pub(super) fn error_px(&self) -> f64 {
        self.bands_error_px + self.via.error_px()
    }
}

/// The bands weighed for a moving rolling shutter.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct BandsSearch {
    /// The fewest bands of [`BAND_COUNTS`] whose error, with the warp's, meets the budget.
    pub(super) chosen: Option<BandsCandidate>,
    /// The most bands tried and the error they leave (px, the warp's included), where none
    /// meets the budget; `None` where no warp was there to try.
    pub(super) most: Option<(u32, f64)>,
}

/// The fewest bands that draw `motions` (each moving frame's readout and motion) through
/// `camera` by the warp of `candidates` (or, where no pinhole source holds the lens, its cube
/// map) within `budget`: each count's error is the largest over the frames, at the distances
/// of `scene`'s vertices from the camera.
pub(super) fn search_bands(
    scene: &Scene,
    camera: &Camera,
    candidates: &Candidates,
    motions: &[(Readout, FrameMotion)],
    budget: f64,
) -> BandsSearch {
    let triangles = scene.mesh.triangle_count() as f64;
    let (via, source_ms) = match (candidates.warp, candidates.cube) {
        (Some(w), _) => (
            BandsVia::Warp(w),
            source_render_ms(camera.width as f64 * camera.height as f64, triangles),
        ),
        (None, Some(c)) => (
            BandsVia::Cube(c),
            6.0 * face_render_ms(f64::from(c.side) * f64::from(c.side), triangles),
        ),
        (None, None) => return BandsSearch::default(),
    };
    // The distances come from at most this many vertices, evenly through the mesh: a range,
    // not a bound, and a dense mesh's neighbours add nothing to it.
    const MAX_POINTS: usize = 1 << 14;
    let step = scene.mesh.vertices.len().div_ceil(MAX_POINTS).max(1);
    let points: Vec<DVec3> = scene
        .mesh
        .vertices
        .iter()
        .step_by(step)
        .map(|v| v.position())
        .collect();
    let ranges: Vec<Option<(f64, f64)>> = motions
        .iter()
        .map(|(_, m)| distance_range(camera, m, points.iter().copied()))
        .collect();
    let mut most = None;
    for count in BAND_COUNTS {
        // The largest over the frames; a frame past the budget settles the count.
        let mut bands_error_px = 0f64;
        for ((readout, m), range) in motions.iter().zip(&ranges) {
            if let Some(r) = range {
                bands_error_px = bands_error_px.max(band_error_px(camera, m, *readout, count, *r));
            }
            if bands_error_px + via.error_px() > budget
                && count != BAND_COUNTS[BAND_COUNTS.len() - 1]
            {
                break;
            }
        }
        let candidate = BandsCandidate {
            count,
            bands_error_px,
            via,
            ms: match via {
                BandsVia::Warp(w) => w.ms,
                BandsVia::Cube(c) => c.ms,
            } + (count - 1) as f64 * source_ms,
            budget_px: budget,
        };
        if candidate.error_px() <= budget {
            return BandsSearch {
                chosen: Some(candidate),
                most: None,
            };
        }
        most = Some((count, candidate.error_px()));
    }
    BandsSearch { chosen: None, most }
}
