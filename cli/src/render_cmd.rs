//! `fspec render`: renders a built-in scene, a TOML scene file or a bare OBJ
//! to PNG / EXR, optionally a spectral EXR and the Fourier coefficient
//! planes, with a progress bar on a terminal.
//!
//! Defaults: the `cornell` scene, 512 × 512, 64 spp, max depth 8 (Mitsuba's
//! Cornell box setting), Fourier transport with N chosen from the scene's
//! spectra (`--coeffs auto`, [`crate::coefficient_choice`]) and a
//! spectral buffer converted by the zeroth-coefficient route, Gaussian
//! filter, outputs `render.png` and `render.exr` in the current folder.
//! Supported sizes: N ∈ {4, 8, 12, 16, 24, 32} (`--coeffs`), C ∈ {1, 2, 4,
//! 8, 12, 16, 32} (`--wavelengths`), control variates with C ∈ {4, 8, 12}
//! and N ∈ {4, 8, 12}: each supported size is compiled once.

use crate::coefficient_choice::{CoeffsChoice, UNRESOLVED_COEFFS, choose_for_scene};
use crate::error::CliError;
use crate::image_out::{
    Exposure, Tone, XyzImage, write_by_extension, write_coefficients_exr, write_spectral_exr,
};
use crate::partial_file::{self, FrameIdentity, PartialFilm};
use crate::scene_file::{FilterChoice, MitsubaOptions};
use crate::scene_source::{SceneDefaults, resolve_scene};
use crate::sensor_file::{ObserverChoice, load_sensor_csv};
use clap::ValueEnum;
use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};
use simd_tracer::film::filter::{Filter, GAUSSIAN_SIGMA_PX};
use simd_tracer::film::{AlphaMode, Buffer, FilmMode};
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{
    FilmState, PassJob, PixelWindow, Progress, RenderResult, RenderSettings, TILE_SIZE,
    render_passes, resolve_state,
};
use simd_tracer::sampling::sampler::SamplerKind;
use simd_tracer::scene::builtin::SceneOptions;
use simd_tracer::scene::{DerivedChecks, Scene};
use simd_tracer::transport::emission_density::{EmissionDensity, emission_density};
use simd_tracer::transport::{
    ControlVariateTransport, FourierTransport, HybridSettings, HybridTransport, SampledTransport,
    Transport,
};
use spectral_core::SpectralRange;
use spectral_core::color::Xyz;
use spectral_core::observer::Observer;
use spectral_core::sampling::WavelengthStrategy;
use spectral_core::xyz::XyzRoute;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Duration;

/// Ctrl-C presses seen since [`install_interrupt_handler`].
static INTERRUPTS: AtomicU32 = AtomicU32::new(0);

/// Exit code of a render stopped by Ctrl-C (128 + SIGINT, the shell's
/// convention), used after the partial image has been written.
pub const INTERRUPTED_EXIT_CODE: u8 = 130;

/// Installs the Ctrl-C handler of `fspec render`: the first press stops the
/// render after the pass in progress and the passes done so far are written
/// as usual; a second press exits at once, removing the temporaries of
/// writes in progress first. Outputs are always written to a temporary
/// name and renamed, so neither leaves a truncated or temporary file.
pub fn install_interrupt_handler() -> Result<(), CliError> {
    ctrlc::set_handler(|| {
        if INTERRUPTS.fetch_add(1, Ordering::SeqCst) == 0 {
            eprintln!(
                "\nfspec: interrupted: finishing the current pass (Ctrl-C again to quit now)"
            );
        } else {
            crate::image_out::remove_temporaries_and_exit(i32::from(INTERRUPTED_EXIT_CODE));
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
    /// N Fourier coefficients until a path meets dispersion, then C sampled
    /// wavelengths; the film adds both.
    Hybrid,
}

/// How the sampled wavelengths are chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Sampling {
    /// Independent uniform wavelengths.
    Uniform,
    /// One uniform wavelength per equal sub-range.
    Stratified,
    /// One uniform hero wavelength, the others at fixed offsets.
    Hero,
    /// Visible-importance density (pbrt-v4 / Mitsuba 3), hero rotation in CDF space.
    Visible,
    /// A density that follows the scene's lamps: the visible density and
    /// each emission spectrum times the observer, in equal parts, hero
    /// rotation in its CDF space (the hybrid's default).
    Lights,
}

/// What a hybrid path does where its direction depends on wavelength (the
/// refraction of smooth dispersive glass).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DispersionPaths {
    /// pbrt's rule: the hero wavelength goes on alone, the secondaries are
    /// terminated (what partial films written before this choice existed
    /// were rendered with).
    #[default]
    Hero,
    /// Every wavelength of the split goes on along its own direction, as a
    /// path of its own: less colour noise in dispersed light, `C − 1` more
    /// paths from every such refraction.
    All,
}

/// Where the hybrid's caustics of dispersive glass come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Caustics {
    /// Camera paths alone, which find a lamp behind glass only by chance
    /// (what partial films written before this choice existed were
    /// rendered with).
    #[default]
    Camera,
    /// Light paths from the lamps carry the light that passes dispersive
    /// glass, or is mirrored by its surface, before its first diffuse
    /// bounce
    /// (`simd_tracer::integrator::light_paths`; perspective cameras, a
    /// pinhole or a thin lens; scenes without fluorescence).
    LightPaths,
}

/// How coefficients become colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
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
    /// Tent, radius 1 px (Mitsuba's `tent` default).
    Tent,
    /// Gaussian, σ = 0.5 px, radius 2 px (Mitsuba's default).
    Gaussian,
    /// Mitchell–Netravali cubic, B = C = 1/3, radius 2 px (Mitsuba's
    /// `mitchell`; negative lobes: splatting film only).
    Mitchell,
    /// Catmull–Rom cubic, radius 2 px (Mitsuba's `catmullrom`; splatting
    /// film only).
    CatmullRom,
    /// Lanczos sinc of 3 lobes, radius 3 px (Mitsuba's `lanczos`;
    /// splatting film only).
    Lanczos,
}

impl From<FilterKind> for FilterChoice {
    /// The filter of the flag's name (`FilterChoice::named`, Mitsuba's
    /// defaults).
    fn from(kind: FilterKind) -> Self {
        let name = kind
            .to_possible_value()
            .map(|value| value.get_name().to_string());
        name.as_deref()
            .and_then(FilterChoice::named)
            .unwrap_or(FilterChoice::Gaussian {
                stddev_px: GAUSSIAN_SIGMA_PX,
            })
    }
}

/// How samples reach pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FilmKind {
    /// Importance-sample the filter: each sample lands in one pixel.
    Sample,
    /// Splat each sample, uniform in its pixel, into every pixel under the
    /// filter, weighted by its value (Mitsuba's film).
    Splat,
}

impl From<FilmKind> for FilmMode {
    fn from(kind: FilmKind) -> Self {
        match kind {
            FilmKind::Sample => Self::Sample,
            FilmKind::Splat => Self::Splat,
        }
    }
}

/// Where a path's numbers come from (`simd_tracer::sampling::sampler`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SamplerChoice {
    /// Independent PCG streams per pixel and pass.
    Independent,
    /// Owen-scrambled Sobol points, one sequence per pixel.
    Sobol,
}

impl From<SamplerChoice> for SamplerKind {
    fn from(choice: SamplerChoice) -> Self {
        match choice {
            SamplerChoice::Independent => Self::Independent,
            SamplerChoice::Sobol => Self::Sobol,
        }
    }
}

/// 8-bit tone mapping.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ToneKind {
    /// Clamp to [0, 1].
    Clamp,
    /// c/(1 + c) per channel.
    Reinhard,
}

