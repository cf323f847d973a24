//! The valid domain of a distortion: where the forward model is invertible.
//!
//! Strong distortion folds over: beyond some radius the distorted radius stops growing (the
//! Jacobian determinant reaches 0), or a rational denominator reaches zero and the model flips
//! through infinity. Past that boundary two ideal points share one distorted point, so no
//! inverse can be right; OpenCV's own iteration silently returns one of them, or garbage.
//!
//! The boundary is computed once per camera by marching along `SAMPLES` rays from the
//! principal point in *ideal* (undistorted, normalized) space until the model stops being
//! locally valid, refined by bisection. Its image under the forward model bounds the valid
//! region in *distorted* space. Both are stored as polar radius tables at uniform angles, so a
//! containment test is one table lookup — cheap enough for every pixel, and the same table goes
//! to the GPU.
//!
//! The domain is star-shaped by construction in ideal space. In distorted space the table holds,
//! per direction, the *nearest* crossing of the boundary image, so a point inside it is inside
//! the image of the domain even where the boundary image is not star-shaped.

use std::f64::consts::TAU;

use glam::DVec2;

/// A camera's valid domain as two polar radius tables (ideal and distorted space).
#[derive(Debug, Clone, PartialEq)]
pub struct ValidDomain {
    ideal: Vec<f64>,
    distorted: Vec<f64>,
    /// Smallest entries of each table: inside them no lookup is needed (the common case).
    min_ideal: f64,
    min_distorted: f64,
    folds: bool,
}

impl ValidDomain {
    /// Rays (and table entries) around the principal point. The GPU gets the very same table
    /// (`CameraParams.domain` in `glsl/include/camera_model.glsl`), so CPU and GPU agree on
    /// what is valid up to f32 rounding.
    pub const SAMPLES: usize = 256;
    /// Largest ideal radius considered (normalized units): tan(88.9°). A lens that never folds
    /// is still bounded here: a perspective image cannot reach 90° off axis.
    pub const RADIUS_CAP: f64 = 50.0;

    /// Computes the domain of a distortion given by its forward map `forward` (ideal → distorted,
    /// both in normalized coordinates centred on the principal point) and a local test
    /// `valid_at(x, dir)` that says whether the model is invertible at `x` when walking outward
    /// along `dir` (Jacobian determinant > 0, denominators > 0, distorted radius growing).
    pub fn compute(
        forward: impl Fn(DVec2) -> Option<DVec2>,
        valid_at: impl Fn(DVec2, DVec2) -> bool,
    ) -> Self {
        let n = Self::SAMPLES;
        let mut ideal = Vec::with_capacity(n);
        let mut folds = false;
        for i in 0..n {
            let angle = TAU * i as f64 / n as f64;
            let dir = DVec2::new(angle.cos(), angle.sin());
            let (radius, folded) = march(&valid_at, dir);
            folds |= folded;
            ideal.push(radius);
        }
        let boundary: Vec<DVec2> = ideal
            .iter()
            .enumerate()
            .map(|(i, &r)| {
                let angle = TAU * i as f64 / n as f64;
                forward(DVec2::new(angle.cos(), angle.sin()) * r).unwrap_or(DVec2::ZERO)
            })
            .collect();
        let distorted = (0..n)
            .map(|j| {
                let angle = TAU * j as f64 / n as f64;
                nearest_crossing(&boundary, DVec2::new(angle.cos(), angle.sin()))
            })
            .collect();
        Self::from_tables(ideal, distorted, folds)
    }

    fn from_tables(ideal: Vec<f64>, distorted: Vec<f64>, folds: bool) -> Self {
        let min = |t: &[f64]| t.iter().copied().fold(f64::INFINITY, f64::min);
        ValidDomain {
            min_ideal: min(&ideal),
            min_distorted: min(&distorted),
            ideal,
            distorted,
            folds,
        }
    }

    /// A domain without any boundary but the radius cap (no distortion).
    pub fn unbounded() -> Self {
        Self::from_tables(
            vec![Self::RADIUS_CAP; Self::SAMPLES],
            vec![Self::RADIUS_CAP; Self::SAMPLES],
            false,
        )
    }

    /// True when the model folds over (or hits a pole) somewhere before the radius cap.
    pub fn folds(&self) -> bool {
        self.folds
    }

    /// Boundary radius in ideal space in the direction of `angle` (radians).
    pub fn ideal_radius(&self, angle: f64) -> f64 {
        lookup(&self.ideal, angle)
    }

