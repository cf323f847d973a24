//! The map warp as a fragment shader over one full-screen triangle (`glsl/warp_raster.*`):
//! the same per-pixel work as [`crate::pass::warp::WarpPass`] in map mode — each channel's
//! precomputed coordinate, one bilinear sample per channel, the fill value where there is no
//! source — but the output is a colour attachment the rasterizer walks instead of a storage
//! image a compute dispatch writes. What that buys depends on the driver: on lavapipe a
//! compute invocation carries a fixed cost that dominates a map warp, and its rasterizer
//! shades pixels in blocks without it; `vklens bench warp` measures both side by side.
//!
//! It reads the maps a [`WarpPass`] built (record that pass's `record_prepare` first) and
//! writes no validity mask (a mask is a second attachment away, if a caller needs one).

use crate::pass::spec;
use ash::vk;

use super::warp::{PixelFormat, WarpPass, WarpPush};
use crate::gpu::{
    shaders, write_storage_image_descriptors, DescriptorPool, Error, Framebuffer, Gpu,
    GraphicsDesc, GraphicsPipeline, RenderPass, Result, SpecConstants, Stage,
};
use crate::imaging::cpu_warp::Sampling;

/// The fragment-shader map warp, built for one [`WarpPass`]'s maps, format and sampling.
pub struct RasterWarpPass {
    gpu: Gpu,
    pipeline: GraphicsPipeline,
    pub render_pass: RenderPass,
    _pool: DescriptorPool,
    set: vk::DescriptorSet,
    push: WarpPush,
    pub output_size: (u32, u32),
    pub format: vk::Format,
}

impl RasterWarpPass {
    /// Builds the pass for `warp`'s geometry and maps; the output ends in `final_layout`.
    /// `warp` must use precomputed maps, colour data (not object IDs).
    pub fn new(gpu: &Gpu, warp: &WarpPass, final_layout: vk::ImageLayout) -> Result<Self> {
        let desc = warp.desc();
        if !desc.coordinates.uses_map() {
            return Err(Error::Input(
                "the fragment-shader warp reads precomputed maps: build the warp with a map".into(),
            ));
        }
        let (format, spirv) = match desc.format {
            PixelFormat::Rgba8 => (vk::Format::R8G8B8A8_UNORM, shaders::WARP_RASTER_FRAG_RGBA8),
            PixelFormat::Rgba32F => (vk::Format::R32G32B32A32_SFLOAT, shaders::WARP_RASTER_FRAG),
            PixelFormat::R32Uint | PixelFormat::R32Float => {
                return Err(Error::Input(
                    "the fragment-shader warp is for colour: IDs and depth take the compute warp"
                        .into(),
                ))
            }
        };
        let render_pass = RenderPass::new(gpu, &[Some(format)], None, final_layout)?;
        let pipeline = GraphicsPipeline::new(
            gpu,
            GraphicsDesc {
                stages: vec![
                    Stage {
                        stage: vk::ShaderStageFlags::VERTEX,
                        spirv: shaders::WARP_RASTER_VERT,
                        constants: SpecConstants::new(),
                    },
                    Stage {
                        stage: vk::ShaderStageFlags::FRAGMENT,
                        spirv,
                        constants: SpecConstants::new()
                            .bool(spec::CHROMATIC, desc.geometry.is_chromatic())
                            .bool(spec::NEAREST, desc.sampling == Sampling::Nearest)
                            .bool(spec::BICUBIC, desc.sampling == Sampling::Bicubic)
                            .u32(spec::BORDER, desc.border.gpu_id()),
                    },
                ],
                bindings: &[vk::DescriptorType::STORAGE_IMAGE; 4],
                vertex: &[],
                render_pass: &render_pass,
                depth_test: false,
                push_size: std::mem::size_of::<WarpPush>() as u32,
                additive: false,
            },
        )?;
        let pool = DescriptorPool::for_pipeline(gpu, &pipeline, 1)?;
        let set = pool.allocate(&pipeline)?;
        let pass = RasterWarpPass {
            gpu: gpu.clone(),
            pipeline,
            render_pass,
            _pool: pool,
            set,
            push: warp.push(),
            output_size: desc.geometry.output_size,
            format,
        };
        let [g, r, b] = warp.map_views();
        // SAFETY: the set was just allocated from a pool made for this pipeline's layout, so no
        // work uses it yet; the buffers and views are this pass's own, alive.
        unsafe { write_storage_image_descriptors(&pass.gpu, pass.set, &[(0, g), (1, r), (2, b)]) };
        Ok(pass)
    }

    /// Points the pass at the source: a view of a storage image of the warp's source size and
    /// format, in `GENERAL` layout when the recorded work runs.
    ///
    /// # Safety
    /// This rewrites the pass's descriptor set: no recorded work that uses
    /// this object may be pending on the GPU (wait for its fence first), as Vulkan
    /// requires of descriptor sets and memory the device reads.
    pub unsafe fn bind(&mut self, source: vk::ImageView) {
        // SAFETY: the caller upholds this function's contract (no pending work uses the set);
        // the set is this pass's own, of its pipeline's layout, and the views and buffers are
        // live.
        unsafe { write_storage_image_descriptors(&self.gpu, self.set, &[(3, source)]) };
    }

    /// Records the warp into `framebuffer` (one colour attachment of `output_size` and this
    /// pass's format, made with `self.render_pass`). The render pass clears it first (its load
    /// op), then every pixel is written.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass, after the [`WarpPass`]'s
    /// `record_prepare` (the maps written and visible to shader reads) and [`Self::bind`];
    /// the source's writes must be visible to fragment-shader reads; everything must stay
    /// alive until the work completes.
    pub unsafe fn record(&self, cmd: vk::CommandBuffer, framebuffer: &Framebuffer) {
        let d = self.gpu.device();
        let clears = [vk::ClearValue {
            color: vk::ClearColorValue { float32: [0.0; 4] },
        }];
        // SAFETY: the caller upholds `record`'s contract: `cmd` is recording outside a render
        // pass after the maps were built and `bind`, the source readable by fragment shaders,
        // everything alive until the work completes. One clear value for the one attachment,
        // a `WarpPush` for the push range; the full-screen triangle needs no vertex buffer,
        // and the render pass is ended here.
        unsafe {
            self.pipeline.begin(
                cmd,
                &self.render_pass,
                framebuffer,
                &clears,
                self.set,
                bytemuck::bytes_of(&self.push),
            );
            d.cmd_draw(cmd, 3, 1, 0, 0);
            d.cmd_end_render_pass(cmd);
        }
    }
}
