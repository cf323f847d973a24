//! The warp from a 360° source (`glsl/sphere_warp.comp`): a cube map of six pinhole faces or an
//! equirectangular panorama, sampled by the ray each output pixel sees. It renders what no
//! single pinhole source can hold: fisheyes of 180° and more, and wide standard-model lenses
//! whose overscanned source would exceed the device's image limit.
//!
//! # Face convention
//!
//! Faces are named in the OpenCV camera frame of the output camera (x right, y down, z
//! forward): `+z` looks ahead, `+x` right, `+y` down. Each face is a square pinhole image of
//! side `S`, `fx = fy = S / 2`, `cx = cy = (S − 1) / 2` (90° across), seen from the centre,
//! whose camera is the rotation [`CubeFace::rotation`] of the output camera: a point `r` of the
//! camera frame is at `R r` in the face's camera frame. The up direction of each image:
//!
//! | face | looks along | image right | image down |
//! |------|-------------|-------------|------------|
//! | `+x` | +x | −z | +y |
//! | `-x` | −x | +z | +y |
//! | `+y` | +y (down) | +x | −z |
//! | `-y` | −y (up) | +x | +z |
//! | `+z` | +z | +x | +y |
//! | `-z` | −z | −x | +y |
//!
//! A horizontal cross (4 × 3 faces) holds them as
//! ```text
//!         [-y]
//!   [-x]  [+z]  [+x]  [-z]
//!         [+y]
//! ```
//!
//! # Panorama convention
//!
//! Longitude runs left to right from −180° to +180°, 0 straight ahead (+z), +90° to the right
//! (+x); latitude top to bottom from −90° (straight up, −y) to +90°.

use ash::vk;
use bytemuck::{Pod, Zeroable};
use glam::{DMat3, DVec3};

use super::camera_params::CameraParams;
use super::spec;
use crate::gpu::{
    shaders, write_storage_image_descriptors, Buffer, ComputePipeline, DescriptorPool, Error, Gpu,
    Result, Sampler,
};
use crate::model::{Camera, Intrinsics};

/// A cube face, by the direction it looks along in the camera frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CubeFace {
    PosX,
    NegX,
    PosY,
    NegY,
    PosZ,
    NegZ,
}

impl CubeFace {
    /// Every face, in the order of file lists (`+x -x +y -y +z -z`).
    pub const ALL: [CubeFace; 6] = [
        CubeFace::PosX,
        CubeFace::NegX,
        CubeFace::PosY,
        CubeFace::NegY,
        CubeFace::PosZ,
        CubeFace::NegZ,
    ];

    /// The face's name as files and messages spell it.
    pub fn name(self) -> &'static str {
        match self {
            CubeFace::PosX => "+x",
            CubeFace::NegX => "-x",
            CubeFace::PosY => "+y",
            CubeFace::NegY => "-y",
            CubeFace::PosZ => "+z",
            CubeFace::NegZ => "-z",
        }
    }

    /// Camera frame → the face camera's frame (rows: the face's image right, image down and
    /// viewing direction, in camera coordinates).
    pub fn rotation(self) -> DMat3 {
        let (right, down, along) = match self {
            CubeFace::PosX => (DVec3::NEG_Z, DVec3::Y, DVec3::X),
            CubeFace::NegX => (DVec3::Z, DVec3::Y, DVec3::NEG_X),
            CubeFace::PosY => (DVec3::X, DVec3::NEG_Z, DVec3::Y),
            CubeFace::NegY => (DVec3::X, DVec3::Z, DVec3::NEG_Y),
            CubeFace::PosZ => (DVec3::X, DVec3::Y, DVec3::Z),
            CubeFace::NegZ => (DVec3::NEG_X, DVec3::Y, DVec3::NEG_Z),
        };
        DMat3::from_cols(right, down, along).transpose()
    }

    /// The layer of the Vulkan cube image that holds this face. Vulkan addresses cubes y-up
    /// (the shader looks up (x, −y, z)), so the camera's +y (down) is Vulkan's −Y layer.
    pub fn layer(self) -> u32 {
        match self {
            CubeFace::PosX => 0,
            CubeFace::NegX => 1,
            CubeFace::NegY => 2,
            CubeFace::PosY => 3,
            CubeFace::PosZ => 4,
            CubeFace::NegZ => 5,
        }
    }

    /// The face's cell (column, row) in a horizontal cross of 4 × 3 faces.
    pub fn cross_cell(self) -> (u32, u32) {
        match self {
            CubeFace::NegY => (1, 0),
            CubeFace::NegX => (0, 1),
            CubeFace::PosZ => (1, 1),
            CubeFace::PosX => (2, 1),
            CubeFace::NegZ => (3, 1),
            CubeFace::PosY => (1, 2),
        }
    }

    /// The pinhole camera of a face of side `side` (90° across).
    pub fn camera(side: u32) -> Result<Camera> {
        let f = side as f64 / 2.0;
        let c = (side as f64 - 1.0) / 2.0;
        Camera::from_coeffs(
            side,
            side,
            Intrinsics {
                fx: f,
                fy: f,
                cx: c,
                cy: c,
            },
            &[0.0; 5],
        )
        .map_err(|e| Error::Input(e.to_string()))
    }
}

