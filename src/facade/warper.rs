//! The post-processing warp as a reusable object: built once per camera, direction, method,
//! chromatic setting and source camera, then run on host images or recorded into the caller's
//! command buffer with the caller's images.

use std::fmt;
use std::str::FromStr;

use ash::vk;

use super::image::{check_host_shape, host_to_texels, texels_to_host};
use crate::gpu::{Gpu, Image};
use crate::host::warp_images::WarpImages;
use crate::imaging::cpu_warp::{Border, Sampling};
use crate::imaging::{Pixels, Raster};
use crate::model::warp::WarpGeometry;
use crate::model::{Camera, InverseMethod};
use crate::pass::warp::{Coordinates, PixelFormat, WarpDesc, WarpPass};
use crate::{Device, Error, HostImage, HostImageMut, HostPixels, Result};

/// Which way an image goes through the lens.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WarpDirection {
    /// Simulate the lens: a pinhole image in, the lens image out (the inverse model per output
    /// pixel; Lambers et al., Sec. 3.3).
    Distort,
    /// Rectify a lens image: the lens image in, a pinhole image out (the forward model per
    /// output pixel, as `cv2.initUndistortRectifyMap` + `cv2.remap`).
    Undistort,
    /// Pre-distort an image for a headset lens: the screen shows what the lens will undo (the
    /// Durham radial-correction paper). The same warp as [`WarpDirection::Undistort`].
    Precorrect,
}

impl FromStr for WarpDirection {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "distort" => Ok(WarpDirection::Distort),
            "undistort" => Ok(WarpDirection::Undistort),
            "precorrect" => Ok(WarpDirection::Precorrect),
            _ => Err(Error::input(format!(
                "direction `{s}`: expected distort, undistort or precorrect"
            ))),
        }
    }
}

/// How output pixels find their source: a coordinate map built once (`lut`), or a method
/// solved per pixel every frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WarpMethod {
    /// A map built once with Newton, then sampled (the cheapest per frame).
    Lut,
    /// Solve per pixel with this inverse (distort) or the forward model (`newton`, the other
    /// directions).
    PerPixel(InverseMethod),
}

impl FromStr for WarpMethod {
    type Err = Error;
    /// `lut`, `newton`, `heikkila` or `fixed-point:N`, as the command line's `--method`.
    fn from_str(s: &str) -> Result<Self> {
        if s == "lut" {
            return Ok(WarpMethod::Lut);
        }
        s.parse()
            .map(WarpMethod::PerPixel)
            .map_err(|e: crate::model::ModelError| {
                Error::input(
                    e.to_string()
                        .replace("newton, heikkila", "newton, lut, heikkila"),
                )
            })
    }
}

impl fmt::Display for WarpMethod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            WarpMethod::Lut => write!(f, "lut"),
            WarpMethod::PerPixel(m) => write!(f, "{m}"),
        }
    }
}

/// Frames in flight a [`Warper`] keeps descriptor sets for unless told otherwise: double
/// buffering, what engines record by default.
pub const DEFAULT_FRAMES_IN_FLIGHT: usize = 2;

/// What a [`Warper`] is built for. Start from [`WarpOptions::distort`],
/// [`WarpOptions::undistort`] or [`WarpOptions::precorrect`] and change what differs.
#[derive(Debug, Clone)]
pub struct WarpOptions {
    /// Which way the image goes.
    pub direction: WarpDirection,
    /// How coordinates are found (default `lut`).
    pub method: WarpMethod,
    /// Lateral chromatic aberration: magnification of the R, G and B images about the
    /// principal point (e.g. `[1.002, 1.0, 0.998]`).
    pub chromatic: Option<[f64; 3]>,
    /// A full camera per channel (R, G, B), overriding the camera for each: the general form of
    /// lateral colour. Needs `method: Lut`.
    pub channel_cameras: Option<Box<[Camera; 3]>>,
    /// The pinhole side, when it differs from the camera's own intrinsics and size: for
    /// distort the input's (e.g. [`crate::overscan`]), for undistort and precorrect the
    /// output's. It must have no distortion.
    pub source_camera: Option<Camera>,
    /// Undistort and precorrect: the rectification rotation R (row-major, OpenCV's R of
    /// `initUndistortRectifyMap(K, D, R, P)`, a ROS `camera_info`'s R), the rotation from the
    /// lens camera's frame to the frame the output looks along; with `source_camera` as P's
    /// camera this is a stereo pair's rectification. `None`: the identity.
    pub rectification: Option<[[f64; 3]; 3]>,
    /// The images' format (default 8-bit RGBA).
    pub format: PixelFormat,
    /// The interpolation (OpenCV's `INTER_*`): bilinear (default) or bicubic for colour,
    /// nearest for data that must not be blended (IDs, depth).
    pub sampling: Sampling,
    /// What source positions off the source image read (OpenCV's `BORDER_*`): the fill
    /// (default), the edge pixel repeated, or the image mirrored. Pixels the lens gives no
    /// source at all (outside the model's valid domain) take the fill whatever the border.
    pub border: Border,
    /// Value of output pixels with no source, in 0..1 (default transparent black).
    pub fill: [f32; 4],
    /// Frames [`Warper::record`] may have in flight at once (default 2, at most 8): the
    /// warper keeps one descriptor set per frame, so the caller may record frame N + 1, with
    /// other images, while frame N still executes.
    pub frames_in_flight: usize,
}

