//! Camera files of the models of the table beyond OpenCV's two: vklens JSON (`"model":
//! "omni"`, `"ucm"`, `"eucm"`, `"double_sphere"`, `"fov"`, `"equirectangular"`, `"ftheta"`,
//! `"ocam"`), NCore's camera JSON for f-theta and OCamCalib's `calib_results.txt`, and the
//! vklens JSON written back for each.

use serde_json::{json, Map, Value};

use super::camera::{dimension, intrinsics_from, number_field, number_list, parse_float};
use crate::error::{Error, Result};
use crate::model::division::Division;
use crate::model::equirect::Equirectangular;
use crate::model::eucm::Eucm;
use crate::model::fov::Fov;
use crate::model::ftheta::{FTheta, Reference};
use crate::model::ocam::Ocam;
use crate::model::omni::Omni;
use crate::model::thin_prism::ThinPrismFisheye;
use crate::model::{Camera, Intrinsics, Lens, ModelKind};

/// The model names this module reads: every model of the list but OpenCV's two (read by
/// `io::camera`), and `"colmap"`.
pub fn model_names() -> Vec<&'static str> {
    ModelKind::ALL
        .into_iter()
        .filter(|k| !matches!(k, ModelKind::Standard | ModelKind::Fisheye))
        .map(ModelKind::name)
        .chain(["colmap"])
        .collect()
}

/// NCore's rolling-shutter names (`shutter_type`), kept on an f-theta camera.
pub const SHUTTER_TYPES: [&str; 5] = [
    "ROLLING_TOP_TO_BOTTOM",
    "ROLLING_LEFT_TO_RIGHT",
    "ROLLING_BOTTOM_TO_TOP",
    "ROLLING_RIGHT_TO_LEFT",
    "GLOBAL",
];

/// A vklens JSON camera of model `model` (one of [`model_names`]).
pub fn camera_from_json(model: &str, obj: &Map<String, Value>) -> Result<Camera> {
    let width = dimension(obj, &["width", "image_width"])?;
    let height = dimension(obj, &["height", "image_height"])?;
    let num = |k: &str| number_field(obj, k);
    // A model whose parameters are named numbers reads them by the names its row lists.
    if let Some(kind) = ModelKind::from_name(model) {
        if let Some(names) = kind.scalar_params() {
            let values = names.iter().map(|n| num(n)).collect::<Result<Vec<f64>>>()?;
            if let Some(lens) = Lens::from_params(kind, &values) {
                let lens = lens?;
                return Camera::with_lens(width, height, pinhole_k(obj)?, lens)
                    .map_err(Error::from);
            }
        }
    }
    let (lens, intrinsics) = match model {
        "omni" => {
            let (key, d) = match obj.get("dist_coeffs") {
                Some(v) => ("dist_coeffs", number_list(v, "dist_coeffs")?),
                None => ("dist_coeffs", vec![0.0; 4]),
            };
            let d: [f64; 4] = d.as_slice().try_into().map_err(|_| {
                Error::input(format!(
                    "`{key}`: the omni model's radial-tangential part has 4 coefficients (k1 k2 p1 p2), this file has {}",
                    d.len()
                ))
            })?;
            (Lens::Omni(Omni::new(num("xi")?, d)?), pinhole_k(obj)?)
        }
        "thin_prism_fisheye" => {
            let list = |key: &str, n: usize| -> Result<Vec<f64>> {
                let v = number_list(required(obj, key)?, key)?;
                if v.len() != n {
                    return Err(Error::input(format!(
                        "`{key}` has {n} numbers, got {}",
                        v.len()
                    )));
                }
                Ok(v)
            };
            let radial = number_list(required(obj, "radial")?, "radial")?;
            let p = list("p", 2)?;
            let s = list("s", 4)?;
            let radial_first = flag(obj, "radial_first")?;
            let lens = ThinPrismFisheye::new(
                radial,
                [p[0], p[1]],
                [s[0], s[1], s[2], s[3]],
                radial_first,
            )?;
            (Lens::ThinPrismFisheye(lens), pinhole_k(obj)?)
        }
        "colmap" => {
            let name = match required(obj, "colmap_model")? {
                Value::String(s) => s.clone(),
                other => {
                    return Err(Error::input(format!(
                        "`colmap_model` must be a COLMAP model name, got {other}"
                    )))
                }
            };
            let params = number_list(required(obj, "params")?, "params")?;
            return colmap_camera(&name, width, height, &params);
        }
        "equirectangular" => {
            let k = if obj.contains_key("fx") || obj.contains_key("camera_matrix") {
                pinhole_k(obj)?
            } else {
                let [fx, fy, cx, cy] = Equirectangular::full_sphere(width, height);
                Intrinsics { fx, fy, cx, cy }
            };
            (Lens::Equirectangular(Equirectangular), k)
        }
        "ftheta" => (Lens::FTheta(ftheta_from(obj)?), centre_only(obj)?),
        "ocam" => {
            let poly = number_list(required(obj, "poly")?, "poly")?;
            let inverse = match obj.get("inverse_poly") {
                Some(v) => number_list(v, "inverse_poly")?,
                None => Vec::new(),
            };
            let k = centre_only(obj)?;
            let lens = Ocam::new(
                poly,
                inverse,
                [num("c")?, num("d")?, num("e")?],
                corner_radius(width, height, &k),
            )?
            .with_fitted_inverse(flag(obj, "fitted_inverse")?)?;
            (Lens::Ocam(lens), k)
        }
        other => {
            return Err(Error::input(format!(
                "`model` is `{other}`, which this reader does not know"
            )))
        }
    };
    Camera::with_lens(width, height, intrinsics, lens).map_err(Error::from)
}

