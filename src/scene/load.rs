//! Meshes from files: Wavefront OBJ (`tobj`) and glTF 2.0 (`gltf`, `.gltf` with its buffers
//! or `.glb`). Positions, texture coordinates, material base colours; each OBJ model or glTF
//! mesh gets its own object ID (1, 2, ...). Files are taken as y-up (both formats' convention)
//! and seen from +z by default. Textures are not loaded: colour comes from the materials.

use crate::{Error, Result};
use std::path::Path;

use glam::{DMat4, DVec3};

use super::{Mesh, Scene, SceneError, Vertex};

fn to_rgba8(c: [f32; 4]) -> [u8; 4] {
    c.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
}

/// Loads an `.obj`, `.gltf` or `.glb` file and validates it.
pub fn load_file(path: &Path) -> Result<Scene, SceneError> {
    let shown = path.display().to_string();
    let err = |problem: String| SceneError {
        source: shown.clone(),
        problem,
    };
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    if !path.exists() {
        return Err(err(
            "no such file (a scene is checkerboard[:COLSxROWS[:SQUARE_M]], grid[:N], boxes, room, or an .obj/.gltf/.glb file)".into(),
        ));
    }
    let (mesh, objects) = match ext.as_deref() {
        Some("obj") => load_obj(path).map_err(|e| err(e.to_string()))?,
        Some("gltf") | Some("glb") => load_gltf(path).map_err(|e| err(e.to_string()))?,
        _ => {
            return Err(err(
                "unsupported scene file (vklens reads .obj, .gltf and .glb)".into(),
            ))
        }
    };
    mesh.validate(&shown)?;
    Ok(Scene {
        name: shown,
        mesh,
        texture: None,
        view_from: DVec3::Z,
        view_down: -DVec3::Y,
        board: None,
        environment: None,
        objects,
    })
}

/// The mesh, and its objects' names by ID (each `o`/`g` group is one object).
fn load_obj(path: &Path) -> Result<(Mesh, Vec<String>)> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, materials) = tobj::load_obj(path, &options)
        .map_err(|e| Error::input(format!("cannot read the OBJ: {e}")))?;
    // A missing .mtl is not fatal: the mesh renders in white.
    let materials = materials.unwrap_or_default();
    let mut mesh = Mesh::default();
    for (k, model) in models.iter().enumerate() {
        let m = &model.mesh;
        let color = m
            .material_id
            .and_then(|i| materials.get(i))
            .and_then(|mat| mat.diffuse)
            .map(|d| to_rgba8([d[0], d[1], d[2], 1.0]))
            .unwrap_or([255; 4]);
        let mut part = Mesh::default();
        for (i, p) in m.positions.chunks_exact(3).enumerate() {
            let uv = m
                .texcoords
                .get(2 * i..2 * i + 2)
                .map(|t| [t[0], 1.0 - t[1]])
                .unwrap_or([0.0; 2]);
            part.vertices.push(Vertex {
                position: [p[0], p[1], p[2]],
                uv,
                color,
                object_id: k as u32 + 1,
                _pad: 0,
            });
        }
        part.indices = m.indices.clone();
        // Check per model, so that a bad index names its model.
        if let Some(&bad) = part
            .indices
            .iter()
            .find(|&&i| i as usize >= part.vertices.len())
        {
            return Err(Error::input(format!(
                "model {:?}: index {bad} past its {} vertices",
                model.name,
                part.vertices.len()
            )));
        }
        mesh.append(&part);
    }
    let names = models.iter().map(|m| m.name.clone()).collect();
    Ok((mesh, names))
}

/// Reads a glTF file. The glTF crate indexes accessors it has not validated and panics on a
/// malformed file; that panic is caught here and reported as the file's error.
fn load_gltf(path: &Path) -> Result<(Mesh, Vec<String>)> {
    crate::error::catch_quietly(|| read_gltf(path)).unwrap_or_else(|_| {
        Err(Error::input(
            "malformed glTF: an index points past its array (the glTF reader gave up)",
        ))
    })
}

