//! The wavelength density of `--sampling lights`: a mixture, in equal
//! parts, of the visible importance density and, for each emission
//! spectrum `E_l` of the scene, `E_l(λ) s(λ) / ∫ E_l s`, where
//! `s = x̄ + ȳ + z̄` is the sum of the observer's curves.
//!
//! **Why.** A sampled path's colour estimate is `x̄(λ) T(λ) L(λ) / p(λ)`.
//! Where the light `L` is a lamp whose power sits in lines (a tri-band
//! fluorescent tube, a laser, an LED's blue pump), the visible density
//! draws most wavelengths where the lamp is dark and weights its rare hits
//! by a large `1/p`: heavy-tailed colour noise. Light that reaches the
//! camera from emitter `l` has `L ∝ E_l` along its last segment, so a
//! density with a share `1/(K+1)` of `E_l s` bounds that light's
//! `L s / p` by `(K+1)` times its value under `E_l s` alone, for every
//! one of the `K` emitters at once (the one-sample mixture estimator of
//! Veach's thesis, §9.2.2, with the balance heuristic's weights folded
//! into `p`). The visible share keeps `p > 0` wherever the observer sees,
//! so the estimator stays unbiased for light that reflectances,
//! fluorescence or an environment map reshape.
//!
//! **Where it is used.** The sampled transport's wavelengths at the camera
//! and the hybrid transport's wavelengths at its split
//! ([`super::HybridTransport`]), where the path's remaining light comes
//! after a dispersive surface. It is the hybrid's default: the split is
//! where a path loses the Fourier transport's exact spectral integral, and
//! a scene's lamps are what make the sampled continuation noisy (measured
//! in `docs/results.md`).
//!
//! **Table.** [`EMISSION_DENSITY_BINS`] bins over the scene's range (under
//! 1 nm on 360–830 nm, the resolution of the dense spectra), each weight
//! the mean of the mixture at [`SUBSAMPLES_PER_BIN`] points in the bin.
//! The table is the density drawn from, so its own pdf is exact; the
//! sub-sampling only decides how well it follows the lamps.

use crate::scene::Scene;
use spectral_core::observer::Observer;
use spectral_core::sampling::{TabulatedDensity, VisibleDensity};

/// Bins of the table: 470 nm (360–830) / 512 = 0.92 nm, finer than the
/// 1 nm grid the scene's dense spectra are stored on.
pub const EMISSION_DENSITY_BINS: usize = 512;

/// Points at which each bin's weight is evaluated (midpoints of equal
/// sub-bins).
pub const SUBSAMPLES_PER_BIN: usize = 4;

/// The density of `--sampling lights` (module docs).
pub type EmissionDensity = TabulatedDensity<EMISSION_DENSITY_BINS>;

