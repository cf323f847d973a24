//! The geometry path (Lambers et al. Sec. 3.2) on lavapipe, validated, against exact oracles:
//! OpenCV's projectPoints (the shared reference) and a CPU ray cast through the f64 model.

use crate::host::geometry::{render, TargetsReadback};
use crate::imaging::{BitDepth, Pixels, Raster};
use crate::model::{Camera, InverseMethod};
use crate::pass::geometry::{
    ColorFormat, GeometryDesc, Outputs, Projection, Rendered, DEFAULT_DELTA,
};
use crate::plan::scene_file::{Antialias, OutputSpec};
use crate::testing::{assert_no_validation_messages, reference_camera, validated_context};
use glam::{DVec2, DVec3};

/// 8-bit colour alone.
const COLOR: OutputSpec = OutputSpec {
    color: true,
    ids: false,
    flow: false,
    depth: false,
    range: false,
    classes: false,
    boxes: false,
    keypoints: false,
    exr: false,
};
use crate::host::plan::render_request as render_scene;
use crate::plan::{PathChoice, RenderRequest};
use crate::scene::builtin::{self, Board};
use crate::scene::tessellate::tessellate;
use crate::scene::{Mesh, Pose, Vertex};

const DATA: Outputs = Outputs {
    color: None,
    ids: true,
    flow: true,
    depth: true,
    range: true,
};

fn lens(camera: &Camera, delta: f64) -> GeometryDesc {
    GeometryDesc::new(camera.clone(), Projection::Lens { delta }, DATA)
}

/// The exact answer for the built-in grid (1.6 m × 1.2 m at z = 0, `n`² quads, ID 1 + b·n + a)
/// at pixel `p`: (ID, camera-frame hit point), by undistorting the pixel (f64 Newton) and
/// intersecting the ray with the plane. `None` where the pixel has no preimage; ID 0 where
/// the ray misses. Also says whether the hit is within `margin` quads of a quad border, where
/// rasterization may pick either side.
fn grid_oracle(
    camera: &Camera,
    pose: &Pose,
    n: u32,
    p: DVec2,
    margin: f64,
) -> Option<(u32, DVec3, bool)> {
    let x =
        camera.undistort_normalized(camera.intrinsics.to_normalized(p), InverseMethod::Newton)?;
    let dir_cam = x.extend(1.0);
    let r_t = pose.rotation.transpose();
    let origin = pose.centre();
    let dir = r_t * dir_cam;
    if dir.z.abs() < 1e-12 {
        return Some((0, DVec3::ZERO, true));
    }
    let t = -origin.z / dir.z;
    if t <= 0.0 {
        return Some((0, DVec3::ZERO, false));
    }
    let hit = origin + dir * t;
    let (u, v) = (
        (hit.x + 0.8) / 1.6 * n as f64,
        (hit.y + 0.6) / 1.2 * n as f64,
    );
    let border = |w: f64| w.fract().min(1.0 - w.fract()) < margin;
    let near_edge = border(u) || border(v) || u.abs() < margin || v.abs() < margin;
    if u < 0.0 || v < 0.0 || u >= n as f64 || v >= n as f64 {
        return Some((0, dir_cam * t, near_edge));
    }
    Some((1 + v as u32 * n + u as u32, dir_cam * t, near_edge))
}

struct Comparison {
    checked: usize,
    /// A wrong non-zero ID: geometry where it does not belong (a stretched triangle).
    wrong: usize,
    /// ID 0 where the oracle sees the surface (a hole: explicit "nothing", never garbage).
    holes: usize,
}

fn compare_ids(camera: &Camera, pose: &Pose, n: u32, r: &Rendered) -> Comparison {
    let ids = r.ids.as_ref().unwrap();
    let mut c = Comparison {
        checked: 0,
        wrong: 0,
        holes: 0,
    };
    for y in 0..camera.height {
        for x in 0..camera.width {
            let p = DVec2::new(x as f64, y as f64);
            let Some((expected, _, near_edge)) = grid_oracle(camera, pose, n, p, 0.02) else {
                continue;
            };
            if near_edge {
                continue;
            }
            c.checked += 1;
            let got = ids[(y * camera.width + x) as usize];
            if got != expected {
                if got == 0 {
                    c.holes += 1;
                } else {
                    c.wrong += 1;
                }
            }
        }
    }
    c
}

