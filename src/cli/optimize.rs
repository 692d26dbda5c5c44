//! `anisospec optimize`: point sets whose spectra meet a target, written as tables (npy, text, C
//! header) with a JSON sidecar and a CSV log.

use crate::error::{number, Error, Result};
use crate::optimize::{
    self, lattice_design, loss::Repulsion, metrics, Limits, Setup, Strata, DEFAULT_ANNULAR_WEIGHT,
    DEFAULT_LIMITS, DEFAULT_REPULSION, DEFAULT_STRATA,
};
use crate::output::{check_outputs, csv_number, write_atomic, write_group};
use crate::points::io::write_points;
use crate::points::PointSets;
use crate::samplers;
use crate::spectrum::Method;
use crate::targets::variance::Design;
use crate::targets::Target;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Optimize point sets toward a target spectrum (DESIGN §6).
#[derive(clap::Args, Debug, Clone)]
pub struct OptimizeArgs {
    /// Target: a TOML file (see targets/*.toml): a spectrum shape (hairline, double-wedge, blue-noise,
    /// image), or kind = "variance", the variance predicted for a family of integrands. A variance
    /// target with design = "lattice" is met by a search over rank-1 lattices instead of by moving
    /// points: every set is the lattice of lowest predicted variance, and --init, --latin, the
    /// solver's limits and the loss weights do not apply.
    #[arg(long)]
    pub target: PathBuf,
    /// Dimensions: 2 (the target on the set's two coordinates) or 4 (the target on xu and yv, xy and
    /// uv kept stratified).
    #[arg(long, default_value_t = 2)]
    pub dims: usize,
    /// Points per set (N × sets × D at most 2^28 coordinates).
    #[arg(short = 'n', long, value_parser = super::parse_count, allow_negative_numbers = true)]
    pub n: usize,
    /// Number of sets; they are optimized in parallel, set s from random stream s of the seed.
    #[arg(long, default_value_t = 1, value_parser = crate::cli::parse_whole, allow_negative_numbers = true)]
    pub sets: usize,
    /// Seed of the random starts (as in every other command).
    #[arg(long, default_value_t = DEFAULT_SEED, value_parser = crate::cli::parse_seed, allow_negative_numbers = true)]
    pub seed: u64,
    /// Output table, `.npy` ([sets, N, D] float64); the same numbers go to `.txt`, `.h`, a `.json`
    /// sidecar and a `.log.csv` next to it. The C header's array is named after the file:
    /// `-o out/fan.npy` gives `anisospec_fan` and the macros `ANISOSPEC_FAN_SETS`, `_N`, `_DIMS`
    /// (the file name needs an ASCII letter or digit); its include guard carries a hash of the
    /// numbers, so two tables whose names give the same C name fail to compile together.
    #[arg(short = 'o', long)]
    pub output: PathBuf,
    /// Draw the starting sets from this sampler (e.g. mj, jittered; see `anisospec samplers`)
    /// instead of uniform random points (the default). Stratified starts keep their dark axes.
    #[arg(long)]
    pub init: Option<String>,
    /// Hold the first coordinate (2D) or x and y (4D) where --init put them, one point per interval
    /// [s/N, (s+1)/N) at its centre (by rank if the start is not stratified), and move only the
    /// others. The k1 axis then stays dark up to N, beyond the loss's frequency grid, and in 4D xy
    /// keeps the start's structure (its strata term and its repulsion are then constants of the
    /// loss, computed once, so --strat-radius and --strat-weight act on uv alone and the repulsion
    /// flags on xu, yv and uv). Use it, with --init padded-pmj02 in 4D,
    /// for tables applied through the transported shear (widened hairline, double wedge).
    #[arg(long)]
    pub latin: bool,
    /// Loss: weight of the term that pulls the mean P of each annulus |k| = r (outside the dark
    /// region) to the target's mean there; 0 (off) to 1e6.
    #[arg(long, default_value_t = DEFAULT_ANNULAR_WEIGHT, allow_negative_numbers = true)]
    pub annular_weight: f64,
    /// Loss: repulsion radius in units of the mean spacing 1/sqrt(N), from 0 (off) to 1.07 (the
    /// spacing of a hexagonal packing; a wider repulsion stacks points into clusters).
    #[arg(long, default_value_t = DEFAULT_REPULSION.radius, allow_negative_numbers = true)]
    pub repulsion_radius: f64,
    /// Loss: weight of the repulsion term; 0 (off) to 1e6.
    #[arg(long, default_value_t = DEFAULT_REPULSION.weight, allow_negative_numbers = true)]
    pub repulsion_weight: f64,
    /// Loss, 4D: radius of the blue-noise dark disc that keeps xy and uv stratified: the disc is
    /// |k| < radius · sqrt(N) in frequency cells (cycles per unit), so the unit is sqrt(N) cells.
    /// Valid: above 1/sqrt(N) (a smaller disc holds no cell at that N) up to about 0.56 = 1/sqrt(π)
    /// (N points can darken about N cells at most); --strat-weight 0 switches the term off.
    #[arg(long, default_value_t = DEFAULT_STRATA.radius, allow_negative_numbers = true)]
    pub strat_radius: f64,
    /// Loss, 4D: weight of the xy and uv stratification terms; 0 (leaves them free) to 1e6.
    #[arg(long, default_value_t = DEFAULT_STRATA.weight, allow_negative_numbers = true)]
    pub strat_weight: f64,
    /// Compute the loss with the exact DFT instead of the NUFFT (slow; the reference).
    #[arg(long, conflicts_with = "eps")]
    pub exact: bool,
    /// NUFFT tolerance for the loss and its gradient, from 1e-12 to 1e-1.
    #[arg(long, default_value = "1e-8", allow_negative_numbers = true)]
    pub eps: f64,
    /// Largest number of solver iterations per set (0 takes no solver step: the starting sets as
    /// --latin centres them, coincident points moved apart).
    #[arg(long, default_value_t = DEFAULT_LIMITS.max_iters, value_parser = parse_iterations, allow_negative_numbers = true)]
    pub max_iters: u64,
    /// Largest wall time per set, in seconds, at most 1e9 (results depend on machine speed only if
    /// this binds). The sets run in parallel on the cores, so S sets on C cores may take up to about
    /// S/C times this.
    #[arg(long, default_value_t = DEFAULT_LIMITS.max_seconds, allow_negative_numbers = true)]
    pub max_seconds: f64,
    /// Stop when a solver round lowers the loss by less than this fraction of the loss it started
    /// from (a finite number >= 0; with 0 a run stops only at a round that gains nothing, or at the
    /// iteration or time limit). A round is one L-BFGS run restarted from the best set so far, which
    /// ends when an iteration changes the loss by less than tol × 1e-3 × min(|loss|, 1), or when its
    /// line search gives up (the run then stops if that round gained nothing); after an L-BFGS
    /// round that fails on a non-finite loss or gradient, a round is 50 iterations of steepest
    /// descent instead.
    #[arg(long, default_value_t = DEFAULT_LIMITS.tol, allow_negative_numbers = true)]
    pub tol: f64,
}

