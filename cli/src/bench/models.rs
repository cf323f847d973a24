//! `vklens bench models`: for every model of the table (one realistic sample each,
//! `model::samples`), what it costs and how exact it is, beside OpenCV's standard model in the
//! same run: the CPU's forward map and inverse (ns per point, and the round trip's error), the
//! GPU's points pass in f32 (ns per point, error against the f64 model), and the GPU time of
//! the inverse over a 1920×1080 grid of pixels (the per-pixel work a warp does), as ratios to
//! the standard model. Where a file carries a fit of the inverse (f-theta's non-reference
//! polynomial, OCamCalib's `inverse_poly`), the fit's error against the exact inverse is
//! measured too, and the same camera evaluating that fit (`fitted_inverse`) has its own row:
//! what the fit saves in time beside what it costs in pixels.

use std::time::Instant;

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use crate::bench::inverse::time_points;
use vklens::host::Context;
use vklens::model::samples::{fitted_inverse_cameras, sample_cameras};
use vklens::model::table::RayModel;
use vklens::model::{Camera, Lens};
use vklens::pass::{PointsMode, Precision};
use vklens::Result;

/// One row (one JSON line with `--json`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ModelRow {
    /// Always `models`; read back (`vklens bench all --from`), whatever the line says.
    #[serde(skip_deserializing, default = "bench_name")]
    pub bench: &'static str,
    pub camera: String,
    pub model: String,
    /// CPU forward map, ns per point.
    pub cpu_forward_ns: f64,
    /// CPU inverse, ns per pixel.
    pub cpu_inverse_ns: f64,
    /// Forward then inverse then forward: the worst pixel error (f64).
    pub round_trip_px: f64,
    /// GPU f32 forward against the f64 model, worst pixel error on the image.
    pub gpu_forward_px: Option<f64>,
    /// GPU f32 inverse, the f64 pixel of its ray against the pixel.
    pub gpu_inverse_px: Option<f64>,
    /// GPU f32 forward, ns per point.
    pub gpu_forward_ns: Option<f64>,
    /// GPU f32 inverse over a 1920×1080 grid, ms per frame.
    pub gpu_map_1080p_ms: Option<f64>,
    /// `gpu_map_1080p_ms` over the standard model's in the same run.
    pub map_ratio: Option<f64>,
    /// The file's fit of the inverse against the exact one (px), where the model has one.
    pub fit_error_px: Option<f64>,
}

fn bench_name() -> &'static str {
    "models"
}

/// Directions over the domain (for the forward map) and a pixel grid over the image.
fn samples(camera: &Camera) -> (Vec<DVec3>, Vec<DVec2>) {
    let max = camera.lens().max_angle() * 0.999;
    let mut rays = Vec::new();
    for i in 0..=40 {
        let t = max * i as f64 / 40.0;
        for j in 0..32 {
            let phi = std::f64::consts::TAU * j as f64 / 32.0;
            let p = DVec3::new(t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos());
            let in_domain = camera.model().is_ray_model()
                || (p.z > 0.0
                    && camera
                        .domain()
                        .contains_ideal(DVec2::new(p.x / p.z, p.y / p.z)));
            if in_domain {
                rays.push(p);
            }
        }
    }
    let (w, h) = (camera.width as f64, camera.height as f64);
    let mut pixels = Vec::new();
    for j in 0..=30 {
        for i in 0..=40 {
            pixels.push(DVec2::new(
                i as f64 / 40.0 * (w - 1.0),
                j as f64 / 30.0 * (h - 1.0),
            ));
        }
    }
    (rays, pixels)
}

fn on_image(camera: &Camera, p: DVec2) -> bool {
    p.x >= -0.5
        && p.y >= -0.5
        && p.x <= camera.width as f64 - 0.5
        && p.y <= camera.height as f64 - 0.5
}

/// ns per call of `f` over `items`, repeated until 20 ms have passed.
fn cpu_ns<T>(items: &[T], mut f: impl FnMut(&T)) -> f64 {
    let start = Instant::now();
    let mut calls = 0usize;
    while start.elapsed().as_millis() < 20 || calls == 0 {
        for x in items {
            f(x);
        }
        calls += items.len();
    }
    start.elapsed().as_nanos() as f64 / calls as f64
}

/// The worst error (px of pixel distance) over the domain of the fitted inverse a file
/// carries, against the exact inverse: f-theta's non-reference polynomial against the solved
/// reference, OCamCalib's `inverse_poly` against the exact root of its `cam2world`.
fn fit_error(camera: &Camera) -> Option<f64> {
    if let Lens::Ocam(o) = camera.lens() {
        if o.inverse_poly.is_empty() {
            return None;
        }
        let max = o.max_angle() * 0.999;
        let worst = (1..=200)
            .filter_map(|i| {
                let angle = max * i as f64 / 200.0;
                Some((o.approximate_radius(angle) - o.radius_of(angle)?).abs())
            })
            .fold(0.0, f64::max);
        return Some(worst);
    }
    let Lens::FTheta(f) = camera.lens() else {
        return None;
    };
    let max = f.max_angle() * 0.999;
    let mut worst = 0.0f64;
    for i in 1..=200 {
        let theta = max * i as f64 / 200.0;
        let Some(exact) = f.distance(theta) else {
            continue;
        };
        let err = match f.reference {
            // The fit is fw: its distance against the exact one.
            vklens::model::ftheta::Reference::PixeldistToAngle => {
                (f.approximate_distance(theta) - exact).abs()
            }
            // The fit is bw: the distance of its angle against the pixel distance it was given.
            vklens::model::ftheta::Reference::AngleToPixeldist => {
                let Some(back) = f.distance(f.approximate_angle(exact)) else {
                    continue;
                };
                (back - exact).abs()
            }
        };
        worst = worst.max(err);
    }
    Some(worst)
}

