//! The route's choice for a calibrated camera: from the candidates and what the scene file asks
//! for, the cheapest route that delivers it, with the reason as data, or the refusal.

use super::cost::CUBE_RAY_ERROR_PX;
use super::search::{
    BandsCandidate, BandsSearch, BandsVia, Candidates, CubeCandidate, VertexCandidate, WarpChoice,
};
use super::{chromatic_scales, PathKind, Route, SceneFile};
use crate::{Error, Result};

/// The route chosen for a lens (a camera without distortion or chromatic aberration takes
/// the pinhole render before any search), with what it needs and why it won.
#[derive(Debug, Clone)]
pub(super) enum Choice {
    /// Alg. 1 for every output.
    Vertex {
        vertex: VertexCandidate,
        why: VertexReason,
    },
    /// The pinhole render and the warp, every output.
    Warp {
        warp: WarpChoice,
        chromatic: Option<[f64; 3]>,
    },
    /// The warp for colour (chromatic aberration), Alg. 1 for IDs and flow.
    WarpAndVertex {
        warp: WarpChoice,
        vertex: VertexCandidate,
        chromatic: Option<[f64; 3]>,
    },
    /// The cube map's faces and the sphere warp, colour alone.
    Cube {
        cube: CubeCandidate,
        chromatic: Option<[f64; 3]>,
        why: CubeReason,
    },
    /// A camera moving during a rolling shutter's readout, drawn by the warp in bands of
    /// lines (each from its middle line's pose); Alg. 1 beside it for IDs and flow.
    Bands {
        bands: BandsCandidate,
        vertex: Option<VertexCandidate>,
        chromatic: Option<[f64; 3]>,
        why: BandsReason,
    },
}

/// Why the bands carry a moving rolling shutter's colour.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum BandsReason {
    /// Chromatic aberration needs the warp (Alg. 1 cannot give each channel its own lens).
    Chromatic,
    /// Cheaper than the exact vertex path (`vertex_ms`), or that path cannot meet the budget
    /// (`None`).
    Cheaper { vertex_ms: Option<f64> },
    /// `[render] path` asks for the warp or the cube map (the exact vertex path: `vertex_ms`).
    Asked { vertex_ms: Option<f64> },
}

/// Why the bands did not carry a moving rolling shutter, where the vertex path does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum BandsLoss {
    /// IDs or flow are asked for, which no warp carries.
    DataOutputs,
    /// No warp meets the budget on this camera, or no pinhole source holds the lens.
    NoWarp,
    /// Even `count` bands leave `error_px` (the warp's included), beyond the budget.
    MissBudget { count: u32, error_px: f64 },
    /// `count` bands meet the budget with `error_px`, but cost `ms`, no less than Alg. 1.
    Dearer { count: u32, error_px: f64, ms: f64 },
}

/// Why Alg. 1 carries every output.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum VertexReason {
    /// Object IDs or flow are asked for, and no warp carries them (Lambers et al. Table 1).
    DataOutputs { ids: bool, flow: bool },
    /// No pinhole source holds the lens (`why`), and the cube map lost.
    NoPinholeWarp { why: String, cube: CubeLoss },
    /// No dearer than the warp (`warp_ms`), or no warp meets the budget (`None`).
    Cheaper { warp_ms: Option<f64> },
    /// The camera moves during a frame read out by a rolling shutter: the vertex path draws
    /// each line from its own pose, exactly, and the bands lost (`bands`).
    MovingRollingShutter { bands: BandsLoss },
    /// `[render] path` asks for it (the pinhole warp and the cube map: their estimates, `None`
    /// where they cannot meet the budget or carry the outputs).
    Asked {
        warp_ms: Option<f64>,
        cube_ms: Option<f64>,
    },
}

/// Why the cube map did not carry a lens no pinhole source holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum CubeLoss {
    /// It would cost `ms` per frame, no less than Alg. 1.
    Dearer { ms: f64 },
    /// Its rays' error is beyond the budget.
    RaysMissBudget,
    /// Something besides colour is asked for.
    ColourAlone,
}

