//! Tessellation for Alg. 1 (Lambers et al. Sec. 3.2, first limitation): the vertex path moves only
//! vertices, so a straight edge stays straight between them; edges must be short in the image
//! for the curved lens image to be followed. This splits every edge whose pinhole image is
//! longer than `max_edge_px`, repeatedly, until none is.
//!
//! Refinement is by edge (red-green): an edge is split or not by its own length alone, so the
//! two triangles sharing it agree and the mesh stays watertight (no T-junction cracks). A
//! triangle with 1, 2 or 3 split edges becomes 2, 3 or 4 triangles with its winding kept.

use crate::{Error, Result};
use std::collections::HashMap;

use glam::{DVec2, DVec3};

use super::{Mesh, Pose, Vertex, MAX_TRIANGLES};
use crate::model::rolling_shutter::{FrameMotion, Readout};
use crate::model::{Camera, Intrinsics};

/// Depth below which a vertex is not measured (it is at or behind the camera, and the
/// geometry path drops its triangles anyway).
const MIN_DEPTH: f64 = 1e-6;

/// Splits edges longer than `max_edge_px` in the pinhole image of `camera` at `pose`. Edges
/// that lie wholly off the image (by more than the image's own size) are left alone: nothing
/// of them is drawn, and near the camera plane they would otherwise split without end.
pub fn tessellate(mesh: &Mesh, pose: &Pose, camera: &Camera, max_edge_px: f64) -> Result<Mesh> {
    let intrinsics = &camera.intrinsics;
    let (w, h) = (camera.width as f64, camera.height as f64);
    // Whether the edge's bounding box meets the image grown by its own size on every side.
    let near_image = |p: DVec2, q: DVec2| {
        let (lo, hi) = (p.min(q), p.max(q));
        hi.x > -w && lo.x < 2.0 * w && hi.y > -h && lo.y < 2.0 * h
    };
    if !(max_edge_px.is_finite() && max_edge_px >= 0.25) {
        return Err(Error::input(format!(
            "tessellation edge length {max_edge_px} px: expected a number of pixels ≥ 0.25"
        )));
    }
    // A fisheye's vertex limit as the cosine of its angle off the axis (Alg. 1 drops vertices
    // past it); `None` where the domain alone decides.
    let fisheye_limit_cos = camera.fisheye_vertex_limit().map(f64::cos);
    let mut out = mesh.clone();
    // Each round at least halves the longest edge; 40 rounds is far past any real need.
    for _ in 0..40 {
        // Camera-frame positions, and where Alg. 1 puts them.
        let points: Vec<DVec3> = out
            .vertices
            .iter()
            .map(|v| pose.apply(v.position()))
            .collect();
        let pixels: Vec<Option<DVec2>> = points
            .iter()
            .map(|&p| {
                if camera.model().is_ray_model() {
                    // A ray model (a fisheye…) sees behind the image plane: edges are measured in its own
                    // image, where Alg. 1 puts them (and not past the vertex limit, where
                    // Alg. 1 drops them).
                    let kept = fisheye_limit_cos.is_none_or(|c| p.z >= p.length() * c);
                    return camera.project(p).filter(|_| kept);
                }
                (p.z > MIN_DEPTH).then(|| intrinsics.to_pixel(DVec2::new(p.x / p.z, p.y / p.z)))
            })
            .collect();
        // Two vertices behind the image plane (one is enough) more than 90° apart around the
        // axis: every triangle with this edge is dropped by Alg. 1's discard
        // (`alg1_spans_behind` in glsl/include/wraps_behind.glsl), and near the direction
        // straight behind a fisheye, splitting it would never end.
        let dropped = |a: u32, b: u32| {
            let (p, q) = (points[a as usize], points[b as usize]);
            if camera.has_seam() {
                // A panorama drops what crosses its seam instead (and [`refine_rim`] follows
                // the seam).
                return camera.crosses_seam(p, q);
            }
            (p.z <= 0.0 || q.z <= 0.0) && !(p.truncate().dot(q.truncate()) > 0.0)
        };
        let long = |a: u32, b: u32| match (pixels[a as usize], pixels[b as usize]) {
            (Some(p), Some(q)) => near_image(p, q) && p.distance(q) > max_edge_px && !dropped(a, b),
            _ => false,
        };
        let what = format!("tessellating to {max_edge_px} px edges");
        let mut vertices = out.vertices.clone();
        let (indices, changed) = split_edges(&mut vertices, &out.indices, long, None, &what)?;
        if !changed {
            return Ok(out);
        }
        out = Mesh { vertices, indices };
    }
    Ok(out)
}

