//! What a user does with a [`Camera`] without a GPU: load it, build it from OpenCV's `K` and
//! `D`, move points through it, write it back.

use std::path::Path;

use glam::{DVec2, DVec3};

use crate::model::rolling_shutter::{FrameMotion, Projection, Readout, WorldToCamera};
use crate::model::{Camera, Fisheye, Intrinsics, InverseMethod};
use crate::{Error, Result};

impl Camera {
    /// Reads any camera file the command line reads: vklens JSON, OpenCV `FileStorage`
    /// (YAML, XML, JSON), ROS `camera_info` YAML, a Kalibr camchain, a COLMAP `cameras.txt`,
    /// or a Brown lens `{"model": "brown", ...}`.
    ///
    /// ```no_run
    /// let camera = vklens::Camera::load("camera.yml")?;
    /// println!("{}×{}, fx = {}", camera.width, camera.height, camera.intrinsics.fx);
    /// # Ok::<(), vklens::Error>(())
    /// ```
    pub fn load(path: impl AsRef<Path>) -> Result<Camera> {
        crate::io::load_camera(path.as_ref())
    }

    /// Reads camera `index` (0-based) of a file that holds several: a Kalibr camchain
    /// (`cam0`, `cam1`, …) or a COLMAP `cameras.txt` (its lines, in order).
    pub fn load_index(path: impl AsRef<Path>, index: usize) -> Result<Camera> {
        crate::io::camera::load_camera_at(path.as_ref(), Some(index))
    }

    /// Reads the camera of a file that `options` pick: by name as the file writes it (`cam1`,
    /// `M2`, `LEFT`, a COLMAP id), by index, and with the image size for a file that gives
    /// none.
    ///
    /// ```no_run
    /// use vklens::LoadOptions;
    /// let options = LoadOptions { name: Some("cam1".into()), ..LoadOptions::default() };
    /// let right = vklens::Camera::load_with("camchain.yaml", &options)?;
    /// # Ok::<(), vklens::Error>(())
    /// ```
    pub fn load_with(
        path: impl AsRef<Path>,
        options: &crate::io::catalog::LoadOptions,
    ) -> Result<Camera> {
        crate::io::camera::load_camera_with(path.as_ref(), options)
    }

    /// Every camera a file holds, each loaded or with why it cannot be, and the format the
    /// file was read as; `size` is the image size for a file that gives none.
    pub fn list(
        path: impl AsRef<Path>,
        size: Option<(u32, u32)>,
    ) -> Result<crate::io::catalog::Listing> {
        crate::io::camera::list_camera_file(path.as_ref(), size)
    }

    /// Parses the text of a camera file; `origin` names it in error messages.
    pub fn parse(text: &str, origin: &str) -> Result<Camera> {
        crate::io::parse_camera(text, origin)
    }

    /// Builds a camera from OpenCV's camera matrix `K` (row-major, as OpenCV stores it), its
    /// distortion vector `D` (4, 5, 8, 12 or 14 coefficients) and the image size.
    ///
    /// `K` must be a pinhole matrix: `[fx, s, cx; 0, fy, cy; 0, 0, 1]` with no skew.
    ///
    /// ```
    /// let k = [[400.0, 0.0, 399.5], [0.0, 400.0, 299.5], [0.0, 0.0, 1.0]];
    /// let camera = vklens::Camera::from_opencv(k, &[-0.05, 0.01, 0.03, -0.01], (800, 600))?;
    /// assert_eq!(camera.dist_coeffs().len(), 4);
    /// # Ok::<(), vklens::Error>(())
    /// ```
    pub fn from_opencv(k: [[f64; 3]; 3], dist_coeffs: &[f64], size: (u32, u32)) -> Result<Camera> {
        let bad = |what: &str| {
            Error::argument(
                "K",
                format!("{what} (expected [fx, 0, cx; 0, fy, cy; 0, 0, 1])"),
            )
        };
        if k.iter().flatten().any(|v| !v.is_finite()) {
            return Err(bad("every entry must be a finite number"));
        }
        if k[0][1] != 0.0 {
            return Err(bad(&format!(
                "K[0][1] = {} is a skew, which OpenCV's standard model does not have",
                k[0][1]
            )));
        }
        if k[1][0] != 0.0 || k[2][0] != 0.0 || k[2][1] != 0.0 || k[2][2] != 1.0 {
            return Err(bad("its last row must be 0 0 1 and K[1][0] must be 0"));
        }
        let intrinsics = Intrinsics {
            fx: k[0][0],
            fy: k[1][1],
            cx: k[0][2],
            cy: k[1][2],
        };
        Camera::from_coeffs(size.0, size.1, intrinsics, dist_coeffs).map_err(opencv_argument)
    }

