//! `FourierSpectrum<L, N>`: a spectrum as `N` cosine coefficients.
//!
//! Formulas ([math](crate::math) §1; paper §2):
//!
//! * coefficients `c_j = (1/π) ∫_{−π}^{0} g(φ) cos(jφ) dφ`, `j = 0..m`,
//!   `m = N − 1`; `c_0` is the mean over the range;
//! * reconstruction `g(φ) ≈ c_0 + 2 Σ_{j=1}^{m} c_j cos(jφ)`, evaluated with
//!   the Chebyshev recurrence `T_j = 2x T_{j−1} − T_{j−2}`, `x = cos φ`: one
//!   cosine per wavelength;
//! * truncated product (the exact product of the two truncated series,
//!   truncated again): `h_k = Σ_{p=0}^{m} c_p d_{|k−p|} + Σ_{p=1}^{m−k} c_p d_{k+p}`,
//!   a Toeplitz plus a Hankel matrix–vector product. Loop bounds depend only
//!   on `N`, so the code has no data-dependent branch; with `L = f32x8` every
//!   multiply-add serves eight ray lanes. `h_0 = c_0 d_0 + 2 Σ c_p d_p`
//!   (Parseval).
//!
//! Projection of piecewise-linear data is exact: on a segment of slope `β`
//! (per radian) the `j ≥ 1` integral is `[g sin(jφ)/j + β cos(jφ)/j²]`; for a
//! continuous polyline over the whole range the `g sin` terms telescope to
//! zero at `φ = −π` and `φ = 0`, leaving
//! `c_j = −(1/π) Σ_seg (Δg/j) sin(j φ_mid) · sinc(j h)`, `h` the half-width of
//! the segment in phase and `sinc(x) = sin x / x`. This form has no
//! cancellation for short segments. `c_0` is the trapezoid sum, exact for
//! linear segments. Data are held flat beyond their ends ([math](crate::math) §1: zero
//! padding would add a step and ringing).

use crate::basis::FourierBasis;
use crate::damping::Damping;
use crate::lane::Lane;
use crate::range::SpectralRange;
use core::f64::consts::PI;
use core::ops::{Add, AddAssign, Mul, Sub};

/// `N` cosine coefficients of one spectrum (`L = f32`, `f64`) or of eight
/// (`L = f32x8`, one per ray lane, coefficient-major). See the crate docs
/// for the convention.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FourierSpectrum<L, const N: usize> {
    /// `c_0 … c_{N−1}`.
    pub coeffs: [L; N],
}

impl<L: Lane, const N: usize> FourierSpectrum<L, N> {
    const AT_LEAST_ONE_COEFFICIENT: () = assert!(N >= 1, "a Fourier spectrum needs N >= 1");

    /// A spectrum from its coefficients `c_0 … c_{N−1}`.
    #[inline(always)]
    pub const fn from_coeffs(coeffs: [L; N]) -> Self {
        let () = Self::AT_LEAST_ONE_COEFFICIENT;
        Self { coeffs }
    }

    /// The zero spectrum.
    #[inline(always)]
    pub fn zero() -> Self {
        Self::from_coeffs([L::splat(0.0); N])
    }

    /// The constant spectrum `value` (only `c_0` is non-zero).
    #[inline(always)]
    pub fn constant(value: L) -> Self {
        let mut s = Self::zero();
        s.coeffs[0] = value;
        s
    }

    /// The mean of the spectrum over its range, `c_0`.
    #[inline(always)]
    pub fn mean(&self) -> L {
        self.coeffs[0]
    }

    /// The same `f64` spectrum in every lane (rounded to the lane precision).
    pub fn splat(spectrum: &FourierSpectrum<f64, N>) -> Self {
        Self::from_coeffs(core::array::from_fn(|j| L::splat(spectrum.coeffs[j])))
    }

    /// Lane `lane` of this spectrum, as `f64` coefficients.
    pub fn lane(&self, lane: usize) -> FourierSpectrum<f64, N> {
        FourierSpectrum::from_coeffs(core::array::from_fn(|j| self.coeffs[j].lane(lane)))
    }

    /// A spectrum whose ray lane `lane` holds `per_lane(lane)`.
    pub fn from_lanes(per_lane: impl Fn(usize) -> FourierSpectrum<f64, N>) -> Self {
        Self::from_coeffs(core::array::from_fn(|j| {
            L::from_fn(|lane| per_lane(lane).coeffs[j])
        }))
    }

