//! A scene through a calibrated lens, by either of Lambers et al.'s two paths:
//!
//! * **vertex** (Sec. 3.2): Alg. 1 per vertex, triangle discard, optional tessellation; every
//!   output exact for its data type (colour, IDs, flow, depth);
//! * **warp** (Sec. 3.3): a pinhole render of the overscanned frustum (so barrel lenses get
//!   their borders), then the compute warp — bilinear for colour, nearest for IDs and depth.
//!   Flow cannot be warped honestly (its vectors live in the pinhole image), so the warp path
//!   refuses it (Table 1);
//! * **cube**: where no pinhole frustum holds the lens (a fisheye of 180° and more, or an
//!   overscanned source beyond the device's image limit), six 90° pinhole faces and the sphere
//!   warp by ray direction; the warp path turns to it by itself and says so.
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

mod antialias;

pub use crate::pass::warp_stage::{DepthWarp, WarpStage};
use crate::{Error, Result};
pub(crate) use antialias::{antialiased, average, shifted};
pub use antialias::{
    downsample, jitter_offsets, scaled_camera, DEFAULT_BACKGROUND, MAX_JITTER, MAX_SUPERSAMPLE,
};
use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::gpu::{Buffer, Context, Image};
use crate::imaging::cpu_warp::Sampling;
use crate::imaging::Raster;
use crate::model::overscan::overscan;
use crate::model::warp::WarpGeometry;
use crate::model::{Camera, InverseMethod, OpenCvDistortion};
use crate::pass::geometry::{
    ColorFormat, GeometryDesc, GeometryPass, GeometryTargets, MeshBuffers, Outputs, Projection,
    Rendered,
};
use crate::pass::warp::{Coordinates, PixelFormat, WarpDesc, WarpPass};
use crate::scene::tessellate::tessellate;
use crate::scene::{Mesh, Pose, Scene};

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
    /// Six pinhole renders of a cube map's 90° faces of `side` pixels, then the sphere warp
    /// samples them by the ray of each output pixel: for lenses no single pinhole frustum can
    /// hold (fisheyes of 180° and more; wide lenses whose overscanned source would exceed the
    /// device's image limit). Colour only.
    Cube { side: u32 },
}

/// Largest overscanned pinhole source the warp path renders before it turns to a cube map,
/// in bytes of RGBA32F (4 GiB: the device limit usually binds first).
pub const MAX_WARP_SOURCE_BYTES: u64 = 4 << 30;

/// Largest cube map the cube path renders, all six faces together, in bytes (512 MiB: the
/// faces are rendered, read back and uploaded again, so the host holds them twice more). A
/// face side beyond it is clamped, and the density it gives is reported.
pub const MAX_CUBE_BYTES: u64 = 512 << 20;

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

impl RenderRequest {
    /// One 8-bit colour image of `camera` by `path`, from the identity pose (the camera at
    /// the world origin): no anti-aliasing, tessellation or chromatic aberration, a
    /// transparent background.
    pub fn color(camera: &Camera, path: RenderPath) -> Self {
        RenderRequest {
            camera: camera.clone(),
            pose: Pose::IDENTITY,
            previous_pose: Pose::IDENTITY,
            path,
            outputs: Outputs::color_only(Some(ColorFormat::Rgba8)),
            supersample: 1,
            jitter: 1,
            tessellate: None,
            background: [0.0; 4],
            chromatic: None,
        }
    }
}

/// Renders scenes through a headless context, keeping geometry passes (their compiled
/// pipelines) across calls: a new camera of the same size and terms, a new pose or a new mesh
/// reuses them. A calibration set's views and the jittered passes all share one.
pub struct SceneRenderer<'a> {
    ctx: &'a Context,
    passes: Vec<(GeometryPass, GeometryTargets)>,
    warp_stages: Vec<WarpStage>,
    cube_stages: Vec<crate::pass::cube_stage::CubeStage>,
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
    /// The warp from a cube map of six pinhole faces.
    SphereWarp,
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
            PassKind::SphereWarp => "sphere warp",
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

impl RecordedPipeline {
    /// A geometry pass's pipeline (pinhole or Alg. 1, by its projection), every stage.
    pub fn geometry(pass: &GeometryPass) -> Self {
        RecordedPipeline {
            kind: geometry_kind(pass),
            constants: pass.pipeline().constants.clone(),
        }
    }

    /// A compute pipeline doing `kind`.
    pub fn compute(kind: PassKind, pipeline: &crate::gpu::ComputePipeline) -> Self {
        RecordedPipeline {
            kind,
            constants: vec![(vk::ShaderStageFlags::COMPUTE, pipeline.constants.clone())],
        }
    }
}

