//! `fspec experiment`: the paper's measurable claims (section
//! «Эксперименты») and three measurements beyond it, each written to a
//! folder as CSV, Markdown and PNG plots.
//!
//! | name | what | module |
//! | --- | --- | --- |
//! | `conversions` | the paper's table (conversion routes × buffers, Spec32, Spec4 hero) and ΔE/PSNR against spp (figures 7, 10) on `lamps` and `laser` | [`conversions`] |
//! | `colorchecker` | direct lighting of the 24 patches: uniform, stratified, hero, Fourier, control variates; mean ΔE2000 against samples (figures 12, 13) | [`colorchecker`] |
//! | `truncation` | bias of Fourier N = 4 … 32 against the reference, and its cost | [`truncation`] |
//! | `ringing` | negative reconstructions with and without Fejér damping, and the ΔE they cost | [`ringing`] |
//! | `memory` | bytes per pixel and per texel of each representation, and its colour error | [`memory`] |
//! | `equal-time` | mean ΔE2000 at equal CPU time, fspec against Mitsuba 3, from `tools/mitsuba_equal_time.py`'s manifest (`--manifest`) | [`equal_time`] |
//! | `all` | all of them but `equal-time`, one report | |
//!
//! Sizes: the full run uses the paper's 512 × 512 pixels and 64 spp; the
//! reference has [`FULL_REFERENCE_SPP`] spp; the truncation renders a
//! quarter of the table's spp. `--quick` shrinks everything for a check in
//! seconds; `--size`, `--spp`, `--reference-spp`, `--runs`,
//! `--max-samples` override single settings. Every run writes
//! `OUT/report.md` (machine, command, load, every section and the claims
//! with verdicts) beside the per-experiment files.

pub mod colorchecker;
pub mod conversions;
pub mod equal_time;
pub mod image;
pub mod memory;
pub mod plot;
pub mod report;
pub mod ringing;
pub mod truncation;

use crate::error::CliError;
use clap::ValueEnum;
use report::{Claim, Section, claims_markdown, write_text};
use spectral_core::observer::StandardObserver;
use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Image side of the full run, pixels (the paper's 512).
pub const FULL_SIZE: u32 = 512;
/// Samples per pixel of the full run (the paper's 64).
pub const FULL_SPP: u32 = 64;
/// Samples per pixel of the full run's reference.
pub const FULL_REFERENCE_SPP: u32 = 512;
/// Independent runs of the colorchecker experiment.
pub const FULL_RUNS: usize = 100;
/// Largest colorchecker sample count.
pub const FULL_MAX_SAMPLES: usize = 1024;
/// `--quick`: side, spp, reference spp, runs, largest sample count.
pub const QUICK: (u32, u32, u32, usize, usize) = (64, 8, 32, 8, 64);
/// Side of the pixel blocks whose means measure bias (noise averages out
/// over `BIAS_BLOCK_PX²` pixels), pixels.
pub const BIAS_BLOCK_PX: u32 = 32;
/// Largest image side accepted, pixels.
pub const MAX_SIZE: u32 = 4096;
/// Largest colorchecker sample count accepted.
pub const MAX_SAMPLES_LIMIT: usize = 1 << 20;
/// Largest samples per pixel accepted (compared renders and reference):
/// 512² pixels at this spp is already days of rendering on a desktop.
pub const MAX_SPP: u32 = 1 << 16;
/// Most render threads accepted (far above any core count; a larger
/// number would only spawn idle threads).
pub const MAX_THREADS: usize = 1024;
/// Largest number of independent colorchecker runs accepted.
pub const MAX_RUNS: usize = 1 << 20;

/// Which experiment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ExperimentName {
    /// The paper's conversion table and ΔE/PSNR-vs-spp curves.
    Conversions,
    /// Direct lighting of the ColorChecker: sampling strategies and control variates.
    Colorchecker,
    /// Truncation bias against the number of coefficients.
    Truncation,
    /// Negative lobes of reconstructions, with and without Fejér damping.
    Ringing,
    /// Memory per pixel and per texel of each representation.
    Memory,
    /// Colour error at equal CPU time against Mitsuba 3 (needs --manifest).
    EqualTime,
    /// Every experiment.
    All,
}

