//! Spectra of a scene under construction: named ones, built-ins by name,
//! scaling, and the messages of invalid spectra.
//!
//! A front end parses a spectrum into a [`SpectrumSource`] and defines it
//! under a name ([`Construction::define_spectrum`]) or adds it where it is
//! used; references by name go through [`Construction::spectrum_named`],
//! which prefers a defined name to a built-in, adds each built-in once and
//! records which names were used (unused ones are warned about at the end).

use super::Construction;
use crate::error::CliError;
use crate::scene_file::source::Spot;
use simd_tracer::ids::SpectrumId;
use simd_tracer::scene::SceneError;
use simd_tracer::spectra::{SceneSpectrum, SpectrumSource};
use spectral_core::registry::{Builtin, BuiltinData};
use spectral_core::upsample::srgb_reflectance;
use spectral_core::{SpectralError, SpectralRange, Spectrum};

/// A spectrum defined under a name.
pub(super) struct NamedSpectrum {
    id: SpectrumId,
    source: SpectrumSource,
    at: Spot,
    used: bool,
}

/// `source` times `s` (module docs of `scene_file`, "Spectrum references").
fn scale_source(
    source: SpectrumSource,
    s: f64,
    range: &SpectralRange,
) -> Result<SpectrumSource, SpectralError> {
    let times = |values: &[f64]| values.iter().map(|v| v * s).collect::<Vec<f64>>();
    Ok(match source {
        SpectrumSource::Builtin(b) => match b.resolve() {
            BuiltinData::Tabulated(t) => SpectrumSource::Tabulated {
                lambda_nm: t.wavelengths_nm().to_vec(),
                values: times(t.values()),
            },
            BuiltinData::Blackbody(blackbody) => SpectrumSource::Blackbody {
                temperature_k: blackbody.temperature_k(),
                scale: s,
            },
        },
        SpectrumSource::Tabulated { lambda_nm, values } => SpectrumSource::Tabulated {
            lambda_nm,
            values: times(&values),
        },
        SpectrumSource::Constant(v) => SpectrumSource::Constant(v * s),
        SpectrumSource::Blackbody {
            temperature_k,
            scale,
        } => SpectrumSource::Blackbody {
            temperature_k,
            scale: scale * s,
        },
        SpectrumSource::RgbReflectance(rgb) => {
            let p = srgb_reflectance(rgb)?;
            let steps = range.width_nm().round().max(1.0) as usize;
            let lambda_nm: Vec<f64> = (0..=steps)
                .map(|i| range.min_nm() + range.width_nm() * i as f64 / steps as f64)
                .collect();
            let values = lambda_nm.iter().map(|&l| s * p.value(l)).collect();
            SpectrumSource::Tabulated { lambda_nm, values }
        }
        SpectrumSource::RgbUnbounded(rgb) => SpectrumSource::RgbUnbounded(rgb.map(|v| v * s)),
        SpectrumSource::RgbIlluminant(rgb) => SpectrumSource::RgbIlluminant(rgb.map(|v| v * s)),
        SpectrumSource::Fourier(c) => SpectrumSource::Fourier(times(&c)),
    })
}

/// The message of a tabulated-spectrum validation error, and the index of
/// the sample it is about.
pub(crate) fn tabulated_message(
    error: &SpectralError,
    lambda: &[f64],
    values: &[f64],
) -> (usize, String) {
    let at = |i: usize| lambda.get(i).copied().unwrap_or(f64::NAN);
    match *error {
        SpectralError::InvalidWavelength { index } => (
            index,
            format!("wavelength {} nm is not a positive number", at(index)),
        ),
        SpectralError::NotIncreasing { index } => (
            index,
            format!(
                "wavelength {} nm is not larger than the previous {} nm (wavelengths must be sorted and unique)",
                at(index),
                at(index.saturating_sub(1))
            ),
        ),
        SpectralError::NonFiniteValue { index } => (index, "value is NaN or infinite".into()),
        SpectralError::NegativeValue { index } => (
            index,
            format!(
                "value {} is negative (spectra must be non-negative)",
                values.get(index).copied().unwrap_or(f64::NAN)
            ),
        ),
        ref other => (0, other.to_string()),
    }
}

/// The message of a built-in name that [`Builtin::lookup`] refused.
pub(crate) fn builtin_error(name: &str, error: SpectralError) -> String {
    match error {
        SpectralError::InvalidTemperature => format!(
            "\"{name}\": a blackbody needs a finite positive temperature in kelvin, e.g. blackbody-6500"
        ),
        _ => format!("unknown built-in spectrum \"{name}\" (run `fspec spectrum --list`)"),
    }
}

