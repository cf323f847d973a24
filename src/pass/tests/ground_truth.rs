//! Labels through the lens against a CPU ray caster (f64, exact by construction): a scene of
//! named boxes on a ground plane around the camera, through a standard lens, a fisheye past
//! 180°, a double sphere and an equirectangular camera. IDs, depth and range per pixel, and the
//! boxes and keypoints computed from them.

use glam::{DVec2, DVec3};

use crate::host::plan::render_request;
use crate::imaging::Rendered;
use crate::labels::{self, ClassRule, Keypoint, LabelRequest, View};
use crate::model::double_sphere::DoubleSphere;
use crate::model::equirect::Equirectangular;
use crate::model::{Camera, Fisheye, Intrinsics, Lens};
use crate::plan::scene_file::OutputSpec;
use crate::plan::{PathChoice, RenderRequest};
use crate::scene::raycast::Bvh;
use crate::scene::{Mesh, Pose, Scene, Vertex};
use crate::testing::{assert_no_validation_messages, reference_camera, validated_context};

/// An axis-aligned box from `lo` to `hi`, each face `n` × `n` quads, outward-facing.
fn cuboid(mesh: &mut Mesh, lo: DVec3, hi: DVec3, n: u32, id: u32) {
    let size = hi - lo;
    let faces = [
        (
            lo,
            DVec3::new(size.x, 0.0, 0.0),
            DVec3::new(0.0, size.y, 0.0),
        ),
        (
            DVec3::new(lo.x, lo.y, hi.z),
            DVec3::new(size.x, 0.0, 0.0),
            DVec3::new(0.0, size.y, 0.0),
        ),
        (
            lo,
            DVec3::new(0.0, 0.0, size.z),
            DVec3::new(0.0, size.y, 0.0),
        ),
        (
            DVec3::new(hi.x, lo.y, lo.z),
            DVec3::new(0.0, 0.0, size.z),
            DVec3::new(0.0, size.y, 0.0),
        ),
        (
            lo,
            DVec3::new(size.x, 0.0, 0.0),
            DVec3::new(0.0, 0.0, size.z),
        ),
        (
            DVec3::new(lo.x, hi.y, lo.z),
            DVec3::new(size.x, 0.0, 0.0),
            DVec3::new(0.0, 0.0, size.z),
        ),
    ];
    for (origin, u, v) in faces {
        quad_grid(mesh, origin, u, v, n, id);
    }
}

fn quad_grid(mesh: &mut Mesh, origin: DVec3, u: DVec3, v: DVec3, n: u32, id: u32) {
    let base = mesh.vertices.len() as u32;
    for b in 0..=n {
        for a in 0..=n {
            let p = origin + u * (a as f64 / n as f64) + v * (b as f64 / n as f64);
            mesh.vertices
                .push(Vertex::new(p, [0.0; 2], [255, 255, 255, 255], id));
        }
    }
    for b in 0..n {
        for a in 0..n {
            let i = base + b * (n + 1) + a;
            mesh.indices
                .extend_from_slice(&[i, i + 1, i + n + 2, i, i + n + 2, i + n + 1]);
        }
    }
}

/// The camera at the origin looking along +z (y down): a ground plane 1.5 m below, boxes in
/// front, beside and behind, so that every lens here sees several, and a fisheye past 180°
/// and the equirectangular camera see some behind the image plane.
fn named_boxes() -> Scene {
    let mut mesh = Mesh::default();
    // The ground: 24 m × 24 m, coarse (the tessellation refines it per camera).
    quad_grid(
        &mut mesh,
        DVec3::new(-12.0, 1.5, -12.0),
        DVec3::new(24.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, 24.0),
        8,
        1,
    );
    let boxes = [
        (DVec3::new(-1.0, -0.2, 4.0), DVec3::new(0.6, 1.5, 5.5)),
        (DVec3::new(1.2, 0.3, 2.5), DVec3::new(2.0, 1.5, 3.2)),
        (DVec3::new(3.0, -0.5, -0.5), DVec3::new(3.8, 1.5, 1.0)),
        (DVec3::new(-3.5, 0.0, -1.5), DVec3::new(-2.5, 1.5, 0.2)),
        (DVec3::new(-0.8, 0.2, -4.0), DVec3::new(0.9, 1.5, -3.2)),
    ];
    for (k, (lo, hi)) in boxes.into_iter().enumerate() {
        cuboid(&mut mesh, lo, hi, 4, 2 + k as u32);
    }
    Scene {
        name: "named boxes".into(),
        mesh,
        texture: None,
        view_from: DVec3::ZERO,
        view_down: DVec3::Y,
        board: None,
        environment: None,
        objects: [
            "ground",
            "car_front",
            "car_right",
            "pedestrian_side",
            "pedestrian_left",
            "car_behind",
        ]
        .map(String::from)
        .to_vec(),
    }
}

