//! Barriers named by what a resource is used for (as vk-sync does). Each site says how a
//! resource was last used and how it is used next; the stage, access mask and layout of each
//! use live in one place, [`Access`], so they cannot drift apart between sites.

use ash::vk;

use super::Gpu;

/// What a resource is used for: each use knows its pipeline stage, access mask and (for
/// images) layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// No earlier use to wait for: the previous contents are discarded.
    Nothing,
    /// The source of a copy.
    TransferRead,
    /// The destination of a copy, clear or buffer update.
    TransferWrite,
    /// Read by a compute shader as a storage image or buffer.
    ComputeRead,
    /// Written by a compute shader as a storage image or buffer.
    ComputeWrite,
    /// Read and written by a compute shader as a storage image or buffer.
    ComputeReadWrite,
    /// Sampled by a compute shader.
    ComputeSampled,
    /// Read by a fragment shader as a storage image.
    FragmentRead,
    /// Sampled by a fragment shader.
    FragmentSampled,
    /// A colour attachment that draws blend into (read and written).
    ColorAttachmentReadWrite,
    /// Vertex attributes read by draws (buffers only).
    VertexBuffer,
    /// Indices read by draws (buffers only).
    IndexBuffer,
    /// Indirect dispatch or draw parameters (buffers only).
    IndirectBuffer,
    /// Read by the host after the fence.
    HostRead,
}

/// Every write bit of Vulkan 1.0's access flags: only writes need making available, so only
/// these of an earlier use enter a barrier's source access mask.
const WRITES: vk::AccessFlags = vk::AccessFlags::from_raw(
    vk::AccessFlags::SHADER_WRITE.as_raw()
        | vk::AccessFlags::COLOR_ATTACHMENT_WRITE.as_raw()
        | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE.as_raw()
        | vk::AccessFlags::TRANSFER_WRITE.as_raw()
        | vk::AccessFlags::HOST_WRITE.as_raw()
        | vk::AccessFlags::MEMORY_WRITE.as_raw(),
);

impl Access {
    /// The pipeline stage the use happens in.
    pub fn stage(self) -> vk::PipelineStageFlags {
        use vk::PipelineStageFlags as S;
        match self {
            Self::Nothing => S::TOP_OF_PIPE,
            Self::TransferRead | Self::TransferWrite => S::TRANSFER,
            Self::ComputeRead
            | Self::ComputeWrite
            | Self::ComputeReadWrite
            | Self::ComputeSampled => S::COMPUTE_SHADER,
            Self::FragmentRead | Self::FragmentSampled => S::FRAGMENT_SHADER,
            Self::ColorAttachmentReadWrite => S::COLOR_ATTACHMENT_OUTPUT,
            Self::VertexBuffer | Self::IndexBuffer => S::VERTEX_INPUT,
            Self::IndirectBuffer => S::DRAW_INDIRECT,
            Self::HostRead => S::HOST,
        }
    }

    /// The memory accesses the use makes.
    pub fn access(self) -> vk::AccessFlags {
        use vk::AccessFlags as A;
        match self {
            Self::Nothing => A::empty(),
            Self::TransferRead => A::TRANSFER_READ,
            Self::TransferWrite => A::TRANSFER_WRITE,
            Self::ComputeRead
            | Self::ComputeSampled
            | Self::FragmentRead
            | Self::FragmentSampled => A::SHADER_READ,
            Self::ComputeWrite => A::SHADER_WRITE,
            Self::ComputeReadWrite => A::SHADER_READ | A::SHADER_WRITE,
            Self::ColorAttachmentReadWrite => A::COLOR_ATTACHMENT_READ | A::COLOR_ATTACHMENT_WRITE,
            Self::VertexBuffer => A::VERTEX_ATTRIBUTE_READ,
            Self::IndexBuffer => A::INDEX_READ,
            Self::IndirectBuffer => A::INDIRECT_COMMAND_READ,
            Self::HostRead => A::HOST_READ,
        }
    }

    /// The layout an image must be in for the use; `UNDEFINED` for [`Access::Nothing`] and
    /// for the uses only buffers have.
    pub fn layout(self) -> vk::ImageLayout {
        use vk::ImageLayout as L;
        match self {
            Self::Nothing | Self::VertexBuffer | Self::IndexBuffer | Self::IndirectBuffer => {
                L::UNDEFINED
            }
            Self::TransferRead => L::TRANSFER_SRC_OPTIMAL,
            Self::TransferWrite => L::TRANSFER_DST_OPTIMAL,
            Self::ComputeRead
            | Self::ComputeWrite
            | Self::ComputeReadWrite
            | Self::FragmentRead
            | Self::HostRead => L::GENERAL,
            Self::ComputeSampled | Self::FragmentSampled => L::SHADER_READ_ONLY_OPTIMAL,
            Self::ColorAttachmentReadWrite => L::COLOR_ATTACHMENT_OPTIMAL,
        }
    }
}

