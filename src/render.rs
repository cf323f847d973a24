//! A scene through a calibrated lens, by either of Lambers et al.'s two paths:
//!
//! * **vertex** (Sec. 3.2): Alg. 1 per vertex, triangle discard, optional tessellation; every
//!   output exact for its data type (colour, IDs, flow, depth);
//! * **warp** (Sec. 3.3): a pinhole render of the overscanned frustum (so barrel lenses get
//!   their borders), then the compute warp — bilinear for colour, nearest for IDs and depth.
//!   Flow cannot be warped honestly (its vectors live in the pinhole image), so the warp path
//!   refuses it (Table 1).
//!
//! Anti-aliasing (colour only; IDs, flow and depth are rendered once at 1×, they must not be
//! averaged): `supersample` renders at `s×` the resolution with the scaled camera (the lens is
//! the same: distortion acts on normalized coordinates) and box-filters down; `jitter` repeats
//! that with the sample grid shifted by sub-sample offsets (Halton 2, 3) and averages. A
//! regular `s × s` grid measures the position of a near-axis-aligned edge only to `1/s` px —
//! for checkerboard corners a systematic ±1/(2s) px error that calibration would fit as lens
//! distortion; jittered passes make it `1/(s·passes)`. Shifting the principal point by δ
//! translates the lens image by −δ exactly (Alg. 1 normalizes with the same cx, cy), so
//! every pass is the same image sampled elsewhere.

use crate::{Error, Result};
use ash::vk;
use glam::DVec2;
use gpu_allocator::MemoryLocation;

use crate::gpu::{image_barrier, Buffer, Context, Image};
use crate::imaging::cpu_warp::Sampling;
use crate::imaging::{BitDepth, Pixels, Raster};
use crate::model::overscan::overscan;
use crate::model::warp::WarpGeometry;
use crate::model::{Camera, Intrinsics, InverseMethod, OpenCvDistortion};
use crate::pass::geometry::{
    ColorFormat, GeometryDesc, GeometryPass, GeometryTargets, MeshBuffers, Outputs, Projection,
    Rendered,
};
use crate::pass::warp::{Coordinates, PixelFormat, WarpDesc, WarpPass};
use crate::scene::tessellate::tessellate;
use crate::scene::{Mesh, Pose, Scene};

/// Largest colour supersampling factor per axis (`--supersample`, `[render] supersample`):
/// at 8× an 800×600 frame is already rendered at 6400×4800.
pub const MAX_SUPERSAMPLE: u32 = 8;
/// Most jittered passes averaged (`--jitter`, `[render] jitter`).
pub const MAX_JITTER: u32 = 64;
/// The background a render clears to unless told otherwise: transparent black, so that what
/// the scene does not cover can be told apart (the same on the command line and in scene
/// files).
pub const DEFAULT_BACKGROUND: [f32; 4] = [0.0; 4];

/// Which path renders the lens.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RenderPath {
    /// Alg. 1 with discard tolerance δ.
    Vertex { delta: f64 },
    /// Pinhole render of the overscanned frustum with `density` source pixels per output
    /// pixel (Lambers et al. Sec. 3.3: "an enlarged frustum and increased resolution"), then the
    /// compute warp with `method`. Bilinear resampling blurs and shifts edges by up to a few
    /// hundredths of a source pixel; a denser source shrinks that in output pixels.
    Warp { method: InverseMethod, density: f64 },
    /// No lens at all: the Sec. 3.1 pinhole projection of the camera's intrinsics (its
    /// distortion is ignored), no geometry shader, no warp.
    Pinhole,
}

/// What to render.
#[derive(Debug, Clone)]
pub struct RenderRequest {
    pub camera: Camera,
    pub pose: Pose,
    /// The pose flow is measured from.
    pub previous_pose: Pose,
    pub path: RenderPath,
    pub outputs: Outputs,
    /// Colour supersampling factor per axis (1 = none).
    pub supersample: u32,
    /// Jittered colour passes averaged (1 = one pass, no jitter).
    pub jitter: u32,
    /// Split mesh edges longer than this many pixels first (vertex path).
    pub tessellate: Option<f64>,
    pub background: [f32; 4],
    /// Lateral chromatic aberration (warp path): per-channel radial scales R, G, B.
    pub chromatic: Option<[f64; 3]>,
}