/// Why the cube map carries the colour.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum CubeReason {
    /// No pinhole source holds the lens (`why`).
    NoPinholeWarp(String),
    /// Cheaper than the pinhole warp (`warp_ms`; `None`: no warp meets the budget).
    Cheaper { warp_ms: Option<f64> },
    /// `[render] path` asks for it (the pinhole warp and Alg. 1: their estimates).
    Asked {
        warp_ms: Option<f64>,
        vertex_ms: Option<f64>,
    },
}

impl Choice {
    /// The route the plan records.
    pub(super) fn route(&self) -> Route {
        match self {
            Choice::Vertex { vertex, .. } => Route::Vertex {
                tessellate: vertex.tessellation.edge_px,
            },
            Choice::Warp { warp, chromatic } => Route::Warp {
                method: warp.method,
                chromatic: *chromatic,
                map: warp.map,
            },
            Choice::WarpAndVertex {
                warp,
                vertex,
                chromatic,
            } => Route::WarpAndVertex {
                method: warp.method,
                chromatic: *chromatic,
                tessellate: vertex.tessellation.edge_px,
                map: warp.map,
            },
            Choice::Cube {
                cube, chromatic, ..
            } => Route::Cube {
                side: cube.side,
                chromatic: *chromatic,
            },
            Choice::Bands {
                bands,
                vertex,
                chromatic,
                ..
            } => match (bands.via, vertex) {
                (BandsVia::Warp(w), Some(vertex)) => Route::WarpAndVertex {
                    method: w.method,
                    chromatic: *chromatic,
                    tessellate: vertex.tessellation.edge_px,
                    map: w.map,
                },
                (BandsVia::Warp(w), None) => Route::Warp {
                    method: w.method,
                    chromatic: *chromatic,
                    map: w.map,
                },
                // The cube map carries colour alone: the choice puts no vertex path beside it.
                (BandsVia::Cube(c), _) => Route::Cube {
                    side: c.side,
                    chromatic: *chromatic,
                },
            },
        }
    }

    /// How many bands of lines the warp draws a moving rolling shutter in (`None`: one pose
    /// per frame, or the vertex path).
    pub(super) fn bands(&self) -> Option<u32> {
        match self {
            Choice::Bands { bands, .. } => Some(bands.count),
            _ => None,
        }
    }

    /// The largest geometric error the route leaves (px), as measured while planning.
    pub(super) fn expected_error_px(&self) -> f64 {
        match self {
            Choice::Vertex { vertex, .. } => vertex.tessellation.error_px,
            Choice::Warp { warp, .. } => warp.error_px,
            Choice::WarpAndVertex { warp, vertex, .. } => {
                warp.error_px.max(vertex.tessellation.error_px)
            }
            Choice::Cube { .. } => CUBE_RAY_ERROR_PX,
            Choice::Bands { bands, vertex, .. } => vertex
                .map_or(0.0, |v| v.tessellation.error_px)
                .max(bands.error_px()),
        }
    }

    /// The route's estimated frame time (ms).
    pub(super) fn estimated_ms(&self) -> f64 {
        match self {
            Choice::Vertex { vertex, .. } => vertex.ms,
            Choice::Warp { warp, .. } => warp.ms,
            Choice::WarpAndVertex { warp, vertex, .. } => warp.ms + vertex.ms,
            Choice::Cube { cube, .. } => cube.ms,
            Choice::Bands { bands, vertex, .. } => bands.ms + vertex.map_or(0.0, |v| v.ms),
        }
    }
}

/// Whether `a` is cheaper than `b` (a missing `b` loses to any `a`).
fn cheaper(a: Option<f64>, b: Option<f64>) -> bool {
    match (a, b) {
        (Some(a), Some(b)) => a < b,
        (a, _) => a.is_some(),
    }
}

