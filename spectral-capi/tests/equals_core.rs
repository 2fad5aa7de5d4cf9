//! Every entry point, called through its Rust signature, gives the values
//! of spectral-core called directly (bit for bit where both run the same
//! code).
// Every call passes Rust buffers of the documented lengths; the tests
// index fixed-size arrays, and their helpers unwrap (a failure there is the
// test's failure).
#![allow(
    clippy::undocumented_unsafe_blocks,
    clippy::indexing_slicing,
    clippy::unwrap_used
)]

use spectral_capi::control_variate::{
    FspecControlVariate, fspec_cv_add, fspec_cv_end_batch, fspec_cv_estimate, fspec_cv_init,
};
use spectral_capi::mese::{fspec_bounded_mese_eval, fspec_mese_eval};
use spectral_capi::sampling::{
    FspecWavelengthStrategy, fspec_sample_wavelengths, fspec_sampled_to_xyz,
};
use spectral_capi::spectra::{
    FspecRgbKind, fspec_eval, fspec_eval_f32, fspec_product, fspec_product_f32, fspec_product_x8,
    fspec_project_blackbody, fspec_project_tabulated, fspec_upsample_srgb,
};
use spectral_capi::table::{
    FSPEC_TABLE_ROWS, fspec_table_build_conductor, fspec_table_build_dielectric,
    fspec_table_lookup, fspec_table_size,
};
use spectral_capi::xyz::{
    FspecXyzKernel, FspecXyzRoute, fspec_xyz, fspec_xyz_converter_apply, fspec_xyz_converter_init,
    fspec_xyz_converter_size, fspec_xyz_kernel_apply, fspec_xyz_kernel_apply_f32,
    fspec_xyz_kernel_apply_x8, fspec_xyz_kernel_init,
};
use spectral_capi::{FspecRange, FspecStatus};
use spectral_core::FourierBasis;
use spectral_core::complex::Complex;
use spectral_core::control_variate::ControlVariate;
use spectral_core::mese::{BoundedMese, Mese};
use spectral_core::sampling::{SampledSpectrum, SampledWavelengths, WavelengthStrategy};
use spectral_core::table::{FourierTable, conductor_reflectance, dielectric_reflectance};
use spectral_core::upsample::{RgbIlluminant, srgb_reflectance};
use spectral_core::xyz::{XyzConverter, XyzKernel, XyzRoute};
use spectral_core::{Blackbody, FourierSpectrum, SpectralRange, Spectrum, TabulatedSpectrum};
use wide::f32x8;

const VISIBLE: FspecRange = FspecRange {
    min_nm: 360.0,
    max_nm: 830.0,
};

/// An LED-like lamp: a blue peak and a broad phosphor hump.
const LAMP_NM: [f64; 9] = [
    380.0, 430.0, 450.0, 470.0, 500.0, 560.0, 600.0, 680.0, 780.0,
];
const LAMP_VALUES: [f64; 9] = [0.0, 0.2, 1.0, 0.25, 0.3, 0.6, 0.55, 0.2, 0.0];

fn lamp<const N: usize>() -> FourierSpectrum<f64, N> {
    let table = TabulatedSpectrum::new(&LAMP_NM, &LAMP_VALUES).unwrap();
    table.project::<N>(&SpectralRange::VISIBLE)
}

fn test_coeffs<const N: usize>(phase: f64) -> [f64; N] {
    core::array::from_fn(|j| 0.3 * (j as f64 * 1.1 + phase).cos() / (1.0 + j as f64))
}

