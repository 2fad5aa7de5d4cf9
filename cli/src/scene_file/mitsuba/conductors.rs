//! Mitsuba 3's measured conductors: the `material` presets of its
//! `conductor` and `roughconductor` (`material="Au"`, `"Cu_palik"`, …), from
//! the tables Mitsuba 3.9.1 ships (`data/mitsuba-ior/`, provenance in
//! `data/README.md`), embedded so that a Mitsuba file's gold is Mitsuba's
//! gold. `material="none"` (Mitsuba's default) is a perfect mirror: the
//! index `η = 0, k = 1`, whose Fresnel reflectance is 1 at every angle.
//!
//! Our own built-in metals (`gold-n`, …: Johnson & Christy 1972, Rakić
//! 1995) are a different measurement: Mitsuba's `Au` comes from the
//! luxpop.com database, and the two golds differ by a few per cent in the
//! green, which is why the importer does not map `Au` to our `gold`.

use super::document::Element;
use super::properties::parse_numbers;
use crate::error::CliError;

/// The measured tables: name, `η` file, `k` file (`wavelength_nm value`
/// lines, `#` comments).
macro_rules! tables {
    ($($name:literal),* $(,)?) => {
        &[$((
            $name,
            include_str!(concat!("../../../../data/mitsuba-ior/", $name, ".eta.spd")),
            include_str!(concat!("../../../../data/mitsuba-ior/", $name, ".k.spd")),
        )),*]
    };
}

/// Every preset Mitsuba 3.9.1 ships.
const TABLES: &[(&str, &str, &str)] = tables![
    "Ag",
    "Al",
    "AlAs",
    "AlAs_palik",
    "AlSb",
    "AlSb_palik",
    "Au",
    "Be",
    "Be_palik",
    "Cr",
    "CsI",
    "CsI_palik",
    "Cu",
    "Cu2O",
    "Cu2O_palik",
    "CuO",
    "CuO_palik",
    "Cu_palik",
    "Hg",
    "HgTe",
    "HgTe_palik",
    "Hg_palik",
    "Ir",
    "Ir_palik",
    "K",
    "K_palik",
    "Li",
    "Li_palik",
    "MgO",
    "MgO_palik",
    "Mo",
    "Mo_palik",
    "Na_palik",
    "Nb",
    "Nb_palik",
    "Ni_palik",
    "Rh",
    "Rh_palik",
    "Se",
    "Se-e",
    "Se-e_palik",
    "Se_palik",
    "SiC",
    "SiC_palik",
    "SnTe",
    "SnTe_palik",
    "Ta",
    "Ta_palik",
    "Te",
    "Te-e",
    "Te-e_palik",
    "Te_palik",
    "ThF4",
    "ThF4_palik",
    "TiC",
    "TiC_palik",
    "TiN",
    "TiN_palik",
    "TiO2",
    "TiO2-e",
    "TiO2-e_palik",
    "TiO2_palik",
    "VC",
    "VC_palik",
    "VN",
    "VN_palik",
    "V_palik",
    "W",
    "a-C",
    "d-C",
    "d-C_palik",
];

/// The names of the presets, for messages.
pub(crate) fn preset_names() -> impl Iterator<Item = &'static str> {
    TABLES.iter().map(|(name, _, _)| *name)
}

/// Samples of a table: wavelengths (nm) and values.
pub(crate) type Samples = (Vec<f64>, Vec<f64>);

/// A preset's `η` and `k` as `(wavelengths_nm, values)`; `None` for an
/// unknown name. Errors only if an embedded table is malformed (a bug,
/// reported at `at`).
pub(crate) fn preset(at: &Element, name: &str) -> Result<Option<[Samples; 2]>, CliError> {
    let Some((_, eta, k)) = TABLES.iter().find(|(n, _, _)| *n == name) else {
        return Ok(None);
    };
    Ok(Some([table(at, eta)?, table(at, k)?]))
}

fn table(at: &Element, text: &str) -> Result<Samples, CliError> {
    let mut lambda_nm = Vec::new();
    let mut values = Vec::new();
    for line in text.lines() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let n = parse_numbers(at, line)?;
        if let [l, v] = n.as_slice() {
            lambda_nm.push(*l);
            values.push(*v);
        }
    }
    Ok((lambda_nm, values))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_file::mitsuba::document::{Input, read_scene};

    #[test]
    fn every_preset_parses_and_covers_the_visible_range() -> Result<(), CliError> {
        let at = read_scene(
            Input::Text {
                name: "t.xml",
                text: "<scene version=\"3.0.0\"/>",
            },
            &[],
        )?
        .root;
        for name in preset_names() {
            let Some([eta, k]) = preset(&at, name)? else {
                panic!("{name} missing");
            };
            for (l, v) in [eta, k] {
                assert!(l.len() >= 2, "{name}");
                assert!(l.windows(2).all(|w| w[1] > w[0]), "{name} not sorted");
                assert!(v.iter().all(|v| v.is_finite() && *v >= 0.0), "{name}");
                // The common metals cover the rendered range (the others
                // are zero outside their tables, as in Mitsuba).
                if ["Au", "Ag", "Al", "Cu", "Cr"].contains(&name) {
                    let last = l.last().copied().unwrap_or(0.0);
                    assert!(l[0] <= 360.0 && last >= 830.0, "{name}: {}–{last}", l[0]);
                }
            }
        }
        // Gold near 550 nm: n 0.3–0.5, k 2.3–2.8 across published tables
        // (Johnson & Christy 1972: 0.43, 2.46; this table: 0.35, 2.73).
        let Some([(l, n), (lk, k)]) = preset(&at, "Au")? else {
            panic!("Au missing");
        };
        let near = |l: &[f64], v: &[f64]| {
            let i = l.iter().position(|&x| x >= 550.0).unwrap_or(0);
            v[i]
        };
        assert!((0.3..=0.5).contains(&near(&l, &n)));
        assert!((2.3..=2.8).contains(&near(&lk, &k)));
        assert!(preset(&at, "unobtainium")?.is_none());
        Ok(())
    }
}