/// Arguments of `fspec experiment`.
#[derive(Debug, Clone, clap::Args)]
pub struct ExperimentArgs {
    /// Which experiment to run.
    #[arg(value_enum)]
    pub name: ExperimentName,
    /// Output folder (created if missing).
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
    /// Image side in pixels (default 512; --quick 64).
    #[arg(long)]
    pub size: Option<u32>,
    /// Samples per pixel of the compared renders (default 64; --quick 8).
    #[arg(long)]
    pub spp: Option<u32>,
    /// Samples per pixel of the reference, in an even number of chunks of at
    /// most 128 (default 512; --quick 32).
    #[arg(long)]
    pub reference_spp: Option<u32>,
    /// Independent runs of the colorchecker experiment (default 100; --quick 8).
    #[arg(long)]
    pub runs: Option<usize>,
    /// Largest colorchecker sample count, a power of two (default 1024; --quick 64).
    #[arg(long)]
    pub max_samples: Option<usize>,
    /// Colorchecker illuminant: a built-in name (d65, led-b4, …) or a CSV
    /// file (default d65; `all` runs d65 and led-b4).
    #[arg(long)]
    pub illuminant: Option<String>,
    /// Colorchecker observer: cie1931-2 (default) or cie1964-10.
    #[arg(long)]
    pub observer: Option<String>,
    /// Colorchecker only: print the results as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// Small sizes for a run of seconds.
    #[arg(long)]
    pub quick: bool,
    /// Worker threads of the renders (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// equal-time only: the manifest `tools/mitsuba_equal_time.py` wrote.
    #[arg(long)]
    pub manifest: Option<PathBuf>,
}

/// The resolved sizes of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    /// Image side, pixels.
    pub size: u32,
    /// Samples per pixel of the compared renders.
    pub spp: u32,
    /// Samples per pixel of the reference (even: two halves).
    pub reference_spp: u32,
    /// Samples per pixel of the truncation renders.
    pub truncation_spp: u32,
    /// Independent colorchecker runs.
    pub runs: usize,
    /// Largest colorchecker sample count (a power of two).
    pub max_samples: usize,
    /// Render threads.
    pub threads: Option<usize>,
    /// The colorchecker's observer.
    pub observer: StandardObserver,
}

impl Config {
    /// Resolves the sizes from the arguments (checking them).
    pub fn from_args(args: &ExperimentArgs) -> Result<Self, CliError> {
        let (size, spp, reference_spp, runs, max_samples) = if args.quick {
            QUICK
        } else {
            (
                FULL_SIZE,
                FULL_SPP,
                FULL_REFERENCE_SPP,
                FULL_RUNS,
                FULL_MAX_SAMPLES,
            )
        };
        let size = args.size.unwrap_or(size);
        let spp = args.spp.unwrap_or(spp);
        let reference_spp = args.reference_spp.unwrap_or(reference_spp);
        let runs = args.runs.unwrap_or(runs);
        let max_samples = args.max_samples.unwrap_or(max_samples);
        if !(1..=MAX_SIZE).contains(&size) {
            return Err(CliError::input(format!(
                "--size {size}: use 1 to {MAX_SIZE} pixels"
            )));
        }
        if !(1..=MAX_SPP).contains(&spp) {
            return Err(CliError::input(format!(
                "--spp {spp}: use 1 to {MAX_SPP} samples per pixel"
            )));
        }
        if reference_spp < 2 || reference_spp % 2 != 0 || reference_spp > MAX_SPP {
            return Err(CliError::input(format!(
                "--reference-spp {reference_spp}: use an even number from 2 to {MAX_SPP} (two independent halves)"
            )));
        }
        if !(1..=MAX_RUNS).contains(&runs) {
            return Err(CliError::input(format!(
                "--runs {runs}: use 1 to {MAX_RUNS} runs"
            )));
        }
        if !max_samples.is_power_of_two() || max_samples > MAX_SAMPLES_LIMIT {
            return Err(CliError::input(format!(
                "--max-samples {max_samples}: use a power of two up to {MAX_SAMPLES_LIMIT}"
            )));
        }
        if let Some(threads) = args.threads
            && !(1..=MAX_THREADS).contains(&threads)
        {
            return Err(CliError::input(format!(
                "--threads {threads}: use 1 to {MAX_THREADS}"
            )));
        }
        Ok(Self {
            size,
            spp,
            reference_spp,
            truncation_spp: (spp / 4).max(1),
            runs,
            max_samples,
            observer: match &args.observer {
                Some(name) => StandardObserver::lookup(name).map_err(|_| {
                    CliError::input(format!("--observer {name}: use cie1931-2 or cie1964-10"))
                })?,
                None => StandardObserver::Cie1931,
            },
            threads: args.threads,
        })
    }

    /// Where reference renders are cached.
    pub fn cache_dir(&self, out: &Path) -> PathBuf {
        out.join("cache")
    }
}

/// One progress line on stderr.
pub fn progress(message: &str) {
    eprintln!("fspec experiment: {message}");
}

/// CPU model, logical cores and load averages (Linux `/proc`; "unknown"
/// elsewhere).
pub fn machine_description() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|text| {
            text.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".to_string());
    let cores = std::thread::available_parallelism().map_or(0, usize::from);
    format!("{model}, {cores} logical cores")
}

