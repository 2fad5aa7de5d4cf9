//! Benchmarks of the Fourier algebra: `cargo bench -p spectral-core`.
//!
//! * `fma_peak`: 12 independent `f32x8` FMA chains — the machine's practical
//!   FMA throughput, the yardstick of the product benchmark.
//! * `product/{f32,f32x8}/N`: eight truncated products per iteration (eight
//!   scalar calls, or one 8-lane call), so "elements" are products.
//! * `xyz/<route>`: one N = 12 spectrum (D65) to XYZ.
//! * `project/471`: exact projection of a 471-sample table to 12 coefficients.
//! * `mese/*`: MESE preparation (O(N²), f64) and evaluation per wavelength.
//! * `table/*`, `upsample/*`: Fourier-table lookups, sRGB → sigmoid lookup and
//!   its projection to 12 coefficients.
//! * `neural/*`: the paper's 1×10×10 sine network, one input or 8 lanes,
//!   against a lookup in the N = 10 Fourier table it replaces.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use spectral_core::FourierBasis;
use spectral_core::data::tables::METALS;
use spectral_core::mese::{BoundedMese, Mese};
use spectral_core::neural::SineMlp;
use spectral_core::registry::Builtin;
use spectral_core::xyz::{XyzConverter, XyzRoute};
use spectral_core::{FourierSpectrum, SpectralRange, Spectrum};
use spectral_core::{table, upsample};
use std::hint::black_box;
use wide::f32x8;

const FMA_CHAINS: usize = 12;
const FMA_STEPS: usize = 256;

fn fma_peak(c: &mut Criterion) {
    let mut group = c.benchmark_group("fma_peak");
    group.throughput(Throughput::Elements((FMA_CHAINS * FMA_STEPS) as u64));
    group.bench_function("f32x8_fma_instructions", |b| {
        let m = black_box(f32x8::splat(0.999_999));
        let a = black_box(f32x8::splat(1e-7));
        b.iter(|| {
            let mut acc = [f32x8::splat(1.0); FMA_CHAINS];
            for _ in 0..FMA_STEPS {
                for x in acc.iter_mut() {
                    *x = x.mul_add(m, a);
                }
            }
            black_box(acc)
        });
    });
    group.finish();
}

fn spectrum<const N: usize>(seed: usize) -> FourierSpectrum<f64, N> {
    FourierSpectrum::from_coeffs(core::array::from_fn(|j| {
        (((seed * 31 + j * 17) % 23) as f64 - 11.0) / 23.0
    }))
}

fn product_for<const N: usize>(c: &mut Criterion) {
    let mut group = c.benchmark_group("product");
    group.throughput(Throughput::Elements(8));
    let scalar_a: [FourierSpectrum<f32, N>; 8] =
        core::array::from_fn(|lane| spectrum::<N>(lane).to_lanes());
    let scalar_b: [FourierSpectrum<f32, N>; 8] =
        core::array::from_fn(|lane| spectrum::<N>(lane + 8).to_lanes());
    group.bench_with_input(BenchmarkId::new("f32", N), &N, |b, _| {
        b.iter(|| {
            let a = black_box(&scalar_a);
            let bb = black_box(&scalar_b);
            let out: [FourierSpectrum<f32, N>; 8] = core::array::from_fn(|i| a[i].product(&bb[i]));
            black_box(out)
        });
    });
    let wide_a = FourierSpectrum::<f32x8, N>::from_lanes(spectrum::<N>);
    let wide_b = FourierSpectrum::<f32x8, N>::from_lanes(|lane| spectrum::<N>(lane + 8));
    group.bench_with_input(BenchmarkId::new("f32x8", N), &N, |b, _| {
        b.iter(|| black_box(black_box(&wide_a).product(black_box(&wide_b))));
    });
    group.finish();
}

fn products(c: &mut Criterion) {
    product_for::<4>(c);
    product_for::<8>(c);
    product_for::<12>(c);
    product_for::<16>(c);
}

fn xyz_routes(c: &mut Criterion) {
    let Ok(converter) = XyzConverter::<12>::new(&FourierBasis::VISIBLE) else {
        return;
    };
    let Some(d65) = Builtin::Illuminant(0).tabulated() else {
        return;
    };
    let s = d65.project::<12>(&SpectralRange::VISIBLE);
    let mut group = c.benchmark_group("xyz");
    for (name, route) in [
        ("series", XyzRoute::Series),
        ("lut", XyzRoute::Lut),
        ("zeroth", XyzRoute::Zeroth),
        ("mese", XyzRoute::Mese),
    ] {
        group.bench_function(name, |b| {
            b.iter(|| black_box(converter.convert(route, black_box(&s))));
        });
    }
    let wide = FourierSpectrum::<f32x8, 12>::from_lanes(spectrum::<12>);
    group.throughput(Throughput::Elements(8));
    group.bench_function("zeroth_f32x8", |b| {
        b.iter(|| black_box(converter.zeroth(black_box(&wide))));
    });
    group.finish();
}

