//! Compute pipelines (with specialization constants) and descriptor pools.

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

use crate::error::VkCall;
use ash::vk;

use super::{Error, Gpu, Result};

/// A specialization constant: its name in the GLSL and its `constant_id`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SpecId {
    /// The name the GLSL declares it under.
    pub name: &'static str,
    /// Its `constant_id`.
    pub id: u32,
}

impl SpecId {
    /// A named id.
    pub const fn new(name: &'static str, id: u32) -> Self {
        SpecId { name, id }
    }
}

/// Specialization constants: `(constant_id, 32-bit value)` pairs. Booleans are 32-bit in
/// SPIR-V (0 or 1).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SpecConstants {
    entries: Vec<(u32, u32)>,
}

impl SpecConstants {
    pub fn new() -> Self {
        Self::default()
    }
    /// Sets a `bool` constant (again: the new value replaces the old).
    pub fn bool(self, spec: SpecId, value: bool) -> Self {
        self.set(spec, value as u32)
    }
    /// Sets a `uint`/`int` constant.
    pub fn u32(self, spec: SpecId, value: u32) -> Self {
        self.set(spec, value)
    }
    /// Sets a `float` constant.
    pub fn f32(self, spec: SpecId, value: f32) -> Self {
        self.set(spec, value.to_bits())
    }
    /// One entry per id: Vulkan refuses a specialization map that names an id twice.
    fn set(mut self, spec: SpecId, value: u32) -> Self {
        match self.entries.iter_mut().find(|(id, _)| *id == spec.id) {
            Some(entry) => entry.1 = value,
            None => self.entries.push((spec.id, value)),
        }
        self
    }
    /// The value given for `id`, if any.
    pub fn get(&self, spec: SpecId) -> Option<u32> {
        self.entries
            .iter()
            .find(|(i, _)| *i == spec.id)
            .map(|(_, v)| *v)
    }
    /// All entries, in the order set.
    pub fn entries(&self) -> &[(u32, u32)] {
        &self.entries
    }
}

/// A compute pipeline with its shader module, descriptor-set layout (set 0) and layout.
///
/// Pipelines are shared: a device keeps the last [`PipelineMemo::CAPACITY`] it built, and
/// `new` with the same SPIR-V, bindings, push size and constants hands out the one built
/// before (see [`PipelineMemo`]).
pub struct ComputePipeline {
    gpu: Gpu,
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    pub set_layout: vk::DescriptorSetLayout,
    /// The Vulkan objects, shared with the device's memo and every other `ComputePipeline`
    /// built the same; the last holder destroys them.
    _handles: Arc<ComputeHandles>,
    /// The specialization constants it was built with (what a plan can be checked against).
    pub constants: SpecConstants,
    bindings: Vec<vk::DescriptorType>,
}

/// The Vulkan objects of one compute pipeline, destroyed with the last reference.
pub(crate) struct ComputeHandles {
    device: ash::Device,
    raw: vk::Pipeline,
    layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    module: vk::ShaderModule,
}

impl ComputeHandles {
    /// Builds the module, set layout, pipeline layout and pipeline.
    fn build(
        gpu: &Gpu,
        spirv: &[u8],
        bindings: &[vk::DescriptorType],
        push_size: u32,
        constants: &SpecConstants,
    ) -> Result<Self> {
        // From here on, `handles` owns what is created, so an early return cleans up.
        let mut handles = ComputeHandles {
            device: gpu.device().clone(),
            raw: vk::Pipeline::null(),
            layout: vk::PipelineLayout::null(),
            set_layout: vk::DescriptorSetLayout::null(),
            module: shader_module(gpu, spirv)?,
        };
        let stages = vk::ShaderStageFlags::COMPUTE;
        handles.set_layout = set_layout(gpu, bindings, stages)?;
        handles.layout = pipeline_layout(gpu, handles.set_layout, push_size, stages)?;

        let (map, data) = specialization_data(constants);
        let spec = vk::SpecializationInfo::default()
            .map_entries(&map)
            .data(&data);
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(handles.module)
            .name(c"main")
            .specialization_info(&spec);
        let info = vk::ComputePipelineCreateInfo::default()
            .stage(stage)
            .layout(handles.layout);
        // SAFETY: `info` points at `stage`, `spec`, `map` and `data`, alive across the call; each
        // map entry lies inside `data` (4 bytes per constant); the module and the layout are live
        // objects of this device. On error `handles`' Drop destroys what was made.
        handles.raw = unsafe {
            gpu.device()
                .create_compute_pipelines(gpu.pipeline_cache(), &[info], None)
                .map_err(|(_, e)| e)
                .call("vkCreateComputePipelines")?[0]
        };
        Ok(handles)
    }
}

