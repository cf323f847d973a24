//! What a geometry pass renders into: its output images, and extra camera-and-pose slots.

use super::*;

/// Extra camera-and-pose slots of a [`GeometryPass`] ([`GeometryPass::slots`]).
pub struct GeometrySlots {
    // The sets live in the pool; the uniform buffers they point at live in the slots.
    pub(super) _pool: DescriptorPool,
    pub(super) slots: Vec<Slot>,
}

impl GeometrySlots {
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }
}

pub(super) struct Slot {
    pub(super) camera: Buffer,
    pub(super) frame: Buffer,
    pub(super) set: vk::DescriptorSet,
}

/// The images a [`GeometryPass`] renders into (the host reads them back with
/// `host::geometry::TargetsReadback`).
pub struct GeometryTargets {
    pub(super) outputs: Outputs,
    /// By location: colour, ID, flow, depth, range.
    pub(super) targets: [Option<Image>; 5],
    pub(super) _depth_buffer: Image,
    pub framebuffer: Framebuffer,
    pub(super) extent: vk::Extent2D,
}

impl GeometryTargets {
    pub fn new(gpu: &Gpu, pass: &GeometryPass) -> Result<Self> {
        let c = &pass.desc.camera;
        let extent = vk::Extent2D {
            width: c.width,
            height: c.height,
        };
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT
            | vk::ImageUsageFlags::TRANSFER_SRC
            | vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::STORAGE;
        let formats = pass.desc.outputs.formats();
        let names = [
            "geometry.color",
            "geometry.ids",
            "geometry.flow",
            "geometry.depth",
            "geometry.range",
        ];
        let mut targets: [Option<Image>; 5] = Default::default();
        for (i, f) in formats.iter().enumerate() {
            if let Some(format) = *f {
                // RGBA16F is not a required storage format; it need not be one.
                let usage = if format == vk::Format::R16G16B16A16_SFLOAT {
                    usage & !vk::ImageUsageFlags::STORAGE
                } else {
                    usage
                };
                targets[i] = Some(Image::new_2d(
                    gpu,
                    names[i],
                    format,
                    extent.width,
                    extent.height,
                    usage,
                )?);
            }
        }
        let depth_buffer = Image::new_2d(
            gpu,
            "geometry.depth_buffer",
            vk::Format::D32_SFLOAT,
            extent.width,
            extent.height,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
        )?;
        let mut views: Vec<vk::ImageView> = targets.iter().flatten().map(|t| t.view).collect();
        views.push(depth_buffer.view);
        // SAFETY: the views are of images just made for this render pass's attachments,
        // `extent` large.
        let framebuffer = unsafe { Framebuffer::new(gpu, &pass.render_pass, &views, extent) }?;
        Ok(GeometryTargets {
            outputs: pass.desc.outputs,
            targets,
            _depth_buffer: depth_buffer,
            framebuffer,
            extent,
        })
    }

    /// The colour image (when rendered), e.g. as the source of a warp.
    pub fn color(&self) -> Option<&Image> {
        self.targets[0].as_ref()
    }

    /// The ID image (when rendered).
    pub fn ids(&self) -> Option<&Image> {
        self.targets[1].as_ref()
    }

    /// The camera-depth image (when rendered; R32F metres, +inf where nothing was drawn).
    pub fn depth(&self) -> Option<&Image> {
        self.targets[3].as_ref()
    }

    /// The range image (when rendered; R32F metres along the pixel's ray, +inf where nothing
    /// was drawn).
    pub fn range(&self) -> Option<&Image> {
        self.targets[4].as_ref()
    }

    /// Every output by location (colour, IDs, flow, depth, range), those rendered. After
    /// [`GeometryPass::record`] they are in the pass's final layout (`TRANSFER_SRC_OPTIMAL` by
    /// default).
    pub fn images(&self) -> [Option<&Image>; 5] {
        self.targets.each_ref().map(Option::as_ref)
    }

    /// What the pass renders.
    pub fn outputs(&self) -> Outputs {
        self.outputs
    }

    /// The size of every output (the pass's camera).
    pub fn extent(&self) -> vk::Extent2D {
        self.extent
    }
}