/// Arguments of `fspec render`.
#[derive(Debug, Clone, clap::Args)]
pub struct RenderArgs {
    /// A built-in scene (`fspec scenes` lists them), a TOML scene file, a
    /// Mitsuba 3 scene file (.xml), or a bare .obj (its MTL colours are
    /// used; lit by a white sky if it has no emitter).
    #[arg(default_value = "cornell")]
    pub scene: String,
    /// A parameter of a Mitsuba scene file, `name=value`: replaces `$name`
    /// and wins over the file's `<default>` (as Mitsuba's `-D`; repeatable).
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    pub define: Vec<String>,
    /// Mitsuba scene files: render unsupported BSDFs as grey diffuse ones
    /// and skip unsupported emitters and parameters, each with a warning
    /// (default: an error naming the file and line).
    #[arg(long)]
    pub lenient: bool,
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
    /// Depth from which Russian roulette may end paths (default: the
    /// scene's, else 5).
    #[arg(long)]
    pub rr_depth: Option<u32>,
    /// What a path carries (default: the scene's `[render] transport`,
    /// else fourier). hybrid: Fourier until a path meets a dispersive
    /// dielectric, sampled wavelengths after it.
    #[arg(long, value_enum)]
    pub transport: Option<TransportKind>,
    /// Fourier coefficients N (4, 8, 12, 16, 24, 32; cv: 4, 8, 12; hybrid:
    /// 12, 16, 24, 32 with C = 4, 12 with C = 1 or 8), or auto: the
    /// smallest N whose truncation keeps the colour of every light ×
    /// reflectance product of the scene within ΔE2000 0.44 (hybrid: the
    /// same, at least 12; cv: 12). Default: the scene's `[render] coeffs`,
    /// else auto.
    #[arg(long, value_name = "N|auto", value_parser = CoeffsChoice::parse)]
    pub coeffs: Option<CoeffsChoice>,
    /// Sampled wavelengths per path C (1, 2, 4, 8, 12, 16, 32; cv: 4, 8, 12;
    /// hybrid: 1, 4, 8, drawn where a path meets dispersion). Default 4 for
    /// sampled and hybrid, 8 for cv.
    #[arg(long)]
    pub wavelengths: Option<usize>,
    /// How sampled wavelengths are chosen [default: lights for hybrid,
    /// hero otherwise].
    #[arg(long, value_enum)]
    pub sampling: Option<Sampling>,
    /// Hybrid: where a path's direction depends on wavelength, trace every
    /// wavelength of its split on its own path (all) or the hero alone
    /// (hero) [default: HYBRID_DISPERSION_PATHS].
    #[arg(long, value_enum)]
    pub dispersion_paths: Option<DispersionPaths>,
    /// Hybrid: where the caustics of dispersive glass come from: light
    /// paths from the lamps (light-paths) or camera paths alone (camera)
    /// [default: HYBRID_CAUSTICS].
    #[arg(long, value_enum)]
    pub caustics: Option<Caustics>,
    /// Conversion from coefficients to colour.
    #[arg(long, value_enum, default_value_t = ToColor::Zeroth)]
    pub to_color: ToColor,
    /// Colour conversion once per pixel (spectral) or per sample (rgb).
    #[arg(long, value_enum, default_value_t = BufferKind::Spectral)]
    pub buffer: BufferKind,
    /// Pixel filter (default: the scene's, else gaussian).
    #[arg(long, value_enum)]
    pub filter: Option<FilterKind>,
    /// How samples reach pixels: importance-sample the filter (one pixel
    /// per sample) or splat each sample into every pixel under the filter
    /// (as Mitsuba; not with --transport cv). Default: the scene's
    /// `[render] film`, else splat (sample with --transport cv).
    #[arg(long, value_enum)]
    pub film: Option<FilmKind>,
    /// Where path decisions' numbers come from: independent random
    /// streams or Owen-scrambled Sobol points (stratified over a pixel's
    /// passes). Default: the scene's `[render] sampler`, else sobol
    /// (independent with --transport cv).
    #[arg(long, value_enum)]
    pub sampler: Option<SamplerChoice>,
    /// Seed of every random stream (same seed, same image).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Camera rays do not see emitters (the environment, emissive
    /// surfaces), which still light the scene (Mitsuba's `hide_emitters`;
    /// default: the scene's `[render] hide_emitters`, else off).
    #[arg(long)]
    pub hide_emitters: bool,
    /// Render only the window X,Y,W,H of the film: W × H pixels from
    /// column X, row Y (0,0 is the top-left), as Mitsuba's crop_offset_x,
    /// crop_offset_y, crop_width, crop_height. The outputs are W × H; each
    /// pixel equals the full render's at the same seed bit for bit (with
    /// --transport cv the pooled α pools the window only; use
    /// --cv-alpha-per-pixel for exact crops).
    #[arg(long, value_name = "X,Y,W,H", value_parser = parse_window)]
    pub crop: Option<PixelWindow>,
    /// Render only passes A..B (A included, B not) of the seeded sequence
    /// instead of --spp passes from 0: parts of one frame rendered apart
    /// (e.g. by a job array) merge exactly with `fspec merge` when written
    /// as partial films (`--out part.fspart`).
    #[arg(long, value_name = "A..B", value_parser = parse_passes, conflicts_with = "spp")]
    pub passes: Option<std::ops::Range<u32>>,
    /// Continue the render of this partial film (.fspart, written by an
    /// earlier `--out part.fspart` that was stopped by --time-limit or
    /// Ctrl-C) from its last pass up to --passes, or else to the passes it
    /// was asked for; the scene and settings must be the same. The result
    /// equals the uninterrupted render bit for bit.
    #[arg(long, value_name = "PART.fspart", conflicts_with = "spp")]
    pub resume: Option<PathBuf>,
    /// Worker threads (default: all cores; the image does not depend on it).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Stop after the batch of passes during which this many seconds have passed (batches last up to half a second and are sized not to run past the limit).
    #[arg(long)]
    pub time_limit: Option<f64>,
    /// Output files; the format follows the extension (.png: 8-bit sRGB,
    /// .exr: float linear sRGB, .fspart: the film's sums for `fspec merge`
    /// and --resume). May be given several times.
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
    /// What the channels measure: a CIE standard observer (cie1931-2, the
    /// default, or cie1964-10); overrides the scene file's.
    #[arg(long, value_name = "NAME", conflicts_with = "sensor")]
    pub observer: Option<String>,
    /// A camera sensor instead: a CSV of three or more response curves and
    /// an optional matrix to XYZ (layout in docs/scene-format.md).
    #[arg(long, value_name = "FILE.csv")]
    pub sensor: Option<PathBuf>,
    /// Do not print progress (a one-line summary only).
    #[arg(long, short)]
    pub quiet: bool,
    /// Check the tree and the other structures the scene's build derives
    /// against the input before rendering (always done by debug builds;
    /// a release build skips these re-derivations, about a sixth of
    /// loading a large mesh, unless asked).
    #[arg(long)]
    pub validate: bool,
}

/// `X,Y,W,H` as a [`PixelWindow`] (whether it fits the film is checked
/// once the film's size is known).
fn parse_window(text: &str) -> Result<PixelWindow, String> {
    let numbers: Vec<&str> = text.split(',').map(str::trim).collect();
    let [x, y, width, height] = numbers.as_slice() else {
        return Err(format!(
            "{text}: expected four whole numbers X,Y,W,H (offset and size in pixels)"
        ));
    };
    let number = |part: &str| {
        part.parse::<u32>()
            .map_err(|_| format!("{text}: {part} is not a whole number of pixels"))
    };
    Ok(PixelWindow {
        x: number(x)?,
        y: number(y)?,
        width: number(width)?,
        height: number(height)?,
    })
}

/// `A..B` as the pass range `A .. B` (non-empty).
fn parse_passes(text: &str) -> Result<std::ops::Range<u32>, String> {
    let Some((start, end)) = text.split_once("..") else {
        return Err(format!(
            "{text}: expected A..B, passes A to B - 1 (e.g. 0..256)"
        ));
    };
    let number = |part: &str| {
        part.trim()
            .parse::<u32>()
            .map_err(|_| format!("{text}: {part} is not a whole number of passes"))
    };
    let (start, end) = (number(start)?, number(end)?);
    if start >= end {
        return Err(format!("{text}: the range is empty (A must be below B)"));
    }
    Ok(start..end)
}

impl RenderArgs {
    /// N as given (`--coeffs`, else the scene's, which [`render`] fills
    /// in), or [`UNRESOLVED_COEFFS`] while it is `auto`: [`render`]
    /// resolves `auto` from the scene before it builds the transport.
    pub fn coeff_count(&self) -> usize {
        match self.coeffs {
            Some(CoeffsChoice::Fixed(n)) => n,
            Some(CoeffsChoice::Auto) | None => UNRESOLVED_COEFFS,
        }
    }
}

/// The built-in scene that `--illuminant` lights.
const COLORCHECKER: &str = "colorchecker";

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
    /// The memory predicted before the render started.
    pub memory: MemoryPrediction,
}

