//! The camera calibrations of SLAM systems' configuration files, read as the systems read them:
//! every parameter, the model included. The caller has already turned the YAML (or JSON) into a
//! tree; numbers arrive as JSON numbers or as text (`as_number`), an `!!opencv-matrix` as a
//! mapping `{rows, cols, dt, data}`, and ORB-SLAM's dotted keys (`Camera.fx`) as top-level keys
//! of that name. A file is recognised by keys no other camera format has; once recognised, every
//! camera it holds is listed, each with its camera or the reason it cannot load (the exact key).
//! The image size is the file's; a file without one (many ORB-SLAM2 settings) loads only with a
//! size from the caller ([`size_or`]).
//!
//! * **ORB-SLAM3 settings of `File.version: "1.0"`** ("ORB-SLAM3 settings file"): `Camera.type`
//!   is `PinHole` (`Camera1.fx fy cx cy`; with `Camera1.k1` present, `k1 k2 p1 p2` and an
//!   optional `k3` are OpenCV's standard model, without it the pinhole has no distortion),
//!   `KannalaBrandt8` (`Camera1.k1 k2 k3 k4`: OpenCV's fisheye) or `Rectified` (a pinhole without
//!   distortion). `Camera2.*` (when the file writes `Camera2.fx`, `fy`, `cx` or `cy`) is the
//!   second camera of a stereo pair, read like the first. A `Rectified` pair's second camera is
//!   listed when `Stereo.b` is given: ORB-SLAM3 takes both images through `Camera1`'s
//!   intrinsics, so `Camera2` is that pinhole. The size is `Camera.width` × `Camera.height`
//!   (`Camera.newWidth` and `Camera.newHeight` are ORB-SLAM's resize for processing, not the
//!   calibration's size). Names: `Camera1`, `Camera2`.
//! * **Older ORB-SLAM3 and ORB-SLAM2 settings** ("ORB-SLAM3 settings file" with a `Camera.type`,
//!   "ORB-SLAM2 settings file" without one): `Camera.fx fy cx cy`; `PinHole` or no type is the
//!   standard model from `Camera.k1 k2 p1 p2` and an optional `Camera.k3`, `KannalaBrandt8` the
//!   fisheye from `Camera.k1 k2 k3 k4`; `Camera2.*` likewise (ORB-SLAM3's stereo fisheye). The
//!   size is `Camera.width` × `Camera.height` when given (`Camera.imageScale` scales the images
//!   ORB-SLAM processes, not the calibration). Names: `Camera`, `Camera2`.
//! * Either ORB-SLAM form's **`LEFT.*` and `RIGHT.*`**: the raw calibration of a stereo pair that
//!   ORB-SLAM rectifies itself (`K` a 3×3 matrix without skew, `D` OpenCV's standard-model
//!   coefficients, 4, 5, 8, 12 or 14 of them, `width`, `height`), while `Camera*` is what it
//!   tracks with. The cameras are listed in the file's sense: `Camera`/`Camera1` (and
//!   `Camera2`) first, then `LEFT`, then `RIGHT`.
//! * **OKVIS and OKVIS2 configs** ("OKVIS config"): `cameras:` a list of mappings with
//!   `image_dimension: [w, h]`, `focal_length: [fu, fv]`, `principal_point: [cu, cv]`,
//!   `distortion_type` and `distortion_coefficients`: `radialtangential` or `plumb_bob` (k1 k2 p1
//!   p2), `radialtangential8` or `plumb_bob8` (k1 k2 p1 p2 k3 k4 k5 k6, OpenCV's rational
//!   model), `equidistant` (k1 k2 k3 k4: OpenCV's fisheye). The `cam_model: eucm` some OKVIS
//!   forks write takes `eucm_parameters: [α, β]` (the enhanced unified model). Names `cam0`,
//!   `cam1`… by position.
//! * **EuRoC `sensor.yaml`** of a camera ("EuRoC sensor.yaml", `sensor_type: camera`):
//!   `resolution: [w, h]`, `camera_model: pinhole`, `intrinsics: [fu, fv, cu, cv]`,
//!   `distortion_model` `radial-tangential` or `radtan` (OpenCV's standard model) or
//!   `equidistant` (the fisheye), `distortion_coefficients`. One camera; the format names none
//!   (its `comment` is free text), so the name is empty.
//! * **SVO / SVO Pro camera files** ("SVO camera file", rpg_vikit's layout): `cameras:` a list of
//!   `{camera: {label, image_width, image_height, type: pinhole, intrinsics: [fx, fy, cx, cy],
//!   distortion: {type, parameters}}, T_B_C}`, the lists as plain lists or Eigen matrices
//!   `{rows, cols, data}`. Distortion `none` (also when `distortion` is absent, as vikit reads
//!   it), `radial-tangential` (k1 k2 p1 p2), `equidistant` (k1 k2 k3 k4: the fisheye) and
//!   `fisheye` — vikit's ATAN distortion, which is Devernay and Faugeras's field-of-view model
//!   with its one parameter ω. Names: `label`.
//! * **Kimera-VIO camera files** ("Kimera camera file"): `camera_id`, `resolution: [w, h]`,
//!   `camera_model: pinhole` (any case), `intrinsics: [fu, fv, cu, cv]`, `distortion_model`
//!   (any case) `radtan`, `radial-tangential` or `plumb_bob` (OpenCV's standard model, all the
//!   coefficients given), `equidistant` (the fisheye) or `none`, `distortion_coefficients`.
//!   Kimera's `omni` camera is not read. Name: `camera_id`.
//! * **stella_vslam configs** ("stella_vslam config": a `Camera:` mapping) and the older
//!   **OpenVSLAM** ones ("OpenVSLAM config": top-level `Camera.model`, `Camera.fx`… told from
//!   ORB-SLAM's `Camera.fx` by `Camera.model`, `Camera.setup`, `Camera.cols` or `Camera.rows`,
//!   which ORB-SLAM never writes): `model` `perspective` (`fx fy cx cy k1 k2 p1 p2 k3`, all
//!   required as stella requires them), `fisheye` (`fx fy cx cy k1 k2 k3 k4`), `radial_division`
//!   (`fx fy cx cy distortion`: the division model, x_u = x_d / (1 + d r_d²)) or
//!   `equirectangular` (no parameters), and `cols` × `rows`. stella maps a panorama as
//!   u = cols (½ + lon / 2π), v = rows (½ + lat / π): vklens's equirectangular camera with
//!   fx = cols / 2π, fy = rows / π, cx = cols / 2, cy = rows / 2 — half a pixel off the symmetric
//!   full sphere, and kept so that the camera projects as stella does. Name: `Camera.name`.
//!
//! Every format here puts pixel centres at integers, as OpenCV and vklens do.

use serde_json::{Map, Value};

use super::camera::as_number;
use super::catalog::{size_or, Found, Listing};
use crate::model::division::Division;
use crate::model::equirect::Equirectangular;
use crate::model::eucm::Eucm;
use crate::model::fov::Fov;
use crate::model::{Camera, Fisheye, Intrinsics, Lens, MAX_IMAGE_SIDE};
use crate::{Error, Result};

type Obj = Map<String, Value>;

/// The cameras of the file, if the tree is one of the formats above; `None` if it is not.
pub fn listing_from_tree(tree: &Value, size: Option<(u32, u32)>) -> Option<Listing> {
    let top = tree.as_object()?;
    // stella first: OpenVSLAM's dotted keys overlap ORB-SLAM's.
    stella(top, size)
        .or_else(|| orb_slam(top, size))
        .or_else(|| okvis(top, size))
        .or_else(|| svo(top, size))
        .or_else(|| kimera(top, size))
        .or_else(|| euroc(top, size))
}