impl Drop for ComputeHandles {
    fn drop(&mut self) {
        // SAFETY: the four handles were created from this device for this pipeline and are
        // destroyed only here, by the last reference (null ones, left by a failed build, are
        // ignored by Vulkan); every `ComputePipeline` holding them is gone, and with it any
        // recording that used them, which its owner waited for.
        unsafe {
            self.device.destroy_pipeline(self.raw, None);
            self.device.destroy_pipeline_layout(self.layout, None);
            self.device
                .destroy_descriptor_set_layout(self.set_layout, None);
            self.device.destroy_shader_module(self.module, None);
        }
    }
}

/// The compute pipelines a device built last, by what they were built from: the SPIR-V bytes,
/// set 0's bindings, the push size and the specialization constants.
///
/// Building a pipeline is where a driver compiles its shader, and on a CPU driver that is
/// most of a small job's time (seconds for the rolling shutter's solve on lavapipe). Every
/// `Warper`, scene renderer or test that builds the same pipeline on the same device gets the
/// one built before. Drivers with a pipeline cache of their own cache compilations across
/// pipelines, but lavapipe's is empty; this memo holds the pipelines themselves. It keeps
/// the last [`Self::CAPACITY`] (the oldest goes first), so a process that builds pipelines
/// with ever new constants holds a bounded number.
#[derive(Default)]
pub(crate) struct PipelineMemo {
    entries: Mutex<VecDeque<MemoEntry>>,
}

struct MemoEntry {
    spirv: Box<[u8]>,
    bindings: Vec<vk::DescriptorType>,
    push_size: u32,
    constants: SpecConstants,
    /// Filled by the first thread to build it; a second asking meanwhile waits for it
    /// instead of compiling the same shader again.
    built: Arc<Mutex<Option<Arc<ComputeHandles>>>>,
}

impl PipelineMemo {
    /// How many pipelines a device keeps.
    pub const CAPACITY: usize = 64;

    /// The pipeline built from these, built now if the memo has none.
    fn get_or_build(
        &self,
        gpu: &Gpu,
        spirv: &[u8],
        bindings: &[vk::DescriptorType],
        push_size: u32,
        constants: &SpecConstants,
    ) -> Result<Arc<ComputeHandles>> {
        let slot = {
            let mut entries = self
                .entries
                .lock()
                .map_err(|_| Error::internal("the pipeline memo's lock was poisoned"))?;
            let found = entries.iter().find(|e| {
                e.push_size == push_size
                    && e.constants == *constants
                    && e.bindings == bindings
                    && *e.spirv == *spirv
            });
            match found {
                Some(e) => e.built.clone(),
                None => {
                    if entries.len() >= Self::CAPACITY {
                        entries.pop_front();
                    }
                    let built = Arc::new(Mutex::new(None));
                    entries.push_back(MemoEntry {
                        spirv: spirv.into(),
                        bindings: bindings.to_vec(),
                        push_size,
                        constants: constants.clone(),
                        built: built.clone(),
                    });
                    built
                }
            }
        };
        let mut built = slot
            .lock()
            .map_err(|_| Error::internal("a pipeline memo entry's lock was poisoned"))?;
        if let Some(handles) = built.as_ref() {
            return Ok(handles.clone());
        }
        let handles = Arc::new(ComputeHandles::build(
            gpu, spirv, bindings, push_size, constants,
        )?);
        *built = Some(handles.clone());
        Ok(handles)
    }