/// The lights density of `scene` seen by `observer`: the visible density
/// alone where the scene has no emission spectrum (an environment map's
/// texels only) or none the observer sees.
pub fn emission_density(scene: &Scene, observer: &Observer) -> Result<EmissionDensity, String> {
    let range = scene.range();
    let bin_nm = range.width_nm() / EMISSION_DENSITY_BINS as f64;
    let points = |k: usize| {
        (0..SUBSAMPLES_PER_BIN).map(move |j| {
            range.min_nm() + (k as f64 + (j as f64 + 0.5) / SUBSAMPLES_PER_BIN as f64) * bin_nm
        })
    };
    let visible = VisibleDensity::new(&range);
    let bin_mean = |f: &dyn Fn(f64) -> f64| -> [f64; EMISSION_DENSITY_BINS] {
        core::array::from_fn(|k| points(k).map(f).sum::<f64>() / SUBSAMPLES_PER_BIN as f64)
    };
    let normalised = |mut w: [f64; EMISSION_DENSITY_BINS]| {
        let total: f64 = w.iter().sum();
        (total > 0.0 && total.is_finite()).then(|| {
            w.iter_mut().for_each(|v| *v /= total);
            w
        })
    };
    let mut parts = vec![
        normalised(bin_mean(&|l| visible.pdf_per_nm(l)))
            .ok_or("the visible density is empty over the scene's range")?,
    ];
    for id in scene.emission_spectra() {
        let spectrum = scene
            .spectra()
            .get(id.0 as usize)
            .ok_or_else(|| format!("emission spectrum {id} is not among the scene's spectra"))?;
        let seen = bin_mean(&|l| {
            let value = f64::from(spectrum.value(l as f32)).max(0.0);
            value * observer.at(l).iter().sum::<f64>()
        });
        parts.extend(normalised(seen));
    }
    let share = 1.0 / parts.len() as f64;
    let weights: [f64; EMISSION_DENSITY_BINS] =
        core::array::from_fn(|k| parts.iter().map(|part| part[k] * share).sum());
    EmissionDensity::from_weights(&range, &weights)
        .map_err(|e| format!("the lights' wavelength density: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin::{SceneOptions, builtin_scene};
    use spectral_core::SpectralRange;

    /// The documented bound: for each emitter `l`, its normalised seen
    /// spectrum `E_l s / ∫ E_l s` is at most `K + 1` times the density
    /// (bin means, to the table's resolution), and at least the visible
    /// share `1/(K+1)` of the visible density is kept everywhere. The
    /// negative control: the visible density alone breaks the bound by far
    /// on the scene's line lamps.
    #[test]
    fn every_lamp_is_within_k_plus_one_of_the_density() -> Result<(), String> {
        let scene = builtin_scene("lamps", SpectralRange::VISIBLE, &SceneOptions::default())
            .map_err(|e| e.to_string())?
            .build()
            .map_err(|e| e.to_string())?;
        let observer = Observer::default();
        let density = emission_density(&scene, &observer)?;
        density.validate().map_err(|e| e.to_string())?;
        let emitters = scene.emission_spectra();
        assert!(emitters.len() >= 2, "{} emitters", emitters.len());
        let bound = (emitters.len() + 1) as f64;
        let range = scene.range();
        let bin_nm = range.width_nm() / EMISSION_DENSITY_BINS as f64;
        let visible = VisibleDensity::new(&range);
        let centre = |k: usize| range.min_nm() + (k as f64 + 0.5) * bin_nm;
        let mut visible_worst: f64 = 0.0;
        for id in emitters {
            let spectrum = &scene.spectra()[id.0 as usize];
            let seen =
                |l: f64| f64::from(spectrum.value(l as f32)) * observer.at(l).iter().sum::<f64>();
            let bin_seen: Vec<f64> = (0..EMISSION_DENSITY_BINS)
                .map(|k| {
                    (0..SUBSAMPLES_PER_BIN)
                        .map(|j| {
                            seen(
                                range.min_nm()
                                    + (k as f64 + (j as f64 + 0.5) / SUBSAMPLES_PER_BIN as f64)
                                        * bin_nm,
                            )
                        })
                        .sum::<f64>()
                        / SUBSAMPLES_PER_BIN as f64
                })
                .collect();
            let total: f64 = bin_seen.iter().sum::<f64>() * bin_nm;
            for (k, &v) in bin_seen.iter().enumerate() {
                let target = v / total;
                let p = density.pdf_per_nm(centre(k));
                assert!(target <= bound * p * (1.0 + 1e-9), "emitter {id} bin {k}");
                visible_worst = visible_worst.max(target / visible.pdf_per_nm(centre(k)));
            }
        }
        for k in 0..EMISSION_DENSITY_BINS {
            let l = centre(k);
            assert!(
                density.pdf_per_nm(l) >= 0.99 * visible.pdf_per_nm(l) / bound,
                "{l} nm"
            );
        }
        assert!(
            visible_worst > 1.5 * bound,
            "visible density's worst ratio {visible_worst} against {bound}"
        );
        Ok(())
    }
}
