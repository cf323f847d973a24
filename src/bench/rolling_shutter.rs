//! `vklens bench rolling-shutter`: what drawing a moving rolling shutter exactly costs. The
//! vertex path that solves each vertex's readout time (`glsl/include/rolling_shutter.glsl`)
//! against the global shutter's vertex path, the same scene, camera and first pose in the same
//! run: grids of 128² and 512² quads through a k1 k2 lens at 800×600, the camera panning 7°
//! and stepping 12 cm sideways during a top-to-bottom readout.
//!
//! Each row has the frame time (wall clock of one whole render, readback included: median of
//! 3 after a warm-up), and the exact path's rows its ratio to the global path's.

use glam::DVec3;
use serde_json::{json, Value};

use super::fixed as f;
use crate::host::Context;
use crate::model::rolling_shutter::Readout;
use crate::model::{Camera, Intrinsics};
use crate::pass::geometry::DEFAULT_DELTA;
use crate::plan::{PathChoice, RenderRequest};
use crate::scene::{builtin, Pose, Scene};
use crate::Result;

/// Grid meshes (quads per side).
pub const GRIDS: [u32; 2] = [128, 512];

/// The camera of every row.
pub fn camera() -> Result<Camera> {
    let k = Intrinsics {
        fx: 400.0,
        fy: 400.0,
        cx: 399.5,
        cy: 299.5,
    };
    Ok(Camera::from_coeffs(800, 600, k, &[-0.11, 0.02, 0.0, 0.0])?)
}

/// The poses when the first and the last line are read.
pub fn pan() -> (Pose, Pose) {
    let start = Pose::look_at(
        DVec3::new(-0.06, 0.0, -1.6),
        DVec3::new(-0.1, 0.0, 0.0),
        DVec3::Y,
    );
    let end = Pose::look_at(
        DVec3::new(0.06, 0.02, -1.6),
        DVec3::new(0.12, 0.0, 0.0),
        DVec3::Y,
    );
    (start, end)
}

/// Median wall-clock ms of three frames after a warm-up, with `rolling_shutter` as the request
/// gives it (`None`: the global shutter).
fn frame_ms(
    ctx: &Context,
    scene: &Scene,
    camera: &Camera,
    rolling_shutter: Option<(Readout, Pose)>,
) -> Result<f64> {
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
    super::wide::request_frame_ms(ctx, scene, &request)
}

/// Every row: per grid, the global path, then the exact path with its ratio to it.
pub fn run(ctx: &Context, progress: &mut dyn FnMut(&str)) -> Result<Vec<Value>> {
    let camera = camera()?;
    let (_, end) = pan();
    let mut rows = Vec::new();
    for n in GRIDS {
        let scene = builtin::grid(n);
        progress(&format!("rolling shutter: grid {n}², global shutter"));
        let global = frame_ms(ctx, &scene, &camera, None)?;
        progress(&format!("rolling shutter: grid {n}², exact per vertex"));
        let exact = frame_ms(ctx, &scene, &camera, Some((Readout::TopToBottom, end)))?;
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

/// The rows as a Markdown table.
pub fn table(rows: &[Value]) -> String {
    let mut out = String::from(
        "| grid (quads, 800×600) | shutter | frame ms | × global |\n|---|---|---:|---:|\n",
    );
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
    out
}
