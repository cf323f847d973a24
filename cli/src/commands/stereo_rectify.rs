//! `vklens stereo-rectify`: a calibrated pair's rectification, as OpenCV computes it, written
//! as the two ROS `camera_info` files `image_proc` and `vklens undistort` rectify with, and,
//! when asked, the rectified pair itself.

use std::path::{Path, PathBuf};

use clap::Args;

use super::{context, CliError};
use vklens::imaging::file::{self as image_io, Channels, Staged};
use vklens::imaging::Raster;
use vklens::io::catalog::LoadOptions;
use vklens::io::stereo::{load_extrinsics, load_stereo_pair};
use vklens::model::stereo::{stereo_rectify, PairRotation, StereoOptions, StereoRectification};
use vklens::model::{Camera, InverseMethod};
use vklens::pass::warp::PixelFormat;
use vklens::{Device, WarpMethod, WarpOptions, Warper};

/// `vklens stereo-rectify`.
#[derive(Args, Debug)]
pub struct StereoRectifyArgs {
    /// A file holding the whole pair: an OpenCV stereo calibration file with R and T beside
    /// the two cameras (M1 D1 M2 D2, K1 D1 K2 D2, cameraMatrix1/2 distCoeffs1/2, as
    /// cv2.stereoCalibrate scripts write it; --size WxH where it gives no image size), or a
    /// Kalibr camchain (cam0, and cam1 with its T_cn_cnm1). With --extrinsics, R and T come
    /// from there instead (stereo_calib.cpp's intrinsics.yml and extrinsics.yml).
    #[arg(value_name = "PAIR_FILE")]
    pair: Option<PathBuf>,
    /// Instead of PAIR_FILE: the two cameras' files, the first (left, or top) camera first:
    /// --camera LEFT --camera RIGHT. Each file's first camera; --size WxH gives a file without
    /// an image size its size.
    #[arg(long, value_name = "CAM", conflicts_with = "pair")]
    camera: Vec<PathBuf>,
    /// R, the rotation from the first camera's frame to the second's (X2 = R·X1 + T, as
    /// cv2.stereoCalibrate reports it): a Rodrigues vector RX,RY,RZ (axis × angle, radians)
    /// or the matrix's nine numbers row by row.
    #[arg(long, value_name = "RX,RY,RZ", allow_hyphen_values = true, value_parser = parse_rotation)]
    rotation: Option<PairRotation>,
    /// T, the translation from the first camera's frame to the second's (minus the second
    /// camera's centre in the first's frame: -0.12,0,0 for a second camera 0.12 to the right),
    /// in any unit: Q and P2's baseline come out in it.
    #[arg(long, value_name = "TX,TY,TZ", allow_hyphen_values = true, value_parser = parse_translation)]
    translation: Option<[f64; 3]>,
    /// R and T from a file of their own (OpenCV FileStorage with keys R and T, as
    /// stereo_calib.cpp's extrinsics.yml), instead of --rotation and --translation.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["rotation", "translation"])]
    extrinsics: Option<PathBuf>,
    /// OpenCV's standard model (cv2.stereoRectify's alpha): 0 keeps only pixels that have a
    /// source in both images, 1 keeps every source pixel of both; between, a blend. Default:
    /// OpenCV's -1, no scaling (the mean focal length).
    #[arg(long, value_name = "A", conflicts_with_all = ["balance", "fov_scale"])]
    alpha: Option<f64>,
    /// OpenCV's fisheye model (cv2.fisheye.stereoRectify's balance): 0 the largest focal
    /// length the edge midpoints allow (cropped), 1 the smallest. Default 0.
    #[arg(long, value_name = "B")]
    balance: Option<f64>,
    /// OpenCV's fisheye model: divide the rectified focal length by F (fov_scale). Default 1.
    #[arg(long, value_name = "F")]
    fov_scale: Option<f64>,
    /// The rectified images' size, as WIDTHxHEIGHT (OpenCV's newImageSize); default: the
    /// cameras' own. camera_info has no field for it: the files say it in a comment, and
    /// `vklens undistort --camera DIR/left.yaml` draws into the raw image's size.
    #[arg(long, value_name = "WxH", value_parser = parse_new_size)]
    new_size: Option<(u32, u32)>,
    /// Leave out OpenCV's CALIB_ZERO_DISPARITY: the principal points then share only the
    /// coordinate across the baseline, instead of being one point (where points at infinity
    /// have zero disparity).
    #[arg(long)]
    no_zero_disparity: bool,
    /// The folder to write DIR/left.yaml and DIR/right.yaml into (made if missing), and the
    /// rectified images with --left and --right.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// The first camera's image (PNG or OpenEXR): written rectified as DIR/left.png (.exr
    /// for an EXR), on the GPU, exactly as `vklens undistort --camera DIR/left.yaml` draws it.
    #[arg(long, value_name = "IMG", requires = "right")]
    left: Option<PathBuf>,
    /// The second camera's image: written rectified as DIR/right.png (.exr).
    #[arg(long, value_name = "IMG", requires = "left")]
    right: Option<PathBuf>,
}

