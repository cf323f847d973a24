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
//! per direction, the *nearest* crossing of the boundary image, raised just enough that its
//! interpolation between directions covers the image curve: a pre-filter that never refuses
//! the image of an in-domain point. The inverse then confirms (its answer must land in the
//! ideal domain with a vanishing residual), so the thin band the raise adds stays invalid.

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
    /// Largest ideal radius considered (normalized units): tan(89.94°), past the 89.9° a point
    /// round-trips from (Kornia's round-trip tests go that far). A lens that never folds
    /// is still bounded here: a perspective image cannot reach 90° off axis.
    pub const RADIUS_CAP: f64 = 1000.0;

    /// Computes the domain of a distortion given by its forward map `forward` (ideal → distorted,
    /// both in normalized coordinates centred on the principal point) and a local test
    /// `valid_at(x, dir)` that says whether the model is invertible at `x` when walking outward
    /// along `dir` (Jacobian determinant > 0, denominators > 0, distorted radius growing).
    pub fn compute(
        forward: impl Fn(DVec2) -> Option<DVec2>,
        valid_at: impl Fn(DVec2, DVec2) -> bool,
    ) -> Self {
        Self::compute_within(Self::RADIUS_CAP, forward, valid_at)
    }

    /// [`ValidDomain::compute`] with another bound than [`ValidDomain::RADIUS_CAP`] on the
    /// ideal radius: a plane that is not a perspective image's (Mei's unit-sphere plane, which
    /// reaches infinity at the edge of the omnidirectional model's domain) goes further out.
    pub fn compute_within(
        cap: f64,
        forward: impl Fn(DVec2) -> Option<DVec2>,
        valid_at: impl Fn(DVec2, DVec2) -> bool,
    ) -> Self {
        let n = Self::SAMPLES;
        let mut ideal = Vec::with_capacity(n);
        let mut folds = false;
        for i in 0..n {
            let angle = TAU * i as f64 / n as f64;
            let dir = DVec2::new(angle.cos(), angle.sin());
            let (radius, folded) = march(&valid_at, dir, cap);
            folds |= folded;
            ideal.push(radius);
        }
        let fine = n * REFINE;
        stay_inside_the_fold(&mut ideal, fine, &valid_at);
        // Between two fine rays a concave fold curve still bends past the interpolation, by
        // about 1/REFINE² of what the table's own interval would: a relative sliver this much
        // wider keeps the Jacobian determinant positive everywhere inside.
        for r in ideal.iter_mut() {
            *r *= 1.0 - FINE_SAG_MARGIN;
        }
        // The image of the boundary, sampled finely along the *interpolated* ideal boundary
        // (the one `contains_ideal` tests against). Sampling only the table's own vertices
        // would put a chord where the image curve bulges: tangential and prism terms turn a
        // vertex at ideal angle i away from distorted angle i, so a table entry then reads a
        // chord, and in-domain points within the sag (1e-5 of the radius near a fold, where
        // every ideal point of the band maps next to the boundary) would read as outside.
        let mut distorted = Vec::new();
        for _ in 0..CLIP_ROUNDS {
            let boundary: Vec<DVec2> = (0..fine)
                .map(|k| {
                    let angle = TAU * k as f64 / fine as f64;
                    let dir = DVec2::new(angle.cos(), angle.sin());
                    forward(dir * lookup(&ideal, angle)).unwrap_or(DVec2::ZERO)
                })
                .collect();
            distorted = nearest_crossings(&boundary, n);
            cover_boundary(&mut distorted, &boundary);
            // Clipping changes the boundary, so its image is read again; a star-shaped image
            // (every ordinary lens) is done after the first round.
            if !clip_to_the_image(&mut ideal, &distorted, REFINE, &forward) {
                break;
            }
        }
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

    /// The domain of a radially symmetric model: the same radii in every direction.
    pub fn radial(ideal: f64, distorted: f64, folds: bool) -> Self {
        Self::from_tables(
            vec![ideal; Self::SAMPLES],
            vec![distorted; Self::SAMPLES],
            folds,
        )
    }

    /// A domain without any boundary but the radius cap (no distortion).
    pub fn unbounded() -> Self {
        Self::unbounded_within(Self::RADIUS_CAP)
    }

    /// A domain without any boundary but `cap` (see [`ValidDomain::compute_within`]).
    pub fn unbounded_within(cap: f64) -> Self {
        Self::from_tables(vec![cap; Self::SAMPLES], vec![cap; Self::SAMPLES], false)
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

    /// Whether the ideal boundary is the same radius in every direction (a lens that never
    /// folds before the radius cap, or a radially symmetric one): then the smallest radius
    /// alone says what the table would.
    pub fn is_round(&self) -> bool {
        self.ideal.iter().all(|&r| r == self.min_ideal)
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

/// Boundary-image samples per table interval (see [`ValidDomain::compute`]).
const REFINE: usize = 16;

/// Relative inward margin of the ideal table for the fold's bend between fine rays.
const FINE_SAG_MARGIN: f64 = 1e-6;

/// Most rounds of reading the boundary image and clipping the ideal table to it.
const CLIP_ROUNDS: usize = 6;

/// Largest shortfall [`cover_boundary`] makes up, relative to the radius: interpolation
/// between table angles misses the image curve by far less. A larger one is a farther
/// crossing of a boundary image that is not star-shaped, which the nearest crossing rightly
/// leaves out.
const COVER_MAX_SHORTFALL: f64 = 1e-3;

/// Outward margin for what the fine samples cannot see: between two of them the image curve
/// bends by about 1/REFINE² of a table interval's sag, and the GPU reads the table in f32.
const COVER_MARGIN: f64 = 1e-6;

/// Lowers the ideal table where its linear interpolation between two rays reaches past the
/// fold of the rays in between. Two ways it can: where the fold curve is concave in polar
/// coordinates, the interpolated radius lands just past it (Newton would start where the
/// Jacobian determinant is negative); and where one ray folds and its neighbour never does
/// (prism terms can outgrow a rational radial part that turns back), the interpolation is a
/// spike whose middle lies beyond a fold and a recovery. Each of `fine` rays between the
/// table's own is checked: marched in full where its interval's ends differ (a spike), at
/// its interpolated radius where they are close. Only the larger end of a failing interval
/// comes down, as far as needed; values only ever fall, so a ray once satisfied stays so.
fn stay_inside_the_fold(table: &mut [f64], fine: usize, valid_at: &impl Fn(DVec2, DVec2) -> bool) {
    let n = table.len();
    let per_fine = n as f64 / fine as f64;
    for k in 0..fine {
        if k % (fine / n) != 0 {
            fold_check(table, k as f64 * per_fine, valid_at);
        }
    }
    // Where the boundary switches between its two conditions (the determinant and the radial
    // growth along the ray), it has a kink that bends inward faster than any sampling rate
    // sees: each gap between fine rays is checked at its middle, and where that fails, the
    // gap is halved again, down to 1/2^KINK_DEPTH of it.
    for k in 0..fine {
        check_gap(table, k as f64 * per_fine, per_fine, valid_at, KINK_DEPTH);
    }
}

/// How many times a gap between fine rays whose middle was past the fold is halved.
const KINK_DEPTH: u32 = 6;

fn check_gap(
    table: &mut [f64],
    from: f64,
    width: f64,
    valid_at: &impl Fn(DVec2, DVec2) -> bool,
    depth: u32,
) {
    let middle = from + 0.5 * width;
    if fold_check(table, middle, valid_at) && depth > 0 {
        check_gap(table, from, 0.5 * width, valid_at, depth - 1);
        check_gap(table, middle, 0.5 * width, valid_at, depth - 1);
    }
}

/// Checks the ray at table position `t` (a fractional index) and lowers the table if its
/// interpolated radius there is past the ray's fold; returns whether it had to. An interval
/// whose ends differ (a spike) is marched in full; a smooth one is probed at the radius only.
fn fold_check(table: &mut [f64], t: f64, valid_at: &impl Fn(DVec2, DVec2) -> bool) -> bool {
    let (i, j, f) = interval(table.len(), t);
    let angle = TAU * t / table.len() as f64;
    let dir = DVec2::new(angle.cos(), angle.sin());
    let (a, b) = (table[i], table[j]);
    let r = a * (1.0 - f) + b * f;
    // Marching past the table's largest radius could not lower it: that bound is the cap.
    let cap = table.iter().copied().fold(0.0, f64::max);
    let fold = if a.max(b) > SMOOTH_INTERVAL * a.min(b) {
        march(valid_at, dir, cap).0
    } else if valid_at(dir * r, dir) {
        return false;
    } else {
        fold_between(valid_at, dir, 0.9 * a.min(b), r, cap)
    };
    if fold >= r {
        return false;
    }
    lower_to(table, t, fold);
    true
}

/// The interval `(i, j)` of a fractional table position and the weight of `j` in it.
fn interval(n: usize, t: f64) -> (usize, usize, f64) {
    let t = t.rem_euclid(n as f64);
    let i = (t.floor() as usize).min(n - 1);
    (i, (i + 1) % n, t - i as f64)
}

/// Lowers the table so that its interpolation at fractional position `t` is at most `limit`:
/// the larger end of the interval comes down as far as needed; if even the smaller end is
/// past `limit`, both come down to it. Values only ever fall, so a position once satisfied
/// stays so.
fn lower_to(table: &mut [f64], t: f64, limit: f64) {
    let (i, j, f) = interval(table.len(), t);
    if table[i] * (1.0 - f) + table[j] * f <= limit {
        return;
    }
    let (big, small, w_big, w_small) = if table[i] >= table[j] {
        (i, j, 1.0 - f, f)
    } else {
        (j, i, f, 1.0 - f)
    };
    let lowered = (limit - table[small] * w_small) / w_big;
    if lowered >= table[small] {
        table[big] = lowered;
    } else {
        table[big] = limit;
        table[small] = limit;
    }
}

/// Lowers the ideal table where the image of its boundary leaves the distorted table by more
/// than the cover allows: a boundary image that is not star-shaped (prism terms outgrowing a
/// radial part that turns back draw a long tentacle) has points the nearest crossing leaves
/// out, and an ideal point whose image is refused before the inverse runs must not count as in
/// the domain. Along each fine ray, bisection finds the last radius whose image is inside.
/// Returns whether anything was lowered.
fn clip_to_the_image(
    ideal: &mut [f64],
    distorted: &[f64],
    refine: usize,
    forward: &impl Fn(DVec2) -> Option<DVec2>,
) -> bool {
    let fine = ideal.len() * refine;
    let inside = |x: DVec2| {
        forward(x).is_some_and(|y| {
            let rho = y.length();
            rho.is_finite() && rho <= lookup(distorted, y.y.atan2(y.x))
        })
    };
    let mut lowered = false;
    for k in 0..fine {
        let angle = TAU * k as f64 / fine as f64;
        let dir = DVec2::new(angle.cos(), angle.sin());
        let r = lookup(ideal, angle);
        if inside(dir * r) {
            continue;
        }
        let last = last_true(0.0, r, |radius| inside(dir * radius));
        lower_to(
            ideal,
            k as f64 / refine as f64,
            last * (1.0 - BOUNDARY_MARGIN),
        );
        lowered = true;
    }
    lowered
}

/// Ratio of an interval's two table radii above which its rays are marched in full.
const SMOOTH_INTERVAL: f64 = 1.05;

/// Raises the distorted table so that its linear interpolation reaches every fine sample of
/// the boundary image near it. The table then bounds the image of the domain from *outside*
/// (up to `COVER_MARGIN`), so an in-domain point is never refused before the inverse runs;
/// the inverse's own check (residual, ideal-domain membership of the answer) decides the
/// thin band beyond the true boundary.
fn cover_boundary(table: &mut [f64], boundary: &[DVec2]) {
    let n = table.len();
    for p in boundary {
        let rho = p.length();
        if !rho.is_finite() || rho == 0.0 {
            continue;
        }
        let (i, j, f) = interval(n, position(n, p.y.atan2(p.x)));
        let reach = table[i] * (1.0 - f) + table[j] * f;
        if rho > reach && rho <= reach * (1.0 + COVER_MAX_SHORTFALL) {
            // Scaling both ends of the interval by one factor scales the interpolation by it.
            let scale = rho / reach;
            table[i] *= scale;
            table[j] *= scale;
        }
    }
    for r in table.iter_mut() {
        *r *= 1.0 + COVER_MARGIN;
    }
}

/// Linear interpolation in a table of radii at uniform angles `TAU * i / len`.
fn lookup(table: &[f64], angle: f64) -> f64 {
    let (i, j, f) = interval(table.len(), position(table.len(), angle));
    table[i] * (1.0 - f) + table[j] * f
}

/// The fractional table position of `angle` (radians) in a table of `n` uniform angles.
fn position(n: usize, angle: f64) -> f64 {
    (angle / TAU).rem_euclid(1.0) * n as f64
}

/// The first failure of `valid_at` on the ray `dir` below `outside` (where it fails), found by
/// bisection from `inside` when that radius is valid, else by a full march from the centre.
fn fold_between(
    valid_at: &impl Fn(DVec2, DVec2) -> bool,
    dir: DVec2,
    inside: f64,
    outside: f64,
    cap: f64,
) -> f64 {
    if !(inside < outside) || !valid_at(dir * inside, dir) {
        return march(valid_at, dir, cap).0;
    }
    last_true(inside, outside, |r| valid_at(dir * r, dir)) * (1.0 - BOUNDARY_MARGIN)
}

/// Bisection between `inside` (where `holds`) and `outside` (where it does not) to a relative
/// 1e-13: the last radius where it holds, assuming one change in between.
fn last_true(mut inside: f64, mut outside: f64, holds: impl Fn(f64) -> bool) -> f64 {
    while outside - inside > 1e-13 * outside {
        let mid = 0.5 * (inside + outside);
        if holds(mid) {
            inside = mid;
        } else {
            outside = mid;
        }
    }
    inside
}

/// Walks outward along `dir` until `valid_at` fails; returns the last valid radius (refined by
/// bisection) and whether a failure was found before the cap.
fn march(valid_at: &impl Fn(DVec2, DVec2) -> bool, dir: DVec2, cap: f64) -> (f64, bool) {
    let mut inside = 0.0_f64;
    let mut r = 1e-6_f64;
    while r < cap {
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
    if valid_at(dir * cap, dir) {
        (cap, false)
    } else {
        (inside * (1.0 - BOUNDARY_MARGIN), true)
    }
}

/// Per table direction `TAU * j / n`, the distance from the origin to the nearest crossing of
/// the closed polygon `boundary`; the smallest vertex radius where a ray misses (a degenerate
/// boundary). A segment is only intersected with the rays inside the shorter arc its ends
/// subtend (it cannot cross any other), so the cost is one pass over the polygon.
fn nearest_crossings(boundary: &[DVec2], n: usize) -> Vec<f64> {
    let mut best = vec![f64::INFINITY; n];
    let step = TAU / n as f64;
    let m = boundary.len();
    for i in 0..m {
        let a = boundary[i];
        let b = boundary[(i + 1) % m];
        let e = b - a;
        let from = a.y.atan2(a.x);
        let sweep =
            (b.y.atan2(b.x) - from + std::f64::consts::PI).rem_euclid(TAU) - std::f64::consts::PI;
        let (lo, hi) = (from.min(from + sweep), from.max(from + sweep));
        // One ray of slack either side: the crossing test below is exact, the arc only culls.
        let first = (lo / step).floor() as i64 - 1;
        let last = (hi / step).ceil() as i64 + 1;
        for j in first..=last {
            let j = j.rem_euclid(n as i64) as usize;
            let angle = step * j as f64;
            let dir = DVec2::new(angle.cos(), angle.sin());
            // Solve t·dir = a + s·(b − a), t > 0, s ∈ [0, 1].
            let denom = dir.perp_dot(e);
            if denom.abs() < 1e-300 {
                continue;
            }
            let t = a.perp_dot(e) / denom;
            let s = a.perp_dot(dir) / denom;
            if t > 0.0 && (0.0..=1.0).contains(&s) {
                best[j] = best[j].min(t);
            }
        }
    }
    let fallback = boundary
        .iter()
        .map(|p| p.length())
        .fold(f64::INFINITY, f64::min);
    best.into_iter()
        .map(|t| if t.is_finite() { t } else { fallback })
        .collect()
}
