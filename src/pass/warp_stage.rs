//! The warp path on the GPU as one record-only stage: a pinhole render of the overscanned
//! source (colour left in `GENERAL`, its writes visible to compute), the warp reading it in
//! place, and optionally depth through a second, nearest warp (Lambers et al., Sec. 3.3).

use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::gpu::{Buffer, Image};
use crate::imaging::cpu_warp::Sampling;
use crate::imaging::{BitDepth, Pixels, Raster};
use crate::model::warp::WarpGeometry;
use crate::model::Camera;
use crate::pass::geometry::{
    ColorFormat, GeometryDesc, GeometryPass, GeometryTargets, MeshBuffers, Outputs, Projection,
};
use crate::pass::warp::{Coordinates, PixelFormat, WarpDesc, WarpPass};
use crate::{Error, Result};

/// The warp path on the GPU in one submission: pinhole render (colour left in `GENERAL`) →
/// compute warp reading it in place → optional readback. Nothing makes a round trip through
/// the host. `render` and `bench vertex` both drive it.
pub struct WarpStage {
    gpu: crate::gpu::Gpu,
    pub pass: GeometryPass,
    pub targets: GeometryTargets,
    pub warp: WarpPass,
    pub output: Image,
    pub mask: Image,
    download: Buffer,
    format: PixelFormat,
    /// The depth through the same warp (nearest, +inf fill), when asked for.
    pub depth: Option<DepthWarp>,
}

/// The second, nearest warp of a [`WarpStage`] that carries the pinhole render's depth.
pub struct DepthWarp {
    pub warp: WarpPass,
    /// R32F, the warp's output size, `GENERAL` after the warp.
    pub output: Image,
    /// Host copy of `output` for headless readback.
    download: Buffer,
}

impl DepthWarp {
    /// Records the copy of the warped depth to the host (after the warp).
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass, after the depth warp was recorded.
    pub unsafe fn record_download(&self, cmd: vk::CommandBuffer) {
        // SAFETY: the caller upholds the contract above; `download` was sized for `output`
        // (R32F, the warp's output size) and `output` has TRANSFER_SRC usage.
        unsafe {
            crate::gpu::record_compute_readback(self.warp.gpu(), cmd, &self.output, &self.download)
        };
    }

    /// The warped depth (after the submission completed): metres, +inf without a source.
    pub fn read(&self) -> Result<Vec<f32>> {
        let e = self.output.extent;
        self.download
            .read_pod::<f32>(e.width as usize * e.height as usize)
    }
}

impl WarpStage {
    /// A pinhole render with the `source` camera (colour in `format`, cleared to
    /// `background`), warped by `geometry` into its output size.
    pub fn new(
        gpu: &crate::gpu::Gpu,
        source: Camera,
        geometry: WarpGeometry,
        coordinates: Coordinates,
        format: ColorFormat,
        background: [f32; 4],
    ) -> Result<Self> {
        Self::with_depth(
            gpu,
            source,
            geometry,
            coordinates,
            format,
            background,
            false,
        )
    }