/// The mesh, and its objects' names by ID (each node with a mesh is one object, named by the
/// node, else by its mesh, else `node_<index>`).
fn read_gltf(path: &Path) -> Result<(Mesh, Vec<String>)> {
    let gltf =
        gltf::Gltf::open(path).map_err(|e| Error::input(format!("cannot read the glTF: {e}")))?;
    let buffers = gltf::import_buffers(&gltf.document, path.parent(), gltf.blob.clone())
        .map_err(|e| Error::input(format!("cannot read the glTF's buffers: {e}")))?;
    let scene = gltf
        .document
        .default_scene()
        .or_else(|| gltf.document.scenes().next())
        .ok_or_else(|| Error::input("the glTF has no scene"))?;
    let mut mesh = Mesh::default();
    let mut names = Vec::new();
    let mut next_id = 1u32;
    // Depth-first over the node tree, composing transforms.
    let mut stack: Vec<(gltf::Node, DMat4)> = scene.nodes().map(|n| (n, DMat4::IDENTITY)).collect();
    let mut visited = 0usize;
    while let Some((node, parent)) = stack.pop() {
        visited += 1;
        if visited > 1_000_000 {
            return Err(Error::input("the glTF node tree does not end (a cycle?)"));
        }
        let local =
            DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(|v| v as f64)));
        let world = parent * local;
        if let Some(m) = node.mesh() {
            for primitive in m.primitives() {
                if primitive.mode() != gltf::mesh::Mode::Triangles {
                    continue;
                }
                let reader = primitive.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
                let positions: Vec<[f32; 3]> = reader
                    .read_positions()
                    .ok_or_else(|| {
                        Error::input(format!("mesh {:?}: a primitive has no positions", m.name()))
                    })?
                    .collect();
                let uvs: Vec<[f32; 2]> = reader
                    .read_tex_coords(0)
                    .map(|t| t.into_f32().collect())
                    .unwrap_or_default();
                let indices: Vec<u32> = match reader.read_indices() {
                    Some(i) => i.into_u32().collect(),
                    None => (0..positions.len() as u32).collect(),
                };
                let color = to_rgba8(
                    primitive
                        .material()
                        .pbr_metallic_roughness()
                        .base_color_factor(),
                );
                let mut part = Mesh::default();
                for (i, p) in positions.iter().enumerate() {
                    let q =
                        world.transform_point3(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64));
                    part.vertices.push(Vertex::new(
                        q,
                        uvs.get(i).copied().unwrap_or([0.0; 2]),
                        color,
                        next_id,
                    ));
                }
                if let Some(&bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
                    return Err(Error::input(format!(
                        "mesh {:?}: index {bad} past its {} vertices",
                        m.name().unwrap_or("unnamed"),
                        positions.len()
                    )));
                }
                part.indices = indices;
                mesh.append(&part);
            }
            next_id += 1;
            names.push(
                node.name()
                    .or(m.name())
                    .map(String::from)
                    .unwrap_or_else(|| format!("node_{}", node.index())),
            );
        }
        for child in node.children() {
            stack.push((child, world));
        }
    }
    Ok((mesh, names))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(name: &str, text: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("vklens-load-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn obj_loads_and_bad_objs_name_the_problem() {
        let ok = write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        let scene = load_file(&ok).unwrap();
        assert_eq!(scene.mesh.triangle_count(), 1);

        let nan = write("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n");
        let e = load_file(&nan).unwrap_err().to_string();
        assert!(e.contains("nan.obj") && e.contains("vertex 1"), "{e}");

        let empty = write("empty.obj", "# nothing\n");
        let e = load_file(&empty).unwrap_err().to_string();
        assert!(e.contains("no triangles"), "{e}");

        let huge = write("huge.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n");
        let e = load_file(&huge).unwrap_err().to_string();
        assert!(e.contains("huge.obj"), "{e}");

        let missing = load_file(Path::new("/nonexistent/x.obj"))
            .unwrap_err()
            .to_string();
        assert!(missing.contains("no such file"), "{missing}");
    }

    #[test]
    fn gltf_loads_with_node_transforms() {
        // One triangle in an embedded base64 buffer, under a node translated by +2 in x.
        let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let bytes: &[u8] = bytemuck::cast_slice(&positions);
        let b64 = base64_encode(bytes);
        let json = format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
            "nodes":[{{"mesh":0,"translation":[2,0,0]}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],
            "bufferViews":[{{"buffer":0,"byteLength":36}}],
            "buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{b64}"}}]}}"#
        );
        let p = write("tri.gltf", &json);
        let scene = load_file(&p).unwrap();
        assert_eq!(scene.mesh.triangle_count(), 1);
        assert_eq!(scene.mesh.vertices[1].position, [3.0, 0.0, 0.0]);
    }

    fn base64_encode(data: &[u8]) -> String {
        const T: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut out = String::new();
        for chunk in data.chunks(3) {
            let b = [
                chunk[0],
                *chunk.get(1).unwrap_or(&0),
                *chunk.get(2).unwrap_or(&0),
            ];
            let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
            for k in 0..4 {
                if k <= chunk.len() {
                    out.push(T[(n >> (18 - 6 * k) & 63) as usize] as char);
                } else {
                    out.push('=');
                }
            }
        }
        out
    }
}
