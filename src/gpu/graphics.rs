//! Graphics-pipeline objects, each owning its handle: [`RenderPass`], [`Framebuffer`],
//! [`Sampler`] and [`GraphicsPipeline`]. Plain Vulkan 1.1 render passes (no dynamic rendering),
//! so any Vulkan 1.1 device can embed the geometry path.

use crate::error::VkCall;
use ash::vk;

use super::pipeline::{
    pipeline_layout, set_layout, shader_module, specialization_data, DescriptorLayout,
};
use super::{Error, Gpu, Result, SpecConstants};

/// A one-subpass render pass: colour attachments by location (`None`: that location is
/// unused), an optional depth attachment. Every attachment is cleared on load and stored
/// ([`RenderPass::accumulating`]: kept), the colour attachments end in `final_layout`, ready
/// for what reads them next.
pub struct RenderPass {
    gpu: Gpu,
    pub raw: vk::RenderPass,
    /// Formats of the colour locations (`None`: unused).
    pub colors: Vec<Option<vk::Format>>,
    pub depth: Option<vk::Format>,
}

impl RenderPass {
    pub fn new(
        gpu: &Gpu,
        colors: &[Option<vk::Format>],
        depth: Option<vk::Format>,
        final_layout: vk::ImageLayout,
    ) -> Result<Self> {
        Self::build(gpu, colors, depth, final_layout, false)
    }

    /// One colour attachment whose contents are kept (load, not clear) and stay in
    /// `COLOR_ATTACHMENT_OPTIMAL` before and after: for draws that add into an image over
    /// many render passes (Heidrich et al.'s accumulation buffer).
    pub fn accumulating(gpu: &Gpu, format: vk::Format) -> Result<Self> {
        Self::build(
            gpu,
            &[Some(format)],
            None,
            vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            true,
        )
    }