    /// The truncated series at a phase given by its cosine `x = cos φ`
    /// (lane-wise: each ray lane may have its own wavelength).
    #[inline]
    pub fn eval_cos(&self, cos_phase: L) -> L {
        let two_x = cos_phase + cos_phase;
        let mut t_prev = L::splat(1.0);
        let mut t = cos_phase;
        let mut tail = L::splat(0.0);
        for j in 1..N {
            tail = self.coeffs[j].mul_add(t, tail);
            let t_next = two_x.mul_add(t, -t_prev);
            t_prev = t;
            t = t_next;
        }
        (tail + tail) + self.coeffs[0]
    }

    /// The truncated series at one wavelength of `basis`'s range (the same
    /// wavelength in every lane).
    ///
    /// ```
    /// use spectral_core::{FourierBasis, FourierSpectrum};
    ///
    /// // c_0 + 2 c_1 cos φ: at 360 nm φ = −π, at 830 nm φ = 0.
    /// let s = FourierSpectrum::<f64, 2>::from_coeffs([0.5, 0.25]);
    /// let basis = FourierBasis::VISIBLE;
    /// assert_eq!(s.eval(&basis, 360.0), 0.0);
    /// assert_eq!(s.eval(&basis, 830.0), 1.0);
    /// ```
    #[inline]
    pub fn eval(&self, basis: &FourierBasis<N>, lambda_nm: f64) -> L {
        self.eval_cos(L::splat(basis.cos_phase(lambda_nm)))
    }

    /// The truncated product `h = self ⊛ other` (module docs), lane-wise;
    /// also `self * other`.
    ///
    /// ```
    /// use spectral_core::{FourierBasis, TabulatedSpectrum};
    ///
    /// // A lamp and a reflectance, both linear ramps over the range.
    /// let basis = FourierBasis::<8>::VISIBLE;
    /// let lamp = basis.project(&TabulatedSpectrum::new(&[360.0, 830.0], &[1.0, 2.0])?);
    /// let paint = basis.project(&TabulatedSpectrum::new(&[360.0, 830.0], &[0.8, 0.2])?);
    /// let reflected = lamp.product(&paint);
    /// assert_eq!(reflected, lamp * paint);
    /// // Its mean is the mean of the product of the truncated series
    /// // (Parseval, `product_mean`), close to the exact mean
    /// // ∫ (1 + t)(0.8 − 0.6 t) dt over t ∈ [0, 1] = 0.7.
    /// assert!((reflected.mean() - lamp.product_mean(&paint)).abs() < 1e-15);
    /// assert!((reflected.mean() - 0.7).abs() < 1e-4);
    /// # Ok::<(), spectral_core::SpectralError>(())
    /// ```
    ///
    /// For `N` = 4, 8, 12, 16 the product runs as fully unrolled straight-line
    /// code (the private `unrolled` module), with the accumulators in registers; other `N` use
    /// the equivalent loops. Both are checked against each other and against
    /// dense quadrature.
    #[inline]
    pub fn product(&self, other: &Self) -> Self {
        let mut h = Self::zero();
        if unrolled::product(&self.coeffs, &other.coeffs, &mut h.coeffs) {
            h
        } else {
            self.product_loops(other)
        }
    }

    /// The truncated product by plain loops (any `N`).
    #[inline]
    pub fn product_loops(&self, other: &Self) -> Self {
        let c = &self.coeffs;
        let d = &other.coeffs;
        let mut h = [L::splat(0.0); N];
        // Toeplitz part: h_k += c_p d_{|k−p|}. The accumulators `h[k]` are
        // independent, so the FMAs of one `p` pipeline.
        for (p, &cp) in c.iter().enumerate() {
            for (k, hk) in h.iter_mut().enumerate() {
                *hk = cp.mul_add(d[k.abs_diff(p)], *hk);
            }
        }
        // Hankel part: h_k += c_p d_{k+p}, p ≥ 1, k + p ≤ m.
        for (p, &cp) in c.iter().enumerate().skip(1) {
            for (hk, &dq) in h.iter_mut().zip(&d[p..]) {
                *hk = cp.mul_add(dq, *hk);
            }
        }
        Self::from_coeffs(h)
    }

