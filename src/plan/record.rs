//! A plan as GPU passes that record into a command buffer the caller owns (an engine's), on
//! any [`Gpu`]: [`PlanRecorder`]. The headless `host::plan::execute` submits it and reads back;
//! [`PlanRecorder::record`] can write a timestamp after every pass.
//!
//! What it records per route (`Stages`, one variant per kind of route, each holding exactly
//! its stages): a pinhole render or Alg. 1 (every output), the warp path's pinhole render +
//! warp (colour, and depth by a second, nearest warp), both for warp + Alg. 1, a cube map's
//! six faces + the sphere warp, or the lens model's frame.

use ash::vk;
use glam::DVec2;

use super::{Plan, Route};
use crate::gpu::{Error, Gpu, QueryPool, Result};
use crate::imaging::Raster;
use crate::model::rolling_shutter::bands::Band;
use crate::model::rolling_shutter::FrameMotion;
use crate::model::warp::WarpGeometry;
use crate::model::{Camera, InverseMethod, OpenCvDistortion};
use crate::pass::cube_stage::CubeStage;
use crate::pass::environment::EnvironmentStage;
use crate::pass::geometry::DEFAULT_NEAR;
use crate::pass::geometry::{
    ColorFormat, GeometryDesc, GeometryPass, GeometrySlots, GeometryTargets, MeshBuffers, Outputs,
    Projection,
};
use crate::pass::lens_render::{LensRenderOptions, LensRenderer};
use crate::pass::sphere_warp::SphereWarpOptions;
use crate::pass::warp::Coordinates;
use crate::pass::warp_stage::{DataOutputs, WarpStage};
use crate::scene::{Environment, Mesh, Pose, Scene};

/// A bug: a plan the planner cannot have made.
fn internal(e: impl ToString) -> Error {
    Error::Internal(e.to_string())
}

/// The mesh every pass of `plan` draws at pose `index`: tessellated where Alg. 1 needs it, at
/// that pose (the straight-edge bound is a property of the pose; the warp's pinhole render of
/// warp + Alg. 1 does not mind the finer mesh).
pub(crate) fn plan_mesh_at(plan: &Plan, scene: &Scene, index: usize) -> Result<Mesh> {
    let pose = plan
        .poses
        .get(index)
        .ok_or_else(|| internal(format!("no pose {index} in the plan")))?;
    let Some(camera) = plan.camera() else {
        return Ok(scene.mesh.clone());
    };
    let mesh = match tessellation(plan) {
        Some(l) => crate::scene::tessellate::tessellate(&scene.mesh, pose, camera, l)?,
        None => scene.mesh.clone(),
    };
    if !matches!(
        plan.route,
        Route::Vertex { .. } | Route::WarpAndVertex { .. }
    ) {
        return Ok(mesh);
    }
    // Alg. 1 drops a triangle with one vertex it does not keep whole: where an object crosses
    // the edge of what the lens sees, split down to the budget instead of losing a strip.
    // A plan held to no budget (a path taken as named) follows it to the default one.
    let budget = if plan.budget_px.is_finite() {
        plan.budget_px
    } else {
        super::scene_file::DEFAULT_MAX_ERROR_PX
    };
    let kept = crate::pass::geometry::vertex_kept(camera, plan.delta, DEFAULT_NEAR)?;
    crate::scene::tessellate::refine_rim(&mesh, pose, camera, kept, budget, tessellation(plan))
}