// ---------------------------------------------------------------------------------------------
// Reading values, with errors that name the key as the file writes it.

/// Where a camera's values are: `obj`, under keys that start with `key` (ORB-SLAM's and
/// OpenVSLAM's dotted top-level keys) and that errors name with `shown` in front
/// (`Camera1.fx`, `cameras[0].focal_length`).
#[derive(Clone, Copy)]
struct Fields<'a> {
    obj: &'a Obj,
    key: &'a str,
    shown: &'a str,
}

impl<'a> Fields<'a> {
    fn new(obj: &'a Obj, key: &'a str, shown: &'a str) -> Self {
        Fields { obj, key, shown }
    }

    fn get(&self, k: &str) -> Option<&'a Value> {
        if self.key.is_empty() {
            self.obj.get(k)
        } else {
            self.obj.get(&format!("{}{k}", self.key))
        }
    }

    fn has(&self, k: &str) -> bool {
        self.get(k).is_some()
    }

    fn name(&self, k: &str) -> String {
        format!("{}{k}", self.shown)
    }

    fn missing(&self, k: &str) -> Error {
        Error::input(format!("missing `{}`", self.name(k)))
    }

    fn number(&self, k: &str) -> Result<f64> {
        self.opt_number(k)?.ok_or_else(|| self.missing(k))
    }

    fn opt_number(&self, k: &str) -> Result<Option<f64>> {
        self.get(k)
            .map(|v| {
                as_number(v).ok_or_else(|| {
                    Error::input(format!("`{}` must be a number, got {v}", self.name(k)))
                })
            })
            .transpose()
    }

    fn numbers<const N: usize>(&self, keys: [&str; N]) -> Result<[f64; N]> {
        let mut out = [0.0; N];
        for (o, k) in out.iter_mut().zip(keys) {
            *o = self.number(k)?;
        }
        Ok(out)
    }

    fn text(&self, k: &str) -> Result<Option<&'a str>> {
        match self.get(k) {
            None => Ok(None),
            Some(Value::String(s)) => Ok(Some(s.as_str())),
            Some(v) => Err(Error::input(format!(
                "`{}` must be text, got {v}",
                self.name(k)
            ))),
        }
    }

    fn required_text(&self, k: &str) -> Result<&'a str> {
        self.text(k)?.ok_or_else(|| self.missing(k))
    }

    /// A list of numbers: a YAML list, or a matrix (`!!opencv-matrix`, an Eigen matrix) whose
    /// `data` holds them.
    fn list(&self, k: &str) -> Result<Vec<f64>> {
        let v = self.get(k).ok_or_else(|| self.missing(k))?;
        list_of(v, &self.name(k))
    }

    fn intrinsics(&self, keys: [&str; 4]) -> Result<Intrinsics> {
        let [fx, fy, cx, cy] = self.numbers(keys)?;
        Ok(Intrinsics { fx, fy, cx, cy })
    }

    /// `[fx, fy, cx, cy]` as one list.
    fn intrinsics_list(&self, k: &str) -> Result<Intrinsics> {
        let [fx, fy, cx, cy] = exactly(self.list(k)?, &self.name(k), "the pinhole", "fx fy cx cy")?;
        Ok(Intrinsics { fx, fy, cx, cy })
    }

    /// Width and height from two keys; neither is no size, one alone an error.
    fn size(&self, w: &str, h: &str) -> Result<Option<(u32, u32)>> {
        match (self.get(w), self.get(h)) {
            (None, None) => Ok(None),
            (Some(wv), Some(hv)) => Ok(Some((
                pixels(wv, &self.name(w))?,
                pixels(hv, &self.name(h))?,
            ))),
            (Some(_), None) => Err(Error::input(format!(
                "`{}` is given but `{}` is missing",
                self.name(w),
                self.name(h)
            ))),
            (None, Some(_)) => Err(Error::input(format!(
                "`{}` is given but `{}` is missing",
                self.name(h),
                self.name(w)
            ))),
        }
    }

    /// Width and height as one list `[w, h]`.
    fn size_list(&self, k: &str) -> Result<Option<(u32, u32)>> {
        if !self.has(k) {
            return Ok(None);
        }
        let shown = self.name(k);
        let [w, h] = exactly(self.list(k)?, &shown, "an image size", "width height")?;
        Ok(Some((pixels(&num(w), &shown)?, pixels(&num(h), &shown)?)))
    }
}

fn num(x: f64) -> Value {
    serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number)
}

fn list_of(v: &Value, shown: &str) -> Result<Vec<f64>> {
    let (items, declared) = match v {
        Value::Array(a) => (a, None),
        Value::Object(m) => {
            let data = m.get("data").and_then(Value::as_array).ok_or_else(|| {
                Error::input(format!(
                    "`{shown}` must be a list of numbers or a matrix with `data`, got {v}"
                ))
            })?;
            let dim = |d: &str| m.get(d).and_then(as_number);
            (data, dim("rows").zip(dim("cols")))
        }
        _ => {
            return Err(Error::input(format!(
                "`{shown}` must be a list of numbers, got {v}"
            )))
        }
    };
    let values = items
        .iter()
        .enumerate()
        .map(|(i, x)| {
            as_number(x).ok_or_else(|| {
                Error::input(format!("`{shown}`: entry {i} must be a number, got {x}"))
            })
        })
        .collect::<Result<Vec<f64>>>()?;
    if let Some((rows, cols)) = declared {
        if rows * cols != values.len() as f64 {
            return Err(Error::input(format!(
                "`{shown}` is declared {rows}×{cols} but its `data` holds {} numbers",
                values.len()
            )));
        }
    }
    Ok(values)
}

fn pixels(v: &Value, shown: &str) -> Result<u32> {
    as_number(v)
        .filter(|n| n.fract() == 0.0 && (1.0..=f64::from(MAX_IMAGE_SIDE)).contains(n))
        .map(|n| n as u32)
        .ok_or_else(|| {
            Error::input(format!(
                "`{shown}` must be a whole number of pixels from 1 to {MAX_IMAGE_SIDE}, got {v}"
            ))
        })
}

/// The first `N` values of a list that `model` takes `N` of (named `names`). More are accepted
/// only when they are zero: the systems read the first `N`, and a zero adds nothing.
fn exactly<const N: usize>(
    values: Vec<f64>,
    shown: &str,
    model: &str,
    names: &str,
) -> Result<[f64; N]> {
    let fits = values.len() >= N && values[N..].iter().all(|&x| x == 0.0);
    if !fits {
        return Err(Error::input(format!(
            "`{shown}` has {} values; {model} takes {N} ({names}){}",
            values.len(),
            if values.len() > N {
                ", and the ones past them are not zero"
            } else {
                ""
            }
        )));
    }
    let mut out = [0.0; N];
    out.copy_from_slice(&values[..N]);
    Ok(out)
}

/// OpenCV's standard-model coefficients, as many as OpenCV takes.
fn opencv_coefficients(values: Vec<f64>, shown: &str, model: &str) -> Result<Vec<f64>> {
    if [4, 5, 8, 12, 14].contains(&values.len()) {
        Ok(values)
    } else {
        Err(Error::input(format!(
            "`{shown}` has {} values; {model} takes OpenCV's 4, 5, 8, 12 or 14 (k1 k2 p1 p2, then k3, k4 k5 k6, s1..s4, τx τy)",
            values.len()
        )))
    }
}

/// The lens of a camera: OpenCV's standard model from its coefficient list, or another model.
enum Model {
    Standard(Vec<f64>),
    Lens(Lens),
}

impl Model {
    fn none() -> Self {
        Model::Standard(vec![0.0; 4])
    }