    /// Only the zeroth coefficient of [`product`](Self::product):
    /// `h_0 = c_0 d_0 + 2 Σ_{p≥1} c_p d_p` (Parseval), `O(N)`.
    #[inline]
    pub fn product_mean(&self, other: &Self) -> L {
        let mut tail = L::splat(0.0);
        for j in 1..N {
            tail = self.coeffs[j].mul_add(other.coeffs[j], tail);
        }
        self.coeffs[0].mul_add(other.coeffs[0], tail + tail)
    }

    /// Every coefficient times `factor` (lane-wise).
    #[inline]
    pub fn scale(&self, factor: L) -> Self {
        Self::from_coeffs(self.coeffs.map(|c| c * factor))
    }

    /// `self + t (other − self)`, lane-wise `t`.
    #[inline]
    pub fn lerp(&self, other: &Self, t: L) -> Self {
        Self::from_coeffs(core::array::from_fn(|j| {
            t.mul_add(other.coeffs[j] - self.coeffs[j], self.coeffs[j])
        }))
    }

    /// The series damped by the σ-factors of `damping` (coefficient `j`
    /// multiplied by `σ_j`).
    pub fn damped(&self, damping: Damping) -> Self {
        let sigma = damping.factors::<N>();
        Self::from_coeffs(core::array::from_fn(|j| {
            self.coeffs[j] * L::splat(sigma[j])
        }))
    }
}

impl<L: Lane, const N: usize> Add for FourierSpectrum<L, N> {
    type Output = Self;
    #[inline]
    fn add(self, rhs: Self) -> Self {
        Self::from_coeffs(core::array::from_fn(|j| self.coeffs[j] + rhs.coeffs[j]))
    }
}

impl<L: Lane, const N: usize> AddAssign for FourierSpectrum<L, N> {
    #[inline]
    fn add_assign(&mut self, rhs: Self) {
        for (a, b) in self.coeffs.iter_mut().zip(rhs.coeffs) {
            *a += b;
        }
    }
}

impl<L: Lane, const N: usize> Sub for FourierSpectrum<L, N> {
    type Output = Self;
    #[inline]
    fn sub(self, rhs: Self) -> Self {
        Self::from_coeffs(core::array::from_fn(|j| self.coeffs[j] - rhs.coeffs[j]))
    }
}

/// `spectrum * spectrum` is the truncated product.
impl<L: Lane, const N: usize> Mul for FourierSpectrum<L, N> {
    type Output = Self;
    #[inline]
    fn mul(self, rhs: Self) -> Self {
        self.product(&rhs)
    }
}

impl<const N: usize> FourierSpectrum<f64, N> {
    /// Rounds every coefficient to the lane type `L` (the same in each lane).
    pub fn to_lanes<L: Lane>(&self) -> FourierSpectrum<L, N> {
        FourierSpectrum::splat(self)
    }
}

/// Straight-line truncated products for the coefficient counts the tracer
/// uses. `macro_rules` expands every `(k, p)` term with literal indices, so
/// the code has no loop, no index arithmetic at run time and no bounds check,
/// and LLVM schedules the `N²` FMAs and the term-pair additions freely.
/// Several times faster than the loops, whose inner trip counts LLVM does
/// not fully unroll, so their accumulators stay in memory. Blocking the
/// rows of `k` inside one function gains nothing: LLVM reorders the
/// straight-line code anyway. At `N = 16` the straight line needs the
/// 16 accumulators and 136 distinct sums `d_{|k−p|} + d_{k+p}` at once,
/// and spills (184 stores of a 2 KB frame per call on AVX2's 16
/// registers); its speed then depends on where the caller's stack lies
/// (up to 1.8× in a renderer, same code). So `N = 16` computes its rows
/// `0‥8` and `8‥16` in two functions that are not inlined, which LLVM
/// cannot interleave (47 spill stores in all): faster alone in a loop
/// (`cargo bench -p spectral-core`) and inside the renderer, and much
/// less at the mercy of its stack. Figures in the workspace's
/// `docs/performance.md`.
mod unrolled {
    use crate::lane::Lane;

