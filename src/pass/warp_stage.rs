//! The warp path on the GPU as one record-only stage: a pinhole render of the overscanned
//! source (colour left in `GENERAL`, its writes visible to compute), the warp reading it in
//! place, and optionally object IDs and depth through nearest warps of their own (Lambers et
//! al., Sec. 3.3: nearest, since IDs and depths must not be blended across an edge).

use ash::vk;

use crate::gpu::Image;
use crate::imaging::cpu_warp::Sampling;
use crate::model::warp::WarpGeometry;
use crate::model::Camera;
use crate::pass::geometry::{
    ColorFormat, GeometryDesc, GeometryPass, GeometryTargets, MeshBuffers, Outputs, Projection,
};
use crate::pass::warp::{Coordinates, PixelFormat, WarpDesc, WarpPass};
use crate::{Error, Result};

/// The warp path on the GPU in one submission: pinhole render (colour left in `GENERAL`) →
/// compute warp reading it in place (the host reads the output back, if it wants it). Nothing makes a round trip through
/// the host. `render` and `bench vertex` both drive it.
pub struct WarpStage {
    gpu: crate::gpu::Gpu,
    pub pass: GeometryPass,
    pub targets: GeometryTargets,
    pub warp: WarpPass,
    pub output: Image,
    pub mask: Image,
    /// The object IDs through the same lens (nearest, 0 fill), when asked for.
    pub ids: Option<DataWarp>,
    /// The depth through the same lens (nearest, +inf fill), when asked for.
    pub depth: Option<DataWarp>,
    /// The range through the same lens (nearest, +inf fill), when asked for.
    pub range: Option<DataWarp>,
}

/// Which data outputs a [`WarpStage`] carries beside its colour.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DataOutputs {
    /// Object IDs (R32 uint, 0 where there is no source).
    pub ids: bool,
    /// Camera depth (R32F metres, +inf where there is no source).
    pub depth: bool,
    /// Range along the ray (R32F metres, +inf where there is no source).
    pub range: bool,
}

