//! `vklens bench wide`: lenses past what one pinhole frustum holds, at 1920×1080 — a 180° and
//! a 200° fisheye and a GoPro-like standard lens — through every path that can render them:
//!
//! * **vertex** — Alg. 1 with the lens's own forward model per vertex (past 90° for the
//!   fisheyes), the room scene of 6 × 32² quads seen from its centre;
//! * **warp** — a pinhole render of the overscanned frustum, then the compute warp: only where
//!   that source fits the device (never for the fisheyes: they see 90° and more);
//! * **cube** — six 90° pinhole faces of the side [`cube_face_side`] gives for density 1 (one
//!   face pixel per output pixel where faces sample most coarsely and the lens most finely),
//!   then the sphere warp.
//!
//! Each row has the frame time (wall clock of one whole render, readback included: median of
//! 3 after a warm-up) as × a plain pinhole render of the same scene at the same size in the
//! same run, and the geometric error of the path's coordinates against the f64 model, in
//! output pixels: the GPU's projected vertices (vertex), the warp's source coordinates
//! (warp, converted from source pixels by the density), the pixel the GPU's ray reprojects to
//! (cube). Bilinear sampling of the source, the same for warp and cube, is not in it.

use glam::{DVec2, DVec3};
use serde_json::{json, Value};

use super::{fixed as f, sci as e};
use vklens::gpu::Result;
use vklens::host::plan::execute;
use vklens::host::points::{run_project, run_unproject};
use vklens::host::Context;
use vklens::model::overscan::{cube_face_side, overscan};
use vklens::model::warp::WarpGeometry;
use vklens::model::{Camera, Fisheye, Intrinsics, InverseMethod};
use vklens::pass::geometry::DEFAULT_DELTA;
use vklens::pass::Precision;
use vklens::plan::limits::pinhole_source_refusal;
use vklens::plan::{PathChoice, Plan, RenderRequest};
use vklens::scene::{builtin, Scene};

/// The output size of every row.
pub const SIZE: (u32, u32) = (1920, 1080);

/// The three cameras: name, camera.
pub fn cameras() -> Vec<(&'static str, Camera)> {
    let (w, h) = SIZE;
    let centre = |fx: f64| Intrinsics {
        fx,
        fy: fx,
        cx: (w as f64 - 1.0) / 2.0,
        cy: (h as f64 - 1.0) / 2.0,
    };
    let fisheye = |fov: f64, k: [f64; 4]| {
        // The image circle of `fov` fills the frame's height.
        let lens = Fisheye::new(k, 0.0, Some(fov)).expect("a valid lens");
        let fx = (h as f64 / 2.0) / lens.theta_d((fov / 2.0).to_radians()).0;
        Camera::fisheye(w, h, centre(fx), lens).expect("a valid camera")
    };
    vec![
        ("fisheye 180°", fisheye(180.0, [0.01, -0.002, 0.0003, 0.0])),
        ("fisheye 200°", fisheye(200.0, [0.02, -0.004, 0.0005, 0.0])),
        (
            "GoPro-like (k1 −0.26)",
            Camera::from_coeffs(w, h, centre(880.0), &[-0.26, 0.072, 0.0, 0.0, -0.0085])
                .expect("a valid camera"),
        ),
    ]
}

/// Median wall-clock ms of three frames (GPU work and readback) after a warm-up, rendered by
/// the plan of `path` on `camera` (the passes built once).
fn frame_ms(ctx: &Context, scene: &Scene, camera: &Camera, path: PathChoice) -> Result<f64> {
    request_frame_ms(ctx, scene, &RenderRequest::color(camera, path))
}

/// Median wall-clock ms of three frames (GPU work and readback) after a warm-up, rendered by
/// the plan of `request` (the passes built once).
pub(super) fn request_frame_ms(
    ctx: &Context,
    scene: &Scene,
    request: &RenderRequest,
) -> Result<f64> {
    let plan = Plan::from_request(request, ctx.gpu().max_image_side())?;
    let mut times = Vec::new();
    execute(ctx, &plan, scene, [0, 0, 0], &mut |frame| {
        times.push(frame.ms);
        Ok(())
    })?;
    times.sort_by(f64::total_cmp);
    times
        .get(1)
        .copied()
        .ok_or_else(|| vklens::Error::internal("three frames expected"))
}