#[test]
fn ids_depth_and_flow_match_a_ray_cast_through_the_f64_model() {
    let ctx = validated_context();
    let camera = reference_camera("seed_fig2");
    let n = 16;
    let scene = builtin::grid(n);
    let pose = Pose::look_at(DVec3::new(0.1, -0.05, -1.0), DVec3::ZERO, DVec3::Y);
    let previous = Pose::look_at(DVec3::new(0.13, -0.04, -1.02), DVec3::ZERO, DVec3::Y);
    let mesh = tessellate(&scene.mesh, &pose, &camera, 4.0).unwrap();
    let r = render(
        ctx,
        lens(&camera, DEFAULT_DELTA),
        &mesh,
        None,
        &pose,
        &previous,
    )
    .unwrap();
    assert_no_validation_messages(ctx);
    let c = compare_ids(&camera, &pose, n, &r);
    assert!(c.checked > 300_000);
    assert_eq!((c.wrong, c.holes), (0, 0), "IDs off the oracle");

    // Depth and flow at every 7th pixel inside the grid, away from quad borders.
    let (depth, flow) = (r.depth.as_ref().unwrap(), r.flow.as_ref().unwrap());
    let (mut worst_depth, mut worst_flow, mut count) = (0f64, 0f64, 0);
    for y in (0..camera.height).step_by(7) {
        for x in (0..camera.width).step_by(7) {
            let p = DVec2::new(x as f64, y as f64);
            let Some((id, hit_cam, _)) = grid_oracle(&camera, &pose, n, p, 0.0) else {
                continue;
            };
            if id == 0 {
                continue;
            }
            let i = (y * camera.width + x) as usize;
            worst_depth = worst_depth.max((depth[i] as f64 - hit_cam.z).abs() / hit_cam.z);
            let world = pose.rotation.transpose() * (hit_cam - pose.translation);
            let before = camera.project(previous.apply(world)).unwrap();
            let f = DVec2::new(flow[i][0] as f64, flow[i][1] as f64);
            worst_flow = worst_flow.max((f - (p - before)).length());
            count += 1;
        }
    }
    assert!(count > 5000);
    // Depth: f32 interpolation; flow: linear interpolation within triangles ≤ 4 px.
    assert!(worst_depth < 1e-5, "depth relative error {worst_depth}");
    assert!(worst_flow < 0.02, "flow error {worst_flow} px");
}

#[test]
fn a_vertex_lands_at_opencv_projectpoints_pixel() {
    // Markers at the shared reference's points (OpenCV's projectPoints output, all 14
    // coefficients on prism_tilt): a 6 px square per point, its vertices placed around the
    // 3D point; the centroid of its image must sit on OpenCV's pixel within rasterization
    // precision.
    let ctx = validated_context();
    let reference = crate::io::reference::load_reference().unwrap();
    for name in ["seed_fig2", "webcam_plumb_bob", "prism_tilt"] {
        let case = reference.cases.iter().find(|c| c.name == name).unwrap();
        let camera = case.camera().unwrap();
        let mut mesh = Mesh::default();
        let mut expected = Vec::new();
        let z = 2.0;
        let half = 3.0 / camera.intrinsics.fx * z; // 6 px squares
        for (k, point) in case.points.iter().enumerate() {
            let [u, v] = point.distorted_pixel;
            let inside = u > 12.0
                && v > 12.0
                && u < camera.width as f64 - 12.0
                && v < camera.height as f64 - 12.0;
            let x = point.undistorted_normalized;
            if !inside || camera.distort_normalized(DVec2::new(x[0], x[1])).is_none() {
                continue;
            }
            let centre = DVec3::new(x[0] * z, x[1] * z, z);
            let id = k as u32 + 1;
            let base = mesh.vertices.len() as u32;
            for (dx, dy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                mesh.vertices.push(Vertex::new(
                    centre + DVec3::new(dx * half, dy * half, 0.0),
                    [0.0; 2],
                    [255; 4],
                    id,
                ));
            }
            mesh.indices
                .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
            expected.push((id, DVec2::new(u, v)));
        }
        // White squares on black, anti-aliased (4× supersampling, 4 jittered passes): the
        // intensity-weighted centroid of each marker locates it to a small fraction of a
        // pixel, unlike the pixel-centre count of an ID image (quantized to ±0.5 px).
        let scene = crate::scene::Scene {
            name: name.into(),
            mesh,
            texture: None,
            view_from: -DVec3::Z,
            view_down: DVec3::Y,
            board: None,
            environment: None,
            objects: Vec::new(),
        };
        let request = RenderRequest {
            camera: camera.clone(),
            pose: Pose::IDENTITY,
            previous_pose: Pose::IDENTITY,
            path: PathChoice::Vertex {
                delta: DEFAULT_DELTA,
                tessellate: None,
            },
            outputs: COLOR,
            antialias: Antialias {
                supersample: 4,
                jitter: 4,
            },
            background: [0.0, 0.0, 0.0, 1.0],
            chromatic: None,
            rolling_shutter: None,
            max_error_px: crate::plan::scene_file::DEFAULT_MAX_ERROR_PX,
        };
        let color = render_scene(ctx, &scene, &request, &mut |_| {})
            .unwrap()
            .color
            .unwrap();
        let mut worst = 0f64;
        for (_, px) in &expected {
            let (mut sum, mut weight) = (DVec2::ZERO, 0.0);
            for y in (px.y as i64 - 8)..=(px.y as i64 + 8) {
                for x in (px.x as i64 - 8)..=(px.x as i64 + 8) {
                    let w = color.rgba_f32((y as u32 * camera.width + x as u32) as usize)[0] as f64;
                    sum += DVec2::new(x as f64, y as f64) * w;
                    weight += w;
                }
            }
            worst = worst.max((sum / weight - *px).length());
        }
        // Alg. 1 moves the corners exactly (f32: ~1e-4 px); what is left is rasterization:
        // edge positions sampled 16 times per pixel (4× supersampling, 4 jittered passes).
        // Measured: ≤ 0.064 px on these three cameras.
        assert!(
            worst < 0.1,
            "{name}: marker centroid {worst} px from projectPoints"
        );
    }
    assert_no_validation_messages(ctx);
}

