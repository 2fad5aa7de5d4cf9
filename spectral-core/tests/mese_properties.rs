//! MESE: moment reproduction for feasible moments, and finite in-range
//! output for any finite input (random, huge, negative, alternating,
//! near-singular, a laser line, a laser × green product).

use proptest::prelude::*;
use spectral_core::FourierBasis;
use spectral_core::mese::{BoundedMese, Mese};
use spectral_core::registry::Builtin;
use spectral_core::spectrum::project_function;
use spectral_core::{FourierSpectrum, SpectralError, SpectralRange, Spectrum, TabulatedSpectrum};

const N: usize = 8;

/// A random polyline on 360–830 nm with values in [lo, hi].
fn polyline(lo: f64, hi: f64) -> impl Strategy<Value = (Vec<f64>, Vec<f64>)> {
    prop::collection::vec(lo..hi, 3..12).prop_map(|values| {
        let step = 470.0 / (values.len() - 1) as f64;
        let nm = (0..values.len()).map(|i| 360.0 + i as f64 * step).collect();
        (nm, values)
    })
}

fn arbitrary_coefficients() -> impl Strategy<Value = [f64; N]> {
    prop::collection::vec(
        prop_oneof![
            -1e300f64..1e300,
            -10.0f64..10.0,
            -1e-300f64..1e-300,
            Just(0.0),
            Just(1.0),
            Just(-1.0)
        ],
        N,
    )
    .prop_map(|v| core::array::from_fn(|j| v[j]))
}

fn assert_unbounded_ok(mese: &Mese<N>) {
    for i in 0..=470 {
        let x = (core::f64::consts::PI * (i as f64 / 470.0 - 1.0)).cos();
        let v = mese.eval_cos(x);
        assert!(v.is_finite() && v >= 0.0, "{v}");
    }
}

