//! The warp from a 360° source (cube map or panorama): faces follow the documented convention,
//! no seam at face edges, every lens sees the direction its inverse model says.

use crate::host::sphere_warp::run_environment;
use crate::imaging::{BitDepth, Pixels, Raster};
use crate::model::{Camera, Fisheye, Intrinsics};
use crate::pass::sphere_warp::{equirect_direction, CubeFace, SphereWarpOptions};
use crate::scene::{Environment, Scene};
use glam::{DVec2, DVec3};

/// A 200° fisheye (what no pinhole source can hold).
fn fisheye_200() -> Camera {
    let k = Intrinsics {
        fx: 180.0,
        fy: 180.0,
        cx: 319.5,
        cy: 319.5,
    };
    let lens = Fisheye::new([0.02, -0.004, 0.0005, 0.0], 0.0, Some(200.0)).expect("lens");
    Camera::fisheye(640, 640, k, lens).expect("camera")
}

/// The GoPro-like standard-model lens of a wide action camera.
fn gopro() -> Camera {
    let k = Intrinsics {
        fx: 880.0 / 2.0,
        fy: 880.0 / 2.0,
        cx: 479.5,
        cy: 269.5,
    };
    Camera::from_coeffs(960, 540, k, &[-0.26, 0.072, 0.0, 0.0, -0.0085]).expect("camera")
}

/// A colour that is a smooth function of direction: 0.5 + 0.5 d, per channel.
fn colour_of(d: DVec3) -> [f32; 4] {
    let d = d.normalize();
    [
        (0.5 + 0.5 * d.x) as f32,
        (0.5 + 0.5 * d.y) as f32,
        (0.5 + 0.5 * d.z) as f32,
        1.0,
    ]
}

fn float_raster(w: u32, h: u32, f: impl Fn(f64, f64) -> [f32; 4]) -> Raster {
    let mut pixels = Vec::with_capacity((w * h) as usize);
    for v in 0..h {
        for u in 0..w {
            pixels.push(f(u as f64, v as f64));
        }
    }
    Raster {
        width: w,
        height: h,
        pixels: Pixels::Rgba32F(pixels),
        bit_depth: BitDepth::F32,
    }
}

/// Six faces, each pixel coloured by the direction it shows under the documented convention.
fn direction_cube(side: u32) -> [Raster; 6] {
    CubeFace::ALL.map(|face| {
        let cam = CubeFace::camera(side).expect("face camera");
        let to_camera = face.rotation().transpose();
        float_raster(side, side, |u, v| {
            let x = cam.intrinsics.to_normalized(DVec2::new(u, v));
            colour_of(to_camera * DVec3::new(x.x, x.y, 1.0))
        })
    })
}

/// The sphere warp of `environment` through `camera`, as a scene of it renders.
fn run_sphere_warp(
    ctx: &crate::host::Context,
    camera: &Camera,
    environment: Environment,
    options: &SphereWarpOptions,
) -> crate::Result<(Raster, Vec<u8>)> {
    run_environment(
        ctx,
        camera,
        &Scene::from_environment("test", environment),
        options,
    )
}

fn options() -> SphereWarpOptions {
    SphereWarpOptions {
        chromatic: None,
        fill: [0.0; 4],
        write_mask: true,
    }
}

/// Largest colour error over valid pixels, against the colour of the direction the f64 model
/// says each pixel sees; also checks the mask is set exactly where the model is valid (away
/// from a one-pixel band at the domain's edge, where f32 and f64 may round apart).
fn worst_error(camera: &Camera, out: &Raster, mask: &[u8]) -> f64 {
    let Pixels::Rgba32F(px) = &out.pixels else {
        panic!("float output expected")
    };
    let mut worst = 0.0_f64;
    let mut valid = 0;
    for v in 0..camera.height {
        for u in 0..camera.width {
            let i = (v * camera.width + u) as usize;
            let ray = camera.unproject(DVec2::new(u as f64, v as f64));
            match ray {
                Some(r) if mask[i] > 127 => {
                    let want = colour_of(r);
                    for c in 0..3 {
                        worst = worst.max((px[i][c] as f64 - want[c] as f64).abs());
                    }
                    valid += 1;
                }
                Some(_) | None => {
                    let edge = [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)]
                        .iter()
                        .any(|(du, dv)| {
                            let q = DVec2::new(u as f64 + du, v as f64 + dv);
                            camera.unproject(q).is_some() != ray.is_some()
                        });
                    assert!(
                        edge || (ray.is_some()) == (mask[i] > 127),
                        "mask at ({u}, {v})"
                    );
                }
            }
        }
    }
    assert!(valid > 0);
    worst
}

