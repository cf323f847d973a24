//! `vklens bench warp`: what the post-processing warp costs per frame, analytic versus map,
//! with and without chromatic offsets, beside a plain copy pass on the same driver (the floor),
//! and what a full-frame inverse map costs to build — each with its coordinate error against
//! the f64 model.
//!
//! Frame time is wall time over a batch of frames recorded back to back into one command
//! buffer (a barrier between frames, as an engine would have), divided by the batch size, the
//! median of 5 batches; GPU timestamps over the same batches are reported alongside.

use std::time::Instant;

use ash::vk;
use glam::DVec2;
use serde_json::{json, Value};

use super::{fixed, sci};

use vklens::gpu::{global_barrier, Access, QueryPool, Result};
use vklens::host::warp::read_maps;
use vklens::host::warp_images::WarpImages;
use vklens::host::Context;
use vklens::imaging::cpu_warp::Sampling;
use vklens::imaging::{BitDepth, Pixels, Raster};
use vklens::model::warp::WarpGeometry;
use vklens::model::{Camera, Intrinsics, InverseMethod};
use vklens::pass::copy::CopyPass;
use vklens::pass::mesh_warp::MeshWarpTarget;
use vklens::pass::warp::{Coordinates, MapInterpolation, PixelFormat, WarpDesc, WarpPass};
use vklens::pass::warp_raster::RasterWarpPass;

/// The sizes measured by default.
pub const SIZES: [(u32, u32); 3] = [(800, 600), (1920, 1080), (3840, 2160)];

/// The bench camera at a size: the shared `prism_tilt` case (all 14 coefficients) scaled to it.
pub fn bench_camera(w: u32, h: u32) -> Camera {
    let s = w as f64 / 1024.0;
    Camera::from_coeffs(
        w,
        h,
        Intrinsics {
            fx: 800.0 * s,
            fy: 790.0 * s,
            cx: (w as f64 - 1.0) / 2.0,
            cy: (h as f64 - 1.0) / 2.0,
        },
        &[
            -0.12, 0.04, 0.002, -0.001, 0.0, 0.0, 0.0, 0.0, 0.003, -0.0005, -0.002, 0.0004, 0.01,
            -0.015,
        ],
    )
    .expect("valid bench camera")
}

/// Most frames per timed batch.
pub const BATCH: u32 = 20;
/// Batches per measurement (the median is reported; the machine is noisy).
pub const REPEATS: usize = 5;
/// How full-frame inverse maps are built, measured for time and error.
pub const MAP_BUILDS: [(&str, Coordinates); 6] = [
    ("newton", Coordinates::Map),
    ("coarse8+bilinear", coarse(8, 0, MapInterpolation::Bilinear)),
    ("coarse4+bilinear", coarse(4, 0, MapInterpolation::Bilinear)),
    ("coarse8+cubic", coarse(8, 0, MapInterpolation::Cubic)),
    ("coarse16+cubic", coarse(16, 0, MapInterpolation::Cubic)),
    (
        "coarse16+bilinear+newton1",
        coarse(16, 1, MapInterpolation::Bilinear),
    ),
];

const fn coarse(stride: u32, refine: u32, interpolation: MapInterpolation) -> Coordinates {
    Coordinates::CoarseMap {
        stride,
        refine,
        interpolation,
    }
}

/// Lateral colour used for the chromatic rows.
pub const CHROMATIC: [f64; 3] = [1.003, 1.0, 0.997];

pub(crate) fn test_source(w: u32, h: u32) -> Raster {
    let pixels = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            [
                (x * 255 / w) as u8,
                (y * 255 / h) as u8,
                (((x / 16) + (y / 16)) % 2 * 255) as u8,
                255,
            ]
        })
        .collect();
    Raster {
        width: w,
        height: h,
        pixels: Pixels::Rgba8(pixels),
        bit_depth: BitDepth::U8,
    }
}