/// An optional true/false key (absent: false).
fn flag(obj: &Map<String, Value>, key: &str) -> Result<bool> {
    match obj.get(key) {
        None => Ok(false),
        Some(Value::Bool(b)) => Ok(*b),
        Some(other) => Err(Error::input(format!(
            "`{key}` must be true or false, got {other}"
        ))),
    }
}

fn required<'a>(obj: &'a Map<String, Value>, key: &str) -> Result<&'a Value> {
    obj.get(key)
        .ok_or_else(|| Error::input(format!("missing field `{key}`")))
}

/// fx fy cx cy (or a camera matrix without skew).
fn pinhole_k(obj: &Map<String, Value>) -> Result<Intrinsics> {
    intrinsics_from(obj, false).map(|(k, _)| k)
}

/// The models whose own parameters carry the scale (f-theta, OCamCalib): cx cy only, and
/// unit focal lengths (the model's distorted point is in pixels).
fn centre_only(obj: &Map<String, Value>) -> Result<Intrinsics> {
    for key in ["fx", "fy"] {
        if obj.contains_key(key) {
            return Err(Error::input(format!(
                "`{key}` is not a parameter of this model: its polynomials map angles to pixel distances directly"
            )));
        }
    }
    Ok(Intrinsics {
        fx: 1.0,
        fy: 1.0,
        cx: number_field(obj, "cx")?,
        cy: number_field(obj, "cy")?,
    })
}

/// The largest distance from the principal point that a pixel of the image reaches (its
/// corners, pixel edges included).
fn corner_radius(width: u32, height: u32, k: &Intrinsics) -> f64 {
    let xs = [-0.5 - k.cx, width as f64 - 0.5 - k.cx];
    let ys = [-0.5 - k.cy, height as f64 - 0.5 - k.cy];
    xs.iter()
        .flat_map(|x| ys.iter().map(move |y| x.hypot(*y)))
        .fold(0.0, f64::max)
}

fn ftheta_from(obj: &Map<String, Value>) -> Result<FTheta> {
    let reference = match required(obj, "reference_poly")? {
        Value::String(s) => Reference::parse(s).ok_or_else(|| {
            Error::input(format!(
                "`reference_poly` is `{s}`; NCore spells it `PIXELDIST_TO_ANGLE` or `ANGLE_TO_PIXELDIST`"
            ))
        })?,
        other => {
            return Err(Error::input(format!(
                "`reference_poly` must be a string (`PIXELDIST_TO_ANGLE` or `ANGLE_TO_PIXELDIST`), got {other}"
            )))
        }
    };
    let poly = |key: &str| -> Result<Vec<f64>> {
        match obj.get(key) {
            Some(v) => number_list(v, key),
            None => Ok(Vec::new()),
        }
    };
    let cde = match obj.get("linear_cde") {
        Some(v) => {
            let l = number_list(v, "linear_cde")?;
            <[f64; 3]>::try_from(l.as_slice()).map_err(|_| {
                Error::input(format!(
                    "`linear_cde` has 3 numbers [c, d, e], got {}",
                    l.len()
                ))
            })?
        }
        None => [1.0, 0.0, 0.0],
    };
    let mut lens = FTheta::new(
        reference,
        poly("pixeldist_to_angle_poly")?,
        poly("angle_to_pixeldist_poly")?,
        cde,
        number_field(obj, "max_angle")?,
    )?
    .with_fitted_inverse(flag(obj, "fitted_inverse")?)?;
    lens.shutter_type = match obj.get("shutter_type") {
        None | Some(Value::Null) => None,
        Some(Value::String(s)) if SHUTTER_TYPES.contains(&s.as_str()) => Some(s.clone()),
        Some(other) => {
            return Err(Error::input(format!(
                "`shutter_type` is {other}; NCore's are {}",
                SHUTTER_TYPES.join(", ")
            )))
        }
    };
    Ok(lens)
}

