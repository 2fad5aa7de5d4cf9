//! `fspec experiment equal-time`: colour error at equal CPU time, fspec
//! against Mitsuba 3 (issue 27), from the renders and timings that
//! `tools/mitsuba_equal_time.py` wrote.
//!
//! **Input.** A manifest (JSON, format [`MANIFEST_FORMAT`]): per scene a
//! reference image (a high-spp Mitsuba render, optionally with its two
//! independent halves), and one row per render — scene, renderer
//! (`mitsuba`, or an fspec configuration's name), budget (the Mitsuba spp
//! whose time the render was given), seed, spp, CPU seconds, image. Image
//! paths are relative to the manifest's folder. Images are linear sRGB
//! (OpenEXR, RGBE, PNG, JPEG through [`crate::hdr_image`]).
//!
//! **Time** is what the script measured: CPU seconds (user + system, every
//! thread) of each renderer at one thread count, Mitsuba's scene load and
//! fspec's fixed cost left out (the script's docs). CPU rather than wall
//! seconds, because a shared machine's load stretches wall time and leaves
//! the work a process does nearly unchanged.
//!
//! **Error**: the mean CIEDE2000 of the image against the reference, pixel
//! by pixel, as the other experiments compare images
//! ([`super::image::compare`]: linear sRGB → clamped to [0, 1] → CIELAB
//! relative to the display white, D65 with `Y = 1`). The reference's own
//! noise is half the mean ΔE2000 between its halves (each half has √2 its
//! noise, their difference 2×; [`super::image`]).
//!
//! **Summary**: per scene, budget and renderer the medians over seeds of
//! ΔE2000, CPU seconds and spp, and the ratio of each renderer's median
//! ΔE2000 to Mitsuba's at the same budget (below 1: less error than
//! Mitsuba at equal time). Medians, because one render's error or time can
//! be thrown by the machine's load.

use super::image::{Comparison, DisplayImage, compare};
use super::plot::{LinePlot, Scale, Series};
use super::report::{Section, Table, fixed, write_text};
use crate::error::CliError;
use crate::hdr_image::{RgbImage, load_rgb_image};
use serde::Deserialize;
use spectral_core::color::{LinearSrgb, Xyz};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The `format` a manifest must declare.
pub const MANIFEST_FORMAT: &str = "fspec-equal-time-v1";
/// The renderer name of Mitsuba's rows.
pub const MITSUBA: &str = "mitsuba";
/// Largest manifest accepted, bytes (a run of thousands of rows is a few
/// hundred KB; anything far larger is not a manifest).
pub const MAX_MANIFEST_BYTES: u64 = 64 << 20;
/// Largest number of render rows accepted.
pub const MAX_RUNS: usize = 100_000;

/// The manifest `tools/mitsuba_equal_time.py` writes (module docs).
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct Manifest {
    /// [`MANIFEST_FORMAT`].
    pub format: String,
    /// The machine, as the script saw it.
    #[serde(default)]
    pub machine: String,
    /// When the manifest was last written (UTC).
    #[serde(default)]
    pub date: String,
    /// Mitsuba's version.
    #[serde(default)]
    pub mitsuba_version: String,
    /// Mitsuba's variant.
    #[serde(default)]
    pub mitsuba_variant: String,
    /// Threads of every render.
    pub threads: u32,
    /// Per scene, its reference.
    pub references: BTreeMap<String, ReferenceEntry>,
    /// Mitsuba's renders.
    #[serde(default)]
    pub mitsuba: Vec<Run>,
    /// fspec's renders.
    #[serde(default)]
    pub fspec: Vec<Run>,
}

/// A scene's reference image.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct ReferenceEntry {
    /// The reference image.
    pub image: String,
    /// The mean of its even passes (optional, with `odd`).
    #[serde(default)]
    pub even: Option<String>,
    /// The mean of its odd passes.
    #[serde(default)]
    pub odd: Option<String>,
    /// Its samples per pixel.
    pub spp: u32,
}

