//! Scalar oracle: every `FourierSpectrum<f32x8, N>` operation equals the
//! scalar `f32` operation in each ray lane, for random and edge inputs
//! (0, −0, tiny, huge, negative) and, in the `*_non_finite` tests, for inputs
//! that overflow f32 or are infinite or NaN.
//!
//! How two lanes are compared ([`agree`]):
//!
//! * Operations without a multiply-add (sum, difference, scale, damping) run
//!   the same correctly rounded IEEE operation in both, so they must agree
//!   bit for bit (NaN with NaN).
//! * `f32x8` fuses multiply-adds and the scalar path does not, so results of
//!   operations with multiply-adds differ by rounding. Both finite: they must
//!   agree to a bound derived per operation from the rounding-error analysis
//!   of each side ([`Tolerance`]), relative to the sum `M` of the absolute
//!   values of the terms (computed in f64) plus a floor for underflow. The
//!   bound scales with `M`, so it holds for huge magnitudes as for small.
//! * Both non-finite: they must be the same kind (NaN, +∞ or −∞).
//! * One finite and one not, or different kinds: allowed only where an
//!   intermediate of that output can reach the f32 overflow threshold, i.e.
//!   where `M` over the terms with finite operands is at least `f32::MAX`:
//!   there a separately rounded product can overflow where the fused one
//!   does not (or the reverse, at the threshold). Below it no intermediate
//!   of either side can overflow, and infinities and NaNs of the inputs
//!   propagate through a multiply-add the same whether it is fused or not.

use proptest::prelude::*;
use spectral_core::damping::Damping;
use spectral_core::xyz::XyzConverter;
use spectral_core::{FourierBasis, FourierSpectrum, Lane};
use wide::f32x8;

const N: usize = 12;

/// Unit roundoff of f32 (round to nearest): every rounding of a finite
/// result `r` errs by at most `U |r|` (or underflows, see [`TINY`]).
const U: f64 = f32::EPSILON as f64 / 2.0;

/// The smallest positive subnormal f32, 2⁻¹⁴⁹. Under gradual underflow a
/// rounding errs by at most 2⁻¹⁵⁰ more than the relative bound (additions
/// of subnormals are exact), so each possibly underflowing rounding of
/// either side adds `TINY / 2`, and of both sides `TINY`.
const TINY: f64 = f32::from_bits(1) as f64;

/// `γ_n = n U / (1 − n U)`: a chain of `n` roundings multiplies a term by
/// at most `1 + γ_n` (Higham, *Accuracy and Stability of Numerical
/// Algorithms*, lemma 3.1), so a sum of products computed in any order with
/// at most `n` roundings per term errs by at most `γ_n M` on each side.
fn gamma(n: usize) -> f64 {
    let nu = n as f64 * U;
    nu / (1.0 - nu)
}

/// How far one output lane of `f32x8` may be from the scalar oracle.
#[derive(Clone, Copy, Debug)]
enum Tolerance {
    /// Both sides run the same correctly rounded IEEE operation: bit for bit.
    Exact,
    /// Multiply-adds, fused on one side only (module docs).
    Rounding {
        /// The largest `|simd − scalar|` when both are finite.
        abs: f64,
        /// Whether an intermediate of this output can reach the f32
        /// overflow threshold (module docs).
        may_overflow: bool,
    },
}

impl Tolerance {
    /// `relative · M + roundings · TINY`, for `M` the sum of the absolute
    /// terms with finite operands and `relative` the bound of both sides
    /// together. Every product and partial sum of either side is at most
    /// `(1 + relative) M` in magnitude, so below `f32::MAX` none overflows.
    fn rounding(relative: f64, magnitude: f64, roundings: usize) -> Self {
        Self::Rounding {
            abs: relative * magnitude + roundings as f64 * TINY,
            may_overflow: magnitude * (1.0 + relative) >= f64::from(f32::MAX),
        }
    }
}

/// The comparison of the module docs.
fn agree(simd: f64, scalar: f64, tolerance: Tolerance) -> bool {
    let same_kind = (simd.is_nan() && scalar.is_nan()) || simd == scalar;
    match tolerance {
        Tolerance::Exact => {
            simd.to_bits() == scalar.to_bits() || (simd.is_nan() && scalar.is_nan())
        }
        Tolerance::Rounding { abs, may_overflow } => match (simd.is_finite(), scalar.is_finite()) {
            (true, true) => (simd - scalar).abs() <= abs,
            (false, false) if same_kind => true,
            _ => may_overflow,
        },
    }
}

