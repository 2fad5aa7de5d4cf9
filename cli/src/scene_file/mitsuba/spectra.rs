//! Spectra in Mitsuba files, with the meaning that Mitsuba 3.9.1's spectral
//! variants give them where they are used.
//!
//! | given as | reflectance (`reflectance`, `specular_reflectance`, …) | emission (`radiance`, `intensity`, `irradiance`) | unbounded (`eta`, `k`) |
//! | --- | --- | --- | --- |
//! | `<rgb>` | sRGB reflectance, Jakob–Hanika upsampling | RGB illuminant: upsampled × D65 (`srgb_d65`) | upsampled unbounded |
//! | `<float>`, `<integer>`, absent (default `v`) | constant `v` | `v` × D65 normalised as Mitsuba's `d65` plugin (an RGB illuminant of grey `v`) | constant `v` |
//! | `<spectrum value="v">` | constant `v` | constant `v` (equal energy, **not** D65) | constant `v` |
//! | `<spectrum value="λ:v, …">` | linear between the samples, **zero outside them** | the same (no D65) | the same |
//! | `<spectrum filename="x.spd">` | the file's samples, as above | the same | the same |
//! | `<spectrum type="blackbody">` | — | Planck's law in W m⁻² sr⁻¹ nm⁻¹ (no normalisation, no scale) | — |
//!
//! Source: Mitsuba 3.9.1 `src/core/properties.cpp` (`get_texture_impl`),
//! checked against its renders. RGB values are clamped to [0, 1] by
//! Mitsuba's upsampling (`srgb_model_fetch`) even where they are unbounded
//! (an RGB conductor `k` of 3.9 is 1 there): the importer does the same,
//! with a warning, so that the file renders as in Mitsuba; an RGB
//! reflectance outside [0, 1] is an error, as in Mitsuba.
//!
//! Mitsuba's `.spd` files are lines of `wavelength value` (nm), `#`
//! comments. The "zero outside" rule is Mitsuba's `irregular` spectrum
//! (`eval` returns 0 outside `[λ_first, λ_last]`); it is kept by adding a
//! zero sample [`ZERO_EDGE_NM`] beyond each end that lies inside the
//! scene's range.
//!
//! The blackbody (`src/spectra/blackbody.cpp`):
//! `B(λ, T) = 2hc² / (λ⁵ (exp(hc / (λ k T)) − 1)) · 10⁻⁹` with `λ` in
//! metres (the `10⁻⁹` makes it per nanometre), CODATA 2014 constants as
//! Mitsuba uses them; it is tabulated every nanometre over the scene's
//! range.

use super::Importer;
use super::document::Element;
use super::properties::{Object, Property, Value, parse_number, parse_numbers};
use crate::error::CliError;
use crate::scene_file::source::read_text;
use simd_tracer::ids::SpectrumId;
use simd_tracer::spectra::SpectrumSource;
use spectral_core::SpectralRange;

/// Where a spectrum is used: what `<rgb>` and uniform values mean there.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SpectrumUse {
    /// A reflectance or transmittance in [0, 1].
    Reflectance,
    /// Emitted radiance, intensity or irradiance.
    Emission,
    /// An unbounded quantity (a complex index of refraction).
    Unbounded,
}

/// Distance of the added zero samples beyond a tabulated spectrum's ends, nm.
pub(crate) const ZERO_EDGE_NM: f64 = 1e-3;
/// Largest `.spd` file read, bytes (1 MiB: tens of thousands of samples).
const MAX_SPD_BYTES: u64 = 1 << 20;
/// Speed of light, m/s (Mitsuba 3.9.1 `blackbody.cpp`).
const SPEED_OF_LIGHT_M_PER_S: f64 = 2.997_924_58e8;
/// Planck's constant, J s (as Mitsuba 3.9.1 uses it).
const PLANCK_J_S: f64 = 6.626_070_04e-34;
/// Boltzmann's constant, J/K (as Mitsuba 3.9.1 uses it).
const BOLTZMANN_J_PER_K: f64 = 1.380_648_52e-23;
/// Metres per nanometre.
const M_PER_NM: f64 = 1e-9;

/// Planck's spectral radiance at `lambda_nm`, W m⁻² sr⁻¹ nm⁻¹.
pub(crate) fn planck_per_nm(lambda_nm: f64, temperature_k: f64) -> f64 {
    let lambda_m = lambda_nm * M_PER_NM;
    let c = SPEED_OF_LIGHT_M_PER_S;
    let exponent = PLANCK_J_S * c / (lambda_m * BOLTZMANN_J_PER_K * temperature_k);
    M_PER_NM * 2.0 * PLANCK_J_S * c * c / (lambda_m.powi(5) * exponent.exp_m1())
}