/// The edge length (px) the plan tessellates to, if it does.
pub(crate) fn tessellation(plan: &Plan) -> Option<f64> {
    match &plan.route {
        Route::Vertex { tessellate } | Route::WarpAndVertex { tessellate, .. } => *tessellate,
        _ => None,
    }
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
    /// A nearest warp that carries IDs or depth along the colour's.
    DataWarp,
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
            PassKind::DataWarp => "data warp (nearest)",
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

pub(crate) fn geometry_kind(pass: &GeometryPass) -> PassKind {
    match pass.desc().projection {
        Projection::Lens { .. } => PassKind::VertexRender,
        Projection::Pinhole => PassKind::PinholeRender,
    }
}

/// A moving rolling shutter drawn by the warp in bands of lines: the warp's pinhole source
/// rendered once per band, from the pose of the band's middle line, and each band of the
/// output warped from its own render.
struct BandedSource {
    gpu: Gpu,
    /// The bands, in readout order.
    bands: Vec<Band>,
    /// One camera-and-pose slot of the warp's pinhole render per band and frame in flight
    /// (band k of frame f at f · bands + k).
    slots: GeometrySlots,
    /// The source camera the slots render with (a jittered pass moves it).
    camera: Camera,
    /// The frame in flight [`PlanRecorder::select_frame`] selected.
    frame: usize,
    /// Each frame in flight's band poses, as last prepared.
    poses: Vec<Vec<Pose>>,
}

impl BandedSource {
    /// Writes the selected frame's slots: each band's pose with `self.camera`.
    ///
    /// # Safety
    /// No recorded work of the selected frame may be pending.
    unsafe fn write_slots(&self, pass: &GeometryPass) -> Result<()> {
        let n = self.bands.len();
        for (k, pose) in self.poses[self.frame].iter().enumerate() {
            // SAFETY: the caller upholds this function's contract: nothing that reads the
            // selected frame's slots is pending.
            unsafe { pass.set_slot(&self.slots, self.frame * n + k, &self.camera, pose, pose) }?;
        }
        Ok(())
    }
}

/// The geometry path's pass with its targets: the pinhole render or Alg. 1.
type GeometryStage = (GeometryPass, GeometryTargets);

/// The warp route's stages: the pinhole source render and the warps (IDs and depth nearest
/// where asked), the source camera and warp geometry as built (jittered passes shift both),
/// and its bands where the camera moves during the readout.
struct WarpRoute {
    stage: WarpStage,
    source: Camera,
    geometry: WarpGeometry,
    bands: Option<BandedSource>,
}

/// What a recorder records, by the plan's route: each variant holds exactly the stages its
/// route has, so no combination of passes exists that no route makes.
// One per recorder, built once and never moved in a loop: its size costs nothing.
#[allow(clippy::large_enum_variant)]
enum Stages {
    /// [`Route::Pinhole`] and [`Route::Vertex`] (every output), and [`Route::WarpAndVertex`]
    /// when it asks for no colour (Alg. 1 for IDs, flow and depth alone).
    Geometry(GeometryStage),
    /// [`Route::Warp`], and [`Route::WarpAndVertex`] with Alg. 1 for its data outputs.
    Warp {
        warp: Box<WarpRoute>,
        data: Option<GeometryStage>,
    },
    /// [`Route::Cube`]: six faces and the sphere warp, in bands (one set of faces each, in the
    /// stage's slots) where the camera moves during the readout.
    Cube {
        cube: CubeStage,
        bands: Option<Vec<Band>>,
    },
    /// [`Route::LensModel`]: Heidrich et al.'s image-based model.
    Lens(LensRenderer),
    /// [`Route::Environment`]: the scene's 360° image and the sphere warp.
    Environment(EnvironmentStage),
}

impl Stages {
    /// The geometry pass, where the route has one.
    fn geometry(&self) -> Option<&GeometryStage> {
        match self {
            Stages::Geometry(g) => Some(g),
            Stages::Warp { data, .. } => data.as_ref(),
            Stages::Cube { .. } | Stages::Lens(_) | Stages::Environment(_) => None,
        }
    }

    fn geometry_mut(&mut self) -> Option<&mut GeometryStage> {
        match self {
            Stages::Geometry(g) => Some(g),
            Stages::Warp { data, .. } => data.as_mut(),
            Stages::Cube { .. } | Stages::Lens(_) | Stages::Environment(_) => None,
        }
    }

    fn warp(&self) -> Option<&WarpRoute> {
        match self {
            Stages::Warp { warp, .. } => Some(warp),
            _ => None,
        }
    }

    fn warp_mut(&mut self) -> Option<&mut WarpRoute> {
        match self {
            Stages::Warp { warp, .. } => Some(warp),
            _ => None,
        }
    }
}

/// What every pass of a recorder is built with: the device, the plan, the frames in flight;
/// and, as they are built, the passes' names and pipelines.
struct Builder<'a> {
    gpu: &'a Gpu,
    plan: &'a Plan,
    frames: usize,
    names: Vec<&'static str>,
    pipelines: Vec<RecordedPipeline>,
}

