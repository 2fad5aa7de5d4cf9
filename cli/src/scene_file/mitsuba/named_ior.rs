//! Mitsuba 3's named indices of refraction (`int_ior="bk7"`,
//! `ext_ior="air"`, …): the table of `include/mitsuba/render/ior.h`
//! (Mitsuba 3.9.1), each a constant at every wavelength as Mitsuba uses
//! it. (`bk7` is therefore 1.5046, not our dispersive Sellmeier N-BK7 of
//! the TOML format.)

/// `(name, index)`, as Mitsuba lists them.
const NAMED_IOR: &[(&str, f64)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// The index named `name` (case-insensitive), if Mitsuba knows it.
pub(crate) fn named_ior(name: &str) -> Option<f64> {
    let lower = name.trim().to_ascii_lowercase();
    NAMED_IOR.iter().find(|(n, _)| *n == lower).map(|(_, v)| *v)
}

/// The names, for messages.
pub(crate) fn names() -> String {
    NAMED_IOR
        .iter()
        .map(|(n, _)| *n)
        .collect::<Vec<_>>()
        .join(", ")
}
