//! `fspec spectrum`: inspect one spectrum — its Fourier coefficients, its XYZ
//! by every route against the exact reference, an sRGB preview, and the
//! reconstruction error of the truncated (and Fejér-damped) series.

use crate::coeffs::{MAX_COEFFS, dispatch_coeffs};
use crate::error::CliError;
use crate::spectrum_file::{SpectrumSource, resolve};
use serde::Serialize;
use spectral_core::color::Xyz;
use spectral_core::damping::Damping;
use spectral_core::delta_e::delta_e2000;
use spectral_core::registry::Builtin;
use spectral_core::xyz::{XyzConverter, XyzRoute, reference_xyz, xyz_of};
use spectral_core::{FourierBasis, FourierSpectrum, SpectralRange, Spectrum, cmf};
use std::io::Write;

/// Arguments of `fspec spectrum`.
#[derive(Debug, Clone, clap::Args)]
pub struct SpectrumArgs {
    /// A two-column CSV file (`wavelength_nm,value`; `#` comments and one
    /// header row allowed) or a built-in name: d65, d50, a, fl2, fl7, fl11,
    /// led-b1 … led-b5, led-bh1, led-rgb1, led-v1, led-v2, colorchecker-1 …
    /// colorchecker-24, cie-x/y/z, gold-n, gold-k, …, `blackbody-<kelvin>`.
    #[arg(required_unless_present = "list")]
    pub spectrum: Option<String>,
    /// Number of Fourier coefficients N (1–32).
    #[arg(long, default_value_t = 12, value_parser = clap::value_parser!(u16).range(1..=MAX_COEFFS as i64))]
    pub coeffs: u16,
    /// Lower end of the spectral range, nm (inside the CIE table, 360–830).
    #[arg(long, default_value_t = cmf::FIRST_NM)]
    pub min_nm: f64,
    /// Upper end of the spectral range, nm (inside the CIE table, 360–830).
    #[arg(long, default_value_t = cmf::LAST_NM)]
    pub max_nm: f64,
    /// Print the report as JSON with the keys coeffs, range_nm, coefficients,
    /// xyz_reference, xyz {series, lut, zeroth, mese}, max_abs_error, rms_error.
    #[arg(long)]
    pub json: bool,
    /// List the built-in spectra and exit.
    #[arg(long)]
    pub list: bool,
}

/// XYZ by each route.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct XyzByRoute {
    /// Route 1: series reconstruction at the table wavelengths.
    pub series: [f64; 3],
    /// Route 2: the same with a precomputed cosine table.
    pub lut: [f64; 3],
    /// Route 3: zeroth coefficient of the product with the CMFs.
    pub zeroth: [f64; 3],
    /// Route 4: unbounded MESE reconstruction.
    pub mese: [f64; 3],
}

/// The JSON report (exactly the documented keys).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct SpectrumReport {
    /// N.
    pub coeffs: usize,
    /// `[min, max]`, nm.
    pub range_nm: [f64; 2],
    /// `c_0 … c_{N−1}`.
    pub coefficients: Vec<f64>,
    /// XYZ of the spectrum itself (exact for tabulated data), `∫ȳ`-normalised.
    pub xyz_reference: [f64; 3],
    /// XYZ from the coefficients by each route.
    pub xyz: XyzByRoute,
    /// Largest |series − spectrum| on the 1 nm grid of the range.
    pub max_abs_error: f64,
    /// RMS of series − spectrum on the same grid.
    pub rms_error: f64,
}

/// Text-only extras.
#[derive(Debug, Clone, PartialEq)]
pub struct Extras {
    /// Max and RMS error of the Fejér-damped series.
    pub fejer_errors: [f64; 2],
    /// Smallest value of the undamped series on the grid (ringing below 0).
    pub series_min: f64,
    /// Smallest value of the Fejér-damped series on the grid.
    pub fejer_min: f64,
}

/// Error statistics of a reconstruction on the 1 nm grid: (max, rms, min).
fn errors<const N: usize>(
    series: &FourierSpectrum<f64, N>,
    spectrum: &impl Spectrum,
    range: &SpectralRange,
) -> (f64, f64, f64) {
    let steps = (range.width_nm() / cmf::STEP_NM).floor() as usize;
    let basis = FourierBasis::new(*range);
    let (mut max, mut sum_sq, mut min) = (0.0f64, 0.0, f64::INFINITY);
    for i in 0..=steps {
        let lambda_nm = range.min_nm() + i as f64 * cmf::STEP_NM;
        let value = series.eval(&basis, lambda_nm);
        let error = value - spectrum.value(lambda_nm);
        max = max.max(error.abs());
        sum_sq += error * error;
        min = min.min(value);
    }
    (max, (sum_sq / (steps + 1) as f64).sqrt(), min)
}