/// NCore's camera JSON (`{"camera_model_type": "ftheta", "camera_model_parameters": {...}}`).
pub fn ncore_camera(tree: &Value) -> Option<Result<Camera>> {
    let kind = tree.get("camera_model_type")?;
    Some((|| {
        if kind.as_str() != Some("ftheta") {
            return Err(Error::input(format!(
                "`camera_model_type` is {kind}; vklens reads NCore's `ftheta` cameras from this layout (its OpenCV cameras as OpenCV files)"
            )));
        }
        let params = tree
            .get("camera_model_parameters")
            .and_then(Value::as_object)
            .ok_or_else(|| Error::input("missing object `camera_model_parameters`"))?;
        if params
            .get("external_distortion_parameters")
            .is_some_and(|v| !v.is_null())
        {
            return Err(Error::unsupported(
                "`external_distortion_parameters` (NCore's windshield distortion) is not a model vklens has: refusing rather than ignoring it",
            ));
        }
        let res = number_list(required(params, "resolution")?, "resolution")?;
        let pp = number_list(required(params, "principal_point")?, "principal_point")?;
        let (&[w, h], &[cx, cy]) = (res.as_slice(), pp.as_slice()) else {
            return Err(Error::input(
                "`resolution` and `principal_point` each have two numbers",
            ));
        };
        let mut obj = params.clone();
        obj.insert("width".into(), json!(w));
        obj.insert("height".into(), json!(h));
        obj.insert("cx".into(), json!(cx));
        obj.insert("cy".into(), json!(cy));
        camera_from_json("ftheta", &obj)
    })())
}

/// OCamCalib's `calib_results.txt`: comment lines (`#`) and blank lines between five data
/// lines — `pol` (its length first), `invpol` (likewise), `xc yc` (row, column centre),
/// `c d e`, `height width`.
pub fn looks_like_ocam(text: &str) -> bool {
    text.lines().next().is_some_and(|l| {
        l.trim_start()
            .starts_with("#polynomial coefficients for the DIRECT mapping function")
    })
}

/// The camera of an OCamCalib `calib_results.txt`.
pub fn ocam_camera(text: &str) -> Result<Camera> {
    let lines: Vec<Vec<f64>> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(|l| {
            l.split_whitespace()
                .map(|t| {
                    parse_float(t).ok_or_else(|| {
                        Error::input(format!("`{t}` is not a number (in line `{l}`)"))
                    })
                })
                .collect::<Result<Vec<f64>>>()
        })
        .collect::<Result<_>>()?;
    let what = ["pol", "invpol", "xc yc", "c d e", "height width"];
    if lines.len() < what.len() {
        return Err(Error::input(format!(
            "an OCamCalib calib_results.txt has 5 data lines ({}), this one has {}",
            what.join("; "),
            lines.len()
        )));
    }
    let counted = |i: usize| -> Result<Vec<f64>> {
        let l = &lines[i];
        let n = l.first().copied().unwrap_or(-1.0);
        if !(n.fract() == 0.0 && n >= 1.0 && (n as usize) == l.len() - 1) {
            return Err(Error::input(format!(
                "the `{}` line must start with its number of coefficients, then that many: {l:?}",
                what[i]
            )));
        }
        Ok(l[1..].to_vec())
    };
    let pair = |i: usize, n: usize| -> Result<&[f64]> {
        let l = &lines[i];
        if l.len() != n {
            return Err(Error::input(format!(
                "the `{}` line must have {n} numbers, got {l:?}",
                what[i]
            )));
        }
        Ok(l)
    };
    let (pol, invpol) = (counted(0)?, counted(1)?);
    let centre = pair(2, 2)?;
    let cde = pair(3, 3)?;
    let size = pair(4, 2)?;
    let mut obj = Map::new();
    obj.insert("model".into(), json!("ocam"));
    obj.insert("height".into(), json!(size[0]));
    obj.insert("width".into(), json!(size[1]));
    // Rows first: xc is the row centre (vklens cy), yc the column centre (cx).
    obj.insert("cy".into(), json!(centre[0]));
    obj.insert("cx".into(), json!(centre[1]));
    obj.insert("poly".into(), json!(pol));
    obj.insert("inverse_poly".into(), json!(invpol));
    for (k, v) in ["c", "d", "e"].into_iter().zip(cde) {
        obj.insert(k.into(), json!(v));
    }
    camera_from_json("ocam", &obj)
}