#[test]
fn a_cube_of_direction_colours_gives_every_pixel_its_direction() {
    let ctx = crate::testing::validated_context();
    let faces = direction_cube(256);
    for camera in [fisheye_200(), gopro()] {
        let (out, mask) = run_sphere_warp(
            ctx,
            &camera,
            Environment::Cube(Box::new(faces.clone())),
            &options(),
        )
        .expect("warp");
        let worst = worst_error(&camera, &out, &mask);
        println!("{}: worst colour error {worst:.2e}", camera.model_name());
        // Bilinear interpolation of a smooth function over 256² faces: well under 1e-3.
        assert!(worst < 1e-3, "{}: {worst}", camera.model_name());
    }
    crate::testing::assert_no_validation_messages(ctx);
}

#[test]
fn a_panorama_of_direction_colours_gives_every_pixel_its_direction() {
    let ctx = crate::testing::validated_context();
    let (w, h) = (1024, 512);
    let pano = float_raster(w, h, |u, v| colour_of(equirect_direction(u, v, (w, h))));
    for camera in [fisheye_200(), gopro()] {
        let (out, mask) = run_sphere_warp(
            ctx,
            &camera,
            Environment::Panorama(pano.clone()),
            &options(),
        )
        .expect("warp");
        let worst = worst_error(&camera, &out, &mask);
        println!("{}: worst colour error {worst:.2e}", camera.model_name());
        // Coarser than the cube near the poles; the seam at ±180° wraps.
        assert!(worst < 5e-3, "{}: {worst}", camera.model_name());
    }
    crate::testing::assert_no_validation_messages(ctx);
}

#[test]
fn a_constant_cube_gives_a_constant_image_without_seams() {
    let ctx = crate::testing::validated_context();
    let colour = [77u8, 150, 200, 255];
    let face = Raster {
        width: 64,
        height: 64,
        pixels: Pixels::Rgba8(vec![colour; 64 * 64]),
        bit_depth: BitDepth::U8,
    };
    let faces = [0; 6].map(|_| face.clone());
    let camera = fisheye_200();
    let (out, mask) = run_sphere_warp(
        ctx,
        &camera,
        Environment::Cube(Box::new(faces.clone())),
        &options(),
    )
    .expect("warp");
    let Pixels::Rgba8(px) = &out.pixels else {
        panic!("an 8-bit source gives an 8-bit output")
    };
    let valid: Vec<_> = px.iter().zip(&mask).filter(|(_, m)| **m > 127).collect();
    assert!(valid.len() > 300_000, "{} valid pixels", valid.len());
    assert!(valid.iter().all(|(p, _)| **p == colour), "a seam or a hole");
    crate::testing::assert_no_validation_messages(ctx);
}

