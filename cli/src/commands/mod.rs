//! The `vklens` command line: parsing and printing only; the work is in the library.
//!
//! Exit codes: 0 success, 2 bad input (missing or unreadable file, bad JSON, bad parameter —
//! one clear line on stderr), 1 a failure of the machine (no Vulkan device, GPU error,
//! validation messages when `VKLENS_VALIDATION=1`).

/// `print!` to stdout that returns an error (exit 1, one line) instead of panicking when
/// stdout is closed, e.g. a pipe whose reader has quit.
macro_rules! out {
    ($($t:tt)*) => {
        $crate::commands::write_stdout(format_args!($($t)*))
    };
}

/// `println!` as [`out!`].
macro_rules! outln {
    () => {
        $crate::commands::write_stdout(format_args!("\n"))
    };
    ($($t:tt)*) => {
        $crate::commands::write_stdout(format_args!("{}\n", format_args!($($t)*)))
    };
}

mod bench;
mod calibration;
mod cameras;
mod demo;
mod lens;
mod new_camera;
mod output;
mod planned;
mod points;
mod render;
mod stereo_rectify;
#[cfg(test)]
mod tests;
mod warp;

use std::path::PathBuf;

use clap::{Parser, Subcommand, ValueEnum};

use vklens::model::rolling_shutter::Readout;
use vklens::model::{Camera, InverseMethod};
use vklens::pass::Precision;

/// Errors of the command line are the library's: the kind decides the exit code.
pub type CliError = vklens::Error;

/// The command-line flag of a library argument ([`vklens::Error::Argument`]).
pub fn flag_of(argument: &str) -> String {
    match argument {
        "size" => "--size WxH".into(),
        "format" => "--to".into(),
        "fstop" => "--fstop, or f_number in a scene's [optics]".into(),
        a => format!("--{}", a.replace('_', "-")),
    }
}

/// An error as the command line says it: an argument by its flag.
pub fn describe(e: &vklens::Error) -> String {
    match e.argument_name() {
        Some(a) => format!("{} ({})", e.message_only(), flag_of(a)),
        None => e.to_string(),
    }
}

/// The exit code of a failure, decided here and nowhere else: 2 when the user can fix it (bad
/// input, a path that does not exist or may not be opened, work the device cannot do), 1 for
/// everything else (a failure of the machine, the driver, or of vklens itself).
pub fn exit_code(e: &vklens::Error) -> i32 {
    use vklens::ErrorKind;
    match e.kind() {
        ErrorKind::Input | ErrorKind::Unsupported => 2,
        ErrorKind::Io if e.is_bad_path() => 2,
        _ => 1,
    }
}

const ABOUT: &str = "Realistic, calibrated camera-lens effects with raw Vulkan.";

/// [`LONG_ABOUT`] with the models of the list (`src/model/list.rs`) and their keys in place of
/// `{MODELS}`, wrapped to 100 columns.
fn long_about() -> String {
    use vklens::model::ModelKind;
    let models: Vec<String> = ModelKind::ALL
        .into_iter()
        .filter(|k| !matches!(k, ModelKind::Standard | ModelKind::Fisheye))
        .map(|k| match k.file_keys() {
            keys if keys.starts_with("none") => format!("\"{}\"", k.name()),
            keys => format!("\"{}\" ({keys})", k.name()),
        })
        .collect();
    let sentence = format!(
        "Every other model the field calibrates, exact to its tool: vklens JSON with \"model\": {}, \
         or \"colmap\" (colmap_model, params: all 18 of COLMAP's models)",
        models.join(", ")
    );
    let mut wrapped = String::new();
    let mut line = 0;
    for word in sentence.split(' ') {
        if line > 0 && line + 1 + word.len() > 100 {
            wrapped.push('\n');
            line = 0;
        } else if line > 0 {
            wrapped.push(' ');
            line += 1;
        }
        wrapped.push_str(word);
        line += word.len();
    }
    LONG_ABOUT.replace("{MODELS}", &wrapped)
}

