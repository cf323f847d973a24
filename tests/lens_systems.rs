//! Real lens systems (seed 004): the shipped prescriptions against their published first-order
//! figures, and `vklens lens info`.

use std::process::Command;

use vklens::lens::{analyse, trace, Prescription, LAMBDA_D};

fn shipped(name: &str) -> Prescription {
    Prescription::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("lenses")
            .join(name),
    )
    .unwrap()
}

#[test]
fn double_gauss_matches_its_published_figures() {
    // Smith, Modern Lens Design p. 312, scaled to 50 mm: f = 50 mm, f/2, 22° half field.
    let p = shipped("dgauss.50mm.dat");
    let par = analyse(&p, LAMBDA_D);
    let efl = par.efl.unwrap();
    assert!((efl - 50.0).abs() < 0.5, "EFL {efl}");
    let n = par.f_number.unwrap();
    assert!((n - 2.0).abs() < 0.06, "f/{n}");
    assert!(
        trace::chief_ray(&p, 22f64.to_radians(), LAMBDA_D).is_some(),
        "22° field vignetted"
    );
    // First-order consistency: H' = F' − f, and the pupils are real images of the stop.
    let rear_focus = par.rear_vertex_z + par.bfl.unwrap();
    assert!((par.rear_principal_z.unwrap() - (rear_focus - efl)).abs() < 1e-9);
    assert!(par.entrance_pupil_diameter > p.surfaces[p.stop_index()].aperture);
}

#[test]
fn wide_angle_matches_its_published_figures() {
    // Smith, Modern Lens Design p. 360 (Nakamura), scaled to 22 mm: 38° field.
    let p = shipped("wide.22mm.dat");
    let par = analyse(&p, LAMBDA_D);
    let efl = par.efl.unwrap();
    assert!((efl - 22.0).abs() < 0.22, "EFL {efl}");
    assert!(
        trace::chief_ray(&p, 19f64.to_radians(), LAMBDA_D).is_some(),
        "19° half field vignetted"
    );
}

