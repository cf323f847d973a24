//! Heidrich et al. Sec. 3.5's accumulation: each cell's perspective image, morphed onto its film
//! grid and weighted by `W_i(x')` at the grid vertices, is added into a float film image
//! (additive blending; Heidrich et al.'s accumulation buffer).
//!
//! Embedding: [`FilmPass::record_clear`], then any number of [`FilmPass::record_cell`]
//! (each after the cell's image was rendered), then the
//! caller's use of the image (left in `COLOR_ATTACHMENT_OPTIMAL`; the host reads it back).

use ash::vk;
use bytemuck::{Pod, Zeroable};

use crate::gpu::{
    image_transition, shaders, Access, Buffer, DescriptorPool, Error, Framebuffer, Gpu,
    GraphicsDesc, GraphicsPipeline, Image, RenderPass, Result, Sampler, SpecConstants, Stage,
};

/// The film's format: float, so that many weighted slices add without clipping or banding.
pub const FILM_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// One film-grid vertex: film position (pixels), where it samples the cell image (0..1),
/// radiometric weight.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct FilmVertex {
    pub film_px: [f32; 2],
    pub cell_uv: [f32; 2],
    pub weight: f32,
    pub _pad: f32,
}

/// `FilmPush` of `glsl/film_morph.{vert,frag}`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct FilmPush {
    /// Film width, height (pixels), unused, unused.
    pub film_size: [f32; 4],
    /// Channels a draw adds to (1 or 0 each; alpha collects the weights: vignetting).
    pub channel_mask: [f32; 4],
}

/// The morph-and-accumulate pipeline; one descriptor set per cell image it reads.
pub struct FilmPass {
    gpu: Gpu,
    pool: DescriptorPool,
    pipeline: GraphicsPipeline,
    pub render_pass: RenderPass,
    sampler: Sampler,
}

impl FilmPass {
    /// `images`: how many distinct cell images (descriptor sets) the caller will bind.
    pub fn new(gpu: &Gpu, images: u32) -> Result<Self> {
        let render_pass = RenderPass::accumulating(gpu, FILM_FORMAT)?;
        let attributes = [
            (0, vk::Format::R32G32_SFLOAT, 0),
            (1, vk::Format::R32G32_SFLOAT, 8),
            (2, vk::Format::R32_SFLOAT, 16),
        ];
        let pipeline = GraphicsPipeline::new(
            gpu,
            GraphicsDesc {
                stages: vec![
                    Stage {
                        stage: vk::ShaderStageFlags::VERTEX,
                        spirv: shaders::FILM_MORPH_VERT,
                        constants: SpecConstants::new(),
                    },
                    Stage {
                        stage: vk::ShaderStageFlags::FRAGMENT,
                        spirv: shaders::FILM_MORPH_FRAG,
                        constants: SpecConstants::new(),
                    },
                ],
                bindings: &[vk::DescriptorType::COMBINED_IMAGE_SAMPLER],
                vertex: &[(std::mem::size_of::<FilmVertex>() as u32, &attributes)],
                render_pass: &render_pass,
                depth_test: false,
                push_size: std::mem::size_of::<FilmPush>() as u32,
                additive: true,
            },
        )?;
        let pool = DescriptorPool::for_pipeline(gpu, &pipeline, images.max(1))?;
        Ok(FilmPass {
            gpu: gpu.clone(),
            pool,
            pipeline,
            render_pass,
            // Clamped: a grid vertex at a cell's edge must not wrap to the other side.
            sampler: Sampler::new(
                gpu,
                vk::Filter::LINEAR,
                vk::SamplerAddressMode::CLAMP_TO_EDGE,
            )?,
        })
    }

    /// A descriptor set that samples `view` (in `SHADER_READ_ONLY_OPTIMAL` when drawn).
    pub fn bind_image(&self, view: vk::ImageView) -> Result<vk::DescriptorSet> {
        let set = self.pool.allocate(&self.pipeline)?;
        // SAFETY: the set was just allocated from a pool made for this pipeline's layout (a
        // sampled image at 0), so no work uses it yet; `view` is the caller's live view.
        unsafe {
            crate::gpu::write_sampled_image_descriptor(&self.gpu, set, 0, &self.sampler, view)
        };
        Ok(set)
    }