const LONG_ABOUT: &str = "\
vklens applies the OpenCV standard camera model (fx fy cx cy; k1..k6, p1 p2, s1..s4, tau_x tau_y)
exactly as OpenCV computes it, on the CPU in f64 or on any Vulkan device (Mesa lavapipe included)
in f32 or f64, and says explicitly where a lens folds over and no inverse can be right.

Camera files (CAM): vklens JSON {\"width\", \"height\", \"fx\", \"fy\", \"cx\", \"cy\", \"dist_coeffs\": [...]},
OpenCV FileStorage YAML/XML/JSON as calibrateCamera writes it (camera_matrix,
distortion_coefficients, image_width, image_height; %YAML:1.0 headers welcome), ROS camera_info,
or a Brown headset lens {\"model\": \"brown\", \"width\", \"height\", \"c1\", \"c2\"} (the Durham radial-correction paper).
Fisheye cameras (OpenCV's cv2.fisheye, k1..k4): vklens JSON with \"model\": \"opencv_fisheye\"
(optional \"alpha\" skew and \"max_fov_deg\"), ROS camera_info with distortion_model equidistant,
a Kalibr camchain (cam0, or --camera-index N), or a COLMAP cameras.txt.
{MODELS}; and the tools' own files as they write them: Kalibr, Basalt,
COLMAP cameras.txt, camodocal/VINS (MEI, PINHOLE, KANNALA_BRANDT, SCARAMUZZA), ORB-SLAM2/3,
OKVIS, EuRoC sensor.yaml, SVO, DSO/DM-VIO camera.txt, LSD-SLAM/PTAM, stella_vslam, Kimera,
Gyroflow lens profiles, OpenCV stereo files (M1 D1 M2 D2 ...), OCamCalib calib_results.txt,
NCore camera JSON (docs/camera-files.md). `vklens cameras FILE` lists a file's cameras;
--camera-index or --camera-name picks one, --size gives a file without one its image size.
docs/how-it-works.md defines each model.

Environment: VKLENS_DEVICE picks the Vulkan device (cpu, gpu, an index, or part of its name);
VKLENS_VALIDATION=1 turns the Khronos validation layer on (any message fails the command).

Examples:
  vklens demo --output grid.png
  echo '[[0.1, 0.2], [0.5, -0.3]]' | vklens points distort --camera cam.yml
  echo '[[400, 300]]' | vklens points undistort --camera cam.yml --method fixed-point:5
  echo '[[1, 0, -0.1]]' | vklens points distort --camera fisheye.json
  echo '[[10, 240]]' | vklens points undistort --camera camchain.yaml --camera-index 1 --rays
  echo '[[0.5, 0.4, 4]]' | vklens points project --camera cam.yml --pose 0,0,0,0,0,0 --end-pose 0,0.02,0,0,0,0 --rolling-shutter top_to_bottom
  vklens distort --camera cam.yml --input pinhole.png --output lens.png --mask valid.png
  vklens undistort --camera cam.yml --input photo.png --output rectified.png
  vklens undistort --camera cam.yml --input photo.png --output rectified.png --alpha 0
  vklens new-camera --camera fisheye.json --balance 0.5 > new.json
  vklens overscan --camera cam.yml > source.json
  vklens stereo-rectify stereo.yml --alpha 0 --out rect/ --left l.png --right r.png
  vklens render --camera cam.yml --scene checkerboard:9x6 --output board.png --ids ids.png
  vklens render --camera cam.yml --scene boxes --output boxes.png --flow flow.exr --tessellate 8
  vklens calibration-set --camera cam.yml --out set/ && python3 tests/calibrate.py set/
  vklens cameras camchain.yaml
  vklens convert --camera EuRoC.yaml --size 752x480 --to kalibr --output camchain.yaml
  vklens lens info --lens lenses/dgauss.50mm.dat
  vklens lens fit-opencv --lens lenses/dgauss.50mm.dat --sensor 36x24 --pixels 1800x1200 --out dgauss.json
  vklens bench inverse --json";

#[derive(Parser, Debug)]
#[command(name = "vklens", version, about = ABOUT, long_about = long_about())]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Which camera of a --camera file that holds several (a Kalibr camchain's camN, a COLMAP
    /// cameras.txt's Nth line), counting from 0. Default: the first. `vklens cameras FILE`
    /// lists them.
    #[arg(long, global = true, value_name = "N")]
    camera_index: Option<usize>,
    /// Which camera of a --camera file, by the name the file gives it: cam1 (Kalibr), M2
    /// (OpenCV stereo), LEFT (ORB-SLAM), a COLMAP camera id as written.
    #[arg(long, global = true, value_name = "NAME")]
    camera_name: Option<String>,
    /// The image size of a --camera file that gives none (ORB-SLAM2 settings, DSO without a
    /// size line, an OpenCV file without image_width), as WIDTHxHEIGHT.
    #[arg(long, global = true, value_name = "WxH", value_parser = parse_size)]
    size: Option<(u32, u32)>,
}

/// The `--camera-index`, `--camera-name` and `--size` of this run (read by every camera load).
static CAMERA_OPTIONS: std::sync::OnceLock<vklens::io::catalog::LoadOptions> =
    std::sync::OnceLock::new();

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    vklens::io::catalog::parse_size(s).map_err(|e| e.to_string())
}

/// The camera-selection options of this run.
pub(crate) fn camera_options() -> vklens::io::catalog::LoadOptions {
    CAMERA_OPTIONS.get().cloned().unwrap_or_default()
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Map points through a camera model: JSON on stdin, JSON on stdout.
    #[command(subcommand)]
    Points(PointsCommand),
    /// Measure what accuracy costs in time.
    #[command(subcommand)]
    Bench(BenchCommand),
    /// Render a procedural grid through a lens to a PNG (no input image needed).
    Demo(demo::DemoArgs),
    /// Simulate the lens on a pinhole image: every output pixel samples the input where the
    /// inverse model says its light came from (Lambers et al. Sec. 3.3).
    Distort(warp::WarpArgs),
    /// Rectify an image taken through the lens into a pinhole image (forward model per pixel,
    /// as OpenCV's initUndistortRectifyMap + remap).
    Undistort(warp::WarpArgs),
    /// Pre-distort an image for a headset lens (the Durham radial-correction paper): the screen shows what the lens will
    /// undo; with --chromatic, lateral colour is pre-corrected per channel.
    Precorrect(warp::WarpArgs),
    /// Print the pinhole source camera (JSON) that covers every valid distorted pixel.
    Overscan(warp::OverscanArgs),
    /// Print the pinhole camera to undistort into, chosen as OpenCV chooses it, and its ROI.
    ///
    /// Prints {"camera": {...}, "roi": [x, y, w, h]}. --alpha A for OpenCV's standard model
    /// (cv2.getOptimalNewCameraMatrix: 0 crops to pixels that all have a source, 1 keeps every
    /// source pixel), --balance B [--fov-scale F] for its fisheye model
    /// (cv2.fisheye.estimateNewCameraMatrixForUndistortRectify). The camera is a vklens JSON
    /// camera: `--source-camera` of `vklens undistort` reads it, and so does every --camera.
    /// `vklens undistort --alpha A` (or --balance B) picks it in one step.
    ///
    /// Examples:
    ///   vklens new-camera --camera cam.yml --alpha 0
    ///   vklens new-camera --camera cam.yml --alpha 1 --new-size 1920x1080 --center-principal-point
    ///   vklens new-camera --camera fisheye.json --balance 0.5 --fov-scale 1.2
    #[command(verbatim_doc_comment)]
    NewCamera(new_camera::NewCameraArgs),
    /// Rectify a calibrated stereo pair as OpenCV does: camera_info files with its R and P.
    ///
    /// Computes what cv2.stereoRectify (OpenCV's standard model) or cv2.fisheye.stereoRectify
    /// (its fisheye model) returns for the pair, and writes DIR/left.yaml and DIR/right.yaml:
    /// ROS camera_info files with each lens's K and D and the pair's R1, P1 (R2, P2), which
    /// `vklens undistort --camera DIR/left.yaml` and ROS image_proc rectify with. With --left
    /// and --right it also writes the rectified images, DIR/left.png and DIR/right.png, in
    /// which a point shows on the same row in both (the same column for a vertical pair).
    /// Prints the baseline, the rectified focal length and principal points and the valid
    /// ROIs on stderr.
    ///
    /// The pair: a PAIR_FILE (an OpenCV stereo file with R and T, or a Kalibr camchain), or
    /// --camera LEFT --camera RIGHT with --rotation and --translation (or --extrinsics FILE).
    /// R and T are cv2.stereoCalibrate's: X2 = R·X1 + T takes a point from the first
    /// camera's frame to the second's. The baseline is laid along the rows, or along the
    /// columns where it is more vertical than horizontal (standard model only: OpenCV's
    /// fisheye rule always takes the rows, turning a vertical pair's images a quarter turn).
    ///
    /// Examples:
    ///   vklens stereo-rectify stereo.yml --alpha 0 --out rect/
    ///   vklens stereo-rectify intrinsics.yml --extrinsics extrinsics.yml --size 640x480 --out rect/
    ///   vklens stereo-rectify camchain.yaml --balance 0.5 --out rect/ --left l.png --right r.png
    ///   vklens stereo-rectify --camera left.yml --camera right.yml \
    ///       --rotation 0.01,-0.02,0.005 --translation -0.12,0.003,0.001 --out rect/
    ///   vklens undistort --camera rect/left.yaml --input l.png --output l_rect.png
    #[command(verbatim_doc_comment)]
    StereoRectify(stereo_rectify::StereoRectifyArgs),
    /// Render a scene through the lens (Lambers et al.): per vertex with Alg. 1 (colour, IDs, flow,
    /// depth, all exact) or as a pinhole render plus the compute warp. With a scene file
    /// (--scene S.toml --out DIR) the planner picks the cheapest pipeline for what it asks.
    Render(render::RenderArgs),
    /// Render checkerboard views through the lens in varied poses (Lambers et al. Sec. 4), for
    /// OpenCV to calibrate from: DIR/view_NN.png and DIR/poses.json. tests/calibrate.py
    /// runs the calibration and reports how well the parameters come back.
    CalibrationSet(calibration::CalibrationSetArgs),
    /// Real lens systems (Heidrich et al.): lens files of spherical surfaces and glasses.
    #[command(subcommand)]
    Lens(lens::LensCommand),
    /// List the cameras a calibration file holds: index, name, model, size, and the format
    /// it was read as (or why a camera cannot load).
    Cameras(cameras::CamerasArgs),
    /// Write a camera in another tool's format: vklens, opencv, ros, kalibr, colmap, basalt
    /// (refused, with the reason, where the format cannot hold the camera exactly).
    Convert(cameras::ConvertArgs),
}

#[derive(Subcommand, Debug)]
enum PointsCommand {
    /// Forward model: undistorted normalized points [[x, y], ...] (x = X/Z, y = Y/Z) or
    /// camera-frame points [[X, Y, Z], ...] (fisheyes and the other wide models see Z ≤ 0 too,
    /// up to their domain's edge)
    /// on stdin → distorted pixels [[u, v], ...] on stdout (null where the model is undefined
    /// or, for points, where the lens does not see).
    Distort {
        /// Camera file (JSON, OpenCV FileStorage YAML/XML/JSON, or ROS camera_info YAML).
        #[arg(long, value_name = "CAM")]
        camera: PathBuf,
        /// cpu: f64, full precision, as cv2.projectPoints. gpu: the shader's result.
        #[arg(long, value_enum, default_value_t = Backend::Cpu)]
        backend: Backend,
        /// Shader arithmetic for --backend gpu (f64 needs shaderFloat64).
        #[arg(long, default_value = "f32", value_parser = parse_precision)]
        precision: Precision,
    },
    /// Inverse model: distorted pixels [[u, v], ...] on stdin → undistorted normalized points
    /// [[x, y] | null, ...] on stdout; null where the pixel has no preimage in the valid domain
    /// (the lens folds over there, or a rational denominator vanishes) and where it sees at or
    /// behind the image plane (a wide model past 90°). With --rays: unit camera-frame rays
    /// [[x, y, z] | null, ...], past 90° too.
    Undistort {
        /// Camera file (JSON, OpenCV FileStorage YAML/XML/JSON, or ROS camera_info YAML).
        #[arg(long, value_name = "CAM")]
        camera: PathBuf,
        /// newton: exact (Newton, analytic Jacobian, all 14 coefficients). heikkila: Lambers et al.
        /// Eq. 2 (k1 k2 p1 p2 only, approximate). fixed-point:N: OpenCV's undistortPoints
        /// iteration with N iterations (OpenCV's default is 5).
        #[arg(long, default_value = "newton", value_parser = parse_method)]
        method: InverseMethod,
        /// cpu: f64. gpu: the shader's result.
        #[arg(long, value_enum, default_value_t = Backend::Cpu)]
        backend: Backend,
        /// Shader arithmetic for --backend gpu. Near a fold f32 loses accuracy (the inverse is
        /// ill-conditioned there); f64 does not, where the device has shaderFloat64.
        #[arg(long, default_value = "f32", value_parser = parse_precision)]
        precision: Precision,
        /// Write unit rays [x, y, z] instead of normalized points [x, y] (what a fisheye needs
        /// past 90° off the axis).
        #[arg(long)]
        rays: bool,
    },
    /// World points [[X, Y, Z], ...] on stdin → pixels [[u, v] | null, ...], global or rolling shutter.
    ///
    /// Global shutter (no --rolling-shutter, and the camera file states none): every line is
    /// read at once from --pose, and the pixels are cv2.projectPoints(X, rvec, tvec, K, D)'s
    /// (any model: the camera's full forward map). null where the lens does not see the point
    /// (behind the camera, past a wide lens's field of view).
    ///
    /// Rolling shutter: the sensor reads its lines one after another, from s = 0 (the first
    /// line) to s = 1 (the last): row v is read at s = v / (H − 1) top_to_bottom, 1 − v / (H − 1)
    /// bottom_to_top; column u at u / (W − 1) left_to_right, 1 − u / (W − 1) right_to_left.
    /// --pose is the camera's pose when the first line is read, --end-pose when the last is; in
    /// between the rotation turns at a constant rate (slerp) and the centre moves on a straight
    /// line. A point appears at the pixel whose own readout time s gives the pose it is seen
    /// from: p = π(pose(s) · X) with s = line_time(p). vklens solves that to 1e-9 px (a scan of
    /// [0, 1] for the first root, then Illinois false position); the one step from mid-frame
    /// that gyroscope-based warps take leaves pixels of error on a fast pan
    /// (docs/rolling-shutter.md). Where motion is so fast that a point is read on several lines,
    /// the first in readout order is written. A point no line reads (outside the image along
    /// the readout, the whole frame) is written where it is when the nearer end of the readout
    /// happens; one that leaves the lens's view during the readout without being read is null.
    ///
    /// Examples:
    ///   echo '[[0.5, 0.4, 4.0]]' | vklens points project --camera cam.yml --pose 0,0,0,0,0,0
    ///   echo '[[0.5, 0.4, 4.0]]' | vklens points project --camera cam.yml --pose 0,0,0,0,0,0 \
    ///       --end-pose 0,0.0175,0,0,0,0 --rolling-shutter top_to_bottom
    ///   # an NCore file's shutter_type gives the readout:
    ///   echo '[[1, 0, 5]]' | vklens points project --camera ncore.json --pose 0,0,0,0,0,0 \
    ///       --end-pose 0,0,0,-0.3,0,0
    #[command(verbatim_doc_comment)]
    Project {
        /// Camera file (any format `vklens cameras` lists).
        #[arg(long, value_name = "CAM")]
        camera: PathBuf,
        /// The camera's pose: OpenCV rvec and tvec (world → camera, as cv2.projectPoints and
        /// cv2.solvePnP), rx,ry,rz,tx,ty,tz. With a rolling shutter, when the first line is read.
        #[arg(long, value_name = "POSE", allow_hyphen_values = true)]
        pose: String,
        /// The pose when the last line is read (same form); needs a rolling shutter. Default:
        /// --pose (the camera does not move during the frame).
        #[arg(long, value_name = "POSE", allow_hyphen_values = true)]
        end_pose: Option<String>,
        /// The order the sensor reads its lines: top_to_bottom, bottom_to_top, left_to_right
        /// or right_to_left. Default: the camera file's own (NCore's shutter_type), else a
        /// global shutter.
        #[arg(long, value_name = "DIR", value_parser = parse_readout)]
        rolling_shutter: Option<Readout>,
    },
}

#[derive(Subcommand, Debug)]
enum BenchCommand {
    /// Error and time of every inverse method and iteration count, CPU and GPU, on the shared
    /// reference cameras, beside OpenCV's own undistortPoints errors.
    Inverse(bench::InverseArgs),
    /// Frame time of the warp (analytic vs map, with and without chromatic offsets) beside a
    /// copy pass on the same driver, and the cost of building a full-frame inverse map.
    Warp(bench::WarpArgs),
    /// The geometry path (Alg. 1) beside a plain pinhole render and pinhole + compute warp on
    /// grids of growing size, what tessellation costs and leaves, and the Durham radial-correction paper's mesh warp.
    Vertex(bench::VertexArgs),
    /// Heidrich et al.'s image-based lens model: lens samples, angle threshold and film grid
    /// against PSNR versus the CPU reference ray tracer, and the speed ratio between them.
    Lens(bench::LensArgs),
    /// The planner's choices for the example scenes beside the everything-on pipeline, and
    /// the error-versus-time trade-off it picks from (inverse methods, tessellations).
    Plan(bench::PlanArgs),
    /// Lenses past one pinhole frustum at 1920×1080 (a 180° and a 200° fisheye, a GoPro-like
    /// lens): the vertex path, the pinhole-overscan warp where it fits and the cube-map warp,
    /// each with its coordinate error against the f64 model and its frame time × a plain
    /// pinhole render, and the cube face size each needs.
    Wide(bench::WideArgs),
    /// What each label costs beside colour alone (boxes scene, 1920×1080, the GoPro-like lens
    /// and the 200° fisheye): the vertex path with IDs, depth, range, IDs and range, each as ×
    /// the colour-alone frame; the CPU time of classes, boxes and keypoints; the cube route
    /// with colour alone and with IDs and range.
    Labels(bench::WideArgs),
    /// A camera panning during a rolling shutter's readout, drawn exactly (each vertex's
    /// readout time solved on the GPU) beside the global shutter's vertex path: frame time and
    /// ratio, on grids of 128² and 512² quads; then the warp in 4 to 64 bands of lines, each
    /// band's time, geometric error and colour difference against the exact path.
    #[command(name = "rolling-shutter")]
    RollingShutter(bench::WideArgs),
    /// What a user waits for before the first frame, cold (fresh processes, no pipeline
    /// cache): `vklens undistort` of a 64×36 image, `vklens undistort` and `distort` at
    /// 1920×1080 beside the Python + OpenCV scripts a user would write, `vklens render` of the
    /// rolling-shutter example and its global twin, Python's `Warper` to its first frame; then
    /// the creation of each warp pipeline for each camera model on a new device.
    Startup(bench::StartupArgs),
    /// Every camera model of the table (one realistic camera each) beside OpenCV's standard
    /// model: CPU forward and inverse time and round-trip error, the GPU's f32 error and time,
    /// the inverse over a 1080p frame as a ratio to the standard model, and the error of the
    /// fits of the inverse that f-theta files carry.
    Models(bench::ModelsArgs),
    /// Every bench above on the device VKLENS_DEVICE picks, in one run, with the OpenCV peers
    /// Python can run (cv2 beside `bench warp`; the Python package's frame loop): writes (or
    /// replaces) that device's section of docs/benchmarks.md, each bench's tables headed by
    /// the device, the driver and the date, then its goals judged on the rows (met, not met,
    /// not measured). A real GPU gets its own section: `VKLENS_DEVICE=gpu vklens bench all`.
    /// Quick paths: `--benches models` (the section keeps the other tables); `--json >
    /// rows.jsonl`, then `--from rows.jsonl` writes the section without measuring.
    All(bench::AllArgs),
}

/// Where the model runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Backend {
    Cpu,
    Gpu,
}

// clap shows a value parser's error as text.
fn parse_method(s: &str) -> Result<InverseMethod, String> {
    s.parse()
        .map_err(|e: vklens::model::ModelError| e.to_string())
}

fn parse_readout(s: &str) -> Result<Readout, String> {
    s.parse()
        .map_err(|e: vklens::model::ModelError| e.to_string())
}

fn parse_precision(s: &str) -> Result<Precision, String> {
    s.parse().map_err(|e: vklens::Error| e.to_string())
}

/// Writes to stdout; a failure (a closed pipe) is an I/O error on `<stdout>`.
pub(crate) fn write_stdout(args: std::fmt::Arguments) -> Result<(), CliError> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    out.write_fmt(args)
        .and_then(|_| out.flush())
        .map_err(|e| CliError::io(std::path::Path::new("<stdout>"), "cannot write", &e))
}