impl Builder<'_> {
    /// The colour target's format: half floats for EXR output, else 8-bit.
    fn color_format(&self) -> ColorFormat {
        if self.plan.outputs.exr {
            ColorFormat::Rgba16F
        } else {
            ColorFormat::Rgba8
        }
    }

    /// The images the plan asks the geometry path for.
    fn outputs(&self) -> Outputs {
        let o = self.plan.outputs;
        Outputs {
            color: o.color.then_some(self.color_format()),
            ids: o.renders_ids(),
            flow: o.flow,
            depth: o.depth,
            range: o.renders_range(),
        }
    }

    /// A geometry pass (Alg. 1 or the pinhole render) with its targets.
    fn geometry(
        &self,
        camera: &Camera,
        projection: Projection,
        outputs: Outputs,
    ) -> Result<(GeometryPass, GeometryTargets)> {
        let mut desc = GeometryDesc::new(camera.clone(), projection, outputs);
        desc.background = self.plan.background;
        desc.readout = self.plan.shutter.moving_readout();
        let pass = GeometryPass::with_frames(self.gpu, desc, self.frames)?;
        let targets = GeometryTargets::new(self.gpu, &pass)?;
        Ok((pass, targets))
    }

    /// The warp route's stage with its overscanned pinhole source camera and geometry.
    fn warp_stage(
        &self,
        camera: &Camera,
        method: InverseMethod,
        chromatic: Option<[f64; 3]>,
        map: bool,
        data: DataOutputs,
    ) -> Result<(WarpStage, Camera, WarpGeometry)> {
        let plan = self.plan;
        let (source, mut g) = WarpGeometry::overscanned(camera, method, plan.density)?;
        if let Some(s) = chromatic {
            g = g.with_chromatic(s)?;
        }
        // The warp reads RGBA8 or RGBA32F sources.
        let f = if self.color_format() == ColorFormat::Rgba8 {
            ColorFormat::Rgba8
        } else {
            ColorFormat::Rgba32F
        };
        let coordinates = if map {
            super::MAP_COORDINATES
        } else {
            Coordinates::Analytic
        };
        let stage = WarpStage::with_data(
            self.gpu,
            source.clone(),
            g.clone(),
            coordinates,
            f,
            plan.background,
            data,
            self.frames,
        )?;
        Ok((stage, source, g))
    }

    /// The stages of the plan's route.
    fn stages(&mut self) -> Result<Stages> {
        let plan = self.plan;
        if let Route::LensModel { .. } = plan.route {
            let setting = plan
                .lens()
                .ok_or_else(|| internal("a lens plan without a lens"))?;
            let lens = LensRenderer::new(
                self.gpu,
                &setting.models,
                LensRenderOptions {
                    frames_in_flight: self.frames,
                    ..Default::default()
                },
            )?;
            self.names.push("image-based lens model (cells + film)");
            self.pipelines.push(RecordedPipeline {
                kind: PassKind::LensModel,
                constants: Vec::new(),
            });
            return Ok(Stages::Lens(lens));
        }
        let camera = plan
            .camera()
            .ok_or_else(|| internal("a camera plan without a camera"))?;
        let o = plan.outputs;
        let outputs = self.outputs();
        let lens_delta = Projection::Lens { delta: plan.delta };
        let stages = match &plan.route {
            Route::Pinhole => {
                self.names.push("pinhole render");
                Stages::Geometry(self.geometry(camera, Projection::Pinhole, outputs)?)
            }
            Route::Vertex { .. } => {
                self.names.push("Alg. 1 (vertex + discard)");
                Stages::Geometry(self.geometry(camera, lens_delta, outputs)?)
            }
            Route::Warp {
                method,
                chromatic,
                map,
            } => {
                if o.flow {
                    return Err(internal(
                        "flow takes Alg. 1 (Lambers et al. Table 1): no plan routes it through the warp",
                    ));
                }
                let data = DataOutputs {
                    ids: o.renders_ids(),
                    depth: o.depth,
                    range: o.renders_range(),
                };
                let warp = self.warp_route(camera, *method, *chromatic, *map, data)?;
                Stages::Warp { warp, data: None }
            }
            Route::WarpAndVertex {
                method,
                chromatic,
                map,
                ..
            } => {
                let warp = if o.color {
                    let none = DataOutputs::default();
                    Some(self.warp_route(camera, *method, *chromatic, *map, none)?)
                } else {
                    None
                };
                let data_outputs = Outputs {
                    color: None,
                    ..outputs
                };
                let data = self.geometry(camera, lens_delta, data_outputs)?;
                self.names.push("Alg. 1 (vertex + discard), data outputs");
                match warp {
                    Some(warp) => Stages::Warp {
                        warp,
                        data: Some(data),
                    },
                    None => Stages::Geometry(data),
                }
            }
            Route::Cube { side, chromatic } => self.cube(camera, *side, *chromatic)?,
            Route::LensModel { .. } => return Err(internal("the lens route has no camera")),
            Route::Environment { .. } => {
                return Err(internal("the environment route is built from its scene"))
            }
        };
        if let Some((pass, _)) = stages.geometry() {
            self.pipelines.push(RecordedPipeline::geometry(pass));
        }
        Ok(stages)
    }

    /// The warp route's stages, and its bands where the plan draws a moving rolling shutter
    /// in them: one slot of the source render per band and frame in flight.
    fn warp_route(
        &mut self,
        camera: &Camera,
        method: InverseMethod,
        chromatic: Option<[f64; 3]>,
        map: bool,
        data: DataOutputs,
    ) -> Result<Box<WarpRoute>> {
        let (stage, source, geometry) = self.warp_stage(camera, method, chromatic, map, data)?;
        self.pipelines.extend([
            RecordedPipeline::geometry(&stage.pass),
            RecordedPipeline::compute(PassKind::Warp, stage.warp.pipeline()),
        ]);
        for d in stage.data_warps() {
            self.pipelines.push(RecordedPipeline::compute(
                PassKind::DataWarp,
                d.warp.pipeline(),
            ));
        }
        let plan = self.plan;
        let bands = match (plan.bands, plan.shutter.moving_readout()) {
            (Some(count), Some(readout)) => {
                let (w, h) = geometry.output_size;
                let bands = crate::model::rolling_shutter::bands::bands(readout, w, h, count);
                let slots = stage.pass.slots((bands.len() * self.frames) as u32)?;
                self.names
                    .push("pinhole render + warp per band (overscanned)");
                Some(BandedSource {
                    gpu: self.gpu.clone(),
                    poses: vec![Vec::new(); self.frames],
                    bands,
                    slots,
                    camera: source.clone(),
                    frame: 0,
                })
            }
            _ => {
                self.names.extend(["pinhole render (overscanned)", "warp"]);
                None
            }
        };
        Ok(Box::new(WarpRoute {
            stage,
            source,
            geometry,
            bands,
        }))
    }

    /// The environment route's stage: the scene's 360° image uploaded, the sphere warp.
    fn environment(
        &mut self,
        environment: &Environment,
        chromatic: Option<[f64; 3]>,
    ) -> Result<Stages> {
        let camera = self
            .plan
            .camera()
            .ok_or_else(|| internal("an environment plan without a camera"))?;
        let options = SphereWarpOptions {
            chromatic,
            fill: self.plan.background,
            write_mask: true,
        };
        let stage = EnvironmentStage::new(self.gpu, camera, environment, &options)?;
        self.pipelines.push(RecordedPipeline::compute(
            PassKind::SphereWarp,
            stage.warp.pipeline(),
        ));
        self.names.push("sphere warp");
        Ok(Stages::Environment(stage))
    }

    /// The cube route's stage: six faces and the sphere warp, in bands where the camera moves
    /// during the readout.
    fn cube(&mut self, camera: &Camera, side: u32, chromatic: Option<[f64; 3]>) -> Result<Stages> {
        let (gpu, plan) = (self.gpu, self.plan);
        let o = plan.outputs;
        if o.flow {
            return Err(internal("the planner routes no flow through a cube map"));
        }
        let data = DataOutputs {
            ids: o.renders_ids(),
            depth: o.depth,
            range: o.renders_range(),
        };
        // Within this device's limits and the cube budget.
        let (f, side) = super::limits::device_cube_faces(gpu, self.color_format(), side);
        let options = SphereWarpOptions {
            chromatic,
            fill: plan.background,
            write_mask: false,
        };
        let mut cube = CubeStage::with_data(gpu, camera, side, f, &options, self.frames, data)?;
        self.pipelines.extend([
            RecordedPipeline::geometry(&cube.pass),
            RecordedPipeline::compute(PassKind::SphereWarp, cube.warp.pipeline()),
        ]);
        if let Some(d) = &cube.data {
            self.pipelines.push(RecordedPipeline::compute(
                PassKind::DataWarp,
                d.pass.pipeline(),
            ));
        }
        let bands = match (plan.bands, plan.shutter.moving_readout()) {
            (Some(count), Some(readout)) => {
                let bands = crate::model::rolling_shutter::bands::bands(
                    readout,
                    camera.width,
                    camera.height,
                    count,
                );
                // SAFETY: the stage is new: nothing recorded with it exists.
                unsafe { cube.set_bands(bands.len()) }?;
                self.names.push("cube faces + sphere warp per band");
                Some(bands)
            }
            _ => {
                self.names
                    .extend(["cube faces (6 pinhole renders)", "sphere warp"]);
                None
            }
        };
        Ok(Stages::Cube { cube, bands })
    }
}

