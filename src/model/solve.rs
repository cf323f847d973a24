//! The one 1D root finder the models share (after COLMAP's single iterative undistortion):
//! Newton's method safeguarded by bisection, for an increasing function on a bracket.

/// Most iterations; quadratic convergence needs well under ten, bisection at most ~60.
pub const MAX_ITERATIONS: usize = 100;

/// Solves `g(r) = target` for `r ∈ [0, hi]`, where `g` is increasing there with `g(0) = 0`
/// (a distortion's radial profile inside its valid domain). `g` returns `(g(r), g'(r))`.
/// Returns `hi` when the target lies beyond `g(hi)` (the caller's domain check decides what
/// that means).
pub fn solve_increasing(g: impl Fn(f64) -> (f64, f64), target: f64, hi: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, hi);
    if g(hi).0 <= target {
        return hi;
    }
    let mut r = target.min(hi);
    for _ in 0..MAX_ITERATIONS {
        let (value, slope) = g(r);
        let v = value - target;
        if v == 0.0 {
            break;
        }
        if v < 0.0 {
            lo = r;
        } else {
            hi = r;
        }
        let next = r - v / slope;
        if next == r {
            // Converged from one side (the bracket need not shrink then).
            break;
        }
        r = if slope > 0.0 && next > lo && next < hi {
            next
        } else {
            0.5 * (lo + hi)
        };
        if hi - lo < 1e-15 * hi {
            break;
        }
    }
    r
}
