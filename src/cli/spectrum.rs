//! `anisospec spectrum`: the expected power spectrum of a sampler or of a point file, in any projection.

use super::{image_kinds, require_extension, sampler_with_shear, ImageKind, ShearArgs};
use crate::error::{Error, Result};
use crate::output::image::{write_spectrum_exr, write_spectrum_png};
use crate::output::{check_outputs, write_npy};
use crate::points::io::read_points;
use crate::points::Projection;
use crate::samplers;
use crate::spectrum::expected::{of_sampler, of_sets, ExpectedSpectrum};
use crate::spectrum::profiles::{dark_withheld_note, radial_profile, write_radial_csv};
use crate::spectrum::{check_res, Method};
use crate::stats::MAX_REALIZATIONS;
use std::path::{Path, PathBuf};

/// Expected power spectrum P(k) = |Σ_j exp(−2πi k·x_j)|² / N of a sampler or a point file.
#[derive(Debug, clap::Args)]
#[command(group = clap::ArgGroup::new("source").required(true).args(["sampler", "input"]))]
pub struct SpectrumArgs {
    /// Sampler to draw the realizations from (see `anisospec samplers`), or table:PATH (optimized
    /// sets), or lattice:Z1:Z2 (2D) or lattice:Z1:Z2:Z3:Z4 (4D) (a rank-1 lattice with that
    /// generating vector).
    #[arg(long)]
    pub sampler: Option<String>,
    /// Point file (.npy [sets, N, D] or .txt): each set is one realization. Its N and D are read from
    /// the file, so -n, --dims, --seed, --shear and --shear-mode do not apply.
    #[arg(long, conflicts_with_all = ["n", "dims", "seed", "shear", "shear_mode"])]
    pub input: Option<PathBuf>,
    /// Dimensions of the sampler's points (2 or 4).
    #[arg(long, default_value_t = 2)]
    pub dims: usize,
    /// Points per set: required with --sampler, no default (N × D at most 2^28 coordinates).
    #[arg(
        short = 'n',
        long = "n",
        required_unless_present = "input",
        value_parser = super::parse_count,
        allow_negative_numbers = true
    )]
    pub n: Option<usize>,
    /// Projection: two of x,y,u,v (xy, uv, xu, yv, ...) or two dimension indices (0,2).
    /// The first is the horizontal frequency k1, the second the vertical k2.
    #[arg(long, default_value = "xy", allow_hyphen_values = true)]
    pub proj: String,
    /// Frequency grid side K (even, at most 8192): k1, k2 run over −K/2 … K/2−1.
    #[arg(long, default_value_t = 128, value_parser = crate::cli::parse_whole, allow_negative_numbers = true)]
    pub res: usize,
    /// Realizations averaged (independent sets). With --sampler, default 32; with --input, at most the
    /// number of sets in the file (default: all of them, so a file of more than 1000000 sets needs
    /// this flag). --stderr needs at least 2. At most 1000000.
    #[arg(long, value_parser = crate::cli::parse_whole, allow_negative_numbers = true)]
    pub realizations: Option<usize>,
    /// Use the exact O(N K²) DFT instead of the NUFFT.
    #[arg(long, conflicts_with = "eps")]
    pub exact: bool,
    /// NUFFT tolerance (relative error of P), from 1e-12 to 1e-1.
    #[arg(long, default_value = "1e-6", allow_negative_numbers = true)]
    pub eps: f64,
    /// Random seed of the realizations (with --sampler).
    #[arg(long, default_value_t = 1, value_parser = crate::cli::parse_seed, allow_negative_numbers = true)]
    pub seed: u64,
    #[command(flatten)]
    pub shear: ShearArgs,
    /// Output files, one or more (repeat -o or separate with commas): .npy (float64 [K, K], row i at
    /// k2 = i − K/2, column j at k1 = j − K/2), .exr (raw values) or .png (log10 P over [−2, 1]).
    /// Images put larger k2 on top.
    #[arg(short = 'o', long, value_delimiter = ',', required = true)]
    pub output: Vec<PathBuf>,
    /// Also write the per-bin standard error of the mean spectrum as .npy (needs 2 or more
    /// realizations).
    #[arg(long)]
    pub stderr: Option<PathBuf>,
    /// Write the radial profile as CSV: r, r/sqrt(N), mean, stderr (empty from one realization),
    /// anisotropy (dB; empty where the annulus is dark or flat within the method's error) and, with
    /// --cones, one column per directional cone; one row per annulus r − ½ ≤ |k| < r + ½,
    /// r = 1 … K/2 − 1 (needs --res 4 or more). The stderr combines the bins' standard errors as
    /// independent, except k and −k, which are equal.
    #[arg(long)]
    pub radial: Option<PathBuf>,
    /// Number of directional cones in the radial CSV (needs --radial; cone c covers the angles
    /// [c − ½, c + ½)·180°/M, so cone 0 is centred on the k1 axis and a k on an edge goes to the
    /// next cone up); at most 360.
    #[arg(long, default_value_t = 0, value_parser = crate::cli::parse_whole, allow_negative_numbers = true)]
    pub cones: usize,
}