    /// Builds a camera of OpenCV's fisheye model (`cv2.fisheye`, Kannala–Brandt) from its
    /// camera matrix `K` (row-major; a skew as `K[0][1] = α fx`, as `cv2.fisheye.calibrate`
    /// writes it), its four coefficients `D` = k1 k2 k3 k4 and the image size.
    /// [`Camera::from_opencv`] reads four coefficients as the standard model's k1 k2 p1 p2.
    ///
    /// ```
    /// let k = [[300.0, 0.0, 639.5], [0.0, 300.0, 399.5], [0.0, 0.0, 1.0]];
    /// let camera = vklens::Camera::from_opencv_fisheye(k, &[0.05, -0.01, 0.002, 0.0], (1280, 800))?;
    /// assert_eq!(camera.model_name(), "opencv_fisheye");
    /// # Ok::<(), vklens::Error>(())
    /// ```
    pub fn from_opencv_fisheye(
        k: [[f64; 3]; 3],
        dist_coeffs: &[f64],
        size: (u32, u32),
    ) -> Result<Camera> {
        let bad = |what: &str| {
            Error::argument(
                "K",
                format!("{what} (expected [fx, skew, cx; 0, fy, cy; 0, 0, 1])"),
            )
        };
        if k.iter().flatten().any(|v| !v.is_finite()) {
            return Err(bad("every entry must be a finite number"));
        }
        if k[1][0] != 0.0 || k[2][0] != 0.0 || k[2][1] != 0.0 || k[2][2] != 1.0 {
            return Err(bad("its last row must be 0 0 1 and K[1][0] must be 0"));
        }
        let coeffs: [f64; 4] = dist_coeffs.try_into().map_err(|_| {
            Error::argument(
                "dist_coeffs",
                format!(
                    "OpenCV's fisheye model has four coefficients k1 k2 k3 k4, got {}",
                    dist_coeffs.len()
                ),
            )
        })?;
        let intrinsics = Intrinsics {
            fx: k[0][0],
            fy: k[1][1],
            cx: k[0][2],
            cy: k[1][2],
        };
        // A focal length that is not positive is refused below, naming fx; the skew is only
        // read off K where it means something.
        let skew = if intrinsics.fx > 0.0 {
            k[0][1] / intrinsics.fx
        } else {
            0.0
        };
        if skew.abs() >= Fisheye::MAX_ALPHA {
            return Err(bad(&format!(
                "K[0][1] = {} is a skew of {skew} pixel widths per pixel height; below {} is a sensor",
                k[0][1],
                Fisheye::MAX_ALPHA
            )));
        }
        let lens = Fisheye::new(coeffs, skew, None).map_err(opencv_argument)?;
        Camera::fisheye(size.0, size.1, intrinsics, lens).map_err(opencv_argument)
    }

    /// OpenCV's camera matrix `K`, row-major (a fisheye's skew as `K[0][1] = α fx`).
    pub fn k_matrix(&self) -> [[f64; 3]; 3] {
        let k = self.intrinsics;
        let skew = self.fisheye_lens().map_or(0.0, |f| f.alpha * k.fx);
        [[k.fx, skew, k.cx], [0.0, k.fy, k.cy], [0.0, 0.0, 1.0]]
    }

