//! `--observer` and `--sensor FILE.csv`: what the film's three channels
//! measure (the core side is `spectral_core::observer`).
//!
//! A sensor file is CSV text (`#` lines are comments):
//!
//! ```text
//! wavelength_nm,r,g,b          header: wavelength_nm, then K ≥ 3 curve names
//! 400,0.012,0.004,0.210        K + 1 numbers per row
//! 405,0.015,0.006,0.260
//! …
//! to_xyz,0.41,0.36,0.18        optional: three rows, K numbers each,
//! to_xyz,0.21,0.72,0.07        the matrix M from the K sensor channels
//! to_xyz,0.02,0.12,0.95        to CIE XYZ (the display space)
//! ```
//!
//! Rules (each broken one is refused with one line naming the file and the
//! line): wavelengths strictly increasing (unsorted or duplicate refused),
//! whole nanometres, inside the CIE table's 360–830 nm (off-range refused);
//! values finite and non-negative; at least two rows; no curve that is
//! zero everywhere; with `K ≠ 3` the matrix is required (it is what makes
//! K channels three). A curve is linear between its rows and zero outside
//! its first and last row. Whole nanometres are required because every
//! observer is carried on the 1 nm grid of the CIE tables: a polyline whose
//! corners lie on that grid is represented exactly, so the sensor is exact
//! in every transport.
//!
//! What is rendered, with `s_k` the raw curves:
//! * with `to_xyz`: the three curves `(M s)_x, (M s)_y, (M s)_z`, divided
//!   by `∫ (M s)_y dλ`: XYZ as the sensor plus its matrix sees it (a
//!   constant spectrum of 1 has `Y = 1`), written like any render
//!   (XYZ → sRGB). Exact, because `M` is linear: the matrix applied to the
//!   channel integrals equals the integrals of the mixed curves;
//! * without: the sensor's own three channels, divided by `∫ s_1 dλ` (a
//!   constant spectrum of 1 has a second channel of 1), written as the
//!   image's linear R, G, B unchanged (the curves are carried as the XYZ
//!   that the outputs' XYZ → linear sRGB matrix maps back to `s`: through
//!   that matrix's inverse computed in `f64`, so the round trip is exact up
//!   to rounding, about 1e-15 of the largest channel).

use crate::error::CliError;
use crate::spectrum_file::read_text_file;
use spectral_core::cmf;
use spectral_core::color::XYZ_TO_LINEAR_SRGB;
use spectral_core::observer::{Observer, SAMPLES, StandardObserver};
use std::path::Path;

/// Largest sensor file accepted, bytes (a 1 nm table of many channels is
/// well under 1 MiB).
pub const MAX_FILE_BYTES: u64 = 16 * 1024 * 1024;
/// Most curves accepted in one sensor file (multispectral cameras have a
/// few dozen bands).
pub const MAX_CURVES: usize = 64;
/// The first field of a matrix row.
pub const MATRIX_LABEL: &str = "to_xyz";

/// What a render's channels measure.
#[derive(Debug, Clone, PartialEq)]
pub enum ObserverChoice {
    /// A CIE standard observer (CIE 1931 2° is the default).
    Standard(StandardObserver),
    /// A camera sensor read from a CSV file.
    Sensor(SensorCurves),
}

impl Default for ObserverChoice {
    fn default() -> Self {
        Self::Standard(StandardObserver::Cie1931)
    }
}

impl ObserverChoice {
    /// `--observer NAME`.
    pub fn standard(name: &str) -> Result<Self, CliError> {
        StandardObserver::lookup(name)
            .map(Self::Standard)
            .map_err(|_| {
                let names: Vec<&str> = StandardObserver::ALL.iter().map(|o| o.name()).collect();
                CliError::input(format!(
                    "observer `{name}`: use one of {}",
                    names.join(", ")
                ))
            })
    }

    /// The observer the transports use.
    pub fn observer(&self) -> Result<Observer, CliError> {
        match self {
            Self::Standard(which) => Ok(Observer::standard(*which)),
            Self::Sensor(sensor) => sensor.observer(),
        }
    }

    /// Whether this is the default (CIE 1931 2°).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// For messages and reports.
    pub fn describe(&self) -> String {
        match self {
            Self::Standard(which) => which.name().to_string(),
            Self::Sensor(sensor) => format!("sensor {}", sensor.origin),
        }
    }
}

/// A parsed sensor file.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorCurves {
    /// The file, for messages.
    pub origin: String,
    /// Curve names from the header.
    pub names: Vec<String>,
    /// Whole-nanometre wavelengths, increasing.
    pub lambda_nm: Vec<f64>,
    /// `curves[k][i]`: curve `k` at `lambda_nm[i]`.
    pub curves: Vec<Vec<f64>>,
    /// The optional 3 × K matrix to CIE XYZ.
    pub to_xyz: Option<[Vec<f64>; 3]>,
}