/// The cheapest of `candidates` that delivers what `file` asks for, or why none does; where
/// the file asks for a path (`[render] path`), `candidates` are its [`asked_candidates`].
pub(super) fn choose(file: &SceneFile, candidates: &Candidates) -> Result<Choice> {
    let src = file.source.display();
    let chromatic = chromatic_scales(file);
    let c = candidates;
    if let (Some(why), Some(_), None) = (&c.no_pinhole_warp, chromatic, c.cube) {
        return Err(Error::input(format!(
            "{src}: [effects] chromatic_aberration: {why}, and a chromatic warp needs a pinhole source, or a cube map, which carries colour alone (no IDs, flow or depth): not planned (drop chromatic_aberration or the data outputs, or use a camera whose frame a pinhole holds)"
        )));
    }
    if let Some(path) = file.path {
        return choose_asked(file, c, path);
    }
    let warp_ms = c.warp.map(|w| w.ms);
    let vertex_ms = c.vertex.map(|v| v.ms);
    // Alg. 1 cannot give each channel its own lens: with chromatic aberration only the
    // warps compete.
    let cube_ms = c.cube.map(|cube| cube.ms);
    let pick_cube =
        cheaper(cube_ms, warp_ms) && (chromatic.is_some() || cheaper(cube_ms, vertex_ms));
    if let Some(cube) = c.cube.filter(|_| pick_cube) {
        let why = match &c.no_pinhole_warp {
            Some(why) => CubeReason::NoPinholeWarp(why.clone()),
            None => CubeReason::Cheaper { warp_ms },
        };
        return Ok(Choice::Cube {
            cube,
            chromatic,
            why,
        });
    }
    let data_needs_vertex = file.outputs.renders_ids() || file.outputs.flow;
    if chromatic.is_some()
        || (!data_needs_vertex && c.warp.is_some() && (c.vertex.is_none() || warp_ms < vertex_ms))
    {
        choose_warp(file, c, chromatic)
    } else {
        choose_vertex(file, c)
    }
}

/// What the path `[render] path` asks for cannot deliver, whatever the budget: chromatic
/// aberration on the vertex path, IDs, flow or depth from a cube map.
pub(super) fn refuse_asked(file: &SceneFile, path: PathKind) -> Result<()> {
    let asked = format!("{}: [render] path = \"{path}\"", file.source.display());
    let o = &file.outputs;
    match path {
        PathKind::Vertex if file.effects.chromatic_aberration => Err(Error::input(format!(
            "{asked}: [effects] chromatic_aberration needs the warp (Alg. 1 cannot give each channel its own lens); ask for path = \"warp\" or drop the key"
        ))),
        PathKind::Cube if o.flow => Err(Error::input(format!(
            "{asked}: a cube map carries no flow (its vectors live in one pinhole image), and [outputs] asks for it; ask for path = \"vertex\", or drop the key"
        ))),
        _ => Ok(()),
    }
}

/// The candidates the path `[render] path` asks for may take: the others dropped, except a
/// cube map standing in for the warp where no pinhole source holds the lens (colour alone,
/// as on the command line), and Alg. 1 beside the warp for IDs and flow.
pub(super) fn asked_candidates(
    file: &SceneFile,
    candidates: &Candidates,
    path: PathKind,
) -> Candidates {
    let mut c = candidates.clone();
    let data = file.outputs.renders_ids() || file.outputs.flow;
    match path {
        PathKind::Vertex => {
            (c.warp, c.per_pixel, c.from_map, c.cube) = (None, None, None, None);
        }
        PathKind::Warp => {
            if !data {
                c.vertex = None;
            }
            if c.no_pinhole_warp.is_none() {
                c.cube = None;
            }
        }
        PathKind::Cube => {
            (c.warp, c.per_pixel, c.from_map, c.vertex) = (None, None, None, None);
        }
    }
    c
}

