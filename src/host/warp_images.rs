//! The staging a headless warp needs: its source, output and mask images and the buffers
//! that upload the source and read the output back. The warp pass itself only records.

use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::gpu::{image_transition, record_compute_download, Access, Buffer, Gpu, Image};
use crate::imaging::{BitDepth, Pixels, Raster};
use crate::pass::warp::check_sizes;
use crate::pass::warp::{PixelFormat, WarpDesc};
use crate::{Error, Result};

/// Images and staging buffers for running a warp headlessly (CLI, tests, benches).
pub struct WarpImages {
    gpu: Gpu,
    pub source: Image,
    pub output: Image,
    pub mask: Image,
    upload: Buffer,
    download: Buffer,
    download_mask: Buffer,
    format: PixelFormat,
    output_size: (u32, u32),
}

impl WarpImages {
    /// Allocates images for `desc` and stages `source` for upload.
    pub fn new(gpu: &Gpu, desc: &WarpDesc, source: &Raster) -> Result<Self> {
        let mut images = Self::allocate(gpu, desc)?;
        images.stage(source)?;
        Ok(images)
    }

    /// Allocates images and staging buffers for `desc`; nothing is staged yet.
    pub fn allocate(gpu: &Gpu, desc: &WarpDesc) -> Result<Self> {
        let g = &desc.geometry;
        check_sizes(gpu, g)?;
        let usage = vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::TRANSFER_SRC
            | vk::ImageUsageFlags::TRANSFER_DST;
        let (sw, sh) = g.source_size;
        let (ow, oh) = g.output_size;
        let fmt = desc.format.vk();
        let texel = desc.format.bytes() as u64;
        Ok(WarpImages {
            source: Image::new_2d(gpu, "warp.source", fmt, sw, sh, usage)?,
            output: Image::new_2d(gpu, "warp.output", fmt, ow, oh, usage)?,
            mask: Image::new_2d(gpu, "warp.mask", vk::Format::R8_UNORM, ow, oh, usage)?,
            upload: Buffer::new(
                gpu,
                "warp.upload",
                sw as u64 * sh as u64 * texel,
                vk::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::CpuToGpu,
            )?,
            download: Buffer::new(
                gpu,
                "warp.download",
                ow as u64 * oh as u64 * texel,
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            )?,
            download_mask: Buffer::new(
                gpu,
                "warp.download.mask",
                ow as u64 * oh as u64,
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            )?,
            gpu: gpu.clone(),
            format: desc.format,
            output_size: (ow, oh),
        })
    }

    /// Stages a new source image (same size and format) for the next [`WarpImages::record_upload`].
    /// Host write: not while recorded work using these images is pending.
    pub fn stage(&mut self, source: &Raster) -> Result<()> {
        let (w, h) = (self.source.extent.width, self.source.extent.height);
        if (source.width, source.height) != (w, h) {
            return Err(Error::Input(format!(
                "the source is {}×{} but the warp expects {w}×{h}",
                source.width, source.height
            )));
        }
        self.upload.write(0, &source_bytes(source, self.format)?)
    }

    /// Stages the source by writing the upload buffer in place: `fill` gets the whole buffer,
    /// tightly packed texels in the pass's format (so a host image is converted once, straight
    /// into the memory the GPU copies from). Host write: not while recorded work using these
    /// images is pending.
    pub fn stage_with<R>(&mut self, fill: impl FnOnce(&mut [u8]) -> R) -> Result<R> {
        let (w, h) = (self.source.extent.width, self.source.extent.height);
        let n = w as usize * h as usize * self.format.bytes();
        self.upload.write_with(|bytes| fill(&mut bytes[..n]))
    }

    /// Hands the downloaded output (tightly packed texels in the pass's format) and mask (one
    /// byte per pixel) to `read`, in place (after the submission completed).
    pub fn read_with<R>(&self, read: impl FnOnce(&[u8], &[u8]) -> R) -> Result<R> {
        let (w, h) = self.output_size;
        let n = w as usize * h as usize;
        let output = self.download.bytes(n * self.format.bytes())?;
        let mask = self.download_mask.bytes(n)?;
        Ok(read(output, mask))
    }

