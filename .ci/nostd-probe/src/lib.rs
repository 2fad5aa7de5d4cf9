//! A `#![no_std]` static library calling the core's 8-lane truncated
//! product, XYZ kernel and projection: it only builds if spectral-core and
//! everything it depends on are free of `std`.
#![no_std]

use core::panic::PanicInfo;
use spectral_core::xyz::XyzKernel;
use spectral_core::{FourierSpectrum, SpectralRange, Spectrum, TabulatedSpectrum};
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
    let range = SpectralRange::VISIBLE;
    let Ok(kernel) = XyzKernel::<12>::new(&range) else {
        return -1.0;
    };
    let Ok(ramp) = TabulatedSpectrum::new(&[400.0, 700.0], &[0.0, 1.0]) else {
        return -1.0;
    };
    let projected = ramp.project::<12>(&range).to_lanes::<f32x8>();
    kernel.apply(&h.product(&projected))[1].reduce_add()
}