    /// Forward model on normalized undistorted coordinates `(X/Z, Y/Z)` → distorted pixels,
    /// in f64, exactly as `cv2.projectPoints` computes them. `None` where the model is
    /// undefined (a rational denominator vanishes, a non-finite input).
    ///
    /// ```
    /// let k = [[400.0, 0.0, 399.5], [0.0, 400.0, 299.5], [0.0, 0.0, 1.0]];
    /// let camera = vklens::Camera::from_opencv(k, &[-0.05, 0.01, 0.0, 0.0], (800, 600))?;
    /// let uv = camera.distort_points(&[[0.0, 0.0], [0.5, 0.25]]);
    /// assert_eq!(uv[0], Some([399.5, 299.5]));
    /// # Ok::<(), vklens::Error>(())
    /// ```
    pub fn distort_points(&self, xy: &[[f64; 2]]) -> Vec<Option<[f64; 2]>> {
        xy.iter()
            .map(|&[x, y]| {
                self.distort_normalized(DVec2::new(x, y))
                    .map(|d| self.intrinsics.to_pixel(d).to_array())
            })
            .collect()
    }

    /// Inverse model: distorted pixels → normalized undistorted coordinates, `None` outside
    /// the valid domain (the lens folds over there, or no preimage exists) and, for a fisheye,
    /// where the pixel sees at or behind the image plane ([`Camera::unproject_points`] has
    /// those). A fisheye has one inverse, Newton on θ, whatever `method` says:
    /// [`Camera::check_method`] refuses the others first where that matters.
    pub fn undistort_points(
        &self,
        uv: &[[f64; 2]],
        method: InverseMethod,
    ) -> Vec<Option<[f64; 2]>> {
        uv.iter()
            .map(|&[u, v]| {
                let y = self.intrinsics.to_normalized(DVec2::new(u, v));
                self.undistort_normalized(y, method).map(|x| x.to_array())
            })
            .collect()
    }

    /// [`Camera::undistort_points`], then as `cv2.undistortPoints(uv, K, D, R, P)`: the
    /// normalized point's ray turned by the rectification `r` (row-major; `None`: the
    /// identity) and projected by `p` (the 3×3 part of a new camera or projection matrix;
    /// `None`: normalized coordinates). `None` also where the turned ray points at or behind
    /// the image plane, where OpenCV returns meaningless numbers.
    pub fn undistort_points_rectified(
        &self,
        uv: &[[f64; 2]],
        method: InverseMethod,
        r: Option<[[f64; 3]; 3]>,
        p: Option<[[f64; 3]; 3]>,
    ) -> Vec<Option<[f64; 2]>> {
        let r = r.map(|r| glam::DMat3::from_cols_array_2d(&r).transpose());
        let p = p.map(|p| glam::DMat3::from_cols_array_2d(&p).transpose());
        uv.iter()
            .map(|&[u, v]| {
                let pixel = DVec2::new(u, v);
                // The ray itself where the model gives one (a fisheye's past 90°, which R may
                // turn into view); OpenCV's other inverses through their normalized point.
                let ray = if self.model().is_ray_model() || method == InverseMethod::Newton {
                    self.unproject(pixel)?
                } else {
                    let y = self.intrinsics.to_normalized(pixel);
                    self.undistort_normalized(y, method)?.extend(1.0)
                };
                let ray = r.map_or(ray, |r| r * ray);
                if !(ray.z > 0.0) {
                    return None;
                }
                let q = p.map_or(ray, |p| p * ray);
                (q.z != 0.0)
                    .then(|| [q.x / q.z, q.y / q.z])
                    .filter(|v| v.iter().all(|c| c.is_finite()))
            })
            .collect()
    }

    /// Projects camera-frame points `(X, Y, Z)` to distorted pixels, as `cv2.projectPoints`
    /// with a zero pose; `None` for points at or behind the camera plane.
    pub fn project_points(&self, points: &[[f64; 3]]) -> Vec<Option<[f64; 2]>> {
        points
            .iter()
            .map(|&p| self.project(DVec3::from_array(p)).map(|d| d.to_array()))
            .collect()
    }

