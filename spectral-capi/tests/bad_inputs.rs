//! Bad input through every entry point returns a status and writes
//! nothing: null pointers, unsupported counts (0, 33), misaligned pointers,
//! unsorted and non-finite data, bad ranges and enumerators, short and
//! uninitialised buffers. A panic here would fail the test (and abort a C
//! caller), so these tests are also the executable half of the crate's
//! panic-freedom argument.
// The pointers passed are null, misaligned or point to Rust buffers of the
// documented lengths: every call stays within its `# Safety` contract or
// is rejected before any dereference.
#![allow(clippy::undocumented_unsafe_blocks, clippy::indexing_slicing)]

use core::ptr::{null, null_mut};
use spectral_capi::FspecRange;
use spectral_capi::FspecStatus::{
    self, BadLength, BufferTooSmall, InvalidParameter, InvalidRange, InvalidWavelength, Misaligned,
    NegativeValue, NonFinite, NonFiniteResult, NotIncreasing, NotInitialised, NullPointer,
    OutOfRange, UnsupportedCount,
};
use spectral_capi::control_variate::{
    FspecControlVariate, fspec_cv_add, fspec_cv_end_batch, fspec_cv_estimate, fspec_cv_init,
};
use spectral_capi::mese::{fspec_bounded_mese_eval, fspec_mese_eval};
use spectral_capi::sampling::{fspec_sample_wavelengths, fspec_sampled_to_xyz};
use spectral_capi::spectra::{
    fspec_eval, fspec_eval_f32, fspec_product, fspec_product_f32, fspec_product_x8,
    fspec_project_blackbody, fspec_project_tabulated, fspec_upsample_srgb,
};
use spectral_capi::table::{
    fspec_table_build_conductor, fspec_table_build_dielectric, fspec_table_lookup, fspec_table_size,
};
use spectral_capi::xyz::{
    FspecXyzKernel, fspec_xyz, fspec_xyz_converter_apply, fspec_xyz_converter_init,
    fspec_xyz_converter_size, fspec_xyz_kernel_apply, fspec_xyz_kernel_apply_f32,
    fspec_xyz_kernel_apply_x8, fspec_xyz_kernel_init,
};

const VISIBLE: FspecRange = FspecRange {
    min_nm: 360.0,
    max_nm: 830.0,
};
/// Ranges every function rejects.
const BAD_RANGES: [FspecRange; 5] = [
    FspecRange {
        min_nm: 500.0,
        max_nm: 400.0,
    },
    FspecRange {
        min_nm: 0.0,
        max_nm: 400.0,
    },
    FspecRange {
        min_nm: f64::NAN,
        max_nm: 400.0,
    },
    FspecRange {
        min_nm: 400.0,
        max_nm: f64::INFINITY,
    },
    FspecRange {
        min_nm: 1.0,
        max_nm: 1.0e9,
    },
];
/// Inside the CIE table? No: XYZ and upsampling reject it.
const WIDE: FspecRange = FspecRange {
    min_nm: 300.0,
    max_nm: 900.0,
};
/// Coefficient counts no function accepts.
const BAD_COUNTS: [u32; 3] = [0, 33, u32::MAX];
/// A sentinel that outputs must keep when a call fails.
const UNTOUCHED: f64 = -12345.0;

/// A pointer one byte into a buffer: misaligned for any wider type.
fn misaligned<T>(buffer: &[u64]) -> *const T {
    buffer.as_ptr().cast::<u8>().wrapping_add(1).cast()
}

fn misaligned_mut<T>(buffer: &mut [u64]) -> *mut T {
    buffer.as_mut_ptr().cast::<u8>().wrapping_add(1).cast()
}

