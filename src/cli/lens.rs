//! `vklens lens ...`: real lens systems (seed 004).

use std::path::PathBuf;

use clap::{Args, Subcommand};
use serde_json::json;

use super::CliError;
use crate::lens::{analyse, distortion_curve, fit_opencv, Prescription, LAMBDA_D};

#[derive(Subcommand, Debug)]
pub enum LensCommand {
    /// First-order properties of a lens file (paraxial, d line) and its distortion curve
    /// (exact chief rays). Axial positions are mm from the front vertex, towards the image.
    Info(InfoArgs),
    /// Fit the OpenCV standard model to the traced lens (focused at infinity, chief rays on
    /// the paraxial focal plane) for a sensor and pixel count, and write a camera file every
    /// other command accepts. The fit residual goes to stderr.
    FitOpencv(FitArgs),
}

#[derive(Args, Debug)]
#[command(after_help = "Example:
  vklens lens fit-opencv --lens lenses/dgauss.50mm.dat --sensor 36x24 --pixels 1800x1200 --out dgauss.json
  vklens render --camera dgauss.json --scene boxes --output boxes.png")]
pub struct FitArgs {
    /// The lens file.
    #[arg(long, value_name = "FILE")]
    lens: PathBuf,
    /// Sensor size in mm, WxH (e.g. 36x24).
    #[arg(long, value_name = "WxH_mm", value_parser = parse_pair_f64)]
    sensor: (f64, f64),
    /// Image size in pixels, WxH (square pixels: the same pitch both ways).
    #[arg(long, value_name = "WxH", value_parser = parse_pair_u32)]
    pixels: (u32, u32),
    /// Camera file to write (vklens JSON); stdout when absent.
    #[arg(long, value_name = "CAM.json")]
    out: Option<PathBuf>,
}

fn parse_pair<T: std::str::FromStr>(s: &str) -> Option<(T, T)> {
    let (a, b) = s.split_once(['x', 'X'])?;
    Some((a.trim().parse().ok()?, b.trim().parse().ok()?))
}

fn parse_pair_f64(s: &str) -> Result<(f64, f64), String> {
    parse_pair::<f64>(s)
        .filter(|(a, b)| a.is_finite() && b.is_finite() && *a > 0.0 && *b > 0.0)
        .ok_or_else(|| format!("{s:?}: expected WxH in mm, e.g. 36x24"))
}

fn parse_pair_u32(s: &str) -> Result<(u32, u32), String> {
    parse_pair::<u32>(s)
        .filter(|(a, b)| (1..=65536).contains(a) && (1..=65536).contains(b))
        .ok_or_else(|| format!("{s:?}: expected WxH in pixels, e.g. 1920x1280"))
}

#[derive(Args, Debug)]
#[command(after_help = "Example:
  vklens lens info --lens lenses/dgauss.50mm.dat --json

