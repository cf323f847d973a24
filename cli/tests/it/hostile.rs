//! The command line over generated bad inputs, as a hostile user would run it: every
//! command, every input family (camera, image, points, lens, scene, mesh), concurrent
//! writers, stdout to a closed pipe, a device node as output. Each run must end without a
//! panic or a signal; a refused input exits 2 with one line naming the file or flag; no output
//! and no temporary file is left behind.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_vklens")
}

fn root() -> PathBuf {
    crate::common::root()
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vklens-hostile-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run(args: &[&str], stdin: Option<&[u8]>) -> Output {
    let mut cmd = Command::new(bin());
    cmd.args(args)
        .env("VKLENS_VALIDATION", "1")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .stdin(if stdin.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        });
    let mut child = cmd.spawn().expect("spawn vklens");
    if let (Some(data), Some(mut input)) = (stdin, child.stdin.take()) {
        use std::io::Write;
        let _ = input.write_all(data);
    }
    child.wait_with_output().expect("wait")
}

/// No panic, no signal, exit 2, one line on stderr containing `names`, and `dir` holds only
/// the files it held before (no output, no temporary file).
fn refused(what: &str, out: &Output, names: &str, dir: &Path, before: &[PathBuf]) -> usize {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.code().is_some(),
        "{what}: killed by a signal: {stderr}"
    );
    assert_ne!(out.status.code(), Some(101), "{what}: panicked: {stderr}");
    assert_eq!(out.status.code(), Some(2), "{what}: {stderr}");
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("vklens:"))
        .collect();
    assert_eq!(lines.len(), 1, "{what}: {stderr}");
    assert!(
        lines[0].contains(names),
        "{what}: `{}` does not name {names}",
        lines[0]
    );
    assert_eq!(&listing(dir), before, "{what}: left files behind");
    1
}

fn listing(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    v.sort();
    v
}