/// The camera rendering `camera`'s image at `s×` its resolution.
pub fn scaled_camera(camera: &Camera, s: u32) -> Result<Camera> {
    let k = camera.intrinsics;
    let f = s as f64;
    Camera::new(
        camera.width * s,
        camera.height * s,
        Intrinsics {
            fx: k.fx * f,
            fy: k.fy * f,
            // Pixel edges scale, not centres: pixel i spans [i − 0.5, i + 0.5].
            cx: (k.cx + 0.5) * f - 0.5,
            cy: (k.cy + 0.5) * f - 0.5,
        },
        camera.distortion,
    )
    .map_err(Error::from)
}

/// The camera whose image is `camera`'s translated by `-shift` px (principal point moved).
pub(crate) fn shifted(camera: &Camera, shift: DVec2) -> Result<Camera> {
    let mut k = camera.intrinsics;
    k.cx -= shift.x;
    k.cy -= shift.y;
    Camera::new(camera.width, camera.height, k, camera.distortion).map_err(Error::from)
}

/// Radical inverse of `i` in `base` (Halton sequence), in [0, 1).
fn radical_inverse(mut i: u32, base: u32) -> f64 {
    let (mut f, mut r) = (1.0, 0.0);
    while i > 0 {
        f /= base as f64;
        r += f * (i % base) as f64;
        i /= base;
    }
    r
}

/// Sub-sample offsets of `passes` jittered passes, in units of one sample (centred on 0).
pub fn jitter_offsets(passes: u32) -> Vec<DVec2> {
    if passes <= 1 {
        return vec![DVec2::ZERO];
    }
    let raw: Vec<DVec2> = (0..passes)
        .map(|i| DVec2::new(radical_inverse(i, 2), radical_inverse(i, 3)))
        .collect();
    // Centre exactly (the mean offset would shift the whole image).
    let mean = raw.iter().sum::<DVec2>() / passes as f64;
    raw.into_iter().map(|o| o - mean).collect()
}

/// The mean of equally sized images (8-bit results rounded).
pub(crate) fn average(images: &[Raster]) -> Raster {
    let n = images.len().max(1) as f32;
    let first = &images[0];
    let mut sums = vec![[0f32; 4]; first.len()];
    for img in images {
        for (i, o) in sums.iter_mut().enumerate() {
            let v = img.rgba_f32(i);
            for c in 0..4 {
                o[c] += v[c] / n;
            }
        }
    }
    let pixels = match first.pixels {
        Pixels::Rgba8(_) => Pixels::Rgba8(
            sums.iter()
                .map(|p| p.map(|c| (c * 255.0).round().clamp(0.0, 255.0) as u8))
                .collect(),
        ),
        _ => Pixels::Rgba32F(sums),
    };
    Raster {
        pixels,
        ..first.clone()
    }
}

/// Anti-aliased colour: for each jitter offset, `pass(big camera, shift)` renders `camera`
/// scaled by `s` with its image translated by `-shift` (1× px); the results are box-filtered
/// and averaged.
fn antialiased(
    camera: &Camera,
    s: u32,
    passes: u32,
    pass: &mut dyn FnMut(Camera, DVec2) -> Result<Raster>,
) -> Result<Raster> {
    let mut images = Vec::new();
    for offset in jitter_offsets(passes) {
        let shift = offset / s as f64;
        let big = scaled_camera(&shifted(camera, shift).map_err(invalid)?, s).map_err(invalid)?;
        images.push(downsample(&pass(big, shift)?, s));
    }
    Ok(average(&images))
}

