//! `vklens bench ...`.

use clap::Args;

use super::{context, finish, CliError};
use crate::bench::inverse::{self, InverseBenchOptions};
use crate::bench::report::BENCHES;
use vklens::io::reference::{load_reference, reference_path};

#[derive(Args, Debug)]
pub struct InverseArgs {
    /// One JSON object per line instead of tables.
    #[arg(long)]
    json: bool,
    /// CPU only (no Vulkan device needed).
    #[arg(long)]
    cpu_only: bool,
    /// Comma-separated methods to measure (default: newton, heikkila and fixed-point with
    /// 1, 2, 3, 5, 10, 20, 50, 200 iterations).
    #[arg(long, value_delimiter = ',', value_parser = super::parse_method)]
    methods: Vec<vklens::model::InverseMethod>,
}

pub fn inverse(args: InverseArgs) -> Result<(), CliError> {
    let reference = load_reference().map_err(|e| {
        CliError::input(format!(
            "{e}\n(the shared reference data is expected at {}; set VKLENS_SHARED to the shared folder)",
            reference_path().display()
        ))
    })?;
    let ctx = if args.cpu_only {
        None
    } else {
        Some(context()?)
    };
    let mut options = InverseBenchOptions::default();
    if !args.methods.is_empty() {
        options.methods = args.methods.clone();
    }
    if let Some(ctx) = &ctx {
        eprintln!("device: {}", ctx.gpu().device_name());
    }
    let rows = inverse::run(&reference, ctx.as_ref(), &options, super::progress_line)?;
    super::progress_done(&format!("measured {} rows", rows.len()));
    if let Some(ctx) = &ctx {
        finish(ctx)?;
    }
    if args.json {
        for r in &rows {
            outln!(
                "{}",
                serde_json::to_string(r).map_err(|e| CliError::internal(e.to_string()))?
            )?;
        }
    } else {
        outln!("{}", inverse::table(&rows))?;
    }
    Ok(())
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', '×'])
        .ok_or_else(|| format!("--size {s}: expected WxH, e.g. 1920x1080"))?;
    let p = |v: &str| {
        v.trim()
            .parse::<u32>()
            .ok()
            .filter(|&n| n > 0 && n <= 16384)
    };
    match (p(w), p(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(format!(
            "--size {s}: width and height must be whole numbers in 1..=16384"
        )),
    }
}

#[derive(Args, Debug)]
pub struct WarpArgs {
    /// Measure only this size (WxH); default 800x600, 1920x1080 and 3840x2160.
    #[arg(long, value_parser = parse_size)]
    size: Option<(u32, u32)>,
    /// One JSON object per line instead of a table.
    #[arg(long)]
    json: bool,
}

pub fn warp(args: WarpArgs) -> Result<(), CliError> {
    let ctx = context()?;
    eprintln!("device: {}", ctx.gpu().device_name());
    let sizes: Vec<(u32, u32)> = match args.size {
        Some(s) => vec![s],
        None => crate::bench::warp::SIZES.to_vec(),
    };
    let rows = crate::bench::warp::run(&ctx, &sizes, super::progress_line)?;
    super::progress_done(&format!("measured {} rows", rows.len()));
    finish(&ctx)?;
    print_rows(&rows, args.json, crate::bench::warp::table)?;
    Ok(())
}

#[derive(Args, Debug)]
pub struct VertexArgs {
    /// Measure only this size (WxH); default 800x600 and 1920x1080.
    #[arg(long, value_parser = parse_size)]
    size: Option<(u32, u32)>,
    /// One JSON object per line instead of tables.
    #[arg(long)]
    json: bool,
}

pub fn vertex(args: VertexArgs) -> Result<(), CliError> {
    let ctx = context()?;
    eprintln!("device: {}", ctx.gpu().device_name());
    let sizes: Vec<(u32, u32)> = match args.size {
        Some(s) => vec![s],
        None => crate::bench::vertex::SIZES.to_vec(),
    };
    let rows = crate::bench::vertex::run(&ctx, &sizes, &mut |s| super::progress_line(s))?;
    super::progress_done(&format!("measured {} rows", rows.len()));
    finish(&ctx)?;
    print_rows(&rows, args.json, crate::bench::vertex::table)?;
    Ok(())
}

#[derive(Args, Debug)]
pub struct LensArgs {
    /// Film pixels per side (24 × 24 mm film; Heidrich et al. timed 256 × 256).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(16..=4096))]
    pixels: u32,
    /// Folder with the lens files (default: ./lenses, else the source tree's).
    #[arg(long, value_name = "DIR")]
    lenses: Option<std::path::PathBuf>,
    /// One JSON object per line instead of tables.
    #[arg(long)]
    json: bool,
}

/// `given`, else `relative` below the working directory, else below the source tree; it
/// must exist.
fn data_folder(
    given: Option<std::path::PathBuf>,
    relative: &str,
    flag: &str,
) -> Result<std::path::PathBuf, CliError> {
    let dir = given.unwrap_or_else(|| {
        let here = std::path::PathBuf::from(relative);
        if here.is_dir() {
            here
        } else {
            crate::repo_root().join(relative)
        }
    });
    if dir.is_dir() {
        Ok(dir)
    } else {
        Err(CliError::input(format!(
            "{flag} {}: no such folder",
            dir.display()
        )))
    }
}

/// Prints rows as JSON lines or as the bench's tables.
fn print_rows(
    rows: &[serde_json::Value],
    json: bool,
    table: fn(&[serde_json::Value]) -> String,
) -> Result<(), CliError> {
    if json {
        for r in rows {
            outln!("{r}")?;
        }
    } else {
        outln!("{}", table(rows))?;
    }
    Ok(())
}

fn bench_error(e: vklens::Error) -> CliError {
    match e {
        vklens::Error::Input(m) => CliError::input(m),
        other => CliError::from(other),
    }
}

pub fn lens(args: LensArgs) -> Result<(), CliError> {
    let dir = data_folder(args.lenses.clone(), "lenses", "--lenses")?;
    let ctx = context()?;
    eprintln!("device: {}", ctx.gpu().device_name());
    let rows = crate::bench::lens::run(&ctx, &dir, args.pixels, &mut |s| super::progress_line(s))
        .map_err(|e| match e {
        vklens::Error::Input(m) => CliError::input(m),
        other => CliError::from(other),
    })?;
    super::progress_done(&format!("measured {} rows", rows.len()));
    finish(&ctx)?;
    if args.json {
        for r in &rows {
            outln!("{r}")?;
        }
    } else {
        outln!("{}", crate::bench::lens::table(&rows))?;
    }
    Ok(())
}

#[derive(Args, Debug)]
pub struct PlanArgs {
    /// Folder of scene files (default: ./examples/scenes, else the source tree's).
    #[arg(long, value_name = "DIR")]
    scenes: Option<std::path::PathBuf>,
    /// One JSON object per line instead of tables.
    #[arg(long)]
    json: bool,
}

pub fn plan(args: PlanArgs) -> Result<(), CliError> {
    let dir = data_folder(args.scenes.clone(), "examples/scenes", "--scenes")?;
    let ctx = context()?;
    eprintln!("device: {}", ctx.gpu().device_name());
    let rows = crate::bench::plan::run(&ctx, &dir, &mut |s| super::progress_line(s))
        .map_err(bench_error)?;
    super::progress_done(&format!("measured {} rows", rows.len()));
    finish(&ctx)?;
    print_rows(&rows, args.json, crate::bench::plan::table)?;
    Ok(())
}

#[derive(Args, Debug)]
pub struct WideArgs {
    /// One JSON object per line instead of a table.
    #[arg(long)]
    json: bool,
}

pub fn wide(args: WideArgs) -> Result<(), CliError> {
    let ctx = context()?;
    eprintln!("device: {}", ctx.gpu().device_name());
    let rows =
        crate::bench::wide::run(&ctx, &mut |s| super::progress_line(s)).map_err(bench_error)?;
    super::progress_done(&format!("measured {} rows", rows.len()));
    finish(&ctx)?;
    print_rows(&rows, args.json, crate::bench::wide::table)?;
    Ok(())
}

pub fn labels(args: WideArgs) -> Result<(), CliError> {
    let ctx = context()?;
    eprintln!("device: {}", ctx.gpu().device_name());
    let rows =
        crate::bench::labels::run(&ctx, &mut |s| super::progress_line(s)).map_err(bench_error)?;
    super::progress_done(&format!("measured {} rows", rows.len()));
    finish(&ctx)?;
    print_rows(&rows, args.json, crate::bench::labels::table)?;
    Ok(())
}

pub fn rolling_shutter(args: WideArgs) -> Result<(), CliError> {
    let ctx = context()?;
    eprintln!("device: {}", ctx.gpu().device_name());
    let rows = crate::bench::rolling_shutter::run(&ctx, &mut |s| super::progress_line(s))
        .map_err(bench_error)?;
    super::progress_done(&format!("measured {} rows", rows.len()));
    finish(&ctx)?;
    print_rows(&rows, args.json, crate::bench::rolling_shutter::table)?;
    Ok(())
}

#[derive(Args, Debug)]
pub struct StartupArgs {
    /// One JSON object per line instead of tables.
    #[arg(long)]
    json: bool,
    /// The Python that runs the OpenCV peers and the `Warper` row (a peer whose imports fail
    /// is left out of its row).
    #[arg(long, value_name = "PROGRAM", default_value = "python3")]
    python: String,
}

pub fn startup(args: StartupArgs) -> Result<(), CliError> {
    let scenes = data_folder(None, "examples/scenes", "examples/scenes")?;
    let rows = crate::bench::startup::run(&args.python, &scenes, &mut |s| super::progress_line(s))
        .map_err(bench_error)?;
    super::progress_done(&format!("measured {} rows", rows.len()));
    print_rows(&rows, args.json, crate::bench::startup::table)?;
    Ok(())
}

#[derive(Args, Debug)]
pub struct ModelsArgs {
    /// One JSON object per line instead of a table.
    #[arg(long)]
    json: bool,
    /// CPU columns only (no Vulkan device needed).
    #[arg(long)]
    cpu_only: bool,
}

pub fn models(args: ModelsArgs) -> Result<(), CliError> {
    let ctx = if args.cpu_only {
        None
    } else {
        let ctx = context()?;
        eprintln!("device: {}", ctx.gpu().device_name());
        Some(ctx)
    };
    let rows =
        crate::bench::models::run(ctx.as_ref(), super::progress_line).map_err(bench_error)?;
    super::progress_done(&format!("measured {} models", rows.len()));
    if let Some(ctx) = &ctx {
        finish(ctx)?;
    }
    if args.json {
        for r in &rows {
            let v = serde_json::to_value(r)
                .map_err(|e| CliError::from(vklens::Error::internal(e.to_string())))?;
            outln!("{v}")?;
        }
    } else {
        outln!("{}", crate::bench::models::table(&rows))?;
    }
    Ok(())
}

fn parse_bench(s: &str) -> Result<String, String> {
    let s = s.trim();
    if BENCHES.contains(&s) {
        Ok(s.to_string())
    } else {
        Err(format!(
            "no bench `{s}`; the benches: {}",
            BENCHES.join(", ")
        ))
    }
}

#[derive(Args, Debug)]
pub struct AllArgs {
    /// One JSON object per line instead of writing the tables: each row with its "bench",
    /// "device", "driver" and "date"; rows with "bench": "all" give each bench's seconds
    /// ("ran") and each peer not measured ("skipped", "why"). `--from` writes them later.
    #[arg(long)]
    json: bool,
    /// The Markdown file whose section for this device is written. The sections of other
    /// devices are kept, and so are this device's tables of benches this run leaves out.
    #[arg(long, value_name = "FILE", default_value = "docs/benchmarks.md")]
    out: std::path::PathBuf,
    /// Run only these, comma-separated: inverse, warp, vertex, lens, wide, models, plan,
    /// rolling-shutter, startup, and python (the Python package's frame loop beside cv2.remap). Default:
    /// all of them.
    #[arg(long, value_delimiter = ',', value_parser = parse_bench, value_name = "LIST")]
    benches: Vec<String>,
    /// Measure nothing: write the section of each device in FILE, the rows a `--json` run
    /// printed (`vklens bench all --json > rows.jsonl`, then `--from rows.jsonl`).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["json", "benches"])]
    from: Option<std::path::PathBuf>,
    /// The Python that runs the OpenCV peers (cli/benches/warp_vs_opencv.py beside `bench warp`,
    /// `python -m vklens.bench`); a peer whose imports (cv2, numpy; vklens for the frame loop)
    /// fail is skipped, and the section says so.
    #[arg(long, value_name = "PROGRAM", default_value = "python3")]
    python: String,
}

/// Today's date (UTC) as YYYY-MM-DD, from the system clock.
fn today() -> String {
    let days = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() / 86_400)
        .unwrap_or(0) as i64;
    // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02}")
}

