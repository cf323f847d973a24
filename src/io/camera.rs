//! Camera files as users bring them, all read into one [`Camera`]:
//!
//! * vklens JSON: `{"width", "height", "fx", "fy", "cx", "cy", "dist_coeffs": [...]}`;
//!   unknown keys are ignored (the cases of the shared reference file load as they stand).
//!   `"model": "opencv_fisheye"` makes it OpenCV's fisheye model: `dist_coeffs` are k1..k4,
//!   and `alpha` (skew) and `max_fov_deg` (field of view, full angle) are optional.
//! * OpenCV `FileStorage` as `calibrateCamera` samples write it — YAML (with the `%YAML:1.0`
//!   header of OpenCV 3/4 that strict YAML parsers reject, or `%YAML 1.2`), XML and JSON:
//!   `camera_matrix` and `distortion_coefficients` as `opencv-matrix`, `image_width`,
//!   `image_height`.
//! * ROS `camera_info` YAML (`plumb_bob`, `rational_polynomial`; `equidistant` and `fisheye`
//!   for the fisheye model, with the skew as `K[0][1] = α fx`).
//! * A Kalibr camchain (`cam0:`, `cam1:` … with `camera_model: pinhole`,
//!   `distortion_model: equidistant` or `radtan`, `intrinsics: [fu, fv, pu, pv]`,
//!   `resolution: [w, h]`): the first camera, or the one `index` names.
//! * COLMAP `cameras.txt` (`SIMPLE_PINHOLE`, `PINHOLE`, `SIMPLE_RADIAL`, `RADIAL`, `OPENCV`,
//!   `FULL_OPENCV`, `OPENCV_FISHEYE`, `SIMPLE_RADIAL_FISHEYE`, `RADIAL_FISHEYE`): COLMAP puts
//!   pixel centres at 0.5, OpenCV (and vklens) at 0, so `cx` and `cy` lose 0.5 on the way in.
//!
//! * A Brown radial lens (the Durham radial-correction paper): `{"model": "brown", "width", "height", "c1", "c2"}`.
//!
//! Every format but COLMAP's text is first turned into a JSON tree, then read by one function,
//! so every format gets the same checks and the same error messages (file, field, value).

use std::path::Path;

use serde_json::{Map, Value};

use super::catalog::{self, Found, Listing, LoadOptions};
use crate::model::double_sphere::DoubleSphere;
use crate::model::eucm::Eucm;
use crate::model::fov::Fov;
use crate::model::omni::Omni;
use crate::model::{BrownRadial, Camera, Fisheye, Intrinsics, Lens, ModelError};
use crate::{Error, Result};

/// The format name of a Kalibr camchain.
pub const KALIBR_FORMAT: &str = "Kalibr camchain";

/// Reads a camera file (format detected from its content). A Brown lens file gives a camera
/// that remembers it ([`Camera::brown`]).
pub fn load_camera(path: &Path) -> Result<Camera> {
    load_camera_with(path, &LoadOptions::default())
}

/// Reads camera `index` (0-based) of a file that holds several (a Kalibr camchain, a COLMAP
/// `cameras.txt`); `None` is the first. A file of one camera accepts only `None` or 0.
pub fn load_camera_at(path: &Path, index: Option<usize>) -> Result<Camera> {
    load_camera_with(
        path,
        &LoadOptions {
            index,
            ..LoadOptions::default()
        },
    )
}

/// Reads the camera of a file that `options` ask for (index, name, size).
pub fn load_camera_with(path: &Path, options: &LoadOptions) -> Result<Camera> {
    let text =
        super::read_text(path).map_err(|e| Error::io(path, "cannot read camera file", &e))?;
    parse_camera_with(&text, &path.display().to_string(), options)
}

/// Every camera of a file, each loaded or with why it cannot be; `size` is the image size for
/// a file that gives none.
pub fn list_camera_file(path: &Path, size: Option<(u32, u32)>) -> Result<Listing> {
    let text =
        super::read_text(path).map_err(|e| Error::io(path, "cannot read camera file", &e))?;
    list_cameras(&text, &path.display().to_string(), size)
}

/// Parses the text of a camera file; `origin` names it in errors.
pub fn parse_camera(text: &str, origin: &str) -> Result<Camera> {
    parse_camera_with(text, origin, &LoadOptions::default())
}

/// [`parse_camera`] for camera `index` of a file that holds several.
pub fn parse_camera_at(text: &str, origin: &str, index: Option<usize>) -> Result<Camera> {
    parse_camera_with(
        text,
        origin,
        &LoadOptions {
            index,
            ..LoadOptions::default()
        },
    )
}

/// [`parse_camera`] for the camera `options` ask for.
pub fn parse_camera_with(text: &str, origin: &str, options: &LoadOptions) -> Result<Camera> {
    let listing = list_cameras(text, origin, options.size)?;
    catalog::select(listing, options).map_err(|e| e.context(origin))
}

/// Every camera of a file's text (format detected from the content); `origin` names the file
/// in errors.
pub fn list_cameras(text: &str, origin: &str, size: Option<(u32, u32)>) -> Result<Listing> {
    let err = |e: Error| e.context(origin);
    // Real files mix line ends (CRLF, and a lone CR from old Mac editors): one kind from here.
    let text = text.replace("\r\n", "\n").replace('\r', "\n");
    let trimmed = text.trim_start_matches('\u{feff}').trim_start();
    if super::models::looks_like_ocam(trimmed) {
        return Ok(Listing::one(
            "OCamCalib calib_results.txt",
            "",
            super::models::ocam_camera(trimmed),
        ));
    }
    if looks_like_colmap(trimmed) {
        return Ok(colmap_listing(trimmed));
    }
    if let Some(listing) = super::dso::listing_from_text(trimmed, size) {
        return Ok(listing);
    }
    Ok(listing_from_tree(
        &parse_tree(trimmed, origin).map_err(err)?,
        size,
    ))
}

