//! The lens renderer on the headless context: render a frame and read it back.

use crate::gpu::Result;
use crate::host::readback::{Download, Left};
use crate::host::Context;
use crate::pass::geometry::MeshBuffers;
use crate::pass::lens_render::*;
use crate::scene::Pose;
use std::time::Instant;

impl LensRenderer {
    /// Renders and reads back one frame of `mesh` (uploaded, its texture recorded, see
    /// [`MeshBuffers::record_upload`]) seen from `pose`, on the headless context.
    pub fn render(&mut self, ctx: &Context, mesh: &MeshBuffers, pose: &Pose) -> Result<LensFrame> {
        // SAFETY: no submission using it is pending (`submit` waits on its fence).
        unsafe { self.prepare(mesh, pose) }?;
        let start = Instant::now();
        let this = &*self;
        ctx.submit(|cmd| {
            // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass,
            // on the context's graphics queue; `prepare` ran above with `mesh`, which the caller
            // uploaded; `this` and `mesh` outlive the submission, which `submit` waits for.
            unsafe { this.record(cmd, mesh) };
            Ok(())
        })?;
        let frame_ms = start.elapsed().as_secs_f64() * 1e3;
        let target = &self.target;
        let film = Download::new(ctx.gpu(), &target.image, "film.download")?;
        ctx.submit(|cmd| {
            // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass,
            // after the frame's submission completed, which left the film in
            // COLOR_ATTACHMENT_OPTIMAL; `target` and `film` outlive this submission too.
            unsafe { film.record(ctx.gpu(), cmd, &target.image, Left::ColorAttachment) }
        })?;
        Ok(LensFrame {
            width: target.width,
            height: target.height,
            pixels: film.read()?,
            projections: self.draws.len(),
            frame_ms,
        })
    }
}