/// One round of red-green refinement of `triangles` (indices into `vertices`): every edge
/// `split_edge` names is halved (its midpoint appended to `vertices` once), each triangle
/// becoming 2, 3 or 4 with its winding kept. Returns the new triangles, and whether any edge
/// was split. A triangle left whole goes to `finished` where given (its edges are final: the
/// caller's rule depends on their ends alone), else with the rest. `what` says what the
/// refinement is for, in the error a mesh too large for the GPU gets.
fn split_edges(
    vertices: &mut Vec<Vertex>,
    triangles: &[u32],
    split_edge: impl Fn(u32, u32) -> bool,
    mut finished: Option<&mut Vec<u32>>,
    what: &str,
) -> Result<(Vec<u32>, bool)> {
    let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
    let mut indices = Vec::with_capacity(triangles.len());
    let mut mid = |a: u32, b: u32, vertices: &mut Vec<Vertex>| -> u32 {
        let key = (a.min(b), a.max(b));
        *midpoints.entry(key).or_insert_with(|| {
            vertices.push(vertices[key.0 as usize].midpoint(&vertices[key.1 as usize]));
            vertices.len() as u32 - 1
        })
    };
    let mut changed = false;
    for t in triangles.chunks_exact(3) {
        let split = [
            split_edge(t[0], t[1]),
            split_edge(t[1], t[2]),
            split_edge(t[2], t[0]),
        ];
        let count = split.iter().filter(|&&s| s).count();
        // Rotate so that the pattern is canonical: 1 split → edge 0; 2 splits → edges
        // 0 and 1 (edge 2 unsplit).
        let r = match count {
            1 => split.iter().position(|&s| s).unwrap_or(0),
            2 => (split.iter().position(|&s| !s).unwrap_or(2) + 1) % 3,
            _ => 0,
        };
        let v = [t[r], t[(r + 1) % 3], t[(r + 2) % 3]];
        match count {
            0 => match finished.as_deref_mut() {
                Some(f) => f.extend_from_slice(&v),
                None => indices.extend_from_slice(&v),
            },
            1 => {
                let m = mid(v[0], v[1], vertices);
                indices.extend_from_slice(&[v[0], m, v[2], m, v[1], v[2]]);
            }
            2 => {
                let m01 = mid(v[0], v[1], vertices);
                let m12 = mid(v[1], v[2], vertices);
                indices.extend_from_slice(&[m01, v[1], m12, v[0], m01, m12, v[0], m12, v[2]]);
            }
            _ => {
                let m01 = mid(v[0], v[1], vertices);
                let m12 = mid(v[1], v[2], vertices);
                let m20 = mid(v[2], v[0], vertices);
                indices.extend_from_slice(&[
                    v[0], m01, m20, m01, v[1], m12, m20, m12, v[2], m01, m12, m20,
                ]);
            }
        }
        changed |= count > 0;
        let total = indices.len() + finished.as_deref().map_or(0, |f| f.len());
        if total / 3 > MAX_TRIANGLES {
            return Err(Error::input(format!(
                "{what} needs more than {MAX_TRIANGLES} triangles: choose a longer edge or a larger error budget"
            )));
        }
    }
    Ok((indices, changed))
}