    fn build(
        gpu: &Gpu,
        colors: &[Option<vk::Format>],
        depth: Option<vk::Format>,
        final_layout: vk::ImageLayout,
        keep: bool,
    ) -> Result<Self> {
        let (load_op, initial_layout) = if keep {
            (vk::AttachmentLoadOp::LOAD, final_layout)
        } else {
            (vk::AttachmentLoadOp::CLEAR, vk::ImageLayout::UNDEFINED)
        };
        let mut attachments = Vec::new();
        let mut refs = Vec::new();
        for format in colors {
            match format {
                Some(f) => {
                    refs.push(vk::AttachmentReference {
                        attachment: attachments.len() as u32,
                        layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                    });
                    attachments.push(
                        vk::AttachmentDescription::default()
                            .format(*f)
                            .samples(vk::SampleCountFlags::TYPE_1)
                            .load_op(load_op)
                            .store_op(vk::AttachmentStoreOp::STORE)
                            .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
                            .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
                            .initial_layout(initial_layout)
                            .final_layout(final_layout),
                    );
                }
                None => refs.push(vk::AttachmentReference {
                    attachment: vk::ATTACHMENT_UNUSED,
                    layout: vk::ImageLayout::UNDEFINED,
                }),
            }
        }
        let depth_ref = depth.map(|f| {
            let r = vk::AttachmentReference {
                attachment: attachments.len() as u32,
                layout: vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
            };
            attachments.push(
                vk::AttachmentDescription::default()
                    .format(f)
                    .samples(vk::SampleCountFlags::TYPE_1)
                    .load_op(vk::AttachmentLoadOp::CLEAR)
                    .store_op(vk::AttachmentStoreOp::DONT_CARE)
                    .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
                    .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
                    .initial_layout(vk::ImageLayout::UNDEFINED)
                    .final_layout(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL),
            );
            r
        });
        let mut subpass = vk::SubpassDescription::default()
            .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
            .color_attachments(&refs);
        if let Some(r) = depth_ref.as_ref() {
            subpass = subpass.depth_stencil_attachment(r);
        }
        let attachment_stages = vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT
            | vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS
            | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS;
        let attachment_writes = vk::AccessFlags::COLOR_ATTACHMENT_WRITE
            | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE;
        let dependencies = [
            // Earlier reads of the images (a transfer, a shader) finish before we clear them.
            vk::SubpassDependency {
                src_subpass: vk::SUBPASS_EXTERNAL,
                dst_subpass: 0,
                src_stage_mask: vk::PipelineStageFlags::TRANSFER
                    | vk::PipelineStageFlags::COMPUTE_SHADER
                    | vk::PipelineStageFlags::FRAGMENT_SHADER
                    | attachment_stages,
                dst_stage_mask: attachment_stages,
                // Kept contents: earlier draws' writes are visible to this pass's blending.
                src_access_mask: if keep {
                    attachment_writes
                } else {
                    vk::AccessFlags::empty()
                },
                dst_access_mask: if keep {
                    attachment_writes | vk::AccessFlags::COLOR_ATTACHMENT_READ
                } else {
                    attachment_writes
                },
                dependency_flags: vk::DependencyFlags::empty(),
            },
            // What we rendered is visible to whatever reads it next (copy, compute, sampling).
            vk::SubpassDependency {
                src_subpass: 0,
                dst_subpass: vk::SUBPASS_EXTERNAL,
                src_stage_mask: attachment_stages,
                dst_stage_mask: vk::PipelineStageFlags::TRANSFER
                    | vk::PipelineStageFlags::COMPUTE_SHADER
                    | vk::PipelineStageFlags::FRAGMENT_SHADER,
                src_access_mask: attachment_writes,
                dst_access_mask: vk::AccessFlags::TRANSFER_READ | vk::AccessFlags::SHADER_READ,
                dependency_flags: vk::DependencyFlags::empty(),
            },
        ];
        let subpasses = [subpass];
        let info = vk::RenderPassCreateInfo::default()
            .attachments(&attachments)
            .subpasses(&subpasses)
            .dependencies(&dependencies);
        // SAFETY: `info` points at `attachments`, `subpasses` (whose references index into
        // `attachments` or are ATTACHMENT_UNUSED) and `dependencies`, all alive across the call.
        let raw = unsafe {
            gpu.device()
                .create_render_pass(&info, None)
                .call("vkCreateRenderPass")?
        };
        Ok(RenderPass {
            gpu: gpu.clone(),
            raw,
            colors: colors.to_vec(),
            depth,
        })
    }
}

impl Drop for RenderPass {
    fn drop(&mut self) {
        // SAFETY: created from this device and destroyed only here; pipelines and framebuffers
        // made with it may outlive it (Vulkan allows that); no pending work still uses it.
        unsafe { self.gpu.device().destroy_render_pass(self.raw, None) };
    }
}

/// A framebuffer: image views in the render pass's attachment order (used colour locations,
/// then depth).
pub struct Framebuffer {
    gpu: Gpu,
    pub raw: vk::Framebuffer,
    pub extent: vk::Extent2D,
}

impl Framebuffer {
    /// A framebuffer of `views` for `render_pass`, `extent` large.
    ///
    /// # Safety
    /// The views are live views of this device matching the render pass's attachments in
    /// number, format and samples, each at least `extent` large.
    pub unsafe fn new(
        gpu: &Gpu,
        render_pass: &RenderPass,
        views: &[vk::ImageView],
        extent: vk::Extent2D,
    ) -> Result<Self> {
        let info = vk::FramebufferCreateInfo::default()
            .render_pass(render_pass.raw)
            .attachments(views)
            .width(extent.width)
            .height(extent.height)
            .layers(1);
        // SAFETY: `render_pass` is alive and of this device; `info` and `views` outlive the
        // call; the views match the render pass's attachments and cover `extent` (the
        // function's contract).
        let raw = unsafe {
            gpu.device()
                .create_framebuffer(&info, None)
                .call("vkCreateFramebuffer")?
        };
        Ok(Framebuffer {
            gpu: gpu.clone(),
            raw,
            extent,
        })
    }
}