/// The passes of one plan, built once; any number of frames recorded.
pub struct PlanRecorder {
    /// The route's stages.
    stages: Stages,
    /// The scene's mesh (none where the scene is a 360° image).
    mesh: Option<MeshBuffers>,
    poses: Vec<Pose>,
    /// One per pose: when the frame's last line is read ([`Plan::end_pose`]).
    end_poses: Vec<Pose>,
    /// The pose the first frame's flow starts from.
    previous_pose: Option<Pose>,
    /// Names of the passes in recording order (for timings).
    names: Vec<&'static str>,
    /// What the plan asks for (which images [`Self::read`] returns).
    outputs: super::scene_file::OutputSpec,
    /// The lens route keeps vignetting (else the accumulated weight is divided out).
    vignetting: bool,
    /// Frames in flight every pass keeps uniforms and descriptor sets for.
    frames_in_flight: usize,
    /// Every pipeline the recorder records, with its specialization constants.
    pipelines: Vec<RecordedPipeline>,
}

impl PlanRecorder {
    /// Builds the plan's passes on `gpu` for `scene` (its mesh tessellated, where the plan
    /// says so, at the first pose), for one frame in flight.
    pub fn new(gpu: &Gpu, plan: &Plan, scene: &Scene) -> Result<Self> {
        Self::with_frames(gpu, plan, scene, 1)
    }

