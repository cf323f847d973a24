//! `vklens distort | undistort | precorrect | overscan`.

use std::path::{Path, PathBuf};

use clap::Args;
use glam::DVec2;

use super::output::check_output;
use super::{context, CliError};
use vklens::imaging::cpu_warp::{self, Border, Sampling};
use vklens::imaging::{file as image_io, BitDepth, Pixels, Raster};
use vklens::model::overscan::overscan;
use vklens::model::{Camera, CameraModel, InverseMethod};
use vklens::pass::sphere_warp::DataSource;
use vklens::pass::warp::PixelFormat;
use vklens::{Device, WarpDirection, WarpMethod, WarpOptions, Warper};

fn parse_warp_method(s: &str) -> Result<WarpMethod, String> {
    s.parse().map_err(|e: vklens::Error| e.to_string())
}

/// Comma-separated numbers, as many as given; `what` names the flag in errors.
pub(super) fn number_list(s: &str, what: &str) -> Result<Vec<f64>, String> {
    s.split(',')
        .map(|t| {
            t.trim()
                .parse::<f64>()
                .map_err(|_| format!("{what}: `{t}` is not a number"))
        })
        .collect()
}

fn parse_numbers<const N: usize>(s: &str, what: &str) -> Result<[f64; N], String> {
    let v = number_list(s, what)?;
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
    s.parse().map_err(|e: vklens::Error| e.to_string())
}

fn parse_border(s: &str) -> Result<Border, String> {
    s.parse().map_err(|e: vklens::Error| e.to_string())
}

/// Arguments shared by `distort`, `undistort` and `precorrect`.
#[derive(Args, Debug)]
pub struct WarpArgs {
    /// The lens: an OpenCV/ROS/vklens camera file, or a Brown lens {"model": "brown", ...}.
    #[arg(long, value_name = "CAM")]
    camera: PathBuf,
    /// Input image (PNG 8/16-bit or OpenEXR).
    #[arg(
        long,
        value_name = "IN",
        required_unless_present_any = ["input_cubemap", "input_equirect"]
    )]
    input: Option<PathBuf>,
    /// distort only, instead of --input: a 360° cube map, as six square face images in the
    /// order +x,-x,+y,-y,+z,-z (comma-separated) or as one horizontal cross (4 × 3 faces:
    /// -y above +z; -x +z +x -z in the middle row; +y below). Faces are named in the camera
    /// frame (x right, y down, z forward), each a 90° pinhole view from the centre; for
    /// fisheyes of 180° and more. docs/how-it-works.md has each face's orientation.
    #[arg(
        long,
        value_name = "FACES",
        value_delimiter = ',',
        num_args = 1,
        conflicts_with_all = ["input", "input_equirect"]
    )]
    input_cubemap: Vec<PathBuf>,
    /// distort only, instead of --input: an equirectangular 360° × 180° panorama (width =
    /// 2 × height; longitude −180°..180° left to right with 0 straight ahead, +90° to the
    /// right; latitude from straight up at the top row to straight down at the bottom).
    #[arg(long, value_name = "PANO", conflicts_with = "input")]
    input_equirect: Option<PathBuf>,
    /// distort with --input-cubemap: the faces' object IDs, in the colour's layout (six face
    /// files or one cross): 8- or 16-bit grey PNG, or EXR (IDs as whole numbers; 0 nothing).
    /// Carried through the lens at the nearest texel, never blended: no ID that is not in the
    /// input appears. Write them with --output-ids.
    #[arg(long, value_name = "FACES", value_delimiter = ',', num_args = 1)]
    input_ids: Vec<PathBuf>,
    /// distort with --input-cubemap: the faces' depth (32-bit float EXR, metres, +inf where
    /// nothing is drawn), in the colour's layout. Converted on each output pixel's own ray:
    /// write it with --output-depth (the lens camera's z) or --output-range.
    #[arg(long, value_name = "FACES", value_delimiter = ',', num_args = 1)]
    input_depth: Vec<PathBuf>,
    /// What --input-depth holds: z (each face's distance along its own axis, what a
    /// rasterizer's depth is) or range (distance from the centre along the texel's ray).
    #[arg(long, value_name = "KIND", default_value = "z", value_parser = ["z", "range"])]
    input_depth_kind: String,
    /// The IDs through the lens (.png 16-bit grey, or .exr): needs --input-ids.
    #[arg(long, value_name = "IDS")]
    output_ids: Option<PathBuf>,
    /// The lens camera's z through the lens (.exr, metres): needs --input-depth.
    #[arg(long, value_name = "D.exr")]
    output_depth: Option<PathBuf>,
    /// Range along each output pixel's ray (.exr, metres): needs --input-depth.
    #[arg(long, value_name = "R.exr")]
    output_range: Option<PathBuf>,
    /// Output image (.png keeps the input's bit depth; .exr writes 32-bit float).
    #[arg(long, value_name = "OUT")]
    output: PathBuf,
    /// The pinhole side's camera, when it differs from CAM's intrinsics and size: for distort,
    /// the input's (e.g. from `vklens overscan`); for undistort and precorrect, the output's
    /// (e.g. the "camera" of `vklens new-camera`).
    #[arg(long, value_name = "SRC", conflicts_with_all = ["alpha", "balance"])]
    source_camera: Option<PathBuf>,
    /// undistort only, instead of --source-camera: the output camera chosen as OpenCV chooses
    /// it (--alpha A [--new-size WxH] [--center-principal-point] for the standard model,
    /// --balance B [--fov-scale F] [--new-size WxH] for the fisheye); `vklens new-camera
    /// --help` says what each means. Without either, the output camera is CAM's intrinsics
    /// and size with no distortion.
    #[command(flatten)]
    rule: super::new_camera::RuleArgs,
    /// undistort only: ignore the rectification a ROS camera_info carries (its R and P) and
    /// undistort with K alone. By default undistort rectifies as ROS image_proc does:
    /// `initUndistortRectifyMap(K, D, R, P)`, the output taking P's intrinsics (a stereo pair's
    /// rectified image); it says on stderr which it used.
    #[arg(long)]
    no_rectification: bool,
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
    /// nearest | bilinear | bicubic, as cv2.remap's INTER_NEAREST, INTER_LINEAR, INTER_CUBIC.
    /// bilinear for colour; bicubic is sharper (16 source reads a pixel instead of 4) and
    /// overshoots at hard edges as OpenCV's does; nearest for IDs and flow (exact values,
    /// rounded positions). --sampling is the older name.
    #[arg(
        long,
        visible_alias = "sampling",
        value_name = "INTERPOLATION",
        default_value = "bilinear",
        value_parser = parse_sampling
    )]
    interpolation: Sampling,
    /// constant | replicate | reflect, as cv2.remap's BORDER_CONSTANT, BORDER_REPLICATE,
    /// BORDER_REFLECT: what a source position off the input image reads. constant: the pixel
    /// takes --fill (and the mask 0); replicate: the edge pixel repeats; reflect: the image
    /// mirrors. Pixels the lens gives no source at all (past its valid domain) take --fill
    /// whatever the border.
    #[arg(long, default_value = "constant", value_parser = parse_border)]
    border: Border,
    /// Where to run: gpu (Vulkan; lavapipe counts) or cpu (the f64 reference warp).
    #[arg(long, value_enum, default_value_t = super::Backend::Gpu)]
    backend: super::Backend,
}