#[test]
fn projections_and_upsampling() {
    let nm = [400.0, 500.0, 600.0];
    let values = [0.1, 0.5, 0.2];
    let mut out = [UNTOUCHED; 32];
    let o = out.as_mut_ptr();
    let project = |range, nm: *const f64, values: *const f64, count, n, out| unsafe {
        fspec_project_tabulated(range, nm, values, count, n, out)
    };
    assert_eq!(
        project(VISIBLE, null(), values.as_ptr(), 3, 8, o),
        NullPointer
    );
    assert_eq!(project(VISIBLE, nm.as_ptr(), null(), 3, 8, o), NullPointer);
    assert_eq!(
        project(VISIBLE, nm.as_ptr(), values.as_ptr(), 3, 8, null_mut()),
        NullPointer
    );
    assert_eq!(
        project(VISIBLE, nm.as_ptr(), values.as_ptr(), 0, 8, o),
        BadLength
    );
    assert_eq!(
        project(VISIBLE, nm.as_ptr(), values.as_ptr(), usize::MAX, 8, o),
        BadLength
    );
    for n in BAD_COUNTS {
        assert_eq!(
            project(VISIBLE, nm.as_ptr(), values.as_ptr(), 3, n, o),
            UnsupportedCount
        );
    }
    for range in BAD_RANGES {
        assert_eq!(
            project(range, nm.as_ptr(), values.as_ptr(), 3, 8, o),
            InvalidRange
        );
    }
    let unsorted = [400.0, 600.0, 500.0];
    let duplicate = [400.0, 500.0, 500.0];
    assert_eq!(
        project(VISIBLE, unsorted.as_ptr(), values.as_ptr(), 3, 8, o),
        NotIncreasing
    );
    assert_eq!(
        project(VISIBLE, duplicate.as_ptr(), values.as_ptr(), 3, 8, o),
        NotIncreasing
    );
    let nan_nm = [400.0, f64::NAN, 600.0];
    let negative_nm = [-1.0, 500.0, 600.0];
    assert_eq!(
        project(VISIBLE, nan_nm.as_ptr(), values.as_ptr(), 3, 8, o),
        InvalidWavelength
    );
    assert_eq!(
        project(VISIBLE, negative_nm.as_ptr(), values.as_ptr(), 3, 8, o),
        InvalidWavelength
    );
    let nan_values = [0.1, f64::NAN, 0.2];
    let infinite_values = [0.1, f64::INFINITY, 0.2];
    let negative_values = [0.1, -0.5, 0.2];
    assert_eq!(
        project(VISIBLE, nm.as_ptr(), nan_values.as_ptr(), 3, 8, o),
        NonFinite
    );
    assert_eq!(
        project(VISIBLE, nm.as_ptr(), infinite_values.as_ptr(), 3, 8, o),
        NonFinite
    );
    assert_eq!(
        project(VISIBLE, nm.as_ptr(), negative_values.as_ptr(), 3, 8, o),
        NegativeValue
    );
    let buffer = [0u64; 8];
    assert_eq!(
        project(VISIBLE, misaligned(&buffer), values.as_ptr(), 3, 8, o),
        Misaligned
    );

    let blackbody = |range, t, n, out| unsafe { fspec_project_blackbody(range, t, n, out) };
    assert_eq!(blackbody(VISIBLE, 3000.0, 8, null_mut()), NullPointer);
    for t in [0.0, -5.0, f64::NAN, f64::INFINITY] {
        assert_eq!(blackbody(VISIBLE, t, 8, o), InvalidParameter, "{t}");
    }
    for n in BAD_COUNTS {
        assert_eq!(blackbody(VISIBLE, 3000.0, n, o), UnsupportedCount);
    }
    for range in BAD_RANGES {
        assert_eq!(blackbody(range, 3000.0, 8, o), InvalidRange);
    }

    let rgb = [0.5, 0.2, 0.1];
    let upsample = |range, kind, rgb: *const f64, n, out| unsafe {
        fspec_upsample_srgb(range, kind, rgb, n, out)
    };
    assert_eq!(upsample(VISIBLE, 0, null(), 8, o), NullPointer);
    assert_eq!(
        upsample(VISIBLE, 0, rgb.as_ptr(), 8, null_mut()),
        NullPointer
    );
    for kind in [-1, 3, i32::MAX] {
        assert_eq!(
            upsample(VISIBLE, kind, rgb.as_ptr(), 8, o),
            InvalidParameter
        );
    }
    for n in BAD_COUNTS {
        assert_eq!(upsample(VISIBLE, 0, rgb.as_ptr(), n, o), UnsupportedCount);
    }
    for range in BAD_RANGES.into_iter().chain([WIDE]) {
        assert_eq!(upsample(range, 0, rgb.as_ptr(), 8, o), InvalidRange);
    }
    for kind in 0..3 {
        let nan_rgb = [0.5, f64::NAN, 0.1];
        assert_eq!(upsample(VISIBLE, kind, nan_rgb.as_ptr(), 8, o), NonFinite);
    }
    assert!(out.iter().all(|&v| v == UNTOUCHED));
}