/// The default `--eps` (spelled "1e-8" in its `#[arg]` so that `--help` shows it so): the NUFFT
/// tolerance of the loss and its gradient.
const DEFAULT_EPS: f64 = 1e-8;

/// Parses `--max-iters`: a whole number, 0 or more.
fn parse_iterations(text: &str) -> std::result::Result<u64, String> {
    crate::cli::parse_whole(text).map(|v| v as u64)
}

/// The largest `--max-seconds` accepted (about 31 years): a limit, not a schedule.
const MAX_SECONDS: f64 = 1e9;

fn check_args(args: &OptimizeArgs) -> Result<()> {
    crate::cli::require_extension(
        &args.output,
        "-o",
        "npy",
        "the table as numpy, and the .txt, .h, .json and .log.csv next to it",
    )?;
    c_name(&args.output)?;
    if args.sets == 0 {
        return Err(Error::Usage(
            "--sets 0 asks for nothing; give at least one set".into(),
        ));
    }
    if args.n < 2 {
        return Err(Error::Usage(format!(
            "-n {}: an optimized set needs at least 2 points",
            args.n
        )));
    }
    crate::points::coordinate_count(args.sets, args.n, args.dims).map_err(Error::Usage)?;
    if !(args.max_seconds.is_finite() && args.max_seconds > 0.0 && args.max_seconds <= MAX_SECONDS)
    {
        return Err(Error::Usage(format!(
            "--max-seconds {}: give a positive number of seconds, at most {MAX_SECONDS:e}",
            number(args.max_seconds)
        )));
    }
    if !(args.tol.is_finite() && args.tol >= 0.0) {
        return Err(Error::Usage(format!(
            "--tol {}: give a finite number >= 0",
            number(args.tol)
        )));
    }
    crate::cli::fourier_method(args.exact, args.eps)?;
    if args.dims == 2 {
        let given: Vec<String> = [
            (args.strat_radius != DEFAULT_STRATA.radius, "--strat-radius"),
            (args.strat_weight != DEFAULT_STRATA.weight, "--strat-weight"),
        ]
        .into_iter()
        .filter(|(is_given, _)| *is_given)
        .map(|(_, flag)| flag.to_string())
        .collect();
        if !given.is_empty() {
            return Err(Error::Usage(format!(
                "{} set{} the 4D loss's xy and uv stratification terms, which a 2D table does not have; leave {} out, or ask for 4D sets with --dims 4",
                super::spoken_list(&given, "and"),
                if given.len() == 1 { "s" } else { "" },
                if given.len() == 1 { "it" } else { "them" }
            )));
        }
    }
    Ok(())
}

