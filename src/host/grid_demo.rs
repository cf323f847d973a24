//! Headless helpers for `pass::grid_demo`: upload, record, submit, wait and read back.

use crate::gpu::{
    host_read_barrier, shaders, write_buffer_descriptors, Buffer, ComputePipeline, DescriptorPool,
    Result,
};
use crate::host::Context;
use crate::model::Camera;
use crate::pass::camera_params::CameraParams;
use crate::pass::spec;
use ash::vk;
use gpu_allocator::MemoryLocation;

/// Renders `camera.width × camera.height` RGBA8 pixels (row-major), grid lines every `grid`
/// ideal pixels.
pub fn render_grid(ctx: &Context, camera: &Camera, grid: u32) -> Result<Vec<u8>> {
    let gpu = ctx.gpu();
    let constants = CameraParams::spec_constants(camera.terms()).u32(spec::GRID, grid.max(2));
    let pipeline = ComputePipeline::new(
        gpu,
        shaders::GRID_DEMO_COMP,
        &[
            vk::DescriptorType::UNIFORM_BUFFER,
            vk::DescriptorType::STORAGE_BUFFER,
        ],
        8,
        constants,
    )?;
    let pool = DescriptorPool::for_pipeline(gpu, &pipeline, 1)?;
    let set = pool.allocate(&pipeline)?;
    let params = Buffer::from_pod(
        gpu,
        "demo.camera",
        &[CameraParams::from_camera(camera)],
        vk::BufferUsageFlags::UNIFORM_BUFFER,
    )?;
    let (w, h) = (camera.width, camera.height);
    let pixels = Buffer::new(
        gpu,
        "demo.pixels",
        w as u64 * h as u64 * 4,
        vk::BufferUsageFlags::STORAGE_BUFFER,
        MemoryLocation::GpuToCpu,
    )?;
    // SAFETY: the set was just allocated from a pool made for this pipeline's layout, so no
    // work uses it yet; the buffers and views are this pass's own, alive.
    unsafe {
        write_buffer_descriptors(
            gpu,
            set,
            &[
                (0, vk::DescriptorType::UNIFORM_BUFFER, &params),
                (1, vk::DescriptorType::STORAGE_BUFFER, &pixels),
            ],
        )
    };
    ctx.submit(|cmd| {
        let size = [w, h];
        // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass;
        // `set` points at `params` and `pixels` (`w × h` packed pixels), which outlive the
        // submission because `submit` waits on its fence; the 8 bytes pushed are the push range.
        unsafe {
            pipeline.record_dispatch(
                cmd,
                set,
                bytemuck::cast_slice(&size),
                (w.div_ceil(8), h.div_ceil(8)),
            );
            // The host reads the pixels after the fence.
            host_read_barrier(gpu, cmd);
        }
        Ok(())
    })?;
    let packed: Vec<u32> = pixels.read_pod(w as usize * h as usize)?;
    Ok(packed.iter().flat_map(|p| p.to_le_bytes()).collect())
}
