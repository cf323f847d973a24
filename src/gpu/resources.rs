//! Buffers, images and query pools, each owning its handle and its memory.

use crate::error::VkCall;
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use super::{Error, Gpu, Result};

/// A buffer with its allocation. Host-visible ones can be read and written directly.
pub struct Buffer {
    gpu: Gpu,
    pub raw: vk::Buffer,
    allocation: Option<Allocation>,
    pub size: u64,
}

impl Buffer {
    /// Creates a buffer of `size` bytes for `usage` in `location`.
    pub fn new(
        gpu: &Gpu,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<Self> {
        let size = size.max(4);
        let device = gpu.device();
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: a complete exclusive-buffer create info (size at least 4, never 0) on a live
        // device; no allocation callbacks.
        let raw = unsafe { device.create_buffer(&info, None).call("vkCreateBuffer")? };
        // SAFETY: `raw` was just created from this device.
        let requirements = unsafe { device.get_buffer_memory_requirements(raw) };
        // SAFETY: `raw` has no memory bound yet, and the allocation was made for its memory
        // requirements, so memory type, size and offset alignment fit.
        let allocation = allocate(gpu, name, requirements, location, true, |a| unsafe {
            device
                .bind_buffer_memory(raw, a.memory(), a.offset())
                .call("vkBindBufferMemory")
        })
        // SAFETY: on error `raw` has no memory bound and was never handed out or used.
        .inspect_err(|_| unsafe { device.destroy_buffer(raw, None) })?;
        Ok(Buffer {
            gpu: gpu.clone(),
            raw,
            allocation: Some(allocation),
            size,
        })
    }

    /// A host-visible buffer holding `data`.
    pub fn from_pod<T: bytemuck::Pod>(
        gpu: &Gpu,
        name: &str,
        data: &[T],
        usage: vk::BufferUsageFlags,
    ) -> Result<Self> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let buffer = Self::new(
            gpu,
            name,
            bytes.len() as u64,
            usage,
            MemoryLocation::CpuToGpu,
        )?;
        buffer.write(0, bytes)?;
        Ok(buffer)
    }

    fn mapped(&self) -> Result<&[u8]> {
        self.allocation
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .ok_or_else(|| Error::internal("buffer is not host-visible"))
    }

    /// Writes bytes at `offset` (host-visible buffers only; memory is host-coherent).
    pub fn write(&self, offset: usize, bytes: &[u8]) -> Result<()> {
        let alloc = self
            .allocation
            .as_ref()
            .ok_or_else(|| Error::internal("buffer has no memory"))?;
        let ptr = alloc
            .mapped_ptr()
            .ok_or_else(|| Error::internal("buffer is not host-visible"))?;
        if offset + bytes.len() > alloc.size() as usize {
            return Err(Error::internal("write past the end of a buffer"));
        }
        // SAFETY: in bounds (checked above), the mapping lives as long as the allocation, and
        // the GPU does not use the buffer while the host writes it (callers wait on fences).
        unsafe {
            std::ptr::copy_nonoverlapping(
                bytes.as_ptr(),
                (ptr.as_ptr() as *mut u8).add(offset),
                bytes.len(),
            )
        };
        Ok(())
    }

    /// Hands the whole mapped buffer to `fill` for writing in place (host-visible buffers
    /// only; memory is host-coherent).
    pub fn write_with<R>(&mut self, fill: impl FnOnce(&mut [u8]) -> R) -> Result<R> {
        let bytes = self
            .allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .ok_or_else(|| Error::internal("buffer is not host-visible"))?;
        Ok(fill(bytes))
    }

    /// The first `len` mapped bytes (host-visible buffers only).
    pub fn bytes(&self, len: usize) -> Result<&[u8]> {
        self.mapped()?
            .get(..len)
            .ok_or_else(|| Error::internal("read past the end of a buffer"))
    }

    /// Reads the first `count` elements back (host-visible buffers only).
    pub fn read_pod<T: bytemuck::Pod>(&self, count: usize) -> Result<Vec<T>> {
        let bytes = self.mapped()?;
        let n = count * std::mem::size_of::<T>();
        if n > bytes.len() {
            return Err(Error::internal("read past the end of a buffer"));
        }
        Ok(bytemuck::pod_collect_to_vec(&bytes[..n]))
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        free(&self.gpu, self.allocation.take());
        // SAFETY: `raw` was created from this device and is destroyed only here (freeing its
        // memory first is allowed: it is not used again). No submitted work may still use it:
        // `Context::submit` waits, and recorded work's contract keeps buffers alive until done.
        unsafe { self.gpu.device().destroy_buffer(self.raw, None) };
    }
}

/// Allocates memory for `requirements` and binds it with `bind`; frees it again if binding fails.
fn allocate(
    gpu: &Gpu,
    name: &str,
    requirements: vk::MemoryRequirements,
    location: MemoryLocation,
    linear: bool,
    bind: impl FnOnce(&Allocation) -> Result<()>,
) -> Result<Allocation> {
    let mut allocator = gpu
        .allocator()
        .lock()
        .map_err(|_| Error::internal("allocator lock poisoned"))?;
    let allocation = allocator.allocate(&AllocationCreateDesc {
        name,
        requirements,
        location,
        linear,
        allocation_scheme: AllocationScheme::GpuAllocatorManaged,
    })?;
    if let Err(e) = bind(&allocation) {
        let _ = allocator.free(allocation);
        return Err(e);
    }
    Ok(allocation)
}

