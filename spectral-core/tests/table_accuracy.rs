//! Fourier tables against direct evaluation: the interpolation error over
//! random angles (max and RMS of the reconstructed reflectance on a 1 nm
//! grid, printed with `--nocapture`), exact rows at the table ends, and the
//! memory per table.

use spectral_core::complex::Complex;
use spectral_core::data::tables::METALS;
use spectral_core::optics::{Layer, fresnel_conductor};
use spectral_core::spectrum::project_function;
use spectral_core::table::{
    FilmQuantity, FilmSide, FourierTable, dielectric_reflectance, film_table, metal_reflectance,
};
use spectral_core::{FourierSpectrum, SpectralRange, Spectrum, TabulatedSpectrum};

const N: usize = 12;
const L: usize = 180;

/// (max, rms) of |table series − direct series| over 1 nm and `samples` angles.
fn interpolation_error(
    table: &FourierTable<N, L>,
    direct: impl Fn(f64, f64) -> f64,
    samples: usize,
) -> (f64, f64) {
    let range = SpectralRange::VISIBLE;
    let (mut max, mut sum_sq, mut count) = (0.0f64, 0.0, 0usize);
    for s in 0..samples {
        // A low-discrepancy sequence of cos θ in (0, 1).
        let cos_i = ((s as f64 + 0.5) * 0.618_033_988_749_895) % 1.0;
        let exact: FourierSpectrum<f64, N> = project_function(&range, |l| direct(cos_i, l));
        let looked_up = table.lookup(cos_i);
        for i in 0..=470 {
            let lambda_nm = 360.0 + i as f64;
            let e = f64::from(looked_up.eval(&range, lambda_nm)) - exact.eval(&range, lambda_nm);
            max = max.max(e.abs());
            sum_sq += e * e;
            count += 1;
        }
    }
    (max, (sum_sq / count as f64).sqrt())
}

fn check_ends(table: &FourierTable<N, L>, direct: impl Fn(f64, f64) -> f64) {
    let range = SpectralRange::VISIBLE;
    for cos_i in [0.0, 1.0] {
        let exact: FourierSpectrum<f64, N> = project_function(&range, |l| direct(cos_i, l));
        let row = table.lookup(cos_i);
        for j in 0..N {
            let e = (f64::from(row.coeffs[j]) - exact.coeffs[j]).abs();
            // Rows project the 1 nm polyline of the function; the reference
            // is Gauss–Legendre on the function itself: they differ by the
            // 1 nm discretisation (h²f''/8 ≈ 3e-6 for a 400 nm film) and f32.
            assert!(e < 1e-5, "cos θ = {cos_i}, j = {j}: {e}");
        }
    }
}

#[test]
fn gold_table_accuracy() {
    let range = SpectralRange::VISIBLE;
    let gold = METALS.iter().find(|m| m.name == "gold").unwrap();
    let table = metal_reflectance::<N, L>(&range, gold).unwrap();
    let n = TabulatedSpectrum::new(gold.lambda_nm, gold.n).unwrap();
    let k = TabulatedSpectrum::new(gold.lambda_nm, gold.k).unwrap();
    let direct =
        |cos_i: f64, l: f64| fresnel_conductor(cos_i, Complex::new(n.value(l), k.value(l)));
    check_ends(&table, direct);
    let (max, rms) = interpolation_error(&table, direct, 200);
    println!("gold conductor table (N = {N}, L = {L}): max {max:.2e}, rms {rms:.2e}");
    assert!(max < 2e-3 && rms < 1e-4, "max {max}, rms {rms}");
    assert_eq!(FourierTable::<N, L>::memory_bytes(), 8640);
}

#[test]
fn dielectric_table_accuracy_both_sides() {
    let range = SpectralRange::VISIBLE;
    for from_inside in [false, true] {
        let table = dielectric_reflectance::<N, L>(&range, |_| 1.5, from_inside).unwrap();
        let sign = if from_inside { -1.0 } else { 1.0 };
        let direct =
            |cos_i: f64, _l: f64| spectral_core::optics::fresnel_dielectric(sign * cos_i, 1.5);
        check_ends(&table, direct);
        let (max, rms) = interpolation_error(&table, direct, 200);
        println!("dielectric table, from inside = {from_inside}: max {max:.2e}, rms {rms:.2e}");
        // From inside, the total-internal-reflection kink at cos θ = 0.745
        // falls between rows: the largest error sits there.
        let bound = if from_inside { 0.05 } else { 2e-3 };
        assert!(max < bound && rms < 5e-3, "max {max}, rms {rms}");
    }
}

#[test]
fn thin_film_tables_accuracy() {
    let range = SpectralRange::VISIBLE;
    let layers = [
        Layer {
            index: Complex::real(2.0),
            thickness_nm: 400.0,
        },
        Layer {
            index: Complex::real(1.38),
            thickness_nm: 110.0,
        },
    ];
    let substrate = Complex::real(1.5);
    for quantity in [FilmQuantity::Reflectance, FilmQuantity::Transmittance] {
        for side in [FilmSide::Front, FilmSide::Back] {
            let table =
                film_table::<N, L>(&range, 1.0, &layers, substrate, quantity, side).unwrap();
            let direct = |cos_i: f64, l: f64| {
                let (incident, exit, stack): (f64, Complex, Vec<Layer>) = match side {
                    FilmSide::Front => (1.0, substrate, layers.to_vec()),
                    FilmSide::Back => (
                        1.5,
                        Complex::real(1.0),
                        layers.iter().rev().copied().collect(),
                    ),
                };
                let r = spectral_core::optics::multilayer(l, incident, &stack, exit, cos_i);
                match quantity {
                    FilmQuantity::Reflectance => r.reflectance(),
                    FilmQuantity::Transmittance => r.transmittance(),
                }
            };
            check_ends(&table, direct);
            let (max, rms) = interpolation_error(&table, direct, 100);
            println!("film {quantity:?} {side:?}: max {max:.2e}, rms {rms:.2e}");
            let bound = if side == FilmSide::Back { 0.05 } else { 5e-3 };
            assert!(
                max < bound && rms < 5e-3,
                "{quantity:?} {side:?}: max {max}, rms {rms}"
            );
        }
    }
}

#[test]
fn lane_lookup_matches_scalar_lookup() {
    let range = SpectralRange::VISIBLE;
    let table = dielectric_reflectance::<N, L>(&range, |l| 1.5 + 4000.0 / (l * l), false).unwrap();
    let params = [0.0f32, 0.1, 0.25, 0.333, 0.5, 0.77, 0.999, 1.0];
    let lanes = table.lookup_lanes(wide::f32x8::new(params));
    for (lane, &p) in params.iter().enumerate() {
        let scalar = table.lookup(f64::from(p));
        for j in 0..N {
            use spectral_core::Lane;
            assert_eq!(lanes.coeffs[j].lane(lane), f64::from(scalar.coeffs[j]));
        }
    }
}