/// The unit direction an equirectangular panorama's pixel `(u, v)` (OpenCV convention) shows.
pub fn equirect_direction(u: f64, v: f64, (w, h): (u32, u32)) -> DVec3 {
    let lon = ((u + 0.5) / w as f64 - 0.5) * std::f64::consts::TAU;
    let lat = ((v + 0.5) / h as f64 - 0.5) * std::f64::consts::PI;
    DVec3::new(lat.cos() * lon.sin(), lat.sin(), lat.cos() * lon.cos())
}

/// `layout(push_constant) uniform SpherePush` of `glsl/sphere_warp.comp`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct SpherePush {
    /// Per-channel magnification R G B, -.
    pub chromatic: [f32; 4],
    /// Value of pixels without a source.
    pub fill: [f32; 4],
    /// -, -, output width, output height.
    pub sizes: [u32; 4],
    /// The output pixels a dispatch covers: `[x0, y0, x1, y1]`, x1 and y1 excluded (the whole
    /// output, or a band of a rolling shutter's lines).
    pub band: [u32; 4],
}

/// Options of one sphere warp.
#[derive(Debug, Clone)]
pub struct SphereWarpOptions {
    /// Per-channel magnification (R, G, B) for lateral chromatic aberration; `None`: off.
    pub chromatic: Option<[f64; 3]>,
    /// Value of pixels without a source (outside the lens's domain).
    pub fill: [f32; 4],
    /// Whether the mask is written.
    pub write_mask: bool,
}

/// The compute pipeline of the sphere warp for one camera and source kind.
pub struct SphereWarpPass {
    gpu: Gpu,
    pipeline: ComputePipeline,
    _pool: DescriptorPool,
    set: vk::DescriptorSet,
    sampler: Sampler,
    camera: Buffer,
    push: SpherePush,
    output_size: (u32, u32),
    /// The terms compiled in.
    terms: crate::model::Terms,
}

impl SphereWarpPass {
    /// Builds the pipeline for `camera` (the output's lens) sampling a cube (`equirect` false)
    /// or a panorama, into an RGBA32F target.
    pub fn new(
        gpu: &Gpu,
        camera: &Camera,
        equirect: bool,
        options: &SphereWarpOptions,
    ) -> Result<Self> {
        Self::with_target(gpu, camera, equirect, options, false)
    }

