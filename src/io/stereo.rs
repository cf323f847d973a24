//! OpenCV stereo calibration files (format name "OpenCV stereo calibration"): `FileStorage`
//! YAML, XML or JSON holding the intrinsics of both cameras of a pair, read from the parsed
//! tree (`!!opencv-matrix` tags dropped, so a matrix is `{rows, cols, dt, data}`; a plain list
//! is accepted too).
//!
//! The layouts, each a camera matrix and its distortion vector per camera:
//!
//! | camera matrix                    | distortion                   | written by                                    |
//! |----------------------------------|------------------------------|-----------------------------------------------|
//! | `M1`, `M2`                       | `D1`, `D2`                   | OpenCV's `samples/cpp/stereo_calib.cpp` (`intrinsics.yml`) |
//! | `K1`, `K2`                       | `D1`, `D2`                   | `stereoCalibrate` scripts naming them so      |
//! | `cameraMatrix1`, `cameraMatrix2` | `distCoeffs1`, `distCoeffs2` | `stereoCalibrate`'s own argument names        |
//! | `cameraMatrixL`, `cameraMatrixR` | `distCoeffsL`, `distCoeffsR` | MATLAB-to-OpenCV exports                      |
//!
//! Each camera matrix present is one camera, named by its key as the file writes it (`M1`,
//! `M2`, `K1`, `cameraMatrixL`, …), in the order of the table; a file may hold one camera of a
//! pair. A camera matrix is `[fx 0 cx; 0 fy cy; 0 0 1]` (a skew is refused: the standard
//! model has none), and the distortion vector of 4, 5, 8, 12 or 14 coefficients is OpenCV's
//! standard model in OpenCV's order.
//!
//! The image size, shared by both cameras, is `image_width`/`image_height`, `imageSize` or
//! `image_size` (OpenCV writes a `cv::Size` as `[w, h]` in YAML and JSON, `w h` in XML), or
//! `width`/`height`; `stereo_calib.cpp` writes none, and the caller gives it ([`size_or`]).
//!
//! The extrinsics (`R`, `T`, `E`, `F`, `R1`, `R2`, `P1`, `P2`, `Q`) are not a camera: a file
//! holding only them (`stereo_calib.cpp`'s `extrinsics.yml`) is not taken for this format.
//!
//! A calibrated pair ([`StereoPair`], what stereo rectification needs) is read from a file of
//! this format that also holds `R` and `T` (`cv2.stereoCalibrate`'s, X2 = R·X1 + T: R a 3×3
//! matrix or a Rodrigues vector, T three numbers) or from a Kalibr camchain (`cam0`, `cam1`,
//! and `cam1.T_cn_cnm1`, the 4×4 transform from cam0's frame to cam1's); R and T alone from an
//! extrinsics file ([`extrinsics_of`]).

use std::path::Path;

use serde_json::{Map, Value};

use super::camera::{as_number, image_side_of, number_list};
use super::catalog::{size_or, Found, Listing};
use crate::model::stereo::PairRotation;
use crate::model::{Camera, Intrinsics, ModelError};
use crate::{Error, Result};

/// The format name of an OpenCV stereo calibration file.
pub const FORMAT: &str = "OpenCV stereo calibration";

/// Camera matrix and distortion keys of each layout, in listing order.
const CAMERAS: [(&str, &str); 8] = [
    ("M1", "D1"),
    ("M2", "D2"),
    ("K1", "D1"),
    ("K2", "D2"),
    ("cameraMatrix1", "distCoeffs1"),
    ("cameraMatrix2", "distCoeffs2"),
    ("cameraMatrixL", "distCoeffsL"),
    ("cameraMatrixR", "distCoeffsR"),
];

/// The cameras of the file, if the tree is in this format.
pub fn listing_from_tree(tree: &Value, size: Option<(u32, u32)>) -> Option<Listing> {
    let obj = tree.as_object()?;
    // A camera matrix key whose value is a matrix (a mapping with `data`, or a list): a key
    // that merely shares a name (a scalar `K1` coefficient) does not make the file a stereo
    // calibration.
    let present: Vec<(&str, &str)> = CAMERAS
        .iter()
        .copied()
        .filter(|(m, _)| obj.get(*m).is_some_and(is_matrix))
        .collect();
    if present.is_empty() {
        return None;
    }
    let file_size = image_size(obj);
    let cameras = present
        .into_iter()
        .map(|(m, d)| {
            let camera = match &file_size {
                Ok(s) => size_or(*s, size),
                Err(e) => Err(Error::input(e.to_string())),
            }
            .and_then(|(w, h)| camera(obj, m, d, w, h));
            Found::new(m, camera)
        })
        .collect();
    Some(Listing {
        format: FORMAT,
        cameras,
    })
}

