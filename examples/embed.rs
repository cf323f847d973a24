//! vklens inside a host engine. The "engine" owns everything: instance, device (with the one
//! feature the warp needs, `shaderStorageImageExtendedFormats`), allocator, images, command
//! buffer and submission. It records three passes into one command buffer:
//!
//!   1. its own "render": a clear of the pinhole image to a colour;
//!   2. vklens's warp: the pinhole image through Lambers et al.'s Fig. 2 lens;
//!   3. its own "present": a copy of the lens image to a host buffer;
//!
//! then writes `embed.png`. vklens creates no instance, device or queue and submits nothing.
//! The engine's side is plain `ash` and `gpu-allocator`; vklens's side is its public API alone.
//!
//! Run: `cargo run --release --example embed`

use std::sync::{Arc, Mutex};

use ash::vk;
use gpu_allocator::vulkan::{
    Allocation, AllocationCreateDesc, AllocationScheme, Allocator, AllocatorCreateDesc,
};
use gpu_allocator::MemoryLocation;
use vklens::{Camera, EnabledFeatures, Gpu, ImageRef, WarpOptions, Warper};

type Shared = Arc<Mutex<Allocator>>;
type AnyError = Box<dyn std::error::Error>;

/// One of the engine's images: a 2D storage image with its view and memory.
struct EngineImage {
    image: vk::Image,
    view: vk::ImageView,
    allocation: Allocation,
    width: u32,
    height: u32,
}

impl EngineImage {
    unsafe fn new(
        device: &ash::Device,
        allocator: &Shared,
        format: vk::Format,
        (width, height): (u32, u32),
    ) -> Result<Self, AnyError> {
        let usage = vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::TRANSFER_DST
            | vk::ImageUsageFlags::TRANSFER_SRC;
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D {
                width,
                height,
                depth: 1,
            })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let image = device.create_image(&info, None)?;
        let allocation = allocator
            .lock()
            .map_err(|_| "allocator poisoned")?
            .allocate(&AllocationCreateDesc {
                name: "engine image",
                requirements: device.get_image_memory_requirements(image),
                location: MemoryLocation::GpuOnly,
                linear: false,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })?;
        device.bind_image_memory(image, allocation.memory(), allocation.offset())?;
        let view = device.create_image_view(
            &vk::ImageViewCreateInfo::default()
                .image(image)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(format)
                .subresource_range(COLOR),
            None,
        )?;
        Ok(EngineImage {
            image,
            view,
            allocation,
            width,
            height,
        })
    }

    /// The image as vklens takes it.
    fn as_ref(&self) -> ImageRef {
        ImageRef {
            image: self.image,
            view: self.view,
            width: self.width,
            height: self.height,
        }
    }

    unsafe fn destroy(self, device: &ash::Device, allocator: &Shared) -> Result<(), AnyError> {
        device.destroy_image_view(self.view, None);
        device.destroy_image(self.image, None);
        allocator
            .lock()
            .map_err(|_| "allocator poisoned")?
            .free(self.allocation)?;
        Ok(())
    }
}

const COLOR: vk::ImageSubresourceRange = vk::ImageSubresourceRange {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    base_mip_level: 0,
    level_count: 1,
    base_array_layer: 0,
    layer_count: 1,
};

/// The engine's own layout transition of a whole colour image.
unsafe fn transition(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    from: (vk::PipelineStageFlags, vk::AccessFlags, vk::ImageLayout),
    to: (vk::PipelineStageFlags, vk::AccessFlags, vk::ImageLayout),
) {
    let barrier = vk::ImageMemoryBarrier::default()
        .src_access_mask(from.1)
        .dst_access_mask(to.1)
        .old_layout(from.2)
        .new_layout(to.2)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(COLOR);
    device.cmd_pipeline_barrier(
        cmd,
        from.0,
        to.0,
        vk::DependencyFlags::empty(),
        &[],
        &[],
        &[barrier],
    );
}