impl WarpOptions {
    fn new(direction: WarpDirection) -> Self {
        WarpOptions {
            direction,
            method: WarpMethod::Lut,
            chromatic: None,
            channel_cameras: None,
            source_camera: None,
            rectification: None,
            format: PixelFormat::Rgba8,
            sampling: Sampling::Bilinear,
            border: Border::Constant,
            fill: [0.0; 4],
            frames_in_flight: DEFAULT_FRAMES_IN_FLIGHT,
        }
    }
    /// Simulate the lens on a pinhole image.
    pub fn distort() -> Self {
        Self::new(WarpDirection::Distort)
    }
    /// Rectify a lens image.
    pub fn undistort() -> Self {
        Self::new(WarpDirection::Undistort)
    }
    /// Pre-distort for a headset lens.
    pub fn precorrect() -> Self {
        Self::new(WarpDirection::Precorrect)
    }

    /// The warp these options describe for `camera`, checked, as f64 geometry (a type of the
    /// `model` layer): where each output pixel takes its light from. The GPU warp, the CPU
    /// reference warp and the coordinate maps all follow it.
    pub fn geometry(&self, camera: &Camera) -> Result<crate::model::warp::WarpGeometry> {
        warp_geometry(camera, self)
    }
}

/// The warp's geometry for `camera` and `options`, checked: the f64 description the GPU warp,
/// the CPU reference warp and the maps all follow.
pub(crate) fn warp_geometry(camera: &Camera, options: &WarpOptions) -> Result<WarpGeometry> {
    let method = match (options.method, options.direction) {
        (WarpMethod::PerPixel(m), WarpDirection::Distort) => m,
        (WarpMethod::PerPixel(InverseMethod::Newton), _) | (WarpMethod::Lut, _) => {
            InverseMethod::Newton
        }
        (WarpMethod::PerPixel(m), _) => {
            return Err(Error::argument(
                "method",
                format!("`{m}`: undistort and precorrect use the forward model; choose newton (per pixel) or lut (a map)"),
            ))
        }
    };
    camera
        .check_method(method)
        .map_err(|e| Error::argument("method", format!("`{method}`: {e}")))?;
    let mut geometry = match options.direction {
        WarpDirection::Distort => WarpGeometry::distort(camera.clone(), method),
        WarpDirection::Undistort | WarpDirection::Precorrect => {
            WarpGeometry::undistort(camera.clone())
        }
    };
    if options.source_camera.is_none() && !camera.model().has_focal_length() {
        return Err(Error::argument(
            "source_camera",
            format!(
                "the `{}` model has no pinhole focal length for the pinhole side of the warp: give that side's camera",
                camera.model_name()
            ),
        ));
    }
    if let Some(p) = &options.source_camera {
        if !p.is_pinhole() {
            return Err(Error::argument(
                "source_camera",
                "the source camera is the pinhole side of the warp and must have no distortion",
            ));
        }
        geometry = geometry.with_ideal(p.intrinsics, (p.width, p.height))?;
    }
    if let Some(r) = options.rectification {
        geometry = geometry
            .with_rectification(r)
            .map_err(|e| Error::argument("rectification", e.to_string()))?;
    }
    if let Some(c) = options.chromatic {
        geometry = geometry
            .with_chromatic(c)
            .map_err(|e| Error::argument("chromatic", e.to_string()))?;
    }
    if let Some(cams) = &options.channel_cameras {
        if options.method != WarpMethod::Lut {
            return Err(Error::argument(
                "method",
                "per-channel cameras run through a map: the method must be lut",
            ));
        }
        for c in cams.iter() {
            if (c.width, c.height) != (camera.width, camera.height) {
                return Err(Error::input(format!(
                    "a channel camera must have the camera's size {}×{}, not {}×{}",
                    camera.width, camera.height, c.width, c.height
                )));
            }
        }
        geometry.channel_cameras = Some(cams.clone());
    }
    Ok(geometry)
}