fn parse_rotation(s: &str) -> Result<PairRotation, String> {
    let v = finite_numbers(s, "--rotation")?;
    match v.as_slice() {
        [x, y, z] => Ok(PairRotation::Rodrigues([*x, *y, *z])),
        [a, b, c, d, e, f, g, h, i] => Ok(PairRotation::Matrix([
            [*a, *b, *c],
            [*d, *e, *f],
            [*g, *h, *i],
        ])),
        _ => Err(format!(
            "--rotation: expected a Rodrigues vector RX,RY,RZ (3 numbers) or a rotation matrix (9 numbers, row by row), got {} numbers",
            v.len()
        )),
    }
}

fn parse_translation(s: &str) -> Result<[f64; 3], String> {
    let v = finite_numbers(s, "--translation")?;
    <[f64; 3]>::try_from(v.as_slice())
        .map_err(|_| format!("--translation: expected TX,TY,TZ, got {} numbers", v.len()))
}

fn parse_new_size(s: &str) -> Result<(u32, u32), String> {
    vklens::io::catalog::parse_size(s).map_err(|e| e.message_only())
}

/// Comma-separated finite numbers, as many as given.
fn finite_numbers(s: &str, flag: &str) -> Result<Vec<f64>, String> {
    let v = super::warp::number_list(s, flag)?;
    if v.iter().any(|x| !x.is_finite()) {
        return Err(format!("{flag}: numbers must be finite"));
    }
    Ok(v)
}

/// Where each input came from, for errors about it: the files (with the camera's name in
/// them), and R and T.
struct Sources {
    left: String,
    right: String,
    rotation: String,
    translation: String,
}

