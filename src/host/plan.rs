//! The headless path of the one recorder: a [`PlanRecorder`] built once records each frame;
//! this submits it, reads the outputs back, and averages anti-aliased colour on the host.

use std::time::Instant;

use crate::gpu::QueryPool;
use crate::host::geometry::TargetsReadback;
use crate::host::readback::{Download, Left};
use crate::imaging::{BitDepth, Pixels, Raster};
use crate::model::Camera;
use crate::pass::geometry::Rendered;
use crate::plan::antialias::{average, shifted};
use crate::plan::record::{plan_mesh_at, tessellation};
use crate::plan::{
    downsample, jitter_offsets, scaled_camera, Optics, PassKind, Plan, PlanRecorder,
    RecordedPipeline, RenderRequest, Route,
};
use crate::scene::Scene;
use crate::{Error, Result};

use super::Context;

/// One rendered frame.
#[derive(Debug, Clone, Default)]
pub struct Frame {
    pub index: usize,
    pub rendered: Rendered,
    /// Wall time of the frame: its GPU work and readback (ms).
    pub ms: f64,
    /// GPU time per pass (timestamps), on the first frame `execute` hands out; empty on the
    /// others and where the queue has no timestamps.
    pub pass_ms: Vec<(&'static str, f64)>,
}

/// What executing a plan recorded: the pipelines, with their specialization constants, and
/// the GPU time of each pass on the first timed frame.
#[derive(Debug, Clone, Default)]
pub struct Recorded {
    /// Every pipeline recorded, with its specialization constants.
    pub pipelines: Vec<RecordedPipeline>,
    /// GPU time per pass (timestamps) of the first timed frame, in recording order; empty
    /// where the queue has no timestamps.
    pub pass_ms: Vec<(&'static str, f64)>,
}

impl Recorded {
    /// Whether a pipeline of `kind` was recorded.
    pub fn has(&self, kind: PassKind) -> bool {
        self.pipelines.iter().any(|p| p.kind == kind)
    }
}

/// Renders the frames `frames` (indices into the plan's poses) of `scene` as `plan` says, on
/// the headless context; `each` receives every frame as it is done, with its wall time and,
/// on the first, the GPU time of each pass (the first frame is rendered once more before, as
/// a warm-up: caches fill on first use).
///
/// This is the headless path of the one recorder: a [`PlanRecorder`] built once records each
/// frame, and this only submits it and reads the outputs back. Anti-aliased colour
/// (`[render] supersample`, `jitter`) is a second recorder of the colour alone at `s×` the
/// resolution, its jittered passes box-filtered and averaged here; IDs, flow and depth stay one
/// sample per pixel.
pub fn execute(
    ctx: &Context,
    plan: &Plan,
    scene: &Scene,
    frames: impl IntoIterator<Item = usize>,
    each: &mut dyn FnMut(Frame) -> Result<()>,
) -> Result<Recorded> {
    run_frames(ctx, plan, scene, frames, true, each)
}

/// As [`execute`], without the warm-up frame and the timestamps: for frames wanted for their
/// pixels alone (a calibration set, a one-off render).
pub fn execute_untimed(
    ctx: &Context,
    plan: &Plan,
    scene: &Scene,
    frames: impl IntoIterator<Item = usize>,
    each: &mut dyn FnMut(Frame) -> Result<()>,
) -> Result<Recorded> {
    run_frames(ctx, plan, scene, frames, false, each)
}

/// Records `what` of every recorder into one submission, and waits.
///
/// # Safety
/// `what`'s contract holds for each recorder in a fresh command buffer recording outside a
/// render pass on the context's graphics and compute queue.
unsafe fn submit_each<'a>(
    ctx: &Context,
    recorders: impl Iterator<Item = &'a PlanRecorder>,
    what: unsafe fn(&PlanRecorder, ash::vk::CommandBuffer),
) -> Result<()> {
    let recorders: Vec<&PlanRecorder> = recorders.collect();
    ctx.submit(|cmd| {
        for r in &recorders {
            // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside a render pass
            // on the context's graphics and compute queue; the rest is this function's
            // contract.
            unsafe { what(r, cmd) };
        }
        Ok(())
    })
}

fn run_frames(
    ctx: &Context,
    plan: &Plan,
    scene: &Scene,
    frames: impl IntoIterator<Item = usize>,
    timing: bool,
    each: &mut dyn FnMut(Frame) -> Result<()>,
) -> Result<Recorded> {
    let frames: Vec<usize> = frames.into_iter().collect();
    // Every index checked before any frame is rendered.
    for &index in &frames {
        check_frame(plan, index)?;
    }
    let first = frames.first().copied().unwrap_or(0);
    let mut runner = FrameRunner::new(ctx, plan, scene, first, timing)?;
    // The first frame once more before timing: caches warm up on first use.
    if timing && !frames.is_empty() {
        runner.frame(first)?;
    }
    for &index in &frames {
        each(runner.frame(index)?)?;
    }
    Ok(runner.into_recorded())
}

/// One plan's recorders and readbacks, built once, rendering frame after frame on the headless
/// context: what [`execute`] runs, and what a benchmark holds two of to alternate their frames
/// (a frame's wall time on a shared machine drifts by more than two paths differ by).
pub struct FrameRunner<'a> {
    ctx: &'a Context,
    plan: &'a Plan,
    scene: &'a Scene,
    /// Every output, or the data outputs alone when the colour is anti-aliased.
    main: Option<PlanRecorder>,
    main_readback: Option<PlanReadback>,
    /// The anti-aliased colour, at `s×` the resolution.
    smooth: Option<PlanRecorder>,
    smooth_readback: Option<PlanReadback>,
    camera: Option<Camera>,
    queries: Option<QueryPool>,
    /// Whether each pose gets its own tessellation, and the pose the mesh holds now.
    per_pose: bool,
    mesh_pose: usize,
    /// Whether the next frame is the first [`FrameRunner::frame`] is asked for after the
    /// warm-up (the one whose passes are timed).
    frames_done: usize,
    warm_up: bool,
    recorded: Recorded,
}

