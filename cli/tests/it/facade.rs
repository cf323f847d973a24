//! The public surface as a user holds it: `Camera`, `Device`, `Warper`, `overscan`,
//! `SceneRenderer`, `Error`. Checked against OpenCV's own numbers (the shared reference file),
//! against the f64 reference warp, and on a caller's own Vulkan device under validation.

use crate::common;

use common::{load_reference, shared_dir};
use vklens::{
    Camera, Device, DeviceOptions, ErrorKind, InverseMethod, PixelFormat, Pixels, Raster,
    SceneRenderer, WarpDirection, WarpMethod, WarpOptions, Warper,
};

fn device() -> Device {
    Device::with_options(DeviceOptions {
        validation: true,
        ..DeviceOptions::from_env()
    })
    .expect("a Vulkan device with the validation layer (README: the test command installs both)")
}

fn assert_no_validation_messages(device: &Device) {
    if let Err(e) = device.check_validation() {
        panic!("{e}");
    }
}

fn pattern(width: u32, height: u32) -> Raster {
    Raster {
        width,
        height,
        pixels: Pixels::Rgba8(
            (0..width * height)
                .map(|i| {
                    let (x, y) = (i % width, i / width);
                    let check = ((x / 16 + y / 16) % 2) as u8 * 200;
                    [check, (x % 251) as u8, (y % 241) as u8, 255]
                })
                .collect(),
        ),
        bit_depth: vklens::BitDepth::U8,
    }
}

#[test]
fn points_match_opencv_on_every_reference_camera() {
    let reference = load_reference();
    for case in &reference.cases {
        let k = [
            [case.fx, 0.0, case.cx],
            [0.0, case.fy, case.cy],
            [0.0, 0.0, 1.0],
        ];
        let camera = Camera::from_opencv(k, &case.dist_coeffs, (case.width, case.height))
            .unwrap_or_else(|e| panic!("{}: {e}", case.name));
        assert_eq!(camera.dist_coeffs(), case.dist_coeffs, "{}", case.name);
        assert_eq!(camera.k_matrix(), k);
        let xy: Vec<[f64; 2]> = case
            .points
            .iter()
            .map(|p| p.undistorted_normalized)
            .collect();
        let uv = camera.distort_points(&xy);
        let projected = camera.project_points(
            &xy.iter()
                .map(|&[x, y]| [2.0 * x, 2.0 * y, 2.0])
                .collect::<Vec<_>>(),
        );
        let back = camera.undistort_points(
            &uv.iter().map(|p| p.unwrap()).collect::<Vec<_>>(),
            InverseMethod::Newton,
        );
        let mut inverted = 0;
        for (i, p) in case.points.iter().enumerate() {
            let got = uv[i].unwrap();
            let d = (got[0] - p.distorted_pixel[0]).hypot(got[1] - p.distorted_pixel[1]);
            assert!(d <= 1e-9, "{} point {i}: forward off by {d} px", case.name);
            let q = projected[i].unwrap();
            assert!((q[0] - got[0]).abs() < 1e-9 && (q[1] - got[1]).abs() < 1e-9);
            // Inside the valid domain the inverse returns the point. A point the lens folds
            // over has no unique preimage: the inverse either says so or returns the one
            // preimage inside the domain, which maps to the same pixel.
            let [x0, y0] = p.undistorted_normalized;
            let inside = camera.domain().contains_ideal(glam::DVec2::new(x0, y0));
            match back[i] {
                Some(x) if inside => {
                    let e = (x[0] - x0).hypot(x[1] - y0);
                    assert!(e < 1e-9, "{} point {i}: inverse off by {e}", case.name);
                    inverted += 1;
                }
                Some(x) => {
                    let again = camera.distort_points(&[x])[0].unwrap();
                    let d = (again[0] - got[0]).hypot(again[1] - got[1]);
                    assert!(
                        d < 1e-6,
                        "{} point {i}: another preimage {d} px away",
                        case.name
                    );
                }
                None => assert!(
                    !inside,
                    "{} point {i}: refused inside the domain",
                    case.name
                ),
            }
        }
        assert!(inverted > case.points.len() / 2, "{}", case.name);
    }
    // Behind the camera: no pixel.
    let camera = common::reference_camera("seed_fig2");
    assert_eq!(
        camera.project_points(&[[0.0, 0.0, -1.0], [1.0, 1.0, 0.0]]),
        [None, None]
    );
}

