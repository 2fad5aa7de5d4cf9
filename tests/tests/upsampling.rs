//! RGB → spectrum → XYZ → sRGB round trips over the sRGB gamut (17³ grid),
//! against the targets of MATH.md §6 / issue 3: mean ΔE2000 < 0.1, max < 1.

use spectral_core::color::{LinearSrgb, Xyz};
use spectral_core::delta_e::delta_e2000;
use spectral_core::registry::Builtin;
use spectral_core::upsample::{RgbIlluminant, RgbUnbounded, srgb_reflectance};
use spectral_core::xyz::{white_point, xyz_of};
use spectral_core::{SpectralRange, Spectrum};

/// XYZ of `reflectance` under D65, normalised so the perfect white has Y = 1.
fn xyz_under_d65(reflectance: &impl Spectrum) -> Xyz {
    let d65 = Builtin::lookup("d65").unwrap();
    struct Lit<'a, S: Spectrum>(&'a S, Builtin);
    impl<S: Spectrum> Spectrum for Lit<'_, S> {
        fn value(&self, l: f64) -> f64 {
            self.0.value(l) * self.1.value(l)
        }
    }
    let range = SpectralRange::VISIBLE;
    let white_y = xyz_of(&d65, &range).y;
    xyz_of(&Lit(reflectance, d65), &range).scale(1.0 / white_y)
}

#[test]
fn reflectance_round_trip_over_the_gamut() {
    let white = white_point(&Builtin::lookup("d65").unwrap()).unwrap();
    let steps = 17;
    let (mut sum, mut max, mut worst) = (0.0f64, 0.0f64, [0.0; 3]);
    let mut count = 0;
    for r in 0..steps {
        for g in 0..steps {
            for b in 0..steps {
                let rgb = [r, g, b].map(|v| v as f64 / (steps - 1) as f64);
                let target = LinearSrgb::new(rgb[0], rgb[1], rgb[2]).to_xyz();
                let spectrum = srgb_reflectance(rgb).unwrap();
                let round_trip = xyz_under_d65(&spectrum);
                let de = delta_e2000(target.to_lab(white), round_trip.to_lab(white));
                sum += de;
                if de > max {
                    max = de;
                    worst = rgb;
                }
                count += 1;
            }
        }
    }
    let mean = sum / count as f64;
    println!(
        "sRGB round trip over {count} colours: mean ΔE2000 {mean:.4}, max {max:.4} at {worst:?}"
    );
    assert!(mean < 0.1, "mean {mean}");
    assert!(max < 1.0, "max {max} at {worst:?}");
}

#[test]
fn unbounded_and_illuminant_variants_keep_their_colour() {
    let white = white_point(&Builtin::lookup("d65").unwrap()).unwrap();
    let range = SpectralRange::VISIBLE;
    // Unbounded: the emission spectrum seen under an equal-energy observer
    // reproduces the colour of the scaled reflectance.
    for rgb in [[18.387, 13.9873, 6.75357], [0.2, 3.0, 0.5], [5.0, 5.0, 5.0]] {
        let light = RgbIlluminant::new(rgb).unwrap();
        let xyz = xyz_of(&light, &range);
        let expected = LinearSrgb::new(rgb[0], rgb[1], rgb[2]).to_xyz();
        let scale = rgb.iter().cloned().fold(0.0, f64::max);
        let de = delta_e2000(
            expected.scale(1.0 / scale).to_lab(white),
            xyz.scale(1.0 / scale).to_lab(white),
        );
        assert!(de < 1.0, "{rgb:?}: ΔE {de}");
        let unbounded = RgbUnbounded::new(rgb).unwrap();
        let peak = (360..=830)
            .map(|l| unbounded.value(l as f64))
            .fold(0.0, f64::max);
        assert!(peak <= 2.0 * scale + 1e-9);
    }
    // The illuminant white (1, 1, 1) is D65 with Y = 1.
    let xyz = xyz_of(&RgbIlluminant::new([1.0; 3]).unwrap(), &range);
    assert!((xyz.y - 1.0).abs() < 1e-9, "{xyz:?}");
    let [x, y] = xyz.chromaticity();
    let [wx, wy] = white.chromaticity();
    assert!((x - wx).abs() < 1e-9 && (y - wy).abs() < 1e-9);
}
