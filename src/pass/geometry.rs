//! The geometry path (Lambers et al. Sec. 3.2): meshes drawn with Alg. 1 in the vertex shader and
//! triangles outside `[-(1+δ+D), 1+δ+D]²` (undistorted NDC) dropped in a geometry shader —
//! or, for the warp path's first pass, a plain pinhole render with the Sec. 3.1 frustum.
//!
//! Outputs (Lambers et al. Table 1), each only when asked for: colour (RGBA8 or RGBA16F), object ID
//! (R32_UINT, flat, never blended), 2D flow (RG32F: pixel motion since a previous pose, NaN
//! where unknown) and camera depth (R32F, metres; +inf where nothing was drawn).
//!
//! Embedding: [`GeometryPass::record`] records one render pass into the caller's command
//! buffer on [`GeometryTargets`] (images the pass made) — the colour attachments end in the
//! desc's `final_layout`.

use crate::pass::spec;
use ash::vk;
use bytemuck::{Pod, Zeroable};
use glam::{DMat4, DVec2};
use gpu_allocator::MemoryLocation;

use super::camera_params::CameraParams;
use crate::gpu::{
    image_barrier, record_download, shaders, Attribute, Buffer, DescriptorPool, Error, Framebuffer,
    Gpu, GraphicsDesc, GraphicsPipeline, Image, RenderPass, Result, Sampler, SpecConstants, Stage,
};
use crate::imaging::{BitDepth, Pixels, Raster};
use crate::model::overscan::valid_region_boundary;
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
    /// width, height, discard bound 1 + δ + D, unused.
    pub viewport: [f32; 4],
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
            Ok(1.0 + delta + discard_margin(camera))
        }
        Projection::Pinhole => Ok(f64::INFINITY),
    }
}

/// The vertex layout of [`Vertex`].
const VERTEX_ATTRIBUTES: [Attribute; 4] = [
    (0, vk::Format::R32G32B32_SFLOAT, 0),
    (1, vk::Format::R32G32_SFLOAT, 12),
    (2, vk::Format::R8G8B8A8_UNORM, 20),
    (3, vk::Format::R32_UINT, 24),
];

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
            image_barrier(
                &self.gpu,
                cmd,
                self.image.raw,
                (
                    vk::ImageLayout::UNDEFINED,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                ),
                (
                    vk::PipelineStageFlags::TOP_OF_PIPE,
                    vk::AccessFlags::empty(),
                ),
                (
                    vk::PipelineStageFlags::TRANSFER,
                    vk::AccessFlags::TRANSFER_WRITE,
                ),
            );
            self.gpu.device().cmd_copy_buffer_to_image(
                cmd,
                self.staging.raw,
                self.image.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[self.image.whole_copy()],
            );
            image_barrier(
                &self.gpu,
                cmd,
                self.image.raw,
                (
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                ),
                (
                    vk::PipelineStageFlags::TRANSFER,
                    vk::AccessFlags::TRANSFER_WRITE,
                ),
                (
                    vk::PipelineStageFlags::FRAGMENT_SHADER,
                    vk::AccessFlags::SHADER_READ,
                ),
            );
        }
    }
}

/// A mesh on the GPU: vertex and index buffers and its texture (white if it has none).
pub struct MeshBuffers {
    pub vertices: Buffer,
    pub indices: Buffer,
    pub index_count: u32,
    pub texture: Texture,
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
        Ok(MeshBuffers {
            vertices: Buffer::from_pod(
                gpu,
                "mesh.vertices",
                &mesh.vertices,
                vk::BufferUsageFlags::VERTEX_BUFFER,
            )?,
            indices: Buffer::from_pod(
                gpu,
                "mesh.indices",
                &mesh.indices,
                vk::BufferUsageFlags::INDEX_BUFFER,
            )?,
            index_count: mesh.indices.len() as u32,
            texture: Texture::new(gpu, texture.unwrap_or(&white))?,
        })
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
    set: vk::DescriptorSet,
    pipeline: GraphicsPipeline,
    render_pass: RenderPass,
    camera: Buffer,
    frame: Buffer,
    sampler: Sampler,
    discard_bound: f64,
}

