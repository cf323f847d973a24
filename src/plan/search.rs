//! The candidates' search: the coarsest tessellation, the cheapest inverse, the precomputed
//! map, each with its error measured on this camera (and scene and pose) against the budget.

use glam::{DVec2, DVec3};

use super::cost::{inverse_candidates_for, MAP_F32_FLOOR_PX};
use super::MAP_COORDINATES;
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
/// (none beyond 4 million triangles).
pub(super) fn search_tessellation(
    scene: &Scene,
    pose: &Pose,
    camera: &Camera,
    budget: f64,
) -> Result<Option<TessellationChoice>> {
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
        let err = crate::scene::tessellate::straight_line_error(camera, pose, &mesh);
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
