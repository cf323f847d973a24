//! A render asked for directly — the flags of `vklens render --camera`, a calibration set's
//! views, a bench's fixed path — turned into a [`Plan`], so that one recorder renders
//! everything. A scene file leaves the route to the planner; a request names it, and the
//! plan takes it even where the planner would not choose it (object IDs through the warp,
//! nearest-sampled, for instance), within what the route can deliver honestly.

use crate::model::overscan::{beyond_a_pinhole, cube_face_side};
use crate::model::rolling_shutter::{FrameMotion, Readout};
use crate::model::{Camera, InverseMethod};
use crate::pass::geometry::DEFAULT_DELTA;
use crate::scene::{Environment, Pose, Scene};
use crate::{Error, Result};

use super::antialias::{scaled_camera, MAX_JITTER, MAX_SUPERSAMPLE};
use super::limits::pinhole_source_refusal;
use super::scene_file::{Antialias, OutputSpec, DEFAULT_MAX_ERROR_PX};
use super::search::{search_bands, BandsVia, Candidates, CubeCandidate, WarpChoice};
use super::{inverse_error_px, Plan, Route, Stage, Step, CUBE_RAY_ERROR_PX};

/// Which path renders the lens, as a caller names it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PathChoice {
    /// Lambers et al.'s Alg. 1 per vertex with discard tolerance δ, the mesh tessellated to
    /// edges of `tessellate` px first when given.
    Vertex { delta: f64, tessellate: Option<f64> },
    /// A pinhole render of the overscanned frustum with `density` source pixels per output
    /// pixel, then the compute warp by `method`. Where no pinhole source holds the lens, a
    /// cube map instead (colour only), and the plan says why.
    Warp { method: InverseMethod, density: f64 },
    /// The camera's pinhole projection, its distortion ignored.
    Pinhole,
    /// Six 90° pinhole faces of `side` px and the sphere warp (colour only).
    Cube { side: u32 },
}

/// The paths a caller can name, spelled one way wherever they are named: `vklens render
/// --path`, `vklens calibration-set --path` and a scene file's `[render] path`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PathKind {
    /// Lambers et al.'s Alg. 1 per vertex.
    Vertex,
    /// A pinhole render of the overscanned frustum and the compute warp.
    Warp,
    /// Six pinhole faces of a cube map and the sphere warp.
    Cube,
}

impl PathKind {
    /// Every path, in the order the help lists them.
    pub const ALL: [PathKind; 3] = [PathKind::Vertex, PathKind::Warp, PathKind::Cube];

    /// How it is spelled: `vertex`, `warp`, `cube`.
    pub fn name(self) -> &'static str {
        match self {
            PathKind::Vertex => "vertex",
            PathKind::Warp => "warp",
            PathKind::Cube => "cube",
        }
    }

    /// The path spelled `name`, if any.
    pub fn from_name(name: &str) -> Option<PathKind> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    /// What the path gives and costs, as `--help` says it.
    pub fn help(self) -> &'static str {
        match self {
            PathKind::Vertex => "Alg. 1 per vertex, triangles outside the frustum ± (δ + D) dropped: exact colour, IDs, flow and depth, as long as the mesh is fine (see --tessellate)",
            PathKind::Warp => "A pinhole render of the overscanned frustum, then the compute warp (inverse model per pixel): colour bilinear, IDs, depth and range nearest, no flow. Where no pinhole source can hold the lens (180° and more, or beyond the device's image limit) it renders a cube map instead, and says so",
            PathKind::Cube => "Six 90° pinhole faces of a cube map, then the warp by each pixel's ray (colour only): any lens, fisheyes past 180° included. Face size from --density",
        }
    }

    /// The path for `camera` with its parameters: Alg. 1's δ and tessellation, the warp's
    /// method and density (source pixels per output pixel, or face pixels per output pixel
    /// for the cube).
    pub fn choice(
        self,
        camera: &Camera,
        delta: f64,
        tessellate: Option<f64>,
        method: InverseMethod,
        density: f64,
    ) -> PathChoice {
        match self {
            PathKind::Vertex => PathChoice::Vertex { delta, tessellate },
            PathKind::Warp => PathChoice::Warp { method, density },
            PathKind::Cube => PathChoice::cube(camera, density),
        }
    }
}

