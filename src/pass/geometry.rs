//! The geometry path (Lambers et al. Sec. 3.2): meshes drawn with Alg. 1 and triangles outside
//! `[-(1+δ+D), 1+δ+D]²` (undistorted NDC) dropped — by two compute dispatches before the draw
//! ([`Discard::Compute`], the default: Alg. 1 once per vertex and pose, and no geometry stage)
//! or by a geometry shader ([`Discard::GeometryShader`]) — or, for the warp path's first pass,
//! a plain pinhole render with the Sec. 3.1 frustum.
//!
//! Outputs (Lambers et al. Table 1), each only when asked for: colour (RGBA8 or RGBA16F), object ID
//! (R32_UINT, flat, never blended), 2D flow (RG32F: pixel motion since a previous pose, NaN
//! where unknown) and camera depth (R32F, metres; +inf where nothing was drawn).
//!
//! Embedding: [`GeometryPass::record`] records the discard's dispatches (when it has them) and
//! one render pass into the caller's command buffer on [`GeometryTargets`] (images the pass
//! made) — the colour attachments end in the desc's `final_layout`.

use crate::pass::spec;
use ash::vk;
use bytemuck::{Pod, Zeroable};
use glam::{DMat4, DVec2};
use gpu_allocator::MemoryLocation;

use super::camera_params::CameraParams;
use crate::gpu::{
    image_transition, shaders, Access, Attribute, Buffer, ComputePipeline, DescriptorPool, Error,
    Framebuffer, Gpu, GraphicsDesc, GraphicsPipeline, Image, RenderPass, Result, Sampler,
    SpecConstants, Stage, VertexBinding,
};
pub use crate::imaging::Rendered;
use crate::imaging::{BitDepth, Pixels, Raster};
use crate::model::overscan::valid_region_boundary;
use crate::model::rolling_shutter::{FrameMotion, LineRate, Readout, RATE_TABLE};
use crate::model::{vulkan_projection, Camera, Frustum};
use crate::scene::{Mesh, Pose, Vertex};

/// How vertices are projected.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Projection {
    /// Alg. 1: the forward standard model per vertex, with Sec. 3.2's discard tolerance δ
    /// (D is computed from the camera).
    Lens { delta: f64 },
    /// The Sec. 3.1 pinhole projection only (no model, no discard).
    Pinhole,
}

/// Colour attachment format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColorFormat {
    Rgba8,
    Rgba16F,
    /// Full float (the warp path's pinhole source for float output: a warp format).
    Rgba32F,
}

/// Which outputs to render.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Outputs {
    pub color: Option<ColorFormat>,
    pub ids: bool,
    pub flow: bool,
    pub depth: bool,
}

impl Outputs {
    pub const COLOR: Outputs = Outputs {
        color: Some(ColorFormat::Rgba8),
        ids: false,
        flow: false,
        depth: false,
    };

    /// Colour in `format` only (no output when `None`).
    pub fn color_only(format: Option<ColorFormat>) -> Outputs {
        Outputs {
            color: format,
            ids: false,
            flow: false,
            depth: false,
        }
    }

    /// Attachment formats by fragment-output location (0 colour, 1 ID, 2 flow, 3 depth).
    fn formats(&self) -> [Option<vk::Format>; 4] {
        [
            self.color.map(|c| match c {
                ColorFormat::Rgba8 => vk::Format::R8G8B8A8_UNORM,
                ColorFormat::Rgba16F => vk::Format::R16G16B16A16_SFLOAT,
                ColorFormat::Rgba32F => vk::Format::R32G32B32A32_SFLOAT,
            }),
            self.ids.then_some(vk::Format::R32_UINT),
            self.flow.then_some(vk::Format::R32G32_SFLOAT),
            self.depth.then_some(vk::Format::R32_SFLOAT),
        ]
    }
}

/// Lambers et al. Sec. 3.2's default tolerance δ.
pub const DEFAULT_DELTA: f64 = 0.1;

/// Where Lambers et al. Sec. 3.2's triangle discard runs (the rule is the same in both).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Discard {
    /// The compute discard: it is the faster on lavapipe (`vklens bench vertex`,
    /// docs/benchmarks.md) and needs no geometry stage, so any device runs it.
    Auto,
    /// Two compute dispatches before the draw: a flag per vertex, then the index buffer
    /// rewritten with a degenerate triangle for each dropped one (`glsl/discard.comp`).
    Compute,
    /// A geometry shader drops triangles (`glsl/geometry.geom`); needs `geometryShader`.
    GeometryShader,
}

impl Discard {
    /// The stage `Auto` stands for on `gpu`: the geometry shader where its context asks for it
    /// (`VKLENS_DISCARD=geometry-shader`, read with the device's other settings), else the
    /// compute discard.
    pub fn resolve_for(self, gpu: &Gpu) -> Discard {
        match self {
            Discard::Auto if gpu.prefers_geometry_shader_discard() => Discard::GeometryShader,
            d => d.resolve(),
        }
    }

    /// The stage `Auto` stands for by default (the compute discard).
    pub fn resolve(self) -> Discard {
        match self {
            Discard::Auto => Discard::Compute,
            d => d,
        }
    }

    /// Its name in reports (`compute`, `geometry-shader`).
    pub fn name(self) -> &'static str {
        match self.resolve() {
            Discard::GeometryShader => "geometry-shader",
            _ => "compute",
        }
    }
}

/// What a [`GeometryPass`] renders.
#[derive(Debug, Clone)]
pub struct GeometryDesc {
    /// The camera: image size, intrinsics (the Sec. 3.1 frustum) and, for
    /// [`Projection::Lens`], the distortion.
    pub camera: Camera,
    pub projection: Projection,
    pub outputs: Outputs,
    /// Near and far clipping depths (metres).
    pub near: f64,
    pub far: f64,
    /// Colour clear value (the background).
    pub background: [f32; 4],
    /// Layout the output images are left in.
    pub final_layout: vk::ImageLayout,
    /// Where the triangle discard runs ([`Projection::Lens`] only).
    pub discard: Discard,
    /// A rolling shutter's readout, for frames whose camera moves during the readout
    /// ([`GeometryPass::set_moving_frame`]): each vertex is drawn where its own line reads
    /// it. `None`: every line at once, and the per-vertex solve is compiled out.
    pub readout: Option<Readout>,
}

impl GeometryDesc {
    pub fn new(camera: Camera, projection: Projection, outputs: Outputs) -> Self {
        GeometryDesc {
            camera,
            projection,
            outputs,
            near: 0.01,
            far: 1000.0,
            background: [0.0; 4],
            final_layout: vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            discard: Discard::Auto,
            readout: None,
        }
    }
}

/// `uniform GeometryFrame` of `glsl/include/geometry_frame.glsl` (std140).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GeometryFrame {
    pub view_projection: [[f32; 4]; 4],
    pub previous_view_projection: [[f32; 4]; 4],
    pub view: [[f32; 4]; 4],
    /// width, height, discard bound 1 + δ + D, near.
    pub viewport: [f32; 4],
    /// The Sec. 3.1 projection alone: a moving rolling shutter's camera-frame points go
    /// through it at their own readout time.
    pub projection: [[f32; 4]; 4],
    /// The first line's pose of the frame flow starts from (`view` is this frame's).
    pub previous_view: [[f32; 4]; 4],
    /// The frame's motion during the readout, and the motion of the frame flow starts from.
    pub motion: MotionGpu,
    pub previous_motion: MotionGpu,
    /// x: the half angle of the cone the lens's line rate was measured on ([`LineRate::cone`],
    /// radians; 0 where it has none, and every vertex is solved by the scan), yzw: 0.
    pub readout_bound: [f32; 4],
    /// The line rate of cones of growing half angle ([`LineRate::per_radian`], entry i in
    /// component i % 4 of row i / 4): with each motion's turn and centres it bounds how fast a
    /// vertex's own line time moves during the readout.
    pub readout_rates: [[f32; 4]; RATE_TABLE / 4],
}

