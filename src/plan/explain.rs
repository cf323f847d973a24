//! The plan as text: each step's reason, built from the route chosen and the candidates it
//! was weighed against, and what `vklens render --explain` prints and
//! `SceneRenderer::explain` returns.

use super::choice::{BandsLoss, BandsReason, Choice, CubeLoss, CubeReason, VertexReason};
use super::cost::CUBE_RAY_ERROR_PX;
use super::lens::Cells;
use super::scene_file::{Antialias, Effects};
use super::search::{BandsCandidate, BandsVia, Candidates, TessellationChoice, WarpChoice};
use super::{Plan, Route, Stage, Step};
use crate::model::Terms;

impl Plan {
    /// The plan as text (what `--explain` prints), with the frame's wall time and each pass's
    /// GPU time (timestamps) where measured.
    pub fn explain(&self, measured_ms: Option<f64>, passes: &[(&str, f64)]) -> String {
        let p = self;
        let bands = p
            .bands
            .map(|k| format!(", in {k} bands of lines (a moving rolling shutter)"))
            .unwrap_or_default();
        let mut out = format!(
            "plan: {}{bands}\n",
            match &p.route {
                Route::Pinhole => "pinhole render".to_string(),
                Route::Vertex { tessellate } => format!(
                    "vertex path (Alg. 1){}",
                    tessellate
                        .map(|l| format!(", tessellated to {l} px"))
                        .unwrap_or_default()
                ),
                Route::Warp {
                    method,
                    chromatic,
                    map,
                } => format!(
                    "pinhole render + warp ({}{})",
                    if *map {
                        "precomputed map".to_string()
                    } else {
                        method.to_string()
                    },
                    if chromatic.is_some() {
                        ", chromatic"
                    } else {
                        ""
                    }
                ),
                Route::WarpAndVertex { method, map, .. } => {
                    let how = if *map {
                        "precomputed map".to_string()
                    } else {
                        method.to_string()
                    };
                    format!("warp ({how}, chromatic) for colour + vertex path for the data")
                }
                Route::Cube { side, chromatic } => format!(
                    "cube map of six {side}×{side} pinhole faces + sphere warp{}",
                    if chromatic.is_some() {
                        " (chromatic)"
                    } else {
                        ""
                    }
                ),
                Route::LensModel { samples, .. } => {
                    format!("image-based lens model, {samples} lens sample(s)")
                }
                Route::Environment { chromatic } => format!(
                    "360° source + sphere warp{}",
                    if chromatic.is_some() {
                        " (chromatic)"
                    } else {
                        ""
                    }
                ),
            }
        );
        if let Some(path) = p.path_asked {
            out.push_str(&format!(
                "  path: {path}, as [render] path asks, in place of the cheapest route\n"
            ));
        }
        out.push_str(&format!("  shutter: {}\n", p.shutter.explain(p.bands)));
        for (i, s) in p.steps.iter().enumerate() {
            out.push_str(&format!("  {}. {}: {}\n", i + 1, s.stage.name(), s.why));
        }
        out.push_str(&format!(
            "  geometric error: {:.2e} px (budget {} px)\n",
            p.expected_error_px, p.budget_px
        ));
        if p.estimated_ms.is_finite() {
            out.push_str(&format!(
                "  estimated {:.1} ms per frame (lavapipe tables)",
                p.estimated_ms
            ));
            out.push_str(&match measured_ms {
                Some(m) => format!("; measured {m:.1} ms on frame 1\n"),
                None => "\n".into(),
            });
        } else if let Some(m) = measured_ms {
            out.push_str(&format!("  measured {m:.1} ms on frame 1\n"));
        }
        if !passes.is_empty() {
            out.push_str("  GPU time per pass (timestamps, frame 1):\n");
            for (name, ms) in passes {
                out.push_str(&format!("    {name}: {ms:.2} ms\n"));
            }
        }
        out
    }
}

/// The step that says colour is anti-aliased, when `[render]` asks for it (`aa`) and colour
/// is an output.
pub(super) fn antialias_step(aa: Antialias, color: bool) -> Option<Step> {
    (aa.is_on() && color).then(|| Step {
        stage: Stage::Antialias,
        why: format!(
            "[render] asks for {}× supersampling and {} jittered pass(es) of the colour, averaged; IDs, flow and depth stay one sample per pixel",
            aa.supersample, aa.jitter
        ),
    })
}

/// The pinhole route's one step: `distortion_asked` is false where `[effects]` switched the
/// camera's distortion off, true where the camera has none.
pub(super) fn pinhole_step(distortion_asked: bool) -> Step {
    Step {
        stage: Stage::PinholeRender,
        why: if distortion_asked {
            "the camera has no distortion: no lens work at all".into()
        } else {
            "no distortion asked: the pinhole projection, no warp, no geometry shader".into()
        },
    }
}

