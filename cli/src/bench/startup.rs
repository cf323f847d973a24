//! `vklens bench startup`: what a user waits for before the first frame, cold. Every other
//! bench warms up first and so never sees it; "simulate only what the scene calls for" is
//! measured here, where pipelines that compile code a run never uses cost the most.
//!
//! Whole processes, each started fresh (no warm-up, no pipeline cache file), and each run
//! beside its peer, pair by pair, so that both see the same machine:
//! - `vklens undistort` of a 64×36 image: the fixed cost of a command;
//! - `vklens undistort` and `vklens distort` of a 1080p RGB PNG against the Python + OpenCV
//!   script a user would write (`cv2.initUndistortRectifyMap` + `cv2.remap` + `cv2.imwrite`;
//!   `cv2.undistortPoints` on every pixel + `cv2.remap` + `cv2.imwrite`);
//! - `vklens render` of the rolling-shutter example scene and of its global twin;
//! - Python: `import vklens` to a new `Warper`'s first 1080p frame.
//!
//! Then, in this process, the creation of each warp pipeline and of the vertex path's (still,
//! and through a moving rolling shutter) for each camera model on a new device (no pipeline
//! of it built before): what each model's shaders cost the driver.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use serde_json::{json, Value};
use vklens::host::Context;
use vklens::model::samples::sample_cameras;
use vklens::pass::geometry::{
    ColorFormat, GeometryDesc, GeometryPass, Outputs, Projection, DEFAULT_DELTA,
};
use vklens::pass::warp::{Coordinates, PixelFormat, WarpDesc, WarpPass};
use vklens::{Error, Result};

/// Runs of each command (and of its peer, alternating): the median is reported.
pub const RUNS: usize = 5;

/// The 1080p camera of the command rows: a k1 k2 p1 p2 lens, as the issue tracker's example.
const CAMERA_1080P: &str = r#"{"model": "opencv", "width": 1920, "height": 1080,
  "fx": 1000, "fy": 1000, "cx": 959.5, "cy": 539.5, "dist_coeffs": [-0.12, 0.03, 0.001, -0.0005]}"#;
/// The same lens at 64×36 (the fixed cost of a command).
const CAMERA_SMALL: &str = r#"{"model": "opencv", "width": 64, "height": 36,
  "fx": 33.3, "fy": 33.3, "cx": 31.5, "cy": 17.5, "dist_coeffs": [-0.12, 0.03, 0.001, -0.0005]}"#;

/// The Python + OpenCV peer of `vklens undistort`: argv camera.json input output.
const PY_UNDISTORT: &str = r#"
import json, sys, cv2, numpy as np
c = json.load(open(sys.argv[1]))
K = np.array([[c["fx"], 0, c["cx"]], [0, c["fy"], c["cy"]], [0, 0, 1]], np.float64)
D = np.array(c["dist_coeffs"], np.float64)
img = cv2.imread(sys.argv[2], cv2.IMREAD_UNCHANGED)
h, w = img.shape[:2]
mx, my = cv2.initUndistortRectifyMap(K, D, None, K, (w, h), cv2.CV_32FC1)
cv2.imwrite(sys.argv[3], cv2.remap(img, mx, my, cv2.INTER_LINEAR))
"#;

/// The Python + OpenCV peer of `vklens distort`: every output pixel's source by
/// `cv2.undistortPoints`, then `cv2.remap`.
const PY_DISTORT: &str = r#"
import json, sys, cv2, numpy as np
c = json.load(open(sys.argv[1]))
K = np.array([[c["fx"], 0, c["cx"]], [0, c["fy"], c["cy"]], [0, 0, 1]], np.float64)
D = np.array(c["dist_coeffs"], np.float64)
img = cv2.imread(sys.argv[2], cv2.IMREAD_UNCHANGED)
h, w = img.shape[:2]
u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
pts = np.stack([u.ravel(), v.ravel()], -1).reshape(-1, 1, 2)
src = cv2.undistortPoints(pts, K, D, P=K).reshape(h, w, 2).astype(np.float32)
cv2.imwrite(sys.argv[3], cv2.remap(img, src[..., 0], src[..., 1], cv2.INTER_LINEAR))
"#;

/// Python's `Warper` to its first 1080p frame, from `import vklens`: prints seconds.
const PY_WARPER: &str = r#"
import time
t = time.perf_counter()
import sys, numpy as np, vklens
cam = vklens.Camera.load(sys.argv[1])
w = vklens.Warper(cam, direction="undistort")
w(np.zeros((1080, 1920, 3), np.uint8))
print(time.perf_counter() - t)
"#;