/// Parses the JSON points `vklens points` reads on stdin: rows of two numbers, or (with
/// `three`) of two or three; errors name the element.
pub fn parse_point_rows(text: &str, three: bool) -> Result<Vec<Vec<f64>>, CliError> {
    points::parse_rows(text, three)
}

/// Loads a camera file, as a one-line input error.
pub(crate) fn load_camera(path: &std::path::Path) -> Result<Camera, CliError> {
    vklens::io::camera::load_camera_with(path, &camera_options())
}

/// A headless context from the environment; validation messages are checked by `finish`.
/// The driver's pipeline cache is kept in the user's cache folder (`VKLENS_PIPELINE_CACHE`
/// names another file; set empty, none).
pub(crate) fn context() -> Result<vklens::host::Context, CliError> {
    let mut options = vklens::host::ContextOptions::from_env();
    if std::env::var_os("VKLENS_PIPELINE_CACHE").is_none() {
        options.pipeline_cache = user_pipeline_cache(options.device.as_deref());
    }
    vklens::host::Context::new(options)
}

/// `$XDG_CACHE_HOME/vklens/pipelines-DEVICE.bin` (else `~/.cache/…`): a file per device
/// choice, since a cache holds one device's pipelines.
fn user_pipeline_cache(device: Option<&str>) -> Option<std::path::PathBuf> {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|d| !d.is_empty())
        .map(std::path::PathBuf::from)
        .or_else(|| {
            std::env::var_os("HOME")
                .filter(|d| !d.is_empty())
                .map(|home| std::path::PathBuf::from(home).join(".cache"))
        })?;
    let device: String = device
        .unwrap_or("default")
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    Some(base.join("vklens").join(format!("pipelines-{device}.bin")))
}