/// The render settings of `args` over a scene's `defaults` (flags win).
pub fn settings_from(
    args: &RenderArgs,
    defaults: &SceneDefaults,
) -> Result<RenderSettings, CliError> {
    let width = args.width.or(defaults.render.width).unwrap_or(512);
    let height = args.height.or(defaults.render.height).unwrap_or(512);
    let spp = args.spp.or(defaults.render.spp).unwrap_or(64);
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
    let max_depth = match args.max_depth.or(defaults.render.max_depth.map(i64::from)) {
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
    // The flag wins over the scene's crop window (Mitsuba's film crop).
    let scene_crop = defaults.render.crop.map(PixelWindow::from);
    let window = match args.crop {
        Some(window) => Some(
            window
                .validate(width, height)
                .map_err(|e| CliError::input(format!("--crop: {e}")))?,
        ),
        None => scene_crop
            .map(|window| window.validate(width, height))
            .transpose()
            .map_err(|e| CliError::input(format!("the scene's crop window: {e}")))?,
    };
    Ok(RenderSettings {
        width,
        height,
        spp,
        integrator: IntegratorSettings {
            max_depth,
            rr_depth: args
                .rr_depth
                .or(defaults.render.rr_depth)
                .unwrap_or(DEFAULT_RR_DEPTH),
            hide_emitters: args.hide_emitters || defaults.render.hide_emitters.unwrap_or(false),
        },
        seed: args.seed.or(defaults.render.seed).unwrap_or(0),
        filter: match (args.filter, defaults.render.filter) {
            (Some(kind), _) => filter_of(FilterChoice::from(kind))?,
            (None, Some(choice)) => filter_of(choice)?,
            (None, None) => Filter::gaussian(),
        },
        threads: args.threads,
        time_limit,
        window,
        film: args
            .film
            .map(FilmMode::from)
            .or(defaults.render.film)
            .unwrap_or(default_film(args.transport_kind())),
        sampler: args
            .sampler
            .map(SamplerKind::from)
            .or(defaults.render.sampler)
            .unwrap_or(default_sampler(args.transport_kind())),
    })
    .and_then(|settings| {
        if settings.film == FilmMode::Sample && settings.filter.has_negative_lobes() {
            Err(CliError::input(
                "the filter has negative lobes, which cannot be drawn as sample offsets: render it with --film splat (the default but with control variates)",
            ))
        } else {
            Ok(settings)
        }
    })
}

/// The sampler when neither `--sampler` nor the scene names one: Sobol,
/// the less colour error at equal CPU time (docs/results.md, "Sobol
/// sampler"); control variates keep independent passes, because their
/// running `α` is unbiased only when a pass is independent of the passes
/// it was estimated from, which a pixel's scrambled Sobol points are not.
pub fn default_sampler(transport: TransportKind) -> SamplerKind {
    match transport {
        TransportKind::Cv => SamplerKind::Independent,
        TransportKind::Fourier | TransportKind::Sampled | TransportKind::Hybrid => {
            SamplerKind::Sobol
        }
    }
}

/// The film when neither `--film` nor the scene names one: splatting, the
/// less colour error at equal CPU time against Mitsuba on its Cornell box
/// and the laser box (`fspec experiment equal-time`, docs/results.md);
/// control variates cannot splat (their pixels are no weighted sums) and
/// keep importance sampling of the filter.
pub fn default_film(transport: TransportKind) -> FilmMode {
    match transport {
        TransportKind::Cv => FilmMode::Sample,
        TransportKind::Fourier | TransportKind::Sampled | TransportKind::Hybrid => FilmMode::Splat,
    }
}

/// Russian-roulette depth when neither the flag nor the scene gives one.
const DEFAULT_RR_DEPTH: u32 = 5;

/// The filter a scene file names (Mitsuba's Gaussian of σ 0.5 px is our
/// tabulated default, bit for bit).
pub fn filter_of(choice: FilterChoice) -> Result<Filter, CliError> {
    match choice {
        FilterChoice::Box => Ok(Filter::Box),
        FilterChoice::Tent { radius_px } => Filter::tent(radius_px),
        FilterChoice::Gaussian { stddev_px } if stddev_px == GAUSSIAN_SIGMA_PX => {
            Ok(Filter::gaussian())
        }
        FilterChoice::Gaussian { stddev_px } => Filter::gaussian_with_stddev(stddev_px),
        FilterChoice::Cubic { b, c } => Filter::cubic(b, c),
        FilterChoice::Lanczos { lobes } => Filter::lanczos(lobes),
    }
    .map_err(|e| CliError::input(format!("the scene's filter: {e}")))
}

/// Bytes of one `f32` sample in the image buffers and the EXR writers.
const F32_BYTES: u64 = size_of::<f32>() as u64;

/// Bytes per pixel of the 8-bit RGB buffer of the PNG writer.
const PNG_BYTES_PER_PIXEL: u64 = 3;

/// Copies of the PNG bytes alive while it is encoded: the sRGB bytes, the
/// `png` crate's filtered rows, and its compressed stream (at most the size
/// of the input for image data).
const PNG_COPIES: u64 = 3;

/// Scan lines per block of the EXR outputs (ZIP16 compression).
const EXR_ROWS_PER_BLOCK: u64 = 16;

/// Blocks the `exr` crate keeps per compressor thread: the one being
/// compressed and one compressed block waiting to be written in order (it
/// compresses on `threads + 2` blocks at a time, `threads` = the cores).
const EXR_BLOCKS_PER_THREAD: u64 = 2;

/// Extra compressor threads of the `exr` crate beyond the cores.
const EXR_EXTRA_THREADS: u64 = 2;

/// Copies of a block's bytes while it is in flight: the uncompressed
/// block, the compressor's working buffer, the compressed output.
const EXR_BLOCK_COPIES: u64 = 3;

/// Channels of an EXR output: R, G, B, and X, Y, Z with `--exr-xyz`.
const EXR_RGB_CHANNELS: u64 = 3;

/// Resident memory of the process before it allocates anything for the
/// render: code, libraries, thread stacks, allocator arenas. Measured at
/// 8 MiB (maximum resident set of a release `fspec render` of 8 × 8 pixels
/// with 1, 2 and 16 threads), doubled for margin.
pub const PROCESS_BASELINE_BYTES: u64 = 16 << 20;

/// The peak memory of a render, predicted before it starts (bytes, by
/// phase). The render holds the scene throughout; the film accumulators,
/// the resolved XYZ image and the coefficient planes (made only for spectral
/// outputs) coexist at the end of the render; the film is then freed and the
/// outputs are written one at a time from the resolved image. The splat
/// rings are counted with the film, an upper bound: they are freed before
/// the resolve. Loading the scene happens before and is
/// bounded by the loaders' own limits (texture size, file size).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MemoryPrediction {
    /// The process itself ([`PROCESS_BASELINE_BYTES`]).
    pub process_bytes: u64,
    /// The built scene ([`Scene::memory_bytes`]).
    pub scene_bytes: u64,
    /// Film accumulators (one transport pixel per image pixel), the
    /// transport's own tables, the XYZ image and the coefficient planes.
    pub render_bytes: u64,
    /// The XYZ image and coefficient planes plus the buffers of the largest
    /// output writer (PNG, EXR, spectral EXR, coefficient EXR).
    pub output_bytes: u64,
}

impl MemoryPrediction {
    /// The predicted peak of the render's own data: the scene plus the
    /// larger phase.
    pub fn data_bytes(&self) -> u64 {
        self.scene_bytes
            .saturating_add(self.render_bytes.max(self.output_bytes))
    }

    /// The predicted peak resident memory of the process: its baseline plus
    /// [`MemoryPrediction::data_bytes`].
    pub fn peak_bytes(&self) -> u64 {
        self.process_bytes.saturating_add(self.data_bytes())
    }
}

/// `bytes` for people: MiB below a GiB, else GiB.
pub fn format_bytes(bytes: u64) -> String {
    const MIB: f64 = (1u64 << 20) as f64;
    const GIB: f64 = (1u64 << 30) as f64;
    let b = bytes as f64;
    if b < GIB {
        format!("{:.1} MiB", b / MIB)
    } else {
        format!("{:.1} GiB", b / GIB)
    }
}

/// The wavelengths of the spectral EXR: `min, min + step, …` up to the end
/// of `range`.
fn spectral_wavelengths(range: &SpectralRange, step_nm: f64) -> Vec<f64> {
    let steps = (range.width_nm() / step_nm).floor() as usize;
    (0..=steps)
        .map(|i| range.min_nm() + i as f64 * step_nm)
        .collect()
}

/// Predicts the peak memory of rendering `settings` with `args` into
/// `output`, for a transport whose pixel takes `film_pixel_bytes` and whose
/// tables take `transport_bytes`, over a scene of `scene_bytes` with
/// `spectral_wavelengths` channels in the spectral EXR.
pub fn predict_memory(
    args: &RenderArgs,
    settings: &RenderSettings,
    output: &OutputOptions,
    film_pixel_bytes: u64,
    transport_bytes: u64,
    scene_bytes: u64,
    spectral_wavelengths: u64,
) -> MemoryPrediction {
    let window = settings.film_window();
    let pixels = window.pixel_count();
    let per_pixel = |bytes: u64| pixels.saturating_mul(bytes);
    let xyz = per_pixel(size_of::<Xyz>() as u64);
    let coefficients = args.coeff_count() as u64;
    let spectral_buffer =
        args.transport_kind() == TransportKind::Fourier && args.buffer == BufferKind::Spectral;
    // Resolved only when something reads them (`PassJob::xyz_only`).
    let planes = if spectral_buffer && output.reads_coefficients() {
        per_pixel(coefficients * F32_BYTES)
    } else {
        0
    };
    let resolved = xyz.saturating_add(planes);
    let render_bytes = per_pixel(film_pixel_bytes)
        .saturating_add(transport_bytes)
        .saturating_add(resolved);
    let exr_channels = if args.exr_xyz {
        2 * EXR_RGB_CHANNELS
    } else {
        EXR_RGB_CHANNELS
    };
    // The `exr` crate compresses blocks of scan lines on one thread per
    // core: the channel planes plus the blocks in flight.
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get() as u64);
    let rows_in_flight = ((cores + EXR_EXTRA_THREADS) * EXR_BLOCKS_PER_THREAD * EXR_ROWS_PER_BLOCK)
        .min(u64::from(window.height));
    let pixels_in_flight = rows_in_flight * u64::from(window.width);
    let exr = |channels: u64| {
        let bytes_per_pixel = channels * F32_BYTES;
        per_pixel(bytes_per_pixel)
            .saturating_add(pixels_in_flight.saturating_mul(bytes_per_pixel * EXR_BLOCK_COPIES))
    };
    let mut writer = 0;
    for path in &output.outputs {
        let bytes = match output_format(path) {
            Some(OutputFormat::Png) => per_pixel(PNG_BYTES_PER_PIXEL * PNG_COPIES),
            Some(OutputFormat::Exr) => exr(exr_channels),
            // The film's state, kept beside the film and written as it is.
            Some(OutputFormat::Partial) | None => 0,
        };
        writer = writer.max(bytes);
    }
    if spectral_buffer {
        if output.coefficients_exr.is_some() {
            writer = writer.max(exr(coefficients));
        }
        if output.spectral_exr.is_some() {
            // The radiance at every wavelength, then its channel planes.
            let radiance = per_pixel(spectral_wavelengths * F32_BYTES);
            writer =
                writer.max(radiance.saturating_add(exr(spectral_wavelengths + EXR_RGB_CHANNELS)));
        }
    }
    MemoryPrediction {
        process_bytes: PROCESS_BASELINE_BYTES,
        scene_bytes,
        render_bytes,
        output_bytes: resolved.saturating_add(writer),
    }
}

/// Physical memory from /proc/meminfo (Linux), if known.
fn physical_memory_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Memory limit where the physical memory is unknown, bytes.
const UNKNOWN_MEMORY_LIMIT_BYTES: u64 = 8 << 30;

/// The memory a render may use: half of the physical memory, or 8 GiB where
/// that is unknown.
pub fn memory_limit_bytes() -> u64 {
    physical_memory_bytes().map_or(UNKNOWN_MEMORY_LIMIT_BYTES, |m| m / 2)
}

/// Refuses a render whose predicted peak exceeds `limit_bytes`.
pub fn check_memory(
    prediction: &MemoryPrediction,
    settings: &RenderSettings,
    limit_bytes: u64,
) -> Result<(), CliError> {
    let peak = prediction.peak_bytes();
    if peak > limit_bytes {
        let window = settings.film_window();
        return Err(CliError::input(format!(
            "{}×{} pixels would need about {} at the peak (film {}, outputs {}, scene {}; limit {}, half the memory): use a smaller image or fewer outputs",
            window.width,
            window.height,
            format_bytes(peak),
            format_bytes(prediction.render_bytes),
            format_bytes(prediction.output_bytes),
            format_bytes(prediction.scene_bytes),
            format_bytes(limit_bytes)
        )));
    }
    Ok(())
}

struct Reporter<'a> {
    bar: Option<ProgressBar>,
    observer: &'a dyn RenderObserver,
}

