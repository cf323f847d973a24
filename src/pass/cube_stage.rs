//! The cube-map warp on the GPU as one record-only stage: six pinhole renders of a cube map's
//! 90° faces, each copied into its layer of a cube image, then the sphere warp
//! (`glsl/sphere_warp.comp`) sampling it by the ray each output pixel sees. Nothing makes a
//! round trip through the host, so an engine records it as it records the warp path, and the
//! planner can weigh it against Alg. 1 and the pinhole warp for a lens no pinhole source
//! holds (a fisheye of 180° and more, a wide lens past the device's image limit).

use ash::vk;

use crate::gpu::{image_discard, image_transition, Access, Image};
use crate::model::Camera;
use crate::pass::geometry::{
    ColorFormat, GeometryDesc, GeometryPass, GeometrySlots, GeometryTargets, MeshBuffers, Outputs,
    Projection,
};
use crate::pass::sphere_warp::{
    CubeFace, DataSource, SphereDataPass, SphereWarpOptions, SphereWarpPass,
};
use crate::pass::warp_stage::DataOutputs;
use crate::scene::Pose;
use crate::{Error, Result};

/// Six face renders into a cube image, then the sphere warp into an output of the lens
/// camera's size: RGBA8 for 8-bit faces, RGBA32F for float ones.
pub struct CubeStage {
    gpu: crate::gpu::Gpu,
    /// The pinhole render of a face (90° across), one slot per face.
    pub pass: GeometryPass,
    /// The six faces' slots, one set of them per frame in flight.
    slots: Vec<GeometrySlots>,
    /// The frame in flight [`Self::prepare`] writes and [`Self::record`] records.
    current: usize,
    /// The face the pass renders into before it is copied to its layer.
    pub targets: GeometryTargets,
    /// The six faces (`SHADER_READ_ONLY_OPTIMAL` after a frame).
    pub cube: Image,
    pub warp: SphereWarpPass,
    /// The faces' format (RGBA8 or RGBA32F), the lens camera's size, `GENERAL` after a frame.
    pub output: Image,
    mask: Image,
    side: u32,
    face_camera: Camera,
    format: ColorFormat,
    options: SphereWarpOptions,
    /// The lens camera's size and terms (a jittered pass keeps both).
    lens: ((u32, u32), crate::model::Terms),
    /// IDs, depth and range through the lens, where asked for.
    pub data: Option<CubeData>,
}

/// The cube route's data outputs: the faces' IDs and depths in cubes of their own, and the
/// nearest-sample pass that carries them through the lens ([`SphereDataPass`]).
pub struct CubeData {
    /// What was asked for (every output is rendered; the readback reads these).
    pub asked: DataOutputs,
    ids_cube: Image,
    depth_cube: Image,
    pub pass: SphereDataPass,
    /// Object IDs (R32_UINT, 0 where nothing is seen), `GENERAL` after a frame.
    pub ids: Image,
    /// Camera-frame z (R32F metres, +inf where nothing is seen), `GENERAL` after a frame.
    pub depth: Image,
    /// Range along each pixel's ray (R32F metres, +inf where nothing is seen).
    pub range: Image,
}

impl CubeStage {
    /// Faces of `side` pixels in `format` (RGBA8 or RGBA32F: the cube is sampled with linear
    /// filtering), cleared to `background`, warped through `camera`.
    pub fn new(
        gpu: &crate::gpu::Gpu,
        camera: &Camera,
        side: u32,
        format: ColorFormat,
        options: &SphereWarpOptions,
    ) -> Result<Self> {
        Self::with_frames(gpu, camera, side, format, options, 1)
    }

    /// As [`Self::new`], with the faces' uniforms and sets for `frames` frames in flight
    /// (1 to [`crate::pass::geometry::MAX_FRAMES_IN_FLIGHT`]), chosen by
    /// [`Self::select_frame`].
    pub fn with_frames(
        gpu: &crate::gpu::Gpu,
        camera: &Camera,
        side: u32,
        format: ColorFormat,
        options: &SphereWarpOptions,
        frames: usize,
    ) -> Result<Self> {
        Self::with_data(
            gpu,
            camera,
            side,
            format,
            options,
            frames,
            DataOutputs::default(),
        )
    }