/// `λ:v` pairs as samples, checked later by the builder.
fn pairs(e: &Element, text: &str) -> Result<(Vec<f64>, Vec<f64>), CliError> {
    let mut lambda_nm = Vec::new();
    let mut values = Vec::new();
    for pair in text
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
    {
        let Some((l, v)) = pair.split_once(':') else {
            return Err(e.error(format!(
                "<spectrum> value \"{pair}\": expected wavelength:value pairs separated by commas"
            )));
        };
        lambda_nm.push(parse_number(e, l)?);
        values.push(parse_number(e, v)?);
    }
    if lambda_nm.len() < 2 {
        return Err(e.error("<spectrum> needs at least two wavelength:value pairs"));
    }
    Ok((lambda_nm, values))
}

/// Samples, with zero samples added beyond the ends (module docs).
pub(crate) fn zero_outside(
    lambda_nm: Vec<f64>,
    values: Vec<f64>,
    range: &SpectralRange,
) -> SpectrumSource {
    let mut l = Vec::with_capacity(lambda_nm.len() + 2);
    let mut v = Vec::with_capacity(values.len() + 2);
    if let Some(&first) = lambda_nm.first()
        && first > range.min_nm()
    {
        l.push(first - ZERO_EDGE_NM);
        v.push(0.0);
    }
    l.extend_from_slice(&lambda_nm);
    v.extend_from_slice(&values);
    if let Some(&last) = lambda_nm.last()
        && last < range.max_nm()
    {
        l.push(last + ZERO_EDGE_NM);
        v.push(0.0);
    }
    SpectrumSource::Tabulated {
        lambda_nm: l,
        values: v,
    }
}

/// The samples of a `.spd` file.
fn spd_file(e: &Element, path: &std::path::Path) -> Result<(Vec<f64>, Vec<f64>), CliError> {
    let text = read_text(path, MAX_SPD_BYTES).map_err(|err| e.error(err))?;
    let mut lambda_nm = Vec::new();
    let mut values = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let n = parse_numbers(e, line).map_err(|_| {
            e.error(format!(
                "{}:{}: expected `wavelength value`",
                path.display(),
                i + 1
            ))
        })?;
        let [l, v] = n.as_slice() else {
            return Err(e.error(format!(
                "{}:{}: expected two numbers `wavelength value`",
                path.display(),
                i + 1
            )));
        };
        lambda_nm.push(*l);
        values.push(*v);
    }
    if lambda_nm.len() < 2 {
        return Err(e.error(format!(
            "{}: a spectrum file needs at least two samples",
            path.display()
        )));
    }
    Ok((lambda_nm, values))
}

