//! The registry of named built-in spectra.
//!
//! Names (case-insensitive):
//!
//! | name | spectrum |
//! | --- | --- |
//! | `equal-energy` (or `e`) | constant 1 |
//! | `d65`, `d50`, `a`, `fl2`, `fl7`, `fl11`, `led-b1` … `led-b5`, `led-bh1`, `led-rgb1`, `led-v1`, `led-v2` | CIE illuminants (relative power, native sampling) |
//! | `colorchecker-1` … `colorchecker-24` | ColorChecker Classic reflectances, chart order |
//! | `cie-x`, `cie-y`, `cie-z` | CIE 1931 2° colour-matching functions |
//! | `gold-n`, `gold-k`, `silver-n`, … `aluminium-k` | metal refractive index, real and imaginary part |
//! | `blackbody-<T>` (e.g. `blackbody-6500`) | Planck, normalised to 1 at its peak |
//!
//! Every name that [`Builtin::all`] lists parses back to itself through
//! [`Builtin::lookup`] (tested).
//!
//! ```
//! use spectral_core::registry::{Builtin, BuiltinData};
//! use spectral_core::Spectrum;
//!
//! let d65 = Builtin::lookup("D65")?;
//! assert_eq!(d65.to_string(), "d65");
//! // CIE D65 is tabulated relative to 100 at 560 nm.
//! assert_eq!(d65.value(560.0), 100.0);
//! assert!(matches!(Builtin::lookup("blackbody-2700")?.resolve(), BuiltinData::Blackbody(_)));
//! # Ok::<(), spectral_core::SpectralError>(())
//! ```

use crate::SpectralError;
use crate::cmf;
use crate::data::tables::{COLORCHECKER_NAMES, COLORCHECKER_NM, COLORCHECKER_REFLECTANCE};
use crate::data::tables::{ILLUMINANTS, METALS};
use crate::fourier::FourierSpectrum;
use crate::range::SpectralRange;
use crate::spectrum::{Blackbody, Spectrum, TabulatedSpectrum};
use core::fmt;

/// A named built-in spectrum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Builtin {
    /// Constant 1 (CIE illuminant E).
    EqualEnergy,
    /// Index into [`ILLUMINANTS`].
    Illuminant(usize),
    /// ColorChecker patch, 0-based chart order.
    ColorChecker(usize),
    /// Colour-matching function 0 = x̄, 1 = ȳ, 2 = z̄.
    Cmf(usize),
    /// Real part `n` of metal [`METALS`]`[i]`.
    MetalN(usize),
    /// Imaginary part `k` of metal [`METALS`]`[i]`.
    MetalK(usize),
    /// A blackbody, normalised to its peak.
    Blackbody(Blackbody),
}

const CMF_NAMES: [&str; 3] = ["cie-x", "cie-y", "cie-z"];
const EQUAL_ENERGY_NM: [f64; 1] = [560.0];
const EQUAL_ENERGY_VALUE: [f64; 1] = [1.0];

impl Builtin {
    /// Parses a built-in name; `Err(UnknownName)` if it is none.
    pub fn lookup(name: &str) -> Result<Self, SpectralError> {
        let name = name.trim();
        let is = |candidate: &str| name.eq_ignore_ascii_case(candidate);
        if is("equal-energy") || is("e") {
            return Ok(Self::EqualEnergy);
        }
        if let Some(index) = ILLUMINANTS.iter().position(|i| is(i.name)) {
            return Ok(Self::Illuminant(index));
        }
        if let Some(index) = CMF_NAMES.iter().position(|n| is(n)) {
            return Ok(Self::Cmf(index));
        }
        if let Some(number) = strip_prefix_ignore_case(name, "colorchecker-") {
            return match number.parse::<usize>() {
                Ok(n) if (1..=COLORCHECKER_NAMES.len()).contains(&n) => {
                    Ok(Self::ColorChecker(n - 1))
                }
                _ => Err(SpectralError::UnknownName),
            };
        }
        if let Some(kelvin) = strip_prefix_ignore_case(name, "blackbody-") {
            let temperature_k = kelvin
                .parse::<f64>()
                .map_err(|_| SpectralError::InvalidTemperature)?;
            return Blackbody::new(temperature_k).map(Self::Blackbody);
        }
        for (index, metal) in METALS.iter().enumerate() {
            if let Some(part) = strip_prefix_ignore_case(name, metal.name) {
                if part.eq_ignore_ascii_case("-n") {
                    return Ok(Self::MetalN(index));
                }
                if part.eq_ignore_ascii_case("-k") {
                    return Ok(Self::MetalK(index));
                }
            }
        }
        Err(SpectralError::UnknownName)
    }

    /// Every tabulated built-in (blackbodies are parametric and not listed).
    pub fn all() -> impl Iterator<Item = Self> {
        let illuminants = (0..ILLUMINANTS.len()).map(Self::Illuminant);
        let patches = (0..COLORCHECKER_NAMES.len()).map(Self::ColorChecker);
        let cmfs = (0..CMF_NAMES.len()).map(Self::Cmf);
        let metals = (0..METALS.len()).flat_map(|i| [Self::MetalN(i), Self::MetalK(i)]);
        core::iter::once(Self::EqualEnergy)
            .chain(illuminants)
            .chain(patches)
            .chain(cmfs)
            .chain(metals)
    }