/// The vklens JSON of a camera of one of these models (`None` for OpenCV's two and Brown's).
pub fn camera_to_json(camera: &Camera) -> Option<Value> {
    let k = camera.intrinsics;
    let mut v = json!({
        "model": camera.model_name(), "width": camera.width, "height": camera.height,
    });
    let pinhole = |v: &mut Value| {
        v["fx"] = k.fx.into();
        v["fy"] = k.fy.into();
        v["cx"] = k.cx.into();
        v["cy"] = k.cy.into();
    };
    match camera.lens() {
        Lens::Standard { .. } | Lens::Fisheye(_) => return None,
        Lens::Omni(m) => {
            pinhole(&mut v);
            v["xi"] = m.xi.into();
            v["dist_coeffs"] = json!(m.dist_coeffs());
        }
        Lens::FTheta(m) => {
            v["cx"] = k.cx.into();
            v["cy"] = k.cy.into();
            v["reference_poly"] = m.reference.name().into();
            v["pixeldist_to_angle_poly"] = json!(m.pixeldist_to_angle);
            v["angle_to_pixeldist_poly"] = json!(m.angle_to_pixeldist);
            v["linear_cde"] = json!(m.linear_cde);
            v["max_angle"] = m.max_angle.into();
            if let Some(s) = &m.shutter_type {
                v["shutter_type"] = s.as_str().into();
            }
            if m.fitted_inverse() {
                v["fitted_inverse"] = true.into();
            }
        }
        Lens::ThinPrismFisheye(m) => {
            pinhole(&mut v);
            v["radial"] = json!(m.radial);
            v["p"] = json!(m.p);
            v["s"] = json!(m.s);
            v["radial_first"] = m.radial_first.into();
        }
        Lens::Ocam(m) => {
            v["cx"] = k.cx.into();
            v["cy"] = k.cy.into();
            v["poly"] = json!(m.poly);
            v["inverse_poly"] = json!(m.inverse_poly);
            for (name, c) in ["c", "d", "e"].into_iter().zip(m.cde) {
                v[name] = c.into();
            }
            if m.fitted_inverse() {
                v["fitted_inverse"] = true.into();
            }
        }
        lens => {
            pinhole(&mut v);
            for (name, value) in lens.params() {
                v[name] = value.into();
            }
        }
    }
    Some(v)
}

