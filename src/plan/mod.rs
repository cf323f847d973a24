//! The planner: from a scene file — optics, the effects and outputs it wants and
//! its accuracy budget — the cheapest pipeline that delivers exactly that, and why.
//!
//! - **Route.** A calibrated camera goes by a pinhole render (no distortion wanted), Alg. 1
//!   (tessellated as far as the budget needs) or a pinhole render + warp (overscanned), by
//!   estimated cost; object IDs and flow force Alg. 1 (Lambers et al. Table 1); chromatic aberration
//!   needs the warp's fused per-channel pass, so colour then goes by the warp and the data by
//!   Alg. 1. A lens prescription goes by Heidrich et al.'s image-based model. A camera moving
//!   during a rolling shutter's readout goes by Alg. 1 solving each vertex's readout time, or
//!   by the warp in the fewest bands of lines (each from its middle line's pose) whose
//!   measured error meets the budget, whichever is cheaper (chromatic aberration needs the
//!   bands).
//! - **Accuracy.** The inverse method is the cheapest whose error, *measured* on this camera
//!   (the f64 model over a grid of the image), meets the budget; the tessellation is the
//!   coarsest whose straight-line error, measured on this scene and pose, meets it; for a
//!   lens, the quad-tree's angle threshold is the budget turned into degrees.
//! - **Nothing unasked.** No warp for a pinhole; the single-fetch warp without chromatic
//!   aberration; one lens sample without depth of field; no border fitting without
//!   vignetting; every distortion term whose coefficient is zero compiled out
//!   (specialization constants). `host::plan::execute` returns what was recorded, so tests check the
//!   plan against the pipelines, not against timings.
//!
//! Cost estimates come from this README's measured lavapipe tables (`bench vertex`,
//! `bench inverse`); `--explain` prints the times measured on the frame itself.

pub(crate) mod antialias;
mod camera;
mod choice;
mod cost;
mod explain;
mod labels;
mod lens;
pub mod limits;
pub mod record;
mod request;
pub mod scene_file;
mod search;
pub mod shutter;
#[cfg(test)]
mod tests;

use crate::{Error, Result};

use crate::lens::Prescription;
use crate::model::{Camera, InverseMethod};
use crate::pass::warp::{Coordinates, MapInterpolation};
use crate::scene::{builtin, Pose, Scene};
pub use antialias::{
    downsample, jitter_offsets, scaled_camera, DEFAULT_BACKGROUND, MAX_JITTER, MAX_SUPERSAMPLE,
};
pub use record::{PassKind, PlanRecorder, RecordedPipeline};
pub use request::{PathChoice, PathKind, RenderRequest};
pub use scene_file::{SceneFile, SceneFileError};
pub use shutter::{ReadoutSource, Shutter};

use camera::plan_camera;
// `request` weighs the cube path's error as the planner does.
use cost::CUBE_RAY_ERROR_PX;
pub use cost::{inverse_candidates, inverse_candidates_for, ray_model_inverse_ns};
pub use labels::SceneLabels;
pub use lens::LensRequest;
use lens::{plan_lens, LensSpec};
pub use search::inverse_error_px;

/// How the frames are made.
#[derive(Debug, Clone, PartialEq)]
pub enum Route {
    /// No lens wanted: the camera's pinhole projection.
    Pinhole,
    /// Alg. 1 for every output, the mesh tessellated to `tessellate` px edges (`None`: as is).
    Vertex { tessellate: Option<f64> },
    /// Pinhole render of the overscanned frustum + compute warp (colour, depth).
    Warp {
        method: InverseMethod,
        chromatic: Option<[f64; 3]>,
        /// Sample a map built once ([`MAP_COORDINATES`], with Newton) instead of solving
        /// `method` per pixel every frame.
        map: bool,
    },
    /// Colour by the warp (chromatic aberration), IDs / flow / depth by Alg. 1.
    WarpAndVertex {
        method: InverseMethod,
        chromatic: Option<[f64; 3]>,
        tessellate: Option<f64>,
        /// As for [`Route::Warp`].
        map: bool,
    },
    /// Six pinhole faces of a cube map (`side` pixels each, at 1×), rendered into the cube on
    /// the GPU, then the sphere warp sampling it along each output pixel's ray: colour for a
    /// lens no pinhole source holds, where it is cheaper than Alg. 1.
    Cube {
        side: u32,
        chromatic: Option<[f64; 3]>,
    },
    /// A scene that is a 360° image (a user's cube map or panorama,
    /// [`crate::scene::Environment`]): the sphere warp sampling it along each output pixel's
    /// ray, colour alone.
    Environment { chromatic: Option<[f64; 3]> },
    /// Heidrich et al.'s image-based model through a lens prescription.
    LensModel {
        samples: u32,
        chromatic: bool,
        vignetting: bool,
        max_angle_deg: f64,
    },
}