/// Largest distance between the GPU's projection of the scene's vertices and the f64 model's,
/// over the vertices Alg. 1 keeps that land on the image (in the lens's domain; elsewhere
/// the standard model's formula runs off to thousands of pixels, where f32 keeps no digits
/// and nothing is drawn).
fn vertex_error(ctx: &Context, camera: &Camera, scene: &Scene) -> Result<f64> {
    let points: Vec<[f64; 3]> = scene
        .mesh
        .vertices
        .iter()
        .map(|v| v.position().to_array())
        .collect();
    let gpu = run_project(ctx, camera, Precision::F32, &points)?;
    let (w, h) = (camera.width as f64, camera.height as f64);
    let mut worst = 0.0f64;
    for (p, g) in points.iter().zip(gpu) {
        let p = DVec3::from_array(*p);
        let kept = camera.model().is_ray_model()
            || (p.z > 0.0
                && camera
                    .domain()
                    .contains_ideal(glam::DVec2::new(p.x / p.z, p.y / p.z)));
        let Some(want) = camera.project(p).filter(|_| kept) else {
            continue;
        };
        if want.x < -0.5 || want.y < -0.5 || want.x > w - 0.5 || want.y > h - 0.5 {
            continue;
        }
        if let Some(got) = g {
            worst = worst.max((want - DVec2::from(got)).length());
        }
    }
    Ok(worst)
}

/// Largest distance between an output pixel and the f64 projection of the ray the GPU
/// computes for it, over a grid of about 40,000 pixels.
fn ray_error(ctx: &Context, camera: &Camera) -> Result<f64> {
    let (w, h) = (camera.width, camera.height);
    let stride = ((w as usize * h as usize / 40_000) as f64).sqrt().max(1.0) as usize;
    let pixels: Vec<[f64; 2]> = (0..h)
        .step_by(stride)
        .flat_map(|y| (0..w).step_by(stride).map(move |x| [x as f64, y as f64]))
        .collect();
    let rays = run_unproject(ctx, camera, Precision::F32, &pixels)?;
    let mut worst = 0.0f64;
    for (p, r) in pixels.iter().zip(rays) {
        if let Some(back) = r.and_then(|r| camera.project(DVec3::from(r))) {
            worst = worst.max((back - DVec2::from(*p)).length());
        }
    }
    Ok(worst)
}

/// GPU ms per frame of the cube path's two passes, recorded as an engine records them (the
/// faces rendered into the cube on the GPU, then the sphere warp): (faces, warp).
fn cube_pass_ms(ctx: &Context, camera: &Camera, scene: &Scene, side: u32) -> Result<(f64, f64)> {
    use vklens::pass::cube_stage::CubeStage;
    use vklens::pass::geometry::{ColorFormat, MeshBuffers};
    use vklens::pass::sphere_warp::SphereWarpOptions;
    let gpu = ctx.gpu();
    let options = SphereWarpOptions {
        chromatic: None,
        fill: [0.0; 4],
        write_mask: false,
    };
    let stage = CubeStage::new(gpu, camera, side, ColorFormat::Rgba8, &options)?;
    let mesh = MeshBuffers::new(gpu, &scene.mesh, scene.texture.as_ref())?;
    render_cube_faces(ctx, &stage, &mesh)?;
    let gpu_ms = |(wall, gpu): (f64, Option<f64>)| gpu.unwrap_or(wall);
    // SAFETY (both): `time_batch` records only into buffers `ctx.submit` is recording, outside
    // any render pass, and waits for each; the mesh is uploaded and the stage prepared, and
    // the faces' first recording above left the cube ready for the warp.
    let faces = gpu_ms(super::warp::time_batch(ctx, &|cmd| unsafe {
        stage.record_faces(cmd, &mesh)
    })?);
    let warp = gpu_ms(super::warp::time_batch(ctx, &|cmd| unsafe {
        stage.record_warp(cmd)
    })?);
    Ok((faces, warp))
}

/// Uploads `mesh` and renders `stage`'s faces of it (identity pose) into its cube, once: the
/// warps timed after it sample them.
fn render_cube_faces(
    ctx: &Context,
    stage: &vklens::pass::cube_stage::CubeStage,
    mesh: &vklens::pass::geometry::MeshBuffers,
) -> Result<()> {
    // SAFETY: every submission `ctx` made has completed (`submit` waits on its fence), so
    // nothing using the stage is pending.
    unsafe { stage.prepare(mesh, &vklens::scene::Pose::IDENTITY) }?;
    ctx.submit(|cmd| {
        // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass, on
        // the context's graphics and compute queue; the mesh upload precedes the faces that
        // draw it, `record_prepare` the faces and warp; everything outlives the submission,
        // which `submit` waits for.
        unsafe {
            mesh.record_upload(cmd);
            stage.record_prepare(cmd);
            stage.record_faces(cmd, mesh);
        }
        Ok(())
    })?;
    Ok(())
}

