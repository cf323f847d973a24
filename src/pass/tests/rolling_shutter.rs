//! The vertex path through a moving rolling shutter, on lavapipe with validation: each vertex's
//! solved pixel, readout time and flow against `FrameMotion::project` in f64; whole frames
//! against a CPU ray cast that casts every pixel's ray from the pose of that pixel's own line
//! (exact by construction); and a still camera against the global shutter, bit for bit.

use ash::vk;
use glam::{DVec2, DVec3};
use gpu_allocator::MemoryLocation;

use crate::gpu::{global_barrier, Access, Buffer};
use crate::host::geometry::{render, render_moving};
use crate::imaging::Rendered;
use crate::model::rolling_shutter::{line_time, FrameMotion, LineRate, Readout, MAX_CONTRACTION};
use crate::model::{Camera, InverseMethod};
use crate::pass::geometry::{Discard, GeometryDesc, GeometryPass, GeometryTargets, Outputs};
use crate::pass::geometry::{Projection, DEFAULT_DELTA};
use crate::scene::raycast::Bvh;
use crate::scene::{builtin, Mesh, Pose};
use crate::testing::{assert_no_validation_messages, upload_mesh, validated_context};

const DATA: Outputs = Outputs {
    color: None,
    ids: true,
    flow: true,
    depth: true,
    range: true,
};

/// A 512² lens with barrel distortion: Alg. 1 bends every edge.
fn camera() -> Camera {
    Camera::from_coeffs(
        512,
        512,
        crate::model::Intrinsics {
            fx: 400.0,
            fy: 400.0,
            cx: 255.5,
            cy: 255.5,
        },
        &[-0.12, 0.03, 0.0, 0.0],
    )
    .unwrap()
}

// A fast pan with a step sideways during the readout: the camera turns about 7° and moves 12 cm
// between the first line and the last, 1.6 m from the grid (the bench's scene).
use crate::host::bands_study::pan;

/// The frame before: the same pan, a readout earlier.
fn previous_pan() -> (Pose, Pose) {
    let start = Pose::look_at(
        DVec3::new(-0.18, 0.0, -1.6),
        DVec3::new(-0.32, 0.0, 0.0),
        DVec3::Y,
    );
    (start, pan().0)
}

fn motion((start, end): (Pose, Pose)) -> FrameMotion {
    FrameMotion::new(start.into(), end.into())
}

fn desc(readout: Option<Readout>, discard: Discard) -> GeometryDesc {
    let mut d = GeometryDesc::new(
        camera(),
        Projection::Lens {
            delta: DEFAULT_DELTA,
        },
        DATA,
    );
    d.readout = readout;
    d.discard = discard;
    d
}

/// The worst errors of the GPU's per-vertex solve (its pixel, readout time and flow, f32)
/// against `FrameMotion::project` in f64.
#[derive(Debug, Default)]
struct Agreement {
    pixel: f64,
    s: f64,
    flow: f64,
    /// Vertices compared: those the f64 solve sees in both frames.
    checked: usize,
}