/// Projection, blackbody and evaluation at several counts, including ones
/// the core has no unrolled product for.
fn projection_and_eval<const N: usize>() {
    let n = N as u32;
    let mut out = [0.0; N];
    let status = unsafe {
        fspec_project_tabulated(
            VISIBLE,
            LAMP_NM.as_ptr(),
            LAMP_VALUES.as_ptr(),
            9,
            n,
            out.as_mut_ptr(),
        )
    };
    assert_eq!(status, FspecStatus::Ok);
    assert_eq!(out, lamp::<N>().coeffs);

    let status = unsafe { fspec_project_blackbody(VISIBLE, 2856.0, n, out.as_mut_ptr()) };
    assert_eq!(status, FspecStatus::Ok);
    let blackbody = Blackbody::new(2856.0)
        .unwrap()
        .project::<N>(&SpectralRange::VISIBLE);
    assert_eq!(out, blackbody.coeffs);

    let mut value = 0.0;
    let status = unsafe { fspec_eval(VISIBLE, out.as_ptr(), n, 555.0, &mut value) };
    assert_eq!(status, FspecStatus::Ok);
    assert_eq!(value, blackbody.eval(&FourierBasis::VISIBLE, 555.0));

    let single = blackbody.to_lanes::<f32>();
    let mut value_f32 = 0.0f32;
    let status =
        unsafe { fspec_eval_f32(VISIBLE, single.coeffs.as_ptr(), n, 555.0, &mut value_f32) };
    assert_eq!(status, FspecStatus::Ok);
    assert_eq!(value_f32, single.eval(&FourierBasis::VISIBLE, 555.0));
}

#[test]
fn projection_blackbody_and_evaluation_equal_the_core() {
    projection_and_eval::<1>();
    projection_and_eval::<5>();
    projection_and_eval::<12>();
    projection_and_eval::<32>();
}

fn products<const N: usize>() {
    let n = N as u32;
    let (a, b) = (test_coeffs::<N>(0.2), test_coeffs::<N>(1.4));
    let expected = FourierSpectrum::from_coeffs(a).product(&FourierSpectrum::from_coeffs(b));
    let mut out = [0.0; N];
    assert_eq!(
        unsafe { fspec_product(a.as_ptr(), b.as_ptr(), n, out.as_mut_ptr()) },
        FspecStatus::Ok
    );
    assert_eq!(out, expected.coeffs);
    // In place: the output aliases the first input.
    let mut in_place = a;
    let pointer = in_place.as_mut_ptr();
    assert_eq!(
        unsafe { fspec_product(pointer, b.as_ptr(), n, pointer) },
        FspecStatus::Ok
    );
    assert_eq!(in_place, expected.coeffs);

    let (a32, b32) = (a.map(|v| v as f32), b.map(|v| v as f32));
    let expected32 = FourierSpectrum::from_coeffs(a32).product(&FourierSpectrum::from_coeffs(b32));
    let mut out32 = [0.0f32; N];
    assert_eq!(
        unsafe { fspec_product_f32(a32.as_ptr(), b32.as_ptr(), n, out32.as_mut_ptr()) },
        FspecStatus::Ok
    );
    assert_eq!(out32, expected32.coeffs);

    // Eight different spectra per operand, coefficient-major.
    let lanes_a = FourierSpectrum::<f32x8, N>::from_lanes(|lane| {
        FourierSpectrum::from_coeffs(test_coeffs::<N>(0.3 * lane as f64))
    });
    let lanes_b = FourierSpectrum::<f32x8, N>::from_lanes(|lane| {
        FourierSpectrum::from_coeffs(test_coeffs::<N>(2.0 - 0.2 * lane as f64))
    });
    let flatten = |s: &FourierSpectrum<f32x8, N>| -> Vec<f32> {
        s.coeffs.iter().flat_map(|c| c.to_array()).collect()
    };
    let (flat_a, flat_b) = (flatten(&lanes_a), flatten(&lanes_b));
    let mut flat_out = vec![0.0f32; 8 * N];
    assert_eq!(
        unsafe { fspec_product_x8(flat_a.as_ptr(), flat_b.as_ptr(), n, flat_out.as_mut_ptr()) },
        FspecStatus::Ok
    );
    assert_eq!(flat_out, flatten(&lanes_a.product(&lanes_b)));
    // Lane `lane` of coefficient `j` is at `j * 8 + lane`.
    assert_eq!(f64::from(flat_a[3 * 8 + 5]), lanes_a.lane(5).coeffs[3]);
}

#[test]
fn products_equal_the_core_single_and_eight_lanes() {
    products::<4>();
    products::<7>();
    products::<16>();
    products::<24>();
    products::<32>();
}

