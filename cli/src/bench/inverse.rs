//! `vklens bench inverse`: for each inverse method and iteration count, on the CPU (f64) and
//! the GPU (f32 and f64), the max and median error in pixels and the time per point, on the
//! shared reference cameras — beside the errors of OpenCV's own `undistortPoints` (default 5
//! iterations and 200 iterations) from the reference file.
//!
//! Errors are measured on the reference points whose true ideal position lies inside the valid
//! domain, as pixel distance to the truth; "refused" counts such points an inverse declared
//! invalid. CPU time is wall time over repeated passes; GPU time is from timestamps over
//! back-to-back dispatches of a large batch, so the per-dispatch overhead is amortised.

use std::time::Instant;
use vklens::{Error, Result};

use ash::vk;
use glam::DVec2;
use gpu_allocator::MemoryLocation;
use serde::{Deserialize, Serialize};

use vklens::gpu::{global_barrier, host_read_barrier, Access, Buffer, QueryPool};
use vklens::host::Context;
use vklens::io::reference::{ReferenceCase, ReferenceFile};
use vklens::model::{Camera, CameraModel, InverseMethod};
use vklens::pass::{PointsMode, PointsPass, Precision};

/// The methods measured by default.
pub fn default_methods() -> Vec<InverseMethod> {
    let mut m = vec![InverseMethod::Newton, InverseMethod::Heikkila];
    m.extend([1, 2, 3, 5, 10, 20, 50, 200].map(InverseMethod::FixedPoint));
    m
}

/// One row of the table (one JSON line with `--json`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct InverseRow {
    /// Always `inverse`; read back (`vklens bench all --from`), whatever the line says.
    #[serde(skip_deserializing, default = "bench_name")]
    pub bench: &'static str,
    pub camera: String,
    pub method: String,
    /// `cpu-f64`, `gpu-f32`, `gpu-f64`, or `opencv` (numbers from the reference file).
    pub backend: String,
    pub max_err_px: f64,
    pub median_err_px: f64,
    /// In-domain points the method refused (declared invalid).
    pub refused: usize,
    /// In-domain points measured.
    pub points: usize,
    /// Time per point in nanoseconds (None for the OpenCV reference rows).
    pub ns_per_point: Option<f64>,
}

fn bench_name() -> &'static str {
    "inverse"
}

/// What to measure.
#[derive(Debug, Clone)]
pub struct InverseBenchOptions {
    pub methods: Vec<InverseMethod>,
    /// GPU precisions to measure (empty: CPU only).
    pub gpu: Vec<Precision>,
    /// Points per GPU dispatch (the reference points repeated).
    pub gpu_batch: usize,
    /// Dispatches timed back to back.
    pub gpu_repeats: u32,
}

impl Default for InverseBenchOptions {
    fn default() -> Self {
        InverseBenchOptions {
            methods: default_methods(),
            gpu: vec![Precision::F32, Precision::F64],
            gpu_batch: 1 << 18,
            gpu_repeats: 4,
        }
    }
}

struct Truth {
    pixels: Vec<[f64; 2]>,
    truth: Vec<DVec2>,
    in_domain: Vec<bool>,
}

fn truth_of(case: &ReferenceCase, cam: &Camera) -> Truth {
    let truth: Vec<DVec2> = case
        .points
        .iter()
        .map(|p| DVec2::from(p.undistorted_normalized))
        .collect();
    Truth {
        pixels: case.points.iter().map(|p| p.distorted_pixel).collect(),
        in_domain: truth
            .iter()
            .map(|&t| cam.ideal_in_domain(cam.intrinsics.to_pixel(t)))
            .collect(),
        truth,
    }
}

/// (max, median, refused, measured) of results against the truth, in pixels.
fn stats(cam: &Camera, t: &Truth, got: &[Option<DVec2>]) -> (f64, f64, usize, usize) {
    let mut errors = Vec::new();
    let mut refused = 0;
    for ((truth, inside), g) in t.truth.iter().zip(&t.in_domain).zip(got) {
        if !inside {
            continue;
        }
        match g {
            Some(x) => {
                let d = *x - *truth;
                errors.push(DVec2::new(d.x * cam.intrinsics.fx, d.y * cam.intrinsics.fy).length());
            }
            None => refused += 1,
        }
    }
    let measured = errors.len() + refused;
    errors.sort_by(f64::total_cmp);
    let max = errors.last().copied().unwrap_or(0.0);
    let median = if errors.is_empty() {
        0.0
    } else {
        errors[errors.len() / 2]
    };
    (max, median, refused, measured)
}

