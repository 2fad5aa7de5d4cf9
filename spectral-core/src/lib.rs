//! # spectral-core
//!
//! The math of Fourier-series spectral rendering (Rodionov, Prikhodko,
//! Frolov, Voloboy, 2025): a spectrum over a wavelength range is carried as
//! `N` cosine coefficients, spectra are multiplied by a truncated
//! convolution and converted to colour once per pixel. The formulas, with
//! their sources, are on the [math page](math).
//!
//! `#![no_std]`, `#![forbid(unsafe_code)]`, no allocation. Every
//! input-driven entry point returns [`Result`]`<_, `[`SpectralError`]`>`
//! (the CSV reader too); internal invariants are `debug_assert!`s.
//!
//! ```
//! use spectral_core::registry::Builtin;
//! use spectral_core::xyz::{XyzConverter, XyzRoute};
//! use spectral_core::FourierBasis;
//!
//! // One basis (range and coefficient count) for everything.
//! let basis = FourierBasis::<12>::VISIBLE;
//! let lamp = basis.project(&Builtin::lookup("d65")?);
//! let paint = basis.project(&Builtin::lookup("colorchecker-19")?); // white
//! let reflected = lamp * paint; // the truncated product
//! let xyz = XyzConverter::new(&basis)?.convert(XyzRoute::Zeroth, &reflected);
//! // D65 off a white patch: D65's chromaticity (0.3127, 0.3290).
//! let [x, y] = xyz.chromaticity();
//! assert!((x - 0.3127).abs() < 2e-3 && (y - 0.3290).abs() < 2e-3);
//! # Ok::<(), spectral_core::SpectralError>(())
//! ```
//!
//! ## Where to start
//!
//! | task | entry point |
//! | --- | --- |
//! | spectra from data, formulas, names | [`TabulatedSpectrum`], [`Blackbody`], [`registry::Builtin`], [`csv::rows`] |
//! | spectra from RGB | [`upsample::srgb_reflectance`], [`upsample::RgbUnbounded`], [`upsample::RgbIlluminant`] |
//! | coefficients | [`FourierBasis::project`], [`Spectrum::project`] |
//! | algebra | [`FourierSpectrum::product`] (`*`), `+`, [`FourierSpectrum::scale`], [`FourierSpectrum::eval`] |
//! | colour | [`xyz::XyzConverter`] (four routes), [`xyz::XyzKernel`], [`Xyz`], [`Lab`], [`LinearSrgb`] |
//! | non-negative reconstruction | [`mese::Mese`], [`mese::BoundedMese`], [`damping::Damping`] |
//! | angle-dependent materials | [`table::FourierTable`], [`table::dielectric_reflectance`], [`table::film_table`] |
//! | sampled-wavelength rendering | [`sampling::SampledWavelengths`], [`sampling::SampledSpectrum`], [`control_variate::ControlVariate`] |
//!
//! ## The coefficient convention (one for the whole crate)
//!
//! With the phase map `φ(λ) = π (λ − λ0)/(λ1 − λ0) − π ∈ [−π, 0]` of a
//! [`SpectralRange`] and the spectrum mirrored to an even function on
//! `[−π, π]`, the coefficients are
//!
//! `c_j = (1/π) ∫_{−π}^{0} g(φ) cos(jφ) dφ`, `j = 0..N−1`,
//!
//! so `c_0` is the mean of `g` over the range and the truncated series is
//! `g(φ) ≈ c_0 + 2 Σ_{j≥1} c_j cos(jφ)`. These are exactly the real
//! trigonometric moments MESE consumes. (The paper's `a` form is
//! `a_0 = c_0`, `a_j = 2 c_j`.)
//!
//! ## The range lives in a context object
//!
//! A [`FourierSpectrum`] is `N` numbers and nothing else; the range that
//! gives them meaning is a [`FourierBasis<N>`](FourierBasis), which every
//! operation reading coefficients as a function of wavelength takes
//! (evaluation, XYZ, MESE evaluation, sampled values). Why not a field of
//! the spectrum: [`basis`].
//!
//! ## The two SIMD axes
//!
//! A [`FourierSpectrum<L, N>`](FourierSpectrum) is generic over its numeric
//! [`Lane`] type `L`: `f32` or `f64` for one spectrum, `wide::f32x8` (feature
//! `simd`) for eight spectra, one per ray lane, stored coefficient-major.
//! The coefficient index `j` (the spectral axis) and the ray lane (the `L`
//! axis) are never mixed: code loops over `j`, and every operation on an `L`
//! is lane-wise.
//!
//! ## NaN policy
//!
//! Constructors from data reject NaN and infinities with an error. The
//! algebra itself is lane-wise IEEE arithmetic: a NaN coefficient given to
//! [`FourierSpectrum::from_coeffs`] propagates and is not hidden.
//!
//! ## Features
//!
//! * `simd` (default): `FourierSpectrum<wide::f32x8, N>` and the 8-lane
//!   paths; pulls in `wide` without its `std` feature.
//! * `upsampling` (default): RGB → spectrum with the embedded 1.2 MB
//!   sigmoid table ([`upsample`]). Without it the table and the functions
//!   reading it are left out.
//! * `fuzzing`: the bodies of the repository's cargo-fuzz targets
//!   (`fuzzing`); not part of the stable API.
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

#[cfg(test)]
extern crate std;

pub mod basis;
pub mod cmf;
pub mod color;
pub mod complex;
pub mod control_variate;
pub mod csv;
pub mod damping;
pub mod data;
pub mod delta_e;
mod error;
pub mod fluorescence;
pub mod fourier;
#[cfg(feature = "fuzzing")]
pub mod fuzzing;
pub mod lane;
#[doc = include_str!("../docs/math.md")]
pub mod math {}
pub mod mese;
pub mod neural;
pub mod observer;
pub mod optics;
pub mod range;
pub mod registry;
pub mod sampling;
pub mod spectrum;
pub mod table;
pub mod upsample;
pub mod xyz;

pub use basis::FourierBasis;
pub use color::{Lab, LinearSrgb, Xyz};
pub use error::SpectralError;
pub use fourier::FourierSpectrum;
pub use lane::Lane;
pub use range::SpectralRange;
pub use spectrum::{Blackbody, ConstantSpectrum, Spectrum, TabulatedSpectrum};

/// The examples of `README.md`, run as doctests (they use both default
/// features).
#[cfg(all(doctest, feature = "simd", feature = "upsampling"))]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