fn pinhole(path: &Path) -> Result<Camera, CliError> {
    // --camera-index is --camera's: the source camera is a file of its own.
    let cam = vklens::io::load_camera(path)?;
    if !cam.is_pinhole() {
        return Err(CliError::input(format!(
            "{}: the source camera is the pinhole side of the warp and must have no distortion",
            path.display()
        )));
    }
    Ok(cam)
}

/// Undistort as ROS `image_proc` does: a camera_info's R and P, unless `--no-rectification`;
/// says on stderr which camera the output has.
fn rectify_as_image_proc(
    args: &WarpArgs,
    cam: &Camera,
    options: &mut WarpOptions,
) -> Result<(), CliError> {
    let found = vklens::io::camera::load_rectification(&args.camera)?
        .filter(|r| !r.is_identity_for(&cam.intrinsics));
    let Some(rect) = found else {
        return Ok(());
    };
    let file = args.camera.display();
    if args.no_rectification {
        eprintln!(
            "undistort: {file} carries a rectification (R, P); --no-rectification: undistorting with K alone"
        );
        return Ok(());
    }
    if args.rule.given() {
        return Err(CliError::input(format!(
            "{file} carries a rectification (R, P), and --alpha and --balance choose the output camera for R = identity as OpenCV's rules do: add --no-rectification to undistort with K alone into that camera"
        )));
    }
    options.rectification = Some(rect.r);
    let output = match &args.source_camera {
        Some(path) => format!("the output camera of --source-camera {}", path.display()),
        None => {
            let k = rect.intrinsics;
            options.source_camera = Some(Camera::from_coeffs(cam.width, cam.height, k, &[0.0; 4])?);
            format!(
                "P's camera (fx {:.6} fy {:.6} cx {:.6} cy {:.6})",
                k.fx, k.fy, k.cx, k.cy
            )
        }
    };
    eprintln!(
        "undistort: rectifying as image_proc does with {file}'s R and {output} (--no-rectification: K alone)"
    );
    Ok(())
}

