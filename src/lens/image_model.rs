//! The image-based lens model of Heidrich et al. Sec. 3, pure f64 CPU work done
//! once per lens setting (focus, f-stop, wavelength):
//!
//! - sample points `p_i` on the image-side (rear) lens surface, over the part of it the axial
//!   film point sees through the stop (equal areas: a Vogel spiral);
//! - for each `p_i`, rays from a film grid through `p_i`, traced out into object space
//!   (Sec. 3.1);
//! - the virtual centre of projection that minimizes the *angle* between traced and
//!   projected rays, by Newton iteration on Σ c² (Sec. 3.3, Eq. 1), and the least-squares
//!   *distance* COP Heidrich et al. reject, kept for comparison;
//! - quad-tree refinement of the film grid until the largest angle error is under a threshold
//!   (Sec. 3.2);
//! - vignetting: border grid points whose rays are blocked move towards the film centre by
//!   bisection, interior points are spread inside the new border (Sec. 3.4);
//! - the radiometric weight `W_i(x') = cos θ' cos θ'' / ‖x'' − x'‖²` at every grid vertex
//!   (Sec. 3.5, Eq. 3).
//!
//! Coordinates. Lens: mm, z along the axis from the front vertex towards the film. Camera
//! (what the renderer and the scene use): OpenCV's frame in metres with its origin at the
//! front vertex, `X = x/1000, Y = −y/1000, Z = −z/1000` (a rotation: the scene lies at
//! Z > 0). The film is read as a camera sensor is: pixel `(u, v)` (OpenCV centres) sits at
//! film `x = −(u − c_x)·pitch, y = (v − c_y)·pitch`, so the image is upright.

use crate::{Error, Result};
use glam::{DMat3, DVec2, DVec3};

use super::paraxial::{analyse, focus};
use super::prescription::{Prescription, LAMBDA_D};
use super::trace::{trace, Ray};
use crate::model::{Camera, Intrinsics, OpenCvDistortion};

/// Slowest f-number accepted: at f/1024 a 50 mm lens's pupil is 0.05 mm, and further down the
/// cells' perspective projections lose all precision.
pub const MAX_F_NUMBER: f64 = 1024.0;

/// The film: its pixel grid and where it sits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    /// Pixel pitch (mm, square pixels).
    pub pitch_mm: f64,
    /// Axial position of the film plane (mm from the front vertex).
    pub z_mm: f64,
}

impl Film {
    /// Lens-space point of film pixel coordinates (OpenCV convention: integer = centre).
    pub fn point(&self, px: DVec2) -> DVec3 {
        let (cx, cy) = self.centre_px();
        DVec3::new(
            -(px.x - cx) * self.pitch_mm,
            (px.y - cy) * self.pitch_mm,
            self.z_mm,
        )
    }

    pub fn centre_px(&self) -> (f64, f64) {
        (
            (self.width as f64 - 1.0) / 2.0,
            (self.height as f64 - 1.0) / 2.0,
        )
    }
}

/// Lens-space point (mm) → camera frame (m).
pub fn lens_to_camera(p: DVec3) -> DVec3 {
    DVec3::new(p.x, -p.y, -p.z) / 1000.0
}

/// Lens-space direction → camera-frame direction.
pub fn lens_dir_to_camera(d: DVec3) -> DVec3 {
    DVec3::new(d.x, -d.y, -d.z)
}

/// A lens set up for rendering: stop set for the f-number, film placed for the focus.
#[derive(Debug, Clone)]
pub struct Optics {
    pub lens: Prescription,
    reversed: Prescription,
    /// Rear vertex z (mm): the mirror plane of the reversed lens.
    rear_z: f64,
    pub film: Film,
    /// Focus distance from the front vertex (m); infinite for infinity focus.
    pub focus_m: f64,
    pub f_number: f64,
}

