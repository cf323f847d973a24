//! `vklens points distort|undistort`.

use std::io::{Read, Write};
use std::path::Path;

use glam::DVec2;
use serde_json::Value;

use super::{context, finish, load_camera, Backend, CliError};
use crate::headless::points::run_points;
use crate::model::InverseMethod;
use crate::pass::{PointsMode, Precision};

/// Most points accepted on stdin (a 16k × 16k image worth).
const MAX_POINTS: usize = 1 << 28;

/// Reads `[[a, b], ...]` from stdin; errors name the element.
fn read_points() -> Result<Vec<[f64; 2]>, CliError> {
    let mut text = String::new();
    std::io::stdin()
        .read_to_string(&mut text)
        .map_err(|e| CliError::input(format!("stdin: cannot read: {e}")))?;
    parse_points(&text)
}

/// Parses a JSON array of `[a, b]` pairs.
pub fn parse_points(text: &str) -> Result<Vec<[f64; 2]>, CliError> {
    let value: Value = serde_json::from_str(text)
        .map_err(|e| CliError::input(format!("stdin: not valid JSON: {e}")))?;
    let items = value
        .as_array()
        .ok_or_else(|| CliError::input("stdin: expected a JSON array of [x, y] pairs"))?;
    if items.len() > MAX_POINTS {
        return Err(CliError::input(format!(
            "stdin: at most {MAX_POINTS} points, got {}",
            items.len()
        )));
    }
    items
        .iter()
        .enumerate()
        .map(|(i, item)| {
            let pair = item.as_array().filter(|a| a.len() == 2).ok_or_else(|| {
                CliError::input(format!(
                    "stdin: element {i} must be a pair [x, y], got {item}"
                ))
            })?;
            let a = pair[0].as_f64();
            let b = pair[1].as_f64();
            match (a, b) {
                (Some(a), Some(b)) => Ok([a, b]),
                _ => Err(CliError::input(format!(
                    "stdin: element {i} must hold two numbers, got {item}"
                ))),
            }
        })
        .collect()
}

fn write_results(results: &[Option<[f64; 2]>]) -> Result<(), CliError> {
    let json: Vec<Value> = results
        .iter()
        .map(|r| match r {
            Some([a, b]) if a.is_finite() && b.is_finite() => serde_json::json!([a, b]),
            _ => Value::Null,
        })
        .collect();
    let mut out = std::io::stdout().lock();
    serde_json::to_writer(&mut out, &json)
        .and_then(|_| writeln!(out).map_err(serde_json::Error::io))
        .map_err(|e| CliError::io(std::path::Path::new("<stdout>"), "cannot write", &e.into()))
}

/// Runs the points pass on a headless context, checking validation messages when enabled.
fn on_gpu(
    cam: &crate::model::Camera,
    mode: PointsMode,
    precision: Precision,
    points: &[[f64; 2]],
) -> Result<Vec<Option<[f64; 2]>>, CliError> {
    let ctx = context()?;
    let r = run_points(&ctx, cam, mode, precision, points)?;
    finish(&ctx)?;
    Ok(r)
}

/// `points distort`: normalized ideal points → distorted pixels.
pub fn distort(camera: &Path, backend: Backend, precision: Precision) -> Result<(), CliError> {
    let cam = load_camera(camera)?;
    let points = read_points()?;
    let results = match backend {
        Backend::Cpu => points
            .iter()
            .map(|p| {
                cam.distort_normalized(DVec2::from(*p))
                    .map(|y| cam.intrinsics.to_pixel(y).to_array())
            })
            .collect(),
        Backend::Gpu => on_gpu(&cam, PointsMode::Distort, precision, &points)?,
    };
    write_results(&results)
}

/// `points undistort`: distorted pixels → normalized ideal points, null outside the domain.
pub fn undistort(
    camera: &Path,
    method: InverseMethod,
    backend: Backend,
    precision: Precision,
) -> Result<(), CliError> {
    let cam = load_camera(camera)?;
    let points = read_points()?;
    let results = match backend {
        Backend::Cpu => points
            .iter()
            .map(|p| {
                cam.undistort_normalized(cam.intrinsics.to_normalized(DVec2::from(*p)), method)
                    .map(|x| x.to_array())
            })
            .collect(),
        Backend::Gpu => on_gpu(&cam, PointsMode::Undistort(method), precision, &points)?,
    };
    write_results(&results)
}
