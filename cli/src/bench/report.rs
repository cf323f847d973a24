//! The section of docs/benchmarks.md that `vklens bench all` writes for one device, rendered
//! from the rows of a run (or of a saved run, `--from`): each bench's tables, headed by device,
//! driver, date and duration, and where the bench has a goal, a table of the goals judged on
//! that run's rows.
//!
//! Every approximation is measured for error and time beside a peer timed in the same run; a
//! goal bounds such a measurement (a ratio to the peer, or an error), so its verdict is
//! computed from the rows it judges and is never written by hand.

use serde_json::Value;

use super::{inverse, lens, models, plan, vertex, warp, wide};
use vklens::{Error, Result};

/// What `vklens bench all` runs, in the order it runs and writes them: the ten benches, then
/// the Python package's frame loop beside `cv2.remap` (`python -m vklens.bench`).
pub const BENCHES: [&str; 11] = [
    "inverse",
    "warp",
    "vertex",
    "lens",
    "wide",
    "labels",
    "rolling-shutter",
    "models",
    "plan",
    "startup",
    "python",
];

/// The `bench` of the rows that describe the run rather than measure: `{"ran": NAME,
/// "seconds": S}` per bench, `{"skipped": PEER, "for": NAME, "why": ...}` per peer not measured.
pub const RUN: &str = "all";

/// Largest coordinate error of a full-frame inverse map, and of the cube path (px).
pub const MAP_ERROR_PX: f64 = 1e-3;
/// Map build against `cv2.undistortPoints` over every pixel: at least this many times faster.
pub const MAP_BUILD_SPEEDUP: f64 = 10.0;
/// The map warp against `cv2.remap`: at most this many times its time.
pub const MAP_WARP_X_REMAP: f64 = 3.0;
/// The chromatic map warp against the copy pass: at most this many times its time.
pub const CHROMATIC_X_COPY: f64 = 2.0;
/// Alg. 1 with the compute discard against a plain pinhole render of the same scene.
pub const VERTEX_X_PINHOLE: f64 = 1.10;
/// The image-based lens model against the CPU reference ray tracer (Heidrich et al.'s ratio:
/// 14 frames a second against 4.5 minutes a frame).
pub const LENS_SPEEDUP: f64 = 100.0;
/// The vertex path through a moving rolling shutter (each vertex's readout time solved)
/// against the global shutter's vertex path, the same scene and run.
pub const ROLLING_X_GLOBAL: f64 = 1.3;
/// A camera model's inverse over a 1080p frame against the standard model's Newton.
pub const MODEL_X_STANDARD: f64 = 1.3;
/// `vklens undistort` of a 64×36 image, process start to exit, cold (ms).
pub const STARTUP_SMALL_MS: f64 = 120.0;
/// Python: `import vklens` to a new `Warper`'s first 1080p frame (ms).
pub const STARTUP_WARPER_MS: f64 = 500.0;
/// `vklens distort` / `undistort` of a 1080p PNG against the Python + OpenCV script.
pub const STARTUP_X_OPENCV: f64 = 2.0;
/// A pipeline's build time against the previous table's for the same pipeline and model (the
/// device's last `docs/benchmarks.md` section): at most this many times it.
pub const PIPELINE_X_PREVIOUS: f64 = 1.5;

/// Whether a goal held on a run's rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    Met,
    NotMet,
    /// A row it needs is missing (a peer that was not measured, a CPU-only run).
    NotMeasured,
}

impl Verdict {
    fn word(self) -> &'static str {
        match self {
            Verdict::Met => "met",
            Verdict::NotMet => "not met",
            Verdict::NotMeasured => "not measured",
        }
    }
}

/// One goal of a bench and what the run measured for it.
#[derive(Debug, Clone)]
pub struct Goal {
    pub goal: String,
    pub measured: String,
    pub verdict: Verdict,
}

/// The goals of `bench`, judged on its rows (peers' rows included); none for a bench without.
pub fn goals(bench: &str, rows: &[Value]) -> Vec<Goal> {
    match bench {
        "warp" => warp_goals(rows),
        "vertex" => vertex_goals(rows),
        "lens" => lens_goals(rows),
        "wide" => wide_goals(rows),
        "rolling-shutter" => rolling_shutter_goals(rows),
        "models" => models_goals(rows),
        "plan" => plan_goals(rows),
        "startup" => startup_goals(rows),
        _ => Vec::new(),
    }
}

/// Goals as a Markdown table.
pub fn goals_table(goals: &[Goal]) -> String {
    let mut out = String::from("| goal | measured | verdict |\n|---|---|---|\n");
    for g in goals {
        out.push_str(&format!(
            "| {} | {} | {} |\n",
            g.goal,
            g.measured,
            g.verdict.word()
        ));
    }
    out
}

fn ratio(x: f64) -> String {
    format!("{x:.2}×")
}

fn px(x: f64) -> String {
    format!("{x:.1e} px")
}

