//! Headless helpers for `pass::points`: upload, record, submit, wait and read back.

use crate::gpu::{host_read_barrier, Buffer, Context, Result};
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
    if points.is_empty() {
        return Ok(Vec::new());
    }
    let gpu = ctx.gpu();
    let mut out = Vec::with_capacity(points.len());
    let mut pass = PointsPass::new(gpu, camera, mode, precision)?;
    let (_, out_stride) = precision.strides();
    for chunk in points.chunks(MAX_POINTS) {
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
            (chunk.len() * out_stride) as u64,
            usage,
            MemoryLocation::GpuToCpu,
        )?;
        // SAFETY: no submission using it is pending (`submit` waits on its fence).
        unsafe { pass.bind(&in_buf, &out_buf) };
        ctx.submit(|cmd| {
            // SAFETY: `cmd` is the fresh buffer `submit` is recording, outside any render pass;
            // `in_buf` and `out_buf` (bound above) hold `chunk.len()` points, at most
            // MAX_POINTS, and outlive the submission, which `submit` waits for.
            unsafe {
                pass.record(cmd, chunk.len() as u32);
                // The host reads the outputs after the fence: make the shader writes visible.
                host_read_barrier(gpu, cmd);
            }
            Ok(())
        })?;
        let results: Vec<[f64; 4]> = match precision {
            Precision::F32 => out_buf
                .read_pod::<[f32; 4]>(chunk.len())?
                .iter()
                .map(|r| r.map(f64::from))
                .collect(),
            Precision::F64 => out_buf.read_pod::<[f64; 4]>(chunk.len())?,
        };
        out.extend(results.iter().map(|r| (r[2] > 0.5).then_some([r[0], r[1]])));
    }
    Ok(out)
}