/// camodocal's (and VINS-Fusion's) camera YAML: `model_type: MEI | PINHOLE | KANNALA_BRANDT`
/// with its own parameter names.
pub fn camodocal_camera(tree: &Value) -> Option<Result<Camera>> {
    let kind = tree.get("model_type")?;
    let obj = tree.as_object()?;
    Some((|| {
        let group = |key: &str| -> Result<&Map<String, Value>> {
            obj.get(key)
                .and_then(Value::as_object)
                .ok_or_else(|| Error::input(format!("missing mapping `{key}`")))
        };
        let num = |g: &Map<String, Value>, key: &str| number_field(g, key);
        let width = dimension(obj, &["image_width"])?;
        let height = dimension(obj, &["image_height"])?;
        let kind = kind.as_str().unwrap_or_default();
        let (intrinsics, lens) = match kind {
            "MEI" => {
                let p = group("projection_parameters")?;
                let d = group("distortion_parameters")?;
                let xi = num(group("mirror_parameters")?, "xi")?;
                let k = Intrinsics {
                    fx: num(p, "gamma1")?,
                    fy: num(p, "gamma2")?,
                    cx: num(p, "u0")?,
                    cy: num(p, "v0")?,
                };
                let c = [num(d, "k1")?, num(d, "k2")?, num(d, "p1")?, num(d, "p2")?];
                (k, Lens::Omni(Omni::new(xi, c)?))
            }
            "PINHOLE" => {
                let p = group("projection_parameters")?;
                let d = group("distortion_parameters")?;
                let k = Intrinsics {
                    fx: num(p, "fx")?,
                    fy: num(p, "fy")?,
                    cx: num(p, "cx")?,
                    cy: num(p, "cy")?,
                };
                let c = [num(d, "k1")?, num(d, "k2")?, num(d, "p1")?, num(d, "p2")?];
                return Camera::from_coeffs(width, height, k, &c).map_err(Error::from);
            }
            "KANNALA_BRANDT" => {
                // camodocal's k2..k5 are OpenCV's fisheye k1..k4 (its θ series starts at θ³).
                let p = group("projection_parameters")?;
                let k = Intrinsics {
                    fx: num(p, "mu")?,
                    fy: num(p, "mv")?,
                    cx: num(p, "u0")?,
                    cy: num(p, "v0")?,
                };
                let c = [num(p, "k2")?, num(p, "k3")?, num(p, "k4")?, num(p, "k5")?];
                (k, Lens::Fisheye(crate::model::Fisheye::new(c, 0.0, None)?))
            }
            // camodocal's OCAMCamera (`ScaramuzzaCamera.cc`, which writes `scaramuzza` and
            // compares the name without case). `poly_parameters` and `inv_poly_parameters` are
            // `p0, p1, …`, ascending, OCamCalib's `pol` and `invpol`. Unlike OCamCalib, its
            // image point is x (column) first: `cx` is subtracted from the column, `cy` from
            // the row, and its `spaceToPlane` applies the affine term to (column, row):
            //   (u − cx, v − cy) = [[ac, ad], [ae, 1]] · (X, Y)/|(X, Y)| · ρ.
            // In OCamCalib's row-first order that is
            //   (v − cy, u − cx) = ac · [[1/ac, ae/ac], [ad/ac, 1]] · (Y, X)/|(X, Y)| · ρ:
            // OCamCalib's model with c = 1/ac, d = ae/ac, e = ad/ac, centre (row cy, column
            // cx) and every radius ac·ρ, so pol_i becomes ac^(1−i)·p_i and invpol_i ac·p_i.
            // With ac = 1, ad = ae = 0 (the usual file) the parameters carry over unchanged,
            // the same `Ocam` as the calib_results.txt they came from.
            s if s.eq_ignore_ascii_case("SCARAMUZZA") => {
                let series = |key: &str| -> Result<Vec<f64>> {
                    let g = group(key)?;
                    let mut p = Vec::new();
                    while let Some(v) = g.get(&format!("p{}", p.len())) {
                        p.push(super::camera::as_number(v).ok_or_else(|| {
                            Error::input(format!(
                                "`{key}.p{}` must be a number, got {v}",
                                p.len()
                            ))
                        })?);
                    }
                    if p.is_empty() {
                        return Err(Error::input(format!("missing `{key}.p0`")));
                    }
                    if let Some(extra) = g.keys().find(|k| {
                        k.strip_prefix('p')
                            .and_then(|i| i.parse::<usize>().ok())
                            .is_none_or(|i| i >= p.len())
                    }) {
                        return Err(Error::input(format!(
                            "`{key}` has `{extra}` beside p0..p{}: camodocal's are p0, p1, … with none missing",
                            p.len() - 1
                        )));
                    }
                    Ok(p)
                };
                let a = group("affine_parameters")?;
                let [ac, ad, ae] = [num(a, "ac")?, num(a, "ad")?, num(a, "ae")?];
                if !(ac.is_finite() && ac > 0.0) {
                    return Err(Error::input(format!(
                        "`affine_parameters.ac` is {ac}: it scales the image radius, and must be a positive number"
                    )));
                }
                let poly: Vec<f64> = series("poly_parameters")?
                    .into_iter()
                    .enumerate()
                    .map(|(i, p)| p * ac.powi(1 - i as i32))
                    .collect();
                let inverse: Vec<f64> = series("inv_poly_parameters")?
                    .into_iter()
                    .map(|p| p * ac)
                    .collect();
                let mut o = Map::new();
                o.insert("model".into(), json!("ocam"));
                o.insert("width".into(), json!(width));
                o.insert("height".into(), json!(height));
                o.insert("cx".into(), json!(num(a, "cx")?));
                o.insert("cy".into(), json!(num(a, "cy")?));
                o.insert("poly".into(), json!(poly));
                o.insert("inverse_poly".into(), json!(inverse));
                o.insert("c".into(), json!(1.0 / ac));
                o.insert("d".into(), json!(ae / ac));
                o.insert("e".into(), json!(ad / ac));
                return camera_from_json("ocam", &o);
            }
            other => {
                return Err(Error::input(format!(
                    "`model_type` is `{other}`; vklens reads camodocal's MEI, PINHOLE, KANNALA_BRANDT and SCARAMUZZA"
                )))
            }
        };
        Camera::with_lens(width, height, intrinsics, lens).map_err(Error::from)
    })())
}

/// Basalt's calibration JSON (`value0.intrinsics[i].camera_type`, `value0.resolution[i]`):
/// camera `index` (default 0).
/// How many cameras a Basalt calibration holds, if the tree is one.
pub fn basalt_camera_count(tree: &Value) -> Option<usize> {
    Some(tree.get("value0")?.get("intrinsics")?.as_array()?.len())
}

