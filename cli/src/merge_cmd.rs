//! `fspec merge`: partial films (`.fspart`) of one frame — rendered over
//! disjoint crop windows, disjoint pass ranges, or both, by separate
//! processes or machines — merged into its image and, optionally, into one
//! partial film.
//!
//! Parts merge when they were rendered from the same scene (its
//! fingerprint) with the same film, seed, depth, filter and transport
//! ([`FrameIdentity`]); every pixel of the frame must be covered by parts
//! whose pass ranges follow one another without overlap or gap, and every
//! pixel by the same range of passes. A pixel's sums are added in pass
//! order whatever the order of the files on the command line, so the merge
//! is deterministic; parts over disjoint windows merge bit for bit, parts
//! over pass ranges within the bound of `simd_tracer::render::FilmState`.
//!
//! How coverage is checked: the windows' edges cut the frame into
//! rectangular cells, inside which every pixel has the same parts; each
//! cell's parts, sorted by their first pass, must chain from the first
//! cell's first pass to its last.

use crate::error::CliError;
use crate::image_out::Exposure;
use crate::partial_file::{self, FrameIdentity, PartialFilm};
use crate::render_cmd::{
    OutputOptions, ResolveTask, ToneKind, TransportBasis, identity_difference, with_transport,
};
use simd_tracer::render::{FilmState, PixelWindow};
use spectral_core::SpectralRange;
use spectral_core::observer::Observer;
use std::ops::Range;
use std::path::PathBuf;
use std::sync::Arc;

/// Arguments of `fspec merge`.
#[derive(Debug, Clone, clap::Args)]
pub struct MergeArgs {
    /// Partial films of one frame (`fspec render … --out part.fspart`).
    #[arg(required = true, value_name = "PART.fspart")]
    pub parts: Vec<PathBuf>,
    /// Output files by extension: .png (8-bit sRGB), .exr (float linear
    /// sRGB), .fspart (the merged partial film, which merges and resumes
    /// like any part). May be given several times.
    #[arg(long = "out", short, required = true)]
    pub out: Vec<PathBuf>,
    /// Also write X, Y, Z channels into EXR outputs.
    #[arg(long)]
    pub exr_xyz: bool,
    /// Write a spectral OpenEXR (Fichet et al. 2021 layout; Fourier parts
    /// with a spectral buffer).
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
}

/// What a merge did.
#[derive(Debug, Clone, PartialEq)]
pub struct MergeSummary {
    /// Parts merged.
    pub parts: usize,
    /// The frame's window, pixels.
    pub frame: PixelWindow,
    /// The passes of every pixel.
    pub passes: Range<u32>,
    /// Files written.
    pub written: Vec<PathBuf>,
}

/// A part with the file it came from.
struct Part {
    path: PathBuf,
    film: PartialFilm,
}

