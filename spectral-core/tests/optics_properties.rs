//! Physical identities of the Fresnel and thin-film code.

use proptest::prelude::*;
use spectral_core::complex::Complex;
use spectral_core::optics::{Layer, airy_film, fresnel_conductor, fresnel_dielectric, multilayer};

fn lossless_layer() -> impl Strategy<Value = Layer> {
    (1.0f64..2.8, 0.0f64..800.0).prop_map(|(n, d)| Layer {
        index: Complex::real(n),
        thickness_nm: d,
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn lossless_stacks_conserve_energy(
        layers in prop::collection::vec(lossless_layer(), 0..6),
        substrate in 1.0f64..2.5,
        incident in 1.0f64..1.6,
        cos_i in 0.01f64..1.0,
        lambda_nm in 360.0f64..830.0,
    ) {
        let r = multilayer(lambda_nm, incident, &layers, Complex::real(substrate), cos_i);
        prop_assert!((r.reflectance_s + r.transmittance_s - 1.0).abs() < 1e-9, "{:?}", r);
        prop_assert!((r.reflectance_p + r.transmittance_p - 1.0).abs() < 1e-9, "{:?}", r);
        if let Some(&first) = layers.first() {
            let a = airy_film(lambda_nm, incident, first, Complex::real(substrate), cos_i);
            prop_assert!((a.reflectance() + a.transmittance() - 1.0).abs() < 1e-9, "{:?}", a);
        }
    }

    #[test]
    fn airy_equals_one_layer_stack_for_absorbing_media(
        n2 in 0.2f64..3.0, k2 in 0.0f64..3.0, d in 0.0f64..500.0,
        n3 in 0.2f64..3.0, k3 in 0.0f64..4.0,
        cos_i in 0.0f64..1.0, lambda_nm in 360.0f64..830.0,
    ) {
        let film = Layer { index: Complex::new(n2, k2), thickness_nm: d };
        let substrate = Complex::new(n3, k3);
        let a = airy_film(lambda_nm, 1.0, film, substrate, cos_i);
        let m = multilayer(lambda_nm, 1.0, &[film], substrate, cos_i);
        prop_assert!((a.reflectance_s - m.reflectance_s).abs() < 1e-9);
        prop_assert!((a.reflectance_p - m.reflectance_p).abs() < 1e-9);
        if cos_i > 1e-6 {
            prop_assert!((a.transmittance_s - m.transmittance_s).abs() < 1e-9);
            prop_assert!((a.transmittance_p - m.transmittance_p).abs() < 1e-9);
        }
        // Absorption never creates energy.
        prop_assert!(a.reflectance() + a.transmittance() <= 1.0 + 1e-9);
        prop_assert!(a.reflectance() >= 0.0 && a.transmittance() >= -1e-12);
    }

    #[test]
    fn zero_thickness_film_is_the_bare_interface(
        n2 in 1.0f64..3.0, n3 in 1.0f64..2.5, k3 in 0.0f64..3.0, cos_i in 0.0f64..1.0,
    ) {
        let film = Layer { index: Complex::real(n2), thickness_nm: 0.0 };
        let substrate = Complex::new(n3, k3);
        let a = airy_film(550.0, 1.0, film, substrate, cos_i);
        let bare = fresnel_conductor(cos_i, substrate);
        prop_assert!((a.reflectance() - bare).abs() < 1e-9);
        let empty = multilayer(550.0, 1.0, &[], substrate, cos_i);
        prop_assert!((empty.reflectance() - bare).abs() < 1e-9);
        if k3 == 0.0 {
            prop_assert!((bare - fresnel_dielectric(cos_i, n3)).abs() < 1e-9);
        }
    }

    #[test]
    fn splitting_a_layer_changes_nothing(
        n in 1.2f64..2.5, d1 in 0.0f64..300.0, d2 in 0.0f64..300.0,
        cos_i in 0.0f64..1.0, lambda_nm in 360.0f64..830.0,
    ) {
        let index = Complex::real(n);
        let whole = [Layer { index, thickness_nm: d1 + d2 }];
        let split = [Layer { index, thickness_nm: d1 }, Layer { index, thickness_nm: d2 }];
        let substrate = Complex::real(1.5);
        let a = multilayer(lambda_nm, 1.0, &whole, substrate, cos_i);
        let b = multilayer(lambda_nm, 1.0, &split, substrate, cos_i);
        prop_assert!((a.reflectance() - b.reflectance()).abs() < 1e-9);
    }
}

/// Regression (found by `fspec train --evidence` at θ = 90°, where
/// `cos θ = 6·10⁻¹⁷`): near-grazing cosines gave NaN through an infinite p
/// admittance. Reflectances must stay finite, in [0, 1], and tend to 1.
#[test]
fn near_grazing_incidence_is_finite_and_tends_to_total_reflection() {
    let angle_90 = 90f64.to_radians().cos();
    for cos_i in [
        0.0, 1e-300, 1e-17, angle_90, 1e-12, 1e-9, 1.4e-8, 1e-7, 2e-7, 1e-6,
    ] {
        for (incident, substrate) in [(1.0, 1.5), (1.0, 1.0), (1.5, 1.0), (1.33, 1.33)] {
            let layer = Layer {
                index: Complex::real(2.0),
                thickness_nm: 400.0,
            };
            let film = Complex::real(substrate);
            for r in [
                multilayer(550.0, incident, &[layer], film, cos_i),
                multilayer(550.0, incident, &[layer, layer], film, cos_i),
                multilayer(550.0, incident, &[], film, cos_i),
                airy_film(550.0, incident, layer, film, cos_i),
            ] {
                let values = [
                    r.reflectance_s,
                    r.reflectance_p,
                    r.transmittance_s,
                    r.transmittance_p,
                ];
                assert!(
                    values
                        .iter()
                        .all(|v| v.is_finite() && (-1e-9..=1.0 + 1e-9).contains(v)),
                    "cos {cos_i:e}, n {incident}/{substrate}: {r:?}"
                );
                // 1 − R = O(cos θ) near grazing, except for a matched
                // interface without a film, which transmits everything.
                if cos_i <= 1e-6 && incident != substrate {
                    assert!(r.reflectance() > 0.99, "cos {cos_i:e}: {r:?}");
                }
            }
        }
    }
}