impl std::fmt::Display for PathKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl PathChoice {
    /// The path it names (`None`: the pinhole projection, which no caller names by a path).
    pub fn kind(&self) -> Option<PathKind> {
        match self {
            PathChoice::Vertex { .. } => Some(PathKind::Vertex),
            PathChoice::Warp { .. } => Some(PathKind::Warp),
            PathChoice::Cube { .. } => Some(PathKind::Cube),
            PathChoice::Pinhole => None,
        }
    }

    /// The cube path with faces of `density` face pixels per output pixel at the centre.
    pub fn cube(camera: &Camera, density: f64) -> Self {
        PathChoice::Cube {
            side: cube_face_side(camera, density),
        }
    }
}

/// What to render, route named: a camera, one pose (and the pose flow starts from), the
/// outputs, anti-aliasing and background.
#[derive(Debug, Clone)]
pub struct RenderRequest {
    pub camera: Camera,
    pub pose: Pose,
    /// The pose flow is measured from.
    pub previous_pose: Pose,
    pub path: PathChoice,
    pub outputs: OutputSpec,
    pub antialias: Antialias,
    pub background: [f32; 4],
    /// Lateral chromatic aberration (warp and cube paths): per-channel radial scales R, G, B.
    pub chromatic: Option<[f64; 3]>,
    /// A rolling shutter: its readout, and the pose when the frame's last line is read
    /// (`pose` is the first line's). With the two poses apart the vertex and pinhole paths
    /// draw each vertex where its own line reads it; the warp and cube paths draw the frame in
    /// bands of lines, as many as `max_error_px` needs ([`Plan::from_request_with_scene`]).
    /// `None`: a global shutter.
    pub rolling_shutter: Option<(Readout, Pose)>,
    /// The largest geometric error (output pixels) the bands of a moving rolling shutter may
    /// leave on the warp and cube paths, the route's own error included, against the exact
    /// per-line projection: the fewest bands that meet it are drawn, as a scene file's
    /// `[accuracy] max_error_px` sizes them. The other paths are taken as named, not held to it.
    pub max_error_px: f64,
}

impl RenderRequest {
    /// One 8-bit colour image of `camera` by `path`, from the identity pose (the camera at the
    /// world origin): no anti-aliasing or chromatic aberration, a transparent background.
    pub fn color(camera: &Camera, path: PathChoice) -> Self {
        RenderRequest {
            camera: camera.clone(),
            pose: Pose::IDENTITY,
            previous_pose: Pose::IDENTITY,
            path,
            outputs: OutputSpec {
                color: true,
                ..OutputSpec::default()
            },
            antialias: Antialias::default(),
            background: [0.0; 4],
            chromatic: None,
            rolling_shutter: None,
            max_error_px: DEFAULT_MAX_ERROR_PX,
        }
    }
}

impl Plan {
    /// The plan that renders `request` by the path it names, on a device whose images are at
    /// most `max_image_side` px on a side. Refuses what the path cannot deliver (flow through
    /// a warp, data through a cube map), naming the request's field. A camera moving during
    /// a rolling shutter's readout goes by the vertex or pinhole path here: the warp and cube
    /// paths need the scene to size their bands ([`Plan::from_request_with_scene`]).
    pub fn from_request(request: &RenderRequest, max_image_side: u32) -> Result<Plan> {
        Self::from_request_in(request, None, max_image_side)
    }

    /// [`Plan::from_request`] for `scene`: a camera that moves during a rolling shutter's
    /// readout is drawn by the warp and cube paths too, in the fewest bands of lines whose
    /// error, measured over the scene's depths as the planner measures a scene file's, meets
    /// the request's `max_error_px`; refused, naming `max_error_px`, where even the most
    /// bands miss it.
    pub fn from_request_with_scene(
        request: &RenderRequest,
        scene: &Scene,
        max_image_side: u32,
    ) -> Result<Plan> {
        Self::from_request_in(request, Some(scene), max_image_side)
    }

