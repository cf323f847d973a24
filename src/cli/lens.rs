//! `vklens lens ...`: real lens systems (seed 004).

use std::path::PathBuf;

use clap::{Args, Subcommand};
use serde_json::json;

use super::CliError;
use crate::lens::{analyse, distortion_curve, Prescription, LAMBDA_D};

#[derive(Subcommand, Debug)]
pub enum LensCommand {
    /// First-order properties of a lens file (paraxial, d line) and its distortion curve
    /// (exact chief rays). Axial positions are mm from the front vertex, towards the image.
    Info(InfoArgs),
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