/// Runs one of the three warp directions.
pub fn run(args: WarpArgs, direction: WarpDirection) -> Result<(), CliError> {
    check_output(&args.output, "image", &["png", "exr"])?;
    if let Some(m) = &args.mask {
        check_output(m, "mask", &["png"])?;
        super::output::distinct_outputs(&[("--output", &args.output), ("--mask", m)])?;
    }
    if direction != WarpDirection::Undistort && args.rule.any() {
        return Err(CliError::input(
            "--alpha, --balance, --new-size and --center-principal-point choose the output camera of `vklens undistort`; distort and precorrect take --source-camera",
        ));
    }
    // The device opens on a second thread while the camera and the image load: the driver's
    // start-up (about 25 ms on lavapipe) then hides behind the camera's valid domain and the
    // image's decoding instead of following them. An input error still comes first; the
    // scope waits for the device, which is dropped unused.
    std::thread::scope(|scope| {
        let opening = (args.backend == super::Backend::Gpu).then(|| scope.spawn(context));
        run_opening(scope, &args, direction, opening)
    })
}

/// A device opening on another thread, or none yet (the CPU backend).
type Opening<'scope> =
    Option<std::thread::ScopedJoinHandle<'scope, Result<vklens::host::Context, CliError>>>;

/// The device `opening` opened, or one opened now.
fn opened(opening: Opening) -> Result<vklens::host::Context, CliError> {
    match opening {
        Some(handle) => handle
            .join()
            .map_err(|_| CliError::from(vklens::Error::internal("opening the device failed")))?,
        None => context(),
    }
}