    /// Projects world points through a rolling shutter read out in `readout` order while the
    /// camera moves from `start` (the pose when the first line is read) to `end` (the last):
    /// each point where its own line's readout time agrees with the pose it is seen from,
    /// with that time and its depth then ([`rolling_shutter`](crate::rolling_shutter));
    /// `None` where the lens does not see it. With `end == start`, the pixels are those of
    /// [`Camera::project_points`] on `start`'s camera-frame points, bit for bit.
    pub fn project_points_rolling(
        &self,
        points: &[[f64; 3]],
        start: &WorldToCamera,
        end: &WorldToCamera,
        readout: Readout,
    ) -> Vec<Option<Projection>> {
        let motion = FrameMotion::new(*start, *end);
        points
            .iter()
            .map(|&p| motion.project(self, readout, DVec3::from_array(p)))
            .collect()
    }

    /// Distorted pixels → unit camera-frame rays, `None` outside the valid domain (a
    /// fisheye's reach past 90° off the axis).
    pub fn unproject_points(&self, uv: &[[f64; 2]]) -> Vec<Option<[f64; 3]>> {
        uv.iter()
            .map(|&p| self.unproject(DVec2::from_array(p)).map(|r| r.to_array()))
            .collect()
    }

    /// The camera as a vklens JSON camera object (a Brown lens as `{"model": "brown", ...}`, a
    /// fisheye as `{"model": "opencv_fisheye", ...}`).
    pub fn to_json(&self) -> serde_json::Value {
        if let Some(v) = crate::io::models::camera_to_json(self) {
            return v;
        }
        let k = self.intrinsics;
        if let Some(f) = self.fisheye_lens() {
            let mut v = serde_json::json!({
                "model": "opencv_fisheye", "width": self.width, "height": self.height,
                "fx": k.fx, "fy": k.fy, "cx": k.cx, "cy": k.cy,
                "dist_coeffs": f.k, "alpha": f.alpha,
            });
            if let Some(fov) = f.max_fov_deg() {
                v["max_fov_deg"] = fov.into();
            }
            return v;
        }
        match self.brown() {
            Some(b) => serde_json::json!({
                "model": "brown", "width": self.width, "height": self.height,
                "c1": b.c1, "c2": b.c2,
            }),
            None => {
                let mut v = serde_json::json!({
                    "width": self.width, "height": self.height,
                    "fx": k.fx, "fy": k.fy, "cx": k.cx, "cy": k.cy,
                    "dist_coeffs": self.dist_coeffs(),
                });
                if let Some(r) = self.max_radius() {
                    v["max_radius"] = r.into();
                }
                v
            }
        }
    }

    /// The camera as a ROS `camera_info` YAML (what `camera_calibration` writes and
    /// `image_proc` reads): `plumb_bob` (k1 k2 p1 p2 k3), `rational_polynomial` (8
    /// coefficients) or, for a fisheye, `equidistant` with the skew as `K[0][1] = α fx`. `P` is
    /// `K` (the raw camera). A camera ROS cannot describe (thin prism or tilt terms) is an
    /// `Unsupported` error that says which terms.
    pub fn to_ros_camera_info(&self) -> Result<String> {
        self.ros_camera_info(None)
    }

    /// [`Camera::to_ros_camera_info`] with a stereo pair's rectification: `R` (the rotation
    /// from the camera's frame to its rectified frame) and `P` (the rectified camera's 3×4
    /// projection), both row-major, as `cv2.stereoRectify` gives them and `image_proc`
    /// applies them (`initUndistortRectifyMap(K, D, R, P)`). `K` and `D` stay the lens's.
    pub fn to_ros_camera_info_rectified(
        &self,
        r: [[f64; 3]; 3],
        p: [[f64; 4]; 3],
    ) -> Result<String> {
        if !r
            .iter()
            .flatten()
            .chain(p.iter().flatten())
            .all(|v| v.is_finite())
        {
            return Err(Error::input(
                "a camera_info's rectification R and projection P must have finite entries",
            ));
        }
        self.ros_camera_info(Some((r, p)))
    }

