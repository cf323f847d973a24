//! The camera files of the TUM direct-SLAM family, plain text detected from the text itself:
//!
//! * **DSO / DM-VIO `camera.txt`** (format name "DSO camera.txt"), as DSO's
//!   `Undistort::getUndistorterForFile` reads it. Line 1 is the model and its parameters:
//!
//!   | line 1                                   | vklens model                                   |
//!   |------------------------------------------|------------------------------------------------|
//!   | `RadTan fx fy cx cy k1 k2 r1 r2`         | OpenCV standard, coefficients k1 k2 p1 p2 (DSO's r1 r2 are OpenCV's p1 p2) |
//!   | `EquiDistant fx fy cx cy k1 k2 k3 k4`    | OpenCV fisheye k1..k4                           |
//!   | `KannalaBrandt fx fy cx cy k0 k1 k2 k3`  | OpenCV fisheye (DSO's k0..k3 are OpenCV's k1..k4) |
//!   | `FOV fx fy cx cy ω`                      | FOV / ATAN (Devernay–Faugeras)                  |
//!   | `Pinhole fx fy cx cy x`                  | pinhole (DSO ignores the fifth number)          |
//!   | 8 bare numbers                           | as `RadTan` (DSO's backward-compatible form)    |
//!   | 5 bare numbers, the fifth 0              | pinhole                                         |
//!   | 5 bare numbers, the fifth ω ≠ 0          | FOV / ATAN                                      |
//!
//!   Line 2 is the input image's `width height`; lines 3 and 4 (`crop`, `full`, `none` or an
//!   output calibration, then the output size) describe the rectified image DSO makes, not the
//!   camera, and are not read. A file without line 2 takes its size from the caller
//!   ([`size_or`]).
//!
//!   DSO's "relative" calibration: where `cx < 1` and `cy < 1` (both), DSO takes all four
//!   intrinsics as fractions of the image size and converts them to pixels as
//!   `fx·w, fy·h, cx·w − 0.5, cy·h − 0.5` (its comment: the file's pixel (0, 0) covers
//!   [0, 1]², DSO's is centred on 0). vklens converts the same way; ω and the distortion
//!   coefficients are unchanged.
//!
//! * **LSD-SLAM / PTAM** (format name "LSD-SLAM/PTAM camera file"), the ATAN camera both
//!   write in normalized units:
//!   - LSD-SLAM's `.cfg` is DSO's bare five-number layout (`fx fy cx cy ω`, then `width
//!     height`). LSD-SLAM's `UndistorterPTAM` *always* reads it as relative, with the same
//!     −0.5 as DSO (`cx·w − 0.5`). A five-number file with `cx < 1` and `cy < 1` therefore
//!     means the same to both programs and is named so; one in pixels only DSO reads, and it
//!     is named "DSO camera.txt".
//!   - PTAM's `camera.cfg`: a line `Camera.Parameters=[ fx fy cx cy ω ]` (GVars3 syntax;
//!     other lines and `//` or `#` comments are skipped), always relative. PTAM's
//!     `ATANCamera::RefreshParams` converts with `fx·w, fy·h, cx·w − 0.5, cy·h − 0.5` too, at
//!     the size of the images it is given: the file holds no size, so the caller gives it.
//!
//!   Eight bare numbers with `cx < 1` and `cy < 1` are refused: DSO reads them as relative
//!   with the −0.5 above, LSD-SLAM's `UndistorterOpenCV` as relative without it (`cx·w`), and
//!   nothing in the file says which program it was written for. In pixels, or prefixed
//!   `RadTan` (which only DSO reads), they load.
//!
//! Every camera of these formats is unnamed (`""`). The FOV model's formula in DSO, LSD-SLAM
//! and PTAM, `r_d = atan(2 r tan(ω/2)) / ω`, is the one of [`Fov`]; DSO's `EquiDistant` and
//! `KannalaBrandt` both evaluate `θ (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸)` on `θ = atan(r)`,
//! OpenCV's fisheye model.

use super::camera::parse_float;
use super::catalog::{size_or, Listing};
use crate::model::fov::Fov;
use crate::model::{Camera, Fisheye, Intrinsics, Lens};
use crate::{Error, Result};