/// Refuses a loss term's flag that its other flag switches off, so that it would be ignored: a
/// radius given with the weight 0, a weight given with the radius 0, and an annular weight when no
/// term of the loss has annuli (a variance target's grid has none, and in 4D neither has the strata
/// term with --strat-weight 0).
fn refuse_flags_without_term(args: &OptimizeArgs, target: &Target) -> Result<()> {
    // A 2D table's strata flags are refused by name in `check_args`.
    let strata = args.dims == 4;
    for (radius, weight, radius_given, weight_given, radius_flag, weight_flag) in [
        (
            args.repulsion_radius,
            args.repulsion_weight,
            args.repulsion_radius != DEFAULT_REPULSION.radius,
            args.repulsion_weight != DEFAULT_REPULSION.weight,
            "--repulsion-radius",
            "--repulsion-weight",
        ),
        (
            args.strat_radius,
            args.strat_weight,
            strata && args.strat_radius != DEFAULT_STRATA.radius,
            strata && args.strat_weight != DEFAULT_STRATA.weight,
            "--strat-radius",
            "--strat-weight",
        ),
    ] {
        if radius_given && weight == 0.0 {
            return Err(Error::Usage(format!(
                "{radius_flag} has no effect with {weight_flag} 0, which switches its term off; leave {radius_flag} out, or give {weight_flag} above 0"
            )));
        }
        if weight_given && weight > 0.0 && radius == 0.0 {
            return Err(Error::Usage(format!(
                "{weight_flag} has no effect with {radius_flag} 0, which switches its term off; leave {weight_flag} out, or give {radius_flag} above 0"
            )));
        }
    }
    let annuli = !matches!(target, Target::Variance(_)) || (strata && args.strat_weight > 0.0);
    if !annuli && args.annular_weight != DEFAULT_ANNULAR_WEIGHT {
        return Err(Error::Usage(format!(
            "--annular-weight has no effect here: {} is a variance target, whose loss is the predicted variance, with no annuli{}; leave --annular-weight out",
            args.target.display(),
            if strata {
                ", and --strat-weight 0 switches off the strata term, which has them"
            } else {
                ""
            }
        )));
    }
    Ok(())
}

