//! The headless context: vklens creates its own instance and device. Tests and the CLI use it;
//! it is just one caller of the passes, which never depend on it.

use crate::error::VkCall;
use std::ffi::{c_void, CStr};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex};

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use crate::gpu::{device_name, Error, Gpu, GpuInner, Owned, Result};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How the headless context is set up.
#[derive(Debug, Clone, Default)]
pub struct ContextOptions {
    /// Enable the Khronos validation layer and collect its messages.
    pub validation: bool,
    /// Which device: `cpu` (lavapipe), `gpu`, an index, or part of the device name.
    /// `None` prefers a discrete GPU, then an integrated one, then anything.
    pub device: Option<String>,
    /// Enable `geometryShader` where the device has it. `false` makes a device report as
    /// one without (MoltenVK, many mobile GPUs) would, for testing the paths that need none.
    pub geometry_shader: bool,
    /// Drop the vertex path's triangles in a geometry shader (Lambers et al.'s own discard)
    /// where the device has one, instead of the faster compute discard: for comparisons.
    pub geometry_shader_discard: bool,
    /// A file that keeps the driver's pipeline cache (`VkPipelineCache`) between runs: read
    /// when the context opens (a missing file, or one another device or driver wrote, starts
    /// the cache empty), written when it closes (to a temporary file beside it, then renamed,
    /// so that a run never sees half a file). `None`: no cache. Drivers that compile shaders
    /// at pipeline creation (most GPUs) start faster with it; lavapipe keeps nothing in it.
    pub pipeline_cache: Option<std::path::PathBuf>,
}

impl ContextOptions {
    /// From the environment: `VKLENS_VALIDATION=1` turns validation on, `VKLENS_DEVICE`
    /// picks the device, `VKLENS_GEOMETRY_SHADER=0` leaves the geometry-shader feature off,
    /// `VKLENS_PIPELINE_CACHE=FILE` keeps the pipeline cache in FILE.
    pub fn from_env() -> Self {
        ContextOptions {
            validation: matches!(
                std::env::var("VKLENS_VALIDATION").as_deref(),
                Ok("1") | Ok("true") | Ok("yes")
            ),
            device: std::env::var("VKLENS_DEVICE")
                .ok()
                .filter(|s| !s.is_empty()),
            geometry_shader: geometry_shader_from_env(),
            geometry_shader_discard: geometry_shader_discard_from_env(),
            pipeline_cache: std::env::var_os("VKLENS_PIPELINE_CACHE")
                .filter(|p| !p.is_empty())
                .map(std::path::PathBuf::from),
        }
    }
}

/// `VKLENS_DISCARD=geometry-shader` asks for the geometry-shader discard (the device must
/// have `geometryShader`); anything else leaves the compute discard.
pub fn geometry_shader_discard_from_env() -> bool {
    std::env::var("VKLENS_DISCARD").as_deref() == Ok("geometry-shader")
}

/// `VKLENS_GEOMETRY_SHADER=0` (or `false`, `no`) turns the geometry-shader feature off.
pub fn geometry_shader_from_env() -> bool {
    !matches!(
        std::env::var("VKLENS_GEOMETRY_SHADER").as_deref(),
        Ok("0") | Ok("false") | Ok("no")
    )
}

/// A headless Vulkan context: instance, device, queue, allocator, command pool.
pub struct Context {
    gpu: Gpu,
    command_pool: vk::CommandPool,
    /// Held for the whole of a `submit`: the command pool and the queue must be externally
    /// synchronized (Vulkan spec, "Threading Behavior"), and a context is shared by threads.
    submitting: Mutex<()>,
    messages: Arc<Mutex<Vec<String>>>,
    validation: bool,
    /// Where the pipeline cache is written when the context closes.
    pipeline_cache_file: Option<std::path::PathBuf>,
}

