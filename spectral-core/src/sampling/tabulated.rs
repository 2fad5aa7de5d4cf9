//! [`TabulatedDensity`]: a wavelength density that is constant on each of
//! `BINS` equal bins of a range, drawn by inverting its cumulative table.
//!
//! A renderer builds one from weights it chooses: pbrt-v4 and Mitsuba 3
//! draw wavelengths from a fixed visible density, which knows nothing of
//! the scene, so a lamp whose power sits in a few lines (a fluorescent
//! tube, an LED's blue pump, a laser) is sampled mostly where it is dark
//! and its rare hits are bright. A density that follows the scene's
//! emission (times the observer) puts the wavelengths where the light is.
//!
//! **Definition.** Over `[λ_min, λ_max)` split into `BINS` bins of width
//! `Δ = (λ_max − λ_min)/BINS`, weights `w_k ≥ 0` with `Σ w_k > 0` give
//! `P_k = w_k / Σ w`, `p(λ) = P_k / Δ` for `λ` in bin `k`, and the
//! cumulative `F_k = Σ_{j ≤ k} P_j`. Drawing `λ(u)`: the bin `k` with
//! `F_{k−1} ≤ u < F_k` (bins of zero weight are never chosen), then
//! `λ = λ_min + (k + (u − F_{k−1})/P_k) Δ`: the exact inverse of the
//! piecewise-linear cumulative, so `p` is the density of `λ(u)` for
//! uniform `u`. [`TabulatedDensity::sample_hero`] rotates `u` in that
//! space (`u_i = u_0 + i/C mod 1`), as `VisibleHero` does for the visible
//! density, so each `λ_i` has the marginal density `p`.
//!
//! **Numbers.** Weights are validated (finite, non-negative, positive sum)
//! and the table is kept in `f64`; `λ` is clamped into the bin it was drawn
//! in, so rounding never moves a wavelength into a bin of zero density.

use super::{SampledWavelengths, wrap_unit};
use crate::error::SpectralError;
use crate::range::SpectralRange;

/// A piecewise-constant wavelength density over `BINS` equal bins (module
/// docs).
#[derive(Debug, Clone, PartialEq)]
pub struct TabulatedDensity<const BINS: usize> {
    min_nm: f64,
    bin_nm: f64,
    /// `P_k`: the probability of bin `k`.
    mass: [f64; BINS],
    /// `F_k`: the probability of bins `0..=k` (the last is 1).
    cumulative: [f64; BINS],
}

impl<const BINS: usize> TabulatedDensity<BINS> {
    /// The density proportional to `weights` over `range`; `weights[k]`
    /// is bin `k`'s share.
    ///
    /// ```
    /// use spectral_core::SpectralRange;
    /// use spectral_core::sampling::TabulatedDensity;
    ///
    /// // 400–800 nm in four bins, the second holding three times the first.
    /// let range = SpectralRange::new(400.0, 800.0)?;
    /// let density = TabulatedDensity::<4>::from_weights(&range, &[1.0, 3.0, 0.0, 0.0])?;
    /// assert_eq!(density.pdf_per_nm(450.0), 0.25 / 100.0);
    /// let (lambda_nm, pdf) = density.sample(0.5);
    /// assert!((lambda_nm - (500.0 + 100.0 / 3.0)).abs() < 1e-9);
    /// assert_eq!(pdf, 0.75 / 100.0);
    /// assert_eq!(density.pdf_per_nm(700.0), 0.0);
    /// # Ok::<(), spectral_core::SpectralError>(())
    /// ```
    pub fn from_weights(
        range: &SpectralRange,
        weights: &[f64; BINS],
    ) -> Result<Self, SpectralError> {
        if BINS == 0 {
            return Err(SpectralError::Empty);
        }
        let mut total = 0.0;
        for (index, &w) in weights.iter().enumerate() {
            if !w.is_finite() {
                return Err(SpectralError::NonFiniteValue { index });
            }
            if w < 0.0 {
                return Err(SpectralError::NegativeValue { index });
            }
            total += w;
        }
        if !(total > 0.0 && total.is_finite()) {
            return Err(SpectralError::InvalidParameter(
                "density weights sum to zero",
            ));
        }
        let mass = weights.map(|w| w / total);
        let mut cumulative = [0.0; BINS];
        let mut sum = 0.0;
        for (f, p) in cumulative.iter_mut().zip(&mass) {
            sum += p;
            *f = sum;
        }
        // From the last bin of positive mass on the cumulative is 1 by
        // definition; set it so that rounding cannot send a u < 1 past
        // that bin into empty ones.
        let last = mass.iter().rposition(|&p| p > 0.0).unwrap_or(BINS - 1);
        for f in &mut cumulative[last..] {
            *f = 1.0;
        }
        let density = Self {
            min_nm: range.min_nm(),
            bin_nm: range.width_nm() / BINS as f64,
            mass,
            cumulative,
        };
        debug_assert!(density.validate().is_ok());
        Ok(density)
    }