impl Optics {
    /// Places the film of `width × height` pixels at `pitch_mm` where an object `focus_m`
    /// metres in front of the front vertex is in (paraxial, d-line) focus, with the stop
    /// scaled for `f_number` (`None`: the lens's own).
    pub fn new(
        lens: &Prescription,
        pixels: (u32, u32),
        pitch_mm: f64,
        focus_m: f64,
        f_number: Option<f64>,
    ) -> Result<Self> {
        if !(pitch_mm.is_finite() && pitch_mm > 0.0) {
            return Err(Error::input(format!(
                "pixel pitch {pitch_mm} mm must be positive"
            )));
        }
        if pixels.0 == 0 || pixels.1 == 0 {
            return Err(Error::input("the film needs at least one pixel"));
        }
        let par = analyse(lens, LAMBDA_D);
        let (Some(efl), Some(own_n)) = (par.efl, par.f_number) else {
            return Err(Error::input("the lens is afocal: it forms no image"));
        };
        if efl <= 0.0 {
            return Err(Error::input(format!(
                "the lens diverges (EFL {efl:.3} mm): no real image"
            )));
        }
        let mut lens = lens.clone();
        let f_number = match f_number {
            None => own_n,
            Some(n) if !(n.is_finite() && n > 0.0) => {
                return Err(Error::input(format!(
                    "f-stop {n} must be a positive number"
                )))
            }
            Some(n) if n > MAX_F_NUMBER => {
                return Err(Error::argument(
                    "fstop",
                    format!("f/{n}: the f-number must be at most f/{MAX_F_NUMBER}; past it the pupil is too small for the cells' projections (a pinhole needs no lens: use a camera file)"),
                ))
            }
            Some(n) if n < own_n * 0.999 => {
                return Err(Error::input(format!(
                    "f/{n} is faster than the lens opens: its widest is f/{own_n:.2}"
                )))
            }
            Some(n) => {
                // The entrance pupil is the stop's (paraxial) image: its diameter scales with
                // the stop's, and N = EFL / pupil diameter.
                let stop = lens.stop_index();
                lens.surfaces[stop].aperture *= own_n / n;
                n
            }
        };
        if !(focus_m > 0.0) {
            return Err(Error::input(format!(
                "focus distance {focus_m} m must be positive"
            )));
        }
        let rear_z = par.rear_vertex_z;
        let image = if focus_m.is_infinite() {
            par.bfl
        } else {
            focus(&lens, focus_m * 1000.0, LAMBDA_D)
        };
        let Some(image) = image.filter(|d| d.is_finite() && *d > 0.0) else {
            return Err(Error::input(format!(
                "cannot focus at {focus_m} m: the image would not be behind the lens \
                 (closer than its front focal length?)"
            )));
        };
        Ok(Optics {
            reversed: lens.reversed(),
            lens,
            rear_z,
            film: Film {
                width: pixels.0,
                height: pixels.1,
                pitch_mm,
                z_mm: rear_z + image,
            },
            focus_m,
            f_number,
        })
    }

    /// A lens with the film placed by hand (no focusing, no f-stop change): `film.z_mm` is
    /// where the film is, `focus_m` where the virtual image planes go. Any lens works here,
    /// afocal ones and bare stops (a pinhole camera) included.
    pub fn with_film(lens: &Prescription, film: Film, focus_m: f64) -> Result<Self> {
        let rear_z = lens.vertex_positions()[lens.surfaces.len() - 1];
        if !(film.pitch_mm > 0.0 && film.z_mm > rear_z && focus_m > 0.0) {
            return Err(Error::input(format!(
                "film at z {} mm must lie behind the rear vertex ({rear_z} mm), with a \
                 positive pitch and focus distance",
                film.z_mm
            )));
        }
        Ok(Optics {
            reversed: lens.reversed(),
            lens: lens.clone(),
            rear_z,
            film,
            focus_m,
            f_number: f64::NAN,
        })
    }

    /// The pinhole camera this lens approximates to first order: the film's pixels, focal
    /// length in pixels = the distance from the rear principal plane to the film (the
    /// magnification of the focused plane), principal point at the film centre. Used to
    /// frame scenes, as the GPU paths' cameras do.
    pub fn equivalent_camera(&self) -> Result<Camera> {
        let par = analyse(&self.lens, LAMBDA_D);
        let h = par
            .rear_principal_z
            .ok_or_else(|| Error::input("the lens is afocal"))?;
        let f = (self.film.z_mm - h) / self.film.pitch_mm;
        let (cx, cy) = self.film.centre_px();
        Camera::new(
            self.film.width,
            self.film.height,
            Intrinsics {
                fx: f,
                fy: f,
                cx,
                cy,
            },
            OpenCvDistortion::default(),
        )
        .map_err(Error::from)
    }