fn k(fx: f64, fy: f64, cx: f64, cy: f64) -> Intrinsics {
    Intrinsics { fx, fy, cx, cy }
}

/// One camera of each family the labels must be exact through.
fn cameras() -> Vec<(&'static str, Camera)> {
    let standard = reference_camera("seed_fig2");
    let fisheye = Camera::fisheye(
        400,
        400,
        k(115.0, 115.0, 199.5, 199.5),
        Fisheye::new([0.02, -0.004, 0.0005, 0.0], 0.0, Some(200.0)).expect("lens"),
    )
    .expect("fisheye");
    let double_sphere = Camera::with_lens(
        752,
        480,
        k(349.7, 348.9, 365.8, 249.9),
        Lens::DoubleSphere(DoubleSphere::new(-0.2, 0.57).expect("lens")),
    )
    .expect("double sphere");
    let [fx, fy, cx, cy] = Equirectangular::full_sphere(720, 360);
    let equirect = Camera::with_lens(
        720,
        360,
        k(fx, fy, cx, cy),
        Lens::Equirectangular(Equirectangular),
    )
    .expect("equirectangular");
    vec![
        ("standard", standard),
        ("fisheye 200°", fisheye),
        ("double sphere", double_sphere),
        ("equirectangular", equirect),
    ]
}

/// The ray caster's frame: per pixel the ID (0: nothing) and the hit's camera-frame point.
struct Reference {
    ids: Vec<u32>,
    points: Vec<DVec3>,
    /// The unit normal of the hit triangle (zero: nothing hit).
    normals: Vec<DVec3>,
}

fn ray_cast(scene: &Scene, camera: &Camera) -> Reference {
    let bvh = Bvh::new(&scene.mesh);
    let (w, h) = (camera.width, camera.height);
    let mut out = Reference {
        ids: vec![0; (w * h) as usize],
        points: vec![DVec3::splat(f64::INFINITY); (w * h) as usize],
        normals: vec![DVec3::ZERO; (w * h) as usize],
    };
    for y in 0..h {
        for x in 0..w {
            let Some(ray) = camera.unproject(DVec2::new(x as f64, y as f64)) else {
                continue;
            };
            // The identity pose: camera frame = world frame.
            if let Some(hit) = bvh.intersect(DVec3::ZERO, ray, 1e-9, f64::INFINITY) {
                let i = (y * w + x) as usize;
                let v = scene.mesh.indices[3 * hit.triangle] as usize;
                out.ids[i] = scene.mesh.vertices[v].object_id;
                out.points[i] = ray * hit.t;
                let [a, b, c] = [0, 1, 2].map(|k| {
                    scene.mesh.vertices[scene.mesh.indices[3 * hit.triangle + k] as usize]
                        .position()
                });
                out.normals[i] = (b - a).cross(c - a).normalize();
            }
        }
    }
    out
}

/// Pixels whose 3 × 3 neighbourhood in the reference is one object (more than a pixel from an
/// ID edge, the lens's rim included).
fn interior(reference: &Reference, camera: &Camera) -> Vec<usize> {
    interior_where(reference, camera, |_, _| true)
}

/// [`interior`], and the neighbourhood on one plane (no crease of an object within a pixel).
fn flat_interior(reference: &Reference, camera: &Camera) -> Vec<usize> {
    interior_where(reference, camera, |a, b| {
        reference.normals[a].dot(reference.normals[b]) > 1.0 - 1e-9
    })
}