    /// As [`Self::new`], every pass keeping its uniforms and descriptor sets for `frames`
    /// frames in flight (1 to [`crate::pass::geometry::MAX_FRAMES_IN_FLIGHT`]; librashader's
    /// frame residuals): select frame k ([`Self::select_frame`]), [`Self::prepare`] it and
    /// record it while frames k − 1 … k − N + 1 still execute. The frames share their output
    /// images and the mesh's discard buffers, so they run on one queue in the order recorded
    /// (the recorded barriers order them), and a frame's outputs are read before a later
    /// frame overwrites them (in the same command buffer, or after its fence).
    pub fn with_frames(gpu: &Gpu, plan: &Plan, scene: &Scene, frames: usize) -> Result<Self> {
        if plan.antialias.is_on() {
            return Err(Error::input(
                "the recorder draws one sample per pixel: the scene's [render] supersample / jitter are averaged on the host by execute(); an engine anti-aliases its own way (MSAA, TAA)",
            ));
        }
        Self::build(gpu, plan, scene, &plan_mesh_at(plan, scene, 0)?, frames)
    }

    /// Builds the passes of `plan` (anti-aliasing ignored) for `scene`, drawing `mesh` (the
    /// scene's, tessellated where the plan says so) as it is.
    pub(crate) fn build(
        gpu: &Gpu,
        plan: &Plan,
        scene: &Scene,
        mesh: &Mesh,
        frames: usize,
    ) -> Result<Self> {
        if !(1..=crate::pass::geometry::MAX_FRAMES_IN_FLIGHT).contains(&frames) {
            return Err(Error::input(format!(
                "{frames} frames in flight: a recorder keeps 1 to {}",
                crate::pass::geometry::MAX_FRAMES_IN_FLIGHT
            )));
        }
        let banded = matches!(
            plan.route,
            Route::Warp { .. } | Route::WarpAndVertex { .. } | Route::Cube { .. }
        ) && plan.bands.is_some();
        if plan.shutter.moving_readout().is_some()
            && !matches!(plan.route, Route::Pinhole | Route::Vertex { .. })
            && !banded
        {
            return Err(internal(
                "a camera moving during a rolling shutter's readout is drawn by the vertex path, or by the warp in bands: the planner routes it there",
            ));
        }
        let mut b = Builder {
            gpu,
            plan,
            frames,
            names: Vec::new(),
            pipelines: Vec::new(),
        };
        // A 360° image is the whole scene: no mesh to draw.
        let (stages, mesh) = match (&plan.route, &scene.environment) {
            (Route::Environment { chromatic }, Some(environment)) => {
                (b.environment(environment, *chromatic)?, None)
            }
            (Route::Environment { .. }, None) => {
                return Err(internal("an environment plan for a scene without one"))
            }
            _ => (
                b.stages()?,
                Some(MeshBuffers::new(gpu, mesh, scene.texture.as_ref())?),
            ),
        };
        let mut r = PlanRecorder {
            stages,
            mesh,
            poses: plan.poses.clone(),
            end_poses: (0..plan.poses.len())
                .filter_map(|i| plan.end_pose(i))
                .collect(),
            previous_pose: plan.previous_pose,
            names: b.names,
            outputs: plan.outputs,
            vignetting: matches!(
                plan.route,
                Route::LensModel {
                    vignetting: true,
                    ..
                }
            ),
            frames_in_flight: frames,
            pipelines: b.pipelines,
        };
        // SAFETY: the passes are new: nothing recorded with them exists yet.
        unsafe { r.bind_mesh() };
        Ok(r)
    }

    /// Points every pass that draws the mesh with a set of its own at it (the cube faces and
    /// the lens cells bind theirs, per frame, in `prepare`).
    ///
    /// # Safety
    /// Rewrites every frame's descriptor sets: no recorded frame may be pending.
    unsafe fn bind_mesh(&mut self) {
        let Some(mesh) = &self.mesh else {
            return;
        };
        // SAFETY: the caller upholds this function's contract.
        unsafe {
            if let Some((pass, _)) = self.stages.geometry_mut() {
                pass.bind_mesh(mesh);
            }
            if let Some(w) = self.stages.warp_mut() {
                w.stage.pass.bind_mesh(mesh);
                if let Some(b) = &w.bands {
                    w.stage.pass.bind_slots_mesh(&b.slots, mesh);
                }
            }
        }
    }

    /// Frames in flight the passes keep uniforms and descriptor sets for.
    pub fn frames_in_flight(&self) -> usize {
        self.frames_in_flight
    }

