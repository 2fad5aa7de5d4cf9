//! Loading spectra from CSV files or the built-in registry, with errors that
//! name the file and line.

use crate::error::CliError;
use spectral_core::csv::rows;
use spectral_core::registry::Builtin;
use spectral_core::{SpectralError, TabulatedSpectrum};
use std::path::Path;

/// Largest spectrum file accepted, bytes (a 1 nm table is ~10 KiB).
pub const MAX_FILE_BYTES: u64 = 64 * 1024 * 1024;

/// A tabulated spectrum owned by the CLI, with the CSV line of each sample.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectrumData {
    /// Wavelengths, nm.
    pub lambda_nm: Vec<f64>,
    /// Values.
    pub values: Vec<f64>,
    /// 1-based source line of each sample (for messages).
    pub lines: Vec<usize>,
}

impl SpectrumData {
    /// The validated borrowed view used by the core.
    pub fn tabulated(&self) -> Result<TabulatedSpectrum<'_>, SpectralError> {
        TabulatedSpectrum::new(&self.lambda_nm, &self.values)
    }
}

/// Parses two-column CSV text (`wavelength_nm,value`) and validates it as a
/// spectrum; `origin` names the source in messages.
pub fn parse_csv(text: &str, origin: &str) -> Result<SpectrumData, CliError> {
    let mut data = SpectrumData {
        lambda_nm: Vec::new(),
        values: Vec::new(),
        lines: Vec::new(),
    };
    for row in rows::<2>(text) {
        let (line, [lambda_nm, value]) =
            row.map_err(|e| CliError::input(format!("{origin}: {e}")))?;
        data.lambda_nm.push(lambda_nm);
        data.values.push(value);
        data.lines.push(line);
    }
    if data.lambda_nm.is_empty() {
        return Err(CliError::input(format!(
            "{origin}: no data rows (expected `wavelength_nm,value` lines)"
        )));
    }
    if let Err(e) = data.tabulated() {
        return Err(CliError::input(describe(&e, &data, origin)));
    }
    Ok(data)
}

/// A message for a validation error that points at the CSV line.
fn describe(error: &SpectralError, data: &SpectrumData, origin: &str) -> String {
    let line = |index: usize| data.lines.get(index).copied().unwrap_or(0);
    match *error {
        SpectralError::InvalidWavelength { index } => format!(
            "{origin}: line {}: wavelength {} nm is not a positive number",
            line(index),
            data.lambda_nm[index]
        ),
        SpectralError::NotIncreasing { index } => format!(
            "{origin}: line {}: wavelength {} nm is not larger than the previous {} nm (wavelengths must be sorted and unique)",
            line(index),
            data.lambda_nm[index],
            data.lambda_nm[index - 1]
        ),
        SpectralError::NonFiniteValue { index } => {
            format!("{origin}: line {}: value is NaN or infinite", line(index))
        }
        SpectralError::NegativeValue { index } => format!(
            "{origin}: line {}: value {} is negative (spectra must be non-negative)",
            line(index),
            data.values[index]
        ),
        other => format!("{origin}: {other}"),
    }
}

/// Reads and parses a CSV spectrum file.
pub fn load_csv(path: &Path) -> Result<SpectrumData, CliError> {
    let (text, origin) = read_text_file(path, MAX_FILE_BYTES, "a spectrum file")?;
    parse_csv(&text, &origin)
}

/// Reads a small text file whole, with the path as messages show it:
/// refuses a directory, a file over `max_bytes` (`what` names the kind of
/// file in that message) and bytes that are not UTF-8, one line each.
pub(crate) fn read_text_file(
    path: &Path,
    max_bytes: u64,
    what: &str,
) -> Result<(String, String), CliError> {
    let origin = path.display().to_string();
    let metadata =
        std::fs::metadata(path).map_err(|e| CliError::input(format!("{origin}: {e}")))?;
    if metadata.is_dir() {
        return Err(CliError::input(format!("{origin}: is a directory")));
    }
    if metadata.len() > max_bytes {
        return Err(CliError::input(format!(
            "{origin}: {} bytes is larger than the {} MiB limit for {what}",
            metadata.len(),
            max_bytes / (1024 * 1024)
        )));
    }
    let bytes = std::fs::read(path).map_err(|e| CliError::input(format!("{origin}: {e}")))?;
    let text = String::from_utf8(bytes)
        .map_err(|_| CliError::input(format!("{origin}: not UTF-8 text")))?;
    Ok((text, origin))
}