fn interior_where(
    reference: &Reference,
    camera: &Camera,
    alike: impl Fn(usize, usize) -> bool,
) -> Vec<usize> {
    let (w, h) = (camera.width as i64, camera.height as i64);
    let id = |x: i64, y: i64| {
        (x >= 0 && y >= 0 && x < w && y < h).then(|| reference.ids[(y * w + x) as usize])
    };
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let c = id(x, y);
            let i = (y * w + x) as usize;
            c.is_some_and(|c| c != 0)
                && (-1..=1).all(|dy| {
                    (-1..=1).all(|dx| {
                        id(x + dx, y + dy) == c && alike(i, ((y + dy) * w + x + dx) as usize)
                    })
                })
        })
        .map(|(x, y)| (y * w + x) as usize)
        .collect()
}

fn render(scene: &Scene, camera: &Camera, outputs: OutputSpec) -> Rendered {
    let ctx = validated_context();
    let mut request = RenderRequest::color(
        camera,
        PathChoice::Vertex {
            delta: 0.05,
            tessellate: Some(4.0),
        },
    );
    request.outputs = outputs;
    let r = render_request(ctx, scene, &request, &mut |_| {}).expect("vertex path");
    assert_no_validation_messages(ctx);
    r
}

const DATA: OutputSpec = OutputSpec {
    color: false,
    ids: true,
    flow: false,
    depth: true,
    range: true,
    classes: false,
    boxes: false,
    keypoints: false,
    exr: false,
};

#[test]
fn ids_depth_and_range_on_the_vertex_path_match_the_ray_caster_through_every_family() {
    let scene = named_boxes();
    for (name, camera) in cameras() {
        let r = render(&scene, &camera, DATA);
        let reference = ray_cast(&scene, &camera);
        let inner = interior(&reference, &camera);
        let (ids, depth, range) = (
            r.ids.as_ref().unwrap(),
            r.depth.as_ref().unwrap(),
            r.range.as_ref().unwrap(),
        );
        let (mut wrong, mut holes, mut worst_z, mut worst_r) = (0, 0, 0f64, 0f64);
        let mut behind = 0;
        for &i in &inner {
            if ids[i] == 0 {
                holes += 1;
                continue;
            }
            if ids[i] != reference.ids[i] {
                wrong += 1;
                continue;
            }
            let p = reference.points[i];
            behind += (p.z < 0.0) as usize;
            worst_z = worst_z.max((depth[i] as f64 - p.z).abs() / p.length());
            worst_r = worst_r.max((range[i] as f64 - p.length()).abs() / p.length());
        }
        println!(
            "{name}: {} interior px, {wrong} wrong IDs, {holes} holes, {behind} behind the image plane; z {worst_z:.2e}, range {worst_r:.2e} relative",
            inner.len()
        );
        assert!(inner.len() > 20_000, "{name}: {} px", inner.len());
        assert_eq!(wrong, 0, "{name}: IDs off the ray caster");
        assert!(holes * 200 < inner.len(), "{name}: {holes} holes");
        assert!(worst_z < 1e-5, "{name}: z off by {worst_z:.2e} relative");
        assert!(
            worst_r < 1e-5,
            "{name}: range off by {worst_r:.2e} relative"
        );
    }
}