/// The format name of a DSO / DM-VIO camera file.
pub const DSO_FORMAT: &str = "DSO camera.txt";
/// The format name of an LSD-SLAM or PTAM ATAN camera file.
pub const LSD_PTAM_FORMAT: &str = "LSD-SLAM/PTAM camera file";

/// DSO's model words, as its `getUndistorterForFile` spells them, with the parameter names
/// each takes after `fx fy cx cy`.
const MODELS: [(&str, &[&str]); 5] = [
    ("RadTan", &["k1", "k2", "r1", "r2"]),
    ("EquiDistant", &["k1", "k2", "k3", "k4"]),
    ("KannalaBrandt", &["k0", "k1", "k2", "k3"]),
    ("FOV", &["omega"]),
    ("Pinhole", &["(ignored)"]),
];

/// The camera of the file, if the text is a DSO / DM-VIO `camera.txt` or an LSD-SLAM / PTAM
/// `.cfg`.
pub fn listing_from_text(text: &str, size: Option<(u32, u32)>) -> Option<Listing> {
    let text = text.trim_start_matches('\u{feff}');
    if let Some((line_no, value)) = ptam_parameters_line(text) {
        let camera = ptam_camera(text, line_no, value, size);
        return Some(Listing::one(LSD_PTAM_FORMAT, "", camera));
    }
    let lines: Vec<&str> = text.lines().map(|l| l.trim_end_matches('\r')).collect();
    // DSO reads its first line as it stands; blank lines before it are forgiven.
    let first = lines.iter().position(|l| !l.trim().is_empty())?;
    let tokens: Vec<&str> = lines[first].split_whitespace().collect();
    let line = |i: usize| lines.get(first + i).copied();
    let line_no = first + 1;
    if let Some(&(word, names)) = MODELS
        .iter()
        .find(|(w, _)| w.eq_ignore_ascii_case(tokens[0]))
    {
        // A model word followed by a number: DSO's layout. (The number keeps a YAML key or a
        // sentence that starts with one of these words from being taken for it.)
        tokens.get(1).and_then(|t| parse_float(t))?;
        let camera = (|| {
            if tokens[0] != word {
                return Err(Error::input(format!(
                    "line {line_no}: DSO spells the model `{word}` (it compares the word exactly), this file writes `{}`",
                    tokens[0]
                )));
            }
            let p = numbers(&tokens[1..], line_no, word, names)?;
            let file_size = size_line(line(1), line_no + 1)?;
            dso_camera(word, &p, file_size, size, line_no)
        })();
        return Some(Listing::one(DSO_FORMAT, "", camera));
    }
    if !tokens.iter().all(|t| parse_float(t).is_some()) {
        return None;
    }
    // Bare numbers: DSO's backward-compatible forms and LSD-SLAM's. Only 5 or 8 are one of
    // them; another count is claimed (and refused) only when line 3 is DSO's rectification
    // word, so that other files of plain numbers are left to their readers.
    let rectification = line(2).map(str::trim);
    if ![5, 8].contains(&tokens.len()) && !matches!(rectification, Some("crop" | "full" | "none")) {
        return None;
    }
    let relative_five = tokens.len() == 5 && {
        let p: Vec<f64> = tokens.iter().filter_map(|t| parse_float(t)).collect();
        p[2] < 1.0 && p[3] < 1.0
    };
    let format = if relative_five {
        LSD_PTAM_FORMAT
    } else {
        DSO_FORMAT
    };
    let camera = (|| {
        let p: Vec<f64> = tokens.iter().filter_map(|t| parse_float(t)).collect();
        let file_size = size_line(line(1), line_no + 1)?;
        match p.len() {
            8 => {
                if p[2] < 1.0 && p[3] < 1.0 {
                    return Err(Error::input(format!(
                        "line {line_no}: eight bare numbers with cx = {} and cy = {} below 1 are a relative calibration, which DSO converts with cx·w − 0.5 and LSD-SLAM with cx·w (no −0.5); nothing in the file says which program it is for. Write the intrinsics in pixels, or start the line with `RadTan` (DSO's form)",
                        p[2], p[3]
                    )));
                }
                dso_camera("RadTan", &p, file_size, size, line_no)
            }
            5 if p[4] == 0.0 => dso_camera("Pinhole", &p, file_size, size, line_no),
            5 => dso_camera("FOV", &p, file_size, size, line_no),
            n => Err(Error::input(format!(
                "line {line_no}: a camera file of bare numbers has 5 (fx fy cx cy ω: FOV/ATAN, or pinhole with ω = 0) or 8 (fx fy cx cy k1 k2 r1 r2: RadTan), this line has {n}"
            ))),
        }
    })();
    Some(Listing::one(format, "", camera))
}