fn analyse<const N: usize>(
    spectrum: &impl Spectrum,
    reference: Xyz,
    range: SpectralRange,
) -> Result<(SpectrumReport, Extras), CliError> {
    let converter = XyzConverter::<N>::new(&FourierBasis::new(range))
        .map_err(|_| CliError::input("the range must lie inside 360–830 nm with min < max"))?;
    let coefficients = spectrum.project::<N>(&range);
    let route = |r| converter.convert(r, &coefficients).to_array();
    let (max_abs_error, rms_error, series_min) = errors(&coefficients, spectrum, &range);
    let fejer = coefficients.damped(Damping::Fejer);
    let (fejer_max, fejer_rms, fejer_min) = errors(&fejer, spectrum, &range);
    Ok((
        SpectrumReport {
            coeffs: N,
            range_nm: [range.min_nm(), range.max_nm()],
            coefficients: coefficients.coeffs.to_vec(),
            xyz_reference: reference.to_array(),
            xyz: XyzByRoute {
                series: route(XyzRoute::Series),
                lut: route(XyzRoute::Lut),
                zeroth: route(XyzRoute::Zeroth),
                mese: route(XyzRoute::Mese),
            },
            max_abs_error,
            rms_error,
        },
        Extras {
            fejer_errors: [fejer_max, fejer_rms],
            series_min,
            fejer_min,
        },
    ))
}

/// Builds the report for already-parsed arguments.
pub fn build_report(args: &SpectrumArgs) -> Result<(String, SpectrumReport, Extras), CliError> {
    let range = SpectralRange::new(args.min_nm, args.max_nm).map_err(|_| {
        CliError::input(format!(
            "--min-nm {} --max-nm {}: need 0 < min < max",
            args.min_nm, args.max_nm
        ))
    })?;
    let argument = args.spectrum.as_deref().unwrap_or_default();
    let source = resolve(argument)?;
    let n = usize::from(args.coeffs);
    let (label, (report, extras)) = match &source {
        SpectrumSource::File(data) => {
            let tabulated = data
                .tabulated()
                .map_err(|e| CliError::input(format!("{argument}: {e}")))?;
            let reference = reference_xyz(&tabulated, &range);
            let label = format!(
                "{argument} ({} samples, {}–{} nm)",
                data.lambda_nm.len(),
                data.lambda_nm[0],
                data.lambda_nm[data.lambda_nm.len() - 1]
            );
            let result = dispatch_coeffs!(n, |N| analyse::<N>(&tabulated, reference, range))?;
            (label, result)
        }
        SpectrumSource::Builtin(builtin) => {
            let reference = match builtin.tabulated() {
                Some(tabulated) => reference_xyz(&tabulated, &range),
                None => xyz_of(builtin, &range),
            };
            let label = format!("{builtin} — {}", builtin.description());
            let result = dispatch_coeffs!(n, |N| analyse::<N>(builtin, reference, range))?;
            (label, result)
        }
    };
    Ok((label, report, extras))
}

fn format_xyz(v: [f64; 3]) -> String {
    format!("{:>12.6} {:>12.6} {:>12.6}", v[0], v[1], v[2])
}

