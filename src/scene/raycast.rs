//! Ray casting against a scene mesh on the CPU (f64), for the reference renderers: a
//! bounding-volume hierarchy (median split on the longest axis), Möller–Trumbore triangle
//! tests, and shading exactly as `glsl/geometry.frag` does it (vertex colour interpolated
//! across the triangle × the texture sampled bilinearly with wrap-around), so that a
//! rasterized image and a ray-traced one of the same scene differ only by the optics.

use glam::{DVec2, DVec3};

use super::Mesh;
use crate::imaging::{Pixels, Raster};

/// A ray hit: distance along the (unit) direction, triangle, barycentrics of vertices 1, 2.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    pub t: f64,
    pub triangle: usize,
    pub barycentric: DVec2,
}

struct Node {
    min: DVec3,
    max: DVec3,
    /// Leaf: first triangle in `order` and count (> 0). Inner: left child index, count 0
    /// (the right child follows the left subtree).
    start: usize,
    count: usize,
    right: usize,
}

/// A BVH over a mesh's triangles.
pub struct Bvh {
    triangles: Vec<[DVec3; 3]>,
    order: Vec<usize>,
    nodes: Vec<Node>,
}

const LEAF: usize = 4;

impl Bvh {
    pub fn new(mesh: &Mesh) -> Self {
        let triangles: Vec<[DVec3; 3]> = mesh
            .indices
            .chunks_exact(3)
            .map(|t| [0, 1, 2].map(|k| mesh.vertices[t[k] as usize].position()))
            .collect();
        let mut bvh = Bvh {
            order: (0..triangles.len()).collect(),
            triangles,
            nodes: Vec::new(),
        };
        if !bvh.triangles.is_empty() {
            bvh.build(0, bvh.triangles.len());
        }
        bvh
    }

    fn bounds(&self, start: usize, end: usize) -> (DVec3, DVec3) {
        self.order[start..end].iter().fold(
            (DVec3::INFINITY, DVec3::NEG_INFINITY),
            |(lo, hi), &t| {
                let [a, b, c] = self.triangles[t];
                (lo.min(a).min(b).min(c), hi.max(a).max(b).max(c))
            },
        )
    }

    fn build(&mut self, start: usize, end: usize) -> usize {
        let (min, max) = self.bounds(start, end);
        let index = self.nodes.len();
        self.nodes.push(Node {
            min,
            max,
            start,
            count: end - start,
            right: 0,
        });
        if end - start <= LEAF {
            return index;
        }
        let extent = max - min;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let mid = (start + end) / 2;
        let tris = &self.triangles;
        self.order[start..end].select_nth_unstable_by(mid - start, |&x, &y| {
            let cx = (tris[x][0] + tris[x][1] + tris[x][2])[axis];
            let cy = (tris[y][0] + tris[y][1] + tris[y][2])[axis];
            cx.total_cmp(&cy)
        });
        self.nodes[index].count = 0;
        self.build(start, mid);
        let right = self.build(mid, end);
        self.nodes[index].right = right;
        index
    }

    /// The nearest hit with `t` in `(t_min, t_max)` of the ray `origin + t·direction`.
    pub fn intersect(
        &self,
        origin: DVec3,
        direction: DVec3,
        t_min: f64,
        t_max: f64,
    ) -> Option<Hit> {
        if self.nodes.is_empty() {
            return None;
        }
        let inv = direction.recip();
        let mut best: Option<Hit> = None;
        let mut far = t_max;
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n];
            if !slab(node.min, node.max, origin, inv, t_min, far) {
                continue;
            }
            if node.count > 0 {
                for &t in &self.order[node.start..node.start + node.count] {
                    if let Some((d, b)) = triangle_hit(&self.triangles[t], origin, direction) {
                        if d > t_min && d < far {
                            far = d;
                            best = Some(Hit {
                                t: d,
                                triangle: t,
                                barycentric: b,
                            });
                        }
                    }
                }
            } else {
                stack.push(node.right);
                stack.push(n + 1);
            }
        }
        best
    }
}

fn slab(min: DVec3, max: DVec3, origin: DVec3, inv: DVec3, t_min: f64, t_max: f64) -> bool {
    let t0 = (min - origin) * inv;
    let t1 = (max - origin) * inv;
    let lo = t0.min(t1);
    let hi = t0.max(t1);
    // NaN (0 × ∞ on a flat box face) compares false: max_element/min_element skip it.
    let enter = lo.max_element().max(t_min);
    let exit = hi.min_element().min(t_max);
    enter <= exit
}