/// `|x y|` in f64 (exact for f32 operands), or 0 if an operand is not
/// finite: such a term makes the output non-finite alike on both sides.
fn term(x: f32, y: f32) -> f64 {
    if x.is_finite() && y.is_finite() {
        f64::from(x.abs()) * f64::from(y.abs())
    } else {
        0.0
    }
}

/// `h_k = Σ_p c_p (d_{|k−p|} + [p ≥ 1, k + p < N] d_{k+p})` (the truncated
/// product, `spectral_core::fourier` module docs) on each side runs at most
/// `2N` roundings per term (the loop form: one multiply and one add per
/// Toeplitz and per Hankel term, `2N − 1` terms; the codelets round less),
/// of which at most `2N` products may underflow.
fn product_tolerance(c: &[f32; N], d: &[f32; N], k: usize) -> Tolerance {
    let magnitude: f64 = (0..N)
        .map(|p| {
            let hankel = if p >= 1 && k + p < N {
                term(c[p], d[k + p])
            } else {
                0.0
            };
            term(c[p], d[k.abs_diff(p)]) + hankel
        })
        .sum();
    Tolerance::rounding(2.0 * gamma(2 * N), magnitude, 2 * N)
}

/// `h_0 = c_0 d_0 + 2 Σ_{j≥1} c_j d_j`: at most `N + 1` roundings per term
/// (multiply, the running sum, the final add) and `N` products.
fn product_mean_tolerance(c: &[f32; N], d: &[f32; N]) -> Tolerance {
    let magnitude = term(c[0], d[0]) + 2.0 * (1..N).map(|j| term(c[j], d[j])).sum::<f64>();
    Tolerance::rounding(2.0 * gamma(N + 1), magnitude, N)
}

/// `c_0 + 2 Σ_{j≥1} c_j T_j(x)` with `T_j` from the recurrence
/// `t_{j+1} = 2x t_j − t_{j−1}`, `|x| ≤ 1`. One step errs by at most `3U`
/// separately rounded (`U |2x t_j| + U |t_{j+1}|`, `|T| ≤ 1`), `U` fused; an
/// error made in `t_{i+1}` reaches `t_j` multiplied by the Chebyshev
/// polynomial of the second kind `U_{j−i−1}(x)`, `|U_n| ≤ n + 1`, so
/// `|t̂_j − T_j| ≤ 3U j(j − 1)/2`, taken as `4U` per step to cover
/// `|t̂| > 1` by that much. With `M = |c_0| + 2 Σ |c_j|` each side is within
/// `(ε + γ_{N+1})(1 + ε) M` of the exact series, `ε` the recurrence bound at
/// `j = N − 1` and `γ_{N+1}` the sum's roundings; `N` products may
/// underflow.
fn eval_tolerance(c: &[f32; N]) -> Tolerance {
    let finite = |v: f32| {
        if v.is_finite() {
            f64::from(v.abs())
        } else {
            0.0
        }
    };
    let magnitude = finite(c[0]) + 2.0 * c[1..].iter().map(|&v| finite(v)).sum::<f64>();
    let recurrence = 4.0 * U * ((N - 1) * (N - 2) / 2) as f64;
    let per_side = (recurrence + gamma(N + 1)) * (1.0 + recurrence);
    Tolerance::rounding(2.0 * per_side, magnitude, N)
}

/// `t (b − a) + a`: `D = fl(b − a)` is common to both sides; fused
/// `(tD + a)(1 + δ₁)`, separate `(tD(1 + δ₂) + a)(1 + δ₃)` differ by at most
/// `2U |tD + a| + U(1 + U)|tD| ≤ 3U(1 + U)² M < 4U M`,
/// `M = |t| (|a| + |b|) + |a|`; one product may underflow.
fn lerp_tolerance(a: f32, b: f32, t: f32) -> Tolerance {
    let magnitude = if a.is_finite() && b.is_finite() && t.is_finite() {
        f64::from(t.abs()) * (f64::from(a.abs()) + f64::from(b.abs())) + f64::from(a.abs())
    } else {
        0.0
    };
    Tolerance::rounding(4.0 * U, magnitude, 1)
}

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

