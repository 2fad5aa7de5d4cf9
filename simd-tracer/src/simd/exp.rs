//! `e^x` for 8 lanes of non-positive arguments: the splat's Gaussian
//! weights, two per sample, were the largest part of the film's work that
//! was not adds (a general `exp` also handles overflow, subnormal results,
//! infinities and NaN, none of which a weight `e^{−x²/2σ²}` of an offset
//! inside the filter's support meets).
//!
//! # Method
//!
//! Cody and Waite's range reduction with Moshier's single-precision
//! polynomial (Cephes Math Library, `expf.c`): `x = n ln 2 + r`,
//! `n = round(x log₂ e)`, `|r| ≤ ln 2 / 2`, with `ln 2` split into
//! [`LN2_HI`] (few significant bits, so `n · LN2_HI` is exact for the `n`
//! of the domain) and [`LN2_LO`]; `e^r = 1 + r + r² P(r)` with the
//! degree-5 minimax `P` of [`EXP_POLY`]; `e^x = e^r · 2ⁿ`, the power of two
//! made from its exponent bits. Arguments are clamped to
//! `[`[`EXP_ARGUMENT_MIN`]`, 0]` first, where `2ⁿ` stays a normal number,
//! so no lane needs the special cases.
//!
//! Accuracy: within 2 ulp of the correctly rounded `e^x` over the whole
//! domain, checked lane by lane against `f64::exp` (the scalar oracle).
//!
//! NaN policy: a NaN lane gives a finite value in `(0, 1]` (the clamps'
//! `max`/`min` do not keep NaN); callers mask such lanes, as the filter
//! masks offsets outside its support.

use wide::bytemuck::cast;
use wide::{f32x8, i32x8};

/// The smallest argument: `e^x` is clamped there, `x log₂ e ≥ −126` (a
/// normal `2ⁿ`).
pub const EXP_ARGUMENT_MIN: f32 = -87.0;

/// The high part of `ln 2` (Cody–Waite): `0.693359375 = 355/512`, nine
/// significant bits, so `n · LN2_HI` is exact for `|n| ≤ 2¹⁵`.
const LN2_HI: f32 = 0.693_359_4;

/// `ln 2 − LN2_HI`, rounded to `f32`.
const LN2_LO: f32 = -2.121_944_4e-4;

/// Moshier's minimax coefficients of `P` (highest degree first), Cephes
/// `expf.c`, rounded to `f32` (the last, 5.0000001201e-1, rounds to 1/2):
/// `e^r ≈ 1 + r + r² P(r)` on `|r| ≤ ln 2 / 2`.
const EXP_POLY: [f32; 6] = [
    1.987_569_2e-4,
    1.398_199_9e-3,
    8.333_452e-3,
    4.166_579_6e-2,
    1.666_666_5e-1,
    0.5,
];

/// The exponent bias of `f32`.
const EXPONENT_BIAS: i32 = 127;

/// The position of the exponent bits in an `f32`.
const MANTISSA_BITS: i32 = 23;

/// `e^x` in each lane for `x ≤ 0` (module docs; arguments below
/// [`EXP_ARGUMENT_MIN`] give `e^EXP_ARGUMENT_MIN`, above 0 give 1).
#[inline(always)]
pub fn exp_nonpositive_x8(x: f32x8) -> f32x8 {
    let x = x
        .fast_max(f32x8::splat(EXP_ARGUMENT_MIN))
        .fast_min(f32x8::ZERO);
    let n = (x * f32x8::splat(core::f32::consts::LOG2_E)).round();
    let r = n.mul_neg_add(f32x8::splat(LN2_HI), x);
    let r = n.mul_neg_add(f32x8::splat(LN2_LO), r);
    let p = EXP_POLY
        .iter()
        .skip(1)
        .fold(f32x8::splat(EXP_POLY[0]), |p, &c| {
            p.mul_add(r, f32x8::splat(c))
        });
    let e_r = p.mul_add(r * r, r) + f32x8::ONE;
    let power: i32x8 = (n.round_int() + i32x8::splat(EXPONENT_BIAS)) << MANTISSA_BITS;
    e_r * cast::<i32x8, f32x8>(power)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The distance in units in the last place between `got` and the
    /// correctly rounded `want`.
    fn ulps(got: f32, want: f64) -> f64 {
        let rounded = want as f32;
        let ulp = f64::from(f32::from_bits(rounded.to_bits() + 1) - rounded);
        (f64::from(got) - want).abs() / ulp
    }

    /// Lane by lane against `f64::exp` over the whole domain (a dense grid
    /// and every lane position), the end points and the clamps. Negative
    /// control, run by hand: leaving out `LN2_LO` puts results thousands of
    /// ulp off at the domain's low end.
    #[test]
    fn lanes_are_within_two_ulp_of_the_exponential() {
        let count = 1 << 18;
        let mut worst = 0.0f64;
        for chunk in 0..count / 8 {
            let x: [f32; 8] = core::array::from_fn(|lane| {
                let k = chunk * 8 + lane;
                EXP_ARGUMENT_MIN * (k as f32 / (count - 1) as f32)
            });
            let got = exp_nonpositive_x8(f32x8::new(x)).to_array();
            for (lane, (&x, &got)) in x.iter().zip(&got).enumerate() {
                let error = ulps(got, f64::from(x).exp());
                assert!(error <= 2.0, "lane {lane}: e^{x} = {got}, {error} ulp");
                worst = worst.max(error);
            }
        }
        assert!(worst > 0.0, "the grid tested nothing");
        let ends = exp_nonpositive_x8(f32x8::new([
            0.0,
            -0.0,
            EXP_ARGUMENT_MIN,
            1.0,
            -1000.0,
            f32::NEG_INFINITY,
            -f32::MIN_POSITIVE,
            -0.5,
        ]))
        .to_array();
        let floor = f64::from(EXP_ARGUMENT_MIN).exp();
        let want = [1.0, 1.0, floor, 1.0, floor, floor, 1.0, (-0.5f64).exp()];
        for (lane, (&got, &want)) in ends.iter().zip(&want).enumerate() {
            assert!(ulps(got, want) <= 2.0, "lane {lane}: {got} against {want}");
        }
    }

    /// NaN lanes give a finite value in `(0, 1]` (module docs).
    #[test]
    fn nan_lanes_give_a_finite_value() {
        let got = exp_nonpositive_x8(f32x8::splat(f32::NAN)).to_array();
        assert!(got.iter().all(|&v| v > 0.0 && v <= 1.0), "{got:?}");
    }
}
