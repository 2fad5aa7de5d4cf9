//! The error type of every input-driven entry point of the crate.

use crate::csv::CsvError;
use core::fmt;

/// What was wrong with the input. Indices refer to the offending sample.
///
/// Every fallible function of the crate returns it, so one `?` serves them
/// all. The enum is `#[non_exhaustive]`: a later version may report a new
/// kind of bad input without a breaking change, so a `match` needs a `_`
/// arm.
///
/// ```
/// use spectral_core::{SpectralError, TabulatedSpectrum};
///
/// let unsorted = TabulatedSpectrum::new(&[500.0, 400.0], &[1.0, 1.0]);
/// assert_eq!(unsorted, Err(SpectralError::NotIncreasing { index: 1 }));
/// assert_eq!(
///     unsorted.unwrap_err().to_string(),
///     "wavelength of sample 2 is not larger than the previous one (unsorted or duplicate)"
/// );
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum SpectralError {
    /// A tabulated spectrum has no samples.
    Empty,
    /// Wavelength and value slices differ in length.
    LengthMismatch {
        /// Number of wavelengths.
        wavelengths: usize,
        /// Number of values.
        values: usize,
    },
    /// A wavelength is NaN, infinite or not positive.
    InvalidWavelength {
        /// Index of the sample.
        index: usize,
    },
    /// Wavelengths are not strictly increasing at this index (unsorted or duplicate).
    NotIncreasing {
        /// Index of the first sample that is not larger than its predecessor.
        index: usize,
    },
    /// A value is NaN or infinite.
    NonFiniteValue {
        /// Index of the sample.
        index: usize,
    },
    /// A spectral value is negative.
    NegativeValue {
        /// Index of the sample.
        index: usize,
    },
    /// A spectral range whose bounds are not finite, positive and increasing.
    InvalidRange,
    /// A blackbody temperature that is not finite and positive.
    InvalidTemperature,
    /// A scalar parameter (named) outside its valid domain.
    InvalidParameter(&'static str),
    /// A name that the built-in registry does not know.
    UnknownName,
    /// A line of CSV text that is not a row of numbers ([`crate::csv`]).
    Csv(CsvError),
}

impl fmt::Display for SpectralError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Empty => write!(f, "the spectrum has no samples"),
            Self::LengthMismatch {
                wavelengths,
                values,
            } => write!(f, "{wavelengths} wavelengths but {values} values"),
            Self::InvalidWavelength { index } => write!(
                f,
                "wavelength of sample {} is not a finite positive number",
                index + 1
            ),
            Self::NotIncreasing { index } => write!(
                f,
                "wavelength of sample {} is not larger than the previous one (unsorted or duplicate)",
                index + 1
            ),
            Self::NonFiniteValue { index } => {
                write!(f, "value of sample {} is NaN or infinite", index + 1)
            }
            Self::NegativeValue { index } => write!(f, "value of sample {} is negative", index + 1),
            Self::InvalidRange => write!(
                f,
                "spectral range bounds must be finite, positive and increasing"
            ),
            Self::InvalidTemperature => {
                write!(f, "blackbody temperature must be finite and positive")
            }
            Self::InvalidParameter(name) => write!(f, "invalid parameter `{name}`"),
            Self::UnknownName => write!(f, "unknown built-in spectrum name"),
            Self::Csv(error) => write!(f, "{error}"),
        }
    }
}

impl core::error::Error for SpectralError {}

impl From<CsvError> for SpectralError {
    fn from(error: CsvError) -> Self {
        Self::Csv(error)
    }
}
