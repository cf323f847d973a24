//! `vklens distort | undistort | precorrect | overscan`.

use std::path::{Path, PathBuf};

use clap::Args;
use glam::DVec2;

use super::output::check_output;
use super::{context, CliError};
use crate::imaging::cpu_warp::{self, Sampling};
use crate::imaging::{file as image_io, BitDepth, Pixels, Raster};
use crate::model::overscan::overscan;
use crate::model::{Camera, CameraModel, InverseMethod};
use crate::pass::warp::PixelFormat;
use crate::{warp_geometry, Device, WarpDirection, WarpMethod, WarpOptions, Warper};

fn parse_warp_method(s: &str) -> Result<WarpMethod, String> {
    s.parse().map_err(|e: crate::Error| e.to_string())
}

fn parse_numbers<const N: usize>(s: &str, what: &str) -> Result<[f64; N], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| {
            t.trim()
                .parse::<f64>()
                .map_err(|_| format!("{what}: `{t}` is not a number"))
        })
        .collect::<Result<_, _>>()?;
    let arr: [f64; N] = v
        .try_into()
        .map_err(|_| format!("{what}: expected {N} comma-separated numbers, got `{s}`"))?;
    if arr.iter().any(|x| !x.is_finite()) {
        return Err(format!("{what}: numbers must be finite"));
    }
    Ok(arr)
}

fn parse_chromatic(s: &str) -> Result<[f64; 3], String> {
    parse_numbers::<3>(s, "--chromatic R_SCALE,G_SCALE,B_SCALE")
}

fn parse_fill(s: &str) -> Result<[f64; 4], String> {
    parse_numbers::<4>(s, "--fill R,G,B,A")
}

// clap shows a value parser's error as text.
fn parse_sampling(s: &str) -> Result<Sampling, String> {
    s.parse().map_err(|e: crate::Error| e.to_string())
}

/// Arguments shared by `distort`, `undistort` and `precorrect`.
#[derive(Args, Debug)]
pub struct WarpArgs {
    /// The lens: an OpenCV/ROS/vklens camera file, or a Brown lens {"model": "brown", ...}.
    #[arg(long, value_name = "CAM")]
    camera: PathBuf,
    /// Input image (PNG 8/16-bit or OpenEXR).
    #[arg(long, value_name = "IN")]
    input: PathBuf,
    /// Output image (.png keeps the input's bit depth; .exr writes 32-bit float).
    #[arg(long, value_name = "OUT")]
    output: PathBuf,
    /// The pinhole side's camera, when it differs from CAM's intrinsics and size: for distort,
    /// the input's (e.g. from `vklens overscan`); for undistort and precorrect, the output's.
    #[arg(long, value_name = "SRC")]
    source_camera: Option<PathBuf>,
    /// newton | lut | heikkila | fixed-point:N. lut builds a coordinate map once with Newton
    /// and samples it. Only distort solves an inverse; the other directions use the forward
    /// model and accept newton or lut.
    #[arg(long, default_value = "newton", value_parser = parse_warp_method)]
    method: WarpMethod,
    /// Lateral chromatic aberration: magnification of the R, G and B images about the principal
    /// point (e.g. 1.002,1,0.998).
    #[arg(long, value_name = "R_SCALE,G_SCALE,B_SCALE", value_parser = parse_chromatic)]
    chromatic: Option<[f64; 3]>,
    /// A full camera per channel, overriding CAM for R, G and B (three camera files, comma-
    /// separated): the general form of lateral colour. Runs through a map (--method lut).
    #[arg(
        long,
        value_name = "R_CAM,G_CAM,B_CAM",
        value_delimiter = ',',
        num_args = 1
    )]
    channel_cameras: Vec<PathBuf>,
    /// Value of pixels with no source (outside the valid domain or the source frame), in 0..1.
    #[arg(long, value_name = "R,G,B,A", value_parser = parse_fill)]
    fill: Option<[f64; 4]>,
    /// Also write the validity mask (8-bit PNG: 255 valid, 0 filled).
    #[arg(long, value_name = "MASK.png")]
    mask: Option<PathBuf>,
    /// bilinear (colour) or nearest (IDs, flow: exact values, rounded positions).
    #[arg(long, default_value = "bilinear", value_parser = parse_sampling)]
    sampling: Sampling,
    /// Where to run: gpu (Vulkan; lavapipe counts) or cpu (the f64 reference warp).
    #[arg(long, value_enum, default_value_t = super::Backend::Gpu)]
    backend: super::Backend,
}

fn pinhole(path: &Path) -> Result<Camera, CliError> {
    let cam = super::load_camera(path)?;
    if !cam.is_pinhole() {
        return Err(CliError::input(format!(
            "{}: the source camera is the pinhole side of the warp and must have no distortion",
            path.display()
        )));
    }
    Ok(cam)
}