impl Drop for Framebuffer {
    fn drop(&mut self) {
        // SAFETY: created from this device and destroyed only here; no pending work still uses
        // it (recorded work's contract keeps it alive until the work completes).
        unsafe { self.gpu.device().destroy_framebuffer(self.raw, None) };
    }
}

/// A sampler: bilinear or nearest, repeating (scene textures tile).
pub struct Sampler {
    gpu: Gpu,
    pub raw: vk::Sampler,
}

impl Sampler {
    pub fn new(gpu: &Gpu, filter: vk::Filter, address: vk::SamplerAddressMode) -> Result<Self> {
        Self::with_modes(gpu, filter, [address; 3])
    }

    /// A sampler with its own addressing per coordinate (u v w): an equirectangular panorama
    /// wraps in longitude and clamps in latitude.
    pub fn with_modes(
        gpu: &Gpu,
        filter: vk::Filter,
        [u, v, w]: [vk::SamplerAddressMode; 3],
    ) -> Result<Self> {
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(filter)
            .min_filter(filter)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(u)
            .address_mode_v(v)
            .address_mode_w(w)
            .max_lod(0.0);
        // SAFETY: a complete sampler create info (no anisotropy, no compare, lod 0) on a live
        // device.
        let raw = unsafe {
            gpu.device()
                .create_sampler(&info, None)
                .call("vkCreateSampler")?
        };
        Ok(Sampler {
            gpu: gpu.clone(),
            raw,
        })
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        // SAFETY: created from this device and destroyed only here; no pending work or live
        // descriptor in use still refers to it (its owners drop it with the passes using it).
        unsafe { self.gpu.device().destroy_sampler(self.raw, None) };
    }
}

/// One shader stage of a graphics pipeline.
pub struct Stage<'a> {
    pub stage: vk::ShaderStageFlags,
    pub spirv: &'a [u8],
    pub constants: SpecConstants,
}

/// One vertex attribute: (location, format, byte offset) in its binding.
pub type Attribute = (u32, vk::Format, u32);

/// One per-vertex buffer binding: its stride and its attributes.
pub type VertexBinding<'a> = (u32, &'a [Attribute]);

/// What a [`GraphicsPipeline`] is built from.
pub struct GraphicsDesc<'a> {
    pub stages: Vec<Stage<'a>>,
    /// Set 0's bindings, visible to every stage.
    pub bindings: &'a [vk::DescriptorType],
    /// The per-vertex buffer bindings, binding `i` at index `i` (empty: no vertex input; the
    /// vertex shader computes positions from `gl_VertexIndex`).
    pub vertex: &'a [VertexBinding<'a>],
    pub render_pass: &'a RenderPass,
    /// Depth test and write (less), when the render pass has a depth attachment.
    pub depth_test: bool,
    /// Bytes of push constants, visible to every stage (0: none).
    pub push_size: u32,
    /// Add fragment outputs to the attachments (ONE + ONE) instead of replacing them.
    pub additive: bool,
}

/// A graphics pipeline with its modules, set-0 layout and pipeline layout. Viewport and
/// scissor are dynamic (set per framebuffer).
pub struct GraphicsPipeline {
    gpu: Gpu,
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    pub set_layout: vk::DescriptorSetLayout,
    modules: Vec<vk::ShaderModule>,
    bindings: Vec<vk::DescriptorType>,
    /// The specialization constants of each stage (what a plan can be checked against).
    pub constants: Vec<(vk::ShaderStageFlags, SpecConstants)>,
    /// Stages that see the push constants.
    pub push_stages: vk::ShaderStageFlags,
}

