//! The rolling-shutter study `vklens bench rolling-shutter` runs and the planner's tests check:
//! a k1 k2 lens at 800×600 panning 7° and stepping 12 cm sideways during its readout, drawn
//! exactly per vertex and approximated by the warp route in bands of lines
//! (`model::rolling_shutter::bands`), with the colour difference between the two.

use glam::DVec3;

use crate::host::plan::execute;
use crate::imaging::{Pixels, Rendered};
use crate::model::rolling_shutter::bands::{band_error_px, distance_range};
use crate::model::rolling_shutter::{FrameMotion, Readout};
use crate::model::{Camera, Intrinsics, InverseMethod};
use crate::pass::geometry::DEFAULT_DELTA;
use crate::plan::{PathChoice, Plan, ReadoutSource, RenderRequest, Shutter};
use crate::scene::{Pose, Scene};
use crate::{Error, Result};

use super::Context;

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

/// The median of `times`.
pub fn median(mut times: Vec<f64>) -> Result<f64> {
    times.sort_by(f64::total_cmp);
    times
        .get(times.len() / 2)
        .copied()
        .ok_or_else(|| Error::internal("a frame per index expected"))
}

/// The exact vertex path's colour request for `camera` through the pan, read in `readout`
/// order.
pub fn exact_request(camera: &Camera, readout: Readout) -> RenderRequest {
    let (start, end) = pan();
    let mut request = RenderRequest::color(
        camera,
        PathChoice::Vertex {
            delta: DEFAULT_DELTA,
            tessellate: None,
        },
    );
    request.pose = start;
    request.previous_pose = start;
    request.rolling_shutter = Some((readout, end));
    request
}

/// The warp route's plan for `camera` through the pan, read in `readout` order, in `count`
/// bands of lines (Newton per pixel, density 1); `count` 1 is one render from the mid-frame
/// pose.
pub fn bands_plan(ctx: &Context, camera: &Camera, readout: Readout, count: u32) -> Result<Plan> {
    let (start, end) = pan();
    let mut request = RenderRequest::color(
        camera,
        PathChoice::Warp {
            method: InverseMethod::Newton,
            density: 1.0,
        },
    );
    request.pose = start;
    request.previous_pose = start;
    let mut plan = Plan::from_request(&request, ctx.gpu().max_image_side())?;
    plan.shutter = Shutter::Moving {
        readout,
        from: ReadoutSource::Request,
        frame: 0,
    };
    plan.end_poses = vec![end];
    plan.bands = Some(count);
    Ok(plan)
}

/// The bands' geometric error (px) for `camera` through the pan, read in `readout` order, over
/// `scene`'s distances, as the planner measures it.
pub fn bands_error_px(camera: &Camera, scene: &Scene, readout: Readout, count: u32) -> f64 {
    let (start, end) = pan();
    let motion = FrameMotion::new(start.into(), end.into());
    let points = scene.mesh.vertices.iter().map(|v| v.position());
    distance_range(camera, &motion, points).map_or(0.0, |range| {
        band_error_px(camera, &motion, readout, count, range)
    })
}

/// Mean absolute difference of two 8-bit colour images (levels, over R, G, B of every pixel).
pub fn colour_mad(a: &Rendered, b: &Rendered) -> Result<f64> {
    let pixels = |r: &Rendered| match r.color.as_ref().map(|c| &c.pixels) {
        Some(Pixels::Rgba8(p)) => Ok(p.clone()),
        _ => Err(Error::internal("an 8-bit colour image expected")),
    };
    let (a, b) = (pixels(a)?, pixels(b)?);
    if a.len() != b.len() || a.is_empty() {
        return Err(Error::internal("colour images of different sizes"));
    }
    let sum: f64 = a
        .iter()
        .zip(&b)
        .flat_map(|(p, q)| (0..3).map(move |c| (f64::from(p[c]) - f64::from(q[c])).abs()))
        .sum();
    Ok(sum / (3 * a.len()) as f64)
}

/// The colour the warp and the vertex path leave apart for a camera that does not move (the
/// first pose of the pan, the global shutter): the floor under the bands' difference from the
/// exact path, from the warp's resampling of its pinhole source against the vertex path's
/// raster (8-bit levels, as [`colour_mad`]).
pub fn still_colour_mad(ctx: &Context, camera: &Camera, scene: &Scene) -> Result<f64> {
    let mut vertex = exact_request(camera, Readout::TopToBottom);
    vertex.rolling_shutter = None;
    let mut warp = bands_plan(ctx, camera, Readout::TopToBottom, 1)?;
    (warp.shutter, warp.end_poses, warp.bands) = (Shutter::Global, Vec::new(), None);
    let max = ctx.gpu().max_image_side();
    let (_, a) = plan_frames(ctx, &Plan::from_request(&vertex, max)?, scene)?;
    let (_, b) = plan_frames(ctx, &warp, scene)?;
    colour_mad(&a, &b)
}

/// Frames each row's time is the median of: on lavapipe with two cores a single frame's wall
/// time scatters by a third from one to the next (thread wake-ups, the allocator), and the
/// ratio of two paths by more.
pub const FRAMES: usize = 9;

/// Median wall-clock ms of [`FRAMES`] frames of `plan` after a warm-up, and the last frame.
pub fn plan_frames(ctx: &Context, plan: &Plan, scene: &Scene) -> Result<(f64, Rendered)> {
    let mut times = Vec::new();
    let mut last = None;
    execute(ctx, plan, scene, [0; FRAMES], &mut |frame| {
        times.push(frame.ms);
        last = Some(frame.rendered);
        Ok(())
    })?;
    let rendered = last.ok_or_else(|| Error::internal("a frame per index expected"))?;
    Ok((median(times)?, rendered))
}
