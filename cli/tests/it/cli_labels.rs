//! `vklens render`'s labels as a training-data script uses them: range, classes, boxes,
//! keypoints and the object list, from flags and from a scene file; bad input is one line,
//! exit 2, and nothing written.

use std::path::PathBuf;

use crate::common::{root, scratch, stderr, vklens};

fn tmp(name: &str) -> PathBuf {
    scratch("clilabels", name)
}

fn fisheye() -> String {
    root()
        .join("examples/cameras/fisheye_200.json")
        .display()
        .to_string()
}

fn json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The boxes scene from 1.5 m above, looking down, through the 200° fisheye.
const POSE: &str = "1.5707963267948966,0,0,0,0.6,1.0";

#[test]
fn flags_write_every_label_and_they_agree_with_each_other() {
    let (c, ids, range, depth, classes) = (
        tmp("c.png"),
        tmp("ids.png"),
        tmp("r.exr"),
        tmp("d.exr"),
        tmp("cl.png"),
    );
    let (boxes, keypoints, objects) = (tmp("b.json"), tmp("k.json"), tmp("o.json"));
    let cam = fisheye();
    let o = vklens(&[
        "render",
        "--camera",
        &cam,
        "--scene",
        "boxes",
        "--pose",
        POSE,
        "--output",
        c.to_str().unwrap(),
        "--ids",
        ids.to_str().unwrap(),
        "--range",
        range.to_str().unwrap(),
        "--depth",
        depth.to_str().unwrap(),
        "--classes",
        classes.to_str().unwrap(),
        "--class",
        "box_r*=7",
        "--class",
        "box_*=3",
        "--boxes",
        boxes.to_str().unwrap(),
        "--keypoint",
        "green_top=0,-0.4,1.2",
        "--keypoint",
        "under_green=0,0.5,1.2",
        "--keypoints",
        keypoints.to_str().unwrap(),
        "--objects",
        objects.to_str().unwrap(),
        "--tessellate",
        "8",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let objects = json(&objects);
    let classes_of: Vec<(String, u64)> = objects
        .as_array()
        .unwrap()
        .iter()
        .map(|o| {
            (
                o["name"].as_str().unwrap().to_string(),
                o["class"].as_u64().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        classes_of,
        [
            ("floor".to_string(), 0),
            ("box_red".to_string(), 7),
            ("box_green".to_string(), 3),
            ("box_blue".to_string(), 3)
        ]
    );
    // The class image is the ID image through the object list, pixel by pixel.
    let ids = image::open(&ids).unwrap().to_luma16();
    let cl = image::open(&classes).unwrap().to_luma16();
    for (i, c) in ids.pixels().zip(cl.pixels()) {
        let want = [0, 0, 7, 3, 3][i[0] as usize];
        assert_eq!(c[0], want);
    }
    // Range against depth: never shorter, +inf where nothing is drawn.
    let r = image::open(&range).unwrap().to_rgba32f();
    let d = image::open(&depth).unwrap().to_rgba32f();
    for ((rp, dp), i) in r.pixels().zip(d.pixels()).zip(ids.pixels()) {
        if i[0] == 0 {
            assert!(rp[0].is_infinite());
        } else {
            assert!(
                rp[0] >= dp[0].abs() * (1.0 - 1e-6),
                "{} vs {}",
                rp[0],
                dp[0]
            );
        }
    }
    // Boxes: one per object with pixels, the visible box the ID image's tight box.
    let boxes = json(&boxes);
    let boxes = boxes.as_array().unwrap();
    assert_eq!(boxes.len(), 4);
    for b in boxes {
        let id = b["id"].as_u64().unwrap() as u16;
        let (mut x0, mut y0, mut x1, mut y1, mut n) = (u32::MAX, u32::MAX, 0, 0, 0u64);
        for (x, y, p) in ids.enumerate_pixels() {
            if p[0] == id {
                (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x + 1), y1.max(y + 1));
                n += 1;
            }
        }
        assert_eq!(b["visible_px"].as_u64().unwrap(), n);
        let got: Vec<u64> = b["bbox_visible"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap())
            .collect();
        assert_eq!(got, [x0 as u64, y0 as u64, x1 as u64, y1 as u64]);
        assert_eq!(b["corners_3d"].as_array().unwrap().len(), 8);
    }
    // Keypoints: the f64 projection, and the floor under the green box hidden by it.
    let camera = vklens::Camera::load(&cam).unwrap();
    let (s, co) = std::f64::consts::FRAC_PI_2.sin_cos();
    let keypoints = json(&keypoints);
    let k = keypoints.as_array().unwrap();
    for (entry, [x, y, z]) in k.iter().zip([[0.0, -0.4, 1.2], [0.0, 0.5, 1.2]]) {
        // rvec (π/2, 0, 0) turns about x; then tvec.
        let p = [x, co * y - s * z + 0.6, s * y + co * z + 1.0];
        let want = camera.project_points(&[p])[0].unwrap();
        let got = entry["pixel"].as_array().unwrap();
        assert!((got[0].as_f64().unwrap() - want[0]).abs() < 1e-6);
        assert!((got[1].as_f64().unwrap() - want[1]).abs() < 1e-6);
    }
    assert_eq!(k[0]["visible"], true);
    assert_eq!(k[1]["visible"], false);
}

#[test]
fn the_ground_truth_example_writes_every_label_beside_its_frames() {
    let out = tmp("gt_out");
    let _ = std::fs::remove_dir_all(&out);
    let scene = root().join("examples/scenes/ground_truth.toml");
    let o = vklens(&[
        "render",
        "--scene",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in [
        "color_0000.png",
        "ids_0000.png",
        "depth_0000.exr",
        "range_0000.exr",
        "classes_0000.png",
        "boxes_0000.json",
        "keypoints_0000.json",
        "objects.json",
        "plan.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let k = json(&out.join("keypoints_0000.json"));
    let visible: Vec<bool> = k
        .as_array()
        .unwrap()
        .iter()
        .map(|k| k["visible"].as_bool().unwrap())
        .collect();
    assert_eq!(visible, [true, true, true, false]);
}

#[test]
fn bad_label_input_is_one_line_exit_2_and_nothing_written() {
    let cam = fisheye();
    let c = tmp("bad_c.png");
    let k = tmp("bad_k.json");
    let _ = std::fs::remove_file(&c);
    let base = [
        "render",
        "--camera",
        cam.as_str(),
        "--scene",
        "boxes",
        "--output",
        c.to_str().unwrap(),
    ];
    let cases: [(&[&str], &str); 5] = [
        (&["--class", "box_*=car"], "--class"),
        (&["--class", "box_*=2"], "--classes"),
        (
            &["--keypoint", "a=1,2", "--keypoints", k.to_str().unwrap()],
            "--keypoint",
        ),
        (&["--keypoints", k.to_str().unwrap()], "--keypoint"),
        (&["--range", "r.png"], ".exr"),
    ];
    for (extra, named) in cases {
        let args: Vec<&str> = base.iter().chain(extra.iter()).copied().collect();
        let o = vklens(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(named), "{args:?}: {err}");
        assert!(!c.exists() && !k.exists(), "{args:?} wrote a file");
    }
    // A scene file's [classes] with a class that is not a whole number names its key.
    let scene = tmp("bad_classes.toml");
    let text = std::fs::read_to_string(root().join("examples/scenes/ground_truth.toml"))
        .unwrap()
        .replace("\"box_*\" = 1", "\"box_*\" = \"car\"")
        .replace(
            "../cameras/",
            &format!("{}/", root().join("examples/cameras").display()),
        );
    std::fs::write(&scene, text).unwrap();
    let out = tmp("bad_classes_out");
    let _ = std::fs::remove_dir_all(&out);
    let o = vklens(&[
        "render",
        "--scene",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("[classes] \"box_*\""), "{err}");
    assert!(!out.exists(), "the output folder was made");
}

/// Six faces of a 4 m room around the camera as a renderer would write them (`side`² each,
/// +x −x +y −y +z −z; file names start with `tag`): grey colour, the wall's ID (1 + the face's index) in a 16-bit PNG, and
/// each face's z (the wall is 2 m along every face's axis) in an EXR. The file lists.
fn room_faces(side: u32, tag: &str) -> (String, String, String) {
    use vklens::imaging::{file::save, BitDepth, Pixels, Raster};
    let n = (side * side) as usize;
    let (mut colour, mut ids, mut depth) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..6u32 {
        let c = tmp(&format!("{tag}_c{k}.png"));
        let i = tmp(&format!("{tag}_i{k}.png"));
        let d = tmp(&format!("{tag}_d{k}.exr"));
        let raster = |pixels, bit_depth| Raster {
            width: side,
            height: side,
            pixels,
            bit_depth,
        };
        save(
            &raster(Pixels::Rgba8(vec![[128, 128, 128, 255]; n]), BitDepth::U8),
            &c,
        )
        .unwrap();
        save(&raster(Pixels::R32Uint(vec![k + 1; n]), BitDepth::U16), &i).unwrap();
        save(
            &raster(
                Pixels::Rgba32F(vec![[2.0, 2.0, 2.0, 1.0]; n]),
                BitDepth::F32,
            ),
            &d,
        )
        .unwrap();
        colour.push(c.display().to_string());
        ids.push(i.display().to_string());
        depth.push(d.display().to_string());
    }
    (colour.join(","), ids.join(","), depth.join(","))
}

#[test]
fn a_renderers_own_cube_faces_give_ids_depth_and_range_through_the_lens() {
    let (colour, ids, depth) = room_faces(64, "room");
    let (c, oi, od, or) = (
        tmp("ext_c.png"),
        tmp("ext_ids.png"),
        tmp("ext_d.exr"),
        tmp("ext_r.exr"),
    );
    let cam = fisheye();
    let o = vklens(&[
        "distort",
        "--camera",
        &cam,
        "--input-cubemap",
        &colour,
        "--input-ids",
        &ids,
        "--input-depth",
        &depth,
        "--output",
        c.to_str().unwrap(),
        "--output-ids",
        oi.to_str().unwrap(),
        "--output-depth",
        od.to_str().unwrap(),
        "--output-range",
        or.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let camera = vklens::Camera::load(&cam).unwrap();
    let got_ids = image::open(&oi).unwrap().to_luma16();
    let range = image::open(&or).unwrap().to_rgba32f();
    let z = image::open(&od).unwrap().to_rgba32f();
    let (mut checked, mut wrong, mut worst) = (0, 0, 0f64);
    for (x, y, id) in got_ids.enumerate_pixels() {
        let id = id[0] as u32;
        assert!(id <= 6, "ID {id} is in no input face");
        let rays = camera.unproject_points(&[[x as f64, y as f64]]);
        let Some(r) = rays[0] else {
            assert_eq!(id, 0, "an ID outside the lens");
            continue;
        };
        let a = r.map(f64::abs);
        let (axis, along) = (0..3)
            .map(|k| (k, a[k]))
            .fold((0, 0.0), |m, v| if v.1 > m.1 { v } else { m });
        let want = 1 + 2 * axis as u32 + (r[axis] < 0.0) as u32;
        // Faces meet at 45°: a pixel that close may take either wall.
        let sorted = {
            let mut s = a;
            s.sort_by(f64::total_cmp);
            s
        };
        if sorted[2] - sorted[1] < 0.02 {
            continue;
        }
        checked += 1;
        wrong += (id != want) as usize;
        let want_range = 2.0 / along;
        worst = worst
            .max((range.get_pixel(x, y)[0] as f64 - want_range).abs() / want_range)
            .max((z.get_pixel(x, y)[0] as f64 - want_range * r[2]).abs() / want_range);
    }
    println!("{checked} px checked, {wrong} wrong IDs, range and z within {worst:.1e}");
    assert!(checked > 100_000 && wrong == 0);
    assert!(worst < 1e-3, "{worst}");
}

#[test]
fn bad_face_data_is_one_line_exit_2_and_nothing_written() {
    use vklens::imaging::{file::save, BitDepth, Pixels, Raster};
    let (colour, ids, depth) = room_faces(32, "bad");
    let cam = fisheye();
    let out = tmp("bad_ext.png");
    let oi = tmp("bad_ext_ids.png");
    let _ = std::fs::remove_file(&out);
    let _ = std::fs::remove_file(&oi);
    // A depth face of another size; a NaN depth; IDs in a colour PNG with alpha.
    let small = tmp("small_d.exr");
    save(
        &Raster {
            width: 16,
            height: 16,
            pixels: Pixels::Rgba32F(vec![[2.0; 4]; 256]),
            bit_depth: BitDepth::F32,
        },
        &small,
    )
    .unwrap();
    let nan = tmp("nan_d.exr");
    save(
        &Raster {
            width: 32,
            height: 32,
            pixels: Pixels::Rgba32F(vec![[f32::NAN, 0.0, 0.0, 1.0]; 1024]),
            bit_depth: BitDepth::F32,
        },
        &nan,
    )
    .unwrap();
    let rgba = tmp("rgba_ids.png");
    save(
        &Raster {
            width: 32,
            height: 32,
            pixels: Pixels::Rgba8(vec![[1, 2, 3, 4]; 1024]),
            bit_depth: BitDepth::U8,
        },
        &rgba,
    )
    .unwrap();
    let with_face = |list: &str, k: usize, p: &std::path::Path| {
        let mut v: Vec<String> = list.split(',').map(String::from).collect();
        v[k] = p.display().to_string();
        v.join(",")
    };
    let cases = [
        (
            vec![
                "--input-depth".to_string(),
                with_face(&depth, 2, &small),
                "--output-range".into(),
                tmp("bad_r.exr").display().to_string(),
            ],
            "--input-depth",
        ),
        (
            vec![
                "--input-depth".to_string(),
                with_face(&depth, 0, &nan),
                "--output-range".into(),
                tmp("bad_r.exr").display().to_string(),
            ],
            "NaN",
        ),
        (
            vec![
                "--input-ids".to_string(),
                with_face(&ids, 1, &rgba),
                "--output-ids".into(),
                oi.display().to_string(),
            ],
            "grey",
        ),
        (
            vec!["--output-ids".to_string(), oi.display().to_string()],
            "--input-ids",
        ),
    ];
    for (extra, named) in cases {
        let mut args: Vec<String> = [
            "distort",
            "--camera",
            cam.as_str(),
            "--input-cubemap",
            colour.as_str(),
            "--output",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        args.push(out.display().to_string());
        args.extend(extra);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = vklens(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(named), "{args:?}: {err}");
        assert!(!out.exists() && !oi.exists(), "{args:?} wrote a file");
    }
    // Beside a pinhole image, one image of IDs: six are refused, naming the flag.
    let src = tmp("src32.json");
    std::fs::write(
        &src,
        r#"{"width": 32, "height": 32, "fx": 16, "fy": 16, "cx": 15.5, "cy": 15.5, "dist_coeffs": [0, 0, 0, 0]}"#,
    )
    .unwrap();
    let o = vklens(&[
        "distort",
        "--camera",
        cam.as_str(),
        "--source-camera",
        src.to_str().unwrap(),
        "--input",
        colour.split(',').nth(4).unwrap(),
        "--output",
        out.to_str().unwrap(),
        "--input-ids",
        &ids,
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("--input-ids: one image"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
    // One image each: the +z face as the pinhole image of a 90° camera, its wall (ID 5) 2 m
    // ahead: straight ahead through the fisheye, ID 5 at range 2.
    let (one_id, one_depth) = (
        ids.split(',').nth(4).unwrap(),
        depth.split(',').nth(4).unwrap(),
    );
    let or = tmp("pinhole_r.exr");
    let o = vklens(&[
        "distort",
        "--camera",
        cam.as_str(),
        "--source-camera",
        src.to_str().unwrap(),
        "--input",
        colour.split(',').nth(4).unwrap(),
        "--output",
        out.to_str().unwrap(),
        "--input-ids",
        one_id,
        "--input-depth",
        one_depth,
        "--output-ids",
        oi.to_str().unwrap(),
        "--output-range",
        or.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let got = image::open(&oi).unwrap().to_luma16();
    let range = image::open(&or).unwrap().to_rgba32f();
    assert!(got.pixels().all(|p| p[0] == 0 || p[0] == 5));
    assert_eq!(got.get_pixel(399, 399)[0], 5);
    assert!((range.get_pixel(399, 399)[0] - 2.0).abs() < 1e-4);
    let _ = std::fs::remove_file(&out);
    let _ = std::fs::remove_file(&oi);
}
