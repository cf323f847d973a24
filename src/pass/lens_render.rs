//! Heidrich et al. Sec. 3.5's rendering loop on the GPU: for every lens sample and every quad-tree
//! cell of an [`ImageModel`], render the scene with that cell's perspective projection (a
//! pinhole [`GeometryPass`] at the virtual centre of projection with the cell's frustum), then
//! morph it onto the film grid with the radiometric weights and add it into the float film
//! ([`FilmPass`]). Depth of field comes from the lens samples, vignetting from the shrunken
//! grids and the weights, distortion and the other aberrations from the morph.
//!
//! With one model per colour channel (each traced at its own wavelength), each channel is
//! accumulated from its own projections: lateral and longitudinal colour come out of the lens.
//!
//! Cost: one render pass and one morph per cell, all recorded into one command buffer (each
//! cell has its own camera-and-pose slot of the geometry pass; cells of one render size share
//! a pipeline and an image, in turn). [`LensRenderer::record`] records a frame into a
//! command buffer the caller owns; [`LensRenderer::render`] is the headless caller.

use ash::vk;
use glam::DVec2;

use super::film::{FilmPass, FilmTarget, FilmVertex};
use super::geometry::{
    ColorFormat, GeometryDesc, GeometryPass, GeometrySlots, GeometryTargets, MeshBuffers,
};
use super::geometry::{Outputs, Projection};
use crate::gpu::{Buffer, Error, Gpu, Result};
use crate::lens::image_model::{Cell, ImageModel};
use crate::model::{Camera, Intrinsics, OpenCvDistortion};
use crate::scene::Pose;

/// What the renderer draws with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LensRenderOptions {
    /// Cell render resolution relative to the film pixels the cell covers (before rounding up
    /// to a power of two).
    pub oversample: f64,
    /// Near and far planes of the cell renders (metres from the COP).
    pub near: f64,
    pub far: f64,
    /// Frames in flight the cells keep uniforms and descriptor sets for
    /// ([`LensRenderer::select_frame`]), 1 to [`crate::pass::geometry::MAX_FRAMES_IN_FLIGHT`].
    pub frames_in_flight: usize,
}

impl Default for LensRenderOptions {
    fn default() -> Self {
        LensRenderOptions {
            oversample: 1.0,
            near: 0.01,
            far: 1000.0,
            frames_in_flight: 1,
        }
    }
}

/// One cell to draw: its projection and its triangles in the film vertex buffer.
pub(crate) struct CellDraw {
    camera: Camera,
    cop: glam::DVec3,
    bucket: usize,
    /// Its slot in the bucket's geometry pass.
    slot: usize,
    first: u32,
    count: u32,
    mask: [f32; 4],
}

/// A render size shared by cells: a geometry pass, its images and the film's view of them.
struct Bucket {
    pass: GeometryPass,
    targets: GeometryTargets,
    /// The cells' slots, one set of them per frame in flight.
    slots: Vec<GeometrySlots>,
    set: vk::DescriptorSet,
}

/// A rendered film.
#[derive(Debug, Clone)]
pub struct LensFrame {
    pub width: u32,
    pub height: u32,
    /// RGB: irradiance relative to the on-axis irradiance of a white scene; alpha: the
    /// accumulated weight (relative illumination where the scene is opaque).
    pub pixels: Vec<[f32; 4]>,
    /// Perspective projections drawn.
    pub projections: usize,
    /// Wall time of the frame's submission (recorded in one command buffer, without the
    /// readback), milliseconds.
    pub frame_ms: f64,
}

/// The GPU side of the image-based model: built once per lens setting on any device (the
/// caller's, through [`Gpu::from_caller`], or the headless [`crate::host::Context`]'s), draws any number
/// of frames (poses) of one scene.
pub struct LensRenderer {
    film: FilmPass,
    pub(crate) target: FilmTarget,
    buckets: Vec<Bucket>,
    pub(crate) draws: Vec<CellDraw>,
    vertices: Buffer,
    /// The frame in flight [`Self::prepare`] writes and [`Self::record`] records.
    current: usize,
}

pub use crate::lens::image_model::{ALL_CHANNELS, RGB_CHANNELS};

