//! Vulkan plumbing.
//!
//! * [`Gpu`] — the handles a pass needs (device, queue, allocator), built from the caller's
//!   objects ([`Gpu::from_caller`]) or created by the headless `host::Context`. Cheap to
//!   clone; the last clone of a context-made `Gpu` destroys the device it created, never a
//!   caller's.
//! * Owned objects: [`Buffer`], [`Image`], [`ComputePipeline`], [`GraphicsPipeline`],
//!   [`RenderPass`], [`Framebuffer`], [`Sampler`], [`DescriptorPool`], [`QueryPool`], each destroying its handle (and freeing its allocation) in `Drop`.
//! * Barriers named by what a resource is used for ([`Access`]): [`global_barrier`],
//!   [`image_transition`], [`image_discard`].

mod barriers;
mod graphics;
mod pipeline;
pub mod reflect;
mod resources;
pub mod shaders;

use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex};

use ash::vk;
use gpu_allocator::vulkan::Allocator;

pub use barriers::{
    global_barrier, host_read_barrier, image_discard, image_transition, record_compute_download,
    record_compute_readback, record_discard_for_compute_write, record_download, record_upload,
    Access,
};
pub use graphics::{
    Attribute, Framebuffer, GraphicsDesc, GraphicsPipeline, RenderPass, Sampler, Stage,
    VertexBinding,
};
pub use pipeline::{
    write_buffer_descriptors, write_sampled_image_descriptor, write_storage_image_descriptors,
    ComputePipeline, DescriptorLayout, DescriptorPool, SpecConstants, SpecId,
};
pub use resources::{Buffer, Image, QueryPool};

pub use crate::error::{Error, Result};

/// Optional device features vklens can use, as the caller enabled them.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct EnabledFeatures {
    /// `shaderFloat64`: the f64 model variants (the precise inverse near folds).
    pub shader_float64: bool,
    /// `geometryShader`: the geometry path (Alg. 1) drops triangles in a geometry shader.
    pub geometry_shader: bool,
}

/// The handles every pass needs: a device, a queue it may use for one-off uploads, and a
/// `gpu-allocator` allocator. Built from the caller's objects or by the headless `host::Context`.
#[derive(Clone)]
pub struct Gpu {
    inner: Arc<GpuInner>,
}

pub(crate) struct GpuInner {
    pub(crate) device: ash::Device,
    pub(crate) queue: vk::Queue,
    pub(crate) queue_family: u32,
    pub(crate) allocator: ManuallyDrop<Arc<Mutex<Allocator>>>,
    pub(crate) timestamp_period_ns: f64,
    pub(crate) timestamps: bool,
    pub(crate) device_name: String,
    /// The driver, as it names itself (e.g. "llvmpipe, Mesa 22.3.6 (LLVM 15.0.6)").
    pub(crate) driver: String,
    /// Whether `shaderFloat64` is enabled on the device (f64 shader variants).
    pub(crate) float64: bool,
    /// Whether `geometryShader` is enabled (the geometry path's triangle discard).
    pub(crate) geometry_shader: bool,
    /// Whether the vertex path's discard runs in a geometry shader where a pass leaves it to
    /// the device (`host::ContextOptions::geometry_shader_discard`).
    pub(crate) geometry_shader_discard: bool,
    /// `maxImageDimension2D`.
    pub(crate) max_image_side: u32,
    /// `maxImageDimensionCube`.
    pub(crate) max_cube_side: u32,
    /// Whether RGBA32F images can be sampled with linear filtering (optimal tiling).
    pub(crate) float_linear: bool,
    /// The compute pipelines built last, handed out again for the same shader and constants.
    pub(crate) compute_pipelines: pipeline::PipelineMemo,
    /// The driver's pipeline cache every pipeline is created with (null: none), owned here.
    pub(crate) pipeline_cache: vk::PipelineCache,
    /// Present when vklens created the device (the headless `host::Context`); destroys it last.
    pub(crate) owner: Option<Owned>,
}

