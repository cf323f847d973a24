//! The geometry of an image warp, in f64: for each output pixel, where its light comes from in
//! the source image, per colour channel. `glsl/include/warp_coords.glsl` mirrors
//! [`WarpGeometry::source_coordinate`] step for step; the CPU reference warp and the GPU warp
//! both start here.

use glam::{DMat3, DVec2, DVec3};

use super::{Camera, Intrinsics, InverseMethod, ModelError};

/// Which way the warp goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// Simulate the lens: the source is a pinhole image, the output the lens image
    /// (inverse model per output pixel; Lambers et al. Sec. 3.3).
    Distort,
    /// Rectify a lens image: the source is the lens image, the output a pinhole image (forward
    /// model per output pixel, like OpenCV's initUndistortRectifyMap + remap). The Durham radial-correction paper's
    /// pre-correction is this direction with the Brown model (see [`super::BrownRadial::to_opencv`]).
    Undistort,
}

/// Everything that decides a warp's coordinates.
#[derive(Debug, Clone)]
pub struct WarpGeometry {
    /// The lens: the output camera when distorting, the source camera when undistorting.
    pub camera: Camera,
    /// The pinhole side: the source's intrinsics when distorting (e.g. overscanned), the
    /// output's when undistorting.
    pub ideal: Intrinsics,
    pub source_size: (u32, u32),
    pub output_size: (u32, u32),
    pub direction: Direction,
    /// Inverse method (distort only).
    pub method: InverseMethod,
    /// Lateral chromatic aberration: magnification of the R, G, B images about the principal
    /// point (the Durham radial-correction paper Sec. III, Lensfun's linear TCA), `None` for none.
    pub chromatic: Option<[f64; 3]>,
    /// A full camera per channel (R, G, B), overriding `camera` — the general form of lateral
    /// colour. Only through a precomputed map on the GPU.
    pub channel_cameras: Option<Box<[Camera; 3]>>,
    /// Undistort only: the rectification rotation R of OpenCV's `initUndistortRectifyMap` and a
    /// ROS `camera_info` (the rotation from the lens camera's frame to the rectified frame the
    /// output pinhole image looks along). `None` is the identity.
    pub rectification: Option<DMat3>,
}