/// Milliseconds of one run of `cmd` (which must succeed), as a whole process.
fn time_process(mut cmd: Command) -> Result<f64> {
    let start = Instant::now();
    let out = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .output()
        .map_err(|e| Error::input(format!("{:?}: {e}", cmd.get_program())))?;
    let ms = start.elapsed().as_secs_f64() * 1e3;
    if !out.status.success() {
        return Err(Error::input(format!(
            "{:?} {:?} failed: {}",
            cmd.get_program(),
            cmd.get_args().collect::<Vec<_>>(),
            String::from_utf8_lossy(&out.stderr).trim()
        )));
    }
    Ok(ms)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// A `vklens` command of this binary, cold: no pipeline cache file, quiet.
fn vklens(args: &[&str]) -> Command {
    let exe = std::env::current_exe().unwrap_or_else(|_| PathBuf::from("vklens"));
    let mut cmd = Command::new(exe);
    cmd.args(args)
        .env("VKLENS_PIPELINE_CACHE", "")
        .env("MESA_VK_IGNORE_CONFORMANCE_WARNING", "1");
    cmd
}

/// The median ms of `RUNS` runs of `ours`, and of `peer` where given, alternating.
fn pair(
    ours: &dyn Fn() -> Command,
    peer: Option<&dyn Fn() -> Command>,
) -> Result<(f64, Option<f64>)> {
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for _ in 0..RUNS {
        a.push(time_process(ours())?);
        if let Some(p) = peer {
            b.push(time_process(p())?);
        }
    }
    Ok((median(a), peer.map(|_| median(b))))
}

/// The inputs of the command rows, written into `dir`: the cameras, and a pinhole render of
/// the boxes scene at each size (RGB, as a photo would be).
fn inputs(dir: &Path) -> Result<()> {
    let write = |name: &str, text: &str| {
        std::fs::write(dir.join(name), text)
            .map_err(|e| Error::input(format!("{}: {e}", dir.join(name).display())))
    };
    write("camera_1080p.json", CAMERA_1080P)?;
    write("camera_small.json", CAMERA_SMALL)?;
    for (camera, image) in [
        ("camera_1080p.json", "in_1080p.png"),
        ("camera_small.json", "in_small.png"),
    ] {
        let (c, i) = (dir.join(camera), dir.join(image));
        let (c, i) = (c.to_string_lossy(), i.to_string_lossy());
        time_process(vklens(&[
            "render",
            "--camera",
            &c,
            "--scene",
            "boxes",
            "--output",
            &i,
            "--path",
            "warp",
            "--background",
            "0.3,0.3,0.3,1",
        ]))?;
        // RGB, as a photo is (the render writes RGBA).
        let path = dir.join(image);
        image::open(&path)
            .and_then(|img| img.to_rgb8().save(&path))
            .map_err(|e| Error::input(format!("{}: {e}", path.display())))?;
    }
    Ok(())
}

/// Whether `python` imports `imports`.
fn python_has(python: &str, imports: &str) -> bool {
    Command::new(python)
        .args(["-c", &format!("import {imports}")])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// The command rows (whole processes), then the pipeline rows (in this process on `ctx`'s
/// device kind). `python` runs the peers; a peer it cannot import is left out of its row.
pub fn run(python: &str, scenes: &Path, progress: &mut dyn FnMut(&str)) -> Result<Vec<Value>> {
    let dir = std::env::temp_dir().join(format!("vklens-bench-startup-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| Error::input(format!("{}: {e}", dir.display())))?;
    let result = command_rows(python, scenes, &dir, progress);
    let _ = std::fs::remove_dir_all(&dir);
    let mut rows = result?;
    rows.extend(pipeline_rows(progress)?);
    Ok(rows)
}

fn command_rows(
    python: &str,
    scenes: &Path,
    dir: &Path,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<Value>> {
    progress("bench startup: inputs");
    inputs(dir)?;
    let p = |name: &str| dir.join(name).to_string_lossy().into_owned();
    let opencv = python_has(python, "cv2, numpy");
    let mut rows = Vec::new();
    let mut row = |what: &str, size: &str, ours: f64, peer: Option<f64>, peer_name: &str| {
        rows.push(json!({
            "kind": "command", "what": what, "size": size, "ms": ours,
            "peer": peer.map(|_| peer_name), "peer_ms": peer,
            "x_faster": peer.map(|p| p / ours),
        }));
    };
    for (command, script, peer_name) in [
        (
            "undistort",
            PY_UNDISTORT,
            "Python: initUndistortRectifyMap + remap + imwrite",
        ),
        (
            "distort",
            PY_DISTORT,
            "Python: undistortPoints every pixel + remap + imwrite",
        ),
    ] {
        progress(&format!("bench startup: vklens {command} 1920×1080"));
        let (cam, input, out) = (p("camera_1080p.json"), p("in_1080p.png"), p("out.png"));
        let ours = || {
            vklens(&[
                command, "--camera", &cam, "--input", &input, "--output", &out,
            ])
        };
        let peer = || {
            let mut c = Command::new(python);
            c.args(["-c", script, &cam, &input, &p("peer.png")]);
            c
        };
        let peer: Option<&dyn Fn() -> Command> = if opencv { Some(&peer) } else { None };
        let (ms, peer_ms) = pair(&ours, peer)?;
        row(
            &format!("vklens {command}"),
            "1920×1080",
            ms,
            peer_ms,
            peer_name,
        );
    }
    progress("bench startup: vklens undistort 64×36");
    let (cam, input, out) = (p("camera_small.json"), p("in_small.png"), p("out.png"));
    let (ms, _) = pair(
        &|| {
            vklens(&[
                "undistort",
                "--camera",
                &cam,
                "--input",
                &input,
                "--output",
                &out,
            ])
        },
        None,
    )?;
    row("vklens undistort", "64×36", ms, None, "");
    for scene in ["rolling_shutter.toml", "rolling_shutter_global.toml"] {
        progress(&format!("bench startup: vklens render {scene}"));
        let file = scenes.join(scene).to_string_lossy().into_owned();
        let frames = p("frames");
        let (ms, _) = pair(
            &|| vklens(&["render", "--scene", &file, "--out", &frames]),
            None,
        )?;
        row(
            &format!("vklens render --scene {scene}"),
            "800×600",
            ms,
            None,
            "",
        );
    }
    if python_has(python, "numpy, vklens") {
        progress("bench startup: Python Warper to its first frame");
        let cam = p("camera_1080p.json");
        let mut times = Vec::new();
        for _ in 0..RUNS {
            let out = Command::new(python)
                .args(["-c", PY_WARPER, &cam])
                .env("VKLENS_PIPELINE_CACHE", "")
                .stderr(Stdio::null())
                .output()
                .map_err(|e| Error::input(format!("{python}: {e}")))?;
            let s: f64 = String::from_utf8_lossy(&out.stdout)
                .trim()
                .parse()
                .map_err(|_| Error::input("the Python Warper run printed no time"))?;
            times.push(s * 1e3);
        }
        rows.push(json!({
            "kind": "python", "what": "import vklens → Warper → first frame", "size": "1920×1080",
            "ms": median(times), "peer": null, "peer_ms": null, "x_faster": null,
        }));
    }
    Ok(rows)
}

/// Milliseconds to build each warp pipeline (distort and undistort, 8-bit) and the vertex
/// path's (still and rolling shutter) for each model's sample camera, on a new device per
/// model so that no pipeline of it was built before.
fn pipeline_rows(progress: &mut dyn FnMut(&str)) -> Result<Vec<Value>> {
    let mut rows = Vec::new();
    let mut seen = Vec::new();
    for (name, camera) in sample_cameras()? {
        let kind = camera.model();
        if seen.contains(&kind) || !kind.has_focal_length() {
            continue;
        }
        seen.push(kind);
        progress(&format!("bench startup: warp pipelines, {}", kind.name()));
        let ctx = Context::from_env()?;
        for direction in ["distort", "undistort"] {
            let geometry = match direction {
                "distort" => vklens::model::warp::WarpGeometry::distort(
                    camera.clone(),
                    vklens::InverseMethod::Newton,
                ),
                _ => vklens::model::warp::WarpGeometry::undistort(camera.clone()),
            };
            let desc = WarpDesc {
                geometry,
                coordinates: Coordinates::Analytic,
                sampling: vklens::Sampling::Bilinear,
                border: vklens::Border::Constant,
                format: PixelFormat::Rgba8,
                fill: [0.0; 4],
                write_mask: false,
            };
            let start = Instant::now();
            let pass = WarpPass::new(ctx.gpu(), desc)?;
            let ms = start.elapsed().as_secs_f64() * 1e3;
            drop(pass);
            rows.push(json!({
                "kind": "pipeline", "what": format!("warp, {direction}"),
                "model": kind.name(), "sample": name, "ms": ms,
            }));
        }
        // The vertex path (Alg. 1 with the compute discard), a still frame and a moving
        // rolling shutter's: the vertex shader and the discard's stages.
        for readout in [None, Some(vklens::rolling_shutter::Readout::TopToBottom)] {
            let mut desc = GeometryDesc::new(
                camera.clone(),
                Projection::Lens {
                    delta: DEFAULT_DELTA,
                },
                Outputs::color_only(Some(ColorFormat::Rgba8)),
            );
            desc.readout = readout;
            let start = Instant::now();
            let pass = GeometryPass::new(ctx.gpu(), desc)?;
            let ms = start.elapsed().as_secs_f64() * 1e3;
            drop(pass);
            let what = match readout {
                None => "vertex path (Alg. 1), still",
                Some(_) => "vertex path (Alg. 1), rolling shutter",
            };
            rows.push(json!({
                "kind": "pipeline", "what": what, "model": kind.name(), "sample": name, "ms": ms,
            }));
        }
    }
    Ok(rows)
}

fn cell(v: &Value, digits: usize) -> String {
    v.as_f64().map_or("—".into(), |x| format!("{x:.digits$}"))
}

/// The command rows and the pipeline rows as two Markdown tables.
pub fn table(rows: &[Value]) -> String {
    let mut out = String::from(
        "| what | size | ms (median, cold) | peer | peer ms | × faster |\n|---|---|---|---|---|---|\n",
    );
    for r in rows
        .iter()
        .filter(|r| r["kind"] == "command" || r["kind"] == "python")
    {
        out.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} |\n",
            r["what"].as_str().unwrap_or("?"),
            r["size"].as_str().unwrap_or("?"),
            cell(&r["ms"], 0),
            r["peer"].as_str().unwrap_or("—"),
            cell(&r["peer_ms"], 0),
            cell(&r["x_faster"], 2),
        ));
    }
    out.push_str(&format!(
        "\n| pipeline | model | {PIPELINE_MS} | previous table's ms | × previous |\n|---|---|---|---|---|\n"
    ));
    for r in rows.iter().filter(|r| r["kind"] == "pipeline") {
        let before = previous_ms(rows, r);
        let grown = match (r["ms"].as_f64(), before) {
            (Some(now), Some(then)) if then > 0.0 => Value::from(now / then),
            _ => Value::Null,
        };
        out.push_str(&format!(
            "| {} | {} | {} | {} | {} |\n",
            r["what"].as_str().unwrap_or("?"),
            r["model"].as_str().unwrap_or("?"),
            cell(&r["ms"], 1),
            cell(&before.map_or(Value::Null, Value::from), 1),
            cell(&grown, 2),
        ));
    }
    out
}

/// The column of the pipeline table that holds each pipeline's build time.
const PIPELINE_MS: &str = "ms to build (new device)";

/// The build time the previous table gave the pipeline of row `r` (a `previous` row of the
/// same pipeline and model), if it had one.
pub fn previous_ms(rows: &[Value], r: &Value) -> Option<f64> {
    rows.iter()
        .find(|p| p["kind"] == "previous" && p["what"] == r["what"] && p["model"] == r["model"])
        .and_then(|p| p["ms"].as_f64())
}

/// The pipeline build times of the previous `bench startup` table of `device` in `markdown`
/// (a `docs/benchmarks.md` that `bench all` wrote), as rows of kind `previous`: what the
/// guard against slower pipeline builds compares a run with. None where the file has no such
/// table for the device.
pub fn previous_rows(markdown: &str, device: &str) -> Vec<Value> {
    let (begin, end) = super::report::markers(device);
    let Some(section) = markdown
        .split_once(begin.as_str())
        .and_then(|(_, rest)| rest.split_once(end.as_str()))
        .map(|(inner, _)| inner)
    else {
        return Vec::new();
    };
    let Some((_, startup)) = section.split_once("### `vklens bench startup`") else {
        return Vec::new();
    };
    let startup = startup.split("\n### ").next().unwrap_or("");
    let cells = |line: &str| -> Vec<String> {
        line.trim()
            .trim_matches('|')
            .split('|')
            .map(|c| c.trim().to_string())
            .collect()
    };
    let mut lines = startup
        .lines()
        .skip_while(|l| !l.starts_with("| pipeline |"));
    let Some(header) = lines.next().map(cells) else {
        return Vec::new();
    };
    let (Some(what), Some(model), Some(ms)) = (
        header.iter().position(|c| c == "pipeline"),
        header.iter().position(|c| c == "model"),
        header.iter().position(|c| c == PIPELINE_MS),
    ) else {
        return Vec::new();
    };
    lines
        .skip(1)
        .take_while(|l| l.starts_with('|'))
        .map(cells)
        .filter_map(|c| {
            let ms: f64 = c.get(ms)?.parse().ok()?;
            Some(json!({
                "kind": "previous", "what": c.get(what)?, "model": c.get(model)?, "ms": ms,
            }))
        })
        .collect()
}
