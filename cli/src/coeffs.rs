//! Dispatch from a runtime coefficient count to the const generic `N` of
//! `FourierSpectrum<_, N>`: one monomorphisation per supported count.

/// Largest number of Fourier coefficients the CLI supports.
pub const MAX_COEFFS: usize = 32;

/// `dispatch_coeffs!(n, |N| expr)` evaluates `expr` with `const N: usize = n`
/// for `n` in `1..=MAX_COEFFS`, and to `Err(CliError)` otherwise.
macro_rules! dispatch_coeffs {
    ($n:expr, |$N:ident| $body:expr) => {
        $crate::coeffs::dispatch_coeffs!(@arms $n, $N, $body,
            [1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31 32])
    };
    (@arms $n:expr, $N:ident, $body:expr, [$($k:literal)*]) => {
        match $n {
            $($k => {
                const $N: usize = $k;
                $body
            })*
            other => Err($crate::CliError::input(format!(
                "{other} coefficients: must be 1 to {}",
                $crate::coeffs::MAX_COEFFS
            ))),
        }
    };
}
pub(crate) use dispatch_coeffs;
