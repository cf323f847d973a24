//! `vklens render`: a scene through a calibrated lens, by the vertex or the warp path.

use std::path::PathBuf;

use clap::Args;

use super::output::{check_output, write_outputs, Targets};
use super::{context, finish, load_camera, progress_done, progress_line, CliError};
use vklens::host::plan::render_request;
use vklens::model::rolling_shutter::Readout;
use vklens::model::InverseMethod;
use vklens::pass::geometry::DEFAULT_DELTA;
use vklens::plan::scene_file::{Antialias, OutputSpec, DEFAULT_MAX_ERROR_PX};
use vklens::plan::{PathKind, RenderRequest};
use vklens::scene::{builtin, Pose, Scene};

/// `--path`: the library's path names, each with its help (one spelling for the command
/// line and the scene file's `[render] path`).
pub fn path_parser() -> impl clap::builder::TypedValueParser<Value = PathKind> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new(PathKind::ALL.map(|k| PossibleValue::new(k.name()).help(k.help())))
        // The possible values admit only the names `from_name` knows.
        .map(|name| PathKind::from_name(&name).unwrap_or(PathKind::Vertex))
}

#[derive(Args, Debug)]
#[command(after_help = "Examples:
  vklens render --camera cam.yml --scene checkerboard:9x6 --output board.png --supersample 4 --jitter 4
  vklens render --camera cam.yml --scene boxes --output c.png --ids ids.png --depth d.exr --flow f.exr --tessellate 8
  vklens render --camera cam.yml --scene model.glb --output c.png --path warp --pose 0.1,0,0,0,0,3
  vklens render --scene examples/scenes/ids_and_flow.toml --out frames/ --explain --frames 0..2

