//! The camera: size, intrinsics and the lens model of any model of the list, with its valid
//! domain computed once. Every pass, the planner and the front ends take it.

use glam::{DMat2, DMat3, DVec2, DVec3};

use super::domain::ValidDomain;
use super::fisheye::Fisheye;
use super::lens::{Lens, ModelKind};
use super::opencv::{
    fixed_point, heikkila, locally_invertible, Intrinsics, OpenCvDistortion, Terms,
};
use super::solve::solve_increasing;
use super::{check_finite, check_size, CameraModel, InverseMethod, ModelError, ABSURD_MAGNITUDE};

/// A calibrated camera: size, intrinsics, the lens model, and (computed once) its tilt
/// matrices and valid domain. This is the one camera noun of vklens: every pass, the planner
/// and the front ends take it, whatever model it holds.
///
/// The camera holds one [`Lens`]: OpenCV's standard model, evaluated on the pinhole-normalized
/// point with its own inverses, or one of the ray models of the table ([`super::table`]),
/// OpenCV's fisheye among them. Brown's radial model (the Durham radial-correction paper) is
/// exactly the standard model with `k1 = c1, k2 = c2` in per-axis normalized coordinates, and
/// the camera remembers that it came from one ([`Camera::brown`]).
///
/// Every type its methods name is exported beside it at the crate root, public by design:
///
/// ```
/// use vklens::{Camera, Intrinsics, Lens, ModelError, ModelKind, OpenCvDistortion};
/// let k = Intrinsics { fx: 400.0, fy: 400.0, cx: 399.5, cy: 299.5 };
/// let d = OpenCvDistortion::from_coeffs(&[-0.5, 0.0, 0.0, 0.0, 0.0])?;
/// let camera = Camera::new(800, 600, k, d)?;
/// assert_eq!(camera.model(), ModelKind::Standard);
/// assert!(matches!(camera.lens(), Lens::Standard { .. }));
/// // Barrel distortion this strong folds: the domain bounds where the inverse is right.
/// assert!(camera.domain().folds());
/// let bad = Camera::new(0, 600, k, d);
/// assert!(matches!(bad, Err(ModelError::BadSize { .. })));
/// # Ok::<(), vklens::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct Camera {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// fx fy cx cy, in OpenCV's pixel-centre convention.
    pub intrinsics: Intrinsics,
    lens: Lens,
    /// The standard model's tilt matrix and its inverse (computed once).
    tilt: Option<(DMat3, DMat3)>,
    /// The pinhole-side valid domain (computed once).
    domain: ValidDomain,
}

impl Camera {
    /// Validates the parameters and computes the valid domain.
    pub fn new(
        width: u32,
        height: u32,
        intrinsics: Intrinsics,
        distortion: OpenCvDistortion,
    ) -> Result<Self, ModelError> {
        check_intrinsics(width, height, &intrinsics)?;
        // Re-validate the coefficients (the struct has public fields).
        let distortion = OpenCvDistortion::from_coeffs(&distortion.to_coeffs())?;
        let tilt = distortion.terms().tilt.then(|| {
            let m = distortion.tilt_matrix();
            (m, m.inverse())
        });
        let coeffs = distortion.to_coeffs();
        // The shortest of OpenCV's lengths that holds every non-zero coefficient (at least 5,
        // the length `calibrateCamera` writes).
        let used = coeffs.iter().rposition(|&c| c != 0.0).map_or(0, |i| i + 1);
        let coeff_count = [5, 8, 12, 14]
            .into_iter()
            .find(|&n| n >= used)
            .unwrap_or(14);
        let mut camera = Camera {
            width,
            height,
            intrinsics,
            lens: Lens::Standard {
                distortion,
                coeff_count,
                brown: None,
                max_radius: None,
            },
            tilt,
            domain: ValidDomain::unbounded(),
        };
        if distortion.terms() != Terms::default() {
            camera = camera.with_radius_cap(ValidDomain::RADIUS_CAP);
        }
        Ok(camera)
    }