/// `--seed`'s default.
const DEFAULT_SEED: u64 = 1;

/// Refuses the flags a lattice design would ignore (it searches lattices; it moves no points and
/// draws nothing at random): the seed, a
/// start, held strata, the solver's limits and the loss's weights. A value given equal to the
/// default cannot be told from the default and passes.
fn refuse_solver_flags(args: &OptimizeArgs) -> Result<()> {
    let given: Vec<&str> = [
        (args.init.is_some(), "--init"),
        (args.latin, "--latin"),
        (args.seed != DEFAULT_SEED, "--seed"),
        (args.exact, "--exact"),
        (args.eps != DEFAULT_EPS, "--eps"),
        (args.max_iters != DEFAULT_LIMITS.max_iters, "--max-iters"),
        (
            args.max_seconds != DEFAULT_LIMITS.max_seconds,
            "--max-seconds",
        ),
        (args.tol != DEFAULT_LIMITS.tol, "--tol"),
        (
            args.annular_weight != DEFAULT_ANNULAR_WEIGHT,
            "--annular-weight",
        ),
        (
            args.repulsion_radius != DEFAULT_REPULSION.radius,
            "--repulsion-radius",
        ),
        (
            args.repulsion_weight != DEFAULT_REPULSION.weight,
            "--repulsion-weight",
        ),
        (args.strat_radius != DEFAULT_STRATA.radius, "--strat-radius"),
        (args.strat_weight != DEFAULT_STRATA.weight, "--strat-weight"),
    ]
    .into_iter()
    .filter_map(|(is_given, flag)| is_given.then_some(flag))
    .collect();
    if given.is_empty() {
        return Ok(());
    }
    Err(Error::Usage(format!(
        "{} sets design = \"lattice\": a search over rank-1 lattices, which moves no points, so {} would not apply; leave {} out, or use a target without design = \"lattice\"",
        args.target.display(),
        super::spoken_list(
            &given.iter().map(|f| f.to_string()).collect::<Vec<_>>(),
            "and"
        ),
        if given.len() == 1 { "it" } else { "them" }
    )))
}