#[test]
fn classes_boxes_and_keypoints_follow_the_ray_caster() {
    let scene = named_boxes();
    let rules = [
        ClassRule {
            pattern: "car*".into(),
            class: 2,
        },
        ClassRule {
            pattern: "pedestrian*".into(),
            class: 4,
        },
    ];
    let objects = labels::object_labels(&scene, &rules);
    let keypoints = [
        // A box's front top corner, seen; the same box's far bottom corner, hidden by it; a
        // point behind the camera.
        Keypoint {
            name: "front_top".into(),
            xyz: DVec3::new(-1.0, -0.2, 4.0),
        },
        Keypoint {
            name: "hidden".into(),
            xyz: DVec3::new(0.0, 1.0, 5.5),
        },
        Keypoint {
            name: "behind".into(),
            xyz: DVec3::new(0.0, 0.0, -3.0),
        },
    ];
    let budget = 0.05;
    for (name, camera) in cameras().into_iter().take(2) {
        let r = render(&scene, &camera, DATA);
        let reference = ray_cast(&scene, &camera);
        let view = View {
            camera: &camera,
            pose: Pose::IDENTITY,
            moving: None,
        };
        let got = labels::frame_labels(
            &view,
            &scene,
            &r,
            &LabelRequest {
                objects: &objects,
                classes: true,
                boxes: true,
                keypoints: &keypoints,
                max_error_px: budget,
            },
        )
        .unwrap();
        // Classes: the object's class at every pixel, never anything else.
        let classes = got.classes.as_ref().unwrap();
        for (i, &id) in r.ids.as_ref().unwrap().iter().enumerate() {
            let want = objects.iter().find(|o| o.id == id).map_or(0, |o| o.class);
            assert_eq!(classes[i] as u16, want);
        }
        // Boxes: the visible box is the ID image's; the reference's own tight boxes agree to
        // the pixels the rasterizer may give either neighbour at an edge.
        let boxes = got.boxes.as_ref().unwrap();
        let w = camera.width as usize;
        for b in boxes {
            let ids = r.ids.as_ref().unwrap();
            let mine: Vec<usize> = (0..ids.len()).filter(|&i| ids[i] == b.id).collect();
            assert_eq!(b.visible_px as usize, mine.len());
            let xs = mine.iter().map(|i| (i % w) as u32);
            let ys = mine.iter().map(|i| (i / w) as u32);
            assert_eq!(
                b.bbox_visible,
                [
                    xs.clone().min().unwrap(),
                    ys.clone().min().unwrap(),
                    xs.max().unwrap() + 1,
                    ys.max().unwrap() + 1
                ]
            );
            let theirs: Vec<usize> = (0..ids.len())
                .filter(|&i| reference.ids[i] == b.id)
                .collect();
            if !theirs.is_empty() {
                let rx = theirs.iter().map(|i| (i % w) as i64);
                let ry = theirs.iter().map(|i| (i / w) as i64);
                let want = [
                    rx.clone().min().unwrap(),
                    ry.clone().min().unwrap(),
                    rx.max().unwrap() + 1,
                    ry.max().unwrap() + 1,
                ];
                for c in 0..4 {
                    assert!(
                        (b.bbox_visible[c] as i64 - want[c]).abs() <= 1,
                        "{name} {}: visible box {:?}, ray caster {want:?}",
                        b.name,
                        b.bbox_visible
                    );
                }
            }
            // The whole box: dense sampling of every triangle (edges and faces) of the object.
            let full = dense_full_box(&scene, &camera, b.id);
            for c in 0..4 {
                assert!(
                    (b.bbox_full[c] - full[c]).abs() <= budget + 0.05,
                    "{name} {}: bbox_full {:?}, dense {full:?}",
                    b.name,
                    b.bbox_full
                );
            }
            // Corners: the f64 projection itself.
            for (c, corner) in b.corners_3d.iter().enumerate() {
                let (lo, hi) = object_bounds(&scene, b.id);
                let x = DVec3::new(
                    if c & 1 != 0 { hi.x } else { lo.x },
                    if c & 2 != 0 { hi.y } else { lo.y },
                    if c & 4 != 0 { hi.z } else { lo.z },
                );
                match (corner, camera.project(x)) {
                    (Some(p), Some(q)) => {
                        assert!((DVec2::from(*p) - q).length() < 1e-6);
                    }
                    (None, None) => {}
                    other => panic!("{name} {} corner {c}: {other:?}", b.name),
                }
            }
        }
        let k = got.keypoints.as_ref().unwrap();
        println!("{name}: {} boxes; keypoints {k:?}", boxes.len());
        assert!(k[0].visible, "{name}: {:?}", k[0]);
        assert!(k[1].pixel.is_some() && !k[1].visible, "{name}: {:?}", k[1]);
        // Behind the camera: a standard lens does not see it; the 200° fisheye does not
        // either (it is 180° off the axis).
        assert!(k[2].pixel.is_none() && !k[2].visible, "{name}: {:?}", k[2]);
    }
}