/// Follows the edge of what the vertex path keeps (`kept`, on camera-frame points: the lens's
/// domain, the discard's bound) to `max_error_px`: Alg. 1 drops a triangle with one vertex it
/// does not keep whole, so an object crossing that edge would lose a strip of itself up to a
/// triangle wide. Each edge with one end kept is halved until the part of it that is kept
/// (from the kept end to where the edge leaves, found by bisection) is at most `max_error_px`
/// long in the image, or lies outside the image; an edge with neither end kept is
/// halved while its midpoint is kept (a large triangle over the view). Through a panorama's
/// seam ([`Camera::crosses_seam`]), where Alg. 1 drops the triangle too, an edge is halved while
/// it spans more than `max_error_px` at the camera. Red-green, like
/// [`tessellate`]: the mesh stays watertight.
///
/// With `max_edge_px`, an edge with both ends kept is halved too while its image through the
/// lens is longer than that and meets the image: the triangles the rim's splits make keep the
/// tessellation's bound (splitting one rim edge makes new edges a tessellation before it never
/// saw).
pub fn refine_rim(
    mesh: &Mesh,
    pose: &Pose,
    camera: &Camera,
    kept: impl Fn(DVec3) -> bool,
    max_error_px: f64,
    max_edge_px: Option<f64>,
) -> Result<Mesh> {
    if !(max_error_px.is_finite() && max_error_px > 0.0) {
        return Err(Error::input(format!(
            "rim error {max_error_px} px: expected a number of pixels > 0"
        )));
    }
    let (w, h) = (camera.width as f64, camera.height as f64);
    // Whether the box of two image points meets the image: what is lost outside it is not
    // drawn anyway (a standard lens's discard bound lies past the image's border).
    let in_image = |p: DVec2, q: DVec2| {
        let (lo, hi) = (p.min(q), p.max(q));
        hi.x >= -0.5 && lo.x <= w - 0.5 && hi.y >= -0.5 && lo.y <= h - 0.5
    };
    let mut vertices = mesh.vertices.clone();
    // Triangles whose edges are all final (the rule reads only their ends), and the rest.
    let mut finished = Vec::with_capacity(mesh.indices.len());
    let mut active = mesh.indices.clone();
    // Per vertex, extended as the rounds add vertices: camera-frame point, kept, pixel.
    let (mut points, mut keeps, mut pixels) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..40 {
        for v in &vertices[points.len()..] {
            let p = pose.apply(v.position());
            points.push(p);
            keeps.push(kept(p));
            pixels.push(camera.project(p));
        }
        let split = |a: u32, b: u32| {
            let (pa, pb) = (points[a as usize], points[b as usize]);
            if camera.crosses_seam(pa, pb) {
                // A triangle through a panorama's seam is dropped: halve the edge while it
                // spans more than the budget (its angle at the camera, in pixels).
                let f = camera.intrinsics.fx.abs().max(camera.intrinsics.fy.abs());
                return keeps[a as usize]
                    && keeps[b as usize]
                    && pa.angle_between(pb) * f > max_error_px;
            }
            match (keeps[a as usize], keeps[b as usize]) {
                (true, true) => {
                    max_edge_px.is_some_and(|l| match (pixels[a as usize], pixels[b as usize]) {
                        (Some(p), Some(q)) => in_image(p, q) && p.distance(q) > l,
                        _ => false,
                    })
                }
                (false, false) => {
                    let m = 0.5 * (pa + pb);
                    kept(m) && camera.project(m).is_some_and(|p| in_image(p, p))
                }
                (ka, _) => {
                    let (inside, outside, from) = if ka {
                        (pa, pb, pixels[a as usize])
                    } else {
                        (pb, pa, pixels[b as usize])
                    };
                    // The last kept point towards `outside`, to 2^-30 of the edge.
                    let (mut lo, mut hi) = (0.0f64, 1.0f64);
                    for _ in 0..30 {
                        let m = 0.5 * (lo + hi);
                        if kept(inside + (outside - inside) * m) {
                            lo = m;
                        } else {
                            hi = m;
                        }
                    }
                    let edge = inside + (outside - inside) * lo;
                    match (from, camera.project(edge)) {
                        (Some(p), Some(q)) => in_image(p, q) && p.distance(q) > max_error_px,
                        _ => false,
                    }
                }
            }
        };
        let what = format!("following the lens's rim to {max_error_px} px");
        let (next, changed) =
            split_edges(&mut vertices, &active, split, Some(&mut finished), &what)?;
        active = next;
        if !changed {
            break;
        }
    }
    finished.extend_from_slice(&active);
    Ok(Mesh {
        vertices,
        indices: finished,
    })
}