    fn fisheye(k: [f64; 4]) -> Result<Self> {
        Ok(Model::Lens(Lens::Fisheye(Fisheye::new(k, 0.0, None)?)))
    }
}

/// The camera of `model`, at the file's size or, for a file without one, the given size.
fn build(
    file_size: Option<(u32, u32)>,
    given: Option<(u32, u32)>,
    k: Intrinsics,
    model: Model,
) -> Result<Camera> {
    let (w, h) = size_or(file_size, given)?;
    Ok(match model {
        Model::Standard(c) => Camera::from_coeffs(w, h, k, &c)?,
        Model::Lens(lens) => Camera::with_lens(w, h, k, lens)?,
    })
}

// ---------------------------------------------------------------------------------------------
// ORB-SLAM2 / ORB-SLAM3.

#[derive(Clone, Copy, PartialEq)]
enum OrbType {
    PinHole,
    Rectified,
    KannalaBrandt8,
}

fn orb_slam(top: &Obj, given: Option<(u32, u32)>) -> Option<Listing> {
    let distinctive = [
        "Camera.fx",
        "Camera1.fx",
        "Camera.type",
        "File.version",
        "LEFT.K",
    ];
    if !distinctive.iter().any(|k| top.contains_key(*k)) {
        return None;
    }
    // ORB-SLAM3 reads the new layout only for `File.version: "1.0"`, the old one otherwise.
    let v1 = top
        .get("File.version")
        .and_then(as_number)
        .is_some_and(|v| v == 1.0);
    let format = if v1 || top.contains_key("Camera.type") {
        "ORB-SLAM3 settings file"
    } else {
        "ORB-SLAM2 settings file"
    };
    let common = Fields::new(top, "Camera.", "Camera.");
    let orb_type = || orb_type(&common, v1);
    let size = || common.size("width", "height");
    let mut cameras = Vec::new();

    let (first, first_prefix) = if v1 {
        ("Camera1", "Camera1.")
    } else {
        ("Camera", "Camera.")
    };
    let first_fields = Fields::new(top, first_prefix, first_prefix);
    let second_fields = Fields::new(top, "Camera2.", "Camera2.");
    // A file of `LEFT.*` and `RIGHT.*` alone has no tracking camera to list.
    let raw_only = !v1
        && !top.contains_key("Camera.type")
        && !["fx", "fy", "cx", "cy"].iter().any(|k| first_fields.has(k));
    if !raw_only {
        let camera = orb_type().and_then(|t| orb_camera(&first_fields, t, v1, size()?, given));
        cameras.push(Found::new(first, camera));
    }
    let second_written = ["fx", "fy", "cx", "cy"]
        .iter()
        .any(|k| second_fields.has(k));
    match orb_type() {
        // ORB-SLAM3 takes both images of a rectified pair through `Camera1`'s intrinsics and
        // ignores `Camera2.*`.
        Ok(OrbType::Rectified) if top.contains_key("Stereo.b") => {
            let camera =
                size().and_then(|s| orb_camera(&first_fields, OrbType::Rectified, v1, s, given));
            cameras.push(Found::new("Camera2", camera));
        }
        Ok(OrbType::Rectified) => {}
        t if second_written => {
            let camera = t.and_then(|t| orb_camera(&second_fields, t, v1, size()?, given));
            cameras.push(Found::new("Camera2", camera));
        }
        _ => {}
    }
    for side in ["LEFT", "RIGHT"] {
        let prefix = format!("{side}.");
        let fields = Fields::new(top, &prefix, &prefix);
        if fields.has("K") || fields.has("D") {
            cameras.push(Found::new(side, orb_raw_camera(&fields, given)));
        }
    }
    Some(Listing { format, cameras })
}

fn orb_type(common: &Fields, v1: bool) -> Result<OrbType> {
    let ty = common.text("type")?;
    match (ty, v1) {
        (Some("PinHole"), _) => Ok(OrbType::PinHole),
        (Some("KannalaBrandt8"), _) => Ok(OrbType::KannalaBrandt8),
        (Some("Rectified"), true) => Ok(OrbType::Rectified),
        (None, false) => Ok(OrbType::PinHole),
        (None, true) => Err(Error::input(
            "missing `Camera.type` (settings of `File.version: \"1.0\"` name the model: `PinHole`, `KannalaBrandt8` or `Rectified`)",
        )),
        (Some(other), true) => Err(Error::input(format!(
            "`Camera.type` is `{other}`; ORB-SLAM3 has `PinHole`, `KannalaBrandt8`, `Rectified`"
        ))),
        (Some(other), false) => Err(Error::input(format!(
            "`Camera.type` is `{other}`; ORB-SLAM3 settings without `File.version: \"1.0\"` have `PinHole` and `KannalaBrandt8`"
        ))),
    }
}

fn orb_camera(
    f: &Fields,
    t: OrbType,
    v1: bool,
    file_size: Option<(u32, u32)>,
    given: Option<(u32, u32)>,
) -> Result<Camera> {
    let k = f.intrinsics(["fx", "fy", "cx", "cy"])?;
    let model = match t {
        OrbType::Rectified => Model::none(),
        OrbType::KannalaBrandt8 => Model::fisheye(f.numbers(["k1", "k2", "k3", "k4"])?)?,
        // ORB-SLAM3's new layout makes the distortion optional, present when `k1` is.
        OrbType::PinHole if v1 && !f.has("k1") => Model::none(),
        OrbType::PinHole => {
            let mut c = f.numbers(["k1", "k2", "p1", "p2"])?.to_vec();
            if let Some(k3) = f.opt_number("k3")? {
                c.push(k3);
            }
            Model::Standard(c)
        }
    };
    build(file_size, given, k, model)
}

/// `LEFT.*` or `RIGHT.*`: `K`, `D` (OpenCV's standard model), `width`, `height`.
fn orb_raw_camera(f: &Fields, given: Option<(u32, u32)>) -> Result<Camera> {
    let shown_k = f.name("K");
    let m: [f64; 9] = exactly(f.list("K")?, &shown_k, "a camera matrix", "3×3")?;
    if m[1] != 0.0 {
        return Err(Error::input(format!(
            "`{shown_k}` has a skew of {} (its row 0, column 1); vklens's pinhole has none",
            m[1]
        )));
    }
    if m[3] != 0.0 || m[6] != 0.0 || m[7] != 0.0 || m[8] != 1.0 {
        return Err(Error::input(format!(
            "`{shown_k}` is not a camera matrix: it must read fx 0 cx, 0 fy cy, 0 0 1"
        )));
    }
    let k = Intrinsics {
        fx: m[0],
        fy: m[4],
        cx: m[2],
        cy: m[5],
    };
    let shown_d = f.name("D");
    let d = opencv_coefficients(f.list("D")?, &shown_d, "OpenCV's standard model")?;
    build(f.size("width", "height")?, given, k, Model::Standard(d))
}

// ---------------------------------------------------------------------------------------------
// OKVIS / OKVIS2.

fn okvis(top: &Obj, given: Option<(u32, u32)>) -> Option<Listing> {
    let list = top.get("cameras")?.as_array()?;
    let first = list.first()?.as_object()?;
    let distinctive = [
        "image_dimension",
        "focal_length",
        "principal_point",
        "distortion_type",
    ];
    if !distinctive.iter().any(|k| first.contains_key(*k)) {
        return None;
    }
    let cameras = list
        .iter()
        .enumerate()
        .map(|(i, entry)| Found::new(format!("cam{i}"), okvis_camera(i, entry, given)))
        .collect();
    Some(Listing {
        format: "OKVIS config",
        cameras,
    })
}

