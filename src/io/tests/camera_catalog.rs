//! Which camera of a file, and in which format: cameras picked by index or by the name the
//! file gives them, image sizes for files without one, what real files do to their text
//! (CRLF, tabs, `key:value`, `%YAML:1.0` and comments, `e-002`, wrapped and aligned lists),
//! and the writers of every format that can hold a camera, read back to the same pixels. The
//! files are small ones written here in each tool's layout (`cli/tests/it/cli_cameras.rs` runs
//! `vklens cameras` and `vklens convert` on them).

use crate::io::camera::{list_cameras, parse_camera_with};
use crate::io::catalog::LoadOptions;
use crate::io::writers::{write_camera, Format};
use crate::model::samples::sample_cameras;
use crate::model::Camera;
use glam::DVec3;

fn load(text: &str, options: &LoadOptions) -> Camera {
    parse_camera_with(text, "test.yaml", options).unwrap_or_else(|e| panic!("{e}"))
}

fn refused(text: &str, options: &LoadOptions) -> String {
    match parse_camera_with(text, "test.yaml", options) {
        Ok(c) => panic!("loaded as {} {}×{}", c.model_name(), c.width, c.height),
        Err(e) => e.to_string(),
    }
}

fn by_name(name: &str) -> LoadOptions {
    LoadOptions {
        name: Some(name.into()),
        ..LoadOptions::default()
    }
}

fn by_index(i: usize) -> LoadOptions {
    LoadOptions {
        index: Some(i),
        ..LoadOptions::default()
    }
}

fn sized(w: u32, h: u32) -> LoadOptions {
    LoadOptions {
        size: Some((w, h)),
        ..LoadOptions::default()
    }
}

/// Points all around, past 90° too: the same pixel to 1e-9 px (a file's numbers round-trip
/// exactly; a solver's bracket may move its last bit) or the same "not seen" for both.
fn same_pixels(a: &Camera, b: &Camera, what: &str) {
    assert_eq!(a.model_name(), b.model_name(), "{what}");
    assert_eq!((a.width, a.height), (b.width, b.height), "{what}");
    for i in 0..200 {
        let t = std::f64::consts::PI * (i as f64 + 0.5) / 200.0;
        let phi = 2.399963 * i as f64;
        let p = DVec3::new(t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos());
        match (a.project(p), b.project(p)) {
            (Some(x), Some(y)) => assert!(
                (x - y).length() <= 1e-9 * (1.0 + x.length()),
                "{what} at {p:?}: {x} vs {y}"
            ),
            (x, y) => assert_eq!(x, y, "{what} at {p:?}"),
        }
    }
}

const KALIBR: &str = "cam2:
  camera_model: pinhole
  intrinsics: [461.6, 460.3, 366.3, 249.3]
  distortion_model: radtan
  distortion_coeffs: [-0.27, 0.06, 1.2e-4, 2.2e-5]
  resolution: [752, 480]
cam10:
  camera_model: pinhole
  intrinsics: [458.7, 457.3, 367.2, 248.4]
  distortion_model: equidistant
  distortion_coeffs: [-0.013, 0.017, -0.012, 0.003]
  resolution: [752, 480]
";

