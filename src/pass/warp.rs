//! The post-processing warp (`glsl/warp.comp`) and its coordinate maps
//! (`glsl/inverse_map.comp`).
//!
//! Build a [`WarpPass`] once per camera and format. Then, in the caller's command buffer:
//! [`WarpPass::record_prepare`] once (builds the maps in map mode), then
//! [`WarpPass::record`] every frame. Images are the caller's: storage images in `GENERAL`
//! layout, bound with [`WarpPass::bind`].

use crate::pass::spec;
use ash::vk;
use bytemuck::{Pod, Zeroable};

use super::camera_params::CameraParams;
use crate::gpu::{
    global_barrier, shaders, write_buffer_descriptors, write_storage_image_descriptors, Access,
    Buffer, ComputePipeline, DescriptorPool, Error, Gpu, Image, Result,
};
use crate::imaging::cpu_warp::{Border, Sampling};
use crate::imaging::{Pixels, Raster};
pub use crate::model::warp::MapInterpolation;
use crate::model::warp::{coarse_cells, coarse_size, Direction, WarpGeometry};
use crate::model::{InverseMethod, Terms};

/// How output pixels get their source coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coordinates {
    /// Solve the model per pixel every frame.
    Analytic,
    /// Sample a map built once per camera (RG32F per channel) with the same code.
    Map,
    /// Sample a map built from a coarse one: every `stride`-th pixel solved exactly, the rest
    /// interpolated (`interpolation`), then `refine` Newton steps (distort only). Next to a
    /// fold, validity is conservative by up to one coarse cell (`Map` is exact there).
    CoarseMap {
        stride: u32,
        refine: u32,
        interpolation: MapInterpolation,
    },
}

impl Coordinates {
    /// Whether the warp samples a map.
    pub fn uses_map(self) -> bool {
        !matches!(self, Coordinates::Analytic)
    }
}

/// The pixel format of the source and output images.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PixelFormat {
    /// `R8G8B8A8_UNORM` (8-bit data).
    Rgba8,
    /// `R32G32B32A32_SFLOAT` (16-bit and float data).
    Rgba32F,
    /// `R32_UINT` (object IDs; nearest only, never blended).
    R32Uint,
    /// `R32_SFLOAT` (depth; nearest only: +inf where nothing was drawn must not be blended).
    /// Headless rasters carry it as RGBA32F, channel 0.
    R32Float,
}

impl PixelFormat {
    /// The Vulkan format.
    pub fn vk(self) -> vk::Format {
        match self {
            PixelFormat::Rgba8 => vk::Format::R8G8B8A8_UNORM,
            PixelFormat::Rgba32F => vk::Format::R32G32B32A32_SFLOAT,
            PixelFormat::R32Uint => vk::Format::R32_UINT,
            PixelFormat::R32Float => vk::Format::R32_SFLOAT,
        }
    }
    /// Bytes per pixel.
    pub fn bytes(self) -> usize {
        match self {
            PixelFormat::Rgba8 | PixelFormat::R32Uint | PixelFormat::R32Float => 4,
            PixelFormat::Rgba32F => 16,
        }
    }
    /// The format that holds `raster` without loss.
    pub fn of(raster: &Raster) -> Self {
        match raster.pixels {
            Pixels::Rgba8(_) => PixelFormat::Rgba8,
            Pixels::Rgba32F(_) => PixelFormat::Rgba32F,
            Pixels::R32Uint(_) => PixelFormat::R32Uint,
        }
    }
}

/// Everything a warp pass is built from.
#[derive(Debug, Clone)]
pub struct WarpDesc {
    pub geometry: WarpGeometry,
    pub coordinates: Coordinates,
    pub sampling: Sampling,
    /// What source positions off the source image read.
    pub border: Border,
    pub format: PixelFormat,
    /// Value of pixels without a source (transparent black by default; for IDs, `.x` is the ID).
    pub fill: [f32; 4],
    /// Write the validity mask (an extra store per pixel; the mask image is bound either way).
    pub write_mask: bool,
}