/// Draws `mesh` through the compute discard with `readout`, this frame's motion `now` and the
/// previous frame's `before`, and compares each vertex's solve with the f64 one.
fn gpu_against_f64(
    ctx: &crate::host::Context,
    mesh: &Mesh,
    readout: Readout,
    now: (Pose, Pose),
    before: (Pose, Pose),
) -> Agreement {
    let gpu = ctx.gpu();
    let cam = camera();
    let n = mesh.vertices.len();
    let mut pass = GeometryPass::new(gpu, desc(Some(readout), Discard::Compute)).unwrap();
    let buffers = upload_mesh(ctx, mesh, None);
    // SAFETY: nothing is pending: `submit` waits on every submission's fence.
    unsafe {
        pass.bind_mesh(&buffers);
        pass.set_moving_frame((&now.0, &now.1), (&before.0, &before.1))
            .unwrap();
    }
    let solve = pass.discard_constants().unwrap()[0].get(crate::pass::spec::READOUT);
    assert_eq!(solve, Some(readout.gpu_id()), "the solve is compiled in");
    let targets = GeometryTargets::new(gpu, &pass).unwrap();
    let [positions, motions] = buffers.discard_results();
    let download = |name, bytes: u64| {
        Buffer::new(
            gpu,
            name,
            bytes,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )
        .unwrap()
    };
    let (ndc_out, motion_out) = (
        download("test.ndc", 8 * n as u64),
        download("test.motion", 16 * n as u64),
    );
    ctx.submit(|cmd| {
        // SAFETY: `cmd` records outside a render pass; the discard's buffers were written
        // by the pass's compute stage and are copied after it; all outlive the wait.
        unsafe {
            pass.record(cmd, &targets, &buffers);
            global_barrier(gpu, cmd, Access::ComputeReadWrite, Access::TransferRead);
            let d = gpu.device();
            let whole = |bytes| [vk::BufferCopy::default().size(bytes)];
            d.cmd_copy_buffer(cmd, positions.raw, ndc_out.raw, &whole(8 * n as u64));
            d.cmd_copy_buffer(cmd, motions.raw, motion_out.raw, &whole(16 * n as u64));
            global_barrier(gpu, cmd, Access::TransferWrite, Access::HostRead);
        }
        Ok(())
    })
    .unwrap();
    let ndc = ndc_out.read_pod::<[f32; 2]>(n).unwrap();
    let moved = motion_out.read_pod::<[f32; 4]>(n).unwrap();
    let (m, m_before) = (motion(now), motion(before));
    let size = DVec2::new(cam.width as f64, cam.height as f64);
    let mut out = Agreement::default();
    for (i, v) in mesh.vertices.iter().enumerate() {
        let x = DVec3::from_array(v.position.map(f64::from));
        let (Some(cpu), Some(cpu_before)) = (
            m.project(&cam, readout, x),
            m_before.project(&cam, readout, x),
        ) else {
            continue;
        };
        let gpu_px = (DVec2::new(ndc[i][0] as f64, ndc[i][1] as f64) + 1.0) * 0.5 * size - 0.5;
        out.pixel = out.pixel.max((gpu_px - cpu.pixel).length());
        out.s = out.s.max((moved[i][3] as f64 - cpu.s).abs());
        let flow = DVec2::new(moved[i][0] as f64, moved[i][1] as f64);
        assert_eq!(moved[i][2], 1.0, "vertex {i}: both frames see it");
        out.flow = out
            .flow
            .max((flow - (cpu.pixel - cpu_before.pixel)).length());
        out.checked += 1;
    }
    println!(
        "{readout}: {} of {n} vertices, GPU (f32) against f64: pixel {:.2e} px, readout time {:.2e}, flow {:.2e} px",
        out.checked, out.pixel, out.s, out.flow
    );
    out
}

/// How many of `mesh`'s vertices the line rate bound lets skip the scan in `now`'s frame (the
/// shaders' test, in f64).
fn bounded_vertices(mesh: &Mesh, readout: Readout, now: (Pose, Pose)) -> usize {
    let rate = LineRate::measure(&camera(), readout).expect("the lens has a line rate");
    let m = motion(now);
    mesh.vertices
        .iter()
        .filter(|v| {
            let x = DVec3::from_array(v.position.map(f64::from));
            m.line_rate_bound(&rate, x)
                .is_some_and(|l| l <= MAX_CONTRACTION)
        })
        .count()
}