    /// Makes frame `frame` (modulo [`Self::frames_in_flight`]) the one [`Self::prepare`]
    /// writes and [`Self::record`] records.
    pub fn select_frame(&mut self, frame: usize) {
        let frames_in_flight = self.frames_in_flight;
        if let Some((pass, _)) = self.stages.geometry_mut() {
            pass.select_frame(frame);
        }
        match &mut self.stages {
            Stages::Warp { warp, .. } => {
                warp.stage.select_frame(frame);
                if let Some(b) = &mut warp.bands {
                    b.frame = frame % frames_in_flight;
                }
            }
            Stages::Cube { cube, .. } => cube.select_frame(frame),
            Stages::Lens(l) => l.select_frame(frame),
            Stages::Geometry(_) | Stages::Environment(_) => {}
        }
    }

    /// Replaces the mesh every pass draws (a tessellation for another pose); the next
    /// [`Self::prepare`] binds it, and [`Self::record_mesh_upload`] must be recorded before the
    /// next frame.
    ///
    /// # Safety
    /// The old mesh's buffers are dropped: no recorded frame of this recorder may be pending.
    pub(crate) unsafe fn set_mesh(
        &mut self,
        gpu: &Gpu,
        mesh: &Mesh,
        texture: Option<&Raster>,
    ) -> Result<()> {
        self.mesh = Some(MeshBuffers::new(gpu, mesh, texture)?);
        // SAFETY: the caller upholds this function's contract: no frame is pending.
        unsafe { self.bind_mesh() };
        Ok(())
    }

    /// Records the upload of the mesh's texture (as [`Self::record_setup`] does once).
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass on a graphics queue of this recorder's
    /// device, before the frame that draws the mesh.
    pub(crate) unsafe fn record_mesh_upload(&self, cmd: vk::CommandBuffer) {
        // SAFETY: the caller upholds the contract above; the mesh's buffers live in `self`
        // until the next `set_mesh`, which requires no pending frame.
        if let Some(mesh) = &self.mesh {
            unsafe { mesh.record_upload(cmd) };
        }
    }

    /// Every pipeline this recorder records, with its specialization constants: what a plan
    /// can be checked against.
    pub fn pipelines(&self) -> &[RecordedPipeline] {
        &self.pipelines
    }

    /// Moves the lens to `camera` (same size and terms as built) and the warp's pinhole source
    /// by `source_shift` pixels: one jittered pass of anti-aliasing, which renders the same
    /// image translated (Alg. 1 normalizes with the same cx, cy).
    ///
    /// # Safety
    /// Host writes to uniforms the recorded frames read: no recorded frame may be pending.
    pub(crate) unsafe fn jitter(&mut self, camera: &Camera, source_shift: DVec2) -> Result<()> {
        if let Some((pass, _)) = self.stages.geometry_mut() {
            // SAFETY: no submission using it is pending (`submit` waits on its fence).
            unsafe { pass.set_camera(camera) }?;
        }
        match &mut self.stages {
            // The faces stay: only the rays the lens casts into them move.
            Stages::Cube { cube, .. } => {
                // SAFETY: no submission using it is pending (`submit` waits on its fence).
                unsafe { cube.set_camera(camera) }?;
            }
            Stages::Warp { warp, .. } => {
                let (source, built) = (&warp.source, &warp.geometry);
                let mut k = source.intrinsics;
                k.cx -= source_shift.x;
                k.cy -= source_shift.y;
                let moved =
                    Camera::new(source.width, source.height, k, OpenCvDistortion::default())?;
                let mut g = WarpGeometry::distort(camera.clone(), built.method)
                    .with_ideal(k, (source.width, source.height))?;
                if let Some(scales) = built.chromatic {
                    g = g.with_chromatic(scales)?;
                }
                let st = &mut warp.stage;
                // SAFETY: no submission using it is pending (`submit` waits on its fence).
                unsafe { st.pass.set_camera(&moved) }?;
                // SAFETY: no submission using it is pending (`submit` waits on its fence).
                unsafe { st.warp.retarget(g) }?;
                if let Some(b) = &mut warp.bands {
                    b.camera = moved;
                    // SAFETY: no submission using it is pending (`submit` waits on its fence).
                    unsafe { b.write_slots(&st.pass) }?;
                }
            }
            Stages::Geometry(_) | Stages::Lens(_) | Stages::Environment(_) => {}
        }
        Ok(())
    }

    /// The passes [`Self::record`] times, in order.
    pub fn pass_names(&self) -> &[&'static str] {
        &self.names
    }

    /// Timestamps [`Self::record`] writes: one before the first pass and one after each.
    pub fn timestamp_count(&self) -> u32 {
        self.names.len() as u32 + 1
    }