    pub fn pipeline(&self) -> &GraphicsPipeline {
        &self.pipeline
    }

    /// Clears the film to zero and leaves it in `COLOR_ATTACHMENT_OPTIMAL` for the cells.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass; `target` must stay alive until the
    /// work completes.
    pub unsafe fn record_clear(&self, cmd: vk::CommandBuffer, target: &FilmTarget) {
        let d = self.gpu.device();
        // SAFETY: the caller upholds `record_clear`'s contract: `cmd` is recording outside a
        // render pass and `target` outlives the work. The film image has TRANSFER_DST and
        // COLOR_ATTACHMENT usage; UNDEFINED is a valid old layout as it is cleared whole.
        unsafe {
            image_transition(
                &self.gpu,
                cmd,
                target.image.raw,
                Access::Nothing,
                Access::TransferWrite,
            );
            d.cmd_clear_color_image(
                cmd,
                target.image.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &vk::ClearColorValue { float32: [0.0; 4] },
                &[Image::color_range()],
            );
            // The cells blend into the cleared film.
            image_transition(
                &self.gpu,
                cmd,
                target.image.raw,
                Access::TransferWrite,
                Access::ColorAttachmentReadWrite,
            );
        }
    }

    /// Adds one cell: `count` vertices (a triangle list) from `first` in `vertices`, sampling
    /// the image of `set`, into the channels of `channel_mask`.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass, after [`Self::record_clear`] and after
    /// the cell image was rendered (its writes visible to fragment shaders, in
    /// `SHADER_READ_ONLY_OPTIMAL`); everything must stay alive until the work completes.
    #[allow(clippy::too_many_arguments)]
    pub unsafe fn record_cell(
        &self,
        cmd: vk::CommandBuffer,
        target: &FilmTarget,
        set: vk::DescriptorSet,
        vertices: &Buffer,
        first: u32,
        count: u32,
        channel_mask: [f32; 4],
    ) {
        let push = FilmPush {
            film_size: [target.width as f32, target.height as f32, 0.0, 0.0],
            channel_mask,
        };
        let d = self.gpu.device();
        // SAFETY: the caller upholds `record_cell`'s contract: `cmd` is recording outside a
        // render pass after `record_clear` (the film in COLOR_ATTACHMENT_OPTIMAL, which this
        // LOAD pass expects, so no clear values are needed), the cell image readable, all alive
        // until the work completes. `first + count` must lie within `vertices`: every caller
        // passes a range it pushed into that buffer. The render pass is ended here.
        unsafe {
            self.pipeline.begin(
                cmd,
                &self.render_pass,
                &target.framebuffer,
                &[],
                set,
                bytemuck::bytes_of(&push),
            );
            d.cmd_bind_vertex_buffers(cmd, 0, &[vertices.raw], &[0]);
            d.cmd_draw(cmd, count, 1, first, 0);
            d.cmd_end_render_pass(cmd);
        }
    }
}

/// The float film image the cells accumulate into.
pub struct FilmTarget {
    pub image: Image,
    pub framebuffer: Framebuffer,
    pub width: u32,
    pub height: u32,
}

impl FilmTarget {
    pub fn new(gpu: &Gpu, pass: &FilmPass, width: u32, height: u32) -> Result<Self> {
        if width == 0 || height == 0 || width.max(height) > gpu.max_image_side() {
            return Err(Error::Input(format!(
                "film {width}×{height}: each side must be 1..={}",
                gpu.max_image_side()
            )));
        }
        let image = Image::new_2d(
            gpu,
            "film",
            FILM_FORMAT,
            width,
            height,
            vk::ImageUsageFlags::COLOR_ATTACHMENT
                | vk::ImageUsageFlags::TRANSFER_SRC
                | vk::ImageUsageFlags::TRANSFER_DST,
        )?;
        // SAFETY: the views are of images just made for this render pass's attachments,
        // `extent` large.
        let framebuffer = unsafe {
            Framebuffer::new(
                gpu,
                &pass.render_pass,
                &[image.view],
                vk::Extent2D { width, height },
            )
        }?;
        Ok(FilmTarget {
            image,
            framebuffer,
            width,
            height,
        })
    }
}