unsafe extern "system" fn on_debug_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if data.is_null() || user.is_null() {
        return vk::FALSE;
    }
    let relevant = kind.intersects(
        vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
            | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
    ) && severity.intersects(
        vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
            | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
    );
    if relevant {
        // SAFETY: the loader passes valid callback data; `user` is the Mutex owned by `Owned`,
        // which outlives the messenger.
        let text = unsafe {
            let d = &*data;
            d.message_as_c_str()
                .map(|m| m.to_string_lossy().into_owned())
                .unwrap_or_default()
        };
        // SAFETY: `user` is `Arc::as_ptr` of the message list, which `Owned` keeps alive until
        // after the messenger is destroyed; only a shared reference is made (the Mutex syncs).
        let messages = unsafe { &*(user as *const Mutex<Vec<String>>) };
        if let Ok(mut m) = messages.lock() {
            m.push(format!("[{severity:?}] {text}"));
        }
    }
    vk::FALSE
}

/// The instance, with the validation layer and a messenger collecting its messages into
/// `messages` when `validation` is on.
fn create_instance(
    entry: &ash::Entry,
    validation: bool,
    messages: &Arc<Mutex<Vec<String>>>,
) -> Result<(
    ash::Instance,
    Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
)> {
    let mut layers = Vec::new();
    let mut extensions = Vec::new();
    if validation {
        // SAFETY: `entry` holds a loaded Vulkan library; this global query has no other
        // preconditions.
        let available = unsafe {
            entry
                .enumerate_instance_layer_properties()
                .call("vkEnumerateInstanceLayerProperties")?
        };
        let found = available.iter().any(|l| {
            l.layer_name_as_c_str()
                .map(|n| n == VALIDATION_LAYER)
                .unwrap_or(false)
        });
        if !found {
            return Err(Error::NoVulkan("the Khronos validation layer was requested but is not installed (apt-get install vulkan-validationlayers)".into()));
        }
        layers.push(VALIDATION_LAYER.as_ptr());
        extensions.push(ash::ext::debug_utils::NAME.as_ptr());
    }
    let app = vk::ApplicationInfo::default()
        .application_name(c"vklens")
        .engine_name(c"vklens")
        .api_version(vk::API_VERSION_1_1);
    let info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layers)
        .enabled_extension_names(&extensions);
    // SAFETY: `info` and everything it points at (`app`, the `'static` layer and extension
    // names in `layers` and `extensions`) outlive the call; no allocation callbacks.
    let instance = unsafe {
        entry
            .create_instance(&info, None)
            .call("vkCreateInstance")?
    };

    let debug = if validation {
        let loader = ash::ext::debug_utils::Instance::new(entry, &instance);
        let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
            .message_severity(
                vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                    | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
            )
            .message_type(
                vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                    | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE
                    | vk::DebugUtilsMessageTypeFlagsEXT::GENERAL,
            )
            .pfn_user_callback(Some(on_debug_message))
            .user_data(Arc::as_ptr(messages) as *mut c_void);
        // SAFETY: the instance was created with VK_EXT_debug_utils (pushed above when
        // validation is on); the user data points at `messages`, which `Owned` keeps alive
        // until the messenger is destroyed, and `on_debug_message` checks for null.
        match unsafe { loader.create_debug_utils_messenger(&info, None) } {
            Ok(m) => Some((loader, m)),
            Err(e) => {
                // SAFETY: nothing was created from the instance (the messenger failed), and
                // it is not used again.
                unsafe { instance.destroy_instance(None) };
                return Err(Error::Vulkan {
                    call: "vkCreateDebugUtilsMessengerEXT",
                    result: e,
                });
            }
        }
    } else {
        None
    };
    Ok((instance, debug))
}

/// A device made from `physical`, its queue and allocator.
struct OpenedDevice {
    device: ash::Device,
    queue: vk::Queue,
    allocator: Allocator,
    float64: bool,
    geometry_shader: bool,
}