/// Edge values plus values whose products or sums overflow f32 (1e19² · 2
/// exceeds `f32::MAX` ≈ 3.4e38) and non-finite values, about one input in
/// twenty non-finite so that many lanes still have finite results.
fn wild_value() -> impl Strategy<Value = f32> {
    prop_oneof![
        16 => edge_value(),
        3 => prop::sample::select(vec![1e19f32, -1e19, 1.5e19, -1.5e19, f32::MAX, -f32::MAX]),
        1 => prop::sample::select(vec![f32::INFINITY, f32::NEG_INFINITY, f32::NAN]),
    ]
}

fn lanes_of(value: impl Strategy<Value = f32>) -> impl Strategy<Value = [[f32; N]; 8]> {
    prop::collection::vec(value, 8 * N)
        .prop_map(|v| core::array::from_fn(|lane| core::array::from_fn(|j| v[lane * N + j])))
}

fn lanes() -> impl Strategy<Value = [[f32; N]; 8]> {
    lanes_of(edge_value())
}

fn wild_lanes() -> impl Strategy<Value = [[f32; N]; 8]> {
    lanes_of(wild_value())
}

fn packet(per_lane: &[[f32; N]; 8]) -> FourierSpectrum<f32x8, N> {
    FourierSpectrum::from_coeffs(core::array::from_fn(|j| {
        f32x8::new(core::array::from_fn(|lane| per_lane[lane][j]))
    }))
}

fn scalar(per_lane: &[[f32; N]; 8], lane: usize) -> FourierSpectrum<f32, N> {
    FourierSpectrum::from_coeffs(per_lane[lane])
}

/// With finite inputs whose `M` stays below `f32::MAX` the results must be
/// finite, so every lane is compared as a value (and none slips through as
/// a pair of equal non-finite values).
fn require_finite(expected: f64, tolerance: Tolerance, what: &str) -> Result<(), TestCaseError> {
    if let Tolerance::Rounding {
        may_overflow: true, ..
    } = tolerance
    {
        return Err(TestCaseError::fail(format!(
            "{what}: finite inputs reach f32::MAX"
        )));
    }
    prop_assert!(
        expected.is_finite(),
        "{}: {} from finite inputs",
        what,
        expected
    );
    Ok(())
}

fn check_product(a: &[[f32; N]; 8], b: &[[f32; N]; 8], finite: bool) -> Result<(), TestCaseError> {
    let simd = packet(a).product(&packet(b));
    let simd_mean = packet(a).product_mean(&packet(b));
    for lane in 0..8 {
        let expected = scalar(a, lane).product(&scalar(b, lane));
        for j in 0..N {
            let (s, e) = (simd.coeffs[j].lane(lane), f64::from(expected.coeffs[j]));
            let tolerance = product_tolerance(&a[lane], &b[lane], j);
            if finite {
                require_finite(e, tolerance, "product")?;
            }
            prop_assert!(
                agree(s, e, tolerance),
                "product lane {} j {}: {} vs {} ({:?})",
                lane,
                j,
                s,
                e,
                tolerance
            );
        }
        let mean = simd_mean.lane(lane);
        let expected_mean = f64::from(scalar(a, lane).product_mean(&scalar(b, lane)));
        let tolerance = product_mean_tolerance(&a[lane], &b[lane]);
        if finite {
            require_finite(expected_mean, tolerance, "product_mean")?;
        }
        prop_assert!(
            agree(mean, expected_mean, tolerance),
            "product_mean lane {}: {} vs {} ({:?})",
            lane,
            mean,
            expected_mean,
            tolerance
        );
    }
    Ok(())
}

fn check_eval(a: &[[f32; N]; 8], x: [f32; 8], finite: bool) -> Result<(), TestCaseError> {
    let simd = packet(a).eval_cos(f32x8::new(x));
    for lane in 0..8 {
        let (s, e) = (
            simd.lane(lane),
            f64::from(scalar(a, lane).eval_cos(x[lane])),
        );
        let tolerance = eval_tolerance(&a[lane]);
        if finite {
            require_finite(e, tolerance, "eval_cos")?;
        }
        prop_assert!(
            agree(s, e, tolerance),
            "eval_cos lane {}: {} vs {} ({:?})",
            lane,
            s,
            e,
            tolerance
        );
    }
    Ok(())
}

