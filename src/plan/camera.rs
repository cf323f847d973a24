//! A calibrated camera's plan: the scene file checked against the camera, the candidates'
//! search (tessellation, inverse, map, cube), the choice among them, and the steps that
//! explain it.

use std::path::Path;

use super::choice::choose;
use super::cost::{estimate_ms, Cost};
use super::search::{search_bands, search_candidates};
use super::{chromatic_scales, explain, file_plan, Optics, Plan, Route, SceneFile, Shutter};
use crate::model::rolling_shutter::{FrameMotion, Readout};
use crate::model::{Camera, OpenCvDistortion};
use crate::scene::{Pose, Scene};
use crate::{Error, Result};

/// The file's camera as the search needs it: loaded, refused where the file asks for effects
/// a calibrated camera cannot have, and its distortion dropped where `[effects]
/// distortion = false`; with the readout its file states (kept when the distortion is dropped).
fn checked_camera(file: &SceneFile, path: &Path) -> Result<(Camera, Option<Readout>)> {
    let src = file.source.display();
    let e = &file.effects;
    let camera =
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
    let readout = camera.readout();
    if e.distortion {
        return Ok((camera, readout));
    }
    let pinhole = Camera::new(
        camera.width,
        camera.height,
        camera.intrinsics,
        OpenCvDistortion::default(),
    )?;
    Ok((pinhole, readout))
}

/// A calibrated camera's plan: a camera without distortion (or without the distortion
/// wanted) and without chromatic aberration is a pinhole render; any other goes by the
/// cheapest candidate route that meets the budget.
pub(super) fn plan_camera(file: &SceneFile, scene: &Scene, path: &Path) -> Result<Plan> {
    let (camera, readout) = checked_camera(file, path)?;
    let shutter = super::shutter::resolve(file, readout)?;
    let poses = if file.poses.is_empty() {
        vec![scene.default_pose(&camera)]
    } else {
        file.poses.clone()
    };
    let terms = camera.terms();
    if terms == Default::default() && chromatic_scales(file).is_none() {
        return Ok(pinhole_plan(file, scene, camera, (poses, shutter)));
    }
    // The first frame that moves during its readout: the tessellation is measured through its
    // motion (edges bend more when each line sees its own pose).
    let moving = match shutter {
        Shutter::Moving { readout, frame, .. } => {
            let end = file.end_poses.get(frame).copied().flatten();
            poses.get(frame).zip(end).map(|(p, e)| (readout, *p, e))
        }
        _ => None,
    };
    let all = search_candidates(file, scene, &camera, &poses, moving)?;
    // A path the file asks for: the others dropped before the route (and the bands) are
    // chosen among what is left.
    let asked = match file.path {
        Some(path) => {
            super::choice::refuse_asked(file, path)?;
            Some(super::choice::asked_candidates(file, &all, path))
        }
        None => None,
    };
    let candidates = asked.as_ref().unwrap_or(&all);
    let choice = match shutter {
        Shutter::Moving { readout, frame, .. } => {
            // Every frame that moves: the bands must meet the budget on each.
            let motions: Vec<_> = poses
                .iter()
                .zip(&file.end_poses)
                .filter_map(|(p, e)| e.filter(|e| e != p).map(|e| (*p, e)))
                .map(|(p, e)| (readout, FrameMotion::new(p.into(), e.into())))
                .collect();
            let bands = search_bands(scene, &camera, candidates, &motions, file.max_error_px);
            super::choice::choose_moving_rolling_shutter(
                file,
                candidates,
                &bands,
                (readout, frame),
            )?
        }
        _ => choose(file, candidates)?,
    };
    // The reason says the path was asked for where it weighed candidates the path dropped.
    let choice = match asked {
        Some(_) => super::choice::asked_reason(choice, &all),
        None => choice,
    };
    // The steps weigh the route against every candidate, the dropped ones included.
    let mut steps = explain::camera_steps(&choice, &all, terms);
    if file.outputs.renders_data() {
        // A cube route asked for with IDs, depth or range: what its data pass does.
        for s in steps
            .iter_mut()
            .filter(|s| matches!(s.stage, super::Stage::SphereWarp { .. }))
        {
            s.why.push_str("; IDs and depth at the nearest texel, the depth carried onto each pixel's own ray as z and range");
        }
    }
    steps.extend(explain::antialias_step(file.antialias, file.outputs.color));
    let mut plan = file_plan(
        file,
        choice.route(),
        steps,
        Optics::Camera(camera),
        (poses, shutter),
        (choice.expected_error_px(), choice.estimated_ms()),
    );
    plan.bands = choice.bands();
    Ok(plan)
}

/// The plan of a camera with no lens work: its pinhole projection alone.
fn pinhole_plan(
    file: &SceneFile,
    scene: &Scene,
    camera: Camera,
    poses: (Vec<Pose>, Shutter),
) -> Plan {
    let mut steps = vec![explain::pinhole_step(file.effects.distortion)];
    steps.extend(explain::antialias_step(file.antialias, file.outputs.color));
    let ms = estimate_ms(
        camera.width as f64 * camera.height as f64,
        scene.mesh.triangle_count() as f64,
        Cost::Pinhole,
    );
    file_plan(
        file,
        Route::Pinhole,
        steps,
        Optics::Camera(camera),
        poses,
        (0.0, ms),
    )
}