    /// The same camera with its domain bounded at `cap` instead of
    /// [`ValidDomain::RADIUS_CAP`] ([`ValidDomain::compute_within`]): for a standard-model
    /// camera that evaluates a plane other than a perspective image's.
    pub(crate) fn with_radius_cap(mut self, cap: f64) -> Self {
        if let Lens::Standard { distortion: d, .. } = self.lens {
            self.domain = if d.terms() == Terms::default() {
                ValidDomain::unbounded_within(cap)
            } else {
                ValidDomain::compute_within(
                    cap,
                    |x| d.distort_pre_tilt(x).map(|(y, _)| y),
                    |x, dir| locally_invertible(&d, x, dir),
                )
            };
        }
        self
    }

    /// The same standard-model camera with its valid domain ending at ideal normalized radius
    /// `r` (Basalt's `rpmax`), or earlier where the lens folds; kept through
    /// [`Camera::with_intrinsics`] and written back by the camera files.
    pub fn with_max_radius(self, r: f64) -> Result<Self, ModelError> {
        if !(r > 0.0 && r.is_finite()) {
            return Err(ModelError::Other(format!(
                "the largest radius (Basalt's rpmax) must be a positive number, got {r}"
            )));
        }
        if !matches!(self.lens, Lens::Standard { .. }) {
            return Err(ModelError::Other(
                "a largest radius (Basalt's rpmax) bounds OpenCV's standard model only".into(),
            ));
        }
        let mut camera = self.with_radius_cap(r.min(ValidDomain::RADIUS_CAP));
        if let Lens::Standard { max_radius, .. } = &mut camera.lens {
            *max_radius = Some(r);
        }
        Ok(camera)
    }

    /// The bound on the ideal normalized radius the camera was given
    /// ([`Camera::with_max_radius`]).
    pub fn max_radius(&self) -> Option<f64> {
        match self.lens {
            Lens::Standard { max_radius, .. } => max_radius,
            _ => None,
        }
    }

    /// A camera of OpenCV's fisheye model. Its pinhole-side domain (what a perspective image
    /// can hold, [`Camera::domain`]) is the lens's cone cut at [`ValidDomain::RADIUS_CAP`]; its
    /// ray domain ([`Camera::project`], [`Camera::unproject`]) is the whole cone, past 90° too.
    pub fn fisheye(
        width: u32,
        height: u32,
        intrinsics: Intrinsics,
        lens: Fisheye,
    ) -> Result<Self, ModelError> {
        check_intrinsics(width, height, &intrinsics)?;
        // Re-validate (the coefficients are public fields).
        let lens = Fisheye::new(lens.k, lens.alpha, lens.max_fov_deg())?;
        let theta = lens.theta_max().min(ValidDomain::RADIUS_CAP.atan());
        let domain = ValidDomain::radial(theta.tan(), lens.theta_d(theta).0, lens.folds());
        Ok(Camera {
            width,
            height,
            intrinsics,
            lens: Lens::Fisheye(lens),
            tilt: None,
            domain,
        })
    }

    /// A camera of any model. Its pinhole-side domain (what a perspective image can hold,
    /// [`Camera::domain`]) is found once from the model's forward map and Jacobian.
    pub fn with_lens(
        width: u32,
        height: u32,
        intrinsics: Intrinsics,
        lens: Lens,
    ) -> Result<Self, ModelError> {
        match lens {
            Lens::Standard {
                distortion,
                coeff_count,
                brown,
                max_radius,
            } => {
                let mut camera = Self::new(width, height, intrinsics, distortion)?;
                if let Lens::Standard {
                    coeff_count: c,
                    brown: b,
                    ..
                } = &mut camera.lens
                {
                    (*c, *b) = (coeff_count, brown);
                }
                match max_radius {
                    Some(r) => camera.with_max_radius(r),
                    None => Ok(camera),
                }
            }
            Lens::Fisheye(f) => Self::fisheye(width, height, intrinsics, f),
            lens => {
                check_intrinsics(width, height, &intrinsics)?;
                let domain = ValidDomain::compute(
                    |x| lens.ray_distort_normalized(x).map(|(m, _)| m),
                    |x, dir| {
                        lens.ray_distort_normalized(x)
                            .is_some_and(|(m, j)| j.determinant() > 0.0 && m.dot(j * dir) > 0.0)
                    },
                );
                Ok(Camera {
                    width,
                    height,
                    intrinsics,
                    lens,
                    tilt: None,
                    domain,
                })
            }
        }
    }

    /// The camera's lens model and parameters.
    pub fn lens(&self) -> &Lens {
        &self.lens
    }