/// One timed render.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct Run {
    /// Scene name (a key of `references`).
    pub scene: String,
    /// fspec's configuration (absent in Mitsuba's rows).
    #[serde(default)]
    pub config: Option<String>,
    /// The Mitsuba spp whose CPU time this render was given.
    pub budget_spp: u32,
    /// Seed.
    pub seed: u64,
    /// Samples per pixel rendered.
    pub spp: u32,
    /// CPU seconds of the render.
    pub cpu_s: f64,
    /// The image.
    pub image: String,
}

impl Run {
    /// The renderer's name: [`MITSUBA`] or fspec's configuration.
    pub fn renderer(&self) -> &str {
        self.config.as_deref().unwrap_or(MITSUBA)
    }
}

impl Manifest {
    /// Parses and validates a manifest's text; `source` names it in errors.
    pub fn parse(text: &str, source: &str) -> Result<Self, CliError> {
        let manifest: Self = serde_json::from_str(text)
            .map_err(|e| CliError::input(format!("{source}: not an equal-time manifest: {e}")))?;
        manifest
            .validate()
            .map_err(|e| CliError::input(format!("{source}: {e}")))?;
        Ok(manifest)
    }

    /// Reads and parses the manifest at `path`.
    pub fn load(path: &Path) -> Result<Self, CliError> {
        let source = path.display().to_string();
        let size = std::fs::metadata(path)
            .map_err(|e| CliError::input(format!("{source}: cannot read: {e}")))?
            .len();
        if size > MAX_MANIFEST_BYTES {
            return Err(CliError::input(format!(
                "{source}: {size} bytes, more than a manifest's {MAX_MANIFEST_BYTES}"
            )));
        }
        let text = std::fs::read_to_string(path)
            .map_err(|e| CliError::input(format!("{source}: cannot read: {e}")))?;
        Self::parse(&text, &source)
    }

    /// Every render row, Mitsuba's first.
    pub fn runs(&self) -> impl Iterator<Item = &Run> {
        self.mitsuba.iter().chain(&self.fspec)
    }

    /// The invariants: the format, at least one thread, one reference and
    /// one render; every row names a known scene, fspec's rows a
    /// configuration and Mitsuba's none, positive spp and budget, finite
    /// non-negative CPU seconds, an image; no two rows of one renderer,
    /// scene, budget and seed; halves of a reference come in pairs.
    pub fn validate(&self) -> Result<(), String> {
        if self.format != MANIFEST_FORMAT {
            return Err(format!(
                "format \"{}\", expected \"{MANIFEST_FORMAT}\"",
                self.format
            ));
        }
        if self.threads == 0 {
            return Err("threads must be at least 1".into());
        }
        if self.references.is_empty() {
            return Err("no references".into());
        }
        for (scene, r) in &self.references {
            if r.image.is_empty() || r.spp == 0 {
                return Err(format!("reference of {scene}: needs an image and spp ≥ 1"));
            }
            if r.even.is_some() != r.odd.is_some() {
                return Err(format!(
                    "reference of {scene}: give both halves (even, odd) or neither"
                ));
            }
        }
        let rows = self.mitsuba.len() + self.fspec.len();
        if rows == 0 {
            return Err("no renders".into());
        }
        if rows > MAX_RUNS {
            return Err(format!("{rows} renders, more than {MAX_RUNS}"));
        }
        for (list, fspec) in [(&self.mitsuba, false), (&self.fspec, true)] {
            for run in list {
                let what = format!(
                    "render of {} by {} at budget {} seed {}",
                    run.scene,
                    run.renderer(),
                    run.budget_spp,
                    run.seed
                );
                if !self.references.contains_key(&run.scene) {
                    return Err(format!("{what}: no reference of scene {}", run.scene));
                }
                match (&run.config, fspec) {
                    (None, true) => return Err(format!("{what}: an fspec row needs a config")),
                    (Some(c), true) if c.is_empty() || c == MITSUBA => {
                        return Err(format!("{what}: config \"{c}\" is not a name"));
                    }
                    (Some(_), false) => {
                        return Err(format!("{what}: a mitsuba row has no config"));
                    }
                    _ => {}
                }
                if run.spp == 0 || run.budget_spp == 0 {
                    return Err(format!("{what}: spp and budget_spp must be at least 1"));
                }
                if !(run.cpu_s.is_finite() && run.cpu_s >= 0.0) {
                    return Err(format!(
                        "{what}: cpu_s {} is not a time in seconds",
                        run.cpu_s
                    ));
                }
                if run.image.is_empty() {
                    return Err(format!("{what}: no image"));
                }
            }
        }
        let mut keys: Vec<_> = self
            .runs()
            .map(|r| (r.renderer(), r.scene.as_str(), r.budget_spp, r.seed))
            .collect();
        keys.sort_unstable();
        if let Some(w) = keys.windows(2).find(|w| w[0] == w[1]) {
            let (renderer, scene, budget, seed) = w[0];
            return Err(format!(
                "two renders of {scene} by {renderer} at budget {budget} seed {seed}"
            ));
        }
        Ok(())
    }
}

