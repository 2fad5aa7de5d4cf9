//! Relighting: every emitter of a scene under construction given one
//! spectrum, each keeping its luminance (`fspec view`'s illuminant swap).
//!
//! An emitter's spectrum `E(λ)` becomes `S(λ) · Y_E / Y_S`, with
//! `Y = ∫ f(λ) ȳ(λ) dλ / ∫ ȳ(λ) dλ` over the scene's range (the
//! trapezoid rule at 1 nm of the built-in scenes, `builtin::luminance`).
//! Keeping `Y` keeps the scene's brightness, so what changes between two
//! illuminants is colour alone: a pair of surfaces that match under one
//! lamp and not under another (metamerism, the reason to render
//! spectrally) shows as a change of hue, not of exposure.
//!
//! Only references are rewritten: a spectrum an emitter shares with a
//! reflectance stays for the reflectance. Emitters are the materials with
//! an emission, point (and spot) and directional lights, and a constant environment;
//! an environment map's texels are RGB illuminants of their own and stay.

use crate::ids::SpectrumId;
use crate::scene::builtin::{luminance, scaled_source};
use crate::scene::{SceneBuilder, SceneError};
use crate::spectra::{SceneSpectrum, SpectrumSource};

impl SceneBuilder {
    /// Gives every emitter the spectrum `source` (named `name` in errors)
    /// at the emitter's own luminance (module docs); returns the number of
    /// distinct emission spectra replaced. Emitters of zero luminance keep
    /// theirs; `source` must have a positive luminance.
    pub fn relight(&mut self, name: &str, source: &SpectrumSource) -> Result<usize, SceneError> {
        let range = self.range;
        let shape = SceneSpectrum::new(source.clone(), range)
            .map_err(|e| SceneError::Spectrum(name.to_string(), e))?;
        let shape_luminance = luminance(&shape, &range);
        if !(shape_luminance.is_finite() && shape_luminance > 0.0) {
            return Err(SceneError::Spectrum(
                name.to_string(),
                spectral_core::SpectralError::InvalidParameter("luminance must be positive"),
            ));
        }
        let emitting: Vec<SpectrumId> = self
            .materials
            .iter()
            .filter_map(|m| m.emission)
            .chain(self.point_lights.iter().map(|l| l.intensity))
            .chain(self.directional_lights.iter().map(|l| l.irradiance))
            .chain(self.environment)
            .collect();
        let mut replaced: Vec<(SpectrumId, SpectrumId)> = Vec::new();
        for id in emitting {
            if replaced.iter().any(|(old, _)| *old == id) {
                continue;
            }
            let Some(old) = self.spectrum(id) else {
                continue;
            };
            let target = luminance(old, &range);
            if !(target.is_finite() && target > 0.0) {
                continue;
            }
            let scaled = scaled_source(source.clone(), target / shape_luminance, &range);
            let new = self.add_spectrum(name, scaled)?;
            replaced.push((id, new));
        }
        let swap = |id: &mut SpectrumId| {
            if let Some((_, new)) = replaced.iter().find(|(old, _)| old == id) {
                *id = *new;
            }
        };
        for material in &mut self.materials {
            if let Some(emission) = &mut material.emission {
                swap(emission);
            }
        }
        for light in &mut self.point_lights {
            swap(&mut light.intensity);
        }
        for light in &mut self.directional_lights {
            swap(&mut light.irradiance);
        }
        if let Some(environment) = &mut self.environment {
            swap(environment);
        }
        Ok(replaced.len())
    }
}

#[cfg(test)]
mod tests {
    use crate::scene::builtin::{SceneOptions, builtin_scene, luminance};
    use crate::spectra::SpectrumSource;
    use spectral_core::SpectralRange;
    use spectral_core::registry::Builtin;

    /// The emission spectra of the scene's emitting materials, in order.
    fn emissions(b: &crate::scene::SceneBuilder) -> Vec<crate::spectra::SceneSpectrum> {
        b.materials
            .iter()
            .filter_map(|m| m.emission)
            .filter_map(|id| b.spectrum(id).cloned())
            .collect()
    }

    #[test]
    fn lamps_under_led_b4_keep_their_luminance_and_take_its_shape()
    -> Result<(), Box<dyn std::error::Error>> {
        let range = SpectralRange::VISIBLE;
        let mut b = builtin_scene("lamps", range, &SceneOptions::default())?;
        let before = emissions(&b);
        assert_eq!(before.len(), 3, "the lamps scene has three lamps");
        let led = SpectrumSource::Builtin(Builtin::lookup("led-b4")?);
        assert_eq!(b.relight("led-b4", &led)?, 3);
        let after = emissions(&b);
        let reference = crate::spectra::SceneSpectrum::new(led, range)?;
        // Wavelengths where LED-B4 is well above zero (its blue peak and
        // phosphor hump), to compare shapes by ratio.
        let probes_nm = [450.0_f32, 500.0, 550.0, 600.0, 650.0];
        for (old, new) in before.iter().zip(&after) {
            let (y_old, y_new) = (luminance(old, &range), luminance(new, &range));
            assert!((y_new / y_old - 1.0).abs() < 1e-6, "{y_old} → {y_new}");
            let ratio = |s: &crate::spectra::SceneSpectrum, l: f32| s.value(l) / reference.value(l);
            let first = ratio(new, probes_nm[0]);
            for &l in &probes_nm {
                assert!((ratio(new, l) / first - 1.0).abs() < 1e-4, "{l} nm");
            }
        }
        // Negative control: the lamps' own spectra (FL11, LED-B4, A) are
        // not all LED-B4's shape.
        let differs = before.iter().any(|old| {
            let first = old.value(probes_nm[0]) / reference.value(probes_nm[0]);
            probes_nm
                .iter()
                .any(|&l| (old.value(l) / reference.value(l) / first - 1.0).abs() > 0.1)
        });
        assert!(differs);
        Ok(())
    }

    #[test]
    fn a_dark_illuminant_is_refused() -> Result<(), Box<dyn std::error::Error>> {
        let mut b = builtin_scene("cornell", SpectralRange::VISIBLE, &SceneOptions::default())?;
        assert!(b.relight("zero", &SpectrumSource::Constant(0.0)).is_err());
        Ok(())
    }
}