/// Box-filters an image by `s` per axis (its size must be a multiple of `s`).
pub fn downsample(image: &Raster, s: u32) -> Raster {
    if s == 1 {
        return image.clone();
    }
    let (w, h) = (image.width / s, image.height / s);
    let (s, iw) = (s as usize, image.width as usize);
    let pixels = match &image.pixels {
        // Integer sums, row by row: this runs on every supersampled pass.
        Pixels::Rgba8(p) => {
            let n = (s * s) as u32;
            let mut out = Vec::with_capacity(w as usize * h as usize);
            let mut sums = vec![[0u32; 4]; w as usize];
            for y in 0..h as usize {
                sums.iter_mut().for_each(|v| *v = [0; 4]);
                for row in p[y * s * iw..(y + 1) * s * iw].chunks_exact(iw) {
                    for (x, block) in row.chunks_exact(s).enumerate() {
                        for px in block {
                            for c in 0..4 {
                                sums[x][c] += px[c] as u32;
                            }
                        }
                    }
                }
                out.extend(sums.iter().map(|v| v.map(|c| ((c + n / 2) / n) as u8)));
            }
            Pixels::Rgba8(out)
        }
        _ => {
            let n = (s * s) as f32;
            let mut out = vec![[0f32; 4]; w as usize * h as usize];
            for y in 0..image.height as usize {
                for x in 0..iw {
                    let v = image.rgba_f32(y * iw + x);
                    let o = &mut out[(y / s) * w as usize + x / s];
                    for c in 0..4 {
                        o[c] += v[c] / n;
                    }
                }
            }
            Pixels::Rgba32F(out)
        }
    };
    Raster {
        width: w,
        height: h,
        pixels,
        bit_depth: image.bit_depth,
    }
}

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
                return Err(invalid("the warp reads RGBA8 or RGBA32F sources"));
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
        let color = targets.color().ok_or_else(|| invalid("no colour target"))?;
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
        let none = (
            vk::PipelineStageFlags::TOP_OF_PIPE,
            vk::AccessFlags::empty(),
        );
        let write = (
            vk::PipelineStageFlags::COMPUTE_SHADER,
            vk::AccessFlags::SHADER_WRITE,
        );
        // SAFETY: the caller upholds `record_prepare`'s contract: `cmd` is recording outside a
        // render pass and no earlier work using these images is pending, so UNDEFINED is a
        // valid old layout for this stage's own output, mask and depth images. The warps'
        // `record_prepare` also need a compute queue, which this contract leaves implicit:
        // every caller records on a queue with graphics and compute.
        unsafe {
            let depth = self.depth.iter().map(|d| &d.output);
            for img in [&self.output, &self.mask].into_iter().chain(depth) {
                image_barrier(
                    &self.gpu,
                    cmd,
                    img.raw,
                    (vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL),
                    none,
                    write,
                );
            }
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
        let e = self.output.extent;
        let n = e.width as usize * e.height as usize;
        let (pixels, depth) = match self.format {
            PixelFormat::Rgba8 => (
                Pixels::Rgba8(self.download.read_pod::<[u8; 4]>(n)?),
                BitDepth::U8,
            ),
            _ => (
                Pixels::Rgba32F(self.download.read_pod::<[f32; 4]>(n)?),
                BitDepth::F32,
            ),
        };
        Ok(Raster {
            width: e.width,
            height: e.height,
            pixels,
            bit_depth: depth,
        })
    }
}

/// Renders scenes through a headless context, keeping geometry passes (their compiled
/// pipelines) across calls: a new camera of the same size and terms, a new pose or a new mesh
/// reuses them. A calibration set's views and the jittered passes all share one.
pub struct SceneRenderer<'a> {
    ctx: &'a Context,
    passes: Vec<(GeometryPass, GeometryTargets)>,
    warp_stages: Vec<WarpStage>,
    /// Every pipeline recorded so far, in order, with the specialization constants it was
    /// built with: what a plan can be checked against (not timings).
    pub recorded: Vec<RecordedPipeline>,
}

/// What a pipeline does, as recorded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PassKind {
    /// The pinhole projection (a warp's source, or a scene without distortion).
    PinholeRender,
    /// Lambers et al.'s Alg. 1: the lens per vertex, triangles discarded.
    VertexRender,
    /// The post-processing warp of colour.
    Warp,
    /// The nearest warp that carries depth along the colour's.
    DepthWarp,
    /// Heidrich et al.'s image-based lens model: cell renders accumulated on the film.
    LensModel,
}

impl PassKind {
    /// How `--explain` and the tables name it.
    pub fn name(self) -> &'static str {
        match self {
            PassKind::PinholeRender => "pinhole render",
            PassKind::VertexRender => "Alg. 1 (vertex + discard)",
            PassKind::Warp => "warp",
            PassKind::DepthWarp => "depth warp",
            PassKind::LensModel => "image-based lens model",
        }
    }
}

/// One recorded use of a pipeline.
#[derive(Debug, Clone)]
pub struct RecordedPipeline {
    /// What the pipeline does.
    pub kind: PassKind,
    /// The constants of each stage.
    pub constants: Vec<(vk::ShaderStageFlags, crate::gpu::SpecConstants)>,
}

impl<'a> SceneRenderer<'a> {
    pub fn new(ctx: &'a Context) -> Self {
        SceneRenderer {
            ctx,
            passes: Vec::new(),
            warp_stages: Vec::new(),
            recorded: Vec::new(),
        }
    }

