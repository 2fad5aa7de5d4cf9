//! `[spectra]` and spectrum references: a spectrum table (one source key,
//! optionally `scale`) read into a [`SpectrumSource`], and a reference (a
//! name or an inline table) resolved through the construction.

use super::Loader;
use crate::error::CliError;
use crate::scene_file::construction::{builtin_error, tabulated_message};
use crate::scene_file::toml_reader::{Item, Table};
use crate::spectrum_file;
use simd_tracer::ids::SpectrumId;
use simd_tracer::spectra::{MAX_COEFFS, SpectrumSource};
use spectral_core::TabulatedSpectrum;
use spectral_core::registry::Builtin;
use toml::de::DeValue;

/// The keys that each give a spectrum's source; a table has exactly one.
const SOURCE_KEYS: [&str; 8] = [
    "builtin",
    "csv",
    "values",
    "blackbody_k",
    "rgb",
    "rgb_emission",
    "fourier",
    "constant",
];

impl Loader<'_> {
    /// Parses a spectrum table (`[spectra.x]` or inline) into its source.
    fn spectrum_source(&self, table: &Table<'_, '_>) -> Result<SpectrumSource, CliError> {
        let src = &self.src;
        let mut allowed = SOURCE_KEYS.to_vec();
        allowed.push("scale");
        table.allow(src, &allowed, "a spectrum")?;
        let sources: Vec<(&str, Item)> = table
            .entries()
            .into_iter()
            .filter(|(k, _)| SOURCE_KEYS.contains(k))
            .collect();
        let (key, item) = match sources.as_slice() {
            [] => {
                return Err(table.err(
                    src,
                    format!(
                        "a spectrum needs one source key: {}",
                        SOURCE_KEYS.join(", ")
                    ),
                ));
            }
            [(key, item)] => (*key, item),
            [(first, _), (second, item), ..] => {
                return Err(item.err(
                    src,
                    format!(
                        "`{first}` and `{second}` are both given; a spectrum has exactly one source key"
                    ),
                ));
            }
        };
        let source = match key {
            "builtin" => {
                let name = item.string(src)?;
                SpectrumSource::Builtin(
                    Builtin::lookup(name).map_err(|e| item.err(src, builtin_error(name, e)))?,
                )
            }
            "csv" => {
                let path = self.file(item)?;
                let data = spectrum_file::load_csv(&path).map_err(|e| item.err(src, e))?;
                SpectrumSource::Tabulated {
                    lambda_nm: data.lambda_nm,
                    values: data.values,
                }
            }
            "values" => {
                let pairs = item.array(src)?;
                if pairs.is_empty() {
                    return Err(
                        item.err(src, "must not be empty (give [wavelength_nm, value] pairs)")
                    );
                }
                let mut lambda = Vec::with_capacity(pairs.len());
                let mut values = Vec::with_capacity(pairs.len());
                for pair in &pairs {
                    let v = match pair.value.get_ref() {
                        DeValue::Array(a) if a.len() == 2 => pair.numbers(src, 2)?,
                        _ => return Err(pair.err(src, "expected a [wavelength_nm, value] pair")),
                    };
                    lambda.push(v[0]);
                    values.push(v[1]);
                }
                if let Err(e) = TabulatedSpectrum::new(&lambda, &values) {
                    let (index, message) = tabulated_message(&e, &lambda, &values);
                    let at = pairs.get(index).unwrap_or(item);
                    return Err(at.err(src, message));
                }
                SpectrumSource::Tabulated {
                    lambda_nm: lambda,
                    values,
                }
            }
            "blackbody_k" => {
                let t = item.number(src)?;
                if t <= 0.0 {
                    return Err(item.err(src, "must be a temperature > 0 (kelvin)"));
                }
                SpectrumSource::Blackbody {
                    temperature_k: t,
                    scale: 1.0,
                }
            }
            "rgb" => {
                let v = item.numbers(src, 3)?;
                if v.iter().any(|c| !(0.0..=1.0).contains(c)) {
                    return Err(item.err(
                        src,
                        "reflectance components must be in [0, 1] (use rgb_emission for light)",
                    ));
                }
                SpectrumSource::RgbReflectance([v[0], v[1], v[2]])
            }
            "rgb_emission" => {
                let v = item.numbers(src, 3)?;
                if v.iter().any(|c| *c < 0.0) {
                    return Err(item.err(src, "components must be >= 0"));
                }
                SpectrumSource::RgbIlluminant([v[0], v[1], v[2]])
            }
            "fourier" => {
                let items = item.array(src)?;
                if items.is_empty() || items.len() > MAX_COEFFS {
                    return Err(item.err(
                        src,
                        format!(
                            "needs 1 to {MAX_COEFFS} coefficients, found {}",
                            items.len()
                        ),
                    ));
                }
                SpectrumSource::Fourier(
                    items
                        .iter()
                        .map(|c| c.number(src))
                        .collect::<Result<_, _>>()?,
                )
            }
            _ => SpectrumSource::Constant(item.non_negative(src)?),
        };
        match table.get("scale") {
            Some(scale) => {
                let s = scale.non_negative(src)?;
                self.cx.scale(&table.spot(), source, s)
            }
            None => Ok(source),
        }
    }

    /// The `[spectra]` section.
    pub(super) fn spectra_section(&mut self, item: &Item<'_, '_>) -> Result<(), CliError> {
        let table = item.table(&self.src)?;
        for (name, entry) in table.entries() {
            let spectrum = entry.table(&self.src)?;
            let source = self.spectrum_source(&spectrum)?;
            self.cx.define_spectrum(name, entry.spot(), source)?;
        }
        Ok(())
    }

    /// A `<spectrum ref>` times `scale`.
    pub(super) fn spectrum_ref(
        &mut self,
        item: &Item<'_, '_>,
        scale: f64,
    ) -> Result<SpectrumId, CliError> {
        match item.value.get_ref() {
            DeValue::String(name) => {
                let name: &str = name.as_ref();
                match self.cx.spectrum_named(&item.spot(), name, scale)? {
                    Some(id) => Ok(id),
                    None => Err(item.err(
                        &self.src,
                        format!(
                            "unknown spectrum \"{name}\" (not in [spectra] and not a built-in)"
                        ),
                    )),
                }
            }
            DeValue::Table(_) => {
                let table = item.table(&self.src)?;
                let source = self.spectrum_source(&table)?;
                self.cx.add_scaled_spectrum(&item.spot(), source, scale)
            }
            _ => Err(item.wrong_type(
                &self.src,
                "a spectrum (a name or an inline table such as { rgb = [0.5, 0.5, 0.5] })",
            )),
        }
    }
}