/// `struct VklMotionBlock` of `glsl/include/geometry_frame.glsl` (std140): a frame's motion
/// during the readout about its middle line's pose (s = ½), where the shaders evaluate it.
/// The turn from the first line's camera frame to the last line's has the same axis in every
/// camera frame of the readout, so the camera-frame point at s is the middle line's turned
/// by (s − ½) · angle, and the centre's travel is linear in s: the middle line's point is
/// computed once per vertex, and the solve's first sample, at s = ½, is that point.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct MotionGpu {
    /// R_cw(½), the middle line's world-to-camera rotation (columns, std140 `mat3`).
    pub rotation: [[f32; 4]; 3],
    /// xyz: the unit axis, w: the angle of the turn from the first line's camera frame to
    /// the last line's ([`FrameMotion::axis`], [`FrameMotion::angle`]).
    pub turn: [f32; 4],
    /// xyz: the camera centre C(½) when the middle line is read; w: 1 where the camera moves
    /// during the frame, else 0 (a still frame takes the global shutter's arithmetic, bit
    /// for bit).
    pub centre: [f32; 4],
    /// xyz: R_cw(½) (C1 − C0), the centre's travel during the readout in the middle line's
    /// camera frame; w: 0.
    pub travel: [f32; 4],
}

/// One frame's poses: when the first line is read, and when the last is (the same for a
/// camera that does not move during the frame).
#[derive(Debug, Clone, Copy)]
struct Motion {
    pose: Pose,
    end: Pose,
}

impl Motion {
    fn new(pose: Pose, end: Pose) -> Self {
        Motion { pose, end }
    }

    fn still(pose: Pose) -> Self {
        Motion { pose, end: pose }
    }

    fn is_still(&self) -> bool {
        self.pose == self.end
    }

    /// The motion as `GeometryFrame` holds it.
    fn gpu(&self) -> MotionGpu {
        let m = FrameMotion::new(self.pose.into(), self.end.into());
        let middle = m.at(0.5);
        let [c0, c1] = m.centres();
        let moving = if self.is_still() { 0.0 } else { 1.0 };
        let r = middle.rotation.as_mat3();
        MotionGpu {
            rotation: [r.x_axis, r.y_axis, r.z_axis].map(|c| c.extend(0.0).to_array()),
            turn: m.axis().as_vec3().extend(m.angle() as f32).to_array(),
            centre: m.centre_at(0.5).as_vec3().extend(moving).to_array(),
            travel: (middle.rotation * (c1 - c0))
                .as_vec3()
                .extend(0.0)
                .to_array(),
        }
    }
}

/// Lambers et al. Sec. 3.2's D for a camera: how far past ±1 the undistorted NDC of the distorted
/// image border reaches. The seed undistorts the four corners; this uses the whole border
/// (and the fold boundary where it lies inside the image), as the overscan does, because for
/// mustache and strongly tangential lenses the extremes are not at the corners.
pub fn discard_margin(camera: &Camera) -> f64 {
    let f = Frustum::from_intrinsics(&camera.intrinsics, camera.width, camera.height);
    valid_region_boundary(camera)
        .iter()
        .map(|p| {
            let ndc = DVec2::new(
                2.0 * (p.x - f.left) / (f.right - f.left) - 1.0,
                2.0 * (p.y - f.top) / (f.bottom - f.top) - 1.0,
            );
            ndc.x.abs().max(ndc.y.abs()) - 1.0
        })
        .fold(0.0, f64::max)
}

/// 1 + δ + D for a projection (infinite for a pinhole render).
fn discard_bound(projection: &Projection, camera: &Camera) -> Result<f64> {
    match *projection {
        Projection::Lens { delta } => {
            if !(delta.is_finite() && delta >= 0.0) {
                return Err(Error::Input(format!(
                    "δ = {delta}: the discard tolerance must be ≥ 0"
                )));
            }
            if camera.model().is_ray_model() {
                // A ray model's (a fisheye's…) vertices are tested in its own distorted image (alg1.glsl): its
                // domain check, not a frustum, keeps the model from folding; a triangle off
                // the image is clipped by the rasterizer like any other.
                return Ok(f64::INFINITY);
            }
            Ok(1.0 + delta + discard_margin(camera))
        }
        Projection::Pinhole => Ok(f64::INFINITY),
    }
}

/// Whether the compute discard's per-vertex pass needs the valid domain's table: not when
/// every vertex inside `bound` (1 + δ + D on undistorted NDC) lies inside the domain's smallest
/// boundary radius, for then a vertex beyond that radius is dropped by the bound whatever the
/// table would say (`VKL_DOMAIN_TABLE` in `glsl/include/camera_model.glsl`). The margin covers
/// the GPU's f32 rounding of both tests. A fisheye's domain is its own cone, tested without
/// the table.
pub fn discard_needs_domain_table(camera: &Camera, bound: f64) -> bool {
    if camera.model().is_ray_model() {
        // Only an omni lens reads the table (its radial-tangential part's domain).
        return matches!(
            camera.model(),
            crate::model::ModelKind::Omni | crate::model::ModelKind::ThinPrismFisheye
        );
    }
    if !bound.is_finite() {
        return true;
    }
    let f = Frustum::from_intrinsics(&camera.intrinsics, camera.width, camera.height);
    let centre = DVec2::new(f.left + f.right, f.top + f.bottom) / 2.0;
    let half = DVec2::new(f.right - f.left, f.bottom - f.top) / 2.0 * bound;
    let corner = centre.abs() + half;
    !(corner.length() <= camera.domain().min_ideal_radius() * (1.0 - 1e-4))
}

/// The vertex layout of [`Vertex`].
const VERTEX_ATTRIBUTES: [Attribute; 4] = [
    (0, vk::Format::R32G32B32_SFLOAT, 0),
    (1, vk::Format::R32G32_SFLOAT, 12),
    (2, vk::Format::R8G8B8A8_UNORM, 20),
    (3, vk::Format::R32_UINT, 24),
];
/// Binding 0: the mesh's vertices.
const MESH_BINDING: VertexBinding = (std::mem::size_of::<Vertex>() as u32, &VERTEX_ATTRIBUTES);
/// Binding 1 with the compute discard: the distorted NDC (`in_distorted_ndc`).
const POSITION_BINDING: VertexBinding = (8, &[(4, vk::Format::R32G32_SFLOAT, 0)]);
/// Binding 2 with the compute discard and flow: the motion (`in_motion`).
const MOTION_BINDING: VertexBinding = (16, &[(5, vk::Format::R32G32B32A32_SFLOAT, 0)]);

/// The draw's vertex bindings: the mesh's vertices, then (`pulled`: the compute discard ran)
/// its positions and, with `flow`, its motion. The pipeline is built with these and the draw
/// binds one buffer for each.
/// A moving rolling shutter reads the motion binding for its solved readout times (its `w`)
/// with flow or without.
fn vertex_bindings(pulled: bool, flow: bool) -> &'static [VertexBinding<'static>] {
    match (pulled, flow) {
        (true, true) => &[MESH_BINDING, POSITION_BINDING, MOTION_BINDING],
        (true, false) => &[MESH_BINDING, POSITION_BINDING],
        _ => &[MESH_BINDING],
    }
}

/// An RGBA8 texture for sampling, staged for upload ([`Texture::record_upload`]).
pub struct Texture {
    gpu: Gpu,
    pub image: Image,
    staging: Buffer,
}