/// A JSON, XML or YAML file's text as a tree, its line ends normalized and a BOM and leading
/// blanks trimmed first, as every camera file's are; the format from the content, or `.json`
/// in `origin`.
pub(super) fn text_tree(text: &str, origin: &str) -> Result<Value> {
    let text = text.replace("\r\n", "\n").replace('\r', "\n");
    parse_tree(text.trim_start_matches('\u{feff}').trim_start(), origin)
}

/// A JSON, XML or YAML camera file's text (line ends normalized, BOM and leading blanks
/// trimmed) as a tree; the format from the content, or `.json` in `origin`.
fn parse_tree(trimmed: &str, origin: &str) -> Result<Value> {
    // A `.json` file is JSON even when broken: its error must say JSON, not YAML.
    if trimmed.starts_with('{') || origin.to_ascii_lowercase().ends_with(".json") {
        serde_json::from_str::<StrictJson>(trimmed)
            .map(|v| v.0)
            .map_err(|e| Error::input(format!("invalid JSON: {e}")))
    } else if trimmed.starts_with('<') {
        xml_to_tree(trimmed)
    } else {
        yaml_to_tree(trimmed)
    }
}

/// What a ROS `camera_info` (or an OpenCV file in its layout) says about the rectified image
/// beside the lens: the rectification rotation R and the projection P of the rectified
/// pinhole camera, as `image_proc` applies them (`initUndistortRectifyMap(K, D, R, P)`).
#[derive(Debug, Clone, PartialEq)]
pub struct Rectification {
    /// R, row-major: the rotation from the lens camera's frame to the rectified frame.
    pub r: [[f64; 3]; 3],
    /// P, row-major: `[fx' 0 cx' Tx; 0 fy' cy' Ty; 0 0 1 0]` (Tx = −fx'·baseline on a stereo
    /// pair's second camera; the warp uses the 3×3 part, as OpenCV does).
    pub p: [[f64; 4]; 3],
    /// P's 3×3 part as the rectified image's intrinsics.
    pub intrinsics: Intrinsics,
}

impl Rectification {
    /// Whether applying it changes nothing: R = I and P's 3×3 part = K.
    pub fn is_identity_for(&self, k: &Intrinsics) -> bool {
        let i = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        self.r == i && self.intrinsics == *k
    }
}

