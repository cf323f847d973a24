//! The Durham radial-correction paper's Brown radial model for headset lenses.
//!
//! Coordinates are normalized per axis to [-1, 1] over the image (the Durham radial-correction paper Sec. II-A:
//! `p_norm = 2 p_uv − 1`), with OpenCV's pixel-centre convention: pixel centre `u` has
//! `uv = (u + 0.5) / w`. Forward (Eq. 1) scales a point radially:
//! `r_d = r_u + c1 r_u³ + c2 r_u⁵`, i.e. `p_d = p_u (1 + c1 r_u² + c2 r_u⁴)`.
//! The Durham paper's approximate inverse (Eq. 2 with Eq. 3, after Mallon & Whelan) is
//! `p_u = p_d (1 − g(r_d))`, `g = (c1 r² + c2 r⁴ + c1² r⁴ + c2² r⁸ + 2 c1 c2 r⁶) / (1 + 4 c1 r² + 6 c2 r⁴)`.

use glam::{DMat2, DVec2};

use super::domain::ValidDomain;
use super::solve::solve_increasing;
use super::{check_finite, check_size, CameraModel, InverseMethod, ModelError, ABSURD_MAGNITUDE};

/// Brown radial distortion over a `width × height` image.
#[derive(Debug, Clone)]
pub struct BrownRadial {
    pub width: u32,
    pub height: u32,
    pub c1: f64,
    pub c2: f64,
    domain: ValidDomain,
}

impl BrownRadial {
    pub fn new(width: u32, height: u32, c1: f64, c2: f64) -> Result<Self, ModelError> {
        check_size(width, height)?;
        check_finite("c1", c1, ABSURD_MAGNITUDE)?;
        check_finite("c2", c2, ABSURD_MAGNITUDE)?;
        let mut model = BrownRadial {
            width,
            height,
            c1,
            c2,
            domain: ValidDomain::unbounded(),
        };
        if c1 != 0.0 || c2 != 0.0 {
            let m = model.clone();
            model.domain = ValidDomain::compute(
                |x| Some(m.distort_normalized(x)),
                |x, _| {
                    let s = x.length_squared();
                    // Scale stays positive and r_d = f(r_u) keeps growing: f'(r) > 0.
                    1.0 + m.c1 * s + m.c2 * s * s > 0.0
                        && 1.0 + 3.0 * m.c1 * s + 5.0 * m.c2 * s * s > 0.0
                },
            );
        }
        Ok(model)
    }

    /// The same lens as an OpenCV camera: per-axis [-1, 1] normalisation is OpenCV's with
    /// `fx = w/2, fy = h/2, cx = (w-1)/2, cy = (h-1)/2`, and Eq. 1 is `k1 = c1, k2 = c2`.
    /// This is how the GPU warp runs the Brown model (the Durham radial-correction paper pre-correction).
    pub fn to_opencv(&self) -> Result<super::Camera, ModelError> {
        let (w, h) = (self.width as f64, self.height as f64);
        super::Camera::from_coeffs(
            self.width,
            self.height,
            super::Intrinsics {
                fx: w / 2.0,
                fy: h / 2.0,
                cx: (w - 1.0) / 2.0,
                cy: (h - 1.0) / 2.0,
            },
            &[self.c1, self.c2, 0.0, 0.0],
        )
    }

    /// The valid domain in normalized [-1, 1] coordinates.
    pub fn domain(&self) -> &ValidDomain {
        &self.domain
    }

    /// Pixel → normalized [-1, 1] coordinates.
    pub fn to_normalized(&self, p: DVec2) -> DVec2 {
        DVec2::new(
            2.0 * (p.x + 0.5) / self.width as f64 - 1.0,
            2.0 * (p.y + 0.5) / self.height as f64 - 1.0,
        )
    }

    /// Normalized [-1, 1] coordinates → pixel.
    pub fn to_pixel(&self, n: DVec2) -> DVec2 {
        DVec2::new(
            (n.x + 1.0) * 0.5 * self.width as f64 - 0.5,
            (n.y + 1.0) * 0.5 * self.height as f64 - 0.5,
        )
    }