/// A file of the source tree, below the working directory or the source tree's root.
fn source_file(relative: &str) -> Option<std::path::PathBuf> {
    [
        std::path::PathBuf::from(relative),
        crate::repo_root().join(relative),
    ]
    .into_iter()
    .find(|p| p.is_file())
}

/// Runs a Python peer after checking that `python` imports `imports`: its stdout, or why it
/// could not run (the last line Python wrote on stderr). Its own stderr (progress) passes
/// through.
fn python_peer(python: &str, imports: &str, args: &[String]) -> Result<String, String> {
    use std::process::{Command, Stdio};
    let last_line = |bytes: &[u8]| {
        String::from_utf8_lossy(bytes)
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("no message")
            .trim()
            .to_string()
    };
    let check = Command::new(python)
        .args(["-c", &format!("import {imports}")])
        .output()
        .map_err(|e| format!("{python}: {e}"))?;
    if !check.status.success() {
        return Err(last_line(&check.stderr));
    }
    let out = Command::new(python)
        .args(args)
        .stdin(Stdio::null())
        .stderr(Stdio::inherit())
        .output()
        .map_err(|e| format!("{python}: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "{python} {} failed ({})",
            args.join(" "),
            out.status
        ));
    }
    String::from_utf8(out.stdout).map_err(|e| e.to_string())
}