fn object_bounds(scene: &Scene, id: u32) -> (DVec3, DVec3) {
    scene
        .mesh
        .vertices
        .iter()
        .filter(|v| v.object_id == id)
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v.position()), hi.max(v.position()))
        })
}

/// The amodal box by brute force: every triangle of the object, its edges sampled densely
/// (4000 points each) and its face on a barycentric grid, projected in f64, clipped to the
/// image, in pixel edges.
fn dense_full_box(scene: &Scene, camera: &Camera, id: u32) -> [f64; 4] {
    let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
    let mut add = |p: DVec3| {
        if let Some(q) = camera.project(p) {
            lo = lo.min(q);
            hi = hi.max(q);
        }
    };
    for t in scene.mesh.indices.chunks_exact(3) {
        let v = [0, 1, 2].map(|k| scene.mesh.vertices[t[k] as usize]);
        if v[0].object_id != id {
            continue;
        }
        let [a, b, c] = v.map(|v| v.position());
        const EDGE: usize = 4000;
        for (p, q) in [(a, b), (b, c), (c, a)] {
            for i in 0..=EDGE {
                add(p + (q - p) * (i as f64 / EDGE as f64));
            }
        }
        const FACE: usize = 40;
        for i in 0..=FACE {
            for j in 0..=FACE - i {
                add(a + (b - a) * (i as f64 / FACE as f64) + (c - a) * (j as f64 / FACE as f64));
            }
        }
    }
    let (w, h) = (camera.width as f64, camera.height as f64);
    [
        (lo.x + 0.5).clamp(0.0, w),
        (lo.y + 0.5).clamp(0.0, h),
        (hi.x + 0.5).clamp(0.0, w),
        (hi.y + 0.5).clamp(0.0, h),
    ]
}

/// How a frame's IDs, z and range compare with the ray caster's: interior pixels (more than
/// a pixel from an ID edge), those with a wrong ID, the worst relative z or range where the
/// pixel and its neighbours see one plane, and the worst relative range anywhere inside (at
/// creases of one object too). Fails on an ID the scene does not have, anywhere.
struct Against {
    interior: usize,
    wrong: usize,
    flat: usize,
    worst_flat: f64,
    worst_crease: f64,
}

fn against(scene: &Scene, camera: &Camera, ids: &[u32], z: &[f32], range: &[f32]) -> Against {
    let reference = ray_cast(scene, camera);
    let inner = interior(&reference, camera);
    let flat = flat_interior(&reference, camera);
    let known = scene.object_ids();
    assert!(
        ids.iter().all(|&id| id == 0 || known.contains(&id)),
        "an ID the scene does not have"
    );
    let right = |i: &&usize| ids[**i] == reference.ids[**i];
    let off = |i: usize| {
        let p = reference.points[i];
        (
            (z[i] as f64 - p.z).abs() / p.length(),
            (range[i] as f64 - p.length()).abs() / p.length(),
        )
    };
    Against {
        interior: inner.len(),
        wrong: inner.iter().filter(|i| !right(i)).count(),
        flat: flat.len(),
        worst_flat: flat
            .iter()
            .filter(right)
            .map(|&i| off(i))
            .fold(0f64, |m, (a, b)| m.max(a).max(b)),
        worst_crease: inner
            .iter()
            .filter(right)
            .map(|&i| off(i).1)
            .fold(0f64, f64::max),
    }
}