    /// The rear (image-side) surface point at radial position `xy` (mm) — on its sphere.
    pub fn rear_point(&self, xy: DVec2) -> DVec3 {
        let r = self.reversed.surfaces[0].radius;
        let sag = if r == 0.0 {
            0.0
        } else {
            r - r.signum() * (r * r - xy.length_squared()).max(0.0).sqrt()
        };
        DVec3::new(xy.x, xy.y, self.rear_z - sag)
    }

    /// The object-space ray (camera frame, metres) of the film point `film` (lens mm) through
    /// the rear-surface point `lens_point` (lens mm) at `lambda_um`; `None` when the lens
    /// blocks it.
    pub fn trace_from_film(&self, film: DVec3, lens_point: DVec3, lambda_um: f64) -> Option<Ray> {
        let mirror = |p: DVec3| DVec3::new(p.x, p.y, self.rear_z - p.z);
        let origin = mirror(film);
        let direction = (mirror(lens_point) - origin).normalize();
        if !(direction.z > 0.0) {
            return None;
        }
        let out = trace(&self.reversed, Ray { origin, direction }, lambda_um).ok()?;
        // Back to lens space, then to the camera frame.
        let o = DVec3::new(out.origin.x, out.origin.y, self.rear_z - out.origin.z);
        let d = DVec3::new(out.direction.x, out.direction.y, -out.direction.z);
        let d = lens_dir_to_camera(d);
        (d.z > 0.0).then(|| Ray {
            origin: lens_to_camera(o),
            direction: d,
        })
    }

    /// Radius (mm) of the disc on the rear surface through which the axial film point sees
    /// light (the exit pupil's footprint there), found by bisection.
    pub fn sample_disc_radius(&self, lambda_um: f64) -> Result<f64> {
        let centre = self.film.point(DVec2::from(self.film.centre_px()));
        let passes = |r: f64| {
            self.trace_from_film(centre, self.rear_point(DVec2::new(r, 0.0)), lambda_um)
                .is_some()
        };
        if !passes(0.0) {
            return Err(Error::input("the axial ray does not pass the lens"));
        }
        let mut lo = 0.0;
        let mut hi = 0.5 * self.reversed.surfaces[0].aperture;
        if passes(hi) {
            return Ok(hi);
        }
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if passes(mid) {
                lo = mid
            } else {
                hi = mid
            }
        }
        Ok(lo)
    }

    /// `n` sample points on the rear surface over the disc of [`Self::sample_disc_radius`],
    /// each standing for an equal area (a Vogel spiral; one sample is the centre), and the
    /// disc's area (mm², projected on the plane normal to the axis).
    pub fn lens_samples(&self, n: u32, lambda_um: f64) -> Result<(Vec<DVec3>, f64)> {
        if n == 0 {
            return Err(Error::input("at least one lens sample"));
        }
        let radius = self.sample_disc_radius(lambda_um)?;
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let points = (0..n)
            .map(|k| {
                if n == 1 {
                    return self.rear_point(DVec2::ZERO);
                }
                let r = radius * ((k as f64 + 0.5) / n as f64).sqrt();
                let a = k as f64 * golden;
                self.rear_point(DVec2::new(r * a.cos(), r * a.sin()))
            })
            .collect();
        Ok((points, std::f64::consts::PI * radius * radius))
    }
}

/// Lens samples with the factor that turns their Eq. 3 weights into relative irradiance:
/// `A/n / E_axis`, where `E_axis = (A/n) Σ_i W_i(film centre)`, so that a white scene gives 1
/// at the film centre (every sample passes there by construction).
#[derive(Debug, Clone, PartialEq)]
pub struct WeightedSamples {
    pub points: Vec<DVec3>,
    /// Multiply `radiometric_weight` by this.
    pub scale: f64,
}

impl Optics {
    /// [`Self::lens_samples`] with their normalization (see [`WeightedSamples`]).
    pub fn weighted_samples(&self, n: u32, lambda_um: f64) -> Result<WeightedSamples> {
        let (points, area) = self.lens_samples(n, lambda_um)?;
        let per_sample = area / points.len() as f64;
        let centre = self.film.point(DVec2::from(self.film.centre_px()));
        let axial_irradiance: f64 = points
            .iter()
            .map(|p| per_sample * radiometric_weight(centre, *p))
            .sum();
        Ok(WeightedSamples {
            points,
            scale: per_sample / axial_irradiance,
        })
    }
}

