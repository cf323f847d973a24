//! The Durham radial-correction paper's Sec. II-B's mesh-based warp, the alternative to the compute warp: an n×n grid
//! over the output image, each vertex carrying the exact source coordinate of its output
//! position (the same f64 [`WarpGeometry::source_coordinate`] the reference warp uses,
//! computed once per camera), drawn with a graphics pipeline that samples the source. In
//! between vertices the coordinate is interpolated linearly — the mesh's error, which
//! `vklens bench vertex` measures for n = 8 … 512 beside its time.
//!
//! Cells with a vertex that has no source (outside the lens's valid domain) are not drawn:
//! those pixels keep the clear value (transparent black), never a smeared edge.

use crate::pass::spec;
use ash::vk;
use bytemuck::{Pod, Zeroable};
use glam::DVec2;

use crate::gpu::{
    shaders, Buffer, DescriptorPool, Error, Framebuffer, Gpu, GraphicsDesc, GraphicsPipeline,
    Image, RenderPass, Result, Sampler, SpecConstants, Stage,
};
use crate::model::warp::WarpGeometry;

/// One grid vertex: output pixel, source pixel (OpenCV coordinates).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GridVertex {
    pub output: [f32; 2],
    pub source: [f32; 2],
}

/// `MeshWarpPush` of `glsl/mesh_warp.{vert,frag}`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct MeshWarpPush {
    /// Output w, h; source w, h.
    pub sizes: [f32; 4],
}

/// The n×n grid of a warp (green channel's geometry).
#[derive(Debug, Clone)]
pub struct MeshWarpGrid {
    pub n: u32,
    pub vertices: Vec<GridVertex>,
    pub indices: Vec<u32>,
}

impl MeshWarpGrid {
    /// Vertices at the output image's pixel edges (−0.5 … w − 0.5), so the grid covers it.
    pub fn new(geometry: &WarpGeometry, n: u32) -> Result<Self> {
        if !(1..=4096).contains(&n) {
            return Err(Error::Input(format!("mesh size {n}: expected 1..=4096")));
        }
        let (w, h) = geometry.output_size;
        let row = n + 1;
        let mut vertices = Vec::with_capacity((row * row) as usize);
        let mut valid = Vec::with_capacity((row * row) as usize);
        for j in 0..=n {
            for i in 0..=n {
                let p = DVec2::new(
                    -0.5 + w as f64 * i as f64 / n as f64,
                    -0.5 + h as f64 * j as f64 / n as f64,
                );
                let s = geometry.source_coordinate(p, 1);
                valid.push(s.is_some());
                let s = s.unwrap_or(DVec2::ZERO);
                vertices.push(GridVertex {
                    output: p.as_vec2().to_array(),
                    source: s.as_vec2().to_array(),
                });
            }
        }
        let mut indices = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let a = j * row + i;
                let quad = [a, a + 1, a + row, a + row + 1];
                if quad.iter().all(|&k| valid[k as usize]) {
                    indices.extend_from_slice(&[a, a + 1, a + row, a + 1, a + row + 1, a + row]);
                }
            }
        }
        if indices.is_empty() {
            return Err(Error::Input(
                "no grid cell lies in the lens's valid domain".into(),
            ));
        }
        Ok(MeshWarpGrid {
            n,
            vertices,
            indices,
        })
    }
}

/// What the mesh warp writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshWarpOutput {
    /// The warped image (RGBA8, bilinear).
    Image,
    /// The interpolated source coordinate (RGBA32F: x, y, 0, 1), to measure the mesh's error.
    Coordinates,
}

/// The mesh warp: grid buffers, pipeline and render pass.
pub struct MeshWarpPass {
    gpu: Gpu,
    _pool: DescriptorPool,
    set: vk::DescriptorSet,
    pipeline: GraphicsPipeline,
    pub render_pass: RenderPass,
    sampler: Sampler,
    vertices: Buffer,
    indices: Buffer,
    index_count: u32,
    push: MeshWarpPush,
    pub output_size: (u32, u32),
    pub format: vk::Format,
}

