//! The camera model on a list of points (`glsl/points.comp`).

use crate::pass::spec;
use ash::vk;

use super::camera_params::{CameraParams, CameraParams64};
use crate::gpu::{
    shaders, write_buffer_descriptors, Buffer, ComputePipeline, DescriptorPool, Error, Gpu, Result,
};
use crate::model::{Camera, InverseMethod};

/// What the pass computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PointsMode {
    /// Ideal normalized (X/Z, Y/Z) → distorted pixel.
    Distort,
    /// Distorted pixel → ideal normalized, by the given method.
    Undistort(InverseMethod),
    /// Camera-frame point (X, Y, Z) → distorted pixel; each point is two input `vec2`s,
    /// `(X, Y)` and `(Z, 0)`.
    Project,
    /// Distorted pixel → unit camera-frame ray, in the output's `x y` and `w`.
    Unproject,
}

impl PointsMode {
    /// Input `vec2`s per point.
    pub fn inputs_per_point(self) -> usize {
        if self == PointsMode::Project {
            2
        } else {
            1
        }
    }
}

/// Arithmetic of the shader: f32 (what the warp uses) or f64 (needs `shaderFloat64`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Precision {
    F32,
    F64,
}

impl Precision {
    /// Bytes per input point and per output point.
    pub(crate) fn strides(self) -> (usize, usize) {
        match self {
            Precision::F32 => (8, 16),
            Precision::F64 => (16, 32),
        }
    }
}

impl std::str::FromStr for Precision {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        match s {
            "f32" => Ok(Precision::F32),
            "f64" => Ok(Precision::F64),
            _ => Err(crate::Error::input(format!(
                "unknown precision `{s}` (expected f32 or f64)"
            ))),
        }
    }
}

impl std::fmt::Display for Precision {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Precision::F32 => "f32",
            Precision::F64 => "f64",
        })
    }
}

const WORKGROUP: u32 = 64;

/// A compute pass mapping `vec2` points through one camera. Build once per camera and mode;
/// bind input/output buffers; record as often as needed.
pub struct PointsPass {
    gpu: Gpu,
    pipeline: ComputePipeline,
    _pool: DescriptorPool,
    set: vk::DescriptorSet,
    camera: Buffer,
    precision: Precision,
}

impl PointsPass {
    /// Builds the pipeline for `camera` (terms it does not use are compiled out), `mode` and
    /// `precision`. F64 needs a device with `shaderFloat64` enabled.
    pub fn new(gpu: &Gpu, camera: &Camera, mode: PointsMode, precision: Precision) -> Result<Self> {
        if precision == Precision::F64 && !gpu.supports_float64() {
            return Err(Error::Input(format!(
                "{} has no shaderFloat64: use f32",
                gpu.device_name()
            )));
        }
        let (mode_id, method, iterations) = match mode {
            PointsMode::Distort => (0, 0, 1),
            PointsMode::Undistort(InverseMethod::Newton) => (1, 0, 1),
            PointsMode::Undistort(InverseMethod::Heikkila) => (1, 1, 1),
            PointsMode::Undistort(InverseMethod::FixedPoint(n)) => (1, 2, n),
            PointsMode::Project => (2, 0, 1),
            PointsMode::Unproject => (3, 0, 1),
        };
        if let PointsMode::Undistort(m) = mode {
            camera
                .check_method(m)
                .map_err(|e| Error::Input(e.to_string()))?;
        }
        let constants = CameraParams::spec_constants(camera.terms())
            .u32(spec::MODE, mode_id)
            .u32(spec::METHOD, method)
            .u32(spec::FIXED_POINT_ITERATIONS, iterations);
        // The module holding this mode's half of glsl/points.comp (which says why).
        let forward = matches!(mode, PointsMode::Distort | PointsMode::Project);
        // ... and of the camera's model alone.
        let by_model = match (precision, forward) {
            (Precision::F32, true) => &shaders::POINTS_COMP_FORWARD_BY_MODEL,
            (Precision::F64, true) => &shaders::POINTS_COMP_FORWARD_F64_BY_MODEL,
            (Precision::F32, false) => &shaders::POINTS_COMP_INVERSE_BY_MODEL,
            (Precision::F64, false) => &shaders::POINTS_COMP_INVERSE_F64_BY_MODEL,
        };
        let spirv = by_model[camera.model().gpu_id() as usize];
        let pipeline = ComputePipeline::new(
            gpu,
            spirv,
            &[
                vk::DescriptorType::UNIFORM_BUFFER,
                vk::DescriptorType::STORAGE_BUFFER,
                vk::DescriptorType::STORAGE_BUFFER,
            ],
            4,
            constants,
        )?;
        let pool = DescriptorPool::for_pipeline(gpu, &pipeline, 1)?;
        let set = pool.allocate(&pipeline)?;
        let usage = vk::BufferUsageFlags::UNIFORM_BUFFER;
        let camera = match precision {
            Precision::F32 => Buffer::from_pod(
                gpu,
                "points.camera",
                &[CameraParams::from_camera(camera)],
                usage,
            )?,
            Precision::F64 => Buffer::from_pod(
                gpu,
                "points.camera64",
                &[CameraParams64::from_camera(camera)],
                usage,
            )?,
        };
        Ok(PointsPass {
            gpu: gpu.clone(),
            pipeline,
            _pool: pool,
            set,
            camera,
            precision,
        })
    }