#[test]
fn lens_info_json_has_the_documented_keys_and_bad_files_name_the_line() {
    let bin = env!("CARGO_BIN_EXE_vklens");
    let lens = format!("{}/lenses/dgauss.50mm.dat", env!("CARGO_MANIFEST_DIR"));
    let o = Command::new(bin)
        .args(["lens", "info", "--lens", &lens, "--json"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for key in [
        "efl_mm",
        "bfl_mm",
        "f_number",
        "exit_pupil_z_mm",
        "exit_pupil_diameter_mm",
    ] {
        assert!(v[key].as_f64().is_some(), "{key} missing: {v}");
    }
    let curve = v["distortion"].as_array().unwrap();
    assert!(curve.len() > 5);
    // A double Gauss has mild barrel distortion at 20°: a few percent at most.
    assert!(curve
        .iter()
        .all(|d| d["distortion_percent"].as_f64().unwrap().abs() < 5.0));

    let bad = std::env::temp_dir().join(format!("vklens-bad-lens-{}.dat", std::process::id()));
    std::fs::write(&bad, "# a lens\n50 5 1.5 20\n-50 x 1 20\n").unwrap();
    let o = Command::new(bin)
        .args(["lens", "info", "--lens", bad.to_str().unwrap()])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        e.contains(&format!("{}:3:", bad.display())) && e.contains("thickness"),
        "{e}"
    );
}

#[test]
fn the_fitted_opencv_camera_reproduces_the_traced_lens() {
    // lens fit-opencv → a camera file every command accepts, whose forward model puts each
    // chief ray where the exact trace does.
    let out = std::env::temp_dir().join(format!("vklens-fit-{}.json", std::process::id()));
    let lens = format!("{}/lenses/dgauss.50mm.dat", env!("CARGO_MANIFEST_DIR"));
    let o = Command::new(env!("CARGO_BIN_EXE_vklens"))
        .args([
            "lens",
            "fit-opencv",
            "--lens",
            &lens,
            "--sensor",
            "36x24",
            "--pixels",
            "1800x1200",
        ])
        .args(["--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let camera = vklens::io::load_camera(&out).unwrap();
    let p = shipped("dgauss.50mm.dat");
    let par = analyse(&p, LAMBDA_D);
    let film = par.rear_vertex_z + par.bfl.unwrap();
    let pitch = 36.0 / 1800.0;
    for deg in [5.0f64, 10.0, 15.0, 20.0] {
        let theta = deg.to_radians();
        let exit =
            trace::trace(&p, trace::chief_ray(&p, theta, LAMBDA_D).unwrap(), LAMBDA_D).unwrap();
        let traced_px = trace::height_at(&exit, film).abs() / pitch;
        let model = camera
            .project(glam::DVec3::new(theta.tan(), 0.0, 1.0))
            .unwrap();
        let model_px = model.x - camera.intrinsics.cx;
        assert!(
            (model_px - traced_px).abs() < 0.01,
            "{deg}°: model {model_px} px, trace {traced_px} px"
        );
    }
    // Non-square pixels are refused with a clear line.
    let o = Command::new(env!("CARGO_BIN_EXE_vklens"))
        .args([
            "lens",
            "fit-opencv",
            "--lens",
            &lens,
            "--sensor",
            "36x24",
            "--pixels",
            "1800x1000",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("square"));
}

#[test]
fn the_achromat_matches_its_published_figures_and_corrects_colour() {
    // Thorlabs AC254-050-A: f = 50.0 mm, back focal distance 43.22 mm (its Zemax file).
    let p = shipped("achromat.50mm.dat");
    let par = analyse(&p, LAMBDA_D);
    let (efl, bfl) = (par.efl.unwrap(), par.bfl.unwrap());
    assert!((efl - 50.0).abs() < 0.5, "EFL {efl}");
    assert!((bfl - 43.22).abs() < 0.43, "BFL {bfl}");
    // An achromat brings F and C light to (nearly) one focus: far less longitudinal colour
    // than a singlet of its crown glass, whose focal length changes by about f / V_d.
    use vklens::lens::prescription::{LAMBDA_C, LAMBDA_F};
    let shift = (analyse(&p, LAMBDA_F).bfl.unwrap() - analyse(&p, LAMBDA_C).bfl.unwrap()).abs();
    let singlet_shift = efl / 47.11;
    // Measured: 0.15 mm against 1.06 mm (7× less; the two-term Cauchy dispersion from n_d and
    // V_d is an approximation of the real glasses, so not exactly zero).
    assert!(
        shift < 0.25 * singlet_shift,
        "F-C focal shift {shift} mm vs singlet {singlet_shift} mm"
    );
}

mod image_model {
    use super::shipped;
    use glam::{DVec2, DVec3};
    use vklens::lens::image_model::{
        fit_cop, least_squares_cop, max_angle_deg, ImageModel, ModelOptions, Optics, PlaneRay,
    };
    use vklens::lens::{Prescription, LAMBDA_D};

    /// 36 × 24 mm film, 360 × 240 pixels, focused at 2 m.
    fn optics(p: &Prescription) -> Optics {
        let pitch: f64 = std::env::var("PITCH").ok().and_then(|v| v.parse().ok()).unwrap_or(0.1);
        Optics::new(p, (360, 240), pitch, 2.0, None).unwrap()
    }

    /// The traced rays of a film grid through one lens sample, on the plane at the focus.
    /// `cell` is the fraction of the film (from the top-left corner) the grid covers.
    fn grid_rays(o: &Optics, sample: DVec3, n: u32, cell: f64) -> Vec<PlaneRay> {
        let mut rays = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let px = DVec2::new(
                    -0.5 + cell * o.film.width as f64 * i as f64 / n as f64,
                    -0.5 + cell * o.film.height as f64 * j as f64 / n as f64,
                );
                if let Some(r) = o.trace_from_film(o.film.point(px), sample, LAMBDA_D) {
                    let plane: f64 = std::env::var("PLANE").ok().and_then(|v| v.parse().ok()).unwrap_or(o.focus_m);
                    let t = (plane - r.origin.z) / r.direction.z;
                    rays.push(PlaneRay {
                        p: r.origin + t * r.direction,
                        d: r.direction,
                    });
                }
            }
        }
        rays
    }

    #[test]
    fn a_lens_that_is_a_pinhole_has_zero_angle_error() {
        // A bare stop (0.01 mm) and a window of air: every ray from the film through the
        // sample point goes on straight, so one centre of projection is exact.
        let p = Prescription::parse("0 5 0 0.01\n0 40 1 30\n", "pinhole").unwrap();
        let o = Optics::new(&p, (100, 100), 0.2, f64::INFINITY, None);
        // Afocal (no glass): give it a film by hand through a focusing lens instead.
        assert!(o.is_err(), "a pinhole has no focal length");
        let p = Prescription::parse(
            "0 5 0 0.01\n0 1 1 30\n0 40 1 30\n",
            "pinhole",
        )
        .unwrap();
        // Still afocal; the COP fit itself is what the test is about: trace through the
        // bare stop with an explicit film.
        let _ = p;
        let pin = DVec3::new(0.0, 0.0, 0.0);
        let rays: Vec<PlaneRay> = (0..121)
            .map(|k| {
                let film = DVec3::new((k % 11) as f64 - 5.0, (k / 11) as f64 - 5.0, 40.0);
                let d = (pin - film).normalize();
                let d = DVec3::new(d.x, -d.y, -d.z);
                let t = 2.0 / d.z;
                PlaneRay { p: t * d, d }
            })
            .collect();
        let (e, angle) = fit_cop(&rays, DVec3::new(0.01, 0.02, 0.03));
        assert!(e.length() < 1e-9 && angle < 1e-9, "{e} {angle}");
    }

    #[test]
    fn newton_beats_the_least_squares_centre_on_the_doublet() {
        let p = shipped(&std::env::var("LENS").unwrap_or("achromat.50mm.dat".into()));
        let o = optics(&p);
        let (samples, _) = o.lens_samples(10, LAMBDA_D).unwrap();
        for cell in [1.0, 0.5, 0.25, 0.125, 0.0625] {
        for s in samples.iter().take(4) {
            let rays = grid_rays(&o, *s, 10, cell);
            let ls = least_squares_cop(&rays).unwrap();
            let ls_angle = max_angle_deg(&rays, ls);
            let (e, newton) = fit_cop(&rays, ls);
            println!("cell {cell} sample {s}: LS {ls_angle:.5}° {ls}, Newton {newton:.5}° {e}");
        }
        }
        let m = ImageModel::build(&o, &ModelOptions::default()).unwrap();
        println!("projections {} max {}", m.projection_count(), m.max_angle_deg());
        let p = shipped("biconvex.50mm.dat");
        let m = ImageModel::build(&optics(&p), &ModelOptions::default()).unwrap();
        println!("singlet projections {} max {}", m.projection_count(), m.max_angle_deg());
    }
}