impl Texture {
    /// Stages `raster` (any pixel type, converted to 8-bit RGBA).
    pub fn new(gpu: &Gpu, raster: &Raster) -> Result<Self> {
        raster.check()?;
        let bytes: Vec<u8> = match &raster.pixels {
            Pixels::Rgba8(p) => p.iter().flatten().copied().collect(),
            _ => (0..raster.len())
                .flat_map(|i| {
                    raster
                        .rgba_f32(i)
                        .map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
                })
                .collect(),
        };
        Ok(Texture {
            image: Image::new_2d(
                gpu,
                "texture",
                vk::Format::R8G8B8A8_UNORM,
                raster.width,
                raster.height,
                vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
            )?,
            staging: Buffer::from_pod(
                gpu,
                "texture.upload",
                &bytes,
                vk::BufferUsageFlags::TRANSFER_SRC,
            )?,
            gpu: gpu.clone(),
        })
    }

    /// Records the upload; afterwards the image is in `SHADER_READ_ONLY_OPTIMAL`, visible to
    /// fragment shaders. Record it once, before the first use.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass.
    pub unsafe fn record_upload(&self, cmd: vk::CommandBuffer) {
        // SAFETY: the caller upholds `record_upload`'s contract: `cmd` is recording outside a
        // render pass. The image has TRANSFER_DST and SAMPLED usage and UNDEFINED is a valid
        // old layout as it is overwritten whole; `staging` holds it as tightly packed RGBA8,
        // which relies on an RGBA8 raster having width × height pixels (`new` does not check).
        unsafe {
            image_transition(
                &self.gpu,
                cmd,
                self.image.raw,
                Access::Nothing,
                Access::TransferWrite,
            );
            self.gpu.device().cmd_copy_buffer_to_image(
                cmd,
                self.staging.raw,
                self.image.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[self.image.whole_copy()],
            );
            image_transition(
                &self.gpu,
                cmd,
                self.image.raw,
                Access::TransferWrite,
                Access::FragmentSampled,
            );
        }
    }
}

/// A mesh on the GPU: vertex and index buffers and its texture (white if it has none), and
/// what the compute discard keeps per mesh (`DiscardBuffers`).
pub struct MeshBuffers {
    discard: DiscardBuffers,
    pub vertices: Buffer,
    pub indices: Buffer,
    pub index_count: u32,
    pub vertex_count: u32,
    pub texture: Texture,
}

/// The compute discard's per-mesh state (`glsl/discard.comp`; it reads the positions from the
/// mesh's own vertex buffer).
struct DiscardBuffers {
    /// Per vertex, read by the draw as vertex attributes: the distorted NDC (two floats), and
    /// the flow with its validity (four).
    positions: Buffer,
    motion: Buffer,
    /// The vertices the last discard dropped, behind the indirect dispatch that visits them
    /// (`Dropped` in the shader: groups, 1, 1, count, then the list).
    dropped: Buffer,
    /// The vertices a moving rolling shutter's per-vertex stage left to stage 3, as `dropped`
    /// (`Deferred` in the shader).
    deferred: Buffer,
    /// Which triangles each vertex belongs to (compressed rows: vertex v's triangles are
    /// `incidence[incidence_start[v] .. incidence_start[v + 1]]`).
    incidence_start: Buffer,
    incidence: Buffer,
    /// The index buffer the draw uses: the mesh's, but for the triangles of dropped vertices,
    /// which are degenerate.
    kept: Buffer,
}

/// The dropped-vertex buffer's header (`Dropped` in `glsl/discard.comp`): no workgroups,
/// y = z = 1, no vertices.
const DROPPED_HEADER: [u32; 4] = [0, 1, 1, 0];

/// The triangles each vertex belongs to, as compressed rows: (start per vertex and one past
/// the last, triangle ids).
fn incidence(indices: &[u32], vertex_count: usize) -> (Vec<u32>, Vec<u32>) {
    let mut start = vec![0u32; vertex_count + 1];
    for &i in indices {
        start[i as usize + 1] += 1;
    }
    for v in 0..vertex_count {
        start[v + 1] += start[v];
    }
    let mut next = start.clone();
    let mut triangles = vec![0u32; indices.len()];
    for (k, &i) in indices.iter().enumerate() {
        let slot = &mut next[i as usize];
        triangles[*slot as usize] = (k / 3) as u32;
        *slot += 1;
    }
    (start, triangles)
}

impl MeshBuffers {
    /// Uploads a (validated) mesh; the texture is staged for [`Self::record_upload`].
    pub fn new(gpu: &Gpu, mesh: &Mesh, texture: Option<&Raster>) -> Result<Self> {
        mesh.validate("mesh")
            .map_err(|e| Error::Input(e.to_string()))?;
        let white = Raster {
            width: 1,
            height: 1,
            pixels: Pixels::Rgba8(vec![[255; 4]]),
            bit_depth: BitDepth::U8,
        };
        use vk::BufferUsageFlags as U;
        let n = mesh.vertices.len();
        let (start, triangles) = incidence(&mesh.indices, n);
        let mut dropped = DROPPED_HEADER.to_vec();
        dropped.resize(DROPPED_HEADER.len() + n, 0);
        let storage = U::STORAGE_BUFFER;
        let per_vertex = |name, bytes: u64| {
            Buffer::new(
                gpu,
                name,
                n as u64 * bytes,
                U::VERTEX_BUFFER | storage | U::TRANSFER_SRC,
                MemoryLocation::GpuOnly,
            )
        };
        let discard = DiscardBuffers {
            positions: per_vertex("mesh.discard.positions", 8)?,
            motion: per_vertex("mesh.discard.motion", 16)?,
            dropped: Buffer::from_pod(
                gpu,
                "mesh.discard.dropped",
                &dropped,
                storage | U::INDIRECT_BUFFER | U::TRANSFER_DST,
            )?,
            deferred: Buffer::from_pod(
                gpu,
                "mesh.discard.deferred",
                &dropped,
                storage | U::INDIRECT_BUFFER | U::TRANSFER_DST,
            )?,
            incidence_start: Buffer::from_pod(
                gpu,
                "mesh.discard.incidence_start",
                &start,
                storage,
            )?,
            incidence: Buffer::from_pod(gpu, "mesh.discard.incidence", &triangles, storage)?,
            // Starts as the mesh's own indices: the first discard has nothing to restore.
            kept: Buffer::from_pod(
                gpu,
                "mesh.discard.kept",
                &mesh.indices,
                U::INDEX_BUFFER | storage,
            )?,
        };
        Ok(MeshBuffers {
            discard,
            // The discard's per-vertex pass reads the positions too.
            vertices: Buffer::from_pod(
                gpu,
                "mesh.vertices",
                &mesh.vertices,
                U::VERTEX_BUFFER | storage,
            )?,
            indices: Buffer::from_pod(
                gpu,
                "mesh.indices",
                &mesh.indices,
                U::INDEX_BUFFER | storage,
            )?,
            index_count: mesh.indices.len() as u32,
            vertex_count: n as u32,
            texture: Texture::new(gpu, texture.unwrap_or(&white))?,
        })
    }

    /// The compute discard's per-vertex results of the last draw: the distorted NDC (two
    /// floats), and the motion (flow, its validity, and a moving rolling shutter's solved
    /// readout time; four floats). Transfer sources, for tests to read back.
    #[cfg(test)]
    pub(crate) fn discard_results(&self) -> [&Buffer; 2] {
        [&self.discard.positions, &self.discard.motion]
    }

    /// Records the texture upload (see [`Texture::record_upload`]).
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass.
    pub unsafe fn record_upload(&self, cmd: vk::CommandBuffer) {
        // SAFETY: the caller upholds this function's contract, which is `Texture::record_upload`'s.
        unsafe { self.texture.record_upload(cmd) }
    }
}