impl<'a> FrameRunner<'a> {
    /// The recorders of `plan` for `scene`, its mesh made for the pose of frame `first`, set
    /// up; with `timing`, the first frame rendered after the warm-up (the second
    /// [`FrameRunner::frame`]) also times each pass.
    pub fn new(
        ctx: &'a Context,
        plan: &'a Plan,
        scene: &'a Scene,
        first: usize,
        timing: bool,
    ) -> Result<Self> {
        let gpu = ctx.gpu();
        let o = plan.outputs;
        let lens = matches!(plan.route, Route::LensModel { .. });
        let antialias = plan.antialias.is_on() && o.color && !lens;
        let mesh = plan_mesh_at(plan, scene, first)?;
        let mut main_plan = plan.clone();
        if antialias {
            main_plan.outputs.color = false;
        }
        let data = main_plan.outputs;
        let main = if data.color || data.renders_data() {
            Some(PlanRecorder::build(gpu, &main_plan, scene, &mesh, 1)?)
        } else {
            None
        };
        let s = plan.antialias.supersample;
        let camera = plan.camera().cloned();
        let smooth = match (&camera, antialias) {
            (Some(cam), true) => {
                let mut p = plan.clone();
                p.optics = Optics::Camera(scaled_camera(cam, s)?);
                p.outputs = o.color_only();
                match plan.route {
                    Route::WarpAndVertex {
                        method,
                        chromatic,
                        map,
                        ..
                    } => {
                        p.route = Route::Warp {
                            method,
                            chromatic,
                            map,
                        };
                    }
                    // Faces as fine as the s× lens camera's pixels.
                    Route::Cube { side, chromatic } => {
                        p.route = Route::Cube {
                            side: side.saturating_mul(s),
                            chromatic,
                        };
                    }
                    _ => {}
                }
                Some(PlanRecorder::build(gpu, &p, scene, &mesh, 1)?)
            }
            _ => None,
        };
        let mut recorded = Recorded::default();
        for r in main.iter().chain(smooth.iter()) {
            recorded.pipelines.extend_from_slice(r.pipelines());
        }
        let queries = main
            .as_ref()
            .filter(|_| timing)
            .and_then(|r| QueryPool::timestamps(gpu, r.timestamp_count()).ok());
        // SAFETY: each recorder's one-off work, recorded once, before any frame.
        unsafe {
            submit_each(
                ctx,
                main.iter().chain(smooth.iter()),
                PlanRecorder::record_setup,
            )
        }?;
        let main_readback = main
            .as_ref()
            .map(|r| PlanReadback::new(gpu, r))
            .transpose()?;
        let smooth_readback = smooth
            .as_ref()
            .map(|r| PlanReadback::new(gpu, r))
            .transpose()?;
        Ok(FrameRunner {
            ctx,
            plan,
            scene,
            main,
            main_readback,
            smooth,
            smooth_readback,
            camera,
            queries,
            // A tessellation holds its straight-edge bound at the pose it was made for: frames
            // of other poses get their own.
            per_pose: tessellation(plan).is_some(),
            mesh_pose: first,
            frames_done: 0,
            warm_up: timing,
            recorded,
        })
    }

