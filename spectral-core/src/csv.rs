//! Allocation-free parsing of numeric CSV text, e.g. `wavelength_nm,value`.
//!
//! Rules: blank lines and lines starting with `#` are skipped; the first
//! other line is a header if any of its cells is not a number (at most one
//! header); every data row has exactly `COLS` cells, separated by commas
//! (or, in a line without commas, by semicolons, tabs or spaces); every cell
//! is a finite decimal number. A UTF-8 byte-order mark is ignored. Errors
//! are [`SpectralError::Csv`], carrying the 1-based line number.
//!
//! ```
//! use spectral_core::SpectralError;
//! use spectral_core::csv::{CsvError, CsvErrorKind, rows};
//!
//! let text = "# lamp, measured 2024\nwavelength_nm,value\n400,0.5\n500,0.75\n";
//! let parsed: Result<Vec<_>, _> = rows::<2>(text).collect();
//! assert_eq!(parsed?, [(3, [400.0, 0.5]), (4, [500.0, 0.75])]);
//!
//! let bad = rows::<2>("400,0.5\n500,abc\n").nth(1);
//! let expected = CsvError { line: 2, kind: CsvErrorKind::NotANumber { column: 2 } };
//! assert_eq!(bad, Some(Err(SpectralError::Csv(expected))));
//! # Ok::<(), SpectralError>(())
//! ```

use crate::SpectralError;
use core::fmt;

/// What was wrong with a line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CsvErrorKind {
    /// The row has this many cells instead of the expected count.
    WrongColumnCount {
        /// Cells found.
        found: usize,
        /// Cells expected.
        expected: usize,
    },
    /// Cell `column` (1-based) is not a number.
    NotANumber {
        /// 1-based column.
        column: usize,
    },
    /// Cell `column` (1-based) is NaN or infinite.
    NonFinite {
        /// 1-based column.
        column: usize,
    },
}

/// A parse error at a line, reported as [`SpectralError::Csv`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CsvError {
    /// 1-based line number.
    pub line: usize,
    /// What was wrong.
    pub kind: CsvErrorKind,
}

impl fmt::Display for CsvError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}: ", self.line)?;
        match self.kind {
            CsvErrorKind::WrongColumnCount { found, expected } => {
                write!(f, "{found} cells, expected {expected}")
            }
            CsvErrorKind::NotANumber { column } => write!(f, "cell {column} is not a number"),
            CsvErrorKind::NonFinite { column } => write!(f, "cell {column} is NaN or infinite"),
        }
    }
}

impl core::error::Error for CsvError {}

/// Iterator over the data rows of CSV text, each `(line, [f64; COLS])` or
/// the first bad line's [`SpectralError::Csv`].
#[derive(Debug, Clone)]
pub struct CsvRows<'a, const COLS: usize> {
    lines: core::str::Lines<'a>,
    line: usize,
    seen_content: bool,
}

/// Parses `text` into rows of `COLS` numbers.
pub fn rows<const COLS: usize>(text: &str) -> CsvRows<'_, COLS> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    CsvRows {
        lines: text.lines(),
        line: 0,
        seen_content: false,
    }
}

fn split_cells(line: &str) -> impl Iterator<Item = &str> {
    let separator: Option<char> = [',', ';', '\t'].into_iter().find(|&c| line.contains(c));
    let by_separator = separator.map(|c| line.split(c).map(str::trim));
    let by_space = match separator {
        Some(_) => None,
        None => Some(line.split_whitespace()),
    };
    by_separator
        .into_iter()
        .flatten()
        .chain(by_space.into_iter().flatten())
}

fn parse_row<const COLS: usize>(line: &str) -> Result<[f64; COLS], CsvErrorKind> {
    let mut values = [0.0; COLS];
    let mut count = 0;
    for (index, cell) in split_cells(line).enumerate() {
        count += 1;
        if index >= COLS {
            continue;
        }
        let value = cell
            .parse::<f64>()
            .map_err(|_| CsvErrorKind::NotANumber { column: index + 1 })?;
        if !value.is_finite() {
            return Err(CsvErrorKind::NonFinite { column: index + 1 });
        }
        values[index] = value;
    }
    if count != COLS {
        return Err(CsvErrorKind::WrongColumnCount {
            found: count,
            expected: COLS,
        });
    }
    Ok(values)
}

impl<const COLS: usize> Iterator for CsvRows<'_, COLS> {
    type Item = Result<(usize, [f64; COLS]), SpectralError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            let raw = self.lines.next()?;
            self.line += 1;
            let line = raw.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let first_content = !self.seen_content;
            self.seen_content = true;
            match parse_row::<COLS>(line) {
                Ok(values) => return Some(Ok((self.line, values))),
                Err(CsvErrorKind::NotANumber { column: 1 }) if first_content => continue,
                Err(kind) => {
                    return Some(Err(SpectralError::Csv(CsvError {
                        line: self.line,
                        kind,
                    })));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    fn parse(text: &str) -> Result<Vec<(usize, [f64; 2])>, CsvError> {
        rows::<2>(text)
            .map(|row| {
                row.map_err(|e| match e {
                    SpectralError::Csv(csv) => csv,
                    other => panic!("not a CSV error: {other}"),
                })
            })
            .collect()
    }

    #[test]
    fn comments_header_and_separators() {
        let text = "\u{feff}# source\n\nwavelength_nm,value\n400, 0.5\n500;1e-1\n600\t2\n700 3\n";
        let parsed = parse(text).unwrap();
        assert_eq!(
            parsed,
            [
                (4, [400.0, 0.5]),
                (5, [500.0, 0.1]),
                (6, [600.0, 2.0]),
                (7, [700.0, 3.0])
            ]
        );
        assert_eq!(parse("").unwrap(), []);
        assert_eq!(parse("# only a comment\nnm,v\n").unwrap(), []);
    }

    #[test]
    fn errors_carry_line_and_cell() {
        assert_eq!(
            parse("nm,v\n400,0.5\n500,abc\n"),
            Err(CsvError {
                line: 3,
                kind: CsvErrorKind::NotANumber { column: 2 }
            })
        );
        assert_eq!(
            parse("nm,v\nunits,units\n"),
            Err(CsvError {
                line: 2,
                kind: CsvErrorKind::NotANumber { column: 1 }
            })
        );
        assert_eq!(
            parse("400,NaN\n"),
            Err(CsvError {
                line: 1,
                kind: CsvErrorKind::NonFinite { column: 2 }
            })
        );
        assert_eq!(
            parse("400,1,2\n"),
            Err(CsvError {
                line: 1,
                kind: CsvErrorKind::WrongColumnCount {
                    found: 3,
                    expected: 2
                }
            })
        );
        assert_eq!(
            parse("400\n"),
            Err(CsvError {
                line: 1,
                kind: CsvErrorKind::WrongColumnCount {
                    found: 1,
                    expected: 2
                }
            })
        );
        assert_eq!(
            parse("400,\n"),
            Err(CsvError {
                line: 1,
                kind: CsvErrorKind::NotANumber { column: 2 }
            })
        );
    }
}