    /// [`Self::new`], into an RGBA8 target where `eight_bit` (from a cube only).
    pub fn with_target(
        gpu: &Gpu,
        camera: &Camera,
        equirect: bool,
        options: &SphereWarpOptions,
        eight_bit: bool,
    ) -> Result<Self> {
        let constants = CameraParams::spec_constants(camera.terms())
            .bool(spec::CHROMATIC, options.chromatic.is_some())
            .bool(spec::WRITE_MASK, options.write_mask);
        // The module of the camera's model alone.
        let by_model = match (equirect, eight_bit) {
            (true, false) => &shaders::SPHERE_WARP_COMP_EQUIRECT_BY_MODEL,
            (false, false) => &shaders::SPHERE_WARP_COMP_BY_MODEL,
            (false, true) => &shaders::SPHERE_WARP_COMP_RGBA8_BY_MODEL,
            (true, true) => return Err(Error::internal("the panorama warp writes RGBA32F only")),
        };
        let spirv = by_model[camera.model().gpu_id() as usize];
        let pipeline = ComputePipeline::new(
            gpu,
            spirv,
            &[
                vk::DescriptorType::UNIFORM_BUFFER,
                vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
                vk::DescriptorType::STORAGE_IMAGE,
                vk::DescriptorType::STORAGE_IMAGE,
            ],
            std::mem::size_of::<SpherePush>() as u32,
            constants,
        )?;
        let pool = DescriptorPool::for_pipeline(gpu, &pipeline, 1)?;
        let set = pool.allocate(&pipeline)?;
        // A cube is filtered across its faces whatever the address mode (CLAMP_TO_EDGE, as
        // the spec asks); a panorama wraps in longitude and clamps at the poles.
        let modes = if equirect {
            [
                vk::SamplerAddressMode::REPEAT,
                vk::SamplerAddressMode::CLAMP_TO_EDGE,
                vk::SamplerAddressMode::CLAMP_TO_EDGE,
            ]
        } else {
            [vk::SamplerAddressMode::CLAMP_TO_EDGE; 3]
        };
        let sampler = Sampler::with_modes(gpu, vk::Filter::LINEAR, modes)?;
        let camera_buf = Buffer::from_pod(
            gpu,
            "sphere_warp.camera",
            &[CameraParams::from_camera(camera)],
            vk::BufferUsageFlags::UNIFORM_BUFFER,
        )?;
        let [r, g, b] = options.chromatic.unwrap_or([1.0; 3]).map(|v| v as f32);
        Ok(SphereWarpPass {
            gpu: gpu.clone(),
            pipeline,
            _pool: pool,
            set,
            sampler,
            camera: camera_buf,
            push: SpherePush {
                chromatic: [r, g, b, 0.0],
                fill: options.fill,
                sizes: [0, 0, camera.width, camera.height],
                band: [0, 0, camera.width, camera.height],
            },
            output_size: (camera.width, camera.height),
            terms: camera.terms(),
        })
    }

    /// The pipeline (its specialization constants show what was compiled in).
    pub fn pipeline(&self) -> &ComputePipeline {
        &self.pipeline
    }

    /// Moves the warp to another lens camera of the same size and terms (the terms are
    /// compiled in): a jittered pass of anti-aliasing.
    ///
    /// # Safety
    /// A host write to the camera uniform: no recorded work using this pass may be pending.
    pub unsafe fn set_camera(&mut self, camera: &Camera) -> Result<()> {
        let (w, h) = self.output_size;
        if (camera.width, camera.height) != (w, h) || camera.terms() != self.terms {
            return Err(Error::Input(
                "the sphere warp takes a camera of the size and terms it was built for".into(),
            ));
        }
        self.camera
            .write(0, bytemuck::bytes_of(&CameraParams::from_camera(camera)))
    }

    /// Points the pass at its source (a cube view or a 2D view, in `SHADER_READ_ONLY_OPTIMAL`)
    /// and its output (of the target format it was built for) and mask (storage images in
    /// `GENERAL`).
    ///
    /// # Safety
    /// No recorded work using this pass may be pending; the views must be live views of this
    /// device of the kinds above.
    pub unsafe fn bind(
        &mut self,
        source: vk::ImageView,
        output: vk::ImageView,
        mask: vk::ImageView,
    ) {
        // SAFETY: the caller upholds this function's contract (no pending work uses the set);
        // the set is this pass's own, of its pipeline's layout, and the views and buffers are
        // live.
        unsafe {
            crate::gpu::write_buffer_descriptors(
                &self.gpu,
                self.set,
                &[(0, vk::DescriptorType::UNIFORM_BUFFER, &self.camera)],
            )
        };
        // SAFETY: the caller upholds this function's contract (no pending work uses the set);
        // the set is this pass's own, of its pipeline's layout, and the views and buffers are
        // live.
        unsafe {
            crate::gpu::write_sampled_image_descriptor(
                &self.gpu,
                self.set,
                1,
                &self.sampler,
                source,
            )
        };
        // SAFETY: the caller upholds this function's contract (no pending work uses the set);
        // the set is this pass's own, of its pipeline's layout, and the views and buffers are
        // live.
        unsafe { write_storage_image_descriptors(&self.gpu, self.set, &[(2, output), (3, mask)]) };
    }

    /// Records the warp over the whole output.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass on a compute queue; the bound images must
    /// be in the layouts [`SphereWarpPass::bind`] names, their writes visible to compute
    /// reads, and alive until the work completes.
    pub unsafe fn record(&self, cmd: vk::CommandBuffer) {
        let (w, h) = self.output_size;
        // SAFETY: the caller upholds `record`'s contract; the push is the pipeline's block.
        unsafe {
            self.pipeline.record_dispatch(
                cmd,
                self.set,
                bytemuck::bytes_of(&self.push),
                (w.div_ceil(8), h.div_ceil(8)),
            )
        };
    }