impl<'a> Reporter<'a> {
    fn new(total: u32, quiet: bool, observer: &'a dyn RenderObserver) -> Self {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = ProgressBar::new(u64::from(total));
            let style =
                ProgressStyle::with_template("{bar:40} {pos}/{len} passes  {msg}  ETA {eta}")
                    .unwrap_or_else(|_| ProgressStyle::default_bar());
            bar.set_style(style);
            bar
        });
        Self { bar, observer }
    }

    fn update(&self, p: &Progress) -> bool {
        if let Some(bar) = &self.bar {
            bar.set_position(u64::from(p.passes_done));
            let rate = p.samples as f64 / p.elapsed.as_secs_f64().max(1e-9);
            bar.set_message(format!("{:.2} M samples/s", rate / 1e6));
        }
        self.observer.keep_going()
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

/// Checked before the film is allocated: from the bytes of one film pixel
/// and of the transport, the memory prediction (or the refusal).
type Preflight<'a> = &'a dyn Fn(u64, u64) -> Result<MemoryPrediction, CliError>;

/// A transport and its sizes, as chosen on the command line and recorded
/// in partial films (only what the transport reads: a Fourier render's
/// wavelength options are not part of it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum TransportSpec {
    /// N Fourier coefficients per path.
    Fourier {
        /// N.
        coeffs: usize,
        /// Where samples become colour.
        buffer: BufferKind,
        /// How coefficients become colour.
        to_color: ToColor,
    },
    /// C sampled wavelengths per path.
    Sampled {
        /// C.
        wavelengths: usize,
        /// How the wavelengths are drawn.
        sampling: Sampling,
    },
    /// Sampled wavelengths with the Fourier estimate as a control variate.
    Cv {
        /// C.
        wavelengths: usize,
        /// N.
        coeffs: usize,
        /// How the wavelengths are drawn.
        sampling: Sampling,
        /// `α` per pixel instead of pooled.
        alpha_per_pixel: bool,
    },
    /// Fourier coefficients until dispersion, sampled wavelengths after.
    Hybrid {
        /// N.
        coeffs: usize,
        /// C, drawn at the split.
        wavelengths: usize,
        /// How the wavelengths are drawn.
        sampling: Sampling,
        /// Where the Fourier part becomes colour.
        buffer: BufferKind,
        /// How the Fourier part's coefficients become colour.
        to_color: ToColor,
        /// What a split path does where its direction depends on
        /// wavelength (absent from older partial films: hero).
        #[serde(default)]
        paths: DispersionPaths,
        /// Where its caustics come from (absent from older partial films:
        /// camera).
        #[serde(default)]
        caustics: Caustics,
    },
}

impl TransportSpec {
    /// How its sampled wavelengths are drawn (none for Fourier).
    pub fn sampling(&self) -> Option<Sampling> {
        match *self {
            Self::Fourier { .. } => None,
            Self::Sampled { sampling, .. }
            | Self::Cv { sampling, .. }
            | Self::Hybrid { sampling, .. } => Some(sampling),
        }
    }

    /// The lights density of `scene` where this transport draws from it
    /// (`--sampling lights`), for [`TransportBasis::density`].
    pub fn lights_density(
        &self,
        scene: &Scene,
        observer: &Observer,
    ) -> Result<Option<Arc<EmissionDensity>>, CliError> {
        if self.sampling() != Some(Sampling::Lights) {
            return Ok(None);
        }
        emission_density(scene, observer)
            .map(|density| Some(Arc::new(density)))
            .map_err(CliError::input)
    }

    /// Whether its film keeps Fourier coefficients per pixel (a Fourier
    /// transport with a spectral buffer): spectral and coefficient EXR
    /// outputs need them.
    pub fn keeps_coefficients(&self) -> bool {
        matches!(
            self,
            Self::Fourier {
                buffer: BufferKind::Spectral,
                ..
            }
        )
    }

    /// The transport `args` ask for (default wavelength counts filled in).
    pub fn of(args: &RenderArgs) -> Self {
        match args.transport_kind() {
            TransportKind::Fourier => Self::Fourier {
                coeffs: args.coeff_count(),
                buffer: args.buffer,
                to_color: args.to_color,
            },
            TransportKind::Sampled => Self::Sampled {
                wavelengths: args.wavelengths.unwrap_or(4),
                sampling: args.sampling.unwrap_or(Sampling::Hero),
            },
            TransportKind::Cv => Self::Cv {
                wavelengths: args.wavelengths.unwrap_or(8),
                coeffs: args.coeff_count(),
                sampling: args.sampling.unwrap_or(Sampling::Hero),
                alpha_per_pixel: args.cv_alpha_per_pixel,
            },
            TransportKind::Hybrid => Self::Hybrid {
                coeffs: args.coeff_count(),
                wavelengths: args.wavelengths.unwrap_or(HYBRID_WAVELENGTHS),
                sampling: args.sampling.unwrap_or(HYBRID_SAMPLING),
                buffer: args.buffer,
                to_color: args.to_color,
                paths: args.dispersion_paths.unwrap_or(HYBRID_DISPERSION_PATHS),
                caustics: args.caustics.unwrap_or(HYBRID_CAUSTICS),
            },
        }
    }
}

impl TransportSpec {
    /// The transport that renders this one on `scene`, and the line that
    /// says so when it is another. Where no material disperses no hybrid
    /// path ever splits, and the hybrid transport's image is the Fourier
    /// transport's bit for bit (`simd-tracer/tests/hybrid.rs`), but every
    /// value still carries the `C` sampled values beside the coefficients
    /// (14 % more time on the Cornell box, `docs/performance.md`): such a
    /// render runs as the Fourier transport with the hybrid's `N`, buffer
    /// and route. Not for partial films (`splitting`): their identity and
    /// pixel state record the transport, so every part of a hybrid frame
    /// stays hybrid, and only compiled hybrid sizes are replaced (others
    /// are refused by [`with_transport`] as before).
    fn for_scene(self, scene: &Scene, splitting: bool) -> (Self, Option<String>) {
        match self {
            Self::Hybrid {
                coeffs,
                wavelengths,
                buffer,
                to_color,
                ..
            } if !splitting
                && HYBRID_SIZES.contains(&(coeffs, wavelengths))
                && !scene.materials().iter().any(|m| m.bsdf.disperses()) =>
            {
                (
                    Self::Fourier {
                        coeffs,
                        buffer,
                        to_color,
                    },
                    Some(format!(
                        "hybrid: no material of the scene disperses, so no path leaves its Fourier coefficients: rendered by the Fourier transport (N = {coeffs}), the same image without the sampled part's cost"
                    )),
                )
            }
            spec => (spec, None),
        }
    }
}

/// The `(N, C)` the hybrid transport is compiled for ([`with_transport`]).
/// With the default `C` ([`HYBRID_WAVELENGTHS`]) every N of
/// `--coeffs auto` from 12 up, so that a hybrid path carries the N the
/// Fourier transport would choose for the scene; the other C at N = 12,
/// where they were measured (docs/results.md, "Hybrid transport").
const HYBRID_SIZES: [(usize, usize); 6] = [(12, 1), (12, 4), (12, 8), (16, 4), (24, 4), (32, 4)];

/// The smallest N the hybrid transport is compiled for (`--coeffs auto`
/// choosing 4 or 8 gives the hybrid 12).
const HYBRID_MIN_COEFFS: usize = 12;

/// How a hybrid path draws its wavelengths at its split when `--sampling`
/// is not given: from the scene's lamps, where the sampled continuation's
/// light comes from (`simd_tracer::transport::emission_density`; measured
/// in docs/results.md, "Hybrid transport").
pub const HYBRID_SAMPLING: Sampling = Sampling::Lights;

/// What the hybrid does where a direction depends on wavelength unless
/// `--dispersion-paths` says otherwise (`docs/results.md`, "Every
/// wavelength of a split on its own path").
pub const HYBRID_DISPERSION_PATHS: DispersionPaths = DispersionPaths::Hero;

/// Where the hybrid's caustics come from unless `--caustics` says
/// otherwise: light paths, which find a lamp behind glass where camera
/// paths only stumble on it (`docs/results.md`, "Light paths for the
/// caustics").
pub const HYBRID_CAUSTICS: Caustics = Caustics::LightPaths;

/// Wavelengths drawn where a hybrid path meets dispersion when
/// `--wavelengths` is not given: 4, measured against 1 and 8 on the
/// `prism` scene (docs/results.md, "Hybrid transport").
pub const HYBRID_WAVELENGTHS: usize = 4;

impl RenderArgs {
    /// The transport asked for (`--transport`, else Fourier; a scene's
    /// `[render] transport` is filled in by [`render`]).
    pub fn transport_kind(&self) -> TransportKind {
        self.transport.unwrap_or(TransportKind::Fourier)
    }
}

/// `args` with the scene's transport and wavelength sampling where
/// `--transport` and `--sampling` are not given (`None` when neither
/// applies).
fn with_scene_transport(args: &RenderArgs, defaults: &SceneDefaults) -> Option<RenderArgs> {
    let kind = defaults
        .render
        .transport
        .as_deref()
        .filter(|_| args.transport.is_none())
        .and_then(|name| TransportKind::from_str(name, false).ok());
    let sampling = defaults
        .render
        .sampling
        .as_deref()
        .filter(|_| args.sampling.is_none())
        .and_then(|name| Sampling::from_str(name, false).ok());
    if kind.is_none() && sampling.is_none() {
        return None;
    }
    Some(RenderArgs {
        transport: kind.or(args.transport),
        sampling: sampling.or(args.sampling),
        ..args.clone()
    })
}

/// Work that needs the transport's concrete type (its sizes are const
/// generics): [`with_transport`] builds the transport and runs the task.
pub trait TransportTask {
    /// What the task gives.
    type Output;
    /// Runs with the built transport.
    fn run<T: Transport>(self, transport: &T) -> Result<Self::Output, CliError>;
}