/// The distortion terms the shaders compile in for `terms` (the rest are specialized out).
fn terms_note(terms: Terms) -> String {
    format!(
        "compiled in: {}",
        [
            (terms.is_ray_model(), terms.model.name()),
            (terms.radial, "radial"),
            (terms.rational, "rational"),
            (terms.tangential, "tangential"),
            (terms.prism, "thin prism"),
            (terms.tilt, "tilt"),
        ]
        .iter()
        .filter(|t| t.0)
        .map(|t| t.1)
        .collect::<Vec<_>>()
        .join(", ")
    )
}

/// The two warps weighed: per pixel and from a precomputed map, each with its error and
/// time, or that it misses the budget.
fn options_note(c: &Candidates) -> String {
    let describe = |choice: &Option<WarpChoice>, what: &str| match choice {
        Some(choice) => format!(
            "{what} {:.1e} px, est. {:.1} ms per frame",
            choice.error_px, choice.ms
        ),
        None => format!("{what} does not meet the budget"),
    };
    format!(
        "options: {}; {}",
        describe(
            &c.per_pixel,
            &c.per_pixel
                .map_or("solved per pixel:".to_string(), |p| format!(
                    "{} per pixel:",
                    p.method
                ))
        ),
        describe(
            &c.from_map,
            &format!(
                "precomputed map (coarse 8 px, cubic; built once over {} frame(s)):",
                c.frames
            )
        )
    )
}

/// The tessellation Alg. 1 renders, and its measured error.
fn describe_tessellation(t: &TessellationChoice) -> String {
    let (err, tris) = (t.error_px, t.triangles);
    match t.edge_px {
        None => format!("the mesh as it is: its straight edges stay within {err:.1e} px of the true curves ({tris} triangles)"),
        Some(l) => format!("edges split to {l} px: straight-line error {err:.1e} px ≤ budget ({tris} triangles)"),
    }
}

/// The warp's coordinates, and why those.
fn describe_warp(w: &WarpChoice, c: &Candidates) -> String {
    let options = options_note(c);
    if w.map {
        format!("a precomputed map: its error on this camera, {:.1e} px, meets the budget, and it is the cheaper per frame ({options}); overscanned source so every valid pixel has one", w.error_px)
    } else {
        format!("inverse {}: the cheapest method whose error on this camera, {:.1e} px, meets the budget ({options}); overscanned source so every valid pixel has one", w.method, w.error_px)
    }
}

/// How many fetches the warp makes, and why.
fn chromatic_note(chromatic: bool) -> &'static str {
    if chromatic {
        "chromatic aberration asked: each channel through its own radial scale"
    } else {
        "no chromatic aberration: the single-fetch variant"
    }
}

/// The steps of the route `choice`, weighed against `candidates`, for a camera of `terms`.
pub(super) fn camera_steps(choice: &Choice, candidates: &Candidates, terms: Terms) -> Vec<Step> {
    let terms = terms_note(terms);
    match choice {
        Choice::Cube {
            cube,
            chromatic,
            why,
        } => cube_steps(
            cube.side,
            cube.ms,
            chromatic.is_some(),
            why,
            candidates,
            &terms,
        ),
        Choice::Warp { warp, chromatic } => {
            warp_steps(warp, chromatic.is_some(), candidates, &terms)
        }
        Choice::WarpAndVertex {
            warp,
            vertex,
            chromatic,
        } => {
            let mut steps = warp_steps(warp, chromatic.is_some(), candidates, &terms);
            steps.push(Step {
                stage: Stage::VertexRenderData,
                why: format!(
                    "IDs and flow cannot be warped (Lambers et al. Table 1); {}; {terms}",
                    describe_tessellation(&vertex.tessellation)
                ),
            });
            steps
        }
        Choice::Bands {
            bands,
            vertex,
            chromatic,
            why,
        } => {
            let mut steps = match &bands.via {
                BandsVia::Warp(w) => warp_steps(w, chromatic.is_some(), candidates, &terms),
                BandsVia::Cube(c) => {
                    let why = CubeReason::NoPinholeWarp(
                        candidates.no_pinhole_warp.clone().unwrap_or_default(),
                    );
                    cube_steps(c.side, c.ms, chromatic.is_some(), &why, candidates, &terms)
                }
            };
            steps[0] = bands_step(bands, why);
            if let Some(vertex) = vertex {
                steps.push(Step {
                    stage: Stage::VertexRenderData,
                    why: format!(
                        "IDs and flow cannot be warped (Lambers et al. Table 1): drawn exactly, each vertex where its own line reads it; {}; {terms}",
                        describe_tessellation(&vertex.tessellation)
                    ),
                });
            }
            steps
        }
        Choice::Vertex { vertex, why } => {
            let why = vertex_reason(why, vertex.ms);
            let t = &vertex.tessellation;
            let mut steps = Vec::new();
            if t.edge_px.is_some() {
                steps.push(Step {
                    stage: Stage::Tessellation,
                    why: describe_tessellation(t),
                });
            }
            steps.push(Step {
                stage: Stage::VertexRender,
                why: format!(
                    "{why}; {}; {terms}",
                    if t.edge_px.is_none() {
                        describe_tessellation(t)
                    } else {
                        "discard δ = 0.1 + D".into()
                    }
                ),
            });
            steps
        }
    }
}