/// `choice`, made among [`asked_candidates`] of `candidates`, with its reason saying the path
/// was asked for (and what the others would have cost) where the reason it was given weighed
/// candidates the path had dropped.
pub(super) fn asked_reason(choice: Choice, candidates: &Candidates) -> Choice {
    let (warp_ms, vertex_ms) = (
        candidates.warp.map(|w| w.ms),
        candidates.vertex.map(|v| v.ms),
    );
    let cube_ms = candidates.cube.map(|c| c.ms);
    match choice {
        Choice::Vertex { vertex, why } if !matches!(why, VertexReason::DataOutputs { .. }) => {
            Choice::Vertex {
                vertex,
                why: VertexReason::Asked { warp_ms, cube_ms },
            }
        }
        Choice::Cube {
            cube,
            chromatic,
            why: CubeReason::Cheaper { .. },
        } => Choice::Cube {
            cube,
            chromatic,
            why: CubeReason::Asked { warp_ms, vertex_ms },
        },
        Choice::Bands {
            bands,
            vertex,
            chromatic,
            why: BandsReason::Cheaper { .. },
        } => Choice::Bands {
            bands,
            vertex,
            chromatic,
            why: BandsReason::Asked { vertex_ms },
        },
        other => other,
    }
}

/// The route of the path `[render] path` asks for among `c`, its [`asked_candidates`] (the
/// caller checked [`refuse_asked`] and gives the reason with [`asked_reason`]), or why that
/// path cannot deliver what the file asks for within its budget.
fn choose_asked(file: &SceneFile, c: &Candidates, path: PathKind) -> Result<Choice> {
    let src = file.source.display();
    let budget = file.max_error_px;
    let chromatic = chromatic_scales(file);
    Ok(match path {
        PathKind::Vertex => {
            if c.vertex.is_none() {
                return Err(Error::input(format!(
                    "{src}: [render] path = \"vertex\", [accuracy] max_error_px = {budget}: even 1 px edges do not meet it"
                )));
            }
            choose_vertex(file, c)?
        }
        PathKind::Warp => match (&c.warp, &c.no_pinhole_warp, c.cube) {
            (None, Some(why), Some(cube)) if !file.outputs.renders_data() => {
                Choice::Cube {
                    cube,
                    chromatic,
                    why: CubeReason::NoPinholeWarp(why.clone()),
                }
            }
            (None, Some(why), _) => {
                return Err(Error::input(format!(
                    "{src}: [render] path = \"warp\": {why}, and a cube map, which stands in for it, carries colour alone and must meet the budget; ask for path = \"vertex\""
                )))
            }
            _ => choose_warp(file, c, chromatic)?,
        },
        PathKind::Cube => match c.cube {
            Some(cube) => Choice::Cube {
                cube,
                chromatic,
                why: CubeReason::Cheaper { warp_ms: None },
            },
            None => {
                return Err(Error::input(format!(
                    "{src}: [render] path = \"cube\", [accuracy] max_error_px = {budget}: the cube map's rays ({CUBE_RAY_ERROR_PX:.1e} px) miss it"
                )))
            }
        },
    })
}

/// The warp route, with Alg. 1 beside it for IDs and flow.
fn choose_warp(
    file: &SceneFile,
    candidates: &Candidates,
    chromatic: Option<[f64; 3]>,
) -> Result<Choice> {
    let src = file.source.display();
    let budget = file.max_error_px;
    let Some(warp) = candidates.warp else {
        return Err(Error::input(format!(
            "{src}: [accuracy] max_error_px = {budget}: no inverse method meets it on this camera"
        )));
    };
    if !(file.outputs.renders_ids() || file.outputs.flow) {
        return Ok(Choice::Warp { warp, chromatic });
    }
    let Some(vertex) = candidates.vertex else {
        return Err(Error::input(format!(
            "{src}: [accuracy] max_error_px = {budget}: tessellation cannot meet it for the ID/flow outputs"
        )));
    };
    Ok(Choice::WarpAndVertex {
        warp,
        vertex,
        chromatic,
    })
}

