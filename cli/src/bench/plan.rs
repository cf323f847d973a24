//! `vklens bench plan`: the user-facing "what accuracy costs in time".
//!
//! * **plans** — for each example scene (`examples/scenes/*.toml`): the plan the planner
//!   chose, its frame time and its geometric error (measured against the exact f64 model while
//!   planning), beside the everything-on pipeline for the same scene: every output, chromatic
//!   aberration, Newton, edges split to 2 px (a lens: 32 samples, colour, vignetting);
//! * **tradeoff** — the choices the planner picks from, on the 14-coefficient `prism_tilt`
//!   camera and the 16² grid: every inverse method of the warp and every tessellation of
//!   Alg. 1, each with its measured error and frame time (the plot in the README).
//!
//! Frame times are wall time of one frame after a warm-up frame (readback included), on the
//! device the run uses.

use std::path::Path;

use super::{fixed as f, sci as e};
use serde_json::{json, Value};

use vklens::gpu::{Error, Result};
use vklens::host::plan::execute;
use vklens::host::Context;
use vklens::plan::scene_file::OpticsSpec;
use vklens::plan::{
    inverse_candidates, inverse_error_px, load_geometry, plan, Plan, Route, SceneFile,
};
use vklens::scene::Scene;

/// Median frame time of three renders of the plan's first pose (ms), by one recorder.
fn time_plan(ctx: &Context, p: &Plan, scene: &Scene) -> Result<f64> {
    let mut times = Vec::new();
    execute(ctx, p, scene, [0, 0, 0], &mut |f| {
        times.push(f.ms);
        Ok(())
    })?;
    times.sort_by(f64::total_cmp);
    Ok(times[times.len() / 2])
}

fn route_name(r: &Route) -> String {
    match r {
        Route::Pinhole => "pinhole".into(),
        Route::Vertex { tessellate } => match tessellate {
            Some(l) => format!("Alg. 1, {l} px edges"),
            None => "Alg. 1".into(),
        },
        Route::Warp {
            method,
            chromatic,
            map,
        } => format!(
            "warp {}{}",
            if *map {
                "map".to_string()
            } else {
                method.to_string()
            },
            if chromatic.is_some() {
                ", chromatic"
            } else {
                ""
            }
        ),
        Route::WarpAndVertex {
            method,
            tessellate,
            map,
            ..
        } => format!(
            "warp {} + Alg. 1{}",
            if *map {
                "map".to_string()
            } else {
                method.to_string()
            },
            tessellate.map(|l| format!(", {l} px")).unwrap_or_default()
        ),
        Route::Cube { side, chromatic } => format!(
            "cube map, 6 × {side}² faces{}",
            if chromatic.is_some() {
                ", chromatic"
            } else {
                ""
            }
        ),
        Route::LensModel {
            samples, chromatic, ..
        } => format!(
            "lens model, {samples} sample(s){}",
            if *chromatic { ", chromatic" } else { "" }
        ),
        Route::Environment { chromatic } => format!(
            "360° source{}",
            if chromatic.is_some() {
                ", chromatic"
            } else {
                ""
            }
        ),
    }
}

/// The everything-on version of a scene file.
fn everything_on(file: &SceneFile) -> SceneFile {
    let mut f = file.clone();
    f.effects.distortion = true;
    f.effects.chromatic_aberration = true;
    match f.optics {
        OpticsSpec::Camera(_) => {
            if f.effects.chromatic_scales == [1.0; 3] {
                f.effects.chromatic_scales = [1.003, 1.0, 0.997];
            }
            f.outputs.ids = true;
            f.outputs.flow = true;
            f.outputs.depth = true;
            f.max_error_px = 1e-4;
        }
        OpticsSpec::Lens { .. } => {
            f.effects.depth_of_field = true;
            f.effects.vignetting = true;
            f.effects.lens_samples = 32;
        }
    }
    f
}