/// One of the caller's images: a 2D storage image with a view, and its size.
#[derive(Debug, Clone, Copy)]
pub struct ImageRef {
    /// The image.
    pub image: vk::Image,
    /// A view of its one mip level and layer.
    pub view: vk::ImageView,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

/// The result of [`Warper::run`]: the warped image and its validity mask.
#[derive(Debug, Clone)]
pub struct Warped {
    /// The output image, in the input's pixel type.
    pub image: Raster,
    /// Per output pixel: `true` where it has a source in the valid domain.
    pub mask: Vec<bool>,
}

/// A warp built once and run on every frame.
///
/// ```no_run
/// use vklens::{Camera, Device, WarpOptions, Warper};
/// let device = Device::new()?;
/// let camera = Camera::load("camera.yml")?;
/// let mut warper = Warper::new(device.gpu(), &camera, &WarpOptions::distort())?;
/// let pinhole = vklens::Raster::load("pinhole.png")?;
/// let lens = warper.run(&device, &pinhole)?;
/// lens.image.save("lens.png")?;
/// # Ok::<(), vklens::Error>(())
/// ```
pub struct Warper {
    gpu: Gpu,
    pass: WarpPass,
    geometry: WarpGeometry,
    source_camera: Camera,
    direction: WarpDirection,
    /// The mask bound when the caller passes none (the shader always writes one).
    own_mask: Image,
    /// The views each frame's descriptor set is bound to now.
    bound: Vec<Option<[vk::ImageView; 3]>>,
    /// Frames recorded so far: the next one uses set `frame % frames_in_flight`.
    frame: usize,
    /// Images for [`Warper::run`], made on its first call.
    headless: Option<WarpImages>,
    /// Whether the map build has been recorded (it runs once).
    prepared_headless: std::cell::Cell<bool>,
}

impl Warper {
    /// Builds the warp's pipelines and, for `lut`, its map images (the maps are built on the
    /// GPU by [`Warper::record_prepare`] or the first [`Warper::run`]).
    pub fn new(gpu: &Gpu, camera: &Camera, options: &WarpOptions) -> Result<Self> {
        if matches!(options.format, PixelFormat::R32Uint | PixelFormat::R32Float)
            && options.sampling != Sampling::Nearest
        {
            return Err(Error::input(
                "object IDs and depth must be warped with nearest sampling",
            ));
        }
        let geometry = warp_geometry(camera, options)?;
        crate::pass::warp::check_sizes(gpu, &geometry)?;
        // The pinhole side: the input when distorting, the output otherwise.
        let (pw, ph) = match options.direction {
            WarpDirection::Distort => geometry.source_size,
            _ => geometry.output_size,
        };
        let source_camera = Camera::from_coeffs(pw, ph, geometry.ideal, &[0.0; 5])?;
        let desc = WarpDesc {
            geometry: geometry.clone(),
            coordinates: match options.method {
                WarpMethod::Lut => Coordinates::Map,
                WarpMethod::PerPixel(_) => Coordinates::Analytic,
            },
            sampling: options.sampling,
            border: options.border,
            format: options.format,
            fill: options.fill,
            write_mask: true,
        };
        if !(1..=crate::pass::warp::MAX_FRAMES_IN_FLIGHT).contains(&options.frames_in_flight) {
            return Err(Error::argument(
                "frames_in_flight",
                format!(
                    "{}: expected 1 to {} frames in flight",
                    options.frames_in_flight,
                    crate::pass::warp::MAX_FRAMES_IN_FLIGHT
                ),
            ));
        }
        let pass = WarpPass::with_frames(gpu, desc, options.frames_in_flight)?;
        let (ow, oh) = geometry.output_size;
        let own_mask = Image::new_2d(
            gpu,
            "warper.mask",
            vk::Format::R8_UNORM,
            ow,
            oh,
            vk::ImageUsageFlags::STORAGE,
        )?;
        Ok(Warper {
            gpu: gpu.clone(),
            pass,
            geometry,
            source_camera,
            direction: options.direction,
            own_mask,
            bound: vec![None; options.frames_in_flight],
            frame: 0,
            headless: None,
            prepared_headless: std::cell::Cell::new(false),
        })
    }