    /// Sets the plan's pose `index` on the selected frame in flight ([`Self::select_frame`]).
    ///
    /// # Safety
    /// This writes the selected frame's host-visible uniforms and descriptor sets: no recorded
    /// work of that frame may be pending on the GPU (wait for its fence first), as Vulkan
    /// requires of descriptor sets and memory the device reads.
    pub unsafe fn prepare(&mut self, index: usize) -> Result<()> {
        let pose = *self
            .poses
            .get(index)
            .ok_or_else(|| Error::input(format!("no frame {index}")))?;
        let end = self.end_poses.get(index).copied().unwrap_or(pose);
        // Flow starts from the previous frame, with its own readout.
        let previous = match index {
            0 => {
                let p = self.previous_pose.unwrap_or(pose);
                (p, p)
            }
            i => {
                let p = self.poses[i - 1];
                (p, self.end_poses.get(i - 1).copied().unwrap_or(p))
            }
        };
        let motion = FrameMotion::new(pose.into(), end.into());
        // Each band from the pose of its middle line (slerp and a linear centre between the
        // frame's two poses).
        let band_poses = |bands: &[Band]| -> Vec<Pose> {
            bands.iter().map(|band| motion.at(band.s).into()).collect()
        };
        // SAFETY (every block below): this function's contract: no recorded work of the
        // selected frame, whose uniforms and sets these are, is pending.
        if let Some((pass, _)) = self.stages.geometry() {
            unsafe { pass.set_moving_frame((&pose, &end), (&previous.0, &previous.1)) }?;
        }
        let mesh = || {
            self.mesh
                .as_ref()
                .ok_or_else(|| internal("a route that draws the mesh without one"))
        };
        match &mut self.stages {
            Stages::Warp { warp, .. } => {
                unsafe { warp.stage.pass.set_frame(&pose, &pose) }?;
                if let Some(b) = &mut warp.bands {
                    b.poses[b.frame] = band_poses(&b.bands);
                    unsafe { b.write_slots(&warp.stage.pass) }?;
                }
            }
            Stages::Cube {
                cube,
                bands: Some(bands),
            } => unsafe { cube.prepare_bands(mesh()?, &band_poses(bands)) }?,
            Stages::Cube { cube, bands: None } => unsafe { cube.prepare(mesh()?, &pose) }?,
            Stages::Lens(l) => unsafe { l.prepare(mesh()?, &pose) }?,
            // The 360° image is at infinity: no pose moves it (the plan turns none).
            Stages::Geometry(_) | Stages::Environment(_) => {}
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
        // render pass on a graphics queue of this device, once, before any frame, so nothing
        // using these images is pending. The warp's `record_prepare` also needs compute on
        // that queue, which this contract leaves implicit.
        unsafe {
            if let Some(mesh) = &self.mesh {
                mesh.record_upload(cmd);
            }
            match &self.stages {
                Stages::Warp { warp, .. } => warp.stage.record_prepare(cmd),
                Stages::Cube { cube, .. } => cube.record_prepare(cmd),
                Stages::Environment(e) => e.record_setup(cmd),
                Stages::Geometry(_) | Stages::Lens(_) => {}
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
                // SAFETY: `record`'s contract: `cmd` is recording outside a render pass and
                // `timestamps` holds `timestamp_count` queries, reset first in this buffer.
                unsafe { q.cmd_write(cmd, k) };
            }
            k += 1;
        };
        if let Some(q) = timestamps {
            // SAFETY: `record`'s contract: `cmd` is recording outside a render pass and
            // `timestamps` holds `timestamp_count` queries, reset first in this buffer.
            unsafe { q.cmd_reset(cmd) };
        }
        stamp();
        let mesh = match (&self.stages, &self.mesh) {
            (Stages::Environment(e), _) => {
                // SAFETY: the caller upholds `record`'s contract: after `record_setup`, which
                // uploaded the 360° image and put the output and mask in GENERAL.
                unsafe { e.record(cmd) };
                stamp();
                return;
            }
            (_, Some(mesh)) => mesh,
            // `build` made a mesh for every route that draws one.
            (_, None) => return,
        };
        // SAFETY: the caller upholds `record`'s contract: `cmd` is recording (outside a render
        // pass on a graphics queue, as for `record_setup`) after `record_setup` and `prepare`,
        // which bound `mesh` to every pass and uploaded its texture; each pass's targets
        // were made for it in `new`, and the warp stage's pinhole render precedes its warps.
        // `timestamps`, when given, must hold `timestamp_count` queries, as the doc asks.
        unsafe {
            match &self.stages {
                Stages::Lens(l) => {
                    l.record(cmd, mesh);
                    stamp();
                }
                Stages::Warp { warp, .. } => match &warp.bands {
                    Some(b) => {
                        let st = &warp.stage;
                        let n = b.bands.len();
                        for (k, band) in b.bands.iter().enumerate() {
                            if k > 0 {
                                // The bands write disjoint pixels of one output image; ordering
                                // the dispatches keeps every hazard tracker's view of that
                                // image simple. The render pass's own dependency already waits
                                // for the last band's warps to finish reading the source
                                // before clearing it.
                                crate::gpu::global_barrier(
                                    &b.gpu,
                                    cmd,
                                    [crate::gpu::Access::ComputeReadWrite],
                                    [crate::gpu::Access::ComputeReadWrite],
                                );
                            }
                            st.pass
                                .record_slot(cmd, &st.targets, mesh, &b.slots, b.frame * n + k);
                            st.warp.record_band(cmd, band.rect);
                            for d in st.data_warps() {
                                d.warp.record_band(cmd, band.rect);
                            }
                        }
                        stamp();
                    }
                    None => {
                        let st = &warp.stage;
                        st.pass.record(cmd, &st.targets, mesh);
                        stamp();
                        st.record_warps(cmd);
                        stamp();
                    }
                },
                Stages::Cube {
                    cube,
                    bands: Some(bands),
                } => {
                    // Each band's faces, then its rows or columns of the output; the next
                    // band's faces discard the cube only after this warp has sampled it.
                    for (k, band) in bands.iter().enumerate() {
                        cube.record_band_faces(cmd, mesh, k);
                        cube.record_warp_band(cmd, band.rect);
                    }
                    stamp();
                }
                Stages::Cube { cube, bands: None } => {
                    cube.record_faces(cmd, mesh);
                    stamp();
                    cube.record_warp(cmd);
                    stamp();
                }
                Stages::Geometry(_) | Stages::Environment(_) => {}
            }
            if let Some((pass, targets)) = self.stages.geometry() {
                pass.record(cmd, targets, mesh);
                stamp();
            }
        }
    }

    /// The warp route's depth (R32F metres, +inf where nothing was drawn or there is no
    /// source; `GENERAL` after a frame), when the plan asks for depth through the warp.
    pub fn warped_depth(&self) -> Option<&crate::gpu::Image> {
        self.stages.warp()?.stage.depth.as_ref().map(|d| &d.output)
    }

    /// The warp route's range (R32F metres, as [`Self::warped_depth`]), when the plan asks
    /// for range through the warp.
    pub fn warped_range(&self) -> Option<&crate::gpu::Image> {
        self.stages.warp()?.stage.range.as_ref().map(|d| &d.output)
    }

    /// The images a recorded frame leaves: colour (warp output, lens film or geometry
    /// colour) and the geometry pass's targets (IDs, flow, depth) for the caller to read or
    /// sample. The warp route's depth is [`Self::warped_depth`].
    pub fn images(&self) -> (Option<&crate::gpu::Image>, Option<&GeometryTargets>) {
        let colour = match &self.stages {
            Stages::Warp { warp, .. } => Some(&warp.stage.output),
            Stages::Cube { cube, .. } => Some(&cube.output),
            Stages::Lens(l) => Some(&l.film().image),
            Stages::Environment(e) => Some(&e.output),
            Stages::Geometry((_, t)) => t.color(),
        };
        (colour, self.geometry_targets())
    }

    /// The geometry pass's targets (Alg. 1 or the pinhole render), when the plan has one;
    /// after a frame in `TRANSFER_SRC_OPTIMAL`.
    pub(crate) fn geometry_targets(&self) -> Option<&GeometryTargets> {
        self.stages.geometry().map(|(_, t)| t)
    }

    /// The warp path's stage (its output and data warps `GENERAL` after a frame).
    pub(crate) fn warp_stage(&self) -> Option<&WarpStage> {
        self.stages.warp().map(|w| &w.stage)
    }

    /// The cube path's stage (its output `GENERAL` after a frame).
    pub(crate) fn cube_stage(&self) -> Option<&CubeStage> {
        match &self.stages {
            Stages::Cube { cube, .. } => Some(cube),
            _ => None,
        }
    }

    /// The environment route's stage (its output and mask `GENERAL` after a frame).
    pub(crate) fn environment_stage(&self) -> Option<&EnvironmentStage> {
        match &self.stages {
            Stages::Environment(e) => Some(e),
            _ => None,
        }
    }

    /// The lens route's renderer (its film `COLOR_ATTACHMENT_OPTIMAL` after a frame).
    pub(crate) fn lens_renderer(&self) -> Option<&LensRenderer> {
        match &self.stages {
            Stages::Lens(l) => Some(l),
            _ => None,
        }
    }

    /// What the plan asks for.
    pub(crate) fn outputs(&self) -> super::scene_file::OutputSpec {
        self.outputs
    }

    /// Whether the lens route keeps vignetting (else the film's accumulated weight is
    /// divided out when it is read).
    pub(crate) fn keeps_vignetting(&self) -> bool {
        self.vignetting
    }
}