/// The wavelength strategy of `--sampling`.
pub fn strategy(sampling: Sampling) -> WavelengthStrategy {
    match sampling {
        Sampling::Uniform => WavelengthStrategy::Uniform,
        Sampling::Stratified => WavelengthStrategy::Stratified,
        Sampling::Hero => WavelengthStrategy::Hero,
        // The lights density's own draws need the scene
        // ([`TransportBasis::density`], built where a render or a probe
        // starts); where nothing is traced (merging parts) the visible
        // density stands in.
        Sampling::Visible | Sampling::Lights => WavelengthStrategy::VisibleHero,
    }
}

/// The density the transport draws from: the scene's lights density for
/// `--sampling lights`, else none (the strategy).
fn density<'a>(sampling: Sampling, basis: &TransportBasis<'a>) -> Option<Arc<EmissionDensity>> {
    (sampling == Sampling::Lights)
        .then(|| basis.density.cloned())
        .flatten()
}

fn route(to_color: ToColor) -> XyzRoute {
    match to_color {
        ToColor::Series => XyzRoute::Series,
        ToColor::Lut => XyzRoute::Lut,
        ToColor::Zeroth => XyzRoute::Zeroth,
        ToColor::Mese => XyzRoute::Mese,
    }
}

fn range_error(e: spectral_core::SpectralError) -> CliError {
    CliError::input(format!("spectral range: {e}"))
}

/// What every transport is built from besides its sizes: the range and
/// the observer.
#[derive(Debug, Clone, Copy)]
pub struct TransportBasis<'a> {
    /// The scene's spectral range.
    pub range: SpectralRange,
    /// What the film's channels measure.
    pub observer: &'a Arc<Observer>,
    /// The scene's lights density (`--sampling lights`); `None` where
    /// nothing is traced (merging parts).
    pub density: Option<&'a Arc<EmissionDensity>>,
}

fn fourier<const N: usize, K: TransportTask>(
    basis: TransportBasis<'_>,
    buffer: BufferKind,
    to_color: ToColor,
    task: K,
) -> Result<K::Output, CliError> {
    let buffer = match buffer {
        BufferKind::Spectral => Buffer::Spectral,
        BufferKind::Rgb => Buffer::Xyz,
    };
    let transport =
        FourierTransport::<N>::with_observer(basis.range, buffer, route(to_color), basis.observer)
            .map_err(range_error)?;
    task.run(&transport)
}

fn sampled<const C: usize, K: TransportTask>(
    basis: TransportBasis<'_>,
    sampling: Sampling,
    task: K,
) -> Result<K::Output, CliError> {
    task.run(
        &SampledTransport::<C>::with_observer(
            basis.range,
            strategy(sampling),
            Arc::clone(basis.observer),
        )
        .with_density(density(sampling, &basis)),
    )
}

fn cv<const C: usize, const N: usize, K: TransportTask>(
    basis: TransportBasis<'_>,
    sampling: Sampling,
    alpha_per_pixel: bool,
    task: K,
) -> Result<K::Output, CliError> {
    if sampling == Sampling::Lights {
        return Err(CliError::input(
            "--sampling lights is not supported by the cv transport (its control variate draws by a fixed strategy): use hero, visible, stratified or uniform",
        ));
    }
    let alpha = if alpha_per_pixel {
        AlphaMode::PerPixel
    } else {
        AlphaMode::Shared
    };
    let transport = ControlVariateTransport::<C, N>::with_observer(
        basis.range,
        strategy(sampling),
        alpha,
        Arc::clone(basis.observer),
    )
    .map_err(range_error)?;
    task.run(&transport)
}

/// The hybrid's choices besides its sizes (`TransportSpec::Hybrid`).
#[derive(Debug, Clone, Copy)]
struct HybridChoices {
    sampling: Sampling,
    buffer: BufferKind,
    to_color: ToColor,
    paths: DispersionPaths,
    caustics: Caustics,
}

fn hybrid<const N: usize, const C: usize, K: TransportTask>(
    basis: TransportBasis<'_>,
    choices: HybridChoices,
    task: K,
) -> Result<K::Output, CliError> {
    let HybridChoices {
        sampling,
        buffer,
        to_color,
        paths,
        caustics,
    } = choices;
    let transport = HybridTransport::<N, C>::new(&HybridSettings {
        range: basis.range,
        buffer: match buffer {
            BufferKind::Spectral => Buffer::Spectral,
            BufferKind::Rgb => Buffer::Xyz,
        },
        route: route(to_color),
        strategy: strategy(sampling),
        observer: basis.observer,
        density: density(sampling, &basis).as_ref(),
        children: paths == DispersionPaths::All,
        light_paths: caustics == Caustics::LightPaths,
    })
    .map_err(range_error)?;
    task.run(&transport)
}

/// Builds the transport of `spec` over `basis.range`, seen by
/// `basis.observer`, and runs `task` with it; sizes that are not compiled
/// in are refused.
pub fn with_transport<K: TransportTask>(
    spec: &TransportSpec,
    basis: TransportBasis<'_>,
    task: K,
) -> Result<K::Output, CliError> {
    let unsupported = |what: &str, value: usize, supported: &str| {
        Err(CliError::input(format!(
            "{what} {value} is not supported (supported: {supported})"
        )))
    };
    match *spec {
        TransportSpec::Fourier {
            coeffs,
            buffer,
            to_color,
        } => match coeffs {
            4 => fourier::<4, K>(basis, buffer, to_color, task),
            8 => fourier::<8, K>(basis, buffer, to_color, task),
            12 => fourier::<12, K>(basis, buffer, to_color, task),
            16 => fourier::<16, K>(basis, buffer, to_color, task),
            24 => fourier::<24, K>(basis, buffer, to_color, task),
            32 => fourier::<32, K>(basis, buffer, to_color, task),
            n => unsupported("--coeffs", n, "4, 8, 12, 16, 24, 32"),
        },
        TransportSpec::Sampled {
            wavelengths,
            sampling,
        } => match wavelengths {
            1 => sampled::<1, K>(basis, sampling, task),
            2 => sampled::<2, K>(basis, sampling, task),
            4 => sampled::<4, K>(basis, sampling, task),
            8 => sampled::<8, K>(basis, sampling, task),
            12 => sampled::<12, K>(basis, sampling, task),
            16 => sampled::<16, K>(basis, sampling, task),
            32 => sampled::<32, K>(basis, sampling, task),
            c => unsupported("--wavelengths", c, "1, 2, 4, 8, 12, 16, 32"),
        },
        TransportSpec::Cv {
            wavelengths,
            coeffs,
            sampling,
            alpha_per_pixel,
        } => {
            let a = alpha_per_pixel;
            match (wavelengths, coeffs) {
                (4, 4) => cv::<4, 4, K>(basis, sampling, a, task),
                (4, 8) => cv::<4, 8, K>(basis, sampling, a, task),
                (4, 12) => cv::<4, 12, K>(basis, sampling, a, task),
                (8, 4) => cv::<8, 4, K>(basis, sampling, a, task),
                (8, 8) => cv::<8, 8, K>(basis, sampling, a, task),
                (8, 12) => cv::<8, 12, K>(basis, sampling, a, task),
                (12, 4) => cv::<12, 4, K>(basis, sampling, a, task),
                (12, 8) => cv::<12, 8, K>(basis, sampling, a, task),
                (12, 12) => cv::<12, 12, K>(basis, sampling, a, task),
                (c, n) => Err(CliError::input(format!(
                    "--transport cv with --wavelengths {c} --coeffs {n} is not supported (C and N in 4, 8, 12)"
                ))),
            }
        }
        TransportSpec::Hybrid {
            coeffs,
            wavelengths,
            sampling,
            buffer,
            to_color,
            paths,
            caustics,
        } => {
            let c = HybridChoices {
                sampling,
                buffer,
                to_color,
                paths,
                caustics,
            };
            match (coeffs, wavelengths) {
                (12, 1) => hybrid::<12, 1, K>(basis, c, task),
                (12, 4) => hybrid::<12, 4, K>(basis, c, task),
                (12, 8) => hybrid::<12, 8, K>(basis, c, task),
                (16, 4) => hybrid::<16, 4, K>(basis, c, task),
                (24, 4) => hybrid::<24, 4, K>(basis, c, task),
                (32, 4) => hybrid::<32, 4, K>(basis, c, task),
                (n, c) => Err(CliError::input(format!(
                    "--transport hybrid with --coeffs {n} --wavelengths {c} is not supported (N in 12, 16, 24, 32 with C = 4; N = 12 with C in 1, 4, 8)"
                ))),
            }
        }
    }
}

/// Copies of a pixel's state alive at once when a render keeps or resumes
/// one: the state read from the file and the state written at the end.
const STATE_COPIES: u64 = 2;

/// `fspec render`'s task: render the passes of `job`.
struct RenderTask<'a> {
    scene: &'a Scene,
    settings: &'a RenderSettings,
    quiet: bool,
    observer: &'a dyn RenderObserver,
    preflight: Preflight<'a>,
    job: PassJob<'a>,
    /// Why `--coeffs auto` chose its N, told once the render is sure to
    /// start (after every check that could refuse it).
    coefficient_note: Option<String>,
}

impl TransportTask for RenderTask<'_> {
    type Output = (RenderResult, Option<FilmState>, MemoryPrediction);

    fn run<T: Transport>(self, transport: &T) -> Result<Self::Output, CliError> {
        use simd_tracer::film::Film;
        let film_pixel = size_of::<simd_tracer::transport::FilmPixel<T>>() as u64;
        let state_pixel =
            transport.film().state_len().unwrap_or(0) as u64 * size_of::<f64>() as u64;
        let (resumes, keeps) = (self.job.resume.is_some(), self.job.keep_state);
        // A resumed render also holds the pixels loaded from the state.
        let pixel_bytes = film_pixel * (1 + u64::from(resumes))
            + if resumes || keeps {
                STATE_COPIES * state_pixel
            } else {
                0
            }
            + splat_ring_bytes(self.settings, film_pixel);
        let memory = (self.preflight)(pixel_bytes, size_of::<T>() as u64)?;
        if let Some(note) = self.coefficient_note {
            self.observer.notice(&RenderNotice::Note(note));
        }
        let reporter = Reporter::new(self.settings.spp, self.quiet, self.observer);
        let result = render_passes(transport, self.scene, self.settings, &self.job, &mut |p| {
            reporter.update(p)
        })
        .map_err(|e| CliError::input(e.to_string()));
        reporter.finish();
        let (result, state) = result?;
        Ok((result, state, memory))
    }
}

