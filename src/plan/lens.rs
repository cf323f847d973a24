//! A lens prescription's plan: the scene file checked against what Heidrich et al.'s
//! image-based model can give, the budget turned into the quad-tree's angle threshold, the
//! models built, and the steps that explain them.

use std::path::Path;

use super::scene_file::{Antialias, Effects, OutputSpec};
use super::shutter::Shutter;
use super::{explain, file_plan, LensSetting, Optics, Plan, Route, SceneFile};
use crate::lens::image_model::{self, channel_models, ImageModel, ModelOptions};
use crate::lens::{frame_scene, Prescription, LAMBDA_D};
use crate::scene::{Pose, Scene};
use crate::{Error, Result};

/// A scene file's lens optics, borrowed.
pub(super) struct LensSpec<'a> {
    pub(super) path: &'a Path,
    pub(super) focus_m: Option<f64>,
    pub(super) f_number: Option<f64>,
    pub(super) sensor_mm: (f64, f64),
    pub(super) pixels: (u32, u32),
}

/// A prescription the scene file may be rendered through: loaded, and its film's pixels
/// checked square.
struct CheckedLens {
    prescription: Prescription,
    /// The film's pixel pitch (mm).
    pitch_mm: f64,
}

/// The cells the image-based models were built of, over every channel.
pub(super) struct Cells {
    /// Perspective projections per frame.
    pub(super) projections: usize,
    /// The largest angle error of any cell (degrees).
    pub(super) max_angle_deg: f64,
}

impl Cells {
    fn of(models: &[(ImageModel, [f32; 4])]) -> Cells {
        Cells {
            projections: models.iter().map(|(m, _)| m.projection_count()).sum(),
            max_angle_deg: models
                .iter()
                .map(|(m, _)| m.max_angle_deg())
                .fold(0.0, f64::max),
        }
    }
}

/// Refuses what the image-based model cannot give (anti-aliasing, IDs, flow, depth, a lens
/// without distortion, chromatic aberration without dispersion, non-square pixels) and
/// loads the prescription.
fn check_lens(file: &SceneFile, spec: &LensSpec) -> Result<CheckedLens> {
    let src = file.source.display();
    let e = &file.effects;
    let o = &file.outputs;
    if file.antialias.is_on() {
        return Err(Error::input(format!(
            "{src}: [render] supersample / jitter: the image-based lens model renders one sample per pixel per lens sample; anti-aliasing is for camera-file scenes"
        )));
    }
    let asked = [
        (o.ids, "[outputs] ids"),
        (o.flow, "[outputs] flow"),
        (o.depth, "[outputs] depth"),
        (o.range, "[outputs] range"),
        (o.classes, "[outputs] classes"),
        (o.boxes, "[outputs] boxes"),
        (o.keypoints, "[[keypoints]]"),
    ];
    for (asked, key) in asked {
        if asked {
            return Err(Error::input(format!(
                "{src}: {key}: the image-based lens model blends many views, so it has no exact {key}; give a calibrated camera (optics.camera; `vklens lens fit-opencv` makes one from the lens) for {key}"
            )));
        }
    }
    if let Some(path) = file.path {
        return Err(Error::input(format!(
            "{src}: [render] path = \"{path}\": a lens prescription renders by Heidrich et al.'s image-based model; the paths are for camera files"
        )));
    }
    if !e.distortion {
        return Err(Error::input(format!(
            "{src}: [effects] distortion = false: a real lens always distorts; use a camera file with the distortion switched off for a pinhole"
        )));
    }
    let prescription = Prescription::load(spec.path)
        .map_err(|e| Error::from(e).named_by(format!("{src}: [optics] lens")))?;
    if e.chromatic_aberration && prescription.surfaces.iter().all(|s| s.abbe.is_none()) {
        return Err(Error::input(format!(
            "{src}: [effects] chromatic_aberration: {} has no Abbe numbers (5th column)",
            spec.path.display()
        )));
    }
    let (sensor_mm, pixels) = (spec.sensor_mm, spec.pixels);
    let pitch_mm = sensor_mm.0 / pixels.0 as f64;
    if ((sensor_mm.1 / pixels.1 as f64) / pitch_mm - 1.0).abs() > 1e-3 {
        return Err(Error::input(format!(
            "{src}: [optics] sensor_mm and pixels give non-square pixels"
        )));
    }
    Ok(CheckedLens {
        prescription,
        pitch_mm,
    })
}