/// Runs one of the three warp directions.
pub fn run(args: WarpArgs, direction: WarpDirection) -> Result<(), CliError> {
    check_output(&args.output, "image", &["png", "exr"])?;
    if let Some(m) = &args.mask {
        check_output(m, "mask", &["png"])?;
        super::output::distinct_outputs(&[("--output", &args.output), ("--mask", m)])?;
    }
    let cam = super::load_camera(&args.camera)?;
    let mut options = match direction {
        WarpDirection::Distort => WarpOptions::distort(),
        WarpDirection::Undistort => WarpOptions::undistort(),
        WarpDirection::Precorrect => WarpOptions::precorrect(),
    };
    options.method = args.method;
    options.sampling = args.sampling;
    options.chromatic = args.chromatic;
    options.fill = args.fill.map(|f| f.map(|c| c as f32)).unwrap_or([0.0; 4]);
    if let Some(src) = &args.source_camera {
        options.source_camera = Some(pinhole(src)?);
    }
    if !args.channel_cameras.is_empty() {
        let [r, g, b] = <[PathBuf; 3]>::try_from(args.channel_cameras.clone())
            .map_err(|_| CliError::input("--channel-cameras: expected three camera files R,G,B"))?;
        let cams = [
            super::load_camera(&r)?,
            super::load_camera(&g)?,
            super::load_camera(&b)?,
        ];
        for (path, c) in [&r, &g, &b].into_iter().zip(&cams) {
            if (c.width, c.height) != (cam.width, cam.height) {
                return Err(CliError::input(format!(
                    "{}: a channel camera must have CAM's size {}×{}",
                    path.display(),
                    cam.width,
                    cam.height
                )));
            }
        }
        options.channel_cameras = Some(Box::new(cams));
    }
    let geometry = warp_geometry(&cam, &options)?;
    let source = image_io::load(&args.input)?;
    if (source.width, source.height) != geometry.source_size {
        let whose = match (direction, &args.source_camera) {
            (WarpDirection::Distort, Some(src)) => src.display().to_string(),
            _ => args.camera.display().to_string(),
        };
        return Err(CliError::input(format!(
            "{}: the input is {}×{} but {whose} expects {}×{}",
            args.input.display(),
            source.width,
            source.height,
            geometry.source_size.0,
            geometry.source_size.1
        )));
    }
    let (out, mask) = match args.backend {
        // imaging::file::save writes float data read from an 8-bit file back as 8-bit.
        super::Backend::Cpu => {
            let (out, mask) = cpu_warp::warp(&geometry, &source, args.sampling, options.fill);
            (out, mask.iter().map(|&m| m > 127).collect::<Vec<_>>())
        }
        super::Backend::Gpu => {
            let device = Device::from_context(context()?);
            options.format = PixelFormat::of(&source);
            let mut warper = Warper::new(device.gpu(), &cam, &options)?;
            let warped = warper.run(&device, &source)?;
            device.check_validation()?;
            (warped.image, warped.mask)
        }
    };
    image_io::save(&out, &args.output)?;
    if let Some(m) = &args.mask {
        let raster = Raster {
            width: out.width,
            height: out.height,
            pixels: Pixels::Rgba8(
                mask.iter()
                    .map(|&v| if v { [255; 4] } else { [0, 0, 0, 255] })
                    .collect(),
            ),
            bit_depth: BitDepth::U8,
        };
        image_io::save(&raster, m)?;
    }
    let filled = mask.iter().filter(|&&m| !m).count();
    eprintln!(
        "wrote {} ({}×{}, {filled} px without a source{})",
        args.output.display(),
        out.width,
        out.height,
        if filled > 0 { ", filled" } else { "" }
    );
    if direction == WarpDirection::Precorrect {
        report_round_trip(&cam);
    }
    Ok(())
}

/// The Durham radial-correction paper's remark made visible: how far the closed-form inverse's round trip f(f⁻¹(r))
/// strays from r along the image diagonal, beside the exact inverse.
fn report_round_trip(cam: &Camera) {
    let worst = |model: &dyn CameraModel, method: InverseMethod| {
        let (w, h) = model.size();
        let mut worst = 0.0f64;
        for i in 0..=200 {
            let t = i as f64 / 200.0;
            let p = DVec2::new(t * (w as f64 - 1.0), t * (h as f64 - 1.0));
            if let Some(x) = model.undistort_pixel(p, method) {
                if let Some(back) = model.distort_pixel(x) {
                    worst = worst.max((back - p).length());
                }
            }
        }
        worst
    };
    let brown = cam.brown();
    let (model, paper): (&dyn CameraModel, &str) = match &brown {
        Some(b) => (b, "the Durham radial-correction paper's"),
        None => (cam, "Lambers et al.'s"),
    };
    eprintln!(
        "round trip f(f⁻¹(r)) along the diagonal: closed-form inverse ({paper} Eq. 2) off by up to {:.3} px; Newton off by up to {:.1e} px",
        worst(model, InverseMethod::Heikkila),
        worst(model, InverseMethod::Newton)
    );
}

/// `vklens overscan`.
#[derive(Args, Debug)]
pub struct OverscanArgs {
    /// The lens.
    #[arg(long, value_name = "CAM")]
    camera: PathBuf,
    /// Source pixels per output pixel at the principal point.
    #[arg(long, default_value_t = 1.0)]
    density: f64,
}

pub fn overscan_command(args: OverscanArgs) -> Result<(), CliError> {
    let cam = super::load_camera(&args.camera)?;
    let o = overscan(&cam, args.density)
        .map_err(|e| CliError::input(format!("{}: {e}", args.camera.display())))?;
    let k = o.intrinsics;
    let json = serde_json::json!({
        "width": o.width, "height": o.height,
        "fx": k.fx, "fy": k.fy, "cx": k.cx, "cy": k.cy,
        "dist_coeffs": [0.0, 0.0, 0.0, 0.0, 0.0],
        "density": args.density,
    });
    outln!("{json}")?;
    Ok(())
}
