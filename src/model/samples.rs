//! One realistic camera of every model of the table, for the generic test suite, the GPU
//! checks and `vklens bench models`: each adding model brings its sample here and inherits
//! every check.

use super::double_sphere::DoubleSphere;
use super::equirect::Equirectangular;
use super::eucm::Eucm;
use super::fov::Fov;
use super::ftheta::{FTheta, Reference};
use super::ocam::Ocam;
use super::omni::Omni;
use super::ucm::Ucm;
use super::{Camera, Fisheye, Intrinsics, Lens, ModelError};

fn k(fx: f64, fy: f64, cx: f64, cy: f64) -> Intrinsics {
    Intrinsics { fx, fy, cx, cy }
}

/// Named sample cameras, one or more per model (parameters of the magnitude real calibrations
/// of each model have: Kalibr and Basalt fits of EuRoC-like 752×480 fisheyes, a 190° Mei
/// lens, an automotive f-theta lens, an OCamCalib catadioptric camera).
pub fn sample_cameras() -> Result<Vec<(&'static str, Camera)>, ModelError> {
    let (w, h) = (752, 480);
    let fisheye = Fisheye::new([-0.013, 0.017, -0.012, 0.003], 0.0, Some(190.0))?;
    // A camera of the EuRoC-like image size.
    let at = |k: Intrinsics, lens: Lens| Camera::with_lens(w, h, k, lens);
    let (ftheta_bw, ftheta_fw) = ftheta_samples()?;
    let (ocam_k, ocam) = ocam_sample()?;
    Ok(vec![
        (
            "standard",
            Camera::from_coeffs(
                w,
                h,
                k(458.7, 457.3, 367.2, 248.4),
                &[-0.28, 0.074, 2e-4, 1.8e-5],
            )?,
        ),
        (
            "fisheye",
            Camera::with_lens(w, h, k(190.9, 190.9, 254.9, 256.9), Lens::Fisheye(fisheye))?,
        ),
        (
            "omni",
            at(
                k(1450.0, 1452.0, 367.3, 248.1),
                Lens::Omni(Omni::new(1.62, [-0.25, 0.11, 3e-4, -2e-4])?),
            )?,
        ),
        (
            "omni_below_1",
            at(
                k(760.0, 761.0, 370.1, 242.6),
                Lens::Omni(Omni::new(0.82, [-0.05, 0.01, 1e-4, 2e-4])?),
            )?,
        ),
        (
            "ucm",
            at(k(349.0, 348.5, 365.0, 249.0), Lens::Ucm(Ucm::new(0.62)?))?,
        ),
        (
            "eucm",
            at(
                k(460.8, 459.7, 365.9, 249.8),
                Lens::Eucm(Eucm::new(0.63, 1.04)?),
            )?,
        ),
        (
            "double_sphere",
            at(
                k(349.7, 348.9, 365.8, 249.9),
                Lens::DoubleSphere(DoubleSphere::new(-0.2, 0.57)?),
            )?,
        ),
        (
            "fov",
            at(k(300.0, 302.0, 370.5, 240.2), Lens::Fov(Fov::new(0.93)?))?,
        ),
        (
            "equirectangular",
            Camera::with_lens(
                2048,
                1024,
                {
                    let [fx, fy, cx, cy] = Equirectangular::full_sphere(2048, 1024);
                    k(fx, fy, cx, cy)
                },
                Lens::Equirectangular(Equirectangular),
            )?,
        ),
        (
            "ftheta",
            Camera::with_lens(
                3848,
                2168,
                k(1.0, 1.0, 1904.9, 1090.6),
                Lens::FTheta(ftheta_bw),
            )?,
        ),
        (
            "ftheta_fw",
            Camera::with_lens(
                3848,
                2168,
                k(1.0, 1.0, 1904.9, 1090.6),
                Lens::FTheta(ftheta_fw),
            )?,
        ),
        (
            "division",
            at(
                k(420.0, 421.0, 375.2, 239.1),
                Lens::Division(super::division::Division::new(-0.35)?),
            )?,
        ),
        (
            "division_pincushion",
            at(
                k(420.0, 421.0, 375.2, 239.1),
                Lens::Division(super::division::Division::new(0.08)?),
            )?,
        ),
        (
            "thin_prism_fisheye",
            at(
                k(240.3, 240.1, 376.4, 241.9),
                Lens::ThinPrismFisheye(super::thin_prism::ThinPrismFisheye::new(
                    vec![0.012, -0.004, 0.0011, -1.5e-4],
                    [2e-4, -3e-4],
                    [4e-4, 0.0, -2e-4, 0.0],
                    false,
                )?),
            )?,
        ),
        (
            "rad_tan_thin_prism_fisheye",
            at(
                k(241.0, 241.0, 375.1, 240.6),
                Lens::ThinPrismFisheye(super::thin_prism::ThinPrismFisheye::new(
                    vec![0.025, -0.016, 0.003, 0.001, -5e-4, 6e-5],
                    [-1e-4, 3e-4],
                    [2e-4, -1e-5, 1e-4, 2e-5],
                    true,
                )?),
            )?,
        ),
        (
            "ocam",
            Camera::with_lens(1024, 768, ocam_k, Lens::Ocam(ocam))?,
        ),
    ])
}

