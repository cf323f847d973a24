//! Lambers et al. Sec. 3.2's triangle discard: its bound 1 + δ + D, and its compute form
//! (`glsl/discard.comp`), for devices without geometry shaders and as the default.

use super::mesh::DROPPED_HEADER;
use super::*;

/// Lambers et al. Sec. 3.2's D for a camera: how far past ±1 the undistorted NDC of the distorted
/// image border reaches. The seed undistorts the four corners; this uses the whole border
/// (and the fold boundary where it lies inside the image), as the overscan does, because for
/// mustache and strongly tangential lenses the extremes are not at the corners.
pub fn discard_margin(camera: &Camera) -> f64 {
    let f = Frustum::from_intrinsics(&camera.intrinsics, camera.width, camera.height);
    valid_region_boundary(camera)
        .iter()
        .map(|p| {
            let ndc = DVec2::new(
                2.0 * (p.x - f.left) / (f.right - f.left) - 1.0,
                2.0 * (p.y - f.top) / (f.bottom - f.top) - 1.0,
            );
            ndc.x.abs().max(ndc.y.abs()) - 1.0
        })
        .fold(0.0, f64::max)
}

/// 1 + δ + D for a projection (infinite for a pinhole render).
pub(super) fn discard_bound(projection: &Projection, camera: &Camera) -> Result<f64> {
    match *projection {
        Projection::Lens { delta } => {
            if !(delta.is_finite() && delta >= 0.0) {
                return Err(Error::Input(format!(
                    "δ = {delta}: the discard tolerance must be ≥ 0"
                )));
            }
            if camera.model().is_ray_model() {
                // A ray model's (a fisheye's…) vertices are tested in its own distorted image (alg1.glsl): its
                // domain check, not a frustum, keeps the model from folding; a triangle off
                // the image is clipped by the rasterizer like any other.
                return Ok(f64::INFINITY);
            }
            Ok(1.0 + delta + discard_margin(camera))
        }
        Projection::Pinhole => Ok(f64::INFINITY),
    }
}

/// Alg. 1's per-vertex test (`alg1_ndc_jacobian` and `vkl_vertex_kept` in
/// glsl/include/alg1.glsl) on a camera-frame point, in f64: whether the vertex path keeps a
/// vertex there (a triangle with one vertex it does not keep is dropped whole). For a ray
/// model: nearer than `near` or past the fisheye's vertex limit or outside its domain drops it;
/// for the standard model: at or behind the camera, outside the domain, or undistorted NDC past
/// 1 + `delta` + D.
pub fn vertex_kept(camera: &Camera, delta: f64, near: f64) -> Result<impl Fn(DVec3) -> bool + '_> {
    let bound = discard_bound(&Projection::Lens { delta }, camera)?;
    let limit = camera.fisheye_vertex_limit().map_or(-2.0, f64::cos);
    let f = Frustum::from_intrinsics(&camera.intrinsics, camera.width, camera.height);
    Ok(move |p: DVec3| {
        if !p.is_finite() {
            return false;
        }
        if camera.model().is_ray_model() {
            let r = p.length();
            return r >= near && p.z >= r * limit && camera.project(p).is_some();
        }
        if !(p.z > 0.0) {
            return false;
        }
        let (x, y) = (p.x / p.z, p.y / p.z);
        let ndc = DVec2::new(
            2.0 * (x - f.left) / (f.right - f.left) - 1.0,
            2.0 * (y - f.top) / (f.bottom - f.top) - 1.0,
        );
        ndc.x.abs() <= bound && ndc.y.abs() <= bound && camera.project(p).is_some()
    })
}

