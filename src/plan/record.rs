//! A plan as GPU passes that record into a command buffer the caller owns (an engine's), on
//! any [`Gpu`]: [`PlanRecorder`]. It is also how `--explain` measures each pass's GPU time:
//! [`PlanRecorder::record`] can write a timestamp after every pass.
//!
//! What it records per route: a pinhole render or Alg. 1 (every output), the warp path's
//! pinhole render + warp (colour, and depth by a second, nearest warp), both for warp + Alg. 1,
//! or the lens model's frame.

use ash::vk;

use super::{Plan, Route};
use crate::gpu::{Error, Gpu, QueryPool, Result};
use crate::model::overscan::overscan;
use crate::model::warp::WarpGeometry;
use crate::model::{Camera, OpenCvDistortion};
use crate::pass::geometry::{
    ColorFormat, GeometryDesc, GeometryPass, GeometryTargets, MeshBuffers, Outputs, Projection,
    DEFAULT_DELTA,
};
use crate::pass::lens_render::{LensRenderOptions, LensRenderer};
use crate::pass::warp::Coordinates;
use crate::render::WarpStage;
use crate::scene::{Pose, Scene};

fn invalid(e: impl ToString) -> Error {
    Error::Input(e.to_string())
}

/// The passes of one plan, built once; any number of frames recorded.
pub struct PlanRecorder {
    /// Alg. 1 or the pinhole render with its targets (every output it renders).
    geometry: Option<(GeometryPass, GeometryTargets)>,
    /// The warp path's colour.
    warp: Option<WarpStage>,
    lens: Option<LensRenderer>,
    mesh: MeshBuffers,
    poses: Vec<Pose>,
    /// Names of the passes in recording order (for timings).
    names: Vec<&'static str>,
}

