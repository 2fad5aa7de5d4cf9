//! The core against published reference data (palette-style): CIE tables,
//! illuminant white points, the published CIELAB of the 24 ColorChecker
//! patches (X-Rite, D50) and the CIEDE2000 test pairs of Sharma, Wu and
//! Dalal (2005).

use spectral_core::SpectralRange;
use spectral_core::cmf::{self, Y_BAR_INTEGRAL};
use spectral_core::color::Lab;
use spectral_core::data::tables::{CIE1931_Y_BAR, COLORCHECKER_NAMES};
use spectral_core::delta_e::{delta_e76, delta_e2000};
use spectral_core::registry::Builtin;
use spectral_core::xyz::{reference_xyz, white_point};
use std::path::Path;

fn data_file(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../data")
        .join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn generated_tables_are_fresh() {
    let generated = datagen::generate(&datagen::data_dir()).unwrap();
    let committed = std::fs::read_to_string(datagen::output_path()).unwrap();
    assert!(
        generated == committed,
        "spectral-core/src/data/tables.rs is stale: run `cargo run -p datagen`"
    );
}

#[test]
fn y_bar_integral_matches_the_published_value() {
    // pbrt-v4 `CIE_Y_integral` (sum of its 1 nm CIE 1931 samples, 360-830 nm).
    // pbrt's table is an older transcription; CIE 018:2019 (ours) sums to
    // 106.856917, 2e-7 relative above it.
    let published_sum = 106.856_895;
    let sum: f64 = CIE1931_Y_BAR.iter().sum();
    assert!((sum / published_sum - 1.0).abs() < 1e-6, "{sum}");
    let ends = 0.5 * (CIE1931_Y_BAR[0] + CIE1931_Y_BAR[CIE1931_Y_BAR.len() - 1]);
    assert!((Y_BAR_INTEGRAL - (sum - ends)).abs() < 1e-12);
    // A constant spectrum of 1 has Y = 1.
    let one = Builtin::EqualEnergy.tabulated().unwrap();
    let y = reference_xyz(&one, &SpectralRange::VISIBLE).y;
    assert!((y - 1.0).abs() < 1e-12, "{y}");
}

#[test]
fn illuminant_white_points() {
    // CIE 15:2018 table 11.3 / 11.6: chromaticities of D65, D50, A (2°).
    let cases = [
        ("d65", [0.31272, 0.32903]),
        ("d50", [0.34567, 0.35851]),
        ("a", [0.44757, 0.40745]),
    ];
    for (name, expected) in cases {
        let illuminant = Builtin::lookup(name).unwrap();
        let white = white_point(&illuminant).unwrap();
        let [x, y] = white.chromaticity();
        assert!((x - expected[0]).abs() < 2e-4, "{name} x = {x}");
        assert!((y - expected[1]).abs() < 2e-4, "{name} y = {y}");
        assert!((white.y - 1.0).abs() < 1e-12);
    }
    // D65 XYZ (Y = 1) as commonly tabulated: (0.95047, 1, 1.08883).
    let d65 = white_point(&Builtin::lookup("d65").unwrap()).unwrap();
    assert!(
        (d65.x - 0.95047).abs() < 5e-4 && (d65.z - 1.08883).abs() < 5e-4,
        "{d65:?}"
    );
}

/// CIELAB of the 24 ColorChecker spectra lit by `illuminant` (CIE 1931 2°),
/// relative to the white of the same illuminant.
fn colorchecker_lab(illuminant: &str) -> Vec<Lab> {
    let light = Builtin::lookup(illuminant).unwrap().tabulated().unwrap();
    let range = SpectralRange::VISIBLE;
    let white = reference_xyz(&light, &range);
    (1..=24)
        .map(|patch| {
            let reflectance = Builtin::lookup(&format!("colorchecker-{patch}"))
                .unwrap()
                .tabulated()
                .unwrap();
            // Reflected radiance resampled on the 1 nm CMF grid.
            let nm: Vec<f64> = (0..cmf::SAMPLES)
                .map(|i| cmf::FIRST_NM + i as f64)
                .collect();
            let product: Vec<f64> = nm
                .iter()
                .map(|&l| {
                    use spectral_core::Spectrum;
                    light.value(l) * reflectance.value(l)
                })
                .collect();
            let radiance = spectral_core::TabulatedSpectrum::new(&nm, &product).unwrap();
            reference_xyz(&radiance, &range).to_lab(white)
        })
        .collect()
}

/// `data/colorchecker_lab_d50.csv`: (patch name, published CIELAB).
fn published_colorchecker_lab() -> Vec<(String, Lab)> {
    let text = data_file("colorchecker_lab_d50.csv");
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|line| {
            let cells: Vec<&str> = line.split(',').map(str::trim).collect();
            assert_eq!(cells.len(), 4, "{line}");
            let v: Vec<f64> = cells[1..].iter().map(|c| c.parse().unwrap()).collect();
            (cells[0].to_string(), Lab::new(v[0], v[1], v[2]))
        })
        .collect()
}

