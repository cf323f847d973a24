//! `vklens bench lens`: what the image-based lens model's accuracy costs in time (Heidrich et al.
//! Sec. 4's comparison, made systematic). For Heidrich et al.'s pair of lenses (the achromatic
//! doublet and the bi-convex singlet) and the wide-angle lens, on the boxes scene focused on
//! its centre:
//!
//! * **samples** — lens samples 1, 4, 10, 32 at Heidrich et al.'s 0.05° threshold;
//! * **threshold** — largest angle error 0.5°, 0.05°, 0.01°, 0.001° and 0.0002° (one
//!   projection per sample already holds the shipped lenses to about 0.001° — 1 % of a
//!   pixel — so only the last two split cells);
//! * **grid** — film grid 5², 10², 20² per cell.
//!
//! Each row: projections per frame, the preprocessing (tracing and fitting) time, the GPU
//! frame time (median of repeated frames, all submissions included), the CPU reference ray
//! tracer's time at the same samples and resolution, their ratio, the PSNR of the GPU frame
//! against that reference (the model's own error) and against a 128-sample reference (what
//! few lens samples cost: depth-of-field noise).

use std::time::Instant;

use super::fixed as f;
use serde_json::{json, Value};

use vklens::gpu::{Error, Result};
use vklens::host::Context;
use vklens::lens::image_model::{ImageModel, ModelOptions, ALL_CHANNELS};
use vklens::lens::reference::{psnr, render_reference, Channel, ReferenceFrame};
use vklens::lens::{frame_scene, Prescription, LAMBDA_D};
use vklens::pass::geometry::MeshBuffers;
use vklens::pass::lens_render::{LensRenderOptions, LensRenderer};
use vklens::scene::builtin;

/// The lenses measured (files under `lenses/`).
pub const LENSES: [&str; 3] = ["achromat.50mm.dat", "biconvex.50mm.dat", "wide.22mm.dat"];
pub const SAMPLES: [u32; 4] = [1, 4, 10, 32];
pub const THRESHOLDS: [f64; 5] = [0.5, 0.05, 0.01, 0.001, 0.0002];
pub const GRIDS: [u32; 3] = [5, 10, 20];

/// Lens samples of the converged reference (the error of few samples, not of the model).
pub const CONVERGED_SAMPLES: u32 = 128;