/// `WarpPush` / `MapPush` of the shaders (same layout).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable, Debug)]
pub struct WarpPush {
    /// fx fy cx cy of the pinhole side.
    pub ideal: [f32; 4],
    /// Per-channel magnification R G B (map builds: .x is this channel's).
    pub chromatic: [f32; 4],
    /// Fill value.
    pub fill: [f32; 4],
    /// Source w h, output w h.
    pub sizes: [u32; 4],
    /// Columns of the homography Rᵀ·K_out⁻¹ from an output pixel to the lens camera's ray
    /// (undistort with a rectification rotation; `w` unused).
    pub rectify: [[f32; 4]; 3],
    /// The output pixels a dispatch of the warp covers: columns x0..x1, rows y0..y1 as
    /// `[x0, y0, x1, y1]` (the whole output, or a band of a rolling shutter's lines; the map
    /// builds ignore it).
    pub band: [u32; 4],
}

// Within the 128 bytes of push constants every device offers.
const _: () = assert!(std::mem::size_of::<WarpPush>() == 128);

const MAP_FORMAT: vk::Format = vk::Format::R32G32_SFLOAT;
/// Largest forward residual (px) a coarse-map pixel may have before it is marked invalid.
pub const COARSE_MAX_RESIDUAL_PX: f32 = 0.05;
/// Most frames in flight a warp keeps descriptor sets for (triple buffering and then some).
pub const MAX_FRAMES_IN_FLIGHT: usize = 8;

/// Map images per channel in shader binding order: R (5), G (4), B (6) → stored as [R, G, B].
const MAP_BINDINGS: [u32; 3] = [5, 4, 6];

/// One dispatch of a map build; a barrier follows when the next step reads its output.
struct MapStep {
    pipeline: usize,
    set: vk::DescriptorSet,
    push: WarpPush,
    groups: (u32, u32),
    barrier_after: bool,
}

/// The warp, built for one geometry, format and sampling.
pub struct WarpPass {
    gpu: Gpu,
    desc: WarpDesc,
    pipeline: ComputePipeline,
    _pool: DescriptorPool,
    /// One descriptor set per frame in flight (librashader's frame residuals): a caller may
    /// bind other images for the next frame while the previous one still reads its set.
    sets: Vec<vk::DescriptorSet>,
    /// The set [`WarpPass::bind`] writes and [`WarpPass::record`] uses.
    slot: usize,
    _camera: Buffer,
    /// [R, G, B] maps (1×1 placeholders in analytic mode; only G without chromatic).
    pub(crate) maps: Vec<Image>,
    map_pipelines: Vec<ComputePipeline>,
    _map_pool: Option<DescriptorPool>,
    _map_cameras: Vec<Buffer>,
    _coarse: Vec<Image>,
    map_steps: Vec<MapStep>,
    push: WarpPush,
}

fn method_constants(method: InverseMethod) -> (u32, u32) {
    match method {
        InverseMethod::Newton => (0, 1),
        InverseMethod::Heikkila => (1, 1),
        InverseMethod::FixedPoint(n) => (2, n),
    }
}

fn f4(v: [f64; 4]) -> [f32; 4] {
    v.map(|x| x as f32)
}

/// Refuses a warp description the shaders cannot run.
fn check_desc(gpu: &Gpu, desc: &WarpDesc) -> Result<()> {
    let g = &desc.geometry;
    if matches!(desc.format, PixelFormat::R32Uint | PixelFormat::R32Float)
        && (desc.sampling != Sampling::Nearest || g.is_chromatic())
    {
        return Err(Error::Input(
                "object IDs (R32_UINT) and depth (R32_SFLOAT) are sampled nearest and without chromatic aberration".into(),
            ));
    }
    if let Coordinates::CoarseMap { stride, refine, .. } = desc.coordinates {
        if !(2..=64).contains(&stride) || refine > 8 || g.direction != Direction::Distort {
            return Err(Error::Input(
                    "a coarse map needs the distort direction, a stride in 2..=64 and at most 8 refinement steps".into(),
                ));
        }
    }
    if g.channel_cameras.is_some() && desc.coordinates == Coordinates::Analytic {
        return Err(Error::Input(
            "per-channel cameras need precomputed maps (Coordinates::Map)".into(),
        ));
    }
    check_sizes(gpu, g)
}