    /// Draws `mesh` (from [`Self::upload`]) once with `desc`.
    pub fn draw(
        &mut self,
        desc: GeometryDesc,
        mesh: &MeshBuffers,
        pose: &Pose,
        previous: &Pose,
    ) -> Result<Rendered> {
        let gpu = self.ctx.gpu();
        let reusable = |p: &GeometryPass| {
            let d = p.desc();
            d.projection == desc.projection
                && d.outputs == desc.outputs
                && d.background == desc.background
                && (d.near, d.far) == (desc.near, desc.far)
                && d.final_layout == desc.final_layout
                && p.accepts_camera(&desc.camera)
        };
        let index = match self.passes.iter().position(|(p, _)| reusable(p)) {
            Some(i) => {
                // SAFETY: no submission using it is pending (`submit` waits on its fence).
                unsafe { self.passes[i].0.set_camera(&desc.camera) }?;
                i
            }
            None => {
                let pass = GeometryPass::new(gpu, desc)?;
                let targets = GeometryTargets::new(gpu, &pass)?;
                self.passes.push((pass, targets));
                self.passes.len() - 1
            }
        };
        let (pass, targets) = &mut self.passes[index];
        self.recorded.push(RecordedPipeline {
            kind: geometry_kind(pass),
            constants: pass.pipeline().constants.clone(),
        });
        // SAFETY: no submission using it is pending (`submit` waits on its fence).
        unsafe { pass.bind_mesh(mesh) };
        // SAFETY: no submission using it is pending (`submit` waits on its fence).
        unsafe { pass.set_frame(pose, previous) }?;
        let (pass, targets) = (&*pass, &*targets);
        self.ctx.submit(|cmd| {
            // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass,
            // on a graphics queue; the previous submission using `pass` completed (`submit`
            // waits), so rebinding above raced nothing. `mesh` is bound, its texture uploaded
            // first; `targets` were made for `pass`. The download needs the outputs in
            // TRANSFER_SRC_OPTIMAL: `GeometryDesc::new`'s default, which this safe method
            // assumes but does not check in `desc`. All outlive the submission.
            unsafe {
                mesh.record_upload(cmd);
                pass.record(cmd, targets, mesh);
                targets.record_download(cmd);
            }
            Ok(())
        })?;
        targets.read()
    }

    /// Uploads a mesh once for any number of draws (jittered passes share it).
    pub fn upload(&self, mesh: &Mesh, texture: Option<&Raster>) -> Result<MeshBuffers> {
        MeshBuffers::new(self.ctx.gpu(), mesh, texture)
    }

    /// The warp path's colour: `mesh` rendered with the pinhole `source` camera, warped by
    /// `geometry` (analytic, bilinear) — all on the GPU. Stages are kept and retargeted.
    #[allow(clippy::too_many_arguments)]
    pub fn draw_warped(
        &mut self,
        mesh: &MeshBuffers,
        pose: &Pose,
        source: Camera,
        geometry: WarpGeometry,
        format: ColorFormat,
        background: [f32; 4],
    ) -> Result<Raster> {
        let reusable = |st: &WarpStage| {
            let d = st.pass.desc();
            d.outputs.color == Some(format)
                && d.background == background
                && st.pass.accepts_camera(&source)
                && st.warp.desc().geometry.output_size == geometry.output_size
        };
        let index = match self.warp_stages.iter().position(reusable) {
            Some(i) => {
                let st = &mut self.warp_stages[i];
                // SAFETY: no submission using it is pending (`submit` waits on its fence).
                unsafe { st.pass.set_camera(&source) }?;
                // SAFETY: no submission using it is pending (`submit` waits on its fence).
                unsafe { st.warp.retarget(geometry) }?;
                i
            }
            None => {
                let stage = WarpStage::new(
                    self.ctx.gpu(),
                    source,
                    geometry,
                    Coordinates::Analytic,
                    format,
                    background,
                )?;
                self.warp_stages.push(stage);
                self.warp_stages.len() - 1
            }
        };
        let st = &mut self.warp_stages[index];
        self.recorded.push(RecordedPipeline {
            kind: geometry_kind(&st.pass),
            constants: st.pass.pipeline().constants.clone(),
        });
        self.recorded.push(RecordedPipeline {
            kind: PassKind::Warp,
            constants: vec![(
                vk::ShaderStageFlags::COMPUTE,
                st.warp.pipeline().constants.clone(),
            )],
        });
        // SAFETY: no submission using it is pending (`submit` waits on its fence).
        unsafe { st.pass.bind_mesh(mesh) };
        // SAFETY: no submission using it is pending (`submit` waits on its fence).
        unsafe { st.pass.set_frame(pose, pose) }?;
        let st = &*st;
        self.ctx.submit(|cmd| {
            // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass,
            // on the context's graphics+compute queue; the previous submission using `st`
            // completed (`submit` waits), so the host writes above and re-preparing race
            // nothing. The calls come in the order their contracts ask (upload, prepare,
            // frame, download) and everything outlives the submission.
            unsafe {
                mesh.record_upload(cmd);
                st.record_prepare(cmd);
                st.record(cmd, mesh);
                st.record_download(cmd);
            }
            Ok(())
        })?;
        st.read()
    }