fn check_linear_ops(
    a: &[[f32; N]; 8],
    b: &[[f32; N]; 8],
    t: [f32; 8],
    finite: bool,
) -> Result<(), TestCaseError> {
    let (pa, pb) = (packet(a), packet(b));
    let tv = f32x8::new(t);
    let simd = [
        pa + pb,
        pa - pb,
        pa.scale(tv),
        pa.lerp(&pb, tv),
        pa.damped(Damping::Fejer),
    ];
    for lane in 0..8 {
        let (sa, sb) = (scalar(a, lane), scalar(b, lane));
        let expected = [
            sa + sb,
            sa - sb,
            sa.scale(t[lane]),
            sa.lerp(&sb, t[lane]),
            sa.damped(Damping::Fejer),
        ];
        for (case, (simd, expected)) in simd.iter().zip(&expected).enumerate() {
            for j in 0..N {
                let (s, e) = (simd.coeffs[j].lane(lane), f64::from(expected.coeffs[j]));
                let tolerance = if case == 3 {
                    lerp_tolerance(a[lane][j], b[lane][j], t[lane])
                } else {
                    Tolerance::Exact
                };
                if finite {
                    require_finite(e, tolerance, "linear op")?;
                }
                prop_assert!(
                    agree(s, e, tolerance),
                    "case {} lane {} j {}: {} vs {} ({:?})",
                    case,
                    lane,
                    j,
                    s,
                    e,
                    tolerance
                );
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn product_per_lane(a in lanes(), b in lanes()) {
        check_product(&a, &b, true)?;
    }

    #[test]
    fn eval_per_lane(a in lanes(), x in prop::array::uniform8(-1.0f32..=1.0)) {
        check_eval(&a, x, true)?;
    }

    #[test]
    fn linear_ops_per_lane(a in lanes(), b in lanes(), t in prop::array::uniform8(-2.0f32..2.0)) {
        check_linear_ops(&a, &b, t, true)?;
    }

    #[test]
    fn product_per_lane_non_finite(a in wild_lanes(), b in wild_lanes()) {
        check_product(&a, &b, false)?;
    }

    #[test]
    fn eval_per_lane_non_finite(a in wild_lanes(), x in prop::array::uniform8(-1.0f32..=1.0)) {
        check_eval(&a, x, false)?;
    }

    #[test]
    fn linear_ops_per_lane_non_finite(
        a in wild_lanes(),
        b in wild_lanes(),
        t in prop::array::uniform8(wild_value()),
    ) {
        check_linear_ops(&a, &b, t, false)?;
    }
}

/// The comparison itself: what it accepts and rejects.
#[test]
fn agree_rules() {
    let bound = Tolerance::rounding(1e-6, 1e30, 0);
    let near_max = Tolerance::rounding(1e-6, f64::from(f32::MAX), 0);
    // Finite values: relative to M, at any magnitude, no skip.
    assert!(agree(1e30 + 0.5e24, 1e30, bound));
    assert!(!agree(1e30 + 2e24, 1e30, bound));
    // Non-finite: the same kind, or nothing unless an overflow was possible.
    let (inf, nan) = (f64::INFINITY, f64::NAN);
    assert!(agree(nan, nan, bound) && agree(inf, inf, bound) && agree(-inf, -inf, bound));
    assert!(!agree(inf, -inf, bound) && !agree(nan, inf, bound) && !agree(1.0, inf, bound));
    assert!(agree(inf, 3e38, near_max) && agree(nan, -inf, near_max));
    assert!(!agree(0.0, 1e33, near_max));
    // Exact: bit for bit, −0 is not +0.
    assert!(agree(-0.0, -0.0, Tolerance::Exact) && agree(nan, nan, Tolerance::Exact));
    assert!(!agree(0.0, -0.0, Tolerance::Exact) && !agree(1.0, 1.0 + 1e-15, Tolerance::Exact));
}
#[test]
fn xyz_routes_per_lane() {
    let converter = XyzConverter::<N>::new(&FourierBasis::VISIBLE).unwrap();
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
            for (got, want) in xyz.to_array().iter().zip(expected.to_array()) {
                let (got, want) = (got.lane(lane), f64::from(want));
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
