//! Built-in scenes: the OpenCV checkerboard, a textured quad grid, and boxes on a floor.
//!
//! All are built in a y-down world (like OpenCV's board coordinates) and seen from −z by
//! default. Every face is its own patch of vertices, so colours and IDs change exactly at
//! the geometric edges — which Alg. 1 bends with the lens, the point of the geometry path.

use crate::{Error, Result};
use glam::DVec3;

use super::{Mesh, Scene, SceneError, Vertex};
use crate::imaging::{BitDepth, Pixels, Raster};

/// A calibration board: inner corners and square size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Board {
    /// Inner corners per row (OpenCV's `patternSize.width`).
    pub columns: u32,
    /// Inner corners per column (`patternSize.height`).
    pub rows: u32,
    /// Square side in metres.
    pub square: f64,
}

impl Board {
    /// Inner corner (i, j) in board coordinates (z = 0), OpenCV's object-point layout.
    pub fn corner(&self, i: u32, j: u32) -> DVec3 {
        DVec3::new(i as f64 * self.square, j as f64 * self.square, 0.0)
    }
}

/// Appends a `n × n`-subdivided parallelogram `origin + s·u + t·v` (s, t ∈ [0, 1]) with one
/// colour and ID; uv runs over `uv0 + s·uv_u + t·uv_v`.
#[allow(clippy::too_many_arguments)]
fn patch(
    mesh: &mut Mesh,
    origin: DVec3,
    u: DVec3,
    v: DVec3,
    n: u32,
    color: [u8; 4],
    id: u32,
    uv: ([f32; 2], [f32; 2], [f32; 2]),
) {
    let base = mesh.vertices.len() as u32;
    let n = n.max(1);
    for b in 0..=n {
        for a in 0..=n {
            let (s, t) = (a as f64 / n as f64, b as f64 / n as f64);
            let tex = [
                uv.0[0] + s as f32 * uv.1[0] + t as f32 * uv.2[0],
                uv.0[1] + s as f32 * uv.1[1] + t as f32 * uv.2[1],
            ];
            mesh.vertices
                .push(Vertex::new(origin + s * u + t * v, tex, color, id));
        }
    }
    let row = n + 1;
    for b in 0..n {
        for a in 0..n {
            let i = base + b * row + a;
            mesh.indices
                .extend_from_slice(&[i, i + 1, i + row, i + 1, i + row + 1, i + row]);
        }
    }
}

const BLACK: [u8; 4] = [0, 0, 0, 255];
const WHITE: [u8; 4] = [255, 255, 255, 255];

/// The OpenCV checkerboard: `(columns + 1) × (rows + 1)` squares around the inner corners,
/// the top-left square black, framed by one square of white (findChessboardCorners needs a
/// quiet border). Each square is `subdivisions²` quads; each square has its own ID
/// (1 + its index, row-major over the framed board).
pub fn checkerboard(board: Board, subdivisions: u32) -> Scene {
    let mut mesh = Mesh::default();
    let s = board.square;
    let (nx, ny) = (board.columns + 3, board.rows + 3);
    for b in 0..ny {
        for a in 0..nx {
            let frame = a == 0 || b == 0 || a == nx - 1 || b == ny - 1;
            let color = if frame || (a + b) % 2 == 1 {
                WHITE
            } else {
                BLACK
            };
            let origin = DVec3::new((a as f64 - 2.0) * s, (b as f64 - 2.0) * s, 0.0);
            patch(
                &mut mesh,
                origin,
                DVec3::X * s,
                DVec3::Y * s,
                subdivisions,
                color,
                1 + b * nx + a,
                ([0.0, 0.0], [0.0, 0.0], [0.0, 0.0]),
            );
        }
    }
    Scene {
        name: format!("checkerboard {}x{}", board.columns, board.rows),
        mesh,
        texture: None,
        view_from: -DVec3::Z,
        view_down: DVec3::Y,
        board: Some(board),
        environment: None,
        objects: (0..ny)
            .flat_map(|b| (0..nx).map(move |a| format!("square_{a}_{b}")))
            .collect(),
    }
}