/// Bad camera files: each family of damage, through every command that reads a camera.
fn camera_cases(dir: &Path) -> Vec<(String, PathBuf)> {
    let good = r#"{"width": 64, "height": 48, "fx": 50, "fy": 50, "cx": 31.5, "cy": 23.5, "dist_coeffs": [-0.1, 0.01, 0, 0]}"#;
    let mut cases: Vec<(String, Vec<u8>)> = vec![
        ("empty".into(), Vec::new()),
        ("binary".into(), (0..=255u8).cycle().take(4096).collect()),
        ("nan".into(), good.replace("50,", "NaN,").into_bytes()),
        (
            "tiny focal".into(),
            good.replace("\"fx\": 50", "\"fx\": 1e-308").into_bytes(),
        ),
        (
            "huge coefficient".into(),
            good.replace("-0.1", "1e300").into_bytes(),
        ),
        (
            "duplicate key".into(),
            good.replace("\"fy\": 50", "\"fx\": 51, \"fy\": 50")
                .into_bytes(),
        ),
        (
            "unknown model".into(),
            good.replace("{", "{\"model\": \"kb8\", ").into_bytes(),
        ),
        (
            "fisheye, 3 coefficients".into(),
            good.replace("{", "{\"model\": \"opencv_fisheye\", ")
                .replace(", 0, 0]", "]")
                .into_bytes(),
        ),
        (
            "colmap, bad count".into(),
            b"1 OPENCV_FISHEYE 64 48 50 50 32 24 0.1\n".to_vec(),
        ),
        (
            "kalibr, omni".into(),
            b"cam0:\n  camera_model: omni\n  intrinsics: [1, 2, 3, 4, 5]\n  resolution: [64, 48]\n"
                .to_vec(),
        ),
        ("yaml alias bomb".into(), {
            let mut s =
                String::from("a: &a [\"x\",\"x\",\"x\",\"x\",\"x\",\"x\",\"x\",\"x\",\"x\"]\n");
            for i in 0..9 {
                let prev = (b'a' + i) as char;
                let next = (b'a' + i + 1) as char;
                s.push_str(&format!("{next}: &{next} [*{prev},*{prev},*{prev},*{prev},*{prev},*{prev},*{prev},*{prev},*{prev}]\n"));
            }
            s.into_bytes()
        }),
        (
            "deep xml".into(),
            format!("{}{}", "<a>".repeat(50_000), "</a>".repeat(50_000)).into_bytes(),
        ),
        (
            "truncated".into(),
            good.as_bytes()[..good.len() / 2].to_vec(),
        ),
    ];
    // A file past the read limit (16 MiB by default).
    cases.push(("too large".into(), vec![b' '; 17 << 20]));
    // The SLAM systems' and tools' own layouts, damaged, under the names they go by.
    let named: Vec<(&str, &str, &str)> = vec![
        ("dso, NaN focal length", "camera.txt", "RadTan nan 457.3 367.2 248.4 -0.28 0.07 0.0002 0.00002\n752 480\ncrop\n640 480\n"),
        ("dso, short line", "camera.txt", "EquiDistant 190.9 190.9 254.9\n512 512\nnone\n512 512\n"),
        ("orb-slam3, missing fy", "orb.yaml", "%YAML:1.0\nFile.version: \"1.0\"\nCamera.type: \"PinHole\"\nCamera1.fx: 458.6\nCamera1.cx: 367.2\nCamera1.cy: 248.4\nCamera.width: 752\nCamera.height: 480\n"),
        ("orb-slam2, no size", "orb2.yaml", "%YAML:1.0\nCamera.fx: 458.6\nCamera.fy: 457.3\nCamera.cx: 367.2\nCamera.cy: 248.4\nCamera.k1: -0.28\nCamera.k2: 0.07\nCamera.p1: 0.0002\nCamera.p2: 0.00002\n"),
        ("okvis, huge focal length", "okvis.yaml", "cameras:\n  - {image_dimension: [752, 480], focal_length: [1e308, 1e308], principal_point: [367, 248], distortion_type: radialtangential, distortion_coefficients: [0, 0, 0, 0]}\n"),
        ("gyroflow, digital lens", "lens.json", r#"{"calib_dimension": {"w": 3840, "h": 2160}, "fisheye_params": {"camera_matrix": [[1800, 0, 1920], [0, 1800, 1080], [0, 0, 1]], "distortion_coeffs": [0.1, 0.01, 0, 0]}, "digital_lens": "gopro_superview"}"#),
        ("opencv stereo, 2x2 matrix", "intrinsics.yml", "%YAML:1.0\nM1: !!opencv-matrix\n   rows: 2\n   cols: 2\n   dt: d\n   data: [ 1., 0., 0., 1. ]\nD1: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   data: [ 0., 0., 0., 0., 0. ]\n"),
        ("svo, unknown distortion", "svo.yaml", "cameras:\n- camera:\n    label: cam0\n    image_width: 752\n    image_height: 480\n    type: pinhole\n    intrinsics: {rows: 4, cols: 1, data: [458.6, 457.3, 367.2, 248.4]}\n    distortion: {type: kb9, parameters: {rows: 4, cols: 1, data: [0, 0, 0, 0]}}\n"),
        ("basalt, negative rpmax", "calib.json", r#"{"value0": {"intrinsics": [{"camera_type": "pinhole-radtan8", "intrinsics": {"fx": 380, "fy": 380, "cx": 320, "cy": 240, "k1": 0, "k2": 0, "p1": 0, "p2": 0, "k3": 0, "k4": 0, "k5": 0, "k6": 0, "rpmax": -2}}], "resolution": [[640, 480]]}}"#),
    ];
    let mut paths: Vec<(String, PathBuf)> = cases
        .into_iter()
        .enumerate()
        .map(|(i, (name, bytes))| {
            let path = dir.join(format!("cam{i}.json"));
            std::fs::write(&path, bytes).unwrap();
            (name, path)
        })
        .collect();
    for (i, (name, file, text)) in named.into_iter().enumerate() {
        let sub = dir.join(format!("named{i}"));
        std::fs::create_dir_all(&sub).unwrap();
        let path = sub.join(file);
        std::fs::write(&path, text).unwrap();
        paths.push((name.into(), path));
    }
    paths
}

#[test]
fn bad_inputs_of_every_family_are_refused_cleanly() {
    let dir = temp_dir("inputs");
    let outs = temp_dir("outputs");
    let before = listing(&outs);
    let out = |name: &str| outs.join(name).to_string_lossy().into_owned();
    let good_cam = dir.join("good.json");
    std::fs::write(
        &good_cam,
        r#"{"width": 64, "height": 48, "fx": 50, "fy": 50, "cx": 31.5, "cy": 23.5, "dist_coeffs": [-0.1, 0.01, 0, 0]}"#,
    )
    .unwrap();
    let png = dir.join("in.png");
    image::RgbImage::from_pixel(64, 48, image::Rgb([10, 200, 30]))
        .save(&png)
        .unwrap();
    let mut count = 0;

    for (name, cam) in camera_cases(&dir) {
        let c = cam.to_string_lossy().into_owned();
        let shown = cam.file_name().unwrap().to_string_lossy().into_owned();
        for args in [
            vec![
                "distort",
                "--camera",
                &c,
                "--input",
                png.to_str().unwrap(),
                "--output",
                &out("o.png"),
            ],
            vec![
                "undistort",
                "--camera",
                &c,
                "--input",
                png.to_str().unwrap(),
                "--output",
                &out("o.png"),
                "--backend",
                "cpu",
            ],
            vec!["overscan", "--camera", &c],
            vec![
                "render",
                "--camera",
                &c,
                "--scene",
                "boxes",
                "--output",
                &out("r.png"),
            ],
        ] {
            let o = run(&args, None);
            count += refused(&format!("{name}: {}", args[0]), &o, &shown, &outs, &before);
        }
        let o = run(
            &["points", "distort", "--camera", &c],
            Some(b"[[0.1, 0.2]]"),
        );
        count += refused(&format!("{name}: points"), &o, &shown, &outs, &before);
    }

    // Images: truncated, empty, not an image, a header claiming 20000 × 20000.
    let good = std::fs::read(&png).unwrap();
    let mut huge = good.clone();
    // IHDR width and height (bytes 16..24 of a PNG): 20000 × 20000.
    huge[16..20].copy_from_slice(&20000u32.to_be_bytes());
    huge[20..24].copy_from_slice(&20000u32.to_be_bytes());
    for (name, bytes) in [
        ("truncated png", good[..good.len() / 2].to_vec()),
        ("empty png", Vec::new()),
        ("text as png", b"not an image".to_vec()),
        ("huge header", huge),
    ] {
        let path = dir.join(format!("{}.png", name.replace(' ', "_")));
        std::fs::write(&path, bytes).unwrap();
        let p = path.to_string_lossy().into_owned();
        let shown = path.file_name().unwrap().to_string_lossy().into_owned();
        let o = run(
            &[
                "distort",
                "--camera",
                good_cam.to_str().unwrap(),
                "--input",
                &p,
                "--output",
                &out("o.png"),
            ],
            None,
        );
        count += refused(name, &o, &shown, &outs, &before);
    }

    // Points on stdin.
    for (name, text) in [
        ("not json", "[[0.1, 0.2"),
        ("four numbers", "[[1, 2, 3, 4]]"),
        ("strings", "[[\"a\", 1]]"),
        ("not a list", "{\"x\": 1}"),
    ] {
        let o = run(
            &["points", "distort", "--camera", good_cam.to_str().unwrap()],
            Some(text.as_bytes()),
        );
        count += refused(name, &o, "stdin", &outs, &before);
    }

    // Lens files, scene files, meshes.
    let lens = dir.join("bad.dat");
    std::fs::write(&lens, "this is not a lens\n50 0 1.5 10\n").unwrap();
    let o = run(&["lens", "info", "--lens", lens.to_str().unwrap()], None);
    count += refused("lens", &o, "bad.dat", &outs, &before);
    let scene = dir.join("bad.toml");
    std::fs::write(&scene, "[geometry\nscene = 3\n").unwrap();
    let o = run(
        &[
            "render",
            "--scene",
            scene.to_str().unwrap(),
            "--out",
            &out("frames"),
        ],
        None,
    );
    count += refused("scene", &o, "bad.toml", &outs, &before);
    let gltf = dir.join("bad.gltf");
    std::fs::write(
        &gltf,
        r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}]}"#,
    )
    .unwrap();
    let obj = dir.join("bad.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nf 1 2 9\n").unwrap();
    for mesh in [&gltf, &obj] {
        let o = run(
            &[
                "render",
                "--camera",
                good_cam.to_str().unwrap(),
                "--scene",
                mesh.to_str().unwrap(),
                "--output",
                &out("m.png"),
            ],
            None,
        );
        let shown = mesh.file_name().unwrap().to_string_lossy().into_owned();
        count += refused("mesh", &o, &shown, &outs, &before);
    }

    // Two outputs naming one file; an output in a read-only or missing folder: refused
    // before rendering, nothing written.
    let o = run(
        &[
            "render",
            "--camera",
            good_cam.to_str().unwrap(),
            "--scene",
            "boxes",
            "--output",
            &out("c.png"),
            "--ids",
            &out("c.png"),
        ],
        None,
    );
    count += refused("same output twice", &o, "c.png", &outs, &before);
    let o = run(
        &[
            "render",
            "--camera",
            good_cam.to_str().unwrap(),
            "--scene",
            "boxes",
            "--output",
            &out("c.png"),
            "--ids",
            "/nonexistent-folder/ids.png",
        ],
        None,
    );
    count += refused("missing folder", &o, "ids.png", &outs, &before);
    println!("{count} hostile runs refused cleanly");
    assert!(count >= 80, "{count}");
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&outs);
}