Lens files: one surface per line, object side first: radius thickness n_d aperture [abbe]
(mm; radius 0 with n 0 marks the aperture stop; # starts a comment). lenses/ ships some.")]
pub struct InfoArgs {
    /// The lens file.
    #[arg(long, value_name = "FILE")]
    lens: PathBuf,
    /// One JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// Largest field angle of the distortion curve (degrees).
    #[arg(long, default_value_t = 30.0)]
    max_field: f64,
}

pub fn run(command: LensCommand) -> Result<(), CliError> {
    match command {
        LensCommand::Info(args) => info(args),
        LensCommand::FitOpencv(args) => fit(args),
    }
}

fn info(args: InfoArgs) -> Result<(), CliError> {
    let lens = Prescription::load(&args.lens).map_err(|e| CliError::input(e.to_string()))?;
    if !(args.max_field.is_finite() && args.max_field > 0.0 && args.max_field < 89.0) {
        return Err(CliError::input(format!(
            "--max-field {}: expected degrees in (0, 89)",
            args.max_field
        )));
    }
    let p = analyse(&lens, LAMBDA_D);
    let curve = distortion_curve(&lens, args.max_field, 12, LAMBDA_D);
    if args.json {
        let points: Vec<_> = curve
            .iter()
            .map(|d| {
                json!({
                    "field_deg": d.field_deg,
                    "image_height_mm": d.image_height_mm,
                    "paraxial_height_mm": d.paraxial_height_mm,
                    "distortion_percent": d.distortion_percent,
                })
            })
            .collect();
        println!(
            "{}",
            json!({
                "name": lens.name,
                "surfaces": lens.surfaces.len(),
                "wavelength_um": LAMBDA_D,
                "efl_mm": p.efl, "bfl_mm": p.bfl, "ffl_mm": p.ffl,
                "f_number": p.f_number,
                "front_principal_plane_z_mm": p.front_principal_z,
                "rear_principal_plane_z_mm": p.rear_principal_z,
                "entrance_pupil_z_mm": p.entrance_pupil_z,
                "entrance_pupil_diameter_mm": p.entrance_pupil_diameter,
                "exit_pupil_z_mm": p.exit_pupil_z,
                "exit_pupil_diameter_mm": p.exit_pupil_diameter,
                "rear_vertex_z_mm": p.rear_vertex_z,
                "z_origin": "front vertex, positive towards the image",
                "distortion": points,
            })
        );
        return Ok(());
    }
    let mm = |v: Option<f64>| {
        v.map(|x| format!("{x:.3} mm"))
            .unwrap_or_else(|| "∞ (afocal)".into())
    };
    println!(
        "{} ({} surfaces; d line, {} µm)",
        lens.name,
        lens.surfaces.len(),
        LAMBDA_D
    );
    println!("  effective focal length   {}", mm(p.efl));
    println!("  back focal length        {}", mm(p.bfl));
    println!("  front focal length       {}", mm(p.ffl));
    println!(
        "  f-number                 {}",
        p.f_number
            .map(|f| format!("f/{f:.2}"))
            .unwrap_or_else(|| "—".into())
    );
    println!("  (z from the front vertex, towards the image)");
    println!(
        "  principal planes         H {}  H' {}",
        mm(p.front_principal_z),
        mm(p.rear_principal_z)
    );
    println!(
        "  entrance pupil           z {:.3} mm, ⌀ {:.3} mm",
        p.entrance_pupil_z, p.entrance_pupil_diameter
    );
    println!(
        "  exit pupil               z {:.3} mm, ⌀ {:.3} mm",
        p.exit_pupil_z, p.exit_pupil_diameter
    );
    println!("  rear vertex              z {:.3} mm", p.rear_vertex_z);
    println!("  distortion (chief rays on the paraxial focal plane, focus at infinity):");
    println!("    field°   height mm   ideal mm   distortion %");
    for d in &curve {
        println!(
            "    {:6.2}  {:9.4}  {:9.4}  {:+8.3}",
            d.field_deg, d.image_height_mm, d.paraxial_height_mm, d.distortion_percent
        );
    }
    if curve.len() < 12 {
        println!(
            "    (beyond {:.1}° the chief ray is vignetted)",
            curve.last().map(|d| d.field_deg).unwrap_or(0.0)
        );
    }
    Ok(())
}

fn fit(args: FitArgs) -> Result<(), CliError> {
    let lens = Prescription::load(&args.lens).map_err(|e| CliError::input(e.to_string()))?;
    let f = fit_opencv(&lens, args.sensor, args.pixels, LAMBDA_D)
        .map_err(|e| CliError::input(format!("{}: {e}", args.lens.display())))?;
    let camera = json!({
        "width": f.width, "height": f.height,
        "fx": f.fx, "fy": f.fy, "cx": f.cx, "cy": f.cy,
        "dist_coeffs": f.dist_coeffs,
        "fitted_to": {
            "lens": lens.name,
            "sensor_mm": [args.sensor.0, args.sensor.1],
            "focus": "infinity",
            "max_field_deg": f.max_field_deg,
            "samples": f.samples,
            "max_residual_px": f.max_residual_px,
            "rms_residual_px": f.rms_residual_px,
        },
    });
    eprintln!(
        "{}: fx = fy = {:.3} px, k1 {:.5} k2 {:.5} k3 {:.5}; residual max {:.4} px, RMS {:.4} px over {} chief rays up to {:.1}°",
        lens.name, f.fx, f.dist_coeffs[0], f.dist_coeffs[1], f.dist_coeffs[4],
        f.max_residual_px, f.rms_residual_px, f.samples, f.max_field_deg
    );
    let text = format!("{camera:#}\n");
    match &args.out {
        Some(path) => crate::imaging::io::write_atomically(path, |tmp| {
            std::fs::write(tmp, &text).map_err(|e| e.to_string())
        })
        .map_err(CliError::input)?,
        None => print!("{text}"),
    }
    Ok(())
}