    /// The plan of `request`; `scene`, where given, sizes the bands of a moving rolling
    /// shutter on the warp and cube paths (without it they are refused).
    fn from_request_in(
        request: &RenderRequest,
        scene: Option<&Scene>,
        max_image_side: u32,
    ) -> Result<Plan> {
        check_request(request)?;
        if let Some(environment) = scene.and_then(|s| s.environment.as_ref()) {
            return environment_plan(request, environment);
        }
        let aa = request.antialias;
        let camera = &request.camera;
        let o = request.outputs;
        let chromatic = request.chromatic;
        let mut steps = Vec::new();
        let mut delta = DEFAULT_DELTA;
        let mut density = 1.0;
        let shutter = request_shutter(request, scene)?;
        let (route, expected) = match request.path {
            PathChoice::Vertex { .. } | PathChoice::Pinhole if chromatic.is_some() => {
                return Err(Error::argument(
                    "chromatic",
                    "chromatic aberration needs the warp path (one fused pass samples each channel through its own lens)",
                ));
            }
            PathChoice::Pinhole => {
                steps.push(Step {
                    stage: Stage::PinholeRender,
                    why: "the pinhole path was asked for: the camera's distortion is not applied"
                        .into(),
                });
                (Route::Pinhole, 0.0)
            }
            PathChoice::Vertex {
                delta: d,
                tessellate,
            } => {
                delta = d;
                vertex_route(d, tessellate, &mut steps)?
            }
            PathChoice::Warp { method, density: q } => {
                density = q;
                warp_route(request, method, q, max_image_side, &mut steps)?
            }
            PathChoice::Cube { side } => cube_route(request, side, &mut steps)?,
        };
        // A moving rolling shutter on the warp or cube path: in bands of lines.
        let banded = match (request.rolling_shutter, scene, &route) {
            (Some((readout, end)), Some(scene), Route::Warp { .. } | Route::Cube { .. })
                if end != request.pose =>
            {
                let motion = FrameMotion::new(request.pose.into(), end.into());
                let b = request_bands(
                    request,
                    scene,
                    &route,
                    expected,
                    (readout, motion),
                    &mut steps,
                )?;
                Some(b)
            }
            _ => None,
        };
        if aa.is_on() && o.color {
            steps.push(Step {
                stage: Stage::Antialias,
                why: format!(
                    "{}× supersampling and {} jittered pass(es) of the colour asked for, averaged; IDs, flow and depth stay one sample per pixel",
                    aa.supersample, aa.jitter
                ),
            });
        }
        let (expected, budget_px, bands) = match banded {
            Some(b) => (b.error_px(), b.budget_px, Some(b.count)),
            None => (expected, f64::INFINITY, None),
        };
        Ok(Plan {
            route,
            steps,
            optics: super::Optics::Camera(camera.clone()),
            expected_error_px: expected,
            budget_px,
            poses: vec![request.pose],
            end_poses: request
                .rolling_shutter
                .map(|(_, end)| vec![end])
                .unwrap_or_default(),
            previous_pose: Some(request.previous_pose),
            delta,
            density,
            outputs: o,
            background: request.background,
            antialias: aa,
            shutter,
            bands,
            estimated_ms: f64::NAN,
            path_asked: None,
        })
    }
}

/// Refuses a request's antialiasing and background where they are out of range.
fn check_request(request: &RenderRequest) -> Result<()> {
    let aa = request.antialias;
    if !(1..=MAX_SUPERSAMPLE).contains(&aa.supersample) {
        return Err(Error::argument(
            "supersample",
            format!(
                "{}: the supersampling factor must be in 1..={MAX_SUPERSAMPLE}",
                aa.supersample
            ),
        ));
    }
    if !(1..=MAX_JITTER).contains(&aa.jitter) {
        return Err(Error::argument(
            "jitter",
            format!(
                "{}: the jittered passes must be in 1..={MAX_JITTER}",
                aa.jitter
            ),
        ));
    }
    if !request.background.iter().all(|c| c.is_finite()) {
        return Err(Error::argument(
            "background",
            format!("{:?}: expected four finite numbers", request.background),
        ));
    }
    Ok(())
}