impl GeometryPass {
    pub fn new(gpu: &Gpu, desc: GeometryDesc) -> Result<Self> {
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
        let vertex_constants =
            CameraParams::spec_constants(cam.distortion.terms()).bool(spec::DISTORT, lens);
        let o = desc.outputs;
        let fragment_constants = SpecConstants::new()
            .bool(spec::WRITE_COLOR, o.color.is_some())
            .bool(spec::WRITE_IDS, o.ids)
            .bool(spec::WRITE_FLOW, o.flow)
            .bool(spec::WRITE_DEPTH, o.depth);
        let mut stages = vec![Stage {
            stage: vk::ShaderStageFlags::VERTEX,
            spirv: if lens {
                shaders::GEOMETRY_VERT
            } else {
                shaders::GEOMETRY_VERT_PINHOLE
            },
            constants: vertex_constants,
        }];
        if lens {
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
                vertex: Some((std::mem::size_of::<Vertex>() as u32, &VERTEX_ATTRIBUTES)),
                render_pass: &render_pass,
                depth_test: true,
                push_size: 0,
                additive: false,
            },
        )?;
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
        let pool = DescriptorPool::for_pipeline(gpu, &pipeline, 1)?;
        let set = pool.allocate(&pipeline)?;
        crate::gpu::write_buffer_descriptors(
            gpu,
            set,
            &[
                (0, vk::DescriptorType::UNIFORM_BUFFER, &camera),
                (1, vk::DescriptorType::UNIFORM_BUFFER, &frame),
            ],
        );
        let pass = GeometryPass {
            gpu: gpu.clone(),
            sampler: Sampler::new(gpu, vk::Filter::LINEAR, vk::SamplerAddressMode::REPEAT)?,
            desc,
            _pool: pool,
            set,
            pipeline,
            render_pass,
            camera,
            frame,
            discard_bound,
        };
        // SAFETY: no submission using it is pending (`submit` waits on its fence).
        unsafe { pass.set_frame(&Pose::IDENTITY, &Pose::IDENTITY) }?;
        Ok(pass)
    }

    pub fn desc(&self) -> &GeometryDesc {
        &self.desc
    }

    /// The pipeline (its specialization constants show what was compiled in).
    pub fn pipeline(&self) -> &GraphicsPipeline {
        &self.pipeline
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
            && c.distortion.terms() == camera.distortion.terms()
    }

    /// Switches to another camera of the same size and terms without rebuilding the pipeline
    /// (jittered passes, a calibration set's views, a zoom). Call [`Self::set_frame`] after
    /// it: the projection changes with the intrinsics. Host write, like `set_frame`.
    ///
    /// # Safety
    /// This writes the pass's host-visible camera uniform: no recorded work that uses
    /// this object may be pending on the GPU (wait for its fence first), as Vulkan
    /// requires of descriptor sets and memory the device reads.
    pub unsafe fn set_camera(&mut self, camera: &Camera) -> Result<()> {
        if !self.accepts_camera(camera) {
            return Err(Error::Input(
                "set_camera needs the same image size and distortion terms; build a new pass"
                    .into(),
            ));
        }
        self.discard_bound = discard_bound(&self.desc.projection, camera)?;
        self.camera
            .write(0, bytemuck::bytes_of(&CameraParams::from_camera(camera)))?;
        self.desc.camera = camera.clone();
        Ok(())
    }

    /// Sets the pose to render from and the pose flow is measured from. Host write: call it
    /// while no recorded draw of this pass is executing.
    ///
    /// # Safety
    /// This writes the pass's host-visible pose uniform: no recorded work that uses
    /// this object may be pending on the GPU (wait for its fence first), as Vulkan
    /// requires of descriptor sets and memory the device reads.
    pub unsafe fn set_frame(&self, pose: &Pose, previous: &Pose) -> Result<()> {
        let frame = self.frame_data(&self.desc.camera, self.discard_bound, pose, previous);
        self.frame.write(0, bytemuck::bytes_of(&frame))
    }

    fn frame_data(
        &self,
        c: &Camera,
        discard_bound: f64,
        pose: &Pose,
        previous: &Pose,
    ) -> GeometryFrame {
        let p = vulkan_projection(
            &Frustum::from_intrinsics(&c.intrinsics, c.width, c.height),
            self.desc.near,
            self.desc.far,
        );
        let m = |m: DMat4| m.as_mat4().to_cols_array_2d();
        GeometryFrame {
            view_projection: m(p * pose.matrix()),
            previous_view_projection: m(p * previous.matrix()),
            view: m(pose.matrix()),
            viewport: [
                c.width as f32,
                c.height as f32,
                discard_bound.min(f32::MAX as f64) as f32,
                0.0,
            ],
        }
    }

    /// `count` extra camera-and-pose slots, so that many views (Heidrich et al.'s cells, a batch of
    /// poses) record into one command buffer: each slot has its own uniforms and descriptor
    /// set, filled with [`Self::set_slot`] and drawn with [`Self::record_slot`].
    pub fn slots(&self, count: u32) -> Result<GeometrySlots> {
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
            crate::gpu::write_buffer_descriptors(
                &self.gpu,
                set,
                &[
                    (0, vk::DescriptorType::UNIFORM_BUFFER, &camera),
                    (1, vk::DescriptorType::UNIFORM_BUFFER, &frame),
                ],
            );
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
        let frame = self.frame_data(camera, bound, pose, previous);
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
            self.write_texture(slot.set, mesh);
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
            unsafe { self.record_with_set(cmd, targets, mesh, slot.set) }
        }
    }

    /// Points the pass at `mesh`'s texture.
    ///
    /// # Safety
    /// This rewrites the pass's descriptor set: no recorded work that uses
    /// this object may be pending on the GPU (wait for its fence first), as Vulkan
    /// requires of descriptor sets and memory the device reads.
    pub unsafe fn bind_mesh(&mut self, mesh: &MeshBuffers) {
        self.write_texture(self.set, mesh);
    }

    fn write_texture(&self, set: vk::DescriptorSet, mesh: &MeshBuffers) {
        let info = [vk::DescriptorImageInfo {
            sampler: self.sampler.raw,
            image_view: mesh.texture.image.view,
            image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
        }];
        let write = vk::WriteDescriptorSet::default()
            .dst_set(set)
            .dst_binding(2)
            .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
            .image_info(&info);
        // SAFETY: `set` is this pass's own or a slot's, of this layout, whose binding 2 is a
        // combined image sampler; the sampler and `mesh`'s texture view are live objects of
        // this device and `info` outlives the call. That no pending work uses `set` is the
        // caller's duty (documented on `set_frame`/`set_slot`; this safe method cannot check).
        unsafe { self.gpu.device().update_descriptor_sets(&[write], &[]) };
    }

    /// Records the render pass: clears every output, draws `mesh`, leaves the outputs in
    /// the desc's `final_layout` with the writes visible to transfers, compute and fragment
    /// shaders.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass on a graphics queue; `targets` must have
    /// been made for this pass; `mesh` must be bound ([`Self::bind_mesh`]) and uploaded; all
    /// must stay alive until the work completes.
    pub unsafe fn record(
        &self,
        cmd: vk::CommandBuffer,
        targets: &GeometryTargets,
        mesh: &MeshBuffers,
    ) {
        // SAFETY: the caller upholds `record`'s contract, which `record_with_set` shares;
        // `self.set` is of this pipeline's layout, its uniforms written in `new`.
        unsafe { self.record_with_set(cmd, targets, mesh, self.set) }
    }

    unsafe fn record_with_set(
        &self,
        cmd: vk::CommandBuffer,
        targets: &GeometryTargets,
        mesh: &MeshBuffers,
        set: vk::DescriptorSet,
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
        unsafe {
            self.pipeline.begin(
                cmd,
                &self.render_pass,
                &targets.framebuffer,
                &clears,
                set,
                &[],
            );
            d.cmd_bind_vertex_buffers(cmd, 0, &[mesh.vertices.raw], &[0]);
            d.cmd_bind_index_buffer(cmd, mesh.indices.raw, 0, vk::IndexType::UINT32);
            d.cmd_draw_indexed(cmd, mesh.index_count, 1, 0, 0, 0);
            d.cmd_end_render_pass(cmd);
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

/// One output image and the host buffer it is read back into.
struct Target {
    image: Image,
    download: Buffer,
}

/// The images a [`GeometryPass`] renders into, with host buffers to read them back.
pub struct GeometryTargets {
    gpu: Gpu,
    outputs: Outputs,
    /// By location: colour, ID, flow, depth.
    targets: [Option<Target>; 4],
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
        let mut targets: [Option<Target>; 4] = Default::default();
        for (i, f) in formats.iter().enumerate() {
            if let Some(format) = *f {
                let bytes_per_pixel = match format {
                    vk::Format::R16G16B16A16_SFLOAT | vk::Format::R32G32_SFLOAT => 8,
                    vk::Format::R32G32B32A32_SFLOAT => 16,
                    _ => 4,
                };
                // RGBA16F is not a required storage format; it need not be one.
                let usage = if format == vk::Format::R16G16B16A16_SFLOAT {
                    usage & !vk::ImageUsageFlags::STORAGE
                } else {
                    usage
                };
                targets[i] = Some(Target {
                    image: Image::new_2d(
                        gpu,
                        names[i],
                        format,
                        extent.width,
                        extent.height,
                        usage,
                    )?,
                    download: Buffer::new(
                        gpu,
                        names[i],
                        extent.width as u64 * extent.height as u64 * bytes_per_pixel,
                        vk::BufferUsageFlags::TRANSFER_DST,
                        MemoryLocation::GpuToCpu,
                    )?,
                });
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
        let mut views: Vec<vk::ImageView> =
            targets.iter().flatten().map(|t| t.image.view).collect();
        views.push(depth_buffer.view);
        let framebuffer = Framebuffer::new(gpu, &pass.render_pass, &views, extent)?;
        Ok(GeometryTargets {
            gpu: gpu.clone(),
            outputs: pass.desc.outputs,
            targets,
            _depth_buffer: depth_buffer,
            framebuffer,
            extent,
        })
    }

    /// The colour image (when rendered), e.g. as the source of a warp.
    pub fn color(&self) -> Option<&Image> {
        self.targets[0].as_ref().map(|t| &t.image)
    }

    /// The ID image (when rendered).
    pub fn ids(&self) -> Option<&Image> {
        self.targets[1].as_ref().map(|t| &t.image)
    }

    /// The camera-depth image (when rendered; R32F metres, +inf where nothing was drawn).
    pub fn depth(&self) -> Option<&Image> {
        self.targets[3].as_ref().map(|t| &t.image)
    }

    /// Records the copies of every output into its host buffer. The outputs must be in
    /// `TRANSFER_SRC_OPTIMAL` (the default final layout).
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass, after [`GeometryPass::record`].
    pub unsafe fn record_download(&self, cmd: vk::CommandBuffer) {
        for t in self.targets.iter().flatten() {
            // SAFETY: the caller upholds `record_download`'s contract: `cmd` is recording
            // outside a render pass after `GeometryPass::record`, with the outputs in
            // TRANSFER_SRC_OPTIMAL (the doc's precondition); each `download` was sized for its
            // image's format in `new`, and every output image has TRANSFER_SRC usage.
            unsafe { record_download(&self.gpu, cmd, &t.image, &t.download) };
        }
    }

    /// Reads the outputs back (after the submission completed).
    pub fn read(&self) -> Result<Rendered> {
        let (w, h) = (self.extent.width, self.extent.height);
        let n = w as usize * h as usize;
        let mut out = Rendered {
            width: w,
            height: h,
            ..Default::default()
        };
        if let Some(t) = &self.targets[0] {
            let pixels = match self.outputs.color {
                Some(ColorFormat::Rgba32F) => Pixels::Rgba32F(t.download.read_pod::<[f32; 4]>(n)?),
                Some(ColorFormat::Rgba16F) => {
                    let halves = t.download.read_pod::<[u16; 4]>(n)?;
                    Pixels::Rgba32F(halves.iter().map(|p| p.map(f16_to_f32)).collect())
                }
                _ => Pixels::Rgba8(t.download.read_pod::<[u8; 4]>(n)?),
            };
            let depth = if matches!(pixels, Pixels::Rgba8(_)) {
                BitDepth::U8
            } else {
                BitDepth::F32
            };
            out.color = Some(Raster {
                width: w,
                height: h,
                pixels,
                bit_depth: depth,
            });
        }
        if let Some(t) = &self.targets[1] {
            out.ids = Some(t.download.read_pod::<u32>(n)?);
        }
        if let Some(t) = &self.targets[2] {
            out.flow = Some(t.download.read_pod::<[f32; 2]>(n)?);
        }
        if let Some(t) = &self.targets[3] {
            out.depth = Some(t.download.read_pod::<f32>(n)?);
        }
        Ok(out)
    }
}

/// IEEE half → f32 (RGBA16F readback).
fn f16_to_f32(h: u16) -> f32 {
    let sign = ((h >> 15) as u32) << 31;
    let exp = ((h >> 10) & 0x1f) as u32;
    let frac = (h & 0x3ff) as u32;
    let bits = match (exp, frac) {
        (0, 0) => sign,
        (0, _) => {
            // Subnormal: frac × 2⁻²⁴.
            let magnitude = frac as f32 * 2f32.powi(-24);
            return if sign != 0 { -magnitude } else { magnitude };
        }
        (31, 0) => sign | 0x7f80_0000,
        (31, _) => sign | 0x7fc0_0000,
        _ => sign | ((exp + 112) << 23) | (frac << 13),
    };
    f32::from_bits(bits)
}

/// Host copies of a geometry render.
#[derive(Debug, Clone, Default)]
pub struct Rendered {
    pub width: u32,
    pub height: u32,
    pub color: Option<Raster>,
    /// Object IDs, 0 = background.
    pub ids: Option<Vec<u32>>,
    /// Pixel motion since the previous pose; NaN where unknown or background.
    pub flow: Option<Vec<[f32; 2]>>,
    /// Camera-frame z in metres; +inf where nothing was drawn.
    pub depth: Option<Vec<f32>>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_floats_convert() {
        assert_eq!(f16_to_f32(0x3c00), 1.0);
        assert_eq!(f16_to_f32(0xc000), -2.0);
        assert_eq!(f16_to_f32(0x3800), 0.5);
        assert!(f16_to_f32(0x7e00).is_nan());
        assert_eq!(f16_to_f32(0x7c00), f32::INFINITY);
        assert_eq!(f16_to_f32(0x0001), 2f32.powi(-24));
        assert_eq!(f16_to_f32(0x8001), -(2f32.powi(-24)));
    }
}