/// Returns an allocation to the allocator (used by `Drop`).
fn free(gpu: &Gpu, allocation: Option<Allocation>) {
    if let Some(a) = allocation {
        if let Ok(mut allocator) = gpu.allocator().lock() {
            let _ = allocator.free(a);
        }
    }
}

/// How many layers an image has, and how its view shows them.
#[derive(Clone, Copy)]
enum Layers {
    One,
    Cube,
}

/// A 2D image (or a cube map) with its view and allocation (device-local).
pub struct Image {
    gpu: Gpu,
    pub raw: vk::Image,
    pub view: vk::ImageView,
    allocation: Option<Allocation>,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    /// Array layers: 1, or 6 for a cube map.
    pub layers: u32,
}

impl Image {
    /// Creates a device-local 2D image with one mip level and a view of its colour (or, for a
    /// depth format, depth) aspect.
    pub fn new_2d(
        gpu: &Gpu,
        name: &str,
        format: vk::Format,
        width: u32,
        height: u32,
        usage: vk::ImageUsageFlags,
    ) -> Result<Self> {
        Self::new_layers(gpu, name, format, (width, height), Layers::One, usage)
    }

    /// A cube map: six square `side × side` layers in Vulkan's face order (+X −X +Y −Y +Z −Z
    /// of its y-up addressing) and a cube view (sampled seamlessly across faces: Vulkan
    /// filters cube maps across face edges always).
    pub fn new_cube(
        gpu: &Gpu,
        name: &str,
        format: vk::Format,
        side: u32,
        usage: vk::ImageUsageFlags,
    ) -> Result<Self> {
        Self::new_layers(gpu, name, format, (side, side), Layers::Cube, usage)
    }

    fn new_layers(
        gpu: &Gpu,
        name: &str,
        format: vk::Format,
        (width, height): (u32, u32),
        layers: Layers,
        usage: vk::ImageUsageFlags,
    ) -> Result<Self> {
        let device = gpu.device();
        let (count, flags, view_type) = match layers {
            Layers::One => (1, vk::ImageCreateFlags::empty(), vk::ImageViewType::TYPE_2D),
            Layers::Cube => (
                6,
                vk::ImageCreateFlags::CUBE_COMPATIBLE,
                vk::ImageViewType::CUBE,
            ),
        };
        let info = vk::ImageCreateInfo::default()
            .flags(flags)
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D {
                width,
                height,
                depth: 1,
            })
            .mip_levels(1)
            .array_layers(count)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: `info` fully describes a 2D image (one mip level, one layer or six square ones
        // for a cube, one sample) on a live device. Vulkan also needs a non-zero extent within maxImageDimension2D (maxImageDimensionCube for a cube) and a
        // format that supports `usage`; this function does not check those, its callers do
        // (validated camera and film sizes, `check_sizes`, formats chosen per usage).
        let raw = unsafe { device.create_image(&info, None).call("vkCreateImage")? };
        // SAFETY: `raw` was just created from this device.
        let requirements = unsafe { device.get_image_memory_requirements(raw) };
        let allocation = allocate(
            gpu,
            name,
            requirements,
            MemoryLocation::GpuOnly,
            false,
            // SAFETY: `raw` has no memory bound yet, and the allocation was made for its memory
            // requirements (optimal tiling: `linear` is false), so type, size and alignment fit.
            |a| unsafe {
                device
                    .bind_image_memory(raw, a.memory(), a.offset())
                    .call("vkBindImageMemory")
            },
        )
        // SAFETY: on error `raw` has no memory bound and was never handed out or used.
        .inspect_err(|_| unsafe { device.destroy_image(raw, None) })?;
        // From here on `image` owns the handle and the memory: Drop cleans up on early return.
        let mut image = Image {
            gpu: gpu.clone(),
            raw,
            view: vk::ImageView::null(),
            allocation: Some(allocation),
            format,
            extent: vk::Extent2D { width, height },
            layers: count,
        };
        let view_info = vk::ImageViewCreateInfo::default()
            .image(raw)
            .view_type(view_type)
            .format(format)
            .subresource_range(vk::ImageSubresourceRange {
                aspect_mask: Self::aspect_of(format),
                ..Self::color_range()
            });
        // SAFETY: `raw` is a live image of this device with memory bound; the view has its
        // format, the type of its layers (2D for one, cube for six cube-compatible ones), its
        // one mip level and all its layers, and the aspect `aspect_of` gives for the format. On error `image`'s Drop destroys the image (the view stays null).
        image.view = unsafe {
            device
                .create_image_view(&view_info, None)
                .call("vkCreateImageView")?
        };
        Ok(image)
    }