/// Heidrich et al. Eq. 3's weight `W_i(x') = cos θ' cos θ'' / ‖x'' − x'‖²` (mm⁻²) for the film point
/// `film` and the lens sample `lens_point`, both normals along the axis (the samples stand
/// for equal areas of the disc normal to the axis).
pub fn radiometric_weight(film: DVec3, lens_point: DVec3) -> f64 {
    let v = lens_point - film;
    let d2 = v.length_squared();
    v.z * v.z / (d2 * d2)
}

/// A traced ray for a COP fit: its point on the virtual image plane and its unit direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneRay {
    pub p: DVec3,
    pub d: DVec3,
}

/// Largest angle (degrees) between each ray and the line from `cop` to its plane point.
pub fn max_angle_deg(rays: &[PlaneRay], cop: DVec3) -> f64 {
    rays.iter()
        .map(|r| {
            // atan2 of |d × f| and d·f: exact near zero, where acos loses half the digits.
            let f = r.p - cop;
            r.d.cross(f).length().atan2(r.d.dot(f)).to_degrees()
        })
        .fold(0.0, f64::max)
}

/// Σ sin²θ = Σ (1 − c²) — Heidrich et al. Eq. 1 turned into a minimization — with its gradient and
/// Hessian in `e`. The sum is taken from |d × f|² rather than as 1 − c², which keeps its
/// digits when the angles are tiny: at 1e-5° a ray's 1 − c² is 3e-14, below what a sum of
/// c² ≈ 121 resolves, and a step could no longer be told better or worse.
fn sin2_terms(rays: &[PlaneRay], e: DVec3) -> (f64, DVec3, DMat3) {
    let mut s = 0.0;
    let mut grad = DVec3::ZERO;
    let mut hess = DMat3::ZERO;
    for r in rays {
        let f = r.p - e;
        let a = f.length_squared();
        let g = r.d.dot(f);
        s += r.d.cross(f).length_squared() / a;
        // c² = g²/a with ∂f/∂e = −I, ∂g/∂e = −d, ∂a/∂e = −2f:
        // ∇c² = 2g (g f − a d) / a², and ∇sin² = −∇c².
        let u = g * f - a * r.d;
        grad -= 2.0 * g / (a * a) * u;
        // ∂u/∂e = −f dᵀ − g I + 2 d fᵀ;
        // ∇²c² = 2/a² (−u dᵀ + g ∂u/∂e) + 8g/a³ u fᵀ, and ∇²sin² = −∇²c².
        let outer = |x: DVec3, y: DVec3| DMat3::from_cols(x * y.x, x * y.y, x * y.z);
        let du = outer(-f, r.d) - DMat3::from_diagonal(DVec3::splat(g)) + outer(2.0 * r.d, f);
        hess -= (outer(-u, r.d) + du * g) * (2.0 / (a * a)) + outer(u, f) * (8.0 * g / (a * a * a));
    }
    (s, grad, hess)
}

/// Heidrich et al. Sec. 3.3: the COP that maximizes Σ c² — the cosine of the angle between each
/// traced ray and the projected one. Newton iteration as Heidrich et al.'s, from `e0` or from the
/// least-squares-distance COP, whichever is better (for a bundle of nearly parallel rays, a
/// start far away can sit where the objective is not concave at all). Returns the COP and its
/// largest angle error (°).
pub fn fit_cop(rays: &[PlaneRay], e0: DVec3) -> (DVec3, f64) {
    let start = match least_squares_cop(rays) {
        Some(ls) if sin2_terms(rays, ls).0 < sin2_terms(rays, e0).0 => ls,
        _ => e0,
    };
    fit_cop_from(rays, start)
}

