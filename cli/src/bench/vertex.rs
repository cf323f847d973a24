//! `vklens bench vertex`: the geometry path's cost and error (Lambers et al. Sec. 3.4's
//! "computational complexity" and first limitation; a seed-002 Table I analogue):
//!
//! * **paths** — textured grids of 8², 128² and 512² quads at 800×600 and 1920×1080: Alg. 1
//!   (vertex shader + Sec. 3.2's discard, by compute dispatches and by a geometry shader)
//!   beside a plain pinhole render of the same scene (the peer, × columns) and beside pinhole render + compute warp (analytic Newton, and a precomputed
//!   map): vertex cost grows with geometry, warp cost with pixels — where they cross;
//! * **tessellation** — what splitting edges to L px costs in triangles and time, and the
//!   straight-line error it leaves (the largest distance between a rendered edge, straight
//!   between its moved vertices, and the true curved image of that edge);
//! * **mesh_warp** — the Durham radial-correction paper's n×n grid warp (n = 8 … 512): its coordinate error against
//!   the f64 model and its time, beside the compute warp on the same image.
//!
//! Times are GPU work per frame recorded back to back (median of batches, see
//! [`super::warp`]); errors are in output pixels.

use super::{fixed as f, sci as e};
use ash::vk;
use glam::DVec2;
use serde_json::{json, Value};

use super::warp::{bench_camera, test_source, time_batch};
use vklens::gpu::Result;
use vklens::host::warp_images::WarpImages;
use vklens::host::Context;
use vklens::imaging::cpu_warp::Sampling;
use vklens::model::overscan::overscan;
use vklens::model::warp::WarpGeometry;
use vklens::model::{Camera, InverseMethod, OpenCvDistortion};
use vklens::pass::geometry::{
    ColorFormat, Discard, GeometryDesc, GeometryPass, GeometryTargets, MeshBuffers, Outputs,
    Projection, Texture, DEFAULT_DELTA,
};
use vklens::pass::mesh_warp::{MeshWarpOutput, MeshWarpPass, MeshWarpTarget};
use vklens::pass::warp::{Coordinates, PixelFormat, WarpDesc, WarpPass};
use vklens::pass::warp_stage::WarpStage;
pub use vklens::scene::tessellate::straight_line_error;
use vklens::scene::tessellate::tessellate;
use vklens::scene::{builtin, Mesh, Pose, Scene};

/// Sizes of the paths and mesh-warp rows.
pub const SIZES: [(u32, u32); 2] = [(800, 600), (1920, 1080)];
/// Grid meshes (quads per side) of the paths rows.
pub const GRIDS: [u32; 3] = [8, 128, 512];
/// Tessellation edge lengths (px) measured on the 8×8 grid.
pub const EDGES: [Option<f64>; 4] = [None, Some(32.0), Some(8.0), Some(2.0)];
/// Mesh-warp grid sizes.
pub const MESH_SIZES: [u32; 4] = [8, 32, 128, 512];

/// GPU-resident render of `mesh`: the pass, its targets and buffers, uploaded.
struct Drawn {
    pass: GeometryPass,
    targets: GeometryTargets,
    buffers: MeshBuffers,
}

fn prepare(
    ctx: &Context,
    camera: &Camera,
    projection: Projection,
    scene: &Scene,
    mesh: &Mesh,
    pose: &Pose,
    discard: Discard,
) -> Result<Drawn> {
    let gpu = ctx.gpu();
    let mut desc = GeometryDesc::new(
        camera.clone(),
        projection,
        Outputs::color_only(Some(ColorFormat::Rgba8)),
    );
    desc.discard = discard;
    let mut pass = GeometryPass::new(gpu, desc)?;
    let targets = GeometryTargets::new(gpu, &pass)?;
    let buffers = MeshBuffers::new(gpu, mesh, scene.texture.as_ref())?;
    // SAFETY: no submission using it is pending (`submit` waits on its fence).
    unsafe { pass.bind_mesh(&buffers) };
    // SAFETY: no submission using it is pending (`submit` waits on its fence).
    unsafe { pass.set_frame(pose, pose) }?;
    ctx.submit(|cmd| {
        // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass;
        // `buffers` outlives the submission, which `submit` waits for.
        unsafe { buffers.record_upload(cmd) };
        Ok(())
    })?;
    Ok(Drawn {
        pass,
        targets,
        buffers,
    })
}