/// Runs every row; `examples` is the folder of scene files.
pub fn run(ctx: &Context, examples: &Path, progress: &mut dyn FnMut(&str)) -> Result<Vec<Value>> {
    let mut files: Vec<_> = std::fs::read_dir(examples)
        .map_err(|e| Error::input(format!("{}: {e}", examples.display())))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    let mut rows = Vec::new();
    for path in &files {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default();
        progress(&format!("{name}: planning"));
        let file = SceneFile::load(path)?;
        let scene = load_geometry(&file)?;
        let chosen = plan(&file, &scene)?;
        progress(&format!("{name}: {}", route_name(&chosen.route)));
        let chosen_ms = time_plan(ctx, &chosen, &scene)?;
        let mut all = everything_on(&file);
        // Everything on: Newton, 3 fetches, every output by Alg. 1 with 2 px edges. Past a
        // pinhole's reach no warp carries lateral colour beside IDs and flow (a cube map holds
        // colour alone), and the f32 vertices of a fisheye miss a 1e-4 px budget: there,
        // everything else on, at the file's own budget.
        let mut full = plan(&all, &scene);
        if full.is_err() && all.effects.chromatic_aberration {
            all.effects.chromatic_aberration = false;
            all.max_error_px = file.max_error_px;
            full = plan(&all, &scene);
        }
        let mut full = full?;
        if let Route::WarpAndVertex {
            tessellate,
            method,
            map,
            ..
        } = &mut full.route
        {
            *tessellate = Some(2.0);
            *method = vklens::model::InverseMethod::Newton;
            *map = false;
        }
        progress(&format!(
            "{name}: everything on ({})",
            route_name(&full.route)
        ));
        let full_ms = time_plan(ctx, &full, &scene)?;
        rows.push(json!({
            "kind": "plans",
            "scene": name,
            "plan": route_name(&chosen.route),
            "budget_px": chosen.budget_px,
            "error_px": chosen.expected_error_px,
            "frame_ms": chosen_ms,
            "everything_on": route_name(&full.route),
            "everything_on_ms": full_ms,
            "saving": full_ms / chosen_ms,
            "device": ctx.gpu().device_name(),
        }));
    }
    // The trade-off the planner walks: prism_tilt on the 16² grid, colour only.
    let text =
        "[geometry]\nscene = \"grid:16\"\n[optics]\ncamera = \"../cameras/prism_tilt.json\"\n";
    let file = SceneFile::parse(text, &examples.join("tradeoff.toml"))?;
    let scene = load_geometry(&file)?;
    let base = plan(&file, &scene)?;
    let camera = base
        .camera()
        .cloned()
        .ok_or_else(|| Error::internal("a camera plan without a camera"))?;
    for (method, _) in inverse_candidates() {
        let Some(error) = inverse_error_px(&camera, method) else {
            continue;
        };
        progress(&format!("trade-off: warp {method}"));
        let p = Plan {
            route: Route::Warp {
                method,
                chromatic: None,
                map: false,
            },
            ..base.clone()
        };
        rows.push(json!({
            "kind": "tradeoff", "path": "warp", "choice": method.to_string(),
            "error_px": error, "frame_ms": time_plan(ctx, &p, &scene)?,
        }));
    }
    let pose = base.poses[0];
    for l in [
        None,
        Some(32.0),
        Some(16.0),
        Some(8.0),
        Some(4.0),
        Some(2.0),
    ] {
        let mesh = match l {
            None => scene.mesh.clone(),
            Some(l) => vklens::scene::tessellate::tessellate(&scene.mesh, &pose, &camera, l)?,
        };
        let error = super::vertex::straight_line_error(&camera, &pose, &mesh);
        progress(&format!("trade-off: Alg. 1, edges {l:?}"));
        let p = Plan {
            route: Route::Vertex { tessellate: l },
            ..base.clone()
        };
        rows.push(json!({
            "kind": "tradeoff", "path": "vertex",
            "choice": l.map(|l| format!("{l} px edges")).unwrap_or_else(|| "as is".into()),
            "triangles": mesh.triangle_count(),
            "error_px": error, "frame_ms": time_plan(ctx, &p, &scene)?,
        }));
    }
    Ok(rows)
}

/// Markdown tables.
pub fn table(rows: &[Value]) -> String {
    let mut out = String::from(
        "Plans (frame ms: one frame after a warm-up, readback included)\n\n\
         | scene | plan | budget px | error px | frame ms | everything on | ms | × saved |\n\
         |---|---|---:|---:|---:|---|---:|---:|\n",
    );
    for r in rows.iter().filter(|r| r["kind"] == "plans") {
        out.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r["scene"].as_str().unwrap_or(""),
            r["plan"].as_str().unwrap_or(""),
            r["budget_px"],
            e(r, "error_px"),
            f(r, "frame_ms", 1),
            r["everything_on"].as_str().unwrap_or(""),
            f(r, "everything_on_ms", 1),
            f(r, "saving", 1),
        ));
    }
    out.push_str(
        "\nWhat the planner chooses from (prism_tilt camera, 16² grid, colour only)\n\n\
         | path | choice | error px | frame ms |\n|---|---|---:|---:|\n",
    );
    for r in rows.iter().filter(|r| r["kind"] == "tradeoff") {
        out.push_str(&format!(
            "| {} | {} | {} | {} |\n",
            r["path"].as_str().unwrap_or(""),
            r["choice"].as_str().unwrap_or(""),
            e(r, "error_px"),
            f(r, "frame_ms", 1),
        ));
    }
    out
}
