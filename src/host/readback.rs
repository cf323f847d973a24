//! Reading images back to the host. The passes only record and leave their outputs in a
//! documented layout; the host side owns the host-visible buffers those outputs are copied
//! into, records the copies after a frame and reads them once the fence has signalled.

use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::gpu::{Buffer, Error, Gpu, Image, Result};
use crate::imaging::{BitDepth, Pixels, Raster};

/// Where a pass left the image it wrote, which decides how the copy is recorded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Left {
    /// `TRANSFER_SRC_OPTIMAL` with its writes visible to transfers (a render pass whose final
    /// layout is that, e.g. the geometry and mesh-warp passes).
    TransferSource,
    /// `GENERAL`, written by a compute shader (the warps); left in `GENERAL` again after the
    /// copy, so that the next frame's compute pass writes it without a one-off transition.
    ComputeGeneral,
    /// `COLOR_ATTACHMENT_OPTIMAL` (the lens film after its cells); left in
    /// `TRANSFER_SRC_OPTIMAL`.
    ColorAttachment,
}

/// A host-visible buffer that holds one image whole, tightly packed.
pub struct Download {
    buffer: Buffer,
    format: vk::Format,
    extent: vk::Extent2D,
}

/// Bytes per texel of the formats the passes write.
fn texel_bytes(format: vk::Format) -> Result<u64> {
    Ok(match format {
        vk::Format::R8_UNORM => 1,
        vk::Format::R8G8B8A8_UNORM
        | vk::Format::R32_UINT
        | vk::Format::R32_SFLOAT
        | vk::Format::B8G8R8A8_UNORM => 4,
        vk::Format::R16G16B16A16_SFLOAT | vk::Format::R32G32_SFLOAT => 8,
        vk::Format::R32G32B32A32_SFLOAT => 16,
        other => {
            return Err(Error::internal(format!(
                "no readback for images of format {other:?}"
            )))
        }
    })
}

impl Download {
    /// A buffer for `image` (its format and size).
    pub fn new(gpu: &Gpu, image: &Image, name: &str) -> Result<Self> {
        let e = image.extent;
        Ok(Download {
            buffer: Buffer::new(
                gpu,
                name,
                e.width as u64 * e.height as u64 * texel_bytes(image.format)?,
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            )?,
            format: image.format,
            extent: e,
        })
    }

    /// Records the copy of `image` (the one this buffer was made for, or one of its format and
    /// size) and makes it visible to host reads after the fence.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass on a queue with transfer (and, for
    /// [`Left::ComputeGeneral`], compute) support, after the work that wrote `image`, which
    /// must be in the layout `left` names, with TRANSFER_SRC usage; this buffer must stay
    /// alive until the work completes.
    pub unsafe fn record(
        &self,
        gpu: &Gpu,
        cmd: vk::CommandBuffer,
        image: &Image,
        left: Left,
    ) -> Result<()> {
        if image.format != self.format || image.extent != self.extent {
            return Err(Error::internal(format!(
                "a readback made for a {:?} {}×{} image was given a {:?} {}×{} one",
                self.format,
                self.extent.width,
                self.extent.height,
                image.format,
                image.extent.width,
                image.extent.height
            )));
        }
        // SAFETY: the caller upholds this function's contract: `cmd` is recording outside a
        // render pass after the writes, `image` is in the layout `left` names, and the buffer,
        // checked above to match the image's format and size, holds it whole.
        unsafe {
            match left {
                Left::TransferSource => {
                    crate::gpu::record_download(gpu, cmd, image, &self.buffer);
                }
                Left::ComputeGeneral => {
                    crate::gpu::record_compute_readback(gpu, cmd, image, &self.buffer);
                }
                Left::ColorAttachment => {
                    crate::gpu::image_transition(
                        gpu,
                        cmd,
                        image.raw,
                        crate::gpu::Access::ColorAttachmentReadWrite,
                        crate::gpu::Access::TransferRead,
                    );
                    crate::gpu::record_download(gpu, cmd, image, &self.buffer);
                }
            }
        }
        Ok(())
    }

    /// The size of the image this buffer holds.
    pub fn extent(&self) -> vk::Extent2D {
        self.extent
    }

    /// The image's texels as `T` (after the submission that copied them completed).
    pub fn read<T: bytemuck::Pod>(&self) -> Result<Vec<T>> {
        self.buffer
            .read_pod::<T>(self.extent.width as usize * self.extent.height as usize)
    }

    /// An RGBA image as a raster: 8-bit stays 8-bit; half and single floats become f32.
    pub fn read_rgba(&self) -> Result<Raster> {
        let (pixels, bit_depth) = match self.format {
            vk::Format::R8G8B8A8_UNORM => (Pixels::Rgba8(self.read::<[u8; 4]>()?), BitDepth::U8),
            vk::Format::R32G32B32A32_SFLOAT => {
                (Pixels::Rgba32F(self.read::<[f32; 4]>()?), BitDepth::F32)
            }
            vk::Format::R16G16B16A16_SFLOAT => (
                Pixels::Rgba32F(
                    self.read::<[u16; 4]>()?
                        .iter()
                        .map(|p| p.map(f16_to_f32))
                        .collect(),
                ),
                BitDepth::F32,
            ),
            other => {
                return Err(Error::internal(format!(
                    "{other:?} is not an RGBA format a raster holds"
                )))
            }
        };
        Ok(Raster {
            width: self.extent.width,
            height: self.extent.height,
            pixels,
            bit_depth,
        })
    }
}

/// IEEE half → f32 (RGBA16F readback).
fn f16_to_f32(h: u16) -> f32 {
    let sign = ((h >> 15) as u32) << 31;
    let exp = ((h >> 10) & 0x1f) as u32;
    let frac = (h & 0x3ff) as u32;
    let bits = match (exp, frac) {
        (0, 0) => sign,
        (0, _) => {
            // Subnormal: frac × 2⁻²⁴.
            let magnitude = frac as f32 * 2f32.powi(-24);
            return if sign != 0 { -magnitude } else { magnitude };
        }
        (31, 0) => sign | 0x7f80_0000,
        (31, _) => sign | 0x7fc0_0000,
        _ => sign | ((exp + 112) << 23) | (frac << 13),
    };
    f32::from_bits(bits)
}

#[cfg(test)]
mod tests {
    use super::f16_to_f32;

    #[test]
    fn half_floats_convert() {
        assert_eq!(f16_to_f32(0x3c00), 1.0);
        assert_eq!(f16_to_f32(0xc000), -2.0);
        assert_eq!(f16_to_f32(0x3800), 0.5);
        assert!(f16_to_f32(0x7e00).is_nan());
        assert_eq!(f16_to_f32(0x7c00), f32::INFINITY);
        assert_eq!(f16_to_f32(0x0001), 2f32.powi(-24));
        assert_eq!(f16_to_f32(0x8001), -(2f32.powi(-24)));
    }
}