/// A test chart texture: coloured checks with a fine grid, so that sampling and warping
/// errors are visible.
pub fn chart_texture(size: u32) -> Raster {
    let mut pixels = Vec::with_capacity((size * size) as usize);
    for y in 0..size {
        for x in 0..size {
            let (cx, cy) = (x * 8 / size, y * 8 / size);
            let fine = x % (size / 32).max(1) == 0 || y % (size / 32).max(1) == 0;
            let base = if (cx + cy) % 2 == 0 {
                [230, 90 + (cx * 20) as u8, 60 + (cy * 20) as u8, 255]
            } else {
                [40 + (cy * 20) as u8, 120, 200 - (cx * 15) as u8, 255]
            };
            pixels.push(if fine { [250, 250, 250, 255] } else { base });
        }
    }
    Raster {
        width: size,
        height: size,
        pixels: Pixels::Rgba8(pixels),
        bit_depth: BitDepth::U8,
    }
}

/// A `n × n` grid of quads, 1.6 m × 1.2 m, textured with the chart; quad k has ID k + 1.
pub fn grid(n: u32) -> Scene {
    let mut mesh = Mesh::default();
    let (w, h) = (1.6, 1.2);
    let (du, dv) = (DVec3::X * (w / n as f64), DVec3::Y * (h / n as f64));
    for b in 0..n {
        for a in 0..n {
            let origin = DVec3::new(-w / 2.0, -h / 2.0, 0.0) + a as f64 * du + b as f64 * dv;
            let step = 1.0 / n as f32;
            patch(
                &mut mesh,
                origin,
                du,
                dv,
                1,
                WHITE,
                1 + b * n + a,
                ([a as f32 * step, b as f32 * step], [step, 0.0], [0.0, step]),
            );
        }
    }
    Scene {
        name: format!("grid {n}x{n}"),
        mesh,
        texture: Some(chart_texture(512)),
        view_from: -DVec3::Z,
        view_down: DVec3::Y,
        board: None,
        environment: None,
        objects: (0..n)
            .flat_map(|b| (0..n).map(move |a| format!("quad_{a}_{b}")))
            .collect(),
    }
}

/// A 4 m room around the origin, seen from inside: six walls of 32 × 32 quads, each tinted
/// (IDs 1..6: +x, −x, +y floor, −y ceiling, +z, −z) under the repeated chart texture. What a
/// fisheye of 180° and more sees from the centre (its default pose: the identity, at the
/// centre, looking along +z).
pub fn room() -> Scene {
    let mut mesh = Mesh::default();
    let h = 2.0;
    let walls: [(DVec3, DVec3, DVec3, [u8; 4]); 6] = [
        (DVec3::X, DVec3::Z, DVec3::Y, [255, 140, 140, 255]),
        (DVec3::NEG_X, DVec3::Z, DVec3::Y, [140, 255, 140, 255]),
        (DVec3::Y, DVec3::X, DVec3::Z, [140, 140, 255, 255]),
        (DVec3::NEG_Y, DVec3::X, DVec3::Z, [255, 255, 140, 255]),
        (DVec3::Z, DVec3::X, DVec3::Y, [255, 140, 255, 255]),
        (DVec3::NEG_Z, DVec3::X, DVec3::Y, [140, 255, 255, 255]),
    ];
    for (id, (normal, u, v, tint)) in walls.into_iter().enumerate() {
        let origin = normal * h - u * h - v * h;
        patch(
            &mut mesh,
            origin,
            u * (2.0 * h),
            v * (2.0 * h),
            32,
            tint,
            id as u32 + 1,
            ([0.0, 0.0], [4.0, 0.0], [0.0, 4.0]),
        );
    }
    Scene {
        name: "room".into(),
        mesh,
        texture: Some(chart_texture(512)),
        view_from: DVec3::ZERO,
        view_down: DVec3::Y,
        board: None,
        environment: None,
        objects: [
            "wall_right",
            "wall_left",
            "floor",
            "ceiling",
            "wall_front",
            "wall_back",
        ]
        .map(String::from)
        .to_vec(),
    }
}

