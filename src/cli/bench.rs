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
            println!(
                "{}",
                serde_json::to_string(r).map_err(|e| CliError::internal(e.to_string()))?
            );
        }
    } else {
        println!("{}", inverse::table(&rows));
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
    print_rows(&rows, args.json, crate::bench::warp::table);
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
    print_rows(&rows, args.json, crate::bench::vertex::table);
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
fn print_rows(rows: &[serde_json::Value], json: bool, table: fn(&[serde_json::Value]) -> String) {
    if json {
        for r in rows {
            println!("{r}");
        }
    } else {
        println!("{}", table(rows));
    }
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
            println!("{r}");
        }
    } else {
        println!("{}", crate::bench::lens::table(&rows));
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
    print_rows(&rows, args.json, crate::bench::plan::table);
    Ok(())
}