/// One use as a slice of uses, so that the barrier functions take one or several alike.
impl AsRef<[Access]> for Access {
    fn as_ref(&self) -> &[Access] {
        std::slice::from_ref(self)
    }
}

/// The stage and access masks of a dependency from the uses `from` to the uses `to`. Only
/// the writes of `from` enter the source access mask: a read needs no making available, its
/// stage alone orders it before a later write.
fn masks(
    from: &[Access],
    to: &[Access],
) -> (
    (vk::PipelineStageFlags, vk::AccessFlags),
    (vk::PipelineStageFlags, vk::AccessFlags),
) {
    let union = |uses: &[Access], part: fn(Access) -> vk::AccessFlags| {
        uses.iter()
            .fold(vk::AccessFlags::empty(), |acc, &a| acc | part(a))
    };
    let stages = |uses: &[Access], none: vk::PipelineStageFlags| {
        let s = uses
            .iter()
            .fold(vk::PipelineStageFlags::empty(), |acc, a| acc | a.stage());
        if s.is_empty() {
            none
        } else {
            s
        }
    };
    (
        (
            stages(from, vk::PipelineStageFlags::TOP_OF_PIPE),
            union(from, |a| a.access() & WRITES),
        ),
        (
            stages(to, vk::PipelineStageFlags::BOTTOM_OF_PIPE),
            union(to, Access::access),
        ),
    )
}

/// A global memory barrier: the work of the uses `from` (one [`Access`], or several as a
/// slice or array) is done, and its writes visible, before the uses `to`.
///
/// # Safety
/// `cmd` must be recording, outside a render pass (or in one with a matching self-dependency).
pub unsafe fn global_barrier(
    gpu: &Gpu,
    cmd: vk::CommandBuffer,
    from: impl AsRef<[Access]>,
    to: impl AsRef<[Access]>,
) {
    let ((src_stage, src_access), (dst_stage, dst_access)) = masks(from.as_ref(), to.as_ref());
    let barrier = [vk::MemoryBarrier::default()
        .src_access_mask(src_access)
        .dst_access_mask(dst_access)];
    // SAFETY: the caller upholds `global_barrier`'s contract: `cmd` is recording, outside a
    // render pass or in one with a matching self-dependency; `barrier` outlives the call.
    unsafe {
        gpu.device().cmd_pipeline_barrier(
            cmd,
            src_stage,
            dst_stage,
            vk::DependencyFlags::empty(),
            &barrier,
            &[],
            &[],
        )
    };
}

/// A layout transition of the whole colour subresource of `image` from `from`'s layout to
/// `to`'s, with the dependency of [`global_barrier`] for that image.
///
/// # Safety
/// As [`global_barrier`]; `image` must be in `from.layout()` (or `from` is
/// [`Access::Nothing`], which discards its contents), and `to` must be a use images have.
pub unsafe fn image_transition(
    gpu: &Gpu,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    from: Access,
    to: Access,
) {
    // A buffer-only use has no layout to start from; discarding must be asked for by name.
    debug_assert!(
        from == Access::Nothing || from.layout() != vk::ImageLayout::UNDEFINED,
        "{from:?} is no use of an image"
    );
    // SAFETY: the caller upholds `image_transition`'s contract, which is `image_barrier`'s
    // with `from`'s layout as the old one.
    unsafe { image_barrier(gpu, cmd, image, from.layout(), from, to) };
}

/// [`image_transition`] of an image whose contents are discarded (the old layout is
/// `UNDEFINED`), after the earlier use `after` of it is done: the write of `to` must not race
/// that use, but needs nothing it left.
///
/// # Safety
/// As [`global_barrier`]; `to` must be a use images have.
pub unsafe fn image_discard(
    gpu: &Gpu,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    after: Access,
    to: Access,
) {
    // SAFETY: the caller upholds `image_discard`'s contract, which is `image_barrier`'s;
    // UNDEFINED is a valid old layout for any image.
    unsafe { image_barrier(gpu, cmd, image, vk::ImageLayout::UNDEFINED, after, to) };
}

/// The image barrier behind [`image_transition`] and [`image_discard`].
///
/// # Safety
/// As [`global_barrier`]; `image` must be in layout `old` (or `old` is `UNDEFINED`), and `to`
/// must be a use images have.
unsafe fn image_barrier(
    gpu: &Gpu,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    old: vk::ImageLayout,
    from: Access,
    to: Access,
) {
    debug_assert_ne!(
        to.layout(),
        vk::ImageLayout::UNDEFINED,
        "{to:?} is no use of an image"
    );
    let ((src_stage, src_access), (dst_stage, dst_access)) = masks(&[from], &[to]);
    let barrier = [vk::ImageMemoryBarrier::default()
        .image(image)
        .old_layout(old)
        .new_layout(to.layout())
        .src_access_mask(src_access)
        .dst_access_mask(dst_access)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .subresource_range(super::Image::color_range())];
    // SAFETY: the caller upholds `image_barrier`'s contract: `cmd` is recording outside a
    // render pass and `image` is in layout `old` (or `old` is UNDEFINED); `to` has a real
    // layout, so the new one is valid. The range is the one mip level and every layer (one,
    // or six for a cube map) of a vklens colour image; `barrier` outlives the call.
    unsafe {
        gpu.device().cmd_pipeline_barrier(
            cmd,
            src_stage,
            dst_stage,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &barrier,
        )
    };
}