/// [`fit_cop`]'s iteration from `e0` alone: a Newton step where it lowers Σ sin²θ, otherwise
/// Levenberg–Marquardt damping (H + μI, μ growing tenfold) until one does. Far from the
/// optimum the Hessian of a tight bundle is indefinite and the plain Newton step points
/// nowhere useful (measured: 52 m long from the lens centre for 1/64 of the doublet's film,
/// where halving it twenty times still did not help); the damped step tends to a short
/// gradient step, which always descends until the optimum.
pub fn fit_cop_from(rays: &[PlaneRay], e0: DVec3) -> (DVec3, f64) {
    let mut e = e0;
    let (mut s, mut g, mut h) = sin2_terms(rays, e);
    // The damping's scale: the Hessian's size (its largest diagonal term).
    let scale = |h: &DMat3| h.x_axis.x.abs().max(h.y_axis.y.abs()).max(h.z_axis.z.abs());
    for _ in 0..200 {
        let mut mu = 0.0;
        let mut moved = None;
        for _ in 0..40 {
            let m = h + DMat3::from_diagonal(DVec3::splat(mu));
            let step = -(m.inverse() * g);
            if m.determinant().abs() > 1e-300 && step.is_finite() {
                let candidate = e + step;
                let (sc, gc, hc) = sin2_terms(rays, candidate);
                if sc < s {
                    moved = Some(step.length());
                    (e, s, g, h) = (candidate, sc, gc, hc);
                    break;
                }
            }
            mu = if mu == 0.0 {
                1e-9 * scale(&h).max(1e-300)
            } else {
                mu * 10.0
            };
        }
        match moved {
            Some(length) if length > 1e-13 * (1.0 + e.length()) => {}
            _ => break,
        }
    }
    (e, max_angle_deg(rays, e))
}

/// The COP Heidrich et al. reject (its ref. \[7\]): the point nearest to all rays in the
/// least-squares sense, Σ (I − d dᵀ)(e − o) = 0, with `o` the rays' plane points.
pub fn least_squares_cop(rays: &[PlaneRay]) -> Option<DVec3> {
    let mut m = DMat3::ZERO;
    let mut b = DVec3::ZERO;
    for r in rays {
        let proj = DMat3::IDENTITY - DMat3::from_cols(r.d * r.d.x, r.d * r.d.y, r.d * r.d.z);
        m += proj;
        b += proj * r.p;
    }
    (m.determinant().abs() > 1e-300).then(|| m.inverse() * b)
}

/// Wavelengths (µm) of the red, green and blue channels when chromatic aberration is
/// simulated: the C, e and F lines (the glass data's Cauchy law is fitted at C, d, F).
pub const RGB_WAVELENGTHS: [f64; 3] = [0.656_27, 0.546_07, 0.486_13];

/// Channel masks: one model for all channels, or one per channel (alpha, the accumulated
/// weight, goes with green).
pub const ALL_CHANNELS: [f32; 4] = [1.0, 1.0, 1.0, 1.0];
pub const RGB_CHANNELS: [[f32; 4]; 3] = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 1.0],
    [0.0, 0.0, 1.0, 0.0],
];

/// The models a frame needs: one at `options.lambda_um` for all channels, or — with
/// `chromatic` — one per channel at [`RGB_WAVELENGTHS`], each with its channel mask (Heidrich et al.
/// could not do this on its hardware; each channel gets its own projections).
pub fn channel_models(
    optics: &Optics,
    options: &ModelOptions,
    chromatic: bool,
) -> Result<Vec<(ImageModel, [f32; 4])>> {
    if !chromatic {
        return Ok(vec![(ImageModel::build(optics, options)?, ALL_CHANNELS)]);
    }
    RGB_WAVELENGTHS
        .iter()
        .zip(RGB_CHANNELS)
        .map(|(&lambda_um, mask)| {
            let o = ModelOptions {
                lambda_um,
                ..*options
            };
            Ok((ImageModel::build(optics, &o)?, mask))
        })
        .collect()
}

/// Settings of the model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelOptions {
    /// Lens sample points (depth of field; 1 = the centre of the rear surface only).
    pub samples: u32,
    /// Film grid per cell: `grid × grid` quads (seed: 10).
    pub grid: u32,
    /// Subdivide a cell while its largest angle error exceeds this (degrees; seed: 0.05).
    pub max_angle_deg: f64,
    /// Deepest quad-tree level (0 = one projection per sample).
    pub max_depth: u32,
    /// Wavelength (µm).
    pub lambda_um: f64,
    /// Fit each sample's lit region (Sec. 3.4's border bisection). Without it the film grid
    /// stays the whole film and quads with blocked rays are dropped: a plan that does not
    /// want vignetting divides the accumulated weight out instead.
    pub vignetting: bool,
}