    /// Drops every pipeline the memo holds (those still in use live on with their users).
    pub(crate) fn clear(&self) {
        if let Ok(mut entries) = self.entries.lock() {
            entries.clear();
        }
    }
}

impl ComputePipeline {
    /// Builds a pipeline from SPIR-V whose set 0 has `bindings` (binding i has type
    /// `bindings[i]`) and whose push-constant block has `push_size` bytes, or hands out the
    /// one this device built from the same (see [`PipelineMemo`]).
    pub fn new(
        gpu: &Gpu,
        spirv: &[u8],
        bindings: &[vk::DescriptorType],
        push_size: u32,
        constants: SpecConstants,
    ) -> Result<Self> {
        let handles = gpu
            .inner
            .compute_pipelines
            .get_or_build(gpu, spirv, bindings, push_size, &constants)?;
        Ok(ComputePipeline {
            gpu: gpu.clone(),
            raw: handles.raw,
            layout: handles.layout,
            set_layout: handles.set_layout,
            _handles: handles,
            constants,
            bindings: bindings.to_vec(),
        })
    }

    /// Records a dispatch of `groups` workgroups with descriptor set `set` bound at 0 and
    /// `push` as the push constants.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass on a compute queue; `set` must match this
    /// pipeline's layout and its resources must stay alive until the work completes.
    pub unsafe fn record_dispatch(
        &self,
        cmd: vk::CommandBuffer,
        set: vk::DescriptorSet,
        push: &[u8],
        groups: (u32, u32),
    ) {
        // SAFETY: the caller upholds `record_dispatch`'s contract, which `bind` shares.
        unsafe {
            self.bind(cmd, set, push);
            self.gpu.device().cmd_dispatch(cmd, groups.0, groups.1, 1);
        }
    }

    /// Records a dispatch whose workgroup counts the GPU reads from `args` at `offset` (a
    /// `VkDispatchIndirectCommand`), with `set` bound at 0 and `push` as the push constants.
    ///
    /// # Safety
    /// As [`Self::record_dispatch`]; `args` must have been made with `INDIRECT_BUFFER` usage,
    /// hold the command at `offset` (a multiple of 4) when the dispatch executes, with counts
    /// within the device's limits, and stay alive until the work completes.
    pub unsafe fn record_dispatch_indirect(
        &self,
        cmd: vk::CommandBuffer,
        set: vk::DescriptorSet,
        push: &[u8],
        args: &super::Buffer,
        offset: u64,
    ) {
        // SAFETY: the caller upholds this function's contract (`record_dispatch`'s, which
        // `bind` shares, and the indirect buffer's).
        unsafe {
            self.bind(cmd, set, push);
            self.gpu
                .device()
                .cmd_dispatch_indirect(cmd, args.raw, offset);
        }
    }

    /// Binds the pipeline and `set`, and pushes `push` (none when empty).
    ///
    /// # Safety
    /// As [`Self::record_dispatch`].
    unsafe fn bind(&self, cmd: vk::CommandBuffer, set: vk::DescriptorSet, push: &[u8]) {
        let d = self.gpu.device();
        // SAFETY: the caller upholds `record_dispatch`'s contract: `cmd` is recording outside a
        // render pass on a compute queue and `set` matches this layout. `push` must fit the push
        // range: each pass pushes the struct whose size it built the pipeline with.
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.raw);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                self.layout,
                0,
                &[set],
                &[],
            );
            if !push.is_empty() {
                d.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::COMPUTE, 0, push);
            }
        }
    }

    /// Descriptor types of set 0, by binding.
    pub fn bindings(&self) -> &[vk::DescriptorType] {
        &self.bindings
    }
}