    /// Renders frame `index` (an index into the plan's poses) and reads it back, with its wall
    /// time and, on the first frame after the warm-up where the runner times, each pass's GPU
    /// time.
    pub fn frame(&mut self, index: usize) -> Result<Frame> {
        let (ctx, plan, scene) = (self.ctx, self.plan, self.scene);
        check_frame(plan, index)?;
        let gpu = ctx.gpu();
        let texture = scene.texture.as_ref();
        let stamps_now = self.frames_done == usize::from(self.warm_up);
        self.frames_done += 1;
        let start = Instant::now();
        if self.per_pose && index != self.mesh_pose {
            let mesh = plan_mesh_at(plan, scene, index)?;
            for r in self.main.iter_mut().chain(self.smooth.iter_mut()) {
                // SAFETY: every submission has completed (`submit` waits on its fence).
                unsafe { r.set_mesh(gpu, &mesh, texture) }?;
            }
            // SAFETY: before the frame that draws the new mesh.
            unsafe {
                submit_each(
                    ctx,
                    self.main.iter().chain(self.smooth.iter()),
                    PlanRecorder::record_mesh_upload,
                )
            }?;
            self.mesh_pose = index;
        }
        let stamps = self.queries.as_ref().filter(|_| stamps_now);
        let mut rendered = match &mut self.main {
            Some(r) => {
                // SAFETY: no submission using it is pending (`submit` waits on its fence).
                unsafe { r.prepare(index) }?;
                run_recorder(ctx, r, self.main_readback.as_ref(), stamps)?
            }
            None => Rendered::default(),
        };
        if let (Some(r), Some(cam)) = (&mut self.smooth, &self.camera) {
            let s = plan.antialias.supersample;
            // SAFETY: no submission using it is pending (`submit` waits on its fence).
            unsafe { r.prepare(index) }?;
            let mut images = Vec::new();
            for offset in jitter_offsets(plan.antialias.jitter) {
                let shift = offset / s as f64;
                let big = scaled_camera(&shifted(cam, shift)?, s)?;
                // SAFETY: the last pass's submission has completed (`submit` waits).
                unsafe { r.jitter(&big, shift * s as f64) }?;
                let colour = run_recorder(ctx, r, self.smooth_readback.as_ref(), None)?
                    .color
                    .ok_or_else(|| Error::internal("the anti-aliased pass rendered no colour"))?;
                images.push(downsample(&colour, s));
            }
            rendered.color = Some(average(&images));
            rendered.width = cam.width;
            rendered.height = cam.height;
        }
        if rendered.width == 0 {
            if let Some(cam) = &self.camera {
                (rendered.width, rendered.height) = (cam.width, cam.height);
            }
        }
        let ms = start.elapsed().as_secs_f64() * 1e3;
        let mut pass_ms = Vec::new();
        if let (Some(q), Some(r), true) = (stamps, &self.main, stamps_now) {
            let ns = q.read_ns()?;
            pass_ms = r
                .pass_names()
                .iter()
                .enumerate()
                .map(|(i, n)| (*n, (ns[i + 1] - ns[i]) / 1e6))
                .collect();
            self.recorded.pass_ms = pass_ms.clone();
        }
        Ok(Frame {
            index,
            rendered,
            ms,
            pass_ms,
        })
    }

    /// The pipelines recorded, and the passes' GPU time of the timed frame.
    pub fn into_recorded(self) -> Recorded {
        self.recorded
    }
}

/// An error naming frame `index` where the plan has no pose of that index.
fn check_frame(plan: &Plan, index: usize) -> Result<()> {
    if index < plan.poses.len() {
        return Ok(());
    }
    Err(Error::input(format!(
        "frame {index}: the scene has {} pose(s)",
        plan.poses.len()
    )))
}

