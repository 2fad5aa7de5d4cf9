//! Tables (CSV and Markdown), claims with verdicts, and the files an
//! experiment writes.

use crate::error::CliError;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A table with a header row; cells are already formatted.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    /// Column names.
    pub headers: Vec<String>,
    /// Rows of cells (each as long as `headers`).
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// An empty table with these column names.
    pub fn new<S: AsRef<str>>(headers: &[S]) -> Self {
        Self {
            headers: headers.iter().map(|h| h.as_ref().to_string()).collect(),
            rows: Vec::new(),
        }
    }

    /// Appends a row.
    pub fn push(&mut self, row: Vec<String>) {
        self.rows.push(row);
    }

    /// RFC 4180 CSV (cells with a comma, quote or newline are quoted).
    pub fn to_csv(&self) -> String {
        let cell = |c: &str| {
            if c.contains([',', '"', '\n']) {
                format!("\"{}\"", c.replace('"', "\"\""))
            } else {
                c.to_string()
            }
        };
        let mut out = String::new();
        for row in std::iter::once(&self.headers).chain(&self.rows) {
            let cells: Vec<String> = row.iter().map(|c| cell(c)).collect();
            out.push_str(&cells.join(","));
            out.push('\n');
        }
        out
    }

    /// A GitHub-flavoured Markdown table.
    pub fn to_markdown(&self) -> String {
        let line = |row: &[String]| format!("| {} |\n", row.join(" | ").replace('\n', " "));
        let mut out = line(&self.headers);
        let rule: Vec<String> = self.headers.iter().map(|_| "---".to_string()).collect();
        out.push_str(&line(&rule));
        for row in &self.rows {
            out.push_str(&line(row));
        }
        out
    }
}

/// How a claim of the paper fared.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// The measurement agrees with the claim.
    Holds,
    /// Part of the claim holds.
    Partially,
    /// The measurement contradicts the claim.
    DoesNotHold,
}

impl Verdict {
    /// The verdict in words.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Holds => "holds",
            Self::Partially => "partially holds",
            Self::DoesNotHold => "does not hold",
        }
    }
}

/// One claim, what was measured, and the verdict.
#[derive(Debug, Clone, PartialEq)]
pub struct Claim {
    /// The claim as the paper (or the issue) states it.
    pub claim: String,
    /// The measured numbers, one sentence.
    pub measured: String,
    /// The verdict.
    pub verdict: Verdict,
}

/// The Markdown list of claims.
pub fn claims_markdown(claims: &[Claim]) -> String {
    let mut out = String::new();
    for c in claims {
        let _ = writeln!(
            out,
            "* **{}** — {} Verdict: **{}**.",
            c.claim,
            c.measured,
            c.verdict.as_str()
        );
    }
    out
}

/// What one experiment produced: its Markdown section (links relative to
/// the output folder), its claims, and the files written.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Section {
    /// Markdown, starting with a `##` heading.
    pub markdown: String,
    /// Claims checked.
    pub claims: Vec<Claim>,
    /// Files written (CSV, Markdown, PNG).
    pub files: Vec<PathBuf>,
}

/// Writes `text` to `dir/name`, returning the path.
pub fn write_text(dir: &Path, name: &str, text: &str) -> Result<PathBuf, CliError> {
    let path = dir.join(name);
    std::fs::write(&path, text)
        .map_err(|e| CliError::input(format!("{}: cannot write: {e}", path.display())))?;
    Ok(path)
}

/// Formats `value` with `decimals` digits after the point; non-finite
/// values as `n/a`.
pub fn fixed(value: f64, decimals: usize) -> String {
    if value.is_finite() {
        format!("{value:.decimals$}")
    } else {
        "n/a".to_string()
    }
}

/// Formats with three significant digits (scientific below 1e-3).
pub fn sig3(value: f64) -> String {
    if !value.is_finite() {
        return "n/a".to_string();
    }
    let magnitude = value.abs();
    if magnitude != 0.0 && magnitude < 1e-3 {
        format!("{value:.2e}")
    } else if magnitude < 1.0 {
        format!("{value:.3}")
    } else if magnitude < 100.0 {
        format!("{value:.2}")
    } else {
        format!("{value:.0}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_quotes_and_markdown_rules() {
        let mut t = Table::new(&["a", "b"]);
        t.push(vec!["1,5".into(), "x\"y".into()]);
        assert_eq!(t.to_csv(), "a,b\n\"1,5\",\"x\"\"y\"\n");
        assert_eq!(
            t.to_markdown(),
            "| a | b |\n| --- | --- |\n| 1,5 | x\"y |\n"
        );
        assert_eq!(fixed(f64::NAN, 2), "n/a");
        assert_eq!(sig3(0.000_123_4), "1.23e-4");
        assert_eq!(sig3(12.3456), "12.35");
    }
}
