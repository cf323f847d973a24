//! Scenes for the geometry path (Lambers et al. Sec. 3.2): triangle meshes with per-vertex colour,
//! texture coordinates and an object ID, a camera pose, and where they come from — the
//! built-in scenes ([`builtin`]), OBJ and glTF files ([`load`]) — plus the tessellation
//! Alg. 1 needs ([`tessellate`]). Pure CPU, no Vulkan.

pub mod builtin;
pub mod calibration;
pub mod load;
pub mod pose;
pub mod raycast;
pub mod tessellate;

use std::fmt;

use glam::DVec3;

pub use pose::Pose;

use crate::imaging::Raster;
use crate::model::{Camera, Frustum};

/// One vertex as the vertex shader reads it (`glsl/geometry.vert`, binding 0): 32 bytes.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    /// World position (metres).
    pub position: [f32; 3],
    /// Texture coordinates (0..1 across the texture; the texture repeats).
    pub uv: [f32; 2],
    /// RGBA8 colour, multiplied with the texture.
    pub color: [u8; 4],
    /// Object ID written to the ID output (0 is the background).
    pub object_id: u32,
    pub _pad: u32,
}

impl Vertex {
    pub fn new(position: DVec3, uv: [f32; 2], color: [u8; 4], object_id: u32) -> Self {
        Vertex {
            position: position.as_vec3().to_array(),
            uv,
            color,
            object_id,
            _pad: 0,
        }
    }

    /// The midpoint of an edge: position, uv and colour interpolated, ID of `self`.
    pub fn midpoint(&self, other: &Vertex) -> Vertex {
        let mid = |a: f32, b: f32| 0.5 * (a + b);
        Vertex {
            position: std::array::from_fn(|i| mid(self.position[i], other.position[i])),
            uv: std::array::from_fn(|i| mid(self.uv[i], other.uv[i])),
            color: std::array::from_fn(|i| {
                (self.color[i] as u16 + other.color[i] as u16).div_ceil(2) as u8
            }),
            object_id: self.object_id,
            _pad: 0,
        }
    }

    pub fn position(&self) -> DVec3 {
        DVec3::new(
            self.position[0] as f64,
            self.position[1] as f64,
            self.position[2] as f64,
        )
    }
}

/// An indexed triangle list.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    pub vertices: Vec<Vertex>,
    pub indices: Vec<u32>,
}

/// What is wrong with a mesh. `Display` is one line naming the source and the problem.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    /// Where the mesh came from (a file path or a built-in scene's name).
    pub source: String,
    pub problem: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.source, self.problem)
    }
}

impl std::error::Error for SceneError {}

/// The most triangles vklens draws in one mesh (the bench's 512×512 grid is 0.5 M).
pub const MAX_TRIANGLES: usize = 1 << 25;

impl Mesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Appends another mesh.
    pub fn append(&mut self, other: &Mesh) {
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.indices.extend(other.indices.iter().map(|i| i + base));
    }

    /// Checks what the GPU would otherwise turn into garbage or a device fault: no triangles,
    /// an index count that is not a multiple of 3, an index past the last vertex, a
    /// non-finite or absurdly large position.
    pub fn validate(&self, source: &str) -> Result<(), SceneError> {
        let err = |problem: String| SceneError {
            source: source.to_string(),
            problem,
        };
        if self.indices.is_empty() || self.vertices.is_empty() {
            return Err(err("the mesh has no triangles".into()));
        }
        if self.indices.len() % 3 != 0 {
            return Err(err(format!(
                "{} indices is not a whole number of triangles",
                self.indices.len()
            )));
        }
        if self.triangle_count() > MAX_TRIANGLES {
            return Err(err(format!(
                "{} triangles (the limit is {MAX_TRIANGLES})",
                self.triangle_count()
            )));
        }
        if let Some((k, &i)) = self
            .indices
            .iter()
            .enumerate()
            .find(|(_, &i)| i as usize >= self.vertices.len())
        {
            return Err(err(format!(
                "index {k} is {i}, but there are only {} vertices",
                self.vertices.len()
            )));
        }
        for (k, v) in self.vertices.iter().enumerate() {
            // 1e15 m keeps every product in the projection finite in f32.
            if v.position.iter().any(|c| !c.is_finite() || c.abs() > 1e15) {
                return Err(err(format!(
                    "vertex {k} has position {:?} (not a finite number of metres)",
                    v.position
                )));
            }
            if v.uv.iter().any(|c| !c.is_finite()) {
                return Err(err(format!(
                    "vertex {k} has texture coordinates {:?}",
                    v.uv
                )));
            }
        }
        Ok(())
    }

    /// Axis-aligned bounds of the positions.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.vertices.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), v| (lo.min(v.position()), hi.max(v.position())),
        )
    }
}