    /// Adds, for each `p` in the first list and each `k` in the second,
    /// `c_p e_{kp}` to `h[k − off]`, where `e_{kp} = d_{|k−p|} + d_{k+p}` (Toeplitz
    /// plus Hankel term) for `p ≥ 1`, `k + p < N`, else `d_{|k−p|}`. The
    /// `N²` multiply-adds take the products; the additions of `e`, formed
    /// once for `(k, p)` and `(p, k)` alike (`e` is symmetric, the compiler
    /// merges the equal sums), run beside them (on cores with separate add
    /// and multiply-add units, such as AMD Zen, they cost no multiply-add
    /// slot; a multiply-add per Hankel term would cost `N(N − 1)/2` more).
    /// `off` is the first row `k` that `h` holds (0 but for `N = 16`'s
    /// halves).
    macro_rules! product_terms {
        ($off:literal, $h:ident, $c:ident, $d:ident, [$($p:literal)*], $ks:tt) => {
            $( product_terms!(@row $off, $h, $c, $d, $p, $ks); )*
        };
        (@row $off:literal, $h:ident, $c:ident, $d:ident, $p:literal, [$($k:literal)*]) => {
            $(
                let toeplitz = $d[usize::abs_diff($k, $p)];
                let e = match $d.get($k + $p) {
                    Some(&hankel) if $p != 0 => toeplitz + hankel,
                    _ => toeplitz,
                };
                $h[$k - $off] = $c[$p].mul_add(e, $h[$k - $off]);
            )*
        };
    }

    #[inline(always)]
    fn product_4<L: Lane>(c: &[L; 4], d: &[L; 4], h: &mut [L; 4]) {
        product_terms!(0, h, c, d, [0 1 2 3], [0 1 2 3]);
    }

    #[inline(always)]
    fn product_8<L: Lane>(c: &[L; 8], d: &[L; 8], h: &mut [L; 8]) {
        product_terms!(0, h, c, d, [0 1 2 3 4 5 6 7], [0 1 2 3 4 5 6 7]);
    }

    #[inline(always)]
    fn product_12<L: Lane>(c: &[L; 12], d: &[L; 12], h: &mut [L; 12]) {
        product_terms!(0, h, c, d, [0 1 2 3 4 5 6 7 8 9 10 11], [0 1 2 3 4 5 6 7 8 9 10 11]);
    }

    /// A function, not inlined, for rows `off ..` (the second list) of
    /// the product at `N = 16` (module docs: why apart), accumulated in
    /// registers and stored once.
    macro_rules! product_16_rows {
        ($name:ident, $off:literal, $ks:tt) => {
            #[inline(never)]
            fn $name<L: Lane>(c: &[L; 16], d: &[L; 16], out: &mut [L; 8]) {
                let mut h = [L::splat(0.0); 8];
                product_terms!($off, h, c, d, [0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15], $ks);
                *out = h;
            }
        };
    }

    product_16_rows!(product_16_low, 0, [0 1 2 3 4 5 6 7]);
    product_16_rows!(product_16_high, 8, [8 9 10 11 12 13 14 15]);

    #[inline(always)]
    fn product_16<L: Lane>(c: &[L; 16], d: &[L; 16], h: &mut [L; 16]) {
        let (low, high) = h.split_at_mut(8);
        if let (Ok(low), Ok(high)) = (low.try_into(), high.try_into()) {
            product_16_low(c, d, low);
            product_16_high(c, d, high);
        }
    }

    /// The unrolled product into `h` (zero on entry) if `N` has a codelet;
    /// `false` (and `h` untouched) if not.
    #[inline(always)]
    pub(super) fn product<L: Lane, const N: usize>(c: &[L; N], d: &[L; N], h: &mut [L; N]) -> bool {
        macro_rules! codelet {
            ($codelet:ident) => {
                match (c[..].try_into(), d[..].try_into(), (&mut h[..]).try_into()) {
                    (Ok(c), Ok(d), Ok(h)) => {
                        $codelet(c, d, h);
                        true
                    }
                    _ => false,
                }
            };
        }
        match N {
            4 => codelet!(product_4),
            8 => codelet!(product_8),
            12 => codelet!(product_12),
            16 => codelet!(product_16),
            _ => false,
        }
    }
}

/// Accumulates the exact projection of a continuous polyline, one segment
/// at a time (module docs).
pub(crate) struct PolylineProjector<const N: usize> {
    range: SpectralRange,
    sums: [f64; N],
    previous: Option<(f64, f64)>,
    first: Option<(f64, f64)>,
}

impl<const N: usize> PolylineProjector<N> {
    pub(crate) fn new(range: SpectralRange) -> Self {
        Self {
            range,
            sums: [0.0; N],
            previous: None,
            first: None,
        }
    }

