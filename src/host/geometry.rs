//! Headless helpers for `pass::geometry`: upload, record, submit, wait and read back.

use crate::gpu::Result;
use crate::host::Context;
use crate::imaging::Raster;
use crate::pass::geometry::*;
use crate::scene::{Mesh, Pose};

/// Renders `mesh` once through a headless context: upload, draw, read back.
pub fn render(
    ctx: &Context,
    desc: GeometryDesc,
    mesh: &Mesh,
    texture: Option<&Raster>,
    pose: &Pose,
    previous: &Pose,
) -> Result<Rendered> {
    let gpu = ctx.gpu();
    let buffers = MeshBuffers::new(gpu, mesh, texture)?;
    let mut pass = GeometryPass::new(gpu, desc)?;
    // SAFETY: no submission using it is pending (`submit` waits on its fence).
    unsafe { pass.bind_mesh(&buffers) };
    // SAFETY: no submission using it is pending (`submit` waits on its fence).
    unsafe { pass.set_frame(pose, previous) }?;
    let targets = GeometryTargets::new(gpu, &pass)?;
    ctx.submit(|cmd| {
        // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass, on
        // a graphics queue; the texture upload comes before the draw that samples it and
        // `targets` were made for `pass`. The download needs the outputs in
        // TRANSFER_SRC_OPTIMAL: `GeometryDesc::new`'s default final layout, which this safe
        // function assumes but does not check in `desc`. Everything outlives the submission,
        // which `submit` waits for.
        unsafe {
            buffers.record_upload(cmd);
            pass.record(cmd, &targets, &buffers);
            targets.record_download(cmd);
        }
        Ok(())
    })?;
    targets.read()
}

/// Uploads `mesh` (and its texture) for any number of draws, and waits.
pub fn upload_mesh(ctx: &Context, mesh: &Mesh, texture: Option<&Raster>) -> Result<MeshBuffers> {
    let buffers = MeshBuffers::new(ctx.gpu(), mesh, texture)?;
    ctx.submit(|cmd| {
        // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass;
        // `buffers` outlives the submission, which `submit` waits for.
        unsafe { buffers.record_upload(cmd) };
        Ok(())
    })?;
    Ok(buffers)
}