fn xyz_routes<const N: usize>() {
    let n = N as u32;
    let coeffs = lamp::<N>().coeffs;
    let converter = XyzConverter::<N>::new(&FourierBasis::VISIBLE).unwrap();
    let mut bytes = 0usize;
    assert_eq!(
        unsafe { fspec_xyz_converter_size(n, &mut bytes) },
        FspecStatus::Ok
    );
    let mut buffer = vec![0u64; bytes.div_ceil(8)];
    let status = unsafe { fspec_xyz_converter_init(buffer.as_mut_ptr().cast(), bytes, VISIBLE, n) };
    assert_eq!(status, FspecStatus::Ok);
    for (route, core_route) in [
        (FspecXyzRoute::Series, XyzRoute::Series),
        (FspecXyzRoute::Lut, XyzRoute::Lut),
        (FspecXyzRoute::Zeroth, XyzRoute::Zeroth),
        (FspecXyzRoute::Mese, XyzRoute::Mese),
    ] {
        let expected = converter
            .convert(core_route, &FourierSpectrum::from_coeffs(coeffs))
            .to_array();
        let mut xyz = [0.0; 3];
        let status = unsafe {
            fspec_xyz_converter_apply(
                buffer.as_ptr().cast(),
                route as i32,
                coeffs.as_ptr(),
                n,
                xyz.as_mut_ptr(),
            )
        };
        assert_eq!(status, FspecStatus::Ok);
        assert_eq!(xyz, expected, "{route:?}");
        let status =
            unsafe { fspec_xyz(VISIBLE, route as i32, coeffs.as_ptr(), n, xyz.as_mut_ptr()) };
        assert_eq!(status, FspecStatus::Ok);
        assert_eq!(xyz, expected, "{route:?}");
    }

    let core_kernel = XyzKernel::<N>::new(&FourierBasis::VISIBLE).unwrap();
    let mut kernel = FspecXyzKernel {
        n: 0,
        rows: [[0.0; 32]; 3],
    };
    assert_eq!(
        unsafe { fspec_xyz_kernel_init(&mut kernel, VISIBLE, n) },
        FspecStatus::Ok
    );
    let mut xyz = [0.0; 3];
    assert_eq!(
        unsafe { fspec_xyz_kernel_apply(&kernel, coeffs.as_ptr(), n, xyz.as_mut_ptr()) },
        FspecStatus::Ok
    );
    assert_eq!(
        xyz,
        core_kernel
            .apply(&FourierSpectrum::from_coeffs(coeffs))
            .to_array()
    );
    let single = coeffs.map(|c| c as f32);
    let mut xyz32 = [0.0f32; 3];
    assert_eq!(
        unsafe { fspec_xyz_kernel_apply_f32(&kernel, single.as_ptr(), n, xyz32.as_mut_ptr()) },
        FspecStatus::Ok
    );
    assert_eq!(
        xyz32,
        core_kernel
            .apply(&FourierSpectrum::from_coeffs(single))
            .to_array()
    );

    let lanes =
        FourierSpectrum::<f32x8, N>::from_lanes(|lane| lamp::<N>().scale(1.0 + lane as f64));
    let flat: Vec<f32> = lanes.coeffs.iter().flat_map(|c| c.to_array()).collect();
    let mut xyz_lanes = [0.0f32; 24];
    assert_eq!(
        unsafe { fspec_xyz_kernel_apply_x8(&kernel, flat.as_ptr(), n, xyz_lanes.as_mut_ptr()) },
        FspecStatus::Ok
    );
    let expected: Vec<f32> = core_kernel
        .apply(&lanes)
        .to_array()
        .iter()
        .flat_map(|c| c.to_array())
        .collect();
    assert_eq!(xyz_lanes.to_vec(), expected);
}

#[test]
fn xyz_by_every_route_equals_the_core() {
    xyz_routes::<3>();
    xyz_routes::<12>();
    xyz_routes::<32>();
}