/// The `rectification_matrix` and `projection_matrix` of a ROS `camera_info` file (`R`, `P`
/// in the flat `sensor_msgs/CameraInfo` layout): `None` where the file has neither (every
/// other format). A file with only one of them has P = K or R = I for the other, as ROS fills
/// them. `origin` names the file in errors.
pub fn rectification_of(text: &str, origin: &str) -> Result<Option<Rectification>> {
    let err = |e: Error| e.context(origin);
    let text = text.replace("\r\n", "\n").replace('\r', "\n");
    let trimmed = text.trim_start_matches('\u{feff}').trim_start();
    // A file that does not parse has no rectification to offer (its camera's reader says why).
    let Ok(tree) = parse_tree(trimmed, origin) else {
        return Ok(None);
    };
    let Some(obj) = tree.as_object() else {
        return Ok(None);
    };
    // The flat `R` and `P` are a CameraInfo message's only beside its `distortion_model`: an
    // OpenCV stereo file's `R` is the rotation between its two cameras, not a rectification.
    let ros = obj.contains_key("distortion_model");
    let (r_keys, p_keys): (&[&str], &[&str]) = if ros {
        (&["rectification_matrix", "R"], &["projection_matrix", "P"])
    } else {
        (&["rectification_matrix"], &["projection_matrix"])
    };
    let r = matrix_data(obj, r_keys).map_err(err)?;
    let p = matrix_data(obj, p_keys).map_err(err)?;
    if r.is_none() && p.is_none() {
        return Ok(None);
    }
    let (k, _) = intrinsics_from(obj, false).map_err(err)?;
    let r = match r {
        None => [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        Some((key, v)) => {
            let v: [f64; 9] = v.try_into().map_err(|v: Vec<f64>| {
                err(Error::input(format!(
                    "`{key}` must have 9 entries (3×3), got {}",
                    v.len()
                )))
            })?;
            [[v[0], v[1], v[2]], [v[3], v[4], v[5]], [v[6], v[7], v[8]]]
        }
    };
    let p = match p {
        None => [
            [k.fx, 0.0, k.cx, 0.0],
            [0.0, k.fy, k.cy, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ],
        Some((key, v)) => {
            let v: [f64; 12] = v.try_into().map_err(|v: Vec<f64>| {
                err(Error::input(format!(
                    "`{key}` must have 12 entries (3×4), got {}",
                    v.len()
                )))
            })?;
            let p = [
                [v[0], v[1], v[2], v[3]],
                [v[4], v[5], v[6], v[7]],
                [v[8], v[9], v[10], v[11]],
            ];
            // All zeros is what an uncalibrated ROS driver publishes: nothing to apply.
            if v.iter().all(|&x| x == 0.0) {
                return Ok(None);
            }
            let pinhole = p[0][1] == 0.0
                && p[1][0] == 0.0
                && p[2][0] == 0.0
                && p[2][1] == 0.0
                && p[2][2] == 1.0
                && p[2][3] == 0.0;
            if !pinhole || !v.iter().all(|x| x.is_finite()) {
                return Err(err(Error::input(format!(
                    "`{key}` {v:?}: expected [fx' 0 cx' Tx; 0 fy' cy' Ty; 0 0 1 0] with finite entries"
                ))));
            }
            p
        }
    };
    let intrinsics = Intrinsics {
        fx: p[0][0],
        fy: p[1][1],
        cx: p[0][2],
        cy: p[1][2],
    };
    Ok(Some(Rectification { r, p, intrinsics }))
}

/// [`rectification_of`] a file.
pub fn load_rectification(path: &Path) -> Result<Option<Rectification>> {
    let text =
        super::read_text(path).map_err(|e| Error::io(path, "cannot read camera file", &e))?;
    rectification_of(&text, &path.display().to_string())
}

/// Everything a reader of untrusted text must survive, in one place for the fuzz target and
/// its corpus replay: every detection (as a `.json`, a `.yaml` and a `.txt`), every camera of
/// the listing with and without a size, picked by index and by name, its model evaluated and
/// written back in every format. Errors are fine; a panic is the bug.
pub fn exercise(text: &str) {
    for origin in ["fuzz.json", "fuzz.yaml", "camera.txt"] {
        for size in [None, Some((640, 480))] {
            let Ok(listing) = list_cameras(text, origin, size) else {
                continue;
            };
            let names: Vec<String> = listing.cameras.iter().map(|f| f.name.clone()).collect();
            for camera in listing
                .cameras
                .iter()
                .filter_map(|f| f.camera.as_ref().ok())
            {
                let _ = camera.to_json();
                let _ = camera.unproject_points(&[[1.0, 2.0], [f64::MAX, -0.0]]);
                let _ = camera.project_points(&[[0.1, -0.2, 1.0], [0.0, 0.0, -1.0]]);
                for format in super::writers::Format::ALL {
                    let _ = super::writers::write_camera(camera, format);
                }
            }
            for name in names.iter().take(4) {
                let options = LoadOptions {
                    name: Some(name.clone()),
                    size,
                    ..LoadOptions::default()
                };
                let _ = parse_camera_with(text, origin, &options);
            }
            let _ = parse_camera_with(
                text,
                origin,
                &LoadOptions {
                    index: Some(1),
                    size,
                    name: None,
                },
            );
        }
    }
}

/// Any camera layout's tree (Kalibr, vklens JSON of every model, FileStorage, ROS, the SLAM
/// systems' configs) → its cameras.
pub(super) fn listing_from_tree(tree: &Value, size: Option<(u32, u32)>) -> Listing {
    if let Some(cams) = kalibr_cameras(tree) {
        return Listing {
            format: KALIBR_FORMAT,
            cameras: cams
                .into_iter()
                .map(|(name, cam)| {
                    let camera = kalibr_camera(&name, &cam);
                    Found::new(name, camera)
                })
                .collect(),
        };
    }
    if let Some(camera) = super::models::ncore_camera(tree) {
        return Listing::one("NCore camera JSON", "", camera);
    }
    if let Some(count) = super::models::basalt_camera_count(tree) {
        return Listing {
            format: "Basalt calibration",
            cameras: (0..count)
                .filter_map(|i| {
                    let camera = super::models::basalt_camera(tree, Some(i))?;
                    Some(Found::new(format!("cam{i}"), camera))
                })
                .collect(),
        };
    }
    for reader in [
        super::slam::listing_from_tree,
        super::stereo::listing_from_tree,
        super::gyroflow::listing_from_tree,
    ] {
        if let Some(listing) = reader(tree, size) {
            return listing;
        }
    }
    if let Some(camera) = super::models::camodocal_camera(tree) {
        let name = tree
            .get("camera_name")
            .and_then(Value::as_str)
            .unwrap_or("");
        return Listing::one("camodocal/VINS camera YAML", name, camera);
    }
    let format = if tree.get("distortion_model").is_some() || tree.get("camera_name").is_some() {
        "ROS camera_info"
    } else if tree.get("camera_matrix").is_some() {
        "OpenCV FileStorage file"
    } else {
        "vklens camera file"
    };
    let name = tree
        .get("camera_name")
        .or_else(|| tree.get("name"))
        .and_then(Value::as_str)
        .unwrap_or("");
    Listing::one(
        format,
        name,
        with_size(tree, size).and_then(|t| camera_from_single_tree(&t)),
    )
}

/// The tree, with `size` as its width and height where it gives none (an OpenCV file written
/// without `image_width`); without either, the error asks for `--size`.
fn with_size(tree: &Value, size: Option<(u32, u32)>) -> Result<std::borrow::Cow<'_, Value>> {
    let Some(obj) = tree.as_object() else {
        return Ok(std::borrow::Cow::Borrowed(tree));
    };
    let has = |keys: [&str; 2]| keys.iter().any(|k| obj.contains_key(*k));
    if has(["width", "image_width"]) || has(["height", "image_height"]) {
        return Ok(std::borrow::Cow::Borrowed(tree));
    }
    let (w, h) = catalog::size_or(None, size)?;
    let mut obj = obj.clone();
    obj.insert("width".into(), w.into());
    obj.insert("height".into(), h.into());
    Ok(std::borrow::Cow::Owned(Value::Object(obj)))
}

/// The camera of a file that holds one (vklens JSON of every model, FileStorage, ROS).
fn camera_from_single_tree(tree: &Value) -> Result<Camera> {
    match tree.get("model") {
        Some(Value::String(m)) if m == "brown" => {
            let brown = brown_from_tree(tree)?;
            return Camera::from_brown(&brown).map_err(Error::from);
        }
        Some(Value::String(m)) if m == "opencv_fisheye" => {
            return fisheye_from_tree(tree);
        }
        Some(Value::String(m)) if super::models::model_names().contains(&m.as_str()) => {
            let obj = tree
                .as_object()
                .ok_or_else(|| Error::input("expected an object/mapping at the top level"))?;
            return super::models::camera_from_json(m, obj);
        }
        // A model vklens does not implement must not load as the standard model: a fisheye's
        // k1..k4 read as k1 k2 p1 p2 put pixels hundreds of thousands of pixels off.
        Some(Value::String(m)) if m != "opencv" => {
            return Err(Error::input(format!(
                "`model` is `{m}`; vklens reads `opencv` (OpenCV's standard model, the default), `opencv_fisheye`, `brown`, `{}`",
                super::models::model_names().join("`, `")
            )));
        }
        Some(Value::String(_)) | None => {}
        Some(other) => {
            return Err(Error::input(format!(
                "`model` must be a string (`opencv`, `opencv_fisheye` or `brown`), got {other}"
            )));
        }
    }
    if let Some(m) = tree.get("distortion_model").and_then(Value::as_str) {
        if ["equidistant", "fisheye"].contains(&m) {
            return fisheye_from_tree(tree);
        }
    }
    camera_from_tree(tree)
}

fn brown_from_tree(tree: &Value) -> Result<BrownRadial> {
    let obj = tree
        .as_object()
        .ok_or_else(|| Error::input("expected an object"))?;
    let width = dimension(obj, &["width", "image_width"])?;
    let height = dimension(obj, &["height", "image_height"])?;
    BrownRadial::new(
        width,
        height,
        number_field(obj, "c1")?,
        number_field(obj, "c2")?,
    )
    .map_err(Error::from)
}

/// Reads a camera from a parsed JSON object (any of the layouts above, every model).
pub fn camera_from_value(value: &Value) -> Result<Camera> {
    catalog::select(listing_from_tree(value, None), &LoadOptions::default())
}

fn camera_from_tree(tree: &Value) -> Result<Camera> {
    let obj = tree
        .as_object()
        .ok_or_else(|| Error::input("expected an object/mapping at the top level"))?;
    let width = dimension(obj, &["width", "image_width"])?;
    let height = dimension(obj, &["height", "image_height"])?;

    let (intrinsics, _) = intrinsics_from(obj, false)?;

    if let Some(model) = obj.get("distortion_model").and_then(Value::as_str) {
        if !["plumb_bob", "rational_polynomial", "opencv"].contains(&model) {
            return Err(Error::input(format!(
                "`distortion_model` is `{model}`; vklens reads `plumb_bob` and `rational_polynomial` (the OpenCV standard model)"
            )));
        }
    }
    let coeffs = distortion_coefficients(obj)?.map_or_else(Vec::new, |(_, d)| d);
    let coeffs = if coeffs.is_empty() {
        vec![0.0; 4]
    } else {
        coeffs
    };
    let camera = Camera::from_coeffs(width, height, intrinsics, &coeffs).map_err(|e| match e {
        ModelError::CoefficientCount(n) => Error::input(format!(
            "distortion coefficients: OpenCV accepts 4, 5, 8, 12 or 14 values, this file has {n}"
        )),
        other => Error::from(other),
    })?;
    // vklens JSON keeps Basalt's rpmax as `max_radius`.
    match obj.get("max_radius") {
        None => Ok(camera),
        Some(_) => camera
            .with_max_radius(number_field(obj, "max_radius")?)
            .map_err(|e| Error::input(format!("`max_radius`: {e}"))),
    }
}

/// `fx fy cx cy` from the keys or from a camera matrix `K`; with `allow_skew`, `K[0][1]` is
/// returned beside them (the fisheye model's `α fx`), else it must be 0.
pub(super) fn intrinsics_from(
    obj: &Map<String, Value>,
    allow_skew: bool,
) -> Result<(Intrinsics, f64)> {
    if obj.contains_key("fx") {
        return Ok((
            Intrinsics {
                fx: number_field(obj, "fx")?,
                fy: number_field(obj, "fy")?,
                cx: number_field(obj, "cx")?,
                cy: number_field(obj, "cy")?,
            },
            0.0,
        ));
    }
    let (key, k) = matrix_data(obj, &["camera_matrix", "K", "k"])?
        .ok_or_else(|| Error::input("missing `fx` (or `camera_matrix`)"))?;
    if k.len() != 9 {
        return Err(Error::input(format!(
            "`{key}` must have 9 entries (3×3), got {}",
            k.len()
        )));
    }
    let expected_zero = [
        (1, "[0][1] (skew)"),
        (3, "[1][0]"),
        (6, "[2][0]"),
        (7, "[2][1]"),
    ];
    // The fisheye model has a skew; the standard model does not.
    for &(i, what) in &expected_zero[usize::from(allow_skew)..] {
        if k[i] != 0.0 {
            return Err(Error::input(format!(
                "`{key}` entry {what} is {}; vklens reads camera matrices [[fx,{},cx],[0,fy,cy],[0,0,1]]",
                k[i],
                if allow_skew { "s" } else { "0" }
            )));
        }
    }
    if k[8] != 1.0 {
        return Err(Error::input(format!(
            "`{key}` entry [2][2] must be 1, got {}",
            k[8]
        )));
    }
    let skew = if allow_skew { k[1] } else { 0.0 };
    Ok((
        Intrinsics {
            fx: k[0],
            fy: k[4],
            cx: k[2],
            cy: k[5],
        },
        skew,
    ))
}

/// The distortion coefficients under `dist_coeffs` (vklens JSON) or as an `opencv-matrix` or
/// list under `distortion_coefficients` / `D` (FileStorage, ROS), with the key they were under.
fn distortion_coefficients(obj: &Map<String, Value>) -> Result<Option<(&'static str, Vec<f64>)>> {
    if let Some(v) = obj.get("dist_coeffs") {
        return Ok(Some(("dist_coeffs", number_list(v, "dist_coeffs")?)));
    }
    matrix_data(obj, &["distortion_coefficients", "D", "d"])
}

/// A fisheye camera from vklens JSON (`"model": "opencv_fisheye"`) or a ROS `camera_info`
/// (`distortion_model: equidistant` or `fisheye`).
fn fisheye_from_tree(tree: &Value) -> Result<Camera> {
    let obj = tree
        .as_object()
        .ok_or_else(|| Error::input("expected an object/mapping at the top level"))?;
    let width = dimension(obj, &["width", "image_width"])?;
    let height = dimension(obj, &["height", "image_height"])?;
    let (intrinsics, skew) = intrinsics_from(obj, true)?;
    let (key, coeffs) = distortion_coefficients(obj)?.ok_or_else(|| {
        Error::input(
            "missing `dist_coeffs` (or `distortion_coefficients`, `D`): the fisheye's k1..k4",
        )
    })?;
    let k: [f64; 4] = coeffs.as_slice().try_into().map_err(|_| {
        Error::input(format!(
            "`{key}`: OpenCV's fisheye model has 4 coefficients (k1..k4), this file has {}",
            coeffs.len()
        ))
    })?;
    let alpha = match obj.get("alpha") {
        Some(_) => {
            if skew != 0.0 {
                return Err(Error::input(
                    "the skew is given twice: `alpha` and the camera matrix's [0][1]",
                ));
            }
            number_field(obj, "alpha")?
        }
        None if skew == 0.0 => 0.0,
        None => {
            // K[0][1] = α fx: fx must be usable before α can be read from it.
            if !(intrinsics.fx.is_finite() && intrinsics.fx > 0.0) {
                return Err(Error::input(format!(
                    "the camera matrix's fx is {}: it must be a positive number (and its [0][1], the skew α·fx, needs it)",
                    intrinsics.fx
                )));
            }
            let alpha = skew / intrinsics.fx;
            if !(alpha.abs() < Fisheye::MAX_ALPHA) {
                return Err(Error::input(format!(
                    "the camera matrix's [0][1] = {skew} is a skew α = {alpha} (α·fx); |α| must be below {}",
                    Fisheye::MAX_ALPHA
                )));
            }
            alpha
        }
    };
    let max_fov = match obj.get("max_fov_deg") {
        None | Some(Value::Null) => None,
        Some(_) => Some(number_field(obj, "max_fov_deg")?),
    };
    let lens = Fisheye::new(k, alpha, max_fov).map_err(Error::from)?;
    Camera::fisheye(width, height, intrinsics, lens).map_err(Error::from)
}

/// The cameras of a Kalibr camchain (`cam0`, `cam1`, … by their number), if the tree is one.
fn kalibr_cameras(tree: &Value) -> Option<Vec<(String, Map<String, Value>)>> {
    let obj = tree.as_object()?;
    let mut cams: Vec<(u64, String, Map<String, Value>)> = obj
        .iter()
        .filter_map(|(key, v)| {
            let n = key.strip_prefix("cam")?.parse::<u64>().ok()?;
            Some((n, key.clone(), v.as_object()?.clone()))
        })
        .collect();
    cams.sort_by_key(|(n, _, _)| *n);
    (!cams.is_empty()).then(|| cams.into_iter().map(|(_, k, c)| (k, c)).collect())
}

/// One camera of a Kalibr camchain (`name` its key: `cam0`, …).
fn kalibr_camera(name: &str, cam: &Map<String, Value>) -> Result<Camera> {
    let field = |key: &str| format!("`{name}.{key}`");
    let text = |key: &str| -> Result<String> {
        match cam.get(key) {
            Some(Value::String(s)) => Ok(s.clone()),
            Some(other) => Err(Error::input(format!(
                "{} must be a string, got {other}",
                field(key)
            ))),
            None => Err(Error::input(format!("missing {}", field(key)))),
        }
    };
    let list = |key: &str, n: usize| -> Result<Vec<f64>> {
        let v = cam
            .get(key)
            .ok_or_else(|| Error::input(format!("missing {}", field(key))))?;
        let values = number_list(v, &format!("{name}.{key}"))?;
        if values.len() != n {
            return Err(Error::input(format!(
                "{} must have {n} numbers, got {}",
                field(key),
                values.len()
            )));
        }
        Ok(values)
    };
    let model = text("camera_model")?;
    // Kalibr's intrinsics: the model's own parameters first, then fu fv pu pv.
    type LensOf = fn(&[f64]) -> std::result::Result<Option<Lens>, ModelError>;
    let (own, lens_of): (usize, LensOf) = match model.as_str() {
        "pinhole" => (0, |_| Ok(None)),
        "omni" => (1, |p| {
            Omni::new(p[0], [0.0; 4]).map(|l| Some(Lens::Omni(l)))
        }),
        "eucm" => (2, |p| Eucm::new(p[0], p[1]).map(|l| Some(Lens::Eucm(l)))),
        "ds" => (2, |p| {
            DoubleSphere::new(p[0], p[1]).map(|l| Some(Lens::DoubleSphere(l)))
        }),
        _ => {
            return Err(Error::input(format!(
                "{} is `{model}`; vklens reads Kalibr's `pinhole`, `omni`, `eucm` and `ds` cameras",
                field("camera_model")
            )))
        }
    };
    let all = list("intrinsics", own + 4)?;
    let (p, f) = all.split_at(own);
    let res = list("resolution", 2)?;
    let side = |v: f64, what: &str| -> Result<u32> {
        image_side(v).ok_or_else(|| {
            Error::input(format!(
                "{}: the {what} must be a whole number of pixels in 1..={}, got {v}",
                field("resolution"),
                crate::model::MAX_IMAGE_SIDE
            ))
        })
    };
    let (width, height) = (side(res[0], "width")?, side(res[1], "height")?);
    let intrinsics = Intrinsics {
        fx: f[0],
        fy: f[1],
        cx: f[2],
        cy: f[3],
    };
    let distortion = match cam.get("distortion_model") {
        None => "none".to_string(),
        Some(_) => text("distortion_model")?,
    };
    let named = |e: ModelError| Error::input(format!("{name}: {e}"));
    let base = lens_of(p).map_err(named)?;
    let coeffs = |n: usize| match cam.get("distortion_coeffs") {
        None if distortion == "none" => Ok(vec![0.0; n]),
        _ => list("distortion_coeffs", n),
    };
    let lens = match (base, distortion.as_str()) {
        (None, "equidistant") => {
            let c = coeffs(4)?;
            Lens::Fisheye(Fisheye::new([c[0], c[1], c[2], c[3]], 0.0, None).map_err(named)?)
        }
        // Kalibr's radtan is k1 k2 r1 r2: OpenCV's k1 k2 p1 p2.
        (None, "radtan" | "none") => {
            return Camera::from_coeffs(width, height, intrinsics, &coeffs(4)?).map_err(named)
        }
        // Kalibr's pinhole-fov: one coefficient, ω.
        (None, "fov") => Lens::Fov(Fov::new(coeffs(1)?[0]).map_err(named)?),
        (Some(Lens::Omni(o)), "radtan" | "none") => {
            let c = coeffs(4)?;
            Lens::Omni(Omni::new(o.xi, [c[0], c[1], c[2], c[3]]).map_err(named)?)
        }
        (Some(lens), "none") => lens,
        (_, other) => {
            return Err(Error::input(format!(
                "{} is `{other}` on a `{model}` camera; vklens reads Kalibr's pinhole with none, radtan, equidistant or fov, omni with none or radtan, eucm and ds with none",
                field("distortion_model")
            )))
        }
    };
    Camera::with_lens(width, height, intrinsics, lens).map_err(named)
}

/// Whether the text is a COLMAP `cameras.txt`: its first line that is not a comment reads
/// `CAMERA_ID MODEL WIDTH HEIGHT ...` with an upper-case model name.
fn looks_like_colmap(text: &str) -> bool {
    let Some(line) = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
    else {
        // Only comments: COLMAP's header with no camera.
        return text.trim_start().starts_with("# Camera list");
    };
    let t: Vec<&str> = line.split_whitespace().collect();
    t.len() >= 4
        && t[0].parse::<u64>().is_ok()
        && !t[1].is_empty()
        && t[1]
            .chars()
            .all(|c| c.is_ascii_uppercase() || c == '_' || c.is_ascii_digit())
}

/// Every camera of a COLMAP `cameras.txt`, one per line, named by its camera id as written.
fn colmap_listing(text: &str) -> Listing {
    let cameras = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'))
        .map(|(line_no, line)| {
            let id = line.split_whitespace().next().unwrap_or("");
            Found::new(id, colmap_line(line_no, line))
        })
        .collect();
    Listing {
        format: "COLMAP cameras.txt",
        cameras,
    }
}

/// The camera of one line of a COLMAP `cameras.txt`.
fn colmap_line(line_no: usize, line: &str) -> Result<Camera> {
    let at = |msg: String| Error::input(format!("line {line_no}: {msg}"));
    let t: Vec<&str> = line.split_whitespace().collect();
    let model = t.get(1).copied().unwrap_or("");
    let side = |s: &str, what: &str| -> Result<u32> {
        s.parse::<u32>()
            .ok()
            .filter(|v| (1..=crate::model::MAX_IMAGE_SIDE).contains(v))
            .ok_or_else(|| {
                at(format!(
                    "the {what} must be a whole number of pixels in 1..={}, got `{s}`",
                    crate::model::MAX_IMAGE_SIDE
                ))
            })
    };
    let (width, height) = (
        side(t.get(2).copied().unwrap_or(""), "width")?,
        side(t.get(3).copied().unwrap_or(""), "height")?,
    );
    let names = super::models::COLMAP_MODELS
        .iter()
        .find(|(m, _)| *m == model)
        .map(|(_, n)| *n)
        .unwrap_or(&[]);
    let mut p = Vec::with_capacity(t.len().saturating_sub(4));
    for (i, s) in t[4..].iter().enumerate() {
        let name = names.get(i).copied().unwrap_or("extra");
        p.push(parse_float(s).ok_or_else(|| {
            at(format!(
                "{model} parameter `{name}` must be a number, got `{s}`"
            ))
        })?);
    }
    super::models::colmap_camera(model, width, height, &p)
        .map_err(|e| e.context(format!("line {line_no}")))
}

pub(super) fn as_number(v: &Value) -> Option<f64> {
    match v {
        Value::Number(n) => n.as_f64(),
        // FileStorage writes `.Nan`/`.Inf` and YAML floats like `400.`; they arrive as text.
        Value::String(s) => parse_float(s),
        _ => None,
    }
}

pub(super) fn parse_float(s: &str) -> Option<f64> {
    let t = s.trim();
    match t.to_ascii_lowercase().as_str() {
        ".nan" | "nan" => Some(f64::NAN),
        ".inf" | "+.inf" | "inf" => Some(f64::INFINITY),
        "-.inf" | "-inf" => Some(f64::NEG_INFINITY),
        _ => t.parse().ok(),
    }
}

pub(super) fn number_field(obj: &Map<String, Value>, key: &str) -> Result<f64> {
    let v = obj
        .get(key)
        .ok_or_else(|| Error::input(format!("missing field `{key}`")))?;
    as_number(v).ok_or_else(|| Error::input(format!("field `{key}` must be a number, got {v}")))
}

pub(super) fn dimension(obj: &Map<String, Value>, keys: &[&str]) -> Result<u32> {
    let (key, v) = keys
        .iter()
        .find_map(|k| obj.get(*k).map(|v| (*k, v)))
        .ok_or_else(|| {
            Error::input(format!(
                "missing field `{}` (image size)",
                keys.join("` or `")
            ))
        })?;
    let n = as_number(v)
        .ok_or_else(|| Error::input(format!("field `{key}` must be a number, got {v}")))?;
    image_side(n).ok_or_else(|| {
        Error::input(format!(
            "field `{key}` must be a whole number of pixels in 1..={}, got {v}",
            crate::model::MAX_IMAGE_SIDE
        ))
    })
}

/// An image side from a number, or an error naming `what`.
pub(super) fn image_side_of(n: f64, what: &str) -> Result<u32> {
    image_side(n).ok_or_else(|| {
        Error::input(format!(
            "the image {what} must be a whole number of pixels in 1..={}, got {n}",
            crate::model::MAX_IMAGE_SIDE
        ))
    })
}

/// An image side: a whole number of pixels in 1..=MAX_IMAGE_SIDE.
fn image_side(n: f64) -> Option<u32> {
    (n.fract() == 0.0 && n >= 1.0 && n <= crate::model::MAX_IMAGE_SIDE as f64).then_some(n as u32)
}

pub(super) fn number_list(v: &Value, key: &str) -> Result<Vec<f64>> {
    let arr = v
        .as_array()
        .ok_or_else(|| Error::input(format!("field `{key}` must be a list of numbers, got {v}")))?;
    arr.iter()
        .enumerate()
        .map(|(i, x)| {
            as_number(x).ok_or_else(|| {
                Error::input(format!("field `{key}`[{i}] must be a number, got {x}"))
            })
        })
        .collect()
}

/// An `opencv-matrix` (`{rows, cols, data}`) or a plain list under one of `keys`.
fn matrix_data<'a>(
    obj: &Map<String, Value>,
    keys: &[&'a str],
) -> Result<Option<(&'a str, Vec<f64>)>> {
    let Some((key, v)) = keys.iter().find_map(|k| obj.get(*k).map(|v| (*k, v))) else {
        return Ok(None);
    };
    let data = match v {
        Value::Object(m) => m
            .get("data")
            .ok_or_else(|| Error::input(format!("field `{key}` has no `data`")))?,
        other => other,
    };
    let values = number_list(data, &format!("{key}.data"))?;
    if let Value::Object(m) = v {
        if let (Some(r), Some(c)) = (
            m.get("rows").and_then(as_number),
            m.get("cols").and_then(as_number),
        ) {
            if (r * c) as usize != values.len() {
                return Err(Error::input(format!(
                    "field `{key}` says {r}×{c} but its data has {} values",
                    values.len()
                )));
            }
        }
    }
    Ok(Some((key, values)))
}

/// YAML (OpenCV FileStorage or ROS) → JSON tree. OpenCV's `%YAML:1.0` directive is not valid
/// YAML 1.1/1.2 syntax, so directive lines are dropped; `!!opencv-matrix` tags are ignored.
/// Most YAML nodes a camera file may expand to, an alias counted as the nodes it repeats. A
/// calibration file has a few hundred; nested aliases (a "billion laughs") would otherwise
/// expand a file of a few hundred bytes to billions of nodes.
pub const MAX_YAML_NODES: u64 = 100_000;

/// The number of nodes `text` expands to, counted from the parser's events without expanding
/// anything (an alias adds the size its anchor was recorded with).
fn yaml_expanded_nodes(text: &str) -> Result<u64> {
    use yaml_rust2::parser::{Event, EventReceiver, Parser};
    #[derive(Default)]
    struct Count {
        /// Open collections: nodes so far, anchor id.
        open: Vec<(u64, usize)>,
        /// Expanded size of each anchor.
        anchors: std::collections::HashMap<usize, u64>,
        total: u64,
    }
    impl Count {
        fn add(&mut self, n: u64) {
            self.total = self.total.saturating_add(n);
            if let Some(top) = self.open.last_mut() {
                top.0 = top.0.saturating_add(n);
            }
        }
    }
    impl EventReceiver for Count {
        fn on_event(&mut self, ev: Event) {
            match ev {
                Event::Scalar(_, _, anchor, _) => {
                    self.add(1);
                    if anchor > 0 {
                        self.anchors.insert(anchor, 1);
                    }
                }
                Event::SequenceStart(anchor, _) | Event::MappingStart(anchor, _) => {
                    self.total = self.total.saturating_add(1);
                    self.open.push((1, anchor));
                }
                Event::SequenceEnd | Event::MappingEnd => {
                    if let Some((n, anchor)) = self.open.pop() {
                        if anchor > 0 {
                            self.anchors.insert(anchor, n);
                        }
                        if let Some(top) = self.open.last_mut() {
                            top.0 = top.0.saturating_add(n);
                        }
                    }
                }
                Event::Alias(id) => {
                    let n = self.anchors.get(&id).copied().unwrap_or(1);
                    self.add(n);
                }
                _ => {}
            }
        }
    }
    let mut count = Count::default();
    Parser::new_from_str(text)
        .load(&mut count, true)
        .map_err(|e| Error::input(format!("invalid YAML: {e}")))?;
    Ok(count.total)
}

/// OpenCV's FileStorage and the SLAM systems that read their settings through it accept what
/// strict YAML refuses, and their users' files do all of it: a `%YAML:1.0` directive (not YAML
/// 1.1/1.2 syntax: dropped, as every `%` directive line), `key:value` and `data:[` without the
/// space after the colon (a space goes in where a line starts with a plain key), and tabs
/// (indentation tabs become four spaces, others one).
fn yaml_as_opencv_writes_it(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 64);
    for line in text.lines() {
        if line.starts_with('%') {
            continue;
        }
        let indent = line.len() - line.trim_start_matches([' ', '\t']).len();
        for c in line[..indent].chars() {
            out.push_str(if c == '\t' { "    " } else { " " });
        }
        let rest = line[indent..].replace('\t', " ");
        out.push_str(&space_after_key(&rest));
        out.push('\n');
    }
    out
}