fn time_render(ctx: &Context, d: &Drawn) -> Result<f64> {
    // SAFETY: `time_batch` calls the closure only with a buffer `ctx.submit` is recording,
    // outside any render pass, and waits for each submission; `prepare` bound and uploaded
    // the mesh and made the targets for this pass, all kept alive by `d`.
    let (wall, gpu) = time_batch(ctx, &|cmd| unsafe {
        d.pass.record(cmd, &d.targets, &d.buffers)
    })?;
    Ok(gpu.unwrap_or(wall))
}

/// GPU ms per frame of drawing `mesh` with `projection` (colour only) and the default
/// discard.
fn time_scene(
    ctx: &Context,
    camera: &Camera,
    projection: Projection,
    scene: &Scene,
    mesh: &Mesh,
    pose: &Pose,
) -> Result<f64> {
    let drawn = prepare(ctx, camera, projection, scene, mesh, pose, Discard::Auto)?;
    time_render(ctx, &drawn)
}

const LENS: Projection = Projection::Lens {
    delta: DEFAULT_DELTA,
};

/// Pinhole render of the overscanned frustum + compute warp, GPU-resident, per frame (the
/// warp path's [`WarpStage`]).
fn time_pinhole_and_warp(
    ctx: &Context,
    camera: &Camera,
    scene: &Scene,
    pose: &Pose,
    coordinates: Coordinates,
) -> Result<f64> {
    let invalid = |e: String| vklens::Error::Input(e);
    let ov = overscan(camera, 1.0).map_err(|e| invalid(e.to_string()))?;
    let source = Camera::new(
        ov.width,
        ov.height,
        ov.intrinsics,
        OpenCvDistortion::default(),
    )
    .map_err(|e| invalid(e.to_string()))?;
    let geometry = WarpGeometry::distort(camera.clone(), InverseMethod::Newton)
        .with_ideal(ov.intrinsics, (ov.width, ov.height))
        .map_err(|e| invalid(e.to_string()))?;
    let gpu = ctx.gpu();
    let mut stage = WarpStage::new(
        gpu,
        source,
        geometry,
        coordinates,
        ColorFormat::Rgba8,
        [0.0; 4],
    )?;
    let mesh = MeshBuffers::new(gpu, &scene.mesh, scene.texture.as_ref())?;
    // SAFETY: no submission using it is pending (`submit` waits on its fence).
    unsafe { stage.pass.bind_mesh(&mesh) };
    // SAFETY: no submission using it is pending (`submit` waits on its fence).
    unsafe { stage.pass.set_frame(pose, pose) }?;
    ctx.submit(|cmd| {
        // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass, on
        // the context's graphics+compute queue; `stage` is new, so nothing using its images is
        // pending; `mesh` and `stage` outlive the submission, which `submit` waits for.
        unsafe {
            mesh.record_upload(cmd);
            stage.record_prepare(cmd);
        }
        Ok(())
    })?;
    // SAFETY: `time_batch` calls the closure only with a buffer `ctx.submit` is recording,
    // outside any render pass, and waits for each submission; `record_prepare` ran above and
    // `mesh` is bound to the stage's pass and uploaded.
    let (wall, gpu_ms) = time_batch(ctx, &|cmd| unsafe { stage.record(cmd, &mesh) })?;
    Ok(gpu_ms.unwrap_or(wall))
}

/// Rounds of the paths rows: each round times the plain render, the compute discard and the
/// geometry shader one after the other, and the × columns are the medians of each round's
/// ratios, so that a drift of the machine's speed between measurements (±30 % on the 2-core
/// machine) moves numerator and denominator together.
pub const ROUNDS: usize = 5;

/// The cheapest lens Alg. 1 can apply (k1 k2 only), beside the 14-term [`bench_camera`]: what
/// the model's terms cost, against what evaluating any model per vertex costs.
fn radial_camera(w: u32, h: u32) -> Camera {
    let c = bench_camera(w, h);
    Camera::from_coeffs(w, h, c.intrinsics, &[-0.12, 0.04, 0.0, 0.0])
        .expect("a k1 k2 camera with the bench intrinsics is valid")
}

