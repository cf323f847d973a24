//! `vklens lens ...`: real lens systems (Heidrich et al.).

use std::path::PathBuf;

use clap::{Args, Subcommand};
use serde_json::json;

use super::{progress_done, progress_line, CliError};
use vklens::imaging::{BitDepth, Pixels, Raster};
use vklens::lens::{analyse, distortion_curve, fit_opencv, Prescription, LAMBDA_D};
use vklens::plan::{LensRequest, Plan};

#[derive(Subcommand, Debug)]
pub enum LensCommand {
    /// First-order properties of a lens file (paraxial, d line) and its distortion curve
    /// (exact chief rays). Axial positions are mm from the front vertex, towards the image.
    Info(InfoArgs),
    /// Fit the OpenCV standard model to the traced lens (focused at infinity or --focus M, chief rays on
    /// the paraxial focal plane) for a sensor and pixel count, and write a camera file every
    /// other command accepts. The fit residual goes to stderr.
    FitOpencv(FitArgs),
    /// Render a scene through the lens with Heidrich et al.'s image-based model on the GPU (or,
    /// with --reference, with the CPU distribution ray tracer it approximates): depth of
    /// field from lens samples, vignetting, distortion and the other aberrations of the real
    /// glass, chromatic aberration per channel with --chromatic.
    Render(RenderArgs),
}

#[derive(Args, Debug)]
#[command(after_help = "Examples:
  vklens lens render --lens lenses/dgauss.50mm.dat --scene boxes --output boxes.png
  vklens lens render --lens lenses/biconvex.50mm.dat --scene boxes --output singlet.png --chromatic --samples 32
  vklens lens render --lens lenses/biconvex.50mm.dat --scene boxes --output ref.png --reference

The camera frame has its origin at the lens's front vertex (OpenCV axes: x right, y down,
z into the scene). Output pixels hold irradiance relative to the film centre of a white
scene: vignetting darkens the corners, nothing is rescaled. `vklens bench lens` shows what
samples, --max-angle and --grid cost in time and error against --reference.")]
pub struct RenderArgs {
    /// The lens file.
    #[arg(long, value_name = "FILE")]
    lens: PathBuf,
    /// checkerboard[:COLSxROWS[:SQUARE_M]], grid[:N], boxes, or an .obj/.gltf/.glb file.
    #[arg(long, value_name = "SCENE")]
    scene: String,
    /// Colour output: .png (8-bit) or .exr (float).
    #[arg(long, value_name = "OUT")]
    output: PathBuf,
    /// Focus distance in metres from the front vertex. Default: the scene's centre.
    #[arg(long, value_name = "M")]
    focus: Option<f64>,
    /// f-number (stops the lens down; default: the lens wide open).
    #[arg(long, value_name = "N")]
    fstop: Option<f64>,
    /// Lens sample points (depth of field; 1 = the centre of the rear lens surface only).
    #[arg(long, value_name = "N", default_value_t = 10,
          value_parser = clap::value_parser!(u32).range(1..=1024))]
    samples: u32,
    /// Subdivide a film cell until its projection's largest angle error is below this
    /// (degrees; Heidrich et al.: 0.05).
    #[arg(long, value_name = "DEG", default_value_t = 0.05)]
    max_angle: f64,
    /// Render with the CPU distribution ray tracer (same lens samples) instead of the GPU.
    #[arg(long)]
    reference: bool,
    /// Film size in mm, WxH.
    #[arg(long, value_name = "WxH_mm", default_value = "36x24", value_parser = parse_pair_f64)]
    sensor: (f64, f64),
    /// Film size in pixels, WxH (square pixels).
    #[arg(long, value_name = "WxH", default_value = "480x320", value_parser = parse_pair_u32)]
    pixels: (u32, u32),
    /// Film grid per cell, N×N quads (Heidrich et al.: 10).
    #[arg(long, value_name = "N", default_value_t = 10,
          value_parser = clap::value_parser!(u32).range(1..=256))]
    grid: u32,
    /// Deepest quad-tree level.
    #[arg(long, value_name = "L", default_value_t = 4,
          value_parser = clap::value_parser!(u32).range(0..=8))]
    max_depth: u32,
    /// Trace R, G and B at their own wavelengths (C, e, F lines): lateral and longitudinal
    /// colour from the glass data (needs Abbe numbers in the lens file).
    #[arg(long)]
    chromatic: bool,
    /// Camera pose: OpenCV rvec and tvec (world → camera), rx,ry,rz,tx,ty,tz. Default: the
    /// scene centred, filling about 80 % of the view.
    #[arg(long, value_name = "POSE", allow_hyphen_values = true)]
    pose: Option<String>,
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
    /// Focus distance in metres from the front vertex (default: infinity). The camera centre
    /// of the fitted model is the entrance pupil.
    #[arg(long, value_name = "M")]
    focus: Option<f64>,
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
        LensCommand::Render(args) => render(args),
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
        outln!(
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
        )?;
        return Ok(());
    }
    let mm = |v: Option<f64>| {
        v.map(|x| format!("{x:.3} mm"))
            .unwrap_or_else(|| "∞ (afocal)".into())
    };
    outln!(
        "{} ({} surfaces; d line, {} µm)",
        lens.name,
        lens.surfaces.len(),
        LAMBDA_D
    )?;
    outln!("  effective focal length   {}", mm(p.efl))?;
    outln!("  back focal length        {}", mm(p.bfl))?;
    outln!("  front focal length       {}", mm(p.ffl))?;
    outln!(
        "  f-number                 {}",
        p.f_number
            .map(|f| format!("f/{f:.2}"))
            .unwrap_or_else(|| "—".into())
    )?;
    outln!("  (z from the front vertex, towards the image)")?;
    outln!(
        "  principal planes         H {}  H' {}",
        mm(p.front_principal_z),
        mm(p.rear_principal_z)
    )?;
    outln!(
        "  entrance pupil           z {:.3} mm, ⌀ {:.3} mm",
        p.entrance_pupil_z,
        p.entrance_pupil_diameter
    )?;
    outln!(
        "  exit pupil               z {:.3} mm, ⌀ {:.3} mm",
        p.exit_pupil_z,
        p.exit_pupil_diameter
    )?;
    outln!("  rear vertex              z {:.3} mm", p.rear_vertex_z)?;
    outln!("  distortion (chief rays on the paraxial focal plane, focus at infinity):")?;
    outln!("    field°   height mm   ideal mm   distortion %")?;
    for d in &curve {
        outln!(
            "    {:6.2}  {:9.4}  {:9.4}  {:+8.3}",
            d.field_deg,
            d.image_height_mm,
            d.paraxial_height_mm,
            d.distortion_percent
        )?;
    }
    if curve.len() < 12 {
        outln!(
            "    (beyond {:.1}° the chief ray is vignetted)",
            curve.last().map(|d| d.field_deg).unwrap_or(0.0)
        )?;
    }
    Ok(())
}