fn okvis_camera(i: usize, entry: &Value, given: Option<(u32, u32)>) -> Result<Camera> {
    let shown = format!("cameras[{i}].");
    let obj = entry
        .as_object()
        .ok_or_else(|| Error::input(format!("`cameras[{i}]` must be a mapping, got {entry}")))?;
    let f = Fields::new(obj, "", &shown);
    let pair = |k: &str, names: &str| -> Result<[f64; 2]> {
        exactly(f.list(k)?, &f.name(k), "OKVIS", names)
    };
    let [fx, fy] = pair("focal_length", "fu fv")?;
    let [cx, cy] = pair("principal_point", "cu cv")?;
    let k = Intrinsics { fx, fy, cx, cy };
    let model = match f.text("cam_model")? {
        None | Some("pinhole") => {
            let ty = f.required_text("distortion_type")?;
            let coeffs = f.list("distortion_coefficients")?;
            let shown_c = f.name("distortion_coefficients");
            let named = |what: &str| format!("`{ty}`{what}");
            match ty {
                "radialtangential" | "plumb_bob" => {
                    let c: [f64; 4] = exactly(coeffs, &shown_c, &named(""), "k1 k2 p1 p2")?;
                    Model::Standard(c.to_vec())
                }
                "radialtangential8" | "plumb_bob8" => {
                    let c: [f64; 8] =
                        exactly(coeffs, &shown_c, &named(""), "k1 k2 p1 p2 k3 k4 k5 k6")?;
                    Model::Standard(c.to_vec())
                }
                "equidistant" => {
                    Model::fisheye(exactly(coeffs, &shown_c, &named(""), "k1 k2 k3 k4")?)?
                }
                other => {
                    return Err(Error::input(format!(
                        "`{}` is `{other}`; OKVIS has `radialtangential` (or `plumb_bob`), `radialtangential8` (or `plumb_bob8`), `equidistant`",
                        f.name("distortion_type")
                    )))
                }
            }
        }
        Some("eucm") => {
            let [alpha, beta] = pair("eucm_parameters", "alpha beta")?;
            Model::Lens(Lens::Eucm(Eucm::new(alpha, beta)?))
        }
        Some(other) => {
            return Err(Error::input(format!(
                "`{}` is `{other}`; OKVIS has `pinhole` (the default) and `eucm`",
                f.name("cam_model")
            )))
        }
    };
    build(f.size_list("image_dimension")?, given, k, model)
}

// ---------------------------------------------------------------------------------------------
// SVO / SVO Pro (rpg_vikit's camera files).

fn svo(top: &Obj, given: Option<(u32, u32)>) -> Option<Listing> {
    let list = top.get("cameras")?.as_array()?;
    if !list.first()?.as_object()?.contains_key("camera") {
        return None;
    }
    let cameras = list
        .iter()
        .enumerate()
        .map(|(i, entry)| {
            let camera = entry
                .get("camera")
                .and_then(Value::as_object)
                .ok_or_else(|| Error::input(format!("`cameras[{i}].camera` must be a mapping")));
            let name = camera
                .as_ref()
                .ok()
                .and_then(|c| c.get("label"))
                .and_then(Value::as_str)
                .unwrap_or("");
            Found::new(name, camera.and_then(|c| svo_camera(i, c, given)))
        })
        .collect();
    Some(Listing {
        format: "SVO camera file",
        cameras,
    })
}

fn svo_camera(i: usize, obj: &Obj, given: Option<(u32, u32)>) -> Result<Camera> {
    let shown = format!("cameras[{i}].camera.");
    let f = Fields::new(obj, "", &shown);
    let ty = f.required_text("type")?;
    if ty != "pinhole" {
        return Err(Error::input(format!(
            "`{}` is `{ty}`; vklens reads SVO's `pinhole` cameras",
            f.name("type")
        )));
    }
    let k = f.intrinsics_list("intrinsics")?;
    let model = match obj.get("distortion") {
        // vikit reads a camera without `distortion` as one without distortion.
        None => Model::none(),
        Some(d) => {
            let shown_d = format!("{shown}distortion.");
            let d = d.as_object().ok_or_else(|| {
                Error::input(format!("`{shown}distortion` must be a mapping, got {d}"))
            })?;
            let f = Fields::new(d, "", &shown_d);
            let ty = f.required_text("type")?;
            let params = || f.list("parameters");
            let shown_p = f.name("parameters");
            let named = format!("`{ty}`");
            match ty {
                "none" => {
                    if f.has("parameters") {
                        exactly::<0>(params()?, &shown_p, &named, "no parameters")?;
                    }
                    Model::none()
                }
                "radial-tangential" => {
                    let c: [f64; 4] = exactly(params()?, &shown_p, &named, "k1 k2 p1 p2")?;
                    Model::Standard(c.to_vec())
                }
                "equidistant" => Model::fisheye(exactly(params()?, &shown_p, &named, "k1 k2 k3 k4")?)?,
                "fisheye" => {
                    let [omega] = exactly(params()?, &shown_p, &named, "ω, the ATAN/FOV model's")?;
                    Model::Lens(Lens::Fov(Fov::new(omega)?))
                }
                other => {
                    return Err(Error::input(format!(
                        "`{}` is `{other}`; SVO has `none`, `radial-tangential`, `equidistant`, `fisheye`",
                        f.name("type")
                    )))
                }
            }
        }
    };
    build(f.size("image_width", "image_height")?, given, k, model)
}

// ---------------------------------------------------------------------------------------------
// Kimera-VIO and EuRoC: one camera at the top level.

fn kimera(top: &Obj, given: Option<(u32, u32)>) -> Option<Listing> {
    let distinctive = [
        "intrinsics",
        "distortion_model",
        "camera_model",
        "resolution",
    ];
    if !top.contains_key("camera_id") || !distinctive.iter().any(|k| top.contains_key(*k)) {
        return None;
    }
    let name = match top.get("camera_id") {
        Some(Value::String(s)) => s.clone(),
        Some(Value::Number(n)) => n.to_string(),
        _ => String::new(),
    };
    Some(Listing::one(
        "Kimera camera file",
        name,
        kimera_camera(top, given),
    ))
}

fn kimera_camera(top: &Obj, given: Option<(u32, u32)>) -> Result<Camera> {
    let f = Fields::new(top, "", "");
    let camera_model = f.required_text("camera_model")?;
    if !camera_model.eq_ignore_ascii_case("pinhole") {
        return Err(Error::input(format!(
            "`camera_model` is `{camera_model}`; vklens reads Kimera's `pinhole` cameras (not `omni`)"
        )));
    }
    let k = f.intrinsics_list("intrinsics")?;
    let ty = f.required_text("distortion_model")?;
    let shown_c = "distortion_coefficients";
    let named = format!("`{ty}`");
    let model = match ty.to_ascii_lowercase().as_str() {
        "none" => {
            // Coefficients under `none` would be ignored; a nonzero one means a mislabelled file.
            if f.has(shown_c) {
                let c = f.list(shown_c)?;
                if c.iter().any(|&x| x != 0.0) {
                    return Err(Error::input(format!(
                        "`distortion_model` is `{ty}` but `{shown_c}` are not all zero"
                    )));
                }
            }
            Model::none()
        }
        "radtan" | "radial-tangential" | "plumb_bob" => {
            Model::Standard(opencv_coefficients(f.list(shown_c)?, shown_c, &named)?)
        }
        "equidistant" => Model::fisheye(exactly(f.list(shown_c)?, shown_c, &named, "k1 k2 k3 k4")?)?,
        _ => {
            return Err(Error::input(format!(
                "`distortion_model` is `{ty}`; Kimera has `none`, `radtan` (or `radial-tangential`, `plumb_bob`), `equidistant`"
            )))
        }
    };
    build(f.size_list("resolution")?, given, k, model)
}