    /// Renders `scene` as `request` asks; `progress` hears each step.
    pub fn render(
        &mut self,
        scene: &Scene,
        request: &RenderRequest,
        progress: &mut dyn FnMut(&str),
    ) -> Result<Rendered> {
        render_with(self, scene, request, progress)
    }
}

fn invalid(e: impl ToString) -> Error {
    Error::Input(e.to_string())
}

pub(crate) fn geometry_kind(pass: &GeometryPass) -> PassKind {
    match pass.desc().projection {
        Projection::Lens { .. } => PassKind::VertexRender,
        Projection::Pinhole => PassKind::PinholeRender,
    }
}

/// Renders `scene` as `request` asks (a one-off [`SceneRenderer`]); `progress` hears each
/// step.
pub fn render_scene(
    ctx: &Context,
    scene: &Scene,
    request: &RenderRequest,
    progress: &mut dyn FnMut(&str),
) -> Result<Rendered> {
    SceneRenderer::new(ctx).render(scene, request, progress)
}

fn render_with(
    renderer: &mut SceneRenderer,
    scene: &Scene,
    request: &RenderRequest,
    progress: &mut dyn FnMut(&str),
) -> Result<Rendered> {
    let s = request.supersample;
    if !(1..=MAX_SUPERSAMPLE).contains(&s) || !(1..=MAX_JITTER).contains(&request.jitter) {
        return Err(invalid(format!(
            "supersample {s} and jitter {} must be in 1..={MAX_SUPERSAMPLE} and 1..={MAX_JITTER}",
            request.jitter
        )));
    }
    match request.path {
        RenderPath::Vertex { .. } | RenderPath::Pinhole => {
            if request.chromatic.is_some() {
                return Err(invalid(
                    "chromatic aberration needs the warp path (one fused pass samples each channel through its own lens)",
                ));
            }
            let mesh = match request.tessellate {
                Some(l) => {
                    progress(&format!("tessellating to {l} px edges"));
                    let m = tessellate(&scene.mesh, &request.pose, &request.camera, l)
                        .map_err(invalid)?;
                    progress(&format!("{} triangles", m.triangle_count()));
                    m
                }
                None => scene.mesh.clone(),
            };
            let buffers = renderer.upload(&mesh, scene.texture.as_ref())?;
            let projection = match request.path {
                RenderPath::Vertex { delta } => Projection::Lens { delta },
                _ => Projection::Pinhole,
            };
            let o = request.outputs;
            let data = Outputs { color: None, ..o };
            let mut run = |camera: Camera, outputs: Outputs| {
                let mut desc = GeometryDesc::new(camera, projection, outputs);
                desc.background = request.background;
                renderer.draw(desc, &buffers, &request.pose, &request.previous_pose)
            };
            if (s == 1 && request.jitter <= 1) || o.color.is_none() {
                progress("rendering (vertex path)");
                return run(request.camera.clone(), o);
            }
            progress(&format!(
                "rendering colour at {s}× in {} pass(es) (vertex path)",
                request.jitter.max(1)
            ));
            let color = antialiased(&request.camera, s, request.jitter, &mut |big, _| {
                run(big, Outputs::color_only(o.color))?
                    .color
                    .ok_or_else(|| invalid("the render produced no colour"))
            })?;
            let mut out = if data.ids || data.flow || data.depth {
                progress("rendering data outputs at 1×");
                run(request.camera.clone(), data)?
            } else {
                Rendered {
                    width: request.camera.width,
                    height: request.camera.height,
                    ..Default::default()
                }
            };
            out.color = Some(color);
            Ok(out)
        }
        RenderPath::Warp { method, density } => {
            render_warp_path(renderer, scene, request, method, density, s, progress)
        }
    }
}