    /// The pinhole side's camera actually used (the input's for distort, the output's for
    /// undistort and precorrect).
    pub fn source_camera(&self) -> &Camera {
        &self.source_camera
    }

    /// Which way the warp goes.
    pub fn direction(&self) -> WarpDirection {
        self.direction
    }

    /// `(width, height)` of the images the warp takes.
    pub fn input_size(&self) -> (u32, u32) {
        self.geometry.source_size
    }

    /// `(width, height)` of the images the warp makes.
    pub fn output_size(&self) -> (u32, u32) {
        self.geometry.output_size
    }

    /// The f64 geometry the warp follows.
    #[cfg(test)]
    pub(crate) fn geometry(&self) -> &WarpGeometry {
        &self.geometry
    }

    /// Records the one-off work: the map build (for `lut`) and the layout transitions of the
    /// warp's own images, followed by the barrier the warp needs. Nothing of the caller's is
    /// touched.
    ///
    /// # Safety
    /// `cmd` must be recording, outside a render pass, on a queue with compute support of the
    /// device this warper was built on. Record it once, before the first [`Warper::record`],
    /// and not again while that work is pending.
    pub unsafe fn record_prepare(&self, cmd: vk::CommandBuffer) {
        // SAFETY: the caller upholds this function's contract, which is the pass's own
        // `record_prepare` contract; `own_mask` is this warper's and nothing else uses it.
        unsafe {
            self.pass.record_prepare(cmd);
            // The fallback mask is written by the warp as a storage image.
            crate::gpu::record_discard_for_compute_write(&self.gpu, cmd, [&self.own_mask]);
        }
    }

    /// Records the warp of `source` into `output` (and `mask`, `R8_UNORM`, 255 where the pixel
    /// has a source, 0 where it has none). Checks the sizes first; on an error nothing is
    /// recorded.
    ///
    /// Layouts: every image is in `VK_IMAGE_LAYOUT_GENERAL` on entry and is left so. Usage:
    /// `STORAGE` for all three. The warp is one compute dispatch: it reads `source` and writes
    /// `output` and `mask` with `SHADER_READ` / `SHADER_WRITE` in `COMPUTE_SHADER`. The
    /// caller's barriers make the source's writes visible to it before, and its writes
    /// visible to whatever reads them after. It never submits and never waits.
    ///
    /// Frames in flight: the warper keeps one descriptor set per frame in flight
    /// ([`WarpOptions::frames_in_flight`], N) and the k-th call uses set k mod N, rewriting it
    /// only when its views differ from those it was last bound to. So up to N − 1 earlier
    /// warps may still execute while this one is recorded, whatever images they used.
    ///
    /// # Safety
    /// `cmd` must be recording outside a render pass, after [`Warper::record_prepare`] was
    /// recorded (in this or an earlier submission that has completed or precedes it). The
    /// images must be alive until the work completes. The warp recorded N calls before this
    /// one (N = frames in flight) must have completed when the views differ from its views:
    /// its descriptor set is rewritten then.
    pub unsafe fn record(
        &mut self,
        cmd: vk::CommandBuffer,
        source: &ImageRef,
        output: &ImageRef,
        mask: Option<&ImageRef>,
    ) -> Result<()> {
        let check = |what: &str, image: &ImageRef, want: (u32, u32)| {
            if (image.width, image.height) != want {
                return Err(Error::input(format!(
                    "{what}: the image is {}×{} but the warp expects {}×{}",
                    image.width, image.height, want.0, want.1
                )));
            }
            if image.view == vk::ImageView::null() {
                return Err(Error::input(format!("{what}: null image view")));
            }
            Ok(())
        };
        check("source", source, self.input_size())?;
        check("output", output, self.output_size())?;
        if let Some(m) = mask {
            check("mask", m, self.output_size())?;
        }
        let views = [
            source.view,
            output.view,
            mask.map_or(self.own_mask.view, |m| m.view),
        ];
        // SAFETY: the caller guarantees that the warp recorded N calls ago, the last user of
        // this frame's set, has completed when the views change (see `# Safety`).
        unsafe { self.bind(views) };
        // SAFETY: the caller upholds `record`'s contract (recording outside a render pass,
        // after `record_prepare`, the images alive and in GENERAL), and the views just bound
        // were checked non-null and of the sizes the pass was built for.
        unsafe { self.pass.record(cmd) };
        Ok(())
    }