/// The body of the `equal_time_manifest` fuzz target: arbitrary bytes as
/// a manifest. A manifest is parsed or refused with a message; a parsed one
/// is valid, and a manifest of only its renders summarises without panics.
pub fn fuzz_manifest(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    match Manifest::parse(&text, "fuzz") {
        Err(e) => assert!(!e.to_string().is_empty()),
        Ok(manifest) => {
            assert!(manifest.validate().is_ok());
            let measured: Vec<Measured> = manifest
                .runs()
                .map(|r| Measured {
                    scene: r.scene.clone(),
                    renderer: r.renderer().to_string(),
                    budget_spp: r.budget_spp,
                    seed: r.seed,
                    spp: r.spp,
                    cpu_s: r.cpu_s,
                    delta_e2000: r.cpu_s,
                })
                .collect();
            let summaries = summarise(&measured);
            for scene in manifest.references.keys() {
                let _ = scene_table(&summaries, scene).to_markdown();
            }
        }
    }
}

/// A linear sRGB image as the experiments compare it (module docs).
pub fn display_image(image: &RgbImage) -> DisplayImage {
    let xyz: Vec<Xyz> = image
        .texels
        .iter()
        .map(|&[r, g, b]| LinearSrgb::new(f64::from(r), f64::from(g), f64::from(b)).to_xyz())
        .collect();
    DisplayImage::new(&xyz)
}

/// `test` against `reference`: both must have the same size.
pub fn compare_images(test: &RgbImage, reference: &RgbImage) -> Result<Comparison, CliError> {
    if (test.width, test.height) != (reference.width, reference.height) {
        return Err(CliError::input(format!(
            "{} × {} pixels against a reference of {} × {}",
            test.width, test.height, reference.width, reference.height
        )));
    }
    compare(&display_image(test), &display_image(reference))
}

/// One render compared with its scene's reference.
#[derive(Debug, Clone, PartialEq)]
pub struct Measured {
    /// Scene.
    pub scene: String,
    /// [`MITSUBA`] or fspec's configuration.
    pub renderer: String,
    /// Budget, Mitsuba spp.
    pub budget_spp: u32,
    /// Seed.
    pub seed: u64,
    /// Samples per pixel.
    pub spp: u32,
    /// CPU seconds.
    pub cpu_s: f64,
    /// Mean CIEDE2000 against the reference.
    pub delta_e2000: f64,
}

/// A scene's reference and its own noise.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceInfo {
    /// Reference spp.
    pub spp: u32,
    /// Half the mean ΔE2000 between the halves (`None` without halves).
    pub noise_delta_e2000: Option<f64>,
}

fn load_image(base: &Path, relative: &str) -> Result<(PathBuf, RgbImage), CliError> {
    let path = base.join(relative);
    let image = load_rgb_image(&path)?;
    Ok((path, image))
}