/// Compute-shader writes made visible to host reads (after the fence).
///
/// # Safety
/// As [`global_barrier`].
pub unsafe fn host_read_barrier(gpu: &Gpu, cmd: vk::CommandBuffer) {
    // SAFETY: the caller upholds `host_read_barrier`'s contract, which is `global_barrier`'s.
    unsafe { global_barrier(gpu, cmd, Access::ComputeWrite, Access::HostRead) };
}

/// Fills `image` whole from `buffer` (its old contents discarded), then hands it to `next`
/// (its layout, its writes visible to that access): the mirror of [`record_download`].
///
/// # Safety
/// As [`global_barrier`]; `buffer` must hold the whole image tightly packed in its format,
/// `image` must have TRANSFER_DST usage and `buffer` TRANSFER_SRC, and no earlier work may
/// still use the image.
pub unsafe fn record_upload(
    gpu: &Gpu,
    cmd: vk::CommandBuffer,
    buffer: &super::Buffer,
    image: &super::Image,
    next: Access,
) {
    // SAFETY: the caller upholds `record_upload`'s contract: nothing uses the image, so
    // UNDEFINED (Nothing) is a valid old layout for contents overwritten whole; the buffer
    // holds them tightly packed; the usages allow the copy.
    unsafe {
        image_transition(gpu, cmd, image.raw, Access::Nothing, Access::TransferWrite);
        gpu.device().cmd_copy_buffer_to_image(
            cmd,
            buffer.raw,
            image.raw,
            Access::TransferWrite.layout(),
            &[image.whole_copy()],
        );
        image_transition(gpu, cmd, image.raw, Access::TransferWrite, next);
    }
}

/// Copies `image` (in `TRANSFER_SRC_OPTIMAL`, its writes visible to transfers) whole into the
/// host-visible `buffer`, and makes the copy visible to host reads after the fence.
///
/// # Safety
/// As [`global_barrier`]; `buffer` must hold the whole image, tightly packed.
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
            Access::TransferRead.layout(),
            buffer.raw,
            &[image.whole_copy()],
        );
        global_barrier(gpu, cmd, Access::TransferWrite, Access::HostRead);
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
    // ComputeWrite's layout, which the transition starts from, and the rest is
    // `record_download`'s contract.
    unsafe {
        image_transition(
            gpu,
            cmd,
            image.raw,
            Access::ComputeWrite,
            Access::TransferRead,
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
    // leaves the image in TRANSFER_SRC_OPTIMAL, TransferRead's layout, which the second
    // transition starts from.
    unsafe {
        record_compute_download(gpu, cmd, image, buffer);
        // The next write (a compute shader's) waits for the copy's read.
        image_transition(
            gpu,
            cmd,
            image.raw,
            Access::TransferRead,
            Access::ComputeWrite,
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
        // SAFETY: the caller upholds this function's contract; with no earlier work pending
        // there is nothing to wait for, and `Nothing`'s UNDEFINED is a valid old layout for
        // any image.
        unsafe { image_transition(gpu, cmd, image.raw, Access::Nothing, Access::ComputeWrite) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vk::{AccessFlags as A, PipelineStageFlags as S};

    #[test]
    fn only_the_writes_of_earlier_uses_are_made_available() {
        let (src, dst) = masks(&[Access::ColorAttachmentReadWrite], &[Access::TransferRead]);
        assert_eq!(src, (S::COLOR_ATTACHMENT_OUTPUT, A::COLOR_ATTACHMENT_WRITE));
        assert_eq!(dst, (S::TRANSFER, A::TRANSFER_READ));
        // A read before a write: its stage orders it, with nothing to make available.
        let (src, _) = masks(&[Access::TransferRead], &[Access::ComputeWrite]);
        assert_eq!(src, (S::TRANSFER, A::empty()));
    }

    #[test]
    fn several_uses_join_their_stages_and_accesses() {
        use Access::*;
        let (src, dst) = masks(
            &[IndexBuffer, VertexBuffer, ComputeReadWrite, IndirectBuffer],
            &[ComputeReadWrite, IndirectBuffer],
        );
        assert_eq!(
            src,
            (
                S::VERTEX_INPUT | S::COMPUTE_SHADER | S::DRAW_INDIRECT,
                A::SHADER_WRITE
            )
        );
        assert_eq!(
            dst,
            (
                S::COMPUTE_SHADER | S::DRAW_INDIRECT,
                A::SHADER_READ | A::SHADER_WRITE | A::INDIRECT_COMMAND_READ
            )
        );
        assert_eq!(
            masks(&[], &[]),
            (
                (S::TOP_OF_PIPE, A::empty()),
                (S::BOTTOM_OF_PIPE, A::empty())
            )
        );
    }
}