/// Three boxes on a textured floor, each face subdivided 8 × 8; the floor is ID 1, the
/// boxes 2, 3, 4.
pub fn boxes() -> Scene {
    let mut mesh = Mesh::default();
    // The floor: y = 0.5 (y points down), 4 m × 4 m, 32 × 32 quads, texture repeated 4×.
    patch(
        &mut mesh,
        DVec3::new(-2.0, 0.5, -1.0),
        DVec3::X * 4.0,
        DVec3::Z * 4.0,
        32,
        WHITE,
        1,
        ([0.0, 0.0], [4.0, 0.0], [0.0, 4.0]),
    );
    let specs = [
        (DVec3::new(-0.9, 0.5, 0.4), 0.6, [220, 60, 50, 255]),
        (DVec3::new(0.0, 0.5, 1.2), 0.9, [60, 170, 80, 255]),
        (DVec3::new(0.9, 0.5, 0.2), 0.45, [60, 90, 220, 255]),
    ];
    for (k, (base, size, color)) in specs.into_iter().enumerate() {
        let id = 2 + k as u32;
        let h = size;
        let o = base + DVec3::new(-size / 2.0, -h, -size / 2.0);
        let (x, y, z) = (DVec3::X * size, DVec3::Y * h, DVec3::Z * size);
        let shade = |f: f64| color.map(|c| ((c as f64) * f) as u8);
        let mut face = |origin, u, v, f: f64| {
            let mut c = shade(f);
            c[3] = 255;
            patch(
                &mut mesh,
                origin,
                u,
                v,
                8,
                c,
                id,
                ([0.0; 2], [0.0; 2], [0.0; 2]),
            )
        };
        face(o, x, y, 1.0); // front (−z)
        face(o + z, x, y, 0.7); // back
        face(o, z, y, 0.8); // left
        face(o + x, z, y, 0.85); // right
        face(o, x, z, 0.95); // top (y = base − h)
    }
    Scene {
        name: "boxes".into(),
        mesh,
        texture: Some(chart_texture(256)),
        view_from: DVec3::new(0.0, -0.6, -1.0),
        view_down: DVec3::Y,
        board: None,
        environment: None,
        objects: ["floor", "box_red", "box_green", "box_blue"]
            .map(String::from)
            .to_vec(),
    }
}

/// Parses a scene argument: `checkerboard[:COLSxROWS[:SQUARE_M]]`, `grid[:N]`, `boxes`, or
/// a path to an `.obj`, `.gltf` or `.glb` file.
pub fn parse(spec: &str) -> Result<Scene, SceneError> {
    let err = |problem: String| SceneError {
        source: format!("scene {spec:?}"),
        problem,
    };
    let mut parts = spec.split(':');
    let head = parts.next().unwrap_or("");
    let rest: Vec<&str> = parts.collect();
    match head {
        "checkerboard" => {
            let (columns, rows) = match rest.first() {
                None => (9, 6),
                Some(s) => parse_board_size(s).map_err(|e| err(e.to_string()))?,
            };
            let square = match rest.get(1) {
                None => 0.04,
                Some(s) => s
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite() && *v > 0.0 && *v < 1e3)
                    .ok_or_else(|| {
                        err(format!(
                            "square size {s:?} is not a positive number of metres"
                        ))
                    })?,
            };
            if rest.len() > 2 {
                return Err(err("expected checkerboard[:COLSxROWS[:SQUARE_M]]".into()));
            }
            Ok(checkerboard(
                Board {
                    columns,
                    rows,
                    square,
                },
                4,
            ))
        }
        "grid" => {
            let n = match rest.first() {
                None => 16,
                Some(s) => s
                    .parse::<u32>()
                    .ok()
                    .filter(|n| (1..=2048).contains(n))
                    .ok_or_else(|| err(format!("grid size {s:?} is not a number in 1..=2048")))?,
            };
            Ok(grid(n))
        }
        "boxes" if rest.is_empty() => Ok(boxes()),
        "room" if rest.is_empty() => Ok(room()),
        _ => super::load::load_file(std::path::Path::new(spec)),
    }
}

/// Parses `9x6` (inner corners per row × per column).
pub fn parse_board_size(s: &str) -> Result<(u32, u32)> {
    let (a, b) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| Error::input(format!("board size {s:?}: expected COLSxROWS, e.g. 9x6")))?;
    let parse = |t: &str| {
        t.trim()
            .parse::<u32>()
            .ok()
            .filter(|n| (2..=200).contains(n))
    };
    match (parse(a), parse(b)) {
        (Some(c), Some(r)) => Ok((c, r)),
        _ => Err(Error::input(format!(
            "board size {s:?}: inner corners must be whole numbers in 2..=200, e.g. 9x6"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtins_are_valid_meshes() {
        for spec in ["checkerboard", "checkerboard:7x5:0.03", "grid:8", "boxes"] {
            let scene = parse(spec).expect(spec);
            scene.mesh.validate(spec).expect(spec);
        }
        let board = parse("checkerboard:9x6").unwrap();
        // 12 × 9 framed squares, 4 × 4 quads each, 2 triangles per quad.
        assert_eq!(board.mesh.triangle_count(), 12 * 9 * 32);
        assert!(parse("checkerboard:9").is_err());
        assert!(parse("grid:0").is_err());
    }
}