/// The median of `v` (NaN when empty).
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// Times the plain pinhole render, Alg. 1 with the compute discard and (where the device has
/// one) with the geometry shader on `scene` through `camera`, interleaved over [`ROUNDS`]
/// rounds: (median ms of each, median ratio to the pinhole of each, smallest and largest
/// ratio of the compute discard).
fn time_paths(ctx: &Context, camera: &Camera, scene: &Scene, pose: &Pose) -> Result<Value> {
    let mesh = &scene.mesh;
    let mut drawn = vec![
        prepare(
            ctx,
            camera,
            Projection::Pinhole,
            scene,
            mesh,
            pose,
            Discard::Auto,
        )?,
        prepare(ctx, camera, LENS, scene, mesh, pose, Discard::Compute)?,
    ];
    if ctx.gpu().supports_geometry_shader() {
        drawn.push(prepare(
            ctx,
            camera,
            LENS,
            scene,
            mesh,
            pose,
            Discard::GeometryShader,
        )?);
    }
    let mut ms = vec![Vec::new(); drawn.len()];
    let mut ratios = vec![Vec::new(); drawn.len()];
    for _ in 0..ROUNDS {
        let t = drawn
            .iter()
            .map(|d| time_render(ctx, d))
            .collect::<Result<Vec<f64>>>()?;
        for (k, &tk) in t.iter().enumerate() {
            ms[k].push(tk);
            ratios[k].push(tk / t[0]);
        }
    }
    let spread = |r: &[f64]| {
        let lo = r.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = r.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        [lo, hi]
    };
    let compute_spread = spread(&ratios[1]);
    let mut ms = ms.into_iter().map(median);
    let mut ratios = ratios.into_iter().map(median);
    Ok(json!({
        "pinhole_ms": ms.next(), "vertex_ms": ms.next(), "vertex_gs_ms": ms.next(),
        "vertex_x_pinhole": ratios.nth(1), "vertex_gs_x_pinhole": ratios.next(),
        "vertex_x_pinhole_range": compute_spread,
        "vertex_discard": Discard::Compute.name(), "rounds": ROUNDS,
    }))
}

