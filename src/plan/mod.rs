//! The planner: from a scene file — optics, the effects and outputs it wants and
//! its accuracy budget — the cheapest pipeline that delivers exactly that, and why.
//!
//! - **Route.** A calibrated camera goes by a pinhole render (no distortion wanted), Alg. 1
//!   (tessellated as far as the budget needs) or a pinhole render + warp (overscanned), by
//!   estimated cost; object IDs and flow force Alg. 1 (Lambers et al. Table 1); chromatic aberration
//!   needs the warp's fused per-channel pass, so colour then goes by the warp and the data by
//!   Alg. 1. A lens prescription goes by Heidrich et al.'s image-based model.
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
mod cost;
mod explain;
pub mod limits;
pub mod record;
mod request;
pub mod scene_file;
mod search;
#[cfg(test)]
mod tests;

use crate::{Error, Result};

use crate::lens::image_model::{channel_models, ModelOptions};
use crate::lens::{frame_scene, Prescription, LAMBDA_D};
use crate::model::{Camera, InverseMethod, OpenCvDistortion};
use crate::pass::warp::{Coordinates, MapInterpolation};
use crate::scene::{builtin, Pose, Scene};
pub use antialias::{
    downsample, jitter_offsets, scaled_camera, DEFAULT_BACKGROUND, MAX_JITTER, MAX_SUPERSAMPLE,
};
pub use record::{PassKind, PlanRecorder, RecordedPipeline};
pub use request::{PathChoice, RenderRequest};
pub use scene_file::{SceneFile, SceneFileError};

use cost::*;
pub use cost::{inverse_candidates, inverse_candidates_for, ray_model_inverse_ns};
pub use search::inverse_error_px;
use search::*;

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
    /// Estimated frame time from the measured tables (ms, lavapipe), for comparison.
    pub estimated_ms: f64,
}