fn euroc(top: &Obj, given: Option<(u32, u32)>) -> Option<Listing> {
    if top.get("sensor_type").and_then(Value::as_str) != Some("camera") {
        return None;
    }
    Some(Listing::one(
        "EuRoC sensor.yaml",
        "",
        euroc_camera(top, given),
    ))
}

fn euroc_camera(top: &Obj, given: Option<(u32, u32)>) -> Result<Camera> {
    let f = Fields::new(top, "", "");
    if let Some(m) = f.text("camera_model")? {
        if m != "pinhole" {
            return Err(Error::input(format!(
                "`camera_model` is `{m}`; EuRoC has `pinhole`"
            )));
        }
    }
    let k = f.intrinsics_list("intrinsics")?;
    let ty = f.required_text("distortion_model")?;
    let shown_c = "distortion_coefficients";
    let named = format!("`{ty}`");
    let model = match ty {
        "radial-tangential" | "radtan" => {
            Model::Standard(opencv_coefficients(f.list(shown_c)?, shown_c, &named)?)
        }
        "equidistant" => Model::fisheye(exactly(f.list(shown_c)?, shown_c, &named, "k1 k2 k3 k4")?)?,
        other => {
            return Err(Error::input(format!(
                "`distortion_model` is `{other}`; EuRoC has `radial-tangential` (or `radtan`) and `equidistant`"
            )))
        }
    };
    build(f.size_list("resolution")?, given, k, model)
}

// ---------------------------------------------------------------------------------------------
// stella_vslam / OpenVSLAM.

fn stella(top: &Obj, given: Option<(u32, u32)>) -> Option<Listing> {
    let (fields, format) = match top.get("Camera") {
        Some(Value::Object(cam)) if cam.contains_key("model") || cam.contains_key("setup") => {
            (Fields::new(cam, "", "Camera."), "stella_vslam config")
        }
        _ => {
            let distinctive = ["Camera.model", "Camera.setup", "Camera.cols", "Camera.rows"];
            if !distinctive.iter().any(|k| top.contains_key(*k)) {
                return None;
            }
            (Fields::new(top, "Camera.", "Camera."), "OpenVSLAM config")
        }
    };
    let name = fields.get("name").and_then(Value::as_str).unwrap_or("");
    Some(Listing::one(format, name, stella_camera(&fields, given)))
}