/// The merged state of `parts` (module docs), or why they do not merge.
fn merge_states(parts: &[Part], frame: PixelWindow) -> Result<FilmState, CliError> {
    let name = |k: usize| parts[k].path.display().to_string();
    let mut xs = vec![frame.x, frame.x + frame.width];
    let mut ys = vec![frame.y, frame.y + frame.height];
    for part in parts {
        let w = part.film.state.window;
        xs.extend([w.x, w.x + w.width]);
        ys.extend([w.y, w.y + w.height]);
    }
    for edges in [&mut xs, &mut ys] {
        edges.sort_unstable();
        edges.dedup();
    }
    // Part indices in the order of their first pass (then of the files).
    let mut order: Vec<usize> = (0..parts.len()).collect();
    order.sort_by_key(|&k| parts[k].film.state.passes.start);
    let mut passes: Option<Range<u32>> = None;
    for rows in ys.windows(2) {
        for columns in xs.windows(2) {
            let cell = PixelWindow {
                x: columns[0],
                y: rows[0],
                width: columns[1] - columns[0],
                height: rows[1] - rows[0],
            };
            if !frame.covers(&cell) {
                continue;
            }
            let covering: Vec<usize> = order
                .iter()
                .copied()
                .filter(|&k| parts[k].film.state.window.covers(&cell))
                .collect();
            let at = format!(
                "pixels ({}, {}) to ({}, {})",
                cell.x,
                cell.y,
                cell.x + cell.width - 1,
                cell.y + cell.height - 1
            );
            let Some(&first) = covering.first() else {
                return Err(CliError::input(format!(
                    "no part holds {at}: a crop is missing"
                )));
            };
            let mut end = parts[first].film.state.passes.start;
            let start = end;
            let mut previous: Option<usize> = None;
            for &k in &covering {
                let range = &parts[k].film.state.passes;
                if range.start < end {
                    let other = previous.map_or_else(String::new, |p| format!(" and {}", name(p)));
                    return Err(CliError::input(format!(
                        "{}{other} overlap: both hold passes from {} of {at}",
                        name(k),
                        range.start
                    )));
                }
                if range.start > end {
                    return Err(CliError::input(format!(
                        "passes {end}..{} of {at} are in no part (a pass range is missing, or a part stopped early: continue it with fspec render --resume)",
                        range.start
                    )));
                }
                end = range.end;
                previous = Some(k);
            }
            match &passes {
                None => passes = Some(start..end),
                Some(frame_passes) if *frame_passes != (start..end) => {
                    return Err(CliError::input(format!(
                        "{at} hold passes {start}..{end}, other pixels {}..{}: every pixel needs the same passes",
                        frame_passes.start, frame_passes.end
                    )));
                }
                Some(_) => {}
            }
        }
    }
    let passes = passes.ok_or_else(|| CliError::input("the frame holds no pixel"))?;
    let values_per_pixel = parts[0].film.state.values_per_pixel;
    let mode = parts[0].film.state.mode;
    let mut merged = FilmState::empty(frame, passes.start, values_per_pixel, mode);
    merged.passes = passes;
    for &k in &order {
        let state = &parts[k].film.state;
        merged.rejected += state.rejected;
        let w = state.window;
        for row in 0..w.height {
            for column in 0..w.width {
                let source = state.pixel((row * w.width + column) as usize);
                let (x, y) = (w.x + column - frame.x, w.y + row - frame.y);
                let at = (y * frame.width + x) as usize * values_per_pixel;
                for (sum, &value) in merged.values[at..at + values_per_pixel]
                    .iter_mut()
                    .zip(source)
                {
                    *sum += value;
                }
            }
        }
    }
    Ok(merged)
}

/// Runs `fspec merge`.
pub fn run(args: &MergeArgs) -> Result<MergeSummary, CliError> {
    let output = OutputOptions {
        outputs: args.out.clone(),
        exr_xyz: args.exr_xyz,
        spectral_exr: args.spectral_exr.clone(),
        spectral_step_nm: args.spectral_step_nm,
        coefficients_exr: args.coefficients_exr.clone(),
        keep_coefficients: false,
        exposure: Exposure {
            stops: args.exposure,
        },
        tone: args.tone.into(),
    };
    let mut parts = Vec::with_capacity(args.parts.len());
    for path in &args.parts {
        parts.push(Part {
            path: path.clone(),
            film: PartialFilm::read(path)?,
        });
    }
    let Some(first) = parts.first() else {
        return Err(CliError::input("no part to merge"));
    };
    let identity: FrameIdentity = first.film.header.identity.clone();
    for part in &parts[1..] {
        if let Some(difference) = identity_difference(&identity, &part.film.header.identity) {
            return Err(CliError::input(format!(
                "{} and {} are not parts of one frame: they differ in {difference}",
                first.path.display(),
                part.path.display()
            )));
        }
    }
    output.check(identity.transport.keeps_coefficients())?;
    let frame = partial_file::array_window(identity.frame);
    let merged = merge_states(&parts, frame)?;
    let [min_nm, max_nm] = identity.range_nm;
    let range = SpectralRange::new(min_nm, max_nm)
        .map_err(|e| CliError::input(format!("spectral range: {e}")))?;
    // Partial films are rendered with the default observer (render_cmd
    // refuses another one for them).
    let basis = TransportBasis {
        range,
        observer: &Arc::new(Observer::default()),
        density: None,
    };
    let result = with_transport(&identity.transport, basis, ResolveTask { state: &merged })?;
    let mut written = output.write_images(&result, &range)?;
    let passes = merged.passes.clone();
    let film = PartialFilm::new(identity, merged, [passes.start, passes.end]);
    written.extend(output.write_partials(&film)?);
    Ok(MergeSummary {
        parts: parts.len(),
        frame,
        passes,
        written,
    })
}

/// The final line of `fspec merge`.
pub fn summary_line(summary: &MergeSummary) -> String {
    let files: Vec<String> = summary
        .written
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    format!(
        "merged {} parts: {}×{} pixels, passes {}..{}; wrote {}",
        summary.parts,
        summary.frame.width,
        summary.frame.height,
        summary.passes.start,
        summary.passes.end,
        files.join(", ")
    )
}