/// Whether the compute discard's per-vertex pass needs the valid domain's table: not when
/// every vertex inside `bound` (1 + δ + D on undistorted NDC) lies inside the domain's smallest
/// boundary radius, for then a vertex beyond that radius is dropped by the bound whatever the
/// table would say (`VKL_DOMAIN_TABLE` in `glsl/include/camera_model.glsl`). The margin covers
/// the GPU's f32 rounding of both tests. A fisheye's domain is its own cone, tested without
/// the table.
pub fn discard_needs_domain_table(camera: &Camera, bound: f64) -> bool {
    if camera.model().is_ray_model() {
        // Only an omni lens reads the table (its radial-tangential part's domain).
        return matches!(
            camera.model(),
            crate::model::ModelKind::Omni | crate::model::ModelKind::ThinPrismFisheye
        );
    }
    if !bound.is_finite() {
        return true;
    }
    let f = Frustum::from_intrinsics(&camera.intrinsics, camera.width, camera.height);
    let centre = DVec2::new(f.left + f.right, f.top + f.bottom) / 2.0;
    let half = DVec2::new(f.right - f.left, f.bottom - f.top) / 2.0 * bound;
    let corner = centre.abs() + half;
    !(corner.length() <= camera.domain().min_ideal_radius() * (1.0 - 1e-4))
}

/// The compute discard's pipelines (`glsl/discard.comp`, STAGE 0 per vertex, 1 restore,
/// 2 drop, and for a moving rolling shutter 3, the vertices stage 0 deferred) and the pool of
/// their sets (one per frame in flight, in [`FrameSlot`]).
pub(super) struct DiscardPass {
    pub(super) stages: [ComputePipeline; 3],
    pub(super) deferred: Option<ComputePipeline>,
    pub(super) pool: DescriptorPool,
}

/// `DiscardPush` of `glsl/discard.comp`: how many vertices (stage 0; the other stages read
/// their count from the dropped list).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct DiscardPush {
    pub count: u32,
}

impl DiscardPass {
    /// The three stages' pipelines, specialized like the vertex shader (camera terms,
    /// DISTORT, WRITE_FLOW), and a pool for one set per frame in flight (their uniforms are
    /// the frame's own; the mesh's buffers are written by [`GeometryPass::bind_mesh`]).
    /// `rolling`: frames may move during a rolling shutter's readout, so the per-vertex stage
    /// carries the readout solve (glsl/discard.comp says why the modules differ).
    /// Each stage's module is `model`'s alone (`ModelKind::gpu_id`).
    pub(super) fn new(
        gpu: &Gpu,
        vertex: SpecConstants,
        model: usize,
        rolling: bool,
        frames: usize,
    ) -> Result<Self> {
        use vk::DescriptorType as T;
        let (uniform, storage) = (T::UNIFORM_BUFFER, T::STORAGE_BUFFER);
        let mut bindings = [storage; 11];
        bindings[0] = uniform;
        bindings[1] = uniform;
        let pipeline = |stage: u32| {
            ComputePipeline::new(
                gpu,
                match (stage, rolling) {
                    (0, true) => shaders::DISCARD_COMP_BOUNDED_BY_MODEL[model],
                    (0, false) => shaders::DISCARD_COMP_GLOBAL_BY_MODEL[model],
                    (3, _) => shaders::DISCARD_COMP_BY_MODEL[model],
                    _ => shaders::DISCARD_COMP_INDICES_BY_MODEL[model],
                },
                &bindings,
                std::mem::size_of::<DiscardPush>() as u32,
                vertex.clone().u32(spec::DISCARD_STAGE, stage),
            )
        };
        let stages = [pipeline(0)?, pipeline(1)?, pipeline(2)?];
        let deferred = if rolling { Some(pipeline(3)?) } else { None };
        // One set per frame for all: their set layouts are identically defined, hence
        // compatible.
        let pool = DescriptorPool::for_pipeline(gpu, &stages[0], frames as u32)?;
        Ok(DiscardPass {
            stages,
            deferred,
            pool,
        })
    }