#[test]
fn barrel_discard_shows_the_border_and_stretches_nothing() {
    // Seed Fig. 1: k1 = -0.11. The camera is close to a large grid, so most of it lies
    // outside the pinhole frustum; the barrel lens sees some of that at its border.
    let ctx = validated_context();
    let camera = reference_camera("seed_fig1_barrel");
    let n = 64;
    let scene = builtin::grid(n);
    let pose = Pose::look_at(DVec3::new(0.0, 0.0, -0.25), DVec3::ZERO, DVec3::Y);
    let mesh = tessellate(&scene.mesh, &pose, &camera, 4.0).unwrap();
    let r = render(ctx, lens(&camera, DEFAULT_DELTA), &mesh, None, &pose, &pose).unwrap();
    let c = compare_ids(&camera, &pose, n, &r);
    assert_eq!((c.wrong, c.holes), (0, 0), "{} checked", c.checked);
    // The middles of the image's sides lie outside the pinhole frustum (their undistorted
    // NDC is beyond ±1) and are drawn. (Its corners are past the lens's fold: no preimage.)
    let ids = r.ids.as_ref().unwrap();
    let f = crate::model::Frustum::from_intrinsics(&camera.intrinsics, 800, 600);
    for (x, y) in [(0, 300), (799, 300), (400, 0), (400, 599)] {
        let p = DVec2::new(x as f64, y as f64);
        let ideal = camera
            .undistort_normalized(camera.intrinsics.to_normalized(p), InverseMethod::Newton)
            .unwrap();
        assert!(ideal.x < f.left || ideal.x > f.right || ideal.y < f.top || ideal.y > f.bottom);
        assert_ne!(ids[y * 800 + x], 0, "({x}, {y}) empty");
    }
    // Even with δ huge, vertices past the lens's fold (where the forward model would bring
    // them back into the image as stretched triangles) are caught by the valid-domain test
    // in the vertex shader: still nothing wrong.
    let r = render(ctx, lens(&camera, 1e6), &mesh, None, &pose, &pose).unwrap();
    let c = compare_ids(&camera, &pose, n, &r);
    assert_eq!(c.wrong, 0);
    assert_no_validation_messages(ctx);
}

#[test]
fn geometry_behind_the_camera_gives_holes_never_garbage() {
    // A grazing view along the grid from 3 cm above it: much of the plane is behind the
    // camera plane; triangles crossing it are dropped whole.
    let ctx = validated_context();
    let camera = reference_camera("seed_fig2");
    let n = 64;
    let scene = builtin::grid(n);
    let eye = DVec3::new(0.0, 0.0, -0.03);
    let pose = Pose::look_at(eye, eye + DVec3::new(0.0, 1.0, 0.6), DVec3::Z);
    let mesh = tessellate(&scene.mesh, &pose, &camera, 4.0).unwrap();
    let r = render(ctx, lens(&camera, DEFAULT_DELTA), &mesh, None, &pose, &pose).unwrap();
    let c = compare_ids(&camera, &pose, n, &r);
    assert!(c.checked > 100_000);
    assert_eq!(
        c.wrong, 0,
        "wrong IDs: geometry drawn where it does not belong"
    );
    assert!(
        (c.holes as f64) < 0.02 * c.checked as f64,
        "{} holes of {} pixels",
        c.holes,
        c.checked
    );
    assert_no_validation_messages(ctx);
}