/// The route of a camera that moves during a rolling shutter's readout (`readout`, first in
/// frame `frame`, counted from 0): Alg. 1 solving each vertex's readout time (exact), or the
/// warp in the fewest bands of lines that meet the budget (`bands`), whichever is cheaper;
/// chromatic aberration needs the warp, IDs and flow Alg. 1. Refuses, naming `[sensor]
/// rolling_shutter` and `[accuracy] max_error_px`, what no route delivers within the budget.
pub(super) fn choose_moving_rolling_shutter(
    file: &SceneFile,
    candidates: &Candidates,
    bands: &BandsSearch,
    (readout, frame): (crate::model::rolling_shutter::Readout, usize),
) -> Result<Choice> {
    let src = file.source.display();
    let budget = file.max_error_px;
    let chromatic = chromatic_scales(file);
    let data = file.outputs.renders_ids() || file.outputs.flow;
    let moving = format!(
        "{src}: [sensor] rolling_shutter, [accuracy] max_error_px = {budget}: [[poses]] #{} moves during its {readout} readout",
        frame + 1
    );
    // What the bands leave at most, where none meets the budget.
    let missed = |why: &str| {
        match (bands.most, &candidates.no_pinhole_warp) {
        (None, Some(no_source)) => Error::input(format!(
            "{moving}; {why}, and the warp draws it only in bands of lines, each from a pinhole source, which cannot hold this lens ({no_source}), or from a cube map's faces, which carry colour alone: not planned (drop what needs the warp, or end_rvec and end_tvec)"
        )),
        (Some((count, error)), _) => Error::input(format!(
            "{moving}; {why}, and drawn in bands of lines (each from the pose of its middle line) the warp leaves {error:.3} px even with {count} bands, beyond the budget: raise max_error_px to {error:.3} or more, or slow the motion (end_rvec, end_tvec nearer rvec, tvec)"
        )),
        (None, None) => Error::input(format!(
            "{moving}; {why}, and no inverse method meets the budget for the warp that would draw it in bands of lines"
        )),
    }
    };
    let vertex_for_data = || {
        candidates.vertex.ok_or_else(|| {
            Error::input(format!(
                "{moving}; the IDs/flow outputs need the vertex path, and even 1 px edges do not meet the budget"
            ))
        })
    };
    if chromatic.is_some() {
        let Some(b) = bands.chosen else {
            return Err(missed(
                "[effects] chromatic_aberration needs the warp (Alg. 1 cannot give each channel its own lens)",
            ));
        };
        let vertex = match b.via {
            BandsVia::Warp(_) if data => Some(vertex_for_data()?),
            _ => None,
        };
        return Ok(Choice::Bands {
            bands: b,
            vertex,
            chromatic,
            why: BandsReason::Chromatic,
        });
    }
    if data {
        return Ok(Choice::Vertex {
            vertex: vertex_for_data()?,
            why: VertexReason::MovingRollingShutter {
                bands: BandsLoss::DataOutputs,
            },
        });
    }
    match (candidates.vertex, bands.chosen) {
        (Some(v), Some(b)) if b.ms < v.ms => Ok(Choice::Bands {
            bands: b,
            vertex: None,
            chromatic,
            why: BandsReason::Cheaper {
                vertex_ms: Some(v.ms),
            },
        }),
        (None, Some(b)) => Ok(Choice::Bands {
            bands: b,
            vertex: None,
            chromatic,
            why: BandsReason::Cheaper { vertex_ms: None },
        }),
        (Some(vertex), b) => {
            let loss = match (b, bands.most) {
                (Some(b), _) => BandsLoss::Dearer {
                    count: b.count,
                    error_px: b.error_px(),
                    ms: b.ms,
                },
                (None, Some((count, error_px))) => BandsLoss::MissBudget { count, error_px },
                (None, None) => BandsLoss::NoWarp,
            };
            Ok(Choice::Vertex {
                vertex,
                why: VertexReason::MovingRollingShutter { bands: loss },
            })
        }
        (None, None) => Err(missed(
            "even 1 px edges do not meet the budget on the vertex path, which draws it exactly",
        )),
    }
}

