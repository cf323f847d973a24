//! Headless helpers for `pass::mesh_warp`: upload, record, submit, wait and read back.

use crate::gpu::{Error, Result};
use crate::host::readback::{Download, Left};
use crate::host::Context;
use crate::imaging::Raster;
use crate::model::warp::WarpGeometry;
use crate::pass::geometry::Texture;
use crate::pass::mesh_warp::*;
use ash::vk;

/// Runs a mesh warp once through a headless context: the warped image, or (with
/// [`MeshWarpOutput::Coordinates`]) the interpolated source coordinates, alpha 0 where no cell
/// was drawn.
pub fn run_mesh_warp(
    ctx: &Context,
    geometry: &WarpGeometry,
    n: u32,
    output: MeshWarpOutput,
    source: &Raster,
) -> Result<Raster> {
    let gpu = ctx.gpu();
    if (source.width, source.height) != geometry.source_size {
        return Err(Error::Input(format!(
            "the source is {}×{} but the warp expects {}×{}",
            source.width, source.height, geometry.source_size.0, geometry.source_size.1
        )));
    }
    let texture = Texture::new(gpu, source)?;
    let mut pass = MeshWarpPass::new(
        gpu,
        geometry,
        n,
        output,
        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
    )?;
    // SAFETY: no submission using it is pending (`submit` waits on its fence).
    unsafe { pass.bind(texture.image.view) };
    let target = MeshWarpTarget::new(gpu, &pass)?;
    let download = Download::new(gpu, &target.image, "mesh_warp.download")?;
    ctx.submit(|cmd| {
        // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass.
        // The upload leaves the texture in SHADER_READ_ONLY_OPTIMAL, visible to fragment
        // shaders, before the warp samples it; the pass's final layout is TRANSFER_SRC_OPTIMAL,
        // as the download needs; everything outlives the submission, which `submit` waits for.
        unsafe {
            texture.record_upload(cmd);
            pass.record(cmd, &target.framebuffer);
            download.record(gpu, cmd, &target.image, Left::TransferSource)
        }
    })?;
    download.read_rgba()
}