/// The upsampler's workgroup in coarse cells (`local_size` of `glsl/upsample_map.comp`).
pub const UPSAMPLE_GROUP: [u32; 2] = [32, 2];

/// The spec constants the warp and map shaders share for a camera's (or the channels'
/// union of) terms: direction, inverse method, rectification, and whether the domain's
/// table is read.
fn model_constants(g: &WarpGeometry, terms: Terms) -> crate::gpu::SpecConstants {
    let (method, iterations) = method_constants(g.method);
    CameraParams::spec_constants(terms)
        .u32(spec::MODE, direction_mode(g))
        .u32(spec::METHOD, method)
        .u32(spec::FIXED_POINT_ITERATIONS, iterations)
        .bool(spec::RECTIFY, g.output_to_ray().is_some())
        .bool(spec::DOMAIN_TABLE, reads_domain_table(g))
}

/// Whether the shaders' test of an ideal point against the valid domain needs the domain's
/// table, or its smallest boundary radius alone gives every answer the table would; then the
/// lookup is compiled out (lavapipe runs both sides of a branch, so an atan and two indexed
/// reads cost it per test whether taken or not). Two cases:
/// - a round domain (a lens that never folds before the radius cap, or a radially symmetric
///   one): every entry of its table is that radius; both directions, the inverse testing each
///   Newton iterate;
/// - an undistort warp whose output pixels all lie inside the radius (the corners bound them:
///   the output is a pinhole image, or a rectified one whose homography keeps every corner in
///   front of the lens), with a margin that keeps f32's rounding from turning an answer.
///
/// The inverse's radial start reads the table for its bracket either way.
fn reads_domain_table(g: &WarpGeometry) -> bool {
    if g.channel_cameras.is_some() {
        return true;
    }
    let domain = g.camera.shader_domain();
    // A round domain's table holds its smallest radius in every entry: the lookup would
    // only repeat the inner test (both directions; the inverse tests every Newton iterate).
    if domain.is_round() {
        return false;
    }
    if g.direction != Direction::Undistort {
        return true;
    }
    let inner = domain.min_ideal_radius();
    let (w, h) = (g.output_size.0 as f64 - 1.0, g.output_size.1 as f64 - 1.0);
    let to_ray = g.output_to_ray();
    let i = &g.ideal;
    let mut largest: f64 = 0.0;
    for (u, v) in [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)] {
        let x = match to_ray {
            Some(m) => {
                let ray = m * glam::DVec3::new(u, v, 1.0);
                if !(ray.z > 0.0) {
                    return true;
                }
                glam::DVec2::new(ray.x / ray.z, ray.y / ray.z)
            }
            None => glam::DVec2::new((u - i.cx) / i.fx, (v - i.cy) / i.fy),
        };
        largest = largest.max(x.length());
    }
    !(largest <= inner * (1.0 - 1e-4))
}

/// The shaders' `MODE`: 0 distort (the inverse per pixel), 1 undistort (the forward model).
fn direction_mode(g: &WarpGeometry) -> u32 {
    match g.direction {
        Direction::Distort => 0,
        Direction::Undistort => 1,
    }
}