    /// Which model the camera holds.
    pub fn model(&self) -> ModelKind {
        self.lens.kind()
    }

    /// Whether the image is cut along the half-plane x = 0 behind the camera (an
    /// equirectangular panorama: longitude jumps from +180° to −180° there), so that a straight
    /// segment through it has no connected image ([`Camera::crosses_seam`]).
    pub fn has_seam(&self) -> bool {
        self.model() == ModelKind::Equirectangular
    }

    /// Whether the camera-frame segment `a`–`b` passes through the camera's seam (never for a
    /// camera without one; NaN does).
    pub fn crosses_seam(&self, a: DVec3, b: DVec3) -> bool {
        if !self.has_seam() || (a.x < 0.0) == (b.x < 0.0) && a.x.is_finite() && b.x.is_finite() {
            return false;
        }
        let t = a.x / (a.x - b.x);
        !(a.z + (b.z - a.z) * t >= 0.0)
    }

    /// The standard model's 14 coefficients (all zero for a camera of another model).
    pub fn distortion(&self) -> OpenCvDistortion {
        match &self.lens {
            Lens::Standard { distortion, .. } => *distortion,
            _ => OpenCvDistortion::default(),
        }
    }

    /// The standard-model coefficients the shaders' standard-model code evaluates: the
    /// camera's own, or the radial-tangential part of an omni lens (zero for other models).
    pub fn shader_coefficients(&self) -> OpenCvDistortion {
        match &self.lens {
            Lens::Omni(o) => o.radtan().distortion(),
            _ => self.distortion(),
        }
    }

    /// The valid-domain table the shaders read: the pinhole-side domain, or for an omni lens
    /// its radial-tangential part's (on the plane of Mei's sphere point).
    pub fn shader_domain(&self) -> &ValidDomain {
        match &self.lens {
            Lens::Omni(o) => o.radtan().domain(),
            Lens::ThinPrismFisheye(t) => t.domain(),
            _ => &self.domain,
        }
    }

    /// The fisheye lens of a camera of OpenCV's fisheye model.
    pub fn fisheye_lens(&self) -> Option<&Fisheye> {
        match &self.lens {
            Lens::Fisheye(f) => Some(f),
            _ => None,
        }
    }

    /// The largest angle off the axis at which Alg. 1 keeps a vertex, for a fisheye whose
    /// domain reaches the direction straight behind the lens (θ_max = π): there the whole
    /// direction maps to the image circle's rim, a triangle near it spans an arc of the rim
    /// however small it is (no tessellation converges), so vertices stop where the ring left
    /// outside is one pixel wide. `None` for every other camera (the domain decides).
    pub fn fisheye_vertex_limit(&self) -> Option<f64> {
        let lens = self.fisheye_lens()?;
        let f = self.intrinsics.fx.max(self.intrinsics.fy);
        let (_, slope) = lens.theta_d(lens.theta_max());
        let ring = 1.0 / (f * slope.max(f64::MIN_POSITIVE));
        let limit = std::f64::consts::PI - ring.min(std::f64::consts::FRAC_PI_2);
        (lens.theta_max() > limit).then_some(limit)
    }

    /// Which term groups (and which model) the camera's shaders compile in.
    pub fn terms(&self) -> Terms {
        match &self.lens {
            Lens::Standard { distortion, .. } => distortion.terms(),
            Lens::Fisheye(f) => Terms {
                radial: f.k.iter().any(|&k| k != 0.0),
                model: ModelKind::Fisheye,
                ..Terms::default()
            },
            Lens::Omni(o) => Terms {
                model: ModelKind::Omni,
                ..o.radtan().distortion().terms()
            },
            lens => Terms {
                model: lens.kind(),
                ..Terms::default()
            },
        }
    }

    /// Whether the camera is an ideal pinhole (no distortion of any model).
    pub fn is_pinhole(&self) -> bool {
        self.terms() == Terms::default()
    }

    /// Refuses an inverse method the camera's model does not have: the fisheye model is
    /// inverted by Newton on θ only (Heikkilä's and OpenCV's iterations are the standard
    /// model's).
    pub fn check_method(&self, method: InverseMethod) -> Result<(), ModelError> {
        if self.model().is_ray_model() && method != InverseMethod::Newton {
            return Err(ModelError::Other(format!(
                "inverse method `{method}` is the standard model's; a camera of the `{}` model is inverted by `newton` (its own exact inverse)",
                self.model().name()
            )));
        }
        Ok(())
    }