fn stella_camera(f: &Fields, given: Option<(u32, u32)>) -> Result<Camera> {
    let model = f.required_text("model")?;
    let file_size = f.size("cols", "rows")?;
    let pinhole = || f.intrinsics(["fx", "fy", "cx", "cy"]);
    let (k, model) = match model {
        "perspective" => (
            pinhole()?,
            Model::Standard(f.numbers(["k1", "k2", "p1", "p2", "k3"])?.to_vec()),
        ),
        "fisheye" => (
            pinhole()?,
            Model::fisheye(f.numbers(["k1", "k2", "k3", "k4"])?)?,
        ),
        "radial_division" => (
            pinhole()?,
            Model::Lens(Lens::Division(Division::new(f.number("distortion")?)?)),
        ),
        "equirectangular" => {
            let (w, h) = size_or(file_size, given)?;
            let (w, h) = (f64::from(w), f64::from(h));
            let tau = std::f64::consts::TAU;
            let k = Intrinsics {
                fx: w / tau,
                fy: h / std::f64::consts::PI,
                cx: w / 2.0,
                cy: h / 2.0,
            };
            (k, Model::Lens(Lens::Equirectangular(Equirectangular)))
        }
        other => {
            return Err(Error::input(format!(
                "`{}` is `{other}`; stella_vslam has `perspective`, `fisheye`, `equirectangular`, `radial_division`",
                f.name("model")
            )))
        }
    };
    build(file_size, given, k, model)
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;

    /// The tree the caller hands the reader: the text through the YAML reader camera files
    /// go through (OpenCV's quirks included).
    fn tree(text: &str) -> Value {
        crate::io::camera::yaml_to_tree(text).expect("valid YAML")
    }

    fn listing(text: &str, size: Option<(u32, u32)>) -> Listing {
        listing_from_tree(&tree(text), size).expect("recognised")
    }

    fn names(l: &Listing) -> Vec<&str> {
        l.cameras.iter().map(|f| f.name.as_str()).collect()
    }

    fn camera(l: &Listing, i: usize) -> &Camera {
        match &l.cameras[i].camera {
            Ok(c) => c,
            Err(e) => panic!("camera {i} ({}): {e}", l.cameras[i].name),
        }
    }

    fn error(l: &Listing, i: usize) -> String {
        match &l.cameras[i].camera {
            Ok(_) => panic!("camera {i} ({}) loaded", l.cameras[i].name),
            Err(e) => e.to_string(),
        }
    }

    fn k(fx: f64, fy: f64, cx: f64, cy: f64) -> Intrinsics {
        Intrinsics { fx, fy, cx, cy }
    }

    const POINTS: [[f64; 3]; 5] = [
        [0.0, 0.0, 1.0],
        [0.3, -0.2, 1.0],
        [-0.5, 0.4, 2.0],
        [0.9, 0.7, 1.5],
        [-0.2, -0.6, 0.8],
    ];

    /// Same size, same intrinsics, same projection everywhere sampled: the same camera.
    fn assert_same(got: &Camera, want: &Camera) {
        assert_eq!((got.width, got.height), (want.width, want.height));
        assert_eq!(got.intrinsics, want.intrinsics);
        assert_eq!(got.model(), want.model());
        for p in POINTS {
            let p = DVec3::from_array(p);
            assert_eq!(got.project(p), want.project(p), "at {p}");
        }
    }

    fn standard(w: u32, h: u32, k: Intrinsics, c: &[f64]) -> Camera {
        Camera::from_coeffs(w, h, k, c).expect("standard camera")
    }

    fn fisheye(w: u32, h: u32, k: Intrinsics, c: [f64; 4]) -> Camera {
        Camera::fisheye(w, h, k, Fisheye::new(c, 0.0, None).expect("lens")).expect("fisheye")
    }

    const ORB2_MONO: &str = r#"%YAML:1.0
Camera.fx: 517.306408
Camera.fy: 516.469215
Camera.cx: 318.643040
Camera.cy: 255.313989
Camera.k1: 0.262383
Camera.k2: -0.953104
Camera.p1: -0.005358
Camera.p2: 0.002628
Camera.k3: 1.163314
Camera.fps: 30.0
Camera.RGB: 1
ORBextractor.nFeatures: 1000
"#;

    #[test]
    fn orb_slam2_needs_a_size_and_takes_the_given_one() {
        let l = listing(ORB2_MONO, None);
        assert_eq!(l.format, "ORB-SLAM2 settings file");
        assert_eq!(names(&l), ["Camera"]);
        let e = error(&l, 0);
        assert!(e.contains("`size`"), "{e}");

        let l = listing(ORB2_MONO, Some((640, 480)));
        let want = standard(
            640,
            480,
            k(517.306408, 516.469215, 318.643040, 255.313989),
            &[0.262383, -0.953104, -0.005358, 0.002628, 1.163314],
        );
        assert_same(camera(&l, 0), &want);
    }

    #[test]
    fn orb_slam2_missing_coefficient_is_named() {
        let text = ORB2_MONO.replace("Camera.p2: 0.002628\n", "");
        let l = listing(&text, Some((640, 480)));
        assert_eq!(error(&l, 0), "missing `Camera.p2`");
    }

    const ORB2_STEREO: &str = r#"%YAML:1.0
Camera.fx: 435.2
Camera.fy: 435.2
Camera.cx: 367.4
Camera.cy: 252.2
Camera.k1: 0.0
Camera.k2: 0.0
Camera.p1: 0.0
Camera.p2: 0.0
Camera.width: 752
Camera.height: 480
Camera.bf: 47.9
LEFT.height: 480
LEFT.width: 752
LEFT.D: !!opencv-matrix
   rows: 1
   cols: 5
   dt: d
   data: [-0.28, 0.07, 0.0002, 1.7e-05, 0.0]
LEFT.K: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [458.6, 0.0, 367.2, 0.0, 457.3, 248.4, 0.0, 0.0, 1.0]
LEFT.R:  !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [1, 0, 0, 0, 1, 0, 0, 0, 1]
RIGHT.height: 480
RIGHT.width: 752
RIGHT.D: !!opencv-matrix
   rows: 1
   cols: 5
   dt: d
   data: [-0.29, 0.08, -1.0e-04, -3.5e-05, 0.0]
RIGHT.K: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [457.6, 0.0, 380.0, 0.0, 456.1, 255.2, 0.0, 0.0, 1]
"#;

    #[test]
    fn orb_slam2_stereo_lists_the_rectified_camera_then_the_raw_pair() {
        let l = listing(ORB2_STEREO, None);
        assert_eq!(names(&l), ["Camera", "LEFT", "RIGHT"]);
        assert_same(
            camera(&l, 0),
            &standard(752, 480, k(435.2, 435.2, 367.4, 252.2), &[0.0; 4]),
        );
        assert_same(
            camera(&l, 1),
            &standard(
                752,
                480,
                k(458.6, 457.3, 367.2, 248.4),
                &[-0.28, 0.07, 0.0002, 1.7e-05, 0.0],
            ),
        );
        assert_same(
            camera(&l, 2),
            &standard(
                752,
                480,
                k(457.6, 456.1, 380.0, 255.2),
                &[-0.29, 0.08, -1.0e-04, -3.5e-05, 0.0],
            ),
        );
        // The file's size and another one given: a calibration holds for its own size.
        let l = listing(ORB2_STEREO, Some((640, 480)));
        assert!(l.cameras.iter().all(|f| f.camera.is_err()));
    }

    #[test]
    fn orb_raw_camera_with_skew_is_refused() {
        let text = ORB2_STEREO.replace("[458.6, 0.0, 367.2", "[458.6, 0.5, 367.2");
        let l = listing(&text, None);
        let e = error(&l, 1);
        assert!(e.contains("`LEFT.K`") && e.contains("skew"), "{e}");
    }

    const ORB3_V1_STEREO_KB: &str = r#"%YAML:1.0
File.version: "1.0"
Camera.type: "KannalaBrandt8"
Camera1.fx: 190.97
Camera1.fy: 190.97
Camera1.cx: 254.93
Camera1.cy: 256.89
Camera1.k1: 0.0034
Camera1.k2: 0.0007
Camera1.k3: -0.0020
Camera1.k4: 0.0002
Camera2.fx: 190.44
Camera2.fy: 190.43
Camera2.cx: 252.60
Camera2.cy: 254.92
Camera2.k1: 0.0034
Camera2.k2: 0.0017
Camera2.k3: -0.0027
Camera2.k4: 0.0003
Camera.width: 512
Camera.height: 512
Camera.fps: 20
Stereo.T_c1_c2: !!opencv-matrix
  rows: 4
  cols: 4
  dt: f
  data: [1,0,0,0.1, 0,1,0,0, 0,0,1,0, 0,0,0,1]
"#;

    #[test]
    fn orb_slam3_v1_fisheye_pair() {
        let l = listing(ORB3_V1_STEREO_KB, None);
        assert_eq!(l.format, "ORB-SLAM3 settings file");
        assert_eq!(names(&l), ["Camera1", "Camera2"]);
        assert_same(
            camera(&l, 0),
            &fisheye(
                512,
                512,
                k(190.97, 190.97, 254.93, 256.89),
                [0.0034, 0.0007, -0.0020, 0.0002],
            ),
        );
        assert_same(
            camera(&l, 1),
            &fisheye(
                512,
                512,
                k(190.44, 190.43, 252.60, 254.92),
                [0.0034, 0.0017, -0.0027, 0.0003],
            ),
        );
        let text = ORB3_V1_STEREO_KB.replace("Camera2.k2: 0.0017\n", "");
        assert_eq!(error(&listing(&text, None), 1), "missing `Camera2.k2`");
    }

    #[test]
    fn orb_slam3_v1_pinhole_distortion_is_optional_and_rectified_has_none() {
        let pinhole = r#"File.version: "1.0"
Camera.type: "PinHole"
Camera1.fx: 500.0
Camera1.fy: 501.0
Camera1.cx: 320.0
Camera1.cy: 240.0
Camera.width: 640
Camera.height: 480
"#;
        let l = listing(pinhole, None);
        assert_same(
            camera(&l, 0),
            &standard(640, 480, k(500.0, 501.0, 320.0, 240.0), &[0.0; 4]),
        );
        let distorted = format!(
            "{pinhole}Camera1.k1: -0.1\nCamera1.k2: 0.01\nCamera1.p1: 0.001\nCamera1.p2: -0.002\nCamera1.k3: 0.003\n"
        );
        let l = listing(&distorted, None);
        assert_same(
            camera(&l, 0),
            &standard(
                640,
                480,
                k(500.0, 501.0, 320.0, 240.0),
                &[-0.1, 0.01, 0.001, -0.002, 0.003],
            ),
        );

        let rectified = pinhole.replace("PinHole", "Rectified") + "Stereo.b: 0.11\n";
        let l = listing(&rectified, None);
        assert_eq!(names(&l), ["Camera1", "Camera2"]);
        let want = standard(640, 480, k(500.0, 501.0, 320.0, 240.0), &[0.0; 4]);
        assert_same(camera(&l, 0), &want);
        assert_same(camera(&l, 1), &want);
    }

    #[test]
    fn orb_slam3_unknown_or_missing_type_is_named() {
        let text = ORB3_V1_STEREO_KB.replace("KannalaBrandt8", "Foo");
        let l = listing(&text, None);
        let e = error(&l, 0);
        assert!(
            e.contains("`Camera.type` is `Foo`") && e.contains("KannalaBrandt8"),
            "{e}"
        );
        let text = ORB3_V1_STEREO_KB.replace("Camera.type: \"KannalaBrandt8\"\n", "");
        let e = error(&listing(&text, None), 0);
        assert!(e.contains("missing `Camera.type`"), "{e}");
    }

    #[test]
    fn orb_slam3_old_style_fisheye() {
        let text = r#"Camera.type: "KannalaBrandt8"
Camera.fx: 190.97
Camera.fy: 190.97
Camera.cx: 254.93
Camera.cy: 256.89
Camera.k1: 0.0034
Camera.k2: 0.0007
Camera.k3: -0.0020
Camera.k4: 0.0002
Camera.width: 512
Camera.height: 512
"#;
        let l = listing(text, None);
        assert_eq!(l.format, "ORB-SLAM3 settings file");
        assert_eq!(names(&l), ["Camera"]);
        assert_same(
            camera(&l, 0),
            &fisheye(
                512,
                512,
                k(190.97, 190.97, 254.93, 256.89),
                [0.0034, 0.0007, -0.0020, 0.0002],
            ),
        );
        let e = error(
            &listing(&text.replace("KannalaBrandt8", "Rectified"), None),
            0,
        );
        assert!(e.contains("`Camera.type` is `Rectified`"), "{e}");
    }

    const OKVIS: &str = r#"%YAML:1.0
cameras:
     - {T_SC:
        [ 0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,
          0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,
         -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949,
          0.0, 0.0, 0.0, 1.0],
        image_dimension: [752, 480],
        distortion_coefficients: [-0.28, 0.07, 0.0002, 1.7e-05],
        distortion_type: radialtangential,
        focal_length: [458.6, 457.3],
        principal_point: [367.2, 248.4]}
     - {T_SC:
        [ 1.0, 0.0, 0.0, 0.1, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0],
        image_dimension: [752, 480],
        distortion_coefficients: [0.01, -0.002, 0.0003, -0.0001],
        distortion_type: equidistant,
        focal_length: [457.6, 456.1],
        principal_point: [380.0, 255.2]}
camera_params:
    camera_rate: 20
"#;

    #[test]
    fn okvis_cameras_by_position() {
        let l = listing(OKVIS, None);
        assert_eq!(l.format, "OKVIS config");
        assert_eq!(names(&l), ["cam0", "cam1"]);
        assert_same(
            camera(&l, 0),
            &standard(
                752,
                480,
                k(458.6, 457.3, 367.2, 248.4),
                &[-0.28, 0.07, 0.0002, 1.7e-05],
            ),
        );
        assert_same(
            camera(&l, 1),
            &fisheye(
                752,
                480,
                k(457.6, 456.1, 380.0, 255.2),
                [0.01, -0.002, 0.0003, -0.0001],
            ),
        );
    }

    #[test]
    fn okvis_rational_model_unknown_type_and_miscounted_coefficients() {
        let text = OKVIS.replace(
            "[-0.28, 0.07, 0.0002, 1.7e-05],\n        distortion_type: radialtangential,",
            "[-0.28, 0.07, 0.0002, 1.7e-05, 0.01, 0.002, -0.001, 0.0005],\n        distortion_type: radialtangential8,",
        );
        let l = listing(&text, None);
        assert_same(
            camera(&l, 0),
            &standard(
                752,
                480,
                k(458.6, 457.3, 367.2, 248.4),
                &[-0.28, 0.07, 0.0002, 1.7e-05, 0.01, 0.002, -0.001, 0.0005],
            ),
        );
        let e = error(&listing(&OKVIS.replace("equidistant", "kb9"), None), 1);
        assert!(e.contains("`cameras[1].distortion_type` is `kb9`"), "{e}");
        let text = OKVIS.replace("[0.01, -0.002, 0.0003, -0.0001]", "[0.01, -0.002, 0.0003]");
        let e = error(&listing(&text, None), 1);
        assert!(
            e.contains("`cameras[1].distortion_coefficients` has 3 values"),
            "{e}"
        );
        let e = error(
            &listing(&OKVIS.replace("focal_length: [457.6, 456.1],", ""), None),
            1,
        );
        assert_eq!(e, "missing `cameras[1].focal_length`");
    }

    const EUROC: &str = r#"# General sensor definitions.
sensor_type: camera
comment: VI-Sensor cam0 (MT9M034)

# Sensor extrinsics wrt. the body-frame.
T_BS:
  cols: 4
  rows: 4
  data: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]

