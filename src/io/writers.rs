//! Writing a camera in another tool's format (`vklens convert`): vklens JSON, OpenCV
//! FileStorage YAML, ROS `camera_info`, a Kalibr camchain, COLMAP `cameras.txt` and Basalt's
//! calibration JSON. A format that cannot hold the camera exactly (ROS has no double sphere,
//! Kalibr's radtan no k3) is refused with the reason, never written approximately: what is
//! written reads back to a camera that projects every point as the original does.

use std::fmt::Write as _;
use std::str::FromStr;

use serde_json::json;

use crate::model::{Camera, Lens};
use crate::{Error, Result};

/// The formats `vklens convert --to` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Vklens,
    Opencv,
    Ros,
    Kalibr,
    Colmap,
    Basalt,
}

impl Format {
    pub const ALL: [Format; 6] = [
        Format::Vklens,
        Format::Opencv,
        Format::Ros,
        Format::Kalibr,
        Format::Colmap,
        Format::Basalt,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Format::Vklens => "vklens",
            Format::Opencv => "opencv",
            Format::Ros => "ros",
            Format::Kalibr => "kalibr",
            Format::Colmap => "colmap",
            Format::Basalt => "basalt",
        }
    }

    /// What the written file is, for messages.
    pub fn describe(self) -> &'static str {
        match self {
            Format::Vklens => "vklens camera JSON",
            Format::Opencv => "OpenCV FileStorage YAML",
            Format::Ros => "ROS camera_info",
            Format::Kalibr => "Kalibr camchain",
            Format::Colmap => "COLMAP cameras.txt",
            Format::Basalt => "Basalt calibration JSON",
        }
    }
}

impl FromStr for Format {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Format::ALL
            .into_iter()
            .find(|f| f.name() == s)
            .ok_or_else(|| {
                Error::input(format!(
                    "unknown format `{s}`; vklens writes {}",
                    Format::ALL.map(Format::name).join(", ")
                ))
            })
    }
}

/// Shortest text that reads back to the same f64.
fn num(x: f64) -> String {
    format!("{x:?}")
}

fn list(v: &[f64]) -> String {
    v.iter().map(|&x| num(x)).collect::<Vec<_>>().join(", ")
}

fn cannot(format: Format, why: String) -> Error {
    Error::Unsupported(format!(
        "{} cannot hold this camera: {why} (vklens JSON holds every camera)",
        format.describe()
    ))
}

/// The standard model's coefficients, if only the first `n` may be non-zero (else the error
/// names the first one that is not).
fn standard_coeffs(camera: &Camera, n: usize, format: Format, what: &str) -> Result<Vec<f64>> {
    let c = camera.distortion().to_coeffs();
    if let Some(i) = (n..c.len()).find(|&i| c[i] != 0.0) {
        return Err(cannot(
            format,
            format!(
                "{what}, and this camera's {} is {}",
                crate::model::opencv::COEFFICIENT_NAMES[i],
                c[i]
            ),
        ));
    }
    Ok(c[..n].to_vec())
}

/// The plain fisheye (no skew, no field-of-view limit) these formats hold.
fn plain_fisheye(camera: &Camera, format: Format) -> Result<[f64; 4]> {
    let Some(f) = camera.fisheye_lens() else {
        return Err(cannot(format, "not a fisheye".into()));
    };
    if f.alpha != 0.0 {
        return Err(cannot(
            format,
            format!(
                "its fisheye has no skew, and this camera's alpha is {}",
                f.alpha
            ),
        ));
    }
    if let Some(fov) = f.max_fov_deg() {
        return Err(cannot(
            format,
            format!("it has no field-of-view limit, and this camera's max_fov_deg is {fov}"),
        ));
    }
    Ok(f.k)
}

/// The camera in `format`; `name` names it where the format does (Kalibr's `cam0`).
pub fn write_camera(camera: &Camera, format: Format) -> Result<String> {
    if camera.brown().is_some() && format != Format::Vklens {
        return Err(cannot(
            format,
            "a Brown headset lens (c1, c2) is vklens's own model".into(),
        ));
    }
    match format {
        Format::Vklens => Ok(format!("{:#}\n", camera.to_json())),
        Format::Ros => {
            if let Some(fov) = camera.fisheye_lens().and_then(|f| f.max_fov_deg()) {
                return Err(cannot(
                    format,
                    format!(
                        "it has no field-of-view limit, and this camera's max_fov_deg is {fov}"
                    ),
                ));
            }
            camera.to_ros_camera_info().map_err(|e| match e {
                Error::Unsupported(m) => cannot(format, m),
                other => other,
            })
        }
        Format::Opencv => opencv(camera),
        Format::Kalibr => kalibr(camera),
        Format::Colmap => colmap(camera),
        Format::Basalt => basalt(camera),
    }
}