/// The cube route's two steps: the faces, and the sphere warp against Alg. 1.
fn cube_steps(
    side: u32,
    ms: f64,
    chromatic: bool,
    why: &CubeReason,
    candidates: &Candidates,
    terms: &str,
) -> Vec<Step> {
    let why = match why {
        CubeReason::NoPinholeWarp(why) => format!("no pinhole warp: {why}"),
        CubeReason::Cheaper { warp_ms } => format!(
            "cheaper than the pinhole warp ({})",
            warp_ms
                .map(|m| format!("{m:.1} ms"))
                .unwrap_or_else(|| "none".into())
        ),
        CubeReason::Asked { warp_ms, vertex_ms } => format!(
            "[render] path asks for it (pinhole + warp: {}; Alg. 1: {})",
            estimate(*warp_ms),
            estimate(*vertex_ms)
        ),
    };
    let alg1 = match candidates.vertex {
        _ if chromatic => "cannot give each channel its own lens".into(),
        Some(v) => format!("est. {:.1} ms", v.ms),
        None => "no tessellation meets the budget".into(),
    };
    vec![
        Step {
            stage: Stage::CubeFaces,
            why: format!("{why}: six 90° pinhole faces of {side}×{side} px (one face pixel per output pixel at the centre), rendered into a cube map on the GPU"),
        },
        Step {
            stage: Stage::SphereWarp { chromatic },
            why: format!(
                "each output pixel samples the cube along its ray, bilinear across faces: {CUBE_RAY_ERROR_PX:.1e} px; est. {ms:.1} ms per frame (Alg. 1: {alg1}); {}; {terms}",
                chromatic_note(chromatic),
            ),
        },
    ]
}

/// The warp route's steps: the overscanned source and the warp.
fn warp_steps(
    warp: &WarpChoice,
    chromatic: bool,
    candidates: &Candidates,
    terms: &str,
) -> Vec<Step> {
    vec![
        Step {
            stage: Stage::OverscannedRender,
            why: "the warp's source, covering every valid output pixel (Lambers et al. Sec. 3.3)"
                .into(),
        },
        Step {
            stage: Stage::Warp { chromatic },
            why: format!(
                "{}; {}; {terms}",
                describe_warp(warp, candidates),
                chromatic_note(chromatic)
            ),
        },
    ]
}

/// The bands' source renders, and why the bands: how many, the error they leave against the
/// budget, and what they were weighed against.
fn bands_step(bands: &BandsCandidate, why: &BandsReason) -> Step {
    let k = bands.count;
    let why = match why {
        BandsReason::Chromatic => {
            "chromatic aberration needs the warp (Alg. 1 cannot give each channel its own lens)"
                .to_string()
        }
        BandsReason::Cheaper { vertex_ms: Some(v) } => format!(
            "est. {:.1} ms against {v:.1} ms for the exact vertex path",
            bands.ms
        ),
        BandsReason::Cheaper { vertex_ms: None } => {
            "no tessellation meets the budget on the exact vertex path".into()
        }
        BandsReason::Asked { vertex_ms } => format!(
            "[render] path asks for it (the exact vertex path: {})",
            estimate(*vertex_ms)
        ),
    };
    let (stage, sources) = match bands.via {
        BandsVia::Warp(_) => (Stage::BandRenders, "the pinhole source is"),
        BandsVia::Cube(_) => (
            Stage::BandCubeFaces,
            "no pinhole source holds the lens, so the cube map's six faces are",
        ),
    };
    Step {
        stage,
        why: format!(
            "the camera moves during the readout and the warp draws a frame from one pose: {why}; {k} bands leave {:.2} px ≤ {:.2} px budget ({:.2} px from the bands, measured against the exact per-line projection over the scene's depths, the fewest of 4, 8, 16, 32, 64 that meet it; the rest the warp's); {sources} rendered once per band, from the pose of the band's middle line, and each band of the output warped from its own render (est. {:.1} ms per frame)",
            bands.error_px(),
            bands.budget_px,
            bands.bands_error_px,
            bands.ms
        ),
    }
}

