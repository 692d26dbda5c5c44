//! The `anisospec` command: see `anisospec --help`.

use anisospec::cli;
use anisospec::error::Error;
use clap::parser::ValueSource;
use clap::{ArgMatches, CommandFactory, FromArgMatches, Parser, Subcommand};
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
    /// Spectra of the classical samplers in xy and xu, written to OUT/gallery.
    Gallery(cli::gallery::GalleryArgs),
    /// List the integrands and their keys.
    Integrands(cli::integrands::IntegrandsArgs),
    /// Predict variance from spectra, Var(N) = (1/N) Σ |f̂(k)|² E[P_N(k)], split by directional cone.
    ///
    /// With --shear the sampler shifts its pattern before it shears it, so the prediction is made in
    /// the unsheared pattern's frame, for the integrand pulled back through the shear: the integrand
    /// must lie on the xu and yv planes (e.g. sheared:s=0.5@xu+sheared:s=0.5@yv), and K is at most
    /// 1024 (the pulled-back integrand is sampled on 4K points per side, at most 4096).
    Variance(cli::variance::VarianceArgs),
    /// Measure the convergence of samplers on an integrand: MSE against N, slope, time.
    Converge(cli::converge::ConvergeArgs),
    /// Render the depth-of-field scene with a sampler, optionally sheared by the depth oracle.
    Render(cli::render::RenderArgs),
    /// Write the depth oracle per pixel: depth, shear, shear range and class.
    Oracle(cli::oracle::OracleArgs),
    /// The spectrum of one pixel's integrand on one 2D slice (xu, yv or any other projection; --proj).
    PixelSpectrum(cli::pixel_spectrum::PixelSpectrumArgs),
    /// Optimize point sets until their spectra match a target (widened hairline, double wedge, ...) or
    /// their predicted variance for a family of integrands is lowest,
    /// and write them as tables.
    Optimize(cli::optimize::OptimizeArgs),
    /// The main job: optimized, sheared and classical samplers compared on analytic integrands and
    /// renderer pixels, written as a report folder.
    Compare(cli::compare::CompareArgs),
}

/// Flags that mean something only beside another, which clap's `requires` would refuse with a bare
/// "required arguments were not provided" and a usage line that marks many flags as required:
/// (subcommand, flag id, the flag it needs (id), that flag as written, why).
const NEEDS: &[(&str, &str, &str, &str, &str)] = &[
    (
        "spectrum",
        "cones",
        "radial",
        "--radial FILE.csv",
        "the cones are columns of the radial profile CSV",
    ),
    (
        "sample",
        "shear_mode",
        "shear",
        "--shear sx,sy",
        "it says how --shear shears the sets",
    ),
    (
        "spectrum",
        "shear_mode",
        "shear",
        "--shear sx,sy",
        "it says how --shear shears the sets",
    ),
    (
        "converge",
        "shear_mode",
        "shear",
        "--shear sx,sy",
        "it says how --shear shears the sets",
    ),
    (
        "variance",
        "shear_mode",
        "shear",
        "--shear sx,sy",
        "it says how --shear shears the sampler's sets",
    ),
    (
        "render",
        "shear_mode",
        "shear",
        "--shear",
        "it says how the oracle's shear is applied",
    ),
    (
        "render",
        "wedge_shear",
        "shear",
        "--shear",
        "it chooses the oracle's shear of double-wedge pixels",
    ),
];

/// A usage error for a flag of [`NEEDS`] given without the flag it needs.
fn check_needs(matches: &ArgMatches) -> anisospec::error::Result<()> {
    let Some((name, sub)) = matches.subcommand() else {
        return Ok(());
    };
    let given = |id: &str| sub.value_source(id) == Some(ValueSource::CommandLine);
    for &(command, id, needed, written, why) in NEEDS {
        if command == name && given(id) && !given(needed) {
            let flag = format!("--{}", id.replace('_', "-"));
            let value = sub
                .get_raw(id)
                .and_then(|mut v| v.next())
                .map(|v| format!(" {}", v.to_string_lossy()))
                .unwrap_or_default();
            return Err(Error::Usage(format!(
                "{flag}{value} needs {written}: {why}; add {written}, or leave out {flag}"
            )));
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    let matches = Cli::command().get_matches();
    anisospec::output::interrupt::remove_temporaries_on_interrupt();
    let result = check_needs(&matches).and_then(|()| {
        let args = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
        run(&args.command)
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // A reader that closed the pipe (`| head`) wanted no more: stop quietly, with the status a
        // process stopped by SIGPIPE has.
        Err(e) if e.is_broken_pipe() => ExitCode::from(141),
        Err(e) => {
            anisospec::output::interrupt::yield_to_interrupt();
            anisospec::eprintln_best_effort!("error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}

/// Runs one subcommand.
fn run(command: &Command) -> anisospec::error::Result<()> {
    match command {
        Command::Samplers => {
            let mut listing = String::new();
            for info in anisospec::samplers::catalog() {
                let dims: Vec<String> = info.dims.iter().map(|d| format!("{d}D")).collect();
                listing += &format!(
                    "{:<12} {:<6} {}  [N: {}]\n",
                    info.name,
                    dims.join(","),
                    info.summary,
                    info.valid_n
                );
            }
            listing += "table:PATH   2D,4D  optimized sets written by `anisospec optimize` (PATH.npy or .txt; \
                 PATH may hold {n} for a family of tables at several N); each use takes one set at \
                 random and shifts it  [N: the tables' own]\n";
            listing += "lattice:Z    2D,4D  rank-1 lattice with the generating vector Z you give, e.g. \
                 lattice:1:34 or lattice:1:163:271:141 (entries taken mod N, each coprime to N), randomly \
                 shifted  [N: any N <= 2^20]\n";
            cli::write_stdout(format_args!("{listing}"))
        }
        Command::Sample(a) => cli::sample::run(a),
        Command::Spectrum(a) => cli::spectrum::run(a),
        Command::Gallery(a) => cli::gallery::run(a),
        Command::Integrands(a) => cli::integrands::run(a),
        Command::Variance(a) => cli::variance::run(a),
        Command::Converge(a) => cli::converge::run(a),
        Command::Render(a) => cli::render::run(a),
        Command::Oracle(a) => cli::oracle::run(a),
        Command::PixelSpectrum(a) => cli::pixel_spectrum::run(a),
        Command::Optimize(a) => cli::optimize::run(a),
        Command::Compare(a) => cli::compare::run(a),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every row of [`NEEDS`] names a subcommand and two of its flags by their clap ids: a renamed
    /// flag would otherwise turn its row into a check that never fires.
    #[test]
    fn needs_rows_name_real_flags() {
        let cli = Cli::command();
        for &(command, id, needed, written, _) in NEEDS {
            let sub = cli
                .find_subcommand(command)
                .unwrap_or_else(|| panic!("no subcommand {command}"));
            for flag in [id, needed] {
                assert!(
                    sub.get_arguments().any(|a| a.get_id() == flag),
                    "{command} has no flag with id {flag}"
                );
            }
            assert!(written.starts_with(&format!("--{}", needed.replace('_', "-"))));
        }
    }
}
