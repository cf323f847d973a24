//! Gyroflow lens profiles (JSON, format name "Gyroflow lens profile"), read as Gyroflow's
//! renderer applies them (`LensProfile::get_camera_matrix` and the undistortion kernels'
//! `rotate_and_distort`). Detected by `fisheye_params` or `calib_dimension`, keys no other
//! camera format vklens reads has.
//!
//! Keys read:
//!
//! * `calib_dimension: {w, h}`: the size of the calibration images.
//! * `fisheye_params.camera_matrix: [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]` and
//!   `fisheye_params.distortion_coeffs`.
//! * `distortion_model`: absent, `null` or `"opencv_fisheye"` is OpenCV's fisheye model
//!   (k1..k4); `"opencv_standard"` is OpenCV's standard model (k1 k2 p1 p2 [k3 [k4 k5 k6 [s1..s4]]],
//!   4, 5, 8 or 12 coefficients: Gyroflow evaluates 12 and would drop a tilt). Every other
//!   model (`poly3`, `poly5`, `ptlens`, `insta360`, `sony`, `gopro`, …) is refused by name:
//!   vklens has none of them.
//! * `asymmetrical`: unless it is `true`, Gyroflow puts the principal point at the centre of
//!   the calibration image, `(w/2, h/2)`, whatever `camera_matrix` says (its `cx cy` are the
//!   calibration's estimate, which Gyroflow does not use); vklens does the same, so that the
//!   camera is the one Gyroflow renders with. Gyroflow's pixel centres are at whole
//!   coordinates, as OpenCV's and vklens's, so `w/2` carries over unchanged.
//! * `crop`: where present, Gyroflow divides `fx` and `fy` by it; so does vklens.
//! * `input_horizontal_stretch`, `input_vertical_stretch` (anamorphic footage; Gyroflow takes
//!   a value ≤ 0.01, its default 0, as 1). Gyroflow calibrates on frames resized by the
//!   stretch (`calib_dimension` is the recorded size times the stretch, rounded), and renders
//!   a recorded frame of `W×H` pixels by scaling the matrix by `W/w · stretch` and dividing
//!   the resulting pixel by the stretch: the recorded frame's pixel is exactly
//!   `(W/w)·(fx·x + cx)`, `(H/h)·(fy·y + cy)`. vklens converts to that camera of the recorded
//!   frames. Their size is the size asked (`--size`), which must round to `calib_dimension`
//!   when stretched as Gyroflow does; with none asked, `calib_dimension / stretch`, which
//!   must then be whole pixels (else the recorded size is not in the file, and the error says
//!   to pass it). Without a stretch the size is `calib_dimension`, and a different size asked
//!   is refused as for every format ([`size_or`]).
//! * `digital_lens`: a second, digital distortion (GoPro SuperView, HyperView, …) Gyroflow
//!   applies after the lens's; a non-empty value is refused by name, since vklens would
//!   otherwise render without it.
//! * `camera_brand`, `camera_model`, `lens_model`: the camera's name, the non-empty ones
//!   joined by spaces.
//!
//! Keys not read, and why:
//!
//! * `fisheye_params.radial_distortion_limit`: Gyroflow recomputes it from the coefficients
//!   whenever it loads a profile (`LensProfile::init`), so the stored value never takes
//!   effect. It is `tan θ` of the angle where `θ_d` stops growing (found by bisection to
//!   1e-4 rad); vklens's fisheye finds that fold itself, exactly, and ends its domain there,
//!   so mapping the stored value to `max_fov_deg` would replace an exact limit by an
//!   approximate, possibly stale one.
//! * `output_dimension`: the size of Gyroflow's stabilized output, not of the camera.
//! * `RMS_error`, `fps`, `frame_readout_time`, `sync_settings`, `compatible_settings`,
//!   `interpolations`, `focal_length`, `crop_factor`: timing, synchronisation and other
//!   settings' profiles, which do not change this camera.
//!
//! One Gyroflow quirk is kept: its fisheye model returns the pinhole point when all four
//! coefficients are 0 (not the equidistant fisheye that k = 0 means in OpenCV), so such a
//! profile is a pinhole camera.

