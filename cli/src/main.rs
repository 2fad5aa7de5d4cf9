//! `fspec`: the command-line front end of the Fourier spectral renderer.

use clap::{Parser, Subcommand};
use fspec_cli::CliError;
use fspec_cli::experiment::{self, ExperimentArgs};
use fspec_cli::merge_cmd::{self, MergeArgs};
use fspec_cli::render_cmd::{self, RenderArgs};
use fspec_cli::spectrum_cmd::{self, SpectrumArgs};
use fspec_cli::texture_cmd::{self, TextureArgs};
use fspec_cli::train::{self, TrainArgs};
use fspec_cli::view::{self, ViewArgs};
use std::process::ExitCode;

/// Fourier-series spectral rendering: spectra as N cosine coefficients.
#[derive(Debug, Parser)]
#[command(name = "fspec", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Reproduce the paper's experiments (and three beyond it): CSV,
    /// Markdown and PNG plots in --out.
    Experiment(Box<ExperimentArgs>),
    /// Merge partial films (.fspart) of one frame, rendered over disjoint
    /// crops or pass ranges by separate processes or machines, into its
    /// image (PNG, EXR, spectral EXR) or one partial film.
    Merge(MergeArgs),
    /// Render a built-in scene, a TOML scene file or an OBJ to PNG/EXR.
    Render(Box<RenderArgs>),
    /// List the built-in scenes.
    Scenes,
    /// Inspect one spectrum: Fourier coefficients, XYZ by every conversion
    /// route, sRGB preview and reconstruction error.
    Spectrum(SpectrumArgs),
    /// Convert a spectral OpenEXR or an sRGB image to a Fourier-coefficient
    /// texture (OpenEXR), reporting the reconstruction error and memory.
    Texture(TextureArgs),
    /// Train the small sine network of a neural thin-film material.
    Train(TrainArgs),
    /// Interactive preview in the browser: a local web server showing the
    /// render pass after pass, with camera, transport, illuminant and
    /// exposure controls.
    View(Box<ViewArgs>),
}

/// Runs the command; `Ok` carries the exit code of a command that finished
/// its work (a render stopped by Ctrl-C still writes its image).
fn run(cli: &Cli) -> Result<ExitCode, CliError> {
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    match &cli.command {
        Command::Experiment(args) => experiment::run(args, &mut out),
        Command::Render(args) => return render(args),
        Command::Merge(args) => {
            let summary = merge_cmd::run(args)?;
            println!("{}", merge_cmd::summary_line(&summary));
            Ok(())
        }
        Command::Scenes => {
            print!("{}", fspec_cli::scene_source::list_scenes());
            Ok(())
        }
        Command::Spectrum(args) => spectrum_cmd::run(args, &mut out),
        Command::Texture(args) => texture_cmd::run(args, &mut out),
        Command::View(args) => view::run(args),
        Command::Train(args) => {
            let trained = train::run(args, &mut out)?;
            let last = trained.curve.last().map_or(f64::NAN, |(_, l)| *l);
            println!("final loss {last:.3e}; wrote {}", args.out.display());
            Ok(())
        }
    }?;
    Ok(ExitCode::SUCCESS)
}

/// `fspec render`: exit code 130 when Ctrl-C stopped it early (after
/// writing the passes done).
fn render(args: &RenderArgs) -> Result<ExitCode, CliError> {
    render_cmd::install_interrupt_handler()?;
    let summary = render_cmd::run(args)?;
    println!("{}", render_cmd::summary_line(&summary));
    Ok(if summary.interrupted {
        ExitCode::from(render_cmd::INTERRUPTED_EXIT_CODE)
    } else {
        ExitCode::SUCCESS
    })
}

fn main() -> ExitCode {
    // Large temporaries of a scene load go back to the system when freed
    // (`heap-tuning`'s docs); the result only says whether glibc is the
    // allocator.
    heap_tuning::return_large_blocks_to_the_system();
    let cli = Cli::parse();
    match run(&cli) {
        Ok(code) => code,
        Err(error) => {
            eprintln!("fspec: error: {error}");
            ExitCode::from(error.exit_code())
        }
    }
}