/// Measures every sample camera (the GPU columns where `ctx` is given).
pub fn run(ctx: Option<&Context>, progress: impl Fn(&str)) -> Result<Vec<ModelRow>> {
    let mut cameras = sample_cameras()?;
    cameras.extend(fitted_inverse_cameras()?);
    let total = cameras.len();
    let mut rows = Vec::new();
    for (k, (name, camera)) in cameras.into_iter().enumerate() {
        progress(&format!("model {}/{total}: {name}", k + 1));
        let (rays, pixels) = samples(&camera);
        let cpu_forward_ns = cpu_ns(&rays, |p| {
            std::hint::black_box(camera.project(*p));
        });
        let cpu_inverse_ns = cpu_ns(&pixels, |p| {
            std::hint::black_box(camera.unproject(*p));
        });
        let mut round_trip_px = 0.0f64;
        for p in &rays {
            let Some(px) = camera.project(*p) else {
                continue;
            };
            if !on_image(&camera, px) {
                continue;
            }
            if let Some(again) = camera.unproject(px).and_then(|r| camera.project(r)) {
                round_trip_px = round_trip_px.max((again - px).length());
            }
        }
        let mut row = ModelRow {
            bench: "models",
            camera: name.to_string(),
            model: camera.model_name().to_string(),
            cpu_forward_ns,
            cpu_inverse_ns,
            round_trip_px,
            gpu_forward_px: None,
            gpu_inverse_px: None,
            gpu_forward_ns: None,
            gpu_map_1080p_ms: None,
            map_ratio: None,
            fit_error_px: fit_error(&camera),
        };
        if let Some(ctx) = ctx {
            let inputs: Vec<[f64; 2]> =
                rays.iter().flat_map(|p| [[p.x, p.y], [p.z, 0.0]]).collect();
            let (raw, ns) = time_points(
                ctx,
                &camera,
                PointsMode::Project,
                Precision::F32,
                &inputs,
                1 << 18,
                4,
            )?;
            let mut worst = 0.0f64;
            for (p, r) in rays.iter().zip(&raw) {
                if let (Some(want), true) = (camera.project(*p), r[2] > 0.5) {
                    if on_image(&camera, want) {
                        worst = worst.max((DVec2::new(r[0], r[1]) - want).length());
                    }
                }
            }
            row.gpu_forward_px = Some(worst);
            row.gpu_forward_ns = ns;
            let grid: Vec<[f64; 2]> = pixels.iter().map(|p| [p.x, p.y]).collect();
            let frame = 1920 * 1080;
            let (raw, ns) = time_points(
                ctx,
                &camera,
                PointsMode::Unproject,
                Precision::F32,
                &grid,
                frame,
                2,
            )?;
            let mut worst = 0.0f64;
            for (px, r) in pixels.iter().zip(&raw) {
                if r[2] > 0.5 {
                    // Against the f64 ray's pixel: the pixel itself, but where the camera
                    // evaluates a fit of its inverse (whose own error is the last column).
                    let want = camera.unproject(*px).and_then(|ray| camera.project(ray));
                    if let (Some(back), Some(want)) =
                        (camera.project(DVec3::new(r[0], r[1], r[3])), want)
                    {
                        worst = worst.max((back - want).length());
                    }
                }
            }
            row.gpu_inverse_px = Some(worst);
            row.gpu_map_1080p_ms = ns.map(|ns| ns * frame as f64 / 1e6);
        }
        rows.push(row);
    }
    let standard = rows
        .iter()
        .find(|r| r.model == "opencv")
        .and_then(|r| r.gpu_map_1080p_ms);
    for r in rows.iter_mut() {
        r.map_ratio = r.gpu_map_1080p_ms.zip(standard).map(|(a, b)| a / b);
    }
    Ok(rows)
}

/// The rows as one Markdown table.
pub fn table(rows: &[ModelRow]) -> String {
    let opt = |v: Option<f64>, d: usize| v.map_or("—".to_string(), |x| format!("{x:.d$}"));
    let sci = |v: Option<f64>| v.map_or("—".to_string(), |x| format!("{x:.1e}"));
    let mut out = String::from(
        "| camera | model | CPU forward ns | CPU inverse ns | round trip px | GPU f32 forward px | GPU f32 inverse px | GPU forward ns | 1080p inverse ms | × standard | fit of the inverse px |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        out.push_str(&format!(
            "| {} | {} | {:.0} | {:.0} | {:.1e} | {} | {} | {} | {} | {} | {} |\n",
            r.camera,
            r.model,
            r.cpu_forward_ns,
            r.cpu_inverse_ns,
            r.round_trip_px,
            sci(r.gpu_forward_px),
            sci(r.gpu_inverse_px),
            opt(r.gpu_forward_ns, 1),
            opt(r.gpu_map_1080p_ms, 1),
            opt(r.map_ratio, 2),
            sci(r.fit_error_px),
        ));
    }
    out
}
