//! The warper beside the machinery a user does not see: its f64 warp geometry against the
//! GPU, and recording into a caller's command buffer with images made the way an engine makes
//! them (the crate's own owning types stand in for the engine's).

use crate::host::ContextOptions;
use crate::host::{geometry_shader_discard_from_env, geometry_shader_from_env, Context};
use crate::imaging::cpu_warp;
use crate::{Camera, Device, InverseMethod, Pixels, Raster, WarpMethod, WarpOptions, Warper};

fn device() -> Device {
    Device::from_context(
        Context::new(ContextOptions {
            validation: true,
            device: std::env::var("VKLENS_DEVICE")
                .ok()
                .filter(|s| !s.is_empty()),
            geometry_shader: geometry_shader_from_env(),
            geometry_shader_discard: geometry_shader_discard_from_env(),
        })
        .expect(
            "a Vulkan device with the validation layer (README: the test command installs both)",
        ),
    )
}

fn reference_camera(name: &str) -> Camera {
    crate::io::reference::load_reference()
        .expect("shared reference file")
        .cases
        .iter()
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("no reference case {name}"))
        .camera()
        .expect("a valid reference camera")
}

fn pattern(width: u32, height: u32) -> Raster {
    Raster {
        width,
        height,
        pixels: Pixels::Rgba8(
            (0..width * height)
                .map(|i| {
                    let (x, y) = (i % width, i / width);
                    let check = ((x / 16 + y / 16) % 2) as u8 * 200;
                    [check, (x % 251) as u8, (y % 241) as u8, 255]
                })
                .collect(),
        ),
        bit_depth: crate::BitDepth::U8,
    }
}

#[test]
fn a_warper_matches_the_f64_reference_warp_and_its_maps_are_the_exact_coordinates() {
    let device = device();
    let camera = reference_camera("seed_fig2");
    let source = crate::overscan(&camera, 1.0).unwrap();
    let mut options = WarpOptions::distort();
    options.source_camera = Some(source.clone());
    options.method = WarpMethod::PerPixel(InverseMethod::Newton);
    let mut warper = Warper::new(device.gpu(), &camera, &options).unwrap();
    let input = pattern(source.width, source.height);
    let first = warper.run(&device, &input).unwrap();
    // Against the f64 reference warp: within one grey level where both have a source.
    let (reference, mask) = cpu_warp::warp(
        warper.geometry(),
        &input,
        crate::Sampling::Bilinear,
        [0.0; 4],
    );
    let mut worst = 0f32;
    for (i, (&m, &valid)) in mask.iter().zip(&first.mask).enumerate() {
        if m == 255 && valid {
            let (a, b) = (reference.rgba_f32(i), first.image.rgba_f32(i));
            worst = (0..4).map(|c| (a[c] - b[c]).abs()).fold(worst, f32::max);
        }
    }
    assert!(worst <= 1.0 / 255.0 + 1e-6, "worst {worst}");
    // The maps: the exact source coordinate of every pixel, NaN where there is none.
    let maps = warper.maps(&device).unwrap();
    let (w, h) = warper.output_size();
    assert_eq!(maps.len(), (w * h) as usize);
    let mut compared = 0;
    for y in (0..h).step_by(37) {
        for x in (0..w).step_by(41) {
            let m = maps[(y * w + x) as usize];
            let exact = warper
                .geometry()
                .source_coordinate(glam::DVec2::new(x as f64, y as f64), 1);
            match exact {
                Some(e) => {
                    let d = (m[0] as f64 - e.x).hypot(m[1] as f64 - e.y);
                    assert!(d < 1e-3, "({x}, {y}): map off by {d} px");
                    compared += 1;
                }
                None => assert!(m[0].is_nan() && m[1].is_nan(), "({x}, {y}): {m:?}"),
            }
        }
    }
    assert!(compared > 100);
    device.check_validation().unwrap();
}