#[test]
fn cameras_load_save_and_refuse_what_opencv_cannot_mean() {
    let file = shared_dir().join("reference/calibration-files/seed_fig2.opencv4.yml");
    let camera = Camera::load(&file).unwrap();
    let dir = std::env::temp_dir().join(format!("vklens-facade-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let saved = dir.join("cam.json");
    camera.save(&saved).unwrap();
    let again = Camera::load(&saved).unwrap();
    assert_eq!(again.intrinsics, camera.intrinsics);
    assert_eq!(again.dist_coeffs(), camera.dist_coeffs());
    assert_eq!((again.width, again.height), (camera.width, camera.height));
    // A Brown lens stays one through save and load.
    let brown = Camera::parse(
        r#"{"model": "brown", "width": 64, "height": 48, "c1": 0.1, "c2": 0.05}"#,
        "brown.json",
    )
    .unwrap();
    assert_eq!(brown.model_name(), "brown");
    assert_eq!(brown.to_json()["model"], "brown");

    let k = [[400.0, 0.0, 399.5], [0.0, 400.0, 299.5], [0.0, 0.0, 1.0]];
    let bad = |k: [[f64; 3]; 3], d: &[f64], size| Camera::from_opencv(k, d, size).unwrap_err();
    let seven = bad(k, &[0.0; 7], (800, 600));
    assert_eq!(seven.kind(), ErrorKind::Input);
    assert!(seven.to_string().contains("got 7"), "{seven}");
    let mut nan = k;
    nan[0][0] = f64::NAN;
    assert!(bad(nan, &[0.0; 5], (800, 600)).to_string().contains("K"));
    let mut skew = k;
    skew[0][1] = 0.5;
    assert!(bad(skew, &[0.0; 5], (800, 600))
        .to_string()
        .contains("skew"));
    let mut negative = k;
    negative[0][0] = -400.0;
    assert!(bad(negative, &[0.0; 5], (800, 600))
        .to_string()
        .contains("fx"));
    assert_eq!(bad(k, &[0.0; 5], (0, 600)).kind(), ErrorKind::Input);
    let missing = Camera::load(dir.join("none.json")).unwrap_err();
    assert_eq!(missing.kind(), ErrorKind::Io);
    assert!(missing.to_string().contains("none.json"), "{missing}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_warper_runs_like_the_reference_warp_and_its_maps_are_the_exact_coordinates() {
    let device = device();
    let camera = common::reference_camera("seed_fig2");
    let source = vklens::overscan(&camera, 1.0).unwrap();
    assert!(source.width > camera.width && source.dist_coeffs().iter().all(|&c| c == 0.0));
    let mut options = WarpOptions::distort();
    options.source_camera = Some(source.clone());
    options.method = WarpMethod::PerPixel(InverseMethod::Newton);
    let mut warper = Warper::new(device.gpu(), &camera, &options).unwrap();
    assert_eq!(warper.input_size(), (source.width, source.height));
    assert_eq!(warper.output_size(), (camera.width, camera.height));
    assert_eq!(warper.source_camera().intrinsics, source.intrinsics);
    assert_eq!(warper.direction(), WarpDirection::Distort);
    let input = pattern(source.width, source.height);
    let first = warper.run(&device, &input).unwrap();
    // Built once, run again: the same image.
    let second = warper.run(&device, &input).unwrap();
    assert_eq!(first.image, second.image);
    assert_eq!(first.mask, second.mask);
    // The maps: one source coordinate per output pixel, NaN where there is none (checked
    // against the f64 warp geometry by the unit tests beside the warper).
    let maps = warper.maps(&device).unwrap();
    let (w, h) = warper.output_size();
    assert_eq!(maps.len(), (w * h) as usize);
    assert!(
        maps.iter().any(|m| m[0].is_finite())
            && maps.iter().all(|m| m[0].is_nan() == m[1].is_nan())
    );
    // Wrong input: named, nothing run.
    let small = pattern(10, 10);
    let e = warper.run(&device, &small).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Input);
    assert!(e.to_string().contains("10×10"), "{e}");
    assert_no_validation_messages(&device);
}

#[test]
fn warper_options_are_checked_with_the_reason() {
    let device = device();
    let camera = common::reference_camera("seed_fig2");
    let mut options = WarpOptions::undistort();
    options.method = WarpMethod::PerPixel(InverseMethod::Heikkila);
    let e = Warper::new(device.gpu(), &camera, &options).err().unwrap();
    assert!(e.to_string().contains("forward model"), "{e}");
    let mut options = WarpOptions::distort();
    options.source_camera = Some(camera.clone());
    let e = Warper::new(device.gpu(), &camera, &options).err().unwrap();
    assert!(e.to_string().contains("no distortion"), "{e}");
    let mut options = WarpOptions::distort();
    options.format = PixelFormat::R32Uint;
    let e = Warper::new(device.gpu(), &camera, &options).err().unwrap();
    assert!(e.to_string().contains("nearest"), "{e}");
    assert!("bisection".parse::<WarpMethod>().is_err());
    assert_eq!("lut".parse::<WarpMethod>().unwrap(), WarpMethod::Lut);
    assert!("sideways".parse::<WarpDirection>().is_err());
    assert_no_validation_messages(&device);
}

#[test]
fn a_scene_renderer_plans_once_and_renders_every_pose() {
    let device = device();
    let path = crate::common::root().join("examples/scenes/ids_and_flow.toml");
    let scene = SceneRenderer::load(&path).unwrap();
    assert!(scene.explain().starts_with("plan: "), "{}", scene.explain());
    let frames = scene.render_all(&device).unwrap();
    assert_eq!(frames.len(), scene.frame_count());
    for (i, f) in frames.iter().enumerate() {
        assert_eq!(f.index, i);
        assert!(f.rendered.ids.is_some() && f.rendered.flow.is_some());
    }
    let e = scene
        .render(&device, 0..scene.frame_count() + 1, &mut |_| Ok(()))
        .unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Input);
    let e = SceneRenderer::parse("[geometry]\nscene = 3\n", &path)
        .err()
        .unwrap();
    assert!(e.to_string().contains("[geometry] scene"), "{e}");
    assert_no_validation_messages(&device);
}

#[test]
fn errors_in_files_a_scene_names_name_the_scene_file_and_key() {
    let dir = std::env::temp_dir().join(format!("vklens-scene-refs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let base = dir.join("scene.toml");
    let err = |text: &str| match vklens::SceneRenderer::parse(text, &base) {
        Ok(_) => panic!("must be refused: {text}"),
        Err(e) => (e.kind(), e.to_string()),
    };
    // A missing camera file: still an I/O error about that file, and the scene key says who
    // named it.
    let (kind, e) = err("[geometry]\nscene = \"boxes\"\n[optics]\ncamera = \"nope.json\"\n");
    assert_eq!(kind, vklens::ErrorKind::Io);
    assert!(
        e.contains("nope.json") && e.contains("scene.toml: [optics] camera"),
        "{e}"
    );
    // A broken one: input, led by the scene file and key.
    std::fs::write(dir.join("bad.json"), "{\"width\": 10").unwrap();
    let (kind, e) = err("[geometry]\nscene = \"boxes\"\n[optics]\ncamera = \"bad.json\"\n");
    assert_eq!(kind, vklens::ErrorKind::Input);
    assert!(
        e.contains("scene.toml: [optics] camera: ") && e.contains("bad.json"),
        "{e}"
    );
    // A missing lens prescription.
    let (_, e) = err(
        "[geometry]\nscene = \"boxes\"\n[optics]\nlens = \"nolens.dat\"\nsensor_mm = [36, 24]\npixels = [360, 240]\n",
    );
    assert!(
        e.contains("scene.toml: [optics] lens") && e.contains("nolens.dat"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