impl<'e> Importer<'e, '_> {
    /// The spectrum source of a property used as `usage` (module docs).
    pub(crate) fn spectrum_source(
        &mut self,
        p: &Property<'e>,
        usage: SpectrumUse,
    ) -> Result<SpectrumSource, CliError> {
        let range = SpectralRange::VISIBLE;
        let uniform = |v: f64| match usage {
            SpectrumUse::Emission => d65_times(v),
            _ => SpectrumSource::Constant(v),
        };
        let source = match p.value {
            Value::Float(v) => uniform(v),
            Value::Integer(v) => uniform(v as f64),
            Value::Rgb(rgb) => match usage {
                SpectrumUse::Reflectance => {
                    if rgb.iter().any(|c| !(0.0..=1.0).contains(c)) {
                        return Err(p.error(format!(
                            "rgb reflectance {rgb:?} is outside [0, 1] (Mitsuba refuses it too)"
                        )));
                    }
                    SpectrumSource::RgbReflectance(rgb)
                }
                SpectrumUse::Emission => SpectrumSource::RgbIlluminant(rgb),
                SpectrumUse::Unbounded => {
                    if rgb.iter().any(|&c| c > 1.0) {
                        self.warn_at(p.element, format!(
                                "property \"{}\": rgb {rgb:?} is clamped to [0, 1] as Mitsuba 3's spectral variants clamp it (give a <spectrum> for larger values)",
                                p.name
                            ),
                        );
                    }
                    SpectrumSource::RgbReflectance(rgb.map(|c| c.clamp(0.0, 1.0)))
                }
            },
            Value::SpectrumText(text) => {
                if text.contains(':') {
                    let (l, v) = pairs(p.element, text)?;
                    zero_outside(l, v, &range)
                } else {
                    SpectrumSource::Constant(parse_number(p.element, text)?)
                }
            }
            Value::SpectrumFile(name) => {
                let path = p.element.place.resolve_local(name).ok_or_else(|| {
                    p.error(format!(
                        "\"{name}\": file references are not available here"
                    ))
                })?;
                let (l, v) = spd_file(p.element, &path)?;
                zero_outside(l, v, &range)
            }
            Value::Object(e) if e.tag == "spectrum" => self.spectrum_plugin(e, usage)?,
            Value::Ref(id) => {
                let target = self.resolve_ref(p.element, id)?;
                if target.tag != "spectrum" {
                    return Err(p.error(format!(
                        "<ref id=\"{id}\"> is a <{}>, expected a spectrum",
                        target.tag
                    )));
                }
                self.spectrum_plugin(target, usage)?
            }
            ref other => return Err(p.wrong_type("a spectrum (rgb, spectrum or float)", other)),
        };
        Ok(source)
    }

    /// A `<spectrum type="…">` plugin.
    fn spectrum_plugin(
        &mut self,
        e: &'e Element,
        usage: SpectrumUse,
    ) -> Result<SpectrumSource, CliError> {
        let object = Object::new(e)?;
        let range = SpectralRange::VISIBLE;
        let source = match object.plugin {
            "blackbody" => {
                if usage != SpectrumUse::Emission {
                    return Err(object.error("a blackbody is an emission spectrum"));
                }
                let temperature_k = object
                    .float_opt("temperature")?
                    .ok_or_else(|| object.error("needs `temperature` (kelvin)"))?;
                if temperature_k <= 0.0 {
                    return Err(object.error("`temperature` must be > 0 K"));
                }
                let steps = range.width_nm().round().max(1.0) as usize;
                let lambda_nm: Vec<f64> = (0..=steps)
                    .map(|i| range.min_nm() + range.width_nm() * i as f64 / steps as f64)
                    .collect();
                let values = lambda_nm
                    .iter()
                    .map(|&l| planck_per_nm(l, temperature_k))
                    .collect();
                SpectrumSource::Tabulated { lambda_nm, values }
            }
            "d65" => d65_times(object.float("scale", 1.0)?),
            "uniform" => {
                let v = object.float("value", 1.0)?;
                SpectrumSource::Constant(v)
            }
            "irregular" => {
                let (Some(l), Some(v)) = (object.get("wavelengths"), object.get("values")) else {
                    return Err(object.error("needs `wavelengths` and `values` strings"));
                };
                let text = |p: &Property<'e>| -> Result<&'e str, CliError> {
                    match p.value {
                        Value::String(s) => Ok(s),
                        ref other => Err(p.wrong_type("a string of numbers", other)),
                    }
                };
                let lambda_nm = parse_numbers(l.element, text(l)?)?;
                let values = parse_numbers(v.element, text(v)?)?;
                if lambda_nm.len() != values.len() || lambda_nm.len() < 2 {
                    return Err(object.error(
                        "`wavelengths` and `values` need the same number (at least 2) of numbers",
                    ));
                }
                zero_outside(lambda_nm, values, &range)
            }
            "regular" => {
                let min = object
                    .float_opt("wavelength_min")?
                    .ok_or_else(|| object.error("needs `wavelength_min`"))?;
                let max = object
                    .float_opt("wavelength_max")?
                    .ok_or_else(|| object.error("needs `wavelength_max`"))?;
                let Some(v) = object.get("values") else {
                    return Err(object.error("needs `values`"));
                };
                let Value::String(text) = v.value else {
                    return Err(v.wrong_type("a string of numbers", &v.value));
                };
                let values = parse_numbers(v.element, text)?;
                if values.len() < 2 || max <= min {
                    return Err(object
                        .error("needs at least 2 `values` and wavelength_max > wavelength_min"));
                }
                let n = values.len() - 1;
                let lambda_nm = (0..=n)
                    .map(|i| min + (max - min) * i as f64 / n as f64)
                    .collect();
                zero_outside(lambda_nm, values, &range)
            }
            _ => {
                return Err(
                    object.error("is not supported (blackbody, d65, uniform, regular, irregular)")
                );
            }
        };
        self.check_unused(&object)?;
        Ok(source)
    }

    /// The spectrum of property `name` of `object` used as `usage`, added to
    /// the scene; `default` when absent.
    pub(crate) fn spectrum_id(
        &mut self,
        object: &Object<'e>,
        name: &str,
        usage: SpectrumUse,
        default: SpectrumSource,
    ) -> Result<SpectrumId, CliError> {
        let (source, at) = match object.get(name) {
            Some(p) => (self.spectrum_source(p, usage)?, p.element),
            None => (default, object.element),
        };
        let spot = Self::spot(at, format!("{} {name}", object.describe()));
        self.cx.add_spectrum(&spot, source)
    }
}

/// D65 normalised to luminance 1, times `scale` (Mitsuba's `d65` plugin).
pub(crate) fn d65_times(scale: f64) -> SpectrumSource {
    SpectrumSource::RgbIlluminant([scale; 3])
}