/// A route's estimated frame time, or that it cannot meet the budget or carry the outputs.
fn estimate(ms: Option<f64>) -> String {
    ms.map(|m| format!("est. {m:.1} ms"))
        .unwrap_or_else(|| "none meeting the budget and the outputs".into())
}

/// Why Alg. 1 (estimated `vertex_ms`) carries every output.
fn vertex_reason(why: &VertexReason, vertex_ms: f64) -> String {
    match why {
        VertexReason::DataOutputs { ids, flow } => format!(
            "{} need the geometry path: a warp cannot carry them (Lambers et al. Table 1)",
            match (ids, flow) {
                (true, true) => "IDs and flow",
                (true, false) => "object IDs",
                _ => "flow vectors",
            }
        ),
        VertexReason::NoPinholeWarp { why, cube } => format!(
            "no pinhole warp: {why}; {}",
            match cube {
                CubeLoss::Dearer { ms } =>
                    format!("estimated {vertex_ms:.1} ms against {ms:.1} ms for a cube map"),
                CubeLoss::RaysMissBudget =>
                    format!("a cube map's rays ({CUBE_RAY_ERROR_PX:.1e} px) miss the budget"),
                CubeLoss::ColourAlone => "a cube map is planned for colour alone (path = \"cube\" carries IDs, depth and range)".into(),
            }
        ),
        VertexReason::MovingRollingShutter { bands } => format!(
            "the camera moves during a rolling shutter's readout: each vertex is drawn where its own line reads it (its readout time solved per vertex, estimated {vertex_ms:.1} ms); the warp and the cube map draw a frame from one pose, {}",
            match bands {
                BandsLoss::DataOutputs =>
                    "and IDs and flow cannot be warped (Lambers et al. Table 1)".to_string(),
                BandsLoss::NoWarp =>
                    "and no warp meets the budget on this camera to draw it in bands of lines".into(),
                BandsLoss::MissBudget { count, error_px } => format!(
                    "and even {count} bands of lines, each from its middle line's pose, leave {error_px:.2} px, beyond the budget"
                ),
                BandsLoss::Dearer { count, error_px, ms } => format!(
                    "and {count} bands of lines, each from its middle line's pose, would leave {error_px:.2} px but cost est. {ms:.1} ms"
                ),
            }
        ),
        VertexReason::Asked { warp_ms, cube_ms } => format!(
            "[render] path asks for it (estimated {vertex_ms:.1} ms; pinhole + warp: {}; cube map: {})",
            estimate(*warp_ms),
            estimate(*cube_ms)
        ),
        VertexReason::Cheaper { warp_ms } => format!(
            "estimated {vertex_ms:.1} ms against {} for pinhole + warp",
            warp_ms
                .map(|w| format!("{w:.1} ms"))
                .unwrap_or_else(|| "no warp meeting the budget".into())
        ),
    }
}

/// The image-based lens model's steps: `samples` lens samples, cells split until
/// `max_angle_deg` (`budget_px` turned into degrees), and the `cells` that came of it.
pub(super) fn lens_steps(
    e: &Effects,
    samples: u32,
    max_angle_deg: f64,
    budget_px: f64,
    cells: &Cells,
) -> Vec<Step> {
    vec![
        Step {
            stage: Stage::LensModel,
            why: format!(
                "optics is a lens prescription; {} lens sample{} ({}), quad-tree until {:.2e}° = {} px",
                samples,
                if samples == 1 { "" } else { "s" },
                if e.depth_of_field {
                    "depth of field asked for"
                } else {
                    "no depth of field asked: the rear surface's centre only"
                },
                max_angle_deg,
                budget_px
            ),
        },
        Step {
            stage: Stage::FilmAccumulation,
            why: if e.chromatic_aberration {
                "chromatic aberration asked: R, G, B traced at the C, e and F lines, each channel its own projections".into()
            } else {
                "one wavelength (d line) for all channels: no chromatic aberration asked".into()
            },
        },
        Step {
            stage: Stage::Vignetting { kept: e.vignetting },
            why: if e.vignetting {
                "vignetting asked: border bisection per sample, radiometric weights kept".into()
            } else {
                "no vignetting asked: no border fitting; the accumulated weight is divided out"
                    .into()
            },
        },
        Step {
            stage: Stage::CellRenders,
            why: format!(
                "{} perspective projections per frame, largest angle error {:.2e}°",
                cells.projections, cells.max_angle_deg
            ),
        },
    ]
}