/// `fx fy cx cy` and the model's own parameters from `tokens` (after the model word).
fn numbers(tokens: &[&str], line_no: usize, word: &str, names: &[&str]) -> Result<Vec<f64>> {
    let expected = 4 + names.len();
    if tokens.len() != expected {
        return Err(Error::input(format!(
            "line {line_no}: `{word}` takes {expected} numbers (fx fy cx cy {}), got {}",
            names.join(" "),
            tokens.len()
        )));
    }
    tokens
        .iter()
        .map(|t| {
            parse_float(t).ok_or_else(|| {
                Error::input(format!(
                    "line {line_no}: `{t}` is not a number (in `{word} {}`)",
                    tokens.join(" ")
                ))
            })
        })
        .collect()
}

/// The `width height` line, if the file has one.
fn size_line(line: Option<&str>, line_no: usize) -> Result<Option<(u32, u32)>> {
    let Some(line) = line.map(str::trim).filter(|l| !l.is_empty()) else {
        return Ok(None);
    };
    let t: Vec<&str> = line.split_whitespace().collect();
    let side = |s: &str| {
        s.parse::<u32>()
            .ok()
            .filter(|v| (1..=crate::model::MAX_IMAGE_SIDE).contains(v))
    };
    match t.as_slice() {
        [w, h] => match (side(w), side(h)) {
            (Some(w), Some(h)) => Ok(Some((w, h))),
            _ => Err(Error::input(format!(
                "line {line_no}: the input image's width and height must be whole numbers of pixels in 1..={}, got `{line}`",
                crate::model::MAX_IMAGE_SIDE
            ))),
        },
        _ => Err(Error::input(format!(
            "line {line_no} must be the input image's `width height` (two whole numbers), got `{line}`"
        ))),
    }
}

/// The camera of DSO model `word` with parameters `p` (`fx fy cx cy` first), converting a
/// relative calibration (`cx < 1` and `cy < 1`) to pixels as DSO does.
fn dso_camera(
    word: &str,
    p: &[f64],
    file_size: Option<(u32, u32)>,
    given: Option<(u32, u32)>,
    line_no: usize,
) -> Result<Camera> {
    let (width, height) = size_or(file_size, given)?;
    let relative = p[2] < 1.0 && p[3] < 1.0;
    let intrinsics = if relative {
        relative_intrinsics(p, width, height)
    } else {
        Intrinsics {
            fx: p[0],
            fy: p[1],
            cx: p[2],
            cy: p[3],
        }
    };
    let at =
        |e: crate::model::ModelError| Error::input(format!("line {line_no}: `{word}` camera: {e}"));
    let rest = &p[4..];
    match word {
        "RadTan" => Camera::from_coeffs(width, height, intrinsics, rest).map_err(at),
        "EquiDistant" | "KannalaBrandt" => {
            let k = [rest[0], rest[1], rest[2], rest[3]];
            let lens = Fisheye::new(k, 0.0, None).map_err(at)?;
            Camera::fisheye(width, height, intrinsics, lens).map_err(at)
        }
        "FOV" => {
            let lens = Lens::Fov(Fov::new(rest[0]).map_err(at)?);
            Camera::with_lens(width, height, intrinsics, lens).map_err(at)
        }
        _ => Camera::from_coeffs(width, height, intrinsics, &[0.0; 4]).map_err(at),
    }
}

/// Relative intrinsics (fractions of the image size) in pixels: DSO's, LSD-SLAM's ATAN and
/// PTAM's rule, `fx·w, fy·h, cx·w − 0.5, cy·h − 0.5`.
fn relative_intrinsics(p: &[f64], width: u32, height: u32) -> Intrinsics {
    let (w, h) = (f64::from(width), f64::from(height));
    Intrinsics {
        fx: p[0] * w,
        fy: p[1] * h,
        cx: p[2] * w - 0.5,
        cy: p[3] * h - 0.5,
    }
}

