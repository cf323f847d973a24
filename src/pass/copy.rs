//! The copy pass (`glsl/copy.comp`): imageLoad → imageStore of an RGBA8 image, the floor every
//! warp is measured against on the same driver.

use ash::vk;

use crate::gpu::{
    shaders, write_storage_image_descriptors, ComputePipeline, DescriptorPool, Gpu, Result,
    SpecConstants,
};

/// Copies one RGBA8 storage image into another of the same size.
pub struct CopyPass {
    gpu: Gpu,
    pipeline: ComputePipeline,
    _pool: DescriptorPool,
    set: vk::DescriptorSet,
    size: (u32, u32),
}

impl CopyPass {
    pub fn new(gpu: &Gpu, width: u32, height: u32) -> Result<Self> {
        let storage = vk::DescriptorType::STORAGE_IMAGE;
        let pipeline = ComputePipeline::new(
            gpu,
            shaders::COPY_COMP,
            &[storage, storage],
            16,
            SpecConstants::new(),
        )?;
        let pool = DescriptorPool::for_pipeline(gpu, &pipeline, 1)?;
        let set = pool.allocate(&pipeline)?;
        Ok(CopyPass {
            gpu: gpu.clone(),
            pipeline,
            _pool: pool,
            set,
            size: (width, height),
        })
    }

    /// Binds the source and destination (storage images in `GENERAL` layout).
    ///
    /// # Safety
    /// This rewrites the pass's descriptor set: no recorded work that uses
    /// this object may be pending on the GPU (wait for its fence first), as Vulkan
    /// requires of descriptor sets and memory the device reads.
    pub unsafe fn bind(&mut self, source: vk::ImageView, target: vk::ImageView) {
        // SAFETY: the caller upholds this function's contract (no pending work uses the set);
        // the set is this pass's own, of its pipeline's layout, and the views and buffers are
        // live.
        unsafe {
            write_storage_image_descriptors(&self.gpu, self.set, &[(0, source), (1, target)])
        };
    }

    /// Records the copy.
    ///
    /// # Safety
    /// As [`crate::pass::warp::WarpPass::record`].
    pub unsafe fn record(&self, cmd: vk::CommandBuffer) {
        let (w, h) = self.size;
        let sizes = [w, h, w, h];
        // SAFETY: the caller upholds `record`'s contract (`WarpPass::record`'s): `cmd` is
        // recording outside a render pass on a compute queue, both images bound and in GENERAL;
        // the 16 bytes pushed are the pipeline's whole push range.
        unsafe {
            self.pipeline.record_dispatch(
                cmd,
                self.set,
                bytemuck::cast_slice(&sizes),
                (w.div_ceil(8), h.div_ceil(8)),
            )
        };
    }
}