/// `key:value` → `key: value` for a line that starts with a plain key (letters, digits, `_`,
/// `.`, `-`; after an optional `- `), the rest untouched.
fn space_after_key(line: &str) -> std::borrow::Cow<'_, str> {
    let body = line.strip_prefix("- ").unwrap_or(line);
    let offset = line.len() - body.len();
    let key_len = body
        .find(|c: char| !(c.is_ascii_alphanumeric() || "_.-".contains(c)))
        .unwrap_or(body.len());
    let after = &body[key_len..];
    let glued = key_len > 0
        && after.starts_with(':')
        && after[1..]
            .chars()
            .next()
            .is_some_and(|c| !c.is_whitespace() && c != ':');
    if glued {
        let at = offset + key_len + 1;
        std::borrow::Cow::Owned(format!("{} {}", &line[..at], &line[at..]))
    } else {
        std::borrow::Cow::Borrowed(line)
    }
}

pub(crate) fn yaml_to_tree(text: &str) -> Result<Value> {
    use yaml_rust2::{Yaml, YamlLoader};
    let cleaned = yaml_as_opencv_writes_it(text);
    let nodes = yaml_expanded_nodes(&cleaned)?;
    if nodes > MAX_YAML_NODES {
        return Err(Error::input(format!(
            "the YAML expands to {nodes} nodes (its aliases repeat anchors), more than a camera file's limit of {MAX_YAML_NODES}"
        )));
    }
    let docs = YamlLoader::load_from_str(&cleaned)
        .map_err(|e| Error::input(format!("invalid YAML: {e}")))?;
    let doc = docs
        .into_iter()
        .next()
        .ok_or_else(|| Error::input("empty YAML file"))?;
    fn convert(y: &Yaml) -> Value {
        match y {
            Yaml::Real(s) => Value::String(s.clone()),
            Yaml::Integer(i) => Value::from(*i),
            Yaml::String(s) => Value::String(s.clone()),
            Yaml::Boolean(b) => Value::Bool(*b),
            Yaml::Array(a) => Value::Array(a.iter().map(convert).collect()),
            Yaml::Hash(h) => Value::Object(
                h.iter()
                    .filter_map(|(k, v)| k.as_str().map(|k| (k.to_string(), convert(v))))
                    .collect(),
            ),
            _ => Value::Null,
        }
    }
    Ok(convert(&doc))
}