/// Runs the benchmark; `progress` is told what is being measured.
pub fn run(
    reference: &ReferenceFile,
    ctx: Option<&Context>,
    options: &InverseBenchOptions,
    mut progress: impl FnMut(&str),
) -> Result<Vec<InverseRow>> {
    let mut rows = Vec::new();
    for case in &reference.cases {
        let cam = case
            .camera()
            .map_err(|e| Error::input(format!("reference case {}: {e}", case.name)))?;
        let t = truth_of(case, &cam);
        for (label, pick) in [
            ("opencv default (5 it.)", 0usize),
            ("opencv 200 it.", 1usize),
        ] {
            let got: Vec<Option<DVec2>> = case
                .points
                .iter()
                .map(|p| {
                    Some(DVec2::from(if pick == 0 {
                        p.opencv_undistort_default
                    } else {
                        p.opencv_undistort_200_iter
                    }))
                })
                .collect();
            let (max, median, refused, points) = stats(&cam, &t, &got);
            rows.push(InverseRow {
                bench: "inverse",
                camera: case.name.clone(),
                method: label.to_string(),
                backend: "opencv".into(),
                max_err_px: max,
                median_err_px: median,
                refused,
                points,
                ns_per_point: None,
            });
        }
        for &method in &options.methods {
            progress(&format!("{} {method} cpu-f64", case.name));
            let ys: Vec<DVec2> = t
                .pixels
                .iter()
                .map(|p| cam.intrinsics.to_normalized(DVec2::from(*p)))
                .collect();
            let got: Vec<Option<DVec2>> = ys
                .iter()
                .map(|&y| cam.undistort_normalized(y, method))
                .collect();
            let (max, median, refused, points) = stats(&cam, &t, &got);
            // Time: repeat until at least 30 ms have passed.
            let start = Instant::now();
            let mut passes = 0u64;
            let mut sink = 0.0;
            while start.elapsed().as_secs_f64() < 0.03 || passes < 2 {
                for &y in &ys {
                    if let Some(x) = cam.undistort_normalized(std::hint::black_box(y), method) {
                        sink += x.x;
                    }
                }
                passes += 1;
            }
            std::hint::black_box(sink);
            let ns = start.elapsed().as_secs_f64() * 1e9 / (passes as f64 * ys.len() as f64);
            rows.push(InverseRow {
                bench: "inverse",
                camera: case.name.clone(),
                method: method.to_string(),
                backend: "cpu-f64".into(),
                max_err_px: max,
                median_err_px: median,
                refused,
                points,
                ns_per_point: Some(ns),
            });
            if let Some(ctx) = ctx {
                for &precision in &options.gpu {
                    if precision == Precision::F64 && !ctx.gpu().supports_float64() {
                        continue;
                    }
                    progress(&format!("{} {method} gpu-{precision}", case.name));
                    let (got, ns) = gpu_run(ctx, &cam, method, precision, &t.pixels, options)
                        .map_err(|e| Error::input(format!("GPU run failed: {e}")))?;
                    let (max, median, refused, points) = stats(&cam, &t, &got);
                    rows.push(InverseRow {
                        bench: "inverse",
                        camera: case.name.clone(),
                        method: method.to_string(),
                        backend: format!("gpu-{precision}"),
                        max_err_px: max,
                        median_err_px: median,
                        refused,
                        points,
                        ns_per_point: ns,
                    });
                }
            }
        }
    }
    Ok(rows)
}

/// Results for `pixels` and GPU nanoseconds per point over a large batch.
fn gpu_run(
    ctx: &Context,
    cam: &Camera,
    method: InverseMethod,
    precision: Precision,
    pixels: &[[f64; 2]],
    options: &InverseBenchOptions,
) -> vklens::gpu::Result<(Vec<Option<DVec2>>, Option<f64>)> {
    let (raw, ns) = time_points(
        ctx,
        cam,
        PointsMode::Undistort(method),
        precision,
        pixels,
        options.gpu_batch,
        options.gpu_repeats,
    )?;
    let got = raw
        .iter()
        .map(|r| (r[2] > 0.5).then(|| DVec2::new(r[0], r[1])))
        .collect();
    Ok((got, ns))
}