    /// Adds the next vertex `(λ, g)`; vertices must come in increasing `λ`.
    pub(crate) fn push(&mut self, lambda_nm: f64, value: f64) {
        match self.previous {
            None => self.first = Some((lambda_nm, value)),
            Some((a_nm, a_value)) => {
                debug_assert!(lambda_nm > a_nm, "polyline vertices must increase");
                self.segment(a_nm, a_value, lambda_nm, value);
            }
        }
        self.previous = Some((lambda_nm, value));
    }

    /// Adds the segment `[a, b]` clipped to the range.
    fn segment(&mut self, a_nm: f64, a_value: f64, b_nm: f64, b_value: f64) {
        let (lo, hi) = (self.range.min_nm(), self.range.max_nm());
        if b_nm <= lo || a_nm >= hi {
            return;
        }
        let slope_per_nm = (b_value - a_value) / (b_nm - a_nm);
        let (a_nm, a_value) = if a_nm < lo {
            (lo, a_value + slope_per_nm * (lo - a_nm))
        } else {
            (a_nm, a_value)
        };
        let (b_nm, b_value) = if b_nm > hi {
            (hi, a_value + slope_per_nm * (hi - a_nm))
        } else {
            (b_nm, b_value)
        };
        let phi_a = self.range.phase(a_nm);
        let phi_b = self.range.phase(b_nm);
        let half_width = 0.5 * (phi_b - phi_a);
        if half_width <= 0.0 {
            return;
        }
        self.sums[0] += (a_value + b_value) * half_width;
        let delta = b_value - a_value;
        if delta == 0.0 || N == 1 {
            return;
        }
        let mid = 0.5 * (phi_a + phi_b);
        // sin(j·mid) and sin(j·h), cos(j·h) by rotation recurrences.
        let (s1_mid, c1_mid) = (libm::sin(mid), libm::cos(mid));
        let (s1_h, c1_h) = (libm::sin(half_width), libm::cos(half_width));
        let (mut s_mid, mut c_mid) = (s1_mid, c1_mid);
        let (mut s_h, mut c_h) = (s1_h, c1_h);
        for (j, sum) in self.sums.iter_mut().enumerate().skip(1) {
            let jh = j as f64 * half_width;
            let sinc = if jh < 1e-4 {
                1.0 - jh * jh / 6.0
            } else {
                s_h / jh
            };
            *sum -= delta / j as f64 * s_mid * sinc;
            let next_s_mid = s_mid * c1_mid + c_mid * s1_mid;
            c_mid = c_mid * c1_mid - s_mid * s1_mid;
            s_mid = next_s_mid;
            let next_s_h = s_h * c1_h + c_h * s1_h;
            c_h = c_h * c1_h - s_h * s1_h;
            s_h = next_s_h;
        }
    }