/// The request's shutter; a camera moving during the readout is refused on the warp and cube
/// paths without a scene to size their bands by.
fn request_shutter(request: &RenderRequest, scene: Option<&Scene>) -> Result<super::Shutter> {
    Ok(match request.rolling_shutter {
        None => super::Shutter::Global,
        Some((readout, end)) if end == request.pose => super::Shutter::Rolling {
            readout,
            from: super::ReadoutSource::Request,
        },
        Some((readout, _)) => {
            if scene.is_none()
                && !matches!(
                    request.path,
                    PathChoice::Vertex { .. } | PathChoice::Pinhole
                )
            {
                return Err(Error::argument(
                    "rolling_shutter",
                    format!("the camera moves during the {readout} readout: only the vertex path draws each line from its own pose (the warp and cube paths draw a frame from one pose, a global shutter's image); use the vertex path"),
                ));
            }
            super::Shutter::Moving {
                readout,
                from: super::ReadoutSource::Request,
                frame: 0,
            }
        }
    })
}

/// The vertex path as asked for: its discard δ and tessellation checked.
fn vertex_route(d: f64, tessellate: Option<f64>, steps: &mut Vec<Step>) -> Result<(Route, f64)> {
    let step = |stage, why: String| Step { stage, why };
    if !(d.is_finite() && d >= 0.0) {
        return Err(Error::argument(
            "delta",
            format!("{d}: the discard tolerance must be a number ≥ 0"),
        ));
    }
    if let Some(l) = tessellate {
        if !(l.is_finite() && l >= 0.25) {
            return Err(Error::argument(
                "tessellate",
                format!("{l}: expected an edge length in pixels ≥ 0.25"),
            ));
        }
        steps.push(step(
            Stage::Tessellation,
            format!("edges longer than {l} px split, at the pose of each frame"),
        ));
    }
    steps.push(step(
        Stage::VertexRender,
        format!("the vertex path was asked for; discard δ = {d} + D"),
    ));
    // Not measured without the scene: the straight edges between vertices are
    // what the tessellation bounds.
    Ok((Route::Vertex { tessellate }, f64::NAN))
}

/// The warp path as asked for, or a cube map where no pinhole source can hold the lens.
fn warp_route(
    request: &RenderRequest,
    method: InverseMethod,
    q: f64,
    max_image_side: u32,
    steps: &mut Vec<Step>,
) -> Result<(Route, f64)> {
    let (camera, o, aa, chromatic) = (
        &request.camera,
        request.outputs,
        request.antialias,
        request.chromatic,
    );
    let step = |stage, why: String| Step { stage, why };
    if o.flow {
        return Err(Error::argument(
            "path",
            "flow needs the vertex path: its vectors live in the pinhole image and a warp cannot carry them (Lambers et al. Table 1)",
        ));
    }
    if !(q.is_finite() && q > 0.0 && q <= 16.0) {
        return Err(Error::argument(
            "density",
            format!("{q}: source pixels per output pixel must be in (0, 16]"),
        ));
    }
    // At s× (supersampling), as the anti-aliased source is rendered.
    let s = if o.color { aa.supersample } else { 1 };
    let big = scaled_camera(camera, s)?;
    Ok(match pinhole_source_refusal(&big, q, max_image_side) {
        Some(why) => {
            let side = cube_face_side(camera, q);
            push_cube_steps(
                steps,
                format!(
                    "{why}{}: a cube map of six {side}×{side} faces instead",
                    if s > 1 {
                        format!(" at {s}× supersampling")
                    } else {
                        String::new()
                    }
                ),
                chromatic.is_some(),
                o.renders_data(),
            );
            (Route::Cube { side, chromatic }, CUBE_RAY_ERROR_PX)
        }
        None => {
            steps.push(step(
                Stage::OverscannedRender,
                format!(
                    "the warp's source, covering every valid output pixel at {q} source px per output px (Lambers et al. Sec. 3.3)"
                ),
            ));
            steps.push(step(
                Stage::Warp {
                    chromatic: chromatic.is_some(),
                },
                format!(
                    "the warp path was asked for: {method} per pixel, colour bilinear{}",
                    if o.renders_data() {
                        ", IDs, depth and range nearest"
                    } else {
                        ""
                    }
                ),
            ));
            let error = inverse_error_px(camera, method).unwrap_or(f64::NAN);
            (
                Route::Warp {
                    method,
                    chromatic,
                    map: false,
                },
                error,
            )
        }
    })
}

