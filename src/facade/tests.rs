//! The warper beside the machinery a user does not see: its f64 warp geometry against the
//! GPU, and recording into a caller's command buffer with images made the way an engine makes
//! them (the crate's own owning types stand in for the engine's).

use crate::imaging::cpu_warp;
use crate::testing::reference_camera;
use ash::vk;

use crate::gpu::{image_transition, record_compute_download, Access, Buffer, Image};
use crate::{Device, ImageRef, InverseMethod, Pixels, Raster, WarpMethod, WarpOptions, Warper};

/// A device of the test's own: a `Device` owns its context.
fn device() -> Device {
    Device::from_context(crate::testing::new_validated_context())
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
        crate::Border::Constant,
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
    // The maps: the exact source coordinate of every pixel, NaN where there is none; from a
    // map build of their own for the per-pixel warper, from the warper's own maps (built by
    // its first run) for a `lut` one.
    let mut lut_options = options.clone();
    lut_options.method = WarpMethod::Lut;
    let mut lut = Warper::new(device.gpu(), &camera, &lut_options).unwrap();
    lut.run(&device, &input).unwrap();
    for warper in [&warper, &lut] {
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
    }
    // A `lut` warper never run builds its maps for the read.
    let fresh = Warper::new(device.gpu(), &camera, &lut_options).unwrap();
    assert_eq!(fresh.maps(&device).unwrap(), lut.maps(&device).unwrap());
    device.check_validation().unwrap();
}

/// One frame's images and staging, as an engine would have them: the source it uploads, the
/// output it reads back.
struct CallerFrame {
    source: Image,
    output: Image,
    upload: Buffer,
    download: Buffer,
}

impl CallerFrame {
    fn new(gpu: &crate::Gpu, input: &Raster) -> Self {
        let (w, h) = (input.width, input.height);
        let usage = vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::TRANSFER_SRC
            | vk::ImageUsageFlags::TRANSFER_DST;
        let fmt = vk::Format::R8G8B8A8_UNORM;
        let Pixels::Rgba8(px) = &input.pixels else {
            unreachable!("the patterns are 8-bit")
        };
        CallerFrame {
            source: Image::new_2d(gpu, "caller.source", fmt, w, h, usage).unwrap(),
            output: Image::new_2d(gpu, "caller.output", fmt, w, h, usage).unwrap(),
            upload: Buffer::from_pod(
                gpu,
                "caller.upload",
                bytemuck::cast_slice::<[u8; 4], u8>(px),
                vk::BufferUsageFlags::TRANSFER_SRC,
            )
            .unwrap(),
            download: Buffer::new(
                gpu,
                "caller.download",
                (w * h * 4) as u64,
                vk::BufferUsageFlags::TRANSFER_DST,
                gpu_allocator::MemoryLocation::GpuToCpu,
            )
            .unwrap(),
        }
    }

    /// Records the source's upload and both images' transitions to what the warp needs.
    ///
    /// # Safety
    /// `cmd` is recording outside a render pass on a queue with graphics and compute.
    unsafe fn record_upload(&self, gpu: &crate::Gpu, cmd: vk::CommandBuffer) {
        let (source, output) = (&self.source, &self.output);
        // SAFETY: the function's contract; both images are this frame's own, fresh or done.
        unsafe {
            image_transition(gpu, cmd, source.raw, Access::Nothing, Access::TransferWrite);
            gpu.device().cmd_copy_buffer_to_image(
                cmd,
                self.upload.raw,
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
        }
    }

    fn image(i: &Image) -> ImageRef {
        ImageRef {
            image: i.raw,
            view: i.view,
            width: i.extent.width,
            height: i.extent.height,
        }
    }

    fn read(&self) -> Pixels {
        let e = self.output.extent;
        Pixels::Rgba8(
            self.download
                .read_pod((e.width * e.height) as usize)
                .unwrap(),
        )
    }
}

#[test]
fn a_warper_records_into_the_callers_command_buffer_with_the_callers_images() {
    let device = device();
    let gpu = device.gpu();
    let camera = reference_camera("prism_tilt");
    let mut warper = Warper::new(gpu, &camera, &WarpOptions::distort()).unwrap();
    let input = pattern(camera.width, camera.height);
    let expected = warper.run(&device, &input).unwrap();
    let frame = CallerFrame::new(gpu, &input);
    let image = CallerFrame::image;
    // A wrong size is refused before anything is recorded.
    let usage = vk::ImageUsageFlags::STORAGE;
    let tiny = Image::new_2d(gpu, "caller.tiny", vk::Format::R8G8B8A8_UNORM, 8, 8, usage).unwrap();
    let refused = device
        .context()
        .submit(|cmd| unsafe { warper.record(cmd, &image(&tiny), &image(&frame.output), None) });
    assert!(refused.unwrap_err().to_string().contains("8×8"));
    device
        .context()
        .submit(|cmd| {
            // SAFETY: `cmd` is recording outside a render pass on the context's queue; every
            // image and buffer outlives the submission, which `submit` waits for.
            unsafe {
                frame.record_upload(gpu, cmd);
                // The map was built by `run` on this warper already; an engine records the
                // prepare once. Recording it again rebuilds the same map.
                warper.record_prepare(cmd);
                warper.record(cmd, &image(&frame.source), &image(&frame.output), None)?;
                record_compute_download(gpu, cmd, &frame.output, &frame.download);
                crate::gpu::host_read_barrier(gpu, cmd);
            }
            Ok(())
        })
        .unwrap();
    assert_eq!(frame.read(), expected.image.pixels, "record and run differ");
    device.check_validation().unwrap();
}

#[test]
fn two_frames_in_flight_warp_other_images_without_waiting_for_each_other() {
    let device = device();
    let gpu = device.gpu();
    let camera = reference_camera("prism_tilt");
    let (w, h) = (camera.width, camera.height);
    let mut warper = Warper::new(gpu, &camera, &WarpOptions::distort()).unwrap();
    assert_eq!(WarpOptions::distort().frames_in_flight, 2);
    // Two frames, each with its own images, as a swapchain-fed engine has them.
    let mut inverted = pattern(w, h);
    if let Pixels::Rgba8(px) = &mut inverted.pixels {
        px.iter_mut().for_each(|q| q[0] = 255 - q[0]);
    }
    let inputs = [pattern(w, h), inverted];
    let expected: Vec<_> = inputs
        .iter()
        .map(|i| warper.run(&device, i).unwrap().image.pixels)
        .collect();
    let frames: Vec<_> = inputs.iter().map(|i| CallerFrame::new(gpu, i)).collect();
    let image = CallerFrame::image;
    // Both frames in one submission: the second is recorded while the first is still
    // pending, with other views. With one set it would be rewritten under the first.
    device
        .context()
        .submit(|cmd| {
            // SAFETY: `cmd` is recording outside a render pass on the context's queue; every
            // image and buffer outlives the submission, which `submit` waits for.
            unsafe {
                for f in &frames {
                    f.record_upload(gpu, cmd);
                }
                // Once, as an engine records it before its first frame.
                warper.record_prepare(cmd);
                for f in &frames {
                    warper.record(cmd, &image(&f.source), &image(&f.output), None)?;
                    record_compute_download(gpu, cmd, &f.output, &f.download);
                }
                crate::gpu::host_read_barrier(gpu, cmd);
            }
            Ok(())
        })
        .unwrap();
    for (f, want) in frames.iter().zip(&expected) {
        assert_eq!(&f.read(), want, "a frame in flight differs from its run");
    }
    device.check_validation().unwrap();
}