/// The geometry pass: pipeline, render pass, camera and frame uniforms.
pub struct GeometryPass {
    gpu: Gpu,
    desc: GeometryDesc,
    // Drop order: descriptor pool and pipeline before the render pass they were made for.
    _pool: DescriptorPool,
    /// One camera block, pose block and descriptor set per frame in flight, so that a caller
    /// writes frame N+1's while frame N executes ([`Self::select_frame`]).
    frames: Vec<FrameSlot>,
    /// The frame [`Self::set_frame`] writes and [`Self::record`] records.
    current: usize,
    pipeline: GraphicsPipeline,
    render_pass: RenderPass,
    sampler: Sampler,
    discard_bound: f64,
    /// The motion and previous motion of the last [`GeometryPass::set_frame`] or
    /// [`GeometryPass::set_moving_frame`]: the frame block is a function of the camera too
    /// (its projection, its viewport), so a new camera rewrites it for them.
    last_frame: std::cell::Cell<(Motion, Motion)>,
    /// Whether the compute discard was built with the valid domain's table
    /// ([`discard_needs_domain_table`]).
    domain_table: bool,
    /// The compute discard (a lens projection with [`Discard::Compute`]).
    discard: Option<DiscardPass>,
    /// The line rate of the camera as the shaders project (lens or pinhole) in the desc's
    /// readout order, where it has one: what lets the shaders skip the scan of a vertex whose
    /// line time provably moves slower than the readout.
    line_rate: Option<LineRate>,
}

/// One frame in flight of a [`GeometryPass`]: its uniforms and the sets that read them.
struct FrameSlot {
    camera: Buffer,
    frame: Buffer,
    set: vk::DescriptorSet,
    /// The compute discard's set for this frame (it reads the same uniforms).
    discard_set: Option<vk::DescriptorSet>,
}

/// Most frames in flight a geometry pass keeps uniforms and sets for (the warp's limit).
pub const MAX_FRAMES_IN_FLIGHT: usize = crate::pass::warp::MAX_FRAMES_IN_FLIGHT;

/// The compute discard's pipelines (`glsl/discard.comp`, STAGE 0 per vertex, 1 restore,
/// 2 drop, and for a moving rolling shutter 3, the vertices stage 0 deferred) and the pool of
/// their sets (one per frame in flight, in [`FrameSlot`]).
struct DiscardPass {
    stages: [ComputePipeline; 3],
    deferred: Option<ComputePipeline>,
    pool: DescriptorPool,
}

/// `DiscardPush` of `glsl/discard.comp`: how many vertices (stage 0; the other stages read
/// their count from the dropped list).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct DiscardPush {
    pub count: u32,
}

impl GeometryPass {
    pub fn new(gpu: &Gpu, desc: GeometryDesc) -> Result<Self> {
        Self::with_frames(gpu, desc, 1)
    }

    /// As [`GeometryPass::new`], with uniforms and descriptor sets for `frames` frames in
    /// flight (1 to [`MAX_FRAMES_IN_FLIGHT`]), chosen by [`Self::select_frame`]. The mesh's
    /// discard buffers are shared: the frames must run on one queue, in the order recorded
    /// (the barriers `record` records order them there).
    pub fn with_frames(gpu: &Gpu, desc: GeometryDesc, frames: usize) -> Result<Self> {
        if !(1..=MAX_FRAMES_IN_FLIGHT).contains(&frames) {
            return Err(Error::Input(format!(
                "{frames} frames in flight: a geometry pass keeps 1 to {MAX_FRAMES_IN_FLIGHT}"
            )));
        }
        let cam = &desc.camera;
        if cam.width > gpu.max_image_side() || cam.height > gpu.max_image_side() {
            return Err(Error::Input(format!(
                "{}×{} is larger than the device's {} px image limit",
                cam.width,
                cam.height,
                gpu.max_image_side()
            )));
        }
        if !(desc.near > 0.0 && desc.far > desc.near && desc.far.is_finite()) {
            return Err(Error::Input(format!(
                "near {} / far {}: need 0 < near < far",
                desc.near, desc.far
            )));
        }
        let lens = matches!(desc.projection, Projection::Lens { .. });
        let discard_bound = discard_bound(&desc.projection, cam)?;
        let formats = desc.outputs.formats();
        if formats.iter().all(|f| f.is_none()) {
            return Err(Error::Input("no output was asked for".into()));
        }
        let render_pass = RenderPass::new(
            gpu,
            &formats,
            Some(vk::Format::D32_SFLOAT),
            desc.final_layout,
        )?;
        let vertex_constants = CameraParams::spec_constants(cam.terms())
            .bool(spec::DISTORT, lens)
            .bool(spec::WRITE_FLOW, desc.outputs.flow)
            .u32(spec::READOUT, desc.readout.map_or(0, Readout::gpu_id));
        let o = desc.outputs;
        let fragment_constants = SpecConstants::new()
            .bool(spec::WRITE_COLOR, o.color.is_some())
            .bool(spec::WRITE_IDS, o.ids)
            .bool(spec::WRITE_FLOW, o.flow)
            .bool(spec::WRITE_DEPTH, o.depth);
        let geometry_stage = lens && desc.discard.resolve_for(gpu) == Discard::GeometryShader;
        // With the compute discard, Alg. 1 runs there once per vertex and pose, and the draw
        // reads its positions and flow as vertex attributes.
        let pulled = lens && !geometry_stage;
        // The pulled draw of a moving rolling shutter reads each vertex's solved readout time
        // from the motion binding, flow or not.
        let flow = desc.outputs.flow || desc.readout.is_some();
        let mut stages = vec![Stage {
            stage: vk::ShaderStageFlags::VERTEX,
            spirv: match (geometry_stage, pulled, flow) {
                (true, _, _) if desc.readout.is_some() => shaders::GEOMETRY_VERT,
                (true, _, _) => shaders::GEOMETRY_VERT_GLOBAL,
                (_, true, true) => shaders::GEOMETRY_VERT_PULLED_FLOW,
                (_, true, false) => shaders::GEOMETRY_VERT_PULLED,
                _ if desc.readout.is_none() => shaders::GEOMETRY_VERT_PLAIN,
                _ => shaders::GEOMETRY_VERT_PINHOLE,
            },
            constants: vertex_constants.clone(),
        }];
        if geometry_stage {
            stages.push(Stage {
                stage: vk::ShaderStageFlags::GEOMETRY,
                spirv: shaders::GEOMETRY_GEOM,
                constants: SpecConstants::new(),
            });
        }
        stages.push(Stage {
            stage: vk::ShaderStageFlags::FRAGMENT,
            spirv: shaders::GEOMETRY_FRAG,
            constants: fragment_constants,
        });
        let bindings = [
            vk::DescriptorType::UNIFORM_BUFFER,
            vk::DescriptorType::UNIFORM_BUFFER,
            vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
        ];
        let pipeline = GraphicsPipeline::new(
            gpu,
            GraphicsDesc {
                stages,
                bindings: &bindings,
                vertex: vertex_bindings(pulled, flow),
                render_pass: &render_pass,
                depth_test: true,
                push_size: 0,
                additive: false,
            },
        )?;
        let domain_table = discard_needs_domain_table(cam, discard_bound);
        let discard = if pulled {
            let constants = vertex_constants.bool(spec::DOMAIN_TABLE, domain_table);
            Some(DiscardPass::new(
                gpu,
                constants,
                desc.readout.is_some(),
                frames,
            )?)
        } else {
            None
        };
        let pool = DescriptorPool::for_pipeline(gpu, &pipeline, frames as u32)?;
        let uniform = vk::DescriptorType::UNIFORM_BUFFER;
        let mut slots = Vec::with_capacity(frames);
        for _ in 0..frames {
            let camera = Buffer::from_pod(
                gpu,
                "geometry.camera",
                &[CameraParams::from_camera(cam)],
                vk::BufferUsageFlags::UNIFORM_BUFFER,
            )?;
            let frame = Buffer::from_pod(
                gpu,
                "geometry.frame",
                &[GeometryFrame::zeroed()],
                vk::BufferUsageFlags::UNIFORM_BUFFER,
            )?;
            let set = pool.allocate(&pipeline)?;
            let uniforms = [(0, uniform, &camera), (1, uniform, &frame)];
            // SAFETY: the set was just allocated from a pool made for this pipeline's layout,
            // so no work uses it yet; the buffers are this pass's own, alive.
            unsafe { crate::gpu::write_buffer_descriptors(gpu, set, &uniforms) };
            let discard_set = match &discard {
                Some(d) => {
                    let set = d.pool.allocate(&d.stages[0])?;
                    // SAFETY: as above, for the discard's layout, whose bindings 0 and 1 are
                    // these uniforms too.
                    unsafe { crate::gpu::write_buffer_descriptors(gpu, set, &uniforms) };
                    Some(set)
                }
                None => None,
            };
            slots.push(FrameSlot {
                camera,
                frame,
                set,
                discard_set,
            });
        }
        let mut pass = GeometryPass {
            gpu: gpu.clone(),
            sampler: Sampler::new(gpu, vk::Filter::LINEAR, vk::SamplerAddressMode::REPEAT)?,
            discard,
            desc,
            _pool: pool,
            frames: slots,
            current: 0,
            pipeline,
            render_pass,
            discard_bound,
            last_frame: std::cell::Cell::new((
                Motion::still(Pose::IDENTITY),
                Motion::still(Pose::IDENTITY),
            )),
            domain_table,
            line_rate: None,
        };
        pass.line_rate = pass.measure_line_rate();
        for i in 0..frames {
            pass.select_frame(i);
            // SAFETY: the pass is new: no submission using it exists.
            unsafe { pass.set_frame(&Pose::IDENTITY, &Pose::IDENTITY) }?;
        }
        pass.select_frame(0);
        Ok(pass)
    }

