//! Property tests of the Fourier algebra against dense f64 quadrature.
//!
//! Random piecewise-linear spectra have breakpoints on a 0.01 nm grid; the
//! dense reference is composite Simpson with 188,000 intervals of 0.0025 nm
//! over 360–830 nm, so every breakpoint falls on a panel boundary and each
//! panel integrates a smooth function: the reference is accurate to ~1e-12
//! and the tolerances below are tight.

use proptest::prelude::*;
use spectral_core::FourierBasis;
use spectral_core::damping::Damping;
use spectral_core::xyz::{XyzConverter, XyzRoute};
use spectral_core::{FourierSpectrum, SpectralRange, Spectrum, TabulatedSpectrum};
use std::f64::consts::PI;

const DENSE_INTERVALS: usize = 188_000;

/// A random polyline: strictly increasing wavelengths on a 0.01 nm grid in
/// [300, 900] nm and values in [0, 10].
fn polyline() -> impl Strategy<Value = (Vec<f64>, Vec<f64>)> {
    prop::collection::vec((1u32..6000, 0.0f64..10.0), 1..40).prop_map(|steps| {
        let mut lambda_cnm = 30_000u32;
        let mut nm = Vec::new();
        let mut values = Vec::new();
        for (step, value) in steps {
            lambda_cnm += step;
            if lambda_cnm > 90_000 {
                break;
            }
            nm.push(f64::from(lambda_cnm) / 100.0);
            values.push(value);
        }
        if nm.is_empty() {
            nm.push(555.0);
            values.push(1.0);
        }
        (nm, values)
    })
}

fn coefficients<const N: usize>() -> impl Strategy<Value = FourierSpectrum<f64, N>> {
    prop::array::uniform(-2.0f64..2.0).prop_map(FourierSpectrum::from_coeffs)
}

/// Composite Simpson over the range of `f(λ)` with `DENSE_INTERVALS`.
fn dense_integral_nm(range: &SpectralRange, f: impl Fn(f64) -> f64) -> f64 {
    let h = range.width_nm() / DENSE_INTERVALS as f64;
    let mut sum = f(range.min_nm()) + f(range.max_nm());
    for i in 1..DENSE_INTERVALS {
        let weight = if i % 2 == 1 { 4.0 } else { 2.0 };
        sum += weight * f(range.min_nm() + i as f64 * h);
    }
    sum * h / 3.0
}

/// `c_j = (1/π) ∫ g cos(jφ) dφ = (1/(λ1−λ0)) ∫ g cos(jφ(λ)) dλ`, densely.
fn dense_projection<const N: usize>(range: &SpectralRange, g: impl Fn(f64) -> f64) -> [f64; N] {
    core::array::from_fn(|j| {
        dense_integral_nm(range, |l| g(l) * (j as f64 * range.phase(l)).cos()) / range.width_nm()
    })
}