/// Judges `values` (where each was measured, the value) against `limit`: every value at most
/// it, or with `at_least` every value at least it. Measured: the range, and where it failed.
fn bound(
    goal: String,
    values: &[(String, f64)],
    limit: f64,
    at_least: bool,
    show: fn(f64) -> String,
) -> Goal {
    let finite: Vec<f64> = values
        .iter()
        .map(|v| v.1)
        .filter(|v| v.is_finite())
        .collect();
    if finite.is_empty() {
        return not_measured(goal, "no rows to judge");
    }
    if finite.len() < values.len() {
        let missing: Vec<&str> = values
            .iter()
            .filter(|(_, v)| !v.is_finite())
            .map(|(w, _)| w.as_str())
            .collect();
        return not_measured(goal, &format!("no value at {}", missing.join("; ")));
    }
    let lo = finite.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let failing: Vec<&str> = values
        .iter()
        .filter(|(_, v)| if at_least { *v < limit } else { *v > limit })
        .map(|(w, _)| w.as_str())
        .collect();
    let mut measured = if show(lo) == show(hi) {
        show(lo)
    } else {
        format!("{}–{}", show(lo), show(hi))
    };
    if !failing.is_empty() && failing.len() < values.len() {
        measured.push_str(&format!(" (not at {})", failing.join("; ")));
    }
    Goal {
        goal,
        measured,
        verdict: if failing.is_empty() {
            Verdict::Met
        } else {
            Verdict::NotMet
        },
    }
}

fn not_measured(goal: String, why: &str) -> Goal {
    Goal {
        goal,
        measured: why.into(),
        verdict: Verdict::NotMeasured,
    }
}

fn size(r: &Value) -> String {
    format!("{}×{}", r["width"], r["height"])
}

fn of_kind<'a>(rows: &'a [Value], kind: &'a str) -> impl Iterator<Item = &'a Value> + 'a {
    rows.iter().filter(move |r| r["kind"] == kind)
}

