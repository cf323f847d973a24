//! `vklens bench rolling-shutter`: what drawing a moving rolling shutter exactly costs. The
//! vertex path that solves each vertex's readout time (`glsl/include/rolling_shutter.glsl`)
//! against the global shutter's vertex path, the same scene, camera and first pose in the same
//! run: grids of 128² and 512² quads through a k1 k2 lens at 800×600, the camera panning 7°
//! and stepping 12 cm sideways during a top-to-bottom readout.
//!
//! Each row has the frame time (wall clock of one whole render, readback included: median of
//! at least [`FRAMES`] after a warm-up, and of as many as four seconds hold), and the exact
//! path's rows its ratio to the global path's. The two paths' frames alternate, one of each in
//! turn: on a shared machine a frame's time drifts within seconds by more than the two paths
//! differ by, and alternating frames lets both medians see the same drift.
//!
//! Then the approximation the warp route can draw (chromatic aberration needs it): the same
//! frame in K = 4 … 64 bands of lines, the warp's pinhole source rendered once per band from
//! the pose of its middle line (`model::rolling_shutter::bands`), on the 128² grid. Each bands
//! row has its frame time and ratio to the exact path's, the geometric error the planner
//! measures for it (f64, against the exact projection over the grid's distances) and the mean
//! absolute difference of its colour from the exact path's (8-bit levels, over every channel
//! of every pixel). A first row gives that difference for a camera that does not move, the
//! floor the warp's resampling leaves against the vertex path's raster whatever the bands.

use serde_json::{json, Value};

use super::fixed as f;
use vklens::host::bands_study::{
    bands_error_px, bands_plan, camera, colour_mad, exact_request, median, pan, plan_frames,
    still_colour_mad, FRAMES,
};
use vklens::host::plan::FrameRunner;
use vklens::host::Context;
use vklens::model::rolling_shutter::bands::BAND_COUNTS;
use vklens::model::rolling_shutter::Readout;
use vklens::model::Camera;
use vklens::pass::geometry::DEFAULT_DELTA;
use vklens::plan::{PathChoice, Plan, RenderRequest};
use vklens::scene::{builtin, Pose, Scene};
use vklens::Result;

/// Grid meshes (quads per side).
pub const GRIDS: [u32; 2] = [128, 512];
/// The grid the bands are measured on (quads per side).
pub const BANDS_GRID: u32 = 128;

/// The vertex path's plan for the first pose of the pan, with `rolling_shutter` as the request
/// gives it (`None`: the global shutter).
fn vertex_plan(
    ctx: &Context,
    camera: &Camera,
    rolling_shutter: Option<(Readout, Pose)>,
) -> Result<Plan> {
    let mut request = RenderRequest::color(
        camera,
        PathChoice::Vertex {
            delta: DEFAULT_DELTA,
            tessellate: None,
        },
    );
    request.pose = pan().0;
    request.previous_pose = request.pose;
    request.rolling_shutter = rolling_shutter;
    Plan::from_request(&request, ctx.gpu().max_image_side())
}

/// Wall-clock seconds the two paths' alternating frames run for at least, together: nine
/// frames of each (a fifth of a second on the small grid, two seconds on the large one) fell
/// on one stretch of slow frames often enough to move the ratio by 0.15 and more from run to
/// run.
pub const MIN_ALTERNATING_SECONDS: f64 = 4.0;

/// Median wall-clock ms of each of two plans' frames, their frames alternating after a
/// warm-up frame each: at least [`FRAMES`] of each, and more until they have run for
/// [`MIN_ALTERNATING_SECONDS`].
fn alternating_ms(ctx: &Context, plans: [&Plan; 2], scene: &Scene) -> Result<[f64; 2]> {
    let mut runners = [
        FrameRunner::new(ctx, plans[0], scene, 0, true)?,
        FrameRunner::new(ctx, plans[1], scene, 0, true)?,
    ];
    for r in &mut runners {
        r.frame(0)?;
    }
    let mut times = [Vec::new(), Vec::new()];
    let start = std::time::Instant::now();
    while times[0].len() < FRAMES || start.elapsed().as_secs_f64() < MIN_ALTERNATING_SECONDS {
        for (r, t) in runners.iter_mut().zip(&mut times) {
            t.push(r.frame(0)?.ms);
        }
    }
    let [a, b] = times;
    Ok([median(a)?, median(b)?])
}

/// Every row: per grid, the global path, then the exact path with its ratio to it; then the
/// bands on [`BANDS_GRID`], each against the exact path.
pub fn run(ctx: &Context, progress: &mut dyn FnMut(&str)) -> Result<Vec<Value>> {
    let mut rows = global_and_exact(ctx, progress)?;
    rows.extend(bands_rows(ctx, progress)?);
    Ok(rows)
}