fn is_matrix(v: &Value) -> bool {
    match v {
        Value::Object(m) => m.contains_key("data"),
        Value::Array(_) => true,
        _ => false,
    }
}

/// The values of a matrix (`{rows, cols, data}` or a plain list) under `key`.
fn matrix_values(obj: &Map<String, Value>, key: &str) -> Result<Vec<f64>> {
    let v = obj
        .get(key)
        .ok_or_else(|| Error::input(format!("missing `{key}`")))?;
    let Value::Object(m) = v else {
        return number_list(v, key);
    };
    let data = m
        .get("data")
        .ok_or_else(|| Error::input(format!("`{key}` has no `data`")))?;
    let values = number_list(data, &format!("{key}.data"))?;
    let dim = |d: &str| m.get(d).and_then(as_number);
    if let (Some(r), Some(c)) = (dim("rows"), dim("cols")) {
        if r * c != values.len() as f64 {
            return Err(Error::input(format!(
                "`{key}` says {r}×{c} but its data has {} values",
                values.len()
            )));
        }
    }
    Ok(values)
}

/// The camera of camera matrix `m` and distortion vector `d`.
fn camera(obj: &Map<String, Value>, m: &str, d: &str, width: u32, height: u32) -> Result<Camera> {
    let k = matrix_values(obj, m)?;
    if k.len() != 9 {
        return Err(Error::input(format!(
            "`{m}` must have 9 entries (3×3), got {}",
            k.len()
        )));
    }
    for (i, what, want) in [
        (1, "[0][1] (skew)", 0.0),
        (3, "[1][0]", 0.0),
        (6, "[2][0]", 0.0),
        (7, "[2][1]", 0.0),
        (8, "[2][2]", 1.0),
    ] {
        if k[i] != want {
            return Err(Error::input(format!(
                "`{m}` entry {what} is {}; OpenCV's standard model reads camera matrices [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]",
                k[i]
            )));
        }
    }
    let intrinsics = Intrinsics {
        fx: k[0],
        fy: k[4],
        cx: k[2],
        cy: k[5],
    };
    if !obj.contains_key(d) {
        return Err(Error::input(format!(
            "missing `{d}`, the distortion coefficients of `{m}`"
        )));
    }
    let coeffs = matrix_values(obj, d)?;
    Camera::from_coeffs(width, height, intrinsics, &coeffs).map_err(|e| match e {
        ModelError::CoefficientCount(n) => Error::input(format!(
            "`{d}`: OpenCV's distortion vectors have 4, 5, 8, 12 or 14 coefficients, this one has {n}"
        )),
        other => Error::input(format!("`{m}`, `{d}`: {other}")),
    })
}

/// The image size the file gives, if any (`Ok(None)`: none), or why the one it gives is
/// unusable. Every spelling present must agree.
fn image_size(obj: &Map<String, Value>) -> Result<Option<(u32, u32)>> {
    let mut found: Vec<(String, (u32, u32))> = Vec::new();
    let side = |v: &Value, key: &str| -> Result<u32> {
        let n = as_number(v)
            .ok_or_else(|| Error::input(format!("`{key}` must be a number, got {v}")))?;
        image_side_of(n, &format!("`{key}`"))
    };
    for (wk, hk) in [("image_width", "image_height"), ("width", "height")] {
        match (obj.get(wk), obj.get(hk)) {
            (Some(w), Some(h)) => {
                found.push((format!("`{wk}`/`{hk}`"), (side(w, wk)?, side(h, hk)?)))
            }
            (None, None) => {}
            (Some(_), None) => return Err(Error::input(format!("`{wk}` without `{hk}`"))),
            (None, Some(_)) => return Err(Error::input(format!("`{hk}` without `{wk}`"))),
        }
    }
    for key in ["imageSize", "image_size"] {
        let Some(v) = obj.get(key) else { continue };
        let pair: Vec<Value> = match v {
            Value::Array(a) => a.clone(),
            // XML FileStorage writes a size as the text `w h`.
            Value::String(s) => s
                .split_whitespace()
                .map(|t| Value::String(t.to_string()))
                .collect(),
            _ => Vec::new(),
        };
        let [w, h] = pair.as_slice() else {
            return Err(Error::input(format!(
                "`{key}` must be the image's [width, height], got {v}"
            )));
        };
        found.push((format!("`{key}`"), (side(w, key)?, side(h, key)?)));
    }
    let Some((first_key, first)) = found.first().cloned() else {
        return Ok(None);
    };
    if let Some((key, s)) = found.iter().find(|(_, s)| *s != first) {
        return Err(Error::input(format!(
            "{first_key} gives an image size of {}×{}, {key} {}×{}",
            first.0, first.1, s.0, s.1
        )));
    }
    Ok(Some(first))
}