fn fit(args: FitArgs) -> Result<(), CliError> {
    let lens = Prescription::load(&args.lens).map_err(|e| CliError::input(e.to_string()))?;
    let focus = args.focus.unwrap_or(f64::INFINITY);
    if !(focus > 0.0) {
        return Err(CliError::input(format!(
            "--focus {focus}: expected a distance in metres > 0"
        )));
    }
    let f = fit_opencv(&lens, args.sensor, args.pixels, focus, LAMBDA_D)
        .map_err(|e| CliError::input(format!("{}: {e}", args.lens.display())))?;
    let camera = json!({
        "width": f.width, "height": f.height,
        "fx": f.fx, "fy": f.fy, "cx": f.cx, "cy": f.cy,
        "dist_coeffs": f.dist_coeffs,
        "fitted_to": {
            "lens": lens.name,
            "sensor_mm": [args.sensor.0, args.sensor.1],
            "focus_m": if focus.is_infinite() { json!("infinity") } else { json!(focus) },
            "camera_centre": "entrance pupil",
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
        Some(path) => {
            vklens::imaging::file::write_atomically(path, |tmp| std::fs::write(tmp, &text))?
        }
        None => out!("{text}")?,
    }
    Ok(())
}

fn render(args: RenderArgs) -> Result<(), CliError> {
    use vklens::lens::image_model::{ModelOptions, RGB_WAVELENGTHS};
    use vklens::lens::reference::{render_reference, Channel};
    use vklens::scene::{builtin, Pose};

    let lens = Prescription::load(&args.lens).map_err(|e| CliError::input(e.to_string()))?;
    let ext = super::output::check_output(&args.output, "colour", &["png", "exr"])?;
    if !(args.max_angle.is_finite() && args.max_angle > 0.0) {
        return Err(CliError::input(format!(
            "--max-angle {}: expected a positive number of degrees",
            args.max_angle
        )));
    }
    if let Some(f) = args.focus {
        if !(f.is_finite() && f > 0.0) {
            return Err(CliError::input(format!(
                "--focus {f}: expected a distance in metres > 0"
            )));
        }
    }
    let pitch = args.sensor.0 / args.pixels.0 as f64;
    if ((args.sensor.1 / args.pixels.1 as f64) / pitch - 1.0).abs() > 1e-3 {
        return Err(CliError::input(format!(
            "--sensor {}x{} mm and --pixels {}x{} give non-square pixels",
            args.sensor.0, args.sensor.1, args.pixels.0, args.pixels.1
        )));
    }
    if args.chromatic && lens.surfaces.iter().all(|s| s.abbe.is_none()) {
        return Err(CliError::input(format!(
            "{}: --chromatic needs Abbe numbers (5th column) for the glasses",
            args.lens.display()
        )));
    }
    let scene = builtin::parse(&args.scene).map_err(|e| CliError::input(e.to_string()))?;
    let lens_error = |e: CliError| e.context(args.lens.display());
    let pose = match &args.pose {
        Some(p) => Some(Pose::parse(p)?),
        None => None,
    };
    let (optics, pose) = vklens::lens::frame_scene(
        &lens,
        args.pixels,
        pitch,
        args.fstop,
        args.focus,
        pose,
        &scene,
    )
    .map_err(lens_error)?;
    let focus = optics.focus_m;
    let options = ModelOptions {
        samples: args.samples,
        grid: args.grid,
        max_angle_deg: args.max_angle,
        max_depth: args.max_depth,
        lambda_um: LAMBDA_D,
        vignetting: true,
    };
    progress_line(&format!(
        "{}: f/{:.2}, focus {:.3} m, film {}×{} at {:.3} mm from the rear vertex",
        lens.name,
        optics.f_number,
        focus,
        args.pixels.0,
        args.pixels.1,
        optics.film.z_mm - lens.vertex_positions()[lens.surfaces.len() - 1]
    ));
    let raster = if args.reference {
        let channels: Vec<Channel> = if args.chromatic {
            RGB_WAVELENGTHS
                .iter()
                .zip(vklens::lens::image_model::RGB_CHANNELS)
                .map(|(&lambda_um, mask)| Channel { lambda_um, mask })
                .collect()
        } else {
            vec![Channel {
                lambda_um: LAMBDA_D,
                mask: vklens::lens::image_model::ALL_CHANNELS,
            }]
        };
        let frame = render_reference(&optics, &channels, args.samples, &scene, &pose, &|f| {
            progress_line(&format!("reference ray tracing: {:3.0} %", 100.0 * f))
        })
        .map_err(lens_error)?;
        progress_done(&format!(
            "reference: {} rays through the lens in {:.2} s",
            frame.rays, frame.seconds
        ));
        film_raster(args.pixels, &frame.pixels, ext == "exr")
    } else {
        progress_line("tracing the film grids through the lens samples");
        let request = LensRequest {
            prescription: lens.clone(),
            pixels: args.pixels,
            pitch_mm: pitch,
            f_number: args.fstop,
            options,
            chromatic: args.chromatic,
            exr: ext == "exr",
        };
        let plan = Plan::from_lens_request(&request, &optics, pose).map_err(lens_error)?;
        render_planned(&plan, &scene)?
    };
    vklens::imaging::file::save(&raster, &args.output)?;
    eprintln!("wrote {}", args.output.display());
    Ok(())
}

/// The image-based model's plan rendered once through the planner's recorder, as a scene
/// file's lens is: the film's colour, its accumulated weight kept (vignetting).
fn render_planned(plan: &Plan, scene: &vklens::scene::Scene) -> Result<Raster, CliError> {
    let ctx = super::context()?;
    let gpu_error = |e: vklens::Error| match e {
        vklens::Error::Input(m) => CliError::input(m),
        other => CliError::from(other),
    };
    let (projections, max_angle) = plan.lens().map_or((0, 0.0), |l| {
        l.models.iter().fold((0, 0.0f64), |(n, a), (m, _)| {
            (n + m.projection_count(), a.max(m.max_angle_deg()))
        })
    });
    progress_line(&format!(
        "rendering {projections} perspective projections (largest angle error {max_angle:.4}°) on {}",
        ctx.gpu().device_name()
    ));
    let mut rendered = None;
    vklens::host::plan::execute_untimed(&ctx, plan, scene, [0], &mut |frame| {
        rendered = Some((frame.rendered, frame.ms));
        Ok(())
    })
    .map_err(gpu_error)?;
    super::finish(&ctx)?;
    let (colour, ms) = rendered
        .and_then(|(r, ms)| Some((r.color?, ms)))
        .ok_or_else(|| CliError::from(vklens::Error::internal("the lens plan rendered no film")))?;
    progress_done(&format!("{projections} projections in {ms:.1} ms"));
    Ok(colour)
}

/// The reference ray tracer's film as an image: float for EXR, else 8-bit; opaque.
fn film_raster((width, height): (u32, u32), pixels: &[[f32; 4]], float: bool) -> Raster {
    let film = Raster {
        width,
        height,
        pixels: Pixels::Rgba32F(pixels.iter().map(|p| [p[0], p[1], p[2], 1.0]).collect()),
        bit_depth: BitDepth::F32,
    };
    if float {
        film
    } else {
        film.to_rgba8_rounded()
    }
}
