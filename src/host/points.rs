//! Headless helpers for `pass::points`: upload, record, submit, wait and read back.

use crate::gpu::{host_read_barrier, Buffer, Result};
use crate::host::Context;
use crate::model::Camera;
use crate::pass::points::*;
use ash::vk;
use gpu_allocator::MemoryLocation;

/// Runs the pass on `points` through a headless context and reads the results back
/// (`None` = invalid / outside the valid domain). In f32, inputs are rounded to f32.
pub fn run_points(
    ctx: &Context,
    camera: &Camera,
    mode: PointsMode,
    precision: Precision,
    points: &[[f64; 2]],
) -> Result<Vec<Option<[f64; 2]>>> {
    let raw = run_raw(ctx, camera, mode, precision, points)?;
    Ok(raw
        .iter()
        .map(|r| (r[2] > 0.5).then_some([r[0], r[1]]))
        .collect())
}

/// Projects camera-frame points `(X, Y, Z)` to distorted pixels on the GPU (a fisheye sees
/// behind the image plane up to its domain's edge).
pub fn run_project(
    ctx: &Context,
    camera: &Camera,
    precision: Precision,
    points: &[[f64; 3]],
) -> Result<Vec<Option<[f64; 2]>>> {
    let inputs: Vec<[f64; 2]> = points
        .iter()
        .flat_map(|p| [[p[0], p[1]], [p[2], 0.0]])
        .collect();
    run_points(ctx, camera, PointsMode::Project, precision, &inputs)
}

/// Distorted pixels → unit camera-frame rays on the GPU (`None` outside the valid domain).
pub fn run_unproject(
    ctx: &Context,
    camera: &Camera,
    precision: Precision,
    pixels: &[[f64; 2]],
) -> Result<Vec<Option<[f64; 3]>>> {
    let raw = run_raw(ctx, camera, PointsMode::Unproject, precision, pixels)?;
    Ok(raw
        .iter()
        .map(|r| (r[2] > 0.5).then_some([r[0], r[1], r[3]]))
        .collect())
}

/// The pass over `inputs` (`mode.inputs_per_point()` of them per point): the raw `vec4` per point.
fn run_raw(
    ctx: &Context,
    camera: &Camera,
    mode: PointsMode,
    precision: Precision,
    inputs: &[[f64; 2]],
) -> Result<Vec<[f64; 4]>> {
    let per = mode.inputs_per_point();
    if inputs.is_empty() {
        return Ok(Vec::new());
    }
    let gpu = ctx.gpu();
    let mut out = Vec::with_capacity(inputs.len() / per);
    let mut pass = PointsPass::new(gpu, camera, mode, precision)?;
    let (_, out_stride) = precision.strides();
    for chunk in inputs.chunks(MAX_POINTS * per) {
        let count = chunk.len() / per;
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let in_buf = match precision {
            Precision::F32 => {
                let v: Vec<[f32; 2]> = chunk.iter().map(|p| [p[0] as f32, p[1] as f32]).collect();
                Buffer::from_pod(gpu, "points.in", &v, usage)?
            }
            Precision::F64 => Buffer::from_pod(gpu, "points.in", chunk, usage)?,
        };
        let out_buf = Buffer::new(
            gpu,
            "points.out",
            (count * out_stride) as u64,
            usage,
            MemoryLocation::GpuToCpu,
        )?;
        // SAFETY: no submission using it is pending (`submit` waits on its fence).
        unsafe { pass.bind(&in_buf, &out_buf) };
        ctx.submit(|cmd| {
            // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass;
            // `in_buf` and `out_buf` (bound above) hold `count` points, at most MAX_POINTS,
            // and outlive the submission, which `submit` waits for.
            unsafe {
                pass.record(cmd, count as u32);
                // The host reads the outputs after the fence: make the shader writes visible.
                host_read_barrier(gpu, cmd);
            }
            Ok(())
        })?;
        match precision {
            Precision::F32 => out.extend(
                out_buf
                    .read_pod::<[f32; 4]>(count)?
                    .iter()
                    .map(|r| r.map(f64::from)),
            ),
            Precision::F64 => out.extend(out_buf.read_pod::<[f64; 4]>(count)?),
        }
    }
    Ok(out)
}
