//! `fspec`: the command-line front end of the Fourier spectral renderer.

use clap::{Parser, Subcommand};
use fspec_cli::CliError;
use fspec_cli::spectrum_cmd::{self, SpectrumArgs};
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
    /// Inspect one spectrum: Fourier coefficients, XYZ by every conversion
    /// route, sRGB preview and reconstruction error.
    Spectrum(SpectrumArgs),
}

fn run(cli: &Cli) -> Result<(), CliError> {
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    match &cli.command {
        Command::Spectrum(args) => spectrum_cmd::run(args, &mut out),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(&cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("fspec: error: {error}");
            ExitCode::from(error.exit_code())
        }
    }
}
