//! σ-factor damping of a truncated cosine series against ringing.
//!
//! A truncated series of a non-negative spectrum can go negative ([math](crate::math) §1:
//! a Cornell-box white dips to −0.12 at `m = 11`). Multiplying coefficient `j`
//! by a σ-factor trades sharpness for smoothness:
//!
//! * Fejér `σ_j = 1 − j/(m+1)`: the Cesàro mean of the partial sums, i.e. the
//!   convolution of the spectrum with the Fejér kernel
//!   `K(φ) = (1/(m+1)) (sin((m+1)φ/2)/sin(φ/2))² ≥ 0` — so the damped series
//!   of a non-negative spectrum is non-negative everywhere (Fejér 1900;
//!   Zygmund, *Trigonometric Series*, ch. III);
//! * Lanczos `σ_j = sinc(j/(m+1))`, `sinc x = sin(πx)/(πx)`: milder, not
//!   positivity-preserving.
//!
//! Policy of the project: linear colour conversions use the undamped,
//! unbiased coefficients; damping is for reconstructions that must stay
//! non-negative (display of a spectrum, MESE-free previews).

use core::f64::consts::PI;

/// Which σ-factors to apply.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Damping {
    /// `σ_j = 1`: the plain truncated series.
    #[default]
    None,
    /// `σ_j = 1 − j/(m+1)`: non-negative for non-negative spectra.
    Fejer,
    /// `σ_j = sinc(j/(m+1))`.
    Lanczos,
}

impl Damping {
    /// `σ_0 … σ_{N−1}` for a series of `N = m + 1` coefficients.
    pub fn factors<const N: usize>(self) -> [f64; N] {
        let count = N as f64;
        core::array::from_fn(|j| {
            let x = j as f64 / count;
            match self {
                Self::None => 1.0,
                Self::Fejer => 1.0 - x,
                Self::Lanczos if j == 0 => 1.0,
                Self::Lanczos => libm::sin(PI * x) / (PI * x),
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn factor_values() {
        assert_eq!(Damping::None.factors::<3>(), [1.0, 1.0, 1.0]);
        assert_eq!(Damping::Fejer.factors::<4>(), [1.0, 0.75, 0.5, 0.25]);
        let l = Damping::Lanczos.factors::<2>();
        assert_eq!(l[0], 1.0);
        assert!((l[1] - 2.0 / PI).abs() < 1e-15);
    }
}