/// Where a spectrum argument resolved to.
#[derive(Debug, Clone, PartialEq)]
pub enum SpectrumSource {
    /// A CSV file.
    File(SpectrumData),
    /// A built-in name.
    Builtin(Builtin),
}

/// Resolves a command-line spectrum argument: an existing file, else a
/// built-in name, else an error that says which of the two was meant.
pub fn resolve(argument: &str) -> Result<SpectrumSource, CliError> {
    let path = Path::new(argument);
    if path.exists() {
        return load_csv(path).map(SpectrumSource::File);
    }
    match Builtin::lookup(argument) {
        Ok(builtin) => Ok(SpectrumSource::Builtin(builtin)),
        Err(SpectralError::InvalidTemperature) => Err(CliError::input(format!(
            "`{argument}`: a blackbody needs a finite positive temperature in kelvin, e.g. blackbody-6500"
        ))),
        Err(_) => {
            let looks_like_path = argument.contains(['/', '\\', '.']);
            if looks_like_path {
                Err(CliError::input(format!("{argument}: no such file")))
            } else {
                Err(CliError::input(format!(
                    "`{argument}` is neither a file nor a built-in spectrum (run `fspec spectrum --list`)"
                )))
            }
        }
    }
}

/// Fuzz entry point: arbitrary bytes through the CSV loader. Valid spectra
/// must project and convert to finite numbers; nothing may panic.
pub fn fuzz_csv_spectrum(bytes: &[u8]) {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    if let Ok(data) = parse_csv(text, "fuzz") {
        if let Ok(spectrum) = data.tabulated() {
            use spectral_core::Spectrum;
            let range = spectral_core::SpectralRange::VISIBLE;
            let coefficients = spectrum.project::<8>(&range);
            let reference = spectral_core::xyz::reference_xyz(&spectrum, &range);
            let largest = data.values.iter().fold(0.0f64, |a, &b| a.max(b));
            // Finite inputs below ~1e300 give finite outputs.
            if largest < 1e300 {
                assert!(coefficients.coeffs.iter().all(|c| c.is_finite()));
                assert!(reference.to_array().iter().all(|c| c.is_finite()));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn message(text: &str) -> String {
        parse_csv(text, "s.csv").unwrap_err().to_string()
    }

    #[test]
    fn good_file_parses_with_lines() {
        let data = parse_csv("# c\nnm,v\n400,1\n500,2\n", "s.csv").unwrap();
        assert_eq!(data.lambda_nm, [400.0, 500.0]);
        assert_eq!(data.lines, [3, 4]);
    }

    #[test]
    fn errors_name_file_and_line() {
        assert_eq!(
            message("nm,v\n400,1\n400,2\n"),
            "s.csv: line 3: wavelength 400 nm is not larger than the previous 400 nm (wavelengths must be sorted and unique)"
        );
        assert_eq!(
            message("400,1\n300,2\n"),
            "s.csv: line 2: wavelength 300 nm is not larger than the previous 400 nm (wavelengths must be sorted and unique)"
        );
        assert_eq!(
            message("400,1\n500,x\n"),
            "s.csv: line 2: cell 2 is not a number"
        );
        assert_eq!(
            message("400,1\n500,nan\n"),
            "s.csv: line 2: cell 2 is NaN or infinite"
        );
        assert_eq!(
            message("400,-1\n"),
            "s.csv: line 1: value -1 is negative (spectra must be non-negative)"
        );
        assert_eq!(
            message("-400,1\n"),
            "s.csv: line 1: wavelength -400 nm is not a positive number"
        );
        assert_eq!(
            message("# nothing\n"),
            "s.csv: no data rows (expected `wavelength_nm,value` lines)"
        );
    }

    #[test]
    fn resolve_prefers_files_then_names() {
        assert!(matches!(resolve("d65"), Ok(SpectrumSource::Builtin(_))));
        assert_eq!(
            resolve("missing.csv").unwrap_err().to_string(),
            "missing.csv: no such file"
        );
        assert!(
            resolve("nosuchname")
                .unwrap_err()
                .to_string()
                .contains("neither a file")
        );
        assert!(
            resolve("blackbody-x")
                .unwrap_err()
                .to_string()
                .contains("temperature")
        );
    }

    #[test]
    fn fuzz_entry_survives_odd_inputs() {
        for input in [
            &b"400,1e308\n500,1e308\n"[..],
            b"\xff\xfe",
            b"1,2\n1,2\n",
            b"5e-324,0\n",
        ] {
            fuzz_csv_spectrum(input);
        }
    }
}