/// Opens the device with one queue of `family` and the features vklens uses where the device
/// has them (refusing one without the storage formats the maps need), and its allocator. On
/// failure nothing of the device is left; the instance is the caller's to destroy.
fn open_device(
    instance: &ash::Instance,
    physical: vk::PhysicalDevice,
    family: u32,
    options: &ContextOptions,
) -> Result<OpenedDevice> {
    let priorities = [1.0f32];
    let queue_info = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(family)
        .queue_priorities(&priorities)];
    // f64 shader variants (the precise inverse near folds) need shaderFloat64; enable it
    // where the device has it (lavapipe does) and fall back to f32 elsewhere.
    // SAFETY: `physical` was enumerated from this live instance by `pick_device`.
    let supported = unsafe { instance.get_physical_device_features(physical) };
    let float64 = supported.shader_float64 == vk::TRUE;
    // rg32f coordinate maps and r8 masks are "extended" storage-image formats.
    if supported.shader_storage_image_extended_formats != vk::TRUE {
        return Err(Error::NoVulkan(
            "no Vulkan device matches: the device lacks shaderStorageImageExtendedFormats".into(),
        ));
    }
    // The geometry path can drop triangles in a geometry shader (lavapipe has them); it
    // has a compute discard for devices without.
    let geometry_shader = options.geometry_shader && supported.geometry_shader == vk::TRUE;
    let features = vk::PhysicalDeviceFeatures::default()
        .shader_float64(float64)
        .geometry_shader(geometry_shader)
        .shader_storage_image_extended_formats(true);
    let device_info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queue_info)
        .enabled_features(&features);
    // SAFETY: `physical` belongs to `instance`; `family` is one of its queue families and
    // one queue of it is requested; every enabled feature was checked as supported above;
    // `device_info` and what it points at outlive the call.
    let device = match unsafe { instance.create_device(physical, &device_info, None) } {
        Ok(d) => d,
        Err(e) => {
            return Err(Error::Vulkan {
                call: "vkCreateDevice",
                result: e,
            })
        }
    };
    // SAFETY: the device was created with one queue in `family`, so index 0 exists.
    let queue = unsafe { device.get_device_queue(family, 0) };
    let allocator = match Allocator::new(&AllocatorCreateDesc {
        instance: instance.clone(),
        device: device.clone(),
        physical_device: physical,
        debug_settings: Default::default(),
        buffer_device_address: false,
        allocation_sizes: Default::default(),
    }) {
        Ok(a) => a,
        Err(e) => {
            // SAFETY: nothing has been created from the new device and nothing else holds
            // it; the caller then destroys the instance it came from, after it.
            unsafe { device.destroy_device(None) };
            return Err(e.into());
        }
    };
    Ok(OpenedDevice {
        device,
        queue,
        allocator,
        float64,
        geometry_shader,
    })
}

impl Context {
    /// Creates a context with options from the environment (see [`ContextOptions::from_env`]).
    pub fn from_env() -> Result<Self> {
        Self::new(ContextOptions::from_env())
    }

    /// Creates a context.
    pub fn new(options: ContextOptions) -> Result<Self> {
        // SAFETY: loading libvulkan runs its initialisers; the system library is trusted to be
        // a conforming Vulkan loader. `Owned` keeps `entry` (the library) loaded as long as any
        // Vulkan object made through it lives.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| Error::NoVulkan(format!("cannot load the Vulkan library ({e}); install it with: apt-get install libvulkan1 mesa-vulkan-drivers")))?;
        let messages = Arc::new(Mutex::new(Vec::new()));

        let (instance, debug) = create_instance(&entry, options.validation, &messages)?;
        let mut owned = Some(Owned {
            _entry: entry,
            instance,
            debug,
            _messages: messages.clone(),
        });
        // On failure below, destroy the instance (and messenger) we made.
        let fail = |owned: &mut Option<Owned>, e: Error| -> Error {
            if let Some(o) = owned.take() {
                // SAFETY: no device exists when `fail` runs (each caller never made one or has
                // destroyed it), so the messenger and then the instance it belongs to can go;
                // `take` makes this happen at most once.
                unsafe {
                    if let Some((loader, m)) = &o.debug {
                        loader.destroy_debug_utils_messenger(*m, None);
                    }
                    o.instance.destroy_instance(None);
                }
            }
            e
        };
        let instance = owned.as_ref().expect("set above").instance.clone();
        let (physical, family) = match pick_device(&instance, options.device.as_deref()) {
            Ok(p) => p,
            Err(e) => return Err(fail(&mut owned, e)),
        };
        let opened = match open_device(&instance, physical, family, &options) {
            Ok(d) => d,
            Err(e) => return Err(fail(&mut owned, e)),
        };
        let OpenedDevice {
            device,
            queue,
            allocator,
            float64,
            geometry_shader,
        } = opened;
        // SAFETY: `physical` was enumerated from this live instance.
        let props = unsafe { instance.get_physical_device_properties(physical) };
        // SAFETY: the same physical device of the same live instance as the query above.
        let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
        let pipeline_cache = match &options.pipeline_cache {
            Some(path) => create_pipeline_cache(&device, &props, path),
            None => vk::PipelineCache::null(),
        };
        let gpu = Gpu::from_inner(GpuInner {
            device,
            queue,
            queue_family: family,
            allocator: ManuallyDrop::new(Arc::new(Mutex::new(allocator))),
            timestamp_period_ns: props.limits.timestamp_period as f64,
            timestamps: families[family as usize].timestamp_valid_bits > 0,
            device_name: device_name(&props),
            driver: crate::gpu::driver_name(&instance, physical, &props),
            float64,
            geometry_shader,
            geometry_shader_discard: options.geometry_shader_discard && geometry_shader,
            max_image_side: props.limits.max_image_dimension2_d,
            max_cube_side: props.limits.max_image_dimension_cube,
            float_linear: crate::gpu::float_linear(&instance, physical),
            compute_pipelines: Default::default(),
            pipeline_cache,
            owner: owned,
        });
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: `family` is the family of the device's queue; the pool is destroyed in
        // `Drop for Context`, which runs before the `gpu` field (and so the device) drops.
        let command_pool = unsafe {
            gpu.device()
                .create_command_pool(&pool_info, None)
                .call("vkCreateCommandPool")?
        };
        Ok(Context {
            gpu,
            command_pool,
            submitting: Mutex::new(()),
            messages,
            validation: options.validation,
            pipeline_cache_file: options
                .pipeline_cache
                .filter(|_| pipeline_cache != vk::PipelineCache::null()),
        })
    }