impl Gpu {
    /// Wraps the caller's device, queue and allocator. vklens never destroys any of them; the
    /// caller must keep them alive as long as this `Gpu` or anything built from it.
    ///
    /// # Safety
    /// `device` must have been created from `physical_device` of `instance`, `queue` must be a
    /// queue of `queue_family` of that device supporting compute, and `allocator` must have
    /// been created for that device. `features` must name only features the device was
    /// created with (they unlock the f64 shader variants and the geometry path).
    pub unsafe fn from_caller(
        instance: &ash::Instance,
        physical_device: vk::PhysicalDevice,
        device: ash::Device,
        queue: vk::Queue,
        queue_family: u32,
        allocator: Arc<Mutex<Allocator>>,
        features: EnabledFeatures,
    ) -> Result<Self> {
        if device.handle() == vk::Device::null() || queue == vk::Queue::null() {
            return Err(Error::input("null device or queue handle"));
        }
        // SAFETY: the caller upholds `from_caller`'s contract, so `physical_device` belongs to
        // the live `instance`.
        let props = unsafe { instance.get_physical_device_properties(physical_device) };
        let families =
            // SAFETY: the same physical device of the same instance as the query above.
            unsafe { instance.get_physical_device_queue_family_properties(physical_device) };
        let family = families
            .get(queue_family as usize)
            .ok_or_else(|| Error::input(format!("queue family {queue_family} does not exist")))?;
        Ok(Gpu {
            inner: Arc::new(GpuInner {
                device,
                queue,
                queue_family,
                allocator: ManuallyDrop::new(allocator),
                timestamp_period_ns: props.limits.timestamp_period as f64,
                timestamps: family.timestamp_valid_bits > 0,
                device_name: device_name(&props),
                driver: driver_name(instance, physical_device, &props),
                float64: features.shader_float64,
                geometry_shader: features.geometry_shader,
                geometry_shader_discard: false,
                max_image_side: props.limits.max_image_dimension2_d,
                max_cube_side: props.limits.max_image_dimension_cube,
                float_linear: float_linear(instance, physical_device),
                compute_pipelines: Default::default(),
                pipeline_cache: vk::PipelineCache::null(),
                owner: None,
            }),
        })
    }

    pub(crate) fn from_inner(inner: GpuInner) -> Self {
        Gpu {
            inner: Arc::new(inner),
        }
    }

    /// Whether the vertex path drops triangles in a geometry shader where a pass does not
    /// say (`host::ContextOptions::geometry_shader_discard`); the compute discard otherwise.
    pub fn prefers_geometry_shader_discard(&self) -> bool {
        self.inner.geometry_shader_discard
    }

    /// The ash device.
    pub fn device(&self) -> &ash::Device {
        &self.inner.device
    }
    /// The driver's pipeline cache pipelines are created with (null: none).
    pub fn pipeline_cache(&self) -> vk::PipelineCache {
        self.inner.pipeline_cache
    }
    /// The queue one-off work is submitted to.
    pub fn queue(&self) -> vk::Queue {
        self.inner.queue
    }
    /// Its family index.
    pub fn queue_family(&self) -> u32 {
        self.inner.queue_family
    }
    /// The shared allocator.
    pub fn allocator(&self) -> &Arc<Mutex<Allocator>> {
        &self.inner.allocator
    }
    /// Nanoseconds per timestamp tick, and whether the queue has timestamps at all.
    pub fn timestamp_period_ns(&self) -> Option<f64> {
        self.inner
            .timestamps
            .then_some(self.inner.timestamp_period_ns)
    }
    /// The largest image side the device supports.
    pub fn max_image_side(&self) -> u32 {
        self.inner.max_image_side
    }

    /// The largest cube map face (`maxImageDimensionCube`, at least 4096 by the spec).
    pub fn max_cube_side(&self) -> u32 {
        self.inner.max_cube_side
    }

    /// Whether RGBA32F images can be sampled with linear filtering (Vulkan does not require
    /// it; the cube-map warp needs it for float sources).
    pub fn supports_float_linear_filter(&self) -> bool {
        self.inner.float_linear
    }
    /// Whether f64 shader variants can run (`shaderFloat64` enabled).
    pub fn supports_float64(&self) -> bool {
        self.inner.float64
    }
    /// Whether the geometry path can run (`geometryShader` enabled).
    pub fn supports_geometry_shader(&self) -> bool {
        self.inner.geometry_shader
    }
    /// The device's name (e.g. `llvmpipe (LLVM 15.0.6, 256 bits)`).
    pub fn device_name(&self) -> &str {
        &self.inner.device_name
    }