/// The pair, and where each part of it came from.
fn load_pair(
    args: &StereoRectifyArgs,
) -> Result<(Camera, Camera, PairRotation, [f64; 3], Sources), CliError> {
    let options = super::camera_options();
    if options.index.is_some() || options.name.is_some() {
        return Err(CliError::input(
            "--camera-index and --camera-name pick one camera of a file; stereo-rectify takes each --camera file's first camera, and a pair file's first two",
        ));
    }
    let size = options.size;
    let extrinsics = match &args.extrinsics {
        Some(path) => Some((load_extrinsics(path)?, path.display().to_string())),
        None => None,
    };
    if let Some(path) = &args.pair {
        if args.rotation.is_some() || args.translation.is_some() {
            return Err(CliError::input(format!(
                "{}: a pair file gives R and T itself; --rotation and --translation go with --camera LEFT --camera RIGHT (--extrinsics FILE replaces the pair file's)",
                path.display()
            )));
        }
        let file = path.display().to_string();
        let pair = load_stereo_pair(path, size, extrinsics.as_ref().map(|(rt, _)| *rt))?;
        let [a, b] = &pair.names;
        let rt_key = if pair.format == vklens::io::camera::KALIBR_FORMAT {
            (format!("`{b}.T_cn_cnm1`"), format!("`{b}.T_cn_cnm1`"))
        } else {
            ("`R`".to_string(), "`T`".to_string())
        };
        let (rotation, translation) = match &extrinsics {
            Some((_, e)) => (format!("{e}: `R`"), format!("{e}: `T`")),
            None => (
                format!("{file}: {}", rt_key.0),
                format!("{file}: {}", rt_key.1),
            ),
        };
        let sources = Sources {
            left: format!("{file}: `{a}`"),
            right: format!("{file}: `{b}`"),
            rotation,
            translation,
        };
        return Ok((
            pair.left,
            pair.right,
            pair.rotation,
            pair.translation,
            sources,
        ));
    }
    let [left_path, right_path] = args.camera.as_slice() else {
        return Err(CliError::input(format!(
            "give the pair: a PAIR_FILE (an OpenCV stereo file with R and T, or a Kalibr camchain), or --camera LEFT --camera RIGHT with --rotation and --translation (or --extrinsics FILE); got {} --camera",
            args.camera.len()
        )));
    };
    let ((rotation, translation), rt_sources) = match (&extrinsics, args.rotation, args.translation) {
        (Some((rt, e)), _, _) => (*rt, (format!("{e}: `R`"), format!("{e}: `T`"))),
        (None, Some(r), Some(t)) => ((r, t), ("--rotation".into(), "--translation".into())),
        _ => {
            return Err(CliError::input(
                "two --camera files need R and T between them: --rotation and --translation, or --extrinsics FILE",
            ))
        }
    };
    let load = |path: &Path| {
        vklens::io::camera::load_camera_with(
            path,
            &LoadOptions {
                size,
                ..LoadOptions::default()
            },
        )
    };
    let sources = Sources {
        left: left_path.display().to_string(),
        right: right_path.display().to_string(),
        rotation: rt_sources.0,
        translation: rt_sources.1,
    };
    Ok((
        load(left_path)?,
        load(right_path)?,
        rotation,
        translation,
        sources,
    ))
}

/// A library error about one of the pair's inputs, said of where it came from.
fn said_of(e: vklens::Error, sources: &Sources) -> CliError {
    let source = match e.argument_name() {
        Some("left") => &sources.left,
        Some("right") => &sources.right,
        Some("R") => &sources.rotation,
        Some("T") => &sources.translation,
        _ => return e,
    };
    CliError::input(format!("{source}: {}", e.message_only()))
}

/// The camera_info file of one camera of the pair.
fn camera_info(
    lens: &Camera,
    r: [[f64; 3]; 3],
    p: [[f64; 4]; 3],
    rectified: &Camera,
) -> Result<String, CliError> {
    let text = lens.to_ros_camera_info_rectified(r, p)?;
    // camera_info's size is the raw image's; the rectified one, where it differs, is kept
    // where a reader can see it.
    if (rectified.width, rectified.height) != (lens.width, lens.height) {
        return Ok(format!(
            "# rectified image size: {}x{} (camera_info has no field for it; image_width and image_height are the raw image's)\n{text}",
            rectified.width, rectified.height
        ));
    }
    Ok(text)
}

/// The rectified image of one camera: the undistort warp with R and P's camera, as `vklens
/// undistort` runs it for a camera_info with R and P.
fn rectify_image(
    device: &Device,
    lens: &Camera,
    r: [[f64; 3]; 3],
    rectified: &Camera,
    source: &Raster,
) -> Result<(Raster, Vec<bool>), CliError> {
    let mut options = WarpOptions::undistort();
    options.method = WarpMethod::PerPixel(InverseMethod::Newton);
    options.rectification = Some(r);
    options.source_camera = Some(rectified.clone());
    options.format = PixelFormat::of(source);
    let mut warper = Warper::new(device.gpu(), lens, &options)?;
    let warped = warper.run(device, source)?;
    Ok((warped.image, warped.mask))
}

/// Reads one camera's image, which must have the camera's size.
fn load_image(path: &Path, lens: &Camera, whose: &str) -> Result<(Raster, Channels), CliError> {
    let (image, channels) = image_io::load_with_channels(path)?;
    if (image.width, image.height) != (lens.width, lens.height) {
        return Err(CliError::input(format!(
            "{}: the {whose} image is {}×{} but its camera's images are {}×{}",
            path.display(),
            image.width,
            image.height,
            lens.width,
            lens.height
        )));
    }
    Ok((image, channels))
}

