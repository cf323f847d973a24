//! The geometry path (seed 000 Sec. 3.2) on lavapipe, validated.

mod common;

use common::{assert_no_validation_messages, reference_camera, validated_context};
use vklens::pass::geometry::{render, GeometryDesc, Outputs, Projection, DEFAULT_DELTA};
use vklens::scene::builtin;

#[test]
fn smoke_all_outputs() {
    let ctx = validated_context();
    let cam = reference_camera("seed_fig2");
    let scene = builtin::parse("checkerboard").unwrap();
    let k = cam.intrinsics;
    let pose = scene.default_pose([
        (k.cx + 0.5) / k.fx,
        (cam.width as f64 - k.cx - 0.5) / k.fx,
        (k.cy + 0.5) / k.fy,
        (cam.height as f64 - k.cy - 0.5) / k.fy,
    ]);
    let outputs = Outputs { color: Some(vklens::pass::geometry::ColorFormat::Rgba8), ids: true, flow: true, depth: true };
    let r = render(&ctx, GeometryDesc::new(cam, Projection::Lens { delta: DEFAULT_DELTA }, outputs), &scene.mesh, None, &pose, &pose).unwrap();
    assert_no_validation_messages(&ctx);
    let ids = r.ids.unwrap();
    assert!(ids.iter().filter(|&&i| i > 0).count() > 1000);
}