/// A mesh with its texture and the view it is best seen from.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Shown in errors and progress ("checkerboard 9x6", a file path).
    pub name: String,
    pub mesh: Mesh,
    /// RGBA8 texture sampled with the vertices' uv (white when absent).
    pub texture: Option<Raster>,
    /// Direction from the scene's centre towards the default camera, and the world direction
    /// that appears downwards in the default view. A zero `view_from` is a scene seen from
    /// inside: its default pose is the identity.
    pub view_from: DVec3,
    pub view_down: DVec3,
    /// For a calibration board: its inner corners (columns, rows) and square size (metres).
    pub board: Option<builtin::Board>,
    /// A 360° image of the world at infinity, seen from the camera's centre (a cube map or a
    /// panorama a user's own renderer made): what the scene is, instead of a mesh.
    pub environment: Option<Environment>,
    /// Object names by ID: `objects[i]` names the vertices with `object_id` i + 1 (OBJ `o`/`g`
    /// names, glTF node names, a built-in scene's own). An ID past the list is
    /// `object_<id>` ([`Scene::object_name`]).
    pub objects: Vec<String>,
}

/// The world as a 360° image at infinity, seen from the camera's centre: each output pixel
/// samples it along the ray its lens sees (the sphere warp).
#[derive(Debug, Clone)]
pub enum Environment {
    /// Six square faces of one size, +x -x +y -y +z -z (OpenCV's camera axes: x right, y
    /// down, z forward).
    Cube(Box<[Raster; 6]>),
    /// An equirectangular panorama, 360° × 180°, twice as wide as high.
    Panorama(Raster),
}

impl Environment {
    /// The images, in order.
    pub fn rasters(&self) -> Vec<&Raster> {
        match self {
            Environment::Cube(faces) => faces.iter().collect(),
            Environment::Panorama(p) => vec![p],
        }
    }

    /// What it is, in words: "a cube map of six 512×512 faces", "a 2048×1024 panorama".
    pub fn describe(&self) -> String {
        match self {
            Environment::Cube(faces) => {
                format!("a cube map of six {0}×{0} faces", faces[0].width)
            }
            Environment::Panorama(p) => format!("a {}×{} panorama", p.width, p.height),
        }
    }
}

impl Scene {
    /// A scene that is only `environment`: no mesh, seen from its centre.
    pub fn from_environment(name: impl Into<String>, environment: Environment) -> Scene {
        Scene {
            name: name.into(),
            mesh: Mesh {
                vertices: Vec::new(),
                indices: Vec::new(),
            },
            texture: None,
            view_from: DVec3::ZERO,
            view_down: DVec3::Y,
            board: None,
            environment: Some(environment),
            objects: Vec::new(),
        }
    }

    /// The name of object `id` (1 and up; 0 is the background): its scene's name for it, or
    /// `object_<id>`.
    pub fn object_name(&self, id: u32) -> String {
        id.checked_sub(1)
            .and_then(|i| self.objects.get(i as usize))
            .filter(|n| !n.is_empty())
            .cloned()
            .unwrap_or_else(|| format!("object_{id}"))
    }

    /// The IDs the mesh's vertices carry, ascending, each once.
    pub fn object_ids(&self) -> Vec<u32> {
        let mut ids: Vec<u32> = self.mesh.vertices.iter().map(|v| v.object_id).collect();
        ids.sort_unstable();
        ids.dedup();
        ids.retain(|&id| id != 0);
        ids
    }

    /// A pose that shows the whole scene, centred, filling about 80 % of the smaller field of
    /// view of `camera` (its Sec. 3.1 frustum).
    pub fn default_pose(&self, camera: &Camera) -> Pose {
        if self.view_from == DVec3::ZERO {
            return Pose::IDENTITY;
        }
        let f = Frustum::from_intrinsics(&camera.intrinsics, camera.width, camera.height);
        let half_tangents = [-f.left, f.right, -f.top, f.bottom];
        let (lo, hi) = self.mesh.bounds();
        let centre = 0.5 * (lo + hi);
        let forward = -self.view_from.normalize();
        let down = self.view_down;
        let right = down.cross(forward).normalize();
        let down = forward.cross(right);
        // Extents of the bounds across the view, then the distance that fits them.
        let corners = (0..8).map(|i| {
            DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            ) - centre
        });
        let (mut sx, mut sy, mut sz) = (0.0f64, 0.0f64, 0.0f64);
        for c in corners {
            sx = sx.max(c.dot(right).abs());
            sy = sy.max(c.dot(down).abs());
            sz = sz.max(c.dot(forward).abs());
        }
        let tx = half_tangents[0].min(half_tangents[1]);
        let ty = half_tangents[2].min(half_tangents[3]);
        let distance = (sx / tx).max(sy / ty) / 0.8 + sz;
        let distance = if distance.is_finite() && distance > 0.0 {
            distance
        } else {
            1.0
        };
        Pose::look_at(centre - forward * distance, centre, down)
    }
}

/// A SceneError names its own file (and line or key): bad input.
impl From<SceneError> for crate::Error {
    fn from(e: SceneError) -> Self {
        crate::Error::Input(e.to_string())
    }
}