/// The warp's own pipeline: the shader variant for the pixel format and direction, specialized
/// for the camera's terms, the sampling, the border and the mask.
fn warp_pipeline(gpu: &Gpu, desc: &WarpDesc) -> Result<ComputePipeline> {
    let g = &desc.geometry;
    let mode = direction_mode(g);
    let constants = model_constants(g, g.camera.terms())
        .bool(spec::CHROMATIC, g.is_chromatic())
        .bool(spec::USE_MAP, desc.coordinates.uses_map())
        .bool(spec::NEAREST, desc.sampling == Sampling::Nearest)
        .bool(spec::BICUBIC, desc.sampling == Sampling::Bicubic)
        .u32(spec::BORDER, desc.border.gpu_id())
        .bool(spec::WRITE_MASK, desc.write_mask);
    // The module of the camera's model alone (the one its `MODEL` constant names).
    let by_model = match desc.format {
        PixelFormat::Rgba8 if mode == 1 => &shaders::WARP_COMP_RGBA8_FORWARD_BY_MODEL,
        PixelFormat::Rgba8 => &shaders::WARP_COMP_RGBA8_BY_MODEL,
        PixelFormat::Rgba32F if mode == 1 => &shaders::WARP_COMP_FORWARD_BY_MODEL,
        PixelFormat::Rgba32F => &shaders::WARP_COMP_BY_MODEL,
        PixelFormat::R32Uint => &shaders::WARP_COMP_R32UI_BY_MODEL,
        PixelFormat::R32Float => &shaders::WARP_COMP_R32F_BY_MODEL,
    };
    let spirv = by_model[g.camera.model().gpu_id() as usize];
    let storage = vk::DescriptorType::STORAGE_IMAGE;
    ComputePipeline::new(
        gpu,
        spirv,
        &[
            vk::DescriptorType::UNIFORM_BUFFER,
            storage,
            storage,
            storage,
            storage,
            storage,
            storage,
        ],
        std::mem::size_of::<WarpPush>() as u32,
        constants,
    )
}

/// The warp's push constants: the ideal camera, the channels' scales, the fill, the sizes,
/// the rectification and the whole output as the band.
fn warp_push(desc: &WarpDesc) -> WarpPush {
    let g = &desc.geometry;
    let scales = g.chromatic.unwrap_or([1.0; 3]);
    let k = &g.ideal;
    WarpPush {
        ideal: f4([k.fx, k.fy, k.cx, k.cy]),
        chromatic: f4([scales[0], scales[1], scales[2], 1.0]),
        fill: desc.fill,
        sizes: [
            g.source_size.0,
            g.source_size.1,
            g.output_size.0,
            g.output_size.1,
        ],
        rectify: g.output_to_ray().map_or([[0.0; 4]; 3], |h| {
            [h.x_axis, h.y_axis, h.z_axis].map(|c| f4([c.x, c.y, c.z, 0.0]))
        }),
        band: [0, 0, g.output_size.0, g.output_size.1],
    }
}

/// Map images usable as storage and copied out (`read_maps`: tests, benches and engines that
/// cache them).
const MAP_USAGE: vk::ImageUsageFlags = vk::ImageUsageFlags::from_raw(
    vk::ImageUsageFlags::STORAGE.as_raw() | vk::ImageUsageFlags::TRANSFER_SRC.as_raw(),
);

/// The [R, G, B] maps: real ones in map mode (one per channel that differs), 1×1
/// placeholders otherwise (the bindings exist in every variant).
fn map_images(gpu: &Gpu, desc: &WarpDesc) -> Result<Vec<Image>> {
    let g = &desc.geometry;
    let (mw, mh) = if desc.coordinates.uses_map() {
        g.output_size
    } else {
        (1, 1)
    };
    (0..3)
        .map(|c| {
            let real = desc.coordinates.uses_map() && (c == 1 || g.is_chromatic());
            let (w, h) = if real { (mw, mh) } else { (1, 1) };
            Image::new_2d(gpu, "warp.map", MAP_FORMAT, w, h, MAP_USAGE)
        })
        .collect()
}

/// What map mode adds to a warp: the map pipelines (the solve, and the upsampler of a coarse
/// map), their sets' pool, each channel's camera, the coarse images and the recorded steps.
#[derive(Default)]
struct MapParts {
    pipelines: Vec<ComputePipeline>,
    pool: Option<DescriptorPool>,
    cameras: Vec<Buffer>,
    coarse: Vec<Image>,
    steps: Vec<MapStep>,
}