impl Construction<'_> {
    /// Adds `source` under the name `at.key`; errors point at `at`.
    pub(crate) fn add_spectrum(
        &mut self,
        at: &Spot,
        source: SpectrumSource,
    ) -> Result<SpectrumId, CliError> {
        self.builder
            .add_spectrum(&at.key, source)
            .map_err(|e| match e {
                SceneError::Spectrum(_, e) => {
                    self.src.error_at(at, format!("invalid spectrum: {e}"))
                }
                other => self.src.error_at(at, other),
            })
    }

    /// `source` times `scale`, added; a scale of 1 adds `source` as it is.
    pub(crate) fn add_scaled_spectrum(
        &mut self,
        at: &Spot,
        source: SpectrumSource,
        scale: f64,
    ) -> Result<SpectrumId, CliError> {
        let source = if scale == 1.0 {
            source
        } else {
            self.scale(at, source, scale)?
        };
        self.add_spectrum(at, source)
    }

    /// `source` times `scale` (module docs of `scene_file`, "Spectrum
    /// references"), even for a scale of 1: built-in tables and RGB
    /// reflectances then become sampled tables, as a spectrum's own
    /// `scale` key makes them. Errors point at `at`.
    pub(crate) fn scale(
        &self,
        at: &Spot,
        source: SpectrumSource,
        scale: f64,
    ) -> Result<SpectrumSource, CliError> {
        scale_source(source, scale, &self.range)
            .map_err(|e| self.src.error_at(at, format!("invalid spectrum: {e}")))
    }

    /// Adds `source` under `name`, defined at `at`; a name that is also a
    /// built-in gets a warning (the definition shadows it).
    pub(crate) fn define_spectrum(
        &mut self,
        name: &str,
        at: Spot,
        source: SpectrumSource,
    ) -> Result<SpectrumId, CliError> {
        let id = self.add_spectrum(&at, source.clone())?;
        if Builtin::lookup(name).is_ok() {
            self.warn(
                &at,
                format!("shadows the built-in spectrum \"{name}\" in this file"),
            );
        }
        self.spectrum_order.push(name.to_string());
        self.spectra.insert(
            name.to_string(),
            NamedSpectrum {
                id,
                source,
                at,
                used: false,
            },
        );
        Ok(id)
    }

    /// The spectrum called `name`, referenced at `at`, times `scale`: a
    /// defined one (marked used), else a built-in (case-insensitive, added
    /// once). `Ok(None)` when it is neither: the front end says where names
    /// come from.
    pub(crate) fn spectrum_named(
        &mut self,
        at: &Spot,
        name: &str,
        scale: f64,
    ) -> Result<Option<SpectrumId>, CliError> {
        if let Some(named) = self.spectra.get_mut(name) {
            named.used = true;
            if scale == 1.0 {
                return Ok(Some(named.id));
            }
            let source = named.source.clone();
            return self.add_scaled_spectrum(at, source, scale).map(Some);
        }
        let builtin = match Builtin::lookup(name) {
            Ok(builtin) => builtin,
            Err(e @ SpectralError::InvalidTemperature) => {
                return Err(self.src.error_at(at, builtin_error(name, e)));
            }
            Err(_) => return Ok(None),
        };
        if scale == 1.0 {
            let cache_key = name.trim().to_ascii_lowercase();
            if let Some(&id) = self.builtins.get(&cache_key) {
                return Ok(Some(id));
            }
            let id = self.add_spectrum(at, SpectrumSource::Builtin(builtin))?;
            self.builtins.insert(cache_key, id);
            return Ok(Some(id));
        }
        self.add_scaled_spectrum(at, SpectrumSource::Builtin(builtin), scale)
            .map(Some)
    }

    /// The built-in spectrum `name` (a canonical lower-case name such as
    /// `gold-n`), added once.
    pub(crate) fn builtin_spectrum(
        &mut self,
        at: &Spot,
        name: &str,
    ) -> Result<SpectrumId, CliError> {
        if let Some(&id) = self.builtins.get(name) {
            return Ok(id);
        }
        let builtin =
            Builtin::lookup(name).map_err(|e| self.src.error_at(at, builtin_error(name, e)))?;
        let id = self.add_spectrum(at, SpectrumSource::Builtin(builtin))?;
        self.builtins.insert(name.to_string(), id);
        Ok(id)
    }

    /// The prepared spectrum `id` (for angular functions that take one).
    pub(crate) fn prepared(
        &self,
        at: &Spot,
        id: SpectrumId,
    ) -> Result<Box<SceneSpectrum>, CliError> {
        self.builder
            .spectrum(id)
            .cloned()
            .map(Box::new)
            .ok_or_else(|| self.src.error_at(at, "internal error: spectrum missing"))
    }

    /// Warns about defined spectra that nothing referred to.
    pub(super) fn warn_unused_spectra(&mut self) {
        for name in &self.spectrum_order {
            if let Some(s) = self.spectra.get(name).filter(|s| !s.used) {
                self.warnings
                    .push(self.src.warning_at(&s.at, "defined but never used"));
            }
        }
    }
}