    /// The range the density covers.
    pub fn range(&self) -> (f64, f64) {
        (self.min_nm, self.min_nm + self.bin_nm * BINS as f64)
    }

    /// The probability of bin `k` (0 outside the table).
    pub fn bin_mass(&self, k: usize) -> f64 {
        self.mass.get(k).copied().unwrap_or(0.0)
    }

    /// `λ(u)` and its density `p(λ)` for `u ∈ [0, 1)` (other values are
    /// wrapped into it).
    pub fn sample(&self, u: f64) -> (f64, f64) {
        let u = wrap_unit(u);
        // The first bin whose cumulative exceeds u: it has positive mass.
        let k = self.cumulative.partition_point(|&f| f <= u).min(BINS - 1);
        let below = if k == 0 { 0.0 } else { self.cumulative[k - 1] };
        let mass = self.mass[k];
        let within = if mass > 0.0 {
            ((u - below) / mass).clamp(0.0, 1.0)
        } else {
            0.5
        };
        let lo = self.min_nm + k as f64 * self.bin_nm;
        // Clamped inside bin k, so rounding cannot leave it.
        let lambda_nm = (lo + within * self.bin_nm).clamp(lo, next_below(lo + self.bin_nm));
        (lambda_nm, mass / self.bin_nm)
    }

    /// `p(λ)` per nm: 0 outside the range.
    pub fn pdf_per_nm(&self, lambda_nm: f64) -> f64 {
        let x = (lambda_nm - self.min_nm) / self.bin_nm;
        if !(x >= 0.0 && x < BINS as f64) {
            return 0.0;
        }
        self.mass[(x as usize).min(BINS - 1)] / self.bin_nm
    }

    /// `C` wavelengths by hero rotation in the density's cumulative space
    /// from one uniform number: each has the marginal density `p`.
    pub fn sample_hero<const C: usize>(&self, u: f32) -> SampledWavelengths<C> {
        let drawn: [(f64, f64); C] =
            core::array::from_fn(|i| self.sample(wrap_unit(f64::from(u)) + i as f64 / C as f64));
        SampledWavelengths::from_parts(
            drawn.map(|(lambda_nm, _)| lambda_nm as f32),
            drawn.map(|(_, pdf)| pdf as f32),
        )
    }

    /// Masses finite, non-negative and summing to 1, the cumulative their
    /// running sum ending at 1, the bin width positive.
    pub fn validate(&self) -> Result<(), SpectralError> {
        if !(self.bin_nm > 0.0 && self.bin_nm.is_finite() && self.min_nm.is_finite()) {
            return Err(SpectralError::InvalidRange);
        }
        let mut sum = 0.0;
        let mut previous = 0.0;
        for (index, (&p, &f)) in self.mass.iter().zip(&self.cumulative).enumerate() {
            if !p.is_finite() || p < 0.0 {
                return Err(SpectralError::NegativeValue { index });
            }
            sum += p;
            if f < previous || (f - sum).abs() > 1e-9 {
                return Err(SpectralError::NotIncreasing { index });
            }
            previous = f;
        }
        if self.cumulative.last() != Some(&1.0) {
            return Err(SpectralError::InvalidParameter(
                "density cumulative does not end at 1",
            ));
        }
        if (sum - 1.0).abs() > 1e-9 {
            return Err(SpectralError::InvalidParameter(
                "density masses do not sum to 1",
            ));
        }
        Ok(())
    }
}