impl MapParts {
    fn new(gpu: &Gpu, desc: &WarpDesc, maps: &[Image], push: WarpPush) -> Result<Self> {
        let g = &desc.geometry;
        let chromatic = g.is_chromatic();
        let storage = vk::DescriptorType::STORAGE_IMAGE;
        let mut map_pipelines = Vec::new();
        let channels: Vec<usize> = if chromatic { vec![0, 1, 2] } else { vec![1] };
        // One pipeline serves every channel: the union of their term groups.
        let terms = channels
            .iter()
            .map(|&c| g.channel_camera(c).terms())
            .fold(Terms::default(), Terms::union);
        let base = model_constants(g, terms);
        let (stride, refine, interpolation) = match desc.coordinates {
            Coordinates::CoarseMap {
                stride,
                refine,
                interpolation,
            } => (stride, refine, interpolation),
            _ => (1, 0, MapInterpolation::Bilinear),
        };
        let uniform = vk::DescriptorType::UNIFORM_BUFFER;
        // The modules of the channels' model alone (the one the `MODEL` constant names).
        let model = terms.model.gpu_id() as usize;
        map_pipelines.push(ComputePipeline::new(
            gpu,
            shaders::INVERSE_MAP_COMP_BY_MODEL[model],
            &[uniform, storage],
            std::mem::size_of::<WarpPush>() as u32,
            base.clone().u32(spec::STRIDE, stride),
        )?);
        if stride > 1 {
            // The per-pixel forward check is compiled out when the host's f64 estimate says
            // interpolation cannot reach the tolerance (and no fold is in view).
            let check = g
                .coarse_interpolation_error(stride, interpolation)
                .is_none_or(|e| e > 0.5 * COARSE_MAX_RESIDUAL_PX as f64);
            map_pipelines.push(ComputePipeline::new(
                gpu,
                shaders::UPSAMPLE_MAP_COMP_BY_MODEL[model],
                &[uniform, storage, storage],
                std::mem::size_of::<WarpPush>() as u32,
                base.u32(spec::STRIDE, stride)
                    .u32(spec::REFINE, refine)
                    .f32(spec::MAX_RESIDUAL_PX, COARSE_MAX_RESIDUAL_PX)
                    .bool(spec::CHECK_RESIDUAL, check)
                    .bool(spec::CUBIC, interpolation == MapInterpolation::Cubic),
            )?);
        }
        let steps_per_channel = if stride > 1 { 2 } else { 1 };
        let mpool = DescriptorPool::for_pipeline(
            gpu,
            &map_pipelines[map_pipelines.len() - 1],
            (channels.len() * steps_per_channel) as u32,
        )?;
        let (ow, oh) = g.output_size;
        let (cw, ch) = coarse_size((ow, oh), stride);
        let (cells_x, cells_y) = coarse_cells((ow, oh), stride);
        let mut parts = MapParts {
            pipelines: map_pipelines,
            ..MapParts::default()
        };
        for &c in &channels {
            let cam = Buffer::from_pod(
                gpu,
                "warp.map.camera",
                &[CameraParams::from_camera(g.channel_camera(c))],
                vk::BufferUsageFlags::UNIFORM_BUFFER,
            )?;
            let mut p = push;
            p.chromatic = [g.channel_scale(c) as f32, 0.0, 0.0, 0.0];
            if stride == 1 {
                parts.solve_step(gpu, &mpool, &cam, maps[c].view, p, (ow, oh), false)?;
            } else {
                let coarse = Image::new_2d(gpu, "warp.map.coarse", MAP_FORMAT, cw, ch, MAP_USAGE)?;
                let mut cp = p;
                cp.sizes = [p.sizes[0], p.sizes[1], cw, ch];
                parts.solve_step(gpu, &mpool, &cam, coarse.view, cp, (cw, ch), true)?;
                let up = mpool.allocate(&parts.pipelines[1])?;
                // SAFETY: the set was just allocated from a pool made for this pipeline's
                // layout, so no work uses it yet; the buffers and views are this pass's
                // own, alive.
                unsafe { write_buffer_descriptors(gpu, up, &[(0, uniform, &cam)]) };
                // SAFETY: as above.
                unsafe {
                    write_storage_image_descriptors(gpu, up, &[(1, coarse.view), (2, maps[c].view)])
                };
                parts.steps.push(MapStep {
                    pipeline: 1,
                    set: up,
                    push: p,
                    // One invocation per coarse cell (glsl/upsample_map.comp).
                    groups: (
                        cells_x.div_ceil(UPSAMPLE_GROUP[0]),
                        cells_y.div_ceil(UPSAMPLE_GROUP[1]),
                    ),
                    barrier_after: false,
                });
                parts.coarse.push(coarse);
            }
            parts.cameras.push(cam);
        }
        parts.pool = Some(mpool);
        Ok(parts)
    }