/// A calibrated pair as a file gives it: two cameras and the transform between them.
#[derive(Debug, Clone)]
pub struct StereoPair {
    /// The format the file was read as ([`FORMAT`] or a Kalibr camchain).
    pub format: &'static str,
    /// The cameras' names as the file writes them (`M1` and `M2`, `cam0` and `cam1`, …).
    pub names: [String; 2],
    /// The first camera.
    pub left: Camera,
    /// The second camera.
    pub right: Camera,
    /// R: X2 = R·X1 + T.
    pub rotation: PairRotation,
    /// T, in the file's units.
    pub translation: [f64; 3],
}

/// R and T: X2 = R·X1 + T.
pub type Extrinsics = (PairRotation, [f64; 3]);

/// [`parse_stereo_pair`] of a file.
pub fn load_stereo_pair(
    path: &Path,
    size: Option<(u32, u32)>,
    extrinsics: Option<Extrinsics>,
) -> Result<StereoPair> {
    let text =
        super::read_text(path).map_err(|e| Error::io(path, "cannot read stereo pair file", &e))?;
    parse_stereo_pair(&text, &path.display().to_string(), size, extrinsics)
}

/// The pair a file's text holds: an OpenCV stereo calibration file with `R` and `T`, or a
/// Kalibr camchain's first two cameras and the second's `T_cn_cnm1`. `size` is the image size
/// for a file that gives none; `extrinsics`, where given, are R and T instead of the file's
/// (which it then need not have: `stereo_calib.cpp` writes them to a file of their own);
/// `origin` names the file in errors.
pub fn parse_stereo_pair(
    text: &str,
    origin: &str,
    size: Option<(u32, u32)>,
    extrinsics: Option<Extrinsics>,
) -> Result<StereoPair> {
    let tree = super::camera::text_tree(text, origin).map_err(|e| e.context(origin))?;
    let listing = super::camera::listing_from_tree(&tree, size);
    let obj = tree.as_object();
    let pair = match (listing.format, obj) {
        (super::camera::KALIBR_FORMAT, Some(obj)) => kalibr_pair(obj, listing, extrinsics),
        (FORMAT, Some(obj)) => opencv_pair(obj, listing, extrinsics),
        (format, _) => Err(Error::input(format!(
            "not a stereo pair: read as {} with {} camera(s); a pair is an OpenCV stereo calibration file (M1 D1 M2 D2 R T, or K1/K2, cameraMatrix1/2, cameraMatrixL/R) or a Kalibr camchain (cam0, cam1 and cam1's T_cn_cnm1); two camera files and R and T do as well",
            format,
            listing.cameras.len()
        ))),
    };
    pair.map_err(|e| e.context(origin))
}

/// The cameras named `a` and `b` of a listing, each loaded (or why not, naming it).
fn two_cameras(listing: Listing, a: &str, b: &str) -> Result<(Camera, Camera)> {
    let mut found = listing.cameras.into_iter();
    let mut take = |name: &str| -> Result<Camera> {
        let f = found
            .find(|f| f.name == name)
            .ok_or_else(|| Error::internal(format!("camera `{name}` was listed but not found")))?;
        f.camera.map_err(|e| e.context(format!("`{name}`")))
    };
    Ok((take(a)?, take(b)?))
}

/// The pair of a Kalibr camchain: its first two cameras, and the second's `T_cn_cnm1`.
fn kalibr_pair(
    obj: &Map<String, Value>,
    listing: Listing,
    extrinsics: Option<Extrinsics>,
) -> Result<StereoPair> {
    let names: Vec<String> = listing.cameras.iter().map(|f| f.name.clone()).collect();
    let [a, b] = match names.as_slice() {
        [a, b, ..] => [a.clone(), b.clone()],
        _ => {
            return Err(Error::input(format!(
            "a Kalibr camchain with {} camera(s) ({}): a pair needs two, the second with T_cn_cnm1",
            names.len(),
            names.join(", ")
        )))
        }
    };
    let (rotation, translation) = match extrinsics {
        Some(rt) => rt,
        None => kalibr_transform(obj, &a, &b)?,
    };
    let (left, right) = two_cameras(listing, &a, &b)?;
    Ok(StereoPair {
        format: super::camera::KALIBR_FORMAT,
        names: [a, b],
        left,
        right,
        rotation,
        translation,
    })
}

