//! `vklens render --scene S.toml --out DIR [--explain] [--frames A..B]`: a scene file through
//! the planner.

use std::path::Path;

use serde_json::json;

use super::output::{write_outputs, Targets};
use super::{context, finish, progress_done, progress_line, CliError};
use vklens::host::plan::execute;
use vklens::plan::{load_geometry, plan, Plan, SceneFile};

/// Parses `A..B` (B excluded) or `A..=B` against `count` poses.
pub fn parse_frames(s: &str, count: usize) -> Result<std::ops::Range<usize>, String> {
    let bad = || format!("--frames {s:?}: expected A..B or A..=B (frame numbers from 0)");
    let (a, b, inclusive) = if let Some((a, b)) = s.split_once("..=") {
        (a, b, true)
    } else if let Some((a, b)) = s.split_once("..") {
        (a, b, false)
    } else {
        return Err(bad());
    };
    let a: usize = if a.trim().is_empty() {
        0
    } else {
        a.trim().parse().map_err(|_| bad())?
    };
    let b: usize = if b.trim().is_empty() {
        count
    } else {
        b.trim().parse::<usize>().map_err(|_| bad())? + inclusive as usize
    };
    if a >= b || b > count {
        return Err(format!(
            "--frames {s:?}: the scene has {count} pose(s), frames 0..{count}"
        ));
    }
    Ok(a..b)
}

fn plan_json(p: &Plan, frames: &[(usize, f64)]) -> serde_json::Value {
    let mut v = json!({
        "route": format!("{:?}", p.route),
        "steps": p.steps.iter().map(|s| json!({"pass": s.stage.name(), "why": s.why})).collect::<Vec<_>>(),
        "expected_error_px": p.expected_error_px,
        "budget_px": p.budget_px,
        "shutter": p.shutter.name(),
        "bands": p.bands,
        "antialias": {"supersample": p.antialias.supersample, "jitter": p.antialias.jitter},
        "estimated_ms": if p.estimated_ms.is_finite() { json!(p.estimated_ms) } else { json!(null) },
        "frames": frames.iter().map(|(i, ms)| json!({"frame": i, "ms": ms})).collect::<Vec<_>>(),
    });
    // Only where the scene file asks for a path: the planner chose every other plan.
    if let (Some(path), Some(o)) = (p.path_asked, v.as_object_mut()) {
        o.insert("path".into(), path.name().into());
    }
    v
}

/// What `render --scene FILE.toml` was asked for besides the file.
pub struct SceneRun<'a> {
    /// `--out DIR`.
    pub out: Option<&'a Path>,
    /// `--frames A..B`.
    pub frames: Option<&'a str>,
    /// `--explain`.
    pub explain: bool,
}

pub fn run(scene_path: &str, args: SceneRun) -> Result<(), CliError> {
    let Some(out) = args.out else {
        return Err(CliError::input(
            "a scene file renders into a folder: give --out DIR",
        ));
    };
    let file =
        SceneFile::load(Path::new(scene_path)).map_err(|e| CliError::input(e.to_string()))?;
    let scene = load_geometry(&file)?;
    let plan = plan(&file, &scene)?;
    let frames = match args.frames {
        Some(f) => parse_frames(f, plan.poses.len()).map_err(CliError::Input)?,
        None => 0..plan.poses.len(),
    };
    if !out.is_dir() {
        std::fs::create_dir(out).map_err(|e| {
            CliError::input(format!(
                "--out {}: cannot create the folder: {e}",
                out.display()
            ))
        })?;
    }
    let ctx = context()?;
    let o = plan.outputs;
    let labels = vklens::plan::SceneLabels::new(&file, &scene);
    let color_ext = if o.exr { "exr" } else { "png" };
    let total = frames.len();
    let done: std::cell::RefCell<Vec<(usize, f64)>> = Default::default();
    // Frames written so far: removed again if anything after them fails (a closed stdout for
    // --explain, a full disk for plan.json) or the run is interrupted.
    let written = std::cell::RefCell::new(vklens::imaging::file::RunOutputs::new());
    let mut write = |f: vklens::host::plan::Frame| -> Result<(), vklens::Error> {
        let name = |kind: &str, ext: &str| out.join(format!("{kind}_{:04}.{ext}", f.index));
        let (c, i, fl, d) = (
            name("color", color_ext),
            name("ids", "png"),
            name("flow", "exr"),
            name("depth", "exr"),
        );
        let (r, cl, b, k) = (
            name("range", "exr"),
            name("classes", "png"),
            name("boxes", "json"),
            name("keypoints", "json"),
        );
        let targets = Targets {
            color: o.color.then_some(c.as_path()),
            ids: o.ids.then_some(i.as_path()),
            flow: o.flow.then_some(fl.as_path()),
            depth: o.depth.then_some(d.as_path()),
            range: o.range.then_some(r.as_path()),
            classes: o.classes.then_some(cl.as_path()),
            boxes: o.boxes.then_some(b.as_path()),
            keypoints: o.keypoints.then_some(k.as_path()),
            objects: None,
        };
        let frame_labels = labels.frame(&plan, &scene, f.index, &f.rendered)?;
        write_outputs(
            &targets,
            &f.rendered,
            &frame_labels,
            Some("png"),
            Some(&mut written.borrow_mut()),
        )?;
        done.borrow_mut().push((f.index, f.ms));
        if args.explain && done.borrow().len() == 1 {
            // On stdout, as soon as the first frame has measured the plan's passes.
            out!("{}", plan.explain(Some(f.ms), &f.pass_ms))?;
        }
        progress_line(&format!(
            "frame {}/{total} ({:.1} ms)",
            done.borrow().len(),
            f.ms
        ));
        Ok(())
    };
    // One recorder for every frame: `--explain` reads its pass times off the first.
    execute(&ctx, &plan, &scene, frames, &mut write)?;
    finish(&ctx)?;
    let done = done.into_inner();
    let mut written = written.into_inner();
    let json = format!("{:#}\n", plan_json(&plan, &done));
    let plan_path = out.join("plan.json");
    vklens::imaging::file::stage(&plan_path, |tmp| std::fs::write(tmp, &json))?
        .commit_into(&mut written)?;
    // Every object's name and class, for the ID, class and box outputs.
    if o.renders_ids() {
        let text = super::output::json_text(&labels.objects)?;
        let objects_path = out.join("objects.json");
        vklens::imaging::file::stage(&objects_path, |tmp| std::fs::write(tmp, &text))?
            .commit_into(&mut written)?;
    }
    // The camera the frames were rendered through, for the user's own pipeline.
    if let Some(camera) = plan.camera() {
        let json_path = out.join("camera.json");
        camera.save(&json_path)?;
        written.add(&json_path);
        match camera.to_ros_camera_info() {
            Ok(text) => {
                let info = out.join("camera_info.yaml");
                vklens::imaging::file::stage(&info, |tmp| std::fs::write(tmp, &text))?
                    .commit_into(&mut written)?;
            }
            Err(e) => progress_done(&format!("camera_info.yaml not written: {e}")),
        }
    }
    written.keep();
    progress_done(&format!("{} frame(s) in {}", done.len(), out.display()));
    Ok(())
}