    /// A step of the map solve (`pipelines[0]`): `cam`'s inverse per pixel of a `size` map
    /// into `target`, a barrier after it where the upsampler reads it next.
    #[allow(clippy::too_many_arguments)]
    fn solve_step(
        &mut self,
        gpu: &Gpu,
        pool: &DescriptorPool,
        cam: &Buffer,
        target: vk::ImageView,
        push: WarpPush,
        size: (u32, u32),
        barrier_after: bool,
    ) -> Result<()> {
        let set = pool.allocate(&self.pipelines[0])?;
        let uniform = vk::DescriptorType::UNIFORM_BUFFER;
        // SAFETY: the set was just allocated from a pool made for this pipeline's layout, so
        // no work uses it yet; the buffers and views are this pass's own, alive.
        unsafe { write_buffer_descriptors(gpu, set, &[(0, uniform, cam)]) };
        // SAFETY: as above.
        unsafe { write_storage_image_descriptors(gpu, set, &[(1, target)]) };
        self.steps.push(MapStep {
            pipeline: 0,
            set,
            push,
            groups: (size.0.div_ceil(8), size.1.div_ceil(8)),
            barrier_after,
        });
        Ok(())
    }
}

impl WarpPass {
    /// Builds the pipelines (terms the camera does not use are compiled out; the single-fetch
    /// variant when there is no chromatic aberration) and, in map mode, the map images.
    pub fn new(gpu: &Gpu, desc: WarpDesc) -> Result<Self> {
        Self::with_frames(gpu, desc, 1)
    }

    /// As [`WarpPass::new`], with `frames` descriptor sets (at least one): one per frame in
    /// flight, chosen by [`WarpPass::select_frame`].
    pub fn with_frames(gpu: &Gpu, desc: WarpDesc, frames: usize) -> Result<Self> {
        let frames = frames.clamp(1, MAX_FRAMES_IN_FLIGHT);
        check_desc(gpu, &desc)?;
        let g = &desc.geometry;
        let pipeline = warp_pipeline(gpu, &desc)?;
        let pool = DescriptorPool::for_pipeline(gpu, &pipeline, frames as u32)?;
        let sets = (0..frames)
            .map(|_| pool.allocate(&pipeline))
            .collect::<Result<Vec<_>>>()?;
        let camera = Buffer::from_pod(
            gpu,
            "warp.camera",
            &[CameraParams::from_camera(&g.camera)],
            vk::BufferUsageFlags::UNIFORM_BUFFER,
        )?;
        for &set in &sets {
            // SAFETY: the set was just allocated from a pool made for this pipeline's layout,
            // so no work uses it yet; the buffers and views are this pass's own, alive.
            unsafe {
                write_buffer_descriptors(
                    gpu,
                    set,
                    &[(0, vk::DescriptorType::UNIFORM_BUFFER, &camera)],
                )
            };
        }
        let push = warp_push(&desc);
        let maps = map_images(gpu, &desc)?;
        let map_views: Vec<(u32, vk::ImageView)> =
            (0..3).map(|c| (MAP_BINDINGS[c], maps[c].view)).collect();
        for &set in &sets {
            // SAFETY: the set was just allocated from a pool made for this pipeline's layout,
            // so no work uses it yet; the buffers and views are this pass's own, alive.
            unsafe { write_storage_image_descriptors(gpu, set, &map_views) };
        }
        let map = if desc.coordinates.uses_map() {
            MapParts::new(gpu, &desc, &maps, push)?
        } else {
            MapParts::default()
        };
        Ok(WarpPass {
            gpu: gpu.clone(),
            desc,
            pipeline,
            _pool: pool,
            sets,
            slot: 0,
            _camera: camera,
            maps,
            map_pipelines: map.pipelines,
            _map_pool: map.pool,
            _map_cameras: map.cameras,
            _coarse: map.coarse,
            map_steps: map.steps,
            push,
        })
    }

