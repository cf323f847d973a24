//! Headless helpers for `pass::geometry`: upload, record, submit, wait and read back.

use crate::gpu::{Gpu, Result};
use crate::host::readback::{Download, Left};
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
    render_moving(ctx, desc, mesh, texture, (pose, pose), (previous, previous))
}

/// As [`render`] for a camera that moves during the readout: `(pose, end)` are the poses when
/// the frame's first and last lines are read, `previous` the same pair for the frame flow
/// starts from (a rolling shutter's readout in `desc.readout`; see
/// [`GeometryPass::set_moving_frame`]).
pub fn render_moving(
    ctx: &Context,
    desc: GeometryDesc,
    mesh: &Mesh,
    texture: Option<&Raster>,
    motion: (&Pose, &Pose),
    previous: (&Pose, &Pose),
) -> Result<Rendered> {
    let gpu = ctx.gpu();
    let buffers = MeshBuffers::new(gpu, mesh, texture)?;
    let mut pass = GeometryPass::new(gpu, desc)?;
    // SAFETY: no submission using it is pending (`submit` waits on its fence).
    unsafe { pass.bind_mesh(&buffers) };
    // SAFETY: no submission using it is pending (`submit` waits on its fence).
    unsafe { pass.set_moving_frame(motion, previous) }?;
    let targets = GeometryTargets::new(gpu, &pass)?;
    let readback = TargetsReadback::new(gpu, &targets)?;
    ctx.submit(|cmd| {
        // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass, on
        // a graphics queue; the texture upload comes before the draw that samples it and
        // `targets` were made for `pass`. The readback is told the outputs' layout from
        // `desc`; everything outlives the submission, which `submit` waits for.
        unsafe {
            buffers.record_upload(cmd);
            pass.record(cmd, &targets, &buffers);
            readback.record(gpu, cmd, &targets, pass.desc().final_layout)
        }
    })?;
    readback.read()
}

/// Host buffers for every output of a [`GeometryTargets`], and their reading into a
/// [`Rendered`].
pub struct TargetsReadback {
    /// By location: colour, IDs, flow, depth, range.
    slots: [Option<Download>; 5],
    extent: ash::vk::Extent2D,
}

impl TargetsReadback {
    /// Buffers for every output `targets` has.
    pub fn new(gpu: &Gpu, targets: &GeometryTargets) -> Result<Self> {
        let names = [
            "geometry.color.download",
            "geometry.ids.download",
            "geometry.flow.download",
            "geometry.depth.download",
            "geometry.range.download",
        ];
        let images = targets.images();
        let mut slots: [Option<Download>; 5] = Default::default();
        for (i, image) in images.iter().enumerate() {
            if let Some(image) = image {
                slots[i] = Some(Download::new(gpu, image, names[i])?);
            }
        }
        Ok(TargetsReadback {
            slots,
            extent: targets.extent(),
        })
    }

    /// Records the copy of every output, which the pass left in `layout` (its
    /// `final_layout`: `TRANSFER_SRC_OPTIMAL`, or `GENERAL` for a warp's source).
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass after [`GeometryPass::record`] into
    /// `targets` (those this readback was made for); the buffers stay alive until the work
    /// completes.
    pub unsafe fn record(
        &self,
        gpu: &Gpu,
        cmd: ash::vk::CommandBuffer,
        targets: &GeometryTargets,
        layout: ash::vk::ImageLayout,
    ) -> Result<()> {
        let left = if layout == ash::vk::ImageLayout::GENERAL {
            Left::ComputeGeneral
        } else if layout == ash::vk::ImageLayout::TRANSFER_SRC_OPTIMAL {
            Left::TransferSource
        } else {
            return Err(crate::gpu::Error::internal(format!(
                "no readback of geometry outputs left in {layout:?}"
            )));
        };
        for (download, image) in self.slots.iter().zip(targets.images()) {
            if let (Some(d), Some(image)) = (download, image) {
                // SAFETY: the caller upholds this function's contract: the pass was recorded
                // into these targets, which it left in `layout`; `record` checks that each
                // image is the one its buffer was made for.
                unsafe { d.record(gpu, cmd, image, left) }?;
            }
        }
        Ok(())
    }

    /// The outputs (after the submission completed).
    pub fn read(&self) -> Result<Rendered> {
        let mut out = Rendered {
            width: self.extent.width,
            height: self.extent.height,
            ..Default::default()
        };
        if let Some(d) = &self.slots[0] {
            out.color = Some(d.read_rgba()?);
        }
        if let Some(d) = &self.slots[1] {
            out.ids = Some(d.read::<u32>()?);
        }
        if let Some(d) = &self.slots[2] {
            out.flow = Some(d.read::<[f32; 2]>()?);
        }
        if let Some(d) = &self.slots[3] {
            out.depth = Some(d.read::<f32>()?);
        }
        if let Some(d) = &self.slots[4] {
            out.range = Some(d.read::<f32>()?);
        }
        Ok(out)
    }
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
