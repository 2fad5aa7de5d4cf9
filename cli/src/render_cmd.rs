//! `fspec render`: renders a built-in scene, a TOML scene file or a bare OBJ
//! to PNG / EXR, optionally a spectral EXR and the Fourier coefficient
//! planes, with a progress bar on a terminal.
//!
//! Defaults: the `cornell` scene, 512 × 512, 64 spp, max depth 8 (Mitsuba's
//! Cornell box setting), Fourier transport with N = 12 coefficients and a
//! spectral buffer converted by the zeroth-coefficient route, Gaussian
//! filter, outputs `render.png` and `render.exr` in the current folder.
//! Supported sizes: N ∈ {4, 8, 12, 16, 24, 32} (`--coeffs`), C ∈ {1, 2, 4,
//! 8, 12, 16, 32} (`--wavelengths`), control variates with C ∈ {4, 8, 12}
//! and N ∈ {4, 8, 12}: each supported size is compiled once.

use crate::error::CliError;
use crate::image_out::{
    Exposure, Tone, XyzImage, write_by_extension, write_coefficients_exr, write_spectral_exr,
};
use crate::scene_source::{SceneDefaults, resolve_scene};
use clap::ValueEnum;
use indicatif::{ProgressBar, ProgressStyle};
use simd_tracer::filter::Filter;
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{Progress, RenderResult, RenderSettings, render};
use simd_tracer::scene::Scene;
use simd_tracer::scenes::SceneOptions;
use simd_tracer::transport::{
    AlphaMode, Buffer, ControlVariateTransport, FourierTransport, SampledTransport, Transport,
};
use spectral_core::SpectralRange;
use spectral_core::sampling::WavelengthStrategy;
use spectral_core::xyz::XyzRoute;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Duration;

/// Ctrl-C presses seen since [`install_interrupt_handler`].
static INTERRUPTS: AtomicU32 = AtomicU32::new(0);

/// Exit code of a render stopped by Ctrl-C (128 + SIGINT, the shell's
/// convention), used after the partial image has been written.
pub const INTERRUPTED_EXIT_CODE: u8 = 130;

/// Installs the Ctrl-C handler of `fspec render`: the first press stops the
/// render after the pass in progress and the passes done so far are written
/// as usual; a second press exits at once. Outputs are always written to a
/// temporary name and renamed, so neither leaves a truncated file.
pub fn install_interrupt_handler() -> Result<(), CliError> {
    ctrlc::set_handler(|| {
        if INTERRUPTS.fetch_add(1, Ordering::SeqCst) == 0 {
            eprintln!(
                "\nfspec: interrupted: finishing the current pass (Ctrl-C again to quit now)"
            );
        } else {
            std::process::exit(i32::from(INTERRUPTED_EXIT_CODE));
        }
    })
    .map_err(|e| CliError::input(format!("cannot install the Ctrl-C handler: {e}")))
}

fn interrupted() -> bool {
    INTERRUPTS.load(Ordering::SeqCst) > 0
}

/// How light is carried along paths.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum TransportKind {
    /// N Fourier coefficients per path (the paper's method).
    Fourier,
    /// C sampled wavelengths per path (pbrt/Mitsuba style).
    Sampled,
    /// Sampled wavelengths with the Fourier estimate as a control variate.
    Cv,
}

/// How the sampled wavelengths are chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Sampling {
    /// Independent uniform wavelengths.
    Uniform,
    /// One uniform wavelength per equal sub-range.
    Stratified,
    /// One uniform hero wavelength, the others at fixed offsets.
    Hero,
    /// Visible-importance density (pbrt-v4 / Mitsuba 3), hero rotation in CDF space.
    Visible,
}

/// How coefficients become colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ToColor {
    /// Reconstruct at the CIE table wavelengths (one cos per wavelength).
    Series,
    /// The same with a precomputed cosine table.
    Lut,
    /// Zeroth coefficient of the product with the CMFs (3×N kernel).
    Zeroth,
    /// Maximum-entropy reconstruction.
    Mese,
}