/// The cube path as asked for.
fn cube_route(request: &RenderRequest, side: u32, steps: &mut Vec<Step>) -> Result<(Route, f64)> {
    let (camera, o, chromatic) = (&request.camera, request.outputs, request.chromatic);
    if o.flow {
        return Err(Error::argument(
            "path",
            "flow through a cube map is not rendered (its vectors live in one pinhole image); the vertex path renders it",
        ));
    }
    if side < 2 {
        return Err(Error::argument(
            "density",
            format!(
                "cube faces of {side} px: the density must be positive (faces are 2·f·density px)"
            ),
        ));
    }
    push_cube_steps(
        steps,
        if beyond_a_pinhole(camera) {
            "the cube path was asked for; the lens sees 90° and more off its axis".into()
        } else {
            "the cube path was asked for".into()
        },
        chromatic.is_some(),
        o.renders_data(),
    );
    Ok((Route::Cube { side, chromatic }, CUBE_RAY_ERROR_PX))
}

/// The fewest bands of lines that draw `request`'s moving rolling shutter (`readout`,
/// `motion`) by `route` (the warp, whose own error is `route_error_px`, or the cube map)
/// within `request.max_error_px`: the planner's own search ([`search_bands`]) with the route
/// the request names as its one candidate. The first of `steps`, the source render, becomes
/// the per-band render, saying the count, the error and the budget; refused, naming
/// `max_error_px`, where even the most bands miss it.
fn request_bands(
    request: &RenderRequest,
    scene: &Scene,
    route: &Route,
    route_error_px: f64,
    (readout, motion): (Readout, FrameMotion),
    steps: &mut [Step],
) -> Result<super::search::BandsCandidate> {
    let budget = request.max_error_px;
    if !(budget.is_finite() && budget > 0.0) {
        return Err(Error::argument(
            "max_error_px",
            format!("{budget}: expected pixels > 0"),
        ));
    }
    // The frame times are not estimated for a named route (the plan's is NaN): the count
    // is chosen by the error alone, as the planner's is.
    let (warp, cube, what) = match *route {
        Route::Warp { method, map, .. } => {
            if !route_error_px.is_finite() {
                return Err(Error::argument(
                    "method",
                    format!("{method} leaves pixels of this camera unsolved that Newton solves, so the error of a moving rolling shutter's bands cannot be held to the budget; use newton"),
                ));
            }
            let w = WarpChoice {
                method,
                map,
                error_px: route_error_px,
                ms: f64::NAN,
            };
            (Some(w), None, "the warp")
        }
        Route::Cube { side, .. } => (
            None,
            Some(CubeCandidate { side, ms: f64::NAN }),
            "the cube map",
        ),
        _ => {
            return Err(Error::internal(
                "bands are drawn by the warp or the cube map",
            ))
        }
    };
    let candidates = Candidates::with_pinhole(None, warp, cube);
    let found = search_bands(
        scene,
        &request.camera,
        &candidates,
        &[(readout, motion)],
        budget,
    );
    let Some(b) = found.chosen else {
        let (count, error) = found
            .most
            .ok_or_else(|| Error::internal("no bands searched for the warp or the cube map"))?;
        return Err(Error::argument(
            "max_error_px",
            format!(
                "{budget} px: the camera moves during the {readout} readout, and {what} draws each band of lines from one pose: even {count} bands leave {error:.3} px, beyond the budget; raise max_error_px to {error:.3} or more, or take the vertex path, which draws each line from its own pose, exactly"
            ),
        ));
    };
    let (stage, sources) = match b.via {
        BandsVia::Warp(_) => (Stage::BandRenders, "the warp's pinhole source"),
        BandsVia::Cube(_) => (Stage::BandCubeFaces, "the cube map's six faces"),
    };
    if let Some(first) = steps.first_mut() {
        *first = Step {
            stage,
            why: format!(
                "the camera moves during the {readout} readout: {} bands of lines leave {:.3} px ≤ {budget} px budget ({:.3} px from the bands, measured against the exact per-line projection over the scene's depths, the fewest of 4, 8, 16, 32, 64 that meet it; the rest {what}'s); {sources} rendered once per band, from the pose of its middle line, and each band warped from its own render",
                b.count,
                b.error_px(),
                b.bands_error_px,
            ),
        };
    }
    Ok(b)
}