/// Runs every row; `progress` hears each.
pub fn run(
    ctx: &Context,
    sizes: &[(u32, u32)],
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<Value>> {
    let mut rows = Vec::new();
    for &(w, h) in sizes {
        for n in GRIDS {
            let scene = builtin::grid(n);
            // The k1 k2 lens where the per-vertex pass is large against the draw.
            let lenses: &[(&str, Camera)] = if n >= 128 {
                &[
                    ("14 terms", bench_camera(w, h)),
                    ("k1 k2", radial_camera(w, h)),
                ]
            } else {
                &[("14 terms", bench_camera(w, h))]
            };
            for (lens, camera) in lenses {
                progress(&format!("paths: {w}×{h}, grid {n}×{n}, {lens}"));
                let pose = scene.default_pose(camera);
                let mut row = time_paths(ctx, camera, &scene, &pose)?;
                let pinhole_ms = row["pinhole_ms"].as_f64().unwrap_or(f64::NAN);
                let (warp_ms, map_ms) = if *lens == "14 terms" {
                    (
                        Some(time_pinhole_and_warp(
                            ctx,
                            camera,
                            &scene,
                            &pose,
                            Coordinates::Analytic,
                        )?),
                        Some(time_pinhole_and_warp(
                            ctx,
                            camera,
                            &scene,
                            &pose,
                            Coordinates::Map,
                        )?),
                    )
                } else {
                    (None, None)
                };
                let fields = json!({
                    "bench": "vertex", "kind": "paths", "width": w, "height": h,
                    "grid": n, "triangles": scene.mesh.triangle_count(),
                    "vertices": scene.mesh.vertices.len(), "lens": lens,
                    "pinhole_warp_analytic_ms": warp_ms, "pinhole_warp_map_ms": map_ms,
                    "warp_map_x_pinhole": map_ms.map(|m| m / pinhole_ms),
                    "straight_line_error_px": straight_line_error(camera, &pose, &scene.mesh),
                });
                if let (Some(row), Some(fields)) = (row.as_object_mut(), fields.as_object()) {
                    row.extend(fields.clone());
                }
                rows.push(row);
            }
        }
    }
    // Tessellation on the coarse grid at the first size.
    let (w, h) = sizes[0];
    let camera = bench_camera(w, h);
    let scene = builtin::grid(8);
    let pose = scene.default_pose(&camera);
    let pinhole_ms = time_scene(
        ctx,
        &camera,
        Projection::Pinhole,
        &scene,
        &scene.mesh,
        &pose,
    )?;
    for edge in EDGES {
        progress(&format!("tessellation: {w}×{h}, L = {edge:?}"));
        let mesh = match edge {
            Some(l) => tessellate(&scene.mesh, &pose, &camera, l)?,
            None => scene.mesh.clone(),
        };
        let ms = time_scene(ctx, &camera, LENS, &scene, &mesh, &pose)?;
        rows.push(json!({
            "bench": "vertex", "kind": "tessellation", "width": w, "height": h,
            "max_edge_px": edge, "triangles": mesh.triangle_count(),
            "vertex_ms": ms, "pinhole_ms": pinhole_ms, "vertex_x_pinhole": ms / pinhole_ms,
            "straight_line_error_px": straight_line_error(&camera, &pose, &mesh),
        }));
    }
    // The Durham radial-correction paper's mesh warp beside the compute warp.
    for &(w, h) in sizes {
        let camera = bench_camera(w, h);
        let geometry = WarpGeometry::distort(camera.clone(), InverseMethod::Newton);
        let source = test_source(w, h);
        // Exact coordinates on a sample of pixels (about 40,000).
        let stride = ((w as usize * h as usize / 40_000) as f64).sqrt().max(1.0) as u32;
        let exact: Vec<(u32, u32, Option<DVec2>)> = (0..h)
            .step_by(stride as usize)
            .flat_map(|y| (0..w).step_by(stride as usize).map(move |x| (x, y)))
            .map(|(x, y)| {
                (
                    x,
                    y,
                    geometry.source_coordinate(DVec2::new(x as f64, y as f64), 1),
                )
            })
            .collect();
        let gpu = ctx.gpu();
        let texture = Texture::new(gpu, &source)?;
        ctx.submit(|cmd| {
            // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass;
            // `texture` outlives the submission, which `submit` waits for.
            unsafe { texture.record_upload(cmd) };
            Ok(())
        })?;
        for n in MESH_SIZES {
            progress(&format!("mesh warp: {w}×{h}, {n}×{n}"));
            let coords = vklens::host::mesh_warp::run_mesh_warp(
                ctx,
                &geometry,
                n,
                MeshWarpOutput::Coordinates,
                &source,
            )?;
            let (mut worst, mut sum, mut count, mut uncovered) = (0f64, 0f64, 0usize, 0usize);
            for &(x, y, e) in &exact {
                let m = coords.rgba_f32((y * w + x) as usize);
                match e {
                    Some(e) if m[3] > 0.5 => {
                        let d = DVec2::new(m[0] as f64, m[1] as f64).distance(e);
                        worst = worst.max(d);
                        sum += d;
                        count += 1;
                    }
                    Some(_) => uncovered += 1,
                    None => {}
                }
            }
            let mut pass = MeshWarpPass::new(
                gpu,
                &geometry,
                n,
                MeshWarpOutput::Image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            )?;
            // SAFETY: no submission using it is pending (`submit` waits on its fence).
            unsafe { pass.bind(texture.image.view) };
            let target = MeshWarpTarget::new(gpu, &pass)?;
            let (wall, gpu_ms) =
                // SAFETY: `time_batch` calls the closure only with a buffer `ctx.submit` is
                // recording, outside any render pass, and waits for each submission; the source
                // is bound, and its upload (a completed submission above) left it in
                // SHADER_READ_ONLY_OPTIMAL, visible to fragment shaders; `target` fits `pass`.
                time_batch(ctx, &|cmd| unsafe { pass.record(cmd, &target.framebuffer) })?;
            rows.push(json!({
                "bench": "vertex", "kind": "mesh_warp", "width": w, "height": h, "n": n,
                "ms": gpu_ms.unwrap_or(wall), "max_err_px": worst,
                "mean_err_px": sum / count.max(1) as f64,
                "uncovered_px_sampled": uncovered,
            }));
        }
        // The compute warp on the same image, for comparison.
        for (name, coordinates) in [
            ("analytic", Coordinates::Analytic),
            ("map", Coordinates::Map),
        ] {
            let desc = WarpDesc {
                geometry: geometry.clone(),
                coordinates,
                sampling: Sampling::Bilinear,
                border: vklens::Border::Constant,
                format: PixelFormat::Rgba8,
                fill: [0.0; 4],
                write_mask: false,
            };
            let images = WarpImages::new(gpu, &desc, &source)?;
            let mut pass = WarpPass::new(gpu, desc)?;
            // SAFETY: no submission using it is pending (`submit` waits on its fence).
            unsafe { pass.bind(images.source.view, images.output.view, images.mask.view) };
            ctx.submit(|cmd| {
                // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render
                // pass, on a compute queue; `pass` is new and bound above, so no prepare of it
                // is pending; `images` and `pass` outlive the submission, which `submit` waits for.
                unsafe {
                    images.record_upload(cmd);
                    pass.record_prepare(cmd);
                }
                Ok(())
            })?;
            // SAFETY: `time_batch` calls the closure only with a buffer `ctx.submit` is
            // recording, outside any render pass, and waits for each submission; the upload
            // and `record_prepare` above left the images in GENERAL, the source visible to compute.
            let (wall, gpu_ms) = time_batch(ctx, &|cmd| unsafe { pass.record(cmd) })?;
            rows.push(json!({
                "bench": "vertex", "kind": "compute_warp", "width": w, "height": h,
                "coordinates": name, "ms": gpu_ms.unwrap_or(wall),
            }));
        }
    }
    Ok(rows)
}

/// The rows as Markdown tables.
pub fn table(rows: &[Value]) -> String {
    let kind = |k: &'static str| rows.iter().filter(move |r| r["kind"] == k);
    let mut out = String::from(
        "Paths (GPU ms per frame, medians of the rounds; × = median over the rounds of the ratio to \
         the plain pinhole render of the same scene, timed in the same round; vertex = Alg. 1 \
         with Sec. 3.2's discard by compute dispatches, and by a geometry shader)\n\n\
         | size | grid | lens | triangles | pinhole | vertex, compute discard | × | × range | vertex, geometry shader | × | pinhole + warp, analytic | pinhole + warp, map | × | straight-line error px |\n\
         |---|---:|---|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in kind("paths") {
        let range = r["vertex_x_pinhole_range"]
            .as_array()
            .map(|v| {
                let x = |i: usize| v.get(i).and_then(|x| x.as_f64()).unwrap_or(f64::NAN);
                format!("{:.2}–{:.2}", x(0), x(1))
            })
            .unwrap_or_default();
        out.push_str(&format!(
            "| {}×{} | {}² | {} | {} | {} | {} | {} | {range} | {} | {} | {} | {} | {} | {} |\n",
            r["width"],
            r["height"],
            r["grid"],
            r["lens"].as_str().unwrap_or(""),
            r["triangles"],
            f(r, "pinhole_ms", 2),
            f(r, "vertex_ms", 2),
            f(r, "vertex_x_pinhole", 2),
            f(r, "vertex_gs_ms", 2),
            f(r, "vertex_gs_x_pinhole", 2),
            f(r, "pinhole_warp_analytic_ms", 2),
            f(r, "pinhole_warp_map_ms", 2),
            f(r, "warp_map_x_pinhole", 2),
            e(r, "straight_line_error_px"),
        ));
    }
    out.push_str(
        "\nTessellation of the 8² grid (Alg. 1 needs fine geometry)\n\n\
         | size | max edge L px | triangles | vertex ms | × pinhole | straight-line error px |\n\
         |---|---:|---:|---:|---:|---:|\n",
    );
    for r in kind("tessellation") {
        let l = r["max_edge_px"]
            .as_f64()
            .map(|v| format!("{v}"))
            .unwrap_or_else(|| "none".into());
        out.push_str(&format!(
            "| {}×{} | {l} | {} | {} | {} | {} |\n",
            r["width"],
            r["height"],
            r["triangles"],
            f(r, "vertex_ms", 2),
            f(r, "vertex_x_pinhole", 2),
            e(r, "straight_line_error_px"),
        ));
    }
    out.push_str(
        "\nMesh warp (the Durham radial-correction paper Sec. II-B) beside the compute warp\n\n\
         | size | warp | ms | max coord err px | mean coord err px |\n|---|---|---:|---:|---:|\n",
    );
    for r in rows {
        match r["kind"].as_str() {
            Some("mesh_warp") => out.push_str(&format!(
                "| {}×{} | mesh {}×{} | {} | {} | {} |\n",
                r["width"],
                r["height"],
                r["n"],
                r["n"],
                f(r, "ms", 2),
                e(r, "max_err_px"),
                e(r, "mean_err_px"),
            )),
            Some("compute_warp") => out.push_str(&format!(
                "| {}×{} | compute, {} | {} | — | — |\n",
                r["width"],
                r["height"],
                r["coordinates"].as_str().unwrap_or(""),
                f(r, "ms", 2),
            )),
            _ => {}
        }
    }
    out
}