/// OpenCV FileStorage XML → JSON tree: `<opencv_storage>`'s children become keys; an element
/// with children becomes an object; `data` text becomes a list of numbers.
/// Deepest element nesting a camera file's XML may have: OpenCV's FileStorage nests three deep.
/// The tree is converted recursively, so a limit keeps a hostile file from overflowing the
/// stack (JSON, YAML and TOML readers stop at their own recursion limits).
pub const MAX_XML_DEPTH: usize = 64;

/// The deepest element nesting of an XML text, from its tags alone (a pre-filter: roxmltree
/// parses recursively, and a hostile file would overflow the stack before it could object).
fn xml_depth(text: &str) -> usize {
    let (mut depth, mut deepest) = (0usize, 0usize);
    let bytes = text.as_bytes();
    let mut i = 0;
    while let Some(k) = bytes[i..].iter().position(|&b| b == b'<') {
        let start = i + k;
        let end = bytes[start..]
            .iter()
            .position(|&b| b == b'>')
            .map_or(bytes.len(), |e| start + e);
        match bytes.get(start + 1) {
            Some(b'/') => depth = depth.saturating_sub(1),
            Some(b'!') | Some(b'?') => {}
            _ if end > 0 && bytes.get(end - 1) == Some(&b'/') => {}
            _ => {
                depth += 1;
                deepest = deepest.max(depth);
            }
        }
        i = end.min(bytes.len().saturating_sub(1)) + 1;
        if i >= bytes.len() {
            break;
        }
    }
    deepest
}