#[test]
fn a_warper_records_into_the_callers_command_buffer_with_the_callers_images() {
    use crate::gpu::{image_transition, record_compute_download, Access, Buffer, Image};
    use crate::ImageRef;
    use ash::vk;
    let device = device();
    let gpu = device.gpu();
    let camera = reference_camera("prism_tilt");
    let (w, h) = (camera.width, camera.height);
    let mut warper = Warper::new(gpu, &camera, &WarpOptions::distort()).unwrap();
    let input = pattern(w, h);
    let expected = warper.run(&device, &input).unwrap();
    // The caller's images and staging, as an engine would have them.
    let usage = vk::ImageUsageFlags::STORAGE
        | vk::ImageUsageFlags::TRANSFER_SRC
        | vk::ImageUsageFlags::TRANSFER_DST;
    let fmt = vk::Format::R8G8B8A8_UNORM;
    let source = Image::new_2d(gpu, "caller.source", fmt, w, h, usage).unwrap();
    let output = Image::new_2d(gpu, "caller.output", fmt, w, h, usage).unwrap();
    let Pixels::Rgba8(px) = &input.pixels else {
        unreachable!()
    };
    let upload = Buffer::from_pod(
        gpu,
        "caller.upload",
        bytemuck::cast_slice::<[u8; 4], u8>(px),
        vk::BufferUsageFlags::TRANSFER_SRC,
    )
    .unwrap();
    let download = Buffer::new(
        gpu,
        "caller.download",
        (w * h * 4) as u64,
        vk::BufferUsageFlags::TRANSFER_DST,
        gpu_allocator::MemoryLocation::GpuToCpu,
    )
    .unwrap();
    let r = |i: &Image| ImageRef {
        image: i.raw,
        view: i.view,
        width: i.extent.width,
        height: i.extent.height,
    };
    // A wrong size is refused before anything is recorded.
    let tiny = Image::new_2d(gpu, "caller.tiny", fmt, 8, 8, usage).unwrap();
    let refused = device
        .context()
        .submit(|cmd| unsafe { warper.record(cmd, &r(&tiny), &r(&output), None) });
    assert!(refused.unwrap_err().to_string().contains("8×8"));
    device
        .context()
        .submit(|cmd| {
            unsafe {
                let d = gpu.device();
                image_transition(gpu, cmd, source.raw, Access::Nothing, Access::TransferWrite);
                d.cmd_copy_buffer_to_image(
                    cmd,
                    upload.raw,
                    source.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[source.whole_copy()],
                );
                image_transition(
                    gpu,
                    cmd,
                    source.raw,
                    Access::TransferWrite,
                    Access::ComputeRead,
                );
                image_transition(gpu, cmd, output.raw, Access::Nothing, Access::ComputeWrite);
                // The map was built by `run` on this warper already; an engine records the
                // prepare once. Recording it again rebuilds the same map.
                warper.record_prepare(cmd);
                warper.record(cmd, &r(&source), &r(&output), None)?;
                record_compute_download(gpu, cmd, &output, &download);
                crate::gpu::host_read_barrier(gpu, cmd);
            }
            Ok(())
        })
        .unwrap();
    let got: Vec<[u8; 4]> = download.read_pod((w * h) as usize).unwrap();
    assert_eq!(
        Pixels::Rgba8(got),
        expected.image.pixels,
        "record and run differ"
    );
    device.check_validation().unwrap();
}