fn push_cube_steps(steps: &mut Vec<Step>, why: String, chromatic: bool, data: bool) {
    steps.push(Step {
        stage: Stage::CubeFaces,
        why,
    });
    steps.push(Step {
        stage: Stage::SphereWarp { chromatic },
        why: if data {
            "each output pixel samples the cube along its ray: colour bilinear across faces; IDs and the faces' depth at the nearest texel, the depth converted to z and range on the pixel's own ray"
        } else {
            "each output pixel samples the cube along its ray, bilinear across faces"
        }
        .into(),
    });
}

/// The plan of a request whose scene is a 360° image: the sphere warp sampling it, colour
/// alone, the camera at the image's centre looking along its axes. Refuses, naming the
/// request's field, what a 360° image cannot give.
fn environment_plan(request: &RenderRequest, environment: &Environment) -> Result<Plan> {
    let o = request.outputs;
    let asked = [
        (o.renders_ids(), "ids"),
        (o.flow, "flow"),
        (o.depth, "depth"),
        (o.renders_range(), "range"),
    ];
    for (asked, field) in asked {
        if asked {
            return Err(Error::argument(
                field,
                format!(
                    "{} holds colour alone: no {field} to warp",
                    environment.describe()
                ),
            ));
        }
    }
    if !o.color {
        return Err(Error::argument(
            "outputs",
            "a 360° source gives colour: ask for it",
        ));
    }
    if request.antialias.is_on() {
        return Err(Error::argument(
            "antialias",
            "a 360° source is sampled bilinearly along each pixel's ray: nothing to supersample",
        ));
    }
    if matches!(
        request.path,
        PathChoice::Vertex { .. } | PathChoice::Pinhole
    ) {
        return Err(Error::argument(
            "path",
            format!(
                "{} has no mesh to draw: it is sampled by the sphere warp (the warp or cube path)",
                environment.describe()
            ),
        ));
    }
    if request.pose.rotation != glam::DMat3::IDENTITY {
        return Err(Error::argument(
            "pose",
            "a 360° source is seen along its own axes from its centre: the pose must not turn the camera",
        ));
    }
    if request
        .rolling_shutter
        .is_some_and(|(_, end)| end.rotation != request.pose.rotation)
    {
        return Err(Error::argument(
            "rolling_shutter",
            "a 360° source is one instant: a camera turning during the readout cannot be drawn from it",
        ));
    }
    let chromatic = request.chromatic;
    Ok(Plan {
        route: Route::Environment { chromatic },
        steps: vec![Step {
            stage: Stage::SphereWarp {
                chromatic: chromatic.is_some(),
            },
            why: format!(
                "the scene is {}, at infinity: each output pixel samples it along the ray its lens sees (Newton inverse per pixel)",
                environment.describe()
            ),
        }],
        optics: super::Optics::Camera(request.camera.clone()),
        expected_error_px: 0.0,
        budget_px: f64::INFINITY,
        poses: vec![request.pose],
        end_poses: Vec::new(),
        previous_pose: None,
        delta: DEFAULT_DELTA,
        density: 1.0,
        outputs: o,
        background: request.background,
        antialias: request.antialias,
        shutter: super::Shutter::Global,
        bands: None,
        estimated_ms: f64::NAN,
        path_asked: None,
    })
}