/// Möller–Trumbore: distance and barycentrics (of vertices 1 and 2), both faces.
fn triangle_hit(tri: &[DVec3; 3], origin: DVec3, direction: DVec3) -> Option<(f64, DVec2)> {
    let e1 = tri[1] - tri[0];
    let e2 = tri[2] - tri[0];
    let p = direction.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - tri[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = direction.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some((e2.dot(q) * inv, DVec2::new(u, v)))
}

/// The colour `glsl/geometry.frag` writes for a hit: interpolated vertex colour × bilinear,
/// repeating texture sample (white without a texture). RGBA in 0..1.
pub fn shade(mesh: &Mesh, texture: Option<&Raster>, hit: &Hit) -> [f64; 4] {
    let idx = &mesh.indices[3 * hit.triangle..3 * hit.triangle + 3];
    let [v0, v1, v2] = [0, 1, 2].map(|k| &mesh.vertices[idx[k] as usize]);
    let (b1, b2) = (hit.barycentric.x, hit.barycentric.y);
    let b0 = 1.0 - b1 - b2;
    let mix = |a: f64, b: f64, c: f64| b0 * a + b1 * b + b2 * c;
    let uv = DVec2::new(
        mix(v0.uv[0] as f64, v1.uv[0] as f64, v2.uv[0] as f64),
        mix(v0.uv[1] as f64, v1.uv[1] as f64, v2.uv[1] as f64),
    );
    let tex = texture.map(|t| sample_repeat(t, uv)).unwrap_or([1.0; 4]);
    std::array::from_fn(|c| {
        let colour = mix(v0.color[c] as f64, v1.color[c] as f64, v2.color[c] as f64) / 255.0;
        colour * tex[c]
    })
}

/// Bilinear sample with wrap-around at normalized `uv` (texel centres at (i + 0.5)/size), as a
/// `LINEAR`/`REPEAT` Vulkan sampler does.
fn sample_repeat(t: &Raster, uv: DVec2) -> [f64; 4] {
    let (w, h) = (t.width as i64, t.height as i64);
    let x = uv.x * w as f64 - 0.5;
    let y = uv.y * h as f64 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let texel = |i: i64, j: i64| -> [f64; 4] {
        let k = (j.rem_euclid(h) * w + i.rem_euclid(w)) as usize;
        match &t.pixels {
            Pixels::Rgba8(p) => p[k].map(|c| c as f64 / 255.0),
            _ => t.rgba_f32(k).map(|c| c as f64),
        }
    };
    let (i, j) = (x0 as i64, y0 as i64);
    let (a, b, c, d) = (
        texel(i, j),
        texel(i + 1, j),
        texel(i, j + 1),
        texel(i + 1, j + 1),
    );
    std::array::from_fn(|k| {
        (a[k] * (1.0 - fx) + b[k] * fx) * (1.0 - fy) + (c[k] * (1.0 - fx) + d[k] * fx) * fy
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    #[test]
    fn the_bvh_finds_what_brute_force_finds() {
        let scene = builtin::boxes();
        let bvh = Bvh::new(&scene.mesh);
        let origin = DVec3::new(0.1, -1.5, -3.0);
        for k in 0..200 {
            let d = DVec3::new(
                ((k * 37) % 100) as f64 / 100.0 - 0.5,
                ((k * 53) % 100) as f64 / 100.0 - 0.2,
                1.0,
            )
            .normalize();
            let fast = bvh.intersect(origin, d, 0.0, f64::INFINITY);
            let slow = bvh
                .triangles
                .iter()
                .enumerate()
                .filter_map(|(i, t)| triangle_hit(t, origin, d).map(|(t, _)| (t, i)))
                .filter(|(t, _)| *t > 0.0)
                .min_by(|a, b| a.0.total_cmp(&b.0));
            assert_eq!(fast.map(|h| h.t), slow.map(|s| s.0), "ray {k}");
        }
    }

    #[test]
    fn shading_interpolates_colour_and_repeats_the_texture() {
        let scene = builtin::checkerboard(
            builtin::Board {
                columns: 3,
                rows: 2,
                square: 0.1,
            },
            1,
        );
        let bvh = Bvh::new(&scene.mesh);
        // Square (a, b) = (2, 2) of the framed board starts at the origin: a + b even, black;
        // its right neighbour is white.
        let hit = bvh
            .intersect(DVec3::new(0.05, 0.05, -1.0), DVec3::Z, 0.0, 10.0)
            .unwrap();
        assert!((hit.t - 1.0).abs() < 1e-12);
        assert_eq!(shade(&scene.mesh, None, &hit), [0.0, 0.0, 0.0, 1.0]);
        let hit = bvh
            .intersect(DVec3::new(0.15, 0.05, -1.0), DVec3::Z, 0.0, 10.0)
            .unwrap();
        assert_eq!(shade(&scene.mesh, None, &hit), [1.0; 4]);
        // Wrap-around: u = 1.25 samples where u = 0.25 does.
        let tex = builtin::chart_texture(64);
        let a = sample_repeat(&tex, DVec2::new(0.25, 0.5));
        let b = sample_repeat(&tex, DVec2::new(1.25, 0.5));
        assert_eq!(a, b);
    }
}