/// Bytes per window pixel of a splatting render's rings: each tile's
/// apron (the tile grown by the filter's margin `M` on every side) less the
/// tile, `((T + 2M)² − T²)/T²` film pixels per pixel (`T` =
/// [`TILE_SIZE`]), rounded up; 0 when sampling.
fn splat_ring_bytes(settings: &RenderSettings, film_pixel_bytes: u64) -> u64 {
    if settings.film != FilmMode::Splat {
        return 0;
    }
    let tile = u64::from(TILE_SIZE);
    let apron_side = tile + 2 * u64::from(settings.filter.splat_margin_px());
    (film_pixel_bytes * (apron_side * apron_side - tile * tile)).div_ceil(tile * tile)
}

/// `fspec merge`'s task: the image of a film state.
pub struct ResolveTask<'a> {
    /// The state to resolve.
    pub state: &'a FilmState,
}

impl TransportTask for ResolveTask<'_> {
    type Output = RenderResult;

    fn run<T: Transport>(self, transport: &T) -> Result<RenderResult, CliError> {
        resolve_state(transport, self.state).map_err(|e| CliError::input(e.to_string()))
    }
}

/// Image formats of `--out`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum OutputFormat {
    Png,
    Exr,
    Partial,
}

/// The format of an output path, by its extension (case-insensitive).
fn output_format(path: &Path) -> Option<OutputFormat> {
    let extension = path.extension()?.to_str()?.to_ascii_lowercase();
    match extension.as_str() {
        "png" => Some(OutputFormat::Png),
        "exr" => Some(OutputFormat::Exr),
        partial_file::EXTENSION => Some(OutputFormat::Partial),
        _ => None,
    }
}

/// Refuses an output that cannot be written: its folder is missing or it
/// names a folder. Checked before rendering, so that no render is lost to
/// a typo and no other output is written before the error.
fn check_writable(path: &Path) -> Result<(), CliError> {
    let parent = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    if !parent.is_dir() {
        return Err(CliError::input(format!(
            "cannot write {}: directory {} does not exist",
            path.display(),
            parent.display()
        )));
    }
    if path.is_dir() {
        return Err(CliError::input(format!(
            "cannot write {}: it is a directory",
            path.display()
        )));
    }
    Ok(())
}

impl From<ToneKind> for Tone {
    fn from(kind: ToneKind) -> Self {
        match kind {
            ToneKind::Clamp => Tone::Clamp,
            ToneKind::Reinhard => Tone::Reinhard,
        }
    }
}

/// The image outputs of a render or a merge and how they are made.
#[derive(Debug, Clone)]
pub struct OutputOptions {
    /// `--out` files (PNG, EXR, partial films).
    pub outputs: Vec<PathBuf>,
    /// X, Y, Z channels in EXR outputs too.
    pub exr_xyz: bool,
    /// The spectral EXR, if asked for.
    pub spectral_exr: Option<PathBuf>,
    /// Its wavelength step, nm.
    pub spectral_step_nm: f64,
    /// The coefficient EXR, if asked for.
    pub coefficients_exr: Option<PathBuf>,
    /// The caller reads the result's coefficient planes itself (Python's
    /// `coefficients=True`); otherwise they are made only for the spectral
    /// and coefficient EXRs.
    pub keep_coefficients: bool,
    /// PNG exposure.
    pub exposure: Exposure,
    /// PNG tone mapping.
    pub tone: Tone,
}

impl OutputOptions {
    /// The outputs of `fspec render` (`render.png` and `render.exr` when no
    /// `--out` is given).
    pub fn of(args: &RenderArgs) -> Self {
        Self {
            outputs: if args.out.is_empty() {
                vec![PathBuf::from("render.png"), PathBuf::from("render.exr")]
            } else {
                args.out.clone()
            },
            exr_xyz: args.exr_xyz,
            spectral_exr: args.spectral_exr.clone(),
            spectral_step_nm: args.spectral_step_nm,
            coefficients_exr: args.coefficients_exr.clone(),
            keep_coefficients: false,
            exposure: Exposure {
                stops: args.exposure,
            },
            tone: args.tone.into(),
        }
    }

    /// Whether anything reads the coefficient planes: a spectral or
    /// coefficient EXR, or the caller ([`OutputOptions::keep_coefficients`]).
    pub fn reads_coefficients(&self) -> bool {
        self.keep_coefficients || self.spectral_exr.is_some() || self.coefficients_exr.is_some()
    }

    /// Whether a partial film is among the outputs.
    pub fn keeps_state(&self) -> bool {
        self.outputs
            .iter()
            .any(|path| output_format(path) == Some(OutputFormat::Partial))
    }

    /// Checks the outputs before rendering (so a typo fails fast): known
    /// formats, writable paths, finite exposure, a positive wavelength
    /// step, and spectral outputs only where the film keeps coefficients
    /// (`spectral`).
    pub fn check(&self, spectral: bool) -> Result<(), CliError> {
        for path in &self.outputs {
            if output_format(path).is_none() {
                return Err(CliError::input(format!(
                    "{}: unsupported output format (use .png, .exr or .fspart)",
                    path.display()
                )));
            }
            check_writable(path)?;
        }
        for (option, path) in [
            ("--spectral-exr", &self.spectral_exr),
            ("--coefficients-exr", &self.coefficients_exr),
        ] {
            if let Some(path) = path {
                if output_format(path) != Some(OutputFormat::Exr) {
                    return Err(CliError::input(format!(
                        "{option} {}: must be an .exr file",
                        path.display()
                    )));
                }
                check_writable(path)?;
            }
        }
        if !self.exposure.stops.is_finite() {
            return Err(CliError::input(format!(
                "--exposure {}: must be a finite number of stops",
                self.exposure.stops
            )));
        }
        if (self.spectral_exr.is_some() || self.coefficients_exr.is_some()) && !spectral {
            return Err(CliError::input(
                "--spectral-exr and --coefficients-exr need --transport fourier with --buffer spectral",
            ));
        }
        if !(self.spectral_step_nm.is_finite() && self.spectral_step_nm > 0.0) {
            return Err(CliError::input(
                "--spectral-step-nm must be a positive number",
            ));
        }
        Ok(())
    }

