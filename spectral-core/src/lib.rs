//! # spectral-core
//!
//! The math of Fourier-series spectral rendering (Rodionov, Prikhodko, Frolov,
//! Voloboy, 2025): a spectrum over a wavelength range is carried as `N`
//! cosine coefficients, spectra are multiplied by a truncated convolution and
//! converted to colour once per pixel.
//!
//! `#![no_std]`, `#![forbid(unsafe_code)]`, no allocation. Every input-driven
//! entry point returns [`Result`]`<_, `[`SpectralError`]`>`; internal
//! invariants are `debug_assert!`s.
//!
//! ## The coefficient convention (one for the whole project)
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
#![no_std]
#![forbid(unsafe_code)]

#[cfg(test)]
extern crate std;

pub mod cmf;
pub mod color;
pub mod complex;
pub mod control_variate;
pub mod csv;
pub mod damping;
pub mod data;
pub mod delta_e;
mod error;
pub mod fourier;
pub mod fuzzing;
pub mod lane;
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

pub use color::{Lab, LinearSrgb, Xyz};
pub use error::SpectralError;
pub use fourier::FourierSpectrum;
pub use lane::Lane;
pub use range::SpectralRange;
pub use spectrum::{Blackbody, ConstantSpectrum, Spectrum, TabulatedSpectrum};
