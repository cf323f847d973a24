//! `vklens points distort|undistort|project`.

use std::io::{Read, Write};
use std::path::Path;

use glam::DVec2;
use serde_json::Value;

use super::{context, finish, load_camera, Backend, CliError};
use vklens::host::points::{run_points, run_project, run_unproject};
use vklens::model::rolling_shutter::{FrameMotion, Readout, WorldToCamera};
use vklens::model::InverseMethod;
use vklens::pass::{PointsMode, Precision};
use vklens::scene::Pose;

/// Most points accepted on stdin (a 16k × 16k image worth).
const MAX_POINTS: usize = 1 << 28;

/// Reads the JSON array of points on stdin; errors name the element.
fn read_rows(three: bool) -> Result<Vec<Vec<f64>>, CliError> {
    let mut text = String::new();
    std::io::stdin()
        .read_to_string(&mut text)
        .map_err(|e| CliError::input(format!("stdin: cannot read: {e}")))?;
    parse_rows(&text, three)
}

/// Parses a JSON array of rows of two numbers (or, with `three`, of two or three).
pub(super) fn parse_rows(text: &str, three: bool) -> Result<Vec<Vec<f64>>, CliError> {
    let shape = if three {
        "[x, y] or [X, Y, Z]"
    } else {
        "[x, y]"
    };
    let value: Value = serde_json::from_str(text)
        .map_err(|e| CliError::input(format!("stdin: not valid JSON: {e}")))?;
    let items = value
        .as_array()
        .ok_or_else(|| CliError::input(format!("stdin: expected a JSON array of {shape} rows")))?;
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
            let row = item
                .as_array()
                .filter(|a| a.len() == 2 || (three && a.len() == 3))
                .ok_or_else(|| {
                    CliError::input(format!(
                        "stdin: element {i} must be a row {shape}, got {item}"
                    ))
                })?;
            row.iter()
                .map(Value::as_f64)
                .collect::<Option<Vec<f64>>>()
                .ok_or_else(|| {
                    CliError::input(format!("stdin: element {i} must hold numbers, got {item}"))
                })
        })
        .collect()
}

fn write_results<const N: usize>(results: &[Option<[f64; N]>]) -> Result<(), CliError> {
    let json: Vec<Value> = results
        .iter()
        .map(|r| match r {
            Some(v) if v.iter().all(|x| x.is_finite()) => serde_json::json!(v.as_slice()),
            _ => Value::Null,
        })
        .collect();
    let mut out = std::io::stdout().lock();
    serde_json::to_writer(&mut out, &json)
        .and_then(|_| writeln!(out).map_err(serde_json::Error::io))
        .map_err(|e| CliError::io(std::path::Path::new("<stdout>"), "cannot write", &e.into()))
}

/// Runs a GPU job on a headless context, checking validation messages when enabled.
fn on_gpu<T>(
    job: impl FnOnce(&vklens::host::Context) -> vklens::gpu::Result<T>,
) -> Result<T, CliError> {
    let ctx = context()?;
    let r = job(&ctx)?;
    finish(&ctx)?;
    Ok(r)
}

/// `points distort`: normalized ideal points `[x, y]` or camera-frame points `[X, Y, Z]` →
/// distorted pixels.
pub fn distort(camera: &Path, backend: Backend, precision: Precision) -> Result<(), CliError> {
    let cam = load_camera(camera)?;
    let rows = read_rows(true)?;
    let pairs: Vec<[f64; 2]> = rows
        .iter()
        .filter(|r| r.len() == 2)
        .map(|r| [r[0], r[1]])
        .collect();
    let triples: Vec<[f64; 3]> = rows
        .iter()
        .filter(|r| r.len() == 3)
        .map(|r| [r[0], r[1], r[2]])
        .collect();
    let (from_pairs, from_triples) = match backend {
        Backend::Cpu => (cam.distort_points(&pairs), cam.project_points(&triples)),
        Backend::Gpu => on_gpu(|ctx| {
            Ok((
                run_points(ctx, &cam, PointsMode::Distort, precision, &pairs)?,
                run_project(ctx, &cam, precision, &triples)?,
            ))
        })?,
    };
    // Back into the order of the input.
    let (mut a, mut b) = (from_pairs.into_iter(), from_triples.into_iter());
    let results: Vec<Option<[f64; 2]>> = rows
        .iter()
        .map(|r| if r.len() == 2 { a.next() } else { b.next() }.flatten())
        .collect();
    write_results(&results)
}

