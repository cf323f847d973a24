//! A mesh on the GPU for the geometry path: its vertex layout, its texture, and what the
//! compute discard keeps per mesh (the triangles of each vertex, the dropped list).

use super::*;

/// The vertex layout of [`Vertex`].
pub(super) const VERTEX_ATTRIBUTES: [Attribute; 4] = [
    (0, vk::Format::R32G32B32_SFLOAT, 0),
    (1, vk::Format::R32G32_SFLOAT, 12),
    (2, vk::Format::R8G8B8A8_UNORM, 20),
    (3, vk::Format::R32_UINT, 24),
];

/// Binding 0: the mesh's vertices.
pub(super) const MESH_BINDING: VertexBinding =
    (std::mem::size_of::<Vertex>() as u32, &VERTEX_ATTRIBUTES);

/// Binding 1 with the compute discard: the distorted NDC (`in_distorted_ndc`).
pub(super) const POSITION_BINDING: VertexBinding = (8, &[(4, vk::Format::R32G32_SFLOAT, 0)]);

/// Binding 2 with the compute discard and flow: the motion (`in_motion`).
pub(super) const MOTION_BINDING: VertexBinding = (16, &[(5, vk::Format::R32G32B32A32_SFLOAT, 0)]);

/// The draw's vertex bindings: the mesh's vertices, then (`pulled`: the compute discard ran)
/// its positions and, with `flow`, its motion. The pipeline is built with these and the draw
/// binds one buffer for each.
/// A moving rolling shutter reads the motion binding for its solved readout times (its `w`)
/// with flow or without.
pub(super) fn vertex_bindings(pulled: bool, flow: bool) -> &'static [VertexBinding<'static>] {
    match (pulled, flow) {
        (true, true) => &[MESH_BINDING, POSITION_BINDING, MOTION_BINDING],
        (true, false) => &[MESH_BINDING, POSITION_BINDING],
        _ => &[MESH_BINDING],
    }
}

/// An RGBA8 texture for sampling, staged for upload ([`Texture::record_upload`]).
pub struct Texture {
    pub(super) gpu: Gpu,
    pub image: Image,
    pub(super) staging: Buffer,
}

impl Texture {
    /// Stages `raster` (any pixel type, converted to 8-bit RGBA).
    pub fn new(gpu: &Gpu, raster: &Raster) -> Result<Self> {
        raster.check()?;
        let bytes: Vec<u8> = match &raster.pixels {
            Pixels::Rgba8(p) => p.iter().flatten().copied().collect(),
            _ => (0..raster.len())
                .flat_map(|i| {
                    raster
                        .rgba_f32(i)
                        .map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
                })
                .collect(),
        };
        Ok(Texture {
            image: Image::new_2d(
                gpu,
                "texture",
                vk::Format::R8G8B8A8_UNORM,
                raster.width,
                raster.height,
                vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
            )?,
            staging: Buffer::from_pod(
                gpu,
                "texture.upload",
                &bytes,
                vk::BufferUsageFlags::TRANSFER_SRC,
            )?,
            gpu: gpu.clone(),
        })
    }

    /// Records the upload; afterwards the image is in `SHADER_READ_ONLY_OPTIMAL`, visible to
    /// fragment shaders. Record it once, before the first use.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass.
    pub unsafe fn record_upload(&self, cmd: vk::CommandBuffer) {
        // SAFETY: the caller upholds `record_upload`'s contract: `cmd` is recording outside a
        // render pass. The image has TRANSFER_DST and SAMPLED usage and UNDEFINED is a valid
        // old layout as it is overwritten whole; `staging` holds it as tightly packed RGBA8,
        // which relies on an RGBA8 raster having width × height pixels (`new` does not check).
        unsafe {
            crate::gpu::record_upload(
                &self.gpu,
                cmd,
                &self.staging,
                &self.image,
                Access::FragmentSampled,
            )
        };
    }
}

/// A mesh on the GPU: vertex and index buffers and its texture (white if it has none), and
/// what the compute discard keeps per mesh (`DiscardBuffers`).
pub struct MeshBuffers {
    pub(super) discard: DiscardBuffers,
    pub vertices: Buffer,
    pub indices: Buffer,
    pub index_count: u32,
    pub vertex_count: u32,
    pub texture: Texture,
}

/// The compute discard's per-mesh state (`glsl/discard.comp`; it reads the positions from the
/// mesh's own vertex buffer).
pub(super) struct DiscardBuffers {
    /// Per vertex, read by the draw as vertex attributes: the distorted NDC (two floats), and
    /// the flow with its validity (four).
    pub(super) positions: Buffer,
    pub(super) motion: Buffer,
    /// The vertices the last discard dropped, behind the indirect dispatch that visits them
    /// (`Dropped` in the shader: groups, 1, 1, count, then the list).
    pub(super) dropped: Buffer,
    /// The vertices a moving rolling shutter's per-vertex stage left to stage 3, as `dropped`
    /// (`Deferred` in the shader).
    pub(super) deferred: Buffer,
    /// Which triangles each vertex belongs to (compressed rows: vertex v's triangles are
    /// `incidence[incidence_start[v] .. incidence_start[v + 1]]`).
    pub(super) incidence_start: Buffer,
    pub(super) incidence: Buffer,
    /// The index buffer the draw uses: the mesh's, but for the triangles of dropped vertices,
    /// which are degenerate.
    pub(super) kept: Buffer,
}

