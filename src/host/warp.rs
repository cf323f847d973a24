//! Headless helpers for `pass::warp`: upload, record, submit, wait and read back.

use crate::gpu::{host_read_barrier, Result};
use crate::host::readback::{Download, Left};
use crate::host::warp_images::WarpImages;
use crate::host::Context;
use crate::imaging::cpu_warp::Sampling;
use crate::imaging::Raster;
use crate::model::warp::WarpGeometry;
use crate::pass::warp::*;

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
    let channels: Vec<usize> = if desc.geometry.is_chromatic() {
        vec![0, 1, 2]
    } else {
        vec![1]
    };
    let downloads = channels
        .iter()
        .map(|&c| Download::new(gpu, &pass.maps[c], "map.read"))
        .collect::<Result<Vec<_>>>()?;
    ctx.submit(|cmd| {
        // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass;
        // the maps are in GENERAL once built (by the prepare recorded here, or by an earlier
        // one that completed), written by compute, with TRANSFER_SRC usage; the copy goes back
        // to GENERAL, where the pass's warps read them. `pass` and `downloads` outlive the
        // submission, which `submit` waits for.
        unsafe {
            if prepare {
                pass.record_prepare(cmd);
            }
            for (&c, d) in channels.iter().zip(&downloads) {
                d.record(gpu, cmd, &pass.maps[c], Left::ComputeGeneral)?;
            }
        }
        Ok(())
    })?;
    downloads.iter().map(|d| d.read::<[f32; 2]>()).collect()
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
        border: crate::Border::Constant,
        format: PixelFormat::Rgba8,
        fill: [0.0; 4],
        write_mask: false,
    };
    let pass = WarpPass::new(gpu, desc)?;
    read_pass_maps(ctx, &pass, true)
}