    /// Points `set` (a frame's discard set) at `mesh`'s buffers.
    ///
    /// # Safety
    /// No pending work uses the set ([`GeometryPass::bind_mesh`]'s contract).
    pub(super) unsafe fn bind(gpu: &Gpu, set: vk::DescriptorSet, mesh: &MeshBuffers) {
        let m = &mesh.discard;
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        // SAFETY: the set has the discard pipeline's layout with these storage buffers at
        // these bindings, the buffers are the mesh's own, live; no pending work uses the set
        // (the function's contract).
        unsafe {
            crate::gpu::write_buffer_descriptors(
                gpu,
                set,
                &[
                    (2, storage, &mesh.vertices),
                    (3, storage, &m.positions),
                    (4, storage, &m.motion),
                    (5, storage, &m.dropped),
                    (6, storage, &m.incidence_start),
                    (7, storage, &m.incidence),
                    (8, storage, &mesh.indices),
                    (9, storage, &m.kept),
                    (10, storage, &m.deferred),
                ],
            )
        };
    }

    /// Records the three stages with the barriers around them: the restore of the triangles
    /// the last discard of this mesh dropped, the dropped list emptied, the per-vertex pass,
    /// the drop; after earlier draws' reads of the index and attribute buffers (they are
    /// reused every frame), and before this draw's.
    ///
    /// # Safety
    /// `cmd` is recording outside a render pass on a queue with graphics and compute; `mesh`
    /// is the mesh last bound to `set` ([`Self::bind`]) and stays alive until the work
    /// completes.
    pub(super) unsafe fn record(
        &self,
        gpu: &Gpu,
        cmd: vk::CommandBuffer,
        mesh: &MeshBuffers,
        set: vk::DescriptorSet,
    ) {
        use crate::gpu::global_barrier;
        use Access::{ComputeReadWrite, IndexBuffer, IndirectBuffer, TransferWrite, VertexBuffer};
        let m = &mesh.discard;
        let none = bytemuck::bytes_of(&DiscardPush { count: 0 });
        // A discard stage: compute shaders reading and writing the buffers, in a dispatch
        // whose group count (the dropped list's header) may be read indirectly.
        let discard = [ComputeReadWrite, IndirectBuffer];
        let draw = [IndexBuffer, VertexBuffer];
        // SAFETY: the caller upholds this function's contract; the push constants are the
        // `DiscardPush` the pipelines were built with; the per-vertex dispatch covers exactly
        // the vertices the buffers were sized for in `MeshBuffers::new`, and the indirect ones
        // read `m.dropped`'s header (INDIRECT_BUFFER usage), whose group count stage 0 keeps
        // at ceil(count / 64) ≤ the vertex count / 64 + 1.
        unsafe {
            // Earlier draws of this mesh read `kept` and the attributes; earlier discards wrote
            // them and the dropped list.
            let earlier = [IndexBuffer, VertexBuffer, ComputeReadWrite, IndirectBuffer];
            global_barrier(gpu, cmd, earlier, discard);
            let [per_vertex, restore, drop] = &self.stages;
            restore.record_dispatch_indirect(cmd, set, none, &m.dropped, 0);
            // The restore has read the list (and its dispatch the header) before it is emptied;
            // its writes of `kept` come before the drop's.
            global_barrier(gpu, cmd, discard, [TransferWrite, ComputeReadWrite]);
            let header = bytemuck::cast_slice(&DROPPED_HEADER);
            gpu.device()
                .cmd_update_buffer(cmd, m.dropped.raw, 0, header);
            if self.deferred.is_some() {
                gpu.device()
                    .cmd_update_buffer(cmd, m.deferred.raw, 0, header);
            }
            global_barrier(gpu, cmd, TransferWrite, ComputeReadWrite);
            let push = DiscardPush {
                count: mesh.vertex_count,
            };
            per_vertex.record_dispatch(
                cmd,
                set,
                bytemuck::bytes_of(&push),
                (push.count.div_ceil(64).max(1), 1),
            );
            global_barrier(gpu, cmd, ComputeReadWrite, discard);
            if let Some(deferred) = &self.deferred {
                deferred.record_dispatch_indirect(cmd, set, none, &m.deferred, 0);
                global_barrier(gpu, cmd, ComputeReadWrite, discard);
            }
            drop.record_dispatch_indirect(cmd, set, none, &m.dropped, 0);
            global_barrier(gpu, cmd, ComputeReadWrite, draw);
        }
    }
}
