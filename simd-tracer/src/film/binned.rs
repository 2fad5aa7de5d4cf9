//! [`BinnedFilm<C>`]: a pixel's radiance per wavelength bin, estimated from
//! sampled wavelengths, with its standard error.
//!
//! A path that carries `C` wavelengths `λ_i`, drawn with pdfs `p(λ_i)` (per
//! nm), contributes to bin `b` of width `Δ` (nm)
//!
//! ```text
//! X_b = (1/Δ) Σ_i 1[λ_i ∈ b] L(λ_i) / (C p(λ_i))
//! ```
//!
//! whose expectation is the bin's mean radiance `(1/Δ) ∫_b L dλ`, since each
//! `λ_i` is marginally distributed by `p` (hero rotations and stratified
//! draws too; a terminated secondary has `p = 0` and the hero's pdf divided
//! by `C`, pbrt's rule, so it is skipped and the hero carries the whole
//! estimate). This is the sampled film's estimator
//! (`SampledSpectrum::to_channels`) with the observer's curve replaced by
//! the bin's indicator. A pixel keeps `Σ X_b` and `Σ X_b²` over its paths,
//! so the mean and its standard error `sqrt((E[X²] − E[X]²)/(M − 1))` come
//! from the sums alone and merge by addition like the other films' states.
//!
//! Why: the viewer's spectrum of a pixel compares this model-free
//! estimate with the Fourier coefficients of the same pixel
//! (`fspec view`), for any transport; the XYZ sums beside the bins keep
//! the pixel's colour, as the [`XyzFilm`](super::XyzFilm) would resolve
//! it.

use super::{Film, FilmMode, all_finite};
use spectral_core::SpectralRange;
use spectral_core::color::Xyz;

/// Equal-width wavelength bins over a range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpectralBins {
    range: SpectralRange,
    count: usize,
}

impl SpectralBins {
    /// `count` bins of equal width over `range`, or why not.
    pub fn new(range: SpectralRange, count: usize) -> Result<Self, String> {
        let bins = Self { range, count };
        bins.validate()?;
        Ok(bins)
    }

    /// The invariants: a valid range and at least one bin.
    pub fn validate(&self) -> Result<(), String> {
        self.range.validate().map_err(|e| e.to_string())?;
        if self.count == 0 {
            return Err("at least one wavelength bin is needed".into());
        }
        Ok(())
    }

    /// Number of bins.
    pub fn count(&self) -> usize {
        self.count
    }

    /// Width of every bin, nm.
    pub fn width_nm(&self) -> f64 {
        self.range.width_nm() / self.count as f64
    }

    /// Centre of bin `index`, nm.
    pub fn centre_nm(&self, index: usize) -> f64 {
        self.range.min_nm() + (index as f64 + 0.5) * self.width_nm()
    }

    /// The bin holding `lambda_nm` (the range's upper end in the last
    /// bin), `None` outside the range.
    pub fn index(&self, lambda_nm: f64) -> Option<usize> {
        if !self.range.contains(lambda_nm) {
            return None;
        }
        let at = ((lambda_nm - self.range.min_nm()) / self.width_nm()).floor();
        Some((at.max(0.0) as usize).min(self.count - 1))
    }
}

/// One path's sample: its XYZ estimate (the sampled film's), and per
/// wavelength the wavelength and `L(λ)/(C p(λ))` (0 where `p = 0`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BinnedSample<const C: usize> {
    /// The XYZ estimate `(1/C) Σ L x̄/p / ∫ȳ`.
    pub xyz: [f32; 3],
    /// The path's wavelengths as the camera sees them, nm.
    pub lambda_nm: [f32; C],
    /// `L(λ_i) / (C p(λ_i))`, radiance per nm of wavelength, 0 where the
    /// pdf is 0.
    pub weight: [f32; C],
}

/// Radiance per wavelength bin (module docs): its bins, and `C`, the
/// wavelengths per path of its samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BinnedFilm<const C: usize> {
    bins: SpectralBins,
}

/// A binned pixel's sums: `Σ X_b` (bins), `Σ X_b²` (bins), XYZ sums, path
/// count, in that order (one `Vec`, the pixel's state as it is).
#[derive(Debug, Clone, PartialEq)]
pub struct BinnedPixel {
    sums: Vec<f64>,
}