fn assert_bounded_ok(mese: &BoundedMese<N>) {
    for i in 0..=470 {
        let x = (core::f64::consts::PI * (i as f64 / 470.0 - 1.0)).cos();
        let v = mese.eval_cos(x);
        assert!((0.0..=1.0).contains(&v), "{v}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn unbounded_mese_reproduces_feasible_moments((nm, values) in polyline(0.05, 1.0)) {
        let range = SpectralRange::VISIBLE;
        let c = TabulatedSpectrum::new(&nm, &values).unwrap().project::<N>(&range);
        let mese = Mese::new(&c).unwrap();
        prop_assert!(mese.feasible());
        let back = project_function::<N>(&range, |l| mese.eval(&FourierBasis::new(range), l));
        for j in 0..N {
            prop_assert!((back.coeffs[j] - c.coeffs[j]).abs() < 1e-7 * c.coeffs[0],
                "j = {}: {} vs {}", j, back.coeffs[j], c.coeffs[j]);
        }
    }

    #[test]
    fn bounded_mese_reproduces_feasible_moments((nm, values) in polyline(0.02, 0.98)) {
        let range = SpectralRange::VISIBLE;
        let c = TabulatedSpectrum::new(&nm, &values).unwrap().project::<N>(&range);
        let mese = BoundedMese::new(&c).unwrap();
        prop_assert!(mese.feasible());
        let back = project_function::<N>(&range, |l| mese.eval(&FourierBasis::new(range), l));
        for j in 0..N {
            prop_assert!((back.coeffs[j] - c.coeffs[j]).abs() < 1e-7,
                "j = {}: {} vs {}", j, back.coeffs[j], c.coeffs[j]);
        }
    }

    #[test]
    fn any_finite_input_gives_finite_in_range_output(coeffs in arbitrary_coefficients()) {
        let c = FourierSpectrum::from_coeffs(coeffs);
        assert_unbounded_ok(&Mese::new(&c).unwrap());
        assert_bounded_ok(&BoundedMese::new(&c).unwrap());
        // Alternating signs of the same magnitude.
        let alternating = FourierSpectrum::from_coeffs(core::array::from_fn(|j| {
            if j % 2 == 0 { coeffs[j].abs() } else { -coeffs[j].abs() }
        }));
        assert_unbounded_ok(&Mese::new(&alternating).unwrap());
        assert_bounded_ok(&BoundedMese::new(&alternating).unwrap());
    }
}

fn laser(center_nm: f64, width_nm: f64) -> Result<FourierSpectrum<f64, N>, SpectralError> {
    let nm = [
        center_nm - width_nm,
        center_nm - width_nm / 2.0,
        center_nm + width_nm / 2.0,
        center_nm + width_nm,
    ];
    let values = [0.0, 1.0, 1.0, 0.0];
    Ok(TabulatedSpectrum::new(&nm, &values)?.project(&SpectralRange::VISIBLE))
}

#[test]
fn laser_lines_and_products_stay_finite_and_non_negative() {
    let range = SpectralRange::VISIBLE;
    let line = laser(532.0, 2.0).unwrap();
    let mese = Mese::new(&line).unwrap();
    assert_unbounded_ok(&mese);
    // The reconstruction peaks near the line.
    let at_line = mese.eval(&FourierBasis::new(range), 532.0);
    assert!(
        at_line > 10.0 * mese.eval(&FourierBasis::new(range), 450.0),
        "{at_line}"
    );
    let green = Builtin::lookup("colorchecker-14")
        .unwrap()
        .project::<N>(&range);
    let product = line.product(&green);
    let mese = Mese::new(&product).unwrap();
    assert_unbounded_ok(&mese);
    let bounded = BoundedMese::new(&product).unwrap();
    assert_bounded_ok(&bounded);
    // Three laser lines (the `laser` scene's light) times every ColorChecker patch.
    let rgb_lasers =
        laser(450.0, 2.0).unwrap() + laser(532.0, 2.0).unwrap() + laser(638.0, 2.0).unwrap();
    for patch in 1..=24 {
        let reflectance = Builtin::lookup(&format!("colorchecker-{patch}"))
            .unwrap()
            .project::<N>(&range);
        assert_unbounded_ok(&Mese::new(&rgb_lasers.product(&reflectance)).unwrap());
    }
}

#[test]
fn near_singular_moments_stay_finite() {
    // Moments of a delta at one phase: the Toeplitz matrix is singular.
    let phi: f64 = -1.234;
    let delta = FourierSpectrum::<f64, N>::from_coeffs(core::array::from_fn(|j| {
        (j as f64 * phi).cos() / std::f64::consts::PI
    }));
    let mese = Mese::new(&delta).unwrap();
    assert_unbounded_ok(&mese);
    let scaled = FourierSpectrum::<f64, N>::from_coeffs(delta.coeffs.map(|c| c * 0.3));
    assert_bounded_ok(&BoundedMese::new(&scaled).unwrap());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn extended_coefficients_are_the_projection_of_the_density((nm, values) in polyline(0.05, 1.0)) {
        let range = SpectralRange::VISIBLE;
        let c = TabulatedSpectrum::new(&nm, &values).unwrap().project::<N>(&range);
        let mese = Mese::new(&c).unwrap();
        let extended = mese.extended_coefficients::<24>();
        let dense = project_function::<24>(&range, |l| mese.eval(&FourierBasis::new(range), l));
        for j in 0..24 {
            prop_assert!((extended.coeffs[j] - dense.coeffs[j]).abs() < 1e-6 * c.coeffs[0],
                "j = {}: {} vs {}", j, extended.coeffs[j], dense.coeffs[j]);
        }
    }
}

#[test]
fn mese_xyz_route_resolves_laser_lines() {
    use spectral_core::xyz::{XyzConverter, XyzRoute};
    let range = SpectralRange::VISIBLE;
    let lines =
        laser(450.0, 2.0).unwrap() + laser(532.0, 2.0).unwrap() + laser(638.0, 2.0).unwrap();
    let converter = XyzConverter::<N>::new(&FourierBasis::new(range)).unwrap();
    let series = converter.convert(XyzRoute::Zeroth, &lines);
    let mese = converter.convert(XyzRoute::Mese, &lines);
    // The density keeps the mean: its luminance is of the same order.
    assert!(
        mese.y > 0.3 * series.y && mese.y < 3.0 * series.y,
        "{mese:?} vs {series:?}"
    );
    assert!(mese.to_array().iter().all(|v| v.is_finite() && *v >= 0.0));
}