    /// How many frames in flight the pass keeps uniforms and sets for.
    pub fn frames_in_flight(&self) -> usize {
        self.frames.len()
    }

    /// Makes frame `frame` (modulo [`Self::frames_in_flight`]) the one [`Self::set_frame`]
    /// and [`Self::set_camera`] write and [`Self::record`] records. A caller with N frames in
    /// flight selects frame k mod N before writing frame k, after waiting only for frame
    /// k − N's fence.
    pub fn select_frame(&mut self, frame: usize) {
        self.current = frame % self.frames.len();
    }

    pub fn desc(&self) -> &GeometryDesc {
        &self.desc
    }

    /// The pipeline (its specialization constants show what was compiled in).
    pub fn pipeline(&self) -> &GraphicsPipeline {
        &self.pipeline
    }

    /// The compute discard's specialization constants (per vertex, restore, drop), when the
    /// pass drops triangles by compute; `None` with a geometry shader or a pinhole
    /// projection.
    pub fn discard_constants(&self) -> Option<[&SpecConstants; 3]> {
        self.discard
            .as_ref()
            .map(|d| d.stages.each_ref().map(|p| &p.constants))
    }

    /// 1 + δ + D: the bound on undistorted NDC beyond which a vertex drops its triangles
    /// (infinite for a pinhole render).
    pub fn discard_bound(&self) -> f64 {
        self.discard_bound
    }

    /// The Sec. 3.1 projection matrix of this pass's camera.
    pub fn projection(&self) -> DMat4 {
        let c = &self.desc.camera;
        vulkan_projection(
            &Frustum::from_intrinsics(&c.intrinsics, c.width, c.height),
            self.desc.near,
            self.desc.far,
        )
    }

    /// Whether [`Self::set_camera`] can switch this pass to `camera` (same image size and the
    /// same distortion terms, which are compiled in).
    pub fn accepts_camera(&self, camera: &Camera) -> bool {
        let c = &self.desc.camera;
        (c.width, c.height) == (camera.width, camera.height)
            && c.terms() == camera.terms()
            // A discard built without the domain table takes only cameras that need none.
            && (self.discard.is_none()
                || self.domain_table
                || discard_bound(&self.desc.projection, camera)
                    .is_ok_and(|bound| !discard_needs_domain_table(camera, bound)))
    }

    /// Switches to another camera of the same size and terms without rebuilding the pipeline
    /// (jittered passes, a calibration set's views, a zoom). Call [`Self::set_frame`] after
    /// it: the projection changes with the intrinsics. Host write, like `set_frame`.
    ///
    /// # Safety
    /// This writes the selected frame's host-visible uniforms: no recorded work of that frame
    /// ([`Self::select_frame`]) may be pending on the GPU (wait for its fence first), as
    /// Vulkan requires of memory the device reads. The other frames take the new camera when
    /// they are next written with [`Self::set_frame`].
    pub unsafe fn set_camera(&mut self, camera: &Camera) -> Result<()> {
        if !self.accepts_camera(camera) {
            return Err(Error::Input(
                "set_camera needs the same image size and distortion terms (and a camera whose \
                 discard bound lies inside its domain's smallest radius, if this one's did); \
                 build a new pass"
                    .into(),
            ));
        }
        self.discard_bound = discard_bound(&self.desc.projection, camera)?;
        // The line rate is the lens's, per radian of ray direction: a moved principal point
        // (a jittered pass of anti-aliasing, once per sample and frame) leaves it as it is,
        // and its cone's margin covers the sub-pixel turn of the image's widest ray. Only
        // another focal length or lens is measured again (tens of milliseconds).
        let old = &self.desc.camera;
        let same_lens = (old.intrinsics.fx, old.intrinsics.fy)
            == (camera.intrinsics.fx, camera.intrinsics.fy)
            && old.lens() == camera.lens();
        self.desc.camera = camera.clone();
        if !same_lens {
            self.line_rate = self.measure_line_rate();
        }
        // The frame block holds the old camera's projection: a jittered pass (a moved
        // principal point) drew with the previous pass's projection, and the average of the
        // passes was shifted by the last pass's offset.
        let (motion, previous) = self.last_frame.get();
        // SAFETY: the caller upholds this function's contract, which is set_frame's.
        unsafe { self.write_frame(motion, previous) }
    }

    /// Sets the pose to render from and the pose flow is measured from (and the pass's
    /// camera), for the selected frame ([`Self::select_frame`]). Host write.
    ///
    /// # Safety
    /// This writes the selected frame's host-visible uniforms: no recorded work of that frame
    /// may be pending on the GPU (wait for its fence first), as Vulkan requires of memory the
    /// device reads.
    pub unsafe fn set_frame(&self, pose: &Pose, previous: &Pose) -> Result<()> {
        // SAFETY: the caller upholds this function's contract, which is write_frame's.
        unsafe { self.write_frame(Motion::still(*pose), Motion::still(*previous)) }
    }

    /// As [`Self::set_frame`] for a camera that moves during the readout: `pose` and `end`
    /// are this frame's poses when its first and its last line are read, `previous` and
    /// `previous_end` those of the frame flow starts from. A pass built without a readout
    /// ([`GeometryDesc::readout`]) draws every line from one pose, so it refuses a frame that
    /// moves.
    ///
    /// # Safety
    /// As [`Self::set_frame`].
    pub unsafe fn set_moving_frame(
        &self,
        (pose, end): (&Pose, &Pose),
        (previous, previous_end): (&Pose, &Pose),
    ) -> Result<()> {
        let (motion, before) = (
            Motion::new(*pose, *end),
            Motion::new(*previous, *previous_end),
        );
        if self.desc.readout.is_none() && !(motion.is_still() && before.is_still()) {
            return Err(Error::Input(
                "the camera moves during the frame, but the pass was built for a global \
                 shutter (GeometryDesc::readout is None): every line would be drawn from the \
                 first line's pose"
                    .into(),
            ));
        }
        // SAFETY: the caller upholds this function's contract, which is write_frame's.
        unsafe { self.write_frame(motion, before) }
    }