/// A pipeline's descriptor set 0: its layout and the type of each binding.
pub trait DescriptorLayout {
    fn set_layout(&self) -> vk::DescriptorSetLayout;
    fn binding_types(&self) -> &[vk::DescriptorType];
}

impl DescriptorLayout for ComputePipeline {
    fn set_layout(&self) -> vk::DescriptorSetLayout {
        self.set_layout
    }
    fn binding_types(&self) -> &[vk::DescriptorType] {
        &self.bindings
    }
}

/// Set 0's layout: binding i has type `bindings[i]`, one descriptor, visible to `stages`.
pub(crate) fn set_layout(
    gpu: &Gpu,
    bindings: &[vk::DescriptorType],
    stages: vk::ShaderStageFlags,
) -> Result<vk::DescriptorSetLayout> {
    let layout_bindings: Vec<_> = bindings
        .iter()
        .enumerate()
        .map(|(i, &ty)| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(i as u32)
                .descriptor_type(ty)
                .descriptor_count(1)
                .stage_flags(stages)
        })
        .collect();
    // SAFETY: the create info points at `layout_bindings` (binding i of type `bindings[i]`,
    // one descriptor each, distinct binding numbers), alive across the call.
    Ok(unsafe {
        gpu.device()
            .create_descriptor_set_layout(
                &vk::DescriptorSetLayoutCreateInfo::default().bindings(&layout_bindings),
                None,
            )
            .call("vkCreateDescriptorSetLayout")?
    })
}

/// A pipeline layout of one set and `push_size` bytes of push constants (0: none) for `stages`.
pub(crate) fn pipeline_layout(
    gpu: &Gpu,
    set_layout: vk::DescriptorSetLayout,
    push_size: u32,
    stages: vk::ShaderStageFlags,
) -> Result<vk::PipelineLayout> {
    let ranges = [vk::PushConstantRange {
        stage_flags: stages,
        offset: 0,
        size: push_size,
    }];
    let set_layouts = [set_layout];
    let mut info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
    if push_size > 0 {
        info = info.push_constant_ranges(&ranges);
    }
    // SAFETY: `set_layout` is a live layout of this device (the caller just made it); the
    // create info points at locals alive across the call, and the push range is only passed
    // when non-empty, as Vulkan needs a non-zero size.
    Ok(unsafe {
        gpu.device()
            .create_pipeline_layout(&info, None)
            .call("vkCreatePipelineLayout")?
    })
}

/// A shader module from SPIR-V bytes.
pub(crate) fn shader_module(gpu: &Gpu, spirv: &[u8]) -> Result<vk::ShaderModule> {
    let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv))
        .map_err(|e| Error::internal(format!("bad SPIR-V: {e}")))?;
    // SAFETY: `read_spv` gave u32-aligned words (code size a multiple of 4), alive across the
    // call. Vulkan needs valid SPIR-V: every caller in the crate passes one of vklens's own
    // compiled shaders, though the safe `ComputePipeline::new` / `GraphicsPipeline::new` would
    // accept any bytes.
    Ok(unsafe {
        gpu.device()
            .create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None)
            .call("vkCreateShaderModule")?
    })
}

/// `constants` as Vulkan specialization data: (map entries, bytes). Every constant is 4 bytes.
pub(crate) fn specialization_data(
    constants: &SpecConstants,
) -> (Vec<vk::SpecializationMapEntry>, Vec<u8>) {
    let map = constants
        .entries()
        .iter()
        .enumerate()
        .map(|(i, (id, _))| vk::SpecializationMapEntry {
            constant_id: *id,
            offset: (i * 4) as u32,
            size: 4,
        })
        .collect();
    let data = constants
        .entries()
        .iter()
        .flat_map(|(_, v)| v.to_ne_bytes())
        .collect();
    (map, data)
}