#[test]
fn cameras_are_picked_by_index_or_by_the_name_the_file_gives() {
    // Kalibr: by their number (cam2 before cam10), named as written.
    let listing = list_cameras(KALIBR, "camchain.yaml", None).expect("listing");
    assert_eq!(listing.format, "Kalibr camchain");
    let names: Vec<_> = listing.cameras.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["cam2", "cam10"]);
    let first = load(KALIBR, &LoadOptions::default());
    assert_eq!(first.model_name(), "opencv");
    let fisheye = load(KALIBR, &by_name("cam10"));
    assert_eq!(fisheye.model_name(), "opencv_fisheye");
    same_pixels(&fisheye, &load(KALIBR, &by_index(1)), "cam10 = index 1");
    let e = refused(KALIBR, &by_name("cam1"));
    assert!(
        e.contains("no camera named `cam1`") && e.contains("cam2") && e.contains("cam10"),
        "{e}"
    );
    let e = refused(KALIBR, &by_index(2));
    assert!(
        e.contains("camera index 2") && e.contains("test.yaml"),
        "{e}"
    );
    let e = refused(
        KALIBR,
        &LoadOptions {
            index: Some(0),
            name: Some("cam10".into()),
            size: None,
        },
    );
    assert!(e.contains("index 1") && e.contains("index 0"), "{e}");

    // COLMAP: ids as written (starting at 2, unsorted), the position in the file as index.
    let colmap = "# Camera list with one line of data per camera:\n\
                  7 PINHOLE 640 480 500 500 320 240\n\
                  2 SIMPLE_RADIAL 800 600 700 400 300 -0.1\n";
    let c = load(colmap, &by_name("2"));
    assert_eq!((c.width, c.height), (800, 600));
    assert_eq!(load(colmap, &by_index(0)).width, 640);
    let e = refused(colmap, &by_name("3"));
    assert!(e.contains("0: 7") && e.contains("1: 2"), "{e}");
    // A malformed line is refused (naming its line), not loaded with made-up values, and
    // only when it is the camera asked for.
    let bad = format!("{colmap}9 OPENCV 640 480 500 500 320 240 0.1\n");
    let e = refused(&bad, &by_name("9"));
    assert!(
        e.contains("line 4") && e.contains("OPENCV has 8 parameters"),
        "{e}"
    );
    assert_eq!(load(&bad, &by_name("7")).width, 640);
    let listing = list_cameras(&bad, "cameras.txt", None).expect("listing");
    assert!(listing.cameras[2].camera.is_err() && listing.cameras[0].camera.is_ok());
}

#[test]
fn a_file_without_an_image_size_loads_only_with_one() {
    let no_size =
        "%YAML:1.0\ncamera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   \
                   data: [ 500., 0., 320., 0., 500., 240., 0., 0., 1. ]\n\
                   distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   \
                   data: [ -0.1, 0.01, 0., 0., 0. ]\n";
    let e = refused(no_size, &LoadOptions::default());
    assert!(e.contains("no image size") && e.contains("`size`"), "{e}");
    let c = load(no_size, &sized(640, 480));
    assert_eq!((c.width, c.height), (640, 480));
    // A file with a size keeps it; a different --size is refused, not rescaled.
    let e = refused(KALIBR, &sized(640, 480));
    assert!(e.contains("752×480") && e.contains("640×480"), "{e}");
    assert_eq!(load(KALIBR, &sized(752, 480)).width, 752);
}