    /// From OpenCV's coefficient vector (length 4, 5, 8, 12 or 14).
    pub fn from_coeffs(
        width: u32,
        height: u32,
        intrinsics: Intrinsics,
        coeffs: &[f64],
    ) -> Result<Self, ModelError> {
        Self::with_lens(
            width,
            height,
            intrinsics,
            Lens::Standard {
                distortion: OpenCvDistortion::from_coeffs(coeffs)?,
                coeff_count: coeffs.len(),
                brown: None,
                max_radius: None,
            },
        )
    }

    /// The camera of a Brown radial lens (evaluated as its exact standard-model twin, see
    /// [`BrownRadial::to_opencv`](super::BrownRadial::to_opencv)).
    pub fn from_brown(brown: &super::BrownRadial) -> Result<Self, ModelError> {
        let mut camera = brown.to_opencv()?;
        if let Lens::Standard { brown: b, .. } = &mut camera.lens {
            *b = Some((brown.c1, brown.c2));
        }
        Ok(camera)
    }

    /// The Brown radial model this camera was made from, if it was.
    pub fn brown(&self) -> Option<super::BrownRadial> {
        let Lens::Standard {
            brown: Some((c1, c2)),
            ..
        } = self.lens
        else {
            return None;
        };
        super::BrownRadial::new(self.width, self.height, c1, c2).ok()
    }