fn warp_goals(rows: &[Value]) -> Vec<Goal> {
    let copies: Vec<&Value> = of_kind(rows, "copy").collect();
    let opencv = rows.iter().any(|r| r["kind"] == "opencv");
    let mut goals = Vec::new();

    let goal = format!(
        "a full-frame inverse map of the 14-coefficient camera within {MAP_ERROR_PX:.0e} px of \
         the f64 model, built ≥ {MAP_BUILD_SPEEDUP:.0}× faster than `cv2.undistortPoints` over \
         every pixel"
    );
    let mut measured = Vec::new();
    let mut speedups = Vec::new();
    let mut none_within = Vec::new();
    for c in &copies {
        let within: Vec<&Value> = of_kind(rows, "inverse_map")
            .filter(|r| r["width"] == c["width"] && r["height"] == c["height"])
            .filter(|r| r["max_err_px"].as_f64().is_some_and(|e| e <= MAP_ERROR_PX))
            .collect();
        let peer =
            warp::same_size(rows, "opencv", c).and_then(|p| p["undistort_points_ms"].as_f64());
        if within.is_empty() {
            none_within.push(size(c));
            continue;
        }
        if let Some(peer) = peer {
            let best = within
                .iter()
                .filter_map(|r| warp::row_ms(r).map(|ms| (*r, peer / ms)))
                .max_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((r, x)) = best {
                measured.push(format!(
                    "{}: {} {x:.1}× ({})",
                    size(c),
                    r["method"].as_str().unwrap_or("?"),
                    px(r["max_err_px"].as_f64().unwrap_or(f64::NAN))
                ));
                speedups.push(x);
            }
        }
    }
    goals.push(if copies.is_empty() {
        not_measured(goal, "no rows to judge")
    } else if !none_within.is_empty() {
        Goal {
            goal,
            measured: format!("no map build within 1e-3 px at {}", none_within.join(", ")),
            verdict: Verdict::NotMet,
        }
    } else if !opencv || speedups.len() < copies.len() {
        not_measured(goal, "`cv2.undistortPoints` not measured")
    } else {
        Goal {
            goal,
            measured: measured.join("; "),
            verdict: if speedups.iter().all(|&x| x >= MAP_BUILD_SPEEDUP) {
                Verdict::Met
            } else {
                Verdict::NotMet
            },
        }
    });

    // The faster of the compute and the fragment-shader map warp at each size: what a caller
    // picking a map warp on this device gets.
    let fastest_map = |c: &Value, chromatic: bool| {
        of_kind(rows, "warp")
            .filter(|r| r["width"] == c["width"] && r["height"] == c["height"])
            .filter(|r| r["chromatic"] == chromatic)
            .filter(|r| r["method"] == "map" || r["method"] == "map_raster")
            .filter_map(|r| r["frame_ms"].as_f64().map(|ms| (r, ms)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
    };
    let goal = format!(
        "the map warp (the faster of compute and fragment shader) ≤ {MAP_WARP_X_REMAP:.0}× \
         `cv2.remap` with precomputed maps"
    );
    goals.push(if !opencv {
        not_measured(goal, "`cv2.remap` not measured")
    } else {
        let values: Vec<(String, f64)> = copies
            .iter()
            .map(|c| {
                let remap = warp::same_size(rows, "opencv", c).and_then(|p| p["remap_ms"].as_f64());
                let x = match (fastest_map(c, false), remap) {
                    (Some((_, ms)), Some(remap)) => ms / remap,
                    _ => f64::NAN,
                };
                (size(c), x)
            })
            .collect();
        bound(goal, &values, MAP_WARP_X_REMAP, false, ratio)
    });

    let values: Vec<(String, f64)> = copies
        .iter()
        .map(|c| {
            let x = match (fastest_map(c, true), c["frame_ms"].as_f64()) {
                (Some((_, ms)), Some(copy)) => ms / copy,
                _ => f64::NAN,
            };
            (size(c), x)
        })
        .collect();
    goals.push(bound(
        format!(
            "the chromatic map warp (the faster of compute and fragment shader) ≤ \
             {CHROMATIC_X_COPY:.0}× the copy pass"
        ),
        &values,
        CHROMATIC_X_COPY,
        false,
        ratio,
    ));
    goals
}

fn vertex_goals(rows: &[Value]) -> Vec<Goal> {
    let values: Vec<(String, f64)> = of_kind(rows, "paths")
        .map(|r| {
            (
                format!(
                    "{}, {}², {}",
                    size(r),
                    r["grid"],
                    r["lens"].as_str().unwrap_or("?")
                ),
                r["vertex_x_pinhole"].as_f64().unwrap_or(f64::NAN),
            )
        })
        .collect();
    vec![bound(
        format!(
            "Alg. 1 with the compute discard ≤ {VERTEX_X_PINHOLE:.2}× the plain pinhole render \
             of the same scene"
        ),
        &values,
        VERTEX_X_PINHOLE,
        false,
        ratio,
    )]
}

fn lens_goals(rows: &[Value]) -> Vec<Goal> {
    let values: Vec<(String, f64)> = rows
        .iter()
        .filter(|r| r["samples"] == 10 && r["max_angle_threshold_deg"].as_f64() == Some(0.05))
        .map(|r| {
            (
                format!("{}, grid {}²", r["lens"].as_str().unwrap_or("?"), r["grid"]),
                r["speedup"].as_f64().unwrap_or(f64::NAN),
            )
        })
        .collect();
    vec![bound(
        format!(
            "≥ {LENS_SPEEDUP:.0}× faster than the CPU reference ray tracer at 10 lens samples \
             and the 0.05° threshold"
        ),
        &values,
        LENS_SPEEDUP,
        true,
        |x| format!("{x:.1}×"),
    )]
}

fn rolling_shutter_goals(rows: &[Value]) -> Vec<Goal> {
    let exact: Vec<(String, f64)> = rows
        .iter()
        .filter(|r| r["path"] == "exact")
        .map(|r| {
            (
                format!("grid {}", r["grid"].as_str().unwrap_or("?")),
                r["x_global"].as_f64().unwrap_or(f64::NAN),
            )
        })
        .collect();
    vec![bound(
        format!(
            "a moving rolling shutter, exact per vertex, ≤ {ROLLING_X_GLOBAL:.2}× the global \
             shutter's vertex path"
        ),
        &exact,
        ROLLING_X_GLOBAL,
        false,
        ratio,
    )]
}

fn startup_goals(rows: &[Value]) -> Vec<Goal> {
    let ms = |what: &str, size: &str| -> Vec<(String, f64)> {
        rows.iter()
            .filter(|r| r["what"] == what && r["size"] == size)
            .map(|r| {
                (
                    format!("{what} {size}"),
                    r["ms"].as_f64().unwrap_or(f64::NAN),
                )
            })
            .collect()
    };
    let x_opencv: Vec<(String, f64)> = of_kind(rows, "command")
        .filter(|r| r["size"] == "1920×1080")
        .map(|r| {
            (
                r["what"].as_str().unwrap_or("?").to_string(),
                r["x_faster"].as_f64().unwrap_or(f64::NAN),
            )
        })
        .collect();
    let ms_text = |x: f64| format!("{x:.0} ms");
    let pipeline_goal = format!(
        "no pipeline builds more than {:.0} % slower than in the previous table",
        (PIPELINE_X_PREVIOUS - 1.0) * 100.0
    );
    let growth: Vec<(String, f64)> = of_kind(rows, "pipeline")
        .filter_map(|r| {
            let before = super::startup::previous_ms(rows, r)?;
            let now = r["ms"].as_f64().unwrap_or(f64::NAN);
            Some((
                format!(
                    "{}, {}",
                    r["what"].as_str().unwrap_or("?"),
                    r["model"].as_str().unwrap_or("?")
                ),
                now / before,
            ))
        })
        .collect();
    let pipelines = if growth.is_empty() {
        not_measured(
            pipeline_goal,
            "no previous table of this device to compare with",
        )
    } else {
        bound(pipeline_goal, &growth, PIPELINE_X_PREVIOUS, false, ratio)
    };
    vec![
        bound(
            format!("`vklens undistort` of a 64×36 image ≤ {STARTUP_SMALL_MS:.0} ms, cold"),
            &ms("vklens undistort", "64×36"),
            STARTUP_SMALL_MS,
            false,
            ms_text,
        ),
        bound(
            format!("Python: a new `Warper` to its first 1080p frame ≤ {STARTUP_WARPER_MS:.0} ms"),
            &ms("import vklens → Warper → first frame", "1920×1080"),
            STARTUP_WARPER_MS,
            false,
            ms_text,
        ),
        bound(
            format!(
                "`vklens distort` and `undistort` at 1080p ≥ {STARTUP_X_OPENCV:.0}× faster end to \
                 end than the Python + OpenCV script"
            ),
            &x_opencv,
            STARTUP_X_OPENCV,
            true,
            ratio,
        ),
        pipelines,
    ]
}

fn wide_goals(rows: &[Value]) -> Vec<Goal> {
    // Lenses past a pinhole's reach: those whose warp path was refused for want of a source.
    let beyond = |camera: &Value| {
        rows.iter()
            .any(|r| &r["camera"] == camera && r["path"] == "warp" && r["refused"].is_string())
    };
    let vertex: Vec<(String, f64)> = rows
        .iter()
        .filter(|r| r["path"] == "vertex" && beyond(&r["camera"]))
        .map(|r| {
            (
                r["camera"].as_str().unwrap_or("?").to_string(),
                r["x_pinhole"].as_f64().unwrap_or(f64::NAN),
            )
        })
        .collect();
    let cube: Vec<(String, f64)> = rows
        .iter()
        .filter(|r| r["path"] == "cube")
        .map(|r| {
            (
                r["camera"].as_str().unwrap_or("?").to_string(),
                r["max_err_px"].as_f64().unwrap_or(f64::NAN),
            )
        })
        .collect();
    vec![
        bound(
            format!(
                "Alg. 1 through the lenses no pinhole source holds ≤ {VERTEX_X_PINHOLE:.2}× a \
                 pinhole render"
            ),
            &vertex,
            VERTEX_X_PINHOLE,
            false,
            ratio,
        ),
        bound(
            format!("the cube path within {MAP_ERROR_PX:.0e} px of the f64 model"),
            &cube,
            MAP_ERROR_PX,
            false,
            px,
        ),
    ]
}

fn models_goals(rows: &[Value]) -> Vec<Goal> {
    let values: Vec<(String, f64)> = rows
        .iter()
        .map(|r| {
            (
                r["camera"].as_str().unwrap_or("?").to_string(),
                r["map_ratio"].as_f64().unwrap_or(f64::NAN),
            )
        })
        .collect();
    vec![bound(
        format!(
            "every model's inverse over a 1080p frame ≤ {MODEL_X_STANDARD:.1}× the standard \
             model's"
        ),
        &values,
        MODEL_X_STANDARD,
        false,
        ratio,
    )]
}

fn plan_goals(rows: &[Value]) -> Vec<Goal> {
    let plans: Vec<&Value> = of_kind(rows, "plans").collect();
    let scene = |r: &Value| r["scene"].as_str().unwrap_or("?").to_string();
    let within: Vec<(String, f64)> = plans
        .iter()
        .map(|r| {
            let x = match (r["error_px"].as_f64(), r["budget_px"].as_f64()) {
                (Some(e), Some(b)) if b > 0.0 => e / b,
                _ => f64::NAN,
            };
            (scene(r), x)
        })
        .collect();
    let saved: Vec<(String, f64)> = plans
        .iter()
        .map(|r| (scene(r), r["saving"].as_f64().unwrap_or(f64::NAN)))
        .collect();
    vec![
        bound(
            "each example scene's plan within its error budget (error ÷ budget ≤ 1)".into(),
            &within,
            1.0,
            false,
            |x| format!("{x:.2}"),
        ),
        bound(
            "each plan no slower than the everything-on pipeline (× saved ≥ 1)".into(),
            &saved,
            1.0,
            true,
            |x| format!("{x:.1}×"),
        ),
    ]
}

/// The Python frame loop's rows (`python -m vklens.bench --json`, one per size and direction)
/// as a Markdown table.
pub fn python_table(rows: &[Value]) -> String {
    let mut out = String::new();
    if let Some(r) = rows.first() {
        out.push_str(&format!(
            "OpenCV {}, numpy {}; opening the device {} ms, once per process; median of {} \
             loops of {} frames.\n\n",
            r["opencv"].as_str().unwrap_or("?"),
            r["numpy"].as_str().unwrap_or("?"),
            super::fixed(r, "device_start_ms", 0),
            r["repeats"],
            r["frames"],
        ));
    }
    out.push_str(
        "| size | direction | vklens fps | cv2.remap fps | × cv2 | vklens first frame ms | OpenCV first frame ms |\n\
         |---|---|---:|---:|---:|---:|---:|\n",
    );
    for r in rows {
        out.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} |\n",
            r["size"].as_str().unwrap_or("?").replace('x', "×"),
            r["direction"].as_str().unwrap_or("?"),
            super::fixed(r, "vklens_fps", 1),
            super::fixed(r, "opencv_fps", 1),
            super::fixed(r, "fps_ratio", 2),
            super::fixed(r, "vklens_first_frame_ms", 0),
            super::fixed(r, "opencv_first_frame_ms", 0),
        ));
    }
    out
}