/// The line (1-based) and value of PTAM's `Camera.Parameters=[ ... ]`, if the text has one
/// (outside comments).
fn ptam_parameters_line(text: &str) -> Option<(usize, &str)> {
    text.lines().enumerate().find_map(|(i, l)| {
        let l = l.trim();
        let rest = l.strip_prefix("Camera.Parameters")?;
        let value = rest.trim_start().strip_prefix('=')?;
        Some((i + 1, value.trim()))
    })
}

/// The camera of a PTAM `camera.cfg`.
fn ptam_camera(
    text: &str,
    line_no: usize,
    value: &str,
    given: Option<(u32, u32)>,
) -> Result<Camera> {
    let key = "Camera.Parameters";
    let twice = text
        .lines()
        .enumerate()
        .filter(|(i, _)| *i + 1 != line_no)
        .any(|(_, l)| {
            let l = l.trim();
            !(l.starts_with("//") || l.starts_with('#')) && l.starts_with(key)
        });
    if twice {
        return Err(Error::input(format!(
            "`{key}` is set on more than one line: the file says two things about one camera"
        )));
    }
    // GVars3 ends a value at a comment.
    let value = value.split("//").next().unwrap_or("").trim();
    let inner = value
        .strip_prefix('[')
        .and_then(|v| v.strip_suffix(']'))
        .ok_or_else(|| {
            Error::input(format!(
                "line {line_no}: `{key}` must be a bracketed list `[ fx fy cx cy ω ]`, got `{value}`"
            ))
        })?;
    let t: Vec<&str> = inner.split_whitespace().collect();
    if t.len() != 5 {
        return Err(Error::input(format!(
            "line {line_no}: `{key}` has 5 numbers (fx fy cx cy ω, relative to the image size), got {}",
            t.len()
        )));
    }
    let p = t
        .iter()
        .map(|s| {
            parse_float(s).ok_or_else(|| {
                Error::input(format!("line {line_no}: `{key}`: `{s}` is not a number"))
            })
        })
        .collect::<Result<Vec<f64>>>()?;
    // PTAM's file holds no image size: it scales the parameters to the images it is given.
    let (width, height) = size_or(None, given)?;
    let intrinsics = relative_intrinsics(&p, width, height);
    let at = |e: crate::model::ModelError| Error::input(format!("line {line_no}: `{key}`: {e}"));
    if p[4] == 0.0 {
        // PTAM turns the distortion off at ω = 0: a pinhole.
        return Camera::from_coeffs(width, height, intrinsics, &[0.0; 4]).map_err(at);
    }
    let lens = Lens::Fov(Fov::new(p[4]).map_err(at)?);
    Camera::with_lens(width, height, intrinsics, lens).map_err(at)
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;

    const RAYS: [DVec3; 4] = [
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(0.3, -0.2, 1.0),
        DVec3::new(-0.5, 0.4, 1.0),
        DVec3::new(0.1, 0.6, 0.8),
    ];

    fn same(a: &Camera, b: &Camera) {
        assert_eq!((a.width, a.height), (b.width, b.height));
        assert_eq!(a.model(), b.model());
        for p in RAYS {
            assert_eq!(a.project(p), b.project(p), "{p}");
        }
    }

    fn read(text: &str, size: Option<(u32, u32)>) -> Listing {
        listing_from_text(text, size).expect("detected")
    }

    fn camera(text: &str, size: Option<(u32, u32)>) -> (&'static str, Camera) {
        let l = read(text, size);
        assert_eq!(l.cameras.len(), 1);
        assert_eq!(l.cameras[0].name, "");
        let format = l.format;
        let c = l.cameras.into_iter().next().expect("one").camera;
        (format, c.expect("loads"))
    }

    fn error(text: &str, size: Option<(u32, u32)>) -> String {
        let l = read(text, size);
        let c = l.cameras.into_iter().next().expect("one").camera;
        c.expect_err("refused").to_string()
    }

    fn k(fx: f64, fy: f64, cx: f64, cy: f64) -> Intrinsics {
        Intrinsics { fx, fy, cx, cy }
    }

    #[test]
    fn radtan_in_pixels() {
        let text = "RadTan 460.5 458.25 367.125 248.5 -0.28 0.07 0.0002 -0.00002\n752 480\ncrop\n640 480\n";
        let (format, c) = camera(text, None);
        assert_eq!(format, DSO_FORMAT);
        let want = Camera::from_coeffs(
            752,
            480,
            k(460.5, 458.25, 367.125, 248.5),
            &[-0.28, 0.07, 0.0002, -0.00002],
        )
        .expect("camera");
        same(&c, &want);
        // The size given must agree with the file's.
        assert!(camera(text, Some((752, 480))).1.width == 752);
        let e = error(text, Some((640, 480)));
        assert!(e.contains("752×480"), "{e}");
    }

    #[test]
    fn equidistant_and_kannala_brandt_are_the_fisheye() {
        for word in ["EquiDistant", "KannalaBrandt"] {
            let text = format!("{word} 380.5 381.25 510.5 512.75 0.01 -0.002 0.0003 -0.00004\n1024 1024\nnone\n1024 1024\n");
            let (format, c) = camera(&text, None);
            assert_eq!(format, DSO_FORMAT);
            let lens = Fisheye::new([0.01, -0.002, 0.0003, -0.00004], 0.0, None).expect("lens");
            let want =
                Camera::fisheye(1024, 1024, k(380.5, 381.25, 510.5, 512.75), lens).expect("cam");
            same(&c, &want);
        }
    }

    #[test]
    fn fov_relative_converts_like_dso() {
        // DSO's relative form: cx, cy < 1, converted with fx·w, cx·w − 0.5.
        let text = "FOV 0.5 0.625 0.4921875 0.5 0.9\n1280 1024\ncrop\n640 480\n";
        let (format, c) = camera(text, None);
        assert_eq!(format, DSO_FORMAT);
        let want = Camera::with_lens(
            1280,
            1024,
            k(640.0, 640.0, 629.5, 511.5),
            Lens::Fov(Fov::new(0.9).expect("fov")),
        )
        .expect("camera");
        same(&c, &want);
    }

    #[test]
    fn pinhole_ignores_its_fifth_number() {
        let (_, c) = camera("Pinhole 500 501 320.5 240.25 0\n640 480\n", None);
        let want = Camera::from_coeffs(640, 480, k(500.0, 501.0, 320.5, 240.25), &[0.0; 4])
            .expect("camera");
        same(&c, &want);
        assert!(c.is_pinhole());
    }

    #[test]
    fn bare_five_numbers_are_lsd_slam_atan_or_pinhole() {
        // Relative: LSD-SLAM's layout, read alike by DSO.
        let text = "0.5 0.625 0.5 0.5 0.75\n640 480\ncrop\n640 480\n";
        let (format, c) = camera(text, None);
        assert_eq!(format, LSD_PTAM_FORMAT);
        let want = Camera::with_lens(
            640,
            480,
            k(320.0, 300.0, 319.5, 239.5),
            Lens::Fov(Fov::new(0.75).expect("fov")),
        )
        .expect("camera");
        same(&c, &want);
        // ω = 0: the pinhole.
        let (_, c) = camera("0.5 0.625 0.5 0.5 0\n640 480\n", None);
        assert!(c.is_pinhole());
        // In pixels: only DSO reads it.
        let (format, c) = camera("320 300 319.5 239.5 0.75\n640 480\n", None);
        assert_eq!(format, DSO_FORMAT);
        same(&c, &want);
    }

    #[test]
    fn bare_eight_numbers_are_radtan() {
        let text = "458.5 457.25 367.5 248.25 -0.28 0.07 0.0002 0.00002\n752 480\ncrop\n752 480\n";
        let (format, c) = camera(text, None);
        assert_eq!(format, DSO_FORMAT);
        let want = Camera::from_coeffs(
            752,
            480,
            k(458.5, 457.25, 367.5, 248.25),
            &[-0.28, 0.07, 0.0002, 0.00002],
        )
        .expect("camera");
        same(&c, &want);
        // Relative bare RadTan: DSO and LSD-SLAM disagree by half a pixel.
        let e = error("0.6 0.9 0.49 0.51 -0.28 0.07 0 0\n752 480\n", None);
        assert!(e.contains("LSD-SLAM") && e.contains("RadTan"), "{e}");
        // Prefixed, it is DSO's and converts.
        let (_, c) = camera(
            "RadTan 0.625 0.9375 0.5 0.5 -0.28 0.07 0 0\n752 480\n",
            None,
        );
        assert_eq!(c.intrinsics, k(470.0, 450.0, 375.5, 239.5));
    }

    #[test]
    fn ptam_camera_cfg() {
        let text = "// PTAM camera\nCamera.Parameters=[ 0.5 0.75 0.5 0.5 0.1 ]\n";
        let (format, c) = camera(text, Some((640, 480)));
        assert_eq!(format, LSD_PTAM_FORMAT);
        let want = Camera::with_lens(
            640,
            480,
            k(320.0, 360.0, 319.5, 239.5),
            Lens::Fov(Fov::new(0.1).expect("fov")),
        )
        .expect("camera");
        same(&c, &want);
        // No size in the file: the caller must give one.
        let e = error(text, None);
        assert!(e.contains("`size`"), "{e}");
        let e = error(
            "Camera.Parameters = [ 0.5 0.75 0.5 0.5 ]\n",
            Some((640, 480)),
        );
        assert!(
            e.contains("Camera.Parameters") && e.contains("5 numbers"),
            "{e}"
        );
        let twice = "Camera.Parameters=[ 0.5 0.75 0.5 0.5 0.1 ]\nCamera.Parameters=[ 0.5 0.75 0.5 0.5 0.2 ]\n";
        assert!(error(twice, Some((640, 480))).contains("more than one line"));
    }

    #[test]
    fn size_comes_from_the_caller_when_missing() {
        let e = error("RadTan 460 458 367 248 -0.28 0.07 0 0\n", None);
        assert!(e.contains("`size`"), "{e}");
        let (_, c) = camera("RadTan 460 458 367 248 -0.28 0.07 0 0\n", Some((752, 480)));
        assert_eq!((c.width, c.height), (752, 480));
    }

    #[test]
    fn errors_name_the_line() {
        let e = error("RadTan 460 458 367 248 -0.28 0.07 0\n752 480\n", None);
        assert!(e.contains("line 1") && e.contains("8 numbers"), "{e}");
        let e = error("FOV 0.5 0.6 0.5 0.5 x\n752 480\n", None);
        assert!(e.contains("line 1") && e.contains("`x`"), "{e}");
        let e = error("FOV 0.5 0.6 0.5 0.5 0.9\n752\n", None);
        assert!(e.contains("line 2"), "{e}");
        let e = error("Equidistant 380 381 510 512 0 0 0 0\n1024 1024\n", None);
        assert!(e.contains("EquiDistant"), "{e}");
        let e = error("1 2 3 4 5 6\n752 480\ncrop\n752 480\n", None);
        assert!(e.contains("5") && e.contains("8"), "{e}");
        // An invalid parameter is the model's error, with the line.
        let e = error("FOV 300 300 320 240 4\n640 480\n", None);
        assert!(e.contains("line 1") && e.contains("omega"), "{e}");
    }

    #[test]
    fn other_formats_are_left_alone() {
        for text in [
            "",
            "{\"width\": 640, \"height\": 480, \"fx\": 500}",
            "%YAML:1.0\ncamera_matrix: !!opencv-matrix\n",
            "cam0:\n  camera_model: pinhole\n",
            "# Camera list with one line of data per camera:\n1 PINHOLE 640 480 500 500 320 240\n",
            "1 PINHOLE 640 480 500 500 320 240\n",
            "#polynomial coefficients for the DIRECT mapping function (ocam_model.ss in MATLAB). These are used by cam2world\n\n5 -1 0 0 0 0\n",
            "model_type: PINHOLE\ncamera_name: cam\n",
            "FOV: 90\n",
            "1 2 3\n",
        ] {
            assert!(listing_from_text(text, None).is_none(), "{text}");
        }
    }
}