    /// Switches an analytic warp to another geometry with the same sizes, direction,
    /// method, chromatic scales and distortion terms (all compiled in) — e.g. the same lens
    /// with its image translated (jittered passes) — without rebuilding the pipeline. Host
    /// write: not while recorded work using the pass is pending.
    ///
    /// # Safety
    /// This writes the pass's host-visible camera uniform: no recorded work that uses
    /// this object may be pending on the GPU (wait for its fence first), as Vulkan
    /// requires of descriptor sets and memory the device reads.
    pub unsafe fn retarget(&mut self, geometry: WarpGeometry) -> Result<()> {
        let g = &self.desc.geometry;
        let same = self.desc.coordinates == Coordinates::Analytic
            && geometry.channel_cameras.is_none()
            && (g.source_size, g.output_size) == (geometry.source_size, geometry.output_size)
            && g.direction == geometry.direction
            && g.method == geometry.method
            && g.chromatic == geometry.chromatic
            && g.camera.terms() == geometry.camera.terms();
        if !same {
            return Err(Error::Input(
                "retarget needs an analytic warp of the same sizes, direction, method, chromatic scales and terms".into(),
            ));
        }
        self._camera.write(
            0,
            bytemuck::bytes_of(&CameraParams::from_camera(&geometry.camera)),
        )?;
        let k = &geometry.ideal;
        self.push.ideal = f4([k.fx, k.fy, k.cx, k.cy]);
        self.desc.geometry = geometry;
        Ok(())
    }

    /// The device the pass was built on.
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// What the pass was built from.
    pub fn desc(&self) -> &WarpDesc {
        &self.desc
    }

    /// Whether a coarse map's per-pixel forward check was compiled in (None without one).
    pub fn coarse_map_checked(&self) -> Option<bool> {
        self.map_pipelines
            .get(1)
            .and_then(|p| p.constants.get(spec::CHECK_RESIDUAL))
            .map(|v| v != 0)
    }

    /// The map images' views as [G, R, B] (R and B are 1×1 placeholders without chromatic
    /// aberration; all are placeholders in analytic mode). They are in `GENERAL` layout after
    /// [`WarpPass::record_prepare`].
    pub fn map_views(&self) -> [vk::ImageView; 3] {
        [self.maps[1].view, self.maps[0].view, self.maps[2].view]
    }

    /// The push constants the warp runs with.
    pub fn push(&self) -> WarpPush {
        self.push
    }

    /// The warp pipeline (its specialization constants show what was compiled in).
    pub fn pipeline(&self) -> &ComputePipeline {
        &self.pipeline
    }

    /// Makes frame `frame`'s descriptor set (`frame` modulo the number of sets) the
    /// one [`WarpPass::bind`] writes and [`WarpPass::record`] records.
    pub fn select_frame(&mut self, frame: usize) {
        self.slot = frame % self.sets.len();
    }

    /// Points the pass at the caller's images (views of storage images that will be in
    /// `GENERAL` layout when the recorded work runs): the source (`source_size`, this pass's
    /// format), the output (`output_size`, same format) and the mask (`output_size`,
    /// `R8_UNORM`: 1 valid, 0 filled). Not while recorded work using the pass is pending.
    ///
    /// # Safety
    /// This rewrites the selected frame's descriptor set: no recorded work that uses that set
    /// (a frame recorded with the same selection) may be pending on the GPU (wait for its
    /// fence first), as Vulkan requires of descriptor sets the device reads.
    pub unsafe fn bind(
        &mut self,
        source: vk::ImageView,
        output: vk::ImageView,
        mask: vk::ImageView,
    ) {
        // SAFETY: the caller upholds this function's contract (no pending work uses the set);
        // the set is this pass's own, of its pipeline's layout, and the views and buffers are
        // live.
        unsafe {
            write_storage_image_descriptors(
                &self.gpu,
                self.sets[self.slot],
                &[(1, source), (2, output), (3, mask)],
            )
        };
    }