impl DescriptorLayout for GraphicsPipeline {
    fn set_layout(&self) -> vk::DescriptorSetLayout {
        self.set_layout
    }
    fn binding_types(&self) -> &[vk::DescriptorType] {
        &self.bindings
    }
}

impl GraphicsPipeline {
    pub fn new(gpu: &Gpu, desc: GraphicsDesc) -> Result<Self> {
        let device = gpu.device();
        let all_stages = desc
            .stages
            .iter()
            .fold(vk::ShaderStageFlags::empty(), |a, s| a | s.stage);
        if all_stages.contains(vk::ShaderStageFlags::GEOMETRY) && !gpu.supports_geometry_shader() {
            return Err(Error::Unsupported(
                "the device was created without the geometryShader feature, which the geometry path needs".into(),
            ));
        }
        let mut pipeline = GraphicsPipeline {
            gpu: gpu.clone(),
            raw: vk::Pipeline::null(),
            layout: vk::PipelineLayout::null(),
            set_layout: vk::DescriptorSetLayout::null(),
            modules: Vec::new(),
            bindings: desc.bindings.to_vec(),
            constants: desc
                .stages
                .iter()
                .map(|s| (s.stage, s.constants.clone()))
                .collect(),
            push_stages: all_stages,
        };
        for s in &desc.stages {
            let module = shader_module(gpu, s.spirv)?;
            pipeline.modules.push(module);
        }
        pipeline.set_layout = set_layout(gpu, desc.bindings, all_stages)?;
        pipeline.layout = pipeline_layout(gpu, pipeline.set_layout, desc.push_size, all_stages)?;

        let spec_data: Vec<_> = desc
            .stages
            .iter()
            .map(|s| specialization_data(&s.constants))
            .collect();
        let spec_infos: Vec<_> = spec_data
            .iter()
            .map(|(map, data)| {
                vk::SpecializationInfo::default()
                    .map_entries(map)
                    .data(data)
            })
            .collect();
        let stages: Vec<_> = desc
            .stages
            .iter()
            .zip(&pipeline.modules)
            .zip(&spec_infos)
            .map(|((s, &module), spec)| {
                vk::PipelineShaderStageCreateInfo::default()
                    .stage(s.stage)
                    .module(module)
                    .name(c"main")
                    .specialization_info(spec)
            })
            .collect();

        let vertex_bindings: Vec<_> = (0u32..)
            .zip(desc.vertex)
            .map(
                |(binding, &(stride, _))| vk::VertexInputBindingDescription {
                    binding,
                    stride,
                    input_rate: vk::VertexInputRate::VERTEX,
                },
            )
            .collect();
        let attributes: Vec<_> = (0u32..)
            .zip(desc.vertex)
            .flat_map(|(binding, &(_, attrs))| {
                attrs.iter().map(move |&(location, format, offset)| {
                    vk::VertexInputAttributeDescription {
                        location,
                        binding,
                        format,
                        offset,
                    }
                })
            })
            .collect();
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(&vertex_bindings)
            .vertex_attribute_descriptions(&attributes);
        let assembly = vk::PipelineInputAssemblyStateCreateInfo::default()
            .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport = vk::PipelineViewportStateCreateInfo::default()
            .viewport_count(1)
            .scissor_count(1);
        // No culling: a lens may mirror nothing, but imported meshes have either winding.
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(vk::CullModeFlags::NONE)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let multisample = vk::PipelineMultisampleStateCreateInfo::default()
            .rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(desc.depth_test)
            .depth_write_enable(desc.depth_test)
            .depth_compare_op(vk::CompareOp::LESS);
        let blend_attachments: Vec<_> = desc
            .render_pass
            .colors
            .iter()
            .map(|_| {
                vk::PipelineColorBlendAttachmentState::default()
                    .blend_enable(desc.additive)
                    .src_color_blend_factor(vk::BlendFactor::ONE)
                    .dst_color_blend_factor(vk::BlendFactor::ONE)
                    .color_blend_op(vk::BlendOp::ADD)
                    .src_alpha_blend_factor(vk::BlendFactor::ONE)
                    .dst_alpha_blend_factor(vk::BlendFactor::ONE)
                    .alpha_blend_op(vk::BlendOp::ADD)
                    .color_write_mask(vk::ColorComponentFlags::RGBA)
            })
            .collect();
        let blend =
            vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let mut info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(pipeline.layout)
            .render_pass(desc.render_pass.raw)
            .subpass(0);
        if desc.render_pass.depth.is_some() {
            info = info.depth_stencil_state(&depth);
        }
        // SAFETY: every pointer in `info` (stages with their modules and specialization data,
        // vertex input, fixed-function, blend and dynamic state) refers to locals alive across
        // the call; the layout and render pass are live objects of this device; the blend state
        // has one attachment per colour location of subpass 0, and depth state is given exactly
        // when the subpass has a depth attachment. On error `pipeline`'s Drop cleans up.
        pipeline.raw = unsafe {
            device
                .create_graphics_pipelines(gpu.pipeline_cache(), &[info], None)
                .map_err(|(_, e)| e)
                .call("vkCreateGraphicsPipelines")?[0]
        };
        Ok(pipeline)
    }