/// `bench`'s tables from its rows.
pub fn tables(bench: &str, rows: &[Value]) -> Result<String> {
    fn typed<T: serde::de::DeserializeOwned>(bench: &str, rows: &[Value]) -> Result<Vec<T>> {
        rows.iter()
            .map(|r| {
                serde_json::from_value(r.clone())
                    .map_err(|e| Error::input(format!("a `{bench}` row: {e}")))
            })
            .collect()
    }
    Ok(match bench {
        "inverse" => inverse::table(&typed(bench, rows)?),
        "warp" => warp::table(rows),
        "vertex" => vertex::table(rows),
        "lens" => lens::table(rows),
        "wide" => wide::table(rows),
        "labels" => super::labels::table(rows),
        "rolling-shutter" => super::rolling_shutter::table(rows),
        "models" => models::table(&typed(bench, rows)?),
        "plan" => plan::table(rows),
        "startup" => super::startup::table(rows),
        "python" => python_table(rows),
        other => return Err(Error::input(format!("no bench `{other}`"))),
    })
}

fn heading_name(bench: &str) -> String {
    if bench == "python" {
        "`python -m vklens.bench` beside `cv2.remap`".into()
    } else {
        format!("`vklens bench {bench}`")
    }
}

/// The bench a subsection heading (`### ...`) names.
fn heading_bench(heading: &str) -> Option<&'static str> {
    let text = heading.trim_start_matches('#').trim();
    BENCHES
        .iter()
        .copied()
        .find(|&b| text.starts_with(&format!("{} ", heading_name(b))) || text == heading_name(b))
}

