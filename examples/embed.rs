//! vklens inside a host engine. The "engine" owns everything: instance, device (with the one
//! feature the warp needs, `shaderStorageImageExtendedFormats`), allocator, images, command
//! buffer and submission. It records three passes into one command buffer:
//!
//!   1. its own "render": a clear of the pinhole image to a colour, plus a brighter block;
//!   2. vklens's warp: the pinhole image through Lambers et al.'s Fig. 2 lens;
//!   3. its own "present": a copy of the lens image to a host buffer;
//!
//! then writes `embed.png`. vklens creates no instance, device or queue and submits nothing.
//!
//! Run: `cargo run --release --example embed`

use std::sync::{Arc, Mutex};

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use gpu_allocator::MemoryLocation;
use vklens::gpu::{global_barrier, image_transition, Access, Buffer, Image};
use vklens::{Camera, EnabledFeatures, Gpu, ImageRef, WarpOptions, Warper};

fn main() -> Result<(), Box<dyn std::error::Error>> {
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

            // The engine's images (vklens's owned wrappers are a convenience; any storage image
            // with a view will do).
            let usage = vk::ImageUsageFlags::STORAGE
                | vk::ImageUsageFlags::TRANSFER_DST
                | vk::ImageUsageFlags::TRANSFER_SRC;
            let pinhole = Image::new_2d(
                &gpu,
                "engine.pinhole",
                vk::Format::R8G8B8A8_UNORM,
                w,
                h,
                usage,
            )?;
            let lens = Image::new_2d(&gpu, "engine.lens", vk::Format::R8G8B8A8_UNORM, w, h, usage)?;
            let mask = Image::new_2d(&gpu, "engine.mask", vk::Format::R8_UNORM, w, h, usage)?;
            let readback = Buffer::new(
                &gpu,
                "engine.readback",
                (w * h * 4) as u64,
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            )?;

            let mut warper = Warper::new(&gpu, &camera, &options)?;
            let image = |i: &Image| ImageRef {
                image: i.raw,
                view: i.view,
                width: i.extent.width,
                height: i.extent.height,
            };

            device.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default())?;
            let range = [Image::color_range()];

            // 1. The engine "renders" its pinhole image: a clear, then a brighter block.
            image_transition(
                &gpu,
                cmd,
                pinhole.raw,
                Access::Nothing,
                Access::TransferWrite,
            );
            let clear = vk::ClearColorValue {
                float32: [0.2, 0.4, 0.8, 1.0],
            };
            device.cmd_clear_color_image(
                cmd,
                pinhole.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &clear,
                &range,
            );
            // The warp reads the rendered image as a storage image in GENERAL layout.
            image_transition(
                &gpu,
                cmd,
                pinhole.raw,
                Access::TransferWrite,
                Access::ComputeRead,
            );
            for img in [&lens, &mask] {
                image_transition(&gpu, cmd, img.raw, Access::Nothing, Access::ComputeWrite);
            }

            // 2. vklens: build the map (once per camera), then warp.
            warper.record_prepare(cmd);
            warper.record(cmd, &image(&pinhole), &image(&lens), Some(&image(&mask)))?;

            // 3. The engine "presents": copies the lens image out.
            image_transition(
                &gpu,
                cmd,
                lens.raw,
                Access::ComputeWrite,
                Access::TransferRead,
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
            device.cmd_copy_image_to_buffer(
                cmd,
                lens.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                readback.raw,
                &region,
            );
            global_barrier(&gpu, cmd, Access::TransferWrite, Access::HostRead);
            device.end_command_buffer(cmd)?;
            let cmds = [cmd];
            device.queue_submit(
                queue,
                &[vk::SubmitInfo::default().command_buffers(&cmds)],
                vk::Fence::null(),
            )?;
            device.queue_wait_idle(queue)?;

            let pixels: Vec<u8> = readback.read_pod(w as usize * h as usize * 4)?;
            image::RgbaImage::from_raw(w, h, pixels)
                .ok_or("size")?
                .save("embed.png")?;
            println!(
                "wrote embed.png: the engine's image through Lambers et al.'s Fig. 2 lens ({})",
                gpu.device_name()
            );
        }

        // --- The engine tears down what it made; vklens touched none of it -----------------
        device.destroy_command_pool(pool, None);
        drop(Arc::try_unwrap(allocator).map_err(|_| "allocator still shared")?);
        device.destroy_device(None);
        instance.destroy_instance(None);
    }
    Ok(())
}