#[test]
fn ids_depth_and_range_through_the_cube_route_match_the_ray_caster() {
    let scene = named_boxes();
    let ctx = validated_context();
    for (name, camera) in cameras() {
        let side = crate::model::overscan::cube_face_side(&camera, 1.0);
        let mut request = RenderRequest::color(&camera, PathChoice::Cube { side });
        request.outputs = DATA;
        let r = render_request(ctx, &scene, &request, &mut |_| {}).expect("cube route");
        assert_no_validation_messages(ctx);
        let (ids, depth, range) = (
            r.ids.as_ref().unwrap(),
            r.depth.as_ref().unwrap(),
            r.range.as_ref().unwrap(),
        );
        let c = against(&scene, &camera, ids, depth, range);
        println!(
            "{name} (cube, {side}² faces): {} interior px, {} wrong IDs; on one plane ({} px): z and range {:.2e} relative; at creases range {:.2e}",
            c.interior, c.wrong, c.flat, c.worst_flat, c.worst_crease
        );
        // Nearest samples move an ID edge by up to half a face texel: a pixel next to the
        // one-pixel margin may take the neighbour's ID.
        assert!(c.wrong * 500 < c.interior, "{name}: {} wrong IDs", c.wrong);
        // Where the pixel and its neighbours see one plane, the texels around the ray are on
        // it, and the ray meets their plane.
        assert!(c.worst_flat < 1e-3, "{name}: off by {:.2e}", c.worst_flat);
        // Within a pixel of a crease the nearest texel's depth is carried along its face's
        // axis: off by the depth's change across half a texel (measured 6e-3 to 1.9e-2 on
        // boxes seen at a slant).
        assert!(
            c.worst_crease < 5e-2,
            "{name}: off by {:.2e} at a crease",
            c.worst_crease
        );
    }
}

/// The ray caster's cube faces of `scene` from the origin (`side`² each, +x −x +y −y +z −z):
/// per face its IDs and its z along its own axis (+inf where nothing is hit).
fn ray_cast_faces(scene: &Scene, side: u32) -> ([Vec<u32>; 6], [Vec<f32>; 6]) {
    use crate::pass::sphere_warp::CubeFace;
    let bvh = Bvh::new(&scene.mesh);
    let face_camera = CubeFace::camera(side).unwrap();
    let mut ids: [Vec<u32>; 6] = Default::default();
    let mut z: [Vec<f32>; 6] = Default::default();
    for (k, face) in CubeFace::ALL.iter().enumerate() {
        // A point r of the lens frame is at R r in the face's frame.
        let to_lens = face.rotation().transpose();
        for y in 0..side {
            for x in 0..side {
                let dir = face_camera
                    .intrinsics
                    .to_normalized(DVec2::new(x as f64, y as f64))
                    .extend(1.0);
                let ray = (to_lens * dir).normalize();
                let hit = bvh.intersect(DVec3::ZERO, ray, 1e-9, f64::INFINITY);
                ids[k].push(hit.map_or(0, |h| {
                    scene.mesh.vertices[scene.mesh.indices[3 * h.triangle] as usize].object_id
                }));
                // The face's z: the hit's distance along the face's axis (its camera's z).
                z[k].push(hit.map_or(f32::INFINITY, |h| (h.t / dir.length()) as f32));
            }
        }
    }
    (ids, z)
}

#[test]
fn a_renderers_own_cube_faces_give_ids_and_range_through_the_lens_where_resampled_z_does_not() {
    let scene = named_boxes();
    let ctx = validated_context();
    let (name, camera) = cameras().swap_remove(1);
    let side = 320;
    let (ids, face_z) = ray_cast_faces(&scene, side);
    let (got_ids, got_z, got_range) =
        crate::host::sphere_warp::run_cube_data(ctx, &camera, side, &ids, &face_z).unwrap();
    assert_no_validation_messages(ctx);
    let c = against(&scene, &camera, &got_ids, &got_z, &got_range);
    let reference = ray_cast(&scene, &camera);
    // The common recipe: the nearest face texel's z taken as the lens camera's z.
    let mut recipe = 0f64;
    for i in flat_interior(&reference, &camera) {
        let p = reference.points[i];
        let r = p.normalize();
        let a = r.abs();
        let (k, along) = if a.x >= a.y && a.x >= a.z {
            (if r.x > 0.0 { 0 } else { 1 }, a.x)
        } else if a.y >= a.z {
            (if r.y > 0.0 { 2 } else { 3 }, a.y)
        } else {
            (if r.z > 0.0 { 4 } else { 5 }, a.z)
        };
        let face = crate::pass::sphere_warp::CubeFace::ALL[k];
        let d = face.rotation() * r / along;
        let f = side as f64 / 2.0;
        let (u, v) = (d.x * f + (f - 0.5), d.y * f + (f - 0.5));
        let t = (v.round().clamp(0.0, side as f64 - 1.0) as usize) * side as usize
            + u.round().clamp(0.0, side as f64 - 1.0) as usize;
        recipe = recipe.max((face_z[k][t] as f64 - p.z).abs() / p.length());
    }
    println!(
        "{name}, six {side}² ray-cast faces: {} interior px, {} wrong IDs; z and range {:.2e} relative on planes; resampled face z as the lens's: {recipe:.2e}",
        c.interior, c.wrong, c.worst_flat
    );
    assert!(c.wrong * 500 < c.interior, "{} wrong IDs", c.wrong);
    assert!(
        c.worst_flat < 1e-3,
        "z or range off by {:.2e}",
        c.worst_flat
    );
    assert!(recipe > 1e-3, "resampling z as it is passed ({recipe:.2e})");
}