Scene files (TOML) name the geometry, the optics (camera file or lens prescription), the
effects and outputs wanted and the accuracy budget; examples/scenes/README.md has the schema.")]
pub struct RenderArgs {
    /// The lens: an OpenCV/ROS/vklens camera file. The output has its width × height.
    /// (Not with a .toml scene: the scene file names its optics.)
    #[arg(long, value_name = "CAM")]
    camera: Option<PathBuf>,
    /// checkerboard[:COLSxROWS[:SQUARE_M]] (OpenCV's board, inner corners, default 9x6 of
    /// 0.04 m), grid[:N] (N×N textured quads, default 16), boxes, room (a 4 m room seen from its centre: for fisheyes), or an .obj/.gltf/.glb file.
    /// Or a scene file (.toml, see examples/scenes/): then the planner builds the cheapest
    /// pipeline for the effects, outputs and accuracy it asks for, and --out names a folder.
    #[arg(long, value_name = "SCENE")]
    scene: String,
    /// Colour output: .png (8-bit RGBA) or .exr (16-bit float RGBA).
    #[arg(long, value_name = "OUT")]
    output: Option<PathBuf>,
    /// Scene files: the folder for every output of every frame (created if missing):
    /// color_NNNN.png|exr, ids_NNNN.png, flow_NNNN.exr, depth_NNNN.exr, and plan.json.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Scene files: print the plan — each pass, why it is there, its measured time on the
    /// first frame — before rendering.
    #[arg(long)]
    explain: bool,
    /// Scene files: render only frames A..B of the pose list (A included, B not; A..=B
    /// includes B).
    #[arg(long, value_name = "A..B")]
    frames: Option<String>,
    /// Object IDs: .png (16-bit grey, 0 = background) or .exr (IDs as floats).
    #[arg(long, value_name = "IDS")]
    ids: Option<PathBuf>,
    /// 2D flow (.exr): R, G = pixel motion from --previous-pose to --pose, A = 1 where known;
    /// NaN where the surface was not visible to the lens in both poses. Vertex path only.
    #[arg(long, value_name = "F.exr")]
    flow: Option<PathBuf>,
    /// Camera depth (.exr): z in metres in R, G, B; +inf where nothing was drawn. Negative
    /// past 90° off the axis of a fisheye; --range is what such a lens wants.
    #[arg(long, value_name = "D.exr")]
    depth: Option<PathBuf>,
    /// Range (.exr): the distance in metres from the projection centre along each pixel's
    /// ray, in R, G, B; +inf where nothing was drawn. The vertex path recomputes depth and
    /// range on each pixel's own ray (exact, f32), the warp path samples them nearest.
    #[arg(long, value_name = "R.exr")]
    range: Option<PathBuf>,
    /// Class IDs (.png, 16-bit grey): each object's class by --class, 0 where none matches
    /// and for the background. Never blended.
    #[arg(long, value_name = "C.png")]
    classes: Option<PathBuf>,
    /// PATTERN=CLASS: objects whose name matches the shell glob PATTERN are class CLASS
    /// (0..=65535); repeat it, the first match wins. Names: OBJ o/g names, glTF node names,
    /// the built-in scenes' own (boxes: floor, box_red, box_green, box_blue); --objects lists
    /// them.
    #[arg(long = "class", value_name = "PATTERN=CLASS", value_parser = parse_class)]
    class: Vec<vklens::labels::ClassRule>,
    /// Boxes (.json): per object with a visible pixel, its visible box, its whole (amodal)
    /// box through the lens and its 3D box's corners (examples/scenes/README.md has the shape).
    #[arg(long, value_name = "B.json")]
    boxes: Option<PathBuf>,
    /// NAME=X,Y,Z: a world point to label (metres); repeat it. Its pixel and visibility go to
    /// --keypoints.
    #[arg(long = "keypoint", value_name = "NAME=X,Y,Z", value_parser = parse_keypoint, allow_hyphen_values = true)]
    keypoint: Vec<vklens::labels::Keypoint>,
    /// Keypoints (.json): each --keypoint's pixel (null where the lens does not see it) and
    /// whether it is visible.
    #[arg(long, value_name = "K.json")]
    keypoints: Option<PathBuf>,
    /// The scene's objects (.json): [{"id", "name", "class"}, …].
    #[arg(long, value_name = "O.json")]
    objects: Option<PathBuf>,
    #[arg(long, value_parser = path_parser(), default_value = "vertex")]
    path: PathKind,
    /// Split mesh edges longer than L pixels (pinhole image) before the vertex path: Alg. 1
    /// moves vertices only, so straight edges between them stay straight (Lambers et al.'s first
    /// limitation). `vklens bench vertex` shows what L costs in error and time.
    #[arg(long, value_name = "L")]
    tessellate: Option<f64>,
    /// Camera pose: OpenCV rvec and tvec (world → camera), rx,ry,rz,tx,ty,tz. Default: the
    /// scene centred, filling about 80 % of the view.
    #[arg(long, value_name = "POSE", allow_hyphen_values = true)]
    pose: Option<String>,
    /// The pose flow starts from (same form). Default: the camera moved sideways by 1 % of
    /// its distance to the scene centre.
    #[arg(long, value_name = "POSE", allow_hyphen_values = true)]
    previous_pose: Option<String>,
    /// The pose when the frame's last line is read (same form; --pose is the first line's):
    /// the camera moves during the readout of a rolling shutter. Needs a rolling shutter
    /// (--rolling-shutter, or the camera file's shutter_type). The vertex path draws each
    /// vertex where its own line reads it (exact); --path warp and cube draw the frame in
    /// bands of lines, each from its middle line's pose, as many as --max-error-px needs.
    #[arg(long, value_name = "POSE", allow_hyphen_values = true)]
    end_pose: Option<String>,
    /// The order the sensor reads its lines: top_to_bottom, bottom_to_top, left_to_right or
    /// right_to_left. Default: the camera file's shutter_type (global where it states none).
    #[arg(long, value_name = "READOUT", value_parser = parse_readout)]
    rolling_shutter: Option<Readout>,
    /// A moving rolling shutter (--end-pose) through --path warp or cube: the largest error
    /// in output pixels its bands of lines may leave against the exact per-line projection,
    /// the warp's own included. The fewest of 4, 8, 16, 32 or 64 bands that meet it are
    /// drawn (the progress line says how many, and their error); where even 64 miss it the
    /// render is refused. Default 0.01, as a scene file's [accuracy] max_error_px. The vertex
    /// path is exact and not held to it.
    #[arg(long, value_name = "PX")]
    max_error_px: Option<f64>,
    /// Lambers et al. Sec. 3.2's discard tolerance δ (D is added automatically).
    #[arg(long, default_value_t = DEFAULT_DELTA)]
    delta: f64,
    /// Inverse method of the warp path: newton, heikkila or fixed-point:N.
    #[arg(long, default_value = "newton", value_parser = super::parse_method)]
    method: InverseMethod,
    /// Render colour at S× per axis and box-filter down (anti-aliasing; 1 = off, max 8).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=vklens::plan::MAX_SUPERSAMPLE as i64))]
    supersample: u32,
    /// Warp path: source pixels per output pixel of the overscanned pinhole render. Above 1
    /// the bilinear warp minifies and aliases; for sharper output raise --supersample, which
    /// supersamples the warp as well.
    #[arg(long, default_value_t = 1.0)]
    density: f64,
    /// Anti-aliasing: this many jittered passes averaged (sub-sample offsets), so edge
    /// positions are not quantized to the 1/S grid.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=vklens::plan::MAX_JITTER as i64))]
    jitter: u32,
    /// Background colour R,G,B,A in 0..1.
    #[arg(long, default_value = "0,0,0,0", value_parser = parse_background)]
    background: Background,
}