pub fn basalt_camera(tree: &Value, index: Option<usize>) -> Option<Result<Camera>> {
    let root = tree.get("value0")?;
    let cams = root.get("intrinsics")?.as_array()?;
    Some((|| {
        let i = index.unwrap_or(0);
        let cam = cams.get(i).ok_or_else(|| {
            Error::input(format!(
                "camera index {i} asked, but this Basalt calibration holds {} camera(s)",
                cams.len()
            ))
        })?;
        let res = root
            .get("resolution")
            .and_then(Value::as_array)
            .and_then(|r| r.get(i))
            .ok_or_else(|| Error::input(format!("missing `value0.resolution[{i}]`")))?;
        let res = number_list(res, "resolution")?;
        let &[w, h] = res.as_slice() else {
            return Err(Error::input(format!(
                "`value0.resolution[{i}]` has two numbers [width, height]"
            )));
        };
        let kind = cam
            .get("camera_type")
            .and_then(Value::as_str)
            .ok_or_else(|| Error::input(format!("missing `value0.intrinsics[{i}].camera_type`")))?;
        let p = cam
            .get("intrinsics")
            .and_then(Value::as_object)
            .ok_or_else(|| Error::input(format!("missing `value0.intrinsics[{i}].intrinsics`")))?;
        let mut obj = p.clone();
        obj.insert("width".into(), json!(w));
        obj.insert("height".into(), json!(h));
        let model = match kind {
            "ds" => "double_sphere",
            "eucm" | "ucm" => kind,
            "fov" => {
                let omega = number_field(p, "w")?;
                obj.insert("omega".into(), json!(omega));
                "fov"
            }
            "pinhole" | "kb4" | "pinhole-radtan8" => {
                let k = pinhole_k(p)?;
                let (w, h) = (
                    super::camera::image_side_of(w, "width")?,
                    super::camera::image_side_of(h, "height")?,
                );
                let n = |key: &str| number_field(p, key);
                return match kind {
                    "pinhole" => Camera::from_coeffs(w, h, k, &[0.0; 4]),
                    "kb4" => crate::model::Fisheye::new(
                        [n("k1")?, n("k2")?, n("k3")?, n("k4")?],
                        0.0,
                        None,
                    )
                    .and_then(|f| Camera::fisheye(w, h, k, f)),
                    // Basalt's rpmax bounds the radius of the undistorted normalized
                    // point its projection accepts (0: none); vklens's domain ends there too.
                    _ => {
                        let rpmax = match p.get("rpmax") {
                            None => 0.0,
                            Some(_) => n("rpmax")?,
                        };
                        if !(rpmax >= 0.0 && rpmax.is_finite()) {
                            return Err(Error::input(format!(
                                "`value0.intrinsics[{i}].intrinsics.rpmax` must be ≥ 0 (0: no limit), got {rpmax}"
                            )));
                        }
                        Camera::from_coeffs(
                            w,
                            h,
                            k,
                            &[
                                n("k1")?,
                                n("k2")?,
                                n("p1")?,
                                n("p2")?,
                                n("k3")?,
                                n("k4")?,
                                n("k5")?,
                                n("k6")?,
                            ],
                        )
                        .and_then(|c| {
                            if rpmax > 0.0 {
                                c.with_max_radius(rpmax)
                            } else {
                                Ok(c)
                            }
                        })
                    }
                }
                .map_err(Error::from);
            }
            other => {
                return Err(Error::input(format!(
                    "`value0.intrinsics[{i}].camera_type` is `{other}`; vklens reads Basalt's pinhole, ds, eucm, ucm, kb4, fov and pinhole-radtan8"
                )))
            }
        };
        camera_from_json(model, &obj)
    })())
}

/// COLMAP's camera models vklens reads: name and parameter names, in COLMAP's order
/// (`src/colmap/sensor/models.h`).
pub const COLMAP_MODELS: [(&str, &[&str]); 18] = [
    ("SIMPLE_PINHOLE", &["f", "cx", "cy"]),
    ("PINHOLE", &["fx", "fy", "cx", "cy"]),
    ("SIMPLE_RADIAL", &["f", "cx", "cy", "k"]),
    ("RADIAL", &["f", "cx", "cy", "k1", "k2"]),
    ("OPENCV", &["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"]),
    (
        "FULL_OPENCV",
        &[
            "fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6",
        ],
    ),
    (
        "OPENCV_FISHEYE",
        &["fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"],
    ),
    ("FOV", &["fx", "fy", "cx", "cy", "omega"]),
    ("SIMPLE_RADIAL_FISHEYE", &["f", "cx", "cy", "k"]),
    ("RADIAL_FISHEYE", &["f", "cx", "cy", "k1", "k2"]),
    ("SIMPLE_DIVISION", &["f", "cx", "cy", "k"]),
    ("DIVISION", &["fx", "fy", "cx", "cy", "k"]),
    ("SIMPLE_FISHEYE", &["f", "cx", "cy"]),
    ("FISHEYE", &["fx", "fy", "cx", "cy"]),
    ("EUCM", &["fx", "fy", "cx", "cy", "alpha", "beta"]),
    ("EQUIRECTANGULAR", &["w", "h"]),
    (
        "THIN_PRISM_FISHEYE",
        &[
            "fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "sx1", "sy1",
        ],
    ),
    (
        "RAD_TAN_THIN_PRISM_FISHEYE",
        &[
            "fx", "fy", "cx", "cy", "k0", "k1", "k2", "k3", "k4", "k5", "p0", "p1", "s0", "s1",
            "s2", "s3",
        ],
    ),
];

