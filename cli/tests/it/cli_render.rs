//! `vklens render` and `vklens calibration-set` as scripts use them: outputs, frames of a
//! scene file, and one-line exit-2 errors that leave nothing behind.

use std::path::{Path, PathBuf};

use crate::common;

use common::{shared_dir, stderr, vklens};
use image::ColorType;

fn tmp(name: &str) -> PathBuf {
    common::scratch("clirender", name)
}

fn fig2() -> String {
    shared_dir()
        .join("reference/calibration-files/seed_fig2.opencv.yml")
        .display()
        .to_string()
}

#[test]
fn render_writes_every_output_at_the_camera_size() {
    let (color, ids, flow, depth) = (tmp("c.png"), tmp("ids.png"), tmp("f.exr"), tmp("d.exr"));
    let cam = fig2();
    let o = vklens(&[
        "render",
        "--camera",
        &cam,
        "--scene",
        "boxes",
        "--output",
        color.to_str().unwrap(),
        "--ids",
        ids.to_str().unwrap(),
        "--flow",
        flow.to_str().unwrap(),
        "--depth",
        depth.to_str().unwrap(),
        "--tessellate",
        "16",
        "--supersample",
        "2",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for p in [&color, &ids, &flow, &depth] {
        let r = image::open(p).unwrap();
        assert_eq!((r.width(), r.height()), (800, 600), "{}", p.display());
    }
    // IDs: the floor (1) and the three boxes (2, 3, 4), nothing else.
    let r = image::open(&ids).unwrap();
    assert!(
        matches!(
            r.color(),
            ColorType::L16 | ColorType::La16 | ColorType::Rgb16 | ColorType::Rgba16
        ),
        "IDs are 16-bit, not {:?}",
        r.color()
    );
    let mut seen: Vec<u32> = r.to_rgba16().pixels().map(|p| p[0] as u32).collect();
    seen.sort();
    seen.dedup();
    assert_eq!(seen, vec![0, 1, 2, 3, 4]);
    // Flow: known (A = 1) on the scene, and the default motion is not zero.
    let f = image::open(&flow).unwrap().to_rgba32f();
    let moving = f
        .pixels()
        .filter(|p| p[3] == 1.0 && p[0].abs() > 0.1)
        .count();
    assert!(moving > 10_000, "{moving}");

    // The warp path renders colour and IDs too, and refuses flow.
    let o = vklens(&[
        "render",
        "--camera",
        &cam,
        "--scene",
        "grid:4",
        "--output",
        color.to_str().unwrap(),
        "--ids",
        ids.to_str().unwrap(),
        "--path",
        "warp",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = vklens(&[
        "render",
        "--camera",
        &cam,
        "--scene",
        "grid",
        "--output",
        color.to_str().unwrap(),
        "--flow",
        flow.to_str().unwrap(),
        "--path",
        "warp",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("--flow needs --path vertex"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn bad_meshes_and_arguments_are_one_line_exit_2_with_no_output() {
    let cam = fig2();
    let out = tmp("never.png");
    let cases = [
        (
            "nan.obj",
            "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n",
            "vertex 1",
        ),
        ("empty.obj", "# no faces\n", "no triangles"),
        (
            "huge.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4000000000\n",
            "huge.obj",
        ),
    ];
    for (name, text, expect) in cases {
        let p = tmp(name);
        std::fs::write(&p, text).unwrap();
        let o = vklens(&[
            "render",
            "--camera",
            &cam,
            "--scene",
            p.to_str().unwrap(),
            "--output",
            out.to_str().unwrap(),
        ]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{name}: {e}");
        assert!(e.contains(expect) && e.contains(name), "{name}: {e}");
        assert_eq!(e.trim().lines().count(), 1, "{name}: {e}");
        assert!(!out.exists());
    }
    for (args, expect) in [
        (vec!["--scene", "checkerboard:9"], "COLSxROWS"),
        (vec!["--scene", "grid", "--pose", "1,2,3"], "six"),
        (vec!["--scene", "grid", "--tessellate", "0"], "--tessellate"),
        (vec!["--scene", "grid", "--depth", "d.png"], ".exr"),
    ] {
        let mut a = vec![
            "render",
            "--camera",
            cam.as_str(),
            "--output",
            out.to_str().unwrap(),
        ];
        a.extend(args.iter().copied());
        let o = vklens(&a);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(expect), "{args:?}: {}", stderr(&o));
        assert!(!out.exists());
    }
}

/// A scene file and the flags that say the same render the same image, pixel for pixel, with
/// supersampling and jittered passes too (a jittered pass used to draw with the previous
/// pass's projection, which shifted the scene route's average by the last offset).
#[test]
fn flags_and_a_scene_file_render_the_same_jittered_image() {
    let cam = tmp("jitter_cam.json");
    std::fs::write(
        &cam,
        r#"{"width": 320, "height": 240, "fx": 280, "fy": 280, "cx": 159.5, "cy": 119.5, "dist_coeffs": [-0.2, 0.05, 0.001, -0.0005]}"#,
    )
    .unwrap();
    for (s, j) in [(1, 4), (2, 3)] {
        let scene = tmp(&format!("jitter_{s}_{j}.toml"));
        std::fs::write(
            &scene,
            format!(
                "[geometry]\nscene = \"checkerboard:9x6:0.04\"\n[optics]\ncamera = \"{}\"\n\
                 [render]\nsupersample = {s}\njitter = {j}\n\
                 [[poses]]\nrvec = [0.25, -0.35, 0.08]\ntvec = [-0.17, -0.09, 0.50]\n",
                cam.display()
            ),
        )
        .unwrap();
        let out = tmp(&format!("jitter_{s}_{j}"));
        let o = vklens(&[
            "render",
            "--scene",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let plan: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("plan.json")).unwrap()).unwrap();
        // The flags take the route the planner took (the vertex path, its tessellation).
        let route = plan["route"].to_string();
        let tessellate = plan["route"]["Vertex"]["tessellate"].as_f64();
        assert!(route.contains("Vertex"), "{route}");
        let flag_png = tmp(&format!("jitter_flags_{s}_{j}.png"));
        let (ss, jj) = (s.to_string(), j.to_string());
        let t = tessellate.map(|t| t.to_string());
        let mut args = vec![
            "render",
            "--camera",
            cam.to_str().unwrap(),
            "--scene",
            "checkerboard:9x6:0.04",
            "--pose",
            "0.25,-0.35,0.08,-0.17,-0.09,0.50",
            "--supersample",
            &ss,
            "--jitter",
            &jj,
            "--output",
            flag_png.to_str().unwrap(),
        ];
        if let Some(t) = &t {
            args.extend(["--tessellate", t.as_str()]);
        }
        let o = vklens(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let a = image::open(&flag_png).unwrap();
        let b = image::open(out.join("color_0000.png")).unwrap();
        let eight = |c: ColorType| {
            matches!(
                c,
                ColorType::L8 | ColorType::La8 | ColorType::Rgb8 | ColorType::Rgba8
            )
        };
        assert!(
            eight(a.color()) && eight(b.color()),
            "8-bit colour expected"
        );
        let (a, b) = (a.to_rgba8(), b.to_rgba8());
        let differ = a.pixels().zip(b.pixels()).filter(|(x, y)| x != y).count();
        assert_eq!(
            differ, 0,
            "supersample {s}, jitter {j}: {differ} pixels differ"
        );
    }
}

#[test]
fn render_scene_cli_writes_every_output_of_every_frame() {
    let bin = env!("CARGO_BIN_EXE_vklens");
    let dir = std::env::temp_dir().join(format!("vklens-plan-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let scene = crate::common::root().join("examples/scenes/ids_and_flow.toml");
    // `vklens render --scene S --out DIR` plus `extra`.
    let render = |extra: &[&str]| {
        std::process::Command::new(bin)
            .args([
                "render",
                "--scene",
                scene.to_str().unwrap(),
                "--out",
                dir.to_str().unwrap(),
            ])
            .args(extra)
            .env("VKLENS_VALIDATION", "1")
            .output()
            .unwrap()
    };
    let o = render(&["--explain", "--frames", "1..=2"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("plan: vertex path") && stdout.contains("measured"),
        "{stdout}"
    );
    for f in 1..=2 {
        for name in [
            "color_{f:04}.png",
            "ids_{f:04}.png",
            "flow_{f:04}.exr",
            "depth_{f:04}.exr",
        ] {
            let name = name.replace("{f:04}", &format!("{f:04}"));
            assert!(dir.join(&name).exists(), "{name}");
        }
    }
    assert!(
        !dir.join("color_0000.png").exists(),
        "frame 0 was not asked for"
    );
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("plan.json")).unwrap()).unwrap();
    assert_eq!(plan["frames"].as_array().unwrap().len(), 2);
    // The camera the frames came through, as vklens JSON and ROS camera_info, loading back to
    // the very camera the scene file names.
    let file: toml::Table = toml::from_str(&std::fs::read_to_string(&scene).unwrap()).unwrap();
    let named = file["optics"]["camera"]
        .as_str()
        .expect("a camera file scene");
    let planned = vklens::Camera::load(scene.parent().unwrap().join(named)).unwrap();
    let back = vklens::Camera::load(dir.join("camera.json")).unwrap();
    assert_eq!(back.to_json(), planned.to_json());
    // This scene's camera has thin prism and tilt terms, which ROS camera_info cannot hold:
    // not written, and said (src/model/tests/fisheye.rs round-trips the cameras it can hold).
    assert!(!dir.join("camera_info.yaml").exists());
    assert!(
        String::from_utf8_lossy(&o.stderr)
            .contains("camera_info.yaml not written: ROS camera_info has no thin prism"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // Out of range frames: one line, exit 2.
    let o = render(&["--frames", "2..9"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("3 pose(s)"));
    // Anti-aliasing flags beside a scene file would be ignored: refused, pointing at the keys.
    let o = render(&["--supersample", "2"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("[render] supersample"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The 16-bit object IDs of a PNG written by `vklens render --ids`.
fn ids_of(path: &Path) -> Vec<u16> {
    image::open(path)
        .unwrap()
        .to_rgba16()
        .pixels()
        .map(|p| p[0])
        .collect()
}

#[test]
fn render_pans_through_a_rolling_shutter_with_end_pose() {
    let cam = fig2();
    let render = |name: &str, extra: &[&str]| {
        let (color, ids) = (tmp(&format!("{name}.png")), tmp(&format!("{name}_ids.png")));
        let mut a = vec![
            "render",
            "--camera",
            cam.as_str(),
            "--scene",
            "grid:8",
            "--pose",
            "0,0,0,0,0,2",
            "--output",
            color.to_str().unwrap(),
            "--ids",
            ids.to_str().unwrap(),
        ];
        a.extend(extra.iter().copied());
        let o = vklens(&a);
        (o, ids)
    };
    let (o, global) = render("rs_global", &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let rolling = ["--rolling-shutter", "top_to_bottom"];
    // The end pose equal to the pose: the global shutter's frame, exactly.
    let (o, still) = render(
        "rs_still",
        &[&rolling[..], &["--end-pose", "0,0,0,0,0,2"]].concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(ids_of(&global), ids_of(&still));
    // A pan during the readout: the lower lines see the grid from further round.
    let pan = ["--end-pose", "0,0.1,0,0.05,0,2"];
    let (o, moving) = render("rs_moving", &[&rolling[..], &pan[..]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let (a, b) = (ids_of(&global), ids_of(&moving));
    let changed = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    assert!(changed > 10_000, "{changed} pixels change ID under the pan");
    // The first line is read from --pose: the top row is the global frame's.
    let w = 800;
    let top = a[..w].iter().zip(&b[..w]).filter(|(x, y)| x != y).count();
    assert!(top < 10, "{top} pixels of the first line differ");
    // Without a rolling shutter an end pose contradicts the global one; through the warp no
    // count of bands of lines meets the default budget on this pan. Both refused, naming what
    // to change.
    for (extra, expect) in [
        (&pan[..], "--end-pose"),
        (
            &[&rolling[..], &pan[..], &["--path", "warp"]].concat()[..],
            "vertex path",
        ),
    ] {
        let (o, _) = render("rs_refused", extra);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(stderr(&o).contains(expect), "{}", stderr(&o));
    }
}

/// Mean absolute difference of two 8-bit colour images, in levels over R, G, B.
fn colour_mad(a: &Path, b: &Path) -> f64 {
    let (a, b) = (
        image::open(a).unwrap().to_rgba8(),
        image::open(b).unwrap().to_rgba8(),
    );
    assert_eq!(a.dimensions(), b.dimensions());
    let sum: f64 = a
        .pixels()
        .zip(b.pixels())
        .flat_map(|(p, q)| (0..3).map(move |c| (f64::from(p[c]) - f64::from(q[c])).abs()))
        .sum();
    sum / (3 * a.width() * a.height()) as f64
}

#[test]
fn the_warp_flags_draw_a_moving_rolling_shutter_in_as_many_bands_as_the_budget_needs() {
    // barrel_k1k2.json at 0.4× (small: lavapipe renders the source once per band).
    let cam = tmp("rs_bands_cam.json");
    std::fs::write(
        &cam,
        r#"{"width": 320, "height": 240, "fx": 160, "fy": 160, "cx": 159.5, "cy": 119.5,
            "dist_coeffs": [-0.11, 0.02, 0, 0]}"#,
    )
    .unwrap();
    let cam = cam.to_str().unwrap().to_string();
    // The grid filling most of the frame, the camera turning 0.1 rad during the readout
    // (16 px at the centre). Supersampled, so that the warp's resampling of the chart's fine
    // texture leaves a low floor against the vertex path's raster.
    let start = ["--pose", "0,0,0,0,0,1.2", "--supersample", "2"];
    let moving = [
        &start[..],
        &[
            "--end-pose",
            "0,0.1,0,0,0,1.2",
            "--rolling-shutter",
            "top_to_bottom",
        ],
    ]
    .concat();
    let render = |name: &str, extra: &[&str]| {
        let out = tmp(&format!("{name}.png"));
        let mut a = vec!["render", "--camera", &cam, "--scene", "grid", "--output"];
        a.push(out.to_str().unwrap());
        a.extend(extra.iter().copied());
        (vklens(&a), out)
    };
    let ok = |(o, out): (std::process::Output, PathBuf)| {
        assert!(o.status.success(), "{}", stderr(&o));
        (stderr(&o), out)
    };
    let vertex = ["--path", "vertex", "--tessellate", "4"];
    let (_, exact) = ok(render("rs_exact", &[&moving[..], &vertex[..]].concat()));
    let (_, still_vertex) = ok(render(
        "rs_still_vertex",
        &[&start[..], &vertex[..]].concat(),
    ));
    let (_, still) = ok(render(
        "rs_still_warp",
        &[&start[..], &["--path", "warp"]].concat(),
    ));
    // A loose budget takes the fewest bands; a tight one more, and says so.
    let (e4, four) = ok(render(
        "rs_bands_loose",
        &[&moving[..], &["--path", "warp", "--max-error-px", "100"]].concat(),
    ));
    assert!(e4.contains("4 bands of lines leave"), "{e4}");
    let (e, banded) = ok(render(
        "rs_bands_tight",
        &[&moving[..], &["--path", "warp", "--max-error-px", "0.25"]].concat(),
    ));
    let k = e
        .split(" bands of lines leave")
        .next()
        .and_then(|s| s.rsplit(' ').next())
        .and_then(|k| k.parse::<u32>().ok())
        .unwrap_or_else(|| panic!("no band count in: {e}"));
    assert!(k > 4 && e.contains("≤ 0.25 px budget"), "{e}");
    // What the warp's resampling leaves against the vertex path's raster, camera still.
    let floor = colour_mad(&still, &still_vertex);
    let (to_exact, four_to_exact, still_to_exact) = (
        colour_mad(&banded, &exact),
        colour_mad(&four, &exact),
        colour_mad(&still, &exact),
    );
    let from_still = colour_mad(&banded, &still);
    eprintln!(
        "{k} bands: {to_exact:.3} levels from the exact path; 4 bands {four_to_exact:.3}; \
         still {still_to_exact:.3}; floor {floor:.3}; {k} bands from the still warp {from_still:.3}"
    );
    // Moved from the still frame, and near the exact path: within the floor, and nearer
    // than 4 bands or the still frame.
    assert!(from_still > 2.0 * to_exact, "{from_still}");
    assert!(
        to_exact < 0.85 * four_to_exact && to_exact < 0.5 * still_to_exact,
        "{to_exact}"
    );
    assert!(to_exact < 1.25 * floor, "{to_exact} above {floor}");

    // The cube path takes its bands too.
    let (e, _) = ok(render(
        "rs_bands_cube",
        &[&moving[..], &["--path", "cube", "--max-error-px", "1"]].concat(),
    ));
    assert!(
        e.contains("cube faces per band") && e.contains("bands of lines leave"),
        "{e}"
    );

    // No count meets the budget: refused, naming the flag, what 64 bands leave and the exact
    // path, and nothing written.
    let (o, out) = render(
        "rs_bands_refused",
        &[&moving[..], &["--path", "warp", "--max-error-px", "0.001"]].concat(),
    );
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("--max-error-px 0.001")
            && e.contains("64 bands leave")
            && e.contains("--path vertex"),
        "{e}"
    );
    assert!(!out.exists());
    for bad in [
        "--max-error-px=0",
        "--max-error-px=-1",
        "--max-error-px=nan",
    ] {
        let (o, _) = render(
            "rs_bands_bad",
            &[&moving[..], &["--path", "warp", bad]].concat(),
        );
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(stderr(&o).contains("--max-error-px"), "{}", stderr(&o));
    }
}