impl LensRenderer {
    /// `models`: each with the channels it draws into (one model: [`ALL_CHANNELS`]; three
    /// wavelengths: [`RGB_CHANNELS`]). All models must share one film.
    pub fn new(
        gpu: &Gpu,
        models: &[(ImageModel, [f32; 4])],
        options: LensRenderOptions,
    ) -> Result<Self> {
        let Some(film) = models.first().map(|(m, _)| m.film) else {
            return Err(Error::Input("no lens model to render".into()));
        };
        if models.iter().any(|(m, _)| m.film != film) {
            return Err(Error::Input("the models have different films".into()));
        }
        let frames = options.frames_in_flight;
        if !(1..=crate::pass::geometry::MAX_FRAMES_IN_FLIGHT).contains(&frames) {
            return Err(Error::Input(format!(
                "{frames} frames in flight: the lens renderer keeps 1 to {}",
                crate::pass::geometry::MAX_FRAMES_IN_FLIGHT
            )));
        }
        if !(options.oversample.is_finite() && options.oversample > 0.0) {
            return Err(Error::Input(format!(
                "oversample {} must be positive",
                options.oversample
            )));
        }
        let max_side = gpu.max_image_side().min(4096);
        let mut sizes: Vec<(u32, u32)> = Vec::new();
        let mut vertices: Vec<FilmVertex> = Vec::new();
        let mut draws = Vec::new();
        for (model, mask) in models {
            for cell in model.samples.iter().flat_map(|s| &s.cells) {
                let size = render_size(cell, options.oversample, max_side);
                let camera = cell_camera(cell, size)?;
                let first = vertices.len() as u32;
                push_triangles(cell, &camera, &mut vertices);
                let count = vertices.len() as u32 - first;
                if count == 0 {
                    continue;
                }
                let bucket = match sizes.iter().position(|s| *s == size) {
                    Some(i) => i,
                    None => {
                        sizes.push(size);
                        sizes.len() - 1
                    }
                };
                let slot = draws
                    .iter()
                    .filter(|d: &&CellDraw| d.bucket == bucket)
                    .count();
                draws.push(CellDraw {
                    camera,
                    cop: cell.cop,
                    bucket,
                    slot,
                    first,
                    count,
                    mask: *mask,
                });
            }
        }
        if vertices.is_empty() {
            return Err(Error::Input(
                "the lens passes no light to the film (every ray is blocked)".into(),
            ));
        }
        let film_pass = FilmPass::new(gpu, sizes.len() as u32)?;
        let target = FilmTarget::new(gpu, &film_pass, film.width, film.height)?;
        let mut buckets = Vec::with_capacity(sizes.len());
        for (index, size) in sizes.into_iter().enumerate() {
            let camera = draws
                .iter()
                .find(|d| d.camera.width == size.0 && d.camera.height == size.1)
                .map(|d| d.camera.clone())
                .ok_or_else(|| Error::internal("bucket without a cell"))?;
            let mut desc = GeometryDesc::new(
                camera,
                Projection::Pinhole,
                Outputs::color_only(Some(ColorFormat::Rgba8)),
            );
            desc.near = options.near;
            desc.far = options.far;
            desc.final_layout = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
            let pass = GeometryPass::new(gpu, desc)?;
            let targets = GeometryTargets::new(gpu, &pass)?;
            let view = targets
                .color()
                .map(|i| i.view)
                .ok_or_else(|| Error::internal("cell render without colour"))?;
            let set = film_pass.bind_image(view)?;
            let count = draws.iter().filter(|d| d.bucket == index).count();
            let slots = (0..frames)
                .map(|_| pass.slots(count as u32))
                .collect::<Result<Vec<_>>>()?;
            buckets.push(Bucket {
                pass,
                targets,
                slots,
                set,
            });
        }
        let vertices = Buffer::from_pod(
            gpu,
            "film.vertices",
            &vertices,
            vk::BufferUsageFlags::VERTEX_BUFFER,
        )?;
        Ok(LensRenderer {
            film: film_pass,
            target,
            buckets,
            draws,
            vertices,
            current: 0,
        })
    }

    /// Perspective projections per frame.
    pub fn projection_count(&self) -> usize {
        self.draws.len()
    }

    /// Prepares a frame of `mesh` seen from `pose` (world → camera frame, origin at the lens's
    /// front vertex): writes every cell's camera and pose. Host writes: no recorded frame of
    /// this renderer may be executing.
    ///
    /// # Safety
    /// This writes the selected frame's host-visible uniforms and rewrites its descriptor sets
    /// ([`Self::select_frame`]): no recorded work of that frame may be pending on the GPU (wait
    /// for its fence first), as Vulkan requires of descriptor sets and memory the device reads.
    pub unsafe fn prepare(&mut self, mesh: &MeshBuffers, pose: &Pose) -> Result<()> {
        for b in &self.buckets {
            // SAFETY: this function's contract: no recorded work of this renderer is pending.
            unsafe { b.pass.bind_slots_mesh(&b.slots[self.current], mesh) };
        }
        for draw in &self.draws {
            let b = &self.buckets[draw.bucket];
            // The cell's camera sits at its COP, axes as the lens's camera frame.
            let cell_pose = Pose {
                rotation: pose.rotation,
                translation: pose.translation - draw.cop,
            };
            // SAFETY: this function's contract: no recorded work of this renderer is pending.
            unsafe {
                b.pass.set_slot(
                    &b.slots[self.current],
                    draw.slot,
                    &draw.camera,
                    &cell_pose,
                    &cell_pose,
                )
            }?;
        }
        Ok(())
    }