/// A lens prescription set up for a plan: film and focus resolved once for every frame, and
/// the image-based models built (one, or one per channel).
#[derive(Debug, Clone)]
pub struct LensSetting {
    pub prescription: Prescription,
    pub pitch_mm: f64,
    pub pixels: (u32, u32),
    pub focus_m: f64,
    pub f_number: Option<f64>,
    pub models: Vec<(crate::lens::image_model::ImageModel, [f32; 4])>,
}

/// A stage of a plan's frame: what [`PlanRecorder`] records (anti-aliasing: what the headless
/// path repeats and averages), as `--explain` and `plan.json` name it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// The camera's pinhole projection, every output.
    PinholeRender,
    /// The warp's pinhole source, overscanned to cover every valid output pixel.
    OverscannedRender,
    /// The warp; `chromatic`: three fetches, one per channel's lens.
    Warp { chromatic: bool },
    /// The mesh's edges split before Alg. 1.
    Tessellation,
    /// Alg. 1 for every output.
    VertexRender,
    /// Alg. 1 for the data outputs beside a warp's colour.
    VertexRenderData,
    /// Supersampled, jittered colour, averaged.
    Antialias,
    /// The six pinhole faces of a cube map.
    CubeFaces,
    /// The warp from the cube map; `chromatic`: three fetches, one per channel's lens.
    SphereWarp { chromatic: bool },
    /// Heidrich et al.'s image-based model.
    LensModel,
    /// The film the cells accumulate on.
    FilmAccumulation,
    /// Vignetting kept, or divided out.
    Vignetting { kept: bool },
    /// The perspective projections of one frame.
    CellRenders,
    /// The warp's pinhole source, overscanned, rendered once per band of a moving rolling
    /// shutter's lines, each band warped from its own render.
    BandRenders,
    /// The six pinhole faces of a cube map, rendered once per band of a moving rolling
    /// shutter's lines, each band warped from its own cube.
    BandCubeFaces,
}

impl Stage {
    /// How `--explain` and `plan.json` name the stage.
    pub fn name(self) -> &'static str {
        match self {
            Stage::PinholeRender => "pinhole render",
            Stage::OverscannedRender => "pinhole render (overscanned)",
            Stage::Warp { chromatic: false } => "warp, single fetch",
            Stage::Warp { chromatic: true } => "warp, 3 fetches (chromatic)",
            Stage::Tessellation => "tessellation",
            Stage::CubeFaces => "cube faces (6 pinhole renders)",
            Stage::SphereWarp { chromatic: false } => "sphere warp, single fetch",
            Stage::SphereWarp { chromatic: true } => "sphere warp, 3 fetches (chromatic)",
            Stage::VertexRender => "Alg. 1 (vertex + discard)",
            Stage::VertexRenderData => "Alg. 1 (vertex + discard) for IDs/flow/depth",
            Stage::Antialias => "anti-aliasing",
            Stage::LensModel => "image-based lens model (Heidrich et al.)",
            Stage::FilmAccumulation => "film accumulation",
            Stage::Vignetting { kept: true } => "vignetting kept",
            Stage::Vignetting { kept: false } => "vignetting divided out",
            Stage::CellRenders => "cell renders",
            Stage::BandRenders => "pinhole render per band (overscanned)",
            Stage::BandCubeFaces => "cube faces per band (6 pinhole renders each)",
        }
    }
}

/// One stage of a plan, and why it is there.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// The stage.
    pub stage: Stage,
    /// The reason: what the scene asked for, what was measured.
    pub why: String,
}

/// What a plan renders through: a calibrated camera (the fast routes) or a lens prescription
/// (the image-based model), never both.
#[derive(Debug, Clone)]
// One per plan, built once per scene: boxing the camera would buy nothing.
#[allow(clippy::large_enum_variant)]
pub enum Optics {
    /// The camera of the fast routes (the file's, distortion removed if unwanted).
    Camera(Camera),
    /// The prescription and its setting.
    Lens(LensSetting),
}

/// A plan: the route, its steps, the geometric error it is expected to hold.
#[derive(Debug, Clone)]
pub struct Plan {
    pub route: Route,
    pub steps: Vec<Step>,
    /// What the frames are rendered through.
    pub optics: Optics,
    /// Largest geometric error the plan's approximations leave (output pixels), as measured
    /// while planning.
    pub expected_error_px: f64,
    pub budget_px: f64,
    pub poses: Vec<Pose>,
    /// One per pose, the pose when the frame's last line is read (a rolling shutter's
    /// `end_rvec`, `end_tvec`); empty, or equal to the pose, where the camera does not move
    /// during the frame ([`Plan::end_pose`]).
    pub end_poses: Vec<Pose>,
    /// The pose the first frame's flow starts from (`None`: the first frame does not move).
    pub previous_pose: Option<Pose>,
    /// Lambers et al. Sec. 3.2's discard tolerance δ of Alg. 1 (D is added per camera).
    pub delta: f64,
    /// Source pixels per output pixel of the warp's overscanned pinhole render.
    pub density: f64,
    pub outputs: scene_file::OutputSpec,
    pub background: [f32; 4],
    /// Colour anti-aliasing (`[render] supersample`, `jitter`); camera files only.
    pub antialias: scene_file::Antialias,
    /// The sensor's shutter, and where its readout came from.
    pub shutter: Shutter,
    /// Where the camera moves during a rolling shutter's readout and the warp draws it: the
    /// bands of lines it is drawn in, each from the pose of its middle line
    /// ([`crate::model::rolling_shutter::bands`]); `None` otherwise.
    pub bands: Option<u32>,
    /// Estimated frame time from the measured tables (ms, lavapipe), for comparison.
    pub estimated_ms: f64,
    /// The path the scene file asked for (`[render] path`), which the route follows instead
    /// of the planner's own choice; `None`: the planner chose.
    pub path_asked: Option<PathKind>,
}