/// The longest pinhole-image edge of the triangles in front of the camera (pixels).
pub fn longest_edge_px(mesh: &Mesh, pose: &Pose, intrinsics: &Intrinsics) -> f64 {
    let px = |i: u32| {
        let p = pose.apply(mesh.vertices[i as usize].position());
        (p.z > MIN_DEPTH).then(|| intrinsics.to_pixel(DVec2::new(p.x / p.z, p.y / p.z)))
    };
    mesh.indices
        .chunks_exact(3)
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .filter_map(|(a, b)| Some(px(a)?.distance(px(b)?)))
        .fold(0.0, f64::max)
}

/// The largest distance (px) between an edge's true image through the lens and the straight
/// segment the rasterizer draws between its moved end points, over the edges whose image is
/// inside the frame (sampled at t = 1/4, 1/2, 3/4).
pub fn straight_line_error(camera: &Camera, pose: &Pose, mesh: &Mesh) -> f64 {
    edge_error(camera, mesh, |x| camera.project(pose.apply(x)))
}

/// [`straight_line_error`] for a camera that moves during a rolling shutter's readout: every
/// point of an edge (its ends and the samples between) is projected where its own line reads
/// it ([`FrameMotion::project`]), which is what the vertex path draws at the ends. The lines
/// read at different times see the edge from different poses, so its image bends more than
/// the lens alone bends it (a straight edge across the readout leans and curves on a pan), and
/// the tessellation must follow that too.
pub fn straight_line_error_moving(
    camera: &Camera,
    motion: &FrameMotion,
    readout: Readout,
    mesh: &Mesh,
) -> f64 {
    edge_error(camera, mesh, |x| {
        motion.project(camera, readout, x).map(|p| p.pixel)
    })
}

