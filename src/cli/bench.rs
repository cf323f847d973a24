//! `vklens bench ...`.

use clap::Args;

use super::{context, finish, CliError};
use crate::bench::inverse::{self, InverseBenchOptions};
use crate::io::reference::{load_reference, reference_path};

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
    methods: Vec<crate::model::InverseMethod>,
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
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
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

fn bench_error(e: crate::Error) -> CliError {
    match e {
        crate::Error::Input(m) => CliError::input(m),
        other => CliError::from(other),
    }
}

pub fn lens(args: LensArgs) -> Result<(), CliError> {
    let dir = data_folder(args.lenses.clone(), "lenses", "--lenses")?;
    let ctx = context()?;
    eprintln!("device: {}", ctx.gpu().device_name());
    let rows = crate::bench::lens::run(&ctx, &dir, args.pixels, &mut |s| super::progress_line(s))
        .map_err(|e| match e {
        crate::Error::Input(m) => CliError::input(m),
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
                .map_err(|e| CliError::from(crate::Error::internal(e.to_string())))?;
            outln!("{v}")?;
        }
    } else {
        outln!("{}", crate::bench::models::table(&rows))?;
    }
    Ok(())
}

#[derive(Args, Debug)]
pub struct AllArgs {
    /// One JSON object per line (each row with its "bench", "device", "driver" and "date")
    /// instead of writing the tables.
    #[arg(long)]
    json: bool,
    /// The Markdown file whose section for this device is written (the sections of other
    /// devices are kept).
    #[arg(long, value_name = "FILE", default_value = "docs/benchmarks.md")]
    out: std::path::PathBuf,
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

/// `vklens bench all`: every bench on one device, its tables written into one section of
/// `--out` that names the device, the driver and the date.
pub fn all(args: AllArgs) -> Result<(), CliError> {
    use std::fmt::Write as _;
    let reference = load_reference()?;
    let lenses = data_folder(None, "lenses", "lenses")?;
    let scenes = data_folder(None, "examples/scenes", "examples/scenes")?;
    if !args.json {
        super::output::check_output(&args.out, "benchmark", &["md"])?;
    }
    let ctx = context()?;
    let (device, driver, date) = (
        ctx.gpu().device_name().to_string(),
        ctx.gpu().driver().to_string(),
        today(),
    );
    eprintln!("device: {device} ({driver})");
    let mut sections: Vec<(&str, String, f64)> = Vec::new();
    let mut json_rows: Vec<serde_json::Value> = Vec::new();
    let mut timed = |name: &'static str,
                     run: &mut dyn FnMut() -> crate::Result<(Vec<serde_json::Value>, String)>|
     -> Result<(), CliError> {
        let start = std::time::Instant::now();
        let (rows, table) = run()?;
        let s = start.elapsed().as_secs_f64();
        super::progress_done(&format!("bench {name}: {} rows in {s:.0} s", rows.len()));
        for mut r in rows {
            if let Some(o) = r.as_object_mut() {
                o.insert("bench".into(), name.into());
                o.insert("device".into(), device.clone().into());
                o.insert("driver".into(), driver.clone().into());
                o.insert("date".into(), date.clone().into());
            }
            json_rows.push(r);
        }
        sections.push((name, table, s));
        Ok(())
    };
    timed("inverse", &mut || {
        let rows = inverse::run(
            &reference,
            Some(&ctx),
            &InverseBenchOptions::default(),
            super::progress_line,
        )?;
        let json = rows
            .iter()
            .map(|r| serde_json::to_value(r).map_err(|e| crate::Error::internal(e.to_string())))
            .collect::<crate::Result<Vec<_>>>()?;
        Ok((json, inverse::table(&rows)))
    })?;
    timed("warp", &mut || {
        let rows = crate::bench::warp::run(&ctx, &crate::bench::warp::SIZES, super::progress_line)?;
        let table = crate::bench::warp::table(&rows);
        Ok((rows, table))
    })?;
    timed("vertex", &mut || {
        let rows = crate::bench::vertex::run(&ctx, &crate::bench::vertex::SIZES, &mut |s| {
            super::progress_line(s)
        })?;
        let table = crate::bench::vertex::table(&rows);
        Ok((rows, table))
    })?;
    timed("lens", &mut || {
        let rows = crate::bench::lens::run(&ctx, &lenses, 256, &mut |s| super::progress_line(s))?;
        let table = crate::bench::lens::table(&rows);
        Ok((rows, table))
    })?;
    timed("wide", &mut || {
        let rows = crate::bench::wide::run(&ctx, &mut |s| super::progress_line(s))?;
        let table = crate::bench::wide::table(&rows);
        Ok((rows, table))
    })?;
    timed("models", &mut || {
        let rows = crate::bench::models::run(Some(&ctx), super::progress_line)?;
        let json = rows
            .iter()
            .map(|r| serde_json::to_value(r).map_err(|e| crate::Error::internal(e.to_string())))
            .collect::<crate::Result<Vec<_>>>()?;
        Ok((json, crate::bench::models::table(&rows)))
    })?;
    timed("plan", &mut || {
        let rows = crate::bench::plan::run(&ctx, &scenes, &mut |s| super::progress_line(s))?;
        let table = crate::bench::plan::table(&rows);
        Ok((rows, table))
    })?;
    finish(&ctx)?;
    if args.json {
        let mut out = std::io::stdout().lock();
        for r in &json_rows {
            use std::io::Write as _;
            writeln!(out, "{r}")
                .map_err(|e| CliError::io(std::path::Path::new("<stdout>"), "cannot write", &e))?;
        }
        return Ok(());
    }
    let begin = format!("<!-- bench all: {device} -->");
    let end = format!("<!-- end bench all: {device} -->");
    let total: f64 = sections.iter().map(|s| s.2).sum();
    let mut section = format!(
        "{begin}\n## {device}\n\n`vklens bench all` on {device}, driver {driver}, {date} \
         ({total:.0} s in all). Every table below is from this one run.\n"
    );
    for (name, table, s) in &sections {
        let _ = write!(
            section,
            "\n### `vklens bench {name}` ({device}, {driver}, {date}; {s:.0} s)\n\n{}\n",
            table.trim_end()
        );
    }
    section.push_str(&end);
    let old = match std::fs::read_to_string(&args.out) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
        Err(e) => return Err(CliError::io(&args.out, "cannot read", &e)),
    };
    let new = match (old.find(&begin), old.find(&end)) {
        (Some(a), Some(b)) if b > a => {
            format!("{}{section}{}", &old[..a], &old[b + end.len()..])
        }
        _ => format!("{}\n\n{section}\n", old.trim_end()),
    };
    crate::imaging::file::write_atomically(&args.out, |tmp| std::fs::write(tmp, &new))?;
    eprintln!("wrote the {device} section of {}", args.out.display());
    Ok(())
}
