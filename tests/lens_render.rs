//! Seed 004's image-based model rendered on the GPU against the CPU distribution ray tracer
//! through the same lens and scene.

mod common;

use common::{assert_no_validation_messages, validated_context};
use vklens::lens::image_model::{ImageModel, ModelOptions, Optics};
use vklens::lens::reference::{psnr, render_reference, Channel};
use vklens::lens::{Prescription, LAMBDA_D};
use vklens::pass::geometry::MeshBuffers;
use vklens::pass::lens_render::{LensRenderOptions, LensRenderer, ALL_CHANNELS};
use vklens::scene::builtin;

fn shipped(name: &str) -> Prescription {
    Prescription::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("lenses")
            .join(name),
    )
    .unwrap()
}

#[test]
fn image_based_render_matches_the_reference() {
    let ctx = validated_context();
    for lens in ["achromat.50mm.dat", "biconvex.50mm.dat"] {
        let p = shipped(lens);
        let scene = builtin::boxes();
        let mut optics = Optics::new(&p, (240, 160), 0.15, 1.0, None).unwrap();
        let pose = scene.default_pose(&optics.equivalent_camera().unwrap());
        let focus = pose.apply(0.5 * (scene.mesh.bounds().0 + scene.mesh.bounds().1)).z;
        optics = Optics::new(&p, (240, 160), 0.15, focus, None).unwrap();
        let options = ModelOptions::default();
        let model = ImageModel::build(&optics, &options).unwrap();
        let mut renderer =
            LensRenderer::new(&ctx, &[(&model, ALL_CHANNELS)], LensRenderOptions::default())
                .unwrap();
        let mesh = MeshBuffers::new(ctx.gpu(), &scene.mesh, scene.texture.as_ref()).unwrap();
        ctx.submit(|cmd| {
            unsafe { mesh.record_upload(cmd) };
            Ok(())
        })
        .unwrap();
        let frame = renderer.render(&mesh, &pose).unwrap();
        let frame = renderer.render(&mesh, &pose).unwrap();
        let reference = render_reference(
            &optics,
            &[Channel {
                lambda_um: LAMBDA_D,
                mask: ALL_CHANNELS,
            }],
            options.samples,
            &scene,
            &pose,
            &|_| {},
        )
        .unwrap();
        let db = psnr(&frame.pixels, &reference.pixels);
        println!(
            "{lens}: focus {focus:.3} m, {} projections, max angle {:.4}°, GPU {:.1} ms, reference {:.2} s, PSNR {db:.1} dB",
            frame.projections,
            model.max_angle_deg(),
            frame.frame_ms,
            reference.seconds
        );
        let save = |px: &[[f32; 4]], name: &str| {
            let raster = vklens::imaging::Raster {
                width: 240,
                height: 160,
                pixels: vklens::imaging::Pixels::Rgba8(
                    px.iter()
                        .map(|p| {
                            let mut c = p.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8);
                            c[3] = 255;
                            c
                        })
                        .collect(),
                ),
                depth: vklens::imaging::Depth::U8,
            };
            vklens::imaging::io::save(&raster, std::path::Path::new(name)).unwrap();
        };
        save(&frame.pixels, &format!("/tmp/{lens}.gpu.png"));
        save(&reference.pixels, &format!("/tmp/{lens}.ref.png"));
    }
    assert_no_validation_messages(&ctx);
}