#[test]
fn mese_equals_the_core() {
    let coeffs = lamp::<8>().coeffs;
    let wavelengths = [360.0, 420.5, 450.0, 555.0, 700.0, 830.0];
    let mut values = [0.0; 6];
    let status = unsafe {
        fspec_mese_eval(
            VISIBLE,
            coeffs.as_ptr(),
            8,
            wavelengths.as_ptr(),
            6,
            values.as_mut_ptr(),
        )
    };
    assert_eq!(status, FspecStatus::Ok);
    let mese = Mese::new(&FourierSpectrum::from_coeffs(coeffs)).unwrap();
    assert_eq!(
        values,
        wavelengths.map(|l| mese.eval(&FourierBasis::VISIBLE, l))
    );

    let reflectance = srgb_reflectance([0.7, 0.2, 0.1])
        .unwrap()
        .project::<8>(&SpectralRange::VISIBLE);
    let status = unsafe {
        fspec_bounded_mese_eval(
            VISIBLE,
            reflectance.coeffs.as_ptr(),
            8,
            wavelengths.as_ptr(),
            6,
            values.as_mut_ptr(),
        )
    };
    assert_eq!(status, FspecStatus::Ok);
    let bounded = BoundedMese::new(&reflectance).unwrap();
    assert_eq!(
        values,
        wavelengths.map(|l| bounded.eval(&FourierBasis::VISIBLE, l))
    );
}

#[test]
fn upsampling_equals_the_core() {
    let rgb = [0.7, 0.2, 0.1];
    let mut out = [0.0; 16];
    let status = unsafe {
        fspec_upsample_srgb(
            VISIBLE,
            FspecRgbKind::Reflectance as i32,
            rgb.as_ptr(),
            16,
            out.as_mut_ptr(),
        )
    };
    assert_eq!(status, FspecStatus::Ok);
    assert_eq!(
        out,
        srgb_reflectance(rgb)
            .unwrap()
            .project::<16>(&SpectralRange::VISIBLE)
            .coeffs
    );
    let status = unsafe {
        fspec_upsample_srgb(
            VISIBLE,
            FspecRgbKind::Illuminant as i32,
            rgb.as_ptr(),
            16,
            out.as_mut_ptr(),
        )
    };
    assert_eq!(status, FspecStatus::Ok);
    let illuminant = RgbIlluminant::new(rgb).unwrap();
    assert_eq!(
        out,
        illuminant.project::<16>(&SpectralRange::VISIBLE).coeffs
    );
}

#[test]
fn sampling_and_the_sampled_estimate_equal_the_core() {
    let u = [0.1f32, 0.35, 0.6, 0.9];
    let (mut lambda, mut pdf) = ([0.0f32; 4], [0.0f32; 4]);
    for (strategy, core_strategy) in [
        (
            FspecWavelengthStrategy::Uniform,
            WavelengthStrategy::Uniform,
        ),
        (
            FspecWavelengthStrategy::Stratified,
            WavelengthStrategy::Stratified,
        ),
        (FspecWavelengthStrategy::Hero, WavelengthStrategy::Hero),
        (
            FspecWavelengthStrategy::Visible,
            WavelengthStrategy::Visible,
        ),
        (
            FspecWavelengthStrategy::VisibleHero,
            WavelengthStrategy::VisibleHero,
        ),
    ] {
        let status = unsafe {
            fspec_sample_wavelengths(
                VISIBLE,
                strategy as i32,
                u.as_ptr(),
                4,
                lambda.as_mut_ptr(),
                pdf.as_mut_ptr(),
            )
        };
        assert_eq!(status, FspecStatus::Ok);
        let expected = SampledWavelengths::<4>::sample(core_strategy, &SpectralRange::VISIBLE, u);
        assert_eq!(&lambda, expected.lambda_nm());
        assert_eq!(&pdf, expected.pdf_per_nm());
    }
    let values = [0.5f32, 1.0, 0.25, 2.0];
    let mut xyz = [0.0; 3];
    let status = unsafe {
        fspec_sampled_to_xyz(
            values.as_ptr(),
            lambda.as_ptr(),
            pdf.as_ptr(),
            4,
            xyz.as_mut_ptr(),
        )
    };
    assert_eq!(status, FspecStatus::Ok);
    let wavelengths = SampledWavelengths::<4>::from_parts(lambda, pdf);
    assert_eq!(
        xyz,
        SampledSpectrum { values }.to_xyz(&wavelengths).to_array()
    );
}