    /// The model's name as camera files spell it: `opencv`, `brown`, `opencv_fisheye`, `omni`…
    pub fn model_name(&self) -> &'static str {
        match self.lens {
            Lens::Standard { brown: Some(_), .. } => "brown",
            _ => self.model().name(),
        }
    }

    /// The distortion coefficients as OpenCV orders them, as many as the camera was given
    /// (4, 5, 8, 12 or 14); a fisheye's k1..k4; another model's own parameters.
    pub fn dist_coeffs(&self) -> Vec<f64> {
        match &self.lens {
            Lens::Standard {
                distortion,
                coeff_count,
                ..
            } => distortion.to_coeffs()[..*coeff_count].to_vec(),
            Lens::Fisheye(f) => f.k.to_vec(),
            lens => lens.params().into_iter().map(|(_, v)| v).collect(),
        }
    }

    /// The same camera with another size and intrinsics (the lens unchanged).
    pub fn with_intrinsics(
        &self,
        width: u32,
        height: u32,
        intrinsics: Intrinsics,
    ) -> Result<Self, ModelError> {
        let mut lens = self.lens.clone();
        // The moved intrinsics are no longer Brown's per-axis normalization.
        if let Lens::Standard { brown, .. } = &mut lens {
            *brown = None;
        }
        Self::with_lens(width, height, intrinsics, lens)
    }

    /// The valid domain (pre-tilt normalized coordinates).
    pub fn domain(&self) -> &ValidDomain {
        &self.domain
    }

    /// OpenCV's tilt matrix and its inverse, if the camera has a tilted sensor.
    pub fn tilt_matrices(&self) -> Option<(DMat3, DMat3)> {
        self.tilt
    }

    /// Forward model on normalized coordinates: ideal (X/Z, Y/Z) → distorted normalized
    /// (x'', y''). This is `cv2.projectPoints` before the intrinsics. `None` only where the
    /// model is undefined (zero denominator, non-finite input or result).
    pub fn distort_normalized(&self, x: DVec2) -> Option<DVec2> {
        self.jacobian_and_distort(x).map(|(y, _)| y)
    }

    /// [`Camera::distort_normalized`] with its Jacobian.
    fn jacobian_and_distort(&self, x: DVec2) -> Option<(DVec2, DMat2)> {
        match &self.lens {
            Lens::Standard { distortion, .. } => {
                let (pre, jac) = distortion.distort_pre_tilt(x)?;
                let (y, tilt_jac) = self.apply_tilt(pre)?;
                Some((y, tilt_jac * jac))
            }
            Lens::Fisheye(f) => f.distort_normalized(x),
            lens => lens.ray_distort_normalized(x),
        }
    }

    /// Jacobian of [`Camera::distort_normalized`].
    pub fn jacobian_normalized(&self, x: DVec2) -> Option<DMat2> {
        self.jacobian_and_distort(x).map(|(_, j)| j)
    }

    /// Projects a 3D point in the OpenCV camera frame to the distorted pixel, as
    /// `cv2.projectPoints` does. `None` for points at or behind the camera plane (z ≤ 0) for
    /// the standard model; the ray models see wherever their domain reaches, past 90° too
    /// ([`super::table::RayModel::contains_ray`]), and give `None` past it.
    pub fn project(&self, p: DVec3) -> Option<DVec2> {
        if self.model().is_ray_model() {
            return self
                .lens
                .project_ray(p)
                .map(|y| self.intrinsics.to_pixel(y));
        }
        if !(p.z > 0.0) || !p.is_finite() {
            return None;
        }
        let x = DVec2::new(p.x / p.z, p.y / p.z);
        self.distort_normalized(x)
            .map(|y| self.intrinsics.to_pixel(y))
    }

    /// Applies the tilt homography to a pre-tilt point, with the homography's Jacobian.
    fn apply_tilt(&self, pre: DVec2) -> Option<(DVec2, DMat2)> {
        let Some((m, _)) = self.tilt else {
            return Some((pre, DMat2::IDENTITY));
        };
        let h = m * DVec3::new(pre.x, pre.y, 1.0);
        // OpenCV uses 1 when the homogeneous coordinate is exactly 0; that is a point at
        // infinity, which we report as undefined instead.
        if h.z == 0.0 {
            return None;
        }
        let out = DVec2::new(h.x / h.z, h.y / h.z);
        let c0 = m.col(0);
        let c1 = m.col(1);
        let jac = DMat2::from_cols(
            DVec2::new(c0.x - out.x * c0.z, c0.y - out.y * c0.z) / h.z,
            DVec2::new(c1.x - out.x * c1.z, c1.y - out.y * c1.z) / h.z,
        );
        out.is_finite().then_some((out, jac))
    }

    /// Removes the tilt: distorted normalized (x'', y'') → pre-tilt (x', y'), exactly (for a
    /// fisheye, the skew: the domain's distorted table is in these coordinates).
    pub fn remove_tilt(&self, y: DVec2) -> Option<DVec2> {
        match &self.lens {
            Lens::Fisheye(f) => return y.is_finite().then(|| f.unskew(y)),
            Lens::Standard { .. } => {}
            // The other models' domain tables are in their own distorted coordinates.
            _ => return y.is_finite().then_some(y),
        }
        let Some((_, inv)) = self.tilt else {
            return y.is_finite().then_some(y);
        };
        let h = inv * DVec3::new(y.x, y.y, 1.0);
        if !(h.z > 0.0) {
            return None;
        }
        let out = DVec2::new(h.x / h.z, h.y / h.z);
        out.is_finite().then_some(out)
    }

    /// Inverse model on normalized coordinates: distorted (x'', y'') → ideal (X/Z, Y/Z), or
    /// `None` when the point has no preimage in the valid domain.
    pub fn undistort_normalized(&self, y: DVec2, method: InverseMethod) -> Option<DVec2> {
        if self.model().is_ray_model() {
            let ray = self.unproject_normalized(y)?;
            let x = DVec2::new(ray.x / ray.z, ray.y / ray.z);
            return (ray.z > 0.0 && self.domain.contains_ideal(x)).then_some(x);
        }
        let pre = self.remove_tilt(y)?;
        if !self.domain.contains_distorted(pre) {
            return None;
        }
        let d = self.distortion();
        let x = match method {
            InverseMethod::Newton => self.newton(pre)?,
            InverseMethod::Heikkila => heikkila(&d, pre)?,
            InverseMethod::FixedPoint(n) => fixed_point(&d, pre, n)?,
        };
        x.is_finite().then_some(x)
    }

    /// Inverse model to a unit camera-frame ray: distorted normalized point → the direction it
    /// sees, past 90° off the axis too for a fisheye; `None` outside the valid domain.
    pub fn unproject_normalized(&self, y: DVec2) -> Option<DVec3> {
        match &self.lens {
            Lens::Standard { .. } => self
                .undistort_normalized(y, InverseMethod::Newton)
                .map(|x| DVec3::new(x.x, x.y, 1.0).normalize()),
            Lens::Fisheye(f) => f.undistort_ray(y),
            lens => lens.unproject_ray(y),
        }
    }

    /// Inverse model from a distorted pixel to a unit camera-frame ray ([`Camera::unproject_normalized`]).
    pub fn unproject(&self, pixel: DVec2) -> Option<DVec3> {
        self.unproject_normalized(self.intrinsics.to_normalized(pixel))
    }

    /// Newton's method with the analytic Jacobian on the pre-tilt distortion, started from the
    /// exact inverse of the radial part and damped so that it never leaves the valid domain.
    ///
    /// Where tangential or prism terms turn the image far from the radial direction (next to a
    /// fold at a wide field angle), the radial start can lie in another basin, and the damped
    /// iteration stalls on the domain's edge. Then it falls back to continuation: the target is
    /// approached from the principal point in `CONTINUATION_STEPS` steps along the segment,
    /// each solved from the last answer. The preimage of that segment is a continuous path
    /// inside the domain whenever the segment is inside the domain's image, which the distorted
    /// table (star-shaped by construction) has already checked.
    fn newton(&self, target: DVec2) -> Option<DVec2> {
        let d = self.distortion();
        super::solve::invert_2d(
            |x| d.distort_pre_tilt(x),
            |x| self.domain.contains_ideal(x),
            self.radial_start(target),
            target,
        )
    }

    /// Start for Newton: solve the radial part r·R(r²) = |target| along the target's direction
    /// on [0, boundary radius], where it is increasing by construction of the domain.
    fn radial_start(&self, target: DVec2) -> DVec2 {
        let d = &self.distortion();
        let rho = target.length();
        if rho == 0.0 {
            return DVec2::ZERO;
        }
        let dir = target / rho;
        let hi = self.domain.ideal_radius(dir.y.atan2(dir.x));
        let r = solve_increasing(
            |r| {
                let s = r * r;
                let (num, den, dnum, dden) = d.radial(s);
                let rr = num / den;
                let drr = (dnum * den - num * dden) / (den * den);
                (r * rr, rr + 2.0 * s * drr)
            },
            rho,
            hi,
        );
        dir * r
    }
}