fn xml_to_tree(text: &str) -> Result<Value> {
    let depth = xml_depth(text);
    if depth > MAX_XML_DEPTH {
        return Err(Error::input(format!(
            "invalid XML: elements nest {depth} deep, more than a camera file's limit of {MAX_XML_DEPTH}"
        )));
    }
    let doc =
        roxmltree::Document::parse(text).map_err(|e| Error::input(format!("invalid XML: {e}")))?;
    let root = doc.root_element();
    if let Some(deep) = doc
        .descendants()
        .find(|n| n.is_element() && n.ancestors().nth(MAX_XML_DEPTH).is_some())
    {
        return Err(Error::input(format!(
            "invalid XML: <{}> is nested deeper than {MAX_XML_DEPTH} elements",
            deep.tag_name().name()
        )));
    }
    fn convert(node: roxmltree::Node) -> Value {
        let children: Vec<_> = node.children().filter(|c| c.is_element()).collect();
        if children.is_empty() {
            let text = node.text().unwrap_or("").trim();
            if node.tag_name().name() == "data" {
                return Value::Array(
                    text.split_whitespace()
                        .map(|t| Value::String(t.to_string()))
                        .collect(),
                );
            }
            return Value::String(text.trim_matches('"').to_string());
        }
        Value::Object(
            children
                .into_iter()
                .map(|c| (c.tag_name().name().to_string(), convert(c)))
                .collect(),
        )
    }
    Ok(convert(root))
}