    /// Records a prepared frame: the film cleared, then every cell rendered and added. The
    /// film is left in `COLOR_ATTACHMENT_OPTIMAL` ([`Self::film`]).
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass on a graphics queue of this renderer's
    /// device, after [`Self::prepare`] with `mesh` (uploaded, its texture recorded); all must
    /// stay alive until the work completes.
    pub unsafe fn record(&self, cmd: vk::CommandBuffer, mesh: &MeshBuffers) {
        // SAFETY: the caller upholds `record`'s contract: `cmd` is recording outside a render
        // pass on a graphics queue, after `prepare` filled every slot and bound `mesh`'s
        // texture. Each bucket's targets were made for its pass and its film set samples their
        // colour, which the geometry pass leaves in SHADER_READ_ONLY_OPTIMAL; each draw's
        // vertex range was pushed into `vertices` in `new`. Every render pass is ended inside.
        unsafe {
            self.film.record_clear(cmd, &self.target);
            for draw in &self.draws {
                let b = &self.buckets[draw.bucket];
                b.pass
                    .record_slot(cmd, &b.targets, mesh, &b.slots[self.current], draw.slot);
                self.film.record_cell(
                    cmd,
                    &self.target,
                    b.set,
                    &self.vertices,
                    draw.first,
                    draw.count,
                    draw.mask,
                );
            }
        }
    }

    /// Makes frame `frame` (modulo the options' `frames_in_flight`) the one
    /// [`Self::prepare`] writes and [`Self::record`] records.
    pub fn select_frame(&mut self, frame: usize) {
        self.current = frame % self.buckets.first().map_or(1, |b| b.slots.len().max(1));
    }

    /// The film image the frame accumulates into.
    pub fn film(&self) -> &FilmTarget {
        &self.target
    }
}

/// The render size of a cell: its film extent × `oversample`, a one-pixel margin, rounded
/// up to a multiple of 32 so that cells of about one size share a pipeline.
fn render_size(cell: &Cell, oversample: f64, max_side: u32) -> (u32, u32) {
    let (lo, hi) = cell.vertices.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), v| (lo.min(v.film_px), hi.max(v.film_px)),
    );
    let side = |extent: f64| {
        ((extent * oversample).ceil().max(1.0) as u32 + 2)
            .next_multiple_of(32)
            .clamp(32, max_side)
    };
    (side(hi.x - lo.x), side(hi.y - lo.y))
}

/// The pinhole camera of a cell: its projected bounds fill the render but for a one-pixel
/// margin (OpenCV convention: `min` lands on u = 0.5, the edge between pixels 0 and 1).
fn cell_camera(cell: &Cell, (w, h): (u32, u32)) -> Result<Camera> {
    let span = (cell.max - cell.min).max(DVec2::splat(1e-9));
    let fx = (w as f64 - 2.0) / span.x;
    let fy = (h as f64 - 2.0) / span.y;
    Camera::new(
        w,
        h,
        Intrinsics {
            fx,
            fy,
            cx: 0.5 - fx * cell.min.x,
            cy: 0.5 - fy * cell.min.y,
        },
        OpenCvDistortion::default(),
    )
    .map_err(|e| Error::Input(format!("cell projection: {e}")))
}

/// Two triangles per grid quad whose four rays all pass the lens.
fn push_triangles(cell: &Cell, camera: &Camera, out: &mut Vec<FilmVertex>) {
    let row = cell.n as usize + 1;
    let i = &camera.intrinsics;
    let vertex = |k: usize| -> Option<FilmVertex> {
        let v = &cell.vertices[k];
        let q = v.projected?;
        let u = i.fx * q.x + i.cx;
        let w = i.fy * q.y + i.cy;
        Some(FilmVertex {
            film_px: v.film_px.as_vec2().to_array(),
            cell_uv: [
                ((u + 0.5) / camera.width as f64) as f32,
                ((w + 0.5) / camera.height as f64) as f32,
            ],
            weight: v.weight as f32,
            _pad: 0.0,
        })
    };
    for j in 0..cell.n as usize {
        for a in 0..cell.n as usize {
            let k = j * row + a;
            let (Some(p00), Some(p10), Some(p01), Some(p11)) = (
                vertex(k),
                vertex(k + 1),
                vertex(k + row),
                vertex(k + row + 1),
            ) else {
                continue;
            };
            out.extend_from_slice(&[p00, p10, p01, p10, p11, p01]);
        }
    }
}