/// Fails if the validation layer (when on) reported anything.
pub(crate) fn finish(ctx: &vklens::host::Context) -> Result<(), CliError> {
    ctx.check_validation()
}

/// The progress bar of this run: drawn on stderr when it is a terminal (indicatif: the step,
/// its rate and the time left), plain lines otherwise (logs, CI).
static PROGRESS: std::sync::Mutex<Option<indicatif::ProgressBar>> = std::sync::Mutex::new(None);

/// `N/M` in a progress message (`view 3/17: view_02.png`): the bar's position and length.
fn step_of(what: &str) -> Option<(u64, u64)> {
    what.split(|c: char| c.is_whitespace() || c == ':' || c == '(' || c == ')')
        .find_map(|t| {
            let (n, m) = t.split_once('/')?;
            Some((n.parse().ok()?, m.parse().ok()?))
        })
        .filter(|&(n, m)| m > 0 && n <= m)
}

/// Progress on stderr: a bar with rate and ETA when the message counts `N/M`, a spinner with
/// the elapsed time otherwise; one line per step when stderr is not a terminal.
pub(crate) fn progress_line(what: &str) {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        eprintln!("{what}");
        return;
    }
    let Ok(mut slot) = PROGRESS.lock() else {
        return;
    };
    let step = step_of(what);
    let bar = slot.get_or_insert_with(|| {
        let bar = indicatif::ProgressBar::new_spinner();
        bar.enable_steady_tick(std::time::Duration::from_millis(120));
        bar
    });
    match step {
        Some((n, m)) => {
            if bar.length() != Some(m) {
                bar.set_style(
                    indicatif::ProgressStyle::with_template(
                        "{bar:24.cyan/blue} {pos}/{len} {rate} ETA {eta:>4} {msg}",
                    )
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
                    .with_key(
                        "rate",
                        |s: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
                            let _ = write!(w, "{:>6.2}/s", s.per_sec());
                        },
                    ),
                );
                bar.set_length(m);
                bar.reset_eta();
            }
            // The message names the step being started: the ones before it are done.
            bar.set_position(n.saturating_sub(1));
        }
        None => bar.set_style(
            indicatif::ProgressStyle::with_template("{spinner} {elapsed:>4} {msg}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
        ),
    }
    bar.set_message(what.to_string());
}