    /// Selects the next frame's descriptor set and binds `views` to it where they differ from
    /// the views it holds.
    ///
    /// # Safety
    /// When `views` differ from that set's, the last warp recorded with it (N calls ago) must
    /// have completed.
    unsafe fn bind(&mut self, views: [vk::ImageView; 3]) {
        let slot = self.frame % self.bound.len();
        self.frame = self.frame.wrapping_add(1);
        self.pass.select_frame(slot);
        if self.bound[slot] != Some(views) {
            // SAFETY: the caller upholds this function's contract.
            unsafe { self.pass.bind(views[0], views[1], views[2]) };
            self.bound[slot] = Some(views);
        }
    }

    /// Warps a host image on a headless device: upload, warp, read back, and wait. The image
    /// must be `input_size()` and of the warper's format (8-bit RGBA for `Rgba8`; 16-bit and
    /// float images for `Rgba32F`).
    pub fn run(&mut self, device: &Device, image: &Raster) -> Result<Warped> {
        let want = self.input_size();
        if (image.width, image.height) != want {
            return Err(Error::input(format!(
                "the input is {}×{} but the warp expects {}×{}",
                image.width, image.height, want.0, want.1
            )));
        }
        let fits = matches!(
            (&image.pixels, self.pass.desc().format),
            (Pixels::Rgba8(_), PixelFormat::Rgba8)
                | (Pixels::R32Uint(_), PixelFormat::R32Uint)
                | (
                    Pixels::Rgba32F(_),
                    PixelFormat::Rgba32F | PixelFormat::R32Float
                )
                | (Pixels::Rgba8(_), PixelFormat::Rgba32F)
        );
        if !fits {
            return Err(Error::input(format!(
                "the input's pixels do not fit the warper's format {:?}",
                self.pass.desc().format
            )));
        }
        self.headless_images()?.stage(image)?;
        self.submit_headless(device)?;
        let (raster, mask) = self.headless_images()?.read(image.bit_depth)?;
        Ok(Warped {
            image: raster,
            mask: mask.iter().map(|&m| m > 127).collect(),
        })
    }

    /// Warps a borrowed host image into a borrowed output on a headless device, converting
    /// straight into the upload buffer and straight out of the download buffer (no other host
    /// copy). `input` is `input_size()`, `output` is `output_size()` with as many channels and
    /// the same sample type; 8-bit images need a warper of format `Rgba8`, 16-bit and float
    /// ones `Rgba32F`. `mask`, when given, gets one `bool` per output pixel: `true` where it
    /// has a source in the valid domain.
    pub fn run_host(
        &mut self,
        device: &Device,
        input: &HostImage<'_>,
        output: &mut HostImageMut<'_>,
        mask: Option<&mut [bool]>,
    ) -> Result<()> {
        check_host_shape(
            "input",
            (input.width, input.height, input.channels),
            input.pixels.len(),
            self.input_size(),
        )?;
        check_host_shape(
            "output",
            (output.width, output.height, output.channels),
            output.pixels.len(),
            self.output_size(),
        )?;
        if output.channels != input.channels || output.pixels.kind() != input.pixels.kind() {
            return Err(Error::input(format!(
                "output: {} channel(s) of {}, but the input has {} of {}",
                output.channels,
                output.pixels.kind(),
                input.channels,
                input.pixels.kind()
            )));
        }
        let format = self.pass.desc().format;
        let fits = matches!(
            (&input.pixels, format),
            (HostPixels::U8(_), PixelFormat::Rgba8)
                | (
                    HostPixels::U16(_) | HostPixels::F32(_),
                    PixelFormat::Rgba32F
                )
        );
        if !fits {
            return Err(Error::input(format!(
                "input: {} samples do not fit a warper of format {format:?} (8-bit needs Rgba8, 16-bit and float need Rgba32F)",
                input.pixels.kind()
            )));
        }
        let (ow, oh) = self.output_size();
        if let Some(m) = &mask {
            if m.len() != ow as usize * oh as usize {
                return Err(Error::input(format!(
                    "mask: {} entries, but the output has {ow}×{oh} pixels",
                    m.len()
                )));
            }
        }
        self.headless_images()?
            .stage_with(|texels| host_to_texels(input, texels))??;
        self.submit_headless(device)?;
        self.headless_images()?.read_with(|texels, valid| {
            texels_to_host(texels, output)?;
            if let Some(mask) = mask {
                for (m, &v) in mask.iter_mut().zip(valid) {
                    *m = v > 127;
                }
            }
            Ok::<(), Error>(())
        })?
    }

