//! The one 1D root finder the models share (after COLMAP's single iterative undistortion):
//! Newton's method safeguarded by bisection, for an increasing function on a bracket; and the
//! one 2D inverse the plane distortions share.

use glam::{DMat2, DVec2};

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

/// Newton: most iterations before giving up. Quadratic convergence from a radial start needs
/// 3-6; the rest is headroom for damped steps near the boundary.
pub const NEWTON_MAX_ITERATIONS: usize = 50;
/// Newton: a solution is accepted when it reproduces the distorted point to this (normalized
/// units; ~1e-9 px at fx = 1000).
pub const NEWTON_ACCEPT_RESIDUAL: f64 = 1e-12;
/// Newton: most step halvings per iteration (damping near the domain boundary).
pub const NEWTON_MAX_HALVINGS: usize = 40;
/// Steps of the continuation Newton falls back to when its first start fails. Only points
/// next to a fold at wide angles ever need it.
pub const CONTINUATION_STEPS: usize = 8;

/// The one 2D inverse the models with a distortion on a plane share (OpenCV's standard model,
/// COLMAP's thin-prism fisheyes): solves `f(x) = target` for x inside the valid domain
/// (`inside`) by Newton's method with the analytic Jacobian, damped so that it never leaves
/// the domain, started at `start`. Where that start lies in another basin (tangential or prism
/// terms next to a fold at a wide angle), the target is approached from the centre in
/// [`CONTINUATION_STEPS`] steps, each solved from the last answer: the preimage of that segment
/// is a continuous path inside the domain whenever the segment lies in the domain's image.
/// `f` returns the value and Jacobian; every term vanishes at the centre, where the answer is
/// the centre itself.
pub fn invert_2d(
    f: impl Fn(DVec2) -> Option<(DVec2, DMat2)>,
    inside: impl Fn(DVec2) -> bool,
    start: DVec2,
    target: DVec2,
) -> Option<DVec2> {
    if target.length() == 0.0 {
        return Some(DVec2::ZERO);
    }
    if let Some(x) = damped_newton(&f, &inside, start, target) {
        return Some(x);
    }
    let mut x = DVec2::ZERO;
    for step in 1..=CONTINUATION_STEPS {
        let along = target * (step as f64 / CONTINUATION_STEPS as f64);
        x = damped_newton(&f, &inside, x, along)?;
    }
    Some(x)
}

/// The damped Newton iteration from `start`; `None` unless it ends inside with a vanishing
/// residual and a positive Jacobian determinant.
fn damped_newton(
    f: &impl Fn(DVec2) -> Option<(DVec2, DMat2)>,
    inside: &impl Fn(DVec2) -> bool,
    start: DVec2,
    target: DVec2,
) -> Option<DVec2> {
    let rho = target.length();
    let mut x = start;
    let (mut fx, mut jac) = f(x)?;
    for _ in 0..NEWTON_MAX_ITERATIONS {
        let residual = (fx - target).length();
        if residual <= f64::EPSILON * (1.0 + rho) {
            break;
        }
        if !(jac.determinant() > 0.0) {
            return None;
        }
        let step = jac.inverse() * (fx - target);
        if x - step == x {
            // Converged to rounding: the step no longer changes x.
            break;
        }
        // Damp: halve the step until the new point stays inside and reduces the residual by
        // at least a (1 - 1e-4 t) fraction (Armijo) — a simple trust region.
        let mut t = 1.0;
        let mut accepted = false;
        for _ in 0..NEWTON_MAX_HALVINGS {
            let candidate = x - step * t;
            if inside(candidate) {
                if let Some((fc, jc)) = f(candidate) {
                    if (fc - target).length() < residual * (1.0 - 1e-4 * t) {
                        (x, fx, jac) = (candidate, fc, jc);
                        accepted = true;
                        break;
                    }
                }
            }
            t *= 0.5;
        }
        if !accepted {
            break;
        }
    }
    let ok = (fx - target).length() <= NEWTON_ACCEPT_RESIDUAL * (1.0 + rho)
        && jac.determinant() > 0.0
        && inside(x);
    ok.then_some(x)
}