/// Film: 24 × 24 mm at `pixels` × `pixels` (Heidrich et al. timed 256 × 256).
pub const FILM_MM: f64 = 24.0;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Runs every row. `lens_dir` holds the lens files.
pub fn run(
    ctx: &Context,
    lens_dir: &std::path::Path,
    pixels: u32,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<Value>> {
    let scene = builtin::boxes();
    let mesh = MeshBuffers::new(ctx.gpu(), &scene.mesh, scene.texture.as_ref())?;
    ctx.submit(|cmd| {
        // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass;
        // `mesh` outlives the submission, which `submit` waits for.
        unsafe { mesh.record_upload(cmd) };
        Ok(())
    })?;
    let invalid = Error::Input;
    let mut rows = Vec::new();
    for name in LENSES {
        let lens = Prescription::load(&lens_dir.join(name)).map_err(|e| invalid(e.to_string()))?;
        let pitch = FILM_MM / pixels as f64;
        let (optics, pose) = frame_scene(&lens, (pixels, pixels), pitch, None, None, None, &scene)
            .map_err(|e| invalid(e.to_string()))?;
        // The references, one per sample count (shared by the rows that use it).
        let mut references: Vec<(u32, ReferenceFrame)> = Vec::new();
        let mut reference =
            |samples: u32, progress: &mut dyn FnMut(&str)| -> Result<ReferenceFrame> {
                if let Some((_, r)) = references.iter().find(|(s, _)| *s == samples) {
                    return Ok(r.clone());
                }
                progress(&format!("{name}: reference ray tracing, {samples} samples"));
                let r = render_reference(
                    &optics,
                    &[Channel {
                        lambda_um: LAMBDA_D,
                        mask: ALL_CHANNELS,
                    }],
                    samples,
                    &scene,
                    &pose,
                    &|_| {},
                )
                .map_err(|e| invalid(e.to_string()))?;
                references.push((samples, r.clone()));
                Ok(r)
            };
        let mut configs: Vec<(&str, ModelOptions)> = Vec::new();
        let base = ModelOptions::default();
        for s in SAMPLES {
            configs.push(("samples", ModelOptions { samples: s, ..base }));
        }
        for t in THRESHOLDS {
            configs.push((
                "threshold",
                ModelOptions {
                    max_angle_deg: t,
                    ..base
                },
            ));
        }
        for g in GRIDS {
            configs.push(("grid", ModelOptions { grid: g, ..base }));
        }
        for (kind, options) in configs {
            progress(&format!(
                "{name}: {kind} — {} samples, {}°, grid {}",
                options.samples, options.max_angle_deg, options.grid
            ));
            let start = Instant::now();
            let model = ImageModel::build(&optics, &options).map_err(|e| invalid(e.to_string()))?;
            let preprocess_ms = start.elapsed().as_secs_f64() * 1e3;
            let max_angle = model.max_angle_deg();
            let mut renderer = LensRenderer::new(
                ctx.gpu(),
                &[(model, ALL_CHANNELS)],
                LensRenderOptions::default(),
            )?;
            let mut times = Vec::new();
            let mut frame = renderer.render(ctx, &mesh, &pose)?; // warm-up
            for _ in 0..3 {
                frame = renderer.render(ctx, &mesh, &pose)?;
                times.push(frame.frame_ms);
            }
            let gpu_ms = median(times);
            let r = reference(options.samples, progress)?;
            let converged = reference(CONVERGED_SAMPLES, progress)?;
            rows.push(json!({
                "kind": kind,
                "lens": name,
                "pixels": pixels,
                "samples": options.samples,
                "max_angle_threshold_deg": options.max_angle_deg,
                "grid": options.grid,
                "projections": frame.projections,
                "max_angle_deg": max_angle,
                "preprocess_ms": preprocess_ms,
                "gpu_frame_ms": gpu_ms,
                "reference_s": r.seconds,
                "speedup": r.seconds * 1e3 / gpu_ms,
                "psnr_db": psnr(&frame.pixels, &r.pixels),
                "psnr_converged_db": psnr(&frame.pixels, &converged.pixels),
                "device": ctx.gpu().device_name(),
            }));
        }
    }
    Ok(rows)
}

/// Markdown tables, one per sweep.
pub fn table(rows: &[Value]) -> String {
    let mut out = String::new();
    for (kind, title) in [
        ("samples", "Lens samples (threshold 0.05°, grid 10²)"),
        ("threshold", "Angle threshold (10 samples, grid 10²)"),
        ("grid", "Film grid per cell (10 samples, threshold 0.05°)"),
    ] {
        out.push_str(&format!(
            "{title}\n\n\
             | lens | samples | threshold ° | grid | projections | max angle ° | preprocess ms | GPU frame ms | reference s | × faster | PSNR dB | PSNR dB vs 128 samples |\n\
             |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n"
        ));
        for r in rows.iter().filter(|r| r["kind"] == kind) {
            out.push_str(&format!(
                "| {} | {} | {} | {}² | {} | {} | {} | {} | {} | {} | {} | {} |\n",
                r["lens"].as_str().unwrap_or(""),
                r["samples"],
                r["max_angle_threshold_deg"],
                r["grid"],
                r["projections"],
                f(r, "max_angle_deg", 4),
                f(r, "preprocess_ms", 1),
                f(r, "gpu_frame_ms", 1),
                f(r, "reference_s", 2),
                f(r, "speedup", 1),
                f(r, "psnr_db", 1),
                f(r, "psnr_converged_db", 1),
            ));
        }
        out.push('\n');
    }
    out
}