impl Plan {
    /// The calibrated camera the frames are rendered through, if the optics are one.
    pub fn camera(&self) -> Option<&Camera> {
        match &self.optics {
            Optics::Camera(c) => Some(c),
            Optics::Lens(_) => None,
        }
    }

    /// The pose when frame `index`'s last line is read: its end pose, or its pose where the
    /// camera does not move during the frame. `None` past the last frame.
    pub fn end_pose(&self, index: usize) -> Option<Pose> {
        let pose = *self.poses.get(index)?;
        Some(self.end_poses.get(index).copied().unwrap_or(pose))
    }

    /// How frame `index` sees the world, for its labels: the camera, the pose, and the
    /// readout and motion where the camera moves during a rolling shutter's readout. `None`
    /// for a lens prescription or a frame past the pose list.
    pub fn view(&self, index: usize) -> Option<crate::labels::View<'_>> {
        let pose = *self.poses.get(index)?;
        let end = self.end_pose(index)?;
        let readout = self.shutter.moving_readout().map(|r| (r, end));
        Some(crate::labels::View::new(self.camera()?, pose, readout))
    }

    /// The lens prescription and its setting, if the optics are one.
    pub fn lens(&self) -> Option<&LensSetting> {
        match &self.optics {
            Optics::Lens(l) => Some(l),
            Optics::Camera(_) => None,
        }
    }
}

/// How the warp route's coordinates come when the planner picks the precomputed map: solved
/// every 8th pixel with Newton, cubic Lagrange between (error O(h⁴)), built once.
pub const MAP_COORDINATES: Coordinates = Coordinates::CoarseMap {
    stride: 8,
    refine: 0,
    interpolation: MapInterpolation::Cubic,
};

/// Loads the scene's geometry.
pub fn load_geometry(file: &SceneFile) -> Result<Scene> {
    builtin::parse(&file.geometry)
        .map_err(|e| Error::input(format!("{}: [geometry] scene: {e}", file.source.display())))
}

/// Plans `file` for `scene`: a lens prescription by Heidrich et al.'s image-based model, a
/// calibrated camera by the cheapest route that meets the budget.
pub fn plan(file: &SceneFile, scene: &Scene) -> Result<Plan> {
    match &file.optics {
        scene_file::OpticsSpec::Lens {
            path,
            focus_m,
            f_number,
            sensor_mm,
            pixels,
        } => plan_lens(
            file,
            scene,
            LensSpec {
                path,
                focus_m: *focus_m,
                f_number: *f_number,
                sensor_mm: *sensor_mm,
                pixels: *pixels,
            },
        ),
        scene_file::OpticsSpec::Camera(path) => plan_camera(file, scene, path),
    }
}

/// The chromatic scales `[effects]` asks for, if it asks for chromatic aberration.
fn chromatic_scales(file: &SceneFile) -> Option<[f64; 3]> {
    let e = &file.effects;
    e.chromatic_aberration.then_some(e.chromatic_scales)
}

/// A scene file's plan once its route is chosen: `(expected error px, estimated ms)` as
/// measured while planning; the rest is the file's.
fn file_plan(
    file: &SceneFile,
    route: Route,
    steps: Vec<Step>,
    optics: Optics,
    (poses, shutter): (Vec<Pose>, Shutter),
    (expected_error_px, estimated_ms): (f64, f64),
) -> Plan {
    Plan {
        route,
        steps,
        optics,
        expected_error_px,
        budget_px: file.max_error_px,
        end_poses: poses
            .iter()
            .enumerate()
            .map(|(i, p)| file.end_poses.get(i).copied().flatten().unwrap_or(*p))
            .collect(),
        poses,
        previous_pose: None,
        delta: crate::pass::geometry::DEFAULT_DELTA,
        density: 1.0,
        outputs: file.outputs,
        background: file.background,
        antialias: file.antialias,
        shutter,
        bands: None,
        estimated_ms,
        path_asked: file.path,
    }
}
