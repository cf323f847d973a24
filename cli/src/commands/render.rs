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
    /// Camera depth (.exr): z in metres in R, G, B; +inf where nothing was drawn.
    #[arg(long, value_name = "D.exr")]
    depth: Option<PathBuf>,
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
    if let Some(p) = &args.depth {
        check_output(p, "depth", &["exr"])?;
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
        exr: color_ext == "exr",
    };
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
    write_outputs(
        &Targets {
            color: Some(output),
            ids: args.ids.as_deref(),
            flow: args.flow.as_deref(),
            depth: args.depth.as_deref(),
        },
        &rendered,
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
        } else if self.ids.is_some() || self.flow.is_some() || self.depth.is_some() {
            Some("--ids/--flow/--depth (the scene file's [outputs] asks for them)")
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
