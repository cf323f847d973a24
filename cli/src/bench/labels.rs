//! `vklens bench labels`: what each label costs beside colour alone, on the boxes scene (named
//! objects on a floor, seen from above as examples/scenes/ground_truth.toml sees them) at
//! 1920×1080 through the GoPro-like lens and the 200° fisheye of `bench wide`:
//!
//! * the vertex path rendering colour alone (the peer), then colour with IDs, with depth, with
//!   range (both recomputed on each pixel's own ray, the inverse model in the fragment stage),
//!   and with IDs and range together (what classes, boxes and keypoints are read from);
//! * the CPU labels of that last frame: the class image, every object's boxes (the amodal box
//!   traced to the default 0.01 px) and four keypoints;
//! * the cube route (six faces and the sphere warp) with colour alone, and with IDs and range
//!   (the faces' IDs and depths sampled nearest, the depth carried onto each pixel's ray).
//!
//! Frame time: wall clock of one whole render, readback included, median of 3 after a warm-up,
//! as × the colour-alone vertex frame of the same camera in the same run.

use serde_json::{json, Value};

use super::fixed as f;
use vklens::gpu::Result;
use vklens::host::plan::render_request;
use vklens::host::Context;
use vklens::labels::{self, ClassRule, Keypoint, LabelRequest, View};
use vklens::model::overscan::cube_face_side;
use vklens::pass::geometry::DEFAULT_DELTA;
use vklens::plan::scene_file::OutputSpec;
use vklens::plan::{PathChoice, RenderRequest};
use vklens::scene::builtin;

/// The rows' output sets, by name: colour plus these.
fn outputs() -> [(&'static str, OutputSpec); 5] {
    let colour = OutputSpec {
        color: true,
        ..OutputSpec::default()
    };
    [
        ("colour (peer)", colour),
        (
            "+ IDs",
            OutputSpec {
                ids: true,
                ..colour
            },
        ),
        (
            "+ depth",
            OutputSpec {
                depth: true,
                ..colour
            },
        ),
        (
            "+ range",
            OutputSpec {
                range: true,
                ..colour
            },
        ),
        (
            "+ IDs + range",
            OutputSpec {
                ids: true,
                range: true,
                ..colour
            },
        ),
    ]
}

/// Runs every row; `progress` hears what is being measured.
pub fn run(ctx: &Context, progress: &mut dyn FnMut(&str)) -> Result<Vec<Value>> {
    let scene = builtin::boxes();
    let cameras: Vec<_> = super::wide::cameras()
        .into_iter()
        .filter(|(name, _)| !name.starts_with("fisheye 180"))
        .collect();
    let rules = [
        ClassRule {
            pattern: "box_r*".into(),
            class: 2,
        },
        ClassRule {
            pattern: "box_*".into(),
            class: 1,
        },
    ];
    let objects = labels::object_labels(&scene, &rules);
    let keypoints: Vec<Keypoint> = [
        ("red_top", [-0.9, -0.1, 0.4]),
        ("green_top", [0.0, -0.4, 1.2]),
        ("blue_top", [0.9, 0.05, 0.2]),
        ("under_green", [0.0, 0.5, 1.2]),
    ]
    .into_iter()
    .map(|(name, xyz)| Keypoint {
        name: name.into(),
        xyz: glam::DVec3::from(xyz),
    })
    .collect();
    let mut rows = Vec::new();
    for (name, camera) in cameras {
        // examples/scenes/ground_truth.toml's pose: half a metre above the boxes, looking down
        // at them.
        let pose = vklens::scene::Pose::from_rvec_tvec(
            glam::DVec3::new(1.1, 0.0, 0.0),
            glam::DVec3::new(-0.1, 0.4, 0.55),
        );
        let vertex = PathChoice::Vertex {
            delta: DEFAULT_DELTA,
            tessellate: Some(8.0),
        };
        let request = |outputs: OutputSpec, path: PathChoice| RenderRequest {
            pose,
            previous_pose: pose,
            outputs,
            ..RenderRequest::color(&camera, path)
        };
        let mut peer = f64::NAN;
        for (k, (what, outputs)) in outputs().into_iter().enumerate() {
            progress(&format!("{name}: vertex path, {what}"));
            let ms = super::wide::request_frame_ms(ctx, &scene, &request(outputs, vertex))?;
            // The first row, colour alone, is the peer.
            if k == 0 {
                peer = ms;
            }
            let mut row = json!({"camera": name, "route": "vertex", "outputs": what,
                "frame_ms": ms, "x_colour": ms / peer});
            if outputs.ids && outputs.range {
                progress(&format!("{name}: classes, boxes and keypoints (CPU)"));
                let r = render_request(ctx, &scene, &request(outputs, vertex), &mut |_| {})?;
                let view = View {
                    camera: &camera,
                    pose,
                    moving: None,
                };
                let ask = LabelRequest {
                    objects: &objects,
                    classes: true,
                    boxes: true,
                    keypoints: &keypoints,
                    max_error_px: vklens::plan::scene_file::DEFAULT_MAX_ERROR_PX,
                };
                let mut times = Vec::new();
                let mut boxes = 0;
                for _ in 0..3 {
                    let start = std::time::Instant::now();
                    let l = labels::frame_labels(&view, &scene, &r, &ask)
                        .map_err(vklens::Error::internal)?;
                    times.push(start.elapsed().as_secs_f64() * 1e3);
                    boxes = l.boxes.map_or(0, |b| b.len());
                }
                times.sort_by(f64::total_cmp);
                if let Some(o) = row.as_object_mut() {
                    o.insert("labels_cpu_ms".into(), times[1].into());
                    o.insert("boxes".into(), boxes.into());
                }
            }
            rows.push(row);
        }
        let side = cube_face_side(&camera, 1.0);
        let cube = PathChoice::Cube { side };
        for (what, outputs) in [outputs()[0], outputs()[4]] {
            progress(&format!("{name}: cube route, {what}"));
            let ms = super::wide::request_frame_ms(ctx, &scene, &request(outputs, cube))?;
            let what = what.replace(" (peer)", "");
            rows.push(
                json!({"camera": name, "route": format!("cube ({side}² faces)"),
                "outputs": what, "frame_ms": ms, "x_colour": ms / peer}),
            );
        }
    }
    Ok(rows)
}

/// The rows as a Markdown table.
pub fn table(rows: &[Value]) -> String {
    let mut out = String::from(
        "| camera (1920×1080) | route | outputs | frame ms | × colour alone | classes + boxes + keypoints, CPU ms |\n|---|---|---|---:|---:|---:|\n",
    );
    for r in rows {
        out.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} |\n",
            r["camera"].as_str().unwrap_or("?"),
            r["route"].as_str().unwrap_or("?"),
            r["outputs"].as_str().unwrap_or("?"),
            f(r, "frame_ms", 1),
            f(r, "x_colour", 2),
            f(r, "labels_cpu_ms", 1),
        ));
    }
    out
}