    /// The line rate of the desc's camera in its readout order, as the shaders project: through
    /// the lens, or for a pinhole render through the pinhole of the same intrinsics. `None`
    /// without a readout.
    fn measure_line_rate(&self) -> Option<LineRate> {
        let readout = self.desc.readout?;
        let c = &self.desc.camera;
        match self.desc.projection {
            Projection::Lens { .. } => LineRate::measure(c, readout),
            Projection::Pinhole => {
                let pinhole = Camera::from_coeffs(c.width, c.height, c.intrinsics, &[0.0; 4]);
                LineRate::measure(&pinhole.ok()?, readout)
            }
        }
    }

    /// Writes the selected frame's uniforms.
    ///
    /// # Safety
    /// As [`Self::set_frame`].
    unsafe fn write_frame(&self, motion: Motion, previous: Motion) -> Result<()> {
        self.last_frame.set((motion, previous));
        let slot = &self.frames[self.current];
        let camera = CameraParams::from_camera(&self.desc.camera);
        slot.camera.write(0, bytemuck::bytes_of(&camera))?;
        let mut frame = self.frame_data(&self.desc.camera, self.discard_bound, motion, previous);
        if let Some(rate) = self.line_rate {
            frame.readout_bound = [rate.cone as f32, 0.0, 0.0, 0.0];
            for (i, r) in rate.per_radian.iter().enumerate() {
                frame.readout_rates[i / 4][i % 4] = *r as f32;
            }
        }
        slot.frame.write(0, bytemuck::bytes_of(&frame))
    }

    fn frame_data(
        &self,
        c: &Camera,
        discard_bound: f64,
        motion: Motion,
        previous: Motion,
    ) -> GeometryFrame {
        let p = vulkan_projection(
            &Frustum::from_intrinsics(&c.intrinsics, c.width, c.height),
            self.desc.near,
            self.desc.far,
        );
        let m = |m: DMat4| m.as_mat4().to_cols_array_2d();
        let (pose, before) = (motion.pose, previous.pose);
        GeometryFrame {
            view_projection: m(p * pose.matrix()),
            previous_view_projection: m(p * before.matrix()),
            view: m(pose.matrix()),
            viewport: [
                c.width as f32,
                c.height as f32,
                discard_bound.min(f32::MAX as f64) as f32,
                self.desc.near as f32,
            ],
            projection: m(p),
            previous_view: m(before.matrix()),
            motion: motion.gpu(),
            previous_motion: previous.gpu(),
            readout_bound: [0.0; 4],
            readout_rates: [[0.0; 4]; RATE_TABLE / 4],
        }
    }

    /// `count` extra camera-and-pose slots, so that many views (Heidrich et al.'s cells, a batch of
    /// poses) record into one command buffer: each slot has its own uniforms and descriptor
    /// set, filled with [`Self::set_slot`] and drawn with [`Self::record_slot`].
    pub fn slots(&self, count: u32) -> Result<GeometrySlots> {
        if self.discard.is_some() {
            // The discard's index buffer is the mesh's, one rewrite per draw: slots would
            // need one each. Their one user renders pinhole cells.
            return Err(Error::Unsupported(
                "slots of a lens projection need Discard::GeometryShader".into(),
            ));
        }
        let pool = DescriptorPool::for_pipeline(&self.gpu, &self.pipeline, count.max(1))?;
        let mut slots = Vec::with_capacity(count as usize);
        for _ in 0..count {
            let camera = Buffer::from_pod(
                &self.gpu,
                "geometry.slot.camera",
                &[CameraParams::from_camera(&self.desc.camera)],
                vk::BufferUsageFlags::UNIFORM_BUFFER,
            )?;
            let frame = Buffer::from_pod(
                &self.gpu,
                "geometry.slot.frame",
                &[GeometryFrame::zeroed()],
                vk::BufferUsageFlags::UNIFORM_BUFFER,
            )?;
            let set = pool.allocate(&self.pipeline)?;
            // SAFETY: the set was just allocated from a pool made for this pipeline's layout,
            // so no work uses it yet; the buffers and views are this pass's own, alive.
            unsafe {
                crate::gpu::write_buffer_descriptors(
                    &self.gpu,
                    set,
                    &[
                        (0, vk::DescriptorType::UNIFORM_BUFFER, &camera),
                        (1, vk::DescriptorType::UNIFORM_BUFFER, &frame),
                    ],
                )
            };
            slots.push(Slot { camera, frame, set });
        }
        Ok(GeometrySlots { _pool: pool, slots })
    }

    /// Fills slot `i` with `camera` (same size and terms as the pass, see
    /// [`Self::accepts_camera`]) seen from `pose`. Host write: no recorded draw of the slot
    /// may be executing.
    ///
    /// # Safety
    /// This writes a slot's host-visible uniforms: no recorded work that uses
    /// this object may be pending on the GPU (wait for its fence first), as Vulkan
    /// requires of descriptor sets and memory the device reads.
    pub unsafe fn set_slot(
        &self,
        slots: &GeometrySlots,
        i: usize,
        camera: &Camera,
        pose: &Pose,
        previous: &Pose,
    ) -> Result<()> {
        if !self.accepts_camera(camera) {
            return Err(Error::Input(
                "a slot needs the pass's image size and distortion terms".into(),
            ));
        }
        let slot = slots
            .slots
            .get(i)
            .ok_or_else(|| Error::Input(format!("no slot {i}")))?;
        let bound = discard_bound(&self.desc.projection, camera)?;
        slot.camera
            .write(0, bytemuck::bytes_of(&CameraParams::from_camera(camera)))?;
        let frame = self.frame_data(
            camera,
            bound,
            Motion::still(*pose),
            Motion::still(*previous),
        );
        slot.frame.write(0, bytemuck::bytes_of(&frame))
    }

    /// Points every slot at `mesh`'s texture.
    ///
    /// # Safety
    /// This rewrites the slots' descriptor sets: no recorded work that uses
    /// this object may be pending on the GPU (wait for its fence first), as Vulkan
    /// requires of descriptor sets and memory the device reads.
    pub unsafe fn bind_slots_mesh(&self, slots: &GeometrySlots, mesh: &MeshBuffers) {
        for slot in &slots.slots {
            // SAFETY: the caller upholds this function's contract: no pending work uses the
            // slots' sets, which have this pipeline's layout.
            unsafe { self.write_texture(slot.set, mesh) };
        }
    }

    /// Records the render pass with slot `i`'s camera and pose (see [`Self::record`]).
    ///
    /// # Safety
    /// As [`Self::record`]; the slot must be filled and its mesh texture bound.
    pub unsafe fn record_slot(
        &self,
        cmd: vk::CommandBuffer,
        targets: &GeometryTargets,
        mesh: &MeshBuffers,
        slots: &GeometrySlots,
        i: usize,
    ) {
        if let Some(slot) = slots.slots.get(i) {
            // SAFETY: the caller upholds `record_slot`'s contract (`record`'s, with the slot
            // filled and its texture bound); `slot.set` is of this pipeline's layout, allocated
            // by `slots` from a pool made for it.
            unsafe { self.record_with_set(cmd, targets, mesh, slot.set, None) }
        }
    }

    /// Points the pass at `mesh`'s texture, in every frame's set.
    ///
    /// # Safety
    /// This rewrites every frame's descriptor sets: no recorded work that uses this object
    /// may be pending on the GPU (wait for every frame's fence first), as Vulkan requires of
    /// descriptor sets the device reads. With the compute discard, its sets are pointed at
    /// the mesh's buffers too.
    pub unsafe fn bind_mesh(&mut self, mesh: &MeshBuffers) {
        for slot in &self.frames {
            // SAFETY: the caller upholds this function's contract: no pending work uses the
            // pass's sets or the discard's.
            unsafe {
                self.write_texture(slot.set, mesh);
                if let Some(set) = slot.discard_set {
                    DiscardPass::bind(&self.gpu, set, mesh);
                }
            }
        }
    }

