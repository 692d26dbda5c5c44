//! `anisospec converge`: the empirical convergence test of one or more samplers on an integrand.

use crate::converge::{converge, plot, write_csv, ConvergeConfig, Convergence};
use crate::error::{Error, Result};
use crate::integrands::parse_with_cache;
use crate::samplers::Sampler;
use std::path::{Path, PathBuf};

/// Measure MSE(N) over independent, randomly shifted realizations, and fit the convergence slope.
#[derive(Clone, Debug, clap::Args)]
pub struct ConvergeArgs {
    /// Samplers, comma-separated (see `anisospec samplers`), e.g. random,jittered,nrooks or
    /// table:PATH (optimized sets), or lattice:Z1:Z2 (2D) or lattice:Z1:Z2:Z3:Z4 (4D) (a rank-1
    /// lattice with that generating vector).
    #[arg(long, value_delimiter = ',', required = true)]
    pub sampler: Vec<String>,
    /// Integrand, NAME:key=value,... (see `anisospec integrands`), e.g. disc:r=0.3. A pixel of the
    /// scene (pixel:px=COLUMN,py=ROW) renders its reference once and keeps it in the --cache folder
    /// for the next run.
    #[arg(long)]
    pub integrand: String,
    /// Sample counts N, comma-separated, e.g. 16,64,256,1024,4096 (N × D at most 2^28 coordinates).
    #[arg(
        short = 'n',
        long = "n",
        value_delimiter = ',',
        required = true,
        value_parser = crate::cli::parse_count,
        allow_negative_numbers = true
    )]
    pub n: Vec<usize>,
    /// Realizations per N (R): each an independent draw of a set (for a table, one of its sets picked
    /// at random) with its own random toroidal shift (made before --shear shears it); 2 to 1000000.
    #[arg(long, default_value_t = 100, value_parser = crate::cli::parse_whole, allow_negative_numbers = true)]
    pub realizations: usize,
    /// Random seed: the same seed gives the same numbers whatever the thread count.
    #[arg(long, default_value_t = 1, value_parser = crate::cli::parse_seed, allow_negative_numbers = true)]
    pub seed: u64,
    /// Also move the integrand at random in every realization (its centre or edge offset); errors are
    /// then taken against each placement's own integral.
    #[arg(long)]
    pub random_placement: bool,
    #[command(flatten)]
    pub shear: crate::cli::ShearArgs,
    /// Write the results as CSV (sampler, integrand, n, mse, mse_stderr, mean_error, seconds,
    /// evaluations, slope, slope_ci_low, slope_ci_high); seconds, as in the printed table, is the wall
    /// time of all R realizations at that N, not of one, without the one-off set-up done before any
    /// timing (the integrand's reference, the thread pool, each sampler's set-up at each N).
    #[arg(short = 'o', long)]
    pub output: Option<PathBuf>,
    /// Write a log-log plot of MSE against N (PNG), one line per sampler, slopes in the legend, R in
    /// the title.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Folder a pixel integrand's reference is cached in and read back from (default $ANISOSPEC_CACHE,
    /// or out/cache under the working folder when that is unset or empty, as for render and compare).
    /// Only a pixel of the scene has a reference to cache.
    #[arg(long)]
    pub cache: Option<PathBuf>,
}