/// The image-based lens model's plan: validation, the model's cells, the steps.
pub(super) fn plan_lens(file: &SceneFile, scene: &Scene, spec: LensSpec) -> Result<Plan> {
    let CheckedLens {
        prescription,
        pitch_mm,
    } = check_lens(file, &spec)?;
    // A prescription states no readout: the scene's key alone decides.
    let shutter = super::shutter::resolve(file, None)?;
    shutter.refuse_one_pose_route(
        &file.source.display().to_string(),
        "the image-based lens model",
        "optics is a lens prescription",
    )?;
    let LensSpec {
        path,
        focus_m,
        f_number,
        pixels,
        ..
    } = spec;
    let e = &file.effects;
    let first = file.poses.first().copied();
    let (optics, _) = frame_scene(
        &prescription,
        pixels,
        pitch_mm,
        f_number,
        focus_m,
        first,
        scene,
    )
    .map_err(|e| Error::input(format!("{}: {e}", path.display())))?;
    let efl = crate::lens::analyse(&prescription, LAMBDA_D)
        .efl
        .unwrap_or(1.0);
    // The budget in degrees: one pixel subtends pitch / EFL radians.
    let px_deg = (pitch_mm / efl).atan().to_degrees();
    let max_angle_deg = file.max_error_px * px_deg;
    let samples = if e.depth_of_field { e.lens_samples } else { 1 };
    let options = ModelOptions {
        samples,
        max_angle_deg,
        vignetting: e.vignetting,
        ..ModelOptions::default()
    };
    let models = channel_models(&optics, &options, e.chromatic_aberration)
        .map_err(|e| Error::input(format!("{}: {e}", path.display())))?;
    let cells = Cells::of(&models);
    let steps = explain::lens_steps(e, samples, max_angle_deg, file.max_error_px, &cells);
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
            prescription,
            pitch_mm,
            pixels,
            focus_m: optics.focus_m,
            f_number,
            models,
        }),
        (poses, shutter),
        (cells.max_angle_deg / px_deg, f64::NAN),
    ))
}

/// A lens prescription rendered as a caller names it (`vklens lens render`): a scene file
/// leaves the lens samples and the quad-tree's threshold to the planner and its budget, a
/// request states them, as Heidrich et al.'s model takes them ([`ModelOptions`]).
#[derive(Debug, Clone)]
pub struct LensRequest {
    pub prescription: Prescription,
    /// The film's pixels and their pitch (mm; square pixels).
    pub pixels: (u32, u32),
    pub pitch_mm: f64,
    /// The aperture (`None`: the prescription's stop wide open).
    pub f_number: Option<f64>,
    /// The image-based model's lens samples, grid, quad-tree and vignetting.
    pub options: ModelOptions,
    /// R, G and B traced at their own wavelengths (the C, e and F lines).
    pub chromatic: bool,
    /// Colour as float (EXR) instead of 8-bit.
    pub exr: bool,
}

impl Plan {
    /// The image-based model's plan for `request`, with the lens focused and the camera
    /// placed as [`frame_scene`] did it (`optics`, `pose`): the models traced (the slow part),
    /// the steps that explain them, one frame at `pose`.
    pub fn from_lens_request(
        request: &LensRequest,
        optics: &image_model::Optics,
        pose: Pose,
    ) -> Result<Plan> {
        let options = &request.options;
        let models = channel_models(optics, options, request.chromatic)?;
        let cells = Cells::of(&models);
        let efl = crate::lens::analyse(&request.prescription, LAMBDA_D)
            .efl
            .unwrap_or(1.0);
        let px_deg = (request.pitch_mm / efl).atan().to_degrees();
        let effects = Effects {
            distortion: true,
            chromatic_aberration: request.chromatic,
            chromatic_scales: [1.0; 3],
            vignetting: options.vignetting,
            depth_of_field: options.samples > 1,
            lens_samples: options.samples,
        };
        let budget_px = options.max_angle_deg / px_deg;
        let steps = explain::lens_steps(
            &effects,
            options.samples,
            options.max_angle_deg,
            budget_px,
            &cells,
        );
        Ok(Plan {
            route: Route::LensModel {
                samples: options.samples,
                chromatic: request.chromatic,
                vignetting: options.vignetting,
                max_angle_deg: options.max_angle_deg,
            },
            steps,
            optics: Optics::Lens(LensSetting {
                prescription: request.prescription.clone(),
                pitch_mm: request.pitch_mm,
                pixels: request.pixels,
                focus_m: optics.focus_m,
                f_number: request.f_number,
                models,
            }),
            expected_error_px: cells.max_angle_deg / px_deg,
            budget_px,
            poses: vec![pose],
            end_poses: Vec::new(),
            previous_pose: None,
            delta: crate::pass::geometry::DEFAULT_DELTA,
            density: 1.0,
            outputs: OutputSpec {
                color: true,
                exr: request.exr,
                ..OutputSpec::default()
            },
            background: [0.0; 4],
            antialias: Antialias::default(),
            shutter: Shutter::Global,
            bands: None,
            estimated_ms: f64::NAN,
            path_asked: None,
        })
    }
}