fn render_warp_path(
    renderer: &mut SceneRenderer,
    scene: &Scene,
    request: &RenderRequest,
    method: InverseMethod,
    density: f64,
    s: u32,
    progress: &mut dyn FnMut(&str),
) -> Result<Rendered> {
    let o = request.outputs;
    if o.flow {
        return Err(invalid(
            "flow needs the vertex path: its vectors live in the pinhole image and a warp cannot carry them (Lambers et al. Table 1); use --path vertex",
        ));
    }
    let cam = &request.camera;
    let ov = overscan(cam, density).map_err(invalid)?;
    let pinhole = Camera::new(
        ov.width,
        ov.height,
        ov.intrinsics,
        OpenCvDistortion::default(),
    )
    .map_err(invalid)?;
    let geometry = WarpGeometry::distort(cam.clone(), method)
        .with_ideal(ov.intrinsics, (ov.width, ov.height))
        .map_err(invalid)?;
    let buffers = renderer.upload(&scene.mesh, scene.texture.as_ref())?;
    let mut out = Rendered {
        width: cam.width,
        height: cam.height,
        ..Default::default()
    };
    if let Some(format) = o.color {
        progress(&format!(
            "pinhole render + warp at {s}× in {} pass(es) (warp path)",
            request.jitter.max(1)
        ));
        // Float output goes through an RGBA32F source (a format the warp reads and writes).
        let format = match format {
            ColorFormat::Rgba8 => ColorFormat::Rgba8,
            _ => ColorFormat::Rgba32F,
        };
        // The warp runs at s× too (output and overscanned source), so its bilinear
        // resampling errors shrink with s like the rasterization's. The overscan is computed
        // once; each jittered pass translates source and lens image together.
        let big_ov =
            overscan(&scaled_camera(cam, s).map_err(invalid)?, density).map_err(invalid)?;
        let background = request.background;
        out.color = Some(antialiased(cam, s, request.jitter, &mut |big, shift| {
            let mut k = big_ov.intrinsics;
            k.cx -= shift.x * s as f64;
            k.cy -= shift.y * s as f64;
            let source = Camera::new(big_ov.width, big_ov.height, k, OpenCvDistortion::default())
                .map_err(invalid)?;
            let mut geometry = WarpGeometry::distort(big, method)
                .with_ideal(k, (big_ov.width, big_ov.height))
                .map_err(invalid)?;
            if let Some(scales) = request.chromatic {
                geometry = geometry.with_chromatic(scales).map_err(invalid)?;
            }
            renderer.draw_warped(
                &buffers,
                &request.pose,
                source,
                geometry,
                format,
                background,
            )
        })?);
    }
    if o.ids || o.depth {
        progress("rendering pinhole IDs/depth at 1× and warping them (nearest) on the GPU");
        let (ids, depth) = warp_data(
            renderer.ctx,
            &buffers,
            &request.pose,
            pinhole,
            &geometry,
            o.ids,
            o.depth,
        )?;
        out.ids = ids;
        out.depth = depth;
    }
    Ok(out)
}

/// Warped object IDs and camera depth, each when asked for.
type WarpedData = (Option<Vec<u32>>, Option<Vec<f32>>);