fn opencv(camera: &Camera) -> Result<String> {
    let f = Format::Opencv;
    if camera.model().is_ray_model() {
        return Err(cannot(
            f,
            format!(
                "calibrateCamera's file holds OpenCV's standard model, not `{}`{}",
                camera.model_name(),
                if camera.fisheye_lens().is_some() {
                    " (a fisheye converts to ros, kalibr, colmap or basalt)"
                } else {
                    ""
                }
            ),
        ));
    }
    let c = camera.distortion().to_coeffs();
    let used = c.iter().rposition(|&x| x != 0.0).map_or(0, |i| i + 1);
    let n = [5, 8, 12, 14]
        .into_iter()
        .find(|&n| n >= used)
        .unwrap_or(14);
    let k = camera.intrinsics;
    let matrix = |rows: usize, cols: usize, data: &[f64]| {
        format!(
            "!!opencv-matrix\n   rows: {rows}\n   cols: {cols}\n   dt: d\n   data: [ {} ]\n",
            list(data)
        )
    };
    Ok(format!(
        "%YAML:1.0\n---\nimage_width: {}\nimage_height: {}\ncamera_matrix: {}distortion_coefficients: {}",
        camera.width,
        camera.height,
        matrix(3, 3, &[k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0]),
        matrix(1, n, &c[..n]),
    ))
}

fn kalibr(camera: &Camera) -> Result<String> {
    let f = Format::Kalibr;
    let k = camera.intrinsics;
    let fk = [k.fx, k.fy, k.cx, k.cy];
    let (model, own, distortion, coeffs): (&str, Vec<f64>, &str, Vec<f64>) = match camera.lens() {
        Lens::Standard { .. } => (
            "pinhole",
            vec![],
            "radtan",
            standard_coeffs(camera, 4, f, "its radtan has k1 k2 r1 r2 only")?,
        ),
        Lens::Fisheye(_) => (
            "pinhole",
            vec![],
            "equidistant",
            plain_fisheye(camera, f)?.to_vec(),
        ),
        Lens::Fov(m) => ("pinhole", vec![], "fov", vec![m.omega]),
        Lens::Omni(m) => ("omni", vec![m.xi], "radtan", m.dist_coeffs().to_vec()),
        Lens::Eucm(m) => ("eucm", vec![m.alpha, m.beta], "none", vec![]),
        Lens::DoubleSphere(m) => ("ds", vec![m.xi, m.alpha], "none", vec![]),
        _ => {
            return Err(cannot(
                f,
                format!(
                    "it has pinhole, omni, eucm and ds cameras, not `{}`",
                    camera.model_name()
                ),
            ))
        }
    };
    let mut out = String::from("cam0:\n");
    let _ = writeln!(out, "  camera_model: {model}");
    let _ = writeln!(
        out,
        "  intrinsics: [{}]",
        list(&[own, fk.to_vec()].concat())
    );
    let _ = writeln!(out, "  distortion_model: {distortion}");
    let _ = writeln!(out, "  distortion_coeffs: [{}]", list(&coeffs));
    let _ = writeln!(out, "  resolution: [{}, {}]", camera.width, camera.height);
    Ok(out)
}