#[test]
fn chromatic_channels_see_their_own_magnified_directions() {
    let ctx = crate::testing::validated_context();
    let faces = direction_cube(256);
    let camera = fisheye_200();
    let scales = [1.01, 1.0, 0.99];
    let opts = SphereWarpOptions {
        chromatic: Some(scales),
        ..options()
    };
    let (out, mask) = run_sphere_warp(
        ctx,
        &camera,
        Environment::Cube(Box::new(faces.clone())),
        &opts,
    )
    .expect("warp");
    let Pixels::Rgba32F(px) = &out.pixels else {
        panic!()
    };
    let k = camera.intrinsics;
    let mut worst = 0.0_f64;
    for v in (0..camera.height).step_by(7) {
        for u in (0..camera.width).step_by(7) {
            let i = (v * camera.width + u) as usize;
            if mask[i] < 128 {
                continue;
            }
            let y = k.to_normalized(DVec2::new(u as f64, v as f64));
            for (c, s) in [(0usize, scales[0]), (2, scales[2])] {
                let Some(ray) = camera.unproject_normalized(y / s) else {
                    continue;
                };
                let want = colour_of(ray)[c] as f64;
                worst = worst.max((px[i][c] as f64 - want).abs());
            }
        }
    }
    assert!(worst < 1e-3, "{worst}");
    crate::testing::assert_no_validation_messages(ctx);
}

#[test]
fn mismatched_faces_are_refused_naming_the_face() {
    let ctx = crate::testing::validated_context();
    let mut faces = direction_cube(32);
    faces[3] = float_raster(32, 16, |_, _| [0.0; 4]);
    let e = run_sphere_warp(
        ctx,
        &fisheye_200(),
        Environment::Cube(Box::new(faces.clone())),
        &options(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("-y") && e.contains("32×16"), "{e}");
}

#[test]
fn a_360_source_is_a_scene_the_planner_routes_to_the_sphere_warp_alone() {
    use crate::host::plan::execute;
    use crate::plan::{PassKind, PathChoice, Plan, RenderRequest, Route};
    use crate::scene::Pose;
    let ctx = crate::testing::validated_context();
    let camera = fisheye_200();
    let scene = Scene::from_environment(
        "direction cube",
        Environment::Cube(Box::new(direction_cube(64))),
    );
    let warp = PathChoice::Warp {
        method: crate::model::InverseMethod::Newton,
        density: 1.0,
    };
    let mut request = RenderRequest::color(&camera, warp);
    request.outputs.exr = true;
    let max_side = ctx.gpu().max_image_side();
    let plan = Plan::from_request_with_scene(&request, &scene, max_side).unwrap();
    assert_eq!(plan.route, Route::Environment { chromatic: None });
    assert!(plan
        .explain(None, &[])
        .contains("a cube map of six 64×64 faces"));

    // The sphere warp's pipeline and nothing of the mesh paths; colour and mask read back,
    // the same pixels as the warp run on its own.
    let mut frame = None;
    let recorded = execute(ctx, &plan, &scene, [0], &mut |f| {
        frame = Some(f.rendered);
        Ok(())
    })
    .unwrap();
    let kinds: Vec<PassKind> = recorded.pipelines.iter().map(|p| p.kind).collect();
    assert_eq!(kinds, [PassKind::SphereWarp]);
    let frame = frame.unwrap();
    let (colour, mask) = (frame.color.unwrap(), frame.mask.unwrap());
    assert!(worst_error(&camera, &colour, &mask) < 0.02);
    let cube = direction_cube(64);
    let (alone, alone_mask) = run_sphere_warp(
        ctx,
        &camera,
        Environment::Cube(Box::new(cube.clone())),
        &options(),
    )
    .unwrap();
    assert_eq!((colour.pixels, mask), (alone.pixels, alone_mask));

    // What a 360° image cannot give is refused, naming the request's field.
    let refused = |request: &RenderRequest| {
        Plan::from_request_with_scene(request, &scene, max_side)
            .unwrap_err()
            .argument_name()
    };
    let mut ids = request.clone();
    ids.outputs.ids = true;
    assert_eq!(refused(&ids), Some("ids"));
    let vertex = RenderRequest::color(
        &camera,
        PathChoice::Vertex {
            delta: 0.0,
            tessellate: None,
        },
    );
    assert_eq!(refused(&vertex), Some("path"));
    let mut turned = request.clone();
    turned.pose = Pose::look_at(glam::DVec3::ZERO, glam::DVec3::X, glam::DVec3::Y);
    assert_eq!(refused(&turned), Some("pose"));
    crate::testing::assert_no_validation_messages(ctx);
}