/// Runs one recorder's prepared frame and reads its outputs back.
fn run_recorder(
    ctx: &Context,
    r: &PlanRecorder,
    readback: Option<&PlanReadback>,
    timestamps: Option<&QueryPool>,
) -> Result<Rendered> {
    let gpu = ctx.gpu();
    let readback = readback.ok_or_else(|| Error::internal("a recorder without its readback"))?;
    ctx.submit(|cmd| {
        // SAFETY: `cmd` is recording outside a render pass; the recorder was set up and
        // prepared, and `submit` waits, so nothing it records outlives the recorder or the
        // readback made for it.
        unsafe {
            r.record(cmd, timestamps);
            readback.record(gpu, cmd, r)
        }
    })?;
    readback.read(r)
}

/// Renders `request` once on the headless context (the plan for `scene`, which sizes the
/// bands of a moving rolling shutter on the warp and cube paths, then [`execute_untimed`]);
/// `progress` hears each step of the plan.
pub fn render_request(
    ctx: &crate::host::Context,
    scene: &Scene,
    request: &RenderRequest,
    progress: &mut dyn FnMut(&str),
) -> Result<Rendered> {
    let plan = Plan::from_request_with_scene(request, scene, ctx.gpu().max_image_side())?;
    for s in &plan.steps {
        progress(&format!("{}: {}", s.stage.name(), s.why));
    }
    let mut out = None;
    execute_untimed(ctx, &plan, scene, [0], &mut |f| {
        out = Some(f.rendered);
        Ok(())
    })?;
    out.ok_or_else(|| Error::internal("the plan rendered no frame"))
}

/// Which output a route's image is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Output {
    /// Colour from the warp or the cube map.
    Colour,
    /// The lens film (its alpha the accumulated weight).
    Film,
    /// A 360° source's colour (RGBA32F, 8-bit unless the plan asks for float).
    Environment,
    /// Where a 360° source's pixels have a source.
    Mask,
    Ids,
    Depth,
    Range,
}

/// The images of `recorder`'s outputs that its geometry targets do not hold, each with the
/// layout a frame leaves it in: one list, so that the buffers and the copies agree.
fn route_images(recorder: &PlanRecorder) -> Vec<(Output, &crate::gpu::Image, Left)> {
    let mut images = Vec::new();
    if let Some(l) = recorder.lens_renderer() {
        images.push((Output::Film, &l.film().image, Left::ColorAttachment));
    }
    if let Some(c) = recorder.cube_stage() {
        if recorder.outputs().color {
            images.push((Output::Colour, &c.output, Left::ComputeGeneral));
        }
        if let Some(d) = &c.data {
            let asked = [
                (d.asked.ids, Output::Ids, &d.ids),
                (d.asked.depth, Output::Depth, &d.depth),
                (d.asked.range, Output::Range, &d.range),
            ];
            for (asked, output, image) in asked {
                if asked {
                    images.push((output, image, Left::ComputeGeneral));
                }
            }
        }
    }
    if let Some(e) = recorder.environment_stage() {
        images.push((Output::Environment, &e.output, Left::ComputeGeneral));
        images.push((Output::Mask, &e.mask, Left::ComputeGeneral));
    }
    if let Some(st) = recorder.warp_stage() {
        if recorder.outputs().color {
            images.push((Output::Colour, &st.output, Left::ComputeGeneral));
        }
        if let Some(d) = &st.ids {
            images.push((Output::Ids, &d.output, Left::ComputeGeneral));
        }
        if let Some(d) = &st.depth {
            images.push((Output::Depth, &d.output, Left::ComputeGeneral));
        }
        if let Some(d) = &st.range {
            images.push((Output::Range, &d.output, Left::ComputeGeneral));
        }
    }
    images
}

/// Host buffers for every output a [`PlanRecorder`]'s plan asks for, and their reading into a
/// [`Rendered`]: the headless path's readback (an engine samples the recorder's images in
/// place instead, see [`PlanRecorder::images`]).
pub struct PlanReadback {
    geometry: Option<TargetsReadback>,
    /// The other outputs, in the order of [`route_images`].
    others: Vec<(Output, Download)>,
}

impl PlanReadback {
    /// Buffers for the outputs `recorder` renders.
    pub fn new(gpu: &crate::gpu::Gpu, recorder: &PlanRecorder) -> Result<Self> {
        let geometry = recorder
            .geometry_targets()
            .map(|t| TargetsReadback::new(gpu, t))
            .transpose()?;
        let others = route_images(recorder)
            .into_iter()
            .map(|(output, image, _)| Ok((output, Download::new(gpu, image, "plan.download")?)))
            .collect::<Result<_>>()?;
        Ok(PlanReadback { geometry, others })
    }

