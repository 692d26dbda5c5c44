//! The `anisospec` command: see `anisospec --help`.

use anisospec::cli;
use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Design Monte Carlo sample patterns with anisotropic spectra, and measure what they buy.
#[derive(Debug, Parser)]
#[command(name = "anisospec", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// List the samplers, one line each with what the sampler is and which N it allows.
    Samplers,
    /// Draw point sets from a sampler and write them as .npy or .txt.
    Sample(cli::sample::SampleArgs),
    /// Expected power spectrum of a sampler or a point file, in any 2D projection.
    Spectrum(cli::spectrum::SpectrumArgs),
    /// The built-in default job: spectra of the classical samplers in xy and xu, written to OUT/gallery.
    Gallery(cli::gallery::GalleryArgs),
}

fn main() -> ExitCode {
    let args = Cli::parse();
    let result = match &args.command {
        Command::Samplers => {
            for info in anisospec::samplers::catalog() {
                let dims: Vec<String> = info.dims.iter().map(|d| format!("{d}D")).collect();
                println!(
                    "{:<12} {:<6} {}  [N: {}]",
                    info.name,
                    dims.join(","),
                    info.summary,
                    info.valid_n
                );
            }
            Ok(())
        }
        Command::Sample(a) => cli::sample::run(a),
        Command::Spectrum(a) => cli::spectrum::run(a),
        Command::Gallery(a) => cli::gallery::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
