//! A `#![no_std]` static library calling the core's 8-lane truncated
//! product, XYZ kernel, projection and RGB upsampling: it only builds if
//! spectral-core (default features) and everything it depends on are free
//! of `std`.
#![no_std]

use core::panic::PanicInfo;
use spectral_core::upsample::srgb_reflectance;
use spectral_core::xyz::XyzKernel;
use spectral_core::{FourierBasis, FourierSpectrum, TabulatedSpectrum};
use wide::f32x8;

#[panic_handler]
fn panic(_info: &PanicInfo) -> ! {
    loop {}
}

/// Truncated product of two 8-lane spectra with 12 coefficients
/// (coefficient-major, 8 lanes per coefficient) and its XYZ.
#[unsafe(no_mangle)]
pub extern "C" fn probe_product(out: &mut [f32; 96], a: &[f32; 96], b: &[f32; 96]) -> f32 {
    let load = |v: &[f32; 96]| -> FourierSpectrum<f32x8, 12> {
        FourierSpectrum::from_coeffs(core::array::from_fn(|j| {
            f32x8::new(core::array::from_fn(|lane| v[j * 8 + lane]))
        }))
    };
    let h = load(a).product(&load(b));
    for (j, c) in h.coeffs.iter().enumerate() {
        out[j * 8..j * 8 + 8].copy_from_slice(&c.to_array());
    }
    let basis = FourierBasis::<12>::VISIBLE;
    let Ok(kernel) = XyzKernel::new(&basis) else {
        return -1.0;
    };
    let Ok(ramp) = TabulatedSpectrum::new(&[400.0, 700.0], &[0.0, 1.0]) else {
        return -1.0;
    };
    // The ramp lit by an upsampled RGB (feature `upsampling`: the table).
    let Ok(paint) = srgb_reflectance([0.8, 0.3, 0.1]) else {
        return -1.0;
    };
    let lit = basis.project(&ramp).product(&basis.project(&paint));
    kernel
        .apply(&h.product(&lit.to_lanes::<f32x8>()))
        .y
        .reduce_add()
}