#[test]
fn vertex_ids_are_never_blended_but_a_bilinear_warp_mixes_them() {
    // Lambers et al. Table 1: post-processing interpolates, which breaks IDs. The vertex path's
    // IDs are all IDs of the scene; a bilinear warp of the pinhole IDs makes values that
    // belong to no object at every ID edge.
    let ctx = validated_context();
    let camera = reference_camera("seed_fig2");
    let board = Board {
        columns: 9,
        rows: 6,
        square: 0.04,
    };
    let scene = builtin::checkerboard(board, 4);
    let pose = scene.default_pose(&camera);
    let valid: std::collections::HashSet<u32> = scene
        .mesh
        .vertices
        .iter()
        .map(|v| v.object_id)
        .chain([0])
        .collect();
    let r = render(
        ctx,
        lens(&camera, DEFAULT_DELTA),
        &scene.mesh,
        None,
        &pose,
        &pose,
    )
    .unwrap();
    let ids = r.ids.unwrap();
    assert!(ids.iter().all(|i| valid.contains(i)));
    assert!(ids.iter().filter(|&&i| i > 0).count() > 100_000);

    // The warp path's IDs (nearest) are scene IDs too; bilinear would not be.
    let request = RenderRequest {
        camera: camera.clone(),
        pose,
        previous_pose: pose,
        path: PathChoice::Warp {
            method: InverseMethod::Newton,
            density: 1.0,
        },
        outputs: OutputSpec {
            ids: true,
            ..OutputSpec::default()
        },
        antialias: Antialias::default(),
        background: [0.0; 4],
        chromatic: None,
        rolling_shutter: None,
        max_error_px: crate::plan::scene_file::DEFAULT_MAX_ERROR_PX,
    };
    let warped = render_scene(ctx, &scene, &request, &mut |_| {}).unwrap();
    assert!(warped.ids.unwrap().iter().all(|i| valid.contains(i)));
    let pinhole = render(
        ctx,
        GeometryDesc::new(
            camera.clone(),
            Projection::Pinhole,
            Outputs {
                color: None,
                ids: true,
                flow: false,
                depth: false,
                range: false,
            },
        ),
        &scene.mesh,
        None,
        &pose,
        &pose,
    )
    .unwrap();
    let as_float = Raster {
        width: camera.width,
        height: camera.height,
        pixels: Pixels::Rgba32F(
            pinhole
                .ids
                .unwrap()
                .iter()
                .map(|&i| [i as f32, 0.0, 0.0, 1.0])
                .collect(),
        ),
        bit_depth: BitDepth::F32,
    };
    let geometry = crate::model::warp::WarpGeometry::distort(camera.clone(), InverseMethod::Newton);
    let (bilinear, _) = crate::host::warp::run_warp(
        ctx,
        crate::pass::warp::WarpDesc {
            geometry,
            coordinates: crate::pass::warp::Coordinates::Analytic,
            sampling: crate::imaging::cpu_warp::Sampling::Bilinear,
            border: crate::Border::Constant,
            format: crate::pass::warp::PixelFormat::Rgba32F,
            fill: [0.0; 4],
            write_mask: false,
        },
        &as_float,
    )
    .unwrap();
    let mixed = (0..bilinear.len())
        .filter(|&i| {
            let v = bilinear.rgba_f32(i)[0];
            v.fract() != 0.0 || !valid.contains(&(v as u32))
        })
        .count();
    assert!(mixed > 1000, "bilinear IDs should mix at edges: {mixed}");
    assert_no_validation_messages(ctx);
}

