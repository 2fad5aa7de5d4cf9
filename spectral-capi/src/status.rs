//! The status code every entry point returns.

use spectral_core::SpectralError;

/// The result of every `fspec_*` function: `FSPEC_STATUS_OK` (0) or a
/// negative code saying what was wrong with the input. On any code but
/// `FSPEC_STATUS_OK` the output buffers are left untouched, except where a
/// function documents otherwise.
///
/// The values are part of the ABI: they never change, new codes get new
/// values.
#[repr(i32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FspecStatus {
    /// Success.
    Ok = 0,
    /// A required pointer argument is null.
    NullPointer = -1,
    /// A pointer is not aligned for its element type (or a buffer for the
    /// value it holds: 8 bytes).
    Misaligned = -2,
    /// The coefficient count `n` (or wavelength count) is outside
    /// `1..=FSPEC_MAX_COEFFS` (`1..=FSPEC_MAX_WAVELENGTHS`), or differs from
    /// the count a converter, table or kernel was built for.
    UnsupportedCount = -3,
    /// A length is zero where samples are needed, or too large for the
    /// address space.
    BadLength = -4,
    /// Wavelengths are not strictly increasing (unsorted or duplicate).
    NotIncreasing = -5,
    /// A wavelength is NaN, infinite or not positive.
    InvalidWavelength = -6,
    /// A value (spectrum sample, coefficient, RGB channel, random number,
    /// estimator input) is NaN or infinite.
    NonFinite = -7,
    /// A spectral value that must not be negative is negative.
    NegativeValue = -8,
    /// The spectral range is not `0 < min_nm < max_nm`, finite, at most
    /// `FSPEC_MAX_RANGE_WIDTH_NM` wide; or, for XYZ and RGB upsampling, not
    /// inside the CIE table (360–830 nm).
    InvalidRange = -9,
    /// A scalar parameter is outside its domain (a blackbody temperature, a
    /// refractive index, an enumerator value such as a route or strategy).
    InvalidParameter = -10,
    /// A caller-allocated buffer is smaller than its `_size` function says.
    BufferTooSmall = -11,
    /// A buffer was not initialised by the matching `_init`/`_build`
    /// function (or holds another kind of value).
    NotInitialised = -12,
    /// The computation produced a NaN or an infinity from valid input (for
    /// example a blackbody so cold that its normalisation underflows).
    NonFiniteResult = -13,
    /// A wavelength or parameter lies outside the interval where the
    /// function is defined (a wavelength outside the spectral range, a
    /// random number outside `[0, 1)`).
    OutOfRange = -14,
}

impl From<SpectralError> for FspecStatus {
    fn from(error: SpectralError) -> Self {
        match error {
            SpectralError::Empty | SpectralError::LengthMismatch { .. } => Self::BadLength,
            SpectralError::InvalidWavelength { .. } => Self::InvalidWavelength,
            SpectralError::NotIncreasing { .. } => Self::NotIncreasing,
            SpectralError::NonFiniteValue { .. } => Self::NonFinite,
            SpectralError::NegativeValue { .. } => Self::NegativeValue,
            SpectralError::InvalidRange => Self::InvalidRange,
            SpectralError::InvalidTemperature
            | SpectralError::InvalidParameter(_)
            | SpectralError::UnknownName
            | SpectralError::Csv(_) => Self::InvalidParameter,
            // `SpectralError` is `#[non_exhaustive]`: a kind of bad input
            // added later is at least a bad parameter.
            _ => Self::InvalidParameter,
        }
    }
}

/// Runs a body returning `Result<(), FspecStatus>` and flattens it to the
/// status code of the ABI.
pub(crate) fn status_of(result: Result<(), FspecStatus>) -> FspecStatus {
    match result {
        Ok(()) => FspecStatus::Ok,
        Err(status) => status,
    }
}