#[test]
fn control_variate_equals_the_core() {
    let mut cv = FspecControlVariate { opaque: [0; 16] };
    let mut core = ControlVariate::new();
    assert_eq!(unsafe { fspec_cv_init(&mut cv) }, FspecStatus::Ok);
    for batch in 0..3 {
        for i in 0..4 {
            let d = (i as f64 - 1.5) * (1.0 + batch as f64);
            let (y, c, mu) = (2.0 + 0.8 * d + 0.1 * i as f64, 7.0 + d, 7.0);
            assert_eq!(unsafe { fspec_cv_add(&mut cv, y, c, mu) }, FspecStatus::Ok);
            core.add(y, c, mu);
        }
        assert_eq!(unsafe { fspec_cv_end_batch(&mut cv) }, FspecStatus::Ok);
        core.end_batch();
    }
    let (mut estimate, mut alpha, mut samples) = (0.0, 0.0, 0.0);
    assert_eq!(
        unsafe { fspec_cv_estimate(&cv, &mut estimate, &mut alpha, &mut samples) },
        FspecStatus::Ok
    );
    assert_eq!(
        (estimate, alpha, samples),
        (core.estimate(), core.alpha(), core.samples())
    );
}

#[test]
fn fourier_tables_equal_the_core() {
    let nm = [400.0, 700.0];
    let eta = [1.55, 1.5];
    let mut bytes = 0usize;
    assert_eq!(unsafe { fspec_table_size(12, &mut bytes) }, FspecStatus::Ok);
    let mut buffer = vec![0u64; bytes.div_ceil(8)];
    let status = unsafe {
        fspec_table_build_dielectric(
            buffer.as_mut_ptr().cast(),
            bytes,
            VISIBLE,
            12,
            nm.as_ptr(),
            eta.as_ptr(),
            2,
            0,
        )
    };
    assert_eq!(status, FspecStatus::Ok);
    let eta_table = TabulatedSpectrum::new(&nm, &eta).unwrap();
    let core: FourierTable<12, FSPEC_TABLE_ROWS> =
        dielectric_reflectance(&SpectralRange::VISIBLE, |l| eta_table.value(l), false).unwrap();
    let mut coeffs = [0.0f32; 12];
    for cos_theta in [0.0, 0.13, 0.5, 1.0] {
        let status = unsafe {
            fspec_table_lookup(buffer.as_ptr().cast(), cos_theta, 12, coeffs.as_mut_ptr())
        };
        assert_eq!(status, FspecStatus::Ok);
        assert_eq!(coeffs, core.lookup(cos_theta).coeffs);
    }

    let k = [3.0, 3.5];
    let status = unsafe {
        fspec_table_build_conductor(
            buffer.as_mut_ptr().cast(),
            bytes,
            VISIBLE,
            12,
            nm.as_ptr(),
            eta.as_ptr(),
            k.as_ptr(),
            2,
            1.0,
        )
    };
    assert_eq!(status, FspecStatus::Ok);
    let k_table = TabulatedSpectrum::new(&nm, &k).unwrap();
    let core: FourierTable<12, FSPEC_TABLE_ROWS> =
        conductor_reflectance(&SpectralRange::VISIBLE, 1.0, |l| {
            Complex::new(eta_table.value(l), k_table.value(l))
        })
        .unwrap();
    let status =
        unsafe { fspec_table_lookup(buffer.as_ptr().cast(), 0.3, 12, coeffs.as_mut_ptr()) };
    assert_eq!(status, FspecStatus::Ok);
    assert_eq!(coeffs, core.lookup(0.3).coeffs);
}

/// The sizes the header's users rely on (README: the plain structs).
#[test]
fn abi_struct_sizes() {
    assert_eq!(size_of::<FspecXyzKernel>(), 776);
    assert_eq!(size_of::<FspecControlVariate>(), 128);
    assert_eq!(size_of::<FspecRange>(), 16);
    assert_eq!(size_of::<FspecStatus>(), 4);
}