/// OpenCV's rows beside `bench warp` (`cli/benches/warp_vs_opencv.py --opencv-only --json`).
fn opencv_warp_rows(python: &str) -> Result<Vec<serde_json::Value>, String> {
    let script = source_file("cli/benches/warp_vs_opencv.py")
        .ok_or("cli/benches/warp_vs_opencv.py is not in this directory or the source tree")?;
    let sizes: Vec<String> = crate::bench::warp::SIZES
        .iter()
        .map(|(w, h)| format!("{w}x{h}"))
        .collect();
    let out = python_peer(
        python,
        "cv2, numpy",
        &[
            script.display().to_string(),
            "--opencv-only".into(),
            "--sizes".into(),
            sizes.join(","),
            "--json".into(),
        ],
    )?;
    out.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| serde_json::from_str(l).map_err(|e| format!("its output: {e}")))
        .collect()
}

/// The Python frame loop's rows (`python -m vklens.bench --json`), each with the run's facts.
fn python_frame_rows(python: &str) -> Result<Vec<serde_json::Value>, String> {
    let out = python_peer(
        python,
        "cv2, numpy, vklens",
        &["-m".into(), "vklens.bench".into(), "--json".into()],
    )?;
    let v: serde_json::Value =
        serde_json::from_str(&out).map_err(|e| format!("its output: {e}"))?;
    let meta = v["meta"].as_object().cloned().unwrap_or_default();
    let rows = v["rows"].as_array().cloned().unwrap_or_default();
    Ok(rows
        .into_iter()
        .map(|mut r| {
            if let Some(o) = r.as_object_mut() {
                for key in ["opencv", "numpy", "device_start_ms", "frames", "repeats"] {
                    if let Some(x) = meta.get(key) {
                        o.insert(key.into(), x.clone());
                    }
                }
                if let Some(d) = meta.get("device") {
                    o.insert("python_device".into(), d.clone());
                }
            }
            r
        })
        .collect())
}

