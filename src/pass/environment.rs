//! A scene that is a 360° image (a cube map or a panorama a user's own renderer made) seen
//! through a lens as one record-only stage: the image uploaded once, then the sphere warp
//! (`glsl/sphere_warp.comp`) sampling it along the ray each output pixel sees. The planner
//! routes such a scene here ([`crate::plan::Route::Environment`]), as it routes a mesh to the
//! cube map it renders itself ([`crate::pass::cube_stage`]).

use ash::vk;

use crate::gpu::{record_upload, Access, Buffer, Gpu, Image};
use crate::imaging::{Pixels, Raster};
use crate::model::Camera;
use crate::pass::sphere_warp::{CubeFace, SphereWarpOptions, SphereWarpPass};
use crate::scene::Environment;
use crate::{Error, Result};

/// Checks an environment: a cube's six faces square and of one size, every image holding
/// colour, within the device's limits (and its float filtering, for a 16-bit or float one).
pub fn check_environment(gpu: &Gpu, environment: &Environment) -> Result<(u32, u32)> {
    let rasters = environment.rasters();
    for r in &rasters {
        r.check().map_err(|e| Error::Input(e.to_string()))?;
        if matches!(r.pixels, Pixels::R32Uint(_)) {
            return Err(Error::Input(
                "a 360° source must hold colour (object IDs are not filtered)".into(),
            ));
        }
    }
    let size = (rasters[0].width, rasters[0].height);
    if let Environment::Cube(faces) = environment {
        for (face, r) in CubeFace::ALL.iter().zip(faces.iter()) {
            if (r.width, r.height) != (size.0, size.0) {
                return Err(Error::Input(format!(
                    "cube face {} is {}×{}; every face must be square and of one size ({}×{} as the first)",
                    face.name(),
                    r.width,
                    r.height,
                    size.0,
                    size.0
                )));
            }
        }
    }
    let (max, what) = match environment {
        Environment::Cube(_) => (gpu.max_cube_side(), "cube map face"),
        Environment::Panorama(_) => (gpu.max_image_side(), "image"),
    };
    if size.0 > max || size.1 > max {
        return Err(Error::Input(format!(
            "the 360° source is {}×{}, larger than the device's {max} px {what} limit",
            size.0, size.1
        )));
    }
    if !is_eight_bit(environment) && !gpu.supports_float_linear_filter() {
        return Err(Error::Unsupported(format!(
            "{} cannot filter RGBA32F images linearly, which a 16-bit or float 360° source needs: give an 8-bit source",
            gpu.device_name()
        )));
    }
    Ok(size)
}

/// Whether every image of `environment` is 8-bit RGBA (else it is sampled as RGBA32F).
pub fn is_eight_bit(environment: &Environment) -> bool {
    environment
        .rasters()
        .iter()
        .all(|r| matches!(r.pixels, Pixels::Rgba8(_)))
}

/// The environment's texels as its image holds them: every layer tightly packed, a cube's
/// faces in the order of their layers, 8-bit RGBA or RGBA32F.
fn texels(environment: &Environment) -> Vec<u8> {
    let eight_bit = is_eight_bit(environment);
    let mut ordered: Vec<&Raster> = environment.rasters();
    if let Environment::Cube(faces) = environment {
        for (face, r) in CubeFace::ALL.iter().zip(faces.iter()) {
            ordered[face.layer() as usize] = r;
        }
    }
    let mut bytes = Vec::new();
    for r in &ordered {
        match &r.pixels {
            Pixels::Rgba8(p) if eight_bit => bytes.extend(p.iter().flatten()),
            _ => {
                let v: Vec<[f32; 4]> = (0..r.len()).map(|i| r.rgba_f32(i)).collect();
                bytes.extend_from_slice(bytemuck::cast_slice(&v));
            }
        }
    }
    bytes
}