fn projection(c: &mut Criterion) {
    let Some(y_bar) = Builtin::Cmf(1).tabulated() else {
        return;
    };
    assert_eq!(y_bar.wavelengths_nm().len(), 471);
    let range = SpectralRange::VISIBLE;
    c.bench_function("project/471_samples_to_12", |b| {
        b.iter(|| black_box(black_box(&y_bar).project::<12>(&range)));
    });
}

fn mese(c: &mut Criterion) {
    let range = SpectralRange::VISIBLE;
    let Some(patch) = Builtin::ColorChecker(6).tabulated() else {
        return;
    };
    let coefficients = patch.project::<12>(&range);
    let mut group = c.benchmark_group("mese");
    group.bench_function("bounded_prepare_N12", |b| {
        b.iter(|| black_box(BoundedMese::new(black_box(&coefficients))));
    });
    group.bench_function("unbounded_prepare_N12", |b| {
        b.iter(|| black_box(Mese::new(black_box(&coefficients))));
    });
    let Ok(bounded) = BoundedMese::new(&coefficients) else {
        return;
    };
    group.bench_function("bounded_eval_N12", |b| {
        b.iter(|| black_box(bounded.eval_cos(black_box(0.3))));
    });
    group.finish();
}

fn tables_and_upsampling(c: &mut Criterion) {
    let range = SpectralRange::VISIBLE;
    let Ok(table) = table::metal_reflectance::<12, 180>(&range, &METALS[0]) else {
        return;
    };
    c.bench_function("table/lookup_N12_L180", |b| {
        b.iter(|| black_box(table.lookup(black_box(0.437))));
    });
    let params = f32x8::new([0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8]);
    c.bench_function("table/lookup_lanes_N12_L180", |b| {
        b.iter(|| black_box(table.lookup_lanes(black_box(params))));
    });
    c.bench_function("upsample/srgb_reflectance_lookup", |b| {
        b.iter(|| black_box(upsample::srgb_reflectance(black_box([0.7, 0.2, 0.4]))));
    });
    let Ok(poly) = upsample::srgb_reflectance([0.7, 0.2, 0.4]) else {
        return;
    };
    c.bench_function("upsample/project_to_N12", |b| {
        b.iter(|| black_box(black_box(&poly).project::<12>(&range)));
    });
}

/// The paper's network (1 input, two hidden layers of 10 sine neurons, 10
/// coefficients) against the Fourier table it replaces (N = 10, 180 rows).
/// Evaluation cost does not depend on the weights' values, so fixed
/// pseudo-random weights stand in for a trained network.
fn neural(c: &mut Criterion) {
    let range = SpectralRange::VISIBLE;
    let mut state = 0x2545_f491u32;
    let mut weight = move || {
        state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (state >> 8) as f32 / (1u32 << 24) as f32 - 0.5
    };
    let network = SineMlp::<1, 10, 10> {
        range,
        normalisation: [(0.5, 2.0)],
        w1: core::array::from_fn(|_| [weight()]),
        b1: core::array::from_fn(|_| weight()),
        w2: core::array::from_fn(|_| core::array::from_fn(|_| weight())),
        b2: core::array::from_fn(|_| weight()),
        w3: core::array::from_fn(|_| core::array::from_fn(|_| weight())),
        b3: core::array::from_fn(|_| weight()),
    };
    let mut group = c.benchmark_group("neural");
    group.bench_function("sine_mlp_1x10x10_f32", |b| {
        b.iter(|| black_box(network.eval::<f32>(black_box([0.437]))));
    });
    let lanes = f32x8::new([0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8]);
    group.bench_function("sine_mlp_1x10x10_f32x8", |b| {
        b.iter(|| black_box(network.eval::<f32x8>(black_box([lanes]))));
    });
    if let Ok(table) = table::metal_reflectance::<10, 180>(&range, &METALS[0]) {
        group.bench_function("table_lookup_N10_L180_f32", |b| {
            b.iter(|| black_box(table.lookup(black_box(0.437))));
        });
        group.bench_function("table_lookup_N10_L180_f32x8", |b| {
            b.iter(|| black_box(table.lookup_lanes(black_box(lanes))));
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    fma_peak,
    products,
    xyz_routes,
    projection,
    mese,
    tables_and_upsampling,
    neural
);
criterion_main!(benches);