#[derive(Debug, Clone, Copy)]
pub struct Background(pub [f32; 4]);

/// `--class PATTERN=CLASS`.
fn parse_class(s: &str) -> Result<vklens::labels::ClassRule, String> {
    let (pattern, class) = s
        .rsplit_once('=')
        .ok_or_else(|| format!("{s:?}: expected PATTERN=CLASS, e.g. \"car*=2\""))?;
    let class = class.trim().parse::<u16>().map_err(|_| {
        format!("{s:?}: the class must be a whole number 0..=65535 (classes are 16-bit)")
    })?;
    if pattern.is_empty() {
        return Err(format!("{s:?}: the pattern is empty"));
    }
    Ok(vklens::labels::ClassRule {
        pattern: pattern.to_string(),
        class,
    })
}

/// `--keypoint NAME=X,Y,Z`.
fn parse_keypoint(s: &str) -> Result<vklens::labels::Keypoint, String> {
    let bad = || format!("{s:?}: expected NAME=X,Y,Z (world metres)");
    let (name, xyz) = s.rsplit_once('=').ok_or_else(bad)?;
    let v: Vec<f64> = xyz
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    match <[f64; 3]>::try_from(v) {
        Ok(a) if a.iter().all(|c| c.is_finite()) && !name.is_empty() => {
            Ok(vklens::labels::Keypoint {
                name: name.to_string(),
                xyz: glam::DVec3::from(a),
            })
        }
        _ => Err(bad()),
    }
}

fn parse_readout(s: &str) -> Result<Readout, String> {
    s.parse::<Readout>().map_err(|e| e.to_string())
}

fn parse_background(s: &str) -> Result<Background, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|t| t.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("background {s:?}: expected R,G,B,A"))?;
    match <[f32; 4]>::try_from(v) {
        Ok(a) if a.iter().all(|c| c.is_finite()) => Ok(Background(a)),
        _ => Err(format!(
            "background {s:?}: expected four finite numbers R,G,B,A"
        )),
    }
}

/// The default previous pose: the camera moved sideways by 1 % of its distance to `target`.
fn nudged(pose: &Pose, scene: &Scene) -> Pose {
    let (lo, hi) = scene.mesh.bounds();
    let centre = 0.5 * (lo + hi);
    let distance = pose.apply(centre).length();
    Pose {
        translation: pose.translation + glam::DVec3::X * (0.01 * distance),
        ..*pose
    }
}

