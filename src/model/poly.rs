//! Polynomials in ascending order (c0 first), as f-theta and OCamCalib files write them, and
//! the one solver their exact inverses share.

use super::jet::Scalar;

/// Σ cᵢ tⁱ (Horner).
pub fn eval<T: Scalar>(c: &[f64], t: T) -> T {
    c.iter().rev().fold(T::cst(0.0), |acc, &ci| acc * t + ci)
}

/// (Σ cᵢ tⁱ, Σ i cᵢ tⁱ⁻¹).
pub fn eval_with_slope(c: &[f64], t: f64) -> (f64, f64) {
    let mut value = 0.0;
    let mut slope = 0.0;
    for &ci in c.iter().rev() {
        slope = slope * t + value;
        value = value * t + ci;
    }
    (value, slope)
}

/// The first point in (0, hi] where `g` stops increasing (its slope reaches zero), by a march
/// of `steps` and bisection on the slope; `hi` when it increases all the way.
pub fn increasing_until(g: impl Fn(f64) -> (f64, f64), hi: f64, steps: usize) -> f64 {
    let mut lo = 0.0;
    for i in 1..=steps {
        let t = hi * i as f64 / steps as f64;
        if !(g(t).1 > 0.0) {
            let mut top = t;
            for _ in 0..80 {
                let mid = 0.5 * (lo + top);
                if g(mid).1 > 0.0 {
                    lo = mid;
                } else {
                    top = mid;
                }
            }
            return lo;
        }
        lo = t;
    }
    hi
}

/// Solves g(t) = target on [0, hi] where g increases, by Newton safeguarded by bisection.
/// `None` when the target lies outside [g(0), g(hi)].
pub fn solve_monotone(g: impl Fn(f64) -> (f64, f64), target: f64, hi: f64) -> Option<f64> {
    let (g0, _) = g(0.0);
    let (g1, _) = g(hi);
    if !(target >= g0 && target <= g1) {
        return None;
    }
    let (mut lo, mut top) = (0.0, hi);
    // Start where the secant through the bracket's ends meets the target.
    let mut t = if g1 > g0 {
        hi * (target - g0) / (g1 - g0)
    } else {
        0.0
    };
    for _ in 0..200 {
        let (v, slope) = g(t);
        let r = v - target;
        if r == 0.0 {
            break;
        }
        if r < 0.0 {
            lo = t;
        } else {
            top = t;
        }
        let next = t - r / slope;
        if next == t {
            break;
        }
        t = if slope > 0.0 && next > lo && next < top {
            next
        } else {
            0.5 * (lo + top)
        };
        if top - lo <= 4.0 * f64::EPSILON * top.max(f64::MIN_POSITIVE) {
            break;
        }
    }
    Some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn horner_and_slope() {
        let c = [1.0, -2.0, 0.5, 3.0];
        let (v, s) = eval_with_slope(&c, 0.7);
        let direct = 1.0 - 2.0 * 0.7 + 0.5 * 0.49 + 3.0 * 0.343;
        assert!((v - direct).abs() < 1e-15);
        assert!((s - (-2.0 + 0.7 + 9.0 * 0.49)).abs() < 1e-14);
        assert!((eval(&c, 0.7f64) - direct).abs() < 1e-15);
    }

    #[test]
    fn solves_and_refuses() {
        let g = |t: f64| (t + t * t * t, 1.0 + 3.0 * t * t);
        let t = solve_monotone(g, 2.0, 5.0).unwrap();
        assert!((t + t * t * t - 2.0).abs() < 1e-14);
        assert_eq!(solve_monotone(g, 1e3, 5.0), None);
        assert_eq!(solve_monotone(g, f64::NAN, 5.0), None);
        let fold = increasing_until(|t| (t - t * t * t, 1.0 - 3.0 * t * t), 2.0, 1000);
        assert!((fold - (1.0f64 / 3.0).sqrt()).abs() < 1e-12);
    }
}
