//! Headless helper for `pass::sphere_warp`: upload a cube map or a panorama, warp, read back.

use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::gpu::{
    image_transition, record_compute_download, Access, Buffer, Error, Gpu, Image, Result,
};
use crate::host::Context;
use crate::imaging::{BitDepth, Pixels, Raster};
use crate::model::Camera;
use crate::pass::sphere_warp::{CubeFace, SphereSource, SphereWarpOptions, SphereWarpPass};

/// Checks a source: a cube's six faces square and of one size, every raster holding colour.
fn check_source(gpu: &Gpu, source: &SphereSource) -> Result<(u32, u32)> {
    let rasters = source.rasters();
    for r in &rasters {
        r.check().map_err(|e| Error::Input(e.to_string()))?;
        if matches!(r.pixels, Pixels::R32Uint(_)) {
            return Err(Error::Input(
                "a 360° source must hold colour (object IDs are not filtered)".into(),
            ));
        }
    }
    let size = (rasters[0].width, rasters[0].height);
    if let SphereSource::Cube(faces) = source {
        for (face, r) in CubeFace::ALL.iter().zip(faces.iter()) {
            if (r.width, r.height) != (size.0, size.0) {
                return Err(Error::Input(format!(
                    "cube face {} is {}×{}; every face must be square and of one size ({}×{} as the first)",
                    face.name(),
                    r.width,
                    r.height,
                    size.0,
                    size.0
                )));
            }
        }
    }
    let (max, what) = match source {
        SphereSource::Cube(_) => (gpu.max_cube_side(), "cube map face"),
        SphereSource::Equirect(_) => (gpu.max_image_side(), "image"),
    };
    if size.0 > max || size.1 > max {
        return Err(Error::Input(format!(
            "the 360° source is {}×{}, larger than the device's {max} px {what} limit",
            size.0, size.1
        )));
    }
    let float = rasters
        .iter()
        .any(|r| !matches!(r.pixels, Pixels::Rgba8(_)));
    if float && !gpu.supports_float_linear_filter() {
        return Err(Error::Unsupported(format!(
            "{} cannot filter RGBA32F images linearly, which a 16-bit or float 360° source needs: give an 8-bit source",
            gpu.device_name()
        )));
    }
    Ok(size)
}

/// Runs a sphere warp once through a headless context: upload, warp, download. The output
/// has the camera's size, and the bit depth of the source (8-bit stays 8-bit).
pub fn run_sphere_warp(
    ctx: &Context,
    camera: &Camera,
    source: SphereSource,
    options: &SphereWarpOptions,
) -> Result<(Raster, Vec<u8>)> {
    let gpu = ctx.gpu();
    let (sw, sh) = check_source(gpu, &source)?;
    let rasters = source.rasters();
    let eight_bit = rasters.iter().all(|r| matches!(r.pixels, Pixels::Rgba8(_)));
    let (format, texel) = if eight_bit {
        (vk::Format::R8G8B8A8_UNORM, 4usize)
    } else {
        (vk::Format::R32G32B32A32_SFLOAT, 16)
    };
    let equirect = matches!(source, SphereSource::Equirect(_));
    let sampled = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
    let image = if equirect {
        Image::new_2d(gpu, "sphere.source", format, sw, sh, sampled)?
    } else {
        Image::new_cube(gpu, "sphere.cube", format, sw, sampled)?
    };
    // Layers in the order the cube image holds them.
    let mut ordered: Vec<&Raster> = rasters.clone();
    if let SphereSource::Cube(faces) = &source {
        for (face, r) in CubeFace::ALL.iter().zip(faces.iter()) {
            ordered[face.layer() as usize] = r;
        }
    }
    let mut bytes: Vec<u8> = Vec::with_capacity(ordered.len() * sw as usize * sh as usize * texel);
    for r in &ordered {
        match &r.pixels {
            Pixels::Rgba8(p) if eight_bit => bytes.extend(p.iter().flatten()),
            _ => {
                let v: Vec<[f32; 4]> = (0..r.len()).map(|i| r.rgba_f32(i)).collect();
                bytes.extend_from_slice(bytemuck::cast_slice(&v));
            }
        }
    }
    let upload = Buffer::from_pod(
        gpu,
        "sphere.upload",
        &bytes,
        vk::BufferUsageFlags::TRANSFER_SRC,
    )?;
    let (ow, oh) = (camera.width, camera.height);
    let storage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
    let output = Image::new_2d(
        gpu,
        "sphere.output",
        vk::Format::R32G32B32A32_SFLOAT,
        ow,
        oh,
        storage,
    )?;
    let mask = Image::new_2d(gpu, "sphere.mask", vk::Format::R8_UNORM, ow, oh, storage)?;
    let n = ow as u64 * oh as u64;
    let download = Buffer::new(
        gpu,
        "sphere.download",
        n * 16,
        vk::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuToCpu,
    )?;
    let download_mask = Buffer::new(
        gpu,
        "sphere.download.mask",
        n,
        vk::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuToCpu,
    )?;
    let mut pass = SphereWarpPass::new(gpu, camera, equirect, options)?;
    // SAFETY: no submission using the pass is pending; the views are live and of the kinds
    // `bind` asks (a cube or 2D sampled view, storage images), in the layouts set below.
    unsafe { pass.bind(image.view, output.view, mask.view) };
    ctx.submit(|cmd| {
        let d = gpu.device();
        // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass.
        // Every image was made above with the usages used here; the upload holds every layer
        // tightly packed in the image's format (`check_source` checked the sizes), and the
        // barriers put each image in the layout the next command expects. Everything outlives
        // the submission, which `submit` waits for.
        unsafe {
            image_transition(gpu, cmd, image.raw, Access::Nothing, Access::TransferWrite);
            d.cmd_copy_buffer_to_image(
                cmd,
                upload.raw,
                image.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[image.whole_copy()],
            );
            image_transition(
                gpu,
                cmd,
                image.raw,
                Access::TransferWrite,
                Access::ComputeSampled,
            );
            crate::gpu::record_discard_for_compute_write(gpu, cmd, [&output, &mask]);
            pass.record(cmd);
            record_compute_download(gpu, cmd, &output, &download);
            record_compute_download(gpu, cmd, &mask, &download_mask);
        }
        Ok(())
    })?;
    let texels: Vec<[f32; 4]> = download.read_pod(n as usize)?;
    let mask_bytes = download_mask.bytes(n as usize)?.to_vec();
    let depth = rasters[0].bit_depth;
    let pixels = if eight_bit {
        Pixels::Rgba8(
            texels
                .iter()
                .map(|t| t.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8))
                .collect(),
        )
    } else {
        Pixels::Rgba32F(texels)
    };
    let bit_depth = if eight_bit { BitDepth::U8 } else { depth };
    Ok((
        Raster {
            width: ow,
            height: oh,
            pixels,
            bit_depth,
        },
        mask_bytes,
    ))
}