pub fn run(args: RenderArgs) -> Result<(), CliError> {
    if args.scene.to_ascii_lowercase().ends_with(".toml") {
        if let Some(flag) = args.conflicts_with_scene_file() {
            return Err(CliError::input(format!(
                "{flag} does not go with a scene file: it names its optics, outputs and poses; write into --out DIR"
            )));
        }
        return super::planned::run(
            &args.scene,
            super::planned::SceneRun {
                out: args.out.as_deref(),
                frames: args.frames.as_deref(),
                explain: args.explain,
            },
        );
    }
    for (given, flag) in [
        (args.out.is_some(), "--out"),
        (args.explain, "--explain"),
        (args.frames.is_some(), "--frames"),
    ] {
        if given {
            return Err(CliError::input(format!(
                "{flag} is for scene files (--scene S.toml); with --camera use --output"
            )));
        }
    }
    let (Some(camera_path), Some(output)) = (&args.camera, &args.output) else {
        return Err(CliError::input(
            "give --camera CAM and --output OUT (or --scene S.toml with --out DIR)",
        ));
    };
    let camera = load_camera(camera_path)?;
    let named: Vec<(&str, &std::path::Path)> = [
        ("--output", Some(output)),
        ("--ids", args.ids.as_ref()),
        ("--flow", args.flow.as_ref()),
        ("--depth", args.depth.as_ref()),
        ("--range", args.range.as_ref()),
        ("--classes", args.classes.as_ref()),
        ("--boxes", args.boxes.as_ref()),
        ("--keypoints", args.keypoints.as_ref()),
        ("--objects", args.objects.as_ref()),
    ]
    .into_iter()
    .filter_map(|(flag, p)| p.map(|p| (flag, p.as_path())))
    .collect();
    super::output::distinct_outputs(&named)?;
    let color_ext = check_output(output, "colour", &["png", "exr"])?;
    let ids_ext = match &args.ids {
        Some(p) => Some(check_output(p, "ID", &["png", "exr"])?),
        None => None,
    };
    if let Some(p) = &args.flow {
        check_output(p, "flow", &["exr"])?;
    }
    for (p, what, ext) in [
        (&args.depth, "depth", "exr"),
        (&args.range, "range", "exr"),
        (&args.classes, "class", "png"),
        (&args.boxes, "box", "json"),
        (&args.keypoints, "keypoint", "json"),
        (&args.objects, "object list", "json"),
    ] {
        if let Some(p) = p {
            check_output(p, what, &[ext])?;
        }
    }
    if !args.class.is_empty()
        && args.classes.is_none()
        && args.objects.is_none()
        && args.boxes.is_none()
    {
        return Err(CliError::input(
            "--class maps object names to classes: give --classes C.png (or --objects O.json, --boxes B.json) for them to go to",
        ));
    }
    if args.keypoint.is_empty() != args.keypoints.is_none() {
        return Err(CliError::input(if args.keypoint.is_empty() {
            "--keypoints names where keypoints go: give the points with --keypoint NAME=X,Y,Z"
        } else {
            "--keypoint names a point to label: give --keypoints K.json for the labels to go to"
        }));
    }
    if args.flow.is_some() && args.path == PathKind::Warp {
        return Err(CliError::input(
            "--flow needs --path vertex: flow vectors live in the pinhole image and a warp cannot carry them (Lambers et al. Table 1)",
        ));
    }
    if let Some(l) = args.tessellate {
        if !(l.is_finite() && l >= 0.25) {
            return Err(CliError::input(format!(
                "--tessellate {l}: expected an edge length in pixels ≥ 0.25"
            )));
        }
    }
    let max_error_px = args.max_error_px.unwrap_or(DEFAULT_MAX_ERROR_PX);
    if !(max_error_px.is_finite() && max_error_px > 0.0) {
        return Err(CliError::input(format!(
            "--max-error-px {max_error_px}: expected pixels > 0"
        )));
    }
    if !(args.delta.is_finite() && args.delta >= 0.0) {
        return Err(CliError::input(format!(
            "--delta {}: expected a number ≥ 0",
            args.delta
        )));
    }
    let scene = builtin::parse(&args.scene).map_err(|e| CliError::input(e.to_string()))?;
    let pose = match &args.pose {
        Some(p) => Pose::parse(p)?,
        None => scene.default_pose(&camera),
    };
    let previous_pose = match &args.previous_pose {
        Some(p) => Pose::parse(p)?,
        None => nudged(&pose, &scene),
    };
    let readout = args.rolling_shutter.or_else(|| camera.readout());
    let rolling_shutter = match (readout, &args.end_pose) {
        (Some(r), end) => Some((
            r,
            end.as_deref().map(Pose::parse).transpose()?.unwrap_or(pose),
        )),
        (None, Some(_)) => {
            return Err(CliError::input(
                "--end-pose: the camera moves during the frame, but the shutter is global (no --rolling-shutter, and no rolling shutter_type in the camera file): a global shutter reads every line at once, from --pose. Give --rolling-shutter top_to_bottom (or bottom_to_top, left_to_right, right_to_left), or drop --end-pose",
            ));
        }
        (None, None) => None,
    };
    let outputs = OutputSpec {
        color: true,
        ids: args.ids.is_some(),
        flow: args.flow.is_some(),
        depth: args.depth.is_some(),
        range: args.range.is_some(),
        classes: args.classes.is_some(),
        boxes: args.boxes.is_some(),
        keypoints: !args.keypoint.is_empty(),
        exr: color_ext == "exr",
    };
    let objects = vklens::labels::object_labels(&scene, &args.class);
    let path = args.path.choice(
        &camera,
        args.delta,
        args.tessellate,
        args.method,
        args.density,
    );
    let request = RenderRequest {
        camera,
        pose,
        previous_pose,
        path,
        outputs,
        antialias: Antialias {
            supersample: args.supersample,
            jitter: args.jitter,
        },
        background: args.background.0,
        chromatic: None,
        rolling_shutter,
        max_error_px,
    };
    let ctx = context()?;
    progress_line(&format!(
        "{}: {} triangles on {}",
        scene.name,
        scene.mesh.triangle_count(),
        ctx.gpu().device_name()
    ));
    let rendered =
        render_request(&ctx, &scene, &request, &mut |s| progress_line(s)).map_err(|e| {
            // The bands' budget missed: name the flag, and the path that needs none.
            if e.argument_name() == Some("max_error_px") {
                CliError::input(format!(
                    "--max-error-px {} (--path vertex)",
                    e.message_only()
                ))
            } else {
                e
            }
        })?;
    finish(&ctx)?;
    let view = vklens::labels::View::new(&request.camera, pose, rolling_shutter);
    let labels = vklens::labels::frame_labels(
        &view,
        &scene,
        &rendered,
        &vklens::labels::LabelRequest {
            objects: &objects,
            classes: outputs.classes,
            boxes: outputs.boxes,
            keypoints: &args.keypoint,
            max_error_px,
        },
    )
    .map_err(CliError::internal)?;
    write_outputs(
        &Targets {
            color: Some(output),
            ids: args.ids.as_deref(),
            flow: args.flow.as_deref(),
            depth: args.depth.as_deref(),
            range: args.range.as_deref(),
            classes: args.classes.as_deref(),
            boxes: args.boxes.as_deref(),
            keypoints: args.keypoints.as_deref(),
            objects: args.objects.as_deref().map(|p| (p, objects.as_slice())),
        },
        &rendered,
        &labels,
        ids_ext.as_deref(),
        None,
    )?;
    progress_done(&format!("wrote {}", output.display()));
    Ok(())
}

