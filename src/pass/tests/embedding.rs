//! vklens inside someone else's engine: the caller creates the instance, device, queue,
//! allocator and command buffer (with the validation layer on); vklens only records. After
//! vklens's objects are dropped the caller destroys its own device — vklens must not have.

use std::sync::{Arc, Mutex};

use crate::gpu::host_read_barrier;
use crate::gpu::{Buffer, EnabledFeatures, Gpu};
use crate::model::InverseMethod;
use crate::pass::{PointsMode, PointsPass, Precision};
use ash::vk;
use glam::DVec2;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use gpu_allocator::MemoryLocation;

#[test]
fn a_pass_records_into_the_callers_command_buffer_on_the_callers_device() {
    unsafe {
        let entry = ash::Entry::load().expect("libvulkan");
        let layers = [c"VK_LAYER_KHRONOS_validation".as_ptr()];
        let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_1);
        let instance = entry
            .create_instance(
                &vk::InstanceCreateInfo::default()
                    .application_info(&app)
                    .enabled_layer_names(&layers),
                None,
            )
            .expect("instance with validation");
        let physical = instance.enumerate_physical_devices().unwrap()[0];
        let family = instance
            .get_physical_device_queue_family_properties(physical)
            .iter()
            .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
            .unwrap() as u32;
        let prio = [1.0];
        let queues = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(family)
            .queue_priorities(&prio)];
        let device = instance
            .create_device(
                physical,
                &vk::DeviceCreateInfo::default().queue_create_infos(&queues),
                None,
            )
            .unwrap();
        let queue = device.get_device_queue(family, 0);
        let allocator = Arc::new(Mutex::new(
            Allocator::new(&AllocatorCreateDesc {
                instance: instance.clone(),
                device: device.clone(),
                physical_device: physical,
                debug_settings: Default::default(),
                buffer_device_address: false,
                allocation_sizes: Default::default(),
            })
            .unwrap(),
        ));
        let pool = device
            .create_command_pool(
                &vk::CommandPoolCreateInfo::default().queue_family_index(family),
                None,
            )
            .unwrap();
        let cmd = device
            .allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(pool)
                    .command_buffer_count(1),
            )
            .unwrap()[0];

        {
            let gpu = Gpu::from_caller(
                &instance,
                physical,
                device.clone(),
                queue,
                family,
                allocator.clone(),
                EnabledFeatures::default(),
            )
            .unwrap();
            let reference = crate::io::reference::load_reference().unwrap();
            let case = &reference.cases[0];
            let cam = case.camera().unwrap();
            let pixels: Vec<[f32; 2]> = case
                .points
                .iter()
                .map(|p| p.distorted_pixel.map(|v| v as f32))
                .collect();
            let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
            let ins = Buffer::from_pod(&gpu, "in", &pixels, usage).unwrap();
            let outs = Buffer::new(
                &gpu,
                "out",
                (pixels.len() * 16) as u64,
                usage,
                MemoryLocation::GpuToCpu,
            )
            .unwrap();
            let mut pass = PointsPass::new(
                &gpu,
                &cam,
                PointsMode::Undistort(InverseMethod::Newton),
                Precision::F32,
            )
            .unwrap();
            // Without shaderFloat64 enabled by the caller, the f64 variant is refused up front.
            assert!(PointsPass::new(&gpu, &cam, PointsMode::Distort, Precision::F64).is_err());
            pass.bind(&ins, &outs);

            // The "engine" frame: its own command buffer, its own submission.
            device
                .begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default())
                .unwrap();
            pass.record(cmd, pixels.len() as u32);
            host_read_barrier(&gpu, cmd);
            device.end_command_buffer(cmd).unwrap();
            let cmds = [cmd];
            device
                .queue_submit(
                    queue,
                    &[vk::SubmitInfo::default().command_buffers(&cmds)],
                    vk::Fence::null(),
                )
                .unwrap();
            device.queue_wait_idle(queue).unwrap();

            let out: Vec<[f32; 4]> = outs.read_pod(pixels.len()).unwrap();
            for (p, o) in case.points.iter().zip(&out) {
                assert_eq!(o[2], 1.0);
                let err = (DVec2::new(o[0] as f64, o[1] as f64)
                    - DVec2::from(p.undistorted_normalized))
                .length()
                    * cam.intrinsics.fx;
                assert!(err < 1e-3, "{err}");
            }
        }
        // vklens's objects are gone; the allocator and device are still the caller's to destroy.
        device.destroy_command_pool(pool, None);
        // Unwrapping proves vklens holds no clone; the allocator is dropped right here, before
        // the device it allocates from.
        assert!(
            Arc::try_unwrap(allocator).is_ok(),
            "vklens released the allocator"
        );
        device.destroy_device(None);
        instance.destroy_instance(None);
    }
}