/// R and T of `b`'s `T_cn_cnm1`, the transform from `a`'s frame to `b`'s.
fn kalibr_transform(obj: &Map<String, Value>, a: &str, b: &str) -> Result<Extrinsics> {
    let key = format!("{b}.T_cn_cnm1");
    let m = obj
        .get(b)
        .and_then(|cam| cam.get("T_cn_cnm1"))
        .ok_or_else(|| {
            Error::input(format!(
                "missing `{key}`, the 4×4 transform from {a}'s frame to {b}'s that Kalibr writes for the second camera of a chain"
            ))
        })?;
    let rows: Vec<f64> = match m {
        Value::Array(rows) if rows.iter().all(Value::is_array) => {
            let mut all = Vec::new();
            for (i, row) in rows.iter().enumerate() {
                let row = number_list(row, &format!("{key}[{i}]"))?;
                if row.len() != 4 {
                    return Err(Error::input(format!(
                        "`{key}` must be 4 rows of 4 numbers; row {i} has {}",
                        row.len()
                    )));
                }
                all.extend(row);
            }
            all
        }
        other => number_list(other, &key)?,
    };
    if rows.len() != 16 {
        return Err(Error::input(format!(
            "`{key}` must be a 4×4 matrix (4 rows of 4 numbers), got {} numbers",
            rows.len()
        )));
    }
    let last = [rows[12], rows[13], rows[14], rows[15]];
    if last != [0.0, 0.0, 0.0, 1.0] {
        return Err(Error::input(format!(
            "`{key}`'s last row is {last:?}; a rigid transform's is [0, 0, 0, 1]"
        )));
    }
    let rotation = PairRotation::Matrix([
        [rows[0], rows[1], rows[2]],
        [rows[4], rows[5], rows[6]],
        [rows[8], rows[9], rows[10]],
    ]);
    Ok((rotation, [rows[3], rows[7], rows[11]]))
}

/// The pair of an OpenCV stereo calibration file: the first layout whose two camera matrices
/// it holds, and its `R` and `T`.
fn opencv_pair(
    obj: &Map<String, Value>,
    listing: Listing,
    extrinsics: Option<Extrinsics>,
) -> Result<StereoPair> {
    let present: Vec<&str> = listing.cameras.iter().map(|f| f.name.as_str()).collect();
    let Some([(a, _), (b, _)]) = CAMERAS
        .chunks_exact(2)
        .find(|pair| pair.iter().all(|(m, _)| present.contains(m)))
        .and_then(|pair| <[(&str, &str); 2]>::try_from(pair).ok())
    else {
        return Err(Error::input(format!(
            "holds the camera matrix {} only: a pair needs both cameras' (M1 and M2, K1 and K2, cameraMatrix1 and cameraMatrix2, or cameraMatrixL and cameraMatrixR)",
            present.iter().map(|m| format!("`{m}`")).collect::<Vec<_>>().join(", ")
        )));
    };
    let (rotation, translation) = match extrinsics {
        Some(rt) => rt,
        None => extrinsics_of(obj)?,
    };
    let (left, right) = two_cameras(listing, a, b)?;
    Ok(StereoPair {
        format: FORMAT,
        names: [a.to_string(), b.to_string()],
        left,
        right,
        rotation,
        translation,
    })
}

/// `R` and `T` of an OpenCV FileStorage tree (a stereo calibration file, or
/// `stereo_calib.cpp`'s `extrinsics.yml`): R a 3×3 matrix or a Rodrigues vector, T three
/// numbers; the error names the key.
pub fn extrinsics_of(obj: &Map<String, Value>) -> Result<Extrinsics> {
    for (key, what) in [
        (
            "R",
            "the rotation from the first camera's frame to the second's",
        ),
        ("T", "the translation between them"),
    ] {
        if !obj.contains_key(key) {
            return Err(Error::input(format!(
                "missing `{key}`, {what} (X2 = R·X1 + T, as cv2.stereoCalibrate gives them)"
            )));
        }
    }
    let r = matrix_values(obj, "R")?;
    let rotation = match r.as_slice() {
        [a, b, c, d, e, f, g, h, i] => {
            PairRotation::Matrix([[*a, *b, *c], [*d, *e, *f], [*g, *h, *i]])
        }
        [x, y, z] => PairRotation::Rodrigues([*x, *y, *z]),
        _ => {
            return Err(Error::input(format!(
                "`R` must have 9 entries (a 3×3 rotation) or 3 (a Rodrigues vector), got {}",
                r.len()
            )))
        }
    };
    let t = matrix_values(obj, "T")?;
    let translation: [f64; 3] = t
        .as_slice()
        .try_into()
        .map_err(|_| Error::input(format!("`T` must have 3 entries, got {}", t.len())))?;
    Ok((rotation, translation))
}

/// [`extrinsics_of`] a file's text; `origin` names it in errors.
pub fn parse_extrinsics(text: &str, origin: &str) -> Result<Extrinsics> {
    let tree = super::camera::text_tree(text, origin).map_err(|e| e.context(origin))?;
    let obj = tree.as_object().ok_or_else(|| {
        Error::input(format!(
            "{origin}: expected a mapping of keys (R, T), got {tree}"
        ))
    })?;
    extrinsics_of(obj).map_err(|e| e.context(origin))
}