fn main() -> Result<(), AnyError> {
    let (w, h) = (800u32, 600u32);
    unsafe {
        // --- The engine's own Vulkan setup -------------------------------------------------
        let entry = ash::Entry::load()?;
        let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_1);
        let instance = entry.create_instance(
            &vk::InstanceCreateInfo::default().application_info(&app),
            None,
        )?;
        let physical = instance.enumerate_physical_devices()?[0];
        let family = instance
            .get_physical_device_queue_family_properties(physical)
            .iter()
            .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
            .ok_or("no compute queue")? as u32;
        let prio = [1.0];
        let queues = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(family)
            .queue_priorities(&prio)];
        let features =
            vk::PhysicalDeviceFeatures::default().shader_storage_image_extended_formats(true);
        let device = instance.create_device(
            physical,
            &vk::DeviceCreateInfo::default()
                .queue_create_infos(&queues)
                .enabled_features(&features),
            None,
        )?;
        let queue = device.get_device_queue(family, 0);
        let allocator = Arc::new(Mutex::new(Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })?));
        let pool = device.create_command_pool(
            &vk::CommandPoolCreateInfo::default().queue_family_index(family),
            None,
        )?;
        let cmd = device.allocate_command_buffers(
            &vk::CommandBufferAllocateInfo::default()
                .command_pool(pool)
                .command_buffer_count(1),
        )?[0];

        {
            // --- vklens, built from the engine's handles --------------------------------------
            let gpu = Gpu::from_caller(
                &instance,
                physical,
                device.clone(),
                queue,
                family,
                allocator.clone(),
                EnabledFeatures::default(),
            )?;
            let k = [[400.0, 0.0, 399.5], [0.0, 400.0, 299.5], [0.0, 0.0, 1.0]];
            let camera = Camera::from_opencv(k, &[-0.05, 0.01, 0.03, -0.01], (w, h))?;
            let mut options = WarpOptions::distort();
            options.fill = [0.0, 0.0, 0.0, 1.0];

            // The engine's images and a host-visible buffer to read the result back.
            let pinhole =
                EngineImage::new(&device, &allocator, vk::Format::R8G8B8A8_UNORM, (w, h))?;
            let lens = EngineImage::new(&device, &allocator, vk::Format::R8G8B8A8_UNORM, (w, h))?;
            let mask = EngineImage::new(&device, &allocator, vk::Format::R8_UNORM, (w, h))?;
            let size = u64::from(w * h * 4);
            let readback = device.create_buffer(
                &vk::BufferCreateInfo::default()
                    .size(size)
                    .usage(vk::BufferUsageFlags::TRANSFER_DST),
                None,
            )?;
            let readback_memory = allocator
                .lock()
                .map_err(|_| "allocator poisoned")?
                .allocate(&AllocationCreateDesc {
                    name: "engine readback",
                    requirements: device.get_buffer_memory_requirements(readback),
                    location: MemoryLocation::GpuToCpu,
                    linear: true,
                    allocation_scheme: AllocationScheme::GpuAllocatorManaged,
                })?;
            device.bind_buffer_memory(
                readback,
                readback_memory.memory(),
                readback_memory.offset(),
            )?;

            let mut warper = Warper::new(&gpu, &camera, &options)?;
            device.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default())?;
            let (top, transfer, compute, host) = (
                vk::PipelineStageFlags::TOP_OF_PIPE,
                vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::COMPUTE_SHADER,
                vk::PipelineStageFlags::HOST,
            );
            let none = vk::AccessFlags::empty();
            let general = vk::ImageLayout::GENERAL;

            // 1. The engine "renders" its pinhole image: a clear.
            let dst = vk::ImageLayout::TRANSFER_DST_OPTIMAL;
            transition(
                &device,
                cmd,
                pinhole.image,
                (top, none, vk::ImageLayout::UNDEFINED),
                (transfer, vk::AccessFlags::TRANSFER_WRITE, dst),
            );
            let clear = vk::ClearColorValue {
                float32: [0.2, 0.4, 0.8, 1.0],
            };
            device.cmd_clear_color_image(cmd, pinhole.image, dst, &clear, &[COLOR]);
            // The warp reads the rendered image as a storage image in GENERAL layout and
            // writes its outputs in GENERAL.
            transition(
                &device,
                cmd,
                pinhole.image,
                (transfer, vk::AccessFlags::TRANSFER_WRITE, dst),
                (compute, vk::AccessFlags::SHADER_READ, general),
            );
            for img in [&lens, &mask] {
                transition(
                    &device,
                    cmd,
                    img.image,
                    (top, none, vk::ImageLayout::UNDEFINED),
                    (compute, vk::AccessFlags::SHADER_WRITE, general),
                );
            }

            // 2. vklens: build the map (once per camera), then warp.
            warper.record_prepare(cmd);
            warper.record(cmd, &pinhole.as_ref(), &lens.as_ref(), Some(&mask.as_ref()))?;

            // 3. The engine "presents": copies the lens image out.
            let src = vk::ImageLayout::TRANSFER_SRC_OPTIMAL;
            transition(
                &device,
                cmd,
                lens.image,
                (compute, vk::AccessFlags::SHADER_WRITE, general),
                (transfer, vk::AccessFlags::TRANSFER_READ, src),
            );
            let region = [vk::BufferImageCopy {
                image_subresource: vk::ImageSubresourceLayers {
                    aspect_mask: vk::ImageAspectFlags::COLOR,
                    mip_level: 0,
                    base_array_layer: 0,
                    layer_count: 1,
                },
                image_extent: vk::Extent3D {
                    width: w,
                    height: h,
                    depth: 1,
                },
                ..Default::default()
            }];
            device.cmd_copy_image_to_buffer(cmd, lens.image, src, readback, &region);
            let to_host = vk::MemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                .dst_access_mask(vk::AccessFlags::HOST_READ);
            device.cmd_pipeline_barrier(
                cmd,
                transfer,
                host,
                vk::DependencyFlags::empty(),
                &[to_host],
                &[],
                &[],
            );
            device.end_command_buffer(cmd)?;
            let cmds = [cmd];
            device.queue_submit(
                queue,
                &[vk::SubmitInfo::default().command_buffers(&cmds)],
                vk::Fence::null(),
            )?;
            device.queue_wait_idle(queue)?;

            let pixels = readback_memory
                .mapped_slice()
                .ok_or("the readback buffer is not mapped")?[..size as usize]
                .to_vec();
            image::RgbaImage::from_raw(w, h, pixels)
                .ok_or("size")?
                .save("embed.png")?;
            println!(
                "wrote embed.png: the engine's image through Lambers et al.'s Fig. 2 lens ({})",
                gpu.device_name()
            );

            // The engine frees its own objects (vklens's warper goes first: it holds none of
            // them, but was recorded against them).
            drop(warper);
            device.destroy_buffer(readback, None);
            allocator
                .lock()
                .map_err(|_| "allocator poisoned")?
                .free(readback_memory)?;
            for img in [pinhole, lens, mask] {
                img.destroy(&device, &allocator)?;
            }
        }

        // --- The engine tears down what it made; vklens touched none of it -----------------
        device.destroy_command_pool(pool, None);
        drop(Arc::try_unwrap(allocator).map_err(|_| "allocator still shared")?);
        device.destroy_device(None);
        instance.destroy_instance(None);
    }
    Ok(())
}