/// Compares every render of the manifest (images relative to `base`).
pub fn measure(
    manifest: &Manifest,
    base: &Path,
) -> Result<(Vec<Measured>, BTreeMap<String, ReferenceInfo>), CliError> {
    let mut references = BTreeMap::new();
    let mut infos = BTreeMap::new();
    for (scene, entry) in &manifest.references {
        let (_, image) = load_image(base, &entry.image)?;
        let noise = match (&entry.even, &entry.odd) {
            (Some(even), Some(odd)) => {
                let (even_path, even) = load_image(base, even)?;
                let (_, odd) = load_image(base, odd)?;
                let c = compare_images(&even, &odd)
                    .map_err(|e| CliError::input(format!("{}: {e}", even_path.display())))?;
                Some(c.delta_e2000 / 2.0)
            }
            _ => None,
        };
        infos.insert(
            scene.clone(),
            ReferenceInfo {
                spp: entry.spp,
                noise_delta_e2000: noise,
            },
        );
        references.insert(scene.clone(), image);
    }
    let mut measured = Vec::new();
    for run in manifest.runs() {
        let (path, image) = load_image(base, &run.image)?;
        let reference = references.get(&run.scene).ok_or_else(|| {
            CliError::input(format!("{}: no reference of {}", path.display(), run.scene))
        })?;
        let c = compare_images(&image, reference)
            .map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
        measured.push(Measured {
            scene: run.scene.clone(),
            renderer: run.renderer().to_string(),
            budget_spp: run.budget_spp,
            seed: run.seed,
            spp: run.spp,
            cpu_s: run.cpu_s,
            delta_e2000: c.delta_e2000,
        });
    }
    Ok((measured, infos))
}

/// The median (the mean of the middle two for an even count); NaN when
/// empty.
pub fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => (v[n / 2 - 1] + v[n / 2]) / 2.0,
    }
}

/// Medians over seeds of one renderer on one scene at one budget.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// Scene.
    pub scene: String,
    /// Renderer.
    pub renderer: String,
    /// Budget, Mitsuba spp.
    pub budget_spp: u32,
    /// Seeds.
    pub seeds: usize,
    /// Median spp.
    pub spp: f64,
    /// Median CPU seconds.
    pub cpu_s: f64,
    /// Median mean ΔE2000.
    pub delta_e2000: f64,
    /// `delta_e2000` over Mitsuba's at the same scene and budget (NaN
    /// without a Mitsuba row).
    pub ratio_to_mitsuba: f64,
}

/// Groups the measurements by scene, budget and renderer (Mitsuba first,
/// then fspec's configurations in name order).
pub fn summarise(measured: &[Measured]) -> Vec<Summary> {
    let mut groups: BTreeMap<(String, u32, bool, String), Vec<&Measured>> = BTreeMap::new();
    for m in measured {
        groups
            .entry((
                m.scene.clone(),
                m.budget_spp,
                m.renderer != MITSUBA,
                m.renderer.clone(),
            ))
            .or_default()
            .push(m);
    }
    let mut out: Vec<Summary> = groups
        .into_iter()
        .map(|((scene, budget_spp, _, renderer), rows)| {
            let of =
                |f: fn(&Measured) -> f64| median(&rows.iter().map(|m| f(m)).collect::<Vec<_>>());
            Summary {
                scene,
                renderer,
                budget_spp,
                seeds: rows.len(),
                spp: of(|m| f64::from(m.spp)),
                cpu_s: of(|m| m.cpu_s),
                delta_e2000: of(|m| m.delta_e2000),
                ratio_to_mitsuba: f64::NAN,
            }
        })
        .collect();
    let mitsuba: BTreeMap<(String, u32), f64> = out
        .iter()
        .filter(|s| s.renderer == MITSUBA)
        .map(|s| ((s.scene.clone(), s.budget_spp), s.delta_e2000))
        .collect();
    for s in &mut out {
        if let Some(m) = mitsuba.get(&(s.scene.clone(), s.budget_spp)) {
            s.ratio_to_mitsuba = s.delta_e2000 / m;
        }
    }
    out
}

