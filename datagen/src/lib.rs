//! Generator of `spectral-core/src/data/tables.rs` from the CSV files in `data/`.
//!
//! The CSV files are copies of the public tables listed in `data/README.md`
//! (`#` comment lines naming the source, one header row, then numbers). The
//! generator keeps every number exactly as written (parsed to `f64`, printed
//! with Rust's shortest round-trip formatting) and copies each file's source
//! comment into the generated docs, so the tables never drift from their
//! provenance. Run `cargo run -p datagen` after changing `data/`; the
//! integration test `generated_tables_are_fresh` fails when the committed file
//! differs from what this generator produces.

pub mod sigmoid_fit;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A parsed CSV table: its source comments, column names and numeric rows.
#[derive(Debug, Clone)]
pub struct Table {
    /// The `#` comment lines (without the `#`), naming the source.
    pub comments: Vec<String>,
    /// Column names from the header row.
    pub columns: Vec<String>,
    /// Numeric rows, each with `columns.len()` values.
    pub rows: Vec<Vec<f64>>,
}

impl Table {
    /// Column `index` as a vector.
    pub fn column(&self, index: usize) -> Vec<f64> {
        self.rows.iter().map(|row| row[index]).collect()
    }
}

/// Parses one CSV file of `data/`. Errors name the file and line.
pub fn read_table(path: &Path) -> Result<Table, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut comments = Vec::new();
    let mut columns: Option<Vec<String>> = None;
    let mut rows = Vec::new();
    for (line_index, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        if let Some(comment) = line.strip_prefix('#') {
            comments.push(comment.trim().to_string());
            continue;
        }
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        match &columns {
            None => columns = Some(cells.iter().map(|c| c.to_string()).collect()),
            Some(names) => {
                if cells.len() != names.len() {
                    return Err(format!(
                        "{}:{}: {} cells, header has {}",
                        path.display(),
                        line_index + 1,
                        cells.len(),
                        names.len()
                    ));
                }
                let row = cells
                    .iter()
                    .map(|c| {
                        c.parse::<f64>().map_err(|e| {
                            format!("{}:{}: `{c}`: {e}", path.display(), line_index + 1)
                        })
                    })
                    .collect::<Result<Vec<f64>, String>>()?;
                rows.push(row);
            }
        }
    }
    let columns = columns.ok_or_else(|| format!("{}: no header row", path.display()))?;
    if rows.is_empty() {
        return Err(format!("{}: no data rows", path.display()));
    }
    Ok(Table {
        comments,
        columns,
        rows,
    })
}

/// The illuminants embedded in the core: (registry name, Rust identifier, CSV file).
pub const ILLUMINANTS: [(&str, &str, &str); 15] = [
    ("d65", "D65", "illuminant_d65.csv"),
    ("d50", "D50", "illuminant_d50.csv"),
    ("a", "A", "illuminant_a.csv"),
    ("fl2", "FL2", "illuminant_fl2.csv"),
    ("fl7", "FL7", "illuminant_fl7.csv"),
    ("fl11", "FL11", "illuminant_fl11.csv"),
    ("led-b1", "LED_B1", "illuminant_led_b1.csv"),
    ("led-b2", "LED_B2", "illuminant_led_b2.csv"),
    ("led-b3", "LED_B3", "illuminant_led_b3.csv"),
    ("led-b4", "LED_B4", "illuminant_led_b4.csv"),
    ("led-b5", "LED_B5", "illuminant_led_b5.csv"),
    ("led-bh1", "LED_BH1", "illuminant_led_bh1.csv"),
    ("led-rgb1", "LED_RGB1", "illuminant_led_rgb1.csv"),
    ("led-v1", "LED_V1", "illuminant_led_v1.csv"),
    ("led-v2", "LED_V2", "illuminant_led_v2.csv"),
];

/// The metals embedded in the core: (registry name, Rust identifier, CSV file).
pub const METALS: [(&str, &str, &str); 4] = [
    ("gold", "GOLD", "metal_gold_nk.csv"),
    ("silver", "SILVER", "metal_silver_nk.csv"),
    ("copper", "COPPER", "metal_copper_nk.csv"),
    ("aluminium", "ALUMINIUM", "metal_aluminium_nk.csv"),
];

/// Path of the repository's `data/` folder.
pub fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../data")
}

/// Path of the generated RGB → spectrum table inside `spectral-core`.
pub fn sigmoid_table_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../spectral-core/src/data/srgb_sigmoid.bin")
}

/// The sRGB → XYZ map the fit targets (linear sRGB, D65 white at Y = 1).
pub fn srgb_to_xyz(rgb: [f64; 3]) -> [f64; 3] {
    spectral_core::LinearSrgb::new(rgb[0], rgb[1], rgb[2])
        .to_xyz()
        .to_array()
}

/// The fitted sRGB sigmoid table as bytes.
pub fn generate_sigmoid_table(threads: usize) -> Result<Vec<u8>, String> {
    let data = sigmoid_fit::fit_table(sigmoid_fit::RESOLUTION, threads, &srgb_to_xyz)?;
    Ok(sigmoid_fit::to_bytes(&data))
}

/// Path of the generated file inside `spectral-core`.
pub fn output_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../spectral-core/src/data/tables.rs")
}

fn write_docs(out: &mut String, lines: &[String]) {
    for line in lines {
        let _ = writeln!(out, "/// {line}");
    }
}

fn write_array(out: &mut String, doc: &[String], name: &str, values: &[f64]) {
    write_docs(out, doc);
    let _ = write!(out, "pub static {name}: [f64; {}] = [", values.len());
    for (i, v) in values.iter().enumerate() {
        if i % 8 == 0 {
            out.push_str("\n    ");
        } else {
            out.push(' ');
        }
        let _ = write!(out, "{v:?},");
    }
    out.push_str("\n];\n\n");
}