    /// The GPU handles passes are built from.
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// Whether the validation layer is on.
    pub fn validation_enabled(&self) -> bool {
        self.validation
    }

    /// Records work with `record` into a fresh command buffer, submits it and waits.
    pub fn submit<T>(&self, record: impl FnOnce(vk::CommandBuffer) -> Result<T>) -> Result<T> {
        // A poisoned lock only means another submission panicked; the pool is still valid.
        let _guard = self
            .submitting
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        let device = self.gpu.device();
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.command_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: the pool belongs to this device and lives as long as `self`. Vulkan needs the
        // pool (and, below, the queue) externally synchronized: this relies on `submit` not
        // running on two threads at once, which `Context` being `Sync` does not prevent.
        let cmd = unsafe {
            device
                .allocate_command_buffers(&alloc)
                .call("vkAllocateCommandBuffers")?[0]
        };
        // SAFETY: an unsignalled fence on a live device; it is destroyed below in every case.
        let fence = match unsafe { device.create_fence(&vk::FenceCreateInfo::default(), None) } {
            Ok(f) => f,
            Err(e) => {
                // SAFETY: `cmd` was just allocated from this pool and never submitted.
                unsafe { device.free_command_buffers(self.command_pool, &[cmd]) };
                return Err(Error::Vulkan {
                    call: "vkCreateFence",
                    result: e,
                });
            }
        };
        let result = (|| {
            // SAFETY: `cmd` is freshly allocated (initial state) from this context's pool.
            unsafe {
                device
                    .begin_command_buffer(
                        cmd,
                        &vk::CommandBufferBeginInfo::default()
                            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                    )
                    .call("vkBeginCommandBuffer")?
            };
            let value = record(cmd)?;
            // SAFETY: `record` is done, so `cmd` is recording with nothing left open (the
            // unsafe recording functions it may call leave no render pass open); `fence` is
            // unsignalled and unused; `cmd`'s pool is of the queue's family. Waiting on the
            // fence keeps `cmd` and everything it uses alive until the GPU is done. The queue
            // must be externally synchronized: see the note at the allocation above.
            unsafe {
                device.end_command_buffer(cmd).call("vkEndCommandBuffer")?;
                let cmds = [cmd];
                let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
                device
                    .queue_submit(self.gpu.queue(), &submit, fence)
                    .call("vkQueueSubmit")?;
                device
                    .wait_for_fences(&[fence], true, u64::MAX)
                    .call("vkWaitForFences")?;
            }
            Ok(value)
        })();
        // SAFETY: either the fence wait above returned (the submission is done) or `cmd` was
        // never submitted, so neither `fence` nor `cmd` is in use; both are of this device.
        unsafe {
            device.destroy_fence(fence, None);
            device.free_command_buffers(self.command_pool, &[cmd]);
        }
        result
    }