/// The camera of COLMAP model `model` with COLMAP's `params` (its pixel centres at +0.5,
/// moved to OpenCV's 0). Errors name the model and the parameter.
pub fn colmap_camera(model: &str, width: u32, height: u32, p: &[f64]) -> Result<Camera> {
    let (_, names) = COLMAP_MODELS
        .iter()
        .find(|(m, _)| *m == model)
        .ok_or_else(|| {
            Error::input(format!(
                "COLMAP model `{model}` is not one vklens reads ({})",
                COLMAP_MODELS.map(|m| m.0).join(", ")
            ))
        })?;
    if p.len() != names.len() {
        return Err(Error::input(format!(
            "{model} has {} parameters ({}), got {}",
            names.len(),
            names.join(" "),
            p.len()
        )));
    }
    let named = |e: crate::model::ModelError| Error::input(format!("{model}: {e}"));
    if model == "EQUIRECTANGULAR" {
        // Its parameters are the panorama's size; COLMAP's x = (lon/2π + 0.5) W.
        let (w, h) = (p[0], p[1]);
        for (name, v) in [("w", w), ("h", h)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::input(format!(
                    "{model} parameter `{name}` must be a positive size, got {v}"
                )));
            }
        }
        let k = Intrinsics {
            fx: w / (2.0 * std::f64::consts::PI),
            fy: h / std::f64::consts::PI,
            cx: w / 2.0 - 0.5,
            cy: h / 2.0 - 0.5,
        };
        return Camera::with_lens(width, height, k, Lens::Equirectangular(Equirectangular))
            .map_err(named);
    }
    let (fx, fy, c) = if names[0] == "f" {
        (p[0], p[0], 1)
    } else {
        (p[0], p[1], 2)
    };
    let k = Intrinsics {
        fx,
        fy,
        cx: p[c] - 0.5,
        cy: p[c + 1] - 0.5,
    };
    let rest = &p[c + 2..];
    let lens = match model {
        "SIMPLE_PINHOLE" | "PINHOLE" | "SIMPLE_RADIAL" | "RADIAL" | "OPENCV" | "FULL_OPENCV" => {
            let mut opencv = vec![0.0; 4.max(rest.len())];
            opencv[..rest.len()].copy_from_slice(rest);
            return Camera::from_coeffs(width, height, k, &opencv).map_err(named);
        }
        "OPENCV_FISHEYE"
        | "SIMPLE_RADIAL_FISHEYE"
        | "RADIAL_FISHEYE"
        | "SIMPLE_FISHEYE"
        | "FISHEYE" => {
            let mut c = [0.0; 4];
            c[..rest.len()].copy_from_slice(rest);
            Lens::Fisheye(crate::model::Fisheye::new(c, 0.0, None).map_err(named)?)
        }
        "FOV" => Lens::Fov(Fov::new(rest[0]).map_err(named)?),
        "SIMPLE_DIVISION" | "DIVISION" => Lens::Division(Division::new(rest[0]).map_err(named)?),
        "EUCM" => Lens::Eucm(Eucm::new(rest[0], rest[1]).map_err(named)?),
        // k1 k2 p1 p2 k3 k4 sx1 sy1: radial k1..k4, thin prism sx1 sy1 (OpenCV's s1 s3).
        "THIN_PRISM_FISHEYE" => Lens::ThinPrismFisheye(
            ThinPrismFisheye::new(
                vec![rest[0], rest[1], rest[4], rest[5]],
                [rest[2], rest[3]],
                [rest[6], 0.0, rest[7], 0.0],
                false,
            )
            .map_err(named)?,
        ),
        // k0..k5 p0 p1 s0..s3: COLMAP's p0 is OpenCV's p2, its p1 OpenCV's p1.
        "RAD_TAN_THIN_PRISM_FISHEYE" => Lens::ThinPrismFisheye(
            ThinPrismFisheye::new(
                rest[..6].to_vec(),
                [rest[7], rest[6]],
                [rest[8], rest[9], rest[10], rest[11]],
                true,
            )
            .map_err(named)?,
        ),
        _ => {
            return Err(Error::input(format!(
                "COLMAP model `{model}` is not one vklens reads"
            )))
        }
    };
    Camera::with_lens(width, height, k, lens).map_err(named)
}

#[cfg(test)]
mod scaramuzza_tests {
    use glam::DVec3;
    use serde_json::{json, Value};

    use super::*;

    const POL: [f64; 5] = [-250.0, 0.0, 1.2e-3, -1.0e-6, 2.0e-9];
    const INVPOL: [f64; 6] = [300.0, 200.0, 10.0, 5.0, 1.0, 0.5];

