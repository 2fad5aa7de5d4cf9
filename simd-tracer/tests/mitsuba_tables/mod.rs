//! Reading the tables of Mitsuba's own BSDF evaluations in `tests/data`
//! (written by `tools/mitsuba_bsdf_table.py`), shared by the tests that
//! compare with them.

use std::collections::BTreeMap;

pub type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

/// The text of the data file `name`.
pub fn data(name: &str) -> TestResult<String> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name);
    Ok(std::fs::read_to_string(path)?)
}

/// Rows of a CSV file as maps from the header's names.
pub fn rows(text: &str) -> TestResult<Vec<BTreeMap<String, String>>> {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().ok_or("empty file")?.split(',').collect();
    Ok(lines
        .filter(|l| !l.is_empty())
        .map(|l| {
            header
                .iter()
                .zip(l.split(','))
                .map(|(k, v)| ((*k).to_string(), v.to_string()))
                .collect()
        })
        .collect())
}

/// The number in column `key` of `row`.
pub fn number(row: &BTreeMap<String, String>, key: &str) -> TestResult<f64> {
    Ok(row.get(key).ok_or_else(|| format!("no {key}"))?.parse()?)
}