use serde_json::{Map, Value};

use super::camera::{as_number, image_side_of, number_list};
use super::catalog::{size_or, Listing};
use crate::model::{Camera, Fisheye, Intrinsics, ModelError};
use crate::{Error, Result};

/// The format name of a Gyroflow lens profile.
pub const FORMAT: &str = "Gyroflow lens profile";

/// The distortion models of Gyroflow that vklens reads.
const MODELS: [&str; 2] = ["opencv_fisheye", "opencv_standard"];

/// The cameras of the file, if the tree is in this format.
pub fn listing_from_tree(tree: &Value, size: Option<(u32, u32)>) -> Option<Listing> {
    let obj = tree.as_object()?;
    if !(obj.contains_key("fisheye_params") || obj.contains_key("calib_dimension")) {
        return None;
    }
    let name = ["camera_brand", "camera_model", "lens_model"]
        .iter()
        .filter_map(|k| obj.get(*k).and_then(Value::as_str).map(str::trim))
        .filter(|s| !s.is_empty())
        .collect::<Vec<_>>()
        .join(" ");
    Some(Listing::one(FORMAT, name, profile_camera(obj, size)))
}

/// The camera of a lens profile, for the recorded frames (see the module documentation).
fn profile_camera(obj: &Map<String, Value>, size: Option<(u32, u32)>) -> Result<Camera> {
    match obj.get("digital_lens") {
        None | Some(Value::Null) => {}
        Some(Value::String(s)) if s.is_empty() => {}
        Some(Value::String(s)) => {
            return Err(Error::input(format!(
                "`digital_lens` is `{s}`: Gyroflow applies that digital distortion after the lens's, and vklens has no model of it (it would render without it); refusing rather than ignoring it"
            )))
        }
        Some(other) => {
            return Err(Error::input(format!(
                "`digital_lens` must be a name or null, got {other}"
            )))
        }
    }
    let model = match obj.get("distortion_model") {
        None | Some(Value::Null) => "opencv_fisheye",
        Some(Value::String(s)) if MODELS.contains(&s.as_str()) => s.as_str(),
        Some(Value::String(s)) => {
            return Err(Error::input(format!(
                "`distortion_model` is `{s}`, a Gyroflow model vklens does not have; it reads `{}`",
                MODELS.join("` and `")
            )))
        }
        Some(other) => {
            return Err(Error::input(format!(
                "`distortion_model` must be a model name, got {other}"
            )))
        }
    };
    let calib = calib_dimension(obj)?;
    let params = obj
        .get("fisheye_params")
        .and_then(Value::as_object)
        .ok_or_else(|| Error::input("missing object `fisheye_params`"))?;
    let matrix = camera_matrix(params)?;
    let coeffs = match params.get("distortion_coeffs") {
        Some(v) => number_list(v, "fisheye_params.distortion_coeffs")?,
        None => Vec::new(),
    };
    if coeffs.is_empty() {
        return Err(Error::input(
            "`fisheye_params.distortion_coeffs` is missing or empty: Gyroflow then takes the lens from the video's metadata, which a profile alone does not hold",
        ));
    }
    let asymmetrical = match obj.get("asymmetrical") {
        None | Some(Value::Null) => false,
        Some(Value::Bool(b)) => *b,
        Some(other) => {
            return Err(Error::input(format!(
                "`asymmetrical` must be true or false, got {other}"
            )))
        }
    };
    let crop = match obj.get("crop") {
        None | Some(Value::Null) => 1.0,
        Some(v) => as_number(v)
            .filter(|c| c.is_finite() && *c > 0.0)
            .ok_or_else(|| {
                Error::input(format!(
                    "`crop` must be a positive number (Gyroflow divides fx and fy by it), got {v}"
                ))
            })?,
    };
    let (width, height) = recorded_size(obj, calib, size)?;
    // Gyroflow's pixel of the recorded frame: (W/w)·(fx·x + cx), (H/h)·(fy·y + cy).
    let sx = f64::from(width) / f64::from(calib.0);
    let sy = f64::from(height) / f64::from(calib.1);
    let (cx, cy) = if asymmetrical {
        (matrix[0][2], matrix[1][2])
    } else {
        (f64::from(calib.0) / 2.0, f64::from(calib.1) / 2.0)
    };
    let intrinsics = Intrinsics {
        fx: matrix[0][0] / crop * sx,
        fy: matrix[1][1] / crop * sy,
        cx: cx * sx,
        cy: cy * sy,
    };
    let named = |e: ModelError| Error::input(format!("`{model}`: {e}"));
    if model == "opencv_standard" {
        if ![4, 5, 8, 12].contains(&coeffs.len()) {
            return Err(Error::input(format!(
                "`fisheye_params.distortion_coeffs`: Gyroflow's `opencv_standard` evaluates 4, 5, 8 or 12 coefficients (k1 k2 p1 p2 k3 k4 k5 k6 s1 s2 s3 s4), this profile has {}",
                coeffs.len()
            )));
        }
        return Camera::from_coeffs(width, height, intrinsics, &coeffs).map_err(named);
    }
    let k: [f64; 4] = coeffs.as_slice().try_into().map_err(|_| {
        Error::input(format!(
            "`fisheye_params.distortion_coeffs`: the OpenCV fisheye model has 4 coefficients (k1..k4), this profile has {}",
            coeffs.len()
        ))
    })?;
    if k == [0.0; 4] {
        // Gyroflow's fisheye returns the undistorted point when every coefficient is 0.
        return Camera::from_coeffs(width, height, intrinsics, &[0.0; 4]).map_err(named);
    }
    let lens = Fisheye::new(k, 0.0, None).map_err(named)?;
    Camera::fisheye(width, height, intrinsics, lens).map_err(named)
}