# Camera specific definitions.
rate_hz: 20
resolution: [752, 480]
camera_model: pinhole
intrinsics: [458.6, 457.3, 367.2, 248.4] #fu, fv, cu, cv
distortion_model: radial-tangential
distortion_coefficients: [-0.28, 0.07, 0.0002, 1.7e-05]
"#;

    #[test]
    fn euroc_sensor_yaml() {
        let l = listing(EUROC, None);
        assert_eq!(l.format, "EuRoC sensor.yaml");
        assert_eq!(names(&l), [""]);
        assert_same(
            camera(&l, 0),
            &standard(
                752,
                480,
                k(458.6, 457.3, 367.2, 248.4),
                &[-0.28, 0.07, 0.0002, 1.7e-05],
            ),
        );
        let l = listing(&EUROC.replace("radial-tangential", "equidistant"), None);
        assert_same(
            camera(&l, 0),
            &fisheye(
                752,
                480,
                k(458.6, 457.3, 367.2, 248.4),
                [-0.28, 0.07, 0.0002, 1.7e-05],
            ),
        );
        let e = error(
            &listing(&EUROC.replace("radial-tangential", "fov"), None),
            0,
        );
        assert!(e.contains("`distortion_model` is `fov`"), "{e}");
        // An IMU's sensor.yaml is not a camera.
        let imu = "sensor_type: imu\nrate_hz: 200\n";
        assert!(listing_from_tree(&tree(imu), None).is_none());
    }

    const KIMERA: &str = r#"%YAML:1.0
# General sensor definitions.
camera_id: left_cam

T_BS:
  cols: 4
  rows: 4
  data: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]

rate_hz: 20
resolution: [752, 480]
camera_model: pinhole
intrinsics: [458.6, 457.3, 367.2, 248.4] #fu, fv, cu, cv
distortion_model: radtan
distortion_coefficients: [-0.28, 0.07, 0.0002, 1.7e-05]
"#;

    #[test]
    fn kimera_camera_file() {
        let l = listing(KIMERA, None);
        assert_eq!(l.format, "Kimera camera file");
        assert_eq!(names(&l), ["left_cam"]);
        assert_same(
            camera(&l, 0),
            &standard(
                752,
                480,
                k(458.6, 457.3, 367.2, 248.4),
                &[-0.28, 0.07, 0.0002, 1.7e-05],
            ),
        );
        let l = listing(&KIMERA.replace("radtan", "Equidistant"), None);
        assert_same(
            camera(&l, 0),
            &fisheye(
                752,
                480,
                k(458.6, 457.3, 367.2, 248.4),
                [-0.28, 0.07, 0.0002, 1.7e-05],
            ),
        );
        let e = error(&listing(&KIMERA.replace("pinhole", "omni"), None), 0);
        assert!(e.contains("`camera_model` is `omni`"), "{e}");
        let e = error(&listing(&KIMERA.replace("radtan", "none"), None), 0);
        assert!(e.contains("not all zero"), "{e}");
        let e = error(
            &listing(&KIMERA.replace("resolution: [752, 480]\n", ""), None),
            0,
        );
        assert!(e.contains("`size`"), "{e}");
    }

    const SVO: &str = r#"cameras:
- camera:
    distortion:
      parameters:
        cols: 1
        rows: 4
        data: [-0.28, 0.07, 0.0002, 1.7e-05]
      type: radial-tangential
    image_height: 480
    image_width: 752
    intrinsics:
      cols: 1
      rows: 4
      data: [458.6, 457.3, 367.2, 248.4]
    label: cam0
    line-delay-nanoseconds: 0
    type: pinhole
  T_B_C:
    cols: 4
    rows: 4
    data: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]
- camera:
    distortion:
      parameters:
        cols: 1
        rows: 1
        data: [0.93]
      type: fisheye
    image_height: 480
    image_width: 752
    intrinsics:
      cols: 1
      rows: 4
      data: [300.1, 299.8, 370.0, 240.5]
    label: cam1
    type: pinhole
  T_B_C:
    cols: 4
    rows: 4
    data: [1, 0, 0, 0.1, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]
