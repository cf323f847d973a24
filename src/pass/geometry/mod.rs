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
use glam::{DMat4, DVec2, DVec3};
use gpu_allocator::MemoryLocation;

use super::camera_params::CameraParams;
use crate::gpu::{
    shaders, Access, Attribute, Buffer, ComputePipeline, DescriptorPool, Error, Framebuffer, Gpu,
    GraphicsDesc, GraphicsPipeline, Image, RenderPass, Result, Sampler, SpecConstants, Stage,
    VertexBinding,
};
pub use crate::imaging::Rendered;
use crate::imaging::{BitDepth, Pixels, Raster};
use crate::model::overscan::valid_region_boundary;
use crate::model::rolling_shutter::{FrameMotion, LineRate, Readout, RATE_TABLE};
use crate::model::{vulkan_projection, Camera, Frustum};
use crate::scene::{Mesh, Pose, Vertex};

mod discard;
mod frame;
mod mesh;
mod targets;

use discard::{discard_bound, DiscardPass};
pub use discard::{discard_margin, discard_needs_domain_table, vertex_kept, DiscardPush};
use frame::Motion;
pub use frame::{GeometryFrame, MotionGpu};
use mesh::vertex_bindings;
pub use mesh::{MeshBuffers, Texture};
use targets::Slot;
pub use targets::{GeometrySlots, GeometryTargets};

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
    /// Camera-frame z (metres).
    pub depth: bool,
    /// Distance from the projection centre along the pixel's ray (metres).
    pub range: bool,
}

impl Outputs {
    pub const COLOR: Outputs = Outputs {
        color: Some(ColorFormat::Rgba8),
        ids: false,
        flow: false,
        depth: false,
        range: false,
    };

    /// Colour in `format` only (no output when `None`).
    pub fn color_only(format: Option<ColorFormat>) -> Outputs {
        Outputs {
            color: format,
            ids: false,
            flow: false,
            depth: false,
            range: false,
        }
    }