/// `points undistort`: distorted pixels → normalized ideal points (null outside the domain
/// and, for a fisheye, where the direction is at or behind the image plane) or, with `rays`,
/// unit camera-frame rays.
pub fn undistort(
    camera: &Path,
    method: InverseMethod,
    backend: Backend,
    precision: Precision,
    rays: bool,
) -> Result<(), CliError> {
    let cam = load_camera(camera)?;
    cam.check_method(method)
        .map_err(|e| CliError::input(format!("--method: {e}")))?;
    let points = read_points()?;
    if rays {
        let results: Vec<Option<[f64; 3]>> = match backend {
            Backend::Cpu => points
                .iter()
                .map(|p| cam.unproject(DVec2::from(*p)).map(|r| r.to_array()))
                .collect(),
            Backend::Gpu => on_gpu(|ctx| run_unproject(ctx, &cam, precision, &points))?,
        };
        return write_results(&results);
    }
    let results = match backend {
        Backend::Cpu => cam.undistort_points(&points, method),
        Backend::Gpu => {
            on_gpu(|ctx| run_points(ctx, &cam, PointsMode::Undistort(method), precision, &points))?
        }
    };
    write_results(&results)
}

fn read_points() -> Result<Vec<[f64; 2]>, CliError> {
    Ok(read_rows(false)?
        .into_iter()
        .map(|r| [r[0], r[1]])
        .collect())
}

/// `points project`: world points `[X, Y, Z]` seen from `pose` → distorted pixels, through a
/// global shutter, or through a rolling shutter read in `rolling` order (default: the camera
/// file's) while the camera moves to `end_pose`.
pub fn project(
    camera: &Path,
    pose: &str,
    end_pose: Option<&str>,
    rolling: Option<Readout>,
) -> Result<(), CliError> {
    let cam = load_camera(camera)?;
    let parse = |argument, text| {
        Pose::parse(text).map_err(|e| CliError::argument(argument, e.message_only()))
    };
    let start = WorldToCamera::from(parse("pose", pose)?);
    let end = end_pose.map(|p| parse("end_pose", p)).transpose()?;
    let readout = rolling.or_else(|| cam.readout());
    if end.is_some() && readout.is_none() {
        return Err(CliError::argument(
            "end_pose",
            format!(
                "a pose when the last line is read needs a rolling shutter, and the shutter is global (every line read at once, from --pose): give --rolling-shutter ({}); {} states no rolling readout",
                Readout::ALL.map(Readout::name).join(", "),
                camera.display()
            ),
        ));
    }
    let rows = read_rows(true)?;
    if let Some(i) = rows.iter().position(|r| r.len() != 3) {
        return Err(CliError::input(format!(
            "stdin: element {i} must be a world point [X, Y, Z], got {:?}",
            rows[i]
        )));
    }
    let points = rows.iter().map(|r| glam::DVec3::new(r[0], r[1], r[2]));
    let results: Vec<Option<[f64; 2]>> = match readout {
        None => points
            .map(|x| cam.project(start.apply(x)).map(|p| p.to_array()))
            .collect(),
        Some(readout) => {
            let motion = FrameMotion::new(start, end.map_or(start, WorldToCamera::from));
            points
                .map(|x| motion.project(&cam, readout, x).map(|p| p.pixel.to_array()))
                .collect()
        }
    };
    write_results(&results)
}