/// An automotive f-theta lens (NCore's form), with each of its polynomials as the reference.
fn ftheta_samples() -> Result<(FTheta, FTheta), ModelError> {
    let ftheta_bw = FTheta::new(
        Reference::PixeldistToAngle,
        vec![0.0, 5.28e-4, 1.2e-9, -2.5e-12, 1.1e-15, -2.2e-19],
        vec![0.0, 1893.98, -8.55142, 33.3686, -28.2658, 10.8627],
        [1.0002, 0.0001, -0.0001],
        1.2,
    )?;
    let ftheta_fw = FTheta::new(
        Reference::AngleToPixeldist,
        vec![0.0, 5.28e-4, 1.2e-9, -2.5e-12, 1.1e-15, -2.2e-19],
        vec![0.0, 1893.98, -8.55142, 33.3686, -28.2658, 10.8627],
        [1.0, 0.0, 0.0],
        1.3,
    )?;
    Ok((ftheta_bw, ftheta_fw))
}

/// An OCamCalib catadioptric camera, as its `calib_results.txt` gives it.
fn ocam_sample() -> Result<(Intrinsics, Ocam), ModelError> {
    let ocam_k = k(1.0, 1.0, 512.8, 384.3);
    let ocam = Ocam::new(
        vec![-253.9, 0.0, 1.4397e-3, -1.6047e-6, 4.1137e-9],
        // OCamCalib's fit of the inverse (degree 10, by least squares over the image).
        vec![
            414.1073028,
            269.7229014,
            1.222095034,
            22.37142009,
            30.32282083,
            1.24705787,
            -4.417058826,
            7.448917923,
            5.617789858,
            0.2968915098,
            -0.3088680792,
        ],
        [1.0003, 0.0002, -0.0001],
        640.0,
    )?;
    Ok((ocam_k, ocam))
}

/// The samples that carry a fit of their inverse (f-theta's non-reference polynomial,
/// OCamCalib's `inverse_poly`), evaluating it instead of the exact solution: the GPU checks,
/// the Jacobian check and `vklens bench models` run them; the round trips do not (a fit is
/// not the model's exact inverse, by its measured error).
pub fn fitted_inverse_cameras() -> Result<Vec<(&'static str, Camera)>, ModelError> {
    let mut out = Vec::new();
    for (name, camera) in sample_cameras()? {
        let lens = match camera.lens() {
            Lens::FTheta(f) => Lens::FTheta(f.clone().with_fitted_inverse(true)?),
            Lens::Ocam(o) => Lens::Ocam(o.clone().with_fitted_inverse(true)?),
            _ => continue,
        };
        let fitted = match name {
            "ftheta" => "ftheta_fitted",
            "ftheta_fw" => "ftheta_fw_fitted",
            _ => "ocam_fitted",
        };
        out.push((
            fitted,
            Camera::with_lens(camera.width, camera.height, camera.intrinsics, lens)?,
        ));
    }
    Ok(out)
}