/// The per-scene table in the issue's layout: one row per budget, Mitsuba's
/// median ΔE2000 (with its median CPU seconds), each fspec configuration's
/// (with its median spp and CPU seconds: the calibration sets its spp, so
/// its own time shows how closely it matched) and its ratio to Mitsuba.
pub fn scene_table(summaries: &[Summary], scene: &str) -> Table {
    let rows: Vec<&Summary> = summaries.iter().filter(|s| s.scene == scene).collect();
    let mut renderers: Vec<&str> = rows
        .iter()
        .filter(|s| s.renderer != MITSUBA)
        .map(|s| s.renderer.as_str())
        .collect();
    renderers.sort_unstable();
    renderers.dedup();
    let mut headers = vec![
        "budget (Mitsuba spp)".to_string(),
        "Mitsuba ΔE2000 (CPU s)".to_string(),
    ];
    for r in &renderers {
        headers.push(format!("fspec {r} ΔE2000 (spp, CPU s)"));
        headers.push(format!("{r} / Mitsuba"));
    }
    let mut table = Table::new(&headers);
    let mut budgets: Vec<u32> = rows.iter().map(|s| s.budget_spp).collect();
    budgets.sort_unstable();
    budgets.dedup();
    for budget in budgets {
        let find = |renderer: &str| {
            rows.iter()
                .find(|s| s.budget_spp == budget && s.renderer == renderer)
        };
        let mut row = vec![budget.to_string()];
        row.push(find(MITSUBA).map_or("–".into(), |s| {
            format!("{} ({})", fixed(s.delta_e2000, 2), fixed(s.cpu_s, 2))
        }));
        for r in &renderers {
            match find(r) {
                Some(s) => {
                    row.push(format!(
                        "{} ({:.0} spp, {} s)",
                        fixed(s.delta_e2000, 2),
                        s.spp,
                        fixed(s.cpu_s, 2)
                    ));
                    row.push(fixed(s.ratio_to_mitsuba, 2));
                }
                None => row.extend(["–".to_string(), "–".to_string()]),
            }
        }
        table.push(row);
    }
    table
}