impl Plan {
    /// The calibrated camera the frames are rendered through, if the optics are one.
    pub fn camera(&self) -> Option<&Camera> {
        match &self.optics {
            Optics::Camera(c) => Some(c),
            Optics::Lens(_) => None,
        }
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

/// The step that says colour is anti-aliased, when `[render]` asks for it.
fn push_antialias_step(steps: &mut Vec<Step>, aa: scene_file::Antialias, color: bool) {
    if aa.is_on() && color {
        steps.push(Step {
            stage: Stage::Antialias,
            why: format!(
                "[render] asks for {}× supersampling and {} jittered pass(es) of the colour, averaged; IDs, flow and depth stay one sample per pixel",
                aa.supersample, aa.jitter
            ),
        });
    }
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

/// A scene file's lens optics, borrowed.
struct LensSpec<'a> {
    path: &'a std::path::Path,
    focus_m: Option<f64>,
    f_number: Option<f64>,
    sensor_mm: (f64, f64),
    pixels: (u32, u32),
}

/// The image-based lens model's plan: validation, the model's cells, the steps.
fn plan_lens(file: &SceneFile, scene: &Scene, spec: LensSpec) -> Result<Plan> {
    let src = file.source.display().to_string();
    let e = &file.effects;
    let o = &file.outputs;
    let mut steps = Vec::new();
    let step = |stage: Stage, why: String| Step { stage, why };
    let LensSpec {
        path,
        focus_m,
        f_number,
        sensor_mm,
        pixels,
    } = spec;
    if file.antialias.is_on() {
        return Err(Error::input(format!(
                    "{src}: [render] supersample / jitter: the image-based lens model renders one sample per pixel per lens sample; anti-aliasing is for camera-file scenes"
                )));
    }
    for (asked, key) in [(o.ids, "ids"), (o.flow, "flow"), (o.depth, "depth")] {
        if asked {
            return Err(Error::input(format!(
                        "{src}: [outputs] {key}: the image-based lens model blends many views, so it has no exact {key}; give a calibrated camera (optics.camera; `vklens lens fit-opencv` makes one from the lens) for {key}"
                    )));
        }
    }
    if !e.distortion {
        return Err(Error::input(format!(
                    "{src}: [effects] distortion = false: a real lens always distorts; use a camera file with the distortion switched off for a pinhole"
                )));
    }
    let lens = Prescription::load(path)
        .map_err(|e| Error::from(e).named_by(format!("{src}: [optics] lens")))?;
    if e.chromatic_aberration && lens.surfaces.iter().all(|s| s.abbe.is_none()) {
        return Err(Error::input(format!(
            "{src}: [effects] chromatic_aberration: {} has no Abbe numbers (5th column)",
            path.display()
        )));
    }
    let pitch = sensor_mm.0 / pixels.0 as f64;
    if ((sensor_mm.1 / pixels.1 as f64) / pitch - 1.0).abs() > 1e-3 {
        return Err(Error::input(format!(
            "{src}: [optics] sensor_mm and pixels give non-square pixels"
        )));
    }
    let first = file.poses.first().copied();
    let (optics, _) = frame_scene(&lens, pixels, pitch, f_number, focus_m, first, scene)
        .map_err(|e| Error::input(format!("{}: {e}", path.display())))?;
    let efl = crate::lens::analyse(&lens, LAMBDA_D).efl.unwrap_or(1.0);
    // The budget in degrees: one pixel subtends pitch / EFL radians.
    let px_deg = (pitch / efl).atan().to_degrees();
    let max_angle_deg = file.max_error_px * px_deg;
    let samples = if e.depth_of_field { e.lens_samples } else { 1 };
    steps.push(step(
        Stage::LensModel,
        format!(
            "optics is a lens prescription; {} lens sample{} ({}), quad-tree until {:.2e}° = {} px",
            samples,
            if samples == 1 { "" } else { "s" },
            if e.depth_of_field {
                "depth of field asked for"
            } else {
                "no depth of field asked: the rear surface's centre only"
            },
            max_angle_deg,
            file.max_error_px
        ),
    ));
    steps.push(step(
                Stage::FilmAccumulation,
                if e.chromatic_aberration {
                    "chromatic aberration asked: R, G, B traced at the C, e and F lines, each channel its own projections".into()
                } else {
                    "one wavelength (d line) for all channels: no chromatic aberration asked".into()
                },
            ));
    steps.push(step(
        Stage::Vignetting { kept: e.vignetting },
        if e.vignetting {
            "vignetting asked: border bisection per sample, radiometric weights kept".into()
        } else {
            "no vignetting asked: no border fitting; the accumulated weight is divided out".into()
        },
    ));
    let options = ModelOptions {
        samples,
        max_angle_deg,
        vignetting: e.vignetting,
        ..ModelOptions::default()
    };
    let models = channel_models(&optics, &options, e.chromatic_aberration)
        .map_err(|e| Error::input(format!("{}: {e}", path.display())))?;
    let model_angle = models
        .iter()
        .map(|(m, _)| m.max_angle_deg())
        .fold(0.0, f64::max);
    let projections: usize = models.iter().map(|(m, _)| m.projection_count()).sum();
    steps.push(step(
                Stage::CellRenders,
                format!("{projections} perspective projections per frame, largest angle error {model_angle:.2e}°"),
            ));
    let frame_pose = first
        .map(Ok)
        .unwrap_or_else(|| optics.equivalent_camera().map(|c| scene.default_pose(&c)))?;
    let poses = if file.poses.is_empty() {
        vec![frame_pose]
    } else {
        file.poses.clone()
    };
    Ok(file_plan(
        file,
        Route::LensModel {
            samples,
            chromatic: e.chromatic_aberration,
            vignetting: e.vignetting,
            max_angle_deg,
        },
        steps,
        Optics::Lens(LensSetting {
            prescription: lens,
            pitch_mm: pitch,
            pixels,
            focus_m: optics.focus_m,
            f_number,
            models,
        }),
        poses,
        (model_angle / px_deg, f64::NAN),
    ))
}

/// A calibrated camera's plan: validation, the candidates' search (tessellation, inverse,
/// map, cube), their costs, and the steps that explain the choice.
fn plan_camera(file: &SceneFile, scene: &Scene, path: &std::path::Path) -> Result<Plan> {
    let src = file.source.display().to_string();
    let e = &file.effects;
    let o = &file.outputs;
    let mut steps = Vec::new();
    let step = |stage: Stage, why: String| Step { stage, why };
    let mut camera =
        crate::io::load_camera(path).map_err(|e| e.named_by(format!("{src}: [optics] camera")))?;
    if e.vignetting || e.depth_of_field {
        let key = if e.vignetting {
            "vignetting"
        } else {
            "depth_of_field"
        };
        return Err(Error::input(format!(
                    "{src}: [effects] {key}: a calibrated camera (OpenCV model) has no {key}; give a lens prescription (optics.lens)"
                )));
    }
    if !e.distortion {
        camera = Camera::new(
            camera.width,
            camera.height,
            camera.intrinsics,
            OpenCvDistortion::default(),
        )
        .map_err(Error::from)?;
    }
    let poses = if file.poses.is_empty() {
        vec![scene.default_pose(&camera)]
    } else {
        file.poses.clone()
    };
    let budget = file.max_error_px;
    let pixels = camera.width as f64 * camera.height as f64;
    let terms = camera.terms();
    let terms_note = format!(
        "compiled in: {}",
        [
            (terms.is_ray_model(), terms.model.name()),
            (terms.radial, "radial"),
            (terms.rational, "rational"),
            (terms.tangential, "tangential"),
            (terms.prism, "thin prism"),
            (terms.tilt, "tilt"),
        ]
        .iter()
        .filter(|t| t.0)
        .map(|t| t.1)
        .collect::<Vec<_>>()
        .join(", ")
    );
    let chromatic = e.chromatic_aberration.then_some(e.chromatic_scales);
    let lensless = terms == Default::default();
    if lensless && chromatic.is_none() {
        steps.push(step(
            Stage::PinholeRender,
            if e.distortion {
                "the camera has no distortion: no lens work at all".into()
            } else {
                "no distortion asked: the pinhole projection, no warp, no geometry shader".into()
            },
        ));
        push_antialias_step(&mut steps, file.antialias, o.color);
        let ms = estimate_ms(pixels, scene.mesh.triangle_count() as f64, Cost::Pinhole);
        return Ok(file_plan(
            file,
            Route::Pinhole,
            steps,
            Optics::Camera(camera),
            poses,
            (0.0, ms),
        ));
    }
    // The vertex path: the coarsest tessellation that meets the budget (not searched
    // when nothing can go that way: chromatic colour without IDs or flow).
    let data_needs_vertex = o.ids || o.flow;
    let vertex = if chromatic.is_none() || data_needs_vertex {
        search_tessellation(scene, &poses[0], &camera, budget)?
    } else {
        None
    };
    let triangles = scene.mesh.triangle_count() as f64;
    // Three fetches (and inverses, or maps) per pixel with chromatic aberration.
    let fetches = if chromatic.is_some() { 3.0 } else { 1.0 };
    // The warp solved per pixel: the cheapest inverse meeting the budget, measured on
    // this camera.
    let per_pixel = search_inverse(&camera, budget, |ns| {
        estimate_ms(
            pixels,
            triangles,
            Cost::Warp {
                coordinate_ns: ns * fetches,
            },
        )
    });
    // The warp from a precomputed map: built once, its build shared by the frames.
    // Jittered anti-aliasing moves the lens every pass, so it solves per pixel.
    let frames = poses.len().max(1) as f64;
    let from_map = if file.antialias.is_on() {
        None
    } else {
        map_error_px(&camera, chromatic)
            .filter(|&e| e <= budget)
            .map(|e| {
                let sample = if chromatic.is_some() {
                    MAP_WARP_CHROMATIC_NS
                } else {
                    MAP_WARP_NS
                };
                WarpChoice {
                    method: InverseMethod::Newton,
                    map: true,
                    error_px: e,
                    ms: estimate_ms(
                        pixels,
                        triangles,
                        Cost::Warp {
                            coordinate_ns: sample + MAP_BUILD_NS * fetches / frames,
                        },
                    ),
                }
            })
    };
    let warp = match (per_pixel, from_map) {
        (Some(a), Some(b)) => Some(if b.ms < a.ms { b } else { a }),
        (a, b) => a.or(b),
    };
    // A lens no overscanned pinhole source holds (180° and more, or past the image
    // limit): the planned warp would miss pixels, so it is not a candidate; the vertex
    // path runs the lens's own model per vertex, the cube map samples six pinhole
    // faces along each pixel's ray.
    let no_pinhole_warp =
        limits::pinhole_source_refusal(&camera, 1.0, crate::model::MAX_IMAGE_SIDE.min(16384));
    let warp = if no_pinhole_warp.is_some() {
        None
    } else {
        warp
    };
    // The cube map carries colour alone: a face's depth is not the lens camera's, and
    // IDs are never filtered across faces. Faces of one face pixel per output pixel at
    // the centre (density 1, as the warp's source).
    let cube =
        (o.color && !data_needs_vertex && !o.depth && CUBE_RAY_ERROR_PX <= budget).then(|| {
            let texel = if o.exr { 16 } else { 4 };
            let wanted = crate::model::overscan::cube_face_side(&camera, 1.0);
            let side = limits::cube_side(wanted, texel, PLANNED_CUBE_MAX_SIDE);
            (
                side,
                estimate_ms(pixels, triangles, Cost::Cube { side, fetches }),
            )
        });
    if let Some(why) = &no_pinhole_warp {
        if chromatic.is_some() && cube.is_none() {
            return Err(Error::input(format!(
                        "{src}: [effects] chromatic_aberration: {why}, and a chromatic warp needs a pinhole source, or a cube map, which carries colour alone (no IDs, flow or depth): not planned (drop chromatic_aberration or the data outputs, or use a camera whose frame a pinhole holds)"
                    )));
        }
    }
    let describe_option = |c: &Option<WarpChoice>, what: &str| match c {
        Some(c) => format!(
            "{what} {:.1e} px, est. {:.1} ms per frame",
            c.error_px, c.ms
        ),
        None => format!("{what} does not meet the budget"),
    };
    let options_note = format!(
        "options: {}; {}",
        describe_option(
            &per_pixel,
            &per_pixel.map_or("solved per pixel:".to_string(), |c| format!(
                "{} per pixel:",
                c.method
            ))
        ),
        describe_option(
            &from_map,
            &format!("precomputed map (coarse 8 px, cubic; built once over {frames} frame(s)):")
        )
    );
    let vertex_ms = vertex.map(|t| {
        estimate_ms(
            pixels,
            t.triangles as f64,
            Cost::Vertex {
                vertices: t.vertices as f64,
            },
        )
    });
    let warp_ms = warp.map(|c| c.ms);
    let cube_ms = cube.map(|(_, ms)| ms);
    // Whether `a` is cheaper than `b` (a missing `b` loses to any `a`).
    let cheaper = |a: Option<f64>, b: Option<f64>| match (a, b) {
        (Some(a), Some(b)) => a < b,
        (a, _) => a.is_some(),
    };
    // Alg. 1 cannot give each channel its own lens: with chromatic aberration only the
    // warps compete.
    let pick_cube =
        cheaper(cube_ms, warp_ms) && (chromatic.is_some() || cheaper(cube_ms, vertex_ms));
    let ms_or = |ms: Option<f64>, none: &str| {
        ms.map(|m| format!("{m:.1} ms"))
            .unwrap_or_else(|| none.into())
    };
    let describe_tess = |l: Option<f64>, err: f64, tris: usize| {
        match l {
                None => format!("the mesh as it is: its straight edges stay within {err:.1e} px of the true curves ({tris} triangles)"),
                Some(l) => format!("edges split to {l} px: straight-line error {err:.1e} px ≤ budget ({tris} triangles)"),
            }
    };
    let describe_warp = |c: &WarpChoice| {
        if c.map {
            format!("a precomputed map: its error on this camera, {:.1e} px, meets the budget, and it is the cheaper per frame ({options_note}); overscanned source so every valid pixel has one", c.error_px)
        } else {
            format!("inverse {}: the cheapest method whose error on this camera, {:.1e} px, meets the budget ({options_note}); overscanned source so every valid pixel has one", c.method, c.error_px)
        }
    };
    let (route, expected, estimated) = if let (true, Some((side, ms))) = (pick_cube, cube) {
        let why = match &no_pinhole_warp {
            Some(why) => format!("no pinhole warp: {why}"),
            None => format!("cheaper than the pinhole warp ({})", ms_or(warp_ms, "none")),
        };
        steps.push(step(
                    Stage::CubeFaces,
                    format!("{why}: six 90° pinhole faces of {side}×{side} px (one face pixel per output pixel at the centre), rendered into a cube map on the GPU"),
                ));
        steps.push(step(
                    Stage::SphereWarp {
                        chromatic: chromatic.is_some(),
                    },
                    format!(
                        "each output pixel samples the cube along its ray, bilinear across faces: {CUBE_RAY_ERROR_PX:.1e} px; est. {ms:.1} ms per frame (Alg. 1: {}); {}; {terms_note}",
                        match vertex_ms {
                            Some(v) if chromatic.is_none() => format!("est. {v:.1} ms"),
                            _ if chromatic.is_some() => "cannot give each channel its own lens".into(),
                            _ => "no tessellation meets the budget".into(),
                        },
                        if chromatic.is_some() {
                            "chromatic aberration asked: each channel through its own radial scale"
                        } else {
                            "no chromatic aberration: the single-fetch variant"
                        },
                    ),
                ));
        (Route::Cube { side, chromatic }, CUBE_RAY_ERROR_PX, ms)
    } else if chromatic.is_some()
        || (!data_needs_vertex && warp.is_some() && (vertex.is_none() || warp_ms < vertex_ms))
    {
        let Some(choice) = warp else {
            return Err(Error::input(format!("{src}: [accuracy] max_error_px = {budget}: no inverse method meets it on this camera")));
        };
        steps.push(step(
            Stage::OverscannedRender,
            "the warp's source, covering every valid output pixel (Lambers et al. Sec. 3.3)".into(),
        ));
        steps.push(step(
            Stage::Warp {
                chromatic: chromatic.is_some(),
            },
            format!(
                "{}; {}; {}",
                describe_warp(&choice),
                if chromatic.is_some() {
                    "chromatic aberration asked: each channel through its own radial scale"
                } else {
                    "no chromatic aberration: the single-fetch variant"
                },
                terms_note
            ),
        ));
        if data_needs_vertex {
            let Some(TessellationChoice {
                edge_px: l,
                error_px: verr,
                triangles: tris,
                ..
            }) = vertex
            else {
                return Err(Error::input(format!("{src}: [accuracy] max_error_px = {budget}: tessellation cannot meet it for the ID/flow outputs")));
            };
            steps.push(step(
                Stage::VertexRenderData,
                format!(
                    "IDs and flow cannot be warped (Lambers et al. Table 1); {}; {terms_note}",
                    describe_tess(l, verr, tris)
                ),
            ));
            (
                Route::WarpAndVertex {
                    method: choice.method,
                    chromatic,
                    tessellate: l,
                    map: choice.map,
                },
                choice.error_px.max(verr),
                warp_ms.unwrap_or(0.0) + vertex_ms.unwrap_or(0.0),
            )
        } else {
            (
                Route::Warp {
                    method: choice.method,
                    chromatic,
                    map: choice.map,
                },
                choice.error_px,
                choice.ms,
            )
        }
    } else {
        let Some(TessellationChoice {
            edge_px: l,
            error_px: verr,
            triangles: tris,
            ..
        }) = vertex
        else {
            return Err(Error::input(format!("{src}: [accuracy] max_error_px = {budget}: even 1 px edges do not meet it, and the outputs (IDs/flow) need the vertex path")));
        };
        let why = if data_needs_vertex {
            format!(
                "{} need the geometry path: a warp cannot carry them (Lambers et al. Table 1)",
                match (o.ids, o.flow) {
                    (true, true) => "IDs and flow",
                    (true, false) => "object IDs",
                    _ => "flow vectors",
                }
            )
        } else if let Some(why) = &no_pinhole_warp {
            format!(
                "no pinhole warp: {why}; {}",
                match cube_ms {
                    Some(c) => format!(
                        "estimated {:.1} ms against {c:.1} ms for a cube map",
                        vertex_ms.unwrap_or(f64::NAN)
                    ),
                    None if CUBE_RAY_ERROR_PX > budget =>
                        format!("a cube map's rays ({CUBE_RAY_ERROR_PX:.1e} px) miss the budget"),
                    None => "a cube map carries colour alone".into(),
                }
            )
        } else {
            format!(
                "estimated {:.1} ms against {} for pinhole + warp",
                vertex_ms.unwrap_or(f64::NAN),
                warp_ms
                    .map(|w| format!("{w:.1} ms"))
                    .unwrap_or_else(|| "no warp meeting the budget".into())
            )
        };
        if l.is_some() {
            steps.push(step(Stage::Tessellation, describe_tess(l, verr, tris)));
        }
        steps.push(step(
            Stage::VertexRender,
            format!(
                "{why}; {}; {terms_note}",
                if l.is_none() {
                    describe_tess(l, verr, tris)
                } else {
                    "discard δ = 0.1 + D".into()
                }
            ),
        ));
        (
            Route::Vertex { tessellate: l },
            verr,
            vertex_ms.unwrap_or(f64::NAN),
        )
    };
    push_antialias_step(&mut steps, file.antialias, o.color);
    Ok(file_plan(
        file,
        route,
        steps,
        Optics::Camera(camera),
        poses,
        (expected, estimated),
    ))
}

/// A scene file's plan once its route is chosen: `(expected error px, estimated ms)` as
/// measured while planning; the rest is the file's.
fn file_plan(
    file: &SceneFile,
    route: Route,
    steps: Vec<Step>,
    optics: Optics,
    poses: Vec<Pose>,
    (expected_error_px, estimated_ms): (f64, f64),
) -> Plan {
    Plan {
        route,
        steps,
        optics,
        expected_error_px,
        budget_px: file.max_error_px,
        poses,
        previous_pose: None,
        delta: crate::pass::geometry::DEFAULT_DELTA,
        density: 1.0,
        outputs: file.outputs,
        background: file.background,
        antialias: file.antialias,
        estimated_ms,
    }
}