impl SensorCurves {
    /// Curve `k` on the 1 nm grid: linear between rows (exact, the rows
    /// are on the grid), zero outside the first and last row.
    fn on_grid(&self, k: usize) -> [f64; SAMPLES] {
        let mut out = [0.0; SAMPLES];
        let values = &self.curves[k];
        for pair in 0..self.lambda_nm.len().saturating_sub(1) {
            let (a, b) = (self.lambda_nm[pair], self.lambda_nm[pair + 1]);
            let first = grid_index(a);
            let last = grid_index(b);
            for (i, slot) in out.iter_mut().enumerate().take(last + 1).skip(first) {
                let lambda_nm = cmf::FIRST_NM + i as f64 * cmf::STEP_NM;
                let t = (lambda_nm - a) / (b - a);
                *slot = values[pair] + t * (values[pair + 1] - values[pair]);
            }
        }
        out
    }

    /// The shape the parser guarantees: 3 to [`MAX_CURVES`] named curves,
    /// each with a value per wavelength, at least two wavelengths, and a
    /// matrix of three rows of one entry per curve (required unless there
    /// are exactly three curves).
    pub fn validate(&self) -> Result<(), CliError> {
        let k = self.curves.len();
        let shape_ok = (3..=MAX_CURVES).contains(&k)
            && self.names.len() == k
            && self.lambda_nm.len() >= 2
            && self.curves.iter().all(|c| c.len() == self.lambda_nm.len())
            && match &self.to_xyz {
                Some(rows) => rows.iter().all(|r| r.len() == k),
                None => k == 3,
            };
        if shape_ok {
            Ok(())
        } else {
            Err(CliError::input(format!(
                "{}: a sensor needs 3 to {MAX_CURVES} curves of one value per wavelength, at least two wavelengths, and a 3-row matrix unless it has exactly three curves",
                self.origin
            )))
        }
    }

    /// The observer the render uses (module docs).
    pub fn observer(&self) -> Result<Observer, CliError> {
        self.validate()?;
        let raw: Vec<[f64; SAMPLES]> = (0..self.curves.len()).map(|k| self.on_grid(k)).collect();
        match &self.to_xyz {
            Some(matrix) => {
                let curves: [[f64; SAMPLES]; 3] = core::array::from_fn(|row| {
                    core::array::from_fn(|i| {
                        matrix[row]
                            .iter()
                            .zip(&raw)
                            .map(|(&m, curve)| m * curve[i])
                            .sum()
                    })
                });
                Observer::from_curves(curves).map_err(|_| {
                    CliError::input(format!(
                        "{}: the `{MATRIX_LABEL}` matrix gives a Y curve with no positive integral, or values too large to be finite",
                        self.origin
                    ))
                })
            }
            None => {
                let to_xyz = inverse3(&XYZ_TO_LINEAR_SRGB);
                let curves: [[f64; SAMPLES]; 3] = core::array::from_fn(|row| {
                    core::array::from_fn(|i| (0..3).map(|k| to_xyz[row][k] * raw[k][i]).sum())
                });
                let normaliser_nm = Observer::from_curves([raw[0], raw[1], raw[2]])
                    .map(|o| o.normaliser_nm())
                    .unwrap_or(0.0);
                Observer::with_normaliser(curves, normaliser_nm).map_err(|_| {
                    CliError::input(format!(
                        "{}: the second curve `{}` has no positive integral, or the values are too large to be finite",
                        self.origin, self.names[1]
                    ))
                })
            }
        }
    }
}

/// The inverse of a 3 × 3 matrix by cofactors (in `f64`; the matrices
/// inverted here are fixed and well conditioned).
fn inverse3(m: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let cofactor = |r: usize, c: usize| {
        let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
        let (c1, c2) = ((c + 1) % 3, (c + 2) % 3);
        m[r1][c1] * m[r2][c2] - m[r1][c2] * m[r2][c1]
    };
    let determinant: f64 = (0..3).map(|c| m[0][c] * cofactor(0, c)).sum();
    core::array::from_fn(|r| core::array::from_fn(|c| cofactor(c, r) / determinant))
}

/// The grid index of a whole-nanometre wavelength inside the grid.
fn grid_index(lambda_nm: f64) -> usize {
    ((lambda_nm - cmf::FIRST_NM) / cmf::STEP_NM).round() as usize
}