/// The summary on stderr.
fn summary(s: &StereoRectification, lens: &Camera) -> String {
    let (a, b) = (s.left.intrinsics, s.right.intrinsics);
    let along = if s.vertical {
        "columns (a vertical pair)"
    } else {
        "rows"
    };
    let rule = if lens.fisheye_lens().is_some() {
        "cv2.fisheye.stereoRectify"
    } else {
        "cv2.stereoRectify"
    };
    format!(
        "stereo-rectify ({rule}): baseline {:.6} (T's units) along the {along}; cameras turned by {:.3}° and {:.3}°\n\
         rectified {}×{} pinhole, focal length {:.6} px, principal points ({:.6}, {:.6}) and ({:.6}, {:.6})\n\
         valid ROI left x {} y {} w {} h {}, right x {} y {} w {} h {}",
        s.baseline(),
        s.turn_degrees()[0],
        s.turn_degrees()[1],
        s.left.width,
        s.left.height,
        a.fx,
        a.cx,
        a.cy,
        b.cx,
        b.cy,
        s.roi1.0,
        s.roi1.1,
        s.roi1.2,
        s.roi1.3,
        s.roi2.0,
        s.roi2.1,
        s.roi2.2,
        s.roi2.3,
    )
}

/// Runs `vklens stereo-rectify`.
pub fn run(args: StereoRectifyArgs) -> Result<(), CliError> {
    if args.out.exists() && !args.out.is_dir() {
        return Err(CliError::input(format!(
            "{}: --out names a folder to write left.yaml and right.yaml into, and this is a file",
            args.out.display()
        )));
    }
    let (left, right, rotation, translation, sources) = load_pair(&args)?;
    let options = StereoOptions {
        alpha: args.alpha,
        new_size: args.new_size,
        zero_disparity: !args.no_zero_disparity,
        balance: args.balance.unwrap_or(0.0),
        fov_scale: args.fov_scale.unwrap_or(1.0),
    };
    let s = stereo_rectify(&left, &right, rotation, translation, &options)
        .map_err(|e| said_of(e, &sources))?;
    let infos = [
        camera_info(&left, s.r1, s.p1, &s.left).map_err(|e| e.context(&sources.left))?,
        camera_info(&right, s.r2, s.p2, &s.right).map_err(|e| e.context(&sources.right))?,
    ];
    // Every image is warped before any file is written: a failure leaves nothing behind.
    let mut images = Vec::new();
    if let (Some(lp), Some(rp)) = (&args.left, &args.right) {
        let inputs = [
            (lp, load_image(lp, &left, "left")?),
            (rp, load_image(rp, &right, "right")?),
        ];
        let device = Device::from_context(context()?);
        for ((path, (image, channels)), (lens, r, rectified, side)) in inputs.into_iter().zip([
            (&left, s.r1, &s.left, "left"),
            (&right, s.r2, &s.right, "right"),
        ]) {
            let (out, mask) = rectify_image(&device, lens, r, rectified, &image)?;
            let ext = if super::output::extension(path).as_deref() == Some("exr") {
                "exr"
            } else {
                "png"
            };
            let filled = mask.iter().filter(|&&m| !m).count();
            images.push((
                args.out.join(format!("{side}.{ext}")),
                out,
                super::warp::output_channels(channels, filled, 0.0),
            ));
        }
        device.check_validation()?;
    }
    std::fs::create_dir_all(&args.out)
        .map_err(|e| CliError::io(&args.out, "cannot make the --out folder", &e))?;
    let mut staged: Vec<Staged> = Vec::new();
    let mut written = Vec::new();
    for (side, text) in ["left", "right"].into_iter().zip(&infos) {
        let path = args.out.join(format!("{side}.yaml"));
        staged.push(image_io::stage(&path, |tmp| std::fs::write(tmp, text))?);
        written.push(path);
    }
    for (path, image, channels) in &images {
        staged.push(image_io::save_staged(image, path, *channels)?);
        written.push(path.clone());
    }
    for s in staged {
        s.commit()?;
    }
    eprintln!("{}", summary(&s, &left));
    eprintln!(
        "wrote {}",
        written
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(())
}