/// The dropped-vertex buffer's header (`Dropped` in `glsl/discard.comp`): no workgroups,
/// y = z = 1, no vertices.
pub(super) const DROPPED_HEADER: [u32; 4] = [0, 1, 1, 0];

/// The triangles each vertex belongs to, as compressed rows: (start per vertex and one past
/// the last, triangle ids).
pub(super) fn incidence(indices: &[u32], vertex_count: usize) -> (Vec<u32>, Vec<u32>) {
    let mut start = vec![0u32; vertex_count + 1];
    for &i in indices {
        start[i as usize + 1] += 1;
    }
    for v in 0..vertex_count {
        start[v + 1] += start[v];
    }
    let mut next = start.clone();
    let mut triangles = vec![0u32; indices.len()];
    for (k, &i) in indices.iter().enumerate() {
        let slot = &mut next[i as usize];
        triangles[*slot as usize] = (k / 3) as u32;
        *slot += 1;
    }
    (start, triangles)
}

impl MeshBuffers {
    /// Uploads a (validated) mesh; the texture is staged for [`Self::record_upload`].
    pub fn new(gpu: &Gpu, mesh: &Mesh, texture: Option<&Raster>) -> Result<Self> {
        mesh.validate("mesh")
            .map_err(|e| Error::Input(e.to_string()))?;
        let white = Raster {
            width: 1,
            height: 1,
            pixels: Pixels::Rgba8(vec![[255; 4]]),
            bit_depth: BitDepth::U8,
        };
        use vk::BufferUsageFlags as U;
        let n = mesh.vertices.len();
        let (start, triangles) = incidence(&mesh.indices, n);
        let mut dropped = DROPPED_HEADER.to_vec();
        dropped.resize(DROPPED_HEADER.len() + n, 0);
        let storage = U::STORAGE_BUFFER;
        let per_vertex = |name, bytes: u64| {
            Buffer::new(
                gpu,
                name,
                n as u64 * bytes,
                U::VERTEX_BUFFER | storage | U::TRANSFER_SRC,
                MemoryLocation::GpuOnly,
            )
        };
        let discard = DiscardBuffers {
            positions: per_vertex("mesh.discard.positions", 8)?,
            motion: per_vertex("mesh.discard.motion", 16)?,
            dropped: Buffer::from_pod(
                gpu,
                "mesh.discard.dropped",
                &dropped,
                storage | U::INDIRECT_BUFFER | U::TRANSFER_DST,
            )?,
            deferred: Buffer::from_pod(
                gpu,
                "mesh.discard.deferred",
                &dropped,
                storage | U::INDIRECT_BUFFER | U::TRANSFER_DST,
            )?,
            incidence_start: Buffer::from_pod(
                gpu,
                "mesh.discard.incidence_start",
                &start,
                storage,
            )?,
            incidence: Buffer::from_pod(gpu, "mesh.discard.incidence", &triangles, storage)?,
            // Starts as the mesh's own indices: the first discard has nothing to restore.
            kept: Buffer::from_pod(
                gpu,
                "mesh.discard.kept",
                &mesh.indices,
                U::INDEX_BUFFER | storage,
            )?,
        };
        Ok(MeshBuffers {
            discard,
            // The discard's per-vertex pass reads the positions too.
            vertices: Buffer::from_pod(
                gpu,
                "mesh.vertices",
                &mesh.vertices,
                U::VERTEX_BUFFER | storage,
            )?,
            indices: Buffer::from_pod(
                gpu,
                "mesh.indices",
                &mesh.indices,
                U::INDEX_BUFFER | storage,
            )?,
            index_count: mesh.indices.len() as u32,
            vertex_count: n as u32,
            texture: Texture::new(gpu, texture.unwrap_or(&white))?,
        })
    }

    /// The compute discard's per-vertex results of the last draw: the distorted NDC (two
    /// floats), and the motion (flow, its validity, and a moving rolling shutter's solved
    /// readout time; four floats). Transfer sources, for tests to read back.
    #[cfg(test)]
    pub(crate) fn discard_results(&self) -> [&Buffer; 2] {
        [&self.discard.positions, &self.discard.motion]
    }

    /// Records the texture upload (see [`Texture::record_upload`]).
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass.
    pub unsafe fn record_upload(&self, cmd: vk::CommandBuffer) {
        // SAFETY: the caller upholds this function's contract, which is `Texture::record_upload`'s.
        unsafe { self.texture.record_upload(cmd) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn incidence_lists_each_vertexs_triangles() {
        // Two triangles sharing an edge, and a degenerate one repeating a vertex.
        let (start, triangles) = incidence(&[0, 1, 2, 2, 1, 3, 3, 3, 0], 5);
        let of = |v: usize| &triangles[start[v] as usize..start[v + 1] as usize];
        assert_eq!(of(0), [0, 2]);
        assert_eq!(of(1), [0, 1]);
        assert_eq!(of(2), [0, 1]);
        assert_eq!(of(3), [1, 2, 2]);
        assert_eq!(of(4), [] as [u32; 0]);
    }
}