    /// Records the upload of the source and the layout transitions the warp expects.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass.
    pub unsafe fn record_upload(&self, cmd: vk::CommandBuffer) {
        // SAFETY: the caller upholds `record_upload`'s contract: `cmd` is recording outside a
        // render pass. The images are this struct's, made in `new` with TRANSFER_DST and
        // STORAGE usage; `upload` holds the source tightly packed in the pass's format, which
        // relies on `source.pixels` having width × height entries (`new` and `stage` check the
        // size but not the pixel count).
        unsafe {
            // Source: fill it by copy, then hand it to the shader for reading.
            crate::gpu::record_upload(
                &self.gpu,
                cmd,
                &self.upload,
                &self.source,
                Access::ComputeRead,
            );
            // Output and mask: the shader writes every pixel, old contents are irrelevant.
            for img in [&self.output, &self.mask] {
                image_transition(
                    &self.gpu,
                    cmd,
                    img.raw,
                    Access::Nothing,
                    Access::ComputeWrite,
                );
            }
        }
    }

    /// Records the download of output and mask after the warp.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass, after the warp.
    pub unsafe fn record_download(&self, cmd: vk::CommandBuffer) {
        // SAFETY: the caller upholds `record_download`'s contract: `cmd` is recording outside a
        // render pass after the warp, which leaves output and mask in GENERAL; `download` and
        // `download_mask` were sized in `new` for the whole output and mask, tightly packed.
        unsafe {
            record_compute_download(&self.gpu, cmd, &self.output, &self.download);
            record_compute_download(&self.gpu, cmd, &self.mask, &self.download_mask);
        }
    }

    /// Reads output and mask back (after the submission completed).
    pub fn read(&self, bit_depth: BitDepth) -> Result<(Raster, Vec<u8>)> {
        let (w, h) = self.output_size;
        let n = w as usize * h as usize;
        let pixels = match self.format {
            PixelFormat::Rgba8 => Pixels::Rgba8(self.download.read_pod::<[u8; 4]>(n)?),
            PixelFormat::Rgba32F => Pixels::Rgba32F(self.download.read_pod::<[f32; 4]>(n)?),
            PixelFormat::R32Uint => Pixels::R32Uint(self.download.read_pod::<u32>(n)?),
            PixelFormat::R32Float => Pixels::Rgba32F(
                self.download
                    .read_pod::<f32>(n)?
                    .into_iter()
                    .map(|z| [z, z, z, 1.0])
                    .collect(),
            ),
        };
        let mask = self.download_mask.read_pod::<u8>(n)?;
        Ok((
            Raster {
                width: w,
                height: h,
                pixels,
                bit_depth,
            },
            mask,
        ))
    }
}

/// The bytes of `source` as the warp's `format` stores them.
fn source_bytes(source: &Raster, format: PixelFormat) -> Result<Vec<u8>> {
    source.check()?;
    Ok(match (&source.pixels, format) {
        (Pixels::Rgba8(p), PixelFormat::Rgba8) => p.iter().flatten().copied().collect(),
        (Pixels::R32Uint(p), PixelFormat::R32Uint) => bytemuck::cast_slice(p).to_vec(),
        (Pixels::Rgba32F(p), PixelFormat::R32Float) => {
            let v: Vec<f32> = p.iter().map(|q| q[0]).collect();
            bytemuck::cast_slice(&v).to_vec()
        }
        (_, PixelFormat::Rgba32F) => {
            let v: Vec<[f32; 4]> = (0..source.len()).map(|i| source.rgba_f32(i)).collect();
            bytemuck::cast_slice(&v).to_vec()
        }
        _ => {
            return Err(Error::Input(
                "the source's pixels do not match the warp's format".into(),
            ))
        }
    })
}