/// The human-readable report.
pub fn render_text(label: &str, report: &SpectrumReport, extras: &Extras) -> String {
    let mut out = String::new();
    let [min_nm, max_nm] = report.range_nm;
    out += &format!("spectrum     {label}\n");
    out += &format!(
        "range        {min_nm}–{max_nm} nm, N = {} cosine coefficients c_j = (1/π)∫g(φ)cos(jφ)dφ\n",
        report.coeffs
    );
    out += "coefficients\n";
    for (j, c) in report.coefficients.iter().enumerate() {
        out += &format!("  c{j:<3} {c:>14.8}\n");
    }
    let reference = Xyz::from_array(report.xyz_reference);
    // ΔE2000 against the reference, relative to the equal-energy white of the
    // same luminance scale (Y of the reference, or 1 if it is darker).
    let white = Xyz::new(1.0, 1.0, 1.0).scale(reference.y.max(1.0));
    out += &format!(
        "xyz          {:>12} {:>12} {:>12}   ΔE2000 vs reference\n",
        "X", "Y", "Z"
    );
    out += &format!("  reference  {}\n", format_xyz(report.xyz_reference));
    for (name, v) in [
        ("series", report.xyz.series),
        ("lut", report.xyz.lut),
        ("zeroth", report.xyz.zeroth),
        ("mese", report.xyz.mese),
    ] {
        let de = delta_e2000(reference.to_lab(white), Xyz::from_array(v).to_lab(white));
        out += &format!("  {name:<9}  {}   {de:.2e}\n", format_xyz(v));
    }
    let preview = reference.scale(1.0 / reference.y.max(1.0)).to_linear_srgb();
    let [r, g, b] = preview.to_srgb8();
    out += &format!(
        "srgb         #{r:02x}{g:02x}{b:02x}  (linear {:.4} {:.4} {:.4}; emission scaled to Y = 1)\n",
        preview.r, preview.g, preview.b
    );
    out += &format!(
        "error (1 nm) truncated series: max {:.6}  rms {:.6}  min value {:.6}\n",
        report.max_abs_error, report.rms_error, extras.series_min
    );
    out += &format!(
        "             Fejér-damped:     max {:.6}  rms {:.6}  min value {:.6}\n",
        extras.fejer_errors[0], extras.fejer_errors[1], extras.fejer_min
    );
    out
}

/// The list of built-ins for `--list`.
pub fn render_list() -> String {
    let mut out =
        String::from("built-in spectra (also blackbody-<kelvin>, e.g. blackbody-6500):\n");
    for builtin in Builtin::all() {
        out += &format!("  {:<16} {}\n", builtin.to_string(), builtin.description());
    }
    out
}

/// Runs `fspec spectrum`, writing to `out`.
pub fn run(args: &SpectrumArgs, out: &mut impl Write) -> Result<(), CliError> {
    let text = if args.list {
        render_list()
    } else {
        let (label, report, extras) = build_report(args)?;
        if args.json {
            let mut json = serde_json::to_string_pretty(&report)
                .map_err(|e| CliError::input(format!("cannot encode JSON: {e}")))?;
            json.push('\n');
            json
        } else {
            render_text(&label, &report, &extras)
        }
    };
    out.write_all(text.as_bytes())
        .map_err(|e| CliError::input(format!("cannot write the report: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(spectrum: &str, coeffs: u16) -> SpectrumArgs {
        SpectrumArgs {
            spectrum: Some(spectrum.to_string()),
            coeffs,
            min_nm: 360.0,
            max_nm: 830.0,
            json: false,
            list: false,
        }
    }

    #[test]
    fn report_routes_agree_with_reference_for_smooth_spectra() {
        let (_, report, _) = build_report(&args("d65", 16)).unwrap();
        assert_eq!(report.coefficients.len(), 16);
        let reference = report.xyz_reference;
        for route in [
            report.xyz.series,
            report.xyz.lut,
            report.xyz.zeroth,
            report.xyz.mese,
        ] {
            for r in 0..3 {
                assert!(
                    (route[r] / reference[r] - 1.0).abs() < 0.01,
                    "{route:?} vs {reference:?}"
                );
            }
        }
    }

    #[test]
    fn black_spectrum_has_a_finite_report() {
        let dir = test_support::ScratchDir::new("fspec-black", "report").unwrap();
        let path = dir.join("black.csv");
        std::fs::write(&path, "400,0\n700,0\n").unwrap();
        let (label, report, extras) = build_report(&args(path.to_str().unwrap(), 4)).unwrap();
        let text = render_text(&label, &report, &extras);
        assert!(!text.contains("NaN"), "{text}");
        assert!(text.contains("#000000"));
    }

    #[test]
    fn range_outside_the_table_is_refused() {
        let mut a = args("d65", 4);
        a.min_nm = 300.0;
        assert!(
            build_report(&a)
                .unwrap_err()
                .to_string()
                .contains("360–830")
        );
        a.min_nm = 900.0;
        assert!(
            build_report(&a)
                .unwrap_err()
                .to_string()
                .contains("min < max")
        );
    }
}
