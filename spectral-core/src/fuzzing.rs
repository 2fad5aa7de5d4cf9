//! Bodies of the cargo-fuzz targets that exercise this crate (`fuzz/`),
//! public (behind the feature `fuzzing`, which `fuzz/` and this crate's
//! tests enable; not part of the stable API) so that ordinary tests replay
//! the committed corpora on stable Rust. Each takes arbitrary bytes and panics only if an invariant of the
//! crate is broken (that panic is the fuzzer's finding).
//!
//! * [`mese`]: MESE and bounded MESE from arbitrary finite coefficients —
//!   outputs finite, non-negative, and in [0, 1] for the bounded variant.
//! * [`product_and_xyz`]: truncated products (codelets and loops) and every
//!   XYZ route on arbitrary finite coefficients — finite outputs, codelets
//!   equal to the loops.
//! * [`sine_mlp`]: the network loader on arbitrary bytes — `Err`, or a
//!   network that evaluates to finite coefficients.

use crate::basis::FourierBasis;
use crate::fourier::FourierSpectrum;
use crate::mese::{BoundedMese, Mese};
use crate::neural::SineMlp;
use crate::xyz::{XyzConverter, XyzRoute};

/// Up to `N` finite `f64` from the bytes (8 bytes each; non-finite values
/// and missing bytes become 0).
fn coefficients<const N: usize>(bytes: &[u8]) -> FourierSpectrum<f64, N> {
    FourierSpectrum::from_coeffs(core::array::from_fn(|j| {
        let v = bytes
            .get(8 * j..8 * j + 8)
            .and_then(|b| b.try_into().ok())
            .map_or(0.0, f64::from_le_bytes);
        if v.is_finite() { v } else { 0.0 }
    }))
}

/// MESE invariants on arbitrary coefficients.
pub fn mese(bytes: &[u8]) {
    let c = coefficients::<8>(bytes);
    let steps = 64;
    if let Ok(m) = Mese::new(&c) {
        for i in 0..=steps {
            let x = libm::cos(core::f64::consts::PI * i as f64 / steps as f64);
            let v = m.eval_cos(x);
            assert!(v.is_finite() && v >= 0.0, "MESE gave {v}");
        }
    }
    if let Ok(b) = BoundedMese::new(&c) {
        for i in 0..=steps {
            let x = libm::cos(core::f64::consts::PI * i as f64 / steps as f64);
            let v = b.eval_cos(x);
            assert!((0.0..=1.0).contains(&v), "bounded MESE gave {v}");
        }
    }
}

/// Products and XYZ routes on arbitrary finite coefficients of moderate size.
pub fn product_and_xyz(bytes: &[u8]) {
    let converter = XyzConverter::new(&FourierBasis::<12>::VISIBLE).ok();
    product_and_xyz_with(converter.as_ref(), bytes);
}

/// [`product_and_xyz`] with the converter over the visible range built by
/// the caller (the fuzz target builds it once: building it costs far more
/// than the rest of the body).
pub fn product_and_xyz_with(converter: Option<&XyzConverter<12>>, bytes: &[u8]) {
    let clamp = |c: FourierSpectrum<f64, 12>| {
        FourierSpectrum::from_coeffs(c.coeffs.map(|v: f64| v.clamp(-1e15, 1e15)))
    };
    let a = clamp(coefficients::<12>(bytes));
    let b = clamp(coefficients::<12>(bytes.get(96..).unwrap_or(&[])));
    let (fast, loops) = (a.product(&b), a.product_loops(&b));
    // Every h_k sums at most 2N terms c_p d_q, each at most |c_p| |d_q|, so
    // both summation orders are exact to a few ulps of 2 Σ|c| Σ|d| (not of
    // h_k itself, which may be a cancellation).
    let sum_abs = |c: &FourierSpectrum<f64, 12>| c.coeffs.iter().map(|v| v.abs()).sum::<f64>();
    let magnitude = 2.0 * sum_abs(&a) * sum_abs(&b);
    for (x, y) in fast.coeffs.iter().zip(&loops.coeffs) {
        assert!(x.is_finite() && y.is_finite());
        let scale = 1e-12 * (1.0 + magnitude);
        assert!((x - y).abs() <= scale, "codelet {x} vs loops {y}");
    }
    if let Some(converter) = converter {
        for route in [
            XyzRoute::Series,
            XyzRoute::Lut,
            XyzRoute::Zeroth,
            XyzRoute::Mese,
        ] {
            let xyz = converter.convert(route, &fast);
            assert!(xyz.to_array().iter().all(|v| v.is_finite()), "{route:?}");
        }
    }
}

/// The network loader on arbitrary bytes.
pub fn sine_mlp(bytes: &[u8]) {
    if let Ok(net) = SineMlp::<1, 10, 10>::from_bytes(bytes) {
        for x in [-1.0f32, 0.0, 0.5, 1.0] {
            let c = net.eval::<f32>([x]);
            assert!(c.coeffs.iter().all(|v| v.is_finite()), "network gave {c:?}");
        }
    }
}