impl Default for ModelOptions {
    fn default() -> Self {
        ModelOptions {
            samples: 10,
            grid: 10,
            max_angle_deg: 0.05,
            max_depth: 4,
            lambda_um: LAMBDA_D,
            vignetting: true,
        }
    }
}

/// One grid vertex of a cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellVertex {
    /// Film position (pixels, OpenCV centres).
    pub film_px: DVec2,
    /// Where its ray lands in the cell's projection: normalized coordinates
    /// `(x/z, y/z)` seen from the COP; `None` where the lens blocks the ray.
    pub projected: Option<DVec2>,
    /// Radiometric weight, normalized so that the sum over all samples on the axis is 1.
    pub weight: f64,
}

/// A leaf of the quad-tree: one perspective projection and the film grid it is morphed onto.
#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    /// Virtual centre of projection (camera frame, m).
    pub cop: DVec3,
    /// Bounds of the projected grid: min and max of `projected`.
    pub min: DVec2,
    pub max: DVec2,
    /// Quads per side; `(n + 1)²` vertices, row-major.
    pub n: u32,
    pub vertices: Vec<CellVertex>,
    /// Largest angle error of the fit (degrees).
    pub max_angle_deg: f64,
    pub depth: u32,
}

/// One lens sample and the cells that cover its part of the film.
#[derive(Debug, Clone, PartialEq)]
pub struct SampleModel {
    /// The sample point on the rear surface (lens mm).
    pub point: DVec3,
    pub cells: Vec<Cell>,
}

/// The whole model for one wavelength.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageModel {
    pub film: Film,
    pub options: ModelOptions,
    pub samples: Vec<SampleModel>,
    /// Virtual image plane depth (camera frame, m).
    pub plane_z: f64,
}

impl ImageModel {
    /// Perspective projections to render per frame.
    pub fn projection_count(&self) -> usize {
        self.samples.iter().map(|s| s.cells.len()).sum()
    }

    /// Largest angle error over all cells (degrees).
    pub fn max_angle_deg(&self) -> f64 {
        self.samples
            .iter()
            .flat_map(|s| s.cells.iter().map(|c| c.max_angle_deg))
            .fold(0.0, f64::max)
    }

    /// Builds the model (the preprocessing of Heidrich et al. Sec. 3.5).
    pub fn build(optics: &Optics, options: &ModelOptions) -> Result<Self> {
        if options.grid == 0 || options.grid > 256 {
            return Err(Error::input(format!(
                "grid {} must be 1..256",
                options.grid
            )));
        }
        if !(options.max_angle_deg.is_finite() && options.max_angle_deg > 0.0) {
            return Err(Error::input(format!(
                "max angle {} must be a positive number of degrees",
                options.max_angle_deg
            )));
        }
        let film = optics.film;
        let lambda = options.lambda_um;
        let WeightedSamples { points, scale } = optics.weighted_samples(options.samples, lambda)?;
        // The virtual image plane: at the focus distance (objects there land exactly where
        // their traced rays say), capped for infinity focus.
        let plane_z = optics.focus_m.min(1.0e4);
        let mut samples = Vec::with_capacity(points.len());
        for point in points {
            let border = Border::new(optics, point, lambda, options.vignetting);
            let mut builder = CellBuilder {
                optics,
                options,
                point,
                lambda,
                plane_z,
                border: &border,
                weight_scale: scale,
                cells: Vec::new(),
            };
            // Seed: the first guess is the centre of the lens; the entrance pupil's centre
            // is the lens's own centre of perspective to first order.
            let e0 = lens_to_camera(DVec3::new(
                0.0,
                0.0,
                analyse(&optics.lens, lambda).entrance_pupil_z,
            ));
            builder.refine(DVec2::ZERO, DVec2::ONE, e0, 0);
            samples.push(SampleModel {
                point,
                cells: builder.cells,
            });
        }
        Ok(ImageModel {
            film,
            options: *options,
            samples,
            plane_z,
        })
    }
}