/// The warp path's IDs and depth, without a round trip through the host: a pinhole render of
/// them (left in `GENERAL`), each warped by a nearest warp of its own in the same submission
/// (IDs filled with 0, depth with +inf where there is no source); only the warped images come
/// back.
#[allow(clippy::too_many_arguments)]
fn warp_data(
    ctx: &Context,
    mesh: &MeshBuffers,
    pose: &Pose,
    pinhole: Camera,
    geometry: &WarpGeometry,
    ids: bool,
    depth: bool,
) -> Result<WarpedData> {
    let gpu = ctx.gpu();
    let mut desc = GeometryDesc::new(
        pinhole,
        Projection::Pinhole,
        Outputs {
            color: None,
            ids,
            flow: false,
            depth,
        },
    );
    desc.final_layout = vk::ImageLayout::GENERAL;
    let mut pass = GeometryPass::new(gpu, desc)?;
    let targets = GeometryTargets::new(gpu, &pass)?;
    let (ow, oh) = geometry.output_size;
    let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
    // Neither warp writes its mask (write_mask is off): they share one.
    let mask = Image::new_2d(
        gpu,
        "warp_path.data.mask",
        vk::Format::R8_UNORM,
        ow,
        oh,
        usage,
    )?;
    let mut warps = Vec::new();
    for (wanted, source, format, fill) in [
        (ids, targets.ids(), PixelFormat::R32Uint, [0.0; 4]),
        (
            depth,
            targets.depth(),
            PixelFormat::R32Float,
            [f32::INFINITY; 4],
        ),
    ] {
        if !wanted {
            continue;
        }
        let source = source.ok_or_else(|| Error::internal("the data render has no target"))?;
        let mut warp = WarpPass::new(
            gpu,
            WarpDesc {
                geometry: geometry.clone(),
                coordinates: Coordinates::Analytic,
                sampling: Sampling::Nearest,
                format,
                fill,
                write_mask: false,
            },
        )?;
        let output = Image::new_2d(gpu, "warp_path.data", format.vk(), ow, oh, usage)?;
        let download = Buffer::new(
            gpu,
            "warp_path.data.download",
            ow as u64 * oh as u64 * 4,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        // SAFETY: the warp is new: nothing recorded with it exists yet.
        unsafe { warp.bind(source.view, output.view, mask.view) };
        warps.push((warp, output, download));
    }
    // SAFETY: the pass is new: nothing recorded with it exists yet.
    unsafe {
        pass.bind_mesh(mesh);
        pass.set_frame(pose, pose)?;
    }
    let (pass, targets) = (&pass, &targets);
    ctx.submit(|cmd| {
        let none = (
            vk::PipelineStageFlags::TOP_OF_PIPE,
            vk::AccessFlags::empty(),
        );
        let write = (
            vk::PipelineStageFlags::COMPUTE_SHADER,
            vk::AccessFlags::SHADER_WRITE,
        );
        // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass,
        // on the context's graphics+compute queue; every object lives until `submit` has
        // waited. The render pass leaves its targets in GENERAL with their writes visible to
        // compute, which the warps read; the warps' outputs go to GENERAL first.
        unsafe {
            mesh.record_upload(cmd);
            for img in std::iter::once(&mask).chain(warps.iter().map(|w| &w.1)) {
                image_barrier(
                    gpu,
                    cmd,
                    img.raw,
                    (vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL),
                    none,
                    write,
                );
            }
            for (warp, _, _) in &warps {
                warp.record_prepare(cmd);
            }
            pass.record(cmd, targets, mesh);
            for (warp, output, download) in &warps {
                warp.record(cmd);
                crate::gpu::record_compute_download(gpu, cmd, output, download);
            }
            crate::gpu::host_read_barrier(gpu, cmd);
        }
        Ok(())
    })?;
    let n = ow as usize * oh as usize;
    let mut warped = warps.iter().map(|w| &w.2);
    let ids = match ids {
        true => warped.next().map(|b| b.read_pod::<u32>(n)).transpose()?,
        false => None,
    };
    let depth = match depth {
        true => warped.next().map(|b| b.read_pod::<f32>(n)).transpose()?,
        false => None,
    };
    Ok((ids, depth))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scaled_camera_keeps_pixel_edges() {
        let cam = Camera::from_coeffs(
            800,
            600,
            Intrinsics {
                fx: 400.0,
                fy: 400.0,
                cx: 399.5,
                cy: 299.5,
            },
            &[-0.05, 0.01, 0.03, -0.01],
        )
        .unwrap();
        let big = scaled_camera(&cam, 4).unwrap();
        // The image's left edge (pixel −0.5) is at the same normalized x in both.
        let edge = |c: &Camera| (-0.5 - c.intrinsics.cx) / c.intrinsics.fx;
        assert!((edge(&cam) - edge(&big)).abs() < 1e-15);
        assert_eq!((big.width, big.height), (3200, 2400));
        let img = Raster {
            width: 4,
            height: 2,
            pixels: Pixels::Rgba8(vec![
                [0; 4], [255; 4], [10; 4], [10; 4], [255; 4], [0; 4], [10; 4], [10; 4],
            ]),
            bit_depth: BitDepth::U8,
        };
        let small = downsample(&img, 2);
        assert_eq!(small.pixels, Pixels::Rgba8(vec![[128; 4], [10; 4]]));
    }
}