#[test]
fn each_vertex_lands_where_the_f64_solve_puts_it() {
    let ctx = validated_context();
    let mesh = builtin::grid(24).mesh;
    for readout in [Readout::TopToBottom, Readout::RightToLeft] {
        let a = gpu_against_f64(ctx, &mesh, readout, pan(), previous_pan());
        assert_eq!(a.checked, mesh.vertices.len(), "the grid is in view");
        // The pan's bound lets every vertex skip the scan: this is the bounded solve.
        assert_eq!(bounded_vertices(&mesh, readout, pan()), mesh.vertices.len());
        // Measured: 7.9e-5 px and 1.3e-4 px of flow (f32 pixels of a 512² image).
        assert!(a.pixel <= 1e-4, "{readout}: pixel off by {} px", a.pixel);
        assert!(a.flow <= 2e-4, "{readout}: flow off by {} px", a.flow);
        // A pixel's worth of readout time is 1/511: the solve finds the same line.
        assert!(a.s <= 1e-5, "{readout}: readout time off by {}", a.s);
    }
    assert_no_validation_messages(ctx);
}

#[test]
fn a_motion_too_fast_for_the_bound_is_scanned_and_lands_where_the_f64_solve_puts_it() {
    // A 35° pan during the readout: the ray to every vertex turns faster than the lens's line
    // rate allows a bound for, so every vertex takes the scan.
    let ctx = validated_context();
    let mesh = builtin::grid(24).mesh;
    let from = DVec3::new(-0.06, 0.0, -1.6);
    let look = |x: f64| Pose::look_at(from, DVec3::new(x, 0.0, 0.0), DVec3::Y);
    let now = (look(-0.5), look(0.5));
    let before = (look(0.5), look(-0.5));
    let readout = Readout::TopToBottom;
    assert_eq!(
        bounded_vertices(&mesh, readout, now),
        0,
        "no vertex is bounded"
    );
    assert_eq!(bounded_vertices(&mesh, readout, before), 0);
    let a = gpu_against_f64(ctx, &mesh, readout, now, before);
    assert!(a.checked > mesh.vertices.len() / 2, "{a:?}");
    assert!(a.pixel <= 1e-3, "pixel off by {} px", a.pixel);
    assert!(a.flow <= 2e-3, "flow off by {} px", a.flow);
    assert!(a.s <= 1e-4, "readout time off by {}", a.s);
    assert_no_validation_messages(ctx);
}

/// The exact frame: every pixel's ray cast from the pose of the line that reads it.
struct Reference {
    ids: Vec<u32>,
    depth: Vec<f64>,
}

fn ray_cast(mesh: &Mesh, cam: &Camera, readout: Readout, m: &FrameMotion) -> Reference {
    let bvh = Bvh::new(mesh);
    let (w, h) = (cam.width, cam.height);
    let mut ids = vec![0; (w * h) as usize];
    let mut depth = vec![f64::INFINITY; (w * h) as usize];
    for v in 0..h {
        for u in 0..w {
            let p = DVec2::new(u as f64, v as f64);
            let Some(x) =
                cam.undistort_normalized(cam.intrinsics.to_normalized(p), InverseMethod::Newton)
            else {
                continue;
            };
            let pose = m.at(line_time(readout, p.x, p.y, w, h));
            let dir = (pose.rotation.transpose() * x.extend(1.0)).normalize();
            if let Some(hit) = bvh.intersect(pose.centre(), dir, 0.0, f64::INFINITY) {
                let k = (v * w + u) as usize;
                let t = &mesh.indices[3 * hit.triangle..3 * hit.triangle + 3];
                ids[k] = mesh.vertices[t[0] as usize].object_id;
                depth[k] = pose.apply(pose.centre() + dir * hit.t).z;
            }
        }
    }
    Reference { ids, depth }
}

/// How a render compares with the reference away from ID edges (pixels whose 3 × 3
/// neighbourhood in the reference holds another ID): IDs that differ, the worst relative
/// depth error, and how many pixels were compared.
fn compare(got: &Rendered, r: &Reference, w: u32, h: u32) -> (usize, f64, usize) {
    let ids = got.ids.as_ref().unwrap();
    let depth = got.depth.as_ref().unwrap();
    let (mut wrong, mut worst, mut compared) = (0, 0f64, 0);
    for v in 1..h - 1 {
        for u in 1..w - 1 {
            let k = (v * w + u) as usize;
            let edge = (-1i32..=1).any(|dv| {
                (-1i32..=1).any(|du| {
                    let j = ((v as i32 + dv) as u32 * w + (u as i32 + du) as u32) as usize;
                    r.ids[j] != r.ids[k]
                })
            });
            if edge {
                continue;
            }
            compared += 1;
            if ids[k] != r.ids[k] {
                wrong += 1;
            } else if r.ids[k] != 0 {
                worst = worst.max((depth[k] as f64 - r.depth[k]).abs() / r.depth[k]);
            }
        }
    }
    (wrong, worst, compared)
}