    fn camodocal(name: &str, affine: [f64; 3]) -> Value {
        let series = |p: &[f64]| -> Value {
            Value::Object(
                p.iter()
                    .enumerate()
                    // camodocal's YAML numbers arrive as text.
                    .map(|(i, v)| (format!("p{i}"), json!(format!("{v:e}"))))
                    .collect(),
            )
        };
        json!({
            "model_type": name,
            "camera_name": "cam0",
            "image_width": 1280,
            "image_height": 960,
            "poly_parameters": series(&POL),
            "inv_poly_parameters": series(&INVPOL),
            "affine_parameters": {
                "ac": affine[0], "ad": affine[1], "ae": affine[2],
                "cx": "640.5", "cy": "480.25"
            }
        })
    }

    const RAYS: [DVec3; 4] = [
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(0.3, -0.2, 1.0),
        DVec3::new(-0.6, 0.5, 1.0),
        DVec3::new(1.0, 0.4, 0.7),
    ];

    #[test]
    fn identity_affine_is_the_calib_results_camera() {
        // The same calibration as OCamCalib writes it: rows first (xc = row, yc = column).
        let text = "#polynomial coefficients for the DIRECT mapping function\n5 -250 0 1.2e-3 -1e-6 2e-9\n\n#polynomial coefficients for the inverse mapping function\n6 300 200 10 5 1 0.5\n\n#center: \"row\" and \"column\", starting from 0 (C convention)\n480.25 640.5\n\n#affine parameters \"c\", \"d\", \"e\"\n1 0 0\n\n#image size: \"height\" and \"width\"\n960 1280\n";
        let want = ocam_camera(text).expect("calib_results");
        for name in ["SCARAMUZZA", "scaramuzza"] {
            let got = camodocal_camera(&camodocal(name, [1.0, 0.0, 0.0]))
                .expect("detected")
                .expect("loads");
            assert_eq!((got.width, got.height), (1280, 960));
            assert_eq!(got.intrinsics, want.intrinsics);
            assert_eq!(got.lens(), want.lens());
            for p in RAYS {
                let (a, b) = (got.project(p), want.project(p));
                assert!(a.is_some());
                assert_eq!(a, b, "{p}");
            }
        }
    }

    #[test]
    fn affine_term_is_applied_to_column_then_row() {
        // camodocal's spaceToPlane: (u − cx, v − cy) = A·(X, Y)/|(X, Y)|·φ, A = [[ac, ad],
        // [ae, 1]], with φ the radius whose ray (φ, −pol(φ)) makes the point's angle.
        let (ac, ad, ae) = (1.002, 0.003, -0.004);
        let c = camodocal_camera(&camodocal("SCARAMUZZA", [ac, ad, ae]))
            .expect("detected")
            .expect("loads");
        let pol = |r: f64| POL.iter().rev().fold(0.0, |acc, p| acc * r + p);
        for p in RAYS {
            let px = c.project(p).expect("in the domain");
            let (du, dv) = (px.x - 640.5, px.y - 480.25);
            let det = ac - ad * ae;
            let (x, y) = ((du - ad * dv) / det, (-ae * du + ac * dv) / det);
            let phi = x.hypot(y);
            let angle = phi.atan2(-pol(phi));
            let want = p.x.hypot(p.y).atan2(p.z);
            assert!((angle - want).abs() < 1e-9, "{p}: {angle} vs {want}");
            if phi > 0.0 {
                let dir = p.x.hypot(p.y);
                assert!((x / phi - p.x / dir).abs() < 1e-9, "{p}");
                assert!((y / phi - p.y / dir).abs() < 1e-9, "{p}");
            }
        }
    }

    #[test]
    fn missing_and_bad_parameters_are_named() {
        let mut t = camodocal("SCARAMUZZA", [1.0, 0.0, 0.0]);
        t["poly_parameters"]
            .as_object_mut()
            .expect("object")
            .remove("p0");
        let e = camodocal_camera(&t).expect("detected").expect_err("no p0");
        assert!(e.to_string().contains("poly_parameters.p0"), "{e}");
        let mut t = camodocal("SCARAMUZZA", [1.0, 0.0, 0.0]);
        t["inv_poly_parameters"]
            .as_object_mut()
            .expect("object")
            .remove("p2");
        let e = camodocal_camera(&t).expect("detected").expect_err("gap");
        assert!(e.to_string().contains("inv_poly_parameters"), "{e}");
        let t = camodocal("SCARAMUZZA", [0.0, 0.0, 0.0]);
        let e = camodocal_camera(&t).expect("detected").expect_err("ac = 0");
        assert!(e.to_string().contains("ac"), "{e}");
        let mut t = camodocal("SCARAMUZZA", [1.0, 0.0, 0.0]);
        t.as_object_mut()
            .expect("object")
            .remove("affine_parameters");
        let e = camodocal_camera(&t)
            .expect("detected")
            .expect_err("no affine");
        assert!(e.to_string().contains("affine_parameters"), "{e}");
    }
}