    /// Closes the polyline with the flat extensions and returns `c`.
    /// An empty polyline projects to zero.
    pub(crate) fn finish(mut self) -> FourierSpectrum<f64, N> {
        let (lo, hi) = (self.range.min_nm(), self.range.max_nm());
        if let (Some((first_nm, first_value)), Some((last_nm, last_value))) =
            (self.first, self.previous)
        {
            if first_nm > lo {
                self.segment(lo, first_value, first_nm, first_value);
            }
            if last_nm < hi {
                self.segment(last_nm, last_value, hi, last_value);
            }
        }
        FourierSpectrum::from_coeffs(self.sums.map(|s| s / PI))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn range() -> SpectralRange {
        SpectralRange::VISIBLE
    }

    fn project<const N: usize>(points: &[(f64, f64)]) -> FourierSpectrum<f64, N> {
        let mut p = PolylineProjector::<N>::new(range());
        for &(l, v) in points {
            p.push(l, v);
        }
        p.finish()
    }

    #[test]
    fn ramp_has_the_analytic_coefficients() {
        // g(φ) = φ + π on [−π, 0]: c_0 = π/2, c_j = (1 − (−1)^j)/(π j²).
        let r = range();
        let c = project::<6>(&[(r.min_nm(), 0.0), (r.max_nm(), PI)]);
        assert!((c.coeffs[0] - PI / 2.0).abs() < 1e-14);
        for j in 1..6 {
            let jf = j as f64;
            let expected = (1.0 - if j % 2 == 0 { 1.0 } else { -1.0 }) / (PI * jf * jf);
            assert!((c.coeffs[j] - expected).abs() < 1e-14, "j = {j}");
        }
    }

    #[test]
    fn constant_and_flat_extension() {
        // One sample: flat everywhere; data far outside the range: clipped.
        let c = project::<8>(&[(500.0, 2.5)]);
        assert!((c.coeffs[0] - 2.5).abs() < 1e-15);
        assert!(c.coeffs[1..].iter().all(|v| v.abs() < 1e-15));
        let c = project::<4>(&[(100.0, 1.0), (200.0, 1.0), (1000.0, 1.0)]);
        assert!((c.coeffs[0] - 1.0).abs() < 1e-14);
        assert!(c.coeffs[1..].iter().all(|v| v.abs() < 1e-14));
        let empty = PolylineProjector::<4>::new(range()).finish();
        assert_eq!(empty, FourierSpectrum::zero());
    }

    #[test]
    fn eval_reconstructs_a_trigonometric_polynomial() {
        let c = FourierSpectrum::<f64, 5>::from_coeffs([1.0, 0.5, -0.25, 0.125, 0.0625]);
        let r = range();
        for lambda_nm in [360.0, 401.3, 555.0, 700.0, 830.0] {
            let phi = r.phase(lambda_nm);
            let direct: f64 = c.coeffs[0]
                + 2.0
                    * (1..5)
                        .map(|j| c.coeffs[j] * libm::cos(j as f64 * phi))
                        .sum::<f64>();
            assert!((c.eval(&FourierBasis::new(r), lambda_nm) - direct).abs() < 1e-13);
        }
    }

    #[test]
    fn product_with_constant_scales_and_parseval_holds() {
        let a = FourierSpectrum::<f64, 6>::from_coeffs([0.7, 0.1, -0.2, 0.05, 0.3, -0.01]);
        let two = FourierSpectrum::constant(2.0);
        let p = a.product(&two);
        for j in 0..6 {
            assert!((p.coeffs[j] - 2.0 * a.coeffs[j]).abs() < 1e-15);
        }
        let b = FourierSpectrum::<f64, 6>::from_coeffs([0.2, -0.3, 0.1, 0.4, 0.0, 0.2]);
        assert!((a.product(&b).coeffs[0] - a.product_mean(&b)).abs() < 1e-15);
        // Commutativity.
        let (ab, ba) = (a.product(&b), b.product(&a));
        for j in 0..6 {
            assert!((ab.coeffs[j] - ba.coeffs[j]).abs() < 1e-15);
        }
    }

    fn unrolled_matches_loops<const N: usize>() {
        let a = FourierSpectrum::<f64, N>::from_coeffs(core::array::from_fn(|j| {
            libm::sin(j as f64 * 1.3 + 0.2)
        }));
        let b = FourierSpectrum::<f64, N>::from_coeffs(core::array::from_fn(|j| {
            libm::cos(j as f64 * 0.7 - 0.5) / (1.0 + j as f64)
        }));
        let (fast, slow) = (a.product(&b), a.product_loops(&b));
        let mut h = [0.0; N];
        assert!(unrolled::product(&a.coeffs, &b.coeffs, &mut h));
        assert_eq!(h, fast.coeffs);
        for j in 0..N {
            assert!(
                (fast.coeffs[j] - slow.coeffs[j]).abs() < 1e-14,
                "N = {N}, j = {j}"
            );
        }
    }

    #[test]
    fn every_codelet_matches_the_loops() {
        unrolled_matches_loops::<4>();
        unrolled_matches_loops::<8>();
        unrolled_matches_loops::<12>();
        unrolled_matches_loops::<16>();
        let c = [1.0f64; 5];
        assert!(!unrolled::product(&c, &c, &mut [0.0; 5]));
    }

    #[test]
    fn lerp_and_ops() {
        let a = FourierSpectrum::<f64, 3>::from_coeffs([1.0, 2.0, 3.0]);
        let b = FourierSpectrum::<f64, 3>::from_coeffs([3.0, 2.0, 1.0]);
        assert_eq!(a.lerp(&b, 0.5).coeffs, [2.0, 2.0, 2.0]);
        assert_eq!((a + b).coeffs, [4.0, 4.0, 4.0]);
        assert_eq!((a - b).coeffs, [-2.0, 0.0, 2.0]);
        assert_eq!(a.scale(2.0).coeffs, [2.0, 4.0, 6.0]);
        let mut c = a;
        c += b;
        assert_eq!(c, a + b);
        assert_eq!((a * b), a.product(&b));
    }
}