#[test]
fn vertex_and_warp_paths_agree_on_a_finely_tessellated_scene() {
    let ctx = validated_context();
    let camera = reference_camera("seed_fig2");
    let scene = builtin::grid(16);
    let pose = Pose::look_at(DVec3::new(0.0, 0.0, -1.2), DVec3::ZERO, DVec3::Y);
    let mut request = RenderRequest {
        camera: camera.clone(),
        pose,
        previous_pose: pose,
        path: PathChoice::Vertex {
            delta: DEFAULT_DELTA,
            tessellate: Some(2.0),
        },
        outputs: COLOR,
        antialias: Antialias {
            supersample: 2,
            jitter: 1,
        },
        background: [0.0; 4],
        chromatic: None,
        rolling_shutter: None,
        max_error_px: crate::plan::scene_file::DEFAULT_MAX_ERROR_PX,
    };
    let vertex = render_scene(ctx, &scene, &request, &mut |_| {}).unwrap();
    request.path = PathChoice::Warp {
        method: InverseMethod::Newton,
        density: 1.0,
    };
    let warp = render_scene(ctx, &scene, &request, &mut |_| {}).unwrap();
    let (a, b) = (vertex.color.unwrap(), warp.color.unwrap());
    let (mut sum, mut count, mut big) = (0f64, 0usize, 0usize);
    for i in 0..a.len() {
        let (p, q) = (a.rgba_f32(i), b.rgba_f32(i));
        let d = (0..3).map(|c| (p[c] - q[c]).abs()).fold(0f32, f32::max) as f64;
        sum += d;
        count += 1;
        if d > 0.25 {
            big += 1;
        }
    }
    let mean = sum / count as f64;
    // Both resample the same texture differently (trilinear-free texture sampling vs a
    // bilinear warp of it), so fine texture detail differs slightly; geometry agrees.
    assert!(mean < 0.02, "mean difference {mean}");
    assert!(
        (big as f64) < 0.002 * count as f64,
        "{big} pixels differ by > 25 %"
    );
    assert_no_validation_messages(ctx);
}

#[test]
fn the_warp_paths_ids_and_depth_stay_on_the_gpu_and_equal_the_host_round_trip() {
    // `render --path warp --ids --depth`: a pinhole render of IDs and depth warped nearest on
    // the GPU in one submission equals rendering them, reading them back and warping them
    // from the host, bit for bit.
    use crate::host::warp::run_warp;
    use crate::imaging::cpu_warp::Sampling;
    use crate::model::warp::WarpGeometry;
    use crate::pass::warp::{Coordinates, PixelFormat, WarpDesc};
    let ctx = validated_context();
    let camera = reference_camera("seed_fig1_barrel");
    let scene = builtin::boxes();
    let pose = scene.default_pose(&camera);
    let data = OutputSpec {
        ids: true,
        depth: true,
        ..OutputSpec::default()
    };
    let request = RenderRequest {
        camera: camera.clone(),
        pose,
        previous_pose: pose,
        path: PathChoice::Warp {
            method: InverseMethod::Newton,
            density: 1.0,
        },
        outputs: data,
        antialias: Antialias::default(),
        background: [0.0; 4],
        chromatic: None,
        rolling_shutter: None,
        max_error_px: crate::plan::scene_file::DEFAULT_MAX_ERROR_PX,
    };
    let got = render_scene(ctx, &scene, &request, &mut |_| {}).unwrap();
    // The host round trip: the overscanned pinhole render read back, then warped.
    let ov = crate::overscan(&camera, 1.0).unwrap();
    let pinhole = render_scene(
        ctx,
        &scene,
        &RenderRequest {
            camera: ov.clone(),
            path: PathChoice::Pinhole,
            ..request.clone()
        },
        &mut |_| {},
    )
    .unwrap();
    let geometry = WarpGeometry::distort(camera.clone(), InverseMethod::Newton)
        .with_ideal(ov.intrinsics, (ov.width, ov.height))
        .unwrap();
    let warp = |pixels: Pixels, format: PixelFormat, fill: [f32; 4]| {
        let raster = Raster {
            width: ov.width,
            height: ov.height,
            pixels,
            bit_depth: BitDepth::F32,
        };
        let desc = WarpDesc {
            geometry: geometry.clone(),
            coordinates: Coordinates::Analytic,
            sampling: Sampling::Nearest,
            border: crate::Border::Constant,
            format,
            fill,
            write_mask: false,
        };
        run_warp(ctx, desc, &raster).unwrap().0
    };
    let ids = warp(
        Pixels::R32Uint(pinhole.ids.unwrap()),
        PixelFormat::R32Uint,
        [0.0; 4],
    );
    let Pixels::R32Uint(expected_ids) = ids.pixels else {
        panic!("IDs come back as IDs")
    };
    let depth = warp(
        Pixels::Rgba32F(
            pinhole
                .depth
                .unwrap()
                .iter()
                .map(|&z| [z, z, z, 1.0])
                .collect(),
        ),
        PixelFormat::R32Float,
        [f32::INFINITY; 4],
    );
    let expected_depth: Vec<u32> = (0..depth.len())
        .map(|i| depth.rgba_f32(i)[0].to_bits())
        .collect();
    let got_ids = got.ids.unwrap();
    assert!(got_ids == expected_ids, "IDs differ");
    assert!(got_ids.iter().any(|&i| i != 0), "the boxes are in view");
    let got_depth: Vec<u32> = got.depth.unwrap().iter().map(|z| z.to_bits()).collect();
    assert!(got_depth == expected_depth, "depth differs");
    assert_no_validation_messages(ctx);
}