/// JSON read like `serde_json::Value`, except that a key given twice in one object is an error
/// (`Value` keeps the last silently, so a file could say two things about one parameter).
struct StrictJson(Value);

impl<'de> serde::Deserialize<'de> for StrictJson {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        d.deserialize_any(StrictVisitor).map(StrictJson)
    }
}

struct StrictVisitor;

impl<'de> serde::de::Visitor<'de> for StrictVisitor {
    type Value = Value;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, v: bool) -> std::result::Result<Value, E> {
        Ok(Value::Bool(v))
    }
    fn visit_i64<E>(self, v: i64) -> std::result::Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_u64<E>(self, v: u64) -> std::result::Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_f64<E>(self, v: f64) -> std::result::Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_str<E>(self, v: &str) -> std::result::Result<Value, E> {
        Ok(Value::String(v.to_string()))
    }
    fn visit_string<E>(self, v: String) -> std::result::Result<Value, E> {
        Ok(Value::String(v))
    }
    fn visit_unit<E>(self) -> std::result::Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_none<E>(self) -> std::result::Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(
        self,
        mut seq: A,
    ) -> std::result::Result<Value, A::Error> {
        let mut out = Vec::new();
        while let Some(StrictJson(v)) = seq.next_element()? {
            out.push(v);
        }
        Ok(Value::Array(out))
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(
        self,
        mut map: A,
    ) -> std::result::Result<Value, A::Error> {
        let mut out = Map::new();
        while let Some(key) = map.next_key::<String>()? {
            if out.contains_key(&key) {
                return Err(serde::de::Error::custom(format!(
                    "key `{key}` appears twice in one object"
                )));
            }
            let StrictJson(v) = map.next_value()?;
            out.insert(key, v);
        }
        Ok(Value::Object(out))
    }
}