/// Runs the experiment on the manifest at `manifest_path`, writing into
/// `dir`: `equal-time-runs.csv` (every render), `equal-time.csv` (the
/// medians), `equal-time-SCENE.png` (median ΔE2000 against median CPU
/// seconds, log–log) and the Markdown section.
pub fn run(manifest_path: &Path, dir: &Path) -> Result<Section, CliError> {
    let manifest = Manifest::load(manifest_path)?;
    let base = manifest_path.parent().unwrap_or(Path::new("."));
    let (measured, references) = measure(&manifest, base)?;
    let summaries = summarise(&measured);
    let mut files = Vec::new();

    let mut runs = Table::new(&[
        "scene",
        "renderer",
        "budget_spp",
        "seed",
        "spp",
        "cpu_s",
        "delta_e2000",
    ]);
    for m in &measured {
        runs.push(vec![
            m.scene.clone(),
            m.renderer.clone(),
            m.budget_spp.to_string(),
            m.seed.to_string(),
            m.spp.to_string(),
            format!("{:.4}", m.cpu_s),
            format!("{:.4}", m.delta_e2000),
        ]);
    }
    files.push(write_text(dir, "equal-time-runs.csv", &runs.to_csv())?);
    let mut medians = Table::new(&[
        "scene",
        "renderer",
        "budget_spp",
        "seeds",
        "median_spp",
        "median_cpu_s",
        "median_delta_e2000",
        "ratio_to_mitsuba",
    ]);
    for s in &summaries {
        medians.push(vec![
            s.scene.clone(),
            s.renderer.clone(),
            s.budget_spp.to_string(),
            s.seeds.to_string(),
            format!("{:.1}", s.spp),
            format!("{:.4}", s.cpu_s),
            format!("{:.4}", s.delta_e2000),
            format!("{:.4}", s.ratio_to_mitsuba),
        ]);
    }
    files.push(write_text(dir, "equal-time.csv", &medians.to_csv())?);

    let mut md = String::new();
    let _ = writeln!(
        md,
        "## Error at equal time against Mitsuba\n\nManifest `{}`: {} renders; machine: {}; written {}; Mitsuba {} `{}`; {} thread(s). Time: CPU seconds (user + system) of each renderer; fspec's spp chosen from a calibration run to match Mitsuba's median CPU seconds at each budget. Error: mean CIEDE2000 against the reference, median over seeds.\n",
        manifest_path.display(),
        measured.len(),
        manifest.machine,
        manifest.date,
        manifest.mitsuba_version,
        manifest.mitsuba_variant,
        manifest.threads
    );
    for (scene, info) in &references {
        let noise = info
            .noise_delta_e2000
            .map_or("not measured (no halves)".to_string(), |n| fixed(n, 3));
        let _ = writeln!(
            md,
            "### {scene}\n\nReference: {} spp; its own noise (half the ΔE2000 between its halves): {noise}.\n",
            info.spp
        );
        md.push_str(&scene_table(&summaries, scene).to_markdown());
        let mut series: Vec<Series> = Vec::new();
        for s in summaries.iter().filter(|s| &s.scene == scene) {
            match series.iter_mut().find(|x| x.name == s.renderer) {
                Some(x) => x.points.push((s.cpu_s, s.delta_e2000)),
                None => series.push(Series {
                    name: s.renderer.clone(),
                    points: vec![(s.cpu_s, s.delta_e2000)],
                }),
            }
        }
        for s in &mut series {
            s.points.sort_by(|a, b| a.0.total_cmp(&b.0));
        }
        let name = format!("equal-time-{scene}.png");
        let title = format!("{scene}: error against CPU time");
        let plot = LinePlot {
            title: &title,
            x_label: "CPU seconds (median over seeds)",
            y_label: "mean ΔE2000 (median over seeds)",
            x_scale: Scale::Log10,
            y_scale: Scale::Log10,
            series: &series,
        };
        let path = dir.join(&name);
        plot.write_png(&path)?;
        files.push(path);
        let _ = writeln!(md, "\n![{scene}]({name})\n");
    }
    files.push(write_text(dir, "equal-time.md", &md)?);
    Ok(Section {
        markdown: md,
        claims: Vec::new(),
        files,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use spectral_core::color::Lab;

    const SHARMA: &str = include_str!("../../../data/ciede2000_sharma.csv");
    /// |b*| of the hue-discontinuity pairs (±0.001, ±0.0009), below
    /// anything else in the table.
    const HUE_TEST_B: f64 = 0.01;

    fn image(texels: Vec<[f32; 3]>) -> RgbImage {
        RgbImage {
            width: texels.len() as u32,
            height: 1,
            texels,
            negative_clamped: 0,
        }
    }

    fn linear_srgb(lab: Lab) -> Option<[f32; 3]> {
        let white = LinearSrgb::new(1.0, 1.0, 1.0).to_xyz();
        let rgb = lab.to_xyz(white).to_linear_srgb();
        let c = [rgb.r, rgb.g, rgb.b];
        c.iter()
            .all(|v| (0.0..=1.0).contains(v))
            .then(|| c.map(|v| v as f32))
    }

    /// Sharma, Wu and Dalal's pairs whose colours are inside the sRGB gamut
    /// (the comparison clamps to it), but for the hue-discontinuity pairs:
    /// as two one-row images, the mean
    /// ΔE2000 is the published value to the table's rounding plus the
    /// `f32` texels' (measured below 2e-4).
    #[test]
    fn known_delta_e_of_published_pairs() {
        let mut tested = Vec::new();
        let mut expected_mean = 0.0;
        let (mut tests, mut refs) = (Vec::new(), Vec::new());
        for line in SHARMA.lines().filter(|l| !l.starts_with('#')).skip(1) {
            let v: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
            // Pairs 9–12 test the hue discontinuity: a b* of ±0.001 decides
            // the hue angle, which the `f32` texels cannot carry.
            if [v[3], v[6]]
                .iter()
                .any(|b| *b != 0.0 && b.abs() < HUE_TEST_B)
            {
                continue;
            }
            let (a, b) = (Lab::new(v[1], v[2], v[3]), Lab::new(v[4], v[5], v[6]));
            let (Some(ta), Some(tb)) = (linear_srgb(a), linear_srgb(b)) else {
                continue;
            };
            let one = compare_images(&image(vec![ta]), &image(vec![tb])).unwrap();
            assert!(
                (one.delta_e2000 - v[7]).abs() < 2e-4,
                "pair {}: {} vs {}",
                v[0],
                one.delta_e2000,
                v[7]
            );
            tested.push(v[0]);
            expected_mean += v[7];
            tests.push(ta);
            refs.push(tb);
        }
        assert!(tested.len() >= 10, "only pairs {tested:?} are in gamut");
        let mean = compare_images(&image(tests.clone()), &image(refs.clone())).unwrap();
        expected_mean /= tested.len() as f64;
        assert!((mean.delta_e2000 - expected_mean).abs() < 2e-4);
        // Negative control: the references shifted by one pixel (each test
        // colour against another pair's) are far from the published mean.
        refs.rotate_left(1);
        let shifted = compare_images(&image(tests), &image(refs)).unwrap();
        assert!((shifted.delta_e2000 - expected_mean).abs() > 1.0);
    }

    #[test]
    fn images_of_different_sizes_are_refused() {
        let e = compare_images(&image(vec![[0.5; 3]]), &image(vec![[0.5; 3]; 2])).unwrap_err();
        assert!(
            e.to_string()
                .contains("1 × 1 pixels against a reference of 2 × 1")
        );
    }

    #[test]
    fn medians() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!(median(&[]).is_nan());
    }

    fn manifest_text(mitsuba: &str, fspec: &str) -> String {
        format!(
            r#"{{"format": "{MANIFEST_FORMAT}", "threads": 1,
               "references": {{"box": {{"image": "ref.exr", "spp": 64}}}},
               "mitsuba": [{mitsuba}], "fspec": [{fspec}]}}"#
        )
    }

    const M1: &str = r#"{"scene": "box", "budget_spp": 4, "seed": 1, "spp": 4, "cpu_s": 0.5, "image": "m1.exr"}"#;
    const F1: &str = r#"{"scene": "box", "config": "a", "budget_spp": 4, "seed": 1, "spp": 9, "cpu_s": 0.5, "image": "f1.exr"}"#;

    #[test]
    fn manifest_parses_and_names_renderers() {
        let m = Manifest::parse(&manifest_text(M1, F1), "m.json").unwrap();
        let names: Vec<_> = m.runs().map(Run::renderer).collect();
        assert_eq!(names, ["mitsuba", "a"]);
    }

    #[test]
    fn bad_manifests_fail_with_one_line() {
        let cases = [
            ("{".to_string(), "not an equal-time manifest"),
            (
                manifest_text(M1, F1).replace(MANIFEST_FORMAT, "v0"),
                "expected \"fspec-equal-time-v1\"",
            ),
            (manifest_text("", ""), "no renders"),
            (
                manifest_text(&M1.replace("\"box\"", "\"other\""), ""),
                "no reference of scene other",
            ),
            (
                manifest_text(M1, &F1.replace("\"config\": \"a\", ", "")),
                "needs a config",
            ),
            (
                manifest_text(&M1.replace("0.5", "-1"), ""),
                "is not a time in seconds",
            ),
            (
                manifest_text(&M1.replace("\"spp\": 4", "\"spp\": 0"), ""),
                "at least 1",
            ),
            (
                manifest_text(&format!("{M1}, {M1}"), ""),
                "two renders of box",
            ),
            (
                manifest_text(M1, "").replace("\"threads\": 1", "\"threads\": 0"),
                "threads must be at least 1",
            ),
        ];
        for (text, message) in cases {
            let e = Manifest::parse(&text, "m.json").unwrap_err().to_string();
            assert!(e.starts_with("m.json: "), "{e}");
            assert!(e.contains(message), "{e} lacks {message}");
            assert!(!e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn summaries_take_medians_and_ratios() {
        let row = |renderer: &str, seed, e, cpu_s| Measured {
            scene: "box".into(),
            renderer: renderer.into(),
            budget_spp: 64,
            seed,
            spp: 10,
            cpu_s,
            delta_e2000: e,
        };
        let m = [
            row("b", 1, 1.0, 2.0),
            row(MITSUBA, 1, 2.0, 1.0),
            row(MITSUBA, 2, 4.0, 3.0),
            row(MITSUBA, 3, 3.0, 2.0),
        ];
        let s = summarise(&m);
        assert_eq!(s[0].renderer, MITSUBA);
        assert_eq!((s[0].delta_e2000, s[0].cpu_s, s[0].seeds), (3.0, 2.0, 3));
        assert_eq!(s[1].ratio_to_mitsuba, 1.0 / 3.0);
        let table = scene_table(&s, "box").to_markdown();
        assert!(
            table.contains("| 64 | 3.00 (2.00) | 1.00 (10 spp, 2.00 s) | 0.33 |"),
            "{table}"
        );
    }
}
