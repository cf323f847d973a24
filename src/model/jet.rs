//! Forward-mode derivatives (COLMAP and Ceres call them jets): a value with its partial
//! derivatives with respect to N inputs, carried through every operation by the chain rule.
//!
//! The camera models of the table write their forward map once, generic over [`Scalar`]; the
//! same code then gives the f64 value (`f64`) and the exact analytic Jacobian (`Jet<N>`), so a
//! model's Jacobian can never drift from its forward map. The derivatives are exact (no
//! finite differences): each elementary function carries its closed-form derivative.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// What the models' generic forward maps compute with: `f64`, or a [`Jet`].
pub trait Scalar:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
{
    /// A constant (all derivatives zero).
    fn cst(v: f64) -> Self;
    /// The value without its derivatives.
    fn value(self) -> f64;
    /// √x.
    fn sqrt(self) -> Self;
    /// atan(x).
    fn atan(self) -> Self;
    /// atan2(self, x).
    fn atan2(self, x: Self) -> Self;
    /// sin(x).
    fn sin(self) -> Self;
    /// cos(x).
    fn cos(self) -> Self;
    /// tan(x).
    fn tan(self) -> Self;
}

impl Scalar for f64 {
    fn cst(v: f64) -> Self {
        v
    }
    fn value(self) -> f64 {
        self
    }
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    fn atan(self) -> Self {
        f64::atan(self)
    }
    fn atan2(self, x: Self) -> Self {
        f64::atan2(self, x)
    }
    fn sin(self) -> Self {
        f64::sin(self)
    }
    fn cos(self) -> Self {
        f64::cos(self)
    }
    fn tan(self) -> Self {
        f64::tan(self)
    }
}

/// A value and its derivatives with respect to N inputs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jet<const N: usize> {
    /// The value.
    pub v: f64,
    /// ∂value/∂input_i.
    pub d: [f64; N],
}

impl<const N: usize> Jet<N> {
    /// Input number `i` with value `v` (derivative 1 with respect to itself).
    pub fn var(v: f64, i: usize) -> Self {
        let mut d = [0.0; N];
        d[i] = 1.0;
        Jet { v, d }
    }

    /// f(self) given f's value and derivative at self.value.
    fn chain(self, v: f64, slope: f64) -> Self {
        Jet {
            v,
            d: self.d.map(|x| x * slope),
        }
    }
}

impl<const N: usize> Add for Jet<N> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Jet {
            v: self.v + o.v,
            d: std::array::from_fn(|i| self.d[i] + o.d[i]),
        }
    }
}
impl<const N: usize> Sub for Jet<N> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Jet {
            v: self.v - o.v,
            d: std::array::from_fn(|i| self.d[i] - o.d[i]),
        }
    }
}
// The product and quotient rules mix + and − into * and / by design.
#[allow(clippy::suspicious_arithmetic_impl)]
impl<const N: usize> Mul for Jet<N> {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        Jet {
            v: self.v * o.v,
            d: std::array::from_fn(|i| self.d[i] * o.v + self.v * o.d[i]),
        }
    }
}
#[allow(clippy::suspicious_arithmetic_impl)]
impl<const N: usize> Div for Jet<N> {
    type Output = Self;
    fn div(self, o: Self) -> Self {
        let q = self.v / o.v;
        Jet {
            v: q,
            d: std::array::from_fn(|i| (self.d[i] - q * o.d[i]) / o.v),
        }
    }
}
impl<const N: usize> Neg for Jet<N> {
    type Output = Self;
    fn neg(self) -> Self {
        Jet {
            v: -self.v,
            d: self.d.map(|x| -x),
        }
    }
}
impl<const N: usize> Add<f64> for Jet<N> {
    type Output = Self;
    fn add(self, o: f64) -> Self {
        Jet {
            v: self.v + o,
            d: self.d,
        }
    }
}
impl<const N: usize> Sub<f64> for Jet<N> {
    type Output = Self;
    fn sub(self, o: f64) -> Self {
        Jet {
            v: self.v - o,
            d: self.d,
        }
    }
}
impl<const N: usize> Mul<f64> for Jet<N> {
    type Output = Self;
    fn mul(self, o: f64) -> Self {
        Jet {
            v: self.v * o,
            d: self.d.map(|x| x * o),
        }
    }
}
impl<const N: usize> Div<f64> for Jet<N> {
    type Output = Self;
    fn div(self, o: f64) -> Self {
        Jet {
            v: self.v / o,
            d: self.d.map(|x| x / o),
        }
    }
}

impl<const N: usize> Scalar for Jet<N> {
    fn cst(v: f64) -> Self {
        Jet { v, d: [0.0; N] }
    }
    fn value(self) -> f64 {
        self.v
    }
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        self.chain(s, 0.5 / s)
    }
    fn atan(self) -> Self {
        self.chain(self.v.atan(), 1.0 / (1.0 + self.v * self.v))
    }
    fn atan2(self, x: Self) -> Self {
        // d atan2(y, x) = (x dy − y dx) / (x² + y²)
        let r2 = x.v * x.v + self.v * self.v;
        Jet {
            v: self.v.atan2(x.v),
            d: std::array::from_fn(|i| (x.v * self.d[i] - self.v * x.d[i]) / r2),
        }
    }
    fn sin(self) -> Self {
        self.chain(self.v.sin(), self.v.cos())
    }
    fn cos(self) -> Self {
        self.chain(self.v.cos(), -self.v.sin())
    }
    fn tan(self) -> Self {
        let t = self.v.tan();
        self.chain(t, 1.0 + t * t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_closed_forms() {
        let x = Jet::<2>::var(0.7, 0);
        let y = Jet::<2>::var(-0.3, 1);
        let f = (x * y + x.sqrt()) / (y.cos() + 2.0) + y.atan2(x) - x.tan().atan();
        // ∂f/∂x and ∂f/∂y written out by hand.
        let (xv, yv) = (0.7f64, -0.3f64);
        let num = xv * yv + xv.sqrt();
        let den = yv.cos() + 2.0;
        let dfx = (yv + 0.5 / xv.sqrt()) / den + (-yv) / (xv * xv + yv * yv) - 1.0;
        let dfy = xv / den + num * yv.sin() / (den * den) + xv / (xv * xv + yv * yv);
        assert!((f.d[0] - dfx).abs() < 1e-14, "{} vs {dfx}", f.d[0]);
        assert!((f.d[1] - dfy).abs() < 1e-14, "{} vs {dfy}", f.d[1]);
    }
}