/// A nearest warp of a [`WarpStage`] that carries one of the pinhole render's data images
/// (IDs or depth) to the output.
pub struct DataWarp {
    pub warp: WarpPass,
    /// The warp's output size, `GENERAL` after the warp.
    pub output: Image,
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
        Self::with_data(
            gpu,
            source,
            geometry,
            coordinates,
            format,
            background,
            DataOutputs::default(),
            1,
        )
    }

    /// As [`Self::new`]; the pinhole render also writes the `data` outputs, and a nearest
    /// warp of each carries it to the output. The render's uniforms and every warp's
    /// descriptor sets are kept for `frames` frames in flight (1 to
    /// [`crate::pass::geometry::MAX_FRAMES_IN_FLIGHT`]), chosen by [`Self::select_frame`].
    #[allow(clippy::too_many_arguments)]
    pub fn with_data(
        gpu: &crate::gpu::Gpu,
        source: Camera,
        geometry: WarpGeometry,
        coordinates: Coordinates,
        format: ColorFormat,
        background: [f32; 4],
        data: DataOutputs,
        frames: usize,
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
                ids: data.ids,
                depth: data.depth,
                range: data.range,
                ..Outputs::color_only(Some(format))
            },
        );
        desc.background = background;
        desc.final_layout = vk::ImageLayout::GENERAL;
        let pass = GeometryPass::with_frames(gpu, desc, frames)?;
        let targets = GeometryTargets::new(gpu, &pass)?;
        let (ow, oh) = geometry.output_size;
        let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
        let output = Image::new_2d(gpu, "warp_path.output", pixel_format.vk(), ow, oh, usage)?;
        let mask = Image::new_2d(gpu, "warp_path.mask", vk::Format::R8_UNORM, ow, oh, usage)?;
        let mut warp = WarpPass::with_frames(
            gpu,
            WarpDesc {
                geometry,
                coordinates,
                sampling: Sampling::Bilinear,
                border: crate::Border::Constant,
                format: pixel_format,
                fill: background,
                write_mask: false,
            },
            frames,
        )?;
        let color = targets
            .color()
            .ok_or_else(|| Error::internal("the warp stage's render has no colour target"))?;
        // Every frame's set reads the same images.
        for frame in 0..frames {
            warp.select_frame(frame);
            // SAFETY: the warp is new: nothing recorded with it exists yet.
            unsafe { warp.bind(color.view, output.view, mask.view) };
        }
        warp.select_frame(0);
        // IDs and depth follow the lens itself (the green channel's reference geometry, unit
        // scale): one coordinate, nearest.
        let mut plain = warp.desc().geometry.clone();
        plain.chromatic = None;
        if let Some(cams) = plain.channel_cameras.take() {
            let [_, green, _] = *cams;
            plain.camera = green;
        }
        let data_warp = |source: Option<&Image>,
                         format: PixelFormat,
                         fill: [f32; 4],
                         name: &str|
         -> Result<Option<DataWarp>> {
            let Some(source) = source else {
                return Ok(None);
            };
            let mut data_warp = WarpPass::with_frames(
                gpu,
                WarpDesc {
                    geometry: plain.clone(),
                    sampling: Sampling::Nearest,
                    border: crate::Border::Constant,
                    format,
                    fill,
                    ..warp.desc().clone()
                },
                frames,
            )?;
            let output = Image::new_2d(gpu, name, format.vk(), ow, oh, usage)?;
            // No warp writes its mask (write_mask is off): they can share one.
            for frame in 0..frames {
                data_warp.select_frame(frame);
                // SAFETY: the warp is new: nothing recorded with it exists yet.
                unsafe { data_warp.bind(source.view, output.view, mask.view) };
            }
            data_warp.select_frame(0);
            Ok(Some(DataWarp {
                warp: data_warp,
                output,
            }))
        };
        let ids = data_warp(
            targets.ids(),
            PixelFormat::R32Uint,
            [0.0; 4],
            "warp_path.ids",
        )?;
        let depth = data_warp(
            targets.depth(),
            PixelFormat::R32Float,
            [f32::INFINITY; 4],
            "warp_path.depth",
        )?;
        let range = data_warp(
            targets.range(),
            PixelFormat::R32Float,
            [f32::INFINITY; 4],
            "warp_path.range",
        )?;
        Ok(WarpStage {
            gpu: gpu.clone(),
            pass,
            targets,
            warp,
            output,
            mask,
            ids,
            depth,
            range,
        })
    }

    /// Makes frame `frame` (modulo the frames in flight it was made with) the one whose
    /// uniforms and sets the render and the warps write and record.
    pub fn select_frame(&mut self, frame: usize) {
        self.pass.select_frame(frame);
        self.warp.select_frame(frame);
        for d in self.ids.iter_mut().chain(self.depth.iter_mut()) {
            d.warp.select_frame(frame);
        }
    }

    /// The nearest warps of the data outputs (IDs, then depth), those asked for.
    pub fn data_warps(&self) -> impl Iterator<Item = &DataWarp> {
        self.ids
            .iter()
            .chain(self.depth.iter())
            .chain(self.range.iter())
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
            let data = self.data_warps().map(|d| &d.output);
            crate::gpu::record_discard_for_compute_write(
                &self.gpu,
                cmd,
                [&self.output, &self.mask].into_iter().chain(data),
            );
            self.warp.record_prepare(cmd);
            for d in self.data_warps() {
                d.warp.record_prepare(cmd);
            }
        }
    }

    /// Records one frame: the pinhole render of `mesh` (bound with `pass.bind_mesh`), then
    /// the warp (and the data warps). The render pass leaves the colour in `GENERAL`, its writes visible to compute.
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

    /// Records the warps alone (colour, then IDs and depth when asked for), after the caller recorded
    /// the pinhole render.
    ///
    /// # Safety
    /// As [`Self::record`], with `self.pass` recorded first.
    pub unsafe fn record_warps(&self, cmd: vk::CommandBuffer) {
        // SAFETY: the caller upholds `record_warps`'s contract: `self.pass` was recorded first,
        // so the warps' sources are in GENERAL with their writes visible to compute, and
        // `record_prepare` put their outputs and mask in GENERAL; every warp was bound in
        // `with_data`.
        unsafe {
            self.warp.record(cmd);
            for d in self.data_warps() {
                d.warp.record(cmd);
            }
        }
    }
}