/// The largest distance (px) between an edge's image by `project` and the straight segment
/// between its ends' images, over the edges whose image is inside the frame.
fn edge_error(camera: &Camera, mesh: &Mesh, project: impl Fn(DVec3) -> Option<DVec2>) -> f64 {
    let project_vertex = |i: u32| project(mesh.vertices[i as usize].position());
    let inside = |p: DVec2| {
        p.x >= -0.5
            && p.y >= -0.5
            && p.x <= camera.width as f64 - 0.5
            && p.y <= camera.height as f64 - 0.5
    };
    let mut seen = std::collections::HashSet::new();
    let mut worst = 0f64;
    for t in mesh.indices.chunks_exact(3) {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            if !seen.insert((a.min(b), a.max(b))) {
                continue;
            }
            let (Some(pa), Some(pb)) = (project_vertex(a), project_vertex(b)) else {
                continue;
            };
            if !inside(pa) || !inside(pb) {
                continue;
            }
            let (wa, wb) = (
                mesh.vertices[a as usize].position(),
                mesh.vertices[b as usize].position(),
            );
            for s in [0.25, 0.5, 0.75] {
                if let Some(p) = project(wa + (wb - wa) * s) {
                    let d = pb - pa;
                    let u = ((p - pa).dot(d) / d.length_squared().max(1e-300)).clamp(0.0, 1.0);
                    worst = worst.max((pa + d * u).distance(p));
                }
            }
        }
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;
    use glam::DVec3;

    #[test]
    fn a_pan_during_the_readout_bends_edges_and_finer_edges_follow_it() {
        // A grid of four big quads through a pinhole (no lens: every edge's image is straight
        // for a still camera), panned 9° during a top-to-bottom readout.
        let camera = Camera::from_coeffs(
            800,
            600,
            Intrinsics {
                fx: 400.0,
                fy: 400.0,
                cx: 399.5,
                cy: 299.5,
            },
            &[0.0; 4],
        )
        .unwrap();
        let mesh = builtin::grid(2).mesh;
        let start = Pose::look_at(
            DVec3::new(-0.1, 0.0, -1.5),
            DVec3::new(-0.2, 0.0, 0.0),
            DVec3::Y,
        );
        let end = Pose::look_at(
            DVec3::new(0.1, 0.0, -1.5),
            DVec3::new(0.2, 0.0, 0.0),
            DVec3::Y,
        );
        let motion = FrameMotion::new(start.into(), end.into());
        let still = straight_line_error(&camera, &start, &mesh);
        let moving = straight_line_error_moving(&camera, &motion, Readout::TopToBottom, &mesh);
        assert!(
            still < 1e-6,
            "a pinhole keeps still edges straight ({still} px)"
        );
        // Measured: 0.57 px.
        assert!(moving > 0.3, "the pan bends them ({moving} px)");
        // A still camera through the moving measure is the still one.
        let none = FrameMotion::still(start.into());
        let same = straight_line_error_moving(&camera, &none, Readout::TopToBottom, &mesh);
        assert!((same - still).abs() < 1e-9);
        // Shorter edges follow the bent image: the error falls about as the edge length squared.
        let fine = tessellate(&mesh, &start, &camera, 16.0).unwrap();
        let fine_error = straight_line_error_moving(&camera, &motion, Readout::TopToBottom, &fine);
        assert!(
            fine_error < moving / 20.0,
            "{fine_error} px after splitting, {moving} before"
        );
    }

    #[test]
    fn splits_until_short_and_stays_watertight() {
        let scene = builtin::grid(2);
        let pose = Pose::look_at(DVec3::new(0.0, 0.0, -2.0), DVec3::ZERO, DVec3::Y);
        let k = Intrinsics {
            fx: 400.0,
            fy: 400.0,
            cx: 399.5,
            cy: 299.5,
        };
        let camera = Camera::from_coeffs(800, 600, k, &[0.0; 4]).unwrap();
        let before = longest_edge_px(&scene.mesh, &pose, &k);
        let fine = tessellate(&scene.mesh, &pose, &camera, 10.0).unwrap();
        assert!(before > 100.0);
        assert!(longest_edge_px(&fine, &pose, &k) <= 10.0);
        fine.validate("tessellated").unwrap();
        // Watertight: an edge without its reverse is on the boundary, and the boundary is
        // as long as before (a T-junction crack would add its long edge and both halves).
        let boundary = |m: &Mesh| -> f64 {
            let mut directed = HashMap::new();
            for t in m.indices.chunks_exact(3) {
                for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                    *directed.entry((a, b)).or_insert(0) += 1;
                }
            }
            assert!(
                directed.values().all(|&n| n == 1),
                "a repeated directed edge"
            );
            directed
                .keys()
                .filter(|(a, b)| !directed.contains_key(&(*b, *a)))
                .map(|&(a, b)| {
                    let p = |i: u32| m.vertices[i as usize].position();
                    p(a).distance(p(b))
                })
                .sum()
        };
        assert!((boundary(&fine) - boundary(&scene.mesh)).abs() < 1e-6);
        // ... the area is unchanged (each patch is split, not stretched).
        let area = |m: &Mesh| -> f64 {
            m.indices
                .chunks_exact(3)
                .map(|t| {
                    let p = |i: u32| m.vertices[i as usize].position();
                    0.5 * (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length()
                })
                .sum()
        };
        assert!((area(&fine) - area(&scene.mesh)).abs() < 1e-6);
        assert!(tessellate(&scene.mesh, &pose, &camera, f64::NAN).is_err());
    }
}