/// [`parse_extrinsics`] of a file.
pub fn load_extrinsics(path: &Path) -> Result<Extrinsics> {
    let text =
        super::read_text(path).map_err(|e| Error::io(path, "cannot read extrinsics file", &e))?;
    parse_extrinsics(&text, &path.display().to_string())
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use serde_json::json;

    use super::*;

    const RAYS: [DVec3; 3] = [
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(0.3, -0.2, 1.0),
        DVec3::new(-0.4, 0.3, 1.0),
    ];

    /// The tree the caller hands the reader: the text through the YAML reader camera files
    /// go through (OpenCV's quirks included).
    fn yaml(text: &str) -> Value {
        crate::io::camera::yaml_to_tree(text).expect("valid YAML")
    }

    const INTRINSICS: &str = "%YAML:1.0
---
M1: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 5.348125e+02, 0., 3.4125e+02, 0.,
       5.3628125e+02, 2.35375e+02, 0., 0., 1. ]
D1: !!opencv-matrix
   rows: 1
   cols: 5
   dt: d
   data: [ -2.7500e-01, 1.0500e-01, 1.5e-003, -6.5e-004, -1.5e-002 ]
M2: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 5.348125e+02, 0., 3.344375e+02, 0.,
       5.3628125e+02, 2.41875e+02, 0., 0., 1. ]
D2: !!opencv-matrix
   rows: 1
   cols: 8
   dt: d
   data: [ -2.8e-01, 9.3e-02, -5.5e-04, 1.1e-04, 0., 0., 0., 1.5e-02 ]
