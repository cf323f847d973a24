//! The generic suite every model of the table runs (its sample in [`super::samples`]): the
//! forward map against its inverse both ways, the Jacobian against finite differences, the
//! domain's edge, and hostile input. A new model inherits all of it.

use std::f64::consts::PI;

use glam::{DVec2, DVec3};

use super::samples::{fitted_inverse_cameras, sample_cameras};
use super::{Camera, ModelKind};

fn ray(theta: f64, phi: f64) -> DVec3 {
    DVec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

fn angle(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// Rays from the axis to just inside the domain's edge, all around.
fn rays_inside(camera: &Camera) -> Vec<DVec3> {
    let max = camera.lens().max_angle();
    let mut out = Vec::new();
    for i in 0..=60 {
        let theta = max * (1.0 - 1e-6) * i as f64 / 60.0;
        for j in 0..24 {
            out.push(ray(theta, 2.0 * PI * j as f64 / 24.0 + 0.1));
        }
    }
    out
}

/// Whether the model's domain is a cone about the axis (every ray inside its max angle sees).
fn cone_domain(camera: &Camera) -> bool {
    !matches!(
        camera.model(),
        ModelKind::Standard | ModelKind::Omni | ModelKind::ThinPrismFisheye
    )
}

#[test]
fn forward_then_inverse_returns_the_ray_within_1e_9() {
    for (name, camera) in sample_cameras().expect("samples") {
        let (mut worst_rad, mut worst_px, mut valid) = (0.0f64, 0.0f64, 0);
        let rays = rays_inside(&camera);
        for p in &rays {
            // The standard model projects past its fold as cv2.projectPoints does; its
            // domain is the pinhole-side table.
            if !camera.model().is_ray_model()
                && !camera
                    .domain()
                    .contains_ideal(DVec2::new(p.x / p.z, p.y / p.z))
            {
                continue;
            }
            let Some(px) = camera.project(*p) else {
                assert!(
                    !cone_domain(&camera),
                    "{name}: {p:?} inside the cone has no pixel"
                );
                continue;
            };
            valid += 1;
            let back = camera
                .unproject(px)
                .unwrap_or_else(|| panic!("{name}: {p:?} → {px:?} has no ray back"));
            worst_rad = worst_rad.max(angle(back, *p));
            let again = camera.project(back).expect("the ray back projects");
            // 1e-9 px on the image; beyond it (the standard model near its fold reaches 1e5
            // px) the same relative rounding.
            let c = DVec2::new(camera.intrinsics.cx, camera.intrinsics.cy);
            let diagonal = (camera.width as f64).hypot(camera.height as f64);
            let scale = ((px - c).length() / diagonal).max(1.0);
            worst_px = worst_px.max((again - px).length() / scale);
        }
        println!(
            "{name}: {valid}/{} rays, {worst_rad:.1e} rad, {worst_px:.1e} px",
            rays.len()
        );
        assert!(
            valid * 2 > rays.len(),
            "{name}: only {valid} of {} rays valid",
            rays.len()
        );
        assert!(worst_rad <= 1e-9, "{name}: ray back {worst_rad:e} rad off");
        assert!(worst_px <= 1e-9, "{name}: reprojection {worst_px:e} px off");
    }
}

#[test]
fn inverse_then_forward_returns_the_pixel_within_1e_9_px() {
    for (name, camera) in sample_cameras().expect("samples") {
        let (w, h) = (camera.width as f64, camera.height as f64);
        let mut worst = 0.0f64;
        let mut valid = 0;
        for i in 0..=40 {
            for j in 0..=40 {
                let px = DVec2::new(-0.5 + w * i as f64 / 40.0, -0.5 + h * j as f64 / 40.0);
                let Some(r) = camera.unproject(px) else {
                    continue;
                };
                valid += 1;
                assert!((r.length() - 1.0).abs() < 1e-12, "{name}: ray not unit");
                let back = camera
                    .project(r)
                    .unwrap_or_else(|| panic!("{name}: {px:?}'s ray {r:?} has no pixel"));
                worst = worst.max((back - px).length());
            }
        }
        println!("{name}: {valid} pixels, worst {worst:.1e} px");
        assert!(valid > 0, "{name}: no pixel has a ray");
        assert!(worst <= 1e-9, "{name}: {worst:e} px");
    }
}

#[test]
fn jacobian_matches_finite_differences() {
    let cameras = sample_cameras().expect("samples");
    let fitted = fitted_inverse_cameras().expect("fitted samples");
    for (name, camera) in cameras.into_iter().chain(fitted) {
        if !camera.model().is_ray_model() {
            continue;
        }
        let max = camera.lens().max_angle();
        for p in rays_inside(&camera) {
            if p.x.hypot(p.y).atan2(p.z) > 0.97 * max || p.x.hypot(p.y) < 1e-3 {
                continue;
            }
            let Some((m, rows)) = camera.lens().project_ray_jacobian(p) else {
                continue;
            };
            let h = 1e-6;
            for (axis, unit) in [DVec3::X, DVec3::Y, DVec3::Z].into_iter().enumerate() {
                let (Some(a), Some(b)) = (
                    camera.lens().project_ray(p + unit * h),
                    camera.lens().project_ray(p - unit * h),
                ) else {
                    continue;
                };
                let fd = (a - b) / (2.0 * h);
                let jac = DVec2::new(rows[0][axis], rows[1][axis]);
                let scale = 1.0 + jac.length() + m.length();
                assert!(
                    (fd - jac).length() <= 1e-6 * scale,
                    "{name} at {p:?}, ∂/∂{axis}: analytic {jac:?}, differences {fd:?}"
                );
            }
        }
    }
}

#[test]
fn the_domain_ends_where_the_model_says() {
    for (name, camera) in sample_cameras().expect("samples") {
        let max = camera.lens().max_angle();
        if !cone_domain(&camera) || max >= PI {
            continue;
        }
        for j in 0..16 {
            let phi = 2.0 * PI * j as f64 / 16.0;
            let inside = ray(max * (1.0 - 1e-6), phi);
            let outside = ray((max + 1e-6).min(PI), phi);
            assert!(
                camera.project(inside).is_some(),
                "{name}: {inside:?} just inside"
            );
            assert!(
                camera.project(outside).is_none(),
                "{name}: {outside:?} just outside"
            );
        }
    }
}

#[test]
fn hostile_points_are_invalid_or_exact_never_a_panic() {
    for (name, camera) in sample_cameras().expect("samples") {
        for p in [
            DVec3::ZERO,
            DVec3::splat(f64::NAN),
            DVec3::new(0.1, f64::INFINITY, 1.0),
            DVec3::new(f64::NAN, 0.0, 1.0),
        ] {
            assert_eq!(camera.project(p), None, "{name}: {p:?}");
        }
        for px in [
            DVec2::splat(f64::NAN),
            DVec2::new(f64::INFINITY, 0.0),
            DVec2::new(1e300, -1e300),
        ] {
            assert_eq!(camera.unproject(px), None, "{name}: {px:?}");
        }
        // A ray model maps rays: a huge or tiny multiple of a point projects as the point.
        if camera.model().is_ray_model() {
            let p = DVec3::new(0.1, -0.2, 1.0);
            let want = camera.project(p).expect("near the axis");
            for s in [1e-300, 1e300] {
                let got = camera.project(p * s).expect("a multiple");
                assert!((got - want).length() < 1e-9, "{name}: ×{s:e} gives {got:?}");
            }
        }
    }
}

#[test]
fn hostile_parameters_are_refused_with_their_name() {
    use super::double_sphere::DoubleSphere;
    use super::eucm::Eucm;
    use super::fov::Fov;
    use super::ftheta::{FTheta, Reference};
    use super::ocam::Ocam;
    use super::omni::Omni;
    use super::ucm::Ucm;
    let msg = |e: super::ModelError| e.to_string();
    for bad in [f64::NAN, f64::INFINITY, -0.5, 1.0, 1e300] {
        assert!(msg(Ucm::new(bad).unwrap_err()).contains("alpha"));
        assert!(msg(Eucm::new(bad, 1.0).unwrap_err()).contains("alpha"));
        assert!(msg(DoubleSphere::new(0.0, bad).unwrap_err()).contains("alpha"));
    }
    for bad in [f64::NAN, 0.0, -1.0, 1e300] {
        assert!(msg(Eucm::new(0.5, bad).unwrap_err()).contains("beta"));
    }
    for bad in [f64::NAN, -0.1, 4.0] {
        assert!(msg(Fov::new(bad).unwrap_err()).contains("omega"));
    }
    for bad in [f64::NAN, -1.0, 1e300] {
        assert!(msg(Omni::new(bad, [0.0; 4]).unwrap_err()).contains("xi"));
    }
    assert!(msg(Omni::new(1.0, [f64::NAN, 0.0, 0.0, 0.0]).unwrap_err()).contains("k1"));
    let poly = vec![0.0, 1e-3];
    assert!(msg(FTheta::new(
        Reference::PixeldistToAngle,
        poly.clone(),
        vec![],
        [1.0, 0.0, 0.0],
        0.0
    )
    .unwrap_err())
    .contains("max_angle"));
    assert!(msg(FTheta::new(
        Reference::AngleToPixeldist,
        poly.clone(),
        vec![0.0; 3],
        [1.0, 0.0, 0.0],
        1.0
    )
    .unwrap_err())
    .contains("all zeros"));
    assert!(msg(FTheta::new(
        Reference::PixeldistToAngle,
        poly.clone(),
        vec![],
        [1.0, 1.0, 1.0],
        1.0
    )
    .unwrap_err())
    .contains("singular"));
    assert!(
        msg(Ocam::new(vec![250.0, 0.0], vec![], [1.0, 0.0, 0.0], 500.0).unwrap_err())
            .contains("negative")
    );
    assert!(
        msg(Ocam::new(vec![-250.0, f64::NAN], vec![], [1.0, 0.0, 0.0], 500.0).unwrap_err())
            .contains("poly")
    );
}

/// A camera that evaluates its file's fit of the inverse gives exactly that polynomial's
/// answer (each written out here as NCore and OCamCalib evaluate it), stays within the fit's
/// error of the exact model.
#[test]
fn fitted_inverses_evaluate_the_files_polynomial() {
    use super::ftheta::Reference;
    use super::Lens;
    let horner = |c: &[f64], t: f64| c.iter().rev().fold(0.0, |a, &ci| a * t + ci);
    for (name, camera) in fitted_inverse_cameras().expect("fitted samples") {
        let exact = sample_cameras()
            .expect("samples")
            .into_iter()
            .find(|(n, _)| name.starts_with(n) && name[n.len()..] == *"_fitted")
            .map(|(_, c)| c)
            .expect("the exact sample");
        let max = camera.lens().max_angle();
        let mut worst_fit = 0.0f64;
        for i in 1..60 {
            let theta = 0.98 * max * i as f64 / 60.0;
            let p = ray(theta, 0.7);
            let rho = p.x.hypot(p.y);
            match camera.lens() {
                Lens::Ocam(o) => {
                    // ocam_functions.cpp world2cam: rho = Σ invpol[i] θⁱ, θ = atan(z/norm) in
                    // OCamCalib's frame (z = −Z), then (x, y) / norm · rho and the affine term.
                    let t = (-p.z / rho).atan();
                    let r = horner(&o.inverse_poly, t);
                    let (xo, yo) = (p.y / rho * r, p.x / rho * r);
                    let [c, d, e] = o.cde;
                    let want = DVec2::new(xo * e + yo, xo * c + yo * d)
                        + DVec2::new(camera.intrinsics.cx, camera.intrinsics.cy);
                    let got = camera.project(p).expect("inside");
                    assert!(
                        (got - want).length() < 1e-9,
                        "{name} θ = {theta}: {got} vs {want}"
                    );
                    let back = exact
                        .project(camera.unproject(got).expect("ray"))
                        .expect("px");
                    assert!(
                        (back - got).length() < 1e-9,
                        "{name}: the inverse stays exact"
                    );
                    worst_fit = worst_fit.max((got - exact.project(p).expect("px")).length());
                }
                Lens::FTheta(f) if f.reference == Reference::PixeldistToAngle => {
                    // NCore's forward before its Newton steps: δ = fw(θ).
                    let delta = horner(&f.angle_to_pixeldist, theta);
                    let [c, d, e] = f.linear_cde;
                    let (x, y) = (p.x / rho * delta, p.y / rho * delta);
                    let want = DVec2::new(c * x + d * y, e * x + y)
                        + DVec2::new(camera.intrinsics.cx, camera.intrinsics.cy);
                    let got = camera.project(p).expect("inside");
                    assert!(
                        (got - want).length() < 1e-9,
                        "{name} θ = {theta}: {got} vs {want}"
                    );
                    worst_fit = worst_fit.max((got - exact.project(p).expect("px")).length());
                }
                Lens::FTheta(f) => {
                    // The reference is fw: the pixel is exact, its ray is bw's.
                    let px = camera.project(p).expect("inside");
                    let got = camera.unproject(px).expect("ray");
                    let delta = horner(&f.angle_to_pixeldist, theta);
                    let want_theta = horner(&f.pixeldist_to_angle, delta);
                    let got_theta = got.x.hypot(got.y).atan2(got.z);
                    assert!((got_theta - want_theta).abs() < 1e-12, "{name} θ = {theta}");
                    let back = exact.project(got).expect("px");
                    worst_fit = worst_fit.max((back - px).length());
                }
                _ => unreachable!("{name}"),
            }
        }
        // The fit differs from the model (else there would be nothing to choose), by less
        // than a pixel on these lenses.
        assert!(
            worst_fit > 1e-9 && worst_fit < 1.0,
            "{name}: fit error {worst_fit} px"
        );
    }
}

#[test]
fn a_fitted_inverse_needs_the_fit() {
    use super::ftheta::{FTheta, Reference};
    let lens = FTheta::new(
        Reference::PixeldistToAngle,
        vec![0.0, 1e-3],
        vec![],
        [1.0, 0.0, 0.0],
        1.0,
    )
    .expect("lens");
    let err = lens
        .with_fitted_inverse(true)
        .expect_err("no fit")
        .to_string();
    assert!(err.contains("angle_to_pixeldist_poly"), "{err}");
    let ocam = super::ocam::Ocam::new(vec![-250.0, 0.0, 1e-3], vec![], [1.0, 0.0, 0.0], 500.0)
        .expect("lens");
    let err = ocam
        .with_fitted_inverse(true)
        .expect_err("no fit")
        .to_string();
    assert!(err.contains("inverse_poly"), "{err}");
}