fn colmap(camera: &Camera) -> Result<String> {
    let f = Format::Colmap;
    let k = camera.intrinsics;
    // COLMAP puts pixel centres at 0.5.
    let fk = vec![k.fx, k.fy, k.cx + 0.5, k.cy + 0.5];
    let (model, params): (&str, Vec<f64>) = match camera.lens() {
        Lens::Standard { .. } => {
            let c = standard_coeffs(camera, 8, f, "its OpenCV models stop at k6 (FULL_OPENCV)")?;
            if c[4..].iter().all(|&x| x == 0.0) {
                ("OPENCV", [fk, c[..4].to_vec()].concat())
            } else {
                ("FULL_OPENCV", [fk, c].concat())
            }
        }
        Lens::Fisheye(_) => (
            "OPENCV_FISHEYE",
            [fk, plain_fisheye(camera, f)?.to_vec()].concat(),
        ),
        Lens::Fov(m) => ("FOV", [fk, vec![m.omega]].concat()),
        Lens::Division(m) => ("DIVISION", [fk, vec![m.k]].concat()),
        Lens::Eucm(m) => ("EUCM", [fk, vec![m.alpha, m.beta]].concat()),
        Lens::ThinPrismFisheye(m) if !m.radial_first => {
            let r = &m.radial;
            if r.len() > 4 || m.s[1] != 0.0 || m.s[3] != 0.0 {
                return Err(cannot(
                    f,
                    "its THIN_PRISM_FISHEYE has k1..k4 and sx1 sy1 only".into(),
                ));
            }
            let rk = |i: usize| r.get(i).copied().unwrap_or(0.0);
            (
                "THIN_PRISM_FISHEYE",
                [
                    fk,
                    vec![rk(0), rk(1), m.p[0], m.p[1], rk(2), rk(3), m.s[0], m.s[2]],
                ]
                .concat(),
            )
        }
        Lens::ThinPrismFisheye(m) => {
            let r = &m.radial;
            if r.len() > 6 {
                return Err(cannot(
                    f,
                    "its RAD_TAN_THIN_PRISM_FISHEYE has k0..k5".into(),
                ));
            }
            let rk = |i: usize| r.get(i).copied().unwrap_or(0.0);
            (
                "RAD_TAN_THIN_PRISM_FISHEYE",
                [
                    fk,
                    (0..6).map(rk).collect(),
                    vec![m.p[1], m.p[0], m.s[0], m.s[1], m.s[2], m.s[3]],
                ]
                .concat(),
            )
        }
        Lens::Equirectangular(_) => {
            // COLMAP's panorama is the whole sphere: x = (lon/2π + 0.5)·W.
            let (w, h) = (camera.width as f64, camera.height as f64);
            let full =
                crate::model::equirect::Equirectangular::full_sphere(camera.width, camera.height);
            if [k.fx, k.fy, k.cx, k.cy] != full {
                return Err(cannot(
                    f,
                    "its EQUIRECTANGULAR is the whole sphere over the image".into(),
                ));
            }
            ("EQUIRECTANGULAR", vec![w, h])
        }
        _ => {
            return Err(cannot(
                f,
                format!("it has no `{}` model", camera.model_name()),
            ))
        }
    };
    Ok(format!(
        "# Camera list with one line of data per camera:\n#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n# Number of cameras: 1\n1 {model} {} {} {}\n",
        camera.width,
        camera.height,
        params.iter().map(|&x| num(x)).collect::<Vec<_>>().join(" ")
    ))
}

fn basalt(camera: &Camera) -> Result<String> {
    let f = Format::Basalt;
    let k = camera.intrinsics;
    let mut p = json!({"fx": k.fx, "fy": k.fy, "cx": k.cx, "cy": k.cy});
    let kind = match camera.lens() {
        Lens::Standard { .. } => {
            let c = standard_coeffs(camera, 8, f, "its pinhole-radtan8 has k1 k2 p1 p2 k3..k6")?;
            if c.iter().all(|&x| x == 0.0) {
                "pinhole"
            } else {
                for (name, v) in ["k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"]
                    .into_iter()
                    .zip(c)
                {
                    p[name] = v.into();
                }
                "pinhole-radtan8"
            }
        }
        Lens::Fisheye(_) => {
            for (name, v) in ["k1", "k2", "k3", "k4"]
                .into_iter()
                .zip(plain_fisheye(camera, f)?)
            {
                p[name] = v.into();
            }
            "kb4"
        }
        Lens::Ucm(m) => {
            p["alpha"] = m.alpha.into();
            "ucm"
        }
        Lens::Eucm(m) => {
            p["alpha"] = m.alpha.into();
            p["beta"] = m.beta.into();
            "eucm"
        }
        Lens::DoubleSphere(m) => {
            p["xi"] = m.xi.into();
            p["alpha"] = m.alpha.into();
            "ds"
        }
        Lens::Fov(m) => {
            p["w"] = m.omega.into();
            "fov"
        }
        _ => {
            return Err(cannot(
                f,
                format!(
                    "it has pinhole, pinhole-radtan8, kb4, ucm, eucm, ds and fov cameras, not `{}`",
                    camera.model_name()
                ),
            ))
        }
    };
    let tree = json!({"value0": {
        "T_imu_cam": [{"px": 0.0, "py": 0.0, "pz": 0.0, "qx": 0.0, "qy": 0.0, "qz": 0.0, "qw": 1.0}],
        "intrinsics": [{"camera_type": kind, "intrinsics": p}],
        "resolution": [[camera.width, camera.height]],
    }});
    Ok(format!("{tree:#}\n"))
}