/// The same OpenCV calibration as real files write it, quirk by quirk: every one loads to
/// the same camera.
#[test]
fn what_real_files_do_to_their_text_changes_nothing() {
    let plain = "%YAML:1.0\n---\nimage_width: 752\nimage_height: 480\n\
                 camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   \
                 data: [ 458.654, 0., 367.215, 0., 457.296, 248.375, 0., 0., 1. ]\n\
                 distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   \
                 data: [ -0.28340811, 0.07395907, 0.00019359, 1.76187114e-05, 0. ]\n";
    let want = load(plain, &LoadOptions::default());
    let quirks: Vec<(&str, String)> = vec![
        ("CRLF line ends", plain.replace('\n', "\r\n")),
        ("lone CR line ends", plain.replace('\n', "\r")),
        ("no final newline", plain.trim_end().to_string()),
        (
            "a directive, comments and a blank line before the document",
            plain.replace("%YAML:1.0\n---\n", "%YAML:1.0\n# calibrated 2019-03-01\n\n---\n# camera 0\n"),
        ),
        ("key:value without a space", plain.replace("image_width: ", "image_width:").replace("data: [", "data:[")),
        ("tabs", plain.replace("   rows", "\trows").replace("   cols", "\tcols").replace("   dt", "\tdt").replace("   data", "\tdata").replace(", ", ",\t")),
        ("e-002 exponents", plain.replace("0.07395907", "7.395907e-002").replace("1.76187114e-05", "1.76187114e-005")),
        (
            "a wrapped, column-aligned matrix",
            plain.replace(
                "data: [ 458.654, 0., 367.215, 0., 457.296, 248.375, 0., 0., 1. ]",
                "data: [ 458.654,   0.,      367.215,\n       0.,        457.296, 248.375,\n       0.,        0.,      1. ]",
            ),
        ),
    ];
    for (what, text) in quirks {
        let got = parse_camera_with(&text, "quirk.yml", &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        same_pixels(&got, &want, what);
    }
    // Flow mappings with comments inside, as Kalibr-style configs write them.
    let flow = "cam0: {camera_model: pinhole, # the left camera\n  \
                intrinsics: [458.654, 457.296, 367.215, 248.375], # fu fv pu pv\n  \
                distortion_model: radtan,\n  \
                distortion_coeffs: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05],\n  \
                resolution: [752, 480]}\n";
    same_pixels(
        &load(flow, &LoadOptions::default()),
        &want,
        "flow mapping with comments",
    );
}

#[test]
fn convert_writes_every_format_that_holds_the_camera_and_reads_back_the_same_pixels() {
    let mut held = 0;
    for (name, camera) in sample_cameras().expect("samples") {
        for format in Format::ALL {
            match write_camera(&camera, format) {
                Ok(text) => {
                    let origin = if matches!(format, Format::Vklens | Format::Basalt) {
                        "out.json"
                    } else {
                        "out.yaml"
                    };
                    let back = parse_camera_with(&text, origin, &LoadOptions::default())
                        .unwrap_or_else(|e| panic!("{name} → {}: {e}\n{text}", format.name()));
                    same_pixels(&back, &camera, &format!("{name} → {}", format.name()));
                    held += 1;
                }
                Err(e) => {
                    let m = e.to_string();
                    assert!(
                        m.contains("cannot hold this camera")
                            && m.contains("vklens JSON holds every camera"),
                        "{name} → {}: {m}",
                        format.name()
                    );
                    assert_eq!(e.kind(), crate::ErrorKind::Unsupported, "{m}");
                    assert_ne!(
                        format,
                        Format::Vklens,
                        "vklens JSON holds every camera: {m}"
                    );
                }
            }
        }
    }
    assert!(held >= 30, "only {held} conversions held");
    // ROS cannot hold a double sphere, and says so.
    let ds = sample_cameras()
        .expect("samples")
        .into_iter()
        .find(|(n, _)| *n == "double_sphere")
        .map(|(_, c)| c)
        .expect("ds");
    let e = write_camera(&ds, Format::Ros).expect_err("ros").to_string();
    assert!(e.contains("double_sphere"), "{e}");
}

/// Basalt's pinhole-radtan8 carries `rpmax`: its projection accepts undistorted normalized
/// radii up to it, and vklens's valid domain (what the inverse, the warps and the renderers
/// keep) ends there too. (Its forward map, like cv2.projectPoints, evaluates any point.)
#[test]
fn basalt_rpmax_bounds_the_domain() {
    let file = |rpmax: &str| {
        format!(
            r#"{{"value0": {{"intrinsics": [{{"camera_type": "pinhole-radtan8", "intrinsics": {{
            "fx": 380.0, "fy": 380.0, "cx": 320.0, "cy": 240.0, "k1": -0.05, "k2": 0.01,
            "p1": 0.0, "p2": 0.0, "k3": 0.0, "k4": 0.0, "k5": 0.0, "k6": 0.0{rpmax}}}}}],
            "resolution": [[640, 480]]}}}}"#
        )
    };
    let open =
        parse_camera_with(&file(""), "calib.json", &LoadOptions::default()).expect("no rpmax");
    let capped = parse_camera_with(
        &file(r#", "rpmax": 1.5"#),
        "calib.json",
        &LoadOptions::default(),
    )
    .expect("rpmax");
    for (r, inside) in [(1.0, true), (1.49, true), (1.51, false), (2.5, false)] {
        let p = DVec3::new(r * 0.6, r * 0.8, 1.0);
        let px = open.project(p).expect("px");
        assert_eq!(capped.project(p), Some(px));
        assert_eq!(capped.unproject(px).is_some(), inside, "r = {r}");
        assert!(
            open.unproject(px).is_some(),
            "without rpmax, r = {r} is seen"
        );
    }
    let e = parse_camera_with(
        &file(r#", "rpmax": -1"#),
        "calib.json",
        &LoadOptions::default(),
    )
    .expect_err("negative");
    assert!(e.to_string().contains("rpmax"), "{e}");
}

#[test]
fn only_a_camera_info_rectifies_an_opencv_stereo_files_r_is_the_pairs_rotation() {
    use crate::io::camera::rectification_of;
    let ros = "image_width: 64
image_height: 48
camera_name: left
camera_matrix: {rows: 3, cols: 3, data: [60, 0, 31.5, 0, 60, 23.5, 0, 0, 1]}
distortion_model: plumb_bob
distortion_coefficients: {rows: 1, cols: 5, data: [-0.1, 0.01, 0, 0, 0]}
rectification_matrix: {rows: 3, cols: 3, data: [0, -1, 0, 1, 0, 0, 0, 0, 1]}
projection_matrix: {rows: 3, cols: 4, data: [55, 0, 30, -5.5, 0, 55, 24, 0, 0, 0, 1, 0]}
";
    let r = rectification_of(ros, "left.yaml")
        .unwrap()
        .expect("R and P");
    assert_eq!(r.r, [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]);
    assert_eq!(r.p[0], [55.0, 0.0, 30.0, -5.5]);
    assert_eq!((r.intrinsics.fx, r.intrinsics.cy), (55.0, 24.0));
    // The flat CameraInfo keys, beside its distortion_model.
    let flat = "{\"width\": 64, \"height\": 48, \"distortion_model\": \"plumb_bob\",
        \"K\": [60, 0, 31.5, 0, 60, 23.5, 0, 0, 1], \"D\": [0, 0, 0, 0, 0],
        \"R\": [1, 0, 0, 0, 1, 0, 0, 0, 1], \"P\": [50, 0, 31.5, 0, 0, 50, 23.5, 0, 0, 0, 1, 0]}";
    let r = rectification_of(flat, "info.json")
        .unwrap()
        .expect("R and P");
    assert_eq!(r.intrinsics.fx, 50.0);
    // An OpenCV stereo file's R (and T) relate its two cameras: nothing to rectify a camera by,
    // and undistorting one of its cameras must not trip over them.
    let stereo = "%YAML:1.0
image_width: 64
image_height: 48
M1: {rows: 3, cols: 3, data: [60, 0, 31.5, 0, 60, 23.5, 0, 0, 1]}
D1: {rows: 1, cols: 5, data: [-0.1, 0.01, 0, 0, 0]}
R: {rows: 3, cols: 3, data: [0.995, 0, 0.0998, 0, 1, 0, -0.0998, 0, 0.995]}
T: {rows: 3, cols: 1, data: [-0.1, 0, 0]}
";
    assert_eq!(rectification_of(stereo, "stereo.yml").unwrap(), None);
    assert_eq!(load(stereo, &LoadOptions::default()).width, 64);
}

#[test]
fn a_rectified_camera_info_reads_back_its_r_and_p_and_its_lens() {
    use crate::io::camera::rectification_of;
    let k = crate::model::Intrinsics {
        fx: 600.25,
        fy: 610.5,
        cx: 330.2,
        cy: 236.9,
    };
    let d = [-0.05, 0.01, 0.001, -0.0015, 0.0002];
    let lens = Camera::from_coeffs(640, 480, k, &d).unwrap();
    let fish = Camera::fisheye(
        640,
        480,
        k,
        crate::model::Fisheye::new([0.02, -0.004, 0.001, -0.0002], 0.0, None).unwrap(),
    )
    .unwrap();
    // Entries no short decimal writes exactly: the file must carry every bit.
    let third = 1.0f64 / 3.0;
    let r = [
        [third.sqrt(), 0.1, 0.2],
        [-0.1, 0.7, std::f64::consts::FRAC_1_SQRT_2],
        [0.3, -0.4, 0.9],
    ];
    let p = [
        [607.123456789, 0.0, 321.7, -72.0 * third],
        [0.0, 607.123456789, 239.1, 0.0],
        [0.0, 0.0, 1.0, 0.0],
    ];
    for camera in [&lens, &fish] {
        let text = camera.to_ros_camera_info_rectified(r, p).unwrap();
        let back = rectification_of(&text, "left.yaml")
            .unwrap()
            .expect("R and P");
        assert_eq!((back.r, back.p), (r, p));
        // K and D are the lens's: the file loads back to the same camera.
        let again = Camera::parse(&text, "left.yaml").unwrap();
        assert_eq!(again.intrinsics, camera.intrinsics);
        assert_eq!(again.dist_coeffs(), camera.dist_coeffs());
        assert_eq!(again.model(), camera.model());
    }
    let mut bad = p;
    bad[0][3] = f64::NAN;
    let e = lens.to_ros_camera_info_rectified(r, bad).unwrap_err();
    assert!(e.to_string().contains("finite"), "{e}");
}