#[test]
fn a_closed_stdout_is_an_error_not_a_panic() {
    let cam = root().join("examples/cameras/prism_tilt.json");
    let c = cam.to_string_lossy().into_owned();
    for args in [
        vec!["overscan", "--camera", c.as_str()],
        vec!["lens", "info", "--lens", "lenses/dgauss.50mm.dat"],
        vec!["--help"],
    ] {
        let mut child = Command::new(bin())
            .args(&args)
            .current_dir(root())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Close the read end before the command writes.
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.code().is_some(), "{args:?}: a signal");
        assert_ne!(out.status.code(), Some(101), "{args:?}: panicked: {stderr}");
        assert!(stderr.lines().count() <= 1, "{args:?}: {stderr}");
    }
}

#[test]
fn concurrent_writers_and_device_nodes() {
    let outs = temp_dir("concurrent");
    let cam = root().join("examples/cameras/prism_tilt.json");
    let src = outs.join("src.png");
    image::RgbaImage::from_pixel(800, 600, image::Rgba([100, 150, 200, 255]))
        .save(&src)
        .unwrap();
    let target = outs.join("o.png");
    let children: Vec<_> = (0..4)
        .map(|i| {
            Command::new(bin())
                .args(["distort", "--camera"])
                .arg(&cam)
                .arg("--input")
                .arg(&src)
                .arg("--output")
                .arg(&target)
                .args(["--fill", &format!("0.{i},0,0,1")])
                .stdout(Stdio::null())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for c in children {
        let o = c.wait_with_output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    // One whole image, one writer's; no temporary file left.
    let img = image::open(&target).expect("a valid PNG");
    assert_eq!((img.width(), img.height()), (800, 600));
    let names: Vec<String> = listing(&outs)
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["o.png", "src.png"], "{names:?}");
    // A device node at the output path is written through, never replaced.
    let o = Command::new(bin())
        .args([
            "lens",
            "fit-opencv",
            "--lens",
            "lenses/dgauss.50mm.dat",
            "--sensor",
            "36x24",
            "--pixels",
            "360x240",
            "--out",
            "/dev/null",
        ])
        .current_dir(root())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::metadata("/dev/null")
        .unwrap()
        .file_type()
        .is_char_device());
    let _ = std::fs::remove_dir_all(&outs);
}

#[test]
fn a_calibration_set_never_looks_complete_unless_it_is() {
    let dir = temp_dir("calibration");
    let set = dir.join("set");
    let cam = root().join("examples/cameras/prism_tilt.json");
    let make = |count: &str| {
        let mut c = Command::new(bin());
        c.args([
            "calibration-set",
            "--supersample",
            "1",
            "--jitter",
            "1",
            "--count",
            count,
            "--camera",
        ])
        .arg(&cam)
        .arg("--out")
        .arg(&set)
        .stdout(Stdio::null())
        .stderr(Stdio::null());
        c
    };
    assert!(make("5").status().unwrap().success());
    // A smaller re-run: the stale views of the larger one go.
    assert!(make("3").status().unwrap().success());
    let names = |d: &Path| -> Vec<String> {
        listing(d)
            .iter()
            .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
            .collect()
    };
    assert_eq!(
        names(&set),
        ["poses.json", "view_00.png", "view_01.png", "view_02.png"]
    );
    // Interrupted (SIGTERM) after its first view: no poses.json (the old one is gone first),
    // no temporary file; exit 130.
    let mut child = make("40").spawn().unwrap();
    let start = std::time::Instant::now();
    while !names(&set).iter().any(|n| n == "view_03.png") {
        assert!(start.elapsed().as_secs() < 120, "no view rendered");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let _ = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130));
    let left = names(&set);
    assert!(!left.iter().any(|n| n == "poses.json"), "{left:?}");
    assert!(!left.iter().any(|n| n.contains("vklens-tmp")), "{left:?}");
    // All or nothing: the views this run had written went with it.
    assert!(!left.iter().any(|n| n.starts_with("view_")), "{left:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `render --scene … --explain` whose standard output is closed fails after its first frame
/// (the plan is printed once that frame has timed its passes): the frames it wrote go too.
#[test]
fn a_failed_scene_render_leaves_none_of_its_frames() {
    let dir = temp_dir("scene-explain");
    let out = dir.join("frames");
    let scene = root().join("examples/scenes/ids_and_flow.toml");
    let mut child = Command::new(bin())
        .args(["render", "--explain", "--scene"])
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_ne!(o.status.code(), Some(0), "{stderr}");
    assert_ne!(o.status.code(), Some(101), "panicked: {stderr}");
    let left: Vec<PathBuf> = if out.is_dir() {
        listing(&out)
    } else {
        Vec::new()
    };
    assert!(left.is_empty(), "left behind: {left:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_rgb_input_gives_an_rgb_output_unless_the_fill_needs_alpha() {
    let dir = temp_dir("channels");
    let cam = root().join("examples/cameras/prism_tilt.json");
    let src = dir.join("rgb.png");
    image::RgbImage::from_pixel(800, 600, image::Rgb([120, 60, 30]))
        .save(&src)
        .unwrap();
    let warp = |out: &str, fill: &[&str]| {
        let o = Command::new(bin())
            .args(["distort", "--camera"])
            .arg(&cam)
            .arg("--input")
            .arg(&src)
            .arg("--output")
            .arg(dir.join(out))
            .args(fill)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (
            image::open(dir.join(out)).unwrap().color(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (color, _) = warp("opaque.png", &["--fill", "0,0,0,1"]);
    assert_eq!(color, image::ColorType::Rgb8);
    // The default fill is transparent and this lens leaves pixels without a source: RGBA, and
    // the command says why.
    let (color, said) = warp("default.png", &[]);
    assert_eq!(color, image::ColorType::Rgba8);
    assert!(said.contains("alpha channel the input lacks"), "{said}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_lens_whose_surfaces_cross_is_refused_with_the_line() {
    let dir = temp_dir("lens");
    let lens = dir.join("crossing.dat");
    // A biconvex singlet 0.1 mm thick at the axis: its surfaces cross 1.6 mm out.
    std::fs::write(&lens, "# crossing\n20 0.1 1.5 30\n-20 5 1 30\n").unwrap();
    let l = lens.to_string_lossy().into_owned();
    let before = listing(&dir);
    for args in [
        vec!["lens", "info", "--lens", l.as_str()],
        vec![
            "lens",
            "fit-opencv",
            "--lens",
            l.as_str(),
            "--sensor",
            "36x24",
            "--pixels",
            "360x240",
            "--out",
            "/dev/null",
        ],
    ] {
        let o = run(&args, None);
        refused("crossing surfaces", &o, "crossing.dat:3", &dir, &before);
        assert!(String::from_utf8_lossy(&o.stderr).contains("crosses the one on line 2"));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn flags_are_checked_where_they_belong() {
    let dir = temp_dir("flags");
    let before = listing(&dir);
    let cam = root().join("examples/cameras/barrel_k1k2.json");
    let c = cam.to_string_lossy().into_owned();
    let out = dir.join("o.png").to_string_lossy().into_owned();
    // A density that is no density: refused naming the flag, not turned into a cube map.
    for d in ["0", "-1", "nan"] {
        let flag = format!("--density={d}");
        let o = run(
            &[
                "render", "--camera", &c, "--scene", "boxes", "--path", "warp", &flag, "--output",
                &out,
            ],
            None,
        );
        refused("density", &o, "--density", &dir, &before);
    }
    // --camera-index picks the camchain's camera; the pinhole --source-camera is read whole.
    let chain = dir.join("chain.yaml");
    std::fs::write(&chain, "cam0:\n  camera_model: pinhole\n  distortion_model: radtan\n  distortion_coeffs: [-0.1, 0.01, 0, 0]\n  intrinsics: [50, 50, 31.5, 23.5]\n  resolution: [64, 48]\ncam1:\n  camera_model: pinhole\n  distortion_model: radtan\n  distortion_coeffs: [-0.2, 0.02, 0, 0]\n  intrinsics: [50, 50, 31.5, 23.5]\n  resolution: [64, 48]\n").unwrap();
    let pin = dir.join("pin.json");
    std::fs::write(
        &pin,
        r#"{"width": 64, "height": 48, "fx": 50, "fy": 50, "cx": 31.5, "cy": 23.5}"#,
    )
    .unwrap();
    let src = dir.join("src.png");
    image::RgbImage::from_pixel(64, 48, image::Rgb([1, 2, 3]))
        .save(&src)
        .unwrap();
    let o = Command::new(bin())
        .args(["distort", "--camera-index", "1", "--camera"])
        .arg(&chain)
        .arg("--source-camera")
        .arg(&pin)
        .arg("--input")
        .arg(&src)
        .arg("--output")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}