/// Runs `anisospec optimize`.
pub fn run(args: &OptimizeArgs) -> Result<()> {
    check_args(args)?;
    let target = Target::load(&args.target)?;
    if matches!(&target, Target::Variance(v) if v.design() == Design::LatticeMixture) {
        return Err(Error::Usage(format!(
            "{} sets design = \"lattice-mixture\", whose sets are a mixture of lattices built by compare: list the target in a compare config's tables = [...]; optimize moves points (design = \"points\") or searches one lattice (design = \"lattice\")",
            args.target.display()
        )));
    }
    let lattice_search = matches!(&target, Target::Variance(v) if v.design() == Design::Lattice);
    // A target beyond reach at this N is the file's problem: say which file.
    let in_file = |e: Error| match e {
        Error::Input(m) => Error::Input(format!("{}: {m}", args.target.display())),
        other => other,
    };
    if let Target::Variance(v) = &target {
        if lattice_search {
            refuse_solver_flags(args)?;
            // The search's own limits, before the integrand is sampled for it.
            lattice_design::check_n(args.n)?;
            v.sampling_side(lattice_design::SEARCH_RES)
                .map_err(in_file)?;
        }
    }
    refuse_flags_without_term(args, &target)?;
    // The table at -o as given (`t.NPY` stays `t.NPY`), the other files beside it.
    let outputs: Vec<PathBuf> = std::iter::once(args.output.clone())
        .chain(
            ["txt", "h", "json", "log.csv"]
                .iter()
                .map(|e| args.output.with_extension(e)),
        )
        .collect();
    let mut inputs = vec![args.target.clone()];
    if let Target::Image(img) = &target {
        inputs.push(
            args.target
                .parent()
                .unwrap_or(Path::new("."))
                .join(&img.file),
        );
    }
    if let Some(init) = &args.init {
        inputs.extend(samplers::input_files(init));
    }
    check_outputs(
        &outputs.iter().map(PathBuf::as_path).collect::<Vec<_>>(),
        &inputs,
    )?;
    let setup = Setup {
        target: target.clone(),
        n: args.n,
        dims: args.dims,
        // A lattice search keeps no strata term: the loss it reports is the target's alone.
        strata: Strata {
            radius: args.strat_radius,
            weight: if lattice_search {
                0.0
            } else {
                args.strat_weight
            },
        },
        repulsion: Repulsion {
            radius: args.repulsion_radius,
            weight: args.repulsion_weight,
        },
        method: if args.exact {
            Method::Exact
        } else {
            Method::Nufft { eps: args.eps }
        },
        limits: Limits {
            max_iters: args.max_iters,
            max_seconds: args.max_seconds,
            tol: args.tol,
        },
        init: args.init.clone(),
        latin: args.latin,
        annular_weight: args.annular_weight,
    };
    let objective = setup.objective().map_err(in_file)?;
    for term in &objective.terms {
        if let Some((cells, largest)) = term.grid.above_reach() {
            crate::eprintln_best_effort!(
                "warning: {}: the target asks for P above N = {} at {cells} frequency cells in {} (up to {}); no set of {} points has P above N, so those cells stay below it and the loss cannot reach 0; scale the image down or raise -n",
                args.target.display(),
                args.n,
                term.proj.name(),
                crate::error::number(largest),
                args.n
            );
        }
    }
    // The wider grid the fit is also judged on, checked before any work.
    let wide = target.check_grid(args.n).map_err(in_file)?;
    let t0 = Instant::now();
    let (points, reports, lattice) = match &target {
        Target::Variance(v) if v.design() == Design::Lattice => {
            crate::eprintln_best_effort!(
                "searching the rank-1 lattices of {} points for the lowest predicted variance",
                args.n
            );
            let design = lattice_design::design(v, args.n, args.dims)?;
            let points = PointSets::from_sets(args.dims, vec![design.points(); args.sets])?;
            (points, Vec::new(), Some(design))
        }
        _ => {
            let (points, reports) = optimize_with_bar(&setup, args)?;
            (points, reports, None)
        }
    };
    let seconds = t0.elapsed().as_secs_f64();
    let timed_out = optimize::time_limited(&reports);
    if timed_out > 0 {
        crate::eprintln_best_effort!(
            "warning: {timed_out} of {} sets stopped at --max-seconds ({} s) before the solver's other limits; the table depends on this machine's speed, and the command in its header may make another; raise --max-seconds",
            args.sets,
            number(args.max_seconds)
        );
    }
    let nudged = reports.iter().filter(|r| r.nudged).count();
    if nudged > 0 {
        crate::eprintln_best_effort!(
            "note: {nudged} of {} starts had no gradient (a stationary point of the loss, as a lattice or a line of points is by symmetry), so their free coordinates were moved by up to 1e-3/sqrt(N) at random before optimizing (\"nudged\" in the sidecar)",
            args.sets
        );
    }

    let mut fits = Vec::new();
    for term in &objective.terms {
        fits.push(metrics::fit(&points, term.proj, &term.grid, setup.method));
    }
    // On the wider grid, every projection the target itself constrains (xu and yv in 4D, xy in 2D;
    // not the strata terms).
    let target_terms = if args.dims == 4 { 2 } else { 1 };
    let wide_fits: Vec<_> = objective.terms[..target_terms.min(objective.terms.len())]
        .iter()
        .map(|term| metrics::fit(&points, term.proj, &wide, setup.method))
        .collect();

    let losses: Vec<f64> = match &lattice {
        // Every set is the same lattice.
        Some(design) => vec![objective.evaluate(&design.points()).loss],
        None => reports.iter().map(|r| r.loss).collect(),
    };
    let sidecar = serde_json::json!({
        "target_file": args.target,
        "target": target,
        "parameters": {
            "n": args.n, "dims": args.dims, "sets": args.sets, "seed": args.seed,
            "method": if args.exact { "exact".to_string() } else { format!("nufft eps={}", number(args.eps)) },
            "strata": (args.dims == 4).then_some(setup.strata), "repulsion": { "radius": setup.repulsion.radius, "weight": setup.repulsion.weight },
            "limits": setup.limits, "init": setup.init, "latin": setup.latin,
            "annular_weight": setup.annular_weight,
            // The shape's weights in use, defaults filled in (the target above shows null for a key
            // the file leaves out); a variance target has none.
            "dark_weight": (!matches!(target, Target::Variance(_))).then(|| target.dark_weight()),
            "falloff": (!matches!(target, Target::Variance(_))).then(|| target.falloff()),
            "grid_res": objective.terms.iter().map(|t| t.grid.res).collect::<Vec<_>>(),
        },
        "final_loss": {
            "mean": losses.iter().sum::<f64>() / losses.len() as f64,
            "max": losses.iter().copied().fold(f64::MIN, f64::max),
        },
        "fit": fits,
        "fit_twice_the_radius": wide_fits,
        "sets": reports,
        "lattice": lattice,
        "seconds": seconds,
    });
    let text = serde_json::to_string_pretty(&sidecar)
        .map_err(|e| Error::Numerical(format!("cannot encode the sidecar: {e}")))?;
    let refs: Vec<&Path> = outputs.iter().map(PathBuf::as_path).collect();
    // All five or none: a failure midway leaves no table without its sidecar.
    write_group(&refs, |staged| {
        write_points(&staged(&outputs[0]), &points)?;
        write_points(&staged(&outputs[1]), &points)?;
        write_header(&staged(&outputs[2]), &points, args, &target, timed_out)?;
        write_atomic(&staged(&outputs[3]), |w| writeln!(w, "{text}"))?;
        write_atomic(&staged(&outputs[4]), |w| {
            writeln!(w, "set,iter,seconds,loss,solver")?;
            for r in &reports {
                for row in &r.log {
                    writeln!(
                        w,
                        "{},{},{},{},{}",
                        r.set,
                        row.iter,
                        csv_number(row.seconds),
                        csv_number(row.loss),
                        row.solver
                    )?;
                }
            }
            Ok(())
        })
    })?;
    for (f, term) in fits.iter().zip(&objective.terms) {
        match f.variance_ratio {
            Some(v) => crate::eprintln_best_effort!(
                "{}: predicted variance {v:.4e} of random sampling's over the fit radius, |k| <= {} (the frequencies the loss weighs), over {}",
                f.proj,
                number((term.grid.fit_radius * 10.0).round() / 10.0),
                super::counted(f.sets, "set")
            ),
            None => crate::eprintln_best_effort!(
                "{}: dark mean P {:.4} over {}, annular error max {:.4} (rms {:.4}) over {}",
                f.proj,
                f.dark_mean,
                super::counted(f.dark_cells, "cell"),
                f.annular_max_error,
                f.annular_rms_error,
                super::counted(f.sets, "set")
            ),
        }
    }
    if let Some(d) = &lattice {
        let h = d.search_res / 2;
        crate::eprintln_best_effort!(
            "lattice z = {:?}: predicted variance {:.4e}, {:.4e} of random sampling's over the lattice search's wider grid, k1 and k2 in -{h}..{} (it also counts the lattice's peaks beyond the fit radius); every set is this lattice",
            d.generator,
            d.predicted_variance,
            d.variance_ratio,
            h - 1
        );
    }
    crate::eprintln_best_effort!(
        "wrote {} and its .txt, .h, .json and .log.csv ({} of {} points in {}D, {:.1} s)",
        outputs[0].display(),
        super::counted(args.sets, "set"),
        args.n,
        args.dims,
        seconds
    );
    Ok(())
}

