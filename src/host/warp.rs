//! Headless helpers for `pass::warp`: upload, record, submit, wait and read back.

use crate::gpu::record_compute_readback;
use crate::gpu::{host_read_barrier, Buffer, Result};
use crate::host::warp_images::WarpImages;
use crate::host::Context;
use crate::imaging::cpu_warp::Sampling;
use crate::imaging::Raster;
use crate::model::warp::WarpGeometry;
use crate::pass::warp::*;
use ash::vk;
use gpu_allocator::MemoryLocation;

/// One submission of a bound warp through staged images: upload what is staged, build the
/// maps first when `prepare` (the first run), warp, download; then waits.
pub(crate) fn run_staged(
    ctx: &Context,
    images: &WarpImages,
    pass: &WarpPass,
    prepare: bool,
) -> Result<()> {
    let gpu = ctx.gpu();
    ctx.submit(|cmd| {
        // SAFETY: `cmd` is a fresh primary command buffer outside any render pass; `pass` is
        // bound to `images`' views by the caller, and every image recorded here outlives the
        // submission, which `submit` waits for.
        unsafe {
            images.record_upload(cmd);
            if prepare {
                pass.record_prepare(cmd);
            }
            pass.record(cmd);
            images.record_download(cmd);
            host_read_barrier(gpu, cmd);
        }
        Ok(())
    })
}

/// Runs a warp once through a headless context: upload, prepare, warp, download.
pub fn run_warp(ctx: &Context, desc: WarpDesc, source: &Raster) -> Result<(Raster, Vec<u8>)> {
    let gpu = ctx.gpu();
    let images = WarpImages::new(gpu, &desc, source)?;
    let mut pass = WarpPass::new(gpu, desc)?;
    // SAFETY: no submission using it is pending (`submit` waits on its fence).
    unsafe { pass.bind(images.source.view, images.output.view, images.mask.view) };
    run_staged(ctx, &images, &pass, true)?;
    images.read(source.bit_depth)
}

/// Reads back the coordinate maps of `pass` (a pass whose coordinates come from a map),
/// recording its map build first when `prepare` (a pass whose maps were never built): per
/// built channel (G only without chromatic aberration; else R, G, B), row-major `[x, y]`
/// source positions, NaN where there is none.
pub(crate) fn read_pass_maps(
    ctx: &Context,
    pass: &WarpPass,
    prepare: bool,
) -> Result<Vec<Vec<[f32; 2]>>> {
    let desc = pass.desc();
    if !desc.coordinates.uses_map() {
        return Err(crate::Error::internal(
            "an analytic warp has no maps to read back",
        ));
    }
    let gpu = ctx.gpu();
    let (w, h) = desc.geometry.output_size;
    let channels: Vec<usize> = if desc.geometry.is_chromatic() {
        vec![0, 1, 2]
    } else {
        vec![1]
    };
    let buffers = channels
        .iter()
        .map(|_| {
            Buffer::new(
                gpu,
                "map.read",
                w as u64 * h as u64 * 8,
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            )
        })
        .collect::<Result<Vec<_>>>()?;
    ctx.submit(|cmd| {
        // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass;
        // the maps are in GENERAL once built (by the prepare recorded here, or by an earlier
        // one that completed), each channel's map is a real `w × h` RG32F image (8 bytes a
        // texel, as each buffer is sized) with TRANSFER_SRC usage, and `pass` and `buffers`
        // outlive the submission, which `submit` waits for.
        unsafe {
            if prepare {
                pass.record_prepare(cmd);
            }
            for (&c, buf) in channels.iter().zip(&buffers) {
                // The copy reads what the map build wrote; the map goes back to GENERAL,
                // where the pass's warps read it.
                record_compute_readback(gpu, cmd, &pass.maps[c], buf);
            }
        }
        Ok(())
    })?;
    buffers
        .iter()
        .map(|b| b.read_pod::<[f32; 2]>(w as usize * h as usize))
        .collect()
}

/// Builds `geometry`'s coordinate maps on the GPU and reads them back: per built channel
/// (G only without chromatic aberration; else R, G, B), row-major `[x, y]` source positions,
/// NaN where there is none. The same code the warp runs per pixel in analytic mode.
pub fn read_maps(
    ctx: &Context,
    geometry: &WarpGeometry,
    coordinates: Coordinates,
) -> Result<Vec<Vec<[f32; 2]>>> {
    let gpu = ctx.gpu();
    let desc = WarpDesc {
        geometry: geometry.clone(),
        coordinates,
        sampling: Sampling::Bilinear,
        format: PixelFormat::Rgba8,
        fill: [0.0; 4],
        write_mask: false,
    };
    let pass = WarpPass::new(gpu, desc)?;
    read_pass_maps(ctx, &pass, true)
}
