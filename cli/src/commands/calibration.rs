//! `vklens calibration-set`: Lambers et al. Sec. 4's proof set — checkerboard views through the
//! lens, by either path, for OpenCV to calibrate from (`tests/calibrate.py`).

use std::path::PathBuf;

use clap::Args;

use super::render::path_parser;
use super::{context, finish, load_camera, progress_done, progress_line, CliError};
use vklens::host::plan::execute_untimed;
use vklens::imaging::file as image_io;
use vklens::pass::geometry::DEFAULT_DELTA;
use vklens::plan::scene_file::{Antialias, OutputSpec};
use vklens::plan::PathKind;
use vklens::plan::{Plan, RenderRequest};
use vklens::scene::builtin::{self, parse_board_size, Board};
use vklens::scene::calibration::board_poses;

#[derive(Args, Debug)]
#[command(
    after_help = "Example (Lambers et al.'s proof, for one camera and path):
  vklens calibration-set --camera cam.yml --out set/ --path vertex
  python3 tests/calibrate.py set/      # OpenCV calibrates; prints each parameter's error and σ"
)]
pub struct CalibrationSetArgs {
    /// The lens to be recovered: an OpenCV/ROS/vklens camera file. Views have its size.
    #[arg(long, value_name = "CAM")]
    camera: PathBuf,
    /// Folder for view_NN.png and poses.json (created if missing).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Number of views (Lambers et al. used 17).
    #[arg(long, default_value_t = 17, value_parser = clap::value_parser!(u32).range(3..=100))]
    count: u32,
    #[arg(long, value_parser = path_parser(), default_value = "vertex")]
    path: PathKind,
    /// Inner corners per row × per column (OpenCV's patternSize).
    #[arg(long, default_value = "9x6")]
    board: String,
    /// Square side in metres (any positive value; calibration is scale-free).
    #[arg(long, default_value_t = 0.04)]
    square: f64,
    /// Anti-aliasing: colour rendered at S× per axis and box-filtered, so corners are
    /// located to a small fraction of a pixel.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=vklens::plan::MAX_SUPERSAMPLE as i64))]
    supersample: u32,
    /// Warp path: source pixels per output pixel of the overscanned pinhole render.
    #[arg(long, default_value_t = 2.0)]
    density: f64,
    /// Anti-aliasing: this many jittered passes averaged (sub-sample offsets), so edge
    /// positions are not quantized to the 1/S grid (which calibration would mistake for lens distortion).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=vklens::plan::MAX_JITTER as i64))]
    jitter: u32,
    /// Vertex path: split board edges longer than L pixels (Alg. 1 needs fine geometry).
    #[arg(long, default_value_t = 4.0)]
    tessellate: f64,
}

pub fn run(args: CalibrationSetArgs) -> Result<(), CliError> {
    let camera = load_camera(&args.camera)?;
    let (columns, rows) = parse_board_size(&args.board)?;
    if !(args.square.is_finite() && args.square > 0.0) {
        return Err(CliError::input(format!(
            "--square {}: expected a positive number of metres",
            args.square
        )));
    }
    if !(args.tessellate.is_finite() && args.tessellate >= 0.25) {
        return Err(CliError::input(format!(
            "--tessellate {}: expected an edge length in pixels ≥ 0.25",
            args.tessellate
        )));
    }
    let board = Board {
        columns,
        rows,
        square: args.square,
    };
    let poses = board_poses(&camera, &board, args.count)
        .map_err(|e| CliError::input(format!("{}: {e}", args.camera.display())))?;
    std::fs::create_dir_all(&args.out).map_err(|e| {
        CliError::input(format!(
            "{}: cannot create the folder: {e}",
            args.out.display()
        ))
    })?;
    // A set is complete when its poses.json is there, and poses.json is written last: remove
    // an old one first, so that an interrupted run never leaves a set that looks complete.
    let poses_path = args.out.join("poses.json");
    match std::fs::remove_file(&poses_path) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => return Err(CliError::io(&poses_path, "cannot replace", &e)),
    }
    let scene = builtin::checkerboard(board, 4);
    let ctx = context()?;
    // One plan for every view: the recorder is built once and renders each pose in turn.
    let first = *poses
        .first()
        .ok_or_else(|| CliError::internal("a calibration set without views"))?;
    let request = RenderRequest {
        camera: camera.clone(),
        pose: first,
        previous_pose: first,
        path: args.path.choice(
            &camera,
            DEFAULT_DELTA,
            Some(args.tessellate),
            vklens::model::InverseMethod::Newton,
            args.density,
        ),
        outputs: OutputSpec {
            color: true,
            ..OutputSpec::default()
        },
        antialias: Antialias {
            supersample: args.supersample,
            jitter: args.jitter,
        },
        background: [0.5, 0.5, 0.5, 1.0],
        chromatic: None,
        rolling_shutter: None,
        // No moving rolling shutter: no bands to size.
        max_error_px: vklens::plan::scene_file::DEFAULT_MAX_ERROR_PX,
    };
    let mut plan = Plan::from_request(&request, ctx.gpu().max_image_side())?;
    plan.poses = poses.clone();
    // A path the set did not ask for (a cube map where no pinhole source fits) is said.
    if let (PathKind::Warp, vklens::plan::Route::Cube { .. }) = (args.path, &plan.route) {
        if let Some(step) = plan.steps.first() {
            progress_done(&step.why);
        }
    }
    let mut views = Vec::new();
    // The views written so far: removed again if the run fails or is interrupted before
    // poses.json (a set is all or nothing).
    let mut written = image_io::RunOutputs::new();
    execute_untimed(&ctx, &plan, &scene, 0..poses.len(), &mut |frame| {
        let i = frame.index;
        let pose = poses[i];
        let file = format!("view_{i:02}.png");
        progress_line(&format!("view {}/{}: {file}", i + 1, poses.len()));
        let color = frame
            .rendered
            .color
            .ok_or_else(|| vklens::Error::internal("the render produced no colour image"))?;
        let view_path = args.out.join(&file);
        image_io::save_staged(&color, &view_path, image_io::Channels(4))?
            .commit_into(&mut written)?;
        let r = pose.rvec();
        let t = pose.translation;
        views.push(serde_json::json!({
            "file": file,
            "rvec": [r.x, r.y, r.z],
            "tvec": [t.x, t.y, t.z],
        }));
        Ok(())
    })?;
    finish(&ctx)?;
    let json = serde_json::json!({
        "board": {"columns": columns, "rows": rows, "square_m": args.square},
        "image_size": [camera.width, camera.height],
        "path": args.path.name(),
        // The camera as a camera file reads it (its model included: tests/calibrate.py picks
        // cv2.fisheye for a fisheye).
        "camera": camera.to_json(),
        "pose_convention": "OpenCV: p_camera = R(rvec) p_board + tvec; board corner (i, j) at (i·square, j·square, 0)",
        "views": views,
    });
    // Views of an earlier, larger set are not this set's: removed before poses.json says the
    // set is complete.
    for i in poses.len().. {
        let stale = args.out.join(format!("view_{i:02}.png"));
        match std::fs::remove_file(&stale) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => break,
            Err(e) => return Err(CliError::io(&stale, "cannot remove the stale view", &e)),
        }
    }
    image_io::write_atomically(&poses_path, |tmp| {
        std::fs::write(tmp, format!("{json:#}\n"))
    })?;
    written.keep();
    progress_done(&format!(
        "wrote {} views and poses.json to {}",
        poses.len(),
        args.out.display()
    ));
    Ok(())
}