";

    fn standard(k: [f64; 4], d: &[f64], w: u32, h: u32) -> Camera {
        let k = Intrinsics {
            fx: k[0],
            fy: k[1],
            cx: k[2],
            cy: k[3],
        };
        Camera::from_coeffs(w, h, k, d).expect("camera")
    }

    fn same(a: &Camera, b: &Camera) {
        assert_eq!((a.width, a.height), (b.width, b.height));
        assert_eq!(a.intrinsics, b.intrinsics);
        assert_eq!(a.dist_coeffs(), b.dist_coeffs());
        for p in RAYS {
            assert_eq!(a.project(p), b.project(p), "{p}");
        }
    }

    #[test]
    fn stereo_calib_intrinsics_yml() {
        let tree = yaml(INTRINSICS);
        let l = listing_from_tree(&tree, Some((640, 480))).expect("detected");
        assert_eq!(l.format, FORMAT);
        let names: Vec<&str> = l.cameras.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["M1", "M2"]);
        let mut cams = l.cameras.into_iter().map(|f| f.camera.expect("loads"));
        let m1 = cams.next().expect("M1");
        let m2 = cams.next().expect("M2");
        same(
            &m1,
            &standard(
                [5.348125e+02, 5.3628125e+02, 3.4125e+02, 2.35375e+02],
                &[-2.75e-01, 1.05e-01, 1.5e-3, -6.5e-4, -1.5e-2],
                640,
                480,
            ),
        );
        same(
            &m2,
            &standard(
                [5.348125e+02, 5.3628125e+02, 3.344375e+02, 2.41875e+02],
                &[-2.8e-01, 9.3e-02, -5.5e-04, 1.1e-04, 0., 0., 0., 1.5e-02],
                640,
                480,
            ),
        );
        // stereo_calib.cpp writes no size: without one from the caller, each camera says so.
        let l = listing_from_tree(&tree, None).expect("detected");
        for f in l.cameras {
            let e = f.camera.expect_err("no size").to_string();
            assert!(e.contains("`size`"), "{e}");
        }
    }

    #[test]
    fn camera_matrix_names_and_sizes() {
        let k = json!({"rows": 3, "cols": 3, "dt": "d",
            "data": [500.5, 0, 320.25, 0, 501.5, 240.75, 0, 0, 1]});
        let d = json!({"rows": 1, "cols": 4, "dt": "d", "data": [-0.1, 0.01, 0.001, -0.002]});
        for (names, size) in [
            (
                [
                    "cameraMatrix1",
                    "distCoeffs1",
                    "cameraMatrix2",
                    "distCoeffs2",
                ],
                json!({"imageSize": [752, 480]}),
            ),
            (
                ["K1", "D1", "K2", "D2"],
                json!({"image_width": 752, "image_height": 480}),
            ),
            (
                [
                    "cameraMatrixL",
                    "distCoeffsL",
                    "cameraMatrixR",
                    "distCoeffsR",
                ],
                json!({"image_size": "752 480", "width": "752", "height": 480}),
            ),
        ] {
            let mut tree = size.clone();
            for (i, key) in names.iter().enumerate() {
                tree[*key] = if i % 2 == 0 { k.clone() } else { d.clone() };
            }
            let l = listing_from_tree(&tree, None).expect("detected");
            let got: Vec<&str> = l.cameras.iter().map(|f| f.name.as_str()).collect();
            assert_eq!(got, [names[0], names[2]]);
            let want = standard(
                [500.5, 501.5, 320.25, 240.75],
                &[-0.1, 0.01, 0.001, -0.002],
                752,
                480,
            );
            for f in l.cameras {
                same(&f.camera.expect("loads"), &want);
            }
        }
    }

    #[test]
    fn xml_tree_with_text_values() {
        // XML FileStorage arrives with `data` as a list of strings and scalars as text.
        let tree = json!({
            "M1": {"rows": "3", "cols": "3", "dt": "d",
                "data": ["500.", "0.", "320.", "0.", "500.", "240.", "0.", "0.", "1."]},
            "D1": {"rows": "1", "cols": "5", "dt": "d",
                "data": ["-1.0e-01", "0.", "0.", "0.", "0."]},
            "imageSize": "640 480",
        });
        let l = listing_from_tree(&tree, None).expect("detected");
        assert_eq!(l.cameras.len(), 1);
        let c = l
            .cameras
            .into_iter()
            .next()
            .expect("M1")
            .camera
            .expect("loads");
        same(
            &c,
            &standard(
                [500.0, 500.0, 320.0, 240.0],
                &[-0.1, 0., 0., 0., 0.],
                640,
                480,
            ),
        );
    }

    #[test]
    fn errors_name_the_key() {
        let k = json!({"rows": 3, "cols": 3, "data": [500, 0, 320, 0, 500, 240, 0, 0, 1]});
        let error = |tree: Value| -> String {
            let l = listing_from_tree(&tree, Some((640, 480))).expect("detected");
            let f = l.cameras.into_iter().next().expect("one");
            f.camera.expect_err("refused").to_string()
        };
        let e = error(json!({"M1": k}));
        assert!(e.contains("`D1`") && e.contains("M1"), "{e}");
        let e = error(json!({"M1": k, "D1": {"rows": 1, "cols": 3, "data": [0.1, 0.2, 0.3]}}));
        assert!(e.contains("`D1`") && e.contains('3'), "{e}");
        let e = error(
            json!({"M1": {"rows": 3, "cols": 3, "data": [500, 1, 320, 0, 500, 240, 0, 0, 1]}, "D1": [0, 0, 0, 0]}),
        );
        assert!(e.contains("`M1`") && e.contains("skew"), "{e}");
        let e = error(
            json!({"M1": {"rows": 2, "cols": 3, "data": [500, 0, 320, 0, 500, 240]}, "D1": [0, 0, 0, 0]}),
        );
        assert!(e.contains("`M1`") && e.contains("9 entries"), "{e}");
        let e = error(
            json!({"M1": {"rows": 3, "cols": 3, "data": [500, 0, 320, 0, 500, 240, 0, 0]}, "D1": [0, 0, 0, 0]}),
        );
        assert!(e.contains("`M1`") && e.contains("3×3"), "{e}");
        let e = error(json!({"M1": k, "D1": [0, 0, 0, 0], "image_width": 640}));
        assert!(e.contains("image_height"), "{e}");
        let e = error(
            json!({"M1": k, "D1": [0, 0, 0, 0], "imageSize": [640, 480], "width": 800, "height": 600}),
        );
        assert!(e.contains("imageSize") && e.contains("800×600"), "{e}");
    }

    #[test]
    fn other_trees_are_left_alone() {
        let m = json!({"rows": 3, "cols": 3, "data": [1, 0, 0, 0, 1, 0, 0, 0, 1]});
        for tree in [
            // stereo_calib.cpp's extrinsics.yml.
            json!({"R": m, "T": {"rows": 3, "cols": 1, "data": [0.1, 0, 0]},
                "R1": m, "R2": m, "P1": m, "P2": m, "Q": m}),
            json!({"camera_matrix": m, "distortion_coefficients": [0, 0, 0, 0, 0],
                "image_width": 640, "image_height": 480}),
            json!({"width": 640, "height": 480, "fx": 500, "fy": 500, "cx": 320, "cy": 240}),
            json!({"cam0": {"camera_model": "pinhole"}}),
            json!({"model_type": "PINHOLE", "K1": 0.1}),
            json!({"value0": {}}),
        ] {
            assert!(listing_from_tree(&tree, None).is_none(), "{tree}");
        }
    }

    /// The pair's R and T as a test compares them: a matrix row-major, or the vector.
    fn matrix_of(r: PairRotation) -> [[f64; 3]; 3] {
        match r {
            PairRotation::Matrix(m) => m,
            PairRotation::Rodrigues(v) => panic!("expected a matrix, got the vector {v:?}"),
        }
    }

    const STEREO_CALIBRATE: &str = "%YAML:1.0