#[test]
fn a_moving_frame_matches_a_ray_cast_from_each_lines_own_pose() {
    let ctx = validated_context();
    let cam = camera();
    // Fine enough that straight edges between the solved vertices follow the curved images
    // of the grid's lines, and depth interpolated across a triangle its true depth.
    let scene = builtin::grid(16);
    let mesh = crate::scene::tessellate::tessellate(&scene.mesh, &pan().0, &cam, 2.0).unwrap();
    let readout = Readout::TopToBottom;
    let (now, before) = (pan(), previous_pan());
    let reference = ray_cast(&mesh, &cam, readout, &motion(now));
    let still = ray_cast(&mesh, &cam, readout, &motion((now.0, now.0)));
    let moved = reference
        .ids
        .iter()
        .zip(&still.ids)
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        moved > 10_000,
        "the pan moves the picture ({moved} px change ID)"
    );
    // With flow the draw rebuilds each vertex's camera-frame point from its solved time;
    // without, it reads the depth and distance the discard left (glsl/discard.comp).
    let mut runs = vec![(Discard::Compute, true), (Discard::Compute, false)];
    if ctx.gpu().supports_geometry_shader() {
        runs.push((Discard::GeometryShader, true));
    }
    for (discard, flow) in runs {
        let mut d = desc(Some(readout), discard);
        d.outputs.flow = flow;
        let got = render_moving(
            ctx,
            d,
            &mesh,
            None,
            (&now.0, &now.1),
            (&before.0, &before.1),
        )
        .unwrap();
        let (wrong, worst, compared) = compare(&got, &reference, cam.width, cam.height);
        println!(
            "{} (flow {flow}): {compared} px compared, {wrong} IDs differ, depth within {worst:.2e} relative",
            discard.name()
        );
        assert!(compared > 200_000);
        assert_eq!(wrong, 0, "{}: IDs away from edges", discard.name());
        assert!(
            worst <= 1e-5,
            "{}: depth off by {worst:.2e} relative",
            discard.name()
        );
    }
    assert_no_validation_messages(ctx);
}

#[test]
fn a_still_camera_renders_the_global_shutters_frame_bit_for_bit() {
    // A readout with the two poses equal: the pass built for a moving rolling shutter is not
    // needed (the planner builds the global one), and the global pass takes the still frame.
    let ctx = validated_context();
    let mesh = builtin::grid(8).mesh;
    let (pose, _) = pan();
    let global = render(ctx, desc(None, Discard::Compute), &mesh, None, &pose, &pose).unwrap();
    let still = render_moving(
        ctx,
        desc(None, Discard::Compute),
        &mesh,
        None,
        (&pose, &pose),
        (&pose, &pose),
    )
    .unwrap();
    let bits = |r: &Rendered| {
        (
            r.ids.clone().unwrap(),
            r.depth
                .as_ref()
                .unwrap()
                .iter()
                .map(|z| z.to_bits())
                .collect::<Vec<_>>(),
        )
    };
    assert!(global.ids.as_ref().unwrap().iter().any(|&id| id != 0));
    assert_eq!(bits(&global), bits(&still));
    // A global pass refuses a frame that moves rather than drawing it from one pose.
    let (start, end) = pan();
    let refused = render_moving(
        ctx,
        desc(None, Discard::Compute),
        &mesh,
        None,
        (&start, &end),
        (&start, &end),
    );
    assert!(refused.is_err_and(|e| e.to_string().contains("global")));
    assert_no_validation_messages(ctx);
}