label: rig
"#;

    #[test]
    fn svo_camera_file() {
        let l = listing(SVO, None);
        assert_eq!(l.format, "SVO camera file");
        assert_eq!(names(&l), ["cam0", "cam1"]);
        assert_same(
            camera(&l, 0),
            &standard(
                752,
                480,
                k(458.6, 457.3, 367.2, 248.4),
                &[-0.28, 0.07, 0.0002, 1.7e-05],
            ),
        );
        let fov = Camera::with_lens(
            752,
            480,
            k(300.1, 299.8, 370.0, 240.5),
            Lens::Fov(Fov::new(0.93).expect("omega")),
        )
        .expect("fov camera");
        assert_same(camera(&l, 1), &fov);
        assert_eq!(camera(&l, 1).lens().params(), vec![("omega", 0.93)]);

        let text = SVO.replacen("type: radial-tangential", "type: equidistant", 1);
        assert_same(
            camera(&listing(&text, None), 0),
            &fisheye(
                752,
                480,
                k(458.6, 457.3, 367.2, 248.4),
                [-0.28, 0.07, 0.0002, 1.7e-05],
            ),
        );
        let e = error(
            &listing(&SVO.replace("type: fisheye", "type: atan2"), None),
            1,
        );
        assert!(
            e.contains("`cameras[1].camera.distortion.type` is `atan2`"),
            "{e}"
        );
        let e = error(
            &listing(&SVO.replacen("    image_height: 480\n", "", 1), None),
            0,
        );
        assert!(
            e.contains("`cameras[0].camera.image_width` is given but `cameras[0].camera.image_height` is missing"),
            "{e}"
        );
    }

    const STELLA: &str = r#"Camera:
  name: "EuRoC monocular"
  setup: "monocular"
  model: "perspective"

  fx: 458.6
  fy: 457.3
  cx: 367.2
  cy: 248.4

  k1: -0.28
  k2: 0.07
  p1: 0.0002
  p2: 1.7e-05
  k3: 0.0

  fps: 20.0
  cols: 752
  rows: 480

  color_order: "Gray"

Feature:
  name: "default ORB feature extraction setting"
"#;

    #[test]
    fn stella_perspective_fisheye_and_division() {
        let l = listing(STELLA, None);
        assert_eq!(l.format, "stella_vslam config");
        assert_eq!(names(&l), ["EuRoC monocular"]);
        assert_same(
            camera(&l, 0),
            &standard(
                752,
                480,
                k(458.6, 457.3, 367.2, 248.4),
                &[-0.28, 0.07, 0.0002, 1.7e-05, 0.0],
            ),
        );
        let e = error(&listing(&STELLA.replace("  k3: 0.0\n", ""), None), 0);
        assert_eq!(e, "missing `Camera.k3`");

        let fish = STELLA.replace("\"perspective\"", "\"fisheye\"").replace(
            "p1: 0.0002\n  p2: 1.7e-05\n  k3: 0.0",
            "k3: 0.0002\n  k4: 1.7e-05",
        );
        assert_same(
            camera(&listing(&fish, None), 0),
            &fisheye(
                752,
                480,
                k(458.6, 457.3, 367.2, 248.4),
                [-0.28, 0.07, 0.0002, 1.7e-05],
            ),
        );

        let division = STELLA
            .replace("\"perspective\"", "\"radial_division\"")
            .replace("  k1: -0.28\n", "  distortion: -0.21\n");
        let want = Camera::with_lens(
            752,
            480,
            k(458.6, 457.3, 367.2, 248.4),
            Lens::Division(Division::new(-0.21).expect("k")),
        )
        .expect("division camera");
        assert_same(camera(&listing(&division, None), 0), &want);

        let e = error(
            &listing(&STELLA.replace("\"perspective\"", "\"ocam\""), None),
            0,
        );
        assert!(e.contains("`Camera.model` is `ocam`"), "{e}");
    }

    #[test]
    fn stella_equirectangular_projects_as_stella_does() {
        let text = r#"Camera:
  name: "RICOH THETA S 960"
  setup: "monocular"
  model: "equirectangular"
  fps: 30.0
  cols: 1920
  rows: 960
  color_order: "RGB"
"#;
        let l = listing(text, None);
        let cam = camera(&l, 0);
        assert_eq!(cam.model(), crate::model::ModelKind::Equirectangular);
        // stella: u = cols (½ + lon / 2π), v = rows (½ − lat / π) with lat = −asin(y / |p|).
        for p in POINTS {
            let p = DVec3::from_array(p);
            let b = p.normalize();
            let lon = b.x.atan2(b.z);
            let lat = -b.y.asin();
            let u = 1920.0 * (0.5 + lon / std::f64::consts::TAU);
            let v = 960.0 * (0.5 - lat / std::f64::consts::PI);
            let got = cam.project(p).expect("on the sphere");
            assert!(
                (got.x - u).abs() < 1e-9 && (got.y - v).abs() < 1e-9,
                "{got} vs {u} {v}"
            );
        }
    }

    #[test]
    fn openvslam_dotted_form_is_not_taken_for_orb_slam() {
        let text = r#"Camera.name: "TUM RGBD monocular 1"
Camera.setup: "monocular"
Camera.model: "perspective"
Camera.fx: 517.3
Camera.fy: 516.5
Camera.cx: 318.6
Camera.cy: 255.3
Camera.k1: 0.2624
Camera.k2: -0.9531
Camera.p1: -0.0054
Camera.p2: 0.0026
Camera.k3: 1.1633
Camera.fps: 30.0
Camera.cols: 640
Camera.rows: 480
Camera.color_order: "RGB"
"#;
        let l = listing(text, None);
        assert_eq!(l.format, "OpenVSLAM config");
        assert_eq!(names(&l), ["TUM RGBD monocular 1"]);
        assert_same(
            camera(&l, 0),
            &standard(
                640,
                480,
                k(517.3, 516.5, 318.6, 255.3),
                &[0.2624, -0.9531, -0.0054, 0.0026, 1.1633],
            ),
        );
    }

    #[test]
    fn other_formats_are_not_claimed() {
        let others = [
            // vklens JSON
            r#"{"width": 640, "height": 480, "fx": 500, "fy": 500, "cx": 320, "cy": 240, "dist_coeffs": [0, 0, 0, 0, 0]}"#,
            // OpenCV FileStorage
            "image_width: 640\nimage_height: 480\ncamera_matrix: {rows: 3, cols: 3, dt: d, data: [500, 0, 320, 0, 500, 240, 0, 0, 1]}\ndistortion_coefficients: {rows: 1, cols: 5, dt: d, data: [0, 0, 0, 0, 0]}\n",
            // ROS camera_info
            "image_width: 640\nimage_height: 480\ncamera_name: cam\ncamera_matrix: {rows: 3, cols: 3, data: [500, 0, 320, 0, 500, 240, 0, 0, 1]}\ndistortion_model: plumb_bob\ndistortion_coefficients: {rows: 1, cols: 5, data: [0, 0, 0, 0, 0]}\n",
            // Kalibr camchain
            "cam0:\n  camera_model: pinhole\n  intrinsics: [500, 500, 320, 240]\n  distortion_model: radtan\n  distortion_coeffs: [0, 0, 0, 0]\n  resolution: [640, 480]\n",
            // camodocal
            "model_type: PINHOLE\ncamera_name: cam\nimage_width: 640\nimage_height: 480\n",
            // Basalt
            "value0:\n  cam_names: [cam0]\n",
        ];
        for text in others {
            assert!(listing_from_tree(&tree(text), None).is_none(), "{text}");
        }
    }

    #[test]
    fn numbers_written_as_text_are_read() {
        // FileStorage writes exponents as `1.5e-002`; a quoted number is read too.
        let text = ORB2_MONO
            .replace("Camera.k3: 1.163314", "Camera.k3: 1.5e-002")
            .replace("Camera.fx: 517.306408", "Camera.fx: \"517.306408\"");
        let l = listing(&text, Some((640, 480)));
        let want = standard(
            640,
            480,
            k(517.306408, 516.469215, 318.643040, 255.313989),
            &[0.262383, -0.953104, -0.005358, 0.002628, 0.015],
        );
        assert_same(camera(&l, 0), &want);
    }
}
