//! Memory barriers. Every call site says why it needs one.

use ash::vk;

use super::Gpu;

/// A global memory barrier: `src` work's `src_access` made visible to `dst` work's `dst_access`.
///
/// # Safety
/// `cmd` must be recording, outside a render pass (or in one with a matching self-dependency).
pub unsafe fn memory_barrier(
    gpu: &Gpu,
    cmd: vk::CommandBuffer,
    src: (vk::PipelineStageFlags, vk::AccessFlags),
    dst: (vk::PipelineStageFlags, vk::AccessFlags),
) {
    let barrier = [vk::MemoryBarrier::default()
        .src_access_mask(src.1)
        .dst_access_mask(dst.1)];
    // SAFETY: the caller upholds `memory_barrier`'s contract: `cmd` is recording, outside a
    // render pass or in one with a matching self-dependency; `barrier` outlives the call.
    unsafe {
        gpu.device().cmd_pipeline_barrier(
            cmd,
            src.0,
            dst.0,
            vk::DependencyFlags::empty(),
            &barrier,
            &[],
            &[],
        )
    };
}

/// Compute-shader writes made visible to host reads (after the fence).
///
/// # Safety
/// As [`memory_barrier`].
pub unsafe fn host_read_barrier(gpu: &Gpu, cmd: vk::CommandBuffer) {
    // SAFETY: the caller upholds `host_read_barrier`'s contract, which is `memory_barrier`'s.
    unsafe {
        memory_barrier(
            gpu,
            cmd,
            (
                vk::PipelineStageFlags::COMPUTE_SHADER,
                vk::AccessFlags::SHADER_WRITE,
            ),
            (vk::PipelineStageFlags::HOST, vk::AccessFlags::HOST_READ),
        )
    };
}

/// A layout transition (and memory dependency) for the whole colour subresource of `image`.
///
/// # Safety
/// As [`memory_barrier`]; `image` must be in layout `from` (or `from` is `UNDEFINED`).
pub unsafe fn image_barrier(
    gpu: &Gpu,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    (from, to): (vk::ImageLayout, vk::ImageLayout),
    src: (vk::PipelineStageFlags, vk::AccessFlags),
    dst: (vk::PipelineStageFlags, vk::AccessFlags),
) {
    let barrier = [vk::ImageMemoryBarrier::default()
        .image(image)
        .old_layout(from)
        .new_layout(to)
        .src_access_mask(src.1)
        .dst_access_mask(dst.1)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .subresource_range(super::Image::color_range())];
    // SAFETY: the caller upholds `image_barrier`'s contract: `cmd` is recording outside a
    // render pass and `image` is in layout `from` (or `from` is UNDEFINED). The range is the
    // one mip level and every layer (one, or six for a cube map) of a vklens colour image; `barrier` outlives the call.
    unsafe {
        gpu.device().cmd_pipeline_barrier(
            cmd,
            src.0,
            dst.0,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &barrier,
        )
    };
}

/// Copies `image` (in `TRANSFER_SRC_OPTIMAL`, its writes visible to transfers) whole into the
/// host-visible `buffer`, and makes the copy visible to host reads after the fence.
///
/// # Safety
/// As [`memory_barrier`]; `buffer` must hold the whole image, tightly packed.
pub unsafe fn record_download(
    gpu: &Gpu,
    cmd: vk::CommandBuffer,
    image: &super::Image,
    buffer: &super::Buffer,
) {
    // SAFETY: the caller upholds `record_download`'s contract: `cmd` is recording outside a
    // render pass, `image` is in TRANSFER_SRC_OPTIMAL and `buffer` holds the whole image
    // tightly packed. Every caller's images have TRANSFER_SRC and its buffers TRANSFER_DST usage.
    unsafe {
        gpu.device().cmd_copy_image_to_buffer(
            cmd,
            image.raw,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            buffer.raw,
            &[image.whole_copy()],
        );
        memory_barrier(
            gpu,
            cmd,
            (
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_WRITE,
            ),
            (vk::PipelineStageFlags::HOST, vk::AccessFlags::HOST_READ),
        );
    }
}

/// [`record_download`] of an image a compute shader wrote in `GENERAL` layout: the transition
/// to `TRANSFER_SRC_OPTIMAL` (making those writes visible to the copy) comes first.
///
/// # Safety
/// As [`record_download`]; `image` must be in `GENERAL` layout.
pub unsafe fn record_compute_download(
    gpu: &Gpu,
    cmd: vk::CommandBuffer,
    image: &super::Image,
    buffer: &super::Buffer,
) {
    // SAFETY: the caller upholds `record_compute_download`'s contract: `image` is in GENERAL,
    // which the transition starts from, and the rest is `record_download`'s contract.
    unsafe {
        image_barrier(
            gpu,
            cmd,
            image.raw,
            (
                vk::ImageLayout::GENERAL,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            ),
            (
                vk::PipelineStageFlags::COMPUTE_SHADER,
                vk::AccessFlags::SHADER_WRITE,
            ),
            (
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_READ,
            ),
        );
        record_download(gpu, cmd, image, buffer);
    }
}

/// [`record_compute_download`], then the image back to `GENERAL` so that the next frame's
/// compute pass can write it again without a one-off transition.
///
/// # Safety
/// As [`record_compute_download`].
pub unsafe fn record_compute_readback(
    gpu: &Gpu,
    cmd: vk::CommandBuffer,
    image: &super::Image,
    buffer: &super::Buffer,
) {
    // SAFETY: the caller upholds `record_compute_download`'s contract; the copy it records
    // leaves the image in TRANSFER_SRC_OPTIMAL, which the second transition starts from.
    unsafe {
        record_compute_download(gpu, cmd, image, buffer);
        // The next write (a compute shader's) waits for the copy's read.
        image_barrier(
            gpu,
            cmd,
            image.raw,
            (
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                vk::ImageLayout::GENERAL,
            ),
            (
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_READ,
            ),
            (
                vk::PipelineStageFlags::COMPUTE_SHADER,
                vk::AccessFlags::SHADER_WRITE,
            ),
        );
    }
}

/// Moves `images` to `GENERAL` for a compute shader to write, discarding what they held (the
/// shader writes every pixel, so their old contents are irrelevant).
///
/// # Safety
/// `cmd` must be recording outside a render pass, and no earlier work using the images may be
/// pending.
pub unsafe fn record_discard_for_compute_write<'a>(
    gpu: &Gpu,
    cmd: vk::CommandBuffer,
    images: impl IntoIterator<Item = &'a super::Image>,
) {
    for image in images {
        // SAFETY: the caller upholds this function's contract; UNDEFINED is a valid old
        // layout for any image, and discards its contents.
        unsafe {
            image_barrier(
                gpu,
                cmd,
                image.raw,
                (vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL),
                (
                    vk::PipelineStageFlags::TOP_OF_PIPE,
                    vk::AccessFlags::empty(),
                ),
                (
                    vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::AccessFlags::SHADER_WRITE,
                ),
            )
        };
    }
}