/// The product of two trigonometric polynomials of degree m has degree 2m;
/// the trapezoid rule over a full period with 1e5 points is exact for it.
fn check_product<const N: usize>(
    a: &FourierSpectrum<f64, N>,
    b: &FourierSpectrum<f64, N>,
) -> Result<(), TestCaseError> {
    let points = 100_000;
    let mut dense = [0.0; N];
    for i in 0..points {
        let phi = -PI + 2.0 * PI * i as f64 / points as f64;
        let x = phi.cos();
        let g = a.eval_cos(x) * b.eval_cos(x);
        for (j, d) in dense.iter_mut().enumerate() {
            *d += g * (j as f64 * phi).cos() / points as f64;
        }
    }
    let h = a.product(b);
    for (j, (got, want)) in h.coeffs.iter().zip(dense).enumerate() {
        prop_assert!((got - want).abs() < 1e-11, "N = {}, j = {}", N, j);
    }
    // Parseval: h_0 alone.
    prop_assert!((a.product_mean(b) - dense[0]).abs() < 1e-11);
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn projection_of_polylines_is_exact((nm, values) in polyline()) {
        let range = SpectralRange::VISIBLE;
        let spectrum = TabulatedSpectrum::new(&nm, &values).unwrap();
        let projected = spectrum.project::<16>(&range);
        let dense = dense_projection::<16>(&range, |l| spectrum.value(l));
        for (j, (got, want)) in projected.coeffs.iter().zip(dense).enumerate() {
            prop_assert!((got - want).abs() < 1e-10, "j = {}: {} vs {}", j, got, want);
        }
    }

    #[test]
    fn truncated_product_is_the_projection_of_the_product_of_series(
        a in coefficients::<12>(), b in coefficients::<12>(),
        a7 in coefficients::<7>(), b7 in coefficients::<7>()
    ) {
        // N = 12 runs the unrolled codelet, N = 7 the loops.
        check_product(&a, &b)?;
        check_product(&a7, &b7)?;
    }

    #[test]
    fn projection_and_product_are_linear(
        (nm, values) in polyline(), scale_a in 0.0f64..3.0, scale_b in 0.0f64..3.0,
        other in coefficients::<8>()
    ) {
        let range = SpectralRange::VISIBLE;
        let a = TabulatedSpectrum::new(&nm, &values).unwrap();
        let second: Vec<f64> = values.iter().rev().copied().collect();
        let b = TabulatedSpectrum::new(&nm, &second).unwrap();
        let combined: Vec<f64> = values.iter().zip(&second)
            .map(|(x, y)| scale_a * x + scale_b * y).collect();
        let c = TabulatedSpectrum::new(&nm, &combined).unwrap();
        let (pa, pb, pc) = (a.project::<8>(&range), b.project::<8>(&range), c.project::<8>(&range));
        let expected = pa.scale(scale_a) + pb.scale(scale_b);
        for j in 0..8 {
            prop_assert!((pc.coeffs[j] - expected.coeffs[j]).abs() < 1e-12);
        }
        let lhs = pc.product(&other);
        let rhs = pa.product(&other).scale(scale_a) + pb.product(&other).scale(scale_b);
        for j in 0..8 {
            prop_assert!((lhs.coeffs[j] - rhs.coeffs[j]).abs() < 1e-11);
        }
    }

    #[test]
    fn evaluation_matches_the_direct_cosine_sum(
        c in coefficients::<16>(), lambda_nm in 360.0f64..830.0
    ) {
        let range = SpectralRange::VISIBLE;
        let phi = range.phase(lambda_nm);
        let direct = c.coeffs[0]
            + 2.0 * (1..16).map(|j| c.coeffs[j] * (j as f64 * phi).cos()).sum::<f64>();
        prop_assert!((c.eval(&FourierBasis::new(range), lambda_nm) - direct).abs() < 1e-12);
    }

    #[test]
    fn fejer_damping_keeps_non_negative_spectra_non_negative((nm, values) in polyline()) {
        let range = SpectralRange::VISIBLE;
        let spectrum = TabulatedSpectrum::new(&nm, &values).unwrap();
        let damped = spectrum.project::<12>(&range).damped(Damping::Fejer);
        for i in 0..=4700 {
            let lambda_nm = 360.0 + i as f64 * 0.1;
            prop_assert!(damped.eval(&FourierBasis::new(range), lambda_nm) >= -1e-12, "{} nm", lambda_nm);
        }
    }

    #[test]
    fn xyz_routes_match_dense_integration_of_the_series(c in coefficients::<12>()) {
        let range = SpectralRange::VISIBLE;
        let converter = XyzConverter::<12>::new(&FourierBasis::new(range)).unwrap();
        let cmfs = spectral_core::cmf::cmfs();
        let dense: [f64; 3] = core::array::from_fn(|r| {
            dense_integral_nm(&range, |l| c.eval(&FourierBasis::new(range), l) * cmfs[r].value(l))
                / spectral_core::cmf::Y_BAR_INTEGRAL
        });
        let zeroth = converter.convert(XyzRoute::Zeroth, &c).to_array();
        let series = converter.convert(XyzRoute::Series, &c).to_array();
        let lut = converter.convert(XyzRoute::Lut, &c).to_array();
        let bound = c.coeffs.iter().map(|v| v.abs()).sum::<f64>() * 2.0;
        // Rigorous trapezoid error bound on the 1 nm grid for f = s·cmf:
        // |E| ≤ Σ_i h³/12 · max|f''|, f'' = s''·cmf + 2 s'·cmf' on each interval,
        // with |s^(k)| ≤ Σ 2|c_j| (jπ/W)^k.
        let w = range.width_nm();
        let s1: f64 = (1..12).map(|j| 2.0 * c.coeffs[j].abs() * j as f64 * PI / w).sum();
        let s2: f64 = (1..12).map(|j| 2.0 * c.coeffs[j].abs() * (j as f64 * PI / w).powi(2)).sum();
        for r in 0..3 {
            let v = cmfs[r].values();
            let trapezoid_bound: f64 = v.windows(2).map(|p| {
                (s2 * p[0].max(p[1]) + 2.0 * s1 * (p[1] - p[0]).abs()) / 12.0
            }).sum::<f64>() / spectral_core::cmf::Y_BAR_INTEGRAL;
            // Route 3 integrates exactly.
            prop_assert!((zeroth[r] - dense[r]).abs() < 1e-10 * bound, "zeroth {}", r);
            // Routes 1-2: trapezoid on the 1 nm grid; the LUT also rounds to f32.
            let e = (series[r] - dense[r]).abs();
            prop_assert!(e <= trapezoid_bound + 1e-10 * bound, "series {}: {} > {}", r, e, trapezoid_bound);
            let e = (lut[r] - dense[r]).abs();
            prop_assert!(e <= trapezoid_bound + 1e-6 * bound, "lut {}: {} > {}", r, e, trapezoid_bound);
        }
    }
}

#[test]
fn blackbody_projection_matches_dense_quadrature() {
    let range = SpectralRange::VISIBLE;
    for temperature_k in [1000.0, 2856.0, 6500.0, 20000.0] {
        let bb = spectral_core::Blackbody::new(temperature_k).unwrap();
        let projected = bb.project::<16>(&range);
        let dense = dense_projection::<16>(&range, |l| bb.value(l));
        let scale = projected.coeffs[0].abs();
        for (j, (got, want)) in projected.coeffs.iter().zip(dense).enumerate() {
            assert!(
                (got - want).abs() < 1e-9 * scale,
                "{temperature_k} K, j = {j}"
            );
        }
    }
}