/// Records `frame` back to back in batches and returns the median over [`REPEATS`] batches of
/// (wall ms, GPU ms) per frame. The batch is sized to about 300 ms from a warm-up frame (which
/// also lets the driver compile the pipeline), between 3 and [`BATCH`] frames.
pub(crate) fn time_batch(
    ctx: &Context,
    frame: &dyn Fn(vk::CommandBuffer),
) -> Result<(f64, Option<f64>)> {
    let gpu = ctx.gpu();
    let queries = QueryPool::timestamps(gpu, 2).ok();
    let write = Access::ComputeWrite;
    let record = |cmd: vk::CommandBuffer, n: u32| {
        for i in 0..n {
            frame(cmd);
            if i + 1 < n {
                // Successive frames write the same output: order them, as an engine would.
                // SAFETY: `record` only runs inside `ctx.submit` below, on the buffer it is
                // recording, and every `frame` leaves no render pass open.
                unsafe { global_barrier(gpu, cmd, write, write) };
            }
        }
    };
    let start = Instant::now();
    ctx.submit(|cmd| {
        record(cmd, 1);
        Ok(())
    })?;
    let estimate = start.elapsed().as_secs_f64() * 1e3;
    let n = ((300.0 / estimate.max(0.01)).round() as u32).clamp(3, BATCH);
    let mut walls = Vec::new();
    let mut gpus = Vec::new();
    for _ in 0..REPEATS {
        let start = Instant::now();
        ctx.submit(|cmd| {
            if let Some(q) = &queries {
                // SAFETY: `cmd` is the buffer `submit` is recording, outside a render pass; the
                // pool holds these indices and is reset first in this buffer.
                unsafe { q.cmd_reset(cmd) };
                // SAFETY: `cmd` is the buffer `submit` is recording, outside a render pass; the
                // pool holds these indices and is reset first in this buffer.
                unsafe { q.cmd_write(cmd, 0) };
            }
            record(cmd, n);
            if let Some(q) = &queries {
                // SAFETY: `cmd` is the buffer `submit` is recording, outside a render pass; the
                // pool holds these indices and is reset first in this buffer.
                unsafe { q.cmd_write(cmd, 1) };
            }
            Ok(())
        })?;
        walls.push(start.elapsed().as_secs_f64() * 1e3 / n as f64);
        if let Some(t) = queries.as_ref().and_then(|q| q.read_ns().ok()) {
            gpus.push((t[1] - t[0]) / 1e6 / n as f64);
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied()
    };
    Ok((median(&mut walls).unwrap_or(f64::NAN), median(&mut gpus)))
}

/// Max distance between GPU map coordinates and the f64 model, over a grid of pixels
/// (about 40,000), in source pixels; sampled pixels that one side calls invalid and the other
/// not are counted separately (a coarse map's conservative validity next to a fold).
pub(crate) fn coordinate_error(
    ctx: &Context,
    g: &WarpGeometry,
    coordinates: Coordinates,
) -> Result<(f64, usize)> {
    let maps = read_maps(ctx, g, coordinates)?;
    let channels: Vec<usize> = if g.is_chromatic() {
        vec![0, 1, 2]
    } else {
        vec![1]
    };
    let (w, h) = g.output_size;
    let stride = ((w as usize * h as usize / 40_000) as f64).sqrt().max(1.0) as u32;
    let (mut worst, mut disagree) = (0.0f64, 0usize);
    for (map, &c) in maps.iter().zip(&channels) {
        for y in (0..h).step_by(stride as usize) {
            for x in (0..w).step_by(stride as usize) {
                let m = map[(y * w + x) as usize];
                let cpu = g.model_coordinate(DVec2::new(x as f64, y as f64), c);
                match (m[0].is_nan(), cpu) {
                    (false, Some(s)) => {
                        worst = worst.max((DVec2::new(m[0] as f64, m[1] as f64) - s).length())
                    }
                    (true, None) => {}
                    _ => disagree += 1,
                }
            }
        }
    }
    Ok((worst, disagree))
}

/// Runs the benchmark at `sizes`; `progress` hears what is being measured. Returns JSON rows,
/// each with `"bench": "warp"` and a `kind`: `copy`, `inverse_map` or `warp`.
pub fn run(
    ctx: &Context,
    sizes: &[(u32, u32)],
    mut progress: impl FnMut(&str),
) -> Result<Vec<Value>> {
    let gpu = ctx.gpu();
    let mut rows = Vec::new();
    for &(w, h) in sizes {
        let cam = bench_camera(w, h);
        let source = test_source(w, h);
        let plain = WarpGeometry::distort(cam.clone(), InverseMethod::Newton);

        progress(&format!("{w}×{h} copy"));
        let desc = |g: &WarpGeometry, coordinates| WarpDesc {
            geometry: g.clone(),
            coordinates,
            sampling: Sampling::Bilinear,
            border: vklens::Border::Constant,
            format: PixelFormat::Rgba8,
            fill: [0.0; 4],
            write_mask: false,
        };
        let images = WarpImages::new(gpu, &desc(&plain, Coordinates::Analytic), &source)?;
        ctx.submit(|cmd| {
            // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass;
            // `images` outlives the submission, which `submit` waits for.
            unsafe { images.record_upload(cmd) };
            Ok(())
        })?;
        let mut copy = CopyPass::new(gpu, w, h)?;
        // SAFETY: no submission using it is pending (`submit` waits on its fence).
        unsafe { copy.bind(images.source.view, images.output.view) };
        // SAFETY: `time_batch` calls the closure only with a buffer `ctx.submit` is recording,
        // outside any render pass, and waits for each submission; the upload above left both
        // bound images in GENERAL with the source's writes visible to compute.
        let (frame_ms, _) = time_batch(ctx, &|cmd| unsafe { copy.record(cmd) })?;
        rows.push(
            json!({"bench": "warp", "kind": "copy", "width": w, "height": h, "frame_ms": frame_ms}),
        );

        // Full-frame inverse maps: exact per pixel, or coarse + interpolation (+ Newton).
        for (label, coordinates) in MAP_BUILDS {
            progress(&format!("{w}×{h} inverse map {label}"));
            let mut build = WarpPass::new(gpu, desc(&plain, coordinates))?;
            // SAFETY: no submission using it is pending (`submit` waits on its fence).
            unsafe { build.bind(images.source.view, images.output.view, images.mask.view) };
            // A map build is a once-per-camera cost: time single builds (median of 3) after a
            // warm-up build.
            let mut times = Vec::new();
            for _ in 0..4 {
                let start = Instant::now();
                ctx.submit(|cmd| {
                    // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render
                    // pass, on a compute queue; the previous build's submission has completed
                    // (`submit` waits), so none is pending when it is recorded again.
                    unsafe { build.record_prepare(cmd) };
                    Ok(())
                })?;
                times.push(start.elapsed().as_secs_f64() * 1e3);
            }
            times.remove(0);
            times.sort_by(f64::total_cmp);
            let (map_err, map_disagree) = coordinate_error(ctx, &plain, coordinates)?;
            rows.push(json!({"bench": "warp", "kind": "inverse_map", "width": w, "height": h, "method": label, "ms": times[1], "max_err_px": map_err, "disagreeing_px": map_disagree, "per_pixel_check": build.coarse_map_checked()}));
        }

        for chromatic in [false, true] {
            let g = if chromatic {
                plain
                    .clone()
                    .with_chromatic(CHROMATIC)
                    .expect("valid scales")
            } else {
                plain.clone()
            };
            let (err, _) = coordinate_error(ctx, &g, Coordinates::Map)?;
            for (label, coordinates) in [
                ("analytic", Coordinates::Analytic),
                ("map", Coordinates::Map),
            ] {
                progress(&format!(
                    "{w}×{h} {label}{}",
                    if chromatic { " chromatic" } else { "" }
                ));
                let pass = prepared_pass(ctx, desc(&g, coordinates), &images)?;
                // SAFETY: `time_batch` calls the closure only with a buffer `ctx.submit` is
                // recording, outside any render pass, and waits for each submission; the
                // images were uploaded and the pass prepared and bound above.
                let (frame_ms, gpu_ms) = time_batch(ctx, &|cmd| unsafe { pass.record(cmd) })?;
                rows.push(json!({
                    "bench": "warp", "kind": "warp", "width": w, "height": h, "method": label, "chromatic": chromatic,
                    "frame_ms": frame_ms, "gpu_ms": gpu_ms, "max_err_px": err,
                }));
                if coordinates.uses_map() {
                    // The same map warp as a fragment shader over a full-screen triangle.
                    progress(&format!(
                        "{w}×{h} map_raster{}",
                        if chromatic { " chromatic" } else { "" }
                    ));
                    let mut raster =
                        RasterWarpPass::new(gpu, &pass, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)?;
                    // SAFETY: no submission using it is pending (`submit` waits on its fence).
                    unsafe { raster.bind(images.source.view) };
                    let target = MeshWarpTarget::for_render_pass(
                        gpu,
                        &raster.render_pass,
                        (w, h),
                        raster.format,
                    )?;
                    // SAFETY: `time_batch` calls the closure only with a buffer `ctx.submit` is
                    // recording, outside any render pass, and waits for each submission;
                    // `target` fits the raster pass, which is bound to the source. Caveat:
                    // `record` wants the maps and source visible to fragment-shader reads, but
                    // the barriers that wrote them (upload, `record_prepare`) name only the
                    // compute stage, and unlike `run_raster_warp` no fragment barrier follows.
                    let (frame_ms, gpu_ms) = time_batch(ctx, &|cmd| unsafe {
                        raster.record(cmd, &target.framebuffer)
                    })?;
                    rows.push(json!({
                        "bench": "warp", "kind": "warp", "width": w, "height": h, "method": "map_raster", "chromatic": chromatic,
                        "frame_ms": frame_ms, "gpu_ms": gpu_ms, "max_err_px": err,
                    }));
                }
            }
        }

        // What the interpolation and border choices cost over the default map warp: the same
        // map and source, only the sampling differs.
        for (label, sampling, border) in FILTERS {
            progress(&format!("{w}×{h} {label}"));
            let filtered = WarpDesc {
                sampling,
                border,
                ..desc(&plain, Coordinates::Map)
            };
            let pass = prepared_pass(ctx, filtered, &images)?;
            // SAFETY: as for the map warp above: images uploaded, pass prepared and bound.
            let (frame_ms, gpu_ms) = time_batch(ctx, &|cmd| unsafe { pass.record(cmd) })?;
            let (err, _) = coordinate_error(ctx, &plain, Coordinates::Map)?;
            rows.push(json!({
                "bench": "warp", "kind": "warp", "width": w, "height": h, "method": label, "chromatic": false,
                "frame_ms": frame_ms, "gpu_ms": gpu_ms, "max_err_px": err,
            }));
        }
    }
    Ok(rows)
}

/// A warp pass bound to `images` with its one-off work (maps, layouts) done.
fn prepared_pass(ctx: &Context, desc: WarpDesc, images: &WarpImages) -> Result<WarpPass> {
    let mut pass = WarpPass::new(ctx.gpu(), desc)?;
    // SAFETY: no submission using it is pending (`submit` waits on its fence).
    unsafe { pass.bind(images.source.view, images.output.view, images.mask.view) };
    ctx.submit(|cmd| {
        // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass, on
        // a compute queue; `pass` is new, so no prepare of it is pending.
        unsafe { pass.record_prepare(cmd) };
        Ok(())
    })?;
    Ok(pass)
}

/// The map warp with other interpolations and borders than bilinear and constant.
const FILTERS: [(&str, Sampling, vklens::Border); 3] = [
    ("map nearest", Sampling::Nearest, vklens::Border::Constant),
    ("map bicubic", Sampling::Bicubic, vklens::Border::Constant),
    ("map reflect", Sampling::Bilinear, vklens::Border::Reflect),
];

/// The ms of a row: a map build's single build, every other kind's frame.
pub(crate) fn row_ms(r: &Value) -> Option<f64> {
    match r["kind"].as_str() {
        Some("inverse_map") => r["ms"].as_f64(),
        _ => r["frame_ms"].as_f64(),
    }
}

/// The row of `kind` at the size of `r` (the copy floor, or the OpenCV peer).
pub(crate) fn same_size<'a>(rows: &'a [Value], kind: &str, r: &Value) -> Option<&'a Value> {
    rows.iter()
        .find(|x| x["kind"] == kind && x["width"] == r["width"] && x["height"] == r["height"])
}