    /// As [`Self::new`]; with `depth`, the pinhole render also writes camera depth and a
    /// second warp (nearest, +inf where there is no source) carries it to the output.
    pub fn with_depth(
        gpu: &crate::gpu::Gpu,
        source: Camera,
        geometry: WarpGeometry,
        coordinates: Coordinates,
        format: ColorFormat,
        background: [f32; 4],
        depth: bool,
    ) -> Result<Self> {
        let pixel_format = match format {
            ColorFormat::Rgba8 => PixelFormat::Rgba8,
            ColorFormat::Rgba32F => PixelFormat::Rgba32F,
            ColorFormat::Rgba16F => {
                return Err(Error::input("the warp reads RGBA8 or RGBA32F sources"));
            }
        };
        let mut desc = GeometryDesc::new(
            source,
            Projection::Pinhole,
            Outputs {
                depth,
                ..Outputs::color_only(Some(format))
            },
        );
        desc.background = background;
        desc.final_layout = vk::ImageLayout::GENERAL;
        let pass = GeometryPass::new(gpu, desc)?;
        let targets = GeometryTargets::new(gpu, &pass)?;
        let (ow, oh) = geometry.output_size;
        let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
        let output = Image::new_2d(gpu, "warp_path.output", pixel_format.vk(), ow, oh, usage)?;
        let mask = Image::new_2d(gpu, "warp_path.mask", vk::Format::R8_UNORM, ow, oh, usage)?;
        let download = Buffer::new(
            gpu,
            "warp_path.download",
            ow as u64 * oh as u64 * pixel_format.bytes() as u64,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        let mut warp = WarpPass::new(
            gpu,
            WarpDesc {
                geometry,
                coordinates,
                sampling: Sampling::Bilinear,
                format: pixel_format,
                fill: background,
                write_mask: false,
            },
        )?;
        let color = targets
            .color()
            .ok_or_else(|| Error::internal("the warp stage's render has no colour target"))?;
        // SAFETY: no submission using it is pending (`submit` waits on its fence).
        unsafe { warp.bind(color.view, output.view, mask.view) };
        let depth = match targets.depth() {
            Some(source) => {
                // Depth follows the lens itself (the green channel's reference geometry,
                // unit scale), as the headless warp path does: one coordinate, nearest.
                let mut plain = warp.desc().geometry.clone();
                plain.chromatic = None;
                if let Some(cams) = plain.channel_cameras.take() {
                    let [_, green, _] = *cams;
                    plain.camera = green;
                }
                let mut depth_warp = WarpPass::new(
                    gpu,
                    WarpDesc {
                        geometry: plain,
                        sampling: Sampling::Nearest,
                        format: PixelFormat::R32Float,
                        fill: [f32::INFINITY; 4],
                        ..warp.desc().clone()
                    },
                )?;
                let r32f = PixelFormat::R32Float.vk();
                let output = Image::new_2d(gpu, "warp_path.depth", r32f, ow, oh, usage)?;
                // Neither warp writes its mask (write_mask is off): they can share one.
                // SAFETY: no submission using it is pending (`submit` waits on its fence).
                unsafe { depth_warp.bind(source.view, output.view, mask.view) };
                let download = Buffer::new(
                    gpu,
                    "warp_path.depth.download",
                    ow as u64 * oh as u64 * 4,
                    vk::BufferUsageFlags::TRANSFER_DST,
                    MemoryLocation::GpuToCpu,
                )?;
                Some(DepthWarp {
                    warp: depth_warp,
                    output,
                    download,
                })
            }
            None => None,
        };
        Ok(WarpStage {
            gpu: gpu.clone(),
            pass,
            targets,
            warp,
            output,
            mask,
            download,
            format: pixel_format,
            depth,
        })
    }

    /// Records the one-off work: output and mask to `GENERAL`, the warp's map builds.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass; not while earlier work is pending.
    pub unsafe fn record_prepare(&self, cmd: vk::CommandBuffer) {
        // SAFETY: the caller upholds `record_prepare`'s contract: `cmd` is recording outside a
        // render pass and no earlier work using these images is pending, so UNDEFINED is a
        // valid old layout for this stage's own output, mask and depth images. The warps'
        // `record_prepare` also need a compute queue, which this contract leaves implicit:
        // every caller records on a queue with graphics and compute.
        unsafe {
            let depth = self.depth.iter().map(|d| &d.output);
            crate::gpu::record_discard_for_compute_write(
                &self.gpu,
                cmd,
                [&self.output, &self.mask].into_iter().chain(depth),
            );
            self.warp.record_prepare(cmd);
            if let Some(d) = &self.depth {
                d.warp.record_prepare(cmd);
            }
        }
    }

    /// Records one frame: the pinhole render of `mesh` (bound with `pass.bind_mesh`), then
    /// the warp (and the depth warp). The render pass leaves the colour in `GENERAL`, its writes visible to compute.
    ///
    /// # Safety
    /// After [`Self::record_prepare`]; `mesh` uploaded and alive until the work completes.
    pub unsafe fn record(&self, cmd: vk::CommandBuffer, mesh: &MeshBuffers) {
        // SAFETY: the caller upholds `record`'s contract: `cmd` is recording (outside a render
        // pass, as for `record_prepare`) after `record_prepare`, `mesh` bound to `pass`,
        // uploaded and alive. `targets` were made for `pass`, whose final layout GENERAL and
        // end-of-pass dependency leave the colour (and depth) readable by the warps' compute.
        unsafe {
            self.pass.record(cmd, &self.targets, mesh);
            self.record_warps(cmd);
        }
    }

    /// Records the warps alone (colour, then depth when asked for), after the caller recorded
    /// the pinhole render.
    ///
    /// # Safety
    /// As [`Self::record`], with `self.pass` recorded first.
    pub unsafe fn record_warps(&self, cmd: vk::CommandBuffer) {
        // SAFETY: the caller upholds `record_warps`'s contract: `self.pass` was recorded first,
        // so the warps' sources are in GENERAL with their writes visible to compute, and
        // `record_prepare` put their outputs and mask in GENERAL; both warps were bound in
        // `with_depth`.
        unsafe {
            self.warp.record(cmd);
            if let Some(d) = &self.depth {
                d.warp.record(cmd);
            }
        }
    }

    /// Records the readback of the warped image (after [`Self::record`]).
    ///
    /// # Safety
    /// As [`Self::record`].
    pub unsafe fn record_download(&self, cmd: vk::CommandBuffer) {
        // SAFETY: the caller upholds `record_download`'s contract (after `record`): the warp
        // left `output` in GENERAL, and `download` was sized for it whole in `with_depth`.
        unsafe {
            crate::gpu::record_compute_readback(&self.gpu, cmd, &self.output, &self.download)
        };
    }

    /// The warped image (after the submission completed).
    pub fn read(&self) -> Result<Raster> {
        read_rgba(
            &self.download,
            self.output.extent,
            self.format == PixelFormat::Rgba8,
        )
    }
}

/// An RGBA image read back into `download`: 8-bit, or f32 samples.
pub(crate) fn read_rgba(
    download: &Buffer,
    extent: vk::Extent2D,
    eight_bit: bool,
) -> Result<Raster> {
    let n = extent.width as usize * extent.height as usize;
    let (pixels, bit_depth) = if eight_bit {
        (
            Pixels::Rgba8(download.read_pod::<[u8; 4]>(n)?),
            BitDepth::U8,
        )
    } else {
        (
            Pixels::Rgba32F(download.read_pod::<[f32; 4]>(n)?),
            BitDepth::F32,
        )
    };
    Ok(Raster {
        width: extent.width,
        height: extent.height,
        pixels,
        bit_depth,
    })
}