impl MeshWarpPass {
    /// Builds the pass; the output image ends in `final_layout`.
    pub fn new(
        gpu: &Gpu,
        geometry: &WarpGeometry,
        n: u32,
        output: MeshWarpOutput,
        final_layout: vk::ImageLayout,
    ) -> Result<Self> {
        let grid = MeshWarpGrid::new(geometry, n)?;
        let format = match output {
            MeshWarpOutput::Image => vk::Format::R8G8B8A8_UNORM,
            MeshWarpOutput::Coordinates => vk::Format::R32G32B32A32_SFLOAT,
        };
        let render_pass = RenderPass::new(gpu, &[Some(format)], None, final_layout)?;
        let attributes = [
            (0, vk::Format::R32G32_SFLOAT, 0),
            (1, vk::Format::R32G32_SFLOAT, 8),
        ];
        let pipeline = GraphicsPipeline::new(
            gpu,
            GraphicsDesc {
                stages: vec![
                    Stage {
                        stage: vk::ShaderStageFlags::VERTEX,
                        spirv: shaders::MESH_WARP_VERT,
                        constants: SpecConstants::new(),
                    },
                    Stage {
                        stage: vk::ShaderStageFlags::FRAGMENT,
                        spirv: shaders::MESH_WARP_FRAG,
                        constants: SpecConstants::new().bool(
                            spec::WRITE_COORDINATES,
                            output == MeshWarpOutput::Coordinates,
                        ),
                    },
                ],
                bindings: &[vk::DescriptorType::COMBINED_IMAGE_SAMPLER],
                vertex: &[(std::mem::size_of::<GridVertex>() as u32, &attributes)],
                render_pass: &render_pass,
                depth_test: false,
                push_size: std::mem::size_of::<MeshWarpPush>() as u32,
                additive: false,
            },
        )?;
        let pool = DescriptorPool::for_pipeline(gpu, &pipeline, 1)?;
        let set = pool.allocate(&pipeline)?;
        let (ow, oh) = geometry.output_size;
        let (sw, sh) = geometry.source_size;
        Ok(MeshWarpPass {
            gpu: gpu.clone(),
            _pool: pool,
            set,
            pipeline,
            render_pass,
            sampler: Sampler::new(
                gpu,
                vk::Filter::LINEAR,
                vk::SamplerAddressMode::CLAMP_TO_BORDER,
            )?,
            vertices: Buffer::from_pod(
                gpu,
                "mesh_warp.vertices",
                &grid.vertices,
                vk::BufferUsageFlags::VERTEX_BUFFER,
            )?,
            indices: Buffer::from_pod(
                gpu,
                "mesh_warp.indices",
                &grid.indices,
                vk::BufferUsageFlags::INDEX_BUFFER,
            )?,
            index_count: grid.indices.len() as u32,
            push: MeshWarpPush {
                sizes: [ow as f32, oh as f32, sw as f32, sh as f32],
            },
            output_size: (ow, oh),
            format,
        })
    }

    /// Points the pass at the source (a sampled image in `SHADER_READ_ONLY_OPTIMAL`).
    ///
    /// # Safety
    /// This rewrites the pass's descriptor set: no recorded work that uses
    /// this object may be pending on the GPU (wait for its fence first), as Vulkan
    /// requires of descriptor sets and memory the device reads.
    pub unsafe fn bind(&mut self, source: vk::ImageView) {
        // SAFETY: the caller upholds this function's contract (no pending work uses the set);
        // the set is this pass's own, of its pipeline's layout, and the views and buffers are
        // live.
        unsafe {
            crate::gpu::write_sampled_image_descriptor(
                &self.gpu,
                self.set,
                0,
                &self.sampler,
                source,
            )
        };
    }

    /// Records the warp into `framebuffer` (one colour attachment of `output_size` and this
    /// pass's format, made with `self.render_pass`), cleared to transparent black first.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass; the source must be bound and readable;
    /// everything must stay alive until the work completes.
    pub unsafe fn record(&self, cmd: vk::CommandBuffer, framebuffer: &Framebuffer) {
        let d = self.gpu.device();
        let clears = [vk::ClearValue {
            color: vk::ClearColorValue { float32: [0.0; 4] },
        }];
        // SAFETY: the caller upholds `record`'s contract: `cmd` is recording outside a render
        // pass, the source bound and readable, everything alive until the work completes. One
        // clear value for the one attachment and a `MeshWarpPush` for the push range; the grid
        // indices all address `vertices` (built together in `new`); the render pass is ended here.
        unsafe {
            self.pipeline.begin(
                cmd,
                &self.render_pass,
                framebuffer,
                &clears,
                self.set,
                bytemuck::bytes_of(&self.push),
            );
            d.cmd_bind_vertex_buffers(cmd, 0, &[self.vertices.raw], &[0]);
            d.cmd_bind_index_buffer(cmd, self.indices.raw, 0, vk::IndexType::UINT32);
            d.cmd_draw_indexed(cmd, self.index_count, 1, 0, 0, 0);
            d.cmd_end_render_pass(cmd);
        }
    }
}

/// Target image and framebuffer for a mesh warp.
pub struct MeshWarpTarget {
    pub image: Image,
    pub framebuffer: Framebuffer,
}

impl MeshWarpTarget {
    pub fn new(gpu: &Gpu, pass: &MeshWarpPass) -> Result<Self> {
        Self::for_render_pass(gpu, &pass.render_pass, pass.output_size, pass.format)
    }

    /// A target for any single-colour-attachment render pass whose output is RGBA8 or RGBA32F
    /// (the fragment-shader warp and its bench use it too).
    pub fn for_render_pass(
        gpu: &Gpu,
        render_pass: &RenderPass,
        (w, h): (u32, u32),
        format: vk::Format,
    ) -> Result<Self> {
        let image = Image::new_2d(
            gpu,
            "mesh_warp.output",
            format,
            w,
            h,
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC,
        )?;
        let extent = vk::Extent2D {
            width: w,
            height: h,
        };
        // SAFETY: the views are of images just made for this render pass's attachments,
        // `extent` large.
        let framebuffer = unsafe { Framebuffer::new(gpu, render_pass, &[image.view], extent) }?;
        Ok(MeshWarpTarget { image, framebuffer })
    }
}