/// The bands rows: K = 4 … 64 on the 128² grid, each against the exact path.
fn bands_rows(ctx: &Context, progress: &mut dyn FnMut(&str)) -> Result<Vec<Value>> {
    let camera = camera()?;
    let scene = builtin::grid(BANDS_GRID);
    progress(&format!(
        "rolling shutter: grid {BANDS_GRID}², exact per vertex (the bands' reference)"
    ));
    let top = Readout::TopToBottom;
    let exact_plan = Plan::from_request(&exact_request(&camera, top), ctx.gpu().max_image_side())?;
    let (exact_ms, exact) = plan_frames(ctx, &exact_plan, &scene)?;
    progress(&format!(
        "rolling shutter: grid {BANDS_GRID}², the warp and the vertex path, camera still"
    ));
    let mut rows = vec![json!({
        "grid": format!("{BANDS_GRID}²"),
        "path": "bands",
        "bands": 0,
        "colour_mad": still_colour_mad(ctx, &camera, &scene)?,
    })];
    for count in BAND_COUNTS {
        progress(&format!(
            "rolling shutter: grid {BANDS_GRID}², {count} bands"
        ));
        let (ms, rendered) = plan_frames(ctx, &bands_plan(ctx, &camera, top, count)?, &scene)?;
        rows.push(json!({
            "grid": format!("{BANDS_GRID}²"),
            "path": "bands",
            "bands": count,
            "frame_ms": ms,
            "x_exact": ms / exact_ms,
            "error_px": bands_error_px(&camera, &scene, top, count),
            "colour_mad": colour_mad(&rendered, &exact)?,
        }));
    }
    Ok(rows)
}

/// Per grid, the global path, then the exact path with its ratio to it.
fn global_and_exact(ctx: &Context, progress: &mut dyn FnMut(&str)) -> Result<Vec<Value>> {
    let camera = camera()?;
    let (_, end) = pan();
    let mut rows = Vec::new();
    for n in GRIDS {
        let scene = builtin::grid(n);
        progress(&format!(
            "rolling shutter: grid {n}², global shutter and exact per vertex, frames alternating"
        ));
        let global = vertex_plan(ctx, &camera, None)?;
        let exact = vertex_plan(ctx, &camera, Some((Readout::TopToBottom, end)))?;
        let [global, exact] = alternating_ms(ctx, [&global, &exact], &scene)?;
        let quads = format!("{n}²");
        rows.push(json!({"grid": quads, "path": "global", "frame_ms": global}));
        rows.push(json!({
            "grid": quads,
            "path": "exact",
            "frame_ms": exact,
            "x_global": exact / global,
        }));
    }
    Ok(rows)
}

/// The rows as Markdown tables: the global and exact paths, then the bands.
pub fn table(rows: &[Value]) -> String {
    let mut out = String::from(
        "| grid (quads, 800×600) | shutter | frame ms | × global |\n|---|---|---:|---:|\n",
    );
    let (bands, rows): (Vec<&Value>, Vec<&Value>) = rows.iter().partition(|r| r["path"] == "bands");
    for r in rows {
        let path = match r["path"].as_str() {
            Some("exact") => "rolling, exact per vertex",
            Some("global") => "global",
            _ => "?",
        };
        out.push_str(&format!(
            "| {} | {path} | {} | {} |\n",
            r["grid"].as_str().unwrap_or("?"),
            f(r, "frame_ms", 1),
            f(r, "x_global", 2),
        ));
    }
    if !bands.is_empty() {
        out.push_str(
            "\n| grid (quads, 800×600) | bands | frame ms | × exact | geometric error px | colour MAD (levels) |\n|---|---:|---:|---:|---:|---:|\n",
        );
        for r in bands {
            out.push_str(&format!(
                "| {} | {} | {} | {} | {} | {} |\n",
                r["grid"].as_str().unwrap_or("?"),
                match r["bands"].as_u64() {
                    Some(0) => "camera still (floor)".to_string(),
                    Some(k) => k.to_string(),
                    None => "?".into(),
                },
                f(r, "frame_ms", 1),
                f(r, "x_exact", 2),
                f(r, "error_px", 3),
                f(r, "colour_mad", 2),
            ));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_puts_the_bands_under_the_exact_and_global_rows() {
        let rows = [
            json!({"grid": "128²", "path": "global", "frame_ms": 11.5}),
            json!({"grid": "128²", "path": "exact", "frame_ms": 29.2, "x_global": 2.53}),
            json!({"grid": "128²", "path": "bands", "bands": 0, "colour_mad": 1.94}),
            json!({"grid": "128²", "path": "bands", "bands": 16, "frame_ms": 218.6,
                   "x_exact": 5.48, "error_px": 2.895, "colour_mad": 3.16}),
        ];
        let t = table(&rows);
        assert!(
            t.contains("| 128² | rolling, exact per vertex | 29.2 | 2.53 |"),
            "{t}"
        );
        assert!(
            t.contains("| 128² | camera still (floor) | — | — | — | 1.94 |"),
            "{t}"
        );
        assert!(
            t.contains("| 128² | 16 | 218.6 | 5.48 | 2.895 | 3.16 |"),
            "{t}"
        );
        assert!(!t.contains('?'), "{t}");
    }
}