#[test]
fn products_and_evaluation() {
    let good = [0.5f64; 32];
    let nan = [f64::NAN; 32];
    let mut out = [UNTOUCHED; 32];
    let o = out.as_mut_ptr();
    let product = |a: *const f64, b: *const f64, n, out| unsafe { fspec_product(a, b, n, out) };
    assert_eq!(product(null(), good.as_ptr(), 8, o), NullPointer);
    assert_eq!(product(good.as_ptr(), null(), 8, o), NullPointer);
    assert_eq!(
        product(good.as_ptr(), good.as_ptr(), 8, null_mut()),
        NullPointer
    );
    assert_eq!(product(nan.as_ptr(), good.as_ptr(), 8, o), NonFinite);
    assert_eq!(product(good.as_ptr(), nan.as_ptr(), 8, o), NonFinite);
    for n in BAD_COUNTS {
        assert_eq!(
            product(good.as_ptr(), good.as_ptr(), n, o),
            UnsupportedCount
        );
    }
    let buffer = [0u64; 40];
    assert_eq!(
        product(misaligned(&buffer), good.as_ptr(), 8, o),
        Misaligned
    );
    // Finite input whose product overflows.
    let huge = [1e200f64; 32];
    assert_eq!(product(huge.as_ptr(), huge.as_ptr(), 8, o), NonFiniteResult);

    let good32 = [0.5f32; 256];
    let nan32 = [f32::NAN; 256];
    let mut out32 = [UNTOUCHED as f32; 256];
    let o32 = out32.as_mut_ptr();
    for product in [fspec_product_f32, fspec_product_x8] {
        let call = |a: *const f32, b: *const f32, n, out| unsafe { product(a, b, n, out) };
        assert_eq!(call(null(), good32.as_ptr(), 8, o32), NullPointer);
        assert_eq!(call(good32.as_ptr(), null(), 8, o32), NullPointer);
        assert_eq!(
            call(good32.as_ptr(), good32.as_ptr(), 8, null_mut()),
            NullPointer
        );
        assert_eq!(call(good32.as_ptr(), nan32.as_ptr(), 8, o32), NonFinite);
        assert_eq!(
            call(misaligned(&buffer), good32.as_ptr(), 4, o32),
            Misaligned
        );
        for n in BAD_COUNTS {
            assert_eq!(
                call(good32.as_ptr(), good32.as_ptr(), n, o32),
                UnsupportedCount
            );
        }
    }

    let eval =
        |range, c: *const f64, n, lambda, out| unsafe { fspec_eval(range, c, n, lambda, out) };
    assert_eq!(eval(VISIBLE, null(), 8, 500.0, o), NullPointer);
    assert_eq!(
        eval(VISIBLE, good.as_ptr(), 8, 500.0, null_mut()),
        NullPointer
    );
    assert_eq!(eval(VISIBLE, nan.as_ptr(), 8, 500.0, o), NonFinite);
    assert_eq!(
        eval(VISIBLE, good.as_ptr(), 8, f64::NAN, o),
        InvalidWavelength
    );
    assert_eq!(eval(VISIBLE, good.as_ptr(), 8, 300.0, o), OutOfRange);
    assert_eq!(eval(VISIBLE, good.as_ptr(), 8, 831.0, o), OutOfRange);
    for n in BAD_COUNTS {
        assert_eq!(eval(VISIBLE, good.as_ptr(), n, 500.0, o), UnsupportedCount);
    }
    for range in BAD_RANGES {
        assert_eq!(eval(range, good.as_ptr(), 8, 500.0, o), InvalidRange);
    }
    let eval32 =
        |c: *const f32, n, lambda, out| unsafe { fspec_eval_f32(VISIBLE, c, n, lambda, out) };
    assert_eq!(eval32(null(), 8, 500.0, o32), NullPointer);
    assert_eq!(eval32(good32.as_ptr(), 8, 500.0, null_mut()), NullPointer);
    assert_eq!(eval32(nan32.as_ptr(), 8, 500.0, o32), NonFinite);
    assert_eq!(eval32(good32.as_ptr(), 8, 100.0, o32), OutOfRange);
    assert_eq!(eval32(good32.as_ptr(), 0, 500.0, o32), UnsupportedCount);
    assert!(out.iter().all(|&v| v == UNTOUCHED));
    assert!(out32.iter().all(|&v| v == UNTOUCHED as f32));
}