    /// Records the copies of the outputs of the frame `recorder` just recorded.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass, after [`PlanRecorder::record`] of
    /// `recorder` (the one this readback was made for); everything alive until the work
    /// completes.
    pub unsafe fn record(
        &self,
        gpu: &crate::gpu::Gpu,
        cmd: ash::vk::CommandBuffer,
        recorder: &PlanRecorder,
    ) -> Result<()> {
        // SAFETY (both blocks): the caller upholds this function's contract; each image is in
        // the layout `PlanRecorder::record` documents for it, named by `Left`, and each
        // `Download::record` checks the image is the one its buffer was made for.
        if let (Some(r), Some(t)) = (&self.geometry, recorder.geometry_targets()) {
            unsafe { r.record(gpu, cmd, t, ash::vk::ImageLayout::TRANSFER_SRC_OPTIMAL) }?;
        }
        for ((_, d), (_, image, left)) in self.others.iter().zip(route_images(recorder)) {
            unsafe { d.record(gpu, cmd, image, left) }?;
        }
        Ok(())
    }

    /// The outputs of the frame (after the submission completed): colour, IDs, flow and
    /// depth as the plan asks for them.
    pub fn read(&self, recorder: &PlanRecorder) -> Result<Rendered> {
        let o = recorder.outputs();
        let mut out = match &self.geometry {
            Some(g) => g.read()?,
            None => Rendered::default(),
        };
        for (output, d) in &self.others {
            let e = d.extent();
            (out.width, out.height) = (e.width, e.height);
            match output {
                Output::Colour | Output::Film => {
                    let colour = if *output == Output::Film {
                        film_colour(d, recorder.keeps_vignetting(), o.exr)?
                    } else {
                        d.read_rgba()?
                    };
                    out.color = Some(colour);
                }
                Output::Environment => {
                    let colour = d.read_rgba()?;
                    out.color = Some(if o.exr {
                        colour
                    } else {
                        colour.to_rgba8_rounded()
                    });
                }
                Output::Mask => out.mask = Some(d.read()?),
                Output::Ids => out.ids = Some(d.read()?),
                Output::Depth => out.depth = Some(d.read()?),
                Output::Range => out.range = Some(d.read()?),
            }
        }
        if !o.color {
            out.color = None;
        }
        Ok(out)
    }
}