/// [`run`] once the device is opening (on a thread of `scope`).
fn run_opening<'scope>(
    scope: &'scope std::thread::Scope<'scope, '_>,
    args: &WarpArgs,
    direction: WarpDirection,
    opening: Opening<'scope>,
) -> Result<(), CliError> {
    let cam = super::load_camera(&args.camera)?;
    let data = [
        (!args.input_ids.is_empty(), "--input-ids"),
        (!args.input_depth.is_empty(), "--input-depth"),
        (args.output_ids.is_some(), "--output-ids"),
        (args.output_depth.is_some(), "--output-depth"),
        (args.output_range.is_some(), "--output-range"),
    ];
    if let Some((_, flag)) = data.iter().find(|(given, _)| *given) {
        if direction != WarpDirection::Distort || args.backend == super::Backend::Cpu {
            return Err(CliError::input(format!(
                "{flag}: IDs and depth go through the lens with `vklens distort` on --backend gpu"
            )));
        }
        for (path, what, ext) in [
            (&args.output_ids, "ID", &["png", "exr"][..]),
            (&args.output_depth, "depth", &["exr"][..]),
            (&args.output_range, "range", &["exr"][..]),
        ] {
            if let Some(p) = path {
                check_output(p, what, ext)?;
            }
        }
    }
    if !args.input_cubemap.is_empty() || args.input_equirect.is_some() {
        return run_sphere(args, direction, &cam, opening);
    }
    let input = args
        .input
        .clone()
        .ok_or_else(|| CliError::input("--input IN is missing"))?;
    let mut options = match direction {
        WarpDirection::Distort => WarpOptions::distort(),
        WarpDirection::Undistort => WarpOptions::undistort(),
        WarpDirection::Precorrect => WarpOptions::precorrect(),
    };
    options.method = args.method;
    options.sampling = args.interpolation;
    options.border = args.border;
    options.chromatic = args.chromatic;
    options.fill = args.fill.map(|f| f.map(|c| c as f32)).unwrap_or([0.0; 4]);
    if let Some(src) = &args.source_camera {
        options.source_camera = Some(pinhole(src)?);
    }
    // Which camera the undistorted image is drawn into, said once the image is written (a
    // failing run keeps its one line of error).
    let mut output_camera = None;
    if let Some((new, roi, rule)) = args.rule.choose(&cam)? {
        output_camera = Some(super::new_camera::describe(&new, roi, &rule));
        options.source_camera = Some(new);
    }
    if direction == WarpDirection::Undistort {
        rectify_as_image_proc(args, &cam, &mut options)?;
        if output_camera.is_none() {
            let out = options.source_camera.as_ref().unwrap_or(&cam);
            let (k, w, h) = (out.intrinsics, out.width, out.height);
            let whose = match (&args.source_camera, &options.source_camera) {
                (Some(src), _) => src.display().to_string(),
                (None, Some(_)) => format!("{}'s rectified P", args.camera.display()),
                (None, None) => format!("{}'s intrinsics and size", args.camera.display()),
            };
            output_camera = Some(format!(
                "output camera ({whose}): {w}×{h} pinhole, fx {} fy {} cx {} cy {}",
                k.fx, k.fy, k.cx, k.cy
            ));
        }
    } else if args.no_rectification {
        return Err(CliError::input(
            "--no-rectification applies to undistort (a camera_info's R and P)",
        ));
    }
    if !args.channel_cameras.is_empty() {
        let [r, g, b] = <[PathBuf; 3]>::try_from(args.channel_cameras.clone())
            .map_err(|_| CliError::input("--channel-cameras: expected three camera files R,G,B"))?;
        let cams = [
            vklens::io::load_camera(&r)?,
            vklens::io::load_camera(&g)?,
            vklens::io::load_camera(&b)?,
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
    let geometry = options.geometry(&cam)?;
    // Once the device is open, the warper's pipeline builds on its thread too, in the format
    // the image's header promises, while the pixels decode here.
    let header_format = match image_io::is_eight_bit(&input) {
        Some(false) => PixelFormat::Rgba32F,
        _ => PixelFormat::Rgba8,
    };
    let building = opening.map(|handle| {
        let (cam, mut early) = (cam.clone(), options.clone());
        early.format = header_format;
        scope.spawn(move || -> Result<(Device, Warper), CliError> {
            let device = Device::from_context(opened(Some(handle))?);
            let warper = Warper::new(device.gpu(), &cam, &early)?;
            Ok((device, warper))
        })
    });
    let (source, channels) = image_io::load_with_channels(&input)?;
    if (source.width, source.height) != geometry.source_size {
        let whose = match (direction, &args.source_camera) {
            (WarpDirection::Distort, Some(src)) => src.display().to_string(),
            _ => args.camera.display().to_string(),
        };
        return Err(CliError::input(format!(
            "{}: the input is {}×{} but {whose} expects {}×{}",
            input.display(),
            source.width,
            source.height,
            geometry.source_size.0,
            geometry.source_size.1
        )));
    }
    // IDs and depth beside the pinhole image: the source camera's, at the lens's centre
    // along its axes.
    let source_k = options
        .source_camera
        .as_ref()
        .map_or(cam.intrinsics, |c| c.intrinsics);
    let data = load_image_data(
        args,
        (source.width, source.height),
        DataSource::Pinhole(source_k),
    )?;
    let mut staged = Vec::new();
    let (out, mask) = match args.backend {
        // imaging::file::save writes float data read from an 8-bit file back as 8-bit.
        super::Backend::Cpu => {
            // The f64 reference warp holds both images in f64-sized pixels on the host: the
            // image budget bounds it as it bounds decoding.
            let (ow, oh) = geometry.output_size;
            image_io::check_budget("--backend cpu: the output", ow, oh)?;
            let (sw, sh) = geometry.source_size;
            image_io::check_budget("--backend cpu: the source", sw, sh)?;
            for (what, side) in [("output", ow.max(oh)), ("source", sw.max(sh))] {
                if side > CPU_MAX_SIDE {
                    return Err(CliError::input(format!(
                        "--backend cpu: the {what} is {side} px on a side, past the {CPU_MAX_SIDE} px the GPU path takes too (a reference warp of that size runs for minutes); use --backend gpu, or a smaller --source-camera"
                    )));
                }
            }
            let (out, mask) = cpu_warp::warp(
                &geometry,
                &source,
                args.interpolation,
                args.border,
                options.fill,
            );
            (out, mask.iter().map(|&m| m > 127).collect::<Vec<_>>())
        }
        super::Backend::Gpu => {
            options.format = PixelFormat::of(&source);
            let (device, mut warper) = match building {
                Some(handle) => handle.join().map_err(|_| {
                    CliError::from(vklens::Error::internal("building the warper failed"))
                })??,
                None => {
                    let device = Device::from_context(context()?);
                    let warper = Warper::new(device.gpu(), &cam, &options)?;
                    (device, warper)
                }
            };
            if options.format != header_format {
                // The header promised another format than the pixels have: built again.
                warper = Warper::new(device.gpu(), &cam, &options)?;
            }
            let warped = warper.run(&device, &source)?;
            if let Some(d) = &data {
                staged = stage_data_outputs(args, &cam, d.run(device.context(), &cam)?)?;
            }
            device.check_validation()?;
            (warped.image, warped.mask)
        }
    };
    save_outputs(args, &out, &mask, channels)?;
    for s in staged {
        s.commit()?;
    }
    if let Some(line) = output_camera {
        eprintln!("{line}");
    }
    if direction == WarpDirection::Precorrect {
        report_round_trip(&cam);
    }
    Ok(())
}

/// Largest side of an image the CPU reference warp takes: the GPU path's usual limit.
const CPU_MAX_SIDE: u32 = 16384;

/// The channels a warped image is written with: the input's, and an alpha channel where
/// `filled` pixels have no source and the fill is transparent (said on stderr).
pub(super) fn output_channels(
    input: image_io::Channels,
    filled: usize,
    fill_alpha: f64,
) -> image_io::Channels {
    if !input.has_alpha() && filled > 0 && fill_alpha < 1.0 {
        eprintln!(
            "the output has an alpha channel the input lacks: {filled} px have no source and the fill is transparent (--fill R,G,B,1 keeps {})",
            if input.0 == 1 { "grey" } else { "RGB" }
        );
        image_io::Channels(input.0 + 1)
    } else {
        input
    }
}

/// Writes the image (with the input's channels, and alpha only where the fill needs it) and,
/// when asked, the mask; reports what was filled.
fn save_outputs(
    args: &WarpArgs,
    out: &Raster,
    mask: &[bool],
    input: image_io::Channels,
) -> Result<(), CliError> {
    let filled = mask.iter().filter(|&&m| !m).count();
    let fill_alpha = args.fill.map_or(0.0, |f| f[3]);
    let channels = output_channels(input, filled, fill_alpha);
    // Both outputs, or neither, as far as writing goes: both are staged before either is
    // renamed into place (a rename failing in between, which a writable folder does not do,
    // would leave the first).
    let mut staged = vec![image_io::save_staged(out, &args.output, channels)?];
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
        staged.push(image_io::save_staged(&raster, m, image_io::Channels(4))?);
    }
    for s in staged {
        s.commit()?;
    }
    eprintln!(
        "wrote {} ({}×{}, {filled} px without a source{})",
        args.output.display(),
        out.width,
        out.height,
        if filled > 0 { ", filled" } else { "" }
    );
    Ok(())
}

/// `distort` from a cube map or a panorama: each output pixel's ray samples it.
fn run_sphere(
    args: &WarpArgs,
    direction: WarpDirection,
    cam: &Camera,
    opening: Opening,
) -> Result<(), CliError> {
    use vklens::host::sphere_warp::run_environment;
    use vklens::pass::sphere_warp::SphereWarpOptions;
    use vklens::scene::{Environment, Scene};
    let flag = if args.input_equirect.is_some() {
        "--input-equirect"
    } else {
        "--input-cubemap"
    };
    if direction != WarpDirection::Distort {
        return Err(CliError::input(format!(
            "{flag}: a 360° source is for `vklens distort` (it renders the lens image); undistort and precorrect take --input"
        )));
    }
    if args.backend == super::Backend::Cpu {
        return Err(CliError::input(format!(
            "{flag}: 360° sources run on --backend gpu"
        )));
    }
    if args.source_camera.is_some() || !args.channel_cameras.is_empty() {
        return Err(CliError::input(format!(
            "{flag}: --source-camera and --channel-cameras are for pinhole sources"
        )));
    }
    if args.method != WarpMethod::PerPixel(InverseMethod::Newton) {
        return Err(CliError::input(format!(
            "{flag}: the 360° warp inverts the lens by Newton per pixel; --method must be newton"
        )));
    }
    if args.interpolation != Sampling::Bilinear || args.border != Border::Constant {
        // A panorama or cube map has no border to extend, and its sampler is bilinear.
        return Err(CliError::input(format!(
            "{flag}: the 360° warp samples bilinearly and has no border; --interpolation and --border are for --input"
        )));
    }
    let options = SphereWarpOptions {
        chromatic: args.chromatic,
        fill: args.fill.map(|f| f.map(|c| c as f32)).unwrap_or([0.0; 4]),
        // The report counts filled pixels from the mask: always written.
        write_mask: true,
    };
    let (environment, channels) = if let Some(pano) = &args.input_equirect {
        let (source, channels) = image_io::load_with_channels(pano)?;
        if source.width != 2 * source.height {
            return Err(CliError::input(format!(
                "{}: an equirectangular panorama is twice as wide as high (360° × 180°), this one is {}×{}",
                pano.display(),
                source.width,
                source.height
            )));
        }
        eprintln!(
            "360° source: equirectangular panorama {}×{} ({:.3}° per pixel)",
            source.width,
            source.height,
            360.0 / source.width as f64
        );
        (Environment::Panorama(source), channels)
    } else {
        let (faces, layout, channels) = load_cube_faces(&args.input_cubemap)?;
        eprintln!(
            "360° source: cube map of six {}×{} faces ({layout})",
            faces[0].width, faces[0].width
        );
        (Environment::Cube(Box::new(faces)), channels)
    };
    let data = match &environment {
        Environment::Cube(faces) => load_cube_data(args, faces[0].width)?,
        Environment::Panorama(p) => {
            load_image_data(args, (p.width, p.height), DataSource::Equirect)?
        }
    };
    // The 360° image is the scene: planned and recorded as any scene is.
    let ctx = opened(opening)?;
    let scene = Scene::from_environment(flag, environment);
    let (out, mask) = run_environment(&ctx, cam, &scene, &options)?;
    // The source's IDs and depth, through the same lens, staged with the colour.
    let staged = match &data {
        Some(d) => stage_data_outputs(args, cam, d.run(&ctx, cam)?)?,
        None => Vec::new(),
    };
    super::finish(&ctx)?;
    let mask: Vec<bool> = mask.iter().map(|&m| m > 127).collect();
    save_outputs(args, &out, &mask, channels)?;
    for s in staged {
        s.commit()?;
    }
    Ok(())
}

/// A source's IDs and depth (`--input-ids`, `--input-depth`), as the data pass takes them.
enum SourceData {
    /// Six faces of `side`² texels, +x −x +y −y +z −z; each face's z.
    Cube(u32, [Vec<u32>; 6], [Vec<f32>; 6]),
    /// One image: a pinhole image's z, or a panorama's range.
    Image(DataSource, (u32, u32), Vec<u32>, Vec<f32>),
}

impl SourceData {
    /// (IDs, z, range) through `cam`'s lens.
    #[allow(clippy::type_complexity)]
    fn run(
        &self,
        ctx: &vklens::host::Context,
        cam: &Camera,
    ) -> Result<(Vec<u32>, Vec<f32>, Vec<f32>), CliError> {
        use vklens::host::sphere_warp::{run_cube_data, run_image_data};
        Ok(match self {
            SourceData::Cube(side, ids, z) => run_cube_data(ctx, cam, *side, ids, z)?,
            SourceData::Image(kind, size, ids, depth) => {
                run_image_data(ctx, cam, *kind, *size, ids, depth)?
            }
        })
    }
}

/// The data outputs (`--output-ids`, `--output-depth`, `--output-range`) of `(ids, z, range)`,
/// staged: put in place with the colour, or not at all.
fn stage_data_outputs(
    args: &WarpArgs,
    cam: &Camera,
    (ids, z, range): (Vec<u32>, Vec<f32>, Vec<f32>),
) -> Result<Vec<image_io::Staged>, CliError> {
    let (w, h) = (cam.width, cam.height);
    let mut staged = Vec::new();
    if let Some(p) = &args.output_ids {
        let raster = Raster {
            width: w,
            height: h,
            pixels: Pixels::R32Uint(ids),
            bit_depth: BitDepth::U16,
        };
        staged.push(image_io::save_staged(&raster, p, image_io::Channels(1))?);
    }
    for (path, values) in [(&args.output_depth, z), (&args.output_range, range)] {
        if let Some(p) = path {
            let raster = Raster {
                width: w,
                height: h,
                pixels: Pixels::Rgba32F(values.iter().map(|&v| [v, v, v, 1.0]).collect()),
                bit_depth: BitDepth::F32,
            };
            staged.push(image_io::save_staged(&raster, p, image_io::Channels(4))?);
        }
    }
    Ok(staged)
}

/// Checks the data flags against each other; whether any source data is given.
fn data_given(args: &WarpArgs) -> Result<bool, CliError> {
    for (out, needs, flag) in [
        (
            &args.output_ids,
            &args.input_ids,
            "--output-ids needs --input-ids",
        ),
        (
            &args.output_depth,
            &args.input_depth,
            "--output-depth needs --input-depth",
        ),
        (
            &args.output_range,
            &args.input_depth,
            "--output-range needs --input-depth",
        ),
    ] {
        if out.is_some() && needs.is_empty() {
            return Err(CliError::input(format!(
                "{flag}: the source's data to carry through the lens"
            )));
        }
    }
    Ok(!args.input_ids.is_empty() || !args.input_depth.is_empty())
}

/// One image of IDs and one of depth (`--input-ids`, `--input-depth`) of the colour's `size`,
/// for a pinhole source (its z) or a panorama (its range), the other kind converted. `None`
/// where neither is given.
fn load_image_data(
    args: &WarpArgs,
    (w, h): (u32, u32),
    kind: DataSource,
) -> Result<Option<SourceData>, CliError> {
    if !data_given(args)? {
        return Ok(None);
    }
    fn one<T>(
        flag: &str,
        paths: &[PathBuf],
        (w, h): (u32, u32),
        load: impl Fn(&Path) -> Result<(u32, u32, Vec<T>), vklens::Error>,
    ) -> Result<Option<Vec<T>>, CliError> {
        match paths {
            [] => Ok(None),
            [p] => {
                let (iw, ih, v) = load(p)?;
                if (iw, ih) != (w, h) {
                    return Err(CliError::input(format!(
                        "{flag} {}: {iw}×{ih}, but the colour input is {w}×{h}",
                        p.display()
                    )));
                }
                Ok(Some(v))
            }
            more => Err(CliError::input(format!(
                "{flag}: one image beside --input or --input-equirect, not {}",
                more.len()
            ))),
        }
    }
    let n = w as usize * h as usize;
    let ids = one("--input-ids", &args.input_ids, (w, h), image_io::load_ids)?
        .unwrap_or_else(|| vec![1; n]);
    let mut depth = one(
        "--input-depth",
        &args.input_depth,
        (w, h),
        image_io::load_depth,
    )?
    .unwrap_or_else(|| vec![f32::INFINITY; n]);
    // Each pixel's ray: a pinhole's at z = 1, a panorama's unit ray.
    let ray = |i: usize| {
        let (x, y) = ((i % w as usize) as f64, (i / w as usize) as f64);
        match kind {
            DataSource::Pinhole(k) => k.to_normalized(DVec2::new(x, y)).extend(1.0),
            _ => {
                let lon = ((x + 0.5) / w as f64 - 0.5) * std::f64::consts::TAU;
                let lat = ((y + 0.5) / h as f64 - 0.5) * std::f64::consts::PI;
                glam::DVec3::new(lat.cos() * lon.sin(), lat.sin(), lat.cos() * lon.cos())
            }
        }
    };
    match (kind, args.input_depth_kind.as_str()) {
        // A pinhole image wants z, a panorama range: the other converted along each ray.
        (DataSource::Pinhole(_), "range") => {
            for (i, d) in depth.iter_mut().enumerate() {
                *d = (*d as f64 / ray(i).length()) as f32;
            }
        }
        (DataSource::Equirect, "z") => {
            for (i, d) in depth.iter_mut().enumerate() {
                *d = (*d as f64 / ray(i).z) as f32;
            }
        }
        _ => {}
    }
    Ok(Some(SourceData::Image(kind, (w, h), ids, depth)))
}

/// The cube faces' IDs and depth (`--input-ids`, `--input-depth`) as `run_cube_data` takes
/// them, each face the colour faces' `side`; a range depth turned into each face's z. `None`
/// where neither is given.
fn load_cube_data(args: &WarpArgs, side: u32) -> Result<Option<SourceData>, CliError> {
    use vklens::pass::sphere_warp::CubeFace;
    if !data_given(args)? {
        return Ok(None);
    }
    // One image per face, or a cross cut into faces, each checked against the colour's size.
    fn per_face<T: Clone>(
        flag: &str,
        paths: &[PathBuf],
        side: u32,
        load: impl Fn(&Path) -> Result<(u32, u32, Vec<T>), vklens::Error>,
    ) -> Result<[Vec<T>; 6], CliError> {
        let cut = |w: u32, v: &[T], col: u32, row: u32| -> Vec<T> {
            (0..side)
                .flat_map(|y| {
                    let start = ((row * side + y) * w + col * side) as usize;
                    v[start..start + side as usize].to_vec()
                })
                .collect()
        };
        match paths {
            [cross] => {
                let (w, h, v) = load(cross)?;
                if (w, h) != (4 * side, 3 * side) {
                    return Err(CliError::input(format!(
                        "{flag} {}: {w}×{h}, but the colour's cross is {}×{}",
                        cross.display(),
                        4 * side,
                        3 * side
                    )));
                }
                Ok(CubeFace::ALL.map(|f| {
                    let (col, row) = f.cross_cell();
                    cut(w, &v, col, row)
                }))
            }
            six if six.len() == 6 => {
                let mut out: Vec<Vec<T>> = Vec::with_capacity(6);
                for (face, p) in CubeFace::ALL.iter().zip(six) {
                    let (w, h, v) = load(p)?;
                    if (w, h) != (side, side) {
                        return Err(CliError::input(format!(
                            "{flag} {}: face {} is {w}×{h}, but the colour's faces are {side}×{side}",
                            p.display(),
                            face.name()
                        )));
                    }
                    out.push(v);
                }
                out.try_into()
                    .map_err(|_| CliError::input(format!("{flag}: six faces expected")))
            }
            other => Err(CliError::input(format!(
                "{flag}: give six face files +x,-x,+y,-y,+z,-z or one horizontal cross, as --input-cubemap, not {} file(s)",
                other.len()
            ))),
        }
    }
    let n = (side * side) as usize;
    let ids = if args.input_ids.is_empty() {
        // Depth alone: every drawn texel one object, so that depth is carried everywhere.
        std::array::from_fn(|_| vec![1u32; n])
    } else {
        per_face("--input-ids", &args.input_ids, side, image_io::load_ids)?
    };
    let mut face_z = if args.input_depth.is_empty() {
        std::array::from_fn(|_| vec![f32::INFINITY; n])
    } else {
        per_face(
            "--input-depth",
            &args.input_depth,
            side,
            image_io::load_depth,
        )?
    };
    if args.input_depth_kind == "range" {
        // Range along the texel's ray → the face's z: divided by the ray's length at z = 1.
        let camera = CubeFace::camera(side)?;
        for face in face_z.iter_mut() {
            for (i, d) in face.iter_mut().enumerate() {
                let p = camera.intrinsics.to_normalized(DVec2::new(
                    (i as u32 % side) as f64,
                    (i as u32 / side) as f64,
                ));
                *d = (*d as f64 / p.extend(1.0).length()) as f32;
            }
        }
    }
    Ok(Some(SourceData::Cube(side, ids, face_z)))
}

/// Six face files (+x -x +y -y +z -z) or one horizontal cross, with the layout's name.
fn load_cube_faces(
    paths: &[PathBuf],
) -> Result<([Raster; 6], &'static str, image_io::Channels), CliError> {
    use vklens::pass::sphere_warp::CubeFace;
    match paths {
        [cross] => {
            let (img, channels) = image_io::load_with_channels(cross)?;
            let side = img.width / 4;
            if side == 0 || img.width != 4 * side || img.height != 3 * side {
                return Err(CliError::input(format!(
                    "{}: a horizontal cross is 4 × 3 square faces (width = 4/3 height), this one is {}×{}; or give six face files +x,-x,+y,-y,+z,-z",
                    cross.display(),
                    img.width,
                    img.height
                )));
            }
            let faces = CubeFace::ALL.map(|f| {
                let (col, row) = f.cross_cell();
                img.crop(col * side, row * side, side, side)
            });
            Ok((faces, "one horizontal cross", channels))
        }
        six if six.len() == 6 => {
            let mut faces = Vec::with_capacity(6);
            let mut channels = image_io::Channels(1);
            for (face, path) in CubeFace::ALL.iter().zip(six) {
                let (img, c) = image_io::load_with_channels(path)?;
                channels = image_io::Channels(channels.0.max(c.0));
                if img.width != img.height {
                    return Err(CliError::input(format!(
                        "{}: cube face {} must be square, it is {}×{}",
                        path.display(),
                        face.name(),
                        img.width,
                        img.height
                    )));
                }
                if let Some(first) = faces.first().map(|f: &Raster| f.width) {
                    if img.width != first {
                        return Err(CliError::input(format!(
                            "{}: cube face {} is {}×{}, the +x face {first}×{first}; every face has one size",
                            path.display(),
                            face.name(),
                            img.width,
                            img.height
                        )));
                    }
                }
                faces.push(img);
            }
            let faces: [Raster; 6] = faces
                .try_into()
                .map_err(|_| CliError::input("--input-cubemap: six faces expected"))?;
            Ok((faces, "six files +x -x +y -y +z -z", channels))
        }
        other => Err(CliError::input(format!(
            "--input-cubemap: give six face files +x,-x,+y,-y,+z,-z (comma-separated) or one horizontal cross, not {} file(s)",
            other.len()
        ))),
    }
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