    /// Eq. 1: undistorted → distorted, in normalized coordinates.
    pub fn distort_normalized(&self, n: DVec2) -> DVec2 {
        let s = n.length_squared();
        n * (1.0 + self.c1 * s + self.c2 * s * s)
    }

    /// Jacobian of Eq. 1 in normalized coordinates.
    pub fn jacobian_normalized(&self, n: DVec2) -> DMat2 {
        let s = n.length_squared();
        let scale = 1.0 + self.c1 * s + self.c2 * s * s;
        let dscale = 2.0 * (self.c1 + 2.0 * self.c2 * s);
        DMat2::from_cols(
            DVec2::new(scale + dscale * n.x * n.x, dscale * n.x * n.y),
            DVec2::new(dscale * n.x * n.y, scale + dscale * n.y * n.y),
        )
    }

    /// Eq. 2 + Eq. 3: the Durham paper's closed-form approximate inverse.
    pub fn approx_inverse_normalized(&self, d: DVec2) -> Option<DVec2> {
        let (c1, c2) = (self.c1, self.c2);
        let s = d.length_squared();
        let den = 1.0 + 4.0 * c1 * s + 6.0 * c2 * s * s;
        if !(den.abs() > 1e-12) {
            return None;
        }
        let g = (c1 * s
            + c2 * s * s
            + c1 * c1 * s * s
            + c2 * c2 * s.powi(4)
            + 2.0 * c1 * c2 * s.powi(3))
            / den;
        Some(d * (1.0 - g))
    }

    /// Inverse on normalized coordinates, `None` outside the valid domain.
    pub fn undistort_normalized(&self, d: DVec2, method: InverseMethod) -> Option<DVec2> {
        if !self.domain.contains_distorted(d) {
            return None;
        }
        let rd = d.length();
        if rd == 0.0 {
            return Some(DVec2::ZERO);
        }
        let out = match method {
            InverseMethod::Heikkila => self.approx_inverse_normalized(d)?,
            InverseMethod::FixedPoint(n) => {
                let mut r = rd;
                for _ in 0..n {
                    let s = r * r;
                    r = rd / (1.0 + self.c1 * s + self.c2 * s * s);
                }
                d * (r / rd)
            }
            InverseMethod::Newton => {
                // f(r) = r + c1 r³ + c2 r⁵ = r_d on [0, r_max], increasing by construction of
                // the domain.
                let (c1, c2) = (self.c1, self.c2);
                let r = solve_increasing(
                    |r| {
                        let s = r * r;
                        (
                            r * (1.0 + c1 * s + c2 * s * s),
                            1.0 + 3.0 * c1 * s + 5.0 * c2 * s * s,
                        )
                    },
                    rd,
                    self.domain.ideal_radius(d.y.atan2(d.x)),
                );
                d * (r / rd)
            }
        };
        out.is_finite().then_some(out)
    }
}

impl CameraModel for BrownRadial {
    fn model_name(&self) -> &'static str {
        "brown"
    }
    fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }
    fn distort_pixel(&self, ideal: DVec2) -> Option<DVec2> {
        let out = self.to_pixel(self.distort_normalized(self.to_normalized(ideal)));
        out.is_finite().then_some(out)
    }
    fn distort_jacobian_pixel(&self, ideal: DVec2) -> Option<DMat2> {
        // The per-axis normalisation scales x and y alike on both sides; the Jacobian
        // transforms by S · J · S⁻¹ with S = diag(w/2, h/2).
        let scale = DMat2::from_diagonal(DVec2::new(
            self.width as f64 * 0.5,
            self.height as f64 * 0.5,
        ));
        let j = scale * self.jacobian_normalized(self.to_normalized(ideal)) * scale.inverse();
        j.is_finite().then_some(j)
    }
    fn undistort_pixel(&self, distorted: DVec2, method: InverseMethod) -> Option<DVec2> {
        self.undistort_normalized(self.to_normalized(distorted), method)
            .map(|n| self.to_pixel(n))
    }
    fn ideal_in_domain(&self, ideal: DVec2) -> bool {
        self.domain.contains_ideal(self.to_normalized(ideal))
    }
}