/// The lens film as an image: alpha is the accumulated weight of what was drawn (relative
/// illumination where the scene is opaque), divided out unless the plan keeps vignetting.
fn film_colour(film: &Download, vignetting: bool, float: bool) -> Result<Raster> {
    let e = film.extent();
    let pixels = film
        .read::<[f32; 4]>()?
        .iter()
        .map(|p| {
            let a = p[3];
            if vignetting || a <= 1e-6 {
                [p[0], p[1], p[2], 1.0]
            } else {
                [p[0] / a, p[1] / a, p[2] / a, 1.0]
            }
        })
        .collect::<Vec<_>>();
    let film = Raster {
        width: e.width,
        height: e.height,
        pixels: Pixels::Rgba32F(pixels),
        bit_depth: BitDepth::F32,
    };
    Ok(if float { film } else { film.to_rgba8_rounded() })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::scene_file::{Antialias, SceneFile};
    use crate::testing::{assert_no_validation_messages, validated_context as context};

    /// An example scene's plan, one sample per pixel, with at least two different poses.
    fn two_pose_plan(name: &str) -> (Plan, Scene) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples/scenes")
            .join(name);
        let file = SceneFile::load(&path).unwrap();
        let scene = crate::plan::load_geometry(&file).unwrap();
        let mut p = crate::plan::plan(&file, &scene).unwrap();
        p.antialias = Antialias::default();
        if p.poses.len() < 2 {
            let mut moved = p.poses[0];
            moved.translation.x += 0.05;
            p.poses.push(moved);
        }
        p.poses.truncate(2);
        (p, scene)
    }

    /// Frames 0 and 1 recorded into one command buffer after both were prepared, as an engine
    /// records frame N + 1 before frame N has run; each read back between the frames.
    fn both_in_one_submission(
        ctx: &Context,
        plan: &Plan,
        scene: &Scene,
        frames: usize,
    ) -> [Rendered; 2] {
        let gpu = ctx.gpu();
        let mut r = PlanRecorder::with_frames(gpu, plan, scene, frames).unwrap();
        let readbacks = [
            PlanReadback::new(gpu, &r).unwrap(),
            PlanReadback::new(gpu, &r).unwrap(),
        ];
        for frame in 0..2 {
            r.select_frame(frame);
            // SAFETY: nothing has been submitted yet.
            unsafe { r.prepare(frame) }.unwrap();
        }
        let r = ctx
            .submit(|cmd| {
                // SAFETY: `cmd` is recording outside a render pass; `submit` waits, so the
                // recorder and the readbacks outlive the work.
                unsafe {
                    r.record_setup(cmd);
                    for (frame, readback) in readbacks.iter().enumerate() {
                        r.select_frame(frame);
                        r.record(cmd, None);
                        readback.record(gpu, cmd, &r)?;
                    }
                }
                Ok(r)
            })
            .unwrap();
        readbacks.map(|b| b.read(&r).unwrap())
    }

    /// The same frames from a one-frame recorder, each submitted and waited for in turn.
    fn one_after_the_other(ctx: &Context, plan: &Plan, scene: &Scene) -> [Rendered; 2] {
        let gpu = ctx.gpu();
        let mut r = PlanRecorder::new(gpu, plan, scene).unwrap();
        let readback = PlanReadback::new(gpu, &r).unwrap();
        // SAFETY: `submit` waits: nothing is pending after it.
        ctx.submit(|cmd| {
            unsafe { r.record_setup(cmd) };
            Ok(())
        })
        .unwrap();
        [0, 1].map(|frame| {
            // SAFETY: the last submission has completed (`submit` waits).
            unsafe { r.prepare(frame) }.unwrap();
            ctx.submit(|cmd| unsafe {
                r.record(cmd, None);
                readback.record(gpu, cmd, &r)
            })
            .unwrap();
            readback.read(&r).unwrap()
        })
    }

    fn same(a: &Rendered, b: &Rendered) -> bool {
        let colour = |r: &Rendered| r.color.as_ref().map(|c| format!("{:?}", c.pixels));
        colour(a) == colour(b) && a.ids == b.ids && a.depth == b.depth && {
            // Flow is NaN in the background: compare bits.
            let bits = |r: &Rendered| {
                r.flow
                    .as_ref()
                    .map(|f| f.iter().map(|v| v.map(f32::to_bits)).collect::<Vec<_>>())
            };
            bits(a) == bits(b)
        }
    }

    #[test]
    fn every_route_keeps_a_frame_in_flight_of_its_own() {
        let ctx = context();
        // Alg. 1 with IDs, flow and depth; the chromatic map warp; the cube map; the lens model;
        // the chromatic warp in bands.
        for name in [
            "ids_and_flow.toml",
            "chromatic.toml",
            "fisheye_chromatic.toml",
            "lens_chromatic.toml",
            // The chromatic warp in bands of a moving rolling shutter's lines: a slot per band
            // and frame in flight.
            "rolling_shutter_chromatic.toml",
        ] {
            let (plan, scene) = two_pose_plan(name);
            let expected = one_after_the_other(ctx, &plan, &scene);
            assert!(
                !same(&expected[0], &expected[1]),
                "{name}: the two poses must render differently for this test to mean anything"
            );
            for refused in [0, crate::pass::geometry::MAX_FRAMES_IN_FLIGHT + 1] {
                let e = PlanRecorder::with_frames(ctx.gpu(), &plan, &scene, refused);
                assert!(
                    e.is_err_and(|e| e.to_string().contains("frames in flight")),
                    "{name}: {refused} frames in flight"
                );
            }
            let got = both_in_one_submission(ctx, &plan, &scene, 2);
            for frame in 0..2 {
                assert!(
                    same(&got[frame], &expected[frame]),
                    "{name}: frame {frame} in flight differs from the same frame rendered alone"
                );
            }
            // One set of uniforms for both: the first frame draws with the second's pose.
            let shared = both_in_one_submission(ctx, &plan, &scene, 1);
            assert!(
                same(&shared[0], &expected[1]),
                "{name}: with one frame in flight the first frame should show the second pose"
            );
        }
        assert_no_validation_messages(ctx);
    }
}