    /// Writes the image outputs of `result` (partial films are written by
    /// their caller), returning the paths written.
    pub fn write_images(
        &self,
        result: &RenderResult,
        range: &SpectralRange,
    ) -> Result<Vec<PathBuf>, CliError> {
        let image = XyzImage {
            width: result.width,
            height: result.height,
            xyz: &result.xyz,
        };
        let mut written = Vec::new();
        for path in &self.outputs {
            if output_format(path) == Some(OutputFormat::Partial) {
                continue;
            }
            write_by_extension(path, &image, self.exposure, self.tone, self.exr_xyz)?;
            written.push(path.clone());
        }
        if let Some((n, coeffs)) = &result.coefficients {
            if let Some(path) = &self.coefficients_exr {
                let bounds = (range.min_nm(), range.max_nm());
                write_coefficients_exr(path, result.width, result.height, *n, coeffs, bounds)?;
                written.push(path.clone());
            }
            if let Some(path) = &self.spectral_exr {
                let wavelengths = spectral_wavelengths(range, self.spectral_step_nm);
                let radiance = spectral_planes(range, *n, coeffs, &wavelengths);
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
        Ok(written)
    }

    /// Writes `film` to every partial-film output, returning their paths.
    pub fn write_partials(&self, film: &PartialFilm) -> Result<Vec<PathBuf>, CliError> {
        let mut written = Vec::new();
        for path in &self.outputs {
            if output_format(path) == Some(OutputFormat::Partial) {
                film.write(path)?;
                written.push(path.clone());
            }
        }
        Ok(written)
    }
}

/// Spectral radiance at `wavelengths` from the coefficient planes (series,
/// negative lobes clamped to 0).
pub fn spectral_planes(
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

/// `name=value` of `-D`.
pub fn parse_define(text: &str) -> Result<(String, String), CliError> {
    match text.split_once('=') {
        Some((name, value))
            if !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') =>
        {
            Ok((name.to_string(), value.to_string()))
        }
        _ => Err(CliError::input(format!(
            "-D {text}: expected NAME=VALUE (NAME of letters, digits and _)"
        ))),
    }
}

/// The pass range, the state to resume and the frame identity of a render
/// (`--passes`, `--resume`, partial films).
struct Parts {
    job_first_pass: u32,
    spp: u32,
    resume: Option<PartialFilm>,
    /// Only for renders that read or write partial films: the scene's
    /// fingerprint reads every triangle (in scenes whose tree holds the
    /// only copy, one block read each), which a plain render need not pay.
    identity: Option<FrameIdentity>,
}

/// What a part is checked against: the frame `fspec render` is asked for.
fn frame_identity(
    args: &RenderArgs,
    settings: &RenderSettings,
    frame: PixelWindow,
    scene: &Scene,
) -> FrameIdentity {
    let range = scene.range();
    FrameIdentity {
        scene: args.scene.clone(),
        scene_fingerprint: format!("{:016x}", scene.fingerprint()),
        fspec_version: env!("CARGO_PKG_VERSION").to_string(),
        width: settings.width,
        height: settings.height,
        frame: partial_file::window_array(&frame),
        range_nm: [range.min_nm(), range.max_nm()],
        seed: settings.seed,
        max_depth: settings.integrator.max_depth,
        rr_depth: settings.integrator.rr_depth,
        hide_emitters: settings.integrator.hide_emitters,
        filter: filter_name(&settings.filter),
        film: settings.film.name().to_string(),
        transport: TransportSpec::of(args),
    }
}

/// A filter's kind and size (its radius: the Gaussian's is 4σ; a cubic's
/// parameters too).
fn filter_name(filter: &Filter) -> String {
    let kind = match filter {
        Filter::Box => "box".to_string(),
        Filter::Tent { .. } => "tent".to_string(),
        Filter::Gaussian(_) => "gaussian".to_string(),
        Filter::Cubic { b, c } => format!("cubic B {b} C {c}"),
        Filter::Lanczos { .. } => "lanczos".to_string(),
    };
    format!("{kind}, radius {} px", filter.radius_px())
}

/// The first field in which two frame identities differ, with both values.
pub fn identity_difference(a: &FrameIdentity, b: &FrameIdentity) -> Option<String> {
    let (Ok(serde_json::Value::Object(a)), Ok(serde_json::Value::Object(b))) =
        (serde_json::to_value(a), serde_json::to_value(b))
    else {
        return (a != b).then(|| "the settings".to_string());
    };
    // The scene's name is for messages: its fingerprint decides.
    a.iter()
        .filter(|(key, _)| key.as_str() != "scene")
        .find(|(key, value)| b.get(key.as_str()) != Some(value))
        .map(|(key, value)| {
            let other = b
                .get(key.as_str())
                .map_or("nothing".to_string(), ToString::to_string);
            format!("{key} ({value} against {other})")
        })
}

/// The pass range and the resumed part of a render, checked against the
/// frame.
fn plan_parts(
    args: &RenderArgs,
    settings: &RenderSettings,
    identity: Option<FrameIdentity>,
) -> Result<Parts, CliError> {
    let Some(path) = &args.resume else {
        let (first, spp) = match &args.passes {
            Some(passes) => (passes.start, passes.end - passes.start),
            None => (0, settings.spp),
        };
        return Ok(Parts {
            job_first_pass: first,
            spp,
            resume: None,
            identity,
        });
    };
    let part = PartialFilm::read(path)?;
    let difference = identity
        .as_ref()
        .and_then(|identity| identity_difference(&part.header.identity, identity));
    if let Some(difference) = difference {
        return Err(CliError::input(format!(
            "--resume {}: rendered with another {difference}",
            path.display()
        )));
    }
    let window = settings.film_window();
    if part.state.window != window {
        return Err(CliError::input(format!(
            "--resume {}: it holds the window {:?}, this render {:?} (give the same --crop)",
            path.display(),
            part.header.window,
            partial_file::window_array(&window)
        )));
    }
    let [requested_start, requested_end] = part.header.requested_passes;
    let passes = args
        .passes
        .clone()
        .unwrap_or(requested_start..requested_end);
    if passes.start != part.state.passes.start || passes.end < part.state.passes.end {
        return Err(CliError::input(format!(
            "--resume {}: it holds passes {}..{}, which do not start --passes {}..{}",
            path.display(),
            part.state.passes.start,
            part.state.passes.end,
            passes.start,
            passes.end
        )));
    }
    Ok(Parts {
        job_first_pass: passes.start,
        spp: passes.end - passes.start,
        resume: Some(part),
        identity,
    })
}

/// What a render tells its caller while it runs (`fspec render` prints
/// to stderr and stops on Ctrl-C; an embedding, such as the Python
/// package, collects the notices and checks its own interruptions).
pub trait RenderObserver {
    /// A warning or a note about the scene, one line.
    fn notice(&self, notice: &RenderNotice);
    /// Checked after every batch of passes: `false` stops the render there
    /// (the passes done so far are kept).
    fn keep_going(&self) -> bool;
}

/// A line a render reports before it starts.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RenderNotice {
    /// Something in the scene or the options was ignored or changed.
    Warning(String),
    /// A fact about the scene worth knowing (instances flattened).
    Note(String),
}

impl std::fmt::Display for RenderNotice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Warning(text) => write!(f, "warning: {text}"),
            Self::Note(text) => f.write_str(text),
        }
    }
}

/// `fspec render`'s observer: notices on stderr, Ctrl-C stops the render.
struct CommandLineObserver;

impl RenderObserver for CommandLineObserver {
    fn notice(&self, notice: &RenderNotice) {
        eprintln!("fspec: {notice}");
    }

    fn keep_going(&self) -> bool {
        !interrupted()
    }
}

/// A finished render, before any file is written.
#[derive(Debug)]
pub struct RenderedFrame {
    /// The image (XYZ per pixel) and, for a spectral buffer, the
    /// coefficient planes.
    pub result: RenderResult,
    /// The spectral range of the scene (and of the coefficients).
    pub range: SpectralRange,
    /// The film's sums, when `output` keeps a partial film.
    pub partial: Option<PartialFilm>,
    /// The memory predicted before the render started.
    pub memory: MemoryPrediction,
}

/// Runs `fspec render`.
pub fn run(args: &RenderArgs) -> Result<RenderSummary, CliError> {
    let output = OutputOptions::of(args);
    output.check(TransportSpec::of(args).keeps_coefficients())?;
    let frame = render(args, &output, &CommandLineObserver)?;
    let mut written = output.write_images(&frame.result, &frame.range)?;
    if let Some(film) = &frame.partial {
        written.extend(output.write_partials(film)?);
    }
    Ok(RenderSummary {
        passes: frame.result.passes,
        samples: frame.result.samples,
        rejected: frame.result.rejected,
        elapsed: frame.result.elapsed,
        written,
        interrupted: interrupted(),
        memory: frame.memory,
    })
}

/// Loads the scene of `args`, checks the settings, the outputs' memory and
/// the pass range, and renders: everything `fspec render` does but write
/// the files (the caller has checked `output`, which sizes the memory
/// prediction and says whether a partial film is kept).
pub fn render(
    args: &RenderArgs,
    output: &OutputOptions,
    observer: &dyn RenderObserver,
) -> Result<RenderedFrame, CliError> {
    let options = SceneOptions {
        illuminant: args
            .illuminant
            .as_deref()
            .map(crate::scene_source::illuminant_source)
            .transpose()?,
    };
    let mitsuba = MitsubaOptions {
        defines: args
            .define
            .iter()
            .map(|d| parse_define(d))
            .collect::<Result<_, _>>()?,
        lenient: args.lenient,
    };
    let (mut builder, defaults, mut warnings) = resolve_scene(&args.scene, &options, &mitsuba)?;
    let scene_args = with_scene_transport(args, &defaults);
    let args = scene_args.as_ref().unwrap_or(args);
    output.check(TransportSpec::of(args).keeps_coefficients())?;
    if (args.passes.is_some() || args.resume.is_some() || output.keeps_state())
        && args.transport_kind() == TransportKind::Cv
    {
        return Err(CliError::input(
            "--passes, --resume and .fspart outputs need --transport fourier, sampled or hybrid: control variates weight each pass by every earlier pass",
        ));
    }
    if args.illuminant.is_some() && args.scene != COLORCHECKER {
        warnings.push(format!(
            "--illuminant only applies to the {COLORCHECKER} scene: ignored for {}",
            args.scene
        ));
    }
    for warning in warnings {
        observer.notice(&RenderNotice::Warning(warning));
    }
    let mut settings = settings_from(args, &defaults)?;
    if settings.film == FilmMode::Splat && args.transport_kind() == TransportKind::Cv {
        return Err(CliError::input(
            "--film splat (or the scene's `film = \"splat\"`) needs --transport fourier, sampled or hybrid: control variates weight each pass by every earlier pass, so their pixels are no weighted sums to splat into",
        ));
    }
    if args.validate {
        builder.set_derived_checks(DerivedChecks::Full);
    }
    let scene = builder
        .build()
        .map_err(|e| CliError::input(format!("{}: {e}", args.scene)))?;
    if scene.skipped_triangles() > 0 {
        observer.notice(&RenderNotice::Warning(format!(
            "{} degenerate triangles skipped",
            scene.skipped_triangles()
        )));
    }
    if defaults.instances.copies > 0 {
        let (kept, meshes) = scene
            .instances()
            .map_or((0, 0), |i| (i.len(), i.meshes().len()));
        observer.notice(&RenderNotice::Note(format!(
            "{} instance(s) placing {} triangles: {} kept as instances of {} shared mesh(es), {} flattened into the scene's own {} triangles; the scene holds {:.1} MiB",
            defaults.instances.copies,
            defaults.instances.triangles,
            kept,
            meshes,
            defaults.instances.copies as usize - kept,
            scene.triangle_count(),
            scene.memory_bytes() as f64 / f64::from(1 << 20),
        )));
    }
    // The frame: the scene's crop window, or the whole film; a part's
    // --crop lies inside it.
    let frame = defaults
        .render
        .crop
        .map(PixelWindow::from)
        .unwrap_or_else(|| PixelWindow::full(settings.width, settings.height));
    let splitting = args.passes.is_some() || args.resume.is_some() || output.keeps_state();
    if splitting && !frame.covers(&settings.film_window()) {
        return Err(CliError::input(
            "--crop must lie inside the scene's crop window for --passes, --resume and .fspart outputs",
        ));
    }
    let observer_choice = observer_choice(args, &defaults)?;
    if splitting && !observer_choice.is_default() {
        return Err(CliError::input(format!(
            "{}: partial films (--passes, --resume, .fspart) record no observer yet: render with the default cie1931-2",
            observer_choice.describe()
        )));
    }
    let colour_observer = Arc::new(observer_choice.observer()?);
    let (resolved, coefficient_note) = resolve_coeffs(args, &defaults, &scene, &colour_observer)?;
    let args = &resolved;
    let identity = splitting.then(|| frame_identity(args, &settings, frame, &scene));
    let parts = plan_parts(args, &settings, identity)?;
    settings.spp = parts.spp;
    let wavelengths = spectral_wavelengths(&scene.range(), args.spectral_step_nm);
    let scene_bytes = scene.memory_bytes() as u64;
    let limit_bytes = memory_limit_bytes();
    let preflight = |film_pixel_bytes: u64, transport_bytes: u64| {
        let prediction = predict_memory(
            args,
            &settings,
            output,
            film_pixel_bytes,
            transport_bytes,
            scene_bytes,
            wavelengths.len() as u64,
        );
        check_memory(&prediction, &settings, limit_bytes)?;
        Ok(prediction)
    };
    let task = RenderTask {
        scene: &scene,
        settings: &settings,
        quiet: args.quiet,
        observer,
        preflight: &preflight,
        job: PassJob {
            first_pass: parts.job_first_pass,
            resume: parts.resume.as_ref().map(|part| &part.state),
            keep_state: output.keeps_state(),
            xyz_only: !output.reads_coefficients(),
        },
        coefficient_note,
    };
    let (spec, dispatch_note) = TransportSpec::of(args).for_scene(&scene, splitting);
    if let Some(note) = dispatch_note {
        observer.notice(&RenderNotice::Note(note));
    }
    let lights = spec.lights_density(&scene, &colour_observer)?;
    let basis = TransportBasis {
        range: scene.range(),
        observer: &colour_observer,
        density: lights.as_ref(),
    };
    let (result, state, memory) = with_transport(&spec, basis, task)?;
    let requested = [parts.job_first_pass, parts.job_first_pass + parts.spp];
    Ok(RenderedFrame {
        result,
        range: scene.range(),
        // Films keep their state only when splitting, which computed the
        // identity.
        partial: state
            .zip(parts.identity)
            .map(|(state, identity)| PartialFilm::new(identity, state, requested)),
        memory,
    })
}