impl<'a> SceneRenderer<'a> {
    pub fn new(ctx: &'a Context) -> Self {
        SceneRenderer {
            ctx,
            passes: Vec::new(),
            warp_stages: Vec::new(),
            cube_stages: Vec::new(),
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
        return Err(Error::input(format!(
            "supersample {s} and jitter {} must be in 1..={MAX_SUPERSAMPLE} and 1..={MAX_JITTER}",
            request.jitter
        )));
    }
    match request.path {
        RenderPath::Vertex { .. } | RenderPath::Pinhole => {
            if request.chromatic.is_some() {
                return Err(Error::input(
                    "chromatic aberration needs the warp path (one fused pass samples each channel through its own lens)",
                ));
            }
            let mesh = match request.tessellate {
                Some(l) => {
                    progress(&format!("tessellating to {l} px edges"));
                    let m = tessellate(&scene.mesh, &request.pose, &request.camera, l)?;
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
                    .ok_or_else(|| Error::internal("the render produced no colour"))
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
        RenderPath::Cube { side } => {
            if side < 2 {
                return Err(Error::argument(
                    "density",
                    format!("cube faces of {side} px: the density must be positive (faces are 2·f·density px)"),
                ));
            }
            render_cube_path(renderer, scene, request, side, s, progress)
        }
    }
}

/// The cube faces' side for `wanted` pixels: at most `max_side` (the device's image and cube
/// limits) and within [`MAX_CUBE_BYTES`] for six faces of `texel_bytes` per pixel.
pub fn cube_side(wanted: u32, texel_bytes: u64, max_side: u32) -> u32 {
    let budget_side = ((MAX_CUBE_BYTES / (6 * texel_bytes)) as f64).sqrt() as u32;
    wanted.min(max_side).min(budget_side)
}

/// The faces this device renders for a colour output in `format` that wants faces of
/// `wanted` pixels: their format (8-bit stays 8-bit, anything else is RGBA32F, the float
/// format every device filters) and their side ([`cube_side`] within the device's image and
/// cube limits).
pub(crate) fn device_cube_faces(
    gpu: &crate::gpu::Gpu,
    format: ColorFormat,
    wanted: u32,
) -> (ColorFormat, u32) {
    let (format, texel) = match format {
        ColorFormat::Rgba8 => (ColorFormat::Rgba8, 4),
        _ => (ColorFormat::Rgba32F, 16),
    };
    let max_side = gpu.max_image_side().min(gpu.max_cube_side());
    (format, cube_side(wanted, texel, max_side))
}

/// Uploads `mesh` and renders `stage`'s faces of it at `pose` into its cube, once: the warps
/// that follow sample them.
pub(crate) fn render_cube_faces(
    ctx: &Context,
    stage: &crate::pass::cube_stage::CubeStage,
    mesh: &MeshBuffers,
    pose: &Pose,
) -> Result<()> {
    // SAFETY: every submission `ctx` made has completed (`submit` waits on its fence), so
    // nothing using the stage is pending.
    unsafe { stage.prepare(mesh, pose) }?;
    ctx.submit(|cmd| {
        // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass, on
        // the context's graphics and compute queue; the mesh upload precedes the faces that
        // draw it, `record_prepare` the faces and warp; everything outlives the submission,
        // which `submit` waits for.
        unsafe {
            mesh.record_upload(cmd);
            stage.record_prepare(cmd);
            stage.record_faces(cmd, mesh);
        }
        Ok(())
    })?;
    Ok(())
}

/// Why the warp path cannot use an overscanned pinhole source for `camera`, if it cannot.
pub fn pinhole_source_refusal(camera: &Camera, density: f64, max_side: u32) -> Option<String> {
    if crate::model::overscan::beyond_a_pinhole(camera) {
        return Some(
            "the lens sees directions 90° and more off its axis, which no pinhole source holds"
                .into(),
        );
    }
    match overscan(camera, density) {
        Err(e) => Some(format!("the overscan fails ({e})")),
        Ok(ov) if ov.width > max_side || ov.height > max_side => Some(format!(
            "the overscanned pinhole source would be {}×{}, beyond the device's {max_side} px image limit",
            ov.width, ov.height
        )),
        Ok(ov) if ov.width as u64 * ov.height as u64 * 16 > MAX_WARP_SOURCE_BYTES => Some(format!(
            "the overscanned pinhole source would be {}×{} ({} MiB), beyond the {} MiB budget",
            ov.width,
            ov.height,
            (ov.width as u64 * ov.height as u64 * 16) >> 20,
            MAX_WARP_SOURCE_BYTES >> 20
        )),
        Ok(_) => None,
    }
}

/// The cube path: six face renders into a cube map on the GPU, then the sphere warp (per
/// jittered pass, at s×).
fn render_cube_path(
    renderer: &mut SceneRenderer,
    scene: &Scene,
    request: &RenderRequest,
    side: u32,
    s: u32,
    progress: &mut dyn FnMut(&str),
) -> Result<Rendered> {
    use crate::pass::cube_stage::CubeStage;
    use crate::pass::sphere_warp::SphereWarpOptions;
    let o = request.outputs;
    if o.flow || o.ids || o.depth {
        return Err(Error::argument(
            "path",
            "IDs, flow and depth through a cube map are not rendered (a face's depth is not the lens camera's, IDs must not be filtered across faces); the vertex path renders them",
        ));
    }
    let cam = &request.camera;
    let mut out = Rendered {
        width: cam.width,
        height: cam.height,
        ..Default::default()
    };
    let Some(format) = o.color else {
        return Ok(out);
    };
    let wanted = side.saturating_mul(s);
    let (format, big_side) = device_cube_faces(renderer.ctx.gpu(), format, wanted);
    if big_side < wanted {
        progress(&format!(
            "cube faces clamped to {big_side}×{big_side} (the device limit or the {} MiB cube budget): {:.2} face pixels per output pixel at the centre instead of {:.2}",
            MAX_CUBE_BYTES >> 20,
            big_side as f64 / (2.0 * cam.intrinsics.fx.max(cam.intrinsics.fy) * s as f64),
            wanted as f64 / (2.0 * cam.intrinsics.fx.max(cam.intrinsics.fy) * s as f64),
        ));
    }
    progress(&format!(
        "cube map: six {big_side}×{big_side} pinhole faces + sphere warp at {s}× in {} pass(es) (cube path)",
        request.jitter.max(1)
    ));
    let buffers = renderer.upload(&scene.mesh, scene.texture.as_ref())?;
    let options = SphereWarpOptions {
        chromatic: request.chromatic,
        fill: request.background,
        write_mask: false,
    };
    // Built for the s× camera (and kept across renders, like the geometry passes); the
    // jittered passes move the lens (its rays into the cube), never the faces, which are
    // rendered once on the GPU and stay there.
    let ctx = renderer.ctx;
    let big = scaled_camera(cam, s)?;
    let index = match renderer
        .cube_stages
        .iter()
        .position(|st| st.fits(&big, big_side, format, &options))
    {
        Some(i) => i,
        None => {
            let st = CubeStage::new(ctx.gpu(), &big, big_side, format, &options)?;
            renderer.cube_stages.push(st);
            renderer.cube_stages.len() - 1
        }
    };
    let stage = &mut renderer.cube_stages[index];
    render_cube_faces(ctx, stage, &buffers, &request.pose)?;
    out.color = Some(antialiased(cam, s, request.jitter, &mut |big, _| {
        // SAFETY: the last submission using the stage has completed (`submit` waits).
        unsafe { stage.set_camera(&big) }?;
        ctx.submit(|cmd| {
            // SAFETY: as above; the faces were recorded into the cube by the first submission,
            // which left it in SHADER_READ_ONLY_OPTIMAL for every warp after it.
            unsafe {
                stage.record_warp(cmd);
                stage.record_download(cmd);
                crate::gpu::host_read_barrier(ctx.gpu(), cmd);
            }
            Ok(())
        })?;
        stage.read()
    })?);
    Ok(out)
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
        return Err(Error::argument(
            "path",
            "flow needs the vertex path: its vectors live in the pinhole image and a warp cannot carry them (Lambers et al. Table 1)",
        ));
    }
    let cam = &request.camera;
    if !(density.is_finite() && density > 0.0 && density <= 16.0) {
        return Err(Error::argument(
            "density",
            format!("{density}: source pixels per output pixel must be in (0, 16]"),
        ));
    }
    // At s× (supersampling), as the source is rendered.
    let max_side = renderer.ctx.gpu().max_image_side();
    if let Some(why) = pinhole_source_refusal(&scaled_camera(cam, s)?, density, max_side) {
        if o.ids || o.depth {
            return Err(Error::argument(
                "path",
                format!("{why}: the warp path would need a cube map, which carries colour only; the vertex path renders IDs and depth"),
            ));
        }
        let side = crate::model::overscan::cube_face_side(cam, density);
        progress(&format!(
            "{why}{}: a cube map of six {side}×{side} faces instead",
            if s > 1 {
                format!(" at {s}× supersampling")
            } else {
                String::new()
            }
        ));
        return render_cube_path(renderer, scene, request, side, s, progress);
    }
    let (pinhole, geometry) = WarpGeometry::overscanned(cam, method, density)?;
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
        let big_ov = overscan(&scaled_camera(cam, s)?, density)?;
        let background = request.background;
        out.color = Some(antialiased(cam, s, request.jitter, &mut |big, shift| {
            let mut k = big_ov.intrinsics;
            k.cx -= shift.x * s as f64;
            k.cy -= shift.y * s as f64;
            let source = Camera::new(big_ov.width, big_ov.height, k, OpenCvDistortion::default())?;
            let mut geometry =
                WarpGeometry::distort(big, method).with_ideal(k, (big_ov.width, big_ov.height))?;
            if let Some(scales) = request.chromatic {
                geometry = geometry.with_chromatic(scales)?;
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
        // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass,
        // on the context's graphics+compute queue; every object lives until `submit` has
        // waited. The render pass leaves its targets in GENERAL with their writes visible to
        // compute, which the warps read; the warps' outputs go to GENERAL first.
        unsafe {
            mesh.record_upload(cmd);
            crate::gpu::record_discard_for_compute_write(
                gpu,
                cmd,
                std::iter::once(&mask).chain(warps.iter().map(|w| &w.1)),
            );
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