/// A descriptor pool sized for `sets` sets of one pipeline's layout; sets are freed with it.
pub struct DescriptorPool {
    gpu: Gpu,
    pub raw: vk::DescriptorPool,
}

impl DescriptorPool {
    pub fn for_pipeline(gpu: &Gpu, pipeline: &impl DescriptorLayout, sets: u32) -> Result<Self> {
        let mut sizes: Vec<vk::DescriptorPoolSize> = Vec::new();
        for &ty in pipeline.binding_types() {
            match sizes.iter_mut().find(|s| s.ty == ty) {
                Some(s) => s.descriptor_count += sets,
                None => sizes.push(vk::DescriptorPoolSize {
                    ty,
                    descriptor_count: sets,
                }),
            }
        }
        let info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(sets)
            .pool_sizes(&sizes);
        // SAFETY: `info` points at `sizes` (one entry per descriptor type), alive across the
        // call. Vulkan needs `sets` > 0; every caller passes at least 1.
        let raw = unsafe {
            gpu.device()
                .create_descriptor_pool(&info, None)
                .call("vkCreateDescriptorPool")?
        };
        Ok(DescriptorPool {
            gpu: gpu.clone(),
            raw,
        })
    }

    /// Allocates one set of `pipeline`'s layout.
    pub fn allocate(&self, pipeline: &impl DescriptorLayout) -> Result<vk::DescriptorSet> {
        let layouts = [pipeline.set_layout()];
        let info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.raw)
            .set_layouts(&layouts);
        // SAFETY: the pool and `pipeline`'s set layout are live objects of this device; a pool
        // out of sets or descriptors returns an error. Vulkan needs the pool externally
        // synchronized: this `&self` method relies on no two threads allocating at once.
        Ok(unsafe {
            self.gpu
                .device()
                .allocate_descriptor_sets(&info)
                .call("vkAllocateDescriptorSets")?[0]
        })
    }
}

impl Drop for DescriptorPool {
    fn drop(&mut self) {
        // SAFETY: created from this device and destroyed only here, which also frees its sets;
        // no pending work still uses them.
        unsafe { self.gpu.device().destroy_descriptor_pool(self.raw, None) };
    }
}

/// Points the bindings of `set` at whole buffers: `(binding, descriptor type, buffer)`.
///
/// # Safety
/// `set` is a live descriptor set of this device with these bindings of these types, and no
/// pending work uses it (Vulkan forbids updating a set a pending command buffer uses).
pub unsafe fn write_buffer_descriptors(
    gpu: &Gpu,
    set: vk::DescriptorSet,
    bindings: &[(u32, vk::DescriptorType, &super::Buffer)],
) {
    let infos: Vec<[vk::DescriptorBufferInfo; 1]> = bindings
        .iter()
        .map(|(_, _, b)| {
            [vk::DescriptorBufferInfo {
                buffer: b.raw,
                offset: 0,
                range: vk::WHOLE_SIZE,
            }]
        })
        .collect();
    let writes: Vec<vk::WriteDescriptorSet> = bindings
        .iter()
        .zip(&infos)
        .map(|((binding, ty, _), info)| {
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(*binding)
                .descriptor_type(*ty)
                .buffer_info(info)
        })
        .collect();
    // SAFETY: `writes` points at `infos`, both alive across the call, and every buffer is a
    // live vklens `Buffer`; `set` is live, has these bindings and is unused by pending work
    // (the function's contract).
    unsafe { gpu.device().update_descriptor_sets(&writes, &[]) };
}

