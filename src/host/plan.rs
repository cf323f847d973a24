//! The headless path of the one recorder: a [`PlanRecorder`] built once records each frame;
//! this submits it, reads the outputs back, and averages anti-aliased colour on the host.

use std::time::Instant;

use crate::gpu::QueryPool;
use crate::pass::geometry::Rendered;
use crate::plan::antialias::{average, shifted};
use crate::plan::record::{plan_mesh_at, tessellation};
use crate::plan::scene_file::OutputSpec;
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
    if let Some(&bad) = frames.iter().find(|&&i| i >= plan.poses.len()) {
        return Err(Error::input(format!(
            "frame {bad}: the scene has {} pose(s)",
            plan.poses.len()
        )));
    }
    let gpu = ctx.gpu();
    let o = plan.outputs;
    let lens = matches!(plan.route, Route::LensModel { .. });
    let antialias = plan.antialias.is_on() && o.color && !lens;
    let first = frames.first().copied().unwrap_or(0);
    let mesh = plan_mesh_at(plan, scene, first)?;
    // A tessellation holds its straight-edge bound at the pose it was made for: frames of
    // other poses get their own.
    let per_pose = tessellation(plan).is_some();
    let mut mesh_pose = first;
    let texture = scene.texture.as_ref();
    // The 1× recorder: every output, or the data outputs alone when the colour is
    // anti-aliased.
    let mut main_plan = plan.clone();
    if antialias {
        main_plan.outputs.color = false;
    }
    let data = main_plan.outputs;
    let mut main = if data.color || data.ids || data.flow || data.depth {
        Some(PlanRecorder::build(gpu, &main_plan, &mesh, texture)?)
    } else {
        None
    };
    let s = plan.antialias.supersample;
    let camera = plan.camera().cloned();
    let mut smooth = match (&camera, antialias) {
        (Some(cam), true) => {
            let mut p = plan.clone();
            p.optics = Optics::Camera(scaled_camera(cam, s)?);
            p.outputs = OutputSpec {
                ids: false,
                flow: false,
                depth: false,
                ..o
            };
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
            Some(PlanRecorder::build(gpu, &p, &mesh, texture)?)
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
    // Run one recorder's prepared frame and read its outputs back.
    let run = |r: &PlanRecorder, timestamps: Option<&QueryPool>| -> Result<Rendered> {
        ctx.submit(|cmd| {
            // SAFETY: `cmd` is recording outside a render pass; the recorder was set up and
            // prepared, and `submit` waits, so nothing it records outlives the recorder.
            unsafe {
                r.record(cmd, timestamps);
                r.record_download(cmd);
                crate::gpu::host_read_barrier(gpu, cmd);
            }
            Ok(())
        })?;
        r.read()
    };
    // The first frame once more before timing: caches warm up on first use.
    let warm_up = frames.first().copied().filter(|_| timing);
    let mut first_timed = true;
    for (index, timed) in warm_up
        .map(|i| (i, false))
        .into_iter()
        .chain(frames.iter().map(|&i| (i, true)))
    {
        let start = Instant::now();
        if per_pose && index != mesh_pose {
            let mesh = plan_mesh_at(plan, scene, index)?;
            for r in main.iter_mut().chain(smooth.iter_mut()) {
                // SAFETY: every submission has completed (`submit` waits on its fence).
                unsafe { r.set_mesh(gpu, &mesh, texture) }?;
            }
            // SAFETY: before the frame that draws the new mesh.
            unsafe {
                submit_each(
                    ctx,
                    main.iter().chain(smooth.iter()),
                    PlanRecorder::record_mesh_upload,
                )
            }?;
            mesh_pose = index;
        }
        let mut rendered = match &mut main {
            Some(r) => {
                // SAFETY: no submission using it is pending (`submit` waits on its fence).
                unsafe { r.prepare(index) }?;
                let stamps = if timed && first_timed {
                    queries.as_ref()
                } else {
                    None
                };
                run(r, stamps)?
            }
            None => Rendered::default(),
        };
        if let (Some(r), Some(cam)) = (&mut smooth, &camera) {
            // SAFETY: no submission using it is pending (`submit` waits on its fence).
            unsafe { r.prepare(index) }?;
            let mut images = Vec::new();
            for offset in jitter_offsets(plan.antialias.jitter) {
                let shift = offset / s as f64;
                let big = scaled_camera(&shifted(cam, shift)?, s)?;
                // SAFETY: the last pass's submission has completed (`submit` waits).
                unsafe { r.jitter(&big, shift * s as f64) }?;
                let colour = run(r, None)?
                    .color
                    .ok_or_else(|| Error::internal("the anti-aliased pass rendered no colour"))?;
                images.push(downsample(&colour, s));
            }
            rendered.color = Some(average(&images));
            rendered.width = cam.width;
            rendered.height = cam.height;
        }
        if rendered.width == 0 {
            if let Some(cam) = &camera {
                (rendered.width, rendered.height) = (cam.width, cam.height);
            }
        }
        let ms = start.elapsed().as_secs_f64() * 1e3;
        if timed {
            let mut pass_ms = Vec::new();
            if first_timed {
                if let (Some(q), Some(r)) = (&queries, &main) {
                    let ns = q.read_ns()?;
                    pass_ms = r
                        .pass_names()
                        .iter()
                        .enumerate()
                        .map(|(i, n)| (*n, (ns[i + 1] - ns[i]) / 1e6))
                        .collect();
                    recorded.pass_ms = pass_ms.clone();
                }
                first_timed = false;
            }
            each(Frame {
                index,
                rendered,
                ms,
                pass_ms,
            })?;
        }
    }
    Ok(recorded)
}

/// Renders `request` once on the headless context (the plan, then [`execute_untimed`]);
/// `progress` hears each step of the plan.
pub fn render_request(
    ctx: &crate::host::Context,
    scene: &Scene,
    request: &RenderRequest,
    progress: &mut dyn FnMut(&str),
) -> Result<Rendered> {
    let plan = Plan::from_request(request, ctx.gpu().max_image_side())?;
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