/// Alg. 1 for every output, and why.
fn choose_vertex(file: &SceneFile, candidates: &Candidates) -> Result<Choice> {
    let o = &file.outputs;
    let budget = file.max_error_px;
    let Some(vertex) = candidates.vertex else {
        return Err(Error::input(format!(
            "{}: [accuracy] max_error_px = {budget}: even 1 px edges do not meet it, and the outputs (IDs/flow) need the vertex path",
            file.source.display()
        )));
    };
    let why = if o.renders_ids() || o.flow {
        VertexReason::DataOutputs {
            ids: o.renders_ids(),
            flow: o.flow,
        }
    } else if let Some(why) = &candidates.no_pinhole_warp {
        let cube = match candidates.cube {
            Some(cube) => CubeLoss::Dearer { ms: cube.ms },
            None if CUBE_RAY_ERROR_PX > budget => CubeLoss::RaysMissBudget,
            None => CubeLoss::ColourAlone,
        };
        VertexReason::NoPinholeWarp {
            why: why.clone(),
            cube,
        }
    } else {
        VertexReason::Cheaper {
            warp_ms: candidates.warp.map(|w| w.ms),
        }
    };
    Ok(Choice::Vertex { vertex, why })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::InverseMethod;
    use crate::plan::search::TessellationChoice;
    use crate::ErrorKind;

    /// A scene file for `camera.json` with `extra` tables, as the choice reads it.
    fn file(extra: &str) -> SceneFile {
        let text =
            format!("[geometry]\nscene = \"grid:8\"\n[optics]\ncamera = \"camera.json\"\n{extra}");
        SceneFile::parse(&text, std::path::Path::new("/scenes/s.toml")).unwrap()
    }

    const CHROMATIC: &str =
        "[effects]\nchromatic_aberration = true\nchromatic_scales = [1.004, 1.0, 0.996]\n";

    fn vertex(ms: f64, error_px: f64) -> VertexCandidate {
        VertexCandidate {
            tessellation: TessellationChoice {
                edge_px: Some(16.0),
                error_px,
                triangles: 6144,
                vertices: 3200,
            },
            ms,
        }
    }

    fn warp(ms: f64, error_px: f64) -> WarpChoice {
        WarpChoice {
            method: InverseMethod::FixedPoint(5),
            map: false,
            error_px,
            ms,
        }
    }

    /// A lens no pinhole source holds: no warp, `vertex` and `cube` only.
    fn wide(vertex: Option<VertexCandidate>, cube: Option<CubeCandidate>) -> Candidates {
        Candidates {
            no_pinhole_warp: Some("the lens sees past 90°".into()),
            ..Candidates::with_pinhole(vertex, None, cube)
        }
    }

    fn refusal(file: &SceneFile, c: &Candidates) -> String {
        let e = choose(file, c).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Input);
        assert!(e.argument_name().is_none());
        let message = e.to_string();
        assert!(message.starts_with("/scenes/s.toml: ["), "{message}");
        message
    }

    #[test]
    fn the_cheaper_of_alg1_and_the_warp_carries_colour() {
        let f = file("");
        let c = Candidates::with_pinhole(Some(vertex(7.5, 9e-3)), Some(warp(16.7, 6e-3)), None);
        let choice = choose(&f, &c).unwrap();
        assert_eq!(
            choice.route(),
            Route::Vertex {
                tessellate: Some(16.0)
            }
        );
        assert!(matches!(
            choice,
            Choice::Vertex {
                why: VertexReason::Cheaper { warp_ms: Some(w) },
                ..
            } if w == 16.7
        ));
        assert_eq!(
            (choice.expected_error_px(), choice.estimated_ms()),
            (9e-3, 7.5)
        );

        let c = Candidates::with_pinhole(Some(vertex(20.0, 9e-3)), Some(warp(16.7, 6e-3)), None);
        let choice = choose(&f, &c).unwrap();
        assert!(matches!(
            choice,
            Choice::Warp {
                chromatic: None,
                ..
            }
        ));
        assert_eq!(
            (choice.expected_error_px(), choice.estimated_ms()),
            (6e-3, 16.7)
        );
    }

    #[test]
    fn ids_and_flow_take_alg1_however_cheap_the_warp() {
        let f = file("[outputs]\nids = true\nflow = true\n");
        let c = Candidates::with_pinhole(Some(vertex(50.0, 9e-3)), Some(warp(1.0, 6e-3)), None);
        let choice = choose(&f, &c).unwrap();
        assert!(matches!(
            choice,
            Choice::Vertex {
                why: VertexReason::DataOutputs {
                    ids: true,
                    flow: true
                },
                ..
            }
        ));
        let none = Candidates::with_pinhole(None, Some(warp(1.0, 6e-3)), None);
        assert!(refusal(&f, &none).contains("[accuracy] max_error_px = 0.01"));
    }

    #[test]
    fn chromatic_colour_goes_by_a_warp_and_the_data_by_alg1() {
        let f = file(&format!("{CHROMATIC}[outputs]\nids = true\n"));
        let c = Candidates::with_pinhole(Some(vertex(5.0, 9e-3)), Some(warp(40.0, 6e-3)), None);
        let choice = choose(&f, &c).unwrap();
        assert!(matches!(
            choice.route(),
            Route::WarpAndVertex {
                chromatic: Some(_),
                tessellate: Some(_),
                map: false,
                ..
            }
        ));
        assert_eq!(
            (choice.expected_error_px(), choice.estimated_ms()),
            (9e-3, 45.0)
        );
        let no_vertex = Candidates::with_pinhole(None, Some(warp(40.0, 6e-3)), None);
        let no_warp = Candidates::with_pinhole(Some(vertex(5.0, 9e-3)), None, None);
        assert!(refusal(&f, &no_vertex).contains("tessellation"));
        assert!(refusal(&f, &no_warp).contains("inverse"));
    }

    #[test]
    fn the_cube_map_wins_on_cost_or_where_no_pinhole_source_holds_the_lens() {
        let cube = CubeCandidate {
            side: 460,
            ms: 48.0,
        };
        let f = file(CHROMATIC);
        // With chromatic aberration Alg. 1 does not compete, however cheap.
        let c =
            Candidates::with_pinhole(Some(vertex(1.0, 9e-3)), Some(warp(125.0, 6e-3)), Some(cube));
        let choice = choose(&f, &c).unwrap();
        assert!(matches!(
            &choice,
            Choice::Cube { why: CubeReason::Cheaper { warp_ms: Some(w) }, chromatic: Some(_), .. } if *w == 125.0
        ));
        assert_eq!(
            choice.route(),
            Route::Cube {
                side: 460,
                chromatic: Some([1.004, 1.0, 0.996])
            }
        );

        let choice = choose(&f, &wide(None, Some(cube))).unwrap();
        assert!(matches!(
            choice,
            Choice::Cube {
                why: CubeReason::NoPinholeWarp(_),
                ..
            }
        ));
        assert!(refusal(&f, &wide(None, None)).contains("[effects] chromatic_aberration"));

        // Without it, the cheaper of the cube and Alg. 1, and why Alg. 1 won.
        let f = file("");
        let choice = choose(&f, &wide(Some(vertex(8.0, 9e-3)), Some(cube))).unwrap();
        assert!(matches!(
            choice,
            Choice::Vertex { why: VertexReason::NoPinholeWarp { cube: CubeLoss::Dearer { ms }, .. }, .. } if ms == 48.0
        ));
        let choice = choose(&f, &wide(Some(vertex(80.0, 9e-3)), Some(cube))).unwrap();
        assert!(matches!(choice, Choice::Cube { .. }));
        let tight = file("[accuracy]\nmax_error_px = 1e-4\n");
        let choice = choose(&tight, &wide(Some(vertex(80.0, 9e-5)), None)).unwrap();
        assert!(matches!(
            choice,
            Choice::Vertex {
                why: VertexReason::NoPinholeWarp {
                    cube: CubeLoss::RaysMissBudget,
                    ..
                },
                ..
            }
        ));
        let depth = file("[outputs]\ndepth = true\n");
        let choice = choose(&depth, &wide(Some(vertex(80.0, 9e-3)), None)).unwrap();
        assert!(matches!(
            choice,
            Choice::Vertex {
                why: VertexReason::NoPinholeWarp {
                    cube: CubeLoss::ColourAlone,
                    ..
                },
                ..
            }
        ));
    }

    fn bands(count: u32, bands_error_px: f64, ms: f64) -> BandsSearch {
        BandsSearch {
            chosen: Some(BandsCandidate {
                count,
                bands_error_px,
                via: BandsVia::Warp(warp(10.0, 1e-3)),
                ms,
                budget_px: 0.5,
            }),
            most: None,
        }
    }

    const MOVING: (crate::model::rolling_shutter::Readout, usize) =
        (crate::model::rolling_shutter::Readout::TopToBottom, 1);

    #[test]
    fn a_moving_rolling_shutter_weighs_the_bands_against_the_exact_vertex_path() {
        let choose = |f: &SceneFile, c: &Candidates, b: &BandsSearch| {
            choose_moving_rolling_shutter(f, c, b, MOVING)
        };
        let c = Candidates::with_pinhole(Some(vertex(30.0, 9e-3)), Some(warp(10.0, 1e-3)), None);
        // Colour alone: the cheaper. Dearer bands lose, and --explain hears what they cost.
        let f = file("[accuracy]\nmax_error_px = 0.5\n");
        let choice = choose(&f, &c, &bands(8, 0.3, 80.0)).unwrap();
        assert!(matches!(
            choice,
            Choice::Vertex {
                why: VertexReason::MovingRollingShutter {
                    bands: BandsLoss::Dearer { count: 8, ms, .. }
                },
                ..
            } if ms == 80.0
        ));
        let choice = choose(&f, &c, &bands(4, 0.3, 20.0)).unwrap();
        assert_eq!(choice.bands(), Some(4));
        assert!(matches!(
            choice.route(),
            Route::Warp {
                chromatic: None,
                ..
            }
        ));
        assert_eq!(
            (choice.expected_error_px(), choice.estimated_ms()),
            (0.3 + 1e-3, 20.0)
        );
        // IDs: the vertex path, however cheap the bands.
        let ids = file("[accuracy]\nmax_error_px = 0.5\n[outputs]\nids = true\n");
        let choice = choose(&ids, &c, &bands(4, 0.3, 1.0)).unwrap();
        assert!(matches!(
            choice,
            Choice::Vertex {
                why: VertexReason::MovingRollingShutter {
                    bands: BandsLoss::DataOutputs
                },
                ..
            }
        ));
        // Chromatic with IDs: the bands for colour, the vertex path for the IDs.
        let both = file(&format!(
            "{CHROMATIC}[accuracy]\nmax_error_px = 0.5\n[outputs]\nids = true\n"
        ));
        let choice = choose(&both, &c, &bands(16, 0.2, 150.0)).unwrap();
        assert!(matches!(
            choice.route(),
            Route::WarpAndVertex {
                chromatic: Some(_),
                ..
            }
        ));
        assert_eq!((choice.bands(), choice.estimated_ms()), (Some(16), 180.0));
        // No route within the budget: refused, naming both keys and what 64 bands leave.
        let missed = BandsSearch {
            chosen: None,
            most: Some((64, 0.8)),
        };
        let chromatic = file(&format!("{CHROMATIC}[accuracy]\nmax_error_px = 0.5\n"));
        let e = choose(&chromatic, &c, &missed).unwrap_err().to_string();
        assert!(
            e.starts_with("/scenes/s.toml: [sensor] rolling_shutter, [accuracy] max_error_px = 0.5: [[poses]] #2 moves during its top_to_bottom readout")
                && e.contains("leaves 0.800 px even with 64 bands"),
            "{e}"
        );
        let none = Candidates::with_pinhole(None, Some(warp(10.0, 1e-3)), None);
        let e = choose(&f, &none, &missed).unwrap_err().to_string();
        assert!(
            e.contains("even 1 px edges") && e.contains("64 bands"),
            "{e}"
        );
        // A lens no pinhole source holds: no bands, and the cube map draws from one pose.
        let e = choose(&chromatic, &wide(None, None), &BandsSearch::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("[sensor] rolling_shutter") && e.contains("the lens sees past 90°"),
            "{e}"
        );
    }
}