/// Produces the full text of `tables.rs` from the CSV files in `data_dir`.
pub fn generate(data_dir: &Path) -> Result<String, String> {
    let mut out = String::new();
    out.push_str(
        "//! Embedded spectral tables.\n//!\n//! GENERATED by `cargo run -p datagen` from the CSV files in `data/`\n\
         //! (sources in `data/README.md` and in each table's docs): do not edit.\n\n",
    );

    // CIE 1931 2° colour-matching functions.
    let cmf = read_table(&data_dir.join("cie1931_2deg_cmf.csv"))?;
    let nm = cmf.column(0);
    for pair in nm.windows(2) {
        if pair[1] - pair[0] != 1.0 {
            return Err("cie1931_2deg_cmf.csv: wavelengths are not on a 1 nm grid".into());
        }
    }
    let _ = writeln!(
        out,
        "/// First wavelength of the CIE 1931 table, nm.\npub const CIE1931_FIRST_NM: f64 = {:?};\n",
        nm[0]
    );
    let _ = writeln!(
        out,
        "/// Number of 1 nm samples of the CIE 1931 table.\npub const CIE1931_SAMPLES: usize = {};\n",
        nm.len()
    );
    write_array(&mut out, &cmf.comments, "CIE1931_NM", &nm);
    let mut doc = cmf.comments.clone();
    for (index, name) in [
        (1, "CIE1931_X_BAR"),
        (2, "CIE1931_Y_BAR"),
        (3, "CIE1931_Z_BAR"),
    ] {
        doc.insert(0, format!("Column `{}`.", cmf.columns[index]));
        write_array(&mut out, &doc, name, &cmf.column(index));
        doc.remove(0);
    }

    // CIE 1964 10° colour-matching functions, on the same 1 nm grid.
    let cmf10 = read_table(&data_dir.join("cie1964_10deg_cmf.csv"))?;
    if cmf10.column(0) != nm {
        return Err("cie1964_10deg_cmf.csv: wavelengths differ from the CIE 1931 table's".into());
    }
    let mut doc = cmf10.comments.clone();
    for (index, name) in [
        (1, "CIE1964_X_BAR"),
        (2, "CIE1964_Y_BAR"),
        (3, "CIE1964_Z_BAR"),
    ] {
        doc.insert(
            0,
            format!(
                "Column `{}` (on the grid of `CIE1931_NM`).",
                cmf10.columns[index]
            ),
        );
        write_array(&mut out, &doc, name, &cmf10.column(index));
        doc.remove(0);
    }

    // Illuminants.
    for (_, ident, file) in ILLUMINANTS {
        let table = read_table(&data_dir.join(file))?;
        write_array(
            &mut out,
            &table.comments,
            &format!("ILLUMINANT_{ident}_NM"),
            &table.column(0),
        );
        write_array(
            &mut out,
            &table.comments,
            &format!("ILLUMINANT_{ident}"),
            &table.column(1),
        );
    }
    out.push_str(
        "/// Registry of the embedded illuminants.\n\
         pub static ILLUMINANTS: [super::Illuminant; ",
    );
    let _ = writeln!(out, "{}] = [", ILLUMINANTS.len());
    for (name, ident, _) in ILLUMINANTS {
        let _ = writeln!(
            out,
            "    super::Illuminant {{ name: \"{name}\", lambda_nm: &ILLUMINANT_{ident}_NM, power: &ILLUMINANT_{ident} }},"
        );
    }
    out.push_str("];\n\n");

    // ColorChecker.
    let cc = read_table(&data_dir.join("colorchecker_iso17321.csv"))?;
    write_array(&mut out, &cc.comments, "COLORCHECKER_NM", &cc.column(0));
    write_docs(&mut out, &cc.comments);
    let patches = cc.columns.len() - 1;
    let _ = writeln!(
        out,
        "pub static COLORCHECKER_REFLECTANCE: [[f64; {}]; {patches}] = [",
        cc.rows.len()
    );
    for patch in 1..=patches {
        out.push_str("    [");
        for (i, v) in cc.column(patch).iter().enumerate() {
            if i % 8 == 0 {
                out.push_str("\n        ");
            } else {
                out.push(' ');
            }
            let _ = write!(out, "{v:?},");
        }
        out.push_str("\n    ],\n");
    }
    out.push_str("];\n\n");
    let _ = writeln!(
        out,
        "/// ColorChecker patch names, chart order (row by row from dark skin to black).\n\
         pub static COLORCHECKER_NAMES: [&str; {patches}] = ["
    );
    for patch in 1..=patches {
        let _ = writeln!(out, "    \"{}\",", cc.columns[patch]);
    }
    out.push_str("];\n\n");

    // Metals.
    for (_, ident, file) in METALS {
        let table = read_table(&data_dir.join(file))?;
        write_array(
            &mut out,
            &table.comments,
            &format!("METAL_{ident}_NM"),
            &table.column(0),
        );
        write_array(
            &mut out,
            &table.comments,
            &format!("METAL_{ident}_N"),
            &table.column(1),
        );
        write_array(
            &mut out,
            &table.comments,
            &format!("METAL_{ident}_K"),
            &table.column(2),
        );
    }
    out.push_str(
        "/// Registry of the embedded metals.\n\
         pub static METALS: [super::Metal; ",
    );
    let _ = writeln!(out, "{}] = [", METALS.len());
    for (name, ident, _) in METALS {
        let _ = writeln!(
            out,
            "    super::Metal {{ name: \"{name}\", lambda_nm: &METAL_{ident}_NM, n: &METAL_{ident}_N, k: &METAL_{ident}_K }},"
        );
    }
    out.push_str("];\n");
    Ok(out)
}