    /// Attachment formats by fragment-output location (0 colour, 1 ID, 2 flow, 3 depth,
    /// 4 range).
    fn formats(&self) -> [Option<vk::Format>; 5] {
        [
            self.color.map(|c| match c {
                ColorFormat::Rgba8 => vk::Format::R8G8B8A8_UNORM,
                ColorFormat::Rgba16F => vk::Format::R16G16B16A16_SFLOAT,
                ColorFormat::Rgba32F => vk::Format::R32G32B32A32_SFLOAT,
            }),
            self.ids.then_some(vk::Format::R32_UINT),
            self.flow.then_some(vk::Format::R32G32_SFLOAT),
            self.depth.then_some(vk::Format::R32_SFLOAT),
            self.range.then_some(vk::Format::R32_SFLOAT),
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

/// The near clipping depth of a [`GeometryDesc`] (metres).
pub const DEFAULT_NEAR: f64 = 0.01;

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
            near: DEFAULT_NEAR,
            far: 1000.0,
            background: [0.0; 4],
            final_layout: vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            discard: Discard::Auto,
            readout: None,
        }
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

impl GeometryPass {
    pub fn new(gpu: &Gpu, desc: GeometryDesc) -> Result<Self> {
        Self::with_frames(gpu, desc, 1)
    }

    /// As [`GeometryPass::new`], with uniforms and descriptor sets for `frames` frames in
    /// flight (1 to [`MAX_FRAMES_IN_FLIGHT`]), chosen by [`Self::select_frame`]. The mesh's
    /// discard buffers are shared: the frames must run on one queue, in the order recorded
    /// (the barriers `record` records order them there).
    pub fn with_frames(gpu: &Gpu, desc: GeometryDesc, frames: usize) -> Result<Self> {
        check_desc(gpu, &desc, frames)?;
        let cam = &desc.camera;
        let lens = matches!(desc.projection, Projection::Lens { .. });
        let discard_bound = discard_bound(&desc.projection, cam)?;
        let formats = desc.outputs.formats();
        let render_pass = RenderPass::new(
            gpu,
            &formats,
            Some(vk::Format::D32_SFLOAT),
            desc.final_layout,
        )?;
        let vertex_constants = CameraParams::spec_constants(cam.terms())
            .bool(spec::DISTORT, lens)
            .bool(spec::WRITE_FLOW, desc.outputs.flow)
            .u32(spec::READOUT, desc.readout.map_or(0, Readout::gpu_id))
            .bool(spec::SEAM_BEHIND, cam.has_seam());
        let o = desc.outputs;
        let outputs_constants = |c: SpecConstants| {
            c.bool(spec::WRITE_COLOR, o.color.is_some())
                .bool(spec::WRITE_IDS, o.ids)
                .bool(spec::WRITE_FLOW, o.flow)
                .bool(spec::WRITE_DEPTH, o.depth)
                .bool(spec::WRITE_RANGE, o.range)
        };
        // Through a lens, depth and range are recomputed on each pixel's own ray, which needs
        // the camera's inverse model in the fragment stage: only where they are asked for.
        // Under a moving rolling shutter each vertex is drawn from its own readout time, no
        // one pose's ray reaches the triangle, and they stay interpolated.
        let exact_depth = lens && (o.depth || o.range) && desc.readout.is_none();
        let geometry_stage = lens && desc.discard.resolve_for(gpu) == Discard::GeometryShader;
        // With the compute discard, Alg. 1 runs there once per vertex and pose, and the draw
        // reads its positions and flow as vertex attributes.
        let pulled = lens && !geometry_stage;
        // The pulled draw of a moving rolling shutter reads each vertex's solved readout time
        // from the motion binding, flow or not.
        let flow = desc.outputs.flow || desc.readout.is_some();
        // The modules of the camera's model alone (the one its `MODEL` constant names).
        let model = cam.model().gpu_id() as usize;
        let mut stages = vec![Stage {
            stage: vk::ShaderStageFlags::VERTEX,
            spirv: match (geometry_stage, pulled, flow) {
                (true, _, _) if desc.readout.is_some() => &shaders::GEOMETRY_VERT_BY_MODEL,
                (true, _, _) => &shaders::GEOMETRY_VERT_GLOBAL_BY_MODEL,
                (_, true, true) => &shaders::GEOMETRY_VERT_PULLED_FLOW_BY_MODEL,
                (_, true, false) => &shaders::GEOMETRY_VERT_PULLED_BY_MODEL,
                _ if desc.readout.is_none() => &shaders::GEOMETRY_VERT_PLAIN_BY_MODEL,
                _ => &shaders::GEOMETRY_VERT_PINHOLE_BY_MODEL,
            }[model],
            constants: vertex_constants.clone(),
        }];
        if geometry_stage {
            stages.push(Stage {
                stage: vk::ShaderStageFlags::GEOMETRY,
                spirv: shaders::GEOMETRY_GEOM,
                constants: SpecConstants::new().bool(spec::SEAM_BEHIND, cam.has_seam()),
            });
        }
        stages.push(if exact_depth {
            Stage {
                stage: vk::ShaderStageFlags::FRAGMENT,
                spirv: shaders::GEOMETRY_EXACT_FRAG_BY_MODEL[model],
                constants: outputs_constants(CameraParams::spec_constants(cam.terms())),
            }
        } else {
            Stage {
                stage: vk::ShaderStageFlags::FRAGMENT,
                spirv: shaders::GEOMETRY_FRAG,
                constants: outputs_constants(SpecConstants::new()),
            }
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
                model,
                desc.readout.is_some(),
                frames,
            )?)
        } else {
            None
        };
        let (pool, slots) = frame_slots(gpu, cam, &pipeline, discard.as_ref(), frames)?;
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
        // Depth and range: +inf where nothing is drawn.
        for _ in 0..(o.depth as usize + o.range as usize) {
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

/// Refuses a desc and frame count the pass cannot render.
fn check_desc(gpu: &Gpu, desc: &GeometryDesc, frames: usize) -> Result<()> {
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
    if desc.outputs.formats().iter().all(|f| f.is_none()) {
        return Err(Error::Input("no output was asked for".into()));
    }
    Ok(())
}

/// One [`FrameSlot`] per frame in flight, its sets allocated from the returned pool and
/// pointed at its own uniforms (the compute discard's too, where the pass has it).
fn frame_slots(
    gpu: &Gpu,
    cam: &Camera,
    pipeline: &GraphicsPipeline,
    discard: Option<&DiscardPass>,
    frames: usize,
) -> Result<(DescriptorPool, Vec<FrameSlot>)> {
    let pool = DescriptorPool::for_pipeline(gpu, pipeline, frames as u32)?;
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
        let set = pool.allocate(pipeline)?;
        let uniforms = [(0, uniform, &camera), (1, uniform, &frame)];
        // SAFETY: the set was just allocated from a pool made for this pipeline's layout,
        // so no work uses it yet; the buffers are this pass's own, alive.
        unsafe { crate::gpu::write_buffer_descriptors(gpu, set, &uniforms) };
        let discard_set = match discard {
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
    Ok((pool, slots))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_discard_reads_positions_where_the_vertex_buffer_has_them() {
        // glsl/discard.comp reads scene::Vertex as 8 floats with the position first.
        assert_eq!(std::mem::size_of::<Vertex>(), 32);
        assert_eq!(std::mem::offset_of!(Vertex, position), 0);
    }
}