/// Where samples are converted to colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BufferKind {
    /// Per-pixel coefficient sums, converted once at the end.
    Spectral,
    /// Every sample converted to XYZ.
    Rgb,
}

/// Pixel reconstruction filter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FilterKind {
    /// One-pixel box.
    Box,
    /// Gaussian, σ = 0.5 px, radius 2 px (Mitsuba's default).
    Gaussian,
}

/// 8-bit tone mapping.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ToneKind {
    /// Clamp to [0, 1].
    Clamp,
    /// c/(1 + c) per channel.
    Reinhard,
}

/// Arguments of `fspec render`.
#[derive(Debug, Clone, clap::Args)]
pub struct RenderArgs {
    /// A built-in scene (`fspec scenes` lists them), a TOML scene file, or a
    /// bare .obj (its MTL colours are used; lit by a white sky if it has no
    /// emitter).
    #[arg(default_value = "cornell")]
    pub scene: String,
    /// Image width in pixels (default: the scene's, else 512).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels (default: the scene's, else 512).
    #[arg(long)]
    pub height: Option<u32>,
    /// Samples per pixel (default: the scene's, else 64).
    #[arg(long)]
    pub spp: Option<u32>,
    /// Longest path in segments, Mitsuba's meaning: 1 = emitters seen
    /// directly, 2 = direct lighting, …; -1 = unlimited (default 8).
    #[arg(long, allow_hyphen_values = true)]
    pub max_depth: Option<i64>,
    /// Depth from which Russian roulette may end paths.
    #[arg(long, default_value_t = 5)]
    pub rr_depth: u32,
    /// What a path carries.
    #[arg(long, value_enum, default_value_t = TransportKind::Fourier)]
    pub transport: TransportKind,
    /// Fourier coefficients N (4, 8, 12, 16, 24, 32; cv: 4, 8, 12).
    #[arg(long, default_value_t = 12)]
    pub coeffs: usize,
    /// Sampled wavelengths per path C (1, 2, 4, 8, 12, 16, 32; cv: 4, 8, 12).
    /// Default 4 for sampled, 8 for cv.
    #[arg(long)]
    pub wavelengths: Option<usize>,
    /// How sampled wavelengths are chosen.
    #[arg(long, value_enum, default_value_t = Sampling::Hero)]
    pub sampling: Sampling,
    /// Conversion from coefficients to colour.
    #[arg(long, value_enum, default_value_t = ToColor::Zeroth)]
    pub to_color: ToColor,
    /// Colour conversion once per pixel (spectral) or per sample (rgb).
    #[arg(long, value_enum, default_value_t = BufferKind::Spectral)]
    pub buffer: BufferKind,
    /// Pixel filter.
    #[arg(long, value_enum, default_value_t = FilterKind::Gaussian)]
    pub filter: FilterKind,
    /// Seed of every random stream (same seed, same image).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Worker threads (default: all cores; the image does not depend on it).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Stop after the pass during which this many seconds have passed.
    #[arg(long)]
    pub time_limit: Option<f64>,
    /// Output files; the format follows the extension (.png: 8-bit sRGB,
    /// .exr: float linear sRGB). May be given several times.
    /// Default: render.png and render.exr.
    #[arg(long = "out", short)]
    pub out: Vec<PathBuf>,
    /// Also write X, Y, Z channels into EXR outputs.
    #[arg(long)]
    pub exr_xyz: bool,
    /// Write a spectral OpenEXR (Fichet et al. 2021 layout) with radiance
    /// every --spectral-step-nm (Fourier transport with a spectral buffer).
    #[arg(long)]
    pub spectral_exr: Option<PathBuf>,
    /// Wavelength step of the spectral EXR, nm.
    #[arg(long, default_value_t = 10.0)]
    pub spectral_step_nm: f64,
    /// Write the N coefficient planes as an EXR (channels F0..F{N-1}).
    #[arg(long)]
    pub coefficients_exr: Option<PathBuf>,
    /// Exposure of the PNG output in stops (linear values × 2^stops).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub exposure: f32,
    /// Tone mapping of the PNG output.
    #[arg(long, value_enum, default_value_t = ToneKind::Clamp)]
    pub tone: ToneKind,
    /// Illuminant of the colorchecker scene: a built-in name or a CSV file.
    #[arg(long)]
    pub illuminant: Option<String>,
    /// Control variates: pool the coefficient α over all pixels (default)
    /// or estimate it per pixel.
    #[arg(long)]
    pub cv_alpha_per_pixel: bool,
    /// Do not print progress (a one-line summary only).
    #[arg(long, short)]
    pub quiet: bool,
}

