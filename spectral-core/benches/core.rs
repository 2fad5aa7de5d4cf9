//! Benchmarks of the Fourier algebra: `cargo bench -p spectral-core`.
//!
//! * `fma_peak`: 12 independent `f32x8` FMA chains — the machine's practical
//!   FMA throughput, the yardstick of the product benchmark.
//! * `product/{f32,f32x8}/N`: eight truncated products per iteration (eight
//!   scalar calls, or one 8-lane call), so "elements" are products.
//! * `xyz/<route>`: one N = 12 spectrum to XYZ.
//! * `project/471`: exact projection of a 471-sample table to 12 coefficients.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use spectral_core::registry::Builtin;
use spectral_core::xyz::{XyzConverter, XyzRoute};
use spectral_core::{FourierSpectrum, SpectralRange, Spectrum};
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
    let Ok(converter) = XyzConverter::<12>::new(SpectralRange::VISIBLE) else {
        return;
    };
    let s = spectrum::<12>(3);
    let mut group = c.benchmark_group("xyz");
    for (name, route) in [
        ("series", XyzRoute::Series),
        ("lut", XyzRoute::Lut),
        ("zeroth", XyzRoute::Zeroth),
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

criterion_group!(benches, fma_peak, products, xyz_routes, projection);
criterion_main!(benches);