/// What a binned pixel estimates: per bin the mean radiance and its
/// standard error, the XYZ and the number of paths.
#[derive(Debug, Clone, PartialEq)]
pub struct BinnedEstimate {
    /// Mean radiance over each bin.
    pub radiance: Vec<f64>,
    /// Standard error of each bin's mean (0 with fewer than two paths).
    pub std_error: Vec<f64>,
    /// Paths summed.
    pub paths: f64,
}

/// XYZ sums and the count after the bins' sums and squares.
const TRAILING_SUMS: usize = 4;

impl<const C: usize> BinnedFilm<C> {
    /// A film over `bins`.
    pub fn new(bins: SpectralBins) -> Result<Self, String> {
        bins.validate()?;
        Ok(Self { bins })
    }

    /// Its bins.
    pub fn bins(&self) -> &SpectralBins {
        &self.bins
    }

    /// The estimate of a pixel's state (as [`Film::save_state`] writes it
    /// and a kept `FilmState` holds it), or `None` for a state of another
    /// length.
    pub fn estimate(&self, state: &[f64]) -> Option<BinnedEstimate> {
        let n = self.bins.count;
        if state.len() != 2 * n + TRAILING_SUMS {
            return None;
        }
        let paths = state[2 * n + TRAILING_SUMS - 1];
        let (sums, squares) = state[..2 * n].split_at(n);
        let mean = |s: f64| if paths > 0.0 { s / paths } else { 0.0 };
        let radiance: Vec<f64> = sums.iter().map(|&s| mean(s)).collect();
        let std_error = radiance
            .iter()
            .zip(squares)
            .map(|(&m, &q)| {
                if paths > 1.0 {
                    ((mean(q) - m * m).max(0.0) / (paths - 1.0)).sqrt()
                } else {
                    0.0
                }
            })
            .collect();
        Some(BinnedEstimate {
            radiance,
            std_error,
            paths,
        })
    }

    /// The bins a sample adds to and how much (`X_b`, module docs), at
    /// most `C` of them, each bin once.
    fn contributions(&self, sample: &BinnedSample<C>) -> ([usize; C], [f64; C], usize) {
        let mut bins = [0usize; C];
        let mut values = [0.0f64; C];
        let mut used = 0;
        let per_nm = 1.0 / self.bins.width_nm();
        for (&lambda_nm, &weight) in sample.lambda_nm.iter().zip(&sample.weight) {
            let Some(bin) = self.bins.index(f64::from(lambda_nm)) else {
                continue;
            };
            let x = f64::from(weight) * per_nm;
            match bins[..used].iter().position(|&b| b == bin) {
                Some(at) => values[at] += x,
                None => {
                    bins[used] = bin;
                    values[used] = x;
                    used += 1;
                }
            }
        }
        (bins, values, used)
    }
}

impl<const C: usize> Film for BinnedFilm<C> {
    type Sample = BinnedSample<C>;
    type Pixel = BinnedPixel;
    type PassShared = ();

    fn empty_pixel(&self) -> Self::Pixel {
        BinnedPixel {
            sums: vec![0.0; 2 * self.bins.count + TRAILING_SUMS],
        }
    }

    fn sample_is_finite(sample: &Self::Sample) -> bool {
        all_finite(&sample.xyz) & all_finite(&sample.lambda_nm) & all_finite(&sample.weight)
    }

    fn accumulate(&self, pixel: &mut Self::Pixel, sample: &Self::Sample) {
        self.accumulate_weighted(pixel, sample, 1.0);
    }

    fn accumulate_weighted(&self, pixel: &mut Self::Pixel, sample: &Self::Sample, weight: f32) {
        let weight = f64::from(weight);
        let n = self.bins.count;
        let (bins, values, used) = self.contributions(sample);
        for (&bin, &x) in bins.iter().zip(&values).take(used) {
            pixel.sums[bin] += weight * x;
            pixel.sums[n + bin] += weight * x * x;
        }
        let tail = &mut pixel.sums[2 * n..];
        for (acc, &v) in tail.iter_mut().zip(&sample.xyz) {
            *acc += weight * f64::from(v);
        }
        tail[TRAILING_SUMS - 1] += weight;
    }