/// The rows as a Markdown table, with each pass's ratio to the copy pass of its size. Where
/// the rows hold OpenCV's times at a size (`kind` `opencv`, from `cli/benches/warp_vs_opencv.py`),
/// two columns more: the ratio to `cv2.remap` and `cv2.undistortPoints`'s time over it.
pub fn table(rows: &[Value]) -> String {
    let peers = rows.iter().any(|r| r["kind"] == "opencv");
    let mut out =
        String::from("| size | pass | chromatic | frame ms | GPU ms | × copy | max coord err px |");
    if peers {
        out.push_str(" × cv2.remap | cv2.undistortPoints ÷ this |");
    }
    out.push_str("\n|---|---|---|---:|---:|---:|---:|");
    if peers {
        out.push_str("---:|---:|");
    }
    out.push('\n');
    let ratio = |a: Option<f64>, b: Option<f64>| match (a, b) {
        (Some(a), Some(b)) if b > 0.0 => format!("{:.2}", a / b),
        _ => "—".into(),
    };
    for r in rows {
        let size = format!("{}×{}", r["width"], r["height"]);
        let pass = match r["kind"].as_str() {
            Some("copy") => "copy (floor)".to_string(),
            Some("inverse_map") => format!(
                "inverse map build, {} (once; {} px invalid only here)",
                r["method"].as_str().unwrap_or(""),
                r["disagreeing_px"]
            ),
            Some("warp") => format!("warp, {}", r["method"].as_str().unwrap_or("")),
            _ => continue,
        };
        let chromatic = match r["kind"].as_str() {
            Some("warp") if r["chromatic"] == true => "yes",
            Some("warp") => "no",
            _ => "—",
        };
        let ms = row_ms(r);
        let copy = same_size(rows, "copy", r).and_then(|c| c["frame_ms"].as_f64());
        out.push_str(&format!(
            "| {size} | {pass} | {chromatic} | {} | {} | {} | {} |",
            ms.map_or("—".into(), |v| format!("{v:.2}")),
            fixed(r, "gpu_ms", 2),
            ratio(ms, copy),
            sci(r, "max_err_px"),
        ));
        if peers {
            let peer = same_size(rows, "opencv", r);
            let remap = peer.and_then(|p| p["remap_ms"].as_f64());
            let undistort = peer.and_then(|p| p["undistort_points_ms"].as_f64());
            out.push_str(&format!(
                " {} | {} |",
                ratio(ms, remap),
                ratio(undistort, ms)
            ));
        }
        out.push('\n');
    }
    if let Some(p) = rows.iter().find(|r| r["kind"] == "opencv") {
        out.push_str(&format!(
            "\nOpenCV {} ({} threads), same run: `cv2.remap` with precomputed CV_32FC1 maps, linear, \
             RGBA8; `cv2.undistortPoints` over every pixel, 5 iterations.\n\n\
             | size | cv2.remap ms | cv2.undistortPoints ms |\n|---|---:|---:|\n",
            p["opencv"].as_str().unwrap_or("?"),
            p["threads"],
        ));
        for r in rows.iter().filter(|r| r["kind"] == "opencv") {
            out.push_str(&format!(
                "| {}×{} | {} | {} |\n",
                r["width"],
                r["height"],
                fixed(r, "remap_ms", 2),
                fixed(r, "undistort_points_ms", 0),
            ));
        }
    }
    out
}