/// Largest image side, pixels.
pub const MAX_SIDE: u32 = 1 << 15;

/// What a finished render reports.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderSummary {
    /// Passes done.
    pub passes: u32,
    /// Samples traced.
    pub samples: u64,
    /// Rejected (non-finite) samples.
    pub rejected: u64,
    /// Wall time of the render.
    pub elapsed: Duration,
    /// Files written.
    pub written: Vec<PathBuf>,
    /// Stopped early by Ctrl-C (the files hold the passes done).
    pub interrupted: bool,
}

fn settings_from(args: &RenderArgs, defaults: &SceneDefaults) -> Result<RenderSettings, CliError> {
    let width = args.width.or(defaults.width).unwrap_or(512);
    let height = args.height.or(defaults.height).unwrap_or(512);
    let spp = args.spp.or(defaults.spp).unwrap_or(64);
    if width == 0 || height == 0 || spp == 0 {
        return Err(CliError::input(
            "--width, --height and --spp must be at least 1",
        ));
    }
    if width > MAX_SIDE || height > MAX_SIDE {
        return Err(CliError::input(format!(
            "{width}×{height} pixels: each side must be at most {MAX_SIDE}"
        )));
    }
    let max_depth = match args.max_depth.or(defaults.max_depth.map(i64::from)) {
        None => 8,
        Some(-1) => u32::MAX,
        Some(d) if d >= 1 && d <= i64::from(u32::MAX) => d as u32,
        Some(d) => {
            return Err(CliError::input(format!(
                "--max-depth {d}: use -1 (unlimited) or a depth >= 1"
            )));
        }
    };
    let time_limit = match args.time_limit {
        None => None,
        Some(t) if t.is_finite() && t > 0.0 => Some(Duration::from_secs_f64(t)),
        Some(t) => {
            return Err(CliError::input(format!(
                "--time-limit {t}: must be a positive number of seconds"
            )));
        }
    };
    if args.threads == Some(0) {
        return Err(CliError::input("--threads must be at least 1"));
    }
    Ok(RenderSettings {
        width,
        height,
        spp,
        integrator: IntegratorSettings {
            max_depth,
            rr_depth: args.rr_depth,
        },
        seed: args.seed.or(defaults.seed).unwrap_or(0),
        filter: match args.filter {
            FilterKind::Box => Filter::Box,
            FilterKind::Gaussian => Filter::gaussian(),
        },
        threads: args.threads,
        time_limit,
    })
}

/// Bytes per pixel the render needs (accumulators and outputs).
fn bytes_per_pixel(args: &RenderArgs) -> u64 {
    let n = args.coeffs as u64;
    match args.transport {
        // Coefficient and XYZ sums (f64), count, XYZ output, coefficient planes.
        TransportKind::Fourier => (n + 4) * 8 + 24 + 4 * n,
        TransportKind::Sampled => 4 * 8 + 24,
        // Three control-variate accumulators of 12 f64 each.
        TransportKind::Cv => 3 * 12 * 8 + 24,
    }
}