    /// Validation messages collected so far (empty when validation is off).
    pub fn validation_messages(&self) -> Vec<String> {
        self.messages.lock().map(|m| m.clone()).unwrap_or_default()
    }

    /// `Err` if the validation layer reported anything.
    pub fn check_validation(&self) -> Result<()> {
        let m = self.validation_messages();
        if m.is_empty() {
            Ok(())
        } else {
            Err(Error::Validation(m))
        }
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        // SAFETY: `submit` frees its buffers and waits for its work, so nothing from the pool
        // is pending (the idle wait makes sure); the pool was created from this device and is
        // destroyed only here, before the `gpu` field drops.
        unsafe {
            let _ = self.gpu.device().device_wait_idle();
            self.gpu
                .device()
                .destroy_command_pool(self.command_pool, None);
        }
        if let Some(path) = &self.pipeline_cache_file {
            // A cache that cannot be written costs the next run its compiles, nothing else:
            // closing a context is no place to fail.
            let _ = save_pipeline_cache(&self.gpu, path);
        }
    }
}

/// `VkPipelineCacheHeaderVersionOne`'s size: length, version, vendor and device ids, UUID.
const CACHE_HEADER_BYTES: usize = 16 + vk::UUID_SIZE;

/// A pipeline cache seeded from `path` where the file holds this device's and driver's data
/// (its header names them), else empty; null where the driver cannot make one.
fn create_pipeline_cache(
    device: &ash::Device,
    props: &vk::PhysicalDeviceProperties,
    path: &std::path::Path,
) -> vk::PipelineCache {
    let data = std::fs::read(path).unwrap_or_default();
    let ours = data.len() >= CACHE_HEADER_BYTES && {
        let word = |i: usize| u32::from_le_bytes([data[i], data[i + 1], data[i + 2], data[i + 3]]);
        word(0) as usize >= CACHE_HEADER_BYTES
            && word(4) == vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32
            && word(8) == props.vendor_id
            && word(12) == props.device_id
            && data[16..CACHE_HEADER_BYTES] == props.pipeline_cache_uuid
    };
    let initial: &[u8] = if ours { &data } else { &[] };
    let info = vk::PipelineCacheCreateInfo::default().initial_data(initial);
    // SAFETY: `info` points at `initial`, alive across the call; its header was checked to be
    // this device's (Vulkan leaves data of another device or driver to the driver, which
    // ignores it, but an unchecked file is nothing to hand a driver).
    unsafe { device.create_pipeline_cache(&info, None) }.unwrap_or_default()
}

/// Writes the device's pipeline cache to `path` by way of a temporary file beside it.
fn save_pipeline_cache(gpu: &Gpu, path: &std::path::Path) -> std::io::Result<()> {
    // SAFETY: the cache is a live object of this device (null caches are not saved), and
    // internally synchronized (it was made without the externally-synchronized flag), so
    // pipelines that other holders of the device create meanwhile are no hazard.
    let data = unsafe { gpu.device().get_pipeline_cache_data(gpu.pipeline_cache()) }
        .map_err(std::io::Error::other)?;
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let mut temporary = path.as_os_str().to_owned();
    temporary.push(format!(".{}.tmp", std::process::id()));
    std::fs::write(&temporary, &data)?;
    std::fs::rename(&temporary, path).inspect_err(|_| {
        let _ = std::fs::remove_file(&temporary);
    })
}