    /// As [`Self::with_frames`]; the faces also render object IDs and depth where `data` asks
    /// for any of IDs, depth or range, and a nearest pass carries them through the lens
    /// ([`Self::data`]).
    pub fn with_data(
        gpu: &crate::gpu::Gpu,
        camera: &Camera,
        side: u32,
        format: ColorFormat,
        options: &SphereWarpOptions,
        frames: usize,
        data: DataOutputs,
    ) -> Result<Self> {
        if !(1..=crate::pass::geometry::MAX_FRAMES_IN_FLIGHT).contains(&frames) {
            return Err(Error::input(format!(
                "{frames} frames in flight: a cube stage keeps 1 to {}",
                crate::pass::geometry::MAX_FRAMES_IN_FLIGHT
            )));
        }
        let max = gpu.max_image_side().min(gpu.max_cube_side());
        if side < 2 || side > max {
            return Err(Error::input(format!(
                "cube faces of {side} px: the device holds 2 to {max}"
            )));
        }
        let vk_format = match format {
            ColorFormat::Rgba8 => vk::Format::R8G8B8A8_UNORM,
            ColorFormat::Rgba32F if gpu.supports_float_linear_filter() => {
                vk::Format::R32G32B32A32_SFLOAT
            }
            ColorFormat::Rgba32F => {
                return Err(Error::Unsupported(format!(
                    "{} cannot filter RGBA32F images linearly, which float cube faces need: render 8-bit colour",
                    gpu.device_name()
                )))
            }
            ColorFormat::Rgba16F => {
                return Err(Error::input("cube faces are RGBA8 or RGBA32F"));
            }
        };
        let face_camera = CubeFace::camera(side)?;
        let with_data = data.ids || data.depth || data.range;
        let mut desc = GeometryDesc::new(
            face_camera.clone(),
            Projection::Pinhole,
            Outputs {
                ids: with_data,
                depth: with_data,
                ..Outputs::color_only(Some(format))
            },
        );
        desc.background = options.fill;
        let pass = GeometryPass::new(gpu, desc)?;
        let slots = (0..frames)
            .map(|_| pass.slots(6))
            .collect::<crate::gpu::Result<Vec<_>>>()?;
        let targets = GeometryTargets::new(gpu, &pass)?;
        let cube = Image::new_cube(
            gpu,
            "cube_stage.cube",
            vk_format,
            side,
            vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
        )?;
        let (ow, oh) = (camera.width, camera.height);
        let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
        let eight_bit = format == ColorFormat::Rgba8;
        let out_format = if eight_bit {
            vk::Format::R8G8B8A8_UNORM
        } else {
            vk::Format::R32G32B32A32_SFLOAT
        };
        let output = Image::new_2d(gpu, "cube_stage.output", out_format, ow, oh, usage)?;
        let mask = Image::new_2d(gpu, "cube_stage.mask", vk::Format::R8_UNORM, ow, oh, usage)?;
        let options = SphereWarpOptions {
            write_mask: false,
            ..options.clone()
        };
        let mut warp = SphereWarpPass::with_target(gpu, camera, false, &options, eight_bit)?;
        let lens = ((camera.width, camera.height), camera.terms());
        // SAFETY: the pass is new, so no recorded work uses it; the views are a cube view and
        // two 2D storage views of this device, in the layouts `record` leaves them in.
        unsafe { warp.bind(cube.view, output.view, mask.view) };
        let data = if with_data {
            let cube_of = |name: &str, format| {
                Image::new_cube(
                    gpu,
                    name,
                    format,
                    side,
                    vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
                )
            };
            let ids_cube = cube_of("cube_stage.ids_cube", vk::Format::R32_UINT)?;
            let depth_cube = cube_of("cube_stage.depth_cube", vk::Format::R32_SFLOAT)?;
            let out = |name: &str, format| Image::new_2d(gpu, name, format, ow, oh, usage);
            let ids = out("cube_stage.ids", vk::Format::R32_UINT)?;
            let depth = out("cube_stage.depth", vk::Format::R32_SFLOAT)?;
            let range = out("cube_stage.range", vk::Format::R32_SFLOAT)?;
            let mut pass = SphereDataPass::new(gpu, camera, DataSource::Cube)?;
            // SAFETY: the pass is new, so no recorded work uses it; the views are two cube
            // views and three 2D storage views of this device, in the layouts `record` leaves
            // them in.
            unsafe {
                pass.bind(
                    [ids_cube.view, depth_cube.view],
                    [ids.view, depth.view, range.view],
                )
            };
            Some(CubeData {
                asked: data,
                ids_cube,
                depth_cube,
                pass,
                ids,
                depth,
                range,
            })
        } else {
            None
        };
        Ok(CubeStage {
            gpu: gpu.clone(),
            pass,
            slots,
            current: 0,
            targets,
            cube,
            warp,
            output,
            mask,
            side,
            face_camera,
            format,
            options,
            lens,
            data,
        })
    }

    /// Whether this stage renders what [`Self::new`] with these arguments would, once moved to
    /// `camera` with [`Self::set_camera`].
    pub fn fits(
        &self,
        camera: &Camera,
        side: u32,
        format: ColorFormat,
        options: &SphereWarpOptions,
    ) -> bool {
        self.side == side
            && self.format == format
            && self.options.chromatic == options.chromatic
            && self.options.fill == options.fill
            && self.lens == ((camera.width, camera.height), camera.terms())
            && self.data.is_none()
    }