impl PlanRecorder {
    /// Builds the plan's passes on `gpu` for `scene` (its mesh tessellated, where the plan
    /// says so, at the first pose).
    pub fn new(gpu: &Gpu, plan: &Plan, scene: &Scene) -> Result<Self> {
        if plan.antialias.is_on() {
            return Err(invalid(
                "the recorder draws one sample per pixel: the scene's [render] supersample / jitter are averaged on the host by execute(); an engine anti-aliases its own way (MSAA, TAA)",
            ));
        }
        let o = plan.outputs;
        let format = if o.exr {
            ColorFormat::Rgba16F
        } else {
            ColorFormat::Rgba8
        };
        let outputs = Outputs {
            color: o.color.then_some(format),
            ids: o.ids,
            flow: o.flow,
            depth: o.depth,
        };
        let first = *plan
            .poses
            .first()
            .ok_or_else(|| invalid("a plan without poses"))?;
        let tessellated = |l: Option<f64>, camera: &Camera| match l {
            Some(l) => crate::scene::tessellate::tessellate(&scene.mesh, &first, camera, l)
                .map_err(invalid),
            None => Ok(scene.mesh.clone()),
        };
        let geometry = |camera: &Camera, projection, outputs| -> Result<_> {
            let mut desc = GeometryDesc::new(camera.clone(), projection, outputs);
            desc.background = plan.background;
            let pass = GeometryPass::new(gpu, desc)?;
            let targets = GeometryTargets::new(gpu, &pass)?;
            Ok((pass, targets))
        };
        let warp_stage = |camera: &Camera,
                          method,
                          chromatic: Option<[f64; 3]>,
                          depth: bool|
         -> Result<WarpStage> {
            let ov = overscan(camera, 1.0).map_err(invalid)?;
            let source = Camera::new(
                ov.width,
                ov.height,
                ov.intrinsics,
                OpenCvDistortion::default(),
            )
            .map_err(invalid)?;
            let mut g = WarpGeometry::distort(camera.clone(), method)
                .with_ideal(ov.intrinsics, (ov.width, ov.height))
                .map_err(invalid)?;
            if let Some(s) = chromatic {
                g = g.with_chromatic(s).map_err(invalid)?;
            }
            // The warp reads RGBA8 or RGBA32F sources.
            let f = if format == ColorFormat::Rgba8 {
                ColorFormat::Rgba8
            } else {
                ColorFormat::Rgba32F
            };
            WarpStage::with_depth(
                gpu,
                source,
                g,
                Coordinates::Analytic,
                f,
                plan.background,
                depth,
            )
        };
        // One mesh for every pass: tessellated where Alg. 1 needs it (the warp's pinhole
        // render of warp + Alg. 1 does not mind the finer mesh).
        let mesh = match (&plan.route, plan.camera.as_ref()) {
            (
                Route::Vertex { tessellate } | Route::WarpAndVertex { tessellate, .. },
                Some(camera),
            ) => tessellated(*tessellate, camera)?,
            _ => scene.mesh.clone(),
        };
        let mut r = PlanRecorder {
            geometry: None,
            warp: None,
            lens: None,
            mesh: MeshBuffers::new(gpu, &mesh, scene.texture.as_ref())?,
            poses: plan.poses.clone(),
            names: Vec::new(),
        };
        let lens_delta = Projection::Lens {
            delta: DEFAULT_DELTA,
        };
        match &plan.route {
            Route::LensModel { .. } => {
                let setting = plan.lens.as_ref().ok_or_else(|| invalid("no lens"))?;
                r.lens = Some(LensRenderer::new(
                    gpu,
                    &setting.models,
                    LensRenderOptions::default(),
                )?);
                r.names.push("image-based lens model (cells + film)");
            }
            route => {
                let camera = plan.camera.as_ref().ok_or_else(|| invalid("no camera"))?;
                match route {
                    Route::Pinhole => {
                        r.geometry = Some(geometry(camera, Projection::Pinhole, outputs)?);
                        r.names.push("pinhole render");
                    }
                    Route::Vertex { .. } => {
                        r.geometry = Some(geometry(camera, lens_delta, outputs)?);
                        r.names.push("Alg. 1 (vertex + discard)");
                    }
                    Route::Warp { method, chromatic } => {
                        if o.ids || o.flow {
                            return Err(invalid(
                                "IDs and flow take Alg. 1 (Lambers et al. Table 1): the planner never routes them through the warp",
                            ));
                        }
                        r.warp = Some(warp_stage(camera, *method, *chromatic, o.depth)?);
                        r.names.extend(["pinhole render (overscanned)", "warp"]);
                    }
                    Route::WarpAndVertex {
                        method, chromatic, ..
                    } => {
                        if o.color {
                            r.warp = Some(warp_stage(camera, *method, *chromatic, false)?);
                            r.names.extend(["pinhole render (overscanned)", "warp"]);
                        }
                        r.geometry = Some(geometry(
                            camera,
                            lens_delta,
                            Outputs {
                                color: None,
                                ..outputs
                            },
                        )?);
                        r.names.push("Alg. 1 (vertex + discard), data outputs");
                    }
                    Route::LensModel { .. } => unreachable!(),
                }
            }
        }
        Ok(r)
    }

    /// The passes [`Self::record`] times, in order.
    pub fn pass_names(&self) -> &[&'static str] {
        &self.names
    }

    /// Timestamps [`Self::record`] writes: one before the first pass and one after each.
    pub fn timestamp_count(&self) -> u32 {
        self.names.len() as u32 + 1
    }

    /// Sets frame `index`'s pose (host writes: no recorded frame may be executing).
    pub fn prepare(&mut self, index: usize) -> Result<()> {
        let pose = *self
            .poses
            .get(index)
            .ok_or_else(|| invalid(format!("no frame {index}")))?;
        let previous = if index > 0 {
            self.poses[index - 1]
        } else {
            pose
        };
        if let Some((pass, _)) = &mut self.geometry {
            pass.bind_mesh(&self.mesh);
            pass.set_frame(&pose, &previous)?;
        }
        if let Some(st) = &mut self.warp {
            st.pass.bind_mesh(&self.mesh);
            st.pass.set_frame(&pose, &pose)?;
        }
        if let Some(l) = &mut self.lens {
            l.prepare(&self.mesh, &pose)?;
        }
        Ok(())
    }

