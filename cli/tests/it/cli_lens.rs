//! `vklens lens` as scripts use it: `lens info` JSON with the documented keys, `lens
//! fit-opencv` writing a camera file whose forward model puts each chief ray where the exact
//! trace does, and `lens render` writing the film; bad input is one line, exit 2, no file.

use std::process::Command;

#[test]
fn lens_info_json_has_the_documented_keys_and_bad_files_name_the_line() {
    let bin = env!("CARGO_BIN_EXE_vklens");
    let lens = format!("{}/lenses/dgauss.50mm.dat", crate::common::root().display());
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
    let lens = format!("{}/lenses/dgauss.50mm.dat", crate::common::root().display());
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
    let camera = vklens::Camera::load(&out).unwrap();
    // The exact trace's chief-ray heights on the paraxial focal plane, as `lens info` reports
    // them: its 12 steps to 20° land on 5°, 10°, 15° and 20°.
    let o = Command::new(env!("CARGO_BIN_EXE_vklens"))
        .args([
            "lens",
            "info",
            "--lens",
            &lens,
            "--json",
            "--max-field",
            "20",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let info: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let curve = info["distortion"].as_array().unwrap();
    let pitch = 36.0 / 1800.0;
    for deg in [5.0f64, 10.0, 15.0, 20.0] {
        let theta = deg.to_radians();
        let traced = curve
            .iter()
            .find(|d| d["field_deg"].as_f64() == Some(deg))
            .unwrap_or_else(|| panic!("no traced chief ray at {deg}°: {info}"));
        let traced_px = traced["image_height_mm"].as_f64().unwrap() / pitch;
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
fn lens_render_cli_writes_the_film_and_refuses_bad_input() {
    let bin = env!("CARGO_BIN_EXE_vklens");
    let dir = std::env::temp_dir().join(format!("vklens-lens-render-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let lens = format!(
        "{}/lenses/achromat.50mm.dat",
        crate::common::root().display()
    );
    let out = dir.join("film.png");
    let run = |extra: &[&str]| {
        Command::new(bin)
            .args(["lens", "render", "--lens", &lens, "--scene", "boxes"])
            .args(["--pixels", "96x64", "--samples", "4"])
            .args(extra)
            .env("VKLENS_VALIDATION", "1")
            .output()
            .unwrap()
    };
    for reference in [false, true] {
        let _ = std::fs::remove_file(&out);
        let mut args = vec!["--output", out.to_str().unwrap()];
        if reference {
            args.push("--reference");
        }
        let o = run(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let img = image::open(&out).unwrap().to_rgba8();
        assert_eq!(img.dimensions(), (96, 64));
        // Something of the scene reached the film (the boxes are lit, not all black).
        assert!(
            img.pixels().any(|p| p[1] > 100),
            "reference {reference}: a black film"
        );
    }
    // Bad input: one line naming the problem, exit 2, nothing written.
    let _ = std::fs::remove_file(&out);
    let bad_file = dir.join("bad.dat");
    std::fs::write(&bad_file, "30 5 1.5 20\n-30 x 1 20\n").unwrap();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (vec!["--fstop".into(), "1.2".into()], "faster than the lens"),
        (vec!["--fstop".into(), "1e9".into()], "--fstop"),
        (vec!["--focus=-1".into()], "--focus"),
        (vec!["--max-angle".into(), "0".into()], "--max-angle"),
        (vec!["--sensor".into(), "36x36".into()], "non-square"),
    ];
    for (extra, expected) in cases {
        let mut args: Vec<&str> = extra.iter().map(|s| s.as_str()).collect();
        args.extend(["--output", out.to_str().unwrap()]);
        let o = run(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {err}");
        assert!(err.contains(expected), "{extra:?}: {err}");
        assert!(!out.exists());
    }
    let o = Command::new(bin)
        .args([
            "lens",
            "render",
            "--lens",
            bad_file.to_str().unwrap(),
            "--scene",
            "boxes",
        ])
        .args(["--output", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("bad.dat:2"));
    let _ = std::fs::remove_dir_all(&dir);
}