    fn ros_camera_info(&self, rectification: Option<RectifyingPair>) -> Result<String> {
        let k = self.intrinsics;
        let (skew, model, coeffs) = if let Some(f) = self.fisheye_lens() {
            (f.alpha * k.fx, "equidistant", f.k.to_vec())
        } else if self.model().is_ray_model() {
            return Err(Error::Unsupported(format!(
                "ROS camera_info has no `{}` model (only plumb_bob, rational_polynomial and equidistant): only camera.json describes this camera",
                self.model_name()
            )));
        } else {
            let t = self.distortion().terms();
            if t.prism || t.tilt {
                return Err(Error::Unsupported(
                    "ROS camera_info has no thin prism (s1..s4) or tilt (tau_x, tau_y) terms: only camera.json describes this camera".into(),
                ));
            }
            let c = self.distortion().to_coeffs();
            if t.rational {
                (0.0, "rational_polynomial", c[..8].to_vec())
            } else {
                (0.0, "plumb_bob", c[..5].to_vec())
            }
        };
        let list = |v: &[f64]| {
            v.iter()
                .map(|x| format!("{x:?}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        // camera_info has no field of view: a comment keeps the fisheye's for a reader
        // (camera.json carries it as a key).
        let fov = self
            .fisheye_lens()
            .and_then(|f| f.max_fov_deg())
            .map(|f| format!("# max_fov_deg: {f} (no camera_info field; camera.json carries it)\n"))
            .unwrap_or_default();
        // The raw camera's P is K: image_proc then undistorts into the lens's own intrinsics.
        let (r, p) = rectification.unwrap_or((
            [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            [
                [k.fx, skew, k.cx, 0.0],
                [0.0, k.fy, k.cy, 0.0],
                [0.0, 0.0, 1.0, 0.0],
            ],
        ));
        Ok(format!(
            "{fov}image_width: {}\nimage_height: {}\ncamera_name: vklens\n\
             camera_matrix:\n  rows: 3\n  cols: 3\n  data: [{}]\n\
             distortion_model: {model}\n\
             distortion_coefficients:\n  rows: 1\n  cols: {}\n  data: [{}]\n\
             rectification_matrix:\n  rows: 3\n  cols: 3\n  data: [{}]\n\
             projection_matrix:\n  rows: 3\n  cols: 4\n  data: [{}]\n",
            self.width,
            self.height,
            list(&[k.fx, skew, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0]),
            coeffs.len(),
            list(&coeffs),
            list(r.as_flattened()),
            list(p.as_flattened()),
        ))
    }

    /// The camera in another tool's format (`vklens convert`): an `Unsupported` error, with
    /// the reason, where the format cannot hold it exactly.
    pub fn to_format(&self, format: crate::io::writers::Format) -> Result<String> {
        crate::io::writers::write_camera(self, format)
    }

    /// Writes the camera as vklens JSON (atomically: a failure leaves no partial file).
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        let text = format!("{:#}\n", self.to_json());
        crate::imaging::file::write_atomically(path.as_ref(), |tmp| std::fs::write(tmp, &text))
    }
}

/// A camera_info's rectification rotation R and projection P, row-major.
type RectifyingPair = ([[f64; 3]; 3], [[f64; 4]; 3]);

/// A model error of [`Camera::from_opencv`] or [`Camera::from_opencv_fisheye`] as the argument
/// it is about (`K`, `dist_coeffs` or `size`), for the front ends to say in their words.
fn opencv_argument(e: crate::model::ModelError) -> Error {
    use crate::model::ModelError as M;
    let argument = match &e {
        M::BadSize { .. } => "size",
        M::CoefficientCount(_) => "dist_coeffs",
        M::NotFinite { name, .. }
        | M::NotPositive { name, .. }
        | M::TooSmall { name, .. }
        | M::Absurd { name, .. } => {
            if ["fx", "fy", "cx", "cy"].contains(name) {
                "K"
            } else {
                "dist_coeffs"
            }
        }
        _ => return Error::from(e),
    };
    Error::argument(argument, e.to_string())
}