/// Parses a sensor file's text; `origin` names it in messages.
pub fn parse_sensor_csv(text: &str, origin: &str) -> Result<SensorCurves, CliError> {
    let fail = |line: usize, what: String| CliError::input(format!("{origin}:{line}: {what}"));
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let Some((header_line, header)) = lines.next() else {
        return Err(CliError::input(format!(
            "{origin}: empty sensor file (expected a `wavelength_nm,<curve>,<curve>,<curve>…` header)"
        )));
    };
    let names: Vec<String> = header.split(',').map(|f| f.trim().to_string()).collect();
    if names.first().map(String::as_str) != Some("wavelength_nm") {
        return Err(fail(
            header_line,
            "the header must start with `wavelength_nm`, then one name per curve".into(),
        ));
    }
    let names = names[1..].to_vec();
    if names.len() < 3 || names.len() > MAX_CURVES {
        return Err(fail(
            header_line,
            format!(
                "{} curves: a sensor has 3 to {MAX_CURVES} response curves",
                names.len()
            ),
        ));
    }
    let k = names.len();
    let mut sensor = SensorCurves {
        origin: origin.to_string(),
        names,
        lambda_nm: Vec::new(),
        curves: vec![Vec::new(); k],
        to_xyz: None,
    };
    let mut matrix: Vec<Vec<f64>> = Vec::new();
    for (line, text) in lines {
        let fields: Vec<&str> = text.split(',').map(str::trim).collect();
        let numbers = |fields: &[&str]| -> Result<Vec<f64>, CliError> {
            fields
                .iter()
                .map(|f| {
                    f.parse::<f64>()
                        .map_err(|_| fail(line, format!("`{f}` is not a number")))
                })
                .collect()
        };
        if fields[0] == MATRIX_LABEL {
            if matrix.len() == 3 {
                return Err(fail(line, format!("more than three `{MATRIX_LABEL}` rows")));
            }
            let row = numbers(&fields[1..])?;
            if row.len() != k {
                return Err(fail(
                    line,
                    format!("a `{MATRIX_LABEL}` row needs {k} numbers, one per curve"),
                ));
            }
            if let Some(bad) = row.iter().find(|v| !v.is_finite()) {
                return Err(fail(line, format!("matrix entry {bad} is not finite")));
            }
            matrix.push(row);
            continue;
        }
        if !matrix.is_empty() {
            return Err(fail(
                line,
                format!("data rows must come before the `{MATRIX_LABEL}` rows"),
            ));
        }
        let row = numbers(&fields)?;
        if row.len() != k + 1 {
            return Err(fail(
                line,
                format!("expected {} numbers (wavelength and {k} curves)", k + 1),
            ));
        }
        let lambda_nm = row[0];
        if !(lambda_nm.is_finite() && lambda_nm.fract() == 0.0) {
            return Err(fail(
                line,
                format!(
                    "wavelength {lambda_nm}: use whole nanometres (curves are carried on the 1 nm grid of the CIE tables)"
                ),
            ));
        }
        if !(cmf::FIRST_NM..=cmf::LAST_NM).contains(&lambda_nm) {
            return Err(fail(
                line,
                format!(
                    "wavelength {lambda_nm} nm is outside the {}–{} nm of the CIE tables",
                    cmf::FIRST_NM,
                    cmf::LAST_NM
                ),
            ));
        }
        if let Some(&previous) = sensor.lambda_nm.last() {
            if lambda_nm <= previous {
                return Err(fail(
                    line,
                    format!(
                        "wavelength {lambda_nm} nm does not increase (previous {previous} nm): rows must be sorted, without repeats"
                    ),
                ));
            }
        }
        for (curve, &value) in row[1..].iter().enumerate() {
            let name = &sensor.names[curve];
            if !value.is_finite() {
                return Err(fail(
                    line,
                    format!("curve `{name}`: {value} is not a finite number"),
                ));
            }
            if value < 0.0 {
                return Err(fail(
                    line,
                    format!("curve `{name}`: {value} is negative (a response cannot be)"),
                ));
            }
            sensor.curves[curve].push(value);
        }
        sensor.lambda_nm.push(lambda_nm);
    }
    if sensor.lambda_nm.len() < 2 {
        return Err(CliError::input(format!(
            "{origin}: {} data rows: a sensor needs at least two wavelengths",
            sensor.lambda_nm.len()
        )));
    }
    if let Some(curve) = sensor
        .curves
        .iter()
        .position(|c| c.iter().all(|&v| v == 0.0))
    {
        return Err(CliError::input(format!(
            "{origin}: curve `{}` is zero everywhere (an empty response)",
            sensor.names[curve]
        )));
    }
    match matrix.len() {
        0 if k != 3 => {
            return Err(CliError::input(format!(
                "{origin}: {k} curves need a `{MATRIX_LABEL}` matrix (three rows of {k} numbers) to make three channels"
            )));
        }
        0 => {}
        3 => {
            let mut rows = matrix.into_iter();
            sensor.to_xyz = Some(core::array::from_fn(|_| rows.next().unwrap_or_default()));
        }
        n => {
            return Err(CliError::input(format!(
                "{origin}: {n} `{MATRIX_LABEL}` rows: the matrix needs three"
            )));
        }
    }
    // Refuse an unusable normaliser here, with the file's name.
    sensor.observer()?;
    Ok(sensor)
}

/// Reads and parses a sensor file.
pub fn load_sensor_csv(path: &Path) -> Result<SensorCurves, CliError> {
    let (text, origin) = read_text_file(path, MAX_FILE_BYTES, "a sensor file")?;
    parse_sensor_csv(&text, &origin)
}

/// Fuzz entry point: arbitrary bytes through the sensor parser. A sensor
/// it accepts must give a valid observer whose curves are finite; nothing
/// may panic.
pub fn fuzz_sensor_csv(bytes: &[u8]) {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    if let Ok(sensor) = parse_sensor_csv(text, "fuzz") {
        let observer = sensor.observer();
        assert!(observer.is_ok(), "an accepted sensor gives an observer");
        if let Ok(observer) = observer {
            assert!(observer.validate().is_ok());
        }
    }
}