    /// Records the one-off work: the mesh texture upload, the warp's output layouts.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass on a graphics queue of this recorder's
    /// device; once, before the first frame.
    pub unsafe fn record_setup(&self, cmd: vk::CommandBuffer) {
        // SAFETY: the caller upholds `record_setup`'s contract: `cmd` is recording outside a
        // render pass on a graphics queue of this device (`Gpu::from_caller` requires compute
        // on it too), once, before any frame, so nothing using these images is pending.
        unsafe {
            self.mesh.record_upload(cmd);
            if let Some(st) = &self.warp {
                st.record_prepare(cmd);
            }
        }
    }

    /// Records a prepared frame. With `timestamps` (at least [`Self::timestamp_count`]
    /// queries, reset here), a timestamp before the first pass and after each.
    ///
    /// Leaves: the geometry outputs in `TRANSFER_SRC_OPTIMAL`, the warp's output in
    /// `GENERAL`, the lens film in `COLOR_ATTACHMENT_OPTIMAL` — see [`Self::images`].
    ///
    /// # Safety
    /// After [`Self::record_setup`] and [`Self::prepare`]; everything alive until the work
    /// completes.
    pub unsafe fn record(&self, cmd: vk::CommandBuffer, timestamps: Option<&QueryPool>) {
        let mut k = 0;
        let mut stamp = || {
            if let Some(q) = timestamps {
                q.cmd_write(cmd, k);
            }
            k += 1;
        };
        if let Some(q) = timestamps {
            q.cmd_reset(cmd);
        }
        stamp();
        unsafe {
            if let Some(l) = &self.lens {
                l.record(cmd, &self.mesh);
                stamp();
            }
            if let Some(st) = &self.warp {
                st.pass.record(cmd, &st.targets, &self.mesh);
                stamp();
                st.record_warps(cmd);
                stamp();
            }
            if let Some((pass, targets)) = &self.geometry {
                pass.record(cmd, targets, &self.mesh);
                stamp();
            }
        }
    }

    /// The warp route's depth (R32F metres, +inf where nothing was drawn or there is no
    /// source; `GENERAL` after a frame), when the plan asks for depth through the warp.
    pub fn warped_depth(&self) -> Option<&crate::gpu::Image> {
        self.warp.as_ref()?.depth.as_ref().map(|d| &d.output)
    }

    /// The images a recorded frame leaves: colour (warp output, lens film or geometry
    /// colour) and the geometry pass's targets (IDs, flow, depth) for the caller to read or
    /// sample. The warp route's depth is [`Self::warped_depth`].
    pub fn images(&self) -> (Option<&crate::gpu::Image>, Option<&GeometryTargets>) {
        let colour = if let Some(st) = &self.warp {
            Some(&st.output)
        } else if let Some(l) = &self.lens {
            Some(&l.film().image)
        } else {
            self.geometry.as_ref().and_then(|(_, t)| t.color())
        };
        (colour, self.geometry.as_ref().map(|(_, t)| t))
    }
}

/// Measures each pass of `plan` on frame `index` with GPU timestamps (after one warm-up
/// frame): (pass, milliseconds). `None` where the queue has no timestamps.
pub fn pass_times(
    ctx: &crate::gpu::Context,
    plan: &Plan,
    scene: &Scene,
    index: usize,
) -> Result<Option<Vec<(&'static str, f64)>>> {
    let mut recorder = PlanRecorder::new(ctx.gpu(), plan, scene)?;
    let Ok(queries) = QueryPool::timestamps(ctx.gpu(), recorder.timestamp_count()) else {
        return Ok(None);
    };
    recorder.prepare(index)?;
    let r = &recorder;
    ctx.submit(|cmd| {
        unsafe {
            r.record_setup(cmd);
            r.record(cmd, None);
        }
        Ok(())
    })?;
    ctx.submit(|cmd| {
        unsafe { r.record(cmd, Some(&queries)) };
        Ok(())
    })?;
    let ns = queries.read_ns()?;
    Ok(Some(
        recorder
            .names
            .iter()
            .enumerate()
            .map(|(i, n)| (*n, (ns[i + 1] - ns[i]) / 1e6))
            .collect(),
    ))
}