/// Typed rows as JSON rows.
fn to_json<T: serde::Serialize>(rows: &[T]) -> vklens::Result<Vec<serde_json::Value>> {
    rows.iter()
        .map(|r| serde_json::to_value(r).map_err(|e| vklens::Error::internal(e.to_string())))
        .collect()
}

/// The devices of `rows`, each once, in the order they appear.
fn devices(rows: &[serde_json::Value]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for r in rows {
        if let Some(d) = r["device"].as_str() {
            if !out.iter().any(|x| x == d) {
                out.push(d.to_string());
            }
        }
    }
    out
}

/// Writes each device's section of `rows` into `out`.
fn write_sections(out: &std::path::Path, rows: &[serde_json::Value]) -> Result<(), CliError> {
    use crate::bench::report::{subsection, write_section, RUN};
    let mut text = match std::fs::read_to_string(out) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
        Err(e) => return Err(CliError::io(out, "cannot read", &e)),
    };
    let names = devices(rows);
    if names.is_empty() {
        return Err(CliError::input("no rows with a \"device\" to write"));
    }
    for device in &names {
        let of_device: Vec<serde_json::Value> = rows
            .iter()
            .filter(|r| r["device"] == device.as_str())
            .cloned()
            .collect();
        let mut fresh = Vec::new();
        for bench in BENCHES {
            let present = of_device.iter().any(|r| {
                r["bench"] == bench
                    || (r["bench"] == RUN && (r["ran"] == bench || r["for"] == bench))
            });
            if present {
                if let Some(s) = subsection(bench, &of_device)? {
                    fresh.push((bench, s));
                }
            }
        }
        text = write_section(&text, device, &fresh);
        eprintln!("wrote the {device} section of {}", out.display());
    }
    vklens::imaging::file::write_atomically(out, |tmp| std::fs::write(tmp, &text))?;
    Ok(())
}

