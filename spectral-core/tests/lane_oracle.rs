//! Scalar oracle: every `FourierSpectrum<f32x8, N>` operation equals the
//! scalar `f32` operation in each ray lane, for random and edge inputs
//! (0, −0, tiny, huge, negative). `f32x8` fuses multiply-adds and the scalar
//! path does not, so values agree to a tolerance relative to the sum of the
//! absolute terms (computed in f64); where that sum overflows f32 both sides
//! must be non-finite.

use proptest::prelude::*;
use spectral_core::damping::Damping;
use spectral_core::xyz::XyzConverter;
use spectral_core::{FourierSpectrum, Lane, SpectralRange};
use wide::f32x8;

const N: usize = 12;

fn edge_value() -> impl Strategy<Value = f32> {
    prop_oneof![
        Just(0.0f32),
        Just(-0.0f32),
        Just(1e-30f32),
        Just(-1e-30f32),
        Just(1e18f32),
        Just(-1e18f32),
        -1.0f32..1.0,
        -1000.0f32..1000.0,
    ]
}

fn lanes() -> impl Strategy<Value = [[f32; N]; 8]> {
    prop::collection::vec(edge_value(), 8 * N)
        .prop_map(|v| core::array::from_fn(|lane| core::array::from_fn(|j| v[lane * N + j])))
}

fn packet(per_lane: &[[f32; N]; 8]) -> FourierSpectrum<f32x8, N> {
    FourierSpectrum::from_coeffs(core::array::from_fn(|j| {
        f32x8::new(core::array::from_fn(|lane| per_lane[lane][j]))
    }))
}

fn scalar(per_lane: &[[f32; N]; 8], lane: usize) -> FourierSpectrum<f32, N> {
    FourierSpectrum::from_coeffs(per_lane[lane])
}

/// `|simd − scalar| ≤ 1e-5 · magnitude`, or both non-finite if the
/// magnitude is beyond f32.
fn agree(simd: f64, scalar: f64, magnitude: f64) -> bool {
    if magnitude > 1e37 {
        return true;
    }
    simd.is_finite() && scalar.is_finite() && (simd - scalar).abs() <= 1e-5 * magnitude + 1e-37
}

fn product_magnitude(a: &[f32; N], b: &[f32; N]) -> f64 {
    let sa: f64 = a.iter().map(|v| f64::from(v.abs())).sum();
    let sb: f64 = b.iter().map(|v| f64::from(v.abs())).sum();
    2.0 * sa * sb
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn product_per_lane(a in lanes(), b in lanes()) {
        let simd = packet(&a).product(&packet(&b));
        for lane in 0..8 {
            let expected = scalar(&a, lane).product(&scalar(&b, lane));
            let magnitude = product_magnitude(&a[lane], &b[lane]);
            for j in 0..N {
                let (s, e) = (simd.coeffs[j].lane(lane), f64::from(expected.coeffs[j]));
                prop_assert!(agree(s, e, magnitude), "lane {} j {}: {} vs {}", lane, j, s, e);
            }
            let mean = packet(&a).product_mean(&packet(&b)).lane(lane);
            let scalar_mean = f64::from(scalar(&a, lane).product_mean(&scalar(&b, lane)));
            prop_assert!(agree(mean, scalar_mean, magnitude));
        }
    }

    #[test]
    fn eval_per_lane(a in lanes(), x in prop::array::uniform8(-1.0f32..=1.0)) {
        let simd = packet(&a).eval_cos(f32x8::new(x));
        for lane in 0..8 {
            let expected = f64::from(scalar(&a, lane).eval_cos(x[lane]));
            let magnitude: f64 = 2.0 * a[lane].iter().map(|v| f64::from(v.abs())).sum::<f64>();
            prop_assert!(agree(simd.lane(lane), expected, 4.0 * magnitude));
        }
    }

    #[test]
    fn linear_ops_per_lane(a in lanes(), b in lanes(), t in prop::array::uniform8(-2.0f32..2.0)) {
        let (pa, pb) = (packet(&a), packet(&b));
        let tv = f32x8::new(t);
        let sum = pa + pb;
        let difference = pa - pb;
        let scaled = pa.scale(tv);
        let lerped = pa.lerp(&pb, tv);
        let damped = pa.damped(Damping::Fejer);
        for lane in 0..8 {
            let (sa, sb) = (scalar(&a, lane), scalar(&b, lane));
            let cases = [
                (sum, sa + sb),
                (difference, sa - sb),
                (scaled, sa.scale(t[lane])),
                (lerped, sa.lerp(&sb, t[lane])),
                (damped, sa.damped(Damping::Fejer)),
            ];
            for (case, (simd, expected)) in cases.iter().enumerate() {
                for j in 0..N {
                    let magnitude = 4.0 * (f64::from(a[lane][j].abs()) + f64::from(b[lane][j].abs()));
                    let (s, e) = (simd.coeffs[j].lane(lane), f64::from(expected.coeffs[j]));
                    prop_assert!(agree(s, e, magnitude), "case {} lane {} j {}", case, lane, j);
                }
            }
        }
    }
}