/// The 1, 5 and 15 minute load averages (`/proc/loadavg`).
pub fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .map(|t| t.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|| "unknown".to_string())
}

fn illuminants(args: &ExperimentArgs) -> Vec<String> {
    match (&args.illuminant, args.name) {
        (Some(name), _) => vec![name.clone()],
        (None, ExperimentName::All) => vec!["d65".into(), "led-b4".into()],
        (None, _) => vec!["d65".into()],
    }
}

/// Runs `fspec experiment`; prints a summary (or, with `--json`, the
/// colorchecker JSON) to `out`.
pub fn run(args: &ExperimentArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let config = Config::from_args(args)?;
    if args.json && args.name != ExperimentName::Colorchecker {
        return Err(CliError::input(
            "--json is only for `fspec experiment colorchecker`",
        ));
    }
    if (args.illuminant.is_some() || args.observer.is_some())
        && !matches!(
            args.name,
            ExperimentName::Colorchecker | ExperimentName::All
        )
    {
        return Err(CliError::input(
            "--illuminant and --observer are only for the colorchecker experiment (or `all`)",
        ));
    }
    match (args.name, &args.manifest) {
        (ExperimentName::EqualTime, None) => {
            return Err(CliError::input(
                "equal-time needs --manifest FILE (written by tools/mitsuba_equal_time.py)",
            ));
        }
        (ExperimentName::EqualTime, Some(_)) | (_, None) => {}
        (_, Some(_)) => {
            return Err(CliError::input(
                "--manifest is only for `fspec experiment equal-time`",
            ));
        }
    }
    let illuminants = illuminants(args)
        .iter()
        .map(|name| colorchecker::Illuminant::resolve(name))
        .collect::<Result<Vec<_>, _>>()?;
    let dir = &args.out;
    std::fs::create_dir_all(dir)
        .map_err(|e| CliError::input(format!("{}: cannot create: {e}", dir.display())))?;
    let started = Instant::now();
    let load_before = load_average();
    let which = |n: ExperimentName| args.name == n || args.name == ExperimentName::All;
    let mut sections: Vec<Section> = Vec::new();
    let mut json = None;
    if which(ExperimentName::Conversions) {
        progress("conversions");
        sections.push(conversions::run(&config, dir)?);
    }
    if which(ExperimentName::Colorchecker) {
        for illuminant in &illuminants {
            progress(&format!("colorchecker under {}", illuminant.name));
            let (section, value) = colorchecker::run(&config, illuminant, dir)?;
            sections.push(section);
            json = Some(value);
        }
    }
    let mut truncation_renders = None;
    if which(ExperimentName::Truncation) {
        progress("truncation");
        let renders = truncation::render_all(&config, dir)?;
        sections.push(truncation::run(&config, &renders, dir)?);
        truncation_renders = Some(renders);
    }
    if which(ExperimentName::Ringing) {
        progress("ringing");
        let renders = match truncation_renders {
            Some(r) => r,
            None => truncation::render_all(&config, dir)?,
        };
        sections.push(ringing::run(&config, &renders, dir)?);
    }
    if which(ExperimentName::Memory) {
        progress("memory");
        sections.push(memory::run(dir)?);
    }
    if let (ExperimentName::EqualTime, Some(manifest)) = (args.name, &args.manifest) {
        progress("equal-time");
        sections.push(equal_time::run(manifest, dir)?);
    }
    let claims: Vec<Claim> = sections.iter().flat_map(|s| s.claims.clone()).collect();
    let command: Vec<String> = std::env::args().collect();
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# fspec experiment results\n\nMachine: {}. Command: `{}`. Wall time {:.0} s. Load average (1, 5, 15 min) before: {load_before}, after: {}.\n",
        machine_description(),
        command.join(" "),
        started.elapsed().as_secs_f64(),
        load_average()
    );
    for s in &sections {
        md.push_str(&s.markdown);
        md.push('\n');
    }
    if !claims.is_empty() {
        let _ = writeln!(md, "## All claims\n\n{}", claims_markdown(&claims));
    }
    let report = write_text(dir, "report.md", &md)?;
    let io = |e: std::io::Error| CliError::input(format!("cannot write the output: {e}"));
    match json {
        Some(value) if args.json => {
            let text = serde_json::to_string_pretty(&value)
                .map_err(|e| CliError::input(format!("cannot format JSON: {e}")))?;
            writeln!(out, "{text}").map_err(io)?;
        }
        _ => {
            for c in &claims {
                writeln!(out, "[{}] {}", c.verdict.as_str(), c.claim).map_err(io)?;
            }
            let files: usize = sections.iter().map(|s| s.files.len()).sum();
            writeln!(out, "wrote {} and {files} more files", report.display()).map_err(io)?;
        }
    }
    Ok(())
}