impl WarpGeometry {
    /// Distort a pinhole image of `camera`'s own intrinsics and size.
    pub fn distort(camera: Camera, method: InverseMethod) -> Self {
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
            rectification: None,
        }
    }

    /// Distort through `camera` from the pinhole source that covers every valid output pixel,
    /// `density` source pixels per output pixel at the principal point (the overscan that
    /// gives a barrel lens its borders, Lambers et al. Sec. 3.3): that source camera and the
    /// warp's geometry.
    pub fn overscanned(
        camera: &Camera,
        method: InverseMethod,
        density: f64,
    ) -> Result<(Camera, Self), ModelError> {
        let ov = super::overscan::overscan(camera, density)?;
        let source = Camera::new(
            ov.width,
            ov.height,
            ov.intrinsics,
            super::OpenCvDistortion::default(),
        )?;
        let geometry = Self::distort(camera.clone(), method)
            .with_ideal(ov.intrinsics, (ov.width, ov.height))?;
        Ok((source, geometry))
    }

    /// Undistort a lens image of `camera` into a pinhole image of the same intrinsics and size.
    pub fn undistort(camera: Camera) -> Self {
        WarpGeometry {
            direction: Direction::Undistort,
            ..Self::distort(camera, InverseMethod::Newton)
        }
    }

    /// Uses a pinhole side with other intrinsics and size (an overscanned source when
    /// distorting; another output camera when undistorting).
    pub fn with_ideal(mut self, ideal: Intrinsics, size: (u32, u32)) -> Result<Self, ModelError> {
        // Reuse the camera checks for the pinhole side.
        Camera::from_coeffs(size.0, size.1, ideal, &[0.0; 4])?;
        self.ideal = ideal;
        match self.direction {
            Direction::Distort => self.source_size = size,
            Direction::Undistort => self.output_size = size,
        }
        Ok(self)
    }

    /// Rectifies as well (undistort only): the output pinhole image looks along the frame that
    /// `r` (row-major, OpenCV's R) turns the lens camera's frame into, as
    /// `cv2.initUndistortRectifyMap(K, D, R, P)` and ROS `image_proc` do. The identity is
    /// stored as no rotation, so the plain path runs.
    pub fn with_rectification(mut self, r: [[f64; 3]; 3]) -> Result<Self, ModelError> {
        if self.direction != Direction::Undistort {
            return Err(ModelError::Other(
                "a rectification rotation applies to undistort (a pinhole output) only".into(),
            ));
        }
        let m = DMat3::from_cols_array_2d(&r).transpose();
        if !m.to_cols_array().iter().all(|v| v.is_finite()) {
            return Err(ModelError::Other(format!("R {r:?} is not finite")));
        }
        // A rotation: RᵀR = I and det R = +1 (to the precision calibration files are written
        // with); anything else would shear or mirror the output.
        let off = (m.transpose() * m - DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .fold(0.0f64, |a, v| a.max(v.abs()));
        if !(off <= 1e-5) || !((m.determinant() - 1.0).abs() <= 1e-5) {
            return Err(ModelError::Other(format!(
                "R {r:?} is not a rotation (RᵀR differs from I by {off:.1e}, det R = {:.6})",
                m.determinant()
            )));
        }
        self.rectification = (m != DMat3::IDENTITY).then_some(m);
        Ok(self)
    }

    /// The homography from an output pixel to the lens camera's ray (undistort): Rᵀ·K_out⁻¹,
    /// or `None` without a rectification (then the plain `(p − c) / f`).
    pub fn output_to_ray(&self) -> Option<DMat3> {
        let r = self.rectification?;
        let i = &self.ideal;
        let k_inv = DMat3::from_cols(
            DVec3::new(1.0 / i.fx, 0.0, 0.0),
            DVec3::new(0.0, 1.0 / i.fy, 0.0),
            DVec3::new(-i.cx / i.fx, -i.cy / i.fy, 1.0),
        );
        Some(r.transpose() * k_inv)
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
    pub fn channel_camera(&self, c: usize) -> &Camera {
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
                let x = match self.output_to_ray() {
                    None => ideal.to_normalized(p),
                    Some(h) => {
                        let ray = h * p.extend(1.0);
                        // A ray the rotation turns behind the lens camera has no image in it.
                        if !(ray.z > 0.0) {
                            return None;
                        }
                        ray.truncate() / ray.z
                    }
                };
                // Beyond a fold the forward model wraps back over valid pixels.
                if !cam.domain().contains_ideal(x) {
                    return None;
                }
                Some(cam.intrinsics.to_pixel(cam.distort_normalized(x)? * scale))
            }
        }
    }

    /// Refines `m`, a coordinate-map entry of output pixel `p` computed in f32, to f64
    /// accuracy: Newton steps in f64 from it (distort), or the forward model itself
    /// (undistort). Near a fold the inverse is ill-conditioned and f32's residual is amplified
    /// there (docs/accuracy.md); from an f32 start a few steps reach f64's. `None` where no
    /// better answer is found (the entry is then kept as it is).
    pub fn refine_coordinate(&self, p: DVec2, m: DVec2, c: usize) -> Option<DVec2> {
        let cam = self.channel_camera(c);
        match self.direction {
            Direction::Distort => {
                let d = cam.intrinsics.to_normalized(p) / self.channel_scale(c);
                let start = self.ideal.to_normalized(m);
                let residual = |x: DVec2| cam.distort_normalized(x).map(|y| y - d);
                let mut x = start;
                // Quadratic convergence from an f32 start: two steps away from folds, a few
                // more where the Jacobian nearly vanishes.
                for _ in 0..8 {
                    let r = residual(x)?;
                    let j = cam.jacobian_normalized(x)?;
                    let det = j.determinant();
                    if !(det.abs() > 1e-300) {
                        return None;
                    }
                    let step = j.inverse() * r;
                    x -= step;
                    if step.length() <= 1e-15 * (1.0 + x.length()) {
                        break;
                    }
                }
                let better = residual(x)?.length() <= residual(start)?.length();
                (better && x.is_finite() && cam.domain().contains_ideal(x))
                    .then(|| self.ideal.to_pixel(x))
            }
            Direction::Undistort => self.model_coordinate(p, c),
        }
    }

    /// The worst error of interpolating this warp's coordinates between samples every `stride`
    /// pixels, as `glsl/upsample_map.comp` does, estimated in f64 at every cell's centre (where
    /// the leading-order error of both interpolations peaks), over all channels. `None` if a
    /// cell corner has no source (a fold in view: there interpolation needs a per-pixel check).
    /// Cubic cells whose outer ring has no source fall back to bilinear, as on the GPU.
    pub fn coarse_interpolation_error(
        &self,
        stride: u32,
        interpolation: MapInterpolation,
    ) -> Option<f64> {
        let channels: &[usize] = if self.is_chromatic() {
            &[0, 1, 2]
        } else {
            &[1]
        };
        let (cells_x, cells_y) = coarse_cells(self.output_size, stride);
        let (cw, ch) = coarse_size(self.output_size, stride);
        let s = stride as f64;
        let centre = lagrange_weights(0.5);
        let mut worst = 0.0f64;
        for &c in channels {
            // Coarse sample k sits at pixel (k - 1) · stride: one ring beyond the cells.
            let grid: Vec<Option<DVec2>> = (0..ch)
                .flat_map(|j| (0..cw).map(move |i| (i, j)))
                .map(|(i, j)| {
                    let p = DVec2::new((i as f64 - 1.0) * s, (j as f64 - 1.0) * s);
                    self.model_coordinate(p, c)
                })
                .collect();
            let at = |i: u32, j: u32| grid[(j * cw + i) as usize];
            for j in 0..cells_y {
                for i in 0..cells_x {
                    let (a, b) = (at(i + 1, j + 1)?, at(i + 2, j + 1)?);
                    let (d, e) = (at(i + 1, j + 2)?, at(i + 2, j + 2)?);
                    // The cubic stencil, row by row, weighted at the centre; None where its
                    // ring has no source (the GPU falls back to bilinear there too).
                    let cubic = || -> Option<DVec2> {
                        let mut sum = DVec2::ZERO;
                        for r in 0..4 {
                            for q in 0..4 {
                                sum +=
                                    at(i + q, j + r)? * (centre[q as usize] * centre[r as usize]);
                            }
                        }
                        Some(sum)
                    };
                    let bilinear = (a + b + d + e) * 0.25;
                    let value = match interpolation {
                        MapInterpolation::Bilinear => bilinear,
                        MapInterpolation::Cubic => cubic().unwrap_or(bilinear),
                    };
                    let p = DVec2::new((i as f64 + 0.5) * s, (j as f64 + 0.5) * s);
                    let exact = self.model_coordinate(p, c)?;
                    worst = worst.max((value - exact).length());
                }
            }
        }
        Some(worst)
    }
}