    /// What the name stands for: embedded samples or a blackbody.
    pub fn resolve(&self) -> BuiltinData {
        BuiltinData::Tabulated(match *self {
            Self::EqualEnergy => TabulatedSpectrum::embedded(&EQUAL_ENERGY_NM, &EQUAL_ENERGY_VALUE),
            Self::Illuminant(i) => {
                TabulatedSpectrum::embedded(ILLUMINANTS[i].lambda_nm, ILLUMINANTS[i].power)
            }
            Self::ColorChecker(i) => {
                TabulatedSpectrum::embedded(&COLORCHECKER_NM, &COLORCHECKER_REFLECTANCE[i])
            }
            Self::Cmf(i) => cmf::cmfs()[i],
            Self::MetalN(i) => TabulatedSpectrum::embedded(METALS[i].lambda_nm, METALS[i].n),
            Self::MetalK(i) => TabulatedSpectrum::embedded(METALS[i].lambda_nm, METALS[i].k),
            Self::Blackbody(b) => return BuiltinData::Blackbody(b),
        })
    }

    /// The tabulated data, or `None` for a blackbody.
    pub fn tabulated(&self) -> Option<TabulatedSpectrum<'static>> {
        match self.resolve() {
            BuiltinData::Tabulated(tabulated) => Some(tabulated),
            BuiltinData::Blackbody(_) => None,
        }
    }

    /// A one-line description.
    pub fn description(&self) -> &'static str {
        match self {
            Self::EqualEnergy => "equal-energy illuminant E (constant 1)",
            Self::Illuminant(_) => "CIE illuminant, relative spectral power (CIE 15:2018)",
            Self::ColorChecker(_) => "ColorChecker Classic patch reflectance (Ohta 1997)",
            Self::Cmf(_) => "CIE 1931 2 degree colour-matching function",
            Self::MetalN(_) => "metal refractive index, real part n",
            Self::MetalK(_) => "metal refractive index, imaginary part k",
            Self::Blackbody(_) => "blackbody (Planck), normalised to 1 at its peak",
        }
    }
}

/// The data behind a [`Builtin`] ([`Builtin::resolve`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BuiltinData {
    /// Embedded samples (illuminants, patches, CMFs, metals, illuminant E).
    Tabulated(TabulatedSpectrum<'static>),
    /// A parametric blackbody.
    Blackbody(Blackbody),
}

impl Spectrum for BuiltinData {
    fn value(&self, lambda_nm: f64) -> f64 {
        match self {
            Self::Tabulated(tabulated) => tabulated.value(lambda_nm),
            Self::Blackbody(blackbody) => blackbody.value(lambda_nm),
        }
    }

    fn project<const N: usize>(&self, range: &SpectralRange) -> FourierSpectrum<f64, N> {
        match self {
            Self::Tabulated(tabulated) => tabulated.project(range),
            Self::Blackbody(blackbody) => blackbody.project(range),
        }
    }
}

fn strip_prefix_ignore_case<'a>(text: &'a str, prefix: &str) -> Option<&'a str> {
    let head = text.get(..prefix.len())?;
    if head.eq_ignore_ascii_case(prefix) {
        text.get(prefix.len()..)
    } else {
        None
    }
}

impl fmt::Display for Builtin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::EqualEnergy => write!(f, "equal-energy"),
            Self::Illuminant(i) => write!(f, "{}", ILLUMINANTS[*i].name),
            Self::ColorChecker(i) => write!(f, "colorchecker-{}", i + 1),
            Self::Cmf(i) => write!(f, "{}", CMF_NAMES[*i]),
            Self::MetalN(i) => write!(f, "{}-n", METALS[*i].name),
            Self::MetalK(i) => write!(f, "{}-k", METALS[*i].name),
            Self::Blackbody(b) => write!(f, "blackbody-{}", b.temperature_k()),
        }
    }
}

impl Spectrum for Builtin {
    fn value(&self, lambda_nm: f64) -> f64 {
        self.resolve().value(lambda_nm)
    }

    fn project<const N: usize>(&self, range: &SpectralRange) -> FourierSpectrum<f64, N> {
        self.resolve().project(range)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::string::ToString;

    #[test]
    fn every_listed_name_round_trips_and_is_valid() {
        let mut count = 0;
        for builtin in Builtin::all() {
            let name = builtin.to_string();
            assert_eq!(Builtin::lookup(&name), Ok(builtin), "{name}");
            assert_eq!(Builtin::lookup(&name.to_uppercase()), Ok(builtin), "{name}");
            builtin.tabulated().unwrap().validate().unwrap();
            count += 1;
        }
        assert_eq!(count, 1 + 15 + 24 + 3 + 8);
    }

    #[test]
    fn unknown_and_malformed_names() {
        for bad in [
            "",
            "d66",
            "colorchecker-0",
            "colorchecker-25",
            "gold",
            "gold-x",
        ] {
            assert_eq!(
                Builtin::lookup(bad),
                Err(SpectralError::UnknownName),
                "{bad}"
            );
        }
        assert_eq!(
            Builtin::lookup("blackbody-abc"),
            Err(SpectralError::InvalidTemperature)
        );
        assert_eq!(
            Builtin::lookup("blackbody--5"),
            Err(SpectralError::InvalidTemperature)
        );
        let bb = Builtin::lookup("blackbody-6500").unwrap();
        assert_eq!(bb.to_string(), "blackbody-6500");
        assert!(bb.tabulated().is_none());
        assert!(bb.value(500.0) > 0.0);
    }

    #[test]
    fn colorchecker_13_is_blue() {
        let blue = Builtin::lookup("colorchecker-13").unwrap();
        assert_eq!(COLORCHECKER_NAMES[12], "blue");
        assert!(blue.value(450.0) > blue.value(650.0));
    }
}