/// `vklens bench all --from FILE`: the sections of saved rows, nothing measured.
fn all_from(from: &std::path::Path, out: &std::path::Path) -> Result<(), CliError> {
    let text = std::fs::read_to_string(from).map_err(|e| CliError::io(from, "cannot read", &e))?;
    let rows = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            serde_json::from_str::<serde_json::Value>(l)
                .map_err(|e| CliError::input(format!("{} line {}: {e}", from.display(), i + 1)))
        })
        .collect::<Result<Vec<_>, _>>()?;
    write_sections(out, &rows)
}

/// `vklens bench all`: every bench on one device (or those `--benches` names), and the OpenCV
/// peers Python can run; the rows as JSON lines, or each bench's tables and goals written into
/// the device's section of `--out` (headed by the device, the driver and the date).
pub fn all(args: AllArgs) -> Result<(), CliError> {
    use crate::bench::report::RUN;
    if !args.json {
        super::output::check_output(&args.out, "benchmark", &["md"])?;
    }
    if let Some(from) = &args.from {
        return all_from(from, &args.out);
    }
    let chosen: Vec<&str> = BENCHES
        .iter()
        .copied()
        .filter(|b| args.benches.is_empty() || args.benches.iter().any(|x| x == b))
        .collect();
    // Everything the benches read is found before the first of them runs.
    let reference = match chosen.contains(&"inverse") {
        true => Some(load_reference()?),
        false => None,
    };
    let lenses = match chosen.contains(&"lens") {
        true => Some(data_folder(None, "lenses", "lenses")?),
        false => None,
    };
    let scenes = match chosen.contains(&"plan") || chosen.contains(&"startup") {
        true => Some(data_folder(None, "examples/scenes", "examples/scenes")?),
        false => None,
    };
    let ctx = context()?;
    let (device, driver, date) = (
        ctx.gpu().device_name().to_string(),
        ctx.gpu().driver().to_string(),
        today(),
    );
    eprintln!("device: {device} ({driver})");
    let mut rows: Vec<serde_json::Value> = Vec::new();
    let push = |rows: &mut Vec<serde_json::Value>, bench: &str, new: Vec<serde_json::Value>| {
        for mut r in new {
            if let Some(o) = r.as_object_mut() {
                o.insert("bench".into(), bench.into());
                o.insert("device".into(), device.clone().into());
                o.insert("driver".into(), driver.clone().into());
                o.insert("date".into(), date.clone().into());
            }
            rows.push(r);
        }
    };
    for &bench in &chosen {
        let start = std::time::Instant::now();
        let mut skipped: Vec<(&str, String)> = Vec::new();
        let measured: Vec<serde_json::Value> = match bench {
            "inverse" => match &reference {
                Some(reference) => to_json(&inverse::run(
                    reference,
                    Some(&ctx),
                    &InverseBenchOptions::default(),
                    super::progress_line,
                )?)?,
                None => Vec::new(),
            },
            "warp" => {
                let mut r = crate::bench::warp::run(
                    &ctx,
                    &crate::bench::warp::SIZES,
                    super::progress_line,
                )?;
                super::progress_done(
                    "bench warp: OpenCV beside it (cli/benches/warp_vs_opencv.py)",
                );
                match opencv_warp_rows(&args.python) {
                    Ok(peers) => r.extend(peers),
                    Err(why) => skipped.push((
                        "`cv2.remap` and `cv2.undistortPoints`, cli/benches/warp_vs_opencv.py",
                        why,
                    )),
                }
                r
            }
            "vertex" => crate::bench::vertex::run(&ctx, &crate::bench::vertex::SIZES, &mut |s| {
                super::progress_line(s)
            })?,
            "lens" => match &lenses {
                Some(dir) => {
                    crate::bench::lens::run(&ctx, dir, 256, &mut |s| super::progress_line(s))?
                }
                None => Vec::new(),
            },
            "wide" => crate::bench::wide::run(&ctx, &mut |s| super::progress_line(s))?,
            "labels" => crate::bench::labels::run(&ctx, &mut |s| super::progress_line(s))?,
            "rolling-shutter" => {
                crate::bench::rolling_shutter::run(&ctx, &mut |s| super::progress_line(s))?
            }
            "startup" => match &scenes {
                Some(dir) => {
                    let mut r = crate::bench::startup::run(&args.python, dir, &mut |s| {
                        super::progress_line(s)
                    })?;
                    // The guard against slower pipeline builds compares with the table this
                    // run replaces (none on a first run, or where --json writes no file).
                    if !args.json {
                        if let Ok(previous) = std::fs::read_to_string(&args.out) {
                            r.extend(crate::bench::startup::previous_rows(&previous, &device));
                        }
                    }
                    r
                }
                None => Vec::new(),
            },
            "models" => to_json(&crate::bench::models::run(
                Some(&ctx),
                super::progress_line,
            )?)?,
            "plan" => match &scenes {
                Some(dir) => crate::bench::plan::run(&ctx, dir, &mut |s| super::progress_line(s))?,
                None => Vec::new(),
            },
            "python" => match python_frame_rows(&args.python) {
                Ok(r) => r,
                Err(why) => {
                    skipped.push(("`python -m vklens.bench`", why));
                    Vec::new()
                }
            },
            _ => Vec::new(),
        };
        let seconds = start.elapsed().as_secs_f64();
        super::progress_done(&format!(
            "bench {bench}: {} rows in {seconds:.0} s",
            measured.len()
        ));
        push(&mut rows, bench, measured);
        let mut run = vec![serde_json::json!({"ran": bench, "seconds": seconds})];
        for (peer, why) in skipped {
            eprintln!("bench {bench}: skipped {peer}: {why}");
            run.push(serde_json::json!({"for": bench, "skipped": peer, "why": why}));
        }
        push(&mut rows, RUN, run);
    }
    finish(&ctx)?;
    if args.json {
        let mut out = std::io::stdout().lock();
        for r in &rows {
            use std::io::Write as _;
            writeln!(out, "{r}")
                .map_err(|e| CliError::io(std::path::Path::new("<stdout>"), "cannot write", &e))?;
        }
        return Ok(());
    }
    write_sections(&args.out, &rows)
}