/// One bench's subsection of a device's section from the rows of one run: heading (device,
/// driver, date, seconds), the peers not measured, its tables and its goals. `rows` are every
/// row of the run: those of `bench` and the run's own (`bench` [`RUN`]). None when the run
/// has nothing of `bench`.
pub fn subsection(bench: &str, rows: &[Value]) -> Result<Option<String>> {
    let own: Vec<Value> = rows
        .iter()
        .filter(|r| r["bench"] == bench)
        .cloned()
        .collect();
    let ran = rows.iter().find(|r| r["bench"] == RUN && r["ran"] == bench);
    let skipped: Vec<&Value> = rows
        .iter()
        .filter(|r| r["bench"] == RUN && r["for"] == bench && r["skipped"].is_string())
        .collect();
    let Some(first) = own.first().or(ran).or(skipped.first().copied()) else {
        return Ok(None);
    };
    let text = |k: &str| first[k].as_str().unwrap_or("?").to_string();
    let seconds = ran
        .and_then(|r| r["seconds"].as_f64())
        .map(|s| format!("; {s:.0} s"))
        .unwrap_or_default();
    let mut out = format!(
        "### {} ({}, {}, {}{seconds})\n\n",
        heading_name(bench),
        text("device"),
        text("driver"),
        text("date"),
    );
    for s in &skipped {
        out.push_str(&format!(
            "Not measured: {}: {}.\n\n",
            s["skipped"].as_str().unwrap_or("?"),
            s["why"].as_str().unwrap_or("?"),
        ));
    }
    if !own.is_empty() {
        out.push_str(tables(bench, &own)?.trim_end());
        out.push('\n');
        let goals = goals(bench, &own);
        if !goals.is_empty() {
            out.push_str("\nGoals, judged on the rows above\n\n");
            out.push_str(&goals_table(&goals));
        }
    }
    Ok(Some(out.trim_end().to_string()))
}

/// The markers around a device's section.
pub fn markers(device: &str) -> (String, String) {
    (
        format!("<!-- bench all: {device} -->"),
        format!("<!-- end bench all: {device} -->"),
    )
}