/// Runs `anisospec spectrum`.
pub fn run(args: &SpectrumArgs) -> Result<()> {
    let kinds = image_kinds(&args.output)?;
    check_res(args.res)?;
    let method = super::fourier_method(args.exact, args.eps)?;
    for (extra, flag, ext, what) in [
        (&args.radial, "--radial", "csv", "a CSV table"),
        (&args.stderr, "--stderr", "npy", "an npy array"),
    ] {
        if let Some(path) = extra {
            require_extension(path, flag, ext, what)?;
        }
    }
    crate::spectrum::profiles::check_cones(args.cones)?;
    if args.radial.is_some() && args.res < 4 {
        // The profile holds the annuli r = 1 … K/2 − 1 that lie inside the grid: none below K = 4.
        return Err(Error::Usage(format!(
            "--radial needs --res 4 or more: the radial profile holds the annuli r = 1 to K/2 - 1, and --res {} has none; raise --res (e.g. --res 128), or leave out --radial",
            args.res
        )));
    }
    match args.realizations {
        Some(0) => {
            return Err(Error::Usage(
                "--realizations 0 averages nothing; give at least 1 (2 or more with --stderr)"
                    .into(),
            ))
        }
        Some(1) if args.stderr.is_some() => {
            return Err(no_stderr(
                "--realizations 1 asks for one",
                "give --realizations 2 or more",
            ))
        }
        Some(r) => crate::stats::check_realizations("--realizations", r)?,
        None => {}
    }
    let inputs = match (&args.sampler, &args.input) {
        (Some(name), _) => samplers::input_files(name),
        (None, Some(path)) => vec![path.clone()],
        (None, None) => Vec::new(),
    };
    let outputs: Vec<&Path> = args
        .output
        .iter()
        .chain(&args.radial)
        .chain(&args.stderr)
        .map(PathBuf::as_path)
        .collect();
    check_outputs(&outputs, &inputs)?;
    let (spec, what) = match (&args.sampler, &args.input) {
        (Some(name), _) => {
            let sampler = sampler_with_shear(name, args.dims, &args.shear)?;
            let proj = Projection::parse(&args.proj, sampler.dims())?;
            let n = args.n.expect("clap requires -n with --sampler");
            let r = args.realizations.unwrap_or(32);
            if let Some(note) = long_exact_note(n, args.res, r, method) {
                crate::eprintln_best_effort!("{note}");
            }
            let spec = of_sampler(sampler.as_ref(), n, proj, args.res, r, args.seed, method)?;
            (spec, sampler_identity(sampler.as_ref(), proj, args.seed))
        }
        (None, Some(path)) => {
            let sets = read_points(path)?;
            let proj = Projection::parse(&args.proj, sets.dims())?;
            let sets = match args.realizations {
                Some(r) if r > sets.sets() => {
                    return Err(Error::Usage(format!(
                        "--realizations {r} but {} holds {}; ask for at most {}",
                        path.display(),
                        super::counted(sets.sets(), "set"),
                        sets.sets()
                    )))
                }
                Some(r) => crate::points::PointSets::new(
                    r,
                    sets.n(),
                    sets.dims(),
                    sets.data()[..r * sets.n() * sets.dims()].to_vec(),
                )?,
                // As many realizations as --realizations allows: each costs a transform.
                None if sets.sets() > MAX_REALIZATIONS => {
                    return Err(Error::Usage(format!(
                        "{} holds {} sets, above the largest realization count, {MAX_REALIZATIONS}; average its first {MAX_REALIZATIONS} with --realizations {MAX_REALIZATIONS}, or fewer",
                        path.display(),
                        sets.sets()
                    )))
                }
                None if sets.sets() < 2 && args.stderr.is_some() => {
                    return Err(no_stderr(
                        &format!("{} holds one set", path.display()),
                        "give a file of 2 or more sets",
                    ))
                }
                None => sets,
            };
            if let Some(note) = long_exact_note(sets.n(), args.res, sets.sets(), method) {
                crate::eprintln_best_effort!("{note}");
            }
            let what = format!("{} in {}", path.display(), proj.name());
            (of_sets(&sets, proj, args.res, method)?, what)
        }
        (None, None) => unreachable!("clap requires --sampler or --input"),
    };
    let profile = args
        .radial
        .as_ref()
        .map(|path| (path, radial_profile(&spec, args.cones, method)));
    crate::output::write_group(&outputs, |staged| {
        let images: Vec<PathBuf> = args.output.iter().map(|p| staged(p)).collect();
        write_spectrum(&spec, &what, &images, &kinds)?;
        if let Some(path) = &args.stderr {
            write_npy(&staged(path), &[spec.res, spec.res], &spec.stderr)?;
        }
        if let Some((path, profile)) = &profile {
            write_radial_csv(&staged(path), profile)?;
        }
        Ok(())
    })?;
    if let Some(note) = profile
        .as_ref()
        .and_then(|(_, profile)| dark_withheld_note(profile, method, spec.n))
    {
        crate::eprintln_best_effort!("{note}");
    }
    let png_key = if kinds.contains(&ImageKind::Png) {
        format!(" (PNG: {})", crate::output::image::spectrum_png_key())
    } else {
        String::new()
    };
    crate::eprintln_best_effort!(
        "spectrum of {} of {} on a {}x{} grid written to {}{png_key}",
        super::counted(spec.realizations, "realization"),
        super::counted(spec.n, "point"),
        spec.res,
        spec.res,
        outputs
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(())
}

/// Exact DFT terms (`N × K² × R`, one complex multiply-add each) above which `spectrum --exact` says
/// what it has taken on: at the 3e8 to 1e9 terms a second per core measured on two AMD EPYC machines
/// (benches/spectrum.rs), a minute or more on two cores.
const LONG_EXACT_TERMS: f64 = 1e11;

/// What a long exact run has taken on, to say on stderr before it starts: `None` for the NUFFT or
/// for an exact run of at most [`LONG_EXACT_TERMS`] terms.
fn long_exact_note(n: usize, res: usize, realizations: usize, method: Method) -> Option<String> {
    let terms = n as f64 * (res as f64).powi(2) * realizations as f64;
    (method == Method::Exact && terms > LONG_EXACT_TERMS).then(|| {
        format!(
            "note: the exact DFT sums N x K^2 x R = {n} x {res}^2 x {realizations} = {terms:.1e} terms, at about 3e8 to 1e9 a second per core: {} to {} on one core; the NUFFT (drop --exact; --eps 1e-9 keeps P within 1e-8 relative) takes a small fraction of that",
            duration(terms / 1e9),
            duration(terms / 3e8)
        )
    })
}

/// Seconds as a short duration: `45 s`, `12 min`, `3.5 h`, `2.1 days`.
fn duration(seconds: f64) -> String {
    match seconds {
        s if s < 120.0 => format!("{s:.0} s"),
        s if s < 7200.0 => format!("{:.0} min", s / 60.0),
        s if s < 172_800.0 => format!("{:.1} h", s / 3600.0),
        s => format!("{:.1} days", s / 86400.0),
    }
}

/// The refusal of `--stderr` over a single realization, whose standard error is 0 in every bin.
fn no_stderr(why: &str, fix: &str) -> Error {
    Error::Usage(format!(
        "--stderr needs 2 or more realizations ({why}, and one realization's spread is 0 in every bin); {fix}, or leave out --stderr"
    ))
}

/// What a sampler's spectrum is of, as its PNG names it: `SAMPLER in PROJ, seed S` (the sampler's
/// name includes its shear).
pub fn sampler_identity(sampler: &dyn samplers::Sampler, proj: Projection, seed: u64) -> String {
    format!("{} in {}, seed {seed}", sampler.name(), proj.name())
}

/// Writes the mean spectrum to every output in its format.
pub fn write_spectrum(
    spec: &ExpectedSpectrum,
    what: &str,
    outputs: &[PathBuf],
    kinds: &[ImageKind],
) -> Result<()> {
    // The PNG's description names what it shows: `what` (the sampler or file, the projection), N
    // and R.
    let identity = format!("{what}, N = {}, {} realizations", spec.n, spec.realizations);
    for (path, kind) in outputs.iter().zip(kinds) {
        match kind {
            ImageKind::Npy => write_npy(path, &[spec.res, spec.res], &spec.mean)?,
            ImageKind::Exr => write_spectrum_exr(path, &spec.mean, spec.res)?,
            ImageKind::Png => write_spectrum_png(path, &spec.mean, spec.res, &identity)?,
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_exact_run_is_announced_with_its_cost() {
        // 4096 × 1024² × 100 = 4.3e11 terms: 7 to 24 minutes on one core.
        let note = long_exact_note(4096, 1024, 100, Method::Exact).unwrap();
        assert!(note.contains("4.3e11 terms"), "{note}");
        assert!(note.contains("7 min to 24 min"), "{note}");
        // The same job through the NUFFT, and an exact job of 1e11 terms or fewer, say nothing.
        assert_eq!(
            long_exact_note(4096, 1024, 100, Method::Nufft { eps: 1e-6 }),
            None
        );
        assert_eq!(long_exact_note(4096, 256, 100, Method::Exact), None);
        assert_eq!(duration(45.0), "45 s");
        assert_eq!(duration(3.5 * 3600.0), "3.5 h");
        assert_eq!(duration(3.0 * 86400.0), "3.0 days");
    }
}