/// Runs every sampler, prints a table per sampler, writes the CSV and the plot.
pub fn run(args: &ConvergeArgs) -> Result<()> {
    let cache = args.cache.as_deref();
    if let Some(csv) = &args.output {
        crate::cli::require_extension(csv, "-o", "csv", "a CSV table")?;
    }
    if let Some(png) = &args.plot {
        crate::cli::require_extension(png, "--plot", "png", "a PNG picture")?;
    }
    let inputs: Vec<PathBuf> = args
        .sampler
        .iter()
        .flat_map(|name| crate::samplers::input_files(name.trim()))
        .chain(crate::integrands::spec::input_files(&args.integrand))
        .collect();
    let outputs: Vec<&Path> = args
        .output
        .iter()
        .chain(&args.plot)
        .map(PathBuf::as_path)
        .collect();
    crate::cli::increasing_counts(&args.n)?;
    crate::output::check_outputs(&outputs, &inputs)?;
    // A pixel's reference goes to the cache once computed: a file in the cache's way is refused
    // before that work.
    if crate::integrands::spec::names_a_pixel(&args.integrand) {
        let (folder, source) = crate::render::pixel::cache_dir_and_source(cache);
        crate::output::check_folder(&folder, source, "cache")?;
    } else if cache.is_some() {
        return Err(Error::Usage(format!(
            "--cache has no effect with --integrand {}: only a pixel of the scene (pixel:px=COLUMN,py=ROW) has a reference to cache; leave --cache out",
            args.integrand.trim()
        )));
    }
    let f = parse_with_cache(&args.integrand, cache)?;
    if args.random_placement && f.placed(&mut crate::rng::stream(0, 0)).is_none() {
        return Err(crate::error::Error::Usage(format!(
            "--random-placement: {} has nothing to move at random (a pixel of the scene has no placement); leave the flag out",
            f.name()
        )));
    }
    // Build and check every sampler before any work starts.
    let built = args
        .sampler
        .iter()
        .map(|name| {
            let s = crate::cli::sampler_with_shear(name.trim(), f.dims(), &args.shear)?;
            crate::converge::check_plan(s.as_ref(), f.as_ref(), &args.n, args.realizations)?;
            Ok(s)
        })
        .collect::<Result<Vec<_>>>()?;
    if let Some(which) = crate::samplers::repeated(&args.sampler, &built) {
        return Err(Error::Usage(format!(
            "--sampler lists {which}; give each sampler once (e.g. --sampler random,jittered,mj)"
        )));
    }
    let cfg = ConvergeConfig {
        realizations: args.realizations,
        seed: args.seed,
        random_placement: args.random_placement,
    };
    warm_up(f.as_ref(), &built, &args.n, args.seed);
    let bar = crate::progress::bar((built.len() * args.n.len()) as u64, "converge");
    let mut studies: Vec<Convergence> = Vec::with_capacity(built.len());
    for s in &built {
        let study = converge(s.as_ref(), f.as_ref(), &args.n, &cfg, |_| bar.inc(1))?;
        studies.push(study);
    }
    bar.finish_and_clear();
    let reference = f.reference();
    let integral = if reference.stderr > 0.0 {
        format!(
            "{:.12e} +- {:.2e} by Monte Carlo, whose squared error, {:.2e}, adds to every MSE on average: \
             the reference floor",
            reference.value,
            reference.stderr,
            reference.stderr * reference.stderr
        )
    } else {
        format!("{:.12e}", reference.value)
    };
    outln!(
        "integrand {} (integral {integral}), R = {}; seconds: wall time of all R realizations at an N, after the one-off set-up",
        f.name(),
        args.realizations
    );
    for s in &studies {
        match &s.fit {
            // Through two N the line fits exactly: no degree of freedom is left to measure the scatter
            // (chi2/dof), and the interval holds only the two points' own errors, not a curvature.
            // A standard error within rounding defines no weight: no interval.
            Some(fit) if fit.interval().is_none() => {
                let flat: Vec<String> = s
                    .points
                    .iter()
                    .filter(|p| {
                        p.mse_stderr / p.mse
                            <= crate::converge::rounding_floor(
                                p.n,
                                args.realizations,
                                p.mse,
                                reference.value,
                            )
                    })
                    .map(|p| p.n.to_string())
                    .collect();
                outln!(
                    "{}: slope {:.3} (95% CI —, chi2/dof —: at N = {} the realizations differ by no more than f64 rounding (stderr about 0 there), as for an estimator with the same error in every realization (every shift, or an integrand with two values whose error is the same either way, at N = 1) or a few realizations that happen to agree; no interval. If the set is random, raise --realizations, or leave those N out)",
                    s.sampler,
                    fit.slope,
                    flat.join(", ")
                )
            }
            Some(fit) if s.points.len() == 2 => outln!(
                "{}: slope {:.3} (95% CI {:.3} .. {:.3} from the two points' errors alone, chi2/dof —: give three or more N to test the fit)",
                s.sampler, fit.slope, fit.ci95.0, fit.ci95.1
            ),
            Some(fit) => outln!(
                "{}: slope {:.3} (95% CI {:.3} .. {:.3}, chi2/dof {})",
                s.sampler,
                fit.slope,
                fit.ci95.0,
                fit.ci95.1,
                fit.chi2(s.points.len())
                    .map_or_else(|| "—".to_string(), |c| format!("{c:.2}"))
            ),
            None => {
                let rounding: Vec<String> = s
                    .points
                    .iter()
                    .filter(|p| {
                        p.mse > 0.0
                            && crate::converge::error_within_rounding(p.n, p.mse, reference.value)
                    })
                    .map(|p| {
                        let bound = crate::converge::rounding_error(p.n, reference.value, p.mse.sqrt());
                        format!("{} (RMS error {:.1e}, rounding up to {bound:.1e})", p.n, p.mse.sqrt())
                    })
                    .collect();
                if rounding.is_empty() {
                    outln!(
                        "{}: no slope (a log-log fit needs two or more distinct N and a positive MSE at each)",
                        s.sampler
                    )
                } else {
                    outln!(
                        "{}: no slope: at N = {} the error is within what f64 rounding of each estimate can make, so the MSE there is rounding, not a value (the sampler integrates {} to f64 precision)",
                        s.sampler,
                        rounding.join(", "),
                        f.name()
                    )
                }
            }
        }
        outln!(
            "{:>8} {:>12} {:>10} {:>12}",
            "N",
            "MSE",
            "stderr",
            "seconds(R)"
        );
        for p in &s.points {
            outln!(
                "{:>8} {:>12.4e} {:>10.2e} {:>12.3e}",
                p.n,
                p.mse,
                p.mse_stderr,
                p.seconds
            );
        }
        if let Some(note) = crate::converge::floor_note(&s.points, reference.stderr) {
            outln!("{}: {note}", s.sampler);
        }
    }
    // A log axis has no place for an MSE of 0: with every MSE 0 (samplers that integrate the
    // integrand exactly at every N) the plot is left out and said so, as in compare's report.
    let plot_file = args.plot.as_ref().filter(|png| {
        let drawable = studies
            .iter()
            .flat_map(|s| &s.points)
            .any(|p| crate::compare::report::drawable(p.mse));
        if !drawable {
            crate::eprintln_best_effort!(
                "no plot written to {}: every MSE is 0 (the samplers integrate {} exactly at every N), which a log axis cannot show",
                png.display(),
                f.name()
            );
        }
        for s in studies.iter().filter(|_| drawable) {
            let zero: Vec<String> = s
                .points
                .iter()
                .filter(|p| p.mse == 0.0)
                .map(|p| p.n.to_string())
                .collect();
            if !zero.is_empty() {
                crate::eprintln_best_effort!(
                    "{}: {} has MSE 0 at N = {} (it integrates {} exactly there), which a log axis cannot show: not drawn, and its line breaks there",
                    png.display(),
                    s.sampler,
                    zero.join(", "),
                    f.name()
                );
            }
        }
        drawable
    });
    let outputs: Vec<&Path> = args
        .output
        .iter()
        .chain(plot_file)
        .map(PathBuf::as_path)
        .collect();
    crate::output::write_group(&outputs, |staged| {
        if let Some(out) = &args.output {
            write_csv(&staged(out), &studies)?;
        }
        if let Some(png) = plot_file {
            plot(
                &staged(png),
                &studies,
                None,
                &format!(
                    "Convergence on {}, R = {} realizations per N",
                    f.name(),
                    args.realizations
                ),
            )?;
        }
        Ok(())
    })
}

/// Does, untimed, the one-off work the first realization would otherwise be charged with: the
/// integrand's reference (a pixel's is computed, or read from the cache, on first use), the start of
/// the thread pool, and each sampler's set-up at each N (e.g. the lattice's generating-vector search,
/// kept per N), by drawing one set of every sampler at every N from a stream no realization uses.
fn warm_up(
    f: &dyn crate::integrands::Integrand,
    samplers: &[Box<dyn Sampler>],
    ns: &[usize],
    seed: u64,
) {
    f.reference();
    rayon::broadcast(|_| ());
    for s in samplers {
        for &n in ns {
            s.generate(n, &mut crate::rng::substream(seed, u64::MAX, n as u64));
        }
    }
}