    /// Points `set` (this pipeline's layout) at `mesh`'s texture.
    ///
    /// # Safety
    /// No pending work uses `set`.
    unsafe fn write_texture(&self, set: vk::DescriptorSet, mesh: &MeshBuffers) {
        // SAFETY: `set` has this pipeline's layout, with the texture's combined image sampler
        // at binding 2; the mesh's texture view is live; no pending work uses `set` (the
        // function's contract).
        unsafe {
            crate::gpu::write_sampled_image_descriptor(
                &self.gpu,
                set,
                2,
                &self.sampler,
                mesh.texture.image.view,
            )
        };
    }

    /// Records the render pass: clears every output, draws `mesh`, leaves the outputs in
    /// the desc's `final_layout` with the writes visible to transfers, compute and fragment
    /// shaders. With the compute discard, two dispatches come first (they bind a compute
    /// pipeline and descriptor set), each behind a global barrier: after earlier vertex-input,
    /// vertex-shader and compute work, and before this draw's index and vertex-shader reads.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass on a queue with graphics (and compute,
    /// for the compute discard); `targets` must have been made for this pass; `mesh` must be
    /// bound ([`Self::bind_mesh`]) and uploaded; all must stay alive until the work completes.
    /// The mesh's discard buffers are rewritten: no other pass's recorded draw of the same
    /// mesh may run concurrently with this one.
    pub unsafe fn record(
        &self,
        cmd: vk::CommandBuffer,
        targets: &GeometryTargets,
        mesh: &MeshBuffers,
    ) {
        let slot = &self.frames[self.current];
        // SAFETY: the caller upholds `record`'s contract, which `record_with_set` shares;
        // the slot's set is of this pipeline's layout, its uniforms written in `with_frames`.
        unsafe { self.record_with_set(cmd, targets, mesh, slot.set, slot.discard_set) }
    }

    unsafe fn record_with_set(
        &self,
        cmd: vk::CommandBuffer,
        targets: &GeometryTargets,
        mesh: &MeshBuffers,
        set: vk::DescriptorSet,
        discard_set: Option<vk::DescriptorSet>,
    ) {
        let bg = self.desc.background;
        let mut clears = Vec::new();
        let o = self.desc.outputs;
        if o.color.is_some() {
            clears.push(vk::ClearValue {
                color: vk::ClearColorValue { float32: bg },
            });
        }
        if o.ids {
            clears.push(vk::ClearValue {
                color: vk::ClearColorValue { uint32: [0; 4] },
            });
        }
        if o.flow {
            clears.push(vk::ClearValue {
                color: vk::ClearColorValue {
                    float32: [f32::NAN; 4],
                },
            });
        }
        if o.depth {
            clears.push(vk::ClearValue {
                color: vk::ClearColorValue {
                    float32: [f32::INFINITY; 4],
                },
            });
        }
        clears.push(vk::ClearValue {
            depth_stencil: vk::ClearDepthStencilValue {
                depth: 1.0,
                stencil: 0,
            },
        });
        let d = self.gpu.device();
        // SAFETY: only `record` and `record_slot` call this, under `record`'s contract: `cmd`
        // is recording outside a render pass on a graphics queue, `targets` were made for this
        // pass (their framebuffer belongs to `render_pass`), `mesh` is bound and uploaded, all
        // alive until the work completes. `clears` has one value per attachment in attachment
        // order; there are no push constants; `mesh`'s indices address its vertices (checked by
        // `Mesh::validate` in `MeshBuffers::new`); the render pass is ended here.
        let m = &mesh.discard;
        // One buffer per binding the pipeline was built with (`vertex_bindings`, in order).
        let buffers = [mesh.vertices.raw, m.positions.raw, m.motion.raw];
        let moving = self.desc.readout.is_some();
        let bound = vertex_bindings(self.discard.is_some(), self.desc.outputs.flow || moving).len();
        let indices = match (&self.discard, discard_set) {
            // SAFETY: as above, and the discard's set was written for `mesh` by `bind_mesh`
            // (the contract's "mesh must be bound"); `record_slot` never reaches here with a
            // discard (`slots` refuses).
            (Some(discard), Some(discard_set)) => unsafe {
                discard.record(&self.gpu, cmd, mesh, discard_set);
                m.kept.raw
            },
            _ => mesh.indices.raw,
        };
        unsafe {
            self.pipeline.begin(
                cmd,
                &self.render_pass,
                &targets.framebuffer,
                &clears,
                set,
                &[],
            );
            d.cmd_bind_vertex_buffers(cmd, 0, &buffers[..bound], &[0; 3][..bound]);
            d.cmd_bind_index_buffer(cmd, indices, 0, vk::IndexType::UINT32);
            d.cmd_draw_indexed(cmd, mesh.index_count, 1, 0, 0, 0);
            d.cmd_end_render_pass(cmd);
        }
    }
}

impl DiscardPass {
    /// The three stages' pipelines, specialized like the vertex shader (camera terms,
    /// DISTORT, WRITE_FLOW), and a pool for one set per frame in flight (their uniforms are
    /// the frame's own; the mesh's buffers are written by [`GeometryPass::bind_mesh`]).
    /// `rolling`: frames may move during a rolling shutter's readout, so the per-vertex stage
    /// carries the readout solve (glsl/discard.comp says why the modules differ).
    fn new(gpu: &Gpu, vertex: SpecConstants, rolling: bool, frames: usize) -> Result<Self> {
        use vk::DescriptorType as T;
        let (uniform, storage) = (T::UNIFORM_BUFFER, T::STORAGE_BUFFER);
        let mut bindings = [storage; 11];
        bindings[0] = uniform;
        bindings[1] = uniform;
        let pipeline = |stage: u32| {
            ComputePipeline::new(
                gpu,
                match (stage, rolling) {
                    (0, true) => shaders::DISCARD_COMP_BOUNDED,
                    (0, false) => shaders::DISCARD_COMP_GLOBAL,
                    (3, _) => shaders::DISCARD_COMP,
                    _ => shaders::DISCARD_COMP_INDICES,
                },
                &bindings,
                std::mem::size_of::<DiscardPush>() as u32,
                vertex.clone().u32(spec::DISCARD_STAGE, stage),
            )
        };
        let stages = [pipeline(0)?, pipeline(1)?, pipeline(2)?];
        let deferred = if rolling { Some(pipeline(3)?) } else { None };
        // One set per frame for all: their set layouts are identically defined, hence
        // compatible.
        let pool = DescriptorPool::for_pipeline(gpu, &stages[0], frames as u32)?;
        Ok(DiscardPass {
            stages,
            deferred,
            pool,
        })
    }

    /// Points `set` (a frame's discard set) at `mesh`'s buffers.
    ///
    /// # Safety
    /// No pending work uses the set ([`GeometryPass::bind_mesh`]'s contract).
    unsafe fn bind(gpu: &Gpu, set: vk::DescriptorSet, mesh: &MeshBuffers) {
        let m = &mesh.discard;
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        // SAFETY: the set has the discard pipeline's layout with these storage buffers at
        // these bindings, the buffers are the mesh's own, live; no pending work uses the set
        // (the function's contract).
        unsafe {
            crate::gpu::write_buffer_descriptors(
                gpu,
                set,
                &[
                    (2, storage, &mesh.vertices),
                    (3, storage, &m.positions),
                    (4, storage, &m.motion),
                    (5, storage, &m.dropped),
                    (6, storage, &m.incidence_start),
                    (7, storage, &m.incidence),
                    (8, storage, &mesh.indices),
                    (9, storage, &m.kept),
                    (10, storage, &m.deferred),
                ],
            )
        };
    }