---
imageSize: [ 640, 480 ]
K1: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 600., 0., 330.25, 0., 610., 236.5, 0., 0., 1. ]
D1: !!opencv-matrix
   rows: 1
   cols: 5
   dt: d
   data: [ -0.05, 0.01, 1.0e-03, -1.5e-03, 0. ]
K2: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 605., 0., 322.25, 0., 603., 240.125, 0., 0., 1. ]
D2: !!opencv-matrix
   rows: 1
   cols: 5
   dt: d
   data: [ -0.06, 0.012, -5.0e-04, 1.0e-03, 0. ]
R: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 0.5, -0.75, 0.25, 0.125, 0.5, 0.875, -0.375, 0.0625, 1. ]
T: !!opencv-matrix
   rows: 3
   cols: 1
   dt: d
   data: [ -0.12, 3.0e-03, 1.0e-03 ]
";

    #[test]
    fn an_opencv_stereo_file_gives_its_pair() {
        let pair = parse_stereo_pair(STEREO_CALIBRATE, "stereo.yml", None, None).expect("a pair");
        assert_eq!(pair.format, FORMAT);
        assert_eq!(pair.names, ["K1".to_string(), "K2".to_string()]);
        same(
            &pair.left,
            &standard(
                [600.0, 610.0, 330.25, 236.5],
                &[-0.05, 0.01, 1e-3, -1.5e-3, 0.0],
                640,
                480,
            ),
        );
        same(
            &pair.right,
            &standard(
                [605.0, 603.0, 322.25, 240.125],
                &[-0.06, 0.012, -5e-4, 1e-3, 0.0],
                640,
                480,
            ),
        );
        // R as the file writes it (whether it is a rotation is the rectification's to say).
        assert_eq!(
            matrix_of(pair.rotation),
            [
                [0.5, -0.75, 0.25],
                [0.125, 0.5, 0.875],
                [-0.375, 0.0625, 1.0]
            ]
        );
        assert_eq!(pair.translation, [-0.12, 3e-3, 1e-3]);
        // stereo_calib.cpp's intrinsics.yml has no R and T: its extrinsics.yml gives them.
        let given = (PairRotation::Rodrigues([0.0, 0.1, 0.0]), [-0.1, 0.0, 0.0]);
        let pair = parse_stereo_pair(INTRINSICS, "intrinsics.yml", Some((640, 480)), Some(given))
            .expect("a pair");
        assert_eq!(pair.names, ["M1".to_string(), "M2".to_string()]);
        assert_eq!((pair.rotation, pair.translation), given);
        let e = parse_stereo_pair(INTRINSICS, "intrinsics.yml", Some((640, 480)), None)
            .expect_err("no R")
            .to_string();
        assert!(
            e.starts_with("intrinsics.yml") && e.contains("missing `R`"),
            "{e}"
        );
        // A Rodrigues vector for R, and R and T alone (stereo_calib.cpp's extrinsics.yml).
        let tree =
            json!({"R": [0.01, -0.02, 0.005], "T": {"rows": 3, "cols": 1, "data": [1, 2, 3]}});
        let (r, t) = extrinsics_of(tree.as_object().expect("a mapping")).expect("R and T");
        assert_eq!(r, PairRotation::Rodrigues([0.01, -0.02, 0.005]));
        assert_eq!(t, [1.0, 2.0, 3.0]);
    }

    const CAMCHAIN: &str = "cam0:
  camera_model: pinhole
  intrinsics: [461.5, 460.25, 363.0, 248.125]
  distortion_model: radtan
  distortion_coeffs: [-0.2917, 0.0823, 5.3e-05, -1.6e-04]
  resolution: [752, 480]
cam1:
  T_cn_cnm1:
  - [0.5, -0.75, 0.25, -0.11]
  - [0.125, 0.5, 0.875, 0.0004]
  - [-0.375, 0.0625, 1.0, 0.0012]
  - [0.0, 0.0, 0.0, 1.0]
  camera_model: pinhole
  intrinsics: [458.75, 457.25, 367.25, 248.375]
  distortion_model: radtan
  distortion_coeffs: [-0.2834, 0.0739, -1.9e-04, 1.8e-05]
  resolution: [752, 480]