/// Optimizes the sets of `setup`, with a progress bar over sets (shown when stderr is a terminal).
fn optimize_with_bar(
    setup: &Setup,
    args: &OptimizeArgs,
) -> Result<(PointSets, Vec<optimize::SetReport>)> {
    let bar = crate::progress::bar(args.sets as u64, "optimize sets");
    let out = optimize::optimize_sets(setup, args.sets, args.seed, &|r| {
        bar.set_message(format!("optimize: set {} loss {:.3e}", r.set, r.loss));
        bar.inc(1);
    });
    bar.finish_and_clear();
    out
}

/// The C name of the table `-o output`: `anisospec_` and the file stem, lower case, with every run
/// of characters that are not ASCII letters or digits made one `_` (the report's `slug`:
/// `out/Fan-A.npy` → `anisospec_fan_a`), so that tables of different names can be included in one
/// C file. A stem with no ASCII letter or digit (`ü.npy`) is refused: its name would be the bare
/// prefix, shared by every such table.
fn c_name(output: &Path) -> Result<String> {
    let stem = output.file_stem().unwrap_or_default().to_string_lossy();
    let slug = crate::compare::report::slug(&stem);
    if slug.is_empty() {
        return Err(Error::Usage(format!(
            "-o {}: the C header names its array after the file name, which has no ASCII letter or digit; choose a name such as table.npy",
            output.display()
        )));
    }
    Ok(format!("anisospec_{slug}"))
}