/// Runs every row; `progress` hears what is being measured.
pub fn run(ctx: &Context, progress: &mut dyn FnMut(&str)) -> Result<Vec<Value>> {
    let scene = builtin::room();
    let mut rows = Vec::new();
    let max_side = ctx.gpu().max_image_side();
    for (name, camera) in cameras() {
        progress(&format!("{name}: pinhole render (the peer)"));
        let pinhole = frame_ms(ctx, &scene, &camera, PathChoice::Pinhole)?;
        rows.push(json!({"camera": name, "path": "pinhole (peer)", "frame_ms": pinhole, "x_pinhole": 1.0}));

        progress(&format!("{name}: vertex path"));
        let vertex = PathChoice::Vertex {
            delta: DEFAULT_DELTA,
            tessellate: None,
        };
        let ms = frame_ms(ctx, &scene, &camera, vertex)?;
        let err = vertex_error(ctx, &camera, &scene)?;
        rows.push(
            json!({"camera": name, "path": "vertex", "frame_ms": ms, "x_pinhole": ms / pinhole,
            "max_err_px": err, "source": format!("{} triangles", scene.mesh.triangle_count())}),
        );

        match pinhole_source_refusal(&camera, 1.0, max_side) {
            Some(why) => rows.push(json!({"camera": name, "path": "warp", "refused": why})),
            None => {
                progress(&format!("{name}: pinhole overscan + warp"));
                let warp = PathChoice::Warp {
                    method: InverseMethod::Newton,
                    density: 1.0,
                };
                let ms = frame_ms(ctx, &scene, &camera, warp)?;
                let (_, geometry) = WarpGeometry::overscanned(&camera, InverseMethod::Newton, 1.0)
                    .map_err(|e| vklens::gpu::Error::Input(e.to_string()))?;
                let (err, _) = super::warp::coordinate_error(
                    ctx,
                    &geometry,
                    // The exact per-pixel map: the analytic warp's own arithmetic, read back.
                    vklens::pass::warp::Coordinates::Map,
                )?;
                let ov =
                    overscan(&camera, 1.0).map_err(|e| vklens::gpu::Error::Input(e.to_string()))?;
                rows.push(json!({"camera": name, "path": "warp", "frame_ms": ms, "x_pinhole": ms / pinhole,
                    "max_err_px": err, "source": format!("{}×{} pinhole", ov.width, ov.height)}));
            }
        }

        let side = cube_face_side(&camera, 1.0);
        progress(&format!("{name}: cube map ({side}² faces) + sphere warp"));
        let ms = frame_ms(ctx, &scene, &camera, PathChoice::Cube { side })?;
        let err = ray_error(ctx, &camera)?;
        let (faces_ms, warp_ms) = cube_pass_ms(ctx, &camera, &scene, side)?;
        rows.push(
            json!({"camera": name, "path": "cube", "frame_ms": ms, "x_pinhole": ms / pinhole,
            "max_err_px": err, "face_side": side, "source": format!("6 × {side}² faces"),
            "faces_gpu_ms": faces_ms, "warp_gpu_ms": warp_ms,
            "warp_ns_per_pixel": warp_ms * 1e6 / (camera.width as f64 * camera.height as f64)}),
        );
    }
    Ok(rows)
}

/// The rows as a Markdown table.
pub fn table(rows: &[Value]) -> String {
    let mut out = String::from(
        "| camera (1920×1080) | path | source | frame ms | × pinhole | max coord err px | GPU ms: faces + warp |\n|---|---|---|---:|---:|---:|---|\n",
    );
    for r in rows {
        let name = r["camera"].as_str().unwrap_or("?");
        let path = r["path"].as_str().unwrap_or("?");
        if let Some(why) = r["refused"].as_str() {
            out.push_str(&format!(
                "| {name} | {path} | — ({why}) | — | — | — | — |\n"
            ));
            continue;
        }
        let passes = match (r["faces_gpu_ms"].as_f64(), r["warp_gpu_ms"].as_f64()) {
            (Some(a), Some(b)) => format!("{a:.1} + {b:.1}"),
            _ => "—".into(),
        };
        out.push_str(&format!(
            "| {name} | {path} | {} | {} | {} | {} | {passes} |\n",
            r["source"].as_str().unwrap_or("—"),
            f(r, "frame_ms", 1),
            f(r, "x_pinhole", 2),
            e(r, "max_err_px"),
        ));
    }
    out
}