#[test]
fn two_frames_in_flight_warp_other_images_without_waiting_for_each_other() {
    use crate::gpu::{image_barrier, record_compute_download, Buffer, Image};
    use crate::ImageRef;
    use ash::vk;
    let device = device();
    let gpu = device.gpu();
    let camera = reference_camera("prism_tilt");
    let (w, h) = (camera.width, camera.height);
    let mut warper = Warper::new(gpu, &camera, &WarpOptions::distort()).unwrap();
    assert_eq!(WarpOptions::distort().frames_in_flight, 2);
    // Two frames, each with its own images, as a swapchain-fed engine has them.
    let inputs = [pattern(w, h), {
        let mut p = pattern(w, h);
        if let Pixels::Rgba8(px) = &mut p.pixels {
            px.iter_mut().for_each(|q| q[0] = 255 - q[0]);
        }
        p
    }];
    let expected: Vec<_> = inputs
        .iter()
        .map(|i| warper.run(&device, i).unwrap().image.pixels)
        .collect();
    let usage = vk::ImageUsageFlags::STORAGE
        | vk::ImageUsageFlags::TRANSFER_SRC
        | vk::ImageUsageFlags::TRANSFER_DST;
    let fmt = vk::Format::R8G8B8A8_UNORM;
    let frames: Vec<_> = inputs
        .iter()
        .map(|input| {
            let Pixels::Rgba8(px) = &input.pixels else {
                unreachable!()
            };
            (
                Image::new_2d(gpu, "frame.source", fmt, w, h, usage).unwrap(),
                Image::new_2d(gpu, "frame.output", fmt, w, h, usage).unwrap(),
                Buffer::from_pod(
                    gpu,
                    "frame.upload",
                    bytemuck::cast_slice::<[u8; 4], u8>(px),
                    vk::BufferUsageFlags::TRANSFER_SRC,
                )
                .unwrap(),
                Buffer::new(
                    gpu,
                    "frame.download",
                    (w * h * 4) as u64,
                    vk::BufferUsageFlags::TRANSFER_DST,
                    gpu_allocator::MemoryLocation::GpuToCpu,
                )
                .unwrap(),
            )
        })
        .collect();
    let r = |i: &Image| ImageRef {
        image: i.raw,
        view: i.view,
        width: i.extent.width,
        height: i.extent.height,
    };
    // Both frames in one submission: the second is recorded while the first is still
    // pending, with other views. With one set it would be rewritten under the first.
    device
        .context()
        .submit(|cmd| {
            let top = (
                vk::PipelineStageFlags::TOP_OF_PIPE,
                vk::AccessFlags::empty(),
            );
            let copy_w = (
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_WRITE,
            );
            let read = (
                vk::PipelineStageFlags::COMPUTE_SHADER,
                vk::AccessFlags::SHADER_READ,
            );
            let write = (
                vk::PipelineStageFlags::COMPUTE_SHADER,
                vk::AccessFlags::SHADER_WRITE,
            );
            // SAFETY: `cmd` is recording outside a render pass on the context's compute
            // queue; every image and buffer outlives the submission, which `submit` waits for.
            unsafe {
                let d = gpu.device();
                for (source, output, upload, _) in &frames {
                    let to_dst = (
                        vk::ImageLayout::UNDEFINED,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    );
                    image_barrier(gpu, cmd, source.raw, to_dst, top, copy_w);
                    d.cmd_copy_buffer_to_image(
                        cmd,
                        upload.raw,
                        source.raw,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        &[source.whole_copy()],
                    );
                    let to_general = (
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        vk::ImageLayout::GENERAL,
                    );
                    image_barrier(gpu, cmd, source.raw, to_general, copy_w, read);
                    let fresh = (vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL);
                    image_barrier(gpu, cmd, output.raw, fresh, top, write);
                }
                // Once, as an engine records it before its first frame.
                warper.record_prepare(cmd);
                for (source, output, _, download) in &frames {
                    warper.record(cmd, &r(source), &r(output), None)?;
                    record_compute_download(gpu, cmd, output, download);
                }
                crate::gpu::host_read_barrier(gpu, cmd);
            }
            Ok(())
        })
        .unwrap();
    for ((_, _, _, download), want) in frames.iter().zip(&expected) {
        let got: Vec<[u8; 4]> = download.read_pod((w * h) as usize).unwrap();
        assert_eq!(
            &Pixels::Rgba8(got),
            want,
            "a frame in flight differs from its run"
        );
    }
    device.check_validation().unwrap();
}