/// Every patch against X-Rite's published CIELAB (D50, 2°; the pre-November
/// 2014 chart formulation, which matches GretagMacbeth's 2005 data), with
/// the colorimetry the publisher used: the D50 spectrum times the
/// reflectance, the CIE 1931 2° observer, the white of D50 (no chromatic
/// adaptation: X-Rite computes D50 values from measured spectra directly).
///
/// The spectra (Ohta 1997 = ISO 17321-1) are the measurement of a chart
/// of 1997, the published values X-Rite's reference for its production
/// charts, so the two disagree by about a ΔE2000 per patch for that
/// reason (different physical charts), not by our colorimetry. Measured
/// (2026-12-02): mean 0.97, max 1.70 (orange); 0.43 (yellow green) to 1.70
/// per patch, 12 patches above 1. The limits sit a small margin above:
/// max 2.0, mean 1.1. For comparison, the same spectra against the
/// post-November-2014 values: mean 1.24, max 2.38; and adapted from D65 by
/// Bradford instead of lit by D50: mean 1.10, max 2.07 — so both the data
/// set and the direct D50 colorimetry are the consistent choices.
#[test]
fn colorchecker_lab_under_d50_matches_published_values() {
    const MAX_DELTA_E: f64 = 2.0;
    const MEAN_DELTA_E: f64 = 1.1;
    let computed = colorchecker_lab("d50");
    let published = published_colorchecker_lab();
    assert_eq!(published.len(), 24);
    assert_eq!(computed.len(), 24);
    let mut sum = 0.0;
    for ((name, expected), (got, our_name)) in published
        .iter()
        .zip(computed.iter().zip(COLORCHECKER_NAMES))
    {
        assert_eq!(name, our_name, "patch order");
        let de = delta_e2000(*got, *expected);
        println!(
            "{name:>22}: computed ({:6.2} {:6.2} {:6.2}) published ({:6.2} {:6.2} {:6.2}) ΔE2000 {de:.2}",
            got.l, got.a, got.b, expected.l, expected.a, expected.b
        );
        assert!(
            de <= MAX_DELTA_E,
            "{name}: ΔE2000 {de:.3} > {MAX_DELTA_E}: computed {got:?}, published {expected:?}"
        );
        sum += de;
    }
    let mean = sum / 24.0;
    println!("mean ΔE2000 {mean:.3}");
    assert!(
        mean <= MEAN_DELTA_E,
        "mean ΔE2000 {mean:.3} > {MEAN_DELTA_E}"
    );
}

#[test]
fn ciede2000_sharma_pairs() {
    let text = data_file("ciede2000_sharma.csv");
    let mut pairs = 0;
    for line in text.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let v: Vec<f64> = line.split(',').map(|c| c.trim().parse().unwrap()).collect();
        let lab1 = Lab::new(v[1], v[2], v[3]);
        let lab2 = Lab::new(v[4], v[5], v[6]);
        let expected = v[7];
        let got = delta_e2000(lab1, lab2);
        assert!(
            (got - expected).abs() < 1e-4,
            "pair {}: {got} vs {expected}",
            v[0]
        );
        assert!(
            (delta_e2000(lab2, lab1) - expected).abs() < 1e-4,
            "pair {} swapped",
            v[0]
        );
        pairs += 1;
    }
    assert_eq!(pairs, 34);
}

#[test]
fn delta_e76_is_euclidean() {
    let a = Lab::new(50.0, 2.6772, -79.7751);
    let b = Lab::new(50.0, 0.0, -82.7485);
    let expected = (2.6772f64.powi(2) + (82.7485f64 - 79.7751).powi(2)).sqrt();
    assert!((delta_e76(a, b) - expected).abs() < 1e-12);
}

#[test]
fn srgb_white_of_d65_is_neutral() {
    let d65 = white_point(&Builtin::lookup("d65").unwrap()).unwrap();
    let rgb = d65.to_linear_srgb();
    for v in [rgb.r, rgb.g, rgb.b] {
        assert!((v - 1.0).abs() < 2e-3, "{rgb:?}");
    }
}

#[test]
fn sigmoid_table_is_fresh() {
    // Refit the RGB → spectrum table and compare with the committed bytes
    // (to 1e-4: the platform's cbrt may differ in the last ulp).
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let fresh = datagen::generate_sigmoid_table(threads).unwrap();
    let committed = std::fs::read(datagen::sigmoid_table_path()).unwrap();
    assert_eq!(
        fresh.len(),
        committed.len(),
        "run `cargo run --release -p datagen`"
    );
    let as_f32 = |b: &[u8]| f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    for (i, (a, b)) in fresh.chunks(4).zip(committed.chunks(4)).enumerate() {
        let (a, b) = (as_f32(a), as_f32(b));
        assert!(
            (a - b).abs() <= 1e-4 * (1.0 + a.abs()),
            "coefficient {i}: fresh {a}, committed {b}: run `cargo run --release -p datagen`"
        );
    }
}