    /// The aspect a view of `format` shows (depth formats: DEPTH; everything else: COLOR).
    pub fn aspect_of(format: vk::Format) -> vk::ImageAspectFlags {
        match format {
            vk::Format::D32_SFLOAT | vk::Format::D16_UNORM | vk::Format::X8_D24_UNORM_PACK32 => {
                vk::ImageAspectFlags::DEPTH
            }
            _ => vk::ImageAspectFlags::COLOR,
        }
    }

    /// A buffer ↔ image copy of the whole image (tightly packed rows; the layers of a cube map
    /// one after the other).
    pub fn whole_copy(&self) -> vk::BufferImageCopy {
        vk::BufferImageCopy {
            buffer_offset: 0,
            buffer_row_length: 0,
            buffer_image_height: 0,
            image_subresource: vk::ImageSubresourceLayers {
                aspect_mask: Self::aspect_of(self.format),
                mip_level: 0,
                base_array_layer: 0,
                layer_count: self.layers,
            },
            image_offset: vk::Offset3D::default(),
            image_extent: vk::Extent3D {
                width: self.extent.width,
                height: self.extent.height,
                depth: 1,
            },
        }
    }

    /// The whole colour subresource (the one mip level, every layer).
    pub fn color_range() -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            base_mip_level: 0,
            level_count: 1,
            base_array_layer: 0,
            layer_count: vk::REMAINING_ARRAY_LAYERS,
        }
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        let device = self.gpu.device();
        // SAFETY: the view was created from this device for `raw` and is destroyed only here
        // (it is null when `new_2d` failed before making it); no pending work still uses it.
        unsafe {
            if self.view != vk::ImageView::null() {
                device.destroy_image_view(self.view, None);
            }
        }
        free(&self.gpu, self.allocation.take());
        // SAFETY: `raw` was created from this device and is destroyed only here, after its
        // view (freeing its memory first is allowed: it is not used again); no pending work
        // still uses it.
        unsafe { device.destroy_image(self.raw, None) };
    }
}

/// A timestamp query pool.
pub struct QueryPool {
    gpu: Gpu,
    pub raw: vk::QueryPool,
    pub count: u32,
}

impl QueryPool {
    /// `count` timestamp queries; fails if the queue has no timestamps.
    pub fn timestamps(gpu: &Gpu, count: u32) -> Result<Self> {
        if gpu.timestamp_period_ns().is_none() {
            return Err(Error::unsupported("this queue does not support timestamps"));
        }
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(count);
        // SAFETY: a timestamp query pool on a live device whose queue supports timestamps
        // (checked above). Vulkan needs `count` > 0; every caller asks for at least 1.
        let raw = unsafe {
            gpu.device()
                .create_query_pool(&info, None)
                .call("vkCreateQueryPool")?
        };
        Ok(QueryPool {
            gpu: gpu.clone(),
            raw,
            count,
        })
    }

    /// Records a reset of every query.
    ///
    /// # Safety
    /// `cmd` is recording, outside a render pass, on a queue of this device.
    pub unsafe fn cmd_reset(&self, cmd: vk::CommandBuffer) {
        // SAFETY: the pool is alive and of this device, and the range is the whole pool; `cmd`
        // is recording outside a render pass (the function's contract).
        unsafe {
            self.gpu
                .device()
                .cmd_reset_query_pool(cmd, self.raw, 0, self.count)
        };
    }

    /// Records a timestamp into query `index` after all prior work.
    ///
    /// # Safety
    /// `cmd` is recording on a queue of this device, the query was reset since its last write
    /// (in this command buffer or an earlier completed one), and `index` is below the pool's
    /// count.
    pub unsafe fn cmd_write(&self, cmd: vk::CommandBuffer, index: u32) {
        // SAFETY: the pool is alive, of this device, and its queue has timestamps (`timestamps`
        // checked); `cmd`, the reset and `index` are as the function's contract says.
        unsafe {
            self.gpu.device().cmd_write_timestamp(
                cmd,
                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                self.raw,
                index,
            )
        };
    }

    /// Reads all timestamps (waiting for them) and returns them in nanoseconds.
    pub fn read_ns(&self) -> Result<Vec<f64>> {
        let mut ticks = vec![0u64; self.count as usize];
        // SAFETY: the pool is alive and of this device; `ticks` holds `count` u64s, matching
        // TYPE_64 and the whole query range. WAIT blocks until the queries are written (callers
        // read after the submission that wrote them completed).
        unsafe {
            self.gpu
                .device()
                .get_query_pool_results(
                    self.raw,
                    0,
                    &mut ticks,
                    vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                )
                .call("vkGetQueryPoolResults")?
        };
        let period = self.gpu.timestamp_period_ns().unwrap_or(1.0);
        Ok(ticks.iter().map(|&t| t as f64 * period).collect())
    }
}

impl Drop for QueryPool {
    fn drop(&mut self) {
        // SAFETY: created from this device and destroyed only here; no pending work still
        // writes its queries (callers read them only after the submission completed).
        unsafe { self.gpu.device().destroy_query_pool(self.raw, None) };
    }
}