impl RenderArgs {
    pub(crate) fn conflicts_with_scene_file(&self) -> Option<&'static str> {
        if self.camera.is_some() {
            Some("--camera")
        } else if self.output.is_some() {
            Some("--output")
        } else if self.ids.is_some()
            || self.flow.is_some()
            || self.depth.is_some()
            || self.range.is_some()
            || self.classes.is_some()
            || self.boxes.is_some()
            || self.objects.is_some()
        {
            Some("--ids/--flow/--depth/--range/--classes/--boxes/--objects (the scene file's [outputs] asks for them)")
        } else if !self.class.is_empty() {
            Some("--class (the scene file's [classes] table)")
        } else if !self.keypoint.is_empty() || self.keypoints.is_some() {
            Some("--keypoint/--keypoints (the scene file's [[keypoints]] tables)")
        } else if self.pose.is_some() || self.previous_pose.is_some() || self.end_pose.is_some() {
            Some("--pose (the scene file's [[poses]] gives them)")
        } else if self.rolling_shutter.is_some() {
            Some("--rolling-shutter (the scene file's [sensor] rolling_shutter)")
        } else if self.max_error_px.is_some() {
            Some("--max-error-px (the scene file's [accuracy] max_error_px)")
        } else if self.supersample != 1 || self.jitter != 1 {
            Some("--supersample/--jitter (the scene file's [render] supersample and jitter)")
        } else {
            None
        }
    }
}