/// The `anisospec optimize` command that makes this table again when run from the same folder (its
/// paths are as given), every setting spelled out (defaults included, numbers in their shortest exact
/// form), for a POSIX shell: paths and names as `--flag=WORD`, so that none reads as a flag, and words
/// with spaces or shell characters in single quotes. A run cut short by `--max-seconds` depends on
/// the machine's speed, so its command may make a different table.
fn command_line(args: &OptimizeArgs) -> String {
    fn word(s: &str) -> String {
        let plain = !s.is_empty()
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || "-_./=,:+@%".contains(c));
        if plain {
            s.to_string()
        } else {
            format!("'{}'", s.replace('\'', "'\\''"))
        }
    }
    let mut parts = vec![
        format!(
            "anisospec optimize --target={}",
            word(&args.target.to_string_lossy())
        ),
        format!(
            "--dims {} -n {} --sets {} --seed {}",
            args.dims, args.n, args.sets, args.seed
        ),
    ];
    if let Some(init) = &args.init {
        parts.push(format!("--init={}", word(init)));
    }
    if args.latin {
        parts.push("--latin".into());
    }
    parts.push(format!(
        "--annular-weight {} --repulsion-radius {} --repulsion-weight {}",
        number(args.annular_weight),
        number(args.repulsion_radius),
        number(args.repulsion_weight),
    ));
    // A 2D table has no strata term (and refuses its flags).
    if args.dims == 4 {
        parts.push(format!(
            "--strat-radius {} --strat-weight {}",
            number(args.strat_radius),
            number(args.strat_weight)
        ));
    }
    parts.push(if args.exact {
        "--exact".to_string()
    } else {
        format!("--eps {}", number(args.eps))
    });
    parts.push(format!(
        "--max-iters {} --max-seconds {} --tol {}",
        args.max_iters,
        number(args.max_seconds),
        number(args.tol)
    ));
    parts.push(format!("--output={}", word(&args.output.to_string_lossy())));
    parts.join(" ")
}

