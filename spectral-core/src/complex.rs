//! A small `f64` complex number for optics and MESE (no_std, no dependency).
//!
//! `sqrt` returns the principal root (non-negative real part, branch cut on
//! the negative real axis, as C99 `csqrt`); `exp(a + ib) = e^a (cos b + i sin b)`.

use core::ops::{Add, AddAssign, Div, Mul, Neg, Sub, SubAssign};

/// `re + i·im`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Complex {
    /// Real part.
    pub re: f64,
    /// Imaginary part.
    pub im: f64,
}

impl Complex {
    /// 0.
    pub const ZERO: Self = Self::new(0.0, 0.0);
    /// 1.
    pub const ONE: Self = Self::new(1.0, 0.0);
    /// `i`.
    pub const I: Self = Self::new(0.0, 1.0);

    /// `re + i·im`.
    pub const fn new(re: f64, im: f64) -> Self {
        Self { re, im }
    }

    /// A real number.
    pub const fn real(re: f64) -> Self {
        Self::new(re, 0.0)
    }

    /// Complex conjugate.
    pub fn conj(self) -> Self {
        Self::new(self.re, -self.im)
    }

    /// `|z|²`.
    pub fn norm_sqr(self) -> f64 {
        self.re * self.re + self.im * self.im
    }

    /// `|z|` (overflow-safe).
    pub fn abs(self) -> f64 {
        libm::hypot(self.re, self.im)
    }

    /// Principal square root.
    pub fn sqrt(self) -> Self {
        if self.re == 0.0 && self.im == 0.0 {
            return Self::ZERO;
        }
        let r = self.abs();
        let t = libm::sqrt(0.5 * (r + self.re.abs()));
        if self.re >= 0.0 {
            Self::new(t, self.im / (2.0 * t))
        } else {
            Self::new(self.im.abs() / (2.0 * t), libm::copysign(t, self.im))
        }
    }

    /// `e^z`.
    pub fn exp(self) -> Self {
        let scale = libm::exp(self.re);
        Self::new(scale * libm::cos(self.im), scale * libm::sin(self.im))
    }

    /// `e^{iθ}`.
    pub fn cis(theta: f64) -> Self {
        Self::new(libm::cos(theta), libm::sin(theta))
    }

    /// `z · s` for real `s`.
    pub fn scale(self, s: f64) -> Self {
        Self::new(self.re * s, self.im * s)
    }

    /// Whether both parts are finite.
    pub fn is_finite(self) -> bool {
        self.re.is_finite() && self.im.is_finite()
    }
}

impl Add for Complex {
    type Output = Self;
    fn add(self, rhs: Self) -> Self {
        Self::new(self.re + rhs.re, self.im + rhs.im)
    }
}

impl AddAssign for Complex {
    fn add_assign(&mut self, rhs: Self) {
        *self = *self + rhs;
    }
}

impl Sub for Complex {
    type Output = Self;
    fn sub(self, rhs: Self) -> Self {
        Self::new(self.re - rhs.re, self.im - rhs.im)
    }
}

impl SubAssign for Complex {
    fn sub_assign(&mut self, rhs: Self) {
        *self = *self - rhs;
    }
}

impl Mul for Complex {
    type Output = Self;
    fn mul(self, rhs: Self) -> Self {
        Self::new(
            self.re * rhs.re - self.im * rhs.im,
            self.re * rhs.im + self.im * rhs.re,
        )
    }
}

impl Div for Complex {
    type Output = Self;
    /// Smith's algorithm (no overflow for large operands).
    fn div(self, rhs: Self) -> Self {
        if rhs.re.abs() >= rhs.im.abs() {
            let ratio = rhs.im / rhs.re;
            let denom = rhs.re + rhs.im * ratio;
            Self::new(
                (self.re + self.im * ratio) / denom,
                (self.im - self.re * ratio) / denom,
            )
        } else {
            let ratio = rhs.re / rhs.im;
            let denom = rhs.re * ratio + rhs.im;
            Self::new(
                (self.re * ratio + self.im) / denom,
                (self.im * ratio - self.re) / denom,
            )
        }
    }
}

impl Neg for Complex {
    type Output = Self;
    fn neg(self) -> Self {
        Self::new(-self.re, -self.im)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Complex, b: Complex) -> bool {
        (a - b).abs() < 1e-12
    }

    #[test]
    fn arithmetic_identities() {
        let a = Complex::new(1.5, -2.0);
        let b = Complex::new(-0.25, 3.0);
        assert!(close((a * b) / b, a));
        assert!(close(a * a.conj(), Complex::real(a.norm_sqr())));
        assert!(close(Complex::I * Complex::I, Complex::real(-1.0)));
        assert!(close(
            Complex::cis(core::f64::consts::PI),
            Complex::real(-1.0)
        ));
        assert!(close(
            Complex::new(0.0, core::f64::consts::FRAC_PI_2).exp(),
            Complex::I
        ));
        assert!((Complex::new(3.0, 4.0).abs() - 5.0).abs() < 1e-15);
    }

    #[test]
    fn principal_square_root() {
        for z in [
            Complex::new(4.0, 0.0),
            Complex::new(-4.0, 0.0),
            Complex::new(-4.0, -0.0),
            Complex::new(0.3, -2.0),
            Complex::new(-1e-3, 5.0),
            Complex::new(-7.0, -1e-9),
        ] {
            let r = z.sqrt();
            assert!(close(r * r, z), "{z:?}");
            assert!(r.re >= 0.0, "{z:?}");
        }
        assert_eq!(Complex::new(-4.0, 0.0).sqrt(), Complex::new(0.0, 2.0));
        assert_eq!(Complex::ZERO.sqrt(), Complex::ZERO);
    }
}