/// Picks a physical device and a queue family with compute and graphics.
fn pick_device(
    instance: &ash::Instance,
    wanted: Option<&str>,
) -> Result<(vk::PhysicalDevice, u32)> {
    // SAFETY: `instance` is live (kept by the caller until it is destroyed on failure).
    let devices = unsafe {
        instance
            .enumerate_physical_devices()
            .call("vkEnumeratePhysicalDevices")?
    };
    let mut candidates = Vec::new();
    for (index, &pd) in devices.iter().enumerate() {
        // SAFETY: `pd` was just enumerated from this live instance.
        let props = unsafe { instance.get_physical_device_properties(pd) };
        // SAFETY: the same physical device of the same live instance as the query above.
        let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
        let need = vk::QueueFlags::COMPUTE | vk::QueueFlags::GRAPHICS;
        if let Some(family) = families.iter().position(|f| f.queue_flags.contains(need)) {
            candidates.push((
                index,
                pd,
                family as u32,
                props.device_type,
                device_name(&props),
            ));
        }
    }
    let names: Vec<String> = candidates
        .iter()
        .map(|c| format!("{}: {} ({:?})", c.0, c.4, c.3))
        .collect();
    if candidates.is_empty() {
        return Err(Error::NoVulkan(
            "no Vulkan device with a compute+graphics queue (install mesa-vulkan-drivers for lavapipe)".into(),
        ));
    }
    let rank = |t: vk::PhysicalDeviceType| match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    };
    let chosen = match wanted.map(|w| w.to_ascii_lowercase()) {
        None => candidates.iter().min_by_key(|c| rank(c.3)),
        Some(w) if w == "cpu" || w == "lavapipe" => candidates
            .iter()
            .find(|c| c.3 == vk::PhysicalDeviceType::CPU),
        Some(w) if w == "gpu" => candidates
            .iter()
            .filter(|c| c.3 != vk::PhysicalDeviceType::CPU)
            .min_by_key(|c| rank(c.3)),
        Some(w) => match w.parse::<usize>() {
            Ok(i) => candidates.iter().find(|c| c.0 == i),
            Err(_) => candidates
                .iter()
                .find(|c| c.4.to_ascii_lowercase().contains(&w)),
        },
    };
    let c = chosen.ok_or_else(|| {
        Error::NoVulkan(format!(
            "no Vulkan device matches: VKLENS_DEVICE={} matches none of: {}",
            wanted.unwrap_or(""),
            names.join("; ")
        ))
    })?;
    Ok((c.1, c.2))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::{shaders::COPY_COMP, ComputePipeline, SpecConstants};

    fn options(cache: &std::path::Path) -> ContextOptions {
        ContextOptions {
            validation: true,
            pipeline_cache: Some(cache.to_path_buf()),
            ..ContextOptions::from_env()
        }
    }

    fn build_copy(ctx: &Context) {
        let storage = vk::DescriptorType::STORAGE_IMAGE;
        ComputePipeline::new(
            ctx.gpu(),
            COPY_COMP,
            &[storage, storage],
            16,
            SpecConstants::new(),
        )
        .unwrap();
    }

    #[test]
    fn the_pipeline_cache_file_is_written_on_close_and_read_back() {
        let dir = std::env::temp_dir().join(format!("vklens-cache-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let file = dir.join("sub").join("pipelines.bin");
        let ctx = Context::new(options(&file)).unwrap();
        build_copy(&ctx);
        crate::testing::assert_no_validation_messages(&ctx);
        drop(ctx);
        let written = std::fs::read(&file).expect("the cache file is written on close");
        assert!(
            written.len() >= CACHE_HEADER_BYTES,
            "{} bytes",
            written.len()
        );
        // Its header names this device, so the next context is seeded with it; no temporary
        // file is left beside it.
        let ctx = Context::new(options(&file)).unwrap();
        build_copy(&ctx);
        crate::testing::assert_no_validation_messages(&ctx);
        drop(ctx);
        let names: Vec<_> = std::fs::read_dir(file.parent().unwrap())
            .unwrap()
            .flatten()
            .collect();
        assert_eq!(names.len(), 1, "{names:?}");
        // A file of another device (or none of Vulkan's) starts the cache empty.
        std::fs::write(&file, b"not a pipeline cache, and longer than a header is").unwrap();
        let ctx = Context::new(options(&file)).unwrap();
        build_copy(&ctx);
        crate::testing::assert_no_validation_messages(&ctx);
        drop(ctx);
        assert!(std::fs::read(&file).unwrap().len() >= CACHE_HEADER_BYTES);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