    /// Boundary radius in distorted space in the direction of `angle` (radians).
    pub fn distorted_radius(&self, angle: f64) -> f64 {
        lookup(&self.distorted, angle)
    }

    /// Smallest ideal boundary radius over all directions.
    pub fn min_ideal_radius(&self) -> f64 {
        self.min_ideal
    }

    /// Whether an ideal normalized point (principal point at 0) lies in the domain.
    pub fn contains_ideal(&self, x: DVec2) -> bool {
        let r2 = x.length_squared();
        if r2 <= self.min_ideal * self.min_ideal {
            return true;
        }
        r2.is_finite() && r2.sqrt() <= self.ideal_radius(x.y.atan2(x.x))
    }

    /// Whether a distorted normalized point has its preimage in the domain.
    pub fn contains_distorted(&self, y: DVec2) -> bool {
        let r2 = y.length_squared();
        if r2 <= self.min_distorted * self.min_distorted {
            return true;
        }
        r2.is_finite() && r2.sqrt() <= self.distorted_radius(y.y.atan2(y.x))
    }

    /// Smallest distorted boundary radius over all directions.
    pub fn min_distorted_radius(&self) -> f64 {
        self.min_distorted
    }

    /// The table as `[ideal, distorted]` radius pairs at angles `TAU * i / SAMPLES`, for the GPU
    /// mirror (which interpolates the same way as [`ValidDomain::ideal_radius`]).
    pub fn table(&self) -> impl Iterator<Item = [f64; 2]> + '_ {
        self.ideal
            .iter()
            .zip(&self.distorted)
            .map(|(&a, &b)| [a, b])
    }
}

/// Relative margin by which a found boundary is pulled inward.
const BOUNDARY_MARGIN: f64 = 1e-9;

/// Linear interpolation in a table of radii at uniform angles `TAU * i / len`.
fn lookup(table: &[f64], angle: f64) -> f64 {
    let n = table.len();
    let t = (angle / TAU).rem_euclid(1.0) * n as f64;
    let i = (t.floor() as usize).min(n - 1);
    let f = t - i as f64;
    table[i] * (1.0 - f) + table[(i + 1) % n] * f
}

/// Walks outward along `dir` until `valid_at` fails; returns the last valid radius (refined by
/// bisection) and whether a failure was found before the cap.
fn march(valid_at: &impl Fn(DVec2, DVec2) -> bool, dir: DVec2) -> (f64, bool) {
    let mut inside = 0.0_f64;
    let mut r = 1e-6_f64;
    while r < ValidDomain::RADIUS_CAP {
        if !valid_at(dir * r, dir) {
            let mut outside = r;
            for _ in 0..64 {
                let mid = 0.5 * (inside + outside);
                if valid_at(dir * mid, dir) {
                    inside = mid;
                } else {
                    outside = mid;
                }
            }
            // Stored strictly inside: interpolating between rays, or a rounding of the radius,
            // must never land on the pole or past the fold itself. The band given up is far
            // thinner than any inverse can resolve there (the Jacobian vanishes at the fold).
            return (inside * (1.0 - BOUNDARY_MARGIN), true);
        }
        inside = r;
        // Steps grow with r: fine near the centre where lenses are tuned, coarser far out.
        r += 0.002 + 0.01 * r;
    }
    if valid_at(dir * ValidDomain::RADIUS_CAP, dir) {
        (ValidDomain::RADIUS_CAP, false)
    } else {
        (inside * (1.0 - BOUNDARY_MARGIN), true)
    }
}

/// Distance from the origin to the nearest crossing of the closed polygon `boundary` along the
/// ray `dir`; the smallest vertex radius if the ray misses (degenerate boundary).
fn nearest_crossing(boundary: &[DVec2], dir: DVec2) -> f64 {
    let mut best = f64::INFINITY;
    let n = boundary.len();
    for i in 0..n {
        let a = boundary[i];
        let b = boundary[(i + 1) % n];
        // Solve t·dir = a + s·(b − a), t > 0, s ∈ [0, 1].
        let e = b - a;
        let denom = dir.perp_dot(e);
        if denom.abs() < 1e-300 {
            continue;
        }
        let t = a.perp_dot(e) / denom;
        let s = a.perp_dot(dir) / denom;
        if t > 0.0 && (0.0..=1.0).contains(&s) {
            best = best.min(t);
        }
    }
    if best.is_finite() {
        best
    } else {
        boundary
            .iter()
            .map(|p| p.length())
            .fold(f64::INFINITY, f64::min)
    }
}