/// Runs the points pass on `inputs` (`mode.inputs_per_point()` per point) repeated to at least
/// `batch` points, and times `repeats` back-to-back dispatches: the raw `vec4` of each of the
/// first points (those `inputs` hold) and the GPU time per point in ns (None where the device
/// has no timestamps).
pub(crate) fn time_points(
    ctx: &Context,
    cam: &Camera,
    mode: PointsMode,
    precision: Precision,
    inputs: &[[f64; 2]],
    batch: usize,
    repeats: u32,
) -> vklens::gpu::Result<(Vec<[f64; 4]>, Option<f64>)> {
    let gpu = ctx.gpu();
    let per = mode.inputs_per_point();
    let points = inputs.len() / per;
    let n = batch.max(points).min(vklens::pass::points::MAX_POINTS);
    let batch: Vec<[f64; 2]> = inputs.iter().cycle().take(n * per).copied().collect();
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let (inputs, out_bytes) = match precision {
        Precision::F32 => {
            let v: Vec<[f32; 2]> = batch.iter().map(|p| [p[0] as f32, p[1] as f32]).collect();
            (Buffer::from_pod(gpu, "bench.in", &v, usage)?, 16)
        }
        Precision::F64 => (Buffer::from_pod(gpu, "bench.in", &batch, usage)?, 32),
    };
    let outputs = Buffer::new(
        gpu,
        "bench.out",
        (n * out_bytes) as u64,
        usage,
        MemoryLocation::GpuToCpu,
    )?;
    let mut pass = PointsPass::new(gpu, cam, mode, precision)?;
    // SAFETY: no submission using it is pending (`submit` waits on its fence).
    unsafe { pass.bind(&inputs, &outputs) };
    // Warm-up run (the driver compiles the pipeline at its first dispatch); its results are
    // the ones checked for accuracy.
    ctx.submit(|cmd| {
        // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass, on
        // a compute queue; `inputs` and `outputs` (bound above) hold `n` points, at most
        // MAX_POINTS, and outlive the submission, which `submit` waits for.
        unsafe {
            pass.record(cmd, n as u32);
            host_read_barrier(gpu, cmd);
        }
        Ok(())
    })?;
    let raw: Vec<[f64; 4]> = match precision {
        Precision::F32 => outputs
            .read_pod::<[f32; 4]>(points)?
            .iter()
            .map(|r| r.map(f64::from))
            .collect(),
        Precision::F64 => outputs.read_pod::<[f64; 4]>(points)?,
    };
    let ns = match QueryPool::timestamps(gpu, 2) {
        Ok(queries) => {
            ctx.submit(|cmd| {
                // SAFETY: `cmd` is the buffer `submit` is recording, outside a render pass; the
                // pool holds these indices and is reset first in this buffer.
                unsafe { queries.cmd_reset(cmd) };
                // SAFETY: `cmd` is the buffer `submit` is recording, outside a render pass; the
                // pool holds these indices and is reset first in this buffer.
                unsafe { queries.cmd_write(cmd, 0) };
                for i in 0..repeats {
                    // SAFETY: as in the warm-up: `cmd` is the fresh buffer `submit` is
                    // recording, outside any render pass, and the bound buffers hold `n` points
                    // and outlive the submission; the barrier orders each dispatch's writes.
                    unsafe {
                        pass.record(cmd, n as u32);
                        if i + 1 < repeats {
                            // Each dispatch rewrites the outputs: order the writes.
                            let write = Access::ComputeWrite;
                            global_barrier(gpu, cmd, write, write);
                        }
                    }
                }
                // SAFETY: `cmd` is the buffer `submit` is recording, outside a render pass; the
                // pool holds these indices and is reset first in this buffer.
                unsafe { queries.cmd_write(cmd, 1) };
                Ok(())
            })?;
            let t = queries.read_ns()?;
            Some((t[1] - t[0]) / (repeats as f64 * n as f64))
        }
        Err(_) => None,
    };
    Ok((raw, ns))
}

/// The rows as one Markdown table: a row per camera and method, max error (median in
/// brackets) and ns/point per backend side by side.
pub fn table(rows: &[InverseRow]) -> String {
    let backends = ["cpu-f64", "gpu-f32", "gpu-f64"];
    let mut out = String::from(
        "| camera | method | cpu-f64 max (median) px | gpu-f32 max (median) px | gpu-f64 max (median) px | refused | ns/pt cpu | ns/pt gpu-f32 | ns/pt gpu-f64 |\n|---|---|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let mut keys: Vec<(&str, &str)> = Vec::new();
    for r in rows {
        if !keys.contains(&(r.camera.as_str(), r.method.as_str())) {
            keys.push((&r.camera, &r.method));
        }
    }
    for (camera, method) in keys {
        let of = |b: &str| {
            rows.iter()
                .find(|r| r.camera == camera && r.method == method && r.backend == b)
        };
        let err = |r: Option<&InverseRow>| {
            r.map(|r| format!("{} ({})", sci(r.max_err_px), sci(r.median_err_px)))
                .unwrap_or_else(|| "—".into())
        };
        let ns = |r: Option<&InverseRow>| {
            r.and_then(|r| r.ns_per_point)
                .map(|n| format!("{n:.0}"))
                .unwrap_or_else(|| "—".into())
        };
        if let Some(o) = of("opencv") {
            out.push_str(&format!(
                "| {camera} | {method} | {} (OpenCV) | | | {}/{} | | | |\n",
                err(Some(o)),
                o.refused,
                o.points
            ));
            continue;
        }
        let refused: Vec<String> = backends
            .iter()
            .filter_map(|b| of(b).map(|r| r.refused.to_string()))
            .collect();
        let points = backends
            .iter()
            .find_map(|b| of(b).map(|r| r.points))
            .unwrap_or(0);
        out.push_str(&format!(
            "| {camera} | {method} | {} | {} | {} | {}/{points} | {} | {} | {} |\n",
            err(of(backends[0])),
            err(of(backends[1])),
            err(of(backends[2])),
            refused.join("·"),
            ns(of(backends[0])),
            ns(of(backends[1])),
            ns(of(backends[2])),
        ));
    }
    out
}

fn sci(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if (1e-2..1e4).contains(&v.abs()) {
        format!("{v:.3}")
    } else {
        format!("{v:.1e}")
    }
}