    /// Makes frame `frame` (modulo the frames in flight it was made with) the one
    /// [`Self::prepare`] writes and [`Self::record`] records.
    pub fn select_frame(&mut self, frame: usize) {
        self.current = frame % self.slots.len();
    }

    /// The faces' side in pixels.
    pub fn side(&self) -> u32 {
        self.side
    }

    /// Points the faces at `mesh` and puts them at `pose` (the lens camera's): face `f`
    /// looks from the same centre, turned by [`CubeFace::rotation`].
    ///
    /// # Safety
    /// Host writes to the selected frame's face uniforms and descriptor sets
    /// ([`Self::select_frame`]): no recorded work of that frame may be pending on the GPU.
    pub unsafe fn prepare(&self, mesh: &MeshBuffers, pose: &Pose) -> Result<()> {
        // SAFETY: the caller upholds this function's contract, which is prepare_bands's.
        unsafe { self.prepare_bands(mesh, std::slice::from_ref(pose)) }
    }

    /// Makes room for `count` sets of faces per frame in flight, one per band of a rolling
    /// shutter's lines ([`Self::prepare_bands`], [`Self::record_band`]).
    ///
    /// # Safety
    /// Drops the faces' slots: no recorded work of this stage may be pending.
    pub unsafe fn set_bands(&mut self, count: usize) -> Result<()> {
        let frames = self.slots.len();
        self.slots = (0..frames)
            .map(|_| self.pass.slots((6 * count.max(1)) as u32))
            .collect::<crate::gpu::Result<Vec<_>>>()?;
        Ok(())
    }

    /// As [`Self::prepare`], one set of faces per pose in `poses` (band k's at `poses[k]`; at
    /// most the bands [`Self::set_bands`] made room for).
    ///
    /// # Safety
    /// As [`Self::prepare`].
    pub unsafe fn prepare_bands(&self, mesh: &MeshBuffers, poses: &[Pose]) -> Result<()> {
        // SAFETY: the caller upholds this function's contract (nothing pending uses the slots).
        unsafe {
            let slots = &self.slots[self.current];
            if 6 * poses.len() > slots.len() {
                return Err(Error::input(format!(
                    "{} poses of cube faces: the stage has room for {}",
                    poses.len(),
                    slots.len() / 6
                )));
            }
            self.pass.bind_slots_mesh(slots, mesh);
            for (k, pose) in poses.iter().enumerate() {
                for face in CubeFace::ALL {
                    let r = face.rotation();
                    let face_pose = Pose {
                        rotation: r * pose.rotation,
                        translation: r * pose.translation,
                    };
                    self.pass.set_slot(
                        slots,
                        6 * k + face.layer() as usize,
                        &self.face_camera,
                        &face_pose,
                        &face_pose,
                    )?;
                }
            }
        }
        Ok(())
    }

    /// Moves the lens to `camera` (same size and terms): a jittered pass of anti-aliasing.
    ///
    /// # Safety
    /// A host write to the warp's camera uniform: no recorded work that uses this stage may be
    /// pending on the GPU.
    pub unsafe fn set_camera(&mut self, camera: &Camera) -> Result<()> {
        // SAFETY: the caller upholds this function's contract.
        unsafe {
            if let Some(d) = &mut self.data {
                d.pass.set_camera(camera)?;
            }
            self.warp.set_camera(camera)
        }
    }

    /// Records the one-off work: output and mask to `GENERAL`.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass; not while earlier work is pending.
    pub unsafe fn record_prepare(&self, cmd: vk::CommandBuffer) {
        // SAFETY: the caller upholds this function's contract: nothing using the images is
        // pending, so UNDEFINED is a valid old layout for the stage's own output and mask.
        unsafe {
            let data = self.data.iter().flat_map(|d| [&d.ids, &d.depth, &d.range]);
            crate::gpu::record_discard_for_compute_write(
                &self.gpu,
                cmd,
                [&self.output, &self.mask].into_iter().chain(data),
            )
        };
    }

    /// Records one frame: [`Self::record_faces`], then [`Self::record_warp`].
    ///
    /// # Safety
    /// As [`Self::record_faces`].
    pub unsafe fn record(&self, cmd: vk::CommandBuffer, mesh: &MeshBuffers) {
        // SAFETY: the caller upholds `record_faces`'s contract, which `record_warp` needs too.
        unsafe {
            self.record_faces(cmd, mesh);
            self.record_warp(cmd);
        }
    }