    /// [`Self::record`] (or, with `band`, [`Self::record_band`]), then its writes made visible
    /// to transfers and compute: what a stage whose output is read back or warped again
    /// records.
    ///
    /// # Safety
    /// As [`Self::record`].
    pub unsafe fn record_for_readers(&self, cmd: vk::CommandBuffer, band: Option<[u32; 4]>) {
        // SAFETY: the caller upholds `record`'s contract, which `record_band`'s is.
        unsafe {
            match band {
                Some(band) => self.record_band(cmd, band),
                None => self.record(cmd),
            }
            crate::gpu::global_barrier(
                &self.gpu,
                cmd,
                crate::gpu::Access::ComputeWrite,
                [
                    crate::gpu::Access::TransferRead,
                    crate::gpu::Access::ComputeRead,
                ],
            );
        }
    }

    /// As [`Self::record`], for the output pixels in `band` alone (`[x0, y0, x1, y1]`, x1
    /// and y1 excluded, clamped to the output). An empty band records nothing.
    ///
    /// # Safety
    /// As [`Self::record`].
    pub unsafe fn record_band(&self, cmd: vk::CommandBuffer, band: [u32; 4]) {
        // SAFETY: as in `record`: the caller upholds its contract; the push is the block.
        unsafe {
            record_band_dispatch(
                &self.pipeline,
                self.set,
                self.push,
                self.output_size,
                band,
                cmd,
            )
        };
    }
}

/// Dispatches `pipeline` (8 × 8 workgroups, `SpherePush` as its push block) over the pixels of
/// `band` (`[x0, y0, x1, y1]`, x1 and y1 excluded) clamped to `size`; an empty band records
/// nothing.
///
/// # Safety
/// `cmd` must be recording outside a render pass on a compute queue; `set` is of `pipeline`'s
/// layout and what it binds is ready for the dispatch and alive until the work completes.
unsafe fn record_band_dispatch(
    pipeline: &ComputePipeline,
    set: vk::DescriptorSet,
    push: SpherePush,
    (w, h): (u32, u32),
    [x0, y0, x1, y1]: [u32; 4],
    cmd: vk::CommandBuffer,
) {
    let (x1, y1) = (x1.min(w), y1.min(h));
    if x0 >= x1 || y0 >= y1 {
        return;
    }
    let push = SpherePush {
        band: [x0, y0, x1, y1],
        ..push
    };
    // SAFETY: the caller upholds this function's contract; the push is the block.
    unsafe {
        pipeline.record_dispatch(
            cmd,
            set,
            bytemuck::bytes_of(&push),
            ((x1 - x0).div_ceil(8), (y1 - y0).div_ceil(8)),
        )
    };
}

/// What a [`SphereDataPass`] reads its IDs and depths from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DataSource {
    /// Six faces (an R32_UINT and an R32F cube image), each face's z along its own axis.
    Cube,
    /// A pinhole image from the lens camera's centre along its axes, of these intrinsics
    /// (2D images; depth: z).
    Pinhole(Intrinsics),
    /// An equirectangular panorama from the lens camera's centre (2D images; depth: range).
    Equirect,
}

/// Object IDs, depth and range through the lens (`glsl/sphere_data.comp`) from a source's IDs
/// and depths ([`DataSource`]), each sampled at the nearest texel, the depth carried onto
/// each output pixel's own ray: the cube route's data outputs, and a renderer's own frames.
pub struct SphereDataPass {
    gpu: Gpu,
    pipeline: ComputePipeline,
    _pool: DescriptorPool,
    set: vk::DescriptorSet,
    sampler: Sampler,
    camera: Buffer,
    push: SpherePush,
    output_size: (u32, u32),
}

