//! The reference for the C and C++ examples (`examples/run.sh`): the same
//! scene computed with spectral-core directly, printed in the same format.
//!
//! An LED-like lamp and a tungsten (2856 K blackbody) lamp light a red
//! paint; each product is converted to XYZ by the four routes, and eight
//! dimmed copies of the LED are multiplied 8 lanes at once.

use spectral_core::FourierBasis;
use spectral_core::lane::Lane;
use spectral_core::xyz::{XyzConverter, XyzKernel, XyzRoute};
use spectral_core::{Blackbody, FourierSpectrum, SpectralRange, Spectrum, TabulatedSpectrum};
use wide::f32x8;

/// Coefficients per spectrum (the examples' `N`).
const N: usize = 16;
/// An LED-like lamp: a blue peak and a broad phosphor hump.
const LED_NM: [f64; 9] = [
    380.0, 430.0, 450.0, 470.0, 500.0, 560.0, 600.0, 680.0, 780.0,
];
const LED_VALUES: [f64; 9] = [0.0, 0.2, 1.0, 0.25, 0.3, 0.6, 0.55, 0.2, 0.0];
/// A red paint's reflectance.
const RED_NM: [f64; 6] = [380.0, 480.0, 560.0, 600.0, 640.0, 780.0];
const RED_VALUES: [f64; 6] = [0.05, 0.05, 0.08, 0.4, 0.7, 0.75];
/// CIE illuminant A's colour temperature, K.
const TUNGSTEN_K: f64 = 2856.0;
/// Ray lanes of the 8-lane product.
const LANES: usize = 8;

fn print_xyz(label: &str, xyz: [f64; 3]) {
    println!("{label} {:.9e} {:.9e} {:.9e}", xyz[0], xyz[1], xyz[2]);
}

fn main() -> Result<(), spectral_core::SpectralError> {
    let range = SpectralRange::VISIBLE;
    let led = TabulatedSpectrum::new(&LED_NM, &LED_VALUES)?.project::<N>(&range);
    let red = TabulatedSpectrum::new(&RED_NM, &RED_VALUES)?.project::<N>(&range);
    let tungsten = Blackbody::new(TUNGSTEN_K)?.project::<N>(&range);
    let converter = XyzConverter::<N>::new(&FourierBasis::new(range))?;
    let led_red = led.product(&red);
    for (name, route) in [
        ("series", XyzRoute::Series),
        ("lut", XyzRoute::Lut),
        ("zeroth", XyzRoute::Zeroth),
        ("mese", XyzRoute::Mese),
    ] {
        print_xyz(
            &format!("led_red_{name}"),
            converter.convert(route, &led_red).to_array(),
        );
    }
    let tungsten_red = tungsten.product(&red);
    print_xyz(
        "tungsten_red_zeroth",
        converter
            .convert(XyzRoute::Zeroth, &tungsten_red)
            .to_array(),
    );

    // Lane `lane` carries the LED dimmed to (lane + 1)/8, every lane the red paint.
    let dimmed =
        FourierSpectrum::<f32x8, N>::from_lanes(|lane| led.scale((lane + 1) as f64 / LANES as f64));
    let paint = red.to_lanes::<f32x8>();
    let kernel = XyzKernel::<N>::new(&FourierBasis::new(range))?;
    let luminance = kernel.apply(&dimmed.product(&paint)).y;
    let values: Vec<String> = (0..LANES)
        .map(|lane| format!("{:.9e}", luminance.lane(lane)))
        .collect();
    println!("lanes_y {}", values.join(" "));
    Ok(())
}
