//! The geometry of an image warp, in f64: for each output pixel, where its light comes from in
//! the source image, per colour channel. `glsl/include/warp_coords.glsl` mirrors
//! [`WarpGeometry::source_coordinate`] step for step; the CPU reference warp and the GPU warp
//! both start here.

use glam::DVec2;

use super::{Intrinsics, InverseMethod, ModelError, OpenCvCamera};

/// Which way the warp goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// Simulate the lens: the source is a pinhole image, the output the lens image
    /// (inverse model per output pixel; seed 000 Sec. 3.3).
    Distort,
    /// Rectify a lens image: the source is the lens image, the output a pinhole image (forward
    /// model per output pixel, like OpenCV's initUndistortRectifyMap + remap). Seed 002's
    /// pre-correction is this direction with the Brown model (see [`super::BrownRadial::to_opencv`]).
    Undistort,
}

/// Everything that decides a warp's coordinates.
#[derive(Debug, Clone)]
pub struct WarpGeometry {
    /// The lens: the output camera when distorting, the source camera when undistorting.
    pub camera: OpenCvCamera,
    /// The pinhole side: the source's intrinsics when distorting (e.g. overscanned), the
    /// output's when undistorting.
    pub ideal: Intrinsics,
    pub source_size: (u32, u32),
    pub output_size: (u32, u32),
    pub direction: Direction,
    /// Inverse method (distort only).
    pub method: InverseMethod,
    /// Lateral chromatic aberration: magnification of the R, G, B images about the principal
    /// point (seed 002 Sec. III, Lensfun's linear TCA), `None` for none.
    pub chromatic: Option<[f64; 3]>,
    /// A full camera per channel (R, G, B), overriding `camera` — the general form of lateral
    /// colour. Only through a precomputed map on the GPU.
    pub channel_cameras: Option<Box<[OpenCvCamera; 3]>>,
}

impl WarpGeometry {
    /// Distort a pinhole image of `camera`'s own intrinsics and size.
    pub fn distort(camera: OpenCvCamera, method: InverseMethod) -> Self {
        let size = (camera.width, camera.height);
        WarpGeometry {
            ideal: camera.intrinsics,
            camera,
            source_size: size,
            output_size: size,
            direction: Direction::Distort,
            method,
            chromatic: None,
            channel_cameras: None,
        }
    }

    /// Undistort a lens image of `camera` into a pinhole image of the same intrinsics and size.
    pub fn undistort(camera: OpenCvCamera) -> Self {
        WarpGeometry {
            direction: Direction::Undistort,
            ..Self::distort(camera, InverseMethod::Newton)
        }
    }

    /// Uses a pinhole side with other intrinsics and size (an overscanned source when
    /// distorting; another output camera when undistorting).
    pub fn with_ideal(mut self, ideal: Intrinsics, size: (u32, u32)) -> Result<Self, ModelError> {
        // Reuse the camera checks for the pinhole side.
        OpenCvCamera::from_coeffs(size.0, size.1, ideal, &[0.0; 4])?;
        self.ideal = ideal;
        match self.direction {
            Direction::Distort => self.source_size = size,
            Direction::Undistort => self.output_size = size,
        }
        Ok(self)
    }

    /// Adds lateral chromatic aberration as per-channel magnifications.
    pub fn with_chromatic(mut self, scales: [f64; 3]) -> Result<Self, ModelError> {
        for (name, s) in ["R scale", "G scale", "B scale"].into_iter().zip(scales) {
            super::check_finite(name, s, 10.0)?;
            if !(s > 0.1) {
                return Err(ModelError::Other(format!("{name} must be > 0.1, got {s}")));
            }
        }
        self.chromatic = Some(scales);
        Ok(self)
    }

    /// Whether channels differ (three coordinates per pixel).
    pub fn is_chromatic(&self) -> bool {
        self.chromatic.is_some() || self.channel_cameras.is_some()
    }

    /// The camera of channel `c` (0 R, 1 G, 2 B).
    pub fn channel_camera(&self, c: usize) -> &OpenCvCamera {
        match &self.channel_cameras {
            Some(cams) => &cams[c],
            None => &self.camera,
        }
    }

    /// The magnification of channel `c`.
    pub fn channel_scale(&self, c: usize) -> f64 {
        self.chromatic.map(|s| s[c]).unwrap_or(1.0)
    }

    /// Whether a source position lies on the source frame `[-0.5, size - 0.5]²`.
    pub fn on_source_frame(&self, s: DVec2) -> bool {
        let (w, h) = self.source_size;
        s.x >= -0.5 && s.y >= -0.5 && s.x <= w as f64 - 0.5 && s.y <= h as f64 - 0.5
    }

    /// The source position of output pixel `p` for channel `c` (0 R, 1 G, 2 B), or `None` when
    /// the light has no valid source (outside the valid domain or the source frame).
    pub fn source_coordinate(&self, p: DVec2, c: usize) -> Option<DVec2> {
        self.model_coordinate(p, c)
            .filter(|&s| self.on_source_frame(s))
    }

    /// As [`WarpGeometry::source_coordinate`] without the source-frame check: what a coordinate
    /// map stores (the warp checks the frame when it samples).
    pub fn model_coordinate(&self, p: DVec2, c: usize) -> Option<DVec2> {
        let cam = self.channel_camera(c);
        let scale = self.channel_scale(c);
        let ideal = &self.ideal;
        match self.direction {
            Direction::Distort => {
                let d = cam.intrinsics.to_normalized(p) / scale;
                Some(ideal.to_pixel(cam.undistort_normalized(d, self.method)?))
            }
            Direction::Undistort => {
                let x = ideal.to_normalized(p);
                // Beyond a fold the forward model wraps back over valid pixels.
                if !cam.domain().contains_ideal(x) {
                    return None;
                }
                Some(cam.intrinsics.to_pixel(cam.distort_normalized(x)? * scale))
            }
        }
    }

    /// The worst error of interpolating this warp's coordinates bilinearly between samples every
    /// `stride` pixels, estimated in f64 at every cell's centre (where bilinear interpolation's
    /// leading-order error peaks), over all channels; `None` if any sample has no source (a
    /// fold in view: there interpolation needs a per-pixel check).
    pub fn coarse_interpolation_error(&self, stride: u32) -> Option<f64> {
        let (w, h) = self.output_size;
        let channels: &[usize] = if self.is_chromatic() {
            &[0, 1, 2]
        } else {
            &[1]
        };
        let s = stride as f64;
        let (cw, ch) = ((w - 1) / stride + 2, (h - 1) / stride + 2);
        let mut worst = 0.0f64;
        for &c in channels {
            let at =
                |i: u32, j: u32| self.model_coordinate(DVec2::new(i as f64 * s, j as f64 * s), c);
            let mut row: Vec<Option<DVec2>> = (0..cw).map(|i| at(i, 0)).collect();
            for j in 1..ch {
                let next: Vec<Option<DVec2>> = (0..cw).map(|i| at(i, j)).collect();
                for i in 0..(cw - 1) as usize {
                    let (a, b, d, e) = (row[i]?, row[i + 1]?, next[i]?, next[i + 1]?);
                    let centre = DVec2::new((i as f64 + 0.5) * s, (j as f64 - 0.5) * s);
                    let exact = self.model_coordinate(centre, c)?;
                    worst = worst.max(((a + b + d + e) * 0.25 - exact).length());
                }
                row = next;
            }
        }
        Some(worst)
    }
}