/// Physical memory from /proc/meminfo (Linux), if known.
fn physical_memory_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Refuses renders whose predicted memory exceeds half of the physical
/// memory (or 8 GiB where that is unknown).
pub fn check_memory(args: &RenderArgs, settings: &RenderSettings) -> Result<u64, CliError> {
    let pixels = u64::from(settings.width) * u64::from(settings.height);
    let predicted = pixels * bytes_per_pixel(args);
    let limit = physical_memory_bytes().map_or(8 << 30, |m| m / 2);
    if predicted > limit {
        return Err(CliError::input(format!(
            "{}×{} pixels would need about {:.1} GiB for the film (limit {:.1} GiB, half the memory): use a smaller image",
            settings.width,
            settings.height,
            predicted as f64 / f64::from(1u32 << 30),
            limit as f64 / f64::from(1u32 << 30)
        )));
    }
    Ok(predicted)
}

struct Reporter {
    bar: Option<ProgressBar>,
}

impl Reporter {
    fn new(total: u32, quiet: bool) -> Self {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = ProgressBar::new(u64::from(total));
            let style =
                ProgressStyle::with_template("{bar:40} {pos}/{len} passes  {msg}  ETA {eta}")
                    .unwrap_or_else(|_| ProgressStyle::default_bar());
            bar.set_style(style);
            bar
        });
        Self { bar }
    }

    fn update(&self, p: &Progress) -> bool {
        if let Some(bar) = &self.bar {
            bar.set_position(u64::from(p.passes_done));
            let rate = p.samples as f64 / p.elapsed.as_secs_f64().max(1e-9);
            bar.set_message(format!("{:.2} M samples/s", rate / 1e6));
        }
        !interrupted()
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

fn run_render<T: Transport>(
    transport: &T,
    scene: &Scene,
    settings: &RenderSettings,
    quiet: bool,
) -> Result<RenderResult, CliError> {
    let reporter = Reporter::new(settings.spp, quiet);
    let result = render(transport, scene, settings, &mut |p| reporter.update(p))
        .map_err(|e| CliError::input(e.to_string()));
    reporter.finish();
    result
}

fn strategy(args: &RenderArgs) -> WavelengthStrategy {
    match args.sampling {
        Sampling::Uniform => WavelengthStrategy::Uniform,
        Sampling::Stratified => WavelengthStrategy::Stratified,
        Sampling::Hero => WavelengthStrategy::Hero,
        Sampling::Visible => WavelengthStrategy::VisibleHero,
    }
}

fn route(args: &RenderArgs) -> XyzRoute {
    match args.to_color {
        ToColor::Series => XyzRoute::Series,
        ToColor::Lut => XyzRoute::Lut,
        ToColor::Zeroth => XyzRoute::Zeroth,
        ToColor::Mese => XyzRoute::Mese,
    }
}

fn fourier<const N: usize>(
    args: &RenderArgs,
    scene: &Scene,
    settings: &RenderSettings,
) -> Result<RenderResult, CliError> {
    let buffer = match args.buffer {
        BufferKind::Spectral => Buffer::Spectral,
        BufferKind::Rgb => Buffer::Xyz,
    };
    let transport = FourierTransport::<N>::new(scene.range, buffer, route(args))
        .map_err(|e| CliError::input(format!("spectral range: {e}")))?;
    run_render(&transport, scene, settings, args.quiet)
}

fn sampled<const C: usize>(
    args: &RenderArgs,
    scene: &Scene,
    settings: &RenderSettings,
) -> Result<RenderResult, CliError> {
    run_render(
        &SampledTransport::<C>::new(scene.range, strategy(args)),
        scene,
        settings,
        args.quiet,
    )
}

fn cv<const C: usize, const N: usize>(
    args: &RenderArgs,
    scene: &Scene,
    settings: &RenderSettings,
) -> Result<RenderResult, CliError> {
    let alpha = if args.cv_alpha_per_pixel {
        AlphaMode::PerPixel
    } else {
        AlphaMode::Shared
    };
    let transport = ControlVariateTransport::<C, N>::new(scene.range, strategy(args), alpha)
        .map_err(|e| CliError::input(format!("spectral range: {e}")))?;
    run_render(&transport, scene, settings, args.quiet)
}

fn dispatch(
    args: &RenderArgs,
    scene: &Scene,
    settings: &RenderSettings,
) -> Result<RenderResult, CliError> {
    let unsupported = |what: &str, value: usize, supported: &str| {
        Err(CliError::input(format!(
            "{what} {value} is not supported (supported: {supported})"
        )))
    };
    match args.transport {
        TransportKind::Fourier => match args.coeffs {
            4 => fourier::<4>(args, scene, settings),
            8 => fourier::<8>(args, scene, settings),
            12 => fourier::<12>(args, scene, settings),
            16 => fourier::<16>(args, scene, settings),
            24 => fourier::<24>(args, scene, settings),
            32 => fourier::<32>(args, scene, settings),
            n => unsupported("--coeffs", n, "4, 8, 12, 16, 24, 32"),
        },
        TransportKind::Sampled => match args.wavelengths.unwrap_or(4) {
            1 => sampled::<1>(args, scene, settings),
            2 => sampled::<2>(args, scene, settings),
            4 => sampled::<4>(args, scene, settings),
            8 => sampled::<8>(args, scene, settings),
            12 => sampled::<12>(args, scene, settings),
            16 => sampled::<16>(args, scene, settings),
            32 => sampled::<32>(args, scene, settings),
            c => unsupported("--wavelengths", c, "1, 2, 4, 8, 12, 16, 32"),
        },
        TransportKind::Cv => match (args.wavelengths.unwrap_or(8), args.coeffs) {
            (4, 4) => cv::<4, 4>(args, scene, settings),
            (4, 8) => cv::<4, 8>(args, scene, settings),
            (4, 12) => cv::<4, 12>(args, scene, settings),
            (8, 4) => cv::<8, 4>(args, scene, settings),
            (8, 8) => cv::<8, 8>(args, scene, settings),
            (8, 12) => cv::<8, 12>(args, scene, settings),
            (12, 4) => cv::<12, 4>(args, scene, settings),
            (12, 8) => cv::<12, 8>(args, scene, settings),
            (12, 12) => cv::<12, 12>(args, scene, settings),
            (c, n) => Err(CliError::input(format!(
                "--transport cv with --wavelengths {c} --coeffs {n} is not supported (C and N in 4, 8, 12)"
            ))),
        },
    }
}

/// Checks the output options before rendering (so a typo fails fast).
fn check_outputs(args: &RenderArgs, outputs: &[PathBuf]) -> Result<(), CliError> {
    for path in outputs {
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        if !matches!(extension.as_deref(), Some("png" | "exr")) {
            return Err(CliError::input(format!(
                "{}: unsupported output format (use .png or .exr)",
                path.display()
            )));
        }
    }
    let spectral = args.transport == TransportKind::Fourier && args.buffer == BufferKind::Spectral;
    if (args.spectral_exr.is_some() || args.coefficients_exr.is_some()) && !spectral {
        return Err(CliError::input(
            "--spectral-exr and --coefficients-exr need --transport fourier with --buffer spectral",
        ));
    }
    if !(args.spectral_step_nm.is_finite() && args.spectral_step_nm > 0.0) {
        return Err(CliError::input(
            "--spectral-step-nm must be a positive number",
        ));
    }
    Ok(())
}

/// Spectral radiance at `wavelengths` from the coefficient planes (series,
/// negative lobes clamped to 0).
fn spectral_planes(
    range: &SpectralRange,
    n: usize,
    coeffs: &[f32],
    wavelengths: &[f64],
) -> Vec<f32> {
    let cosines: Vec<Vec<f64>> = wavelengths
        .iter()
        .map(|&l| {
            let phi = range.phase(l);
            (0..n)
                .map(|j| (j as f64 * phi).cos() * if j == 0 { 1.0 } else { 2.0 })
                .collect()
        })
        .collect();
    let mut out = Vec::with_capacity(coeffs.len() / n.max(1) * wavelengths.len());
    for pixel in coeffs.chunks_exact(n.max(1)) {
        for c in &cosines {
            let v: f64 = pixel.iter().zip(c).map(|(&a, &b)| f64::from(a) * b).sum();
            out.push(v.max(0.0) as f32);
        }
    }
    out
}

/// Runs `fspec render`.
pub fn run(args: &RenderArgs) -> Result<RenderSummary, CliError> {
    let outputs = if args.out.is_empty() {
        vec![PathBuf::from("render.png"), PathBuf::from("render.exr")]
    } else {
        args.out.clone()
    };
    check_outputs(args, &outputs)?;
    let options = SceneOptions {
        illuminant: args
            .illuminant
            .as_deref()
            .map(crate::scene_source::illuminant_source)
            .transpose()?,
    };
    let (builder, defaults, warnings) = resolve_scene(&args.scene, &options)?;
    for warning in &warnings {
        eprintln!("fspec: warning: {warning}");
    }
    let settings = settings_from(args, &defaults)?;
    check_memory(args, &settings)?;
    let scene = builder
        .build()
        .map_err(|e| CliError::input(format!("{}: {e}", args.scene)))?;
    if scene.skipped_triangles() > 0 {
        eprintln!(
            "fspec: warning: {} degenerate triangles skipped",
            scene.skipped_triangles()
        );
    }
    let result = dispatch(args, &scene, &settings)?;
    let image = XyzImage {
        width: result.width,
        height: result.height,
        xyz: &result.xyz,
    };
    let exposure = Exposure {
        stops: args.exposure,
    };
    let tone = match args.tone {
        ToneKind::Clamp => Tone::Clamp,
        ToneKind::Reinhard => Tone::Reinhard,
    };
    let mut written = Vec::new();
    for path in &outputs {
        write_by_extension(path, &image, exposure, tone, args.exr_xyz)?;
        written.push(path.clone());
    }
    if let Some((n, coeffs)) = &result.coefficients {
        if let Some(path) = &args.coefficients_exr {
            let range = (scene.range.min_nm(), scene.range.max_nm());
            write_coefficients_exr(path, result.width, result.height, *n, coeffs, range)?;
            written.push(path.clone());
        }
        if let Some(path) = &args.spectral_exr {
            let steps = (scene.range.width_nm() / args.spectral_step_nm).floor() as usize;
            let wavelengths: Vec<f64> = (0..=steps)
                .map(|i| scene.range.min_nm() + i as f64 * args.spectral_step_nm)
                .collect();
            let radiance = spectral_planes(&scene.range, *n, coeffs, &wavelengths);
            write_spectral_exr(
                path,
                result.width,
                result.height,
                &wavelengths,
                &radiance,
                &image,
            )?;
            written.push(path.clone());
        }
    }
    Ok(RenderSummary {
        passes: result.passes,
        samples: result.samples,
        rejected: result.rejected,
        elapsed: result.elapsed,
        written,
        interrupted: interrupted(),
    })
}

/// The final line: time, samples/s, rejected samples, output paths.
pub fn summary_line(summary: &RenderSummary) -> String {
    let seconds = summary.elapsed.as_secs_f64();
    let files: Vec<String> = summary
        .written
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    let rejected = if summary.rejected > 0 {
        format!(", {} samples rejected (NaN/Inf)", summary.rejected)
    } else {
        String::new()
    };
    let stopped = if summary.interrupted {
        " (interrupted)"
    } else {
        ""
    };
    format!(
        "rendered {} passes{stopped} in {seconds:.2} s ({:.2} M samples/s{rejected}); wrote {}",
        summary.passes,
        summary.samples as f64 / seconds.max(1e-9) / 1e6,
        files.join(", ")
    )
}