    /// Records the one-off work: the map images' transition to `GENERAL` and, in map mode, the
    /// map builds (one dispatch per channel), followed by the barrier the warp needs.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass on a compute queue; record this once,
    /// before the first [`WarpPass::record`], and not again while that work is pending.
    pub unsafe fn record_prepare(&self, cmd: vk::CommandBuffer) {
        let (write, read) = (Access::ComputeWrite, Access::ComputeRead);
        // SAFETY: the caller upholds `record_prepare`'s contract: `cmd` is recording outside a
        // render pass on a compute queue, and no earlier prepare is pending. The maps are this
        // pass's own images, so UNDEFINED is a valid old layout; each map-build set was written
        // in `new` and pushes a `WarpPush`, the size the map pipelines were built with.
        unsafe {
            // Maps are written (map builds) then read (warp) as storage images.
            crate::gpu::record_discard_for_compute_write(
                &self.gpu,
                cmd,
                self.maps.iter().chain(&self._coarse),
            );
            for step in &self.map_steps {
                self.map_pipelines[step.pipeline].record_dispatch(
                    cmd,
                    step.set,
                    bytemuck::bytes_of(&step.push),
                    step.groups,
                );
                if step.barrier_after {
                    // The upsampling reads the coarse map just written.
                    global_barrier(&self.gpu, cmd, write, read);
                }
            }
            // The warp reads the maps the builds wrote.
            global_barrier(&self.gpu, cmd, write, read);
        }
    }

    /// Records the warp.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass on a compute queue, after
    /// [`WarpPass::record_prepare`] and [`WarpPass::bind`]. On entry the source must be in
    /// `GENERAL` layout with its writes visible to `COMPUTE_SHADER` reads, and the output and
    /// mask in `GENERAL` layout; they stay in `GENERAL`. The caller makes the output's
    /// `SHADER_WRITE`s visible to whatever reads them next.
    pub unsafe fn record(&self, cmd: vk::CommandBuffer) {
        let (w, h) = self.desc.geometry.output_size;
        // SAFETY: the caller upholds `record`'s contract: `cmd` is recording outside a render
        // pass after `record_prepare` and `bind`, the images in GENERAL with the source's writes
        // visible; `push` is a `WarpPush`, the pipeline's push range.
        unsafe {
            self.pipeline.record_dispatch(
                cmd,
                self.sets[self.slot],
                bytemuck::bytes_of(&self.push),
                (w.div_ceil(8), h.div_ceil(8)),
            )
        };
    }

    /// As [`Self::record`], for the output pixels in `band` alone (`[x0, y0, x1, y1]`, x1
    /// and y1 excluded, clamped to the output): the others keep what they hold. An empty band
    /// records nothing.
    ///
    /// # Safety
    /// As [`Self::record`].
    pub unsafe fn record_band(&self, cmd: vk::CommandBuffer, band: [u32; 4]) {
        let (w, h) = self.desc.geometry.output_size;
        let [x0, y0, x1, y1] = band;
        let (x1, y1) = (x1.min(w), y1.min(h));
        if x0 >= x1 || y0 >= y1 {
            return;
        }
        let push = WarpPush {
            band: [x0, y0, x1, y1],
            ..self.push
        };
        // SAFETY: as in `record`: the caller upholds its contract; `push` is a `WarpPush`.
        unsafe {
            self.pipeline.record_dispatch(
                cmd,
                self.sets[self.slot],
                bytemuck::bytes_of(&push),
                ((x1 - x0).div_ceil(8), (y1 - y0).div_ceil(8)),
            )
        };
    }
}

/// Refuses images the device cannot hold, before any is created.
pub(crate) fn check_sizes(gpu: &Gpu, g: &WarpGeometry) -> Result<()> {
    let max = gpu.max_image_side();
    for (what, (w, h)) in [("source", g.source_size), ("output", g.output_size)] {
        if w > max || h > max {
            return Err(Error::Unsupported(format!(
                "the {what} is {w}×{h}, larger than {} supports ({max} px per side)",
                gpu.device_name()
            )));
        }
    }
    Ok(())
}