    /// The driver and its version, as the driver reports them (for benchmark tables).
    pub fn driver(&self) -> &str {
        &self.inner.driver
    }
}

impl Drop for GpuInner {
    fn drop(&mut self) {
        // SAFETY: this is the last `Gpu` clone, and every object vklens makes holds one, so
        // nothing made from the device is left. `allocator` is dropped once, here, before
        // `owner` (present only for a device vklens created) destroys device and instance.
        // This assumes no clone of the allocator `Arc` (which `Gpu::allocator` hands out)
        // outlives the device: its drop would free memory of a destroyed device.
        unsafe {
            // The memo's pipelines, which no user holds any more, go before the device, and
            // the pipeline cache with them (a null one is ignored).
            self.compute_pipelines.clear();
            self.device
                .destroy_pipeline_cache(self.pipeline_cache, None);
            // The allocator goes before the device it allocates from.
            ManuallyDrop::drop(&mut self.allocator);
            if let Some(owner) = self.owner.take() {
                owner.destroy(&self.device);
            }
        }
    }
}

/// The driver's name and version: `VK_KHR_driver_properties` where the device has it (its
/// name and info strings, e.g. "llvmpipe, Mesa 22.3.6 (LLVM 15.0.6)"), else the raw
/// `driverVersion` (whose encoding is the vendor's).
pub(crate) fn driver_name(
    instance: &ash::Instance,
    physical: vk::PhysicalDevice,
    props: &vk::PhysicalDeviceProperties,
) -> String {
    // SAFETY: `physical` is a physical device of the live `instance`.
    let has_driver_properties = unsafe { instance.enumerate_device_extension_properties(physical) }
        .map(|exts| {
            exts.iter().any(|e| {
                e.extension_name_as_c_str()
                    .is_ok_and(|n| n == ash::khr::driver_properties::NAME)
            })
        })
        .unwrap_or(false);
    if has_driver_properties {
        let mut driver = vk::PhysicalDeviceDriverProperties::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
        // SAFETY: vkGetPhysicalDeviceProperties2 is core in the instance's Vulkan 1.1, and a
        // physical device may be queried for the properties of an extension it supports.
        unsafe { instance.get_physical_device_properties2(physical, &mut props2) };
        let text = |s: Result<&std::ffi::CStr, _>| {
            s.map(|c| c.to_string_lossy().into_owned())
                .unwrap_or_default()
        };
        let name = text(driver.driver_name_as_c_str());
        let info = text(driver.driver_info_as_c_str());
        if !name.is_empty() {
            return format!("{name}, {info}");
        }
    }
    format!("driver version {:#x}", props.driver_version)
}

pub(crate) fn device_name(props: &vk::PhysicalDeviceProperties) -> String {
    props
        .device_name_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|_| "unnamed device".into())
}

/// Whether `R32G32B32A32_SFLOAT` with optimal tiling supports linear filtering.
pub(crate) fn float_linear(instance: &ash::Instance, physical: vk::PhysicalDevice) -> bool {
    // SAFETY: `physical` belongs to the live `instance` (both callers' contracts).
    let props = unsafe {
        instance.get_physical_device_format_properties(physical, vk::Format::R32G32B32A32_SFLOAT)
    };
    props
        .optimal_tiling_features
        .contains(vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR)
}

/// What the headless context created and must destroy after the device's last user.
pub(crate) struct Owned {
    pub(crate) _entry: ash::Entry,
    pub(crate) instance: ash::Instance,
    pub(crate) debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    pub(crate) _messages: Arc<Mutex<Vec<String>>>,
}

impl Owned {
    pub(crate) unsafe fn destroy(self, device: &ash::Device) {
        // SAFETY: only `GpuInner::drop` calls this, once, with the last `Gpu` clone and after
        // the allocator has gone; every object vklens makes from the device holds a `Gpu`, so
        // none is left. The messenger goes before the instance it belongs to, the instance last.
        unsafe {
            device.destroy_device(None);
            if let Some((loader, messenger)) = &self.debug {
                loader.destroy_debug_utils_messenger(*messenger, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}
