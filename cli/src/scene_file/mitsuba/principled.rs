//! Mitsuba 3.9.1's `principled` BSDF (src/bsdfs/principled.cpp), the
//! material Blender's Principled BSDF exports to, as `simd_tracer`'s
//! `Principled` (formulas in its module docs).
//!
//! | parameter | default | here |
//! | --- | --- | --- |
//! | `base_color` | 0.5 | a spectrum or a bitmap |
//! | `roughness` | 0.5 | a number in [0, 1] or a grey bitmap |
//! | `metallic`, `spec_trans`, `spec_tint`, `sheen`, `sheen_tint`, `clearcoat`, `clearcoat_gloss`, `flatness` | 0 | the same |
//! | `eta` or `specular` (not both) | `specular` 0.5: `η = 2/(1 − √(0.08 specular)) − 1` = 1.5 | numbers; with transmission an `eta` of 1 becomes 1.001 and a `specular` of 0 becomes 10⁻³, as in Mitsuba |
//! | `anisotropic` | 0 | the same; the specular lobes stretched along the surface's `∂p/∂u` |
//! | `main_specular_sampling_rate`, `clearcoat_sampling_rate`, `diffuse_reflectance_sampling_rate` | 1 | numbers ≥ 0 (they change the noise, not the image) |
//!
//! Mitsuba does not clamp these parameters; values outside [0, 1] are
//! refused here rather than rendered as an extrapolated model. A textured
//! `base_color` cannot carry transmission (its `√ρ` would be a texture of
//! its own) or a tint (its luminance varies per texel): both are refused
//! with a message.

use super::Importer;
use super::properties::Object;
use crate::error::CliError;
use crate::scene_file::source::Spot;
use simd_tracer::shading::material::{
    Bsdf, Fraction, PRINCIPLED_FRACTIONS, Principled, SamplingRates,
};

/// Mitsuba's default `specular` (`η` = 1.5).
const DEFAULT_SPECULAR: f64 = 0.5;
/// `specular` maps to `R₀ = 0.08 specular` (Burley's 0.5 ↔ 4 %); `R₀ < 1`
/// bounds it.
const SPECULAR_TO_R0: f64 = 0.08;
/// Mitsuba's stand-in for a `specular` of 0 with transmission.
const SPECULAR_WITH_TRANSMISSION: f64 = 1e-3;

impl<'e> Importer<'e, '_> {
    /// Mitsuba's `principled` (module docs).
    pub(super) fn principled(
        &mut self,
        object: &Object<'e>,
        spot: &Spot,
    ) -> Result<Bsdf, CliError> {
        let mut principled = Principled::new(self.albedo(object, "base_color")?);
        let mut fraction = |name: &str, default: f32| -> Result<Fraction, CliError> {
            if object.get(name).is_some() && self.texture_property(object, name)?.is_none() {
                let value = self.scalar(object, name, f64::from(default))?;
                if !(0.0..=1.0).contains(&value) {
                    return Err(object.error(format!("{name} {value}: must be in [0, 1]")));
                }
            }
            self.fraction(object, name, Some(f64::from(default)))
        };
        for (name, default) in PRINCIPLED_FRACTIONS {
            if let Some(slot) = principled.fraction_mut(name) {
                *slot = fraction(name, default)?;
            }
        }
        principled.eta = self.principled_eta(object, principled.transmits())?;
        principled.sampling_rates = SamplingRates {
            specular: self.sampling_rate(object, "main_specular_sampling_rate")?,
            clearcoat: self.sampling_rate(object, "clearcoat_sampling_rate")?,
            diffuse: self.sampling_rate(object, "diffuse_reflectance_sampling_rate")?,
        };
        self.cx.principled(spot, principled)
    }

    /// `eta`, or `η` from `specular` (module docs).
    fn principled_eta(&mut self, object: &Object<'e>, transmits: bool) -> Result<f32, CliError> {
        let eta = match (
            object.get("eta").is_some(),
            object.get("specular").is_some(),
        ) {
            (true, true) => return Err(object.error("give either `eta` or `specular`, not both")),
            (true, false) => {
                let eta = self.scalar(object, "eta", 1.0)?;
                if !(eta.is_finite() && eta > 0.0) {
                    return Err(object.error(format!("eta {eta}: must be a positive number")));
                }
                eta
            }
            (false, _) => {
                let mut specular = self.scalar(object, "specular", DEFAULT_SPECULAR)?;
                let limit = 1.0 / SPECULAR_TO_R0;
                if !(0.0..limit).contains(&specular) {
                    return Err(
                        object.error(format!("specular {specular}: must be in [0, {limit})"))
                    );
                }
                if transmits && specular == 0.0 {
                    specular = SPECULAR_WITH_TRANSMISSION;
                }
                2.0 / (1.0 - (SPECULAR_TO_R0 * specular).sqrt()) - 1.0
            }
        };
        Ok(eta as f32)
    }

    /// A lobe-choice rate: a number ≥ 0 (default 1).
    fn sampling_rate(&mut self, object: &Object<'e>, name: &str) -> Result<f32, CliError> {
        let rate = self.scalar(object, name, 1.0)?;
        if !(rate.is_finite() && rate >= 0.0) {
            return Err(object.error(format!("{name} {rate}: must be a number >= 0")));
        }
        Ok(rate as f32)
    }
}