    /// Begins `render_pass` on `framebuffer` with `clears` (one per attachment, in attachment
    /// order), binds this pipeline and `set`, sets viewport and scissor to the whole
    /// framebuffer and pushes `push` (every push-constant stage; empty: none). The caller
    /// draws, then ends the render pass.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass; `framebuffer` must belong to
    /// `render_pass` and `set` to this pipeline's layout, all alive until the work completes.
    pub unsafe fn begin(
        &self,
        cmd: vk::CommandBuffer,
        render_pass: &RenderPass,
        framebuffer: &Framebuffer,
        clears: &[vk::ClearValue],
        set: vk::DescriptorSet,
        push: &[u8],
    ) {
        let d = self.gpu.device();
        let extent = framebuffer.extent;
        let area = vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent,
        };
        let begin = vk::RenderPassBeginInfo::default()
            .render_pass(render_pass.raw)
            .framebuffer(framebuffer.raw)
            .render_area(area)
            .clear_values(clears);
        // SAFETY: the caller upholds `begin`'s contract: `cmd` is recording outside a render
        // pass, `framebuffer` belongs to `render_pass` and `set` to this layout, all alive until
        // the work completes. `clears` (one per cleared attachment) and `push` (at most the
        // layout's push range) are the caller's too: each pass passes its own. Viewport and
        // scissor are dynamic state of this pipeline and cover exactly the framebuffer.
        unsafe {
            d.cmd_begin_render_pass(cmd, &begin, vk::SubpassContents::INLINE);
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.raw);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::GRAPHICS,
                self.layout,
                0,
                &[set],
                &[],
            );
            d.cmd_set_viewport(
                cmd,
                0,
                &[vk::Viewport {
                    x: 0.0,
                    y: 0.0,
                    width: extent.width as f32,
                    height: extent.height as f32,
                    min_depth: 0.0,
                    max_depth: 1.0,
                }],
            );
            d.cmd_set_scissor(cmd, 0, &[area]);
            if !push.is_empty() {
                d.cmd_push_constants(cmd, self.layout, self.push_stages, 0, push);
            }
        }
    }
}

impl Drop for GraphicsPipeline {
    fn drop(&mut self) {
        let d = self.gpu.device();
        // SAFETY: the pipeline, layouts and modules were created from this device for this
        // pipeline and are destroyed only here (null ones, left by a failed `new`, are ignored
        // by Vulkan); no pending work still uses them.
        unsafe {
            d.destroy_pipeline(self.raw, None);
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
            for &m in &self.modules {
                d.destroy_shader_module(m, None);
            }
        }
    }
}