/// Renders `desc` with the geometry-shader discard and with the compute discard: the same
/// triangles reach the rasterizer. lavapipe takes a pipeline with a geometry stage through
/// another path of its draw module (the same vertex shader either way shows the same
/// differences), whose window coordinates can differ in the last bits: interpolated values
/// differ by a few ulps (depth within 32, about 4e-6 relative, measured 16 on the grazing
/// view; flow within 1e-5 px, measured 7.6e-6 px;
/// colour within a level), and a pixel centre on an edge two triangles share can go to the
/// other one (measured: 2 of 480,000 pixels, in the barrel scene). Returns the IDs.
fn same_with_both_discards(
    ctx: &crate::host::Context,
    desc: GeometryDesc,
    mesh: &Mesh,
    pose: &Pose,
    previous: &Pose,
    what: &str,
) -> Vec<u32> {
    use crate::pass::geometry::Discard;
    let with = |discard| {
        let mut d = desc.clone();
        d.discard = discard;
        render(ctx, d, mesh, None, pose, previous).unwrap()
    };
    let (gs, cs) = (with(Discard::GeometryShader), with(Discard::Compute));
    // The same triangles survive (a dropped one would leave background against an ID over
    // its whole area); a pixel centre on an edge two triangles share may go to either.
    let (a, b) = (
        gs.ids.clone().unwrap_or_default(),
        cs.ids.clone().unwrap_or_default(),
    );
    assert_eq!(a.len(), b.len());
    let differ: Vec<(u32, u32)> = a
        .iter()
        .zip(&b)
        .filter(|(x, y)| x != y)
        .map(|(x, y)| (*x, *y))
        .collect();
    eprintln!(
        "{what}: {} of {} IDs differ (edge ties)",
        differ.len(),
        a.len()
    );
    assert!(
        differ.len() * 10_000 <= a.len(),
        "{what}: {} IDs differ",
        differ.len()
    );
    assert!(
        differ.iter().all(|&(x, y)| x != 0 && y != 0),
        "{what}: background against an ID: {differ:?}"
    );
    let ulps = |a: f32, b: f32| (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs();
    for (name, a, b) in [
        ("depth", &gs.depth, &cs.depth),
        ("range", &gs.range, &cs.range),
    ] {
        let (Some(a), Some(b)) = (a, b) else {
            continue;
        };
        // +inf where nothing was drawn in both, since the IDs agree. Both recompute the point
        // on the pixel's ray from the plane the interpolated positions' derivatives span;
        // seen at a grazing angle, 1 / (n · ray) magnifies the last bits of those
        // derivatives, which the two pipelines round differently: 128 ulps is 7.6e-6
        // relative, inside the 1e-5 the ray caster holds both to.
        let worst = a
            .iter()
            .zip(b)
            .map(|(&x, &y)| ulps(x, y))
            .max()
            .unwrap_or(0);
        eprintln!("{what}: {name} up to {worst} ulps apart");
        assert!(worst <= 128, "{what}: {name} {worst} ulps apart");
    }
    if let (Some(a), Some(b)) = (&gs.flow, &cs.flow) {
        for (x, y) in a.iter().zip(b) {
            for c in 0..2 {
                assert_eq!(
                    x[c].is_nan(),
                    y[c].is_nan(),
                    "{what}: flow validity differs"
                );
                if !x[c].is_nan() {
                    assert!((x[c] - y[c]).abs() <= 1e-5, "{what}: flow {x:?} vs {y:?}");
                }
            }
        }
    }
    if let (Some(a), Some(b)) = (&gs.color, &cs.color) {
        for i in 0..a.len() {
            let (p, q) = (a.rgba_f32(i), b.rgba_f32(i));
            assert!(
                (0..4).all(|c| (p[c] - q[c]).abs() <= 1.0 / 255.0 + 1e-6),
                "{what}: colour at {i}"
            );
        }
    }
    assert_no_validation_messages(ctx);
    gs.ids.unwrap_or_default()
}

#[test]
fn the_compute_discard_renders_what_the_geometry_shader_does() {
    let ctx = validated_context();
    let all = Outputs {
        color: Some(ColorFormat::Rgba8),
        ids: true,
        flow: true,
        depth: true,
        range: true,
    };
    // Flow between two poses through all 14 coefficients.
    let camera = reference_camera("prism_tilt");
    let scene = builtin::grid(16);
    let pose = Pose::look_at(DVec3::new(0.1, -0.05, -1.0), DVec3::ZERO, DVec3::Y);
    let previous = Pose::look_at(DVec3::new(0.13, -0.04, -1.02), DVec3::ZERO, DVec3::Y);
    let mesh = tessellate(&scene.mesh, &pose, &camera, 4.0).unwrap();
    let desc = GeometryDesc::new(
        camera.clone(),
        Projection::Lens {
            delta: DEFAULT_DELTA,
        },
        all,
    );
    same_with_both_discards(ctx, desc, &mesh, &pose, &previous, "flow scene");

    // The barrel discard scene (most of the grid outside the frustum), with δ as the seed
    // sets it and with δ huge (only the valid domain drops triangles).
    let camera = reference_camera("seed_fig1_barrel");
    let scene = builtin::grid(64);
    let pose = Pose::look_at(DVec3::new(0.0, 0.0, -0.25), DVec3::ZERO, DVec3::Y);
    let mesh = tessellate(&scene.mesh, &pose, &camera, 4.0).unwrap();
    for delta in [DEFAULT_DELTA, 1e6] {
        let ids = same_with_both_discards(ctx, lens(&camera, delta), &mesh, &pose, &pose, "barrel");
        assert!(
            ids.iter().filter(|&&i| i == 0).count() > 1000,
            "the discard dropped nothing"
        );
    }

    // The grazing view with geometry behind the camera.
    let camera = reference_camera("seed_fig2");
    let eye = DVec3::new(0.0, 0.0, -0.03);
    let pose = Pose::look_at(eye, eye + DVec3::new(0.0, 1.0, 0.6), DVec3::Z);
    let mesh = tessellate(&scene.mesh, &pose, &camera, 4.0).unwrap();
    same_with_both_discards(
        ctx,
        lens(&camera, DEFAULT_DELTA),
        &mesh,
        &pose,
        &pose,
        "grazing",
    );
}

#[test]
fn a_device_without_geometry_shaders_renders_the_vertex_path_through_the_compute_discard() {
    use crate::host::{Context, ContextOptions};
    use crate::pass::geometry::Discard;
    let ctx = Context::new(ContextOptions {
        validation: true,
        device: std::env::var("VKLENS_DEVICE")
            .ok()
            .filter(|s| !s.is_empty()),
        geometry_shader: false,
        geometry_shader_discard: false,
        pipeline_cache: None,
    })
    .unwrap();
    assert!(!ctx.gpu().supports_geometry_shader());
    // The barrel scene: every ID on the f64 oracle, nothing stretched.
    let camera = reference_camera("seed_fig1_barrel");
    let n = 64;
    let scene = builtin::grid(n);
    let pose = Pose::look_at(DVec3::new(0.0, 0.0, -0.25), DVec3::ZERO, DVec3::Y);
    let mesh = tessellate(&scene.mesh, &pose, &camera, 4.0).unwrap();
    let mut desc = lens(&camera, DEFAULT_DELTA);
    desc.discard = Discard::Auto;
    let r = render(&ctx, desc.clone(), &mesh, None, &pose, &pose).unwrap();
    let c = compare_ids(&camera, &pose, n, &r);
    assert!(c.checked > 100_000);
    assert_eq!((c.wrong, c.holes), (0, 0));
    // The geometry shader, asked for on such a device, is refused up front.
    desc.discard = Discard::GeometryShader;
    let Err(e) = render(&ctx, desc, &mesh, None, &pose, &pose) else {
        panic!("the geometry shader was not refused");
    };
    assert!(e.to_string().contains("geometryShader"), "{e}");
    assert_no_validation_messages(&ctx);
}

/// The compute discard keeps per-mesh state between draws: the triangles it made degenerate
/// stay so in the mesh's draw index buffer until the next draw of that mesh restores them. A
/// run of frames that drop different triangles (and none), and two passes of different lenses
/// sharing one mesh inside one command buffer, each render what a fresh mesh renders.
#[test]
fn the_compute_discard_restores_what_an_earlier_frame_dropped() {
    use crate::pass::geometry::{Discard, GeometryPass, GeometryTargets, MeshBuffers};
    let ctx = validated_context();
    let gpu = ctx.gpu();
    let barrel = reference_camera("seed_fig1_barrel");
    let scene = builtin::grid(48);
    let near = Pose::look_at(DVec3::new(0.0, 0.0, -0.25), DVec3::ZERO, DVec3::Y);
    let far = Pose::look_at(DVec3::new(0.0, 0.0, -3.0), DVec3::ZERO, DVec3::Y);
    let aside = Pose::look_at(
        DVec3::new(0.3, 0.1, -0.3),
        DVec3::new(0.2, 0.0, 0.0),
        DVec3::Y,
    );
    let mesh = &scene.mesh;
    let desc = |camera: &Camera| {
        let mut d = lens(camera, DEFAULT_DELTA);
        d.discard = Discard::Compute;
        d
    };
    let fresh = |camera: &Camera, pose: &Pose| {
        render(ctx, desc(camera), mesh, None, pose, pose)
            .unwrap()
            .ids
            .unwrap()
    };
    let dropped = |ids: &[u32]| ids.iter().filter(|&&i| i == 0).count();

    // One pass, one mesh, frame after frame.
    let buffers = MeshBuffers::new(gpu, mesh, None).unwrap();
    let mut pass = GeometryPass::new(gpu, desc(&barrel)).unwrap();
    let targets = GeometryTargets::new(gpu, &pass).unwrap();
    let readback = TargetsReadback::new(gpu, &targets).unwrap();
    unsafe { pass.bind_mesh(&buffers) };
    ctx.submit(|cmd| {
        unsafe { buffers.record_upload(cmd) };
        Ok(())
    })
    .unwrap();
    let frame = |pose: &Pose| {
        unsafe { pass.set_frame(pose, pose) }.unwrap();
        ctx.submit(|cmd| unsafe {
            pass.record(cmd, &targets, &buffers);
            readback.record(
                gpu,
                cmd,
                &targets,
                ash::vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            )
        })
        .unwrap();
        readback.read().unwrap().ids.unwrap()
    };
    let expected_near = fresh(&barrel, &near);
    let expected_far = fresh(&barrel, &far);
    assert!(
        dropped(&expected_near) > 1000,
        "the near view drops triangles"
    );
    for (what, pose, expected) in [
        ("near", &near, &expected_near),
        ("far", &far, &expected_far),
        ("near again", &near, &expected_near),
        ("aside", &aside, &fresh(&barrel, &aside)),
        ("far again", &far, &expected_far),
    ] {
        let got = frame(pose);
        let differ = got.iter().zip(expected).filter(|(a, b)| a != b).count();
        assert_eq!(differ, 0, "{what}: {differ} IDs differ from a fresh render");
    }

    // Two lenses, one mesh, one command buffer: the second draw restores what the first
    // dropped before dropping its own.
    let mild = Camera::new(
        barrel.width,
        barrel.height,
        barrel.intrinsics,
        crate::model::OpenCvDistortion {
            k1: -0.05,
            ..Default::default()
        },
    )
    .unwrap();
    let mut second = GeometryPass::new(gpu, desc(&mild)).unwrap();
    let second_targets = GeometryTargets::new(gpu, &second).unwrap();
    let second_readback = TargetsReadback::new(gpu, &second_targets).unwrap();
    unsafe {
        second.bind_mesh(&buffers);
        pass.set_frame(&near, &near).unwrap();
        second.set_frame(&aside, &aside).unwrap();
    }
    ctx.submit(|cmd| unsafe {
        pass.record(cmd, &targets, &buffers);
        readback.record(
            gpu,
            cmd,
            &targets,
            ash::vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        )?;
        second.record(cmd, &second_targets, &buffers);
        second_readback.record(
            gpu,
            cmd,
            &second_targets,
            ash::vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        )
    })
    .unwrap();
    let (first_ids, second_ids) = (
        readback.read().unwrap().ids.unwrap(),
        second_readback.read().unwrap().ids.unwrap(),
    );
    assert!(first_ids == expected_near, "the first lens");
    assert!(second_ids == fresh(&mild, &aside), "the second lens");
    assert_no_validation_messages(ctx);
}