/// `calib_dimension: {w, h}`.
fn calib_dimension(obj: &Map<String, Value>) -> Result<(u32, u32)> {
    let dim = obj
        .get("calib_dimension")
        .and_then(Value::as_object)
        .ok_or_else(|| {
            Error::input("missing object `calib_dimension` ({w, h}: the calibration image size)")
        })?;
    let side = |key: &str| -> Result<u32> {
        let v = dim
            .get(key)
            .ok_or_else(|| Error::input(format!("missing `calib_dimension.{key}`")))?;
        let n = as_number(v).ok_or_else(|| {
            Error::input(format!("`calib_dimension.{key}` must be a number, got {v}"))
        })?;
        image_side_of(n, &format!("`calib_dimension.{key}`"))
    };
    Ok((side("w")?, side("h")?))
}

/// `fisheye_params.camera_matrix`: three rows of three numbers, without skew.
fn camera_matrix(params: &Map<String, Value>) -> Result<[[f64; 3]; 3]> {
    let key = "fisheye_params.camera_matrix";
    let v = params
        .get("camera_matrix")
        .ok_or_else(|| Error::input(format!("missing `{key}`")))?;
    let rows = v
        .as_array()
        .filter(|r| r.len() == 3)
        .ok_or_else(|| Error::input(format!("`{key}` must be 3 rows of 3 numbers, got {v}")))?;
    let mut m = [[0.0; 3]; 3];
    for (i, row) in rows.iter().enumerate() {
        let r = number_list(row, &format!("{key}[{i}]"))?;
        m[i] = r.as_slice().try_into().map_err(|_| {
            Error::input(format!("`{key}[{i}]` must have 3 numbers, got {}", r.len()))
        })?;
    }
    for (i, j, want) in [
        (0, 1, 0.0),
        (1, 0, 0.0),
        (2, 0, 0.0),
        (2, 1, 0.0),
        (2, 2, 1.0),
    ] {
        if m[i][j] != want {
            return Err(Error::input(format!(
                "`{key}[{i}][{j}]` is {}; a Gyroflow camera matrix is [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] (Gyroflow calibrates without skew and would ignore it)",
                m[i][j]
            )));
        }
    }
    Ok(m)
}