    /// The arithmetic the pass was built with.
    pub fn precision(&self) -> Precision {
        self.precision
    }

    /// The pipeline (its specialization constants show what was compiled in).
    pub fn pipeline(&self) -> &ComputePipeline {
        &self.pipeline
    }

    /// Points the pass at `inputs` (`vec2` per point; `dvec2` in f64) and `outputs` (`vec4`
    /// per point: result xy, valid flag; `dvec4` in f64). Must not be called while a recorded dispatch is pending.
    ///
    /// # Safety
    /// This rewrites the pass's descriptor set: no recorded work that uses
    /// this object may be pending on the GPU (wait for its fence first), as Vulkan
    /// requires of descriptor sets and memory the device reads.
    pub unsafe fn bind(&mut self, inputs: &Buffer, outputs: &Buffer) {
        // SAFETY: the caller upholds this function's contract (no pending work uses the set);
        // the set is this pass's own, of its pipeline's layout, and the views and buffers are
        // live.
        unsafe {
            write_buffer_descriptors(
                &self.gpu,
                self.set,
                &[
                    (0, vk::DescriptorType::UNIFORM_BUFFER, &self.camera),
                    (1, vk::DescriptorType::STORAGE_BUFFER, inputs),
                    (2, vk::DescriptorType::STORAGE_BUFFER, outputs),
                ],
            )
        };
    }

    /// Records the dispatch over `count` points.
    ///
    /// # Safety
    /// `cmd` must be in the recording state, outside a render pass, on a queue with compute.
    /// The bound buffers must hold `count` points (`count × inputs_per_point` input `vec2`s)
    /// and stay alive until the work completes.
    /// The caller orders the dispatch against other work: host or transfer writes to the
    /// inputs must be visible to `COMPUTE_SHADER` reads, and reads of the outputs need a
    /// barrier from `COMPUTE_SHADER` / `SHADER_WRITE`.
    pub unsafe fn record(&self, cmd: vk::CommandBuffer, count: u32) {
        // SAFETY: the caller upholds `record`'s contract: `cmd` is recording outside a render
        // pass on a compute queue and the bound buffers hold `count` points; the 4 bytes pushed
        // are the pipeline's push range.
        unsafe {
            self.pipeline.record_dispatch(
                cmd,
                self.set,
                &count.to_ne_bytes(),
                (count.div_ceil(WORKGROUP), 1),
            )
        };
    }
}

/// Largest number of points one dispatch takes (the dispatch size limit × workgroup size).
pub const MAX_POINTS: usize = 65_535 * WORKGROUP as usize;