/// `args` with N settled: `--coeffs`, else the scene's `[render] coeffs`,
/// else `auto`; `auto` on the Fourier transport is chosen from the scene's
/// spectra (`coefficient_choice`), with the line that says why, and on the
/// hybrid transport likewise (its Fourier part is the Fourier transport's,
/// so it carries the same N), raised to [`HYBRID_MIN_COEFFS`] and kept at
/// it for C other than [`HYBRID_WAVELENGTHS`] ([`HYBRID_SIZES`]); control
/// variates and sampled transports keep [`UNRESOLVED_COEFFS`].
fn resolve_coeffs(
    args: &RenderArgs,
    defaults: &SceneDefaults,
    scene: &Scene,
    observer: &Observer,
) -> Result<(RenderArgs, Option<String>), CliError> {
    let choice = args
        .coeffs
        .or(defaults.render.coeffs)
        .unwrap_or(CoeffsChoice::Auto);
    let (coeffs, note) = match (choice, args.transport_kind()) {
        (CoeffsChoice::Fixed(n), _) => (n, None),
        (CoeffsChoice::Auto, TransportKind::Fourier) => {
            let chosen = choose_for_scene(scene, observer)?;
            (chosen.coeffs, Some(chosen.describe()))
        }
        (CoeffsChoice::Auto, TransportKind::Hybrid) => {
            let chosen = choose_for_scene(scene, observer)?;
            let wavelengths = args.wavelengths.unwrap_or(HYBRID_WAVELENGTHS);
            let coeffs = if wavelengths == HYBRID_WAVELENGTHS {
                chosen.coeffs.max(HYBRID_MIN_COEFFS)
            } else {
                HYBRID_MIN_COEFFS
            };
            let note = if coeffs == chosen.coeffs {
                chosen.describe()
            } else {
                format!(
                    "{}; the hybrid transport with C = {wavelengths} takes N = {coeffs}",
                    chosen.describe()
                )
            };
            (coeffs, Some(note))
        }
        (CoeffsChoice::Auto, TransportKind::Cv | TransportKind::Sampled) => {
            (UNRESOLVED_COEFFS, None)
        }
    };
    let resolved = RenderArgs {
        coeffs: Some(CoeffsChoice::Fixed(coeffs)),
        ..args.clone()
    };
    Ok((resolved, note))
}

/// What the channels measure: `--observer` or `--sensor`, else the scene
/// file's `[render]` choice, else CIE 1931 2°.
fn observer_choice(
    args: &RenderArgs,
    defaults: &SceneDefaults,
) -> Result<ObserverChoice, CliError> {
    if let Some(name) = &args.observer {
        return ObserverChoice::standard(name);
    }
    if let Some(path) = &args.sensor {
        return load_sensor_csv(path).map(ObserverChoice::Sensor);
    }
    Ok(defaults.render.observer.clone().unwrap_or_default())
}

/// The final line: time, samples/s, rejected samples, predicted peak
/// memory, output paths.
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
        "rendered {} passes{stopped} in {seconds:.2} s ({:.2} M samples/s{rejected}); predicted peak memory {} (scene {}); wrote {}",
        summary.passes,
        summary.samples as f64 / seconds.max(1e-9) / 1e6,
        format_bytes(summary.memory.peak_bytes()),
        format_bytes(summary.memory.scene_bytes),
        files.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_file::RenderDefaults;
    use clap::Parser;

    #[derive(Parser)]
    struct Render {
        #[command(flatten)]
        args: RenderArgs,
    }

    fn args(argv: &[&str]) -> RenderArgs {
        let Ok(render) =
            Render::try_parse_from(std::iter::once("render").chain(argv.iter().copied()))
        else {
            panic!("{argv:?}");
        };
        render.args
    }

    /// Every hybrid size of [`HYBRID_SIZES`] is compiled in, and the sizes
    /// beside them are refused.
    #[test]
    fn the_hybrid_sizes_are_the_compiled_ones() {
        struct Build;
        impl TransportTask for Build {
            type Output = ();
            fn run<T: Transport>(self, _transport: &T) -> Result<(), CliError> {
                Ok(())
            }
        }
        let observer = Arc::new(Observer::default());
        let basis = TransportBasis {
            range: SpectralRange::VISIBLE,
            observer: &observer,
            density: None,
        };
        let spec = |coeffs, wavelengths| TransportSpec::Hybrid {
            coeffs,
            wavelengths,
            sampling: Sampling::Hero,
            buffer: BufferKind::Rgb,
            to_color: ToColor::Series,
            paths: DispersionPaths::All,
            caustics: Caustics::LightPaths,
        };
        for (coeffs, wavelengths) in HYBRID_SIZES {
            assert!(
                with_transport(&spec(coeffs, wavelengths), basis, Build).is_ok(),
                "N = {coeffs}, C = {wavelengths}"
            );
        }
        assert!(HYBRID_SIZES.contains(&(HYBRID_MIN_COEFFS, HYBRID_WAVELENGTHS)));
        for (coeffs, wavelengths) in [(8, 4), (16, 1), (32, 8), (12, 2), (48, 4)] {
            assert!(!HYBRID_SIZES.contains(&(coeffs, wavelengths)));
            assert!(with_transport(&spec(coeffs, wavelengths), basis, Build).is_err());
        }
    }

    /// A scene's `[render] transport` applies where `--transport` is not
    /// given, and every name it may hold is a transport of the command
    /// line (an unknown name would otherwise be ignored).
    #[test]
    fn the_scene_transport_fills_in_a_missing_flag() {
        let scene = SceneDefaults {
            render: RenderDefaults {
                transport: Some("hybrid".into()),
                ..RenderDefaults::default()
            },
            ..SceneDefaults::default()
        };
        let Some(filled) = with_scene_transport(&args(&[]), &scene) else {
            panic!("not filled in");
        };
        assert_eq!(filled.transport_kind(), TransportKind::Hybrid);
        assert!(matches!(
            TransportSpec::of(&filled),
            TransportSpec::Hybrid {
                coeffs: 12,
                wavelengths: HYBRID_WAVELENGTHS,
                ..
            }
        ));
        assert!(with_scene_transport(&args(&["--transport", "sampled"]), &scene).is_none());
        assert!(with_scene_transport(&args(&[]), &SceneDefaults::default()).is_none());
        for name in crate::scene_file::TRANSPORT_NAMES {
            assert!(TransportKind::from_str(name, false).is_ok(), "{name}");
        }
        assert_eq!(
            TransportKind::value_variants().len(),
            crate::scene_file::TRANSPORT_NAMES.len()
        );
    }

    /// A scene's `[render] sampling` applies where `--sampling` is not
    /// given, with the scene's transport or the flag's, and every name it
    /// may hold is a sampling of the command line.
    #[test]
    fn the_scene_sampling_fills_in_a_missing_flag() {
        let scene = SceneDefaults {
            render: RenderDefaults {
                sampling: Some("visible".into()),
                ..RenderDefaults::default()
            },
            ..SceneDefaults::default()
        };
        let Some(filled) = with_scene_transport(&args(&["--transport", "hybrid"]), &scene) else {
            panic!("not filled in");
        };
        assert_eq!(
            TransportSpec::of(&filled).sampling(),
            Some(Sampling::Visible)
        );
        assert_eq!(filled.transport_kind(), TransportKind::Hybrid);
        let flag = args(&["--transport", "sampled", "--sampling", "uniform"]);
        assert!(with_scene_transport(&flag, &scene).is_none());
        let both = SceneDefaults {
            render: RenderDefaults {
                transport: Some("sampled".into()),
                sampling: Some("lights".into()),
                ..RenderDefaults::default()
            },
            ..SceneDefaults::default()
        };
        let Some(filled) = with_scene_transport(&args(&[]), &both) else {
            panic!("not filled in");
        };
        assert_eq!(
            TransportSpec::of(&filled).sampling(),
            Some(Sampling::Lights)
        );
        for name in crate::scene_file::SAMPLING_NAMES {
            assert!(Sampling::from_str(name, false).is_ok(), "{name}");
        }
        assert_eq!(
            Sampling::value_variants().len(),
            crate::scene_file::SAMPLING_NAMES.len()
        );
    }
}