/// The checks every camera's size and intrinsics pass, whatever its model.
fn check_intrinsics(width: u32, height: u32, intrinsics: &Intrinsics) -> Result<(), ModelError> {
    check_size(width, height)?;
    for (name, v) in [
        ("fx", intrinsics.fx),
        ("fy", intrinsics.fy),
        ("cx", intrinsics.cx),
        ("cy", intrinsics.cy),
    ] {
        check_finite(name, v, ABSURD_MAGNITUDE)?;
    }
    for (name, v) in [("fx", intrinsics.fx), ("fy", intrinsics.fy)] {
        if v <= 0.0 {
            return Err(ModelError::NotPositive { name, value: v });
        }
        if v < super::MIN_FOCAL_PX {
            return Err(ModelError::TooSmall {
                name,
                value: v,
                min: super::MIN_FOCAL_PX,
            });
        }
    }
    Ok(())
}

impl CameraModel for Camera {
    fn model_name(&self) -> &'static str {
        Camera::model_name(self)
    }
    fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }
    fn distort_pixel(&self, ideal: DVec2) -> Option<DVec2> {
        let x = self.intrinsics.to_normalized(ideal);
        self.distort_normalized(x)
            .map(|y| self.intrinsics.to_pixel(y))
    }
    fn distort_jacobian_pixel(&self, ideal: DVec2) -> Option<DMat2> {
        let k = &self.intrinsics;
        let x = k.to_normalized(ideal);
        let scale = DMat2::from_diagonal(DVec2::new(k.fx, k.fy));
        let inv = DMat2::from_diagonal(DVec2::new(1.0 / k.fx, 1.0 / k.fy));
        self.jacobian_normalized(x).map(|j| scale * j * inv)
    }
    fn undistort_pixel(&self, distorted: DVec2, method: InverseMethod) -> Option<DVec2> {
        let y = self.intrinsics.to_normalized(distorted);
        self.undistort_normalized(y, method)
            .map(|x| self.intrinsics.to_pixel(x))
    }
    fn ideal_in_domain(&self, ideal: DVec2) -> bool {
        self.domain
            .contains_ideal(self.intrinsics.to_normalized(ideal))
    }
}