#[test]
fn xyz_converters_and_kernels() {
    let good = [0.5f64; 32];
    let nan = [f64::NAN; 32];
    let mut xyz = [UNTOUCHED; 3];
    let x = xyz.as_mut_ptr();

    let mut bytes = 0usize;
    assert_eq!(
        unsafe { fspec_xyz_converter_size(8, null_mut()) },
        NullPointer
    );
    for n in BAD_COUNTS {
        assert_eq!(
            unsafe { fspec_xyz_converter_size(n, &mut bytes) },
            UnsupportedCount
        );
    }
    assert_eq!(
        unsafe { fspec_xyz_converter_size(8, &mut bytes) },
        FspecStatus::Ok
    );
    let mut buffer = vec![0u64; bytes.div_ceil(8) + 1];
    let b = buffer.as_mut_ptr().cast();
    let init =
        |buffer, bytes, range, n| unsafe { fspec_xyz_converter_init(buffer, bytes, range, n) };
    assert_eq!(init(null_mut(), bytes, VISIBLE, 8), NullPointer);
    assert_eq!(init(b, bytes - 1, VISIBLE, 8), BufferTooSmall);
    assert_eq!(init(b, 0, VISIBLE, 8), BufferTooSmall);
    for n in BAD_COUNTS {
        assert_eq!(init(b, bytes, VISIBLE, n), UnsupportedCount);
    }
    for range in BAD_RANGES.into_iter().chain([WIDE]) {
        assert_eq!(init(b, bytes, range, 8), InvalidRange);
    }
    let apply = |buffer: *const core::ffi::c_void, route, c: *const f64, n, out| unsafe {
        fspec_xyz_converter_apply(buffer, route, c, n, out)
    };
    // Zeroed memory never went through `fspec_xyz_converter_init`.
    assert_eq!(
        apply(buffer.as_ptr().cast(), 0, good.as_ptr(), 8, x),
        NotInitialised
    );
    assert_eq!(
        init(misaligned_mut(&mut buffer), bytes, VISIBLE, 8),
        Misaligned
    );
    assert_eq!(
        init(buffer.as_mut_ptr().cast(), bytes, VISIBLE, 8),
        FspecStatus::Ok
    );
    let b = buffer.as_ptr().cast();
    assert_eq!(apply(null(), 0, good.as_ptr(), 8, x), NullPointer);
    assert_eq!(apply(b, 0, null(), 8, x), NullPointer);
    assert_eq!(apply(b, 0, good.as_ptr(), 8, null_mut()), NullPointer);
    assert_eq!(apply(b, 0, nan.as_ptr(), 8, x), NonFinite);
    assert_eq!(apply(b, 4, good.as_ptr(), 8, x), InvalidParameter);
    assert_eq!(apply(b, -1, good.as_ptr(), 8, x), InvalidParameter);
    assert_eq!(apply(b, 0, good.as_ptr(), 12, x), UnsupportedCount);
    for n in BAD_COUNTS {
        assert_eq!(apply(b, 0, good.as_ptr(), n, x), UnsupportedCount);
    }
    // A converter's buffer is not a table.
    let mut coeffs = [0.0f32; 8];
    assert_eq!(
        unsafe { fspec_table_lookup(b, 0.5, 8, coeffs.as_mut_ptr()) },
        NotInitialised
    );

    let once = |range, route, c: *const f64, n, out| unsafe { fspec_xyz(range, route, c, n, out) };
    assert_eq!(once(VISIBLE, 0, null(), 8, x), NullPointer);
    assert_eq!(once(VISIBLE, 0, good.as_ptr(), 8, null_mut()), NullPointer);
    assert_eq!(once(VISIBLE, 0, nan.as_ptr(), 8, x), NonFinite);
    assert_eq!(once(VISIBLE, 9, good.as_ptr(), 8, x), InvalidParameter);
    for n in BAD_COUNTS {
        assert_eq!(once(VISIBLE, 3, good.as_ptr(), n, x), UnsupportedCount);
    }
    for range in BAD_RANGES.into_iter().chain([WIDE]) {
        assert_eq!(once(range, 3, good.as_ptr(), 8, x), InvalidRange);
    }

    let mut kernel = FspecXyzKernel {
        n: 0,
        rows: [[0.0; 32]; 3],
    };
    assert_eq!(
        unsafe { fspec_xyz_kernel_init(null_mut(), VISIBLE, 8) },
        NullPointer
    );
    for n in BAD_COUNTS {
        assert_eq!(
            unsafe { fspec_xyz_kernel_init(&mut kernel, VISIBLE, n) },
            UnsupportedCount
        );
    }
    for range in BAD_RANGES.into_iter().chain([WIDE]) {
        assert_eq!(
            unsafe { fspec_xyz_kernel_init(&mut kernel, range, 8) },
            InvalidRange
        );
    }
    let apply = |k: *const FspecXyzKernel, c: *const f64, n, out| unsafe {
        fspec_xyz_kernel_apply(k, c, n, out)
    };
    // A kernel that was never initialised has n = 0, which matches no count.
    assert_eq!(apply(&kernel, good.as_ptr(), 8, x), UnsupportedCount);
    kernel.n = 1000;
    assert_eq!(apply(&kernel, good.as_ptr(), 8, x), UnsupportedCount);
    assert_eq!(
        unsafe { fspec_xyz_kernel_init(&mut kernel, VISIBLE, 8) },
        FspecStatus::Ok
    );
    assert_eq!(apply(null(), good.as_ptr(), 8, x), NullPointer);
    assert_eq!(apply(&kernel, null(), 8, x), NullPointer);
    assert_eq!(apply(&kernel, good.as_ptr(), 8, null_mut()), NullPointer);
    assert_eq!(apply(&kernel, nan.as_ptr(), 8, x), NonFinite);
    assert_eq!(apply(&kernel, good.as_ptr(), 9, x), UnsupportedCount);
    for n in BAD_COUNTS {
        assert_eq!(apply(&kernel, good.as_ptr(), n, x), UnsupportedCount);
    }
    let good32 = [0.5f32; 256];
    let nan32 = [f32::NAN; 256];
    let mut xyz32 = [UNTOUCHED as f32; 24];
    let x32 = xyz32.as_mut_ptr();
    for apply in [fspec_xyz_kernel_apply_f32, fspec_xyz_kernel_apply_x8] {
        let call = |k: *const FspecXyzKernel, c: *const f32, n, out| unsafe { apply(k, c, n, out) };
        assert_eq!(call(null(), good32.as_ptr(), 8, x32), NullPointer);
        assert_eq!(call(&kernel, null(), 8, x32), NullPointer);
        assert_eq!(call(&kernel, good32.as_ptr(), 8, null_mut()), NullPointer);
        assert_eq!(call(&kernel, nan32.as_ptr(), 8, x32), NonFinite);
        assert_eq!(call(&kernel, good32.as_ptr(), 4, x32), UnsupportedCount);
        for n in BAD_COUNTS {
            assert_eq!(call(&kernel, good32.as_ptr(), n, x32), UnsupportedCount);
        }
    }
    assert!(xyz.iter().all(|&v| v == UNTOUCHED));
    assert!(xyz32.iter().all(|&v| v == UNTOUCHED as f32));
}