    /// Records each face rendered (`prepare`d) and copied into its layer; leaves the cube in
    /// `SHADER_READ_ONLY_OPTIMAL`, its writes visible to compute.
    ///
    /// # Safety
    /// After [`Self::record_prepare`] and [`Self::prepare`]; `cmd` recording outside a render
    /// pass on a queue with graphics and compute; `mesh` uploaded and alive until the work
    /// completes.
    pub unsafe fn record_faces(&self, cmd: vk::CommandBuffer, mesh: &MeshBuffers) {
        // SAFETY: the caller upholds this function's contract, which is record_band_faces's.
        unsafe { self.record_band_faces(cmd, mesh, 0) }
    }

    /// As [`Self::record_faces`], from band `band`'s poses ([`Self::prepare_bands`]). The
    /// cube is discarded first, after the last warp's reads of it: bands take turns.
    ///
    /// # Safety
    /// As [`Self::record_faces`], the band prepared.
    pub unsafe fn record_band_faces(
        &self,
        cmd: vk::CommandBuffer,
        mesh: &MeshBuffers,
        band: usize,
    ) {
        use vk::ImageLayout as L;
        let d = self.gpu.device();
        let Some(face_image) = self.targets.color() else {
            // `new` made a colour output: unreachable.
            return;
        };
        let whole = |layer: u32| vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: layer,
            layer_count: 1,
        };
        let extent = vk::Extent3D {
            width: self.side,
            height: self.side,
            depth: 1,
        };
        // Each face image copied into its cube: the colour, and the IDs and depth where asked.
        let mut copies: Vec<(&Image, &Image)> = vec![(face_image, &self.cube)];
        if let Some(data) = &self.data {
            for (face, cube) in [
                (self.targets.ids(), &data.ids_cube),
                (self.targets.depth(), &data.depth_cube),
            ] {
                if let Some(face) = face {
                    copies.push((face, cube));
                }
            }
        }
        // SAFETY: the caller upholds this function's contract. Each cube is written whole each
        // frame, so it starts from UNDEFINED (after the last frame's warp read it); the face
        // targets are left in TRANSFER_SRC_OPTIMAL by the geometry pass (its desc's default
        // final layout), whose render pass orders its clear after the copy's read; copies are
        // within both images (same side, one layer each).
        unsafe {
            for (_, cube) in &copies {
                image_discard(
                    &self.gpu,
                    cmd,
                    cube.raw,
                    Access::ComputeSampled,
                    Access::TransferWrite,
                );
            }
            for face in CubeFace::ALL {
                let layer = face.layer();
                self.pass.record_slot(
                    cmd,
                    &self.targets,
                    mesh,
                    &self.slots[self.current],
                    6 * band + layer as usize,
                );
                for (src, dst) in &copies {
                    d.cmd_copy_image(
                        cmd,
                        src.raw,
                        L::TRANSFER_SRC_OPTIMAL,
                        dst.raw,
                        L::TRANSFER_DST_OPTIMAL,
                        &[vk::ImageCopy {
                            src_subresource: whole(0),
                            src_offset: vk::Offset3D::default(),
                            dst_subresource: whole(layer),
                            dst_offset: vk::Offset3D::default(),
                            extent,
                        }],
                    );
                }
            }
            for (_, cube) in &copies {
                image_transition(
                    &self.gpu,
                    cmd,
                    cube.raw,
                    Access::TransferWrite,
                    Access::ComputeSampled,
                );
            }
        }
    }

    /// Records the sphere warp of the faces [`Self::record_faces`] rendered. Leaves the output
    /// in `GENERAL`, its writes visible to transfers and compute.
    ///
    /// # Safety
    /// As [`Self::record_faces`], recorded after it.
    pub unsafe fn record_warp(&self, cmd: vk::CommandBuffer) {
        // SAFETY: the caller upholds this function's contract: the cube is in
        // SHADER_READ_ONLY_OPTIMAL with its writes visible to compute, and `record_prepare` put
        // the output and mask, which the warp was bound to with the cube in `new`, in GENERAL.
        unsafe {
            self.warp.record_for_readers(cmd, None);
            if let Some(d) = &self.data {
                d.pass.record_for_readers(cmd, None);
            }
        }
    }

    /// As [`Self::record_warp`], for the output pixels in `band` alone (`[x0, y0, x1, y1]`).
    ///
    /// # Safety
    /// As [`Self::record_warp`].
    pub unsafe fn record_warp_band(&self, cmd: vk::CommandBuffer, band: [u32; 4]) {
        // SAFETY: as in `record_warp`.
        unsafe {
            self.warp.record_for_readers(cmd, Some(band));
            if let Some(d) = &self.data {
                d.pass.record_for_readers(cmd, Some(band));
            }
        }
    }
}