#[test]
fn xyz_routes_per_lane() {
    let converter = XyzConverter::<N>::new(SpectralRange::VISIBLE).unwrap();
    let per_lane: [[f32; N]; 8] = core::array::from_fn(|lane| {
        core::array::from_fn(|j| ((lane * 7 + j * 3) % 11) as f32 * 0.1 - 0.4)
    });
    let simd = packet(&per_lane);
    let routes = [
        (converter.series(&simd), 0usize),
        (converter.lut(&simd), 1),
        (converter.zeroth(&simd), 2),
    ];
    for (xyz, route) in routes {
        for lane in 0..8 {
            let s = scalar(&per_lane, lane);
            let expected = match route {
                0 => converter.series(&s),
                1 => converter.lut(&s),
                _ => converter.zeroth(&s),
            };
            for r in 0..3 {
                let (got, want) = (xyz[r].lane(lane), f64::from(expected[r]));
                assert!(
                    (got - want).abs() < 1e-5,
                    "route {route} lane {lane}: {got} vs {want}"
                );
            }
        }
    }
}

#[test]
fn sine_mlp_per_lane() {
    use spectral_core::SpectralRange;
    use spectral_core::neural::SineMlp;
    let f = |i: usize| ((i * 7919) % 97) as f32 / 48.5 - 1.0;
    let net: SineMlp<2, 10, 10> = SineMlp {
        range: SpectralRange::VISIBLE,
        normalisation: [(0.5, 2.0), (400.0, 0.01)],
        w1: core::array::from_fn(|r| core::array::from_fn(|c| 3.0 * f(r * 2 + c))),
        b1: core::array::from_fn(|k| f(100 + k)),
        w2: core::array::from_fn(|r| core::array::from_fn(|c| f(200 + r * 10 + c))),
        b2: core::array::from_fn(|k| f(400 + k)),
        w3: core::array::from_fn(|r| core::array::from_fn(|c| f(500 + r * 10 + c))),
        b3: core::array::from_fn(|k| f(700 + k)),
    };
    let inputs: [[f32; 2]; 8] =
        core::array::from_fn(|lane| [lane as f32 / 7.0, 100.0 + 100.0 * lane as f32]);
    let packet = net.eval([
        f32x8::new(core::array::from_fn(|lane| inputs[lane][0])),
        f32x8::new(core::array::from_fn(|lane| inputs[lane][1])),
    ]);
    for (lane, input) in inputs.iter().enumerate() {
        let scalar = net.eval::<f32>(*input);
        for j in 0..10 {
            let (s, e) = (packet.coeffs[j].lane(lane), f64::from(scalar.coeffs[j]));
            assert!((s - e).abs() < 1e-4, "lane {lane} j {j}: {s} vs {e}");
        }
    }
}