#[test]
fn mese_evaluations() {
    let good = [0.5, 0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let nan = [f64::NAN; 8];
    let nm = [400.0, 500.0];
    let mut out = [UNTOUCHED; 2];
    let o = out.as_mut_ptr();
    for mese in [fspec_mese_eval, fspec_bounded_mese_eval] {
        let call = |range, c: *const f64, n, nm: *const f64, count, out| unsafe {
            mese(range, c, n, nm, count, out)
        };
        assert_eq!(call(VISIBLE, null(), 8, nm.as_ptr(), 2, o), NullPointer);
        assert_eq!(call(VISIBLE, good.as_ptr(), 8, null(), 2, o), NullPointer);
        assert_eq!(
            call(VISIBLE, good.as_ptr(), 8, nm.as_ptr(), 2, null_mut()),
            NullPointer
        );
        assert_eq!(
            call(VISIBLE, good.as_ptr(), 8, nm.as_ptr(), 0, o),
            BadLength
        );
        assert_eq!(call(VISIBLE, nan.as_ptr(), 8, nm.as_ptr(), 2, o), NonFinite);
        let outside = [400.0, 900.0];
        let nan_nm = [400.0, f64::NAN];
        assert_eq!(
            call(VISIBLE, good.as_ptr(), 8, outside.as_ptr(), 2, o),
            OutOfRange
        );
        assert_eq!(
            call(VISIBLE, good.as_ptr(), 8, nan_nm.as_ptr(), 2, o),
            InvalidWavelength
        );
        for n in BAD_COUNTS {
            assert_eq!(
                call(VISIBLE, good.as_ptr(), n, nm.as_ptr(), 2, o),
                UnsupportedCount
            );
        }
        for range in BAD_RANGES {
            assert_eq!(
                call(range, good.as_ptr(), 8, nm.as_ptr(), 2, o),
                InvalidRange
            );
        }
    }
    assert!(out.iter().all(|&v| v == UNTOUCHED));
}

#[test]
fn sampling() {
    let u = [0.25f32; 4];
    let mut lambda = [UNTOUCHED as f32; 4];
    let mut pdf = [UNTOUCHED as f32; 4];
    let (l, p) = (lambda.as_mut_ptr(), pdf.as_mut_ptr());
    let sample = |range, strategy, u: *const f32, count, l, p| unsafe {
        fspec_sample_wavelengths(range, strategy, u, count, l, p)
    };
    assert_eq!(sample(VISIBLE, 0, null(), 4, l, p), NullPointer);
    assert_eq!(
        sample(VISIBLE, 0, u.as_ptr(), 4, null_mut(), p),
        NullPointer
    );
    assert_eq!(
        sample(VISIBLE, 0, u.as_ptr(), 4, l, null_mut()),
        NullPointer
    );
    assert_eq!(sample(VISIBLE, 5, u.as_ptr(), 4, l, p), InvalidParameter);
    assert_eq!(sample(VISIBLE, -1, u.as_ptr(), 4, l, p), InvalidParameter);
    for count in BAD_COUNTS {
        assert_eq!(
            sample(VISIBLE, 0, u.as_ptr(), count, l, p),
            UnsupportedCount
        );
    }
    for range in BAD_RANGES {
        assert_eq!(sample(range, 0, u.as_ptr(), 4, l, p), InvalidRange);
    }
    let nan_u = [0.25, f32::NAN, 0.5, 0.5];
    let one_u = [0.25, 1.0, 0.5, 0.5];
    let negative_u = [0.25, -0.1, 0.5, 0.5];
    assert_eq!(sample(VISIBLE, 0, nan_u.as_ptr(), 4, l, p), NonFinite);
    assert_eq!(sample(VISIBLE, 0, one_u.as_ptr(), 4, l, p), OutOfRange);
    assert_eq!(sample(VISIBLE, 2, negative_u.as_ptr(), 4, l, p), OutOfRange);
    assert!(lambda.iter().chain(&pdf).all(|&v| v == UNTOUCHED as f32));

    let values = [1.0f32; 4];
    let nm = [450.0f32, 500.0, 550.0, 600.0];
    let density = [1.0f32 / 470.0; 4];
    let mut xyz = [UNTOUCHED; 3];
    let x = xyz.as_mut_ptr();
    let estimate = |v: *const f32, l: *const f32, p: *const f32, count, x| unsafe {
        fspec_sampled_to_xyz(v, l, p, count, x)
    };
    assert_eq!(
        estimate(null(), nm.as_ptr(), density.as_ptr(), 4, x),
        NullPointer
    );
    assert_eq!(
        estimate(values.as_ptr(), null(), density.as_ptr(), 4, x),
        NullPointer
    );
    assert_eq!(
        estimate(values.as_ptr(), nm.as_ptr(), null(), 4, x),
        NullPointer
    );
    assert_eq!(
        estimate(
            values.as_ptr(),
            nm.as_ptr(),
            density.as_ptr(),
            4,
            null_mut()
        ),
        NullPointer
    );
    for count in BAD_COUNTS {
        assert_eq!(
            estimate(values.as_ptr(), nm.as_ptr(), density.as_ptr(), count, x),
            UnsupportedCount
        );
    }
    let nan_values = [1.0, f32::NAN, 1.0, 1.0];
    let bad_nm = [450.0, 0.0, 550.0, 600.0];
    let negative_pdf = [0.01, -0.01, 0.01, 0.01];
    assert_eq!(
        estimate(nan_values.as_ptr(), nm.as_ptr(), density.as_ptr(), 4, x),
        NonFinite
    );
    assert_eq!(
        estimate(values.as_ptr(), bad_nm.as_ptr(), density.as_ptr(), 4, x),
        InvalidWavelength
    );
    assert_eq!(
        estimate(values.as_ptr(), nm.as_ptr(), negative_pdf.as_ptr(), 4, x),
        NegativeValue
    );
    assert!(xyz.iter().all(|&v| v == UNTOUCHED));
}

#[test]
fn control_variates() {
    let mut cv = FspecControlVariate { opaque: [0; 16] };
    let mut estimate = UNTOUCHED;
    let (mut alpha, mut samples) = (UNTOUCHED, UNTOUCHED);
    // Zeroed memory never went through `fspec_cv_init`.
    assert_eq!(
        unsafe { fspec_cv_add(&mut cv, 1.0, 1.0, 1.0) },
        NotInitialised
    );
    assert_eq!(unsafe { fspec_cv_end_batch(&mut cv) }, NotInitialised);
    assert_eq!(
        unsafe { fspec_cv_estimate(&cv, &mut estimate, &mut alpha, &mut samples) },
        NotInitialised
    );
    assert_eq!(unsafe { fspec_cv_init(null_mut()) }, NullPointer);
    assert_eq!(
        unsafe { fspec_cv_add(null_mut(), 1.0, 1.0, 1.0) },
        NullPointer
    );
    assert_eq!(unsafe { fspec_cv_end_batch(null_mut()) }, NullPointer);
    assert_eq!(
        unsafe { fspec_cv_estimate(null(), &mut estimate, &mut alpha, &mut samples) },
        NullPointer
    );
    assert_eq!(unsafe { fspec_cv_init(&mut cv) }, FspecStatus::Ok);
    for (y, c, mu) in [
        (f64::NAN, 1.0, 1.0),
        (1.0, f64::INFINITY, 1.0),
        (1.0, 1.0, f64::NAN),
    ] {
        assert_eq!(unsafe { fspec_cv_add(&mut cv, y, c, mu) }, NonFinite);
    }
    assert_eq!(
        unsafe { fspec_cv_estimate(&cv, null_mut(), &mut alpha, &mut samples) },
        NullPointer
    );
    assert_eq!(
        unsafe { fspec_cv_estimate(&cv, &mut estimate, null_mut(), &mut samples) },
        NullPointer
    );
    assert_eq!(
        unsafe { fspec_cv_estimate(&cv, &mut estimate, &mut alpha, null_mut()) },
        NullPointer
    );
    assert_eq!([estimate, alpha, samples], [UNTOUCHED; 3]);
    let mut words = [0u64; 17];
    let shifted = misaligned_mut::<FspecControlVariate>(&mut words);
    assert_eq!(unsafe { fspec_cv_init(shifted) }, Misaligned);
}

#[test]
fn fourier_tables() {
    let nm = [400.0, 700.0];
    let eta = [1.5, 1.4];
    let k = [3.0, 3.2];
    let mut bytes = 0usize;
    assert_eq!(unsafe { fspec_table_size(8, null_mut()) }, NullPointer);
    for n in BAD_COUNTS {
        assert_eq!(unsafe { fspec_table_size(n, &mut bytes) }, UnsupportedCount);
    }
    assert_eq!(unsafe { fspec_table_size(8, &mut bytes) }, FspecStatus::Ok);
    let mut buffer = vec![0u64; bytes.div_ceil(8) + 1];
    let b = buffer.as_mut_ptr().cast();
    let dielectric = |buffer, bytes, range, n, nm: *const f64, eta: *const f64, count| unsafe {
        fspec_table_build_dielectric(buffer, bytes, range, n, nm, eta, count, 0)
    };
    assert_eq!(
        dielectric(null_mut(), bytes, VISIBLE, 8, nm.as_ptr(), eta.as_ptr(), 2),
        NullPointer
    );
    assert_eq!(
        dielectric(b, bytes, VISIBLE, 8, null(), eta.as_ptr(), 2),
        NullPointer
    );
    assert_eq!(
        dielectric(b, bytes, VISIBLE, 8, nm.as_ptr(), null(), 2),
        NullPointer
    );
    assert_eq!(
        dielectric(b, bytes, VISIBLE, 8, nm.as_ptr(), eta.as_ptr(), 0),
        BadLength
    );
    assert_eq!(
        dielectric(b, bytes - 1, VISIBLE, 8, nm.as_ptr(), eta.as_ptr(), 2),
        BufferTooSmall
    );
    for n in BAD_COUNTS {
        assert_eq!(
            dielectric(b, bytes, VISIBLE, n, nm.as_ptr(), eta.as_ptr(), 2),
            UnsupportedCount
        );
    }
    for range in BAD_RANGES {
        assert_eq!(
            dielectric(b, bytes, range, 8, nm.as_ptr(), eta.as_ptr(), 2),
            InvalidRange
        );
    }
    let unsorted = [700.0, 400.0];
    let zero_eta = [1.5, 0.0];
    let nan_eta = [1.5, f64::NAN];
    assert_eq!(
        dielectric(b, bytes, VISIBLE, 8, unsorted.as_ptr(), eta.as_ptr(), 2),
        NotIncreasing
    );
    assert_eq!(
        dielectric(b, bytes, VISIBLE, 8, nm.as_ptr(), zero_eta.as_ptr(), 2),
        InvalidParameter
    );
    assert_eq!(
        dielectric(b, bytes, VISIBLE, 8, nm.as_ptr(), nan_eta.as_ptr(), 2),
        NonFinite
    );

    let conductor = |buffer, range, n, k: *const f64, outside| unsafe {
        fspec_table_build_conductor(
            buffer,
            bytes,
            range,
            n,
            nm.as_ptr(),
            eta.as_ptr(),
            k,
            2,
            outside,
        )
    };
    assert_eq!(
        conductor(null_mut(), VISIBLE, 8, k.as_ptr(), 1.0),
        NullPointer
    );
    assert_eq!(conductor(b, VISIBLE, 8, null(), 1.0), NullPointer);
    for outside in [0.0, -1.0, f64::NAN] {
        assert_eq!(
            conductor(b, VISIBLE, 8, k.as_ptr(), outside),
            InvalidParameter
        );
    }
    let negative_k = [3.0, -1.0];
    assert_eq!(
        conductor(b, VISIBLE, 8, negative_k.as_ptr(), 1.0),
        NegativeValue
    );
    for n in BAD_COUNTS {
        assert_eq!(conductor(b, VISIBLE, n, k.as_ptr(), 1.0), UnsupportedCount);
    }

    let mut coeffs = [UNTOUCHED as f32; 32];
    let c = coeffs.as_mut_ptr();
    let lookup = |table: *const core::ffi::c_void, cos_theta, n, out| unsafe {
        fspec_table_lookup(table, cos_theta, n, out)
    };
    assert_eq!(lookup(buffer.as_ptr().cast(), 0.5, 8, c), NotInitialised);
    assert_eq!(
        dielectric(
            buffer.as_mut_ptr().cast(),
            bytes,
            VISIBLE,
            8,
            nm.as_ptr(),
            eta.as_ptr(),
            2
        ),
        FspecStatus::Ok
    );
    let t = buffer.as_ptr().cast();
    assert_eq!(lookup(null(), 0.5, 8, c), NullPointer);
    assert_eq!(lookup(t, 0.5, 8, null_mut()), NullPointer);
    assert_eq!(lookup(t, f64::NAN, 8, c), NonFinite);
    assert_eq!(lookup(t, 1.5, 8, c), OutOfRange);
    assert_eq!(lookup(t, -0.1, 8, c), OutOfRange);
    assert_eq!(lookup(t, 0.5, 12, c), UnsupportedCount);
    for n in BAD_COUNTS {
        assert_eq!(lookup(t, 0.5, n, c), UnsupportedCount);
    }
    assert_eq!(lookup(misaligned(&buffer), 0.5, 8, c), Misaligned);
    assert!(coeffs.iter().all(|&v| v == UNTOUCHED as f32));
}