    /// The images [`Warper::run`] and [`Warper::run_host`] warp through, made on first use.
    fn headless_images(&mut self) -> Result<&mut WarpImages> {
        if self.headless.is_none() {
            self.headless = Some(WarpImages::allocate(&self.gpu, self.pass.desc())?);
        }
        self.headless
            .as_mut()
            .ok_or_else(|| Error::internal("headless warp images missing"))
    }

    /// Uploads what is staged, warps (building the maps on the first run) and downloads, then
    /// waits.
    fn submit_headless(&mut self, device: &Device) -> Result<()> {
        let views = {
            let i = self.headless_images()?;
            [i.source.view, i.output.view, i.mask.view]
        };
        // SAFETY: the previous run has completed (`submit` waits on its fence), and a caller's
        // recorded warp is theirs to have waited for (`record`'s contract).
        unsafe { self.bind(views) };
        let Some(images) = self.headless.as_ref() else {
            return Err(Error::internal("headless warp images missing"));
        };
        crate::host::warp::run_staged(
            device.context(),
            images,
            &self.pass,
            !self.prepared_headless.get(),
        )?;
        self.prepared_headless.set(true);
        Ok(())
    }

    /// The warp's coordinate map: per output pixel, the source position `[x, y]` its light
    /// comes from (NaN where it has none in the valid domain), row-major, ready for
    /// `cv2.remap`. Solved per pixel with Newton on the GPU, then refined on the host in f64
    /// (the f32 solve alone loses up to a tenth of a pixel next to a fold), so every entry is
    /// the f64 coordinate rounded to f32.
    ///
    /// A `lut` warper hands out the maps it warps with (built by its first run or prepare);
    /// a per-pixel method has none, and its coordinates are solved by a map build of their own.
    /// Either way the device is waited for: no warp recorded into your own command buffers may
    /// be pending while the maps are built.
    pub fn maps(&self, device: &Device) -> Result<Vec<[f32; 2]>> {
        let ctx = device.context();
        let mut maps = if self.pass.desc().coordinates == Coordinates::Map {
            let maps =
                crate::host::warp::read_pass_maps(ctx, &self.pass, !self.prepared_headless.get())?;
            self.prepared_headless.set(true);
            maps
        } else {
            crate::host::warp::read_maps(ctx, &self.geometry, Coordinates::Map)?
        };
        // G is the geometric map (the only one without chromatic aberration).
        let index = if maps.len() == 3 { 1 } else { 0 };
        let mut map = maps.swap_remove(index);
        let width = self.geometry.output_size.0.max(1) as usize;
        for (i, m) in map.iter_mut().enumerate() {
            if !(m[0].is_finite() && m[1].is_finite()) {
                continue;
            }
            let p = glam::DVec2::new((i % width) as f64, (i / width) as f64);
            let gpu = glam::DVec2::new(m[0] as f64, m[1] as f64);
            if let Some(r) = self.geometry.refine_coordinate(p, gpu, 1) {
                *m = [r.x as f32, r.y as f32];
            }
        }
        Ok(map)
    }
}

/// The pinhole camera whose image covers every valid pixel of `camera` with `density` source
/// pixels per output pixel at the principal point: the source a distort warp needs so that
/// a barrel lens gets its borders (Lambers et al., Sec. 3.3).
///
/// ```
/// let k = [[400.0, 0.0, 399.5], [0.0, 400.0, 299.5], [0.0, 0.0, 1.0]];
/// let camera = vklens::Camera::from_opencv(k, &[-0.2, 0.03, 0.0, 0.0], (800, 600))?;
/// let source = vklens::overscan(&camera, 1.0)?;
/// assert!(source.width > 800 && source.height > 600);
/// # Ok::<(), vklens::Error>(())
/// ```
pub fn overscan(camera: &Camera, density: f64) -> Result<Camera> {
    let o = crate::model::overscan::overscan(camera, density)?;
    Camera::from_coeffs(o.width, o.height, o.intrinsics, &[0.0; 5]).map_err(Error::from)
}