impl SphereDataPass {
    /// The pass for `camera`'s lens (its model alone compiled in) reading `source`.
    pub fn new(gpu: &Gpu, camera: &Camera, source: DataSource) -> Result<Self> {
        let by_model = match source {
            DataSource::Cube => &shaders::SPHERE_DATA_COMP_BY_MODEL,
            DataSource::Pinhole(_) => &shaders::SPHERE_DATA_COMP_PINHOLE_BY_MODEL,
            DataSource::Equirect => &shaders::SPHERE_DATA_COMP_EQUIRECT_BY_MODEL,
        };
        let spirv = by_model[camera.model().gpu_id() as usize];
        let pipeline = ComputePipeline::new(
            gpu,
            spirv,
            &[
                vk::DescriptorType::UNIFORM_BUFFER,
                vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
                vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
                vk::DescriptorType::STORAGE_IMAGE,
                vk::DescriptorType::STORAGE_IMAGE,
                vk::DescriptorType::STORAGE_IMAGE,
            ],
            std::mem::size_of::<SpherePush>() as u32,
            CameraParams::spec_constants(camera.terms()),
        )?;
        let pool = DescriptorPool::for_pipeline(gpu, &pipeline, 1)?;
        let set = pool.allocate(&pipeline)?;
        // Nearest: an ID must never be a mix, nor a depth one across an edge.
        let sampler = Sampler::with_modes(
            gpu,
            vk::Filter::NEAREST,
            [vk::SamplerAddressMode::CLAMP_TO_EDGE; 3],
        )?;
        let camera_buf = Buffer::from_pod(
            gpu,
            "sphere_data.camera",
            &[CameraParams::from_camera(camera)],
            vk::BufferUsageFlags::UNIFORM_BUFFER,
        )?;
        let (w, h) = (camera.width, camera.height);
        Ok(SphereDataPass {
            gpu: gpu.clone(),
            pipeline,
            _pool: pool,
            set,
            sampler,
            camera: camera_buf,
            push: SpherePush {
                // The pinhole source's intrinsics ride in the slot the data pass has no
                // other use for.
                chromatic: match source {
                    DataSource::Pinhole(k) => [k.fx, k.fy, k.cx, k.cy].map(|v| v as f32),
                    _ => [1.0; 4],
                },
                fill: [0.0; 4],
                sizes: [0, 0, w, h],
                band: [0, 0, w, h],
            },
            output_size: (w, h),
        })
    }

    /// The pipeline (its specialization constants show what was compiled in).
    pub fn pipeline(&self) -> &ComputePipeline {
        &self.pipeline
    }

    /// Moves the pass to another lens camera of the same size and terms.
    ///
    /// # Safety
    /// A host write to the camera uniform: no recorded work using this pass may be pending.
    pub unsafe fn set_camera(&mut self, camera: &Camera) -> Result<()> {
        self.camera
            .write(0, bytemuck::bytes_of(&CameraParams::from_camera(camera)))
    }

    /// Points the pass at the source's ID and depth images (R32_UINT and R32F cube views, or
    /// 2D views for a pinhole or panorama source, in `SHADER_READ_ONLY_OPTIMAL`) and its outputs (R32_UINT, R32F, R32F storage images of the
    /// lens camera's size in `GENERAL`).
    ///
    /// # Safety
    /// No recorded work using this pass may be pending; the views must be live views of this
    /// device of the kinds above.
    pub unsafe fn bind(
        &mut self,
        [ids_cube, depth_cube]: [vk::ImageView; 2],
        [ids, depth, range]: [vk::ImageView; 3],
    ) {
        // SAFETY (all three): the caller upholds this function's contract (no pending work
        // uses the set); the set is this pass's own, of its pipeline's layout, and the views
        // and the buffer are live.
        unsafe {
            crate::gpu::write_buffer_descriptors(
                &self.gpu,
                self.set,
                &[(0, vk::DescriptorType::UNIFORM_BUFFER, &self.camera)],
            );
            crate::gpu::write_sampled_image_descriptor(
                &self.gpu,
                self.set,
                1,
                &self.sampler,
                ids_cube,
            );
            crate::gpu::write_sampled_image_descriptor(
                &self.gpu,
                self.set,
                2,
                &self.sampler,
                depth_cube,
            );
            write_storage_image_descriptors(
                &self.gpu,
                self.set,
                &[(3, ids), (4, depth), (5, range)],
            );
        }
    }

    /// Records the pass over the output pixels in `band` (`[x0, y0, x1, y1]`, clamped; `None`:
    /// all), then its writes made visible to transfers and compute.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass on a compute queue; the bound images in
    /// the layouts [`Self::bind`] names, the cubes' writes visible to compute reads, all alive
    /// until the work completes.
    pub unsafe fn record_for_readers(&self, cmd: vk::CommandBuffer, band: Option<[u32; 4]>) {
        let (w, h) = self.output_size;
        // SAFETY: the caller upholds this function's contract; the push is the block.
        unsafe {
            record_band_dispatch(
                &self.pipeline,
                self.set,
                self.push,
                self.output_size,
                band.unwrap_or([0, 0, w, h]),
                cmd,
            );
            crate::gpu::global_barrier(
                &self.gpu,
                cmd,
                crate::gpu::Access::ComputeWrite,
                [
                    crate::gpu::Access::TransferRead,
                    crate::gpu::Access::ComputeRead,
                ],
            );
        }
    }
}