/// The ray caster's image of `scene` from the origin through `ray_of` (pixel → unit ray, or
/// none): IDs and, per pixel, `depth_of(ray, hit distance)`.
fn ray_cast_image(
    scene: &Scene,
    (w, h): (u32, u32),
    ray_of: impl Fn(DVec2) -> Option<DVec3>,
    depth_of: impl Fn(DVec3, f64) -> f64,
) -> (Vec<u32>, Vec<f32>) {
    let bvh = Bvh::new(&scene.mesh);
    let (mut ids, mut depth) = (Vec::new(), Vec::new());
    for y in 0..h {
        for x in 0..w {
            let hit = ray_of(DVec2::new(x as f64, y as f64))
                .and_then(|r| Some((r, bvh.intersect(DVec3::ZERO, r, 1e-9, f64::INFINITY)?)));
            ids.push(hit.map_or(0, |(_, h)| {
                scene.mesh.vertices[scene.mesh.indices[3 * h.triangle] as usize].object_id
            }));
            depth.push(hit.map_or(f32::INFINITY, |(r, h)| depth_of(r, h.t) as f32));
        }
    }
    (ids, depth)
}

#[test]
fn a_renderers_own_pinhole_image_and_panorama_give_ids_and_range_through_the_lens() {
    use crate::pass::sphere_warp::DataSource;
    let scene = named_boxes();
    let ctx = validated_context();
    let mut all = cameras();
    let fisheye = all.swap_remove(1).1;
    let standard = all.swap_remove(0).1;
    // A pinhole image (z) of the overscanned source camera of the standard lens, and a
    // panorama (range) seen through the fisheye.
    let source = crate::model::overscan::overscan(&standard, 1.0).unwrap();
    let k = source.intrinsics;
    let pinhole = ray_cast_image(
        &scene,
        (source.width, source.height),
        |p| Some(k.to_normalized(p).extend(1.0).normalize()),
        |r, t| r.z * t,
    );
    let (pw, ph) = (720u32, 360u32);
    let pano = ray_cast_image(
        &scene,
        (pw, ph),
        |p| {
            let lon = ((p.x + 0.5) / pw as f64 - 0.5) * std::f64::consts::TAU;
            let lat = ((p.y + 0.5) / ph as f64 - 0.5) * std::f64::consts::PI;
            Some(DVec3::new(
                lat.cos() * lon.sin(),
                lat.sin(),
                lat.cos() * lon.cos(),
            ))
        },
        |_, t| t,
    );
    let runs = [
        (
            "pinhole image → standard",
            &standard,
            DataSource::Pinhole(k),
            (source.width, source.height),
            &pinhole,
        ),
        (
            "panorama → fisheye 200°",
            &fisheye,
            DataSource::Equirect,
            (pw, ph),
            &pano,
        ),
    ];
    for (name, camera, kind, size, (ids, depth)) in runs {
        let (got_ids, got_z, got_range) =
            crate::host::sphere_warp::run_image_data(ctx, camera, kind, size, ids, depth).unwrap();
        assert_no_validation_messages(ctx);
        let c = against(&scene, camera, &got_ids, &got_z, &got_range);
        println!(
            "{name}: {} interior px, {} wrong IDs; z and range {:.2e} relative on planes",
            c.interior, c.wrong, c.worst_flat
        );
        assert!(c.wrong * 500 < c.interior, "{name}: {} wrong IDs", c.wrong);
        assert!(c.worst_flat < 1e-3, "{name}: off by {:.2e}", c.worst_flat);
    }
}
