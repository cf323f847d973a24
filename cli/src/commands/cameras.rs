//! `vklens cameras FILE`: what a calibration file holds; `vklens convert`: one of its cameras
//! in another tool's format.

use std::path::{Path, PathBuf};

use clap::Args;

use super::CliError;
use vklens::io::catalog;
use vklens::io::writers::{self, Format};

#[derive(Args, Debug)]
pub struct CamerasArgs {
    /// The calibration file (any format vklens reads; detected from its content).
    #[arg(value_name = "FILE")]
    file: PathBuf,
    /// One JSON object per camera (index, name, model, width, height, format, error) instead
    /// of the table.
    #[arg(long)]
    json: bool,
}

#[derive(Args, Debug)]
pub struct ConvertArgs {
    /// The camera to convert (pick one of several with --camera-index or --camera-name; give
    /// a file without an image size one with --size WxH).
    #[arg(long, value_name = "CAM")]
    camera: PathBuf,
    /// vklens: vklens JSON (holds every camera). opencv: FileStorage YAML as calibrateCamera
    /// writes it. ros: camera_info. kalibr: a camchain (cam0). colmap: cameras.txt. basalt:
    /// Basalt's calibration JSON. A format that cannot hold the camera exactly is refused.
    #[arg(long, value_name = "FORMAT", value_parser = parse_format)]
    to: Format,
    /// Where to write (atomically); `-` for stdout.
    #[arg(long, value_name = "OUT")]
    output: PathBuf,
}

fn parse_format(s: &str) -> Result<Format, String> {
    s.parse().map_err(|e: vklens::Error| e.to_string())
}

/// `vklens cameras`.
pub fn list(args: CamerasArgs) -> Result<(), CliError> {
    let options = super::camera_options();
    let listing = vklens::io::camera::list_camera_file(&args.file, options.size)?;
    let format = listing.format;
    if args.json {
        for (index, found) in listing.cameras.iter().enumerate() {
            let mut v = serde_json::json!({
                "index": index, "name": found.name, "format": format,
            });
            match &found.camera {
                Ok(c) => {
                    v["model"] = c.model_name().into();
                    v["width"] = c.width.into();
                    v["height"] = c.height.into();
                }
                Err(e) => v["error"] = e.to_string().into(),
            }
            outln!("{v}")?;
        }
        return Ok(());
    }
    outln!(
        "{}: {} ({} camera{})",
        args.file.display(),
        catalog::article(format),
        listing.cameras.len(),
        if listing.cameras.len() == 1 { "" } else { "s" }
    )?;
    outln!(
        "{:>5}  {:<14} {:<20} {:>11}",
        "index",
        "name",
        "model",
        "size"
    )?;
    for (index, found) in listing.cameras.iter().enumerate() {
        let name = if found.name.is_empty() {
            "-"
        } else {
            &found.name
        };
        match &found.camera {
            Ok(c) => outln!(
                "{index:>5}  {name:<14} {:<20} {:>11}",
                c.model_name(),
                format!("{}x{}", c.width, c.height)
            )?,
            Err(e) => outln!("{index:>5}  {name:<14} cannot load: {e}")?,
        }
    }
    Ok(())
}

/// `vklens convert`.
pub fn convert(args: ConvertArgs) -> Result<(), CliError> {
    let camera = super::load_camera(&args.camera)?;
    let text = writers::write_camera(&camera, args.to)?;
    if args.output == Path::new("-") {
        return super::write_stdout(format_args!("{text}"));
    }
    vklens::imaging::file::write_atomically(&args.output, |tmp| std::fs::write(tmp, &text))?;
    eprintln!(
        "wrote {} ({}, {} camera)",
        args.output.display(),
        args.to.describe(),
        camera.model_name()
    );
    Ok(())
}