";

    #[test]
    fn a_kalibr_camchain_gives_its_first_two_cameras() {
        let pair = parse_stereo_pair(CAMCHAIN, "camchain.yaml", None, None).expect("a pair");
        assert_eq!(pair.format, crate::io::camera::KALIBR_FORMAT);
        assert_eq!(pair.names, ["cam0".to_string(), "cam1".to_string()]);
        same(
            &pair.left,
            &standard(
                [461.5, 460.25, 363.0, 248.125],
                &[-0.2917, 0.0823, 5.3e-05, -1.6e-04],
                752,
                480,
            ),
        );
        same(
            &pair.right,
            &standard(
                [458.75, 457.25, 367.25, 248.375],
                &[-0.2834, 0.0739, -1.9e-04, 1.8e-05],
                752,
                480,
            ),
        );
        // T_cn_cnm1 maps cam0's frame to cam1's: X1 = R X0 + T, OpenCV's R and T.
        assert_eq!(
            matrix_of(pair.rotation),
            [
                [0.5, -0.75, 0.25],
                [0.125, 0.5, 0.875],
                [-0.375, 0.0625, 1.0]
            ]
        );
        assert_eq!(pair.translation, [-0.11, 0.0004, 0.0012]);
    }

    #[test]
    fn pair_errors_name_the_file_and_key() {
        let error = |text: &str| -> String {
            parse_stereo_pair(text, "pair.yaml", Some((640, 480)), None)
                .expect_err("refused")
                .to_string()
        };
        let without = |key: &str| {
            let mut out = String::new();
            let mut skipping = false;
            for line in STEREO_CALIBRATE.lines() {
                if !line.starts_with(' ') {
                    skipping = line.starts_with(&format!("{key}:"));
                }
                if !skipping {
                    out.push_str(line);
                    out.push('\n');
                }
            }
            out
        };
        let e = error(&without("T"));
        assert!(
            e.starts_with("pair.yaml") && e.contains("missing `T`"),
            "{e}"
        );
        let e = error(&without("R"));
        assert!(e.contains("missing `R`"), "{e}");
        let e = error(
            &STEREO_CALIBRATE
                .replace("rows: 3\n   cols: 1", "rows: 4\n   cols: 1")
                .replace(
                    "[ -0.12, 3.0e-03, 1.0e-03 ]",
                    "[ -0.12, 3.0e-03, 1.0e-03, 5. ]",
                ),
        );
        assert!(e.contains("`T` must have 3 entries, got 4"), "{e}");
        let e = error(
            &STEREO_CALIBRATE
                .replace("0.0625, 1. ]", "0.0625 ]")
                .replace(
                    "R: !!opencv-matrix\n   rows: 3\n   cols: 3",
                    "R: !!opencv-matrix\n   rows: 1\n   cols: 8",
                ),
        );
        assert!(
            e.contains("`R` must have 9 entries") && e.contains("got 8"),
            "{e}"
        );
        let e = error(&without("K2"));
        assert!(e.contains("`K1` only") && e.contains("pair"), "{e}");
        let e = error(&STEREO_CALIBRATE.replace("data: [ -0.06", "data: [ oops"));
        assert!(e.contains("`K2`") && e.contains("D2"), "{e}");
        // Kalibr: the transform's key, its shape and its last row.
        let e = error(&CAMCHAIN.replace("  T_cn_cnm1:", "  T_other:"));
        assert!(e.contains("missing `cam1.T_cn_cnm1`"), "{e}");
        let e = error(&CAMCHAIN.replace("  - [0.0, 0.0, 0.0, 1.0]\n", ""));
        assert!(
            e.contains("`cam1.T_cn_cnm1` must be a 4×4 matrix") && e.contains("12"),
            "{e}"
        );
        let e = error(&CAMCHAIN.replace("[0.5, -0.75, 0.25, -0.11]", "[0.5, -0.75, 0.25]"));
        assert!(
            e.contains("`cam1.T_cn_cnm1`") && e.contains("row 0 has 3"),
            "{e}"
        );
        let e = error(&CAMCHAIN.replace("[0.0, 0.0, 0.0, 1.0]", "[0.0, 0.0, 0.1, 1.0]"));
        assert!(e.contains("last row"), "{e}");
        let first = CAMCHAIN.split("cam1:").next().expect("cam0");
        let e = error(first);
        assert!(e.contains("1 camera(s)") && e.contains("cam0"), "{e}");
        // A file that is no pair says what one is.
        let e = error(
            "{\"width\": 640, \"height\": 480, \"fx\": 500, \"fy\": 500, \"cx\": 320, \"cy\": 240}",
        );
        assert!(
            e.contains("not a stereo pair") && e.contains("T_cn_cnm1"),
            "{e}"
        );
        let e = parse_extrinsics("R: [1, 0, 0]\n", "extrinsics.yml")
            .expect_err("no T")
            .to_string();
        assert!(
            e.starts_with("extrinsics.yml") && e.contains("missing `T`"),
            "{e}"
        );
    }
}
