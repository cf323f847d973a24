//! Headless helpers for `pass::warp_raster`: upload, record, submit, wait and read back.

use crate::gpu::{global_barrier, Access, Result};
use crate::host::readback::{Download, Left};
use crate::host::warp_images::WarpImages;
use crate::host::Context;
use crate::imaging::Raster;
use crate::pass::mesh_warp::MeshWarpTarget;
use crate::pass::warp::{WarpDesc, WarpPass};
use crate::pass::warp_raster::*;
use ash::vk;

/// Runs the fragment-shader map warp once through a headless context (the maps built by a
/// [`WarpPass`] for `desc` first): the warped image.
pub fn run_raster_warp(ctx: &Context, desc: WarpDesc, source: &Raster) -> Result<Raster> {
    let gpu = ctx.gpu();
    let images = WarpImages::new(gpu, &desc, source)?;
    let maps = WarpPass::new(gpu, desc)?;
    let mut pass = RasterWarpPass::new(gpu, &maps, vk::ImageLayout::TRANSFER_SRC_OPTIMAL)?;
    // SAFETY: no submission using it is pending (`submit` waits on its fence).
    unsafe { pass.bind(images.source.view) };
    let target =
        MeshWarpTarget::for_render_pass(gpu, &pass.render_pass, pass.output_size, pass.format)?;
    let download = Download::new(gpu, &target.image, "mesh_warp.download")?;
    ctx.submit(|cmd| {
        // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass.
        // The upload and map builds come first and the barrier below makes their writes
        // visible to the fragment shader, as `record` asks; `target` was made for this pass's
        // render pass and size; everything outlives the submission, which `submit` waits for.
        unsafe {
            images.record_upload(cmd);
            maps.record_prepare(cmd);
            // The maps (compute) and the source (upload) are read by the fragment shader.
            global_barrier(
                gpu,
                cmd,
                [Access::ComputeWrite, Access::TransferWrite],
                Access::FragmentRead,
            );
            pass.record(cmd, &target.framebuffer);
            download.record(gpu, cmd, &target.image, Left::TransferSource)
        }
    })?;
    download.read_rgba()
}