/// A C header with the same numbers as the npy table: `static const double NAME[sets][n][dims]` and
/// the macros `NAME_SETS`, `NAME_N`, `NAME_DIMS` (upper case), with `NAME` from [`c_name`] of `-o`.
/// Its first line, a comment, is the [`command_line`] of the run; a second says when `timed_out`
/// sets stopped at `--max-seconds`; a third what the numbers are and how a renderer uses them (with
/// the shear a 4D `--latin` table or `target`'s own shear asks for). The
/// include guard `NAME_H_HASH` carries a hash of the numbers: two different tables whose file names
/// give the same `NAME` (`fan-a.npy`, `fan_a.npy`) then fail to compile together (a redefinition)
/// instead of one silently hiding the other, and the same table included twice is read once.
fn write_header(
    path: &Path,
    points: &PointSets,
    args: &OptimizeArgs,
    target: &Target,
    timed_out: usize,
) -> Result<()> {
    let name = c_name(&args.output)?;
    let upper = name.to_ascii_uppercase();
    // The shape too: the same numbers as [2][8][2] and [1][16][2] are different tables.
    let bytes: Vec<u8> = [points.sets(), points.n(), points.dims()]
        .iter()
        .flat_map(|&d| (d as u64).to_le_bytes())
        .chain(points.data().iter().flat_map(|c| c.to_le_bytes()))
        .collect();
    let guard = format!("{upper}_H_{:016X}", crate::output::stable_hash(&bytes));
    let coordinates = if points.dims() == 4 {
        "(x, y, u, v), x and y on the pixel, u and v on the lens, the target met on xu and yv"
    } else {
        "the two whose spectrum meets the target, the first along k1"
    };
    write_atomic(path, |w| {
        // A comment ends at the first "*/": a path holding one is broken up.
        writeln!(w, "/* {} */", command_line(args).replace("*/", "* /"))?;
        if timed_out > 0 {
            writeln!(
                w,
                "/* {timed_out} of {} sets stopped at --max-seconds: the command above may make another table on another machine or run. */",
                points.sets()
            )?;
        }
        // Where the table is sheared at use: by its variance target's own shear, or, a 4D --latin
        // table, by each pixel's oracle shear.
        let shear = match target {
            Target::Variance(v) if v.shear != 0.0 => format!(
                " Its target saw the integrands through the seam-free shear {}: move each shifted set \
                 through it (the transported shear of anisospec, src/points/shear.rs).",
                number(v.shear)
            ),
            _ if points.dims() == 4 && args.latin => " Made for the depth oracle's shear: move each \
                 shifted set through the seam-free shear by the pixel's shear (the transported shear of \
                 anisospec, src/points/shear.rs)."
                .to_string(),
            _ => String::new(),
        };
        writeln!(
            w,
            "/* {name}[set][point][dim]: {} of {} points in {}D, each coordinate in [0, 1): {coordinates}. \
             Each estimate takes one set and adds a random toroidal shift to it (mod 1).{shear} */",
            crate::cli::counted(points.sets(), "set"),
            points.n(),
            points.dims()
        )?;
        writeln!(w, "#ifndef {guard}\n#define {guard}")?;
        writeln!(w, "#define {upper}_SETS {}", points.sets())?;
        writeln!(w, "#define {upper}_N {}", points.n())?;
        writeln!(w, "#define {upper}_DIMS {}", points.dims())?;
        writeln!(
            w,
            "static const double {name}[{}][{}][{}] = {{",
            points.sets(),
            points.n(),
            points.dims()
        )?;
        for s in 0..points.sets() {
            writeln!(w, "  {{")?;
            for p in points.set(s).chunks_exact(points.dims()) {
                let cells: Vec<String> = p.iter().map(|c| format!("{c:.17e}")).collect();
                writeln!(w, "    {{{}}},", cells.join(", "))?;
            }
            writeln!(w, "  }},")?;
        }
        writeln!(w, "}};\n#endif")
    })
}