/// The film region a lens sample lights (Sec. 3.4): the film rectangle's border with every
/// blocked point moved towards the film centre by bisection, sampled at `SIDE + 1` points per
/// side, and a Coons patch that spreads the interior inside it.
struct Border {
    /// Bottom (t = 0), top (t = 1), left (s = 0), right (s = 1): film pixels.
    sides: [Vec<DVec2>; 4],
}

const SIDE: usize = 64;

impl Border {
    fn new(optics: &Optics, point: DVec3, lambda: f64, fit: bool) -> Self {
        let film = optics.film;
        let (w, h) = (film.width as f64, film.height as f64);
        let corner = |s: f64, t: f64| DVec2::new(-0.5 + s * w, -0.5 + t * h);
        let centre = DVec2::from(film.centre_px());
        let lit = |px: DVec2| {
            optics
                .trace_from_film(film.point(px), point, lambda)
                .is_some()
        };
        let centre_lit = fit && lit(centre);
        let pull_in = |px: DVec2| -> DVec2 {
            if lit(px) || !centre_lit {
                return px;
            }
            let (mut lo, mut hi) = (0.0, 1.0); // fraction of the way from the centre
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                if lit(centre + mid * (px - centre)) {
                    lo = mid
                } else {
                    hi = mid
                }
            }
            centre + lo * (px - centre)
        };
        let side = |f: &dyn Fn(f64) -> DVec2| -> Vec<DVec2> {
            (0..=SIDE)
                .map(|k| pull_in(f(k as f64 / SIDE as f64)))
                .collect()
        };
        Border {
            sides: [
                side(&|s| corner(s, 0.0)),
                side(&|s| corner(s, 1.0)),
                side(&|t| corner(0.0, t)),
                side(&|t| corner(1.0, t)),
            ],
        }
    }

    fn along(side: &[DVec2], s: f64) -> DVec2 {
        let x = s.clamp(0.0, 1.0) * (side.len() - 1) as f64;
        let i = (x.floor() as usize).min(side.len() - 2);
        side[i].lerp(side[i + 1], x - i as f64)
    }

    /// The Coons patch: film pixels of parameter `(s, t)` ∈ [0, 1]².
    fn at(&self, st: DVec2) -> DVec2 {
        let (s, t) = (st.x, st.y);
        let [bottom, top, left, right] = &self.sides;
        let ruled = (1.0 - t) * Self::along(bottom, s)
            + t * Self::along(top, s)
            + (1.0 - s) * Self::along(left, t)
            + s * Self::along(right, t);
        let corners = (1.0 - s) * (1.0 - t) * bottom[0]
            + s * (1.0 - t) * bottom[SIDE]
            + (1.0 - s) * t * top[0]
            + s * t * top[SIDE];
        ruled - corners
    }
}

struct CellBuilder<'a> {
    optics: &'a Optics,
    options: &'a ModelOptions,
    point: DVec3,
    lambda: f64,
    plane_z: f64,
    border: &'a Border,
    weight_scale: f64,
    cells: Vec<Cell>,
}