/// `file` with `device`'s section holding `fresh` (bench, subsection) in [`BENCHES`] order;
/// the section's subsections of benches `fresh` lacks are kept as they were, and so are other
/// devices' sections. A file without the section gets it at its end.
pub fn write_section(file: &str, device: &str, fresh: &[(&str, String)]) -> String {
    let (begin, end) = markers(device);
    let span = match (file.find(&begin), file.find(&end)) {
        (Some(a), Some(b)) if b > a => Some((a, b + end.len())),
        _ => None,
    };
    let mut kept: Vec<(&'static str, String)> = Vec::new();
    if let Some((a, b)) = span {
        let inner = &file[a + begin.len()..b - end.len()];
        for part in inner.split("\n### ").skip(1) {
            let part = format!("### {}", part.trim_end());
            if let Some(bench) = heading_bench(part.lines().next().unwrap_or("")) {
                if !fresh.iter().any(|(f, _)| *f == bench) {
                    kept.push((bench, part));
                }
            }
        }
    }
    let mut section = format!(
        "{begin}\n## {device}\n\nWritten by `vklens bench all`. Each heading names the device, the \
         driver, the date and the duration of the run that measured its tables.\n"
    );
    for bench in BENCHES {
        let text = fresh
            .iter()
            .find(|(f, _)| *f == bench)
            .map(|(_, t)| t.as_str())
            .or_else(|| {
                kept.iter()
                    .find(|(k, _)| *k == bench)
                    .map(|(_, t)| t.as_str())
            });
        if let Some(text) = text {
            section.push('\n');
            section.push_str(text.trim_end());
            section.push('\n');
        }
    }
    section.push_str(&end);
    match span {
        Some((a, b)) => format!("{}{section}{}", &file[..a], &file[b..]),
        None => format!("{}\n\n{section}\n", file.trim_end()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn warp_rows(remap_ms: Option<f64>) -> Vec<Value> {
        let mut rows = Vec::new();
        for (w, h, copy) in [(800, 600, 2.0), (1920, 1080, 8.0)] {
            rows.push(
                json!({"bench": "warp", "kind": "copy", "width": w, "height": h, "frame_ms": copy}),
            );
            // A map build within 1e-3 px at 1.5 copies, and a faster one outside it.
            rows.push(json!({"bench": "warp", "kind": "inverse_map", "width": w, "height": h,
                "method": "coarse8+cubic", "ms": 1.5 * copy, "max_err_px": 5e-4, "disagreeing_px": 0}));
            rows.push(
                json!({"bench": "warp", "kind": "inverse_map", "width": w, "height": h,
                "method": "coarse8+bilinear", "ms": copy, "max_err_px": 3e-3, "disagreeing_px": 0}),
            );
            // Compute map warp at 3 copies, fragment shader at 2.5; chromatic 4 and 2.2.
            for (method, chromatic, x) in [
                ("map", false, 3.0),
                ("map_raster", false, 2.5),
                ("map", true, 4.0),
                ("map_raster", true, 2.2),
            ] {
                rows.push(json!({"bench": "warp", "kind": "warp", "width": w, "height": h,
                    "method": method, "chromatic": chromatic, "frame_ms": x * copy, "max_err_px": 5e-4}));
            }
            if let Some(remap) = remap_ms {
                // undistortPoints at 30 copies: coarse8+cubic is 20× faster.
                rows.push(
                    json!({"bench": "warp", "kind": "opencv", "width": w, "height": h,
                    "remap_ms": remap * copy, "undistort_points_ms": 30.0 * copy,
                    "opencv": "5.0.0", "threads": 2}),
                );
            }
        }
        rows
    }

    fn verdicts(goals: &[Goal]) -> Vec<Verdict> {
        goals.iter().map(|g| g.verdict).collect()
    }

    #[test]
    fn the_rolling_shutter_goal_judges_every_grid_against_the_global_path() {
        let rows = |small: f64, big: f64| {
            vec![
                serde_json::json!({"grid": "128²", "path": "global", "frame_ms": 10.0}),
                serde_json::json!({"grid": "128²", "path": "exact", "frame_ms": 10.0 * small, "x_global": small}),
                serde_json::json!({"grid": "512²", "path": "global", "frame_ms": 40.0}),
                serde_json::json!({"grid": "512²", "path": "exact", "frame_ms": 40.0 * big, "x_global": big}),
            ]
        };
        assert_eq!(
            verdicts(&rolling_shutter_goals(&rows(1.1, 1.25))),
            [Verdict::Met]
        );
        let goals = rolling_shutter_goals(&rows(1.1, 2.5));
        assert_eq!(verdicts(&goals), [Verdict::NotMet]);
        assert!(goals[0].measured.contains("2.50×"), "{}", goals[0].measured);
        assert_eq!(
            verdicts(&rolling_shutter_goals(&[])),
            [Verdict::NotMeasured]
        );
    }

    #[test]
    fn warp_goals_judge_the_rows_against_their_peers() {
        // cv2.remap at one copy: the fastest map warp is 2.5× it (met); the chromatic one
        // 2.2× the copy (not met); the best map within 1e-3 px is 20× undistortPoints (met).
        let goals = warp_goals(&warp_rows(Some(1.0)));
        assert_eq!(
            verdicts(&goals),
            [Verdict::Met, Verdict::Met, Verdict::NotMet]
        );
        assert!(goals[0].measured.contains("coarse8+cubic 20.0×"));
        assert!(!goals[0].measured.contains("bilinear"));
        assert_eq!(goals[1].measured, "2.50×");
        assert_eq!(goals[2].measured, "2.20×");

        // cv2.remap four times faster: the map warp is 10× it.
        let goals = warp_goals(&warp_rows(Some(0.25)));
        assert_eq!(goals[1].verdict, Verdict::NotMet);
        assert_eq!(goals[1].measured, "10.00×");
    }

    #[test]
    fn warp_goals_without_opencv_are_not_measured_but_the_copy_ratio_is() {
        let goals = warp_goals(&warp_rows(None));
        assert_eq!(
            verdicts(&goals),
            [Verdict::NotMeasured, Verdict::NotMeasured, Verdict::NotMet]
        );
    }

    #[test]
    fn a_map_outside_the_error_bound_fails_whatever_its_speed() {
        let rows: Vec<Value> = warp_rows(Some(1.0))
            .into_iter()
            .filter(|r| !(r["method"] == "coarse8+cubic" && r["width"] == 1920))
            .collect();
        let goals = warp_goals(&rows);
        assert_eq!(goals[0].verdict, Verdict::NotMet);
        assert!(goals[0].measured.contains("1920×1080"));
    }

    #[test]
    fn bounds_name_the_rows_that_fail() {
        let rows = [
            json!({"kind": "paths", "width": 800, "height": 600, "grid": 8, "lens": "k1 k2", "vertex_x_pinhole": 1.02}),
            json!({"kind": "paths", "width": 800, "height": 600, "grid": 512, "lens": "14 terms", "vertex_x_pinhole": 1.2}),
        ];
        let goals = vertex_goals(&rows);
        assert_eq!(goals[0].verdict, Verdict::NotMet);
        assert_eq!(
            goals[0].measured,
            "1.02×–1.20× (not at 800×600, 512², 14 terms)"
        );
        let goals = vertex_goals(&rows[..1]);
        assert_eq!(goals[0].verdict, Verdict::Met);
        assert_eq!(vertex_goals(&[])[0].verdict, Verdict::NotMeasured);
        let partial = [
            rows[0].clone(),
            json!({"kind": "paths", "width": 8, "height": 6, "grid": 8, "lens": "k1 k2"}),
        ];
        let goals = vertex_goals(&partial);
        assert_eq!(goals[0].verdict, Verdict::NotMeasured);
        assert_eq!(goals[0].measured, "no value at 8×6, 8², k1 k2");
    }

    #[test]
    fn lens_models_plan_and_wide_goals() {
        let lens = [
            json!({"kind": "samples", "lens": "a", "samples": 10, "max_angle_threshold_deg": 0.05, "grid": 10, "speedup": 120.0}),
            json!({"kind": "samples", "lens": "a", "samples": 32, "max_angle_threshold_deg": 0.05, "grid": 10, "speedup": 5.0}),
            json!({"kind": "threshold", "lens": "a", "samples": 10, "max_angle_threshold_deg": 0.5, "grid": 10, "speedup": 5.0}),
        ];
        // Only the 10-sample row at 0.05° counts.
        assert_eq!(verdicts(&lens_goals(&lens)), [Verdict::Met]);

        let models = [
            json!({"camera": "standard", "map_ratio": 1.0}),
            json!({"camera": "thin_prism_fisheye", "map_ratio": 1.31}),
        ];
        assert_eq!(verdicts(&models_goals(&models)), [Verdict::NotMet]);
        // A CPU-only run has no GPU ratios.
        let cpu = [json!({"camera": "standard", "map_ratio": null})];
        assert_eq!(verdicts(&models_goals(&cpu)), [Verdict::NotMeasured]);

        let plans = [
            json!({"kind": "plans", "scene": "a.toml", "budget_px": 0.01, "error_px": 0.009, "saving": 12.0}),
            json!({"kind": "plans", "scene": "b.toml", "budget_px": 0.05, "error_px": 0.06, "saving": 0.8}),
            json!({"kind": "tradeoff", "path": "warp", "error_px": 9.0}),
        ];
        assert_eq!(
            verdicts(&plan_goals(&plans)),
            [Verdict::NotMet, Verdict::NotMet]
        );
        assert_eq!(
            verdicts(&plan_goals(&plans[..1])),
            [Verdict::Met, Verdict::Met]
        );

        let wide = [
            json!({"camera": "fisheye", "path": "vertex", "x_pinhole": 0.8}),
            json!({"camera": "fisheye", "path": "warp", "refused": "no pinhole source"}),
            json!({"camera": "fisheye", "path": "cube", "max_err_px": 1e-4}),
            // A lens a pinhole source holds: its vertex ratio is not the goal's.
            json!({"camera": "gopro", "path": "vertex", "x_pinhole": 1.5}),
            json!({"camera": "gopro", "path": "warp", "frame_ms": 100.0}),
            json!({"camera": "gopro", "path": "cube", "max_err_px": 2e-3}),
        ];
        let goals = wide_goals(&wide);
        assert_eq!(verdicts(&goals), [Verdict::Met, Verdict::NotMet]);
        assert!(goals[1].measured.contains("not at gopro"));
    }

    fn run(bench: &str, ran: bool) -> Vec<Value> {
        let meta = json!({"device": "dev", "driver": "drv 1", "date": "2030-01-02"});
        let with = |mut v: Value| {
            for (k, x) in meta.as_object().unwrap() {
                v[k] = x.clone();
            }
            v
        };
        let mut rows = vec![with(
            json!({"bench": bench, "kind": "paths", "width": 8, "height": 6,
            "grid": 8, "lens": "k1 k2", "triangles": 128, "vertex_x_pinhole": 1.05}),
        )];
        if ran {
            rows.push(with(json!({"bench": RUN, "ran": bench, "seconds": 12.4})));
        }
        rows
    }

    #[test]
    fn a_subsection_has_its_heading_tables_and_goals() {
        let text = subsection("vertex", &run("vertex", true)).unwrap().unwrap();
        assert!(text.starts_with("### `vklens bench vertex` (dev, drv 1, 2030-01-02; 12 s)\n"));
        assert!(text.contains("| 8×6 | 8² | k1 k2 | 128 |"));
        let goals = text
            .split("Goals, judged on the rows above")
            .nth(1)
            .unwrap();
        assert!(goals.contains("| 1.05× | met |"));
        assert!(subsection("lens", &run("vertex", true)).unwrap().is_none());
    }

    #[test]
    fn the_warp_table_gains_the_peers_columns_when_opencv_was_measured() {
        let with = tables("warp", &warp_rows(Some(1.0))).unwrap();
        let head = with.lines().next().unwrap();
        assert!(head.ends_with("| × cv2.remap | cv2.undistortPoints ÷ this |"));
        // The fragment-shader map warp at 2.5 copies, cv2.remap at one: 2.50× it, and
        // undistortPoints (30 copies) 12× its time.
        let raster = with
            .lines()
            .find(|l| l.starts_with("| 800×600 | warp, map_raster | no |"))
            .unwrap();
        assert!(raster.ends_with("| 2.50 | 12.00 |"));
        assert!(with.contains("| 1920×1080 | 8.00 | 240 |"));
        let without = tables("warp", &warp_rows(None)).unwrap();
        assert!(!without.contains("cv2"));
        assert_eq!(
            without.lines().nth(2).unwrap().matches('|').count(),
            head.matches('|').count() - 2
        );
    }

    #[test]
    fn a_skipped_peer_is_said_in_its_subsection() {
        let rows = vec![
            json!({"bench": RUN, "for": "python", "skipped": "python -m vklens.bench",
            "why": "No module named 'cv2'", "device": "dev", "driver": "drv", "date": "d"}),
        ];
        let text = subsection("python", &rows).unwrap().unwrap();
        assert!(text.contains("Not measured: python -m vklens.bench: No module named 'cv2'."));
    }

    #[test]
    fn rows_that_are_not_the_benchs_are_an_input_error() {
        let rows = [json!({"bench": "inverse", "camera": 3})];
        let e = tables("inverse", &rows).unwrap_err();
        assert_eq!(e.kind(), vklens::ErrorKind::Input);
    }

    #[test]
    fn writing_a_section_keeps_other_benches_and_devices() {
        let other = "<!-- bench all: gpu -->\n## gpu\n\n### `vklens bench lens` (gpu)\n\nGPU LENS\n<!-- end bench all: gpu -->";
        let file = format!(
            "# Benchmarks\n\nintro\n\n{other}\n\n<!-- bench all: dev -->\n## dev\n\nold header\n\n\
             ### `vklens bench inverse` (dev, old)\n\nOLD INVERSE\n\n### `vklens bench vertex` (dev, old)\n\nOLD VERTEX\n\
             <!-- end bench all: dev -->\n"
        );
        let fresh = subsection("vertex", &run("vertex", true)).unwrap().unwrap();
        let new = write_section(&file, "dev", &[("vertex", fresh)]);
        assert!(new.starts_with("# Benchmarks\n\nintro\n\n"));
        assert!(new.contains(other));
        assert!(new.contains("OLD INVERSE"));
        assert!(!new.contains("OLD VERTEX"));
        assert!(!new.contains("old header"));
        // Inverse before vertex, as they run.
        let inverse = new.find("### `vklens bench inverse`").unwrap();
        let vertex = new.find("### `vklens bench vertex` (dev, drv 1").unwrap();
        assert!(inverse < vertex);
        assert!(new.trim_end().ends_with("<!-- end bench all: dev -->"));

        // A new device's section goes at the end.
        let appended = write_section("# B\n", "new", &[]);
        assert!(appended.starts_with("# B\n\n<!-- bench all: new -->\n## new\n"));
        assert!(appended.ends_with("<!-- end bench all: new -->\n"));
    }
}

#[cfg(test)]
mod pipeline_guard_tests {
    use super::*;
    use serde_json::json;

    fn pipeline(what: &str, model: &str, ms: f64) -> Value {
        json!({"bench": "startup", "kind": "pipeline", "what": what, "model": model, "ms": ms,
               "device": "dev", "driver": "drv", "date": "2026-12-07"})
    }

    fn guard(rows: &[Value]) -> Goal {
        startup_goals(rows)
            .into_iter()
            .find(|g| g.goal.starts_with("no pipeline builds"))
            .expect("the pipeline guard")
    }

    #[test]
    fn the_guard_reads_the_previous_section_back_and_flags_a_build_half_again_slower() {
        // The section a first run writes, read back as the previous table by the next run.
        let first = vec![
            pipeline("warp, distort", "opencv", 40.0),
            pipeline("warp, undistort", "opencv", 12.0),
        ];
        assert_eq!(
            guard(&first).verdict,
            Verdict::NotMeasured,
            "no previous table"
        );
        let section = subsection("startup", &first).unwrap().unwrap();
        let file = write_section("# Benchmarks\n", "dev", &[("startup", section)]);
        let previous = super::super::startup::previous_rows(&file, "dev");
        assert_eq!(previous.len(), 2, "{file}");
        assert!(super::super::startup::previous_rows(&file, "another device").is_empty());

        // Distort builds 10 % slower (noise), undistort 60 % slower: flagged, by name.
        let mut second = vec![
            pipeline("warp, distort", "opencv", 44.0),
            pipeline("warp, undistort", "opencv", 19.2),
            // A pipeline the previous table lacks is not judged.
            pipeline("warp, distort", "ucm", 400.0),
        ];
        second.extend(previous);
        let g = guard(&second);
        assert_eq!(g.verdict, Verdict::NotMet, "{g:?}");
        assert!(
            g.measured.contains("not at warp, undistort, opencv"),
            "{g:?}"
        );
        assert!(!g.measured.contains("ucm"), "{g:?}");
        // The table shows the previous figure and the ratio beside each pipeline.
        let table = super::super::startup::table(&second);
        assert!(
            table.contains("| warp, undistort | opencv | 19.2 | 12.0 | 1.60 |"),
            "{table}"
        );
        assert!(
            table.contains("| warp, distort | ucm | 400.0 | — | — |"),
            "{table}"
        );
        // The previous figures are read, not rows of the run's own command table.
        assert!(!table.contains("| ? |"), "{table}");

        // Its own run's table read back: the ratios are 1.
        let section = subsection("startup", &second).unwrap().unwrap();
        let file = write_section(&file, "dev", &[("startup", section)]);
        let again = super::super::startup::previous_rows(&file, "dev");
        assert_eq!(again.len(), 3);
        let mut third = second
            .iter()
            .filter(|r| r["kind"] == "pipeline")
            .cloned()
            .collect::<Vec<_>>();
        third.extend(again);
        assert_eq!(guard(&third).verdict, Verdict::Met);
    }
}