/// A stretch as Gyroflow takes it: a value above 0.01, else none (1).
fn stretch(obj: &Map<String, Value>, key: &str) -> Result<f64> {
    match obj.get(key) {
        None | Some(Value::Null) => Ok(1.0),
        Some(v) => {
            let s = as_number(v)
                .filter(|s| s.is_finite())
                .ok_or_else(|| Error::input(format!("`{key}` must be a number, got {v}")))?;
            Ok(if s > 0.01 { s } else { 1.0 })
        }
    }
}

/// The size of the recorded frames the camera is for.
fn recorded_size(
    obj: &Map<String, Value>,
    calib: (u32, u32),
    given: Option<(u32, u32)>,
) -> Result<(u32, u32)> {
    let (hs, vs) = (
        stretch(obj, "input_horizontal_stretch")?,
        stretch(obj, "input_vertical_stretch")?,
    );
    if hs == 1.0 && vs == 1.0 {
        return size_or(Some(calib), given);
    }
    let what = format!(
        "the profile was calibrated on frames stretched {hs}× horizontally and {vs}× vertically (`input_horizontal_stretch`, `input_vertical_stretch`) to {}×{}",
        calib.0, calib.1
    );
    match given {
        Some((w, h)) => {
            let stretched = ((f64::from(w) * hs).round(), (f64::from(h) * vs).round());
            if stretched != (f64::from(calib.0), f64::from(calib.1)) {
                return Err(Error::input(format!(
                    "{what}; recorded frames of {w}×{h} stretch to {}×{}, so the profile is not for them",
                    stretched.0, stretched.1
                )));
            }
            Ok((w, h))
        }
        None => {
            let (w, h) = (f64::from(calib.0) / hs, f64::from(calib.1) / vs);
            if w.fract() != 0.0 || h.fract() != 0.0 {
                return Err(Error::argument(
                    "size",
                    format!("{what}, and {w}×{h} is not a whole number of pixels: give the recorded frames' size"),
                ));
            }
            Ok((
                image_side_of(w, "width (calib_dimension.w / input_horizontal_stretch)")?,
                image_side_of(h, "height (calib_dimension.h / input_vertical_stretch)")?,
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use serde_json::json;

    use super::*;

    const RAYS: [DVec3; 4] = [
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(0.3, -0.2, 1.0),
        DVec3::new(-0.9, 0.7, 1.0),
        DVec3::new(0.1, 0.6, 0.5),
    ];

    fn same(a: &Camera, b: &Camera) {
        assert_eq!((a.width, a.height), (b.width, b.height));
        assert_eq!(a.model(), b.model());
        assert_eq!(a.intrinsics, b.intrinsics);
        for p in RAYS {
            assert_eq!(a.project(p), b.project(p), "{p}");
        }
    }

    fn profile() -> Value {
        json!({
            "name": "Brand_Model_Lens_4k",
            "camera_brand": "Brand",
            "camera_model": "Model X",
            "lens_model": "",
            "calib_dimension": {"w": 3840, "h": 2160},
            "orig_dimension": {"w": 3840, "h": 2160},
            "output_dimension": {"w": 3840, "h": 2160},
            "input_horizontal_stretch": 1.0,
            "input_vertical_stretch": 1.0,
            "fisheye_params": {
                "RMS_error": 0.41,
                "camera_matrix": [[1820.5, 0.0, 1915.25], [0.0, 1818.75, 1083.5], [0.0, 0.0, 1.0]],
                "distortion_coeffs": [0.051, 0.013, -0.0021, 0.00042],
                "radial_distortion_limit": null
            },
            "distortion_model": null,
            "digital_lens": null,
            "calibrator_version": "1.5.4"
        })
    }

    fn load(tree: &Value, size: Option<(u32, u32)>) -> Result<Camera> {
        let l = listing_from_tree(tree, size).expect("detected");
        assert_eq!(l.format, FORMAT);
        assert_eq!(l.cameras.len(), 1);
        l.cameras.into_iter().next().expect("one").camera
    }

    fn fisheye(w: u32, h: u32, k: Intrinsics) -> Camera {
        let lens = Fisheye::new([0.051, 0.013, -0.0021, 0.00042], 0.0, None).expect("lens");
        Camera::fisheye(w, h, k, lens).expect("camera")
    }

    #[test]
    fn symmetric_profile_centres_the_principal_point() {
        let tree = profile();
        let l = listing_from_tree(&tree, None).expect("detected");
        assert_eq!(l.cameras[0].name, "Brand Model X");
        let c = load(&tree, None).expect("loads");
        let k = Intrinsics {
            fx: 1820.5,
            fy: 1818.75,
            cx: 1920.0,
            cy: 1080.0,
        };
        same(&c, &fisheye(3840, 2160, k));
        // "opencv_fisheye" spelled out is the same.
        let mut t = profile();
        t["distortion_model"] = json!("opencv_fisheye");
        same(&load(&t, Some((3840, 2160))).expect("loads"), &c);
    }

    #[test]
    fn asymmetrical_profile_keeps_the_matrix_centre_and_crop_scales_focal() {
        let mut t = profile();
        t["asymmetrical"] = json!(true);
        t["crop"] = json!(1.25);
        let c = load(&t, None).expect("loads");
        let k = Intrinsics {
            fx: 1820.5 / 1.25,
            fy: 1818.75 / 1.25,
            cx: 1915.25,
            cy: 1083.5,
        };
        same(&c, &fisheye(3840, 2160, k));
    }

    #[test]
    fn anamorphic_stretch_converts_to_the_recorded_frames() {
        let mut t = profile();
        t["input_horizontal_stretch"] = json!(2.0);
        t["calib_dimension"] = json!({"w": 3840, "h": 1080});
        // No size asked: 3840 / 2 = 1920 recorded pixels.
        let c = load(&t, None).expect("loads");
        let k = Intrinsics {
            fx: 1820.5 * (1920.0 / 3840.0),
            fy: 1818.75,
            cx: 1920.0 * (1920.0 / 3840.0),
            cy: 540.0,
        };
        same(&c, &fisheye(1920, 1080, k));
        // A size that stretches to the calibration size (1.33 × 1444 = 1920.52 → 1921).
        t["input_horizontal_stretch"] = json!(1.33);
        t["calib_dimension"] = json!({"w": 1921, "h": 1080});
        let e = load(&t, None).expect_err("size not in file").to_string();
        assert!(
            e.contains("`size`") && e.contains("input_horizontal_stretch"),
            "{e}"
        );
        let c = load(&t, Some((1444, 1080))).expect("loads");
        let s = 1444.0 / 1921.0;
        let k = Intrinsics {
            fx: 1820.5 * s,
            fy: 1818.75,
            cx: 960.5 * s,
            cy: 540.0,
        };
        same(&c, &fisheye(1444, 1080, k));
        let e = load(&t, Some((1921, 1080)))
            .expect_err("wrong size")
            .to_string();
        assert!(e.contains("not for them"), "{e}");
        // Gyroflow takes 0 (its default) as no stretch.
        let mut t = profile();
        t["input_horizontal_stretch"] = json!(0);
        t["input_vertical_stretch"] = json!(0.0);
        assert_eq!(load(&t, None).expect("loads").width, 3840);
    }

    #[test]
    fn opencv_standard_and_zero_fisheye() {
        let mut t = profile();
        t["distortion_model"] = json!("opencv_standard");
        t["fisheye_params"]["distortion_coeffs"] = json!([-0.21, 0.05, 0.001, -0.0005, 0.002]);
        let c = load(&t, None).expect("loads");
        let k = Intrinsics {
            fx: 1820.5,
            fy: 1818.75,
            cx: 1920.0,
            cy: 1080.0,
        };
        let want = Camera::from_coeffs(3840, 2160, k, &[-0.21, 0.05, 0.001, -0.0005, 0.002])
            .expect("camera");
        same(&c, &want);
        // Gyroflow's fisheye with k = 0 is the pinhole.
        let mut t = profile();
        t["fisheye_params"]["distortion_coeffs"] = json!([0, 0, 0, 0]);
        let c = load(&t, None).expect("loads");
        assert!(c.is_pinhole());
    }

    #[test]
    fn refusals_name_what_is_refused() {
        for model in ["poly3", "poly5", "ptlens", "insta360", "sony", "gopro"] {
            let mut t = profile();
            t["distortion_model"] = json!(model);
            let e = load(&t, None).expect_err(model).to_string();
            assert!(e.contains(model) && e.contains("distortion_model"), "{e}");
        }
        let mut t = profile();
        t["digital_lens"] = json!("gopro_superview");
        let e = load(&t, None).expect_err("digital").to_string();
        assert!(
            e.contains("gopro_superview") && e.contains("digital_lens"),
            "{e}"
        );
        t["digital_lens"] = json!("");
        assert!(load(&t, None).is_ok());

        let mut t = profile();
        t["fisheye_params"]["distortion_coeffs"] = json!([0.1, 0.2, 0.3]);
        let e = load(&t, None).expect_err("3 coefficients").to_string();
        assert!(e.contains("distortion_coeffs") && e.contains('3'), "{e}");
        let mut t = profile();
        t["fisheye_params"]["distortion_coeffs"] = json!([]);
        assert!(load(&t, None)
            .expect_err("empty")
            .to_string()
            .contains("distortion_coeffs"));
        let mut t = profile();
        t["fisheye_params"]["camera_matrix"][0][1] = json!(2.0);
        let e = load(&t, None).expect_err("skew").to_string();
        assert!(e.contains("camera_matrix[0][1]"), "{e}");
        let mut t = profile();
        t["fisheye_params"]["camera_matrix"] = json!([[1, 0, 2], [0, 1, 2]]);
        assert!(load(&t, None)
            .expect_err("rows")
            .to_string()
            .contains("camera_matrix"));
        let mut t = profile();
        t.as_object_mut().expect("object").remove("calib_dimension");
        let e = load(&t, None).expect_err("no size").to_string();
        assert!(e.contains("calib_dimension"), "{e}");
        let mut t = profile();
        t["calib_dimension"] = json!({"w": 3840});
        let e = load(&t, None).expect_err("no h").to_string();
        assert!(e.contains("calib_dimension.h"), "{e}");
        let mut t = profile();
        t.as_object_mut().expect("object").remove("fisheye_params");
        let e = load(&t, None).expect_err("no params").to_string();
        assert!(e.contains("fisheye_params"), "{e}");
        // A size other than the calibration's is refused (no silent rescale).
        let e = load(&profile(), Some((1920, 1080)))
            .expect_err("size")
            .to_string();
        assert!(e.contains("3840×2160"), "{e}");
    }

    #[test]
    fn other_trees_are_left_alone() {
        for tree in [
            json!({"width": 640, "height": 480, "fx": 500, "fy": 500, "cx": 320, "cy": 240}),
            json!({"camera_matrix": {"rows": 3, "cols": 3, "data": [1, 0, 0, 0, 1, 0, 0, 0, 1]}}),
            json!({"cam0": {"camera_model": "pinhole"}}),
            json!({"model_type": "PINHOLE"}),
            json!({"value0": {}}),
            json!([1, 2]),
        ] {
            assert!(listing_from_tree(&tree, None).is_none(), "{tree}");
        }
    }
}