    /// Records the three stages with the barriers around them: the restore of the triangles
    /// the last discard of this mesh dropped, the dropped list emptied, the per-vertex pass,
    /// the drop; after earlier draws' reads of the index and attribute buffers (they are
    /// reused every frame), and before this draw's.
    ///
    /// # Safety
    /// `cmd` is recording outside a render pass on a queue with graphics and compute; `mesh`
    /// is the mesh last bound to `set` ([`Self::bind`]) and stays alive until the work
    /// completes.
    unsafe fn record(
        &self,
        gpu: &Gpu,
        cmd: vk::CommandBuffer,
        mesh: &MeshBuffers,
        set: vk::DescriptorSet,
    ) {
        use crate::gpu::global_barrier;
        use Access::{ComputeReadWrite, IndexBuffer, IndirectBuffer, TransferWrite, VertexBuffer};
        let m = &mesh.discard;
        let none = bytemuck::bytes_of(&DiscardPush { count: 0 });
        // A discard stage: compute shaders reading and writing the buffers, in a dispatch
        // whose group count (the dropped list's header) may be read indirectly.
        let discard = [ComputeReadWrite, IndirectBuffer];
        let draw = [IndexBuffer, VertexBuffer];
        // SAFETY: the caller upholds this function's contract; the push constants are the
        // `DiscardPush` the pipelines were built with; the per-vertex dispatch covers exactly
        // the vertices the buffers were sized for in `MeshBuffers::new`, and the indirect ones
        // read `m.dropped`'s header (INDIRECT_BUFFER usage), whose group count stage 0 keeps
        // at ceil(count / 64) ≤ the vertex count / 64 + 1.
        unsafe {
            // Earlier draws of this mesh read `kept` and the attributes; earlier discards wrote
            // them and the dropped list.
            let earlier = [IndexBuffer, VertexBuffer, ComputeReadWrite, IndirectBuffer];
            global_barrier(gpu, cmd, earlier, discard);
            let [per_vertex, restore, drop] = &self.stages;
            restore.record_dispatch_indirect(cmd, set, none, &m.dropped, 0);
            // The restore has read the list (and its dispatch the header) before it is emptied;
            // its writes of `kept` come before the drop's.
            global_barrier(gpu, cmd, discard, [TransferWrite, ComputeReadWrite]);
            let header = bytemuck::cast_slice(&DROPPED_HEADER);
            gpu.device()
                .cmd_update_buffer(cmd, m.dropped.raw, 0, header);
            if self.deferred.is_some() {
                gpu.device()
                    .cmd_update_buffer(cmd, m.deferred.raw, 0, header);
            }
            global_barrier(gpu, cmd, TransferWrite, ComputeReadWrite);
            let push = DiscardPush {
                count: mesh.vertex_count,
            };
            per_vertex.record_dispatch(
                cmd,
                set,
                bytemuck::bytes_of(&push),
                (push.count.div_ceil(64).max(1), 1),
            );
            global_barrier(gpu, cmd, ComputeReadWrite, discard);
            if let Some(deferred) = &self.deferred {
                deferred.record_dispatch_indirect(cmd, set, none, &m.deferred, 0);
                global_barrier(gpu, cmd, ComputeReadWrite, discard);
            }
            drop.record_dispatch_indirect(cmd, set, none, &m.dropped, 0);
            global_barrier(gpu, cmd, ComputeReadWrite, draw);
        }
    }
}

/// Extra camera-and-pose slots of a [`GeometryPass`] ([`GeometryPass::slots`]).
pub struct GeometrySlots {
    // The sets live in the pool; the uniform buffers they point at live in the slots.
    _pool: DescriptorPool,
    slots: Vec<Slot>,
}

impl GeometrySlots {
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }
}

struct Slot {
    camera: Buffer,
    frame: Buffer,
    set: vk::DescriptorSet,
}

/// The images a [`GeometryPass`] renders into (the host reads them back with
/// `host::geometry::TargetsReadback`).
pub struct GeometryTargets {
    outputs: Outputs,
    /// By location: colour, ID, flow, depth.
    targets: [Option<Image>; 4],
    _depth_buffer: Image,
    pub framebuffer: Framebuffer,
    extent: vk::Extent2D,
}

impl GeometryTargets {
    pub fn new(gpu: &Gpu, pass: &GeometryPass) -> Result<Self> {
        let c = &pass.desc.camera;
        let extent = vk::Extent2D {
            width: c.width,
            height: c.height,
        };
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT
            | vk::ImageUsageFlags::TRANSFER_SRC
            | vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::STORAGE;
        let formats = pass.desc.outputs.formats();
        let names = [
            "geometry.color",
            "geometry.ids",
            "geometry.flow",
            "geometry.depth",
        ];
        let mut targets: [Option<Image>; 4] = Default::default();
        for (i, f) in formats.iter().enumerate() {
            if let Some(format) = *f {
                // RGBA16F is not a required storage format; it need not be one.
                let usage = if format == vk::Format::R16G16B16A16_SFLOAT {
                    usage & !vk::ImageUsageFlags::STORAGE
                } else {
                    usage
                };
                targets[i] = Some(Image::new_2d(
                    gpu,
                    names[i],
                    format,
                    extent.width,
                    extent.height,
                    usage,
                )?);
            }
        }
        let depth_buffer = Image::new_2d(
            gpu,
            "geometry.depth_buffer",
            vk::Format::D32_SFLOAT,
            extent.width,
            extent.height,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
        )?;
        let mut views: Vec<vk::ImageView> = targets.iter().flatten().map(|t| t.view).collect();
        views.push(depth_buffer.view);
        // SAFETY: the views are of images just made for this render pass's attachments,
        // `extent` large.
        let framebuffer = unsafe { Framebuffer::new(gpu, &pass.render_pass, &views, extent) }?;
        Ok(GeometryTargets {
            outputs: pass.desc.outputs,
            targets,
            _depth_buffer: depth_buffer,
            framebuffer,
            extent,
        })
    }

    /// The colour image (when rendered), e.g. as the source of a warp.
    pub fn color(&self) -> Option<&Image> {
        self.targets[0].as_ref()
    }

    /// The ID image (when rendered).
    pub fn ids(&self) -> Option<&Image> {
        self.targets[1].as_ref()
    }

    /// The camera-depth image (when rendered; R32F metres, +inf where nothing was drawn).
    pub fn depth(&self) -> Option<&Image> {
        self.targets[3].as_ref()
    }

    /// Every output by location (colour, IDs, flow, depth), those rendered. After
    /// [`GeometryPass::record`] they are in the pass's final layout (`TRANSFER_SRC_OPTIMAL` by
    /// default).
    pub fn images(&self) -> [Option<&Image>; 4] {
        self.targets.each_ref().map(Option::as_ref)
    }

    /// What the pass renders.
    pub fn outputs(&self) -> Outputs {
        self.outputs
    }

    /// The size of every output (the pass's camera).
    pub fn extent(&self) -> vk::Extent2D {
        self.extent
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn incidence_lists_each_vertexs_triangles() {
        // Two triangles sharing an edge, and a degenerate one repeating a vertex.
        let (start, triangles) = incidence(&[0, 1, 2, 2, 1, 3, 3, 3, 0], 5);
        let of = |v: usize| &triangles[start[v] as usize..start[v + 1] as usize];
        assert_eq!(of(0), [0, 2]);
        assert_eq!(of(1), [0, 1]);
        assert_eq!(of(2), [0, 1]);
        assert_eq!(of(3), [1, 2, 2]);
        assert_eq!(of(4), [] as [u32; 0]);
    }

    #[test]
    fn the_discard_reads_positions_where_the_vertex_buffer_has_them() {
        // glsl/discard.comp reads scene::Vertex as 8 floats with the position first.
        assert_eq!(std::mem::size_of::<Vertex>(), 32);
        assert_eq!(std::mem::offset_of!(Vertex, position), 0);
    }
}