    fn add_pixel(&self, into: &mut Self::Pixel, from: &Self::Pixel) {
        for (acc, &v) in into.sums.iter_mut().zip(&from.sums) {
            *acc += v;
        }
    }

    fn resolve(&self, pixel: &Self::Pixel) -> Xyz {
        let tail = &pixel.sums[2 * self.bins.count..];
        let count = tail[TRAILING_SUMS - 1];
        if count == 0.0 {
            return Xyz::default();
        }
        Xyz::from_array([tail[0], tail[1], tail[2]].map(|v| v / count))
    }

    fn state_len(&self) -> Option<usize> {
        Some(2 * self.bins.count + TRAILING_SUMS)
    }

    fn save_state(&self, pixel: &Self::Pixel, out: &mut [f64]) {
        for (slot, &value) in out.iter_mut().zip(&pixel.sums) {
            *slot = value;
        }
    }

    fn load_state(&self, values: &[f64], mode: FilmMode, passes: f64) -> Option<Self::Pixel> {
        let count = *values.last()?;
        (values.len() == 2 * self.bins.count + TRAILING_SUMS
            && values.iter().all(|v| v.is_finite())
            && mode.is_weight_sum(count, passes))
        .then(|| BinnedPixel {
            sums: values.to_vec(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn film() -> BinnedFilm<2> {
        let Ok(bins) = SpectralBins::new(SpectralRange::VISIBLE, 47) else {
            panic!("bins");
        };
        let Ok(film) = BinnedFilm::new(bins) else {
            panic!("film");
        };
        film
    }

    #[test]
    fn bins_cover_the_range_and_nothing_else() {
        let bins = *film().bins();
        assert_eq!(bins.width_nm(), 10.0);
        assert_eq!(bins.index(360.0), Some(0));
        assert_eq!(bins.index(369.999), Some(0));
        assert_eq!(bins.index(370.0), Some(1));
        assert_eq!(bins.index(830.0), Some(46));
        assert_eq!(bins.index(359.9), None);
        assert_eq!(bins.index(f64::NAN), None);
        assert_eq!(bins.centre_nm(0), 365.0);
        assert!(SpectralBins::new(SpectralRange::VISIBLE, 0).is_err());
    }

    /// Two paths by hand: the sums, the means, the standard error, and a
    /// repeated bin counted once per path.
    #[test]
    fn a_pixel_is_the_mean_of_its_paths_per_bin() {
        let film = film();
        let mut pixel = film.empty_pixel();
        // Both wavelengths of the first path in bin 1 (370–380 nm).
        film.accumulate(
            &mut pixel,
            &BinnedSample {
                xyz: [1.0, 2.0, 3.0],
                lambda_nm: [371.0, 379.0],
                weight: [10.0, 30.0],
            },
        );
        film.accumulate(
            &mut pixel,
            &BinnedSample {
                xyz: [3.0, 2.0, 1.0],
                lambda_nm: [375.0, 800.0],
                weight: [20.0, 0.0],
            },
        );
        let Some(n) = film.state_len() else {
            panic!("a state");
        };
        let mut state = vec![0.0; n];
        film.save_state(&pixel, &mut state);
        let Some(estimate) = film.estimate(&state) else {
            panic!("an estimate");
        };
        // X_1 = 4 (40/10 nm) and 2 (20/10 nm): mean 3, sample variance 2,
        // standard error sqrt(2/2).
        assert_eq!(estimate.paths, 2.0);
        assert_eq!(estimate.radiance[1], 3.0);
        assert!((estimate.std_error[1] - 1.0).abs() < 1e-12);
        assert_eq!(estimate.radiance[0], 0.0);
        assert_eq!(film.resolve(&pixel).to_array(), [2.0, 2.0, 2.0]);
        let Some(loaded) = film.load_state(&state, FilmMode::Sample, 2.0) else {
            panic!("the state loads back");
        };
        assert_eq!(loaded, pixel);
        assert!(film.load_state(&state, FilmMode::Sample, 1.0).is_none());
        assert!(
            film.load_state(&state[1..], FilmMode::Sample, 2.0)
                .is_none()
        );
        assert!(film.estimate(&state[1..]).is_none());
    }
}