/// How a coarse coordinate map is interpolated to full resolution (`glsl/upsample_map.comp`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapInterpolation {
    /// The cell's four corners: error O(stride²).
    Bilinear,
    /// Cubic Lagrange through the 4×4 samples around the cell: error O(stride⁴) for the
    /// same solves, so a coarser grid reaches the same accuracy. Where the outer ring has no
    /// source (next to the valid domain's edge) the cell falls back to bilinear.
    Cubic,
}

/// Cubic Lagrange weights of the nodes −1, 0, 1, 2 at `t` ∈ [0, 1] (`vkl_lagrange` in
/// `glsl/upsample_map.comp`).
pub fn lagrange_weights(t: f64) -> [f64; 4] {
    [
        -t * (t - 1.0) * (t - 2.0) / 6.0,
        (t + 1.0) * (t - 1.0) * (t - 2.0) / 2.0,
        -(t + 1.0) * t * (t - 2.0) / 2.0,
        (t + 1.0) * t * (t - 1.0) / 6.0,
    ]
}

/// Cells of a coarse map: every pixel of `output_size` lies in one.
pub fn coarse_cells(output_size: (u32, u32), stride: u32) -> (u32, u32) {
    (
        output_size.0.div_ceil(stride),
        output_size.1.div_ceil(stride),
    )
}

/// Samples of a coarse map: the cells' corners plus one ring beyond them (cubic stencils);
/// sample k sits at pixel (k − 1) · stride.
pub fn coarse_size(output_size: (u32, u32), stride: u32) -> (u32, u32) {
    let (x, y) = coarse_cells(output_size, stride);
    (x + 3, y + 3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lagrange_weights_reproduce_cubics_and_the_nodes() {
        // Exact for every cubic through the nodes −1, 0, 1, 2: the O(h⁴) error of the cubic map.
        let f = |x: f64| 0.3 * x * x * x - 1.7 * x * x + 0.2 * x + 5.0;
        for t in [0.0, 0.125, 0.5, 0.8, 1.0] {
            let w = lagrange_weights(t);
            let value: f64 = (0..4).map(|i| w[i] * f(i as f64 - 1.0)).sum();
            assert!((value - f(t)).abs() < 1e-12, "t {t}: {value} vs {}", f(t));
        }
        assert_eq!(lagrange_weights(0.0), [0.0, 1.0, 0.0, 0.0]);
        assert_eq!(lagrange_weights(1.0), [0.0, 0.0, 1.0, 0.0]);
    }

    #[test]
    fn coarse_maps_cover_every_pixel_with_a_ring_to_spare() {
        for (size, stride) in [((1920, 1080), 8), ((1, 1), 4), ((17, 9), 16), ((16, 8), 8)] {
            let (cx, cy) = coarse_cells(size, stride);
            assert!(
                cx * stride >= size.0 && (cx - 1) * stride < size.0,
                "{size:?}/{stride}"
            );
            assert!(
                cy * stride >= size.1 && (cy - 1) * stride < size.1,
                "{size:?}/{stride}"
            );
            assert_eq!(coarse_size(size, stride), (cx + 3, cy + 3));
        }
    }

    #[test]
    fn cubic_interpolation_of_a_smooth_lens_is_far_below_bilinear() {
        let camera = Camera::new(
            800,
            600,
            Intrinsics {
                fx: 600.0,
                fy: 600.0,
                cx: 400.0,
                cy: 300.0,
            },
            crate::model::OpenCvDistortion::from_coeffs(&[-0.2, 0.05, 0.001, -0.001, 0.0])
                .expect("five coefficients"),
        )
        .expect("valid camera");
        let g = WarpGeometry::distort(camera, InverseMethod::Newton);
        let bilinear = g
            .coarse_interpolation_error(8, MapInterpolation::Bilinear)
            .expect("no fold in view");
        let cubic = g
            .coarse_interpolation_error(8, MapInterpolation::Cubic)
            .expect("no fold in view");
        // O(h²) against O(h⁴): at stride 8 the cubic error is a small fraction of bilinear's.
        assert!(bilinear > 1e-3, "bilinear {bilinear}");
        assert!(
            cubic < bilinear / 20.0,
            "cubic {cubic} vs bilinear {bilinear}"
        );
    }
}