/// The largest `f64` below `x` (for positive finite `x`).
fn next_below(x: f64) -> f64 {
    f64::from_bits(x.to_bits() - 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const BINS: usize = 16;

    fn range() -> SpectralRange {
        SpectralRange::VISIBLE
    }

    /// A lamp-like table: two lines and a weak floor, one empty bin.
    fn weights() -> [f64; BINS] {
        let mut w = [0.05; BINS];
        w[3] = 2.0;
        w[9] = 5.0;
        w[12] = 0.0;
        w
    }

    #[test]
    fn the_density_integrates_to_one_and_matches_the_weights() -> Result<(), SpectralError> {
        let density = TabulatedDensity::<BINS>::from_weights(&range(), &weights())?;
        density.validate()?;
        let total: f64 = weights().iter().sum();
        let (lo, hi) = density.range();
        let bin_nm = (hi - lo) / BINS as f64;
        let mut integral = 0.0;
        for (k, w) in weights().iter().enumerate() {
            let centre = lo + (k as f64 + 0.5) * bin_nm;
            let p = density.pdf_per_nm(centre);
            assert!((p * bin_nm - w / total).abs() < 1e-12, "bin {k}");
            integral += p * bin_nm;
        }
        assert!((integral - 1.0).abs() < 1e-12);
        assert_eq!(density.pdf_per_nm(lo - 1.0), 0.0);
        assert_eq!(density.pdf_per_nm(hi), 0.0);
        Ok(())
    }

    /// Stratified `u` put each bin's share of the draws in it (to one draw
    /// per bin boundary), never one in the empty bin, and each draw's pdf
    /// is the table's at its wavelength. The negative control: the counts
    /// of a uniform table are far from these weights.
    #[test]
    fn draws_follow_the_table() -> Result<(), SpectralError> {
        let density = TabulatedDensity::<BINS>::from_weights(&range(), &weights())?;
        let uniform = TabulatedDensity::<BINS>::from_weights(&range(), &[1.0; BINS])?;
        let draws = 100_000;
        let total: f64 = weights().iter().sum();
        let (lo, hi) = density.range();
        let bin_of = |l: f64| ((l - lo) / (hi - lo) * BINS as f64) as usize;
        let mut counts = [0usize; BINS];
        let mut uniform_counts = [0usize; BINS];
        for i in 0..draws {
            let u = (i as f64 + 0.5) / draws as f64;
            let (lambda_nm, pdf) = density.sample(u);
            assert!((lo..hi).contains(&lambda_nm));
            assert_eq!(pdf, density.pdf_per_nm(lambda_nm));
            counts[bin_of(lambda_nm)] += 1;
            uniform_counts[bin_of(uniform.sample(u).0)] += 1;
        }
        assert_eq!(counts[12], 0);
        let mut uniform_far = false;
        for (k, w) in weights().iter().enumerate() {
            let expected = w / total * draws as f64;
            assert!((counts[k] as f64 - expected).abs() <= 1.0, "bin {k}");
            uniform_far |= (uniform_counts[k] as f64 - expected).abs() > 100.0;
        }
        assert!(uniform_far);
        Ok(())
    }

    /// Hero rotation: every rotated wavelength has the marginal density of
    /// the table (the mean of `1_{bin}(λ_i)` over a stratified `u_0` is the
    /// bin's mass for each `i`).
    #[test]
    fn hero_rotations_have_the_tables_marginals() -> Result<(), SpectralError> {
        let density = TabulatedDensity::<BINS>::from_weights(&range(), &weights())?;
        let draws = 40_000;
        let (lo, hi) = density.range();
        let mut counts = [[0usize; BINS]; 4];
        for i in 0..draws {
            let u = ((i as f64 + 0.5) / draws as f64) as f32;
            let w = density.sample_hero::<4>(u);
            for (c, (&l, &p)) in w.lambda_nm().iter().zip(w.pdf_per_nm()).enumerate() {
                let l = f64::from(l);
                assert!(
                    (f64::from(p) - density.pdf_per_nm(l)).abs() < 1e-6 * density.pdf_per_nm(l)
                );
                counts[c][((l - lo) / (hi - lo) * BINS as f64) as usize] += 1;
            }
        }
        for rotation in &counts {
            for (k, &n) in rotation.iter().enumerate() {
                let expected = density.bin_mass(k) * draws as f64;
                assert!(
                    (n as f64 - expected).abs() <= 2.0,
                    "bin {k}: {n} vs {expected}"
                );
            }
        }
        Ok(())
    }

    #[test]
    fn bad_weights_are_refused() {
        let mut w = weights();
        w[2] = f64::NAN;
        assert_eq!(
            TabulatedDensity::<BINS>::from_weights(&range(), &w),
            Err(SpectralError::NonFiniteValue { index: 2 })
        );
        w[2] = -1.0;
        assert_eq!(
            TabulatedDensity::<BINS>::from_weights(&range(), &w),
            Err(SpectralError::NegativeValue { index: 2 })
        );
        assert!(TabulatedDensity::<BINS>::from_weights(&range(), &[0.0; BINS]).is_err());
        assert!(TabulatedDensity::<BINS>::from_weights(&range(), &[f64::MAX; BINS]).is_err());
    }

    #[test]
    fn validate_detects_a_corrupted_table() -> Result<(), SpectralError> {
        let mut density = TabulatedDensity::<BINS>::from_weights(&range(), &weights())?;
        density.mass[4] += 0.1;
        assert!(density.validate().is_err());
        Ok(())
    }

    proptest! {
        /// Any table: every draw lies in a bin of positive mass, inside the
        /// range, with the table's pdf there.
        #[test]
        fn draws_land_in_bins_of_positive_mass(
            raw in proptest::collection::vec(0.0f64..10.0, BINS),
            zeros in proptest::collection::vec(any::<bool>(), BINS),
            u in 0.0f64..1.0,
        ) {
            let mut w = [0.0; BINS];
            for k in 0..BINS {
                w[k] = if zeros[k] { 0.0 } else { raw[k] };
            }
            prop_assume!(w.iter().sum::<f64>() > 0.0);
            let density = TabulatedDensity::<BINS>::from_weights(&range(), &w).map_err(|e| TestCaseError::fail(std::format!("{e}")))?;
            let (lambda_nm, pdf) = density.sample(u);
            let (lo, hi) = density.range();
            prop_assert!(lambda_nm >= lo && lambda_nm < hi);
            prop_assert!(pdf > 0.0);
            prop_assert_eq!(pdf, density.pdf_per_nm(lambda_nm));
        }
    }
}