/// Clears the progress bar, if one is drawn (before an error is printed).
pub fn progress_clear() {
    if let Ok(mut slot) = PROGRESS.lock() {
        if let Some(bar) = slot.take() {
            bar.finish_and_clear();
        }
    }
}

/// The end of a run of progress lines: the bar is cleared and `what` printed as a line.
pub(crate) fn progress_done(what: &str) {
    if let Ok(mut slot) = PROGRESS.lock() {
        if let Some(bar) = slot.take() {
            bar.finish_and_clear();
        }
    }
    eprintln!("{what}");
}

/// Runs the command line.
pub fn run(cli: Cli) -> Result<(), CliError> {
    // Set once per process; a second `run` in one process keeps the first options.
    let _ = CAMERA_OPTIONS.set(vklens::io::catalog::LoadOptions {
        index: cli.camera_index,
        name: cli.camera_name,
        size: cli.size,
    });
    match cli.command {
        Command::Points(PointsCommand::Distort {
            camera,
            backend,
            precision,
        }) => points::distort(&camera, backend, precision),
        Command::Points(PointsCommand::Undistort {
            camera,
            method,
            backend,
            precision,
            rays,
        }) => points::undistort(&camera, method, backend, precision, rays),
        Command::Points(PointsCommand::Project {
            camera,
            pose,
            end_pose,
            rolling_shutter,
        }) => points::project(&camera, &pose, end_pose.as_deref(), rolling_shutter),
        Command::Bench(BenchCommand::Inverse(args)) => bench::inverse(args),
        Command::Bench(BenchCommand::Warp(args)) => bench::warp(args),
        Command::Bench(BenchCommand::Vertex(args)) => bench::vertex(args),
        Command::Bench(BenchCommand::Lens(args)) => bench::lens(args),
        Command::Bench(BenchCommand::Plan(args)) => bench::plan(args),
        Command::Bench(BenchCommand::Wide(args)) => bench::wide(args),
        Command::Bench(BenchCommand::Labels(args)) => bench::labels(args),
        Command::Bench(BenchCommand::RollingShutter(args)) => bench::rolling_shutter(args),
        Command::Bench(BenchCommand::Startup(args)) => bench::startup(args),
        Command::Bench(BenchCommand::Models(args)) => bench::models(args),
        Command::Bench(BenchCommand::All(args)) => bench::all(args),
        Command::Demo(args) => demo::run(args),
        Command::Distort(args) => warp::run(args, vklens::WarpDirection::Distort),
        Command::Undistort(args) => warp::run(args, vklens::WarpDirection::Undistort),
        Command::Precorrect(args) => warp::run(args, vklens::WarpDirection::Precorrect),
        Command::Overscan(args) => warp::overscan_command(args),
        Command::NewCamera(args) => new_camera::run(args),
        Command::StereoRectify(args) => stereo_rectify::run(args),
        Command::Render(args) => render::run(args),
        Command::CalibrationSet(args) => calibration::run(args),
        Command::Lens(command) => lens::run(command),
        Command::Cameras(args) => cameras::list(args),
        Command::Convert(args) => cameras::convert(args),
    }
}