/// The environment on the device and the sphere warp through the lens camera: RGBA32F
/// output of the camera's size, and the mask (255 where a pixel has a source).
pub struct EnvironmentStage {
    gpu: Gpu,
    /// A cube image or a 2D one (`SHADER_READ_ONLY_OPTIMAL` after [`Self::record_setup`]).
    source: Image,
    /// The texels, staged for [`Self::record_setup`].
    upload: Buffer,
    pub warp: SphereWarpPass,
    /// RGBA32F, the lens camera's size, `GENERAL` after a frame.
    pub output: Image,
    /// R8, 255 where the pixel has a source, 0 where it was filled; `GENERAL` after a frame.
    pub mask: Image,
}

impl EnvironmentStage {
    /// Uploads nothing yet: stages `environment`'s texels and builds the warp through `camera`.
    pub fn new(
        gpu: &Gpu,
        camera: &Camera,
        environment: &Environment,
        options: &SphereWarpOptions,
    ) -> Result<Self> {
        let (sw, sh) = check_environment(gpu, environment)?;
        let format = if is_eight_bit(environment) {
            vk::Format::R8G8B8A8_UNORM
        } else {
            vk::Format::R32G32B32A32_SFLOAT
        };
        let panorama = matches!(environment, Environment::Panorama(_));
        let sampled = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
        let source = if panorama {
            Image::new_2d(gpu, "environment.source", format, sw, sh, sampled)?
        } else {
            Image::new_cube(gpu, "environment.cube", format, sw, sampled)?
        };
        let upload = Buffer::from_pod(
            gpu,
            "environment.upload",
            &texels(environment),
            vk::BufferUsageFlags::TRANSFER_SRC,
        )?;
        let (ow, oh) = (camera.width, camera.height);
        let storage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
        let output = Image::new_2d(
            gpu,
            "environment.output",
            vk::Format::R32G32B32A32_SFLOAT,
            ow,
            oh,
            storage,
        )?;
        let mask = Image::new_2d(
            gpu,
            "environment.mask",
            vk::Format::R8_UNORM,
            ow,
            oh,
            storage,
        )?;
        let options = SphereWarpOptions {
            write_mask: true,
            ..options.clone()
        };
        let mut warp = SphereWarpPass::new(gpu, camera, panorama, &options)?;
        // SAFETY: the pass is new, so no recorded work uses it; the views are a cube or 2D
        // sampled view and two 2D storage views of this device, in the layouts
        // `record_setup` leaves them in.
        unsafe { warp.bind(source.view, output.view, mask.view) };
        Ok(EnvironmentStage {
            gpu: gpu.clone(),
            source,
            upload,
            warp,
            output,
            mask,
        })
    }

    /// Records the one-off work: the environment's upload (left `SHADER_READ_ONLY_OPTIMAL`,
    /// visible to compute), the output and mask to `GENERAL`.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass on a queue with compute; once, before
    /// the first frame, with nothing using these images pending.
    pub unsafe fn record_setup(&self, cmd: vk::CommandBuffer) {
        let gpu = &self.gpu;
        // SAFETY: the caller upholds this function's contract (nothing uses the images yet).
        // The source was made with TRANSFER_DST and the upload, with TRANSFER_SRC, holds every
        // layer tightly packed in its format (`check_environment` checked the sizes).
        unsafe {
            record_upload(gpu, cmd, &self.upload, &self.source, Access::ComputeSampled);
            crate::gpu::record_discard_for_compute_write(gpu, cmd, [&self.output, &self.mask]);
        }
    }

    /// Records the warp; leaves the output and mask in `GENERAL`, their writes visible to
    /// transfers and compute.
    ///
    /// # Safety
    /// After [`Self::record_setup`]; `cmd` recording outside a render pass on a queue with
    /// compute; everything alive until the work completes.
    pub unsafe fn record(&self, cmd: vk::CommandBuffer) {
        // SAFETY: the caller upholds this function's contract: the source is in
        // SHADER_READ_ONLY_OPTIMAL and the output and mask in GENERAL, as `bind` asked.
        unsafe { self.warp.record_for_readers(cmd, None) };
    }
}