impl CellBuilder<'_> {
    /// Sec. 3.2's recursion over the parameter rectangle `[lo, hi]`.
    fn refine(&mut self, lo: DVec2, hi: DVec2, e0: DVec3, depth: u32) {
        let n = self.options.grid;
        let film = self.optics.film;
        let mut rays = Vec::new();
        let mut grid = Vec::with_capacity(((n + 1) * (n + 1)) as usize);
        for j in 0..=n {
            for i in 0..=n {
                let st = lo + (hi - lo) * DVec2::new(i as f64, j as f64) / n as f64;
                let px = self.border.at(st);
                let x_film = film.point(px);
                let ray = self
                    .optics
                    .trace_from_film(x_film, self.point, self.lambda)
                    .and_then(|r| {
                        let t = (self.plane_z - r.origin.z) / r.direction.z;
                        (t.is_finite() && t > 0.0).then(|| PlaneRay {
                            p: r.origin + t * r.direction,
                            d: r.direction,
                        })
                    });
                if let Some(r) = ray {
                    rays.push(r);
                }
                grid.push((px, ray, radiometric_weight(x_film, self.point)));
            }
        }
        if rays.len() < 3 {
            return; // nothing (or too little) of this cell is lit through this sample
        }
        let (cop, angle) = fit_cop(&rays, e0);
        if angle > self.options.max_angle_deg && depth < self.options.max_depth {
            let mid = 0.5 * (lo + hi);
            for (a, b) in [
                (lo, mid),
                (DVec2::new(mid.x, lo.y), DVec2::new(hi.x, mid.y)),
                (DVec2::new(lo.x, mid.y), DVec2::new(mid.x, hi.y)),
                (mid, hi),
            ] {
                self.refine(a, b, cop, depth + 1);
            }
            return;
        }
        let vertices: Vec<CellVertex> = grid
            .into_iter()
            .map(|(film_px, ray, w)| CellVertex {
                film_px,
                projected: ray.and_then(|r| {
                    let f = r.p - cop;
                    (f.z > 0.0).then(|| DVec2::new(f.x / f.z, f.y / f.z))
                }),
                weight: w * self.weight_scale,
            })
            .collect();
        let projected = vertices.iter().filter_map(|v| v.projected);
        let min = projected
            .clone()
            .fold(DVec2::splat(f64::INFINITY), DVec2::min);
        let max = projected.fold(DVec2::splat(f64::NEG_INFINITY), DVec2::max);
        if !(min.is_finite() && max.is_finite()) {
            return;
        }
        self.cells.push(Cell {
            cop,
            min,
            max,
            n,
            vertices,
            max_angle_deg: angle,
            depth,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rays_through(e: DVec3) -> Vec<PlaneRay> {
        (0..25)
            .map(|k| {
                let p = DVec3::new((k % 5) as f64 - 2.0, (k / 5) as f64 - 2.0, 10.0);
                PlaneRay {
                    p,
                    d: (p - e).normalize(),
                }
            })
            .collect()
    }

    #[test]
    fn the_hessian_matches_finite_differences() {
        let mut rays = rays_through(DVec3::new(0.1, -0.2, 0.3));
        for (k, r) in rays.iter_mut().enumerate() {
            r.d = (r.d + DVec3::new(0.01 * (k as f64).sin(), 0.02, 0.0)).normalize();
        }
        let e = DVec3::new(0.3, 0.1, -0.5);
        let (_, g, h) = sin2_terms(&rays, e);
        let eps = 1e-6;
        for axis in 0..3 {
            let mut de = DVec3::ZERO;
            de[axis] = eps;
            let (sp, gp, _) = sin2_terms(&rays, e + de);
            let (sm, gm, _) = sin2_terms(&rays, e - de);
            assert!(((sp - sm) / (2.0 * eps) - g[axis]).abs() < 1e-6);
            let column = (gp - gm) / (2.0 * eps);
            assert!(
                (column - h.col(axis)).length() < 1e-5,
                "{column} {}",
                h.col(axis)
            );
        }
    }

    #[test]
    fn newton_finds_an_exact_centre_from_a_poor_guess() {
        let truth = DVec3::new(0.2, -0.1, 0.05);
        let rays = rays_through(truth);
        let (e, angle) = fit_cop_from(&rays, DVec3::new(-0.5, 0.4, 1.0));
        assert!((e - truth).length() < 1e-9, "{e}");
        assert!(angle < 1e-6, "{angle}");
        let ls = least_squares_cop(&rays).unwrap();
        assert!((ls - truth).length() < 1e-9);
    }

    #[test]
    fn reversing_twice_gives_the_lens_back() {
        let p = Prescription::parse(
            "30 5 1.6 20 40\n0 2 0 10\n-40 3 1.7 20 30\n-200 40 1 20\n",
            "t",
        )
        .unwrap();
        let back = p.reversed().reversed();
        for (a, b) in p.surfaces.iter().zip(&back.surfaces) {
            assert_eq!(
                (a.radius, a.ior, a.abbe, a.aperture, a.stop),
                (b.radius, b.ior, b.abbe, b.aperture, b.stop)
            );
        }
        // Thicknesses between surfaces survive (the last one is the film distance, not part
        // of the reversed lens).
        for k in 0..p.surfaces.len() - 1 {
            assert_eq!(p.surfaces[k].thickness, back.surfaces[k].thickness);
        }
    }
}