/// Points `binding` of `set` at a sampled image (in `SHADER_READ_ONLY_OPTIMAL`) with `sampler`.
///
/// # Safety
/// `set` is a live descriptor set of this device with a combined image sampler at `binding`,
/// `view` a live view of this device, and no pending work uses `set`.
pub unsafe fn write_sampled_image_descriptor(
    gpu: &Gpu,
    set: vk::DescriptorSet,
    binding: u32,
    sampler: &super::Sampler,
    view: vk::ImageView,
) {
    let info = [vk::DescriptorImageInfo {
        sampler: sampler.raw,
        image_view: view,
        image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
    }];
    let write = vk::WriteDescriptorSet::default()
        .dst_set(set)
        .dst_binding(binding)
        .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
        .image_info(&info);
    // SAFETY: `write` points at `info`, alive across the call; `sampler` is a live vklens
    // sampler; `set`, `binding` and `view` are as the function's contract says.
    unsafe { gpu.device().update_descriptor_sets(&[write], &[]) };
}

/// Points the bindings of `set` at storage images in `GENERAL` layout: `(binding, view)`.
///
/// # Safety
/// `set` is a live descriptor set of this device whose `binding`s are storage images, the
/// views are live views of this device, and no pending work uses `set`.
pub unsafe fn write_storage_image_descriptors(
    gpu: &Gpu,
    set: vk::DescriptorSet,
    bindings: &[(u32, vk::ImageView)],
) {
    let infos: Vec<[vk::DescriptorImageInfo; 1]> = bindings
        .iter()
        .map(|(_, view)| {
            [vk::DescriptorImageInfo {
                sampler: vk::Sampler::null(),
                image_view: *view,
                image_layout: vk::ImageLayout::GENERAL,
            }]
        })
        .collect();
    let writes: Vec<vk::WriteDescriptorSet> = bindings
        .iter()
        .zip(&infos)
        .map(|((binding, _), info)| {
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(*binding)
                .descriptor_type(vk::DescriptorType::STORAGE_IMAGE)
                .image_info(info)
        })
        .collect();
    // SAFETY: `writes` points at `infos`, both alive across the call; `set`, the bindings and
    // the views are as the function's contract says.
    unsafe { gpu.device().update_descriptor_sets(&writes, &[]) };
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::shaders::COPY_COMP;
    use crate::pass::spec::NEAREST;

    fn copy(gpu: &Gpu, constants: SpecConstants) -> ComputePipeline {
        let storage = vk::DescriptorType::STORAGE_IMAGE;
        ComputePipeline::new(gpu, COPY_COMP, &[storage, storage], 16, constants).unwrap()
    }

    #[test]
    fn a_pipeline_built_twice_is_built_once_and_outlives_its_memo_entry() {
        // A device of its own: the memo's contents are this test's alone.
        let ctx = crate::testing::new_validated_context();
        let gpu = ctx.gpu();
        let a = copy(gpu, SpecConstants::new());
        let b = copy(gpu, SpecConstants::new());
        assert_eq!(
            a.raw, b.raw,
            "the same SPIR-V and constants: the same pipeline"
        );
        let c = copy(gpu, SpecConstants::new().bool(NEAREST, true));
        assert_ne!(a.raw, c.raw, "other constants: another pipeline");
        // The same bytes from another address are the same shader.
        let moved = COPY_COMP.to_vec();
        let storage = vk::DescriptorType::STORAGE_IMAGE;
        let d = ComputePipeline::new(gpu, &moved, &[storage, storage], 16, SpecConstants::new())
            .unwrap();
        assert_eq!(a.raw, d.raw);
        // Past the capacity the oldest entry goes; the pipelines built from it stay usable and
        // a new request builds anew.
        let held = a.raw;
        for i in 0..PipelineMemo::CAPACITY as u32 {
            copy(
                gpu,
                SpecConstants::new().u32(SpecId::new("UNUSED", 100 + i), 1),
            );
        }
        let e = copy(gpu, SpecConstants::new());
        assert_ne!(e.raw, held, "evicted: built again");
        assert_eq!(a.raw, held);
        drop((b, c, d, e));
        drop(a);
        crate::testing::assert_no_validation_messages(&ctx);
    }
}
