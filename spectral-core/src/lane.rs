//! The numeric lane type of the Fourier algebra.
//!
//! One implementation of the algebra serves a single spectrum (`f32`, `f64`)
//! and a bundle of eight ray lanes (`wide::f32x8`, feature `simd`): every
//! operation here is lane-wise, so a `FourierSpectrum<f32x8, N>` is eight
//! independent spectra stored coefficient-major.
//!
//! `mul_add` is fused (one rounding) for `f32x8` on FMA hardware and
//! unfused (`a * b + c`) for the scalar types, because a scalar software FMA
//! would be far slower than the multiply-add a scalar renderer actually does.
//! The lane-vs-scalar oracle tests therefore compare with a tolerance.
//!
//! NaN policy: arithmetic is IEEE and NaN propagates; `min`/`max` return the
//! non-NaN operand where the platform allows it (`f32::min`, `wide`'s
//! NaN-checked `min`/`max`).

use core::fmt::Debug;
use core::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// A lane-wise numeric type: `f32`, `f64` or `wide::f32x8`.
pub trait Lane:
    Copy
    + Debug
    + PartialEq
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
{
    /// Number of independent lanes (1 for scalars, 8 for `f32x8`).
    const LANES: usize;
    /// The result of a lane-wise comparison.
    type Mask: Copy;

    /// Every lane set to `value` (rounded to the lane precision).
    fn splat(value: f64) -> Self;
    /// `self * a + b`, lane-wise.
    fn mul_add(self, a: Self, b: Self) -> Self;
    /// Lane-wise minimum.
    fn min(self, other: Self) -> Self;
    /// Lane-wise maximum.
    fn max(self, other: Self) -> Self;
    /// Lane-wise `self < other`.
    fn lt(self, other: Self) -> Self::Mask;
    /// Lane-wise `if mask { if_true } else { if_false }`.
    fn select(mask: Self::Mask, if_true: Self, if_false: Self) -> Self;
    /// Lane-wise sine (radians).
    fn sin(self) -> Self;
    /// Lane `index` as `f64` (`index < LANES`).
    fn lane(self, index: usize) -> f64;
    /// A value whose lane `i` is `f(i)`.
    fn from_fn(f: impl FnMut(usize) -> f64) -> Self;
}

impl Lane for f64 {
    const LANES: usize = 1;
    type Mask = bool;

    #[inline(always)]
    fn splat(value: f64) -> Self {
        value
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        self * a + b
    }
    #[inline(always)]
    fn min(self, other: Self) -> Self {
        f64::min(self, other)
    }
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        f64::max(self, other)
    }
    #[inline(always)]
    fn lt(self, other: Self) -> bool {
        self < other
    }
    #[inline(always)]
    fn select(mask: bool, if_true: Self, if_false: Self) -> Self {
        if mask { if_true } else { if_false }
    }
    #[inline(always)]
    fn sin(self) -> Self {
        libm::sin(self)
    }
    #[inline(always)]
    fn lane(self, index: usize) -> f64 {
        debug_assert!(index < Self::LANES);
        self
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f64) -> Self {
        f(0)
    }
}

impl Lane for f32 {
    const LANES: usize = 1;
    type Mask = bool;

    #[inline(always)]
    fn splat(value: f64) -> Self {
        value as f32
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        self * a + b
    }
    #[inline(always)]
    fn min(self, other: Self) -> Self {
        f32::min(self, other)
    }
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        f32::max(self, other)
    }
    #[inline(always)]
    fn lt(self, other: Self) -> bool {
        self < other
    }
    #[inline(always)]
    fn select(mask: bool, if_true: Self, if_false: Self) -> Self {
        if mask { if_true } else { if_false }
    }
    #[inline(always)]
    fn sin(self) -> Self {
        libm::sinf(self)
    }
    #[inline(always)]
    fn lane(self, index: usize) -> f64 {
        debug_assert!(index < Self::LANES);
        f64::from(self)
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f64) -> Self {
        f(0) as f32
    }
}

#[cfg(feature = "simd")]
mod wide_lane {
    use super::Lane;
    use wide::f32x8;

    impl Lane for f32x8 {
        const LANES: usize = 8;
        type Mask = f32x8;

        #[inline(always)]
        fn splat(value: f64) -> Self {
            f32x8::splat(value as f32)
        }
        #[inline(always)]
        fn mul_add(self, a: Self, b: Self) -> Self {
            f32x8::mul_add(self, a, b)
        }
        #[inline(always)]
        fn min(self, other: Self) -> Self {
            f32x8::min(self, other)
        }
        #[inline(always)]
        fn max(self, other: Self) -> Self {
            f32x8::max(self, other)
        }
        #[inline(always)]
        fn lt(self, other: Self) -> f32x8 {
            self.simd_lt(other)
        }
        #[inline(always)]
        fn select(mask: f32x8, if_true: Self, if_false: Self) -> Self {
            mask.select(if_true, if_false)
        }
        #[inline(always)]
        fn sin(self) -> Self {
            f32x8::sin(self)
        }
        #[inline(always)]
        fn lane(self, index: usize) -> f64 {
            f64::from(self.to_array()[index])
        }
        #[inline(always)]
        fn from_fn(mut f: impl FnMut(usize) -> f64) -> Self {
            let mut lanes = [0.0f32; 8];
            for (index, lane) in lanes.iter_mut().enumerate() {
                *lane = f(index) as f32;
            }
            f32x8::new(lanes)
        }
    }
}

#[cfg(all(test, feature = "simd"))]
mod tests {
    use super::Lane;
    use wide::f32x8;

    fn edge_values() -> [f32; 8] {
        [0.0, -0.0, 1e-30, -3.5, 7.25, 1e30, -1e-12, 0.5]
    }

    #[test]
    fn f32x8_ops_match_scalar_lane_by_lane() {
        let a = edge_values();
        let mut b = edge_values();
        b.reverse();
        let c = [1.0f32, -2.0, 3.0, 1e-20, -1e20, 0.0, 5.0, -0.25];
        let (va, vb, vc) = (f32x8::new(a), f32x8::new(b), f32x8::new(c));
        let mask = Lane::lt(va, vb);
        for i in 0..8 {
            let fused = Lane::mul_add(va, vb, vc).lane(i);
            let exact = f64::from(a[i]) * f64::from(b[i]) + f64::from(c[i]);
            let scale = (f64::from(a[i]) * f64::from(b[i])).abs() + f64::from(c[i]).abs();
            assert!((fused - exact).abs() <= scale * 1e-7, "lane {i}");
            assert_eq!(Lane::min(va, vb).lane(i), f64::from(a[i].min(b[i])));
            assert_eq!(Lane::max(va, vb).lane(i), f64::from(a[i].max(b[i])));
            let chosen = <f32x8 as Lane>::select(mask, va, vb).lane(i);
            let expected = if a[i] < b[i] { a[i] } else { b[i] };
            assert_eq!(chosen, f64::from(expected));
            assert_eq!(<f32x8 as Lane>::from_fn(|k| k as f64).lane(i), i as f64);
        }
    }

    #[test]
    fn nan_in_min_max_prefers_the_number() {
        let nan = f32x8::splat(f32::NAN);
        let one = f32x8::splat(1.0);
        assert_eq!(Lane::min(one, nan).lane(3), 1.0);
        assert_eq!(Lane::max(one, nan).lane(3), 1.0);
        assert_eq!(Lane::min(1.0f32, f32::NAN), 1.0);
    }
}
