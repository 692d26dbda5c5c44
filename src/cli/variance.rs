//! `anisospec variance`: the Fourier-domain variance prediction of a sampler on an integrand, with the
//! directional-cone breakdown and the predicted slope.

use super::{sampler_with_shear, ShearArgs};
use crate::error::Result;
use crate::integrands::parse;
use crate::samplers;
use crate::variance::{predict_with_progress, write_csv, VarianceConfig, VariancePrediction};
use std::path::PathBuf;

/// Above this share of the predicted variance (a fraction), the white-noise tail is reported as
/// dominating. Half, because the tail assumes the sampler's spectrum is white (`P = 1`) beyond the grid,
/// while a jittered-like sampler's spectrum is still below 1 just past a grid of a few `N`: if the true tail
/// were 0, a prediction whose tail is a share `s` of it would overstate the variance by `1/(1 − s)`, so
/// past one half that assumption alone could be off by more than a factor 2, more than the measured grid
/// sum it is added to. The README example (`nrooks` on `step:theta=0`, K = 128) shows both sides: at
/// N = 64 the tail is 31 % and `--res-per-n 4` moves the prediction by 0.1 %; at N = 256 it is 83 % and
/// the same flag lowers the prediction from 7.4e-6 to 5.1e-6 (measured MSE 5.0e-6, R = 2000).
pub const TAIL_WARNING_SHARE: f64 = 0.5;

/// Predict Var(N) = (1/N) Σ_k |f̂(k)|² E[P_N(k)] for a sampler on an integrand, split by direction.
#[derive(Clone, Debug, clap::Args)]
pub struct VarianceArgs {
    /// Sampler (see `anisospec samplers`); its dimension is the integrand's.
    #[arg(long)]
    pub sampler: String,
    /// Integrand, NAME:key=value,... (see `anisospec integrands`), e.g. step:theta=30.
    #[arg(long)]
    pub integrand: String,
    /// Sample counts N, comma-separated, e.g. 16,64,256,1024 (N × D at most 2^28 coordinates).
    #[arg(
        short = 'n',
        long = "n",
        value_delimiter = ',',
        required = true,
        value_parser = crate::cli::parse_count,
        allow_negative_numbers = true
    )]
    pub n: Vec<usize>,
    /// Frequency grid side K (even, at most 8192; with --shear at most 1024, as the integrand pulled
    /// back through the shear is sampled on 4K points per side) in each projection; the rest of the sum
    /// is estimated as white noise (Parseval: Var(f) less the grid's sum of |f̂|², over N) and reported
    /// as the tail. Var(f) is exact, except for sums of overlapping shapes: there it is estimated by
    /// randomized QMC (the mean of (f − ∫f)² over 2^21 points), whose standard error enters the
    /// stderr column.
    #[arg(long, default_value_t = 128, value_parser = crate::cli::parse_whole, allow_negative_numbers = true)]
    pub res: usize,
    /// Grow the grid with N: K = max(--res, M·N), with K² times the integrand's planes at most 8192².
    /// Discontinuous integrands under stratified samplers need K of a few N for an accurate sum; cheap
    /// for edges aligned with an axis. Off by default (K = --res at every N).
    #[arg(long, value_name = "M")]
    pub res_per_n: Option<usize>,
    /// Realizations of the sampler averaged for E[P_N(k)]; 2 to 1000000.
    #[arg(long, default_value_t = 100, value_parser = crate::cli::parse_whole, allow_negative_numbers = true)]
    pub realizations: usize,
    /// Number of directional cones (cone c covers the angles [c − ½, c + ½)·180°/M: cone 0 is centred
    /// on the k1 axis, and a k on an edge goes to the next cone up); 1 to 360.
    /// The printed table gives each cone's share, in %, of the sum over the grid; the tail beyond
    /// the grid is not split by cone. With --shear the directions are the unsheared pattern's: an
    /// edge the shear matches lies on its k1 axis, in cone 0.
    #[arg(long, default_value_t = 4, value_parser = crate::cli::parse_whole, allow_negative_numbers = true)]
    pub cones: usize,
    /// Use the exact DFT instead of the NUFFT for full-grid planes: a plane is summed over its whole
    /// K × K grid at once when more than a quarter of the grid's frequencies carry the integrand's
    /// |f̂|²; a sparser plane is always summed exactly at those frequencies alone, which --exact and
    /// --eps do not change.
    #[arg(long, conflicts_with = "eps")]
    pub exact: bool,
    /// NUFFT tolerance (relative error of P), from 1e-12 to 1e-1, for full-grid planes (more than a
    /// quarter of the K × K grid carries |f̂|²; see --exact).
    #[arg(long, default_value = "1e-9", allow_negative_numbers = true)]
    pub eps: f64,
    /// Random seed of the realizations.
    #[arg(long, default_value_t = 1, value_parser = crate::cli::parse_seed, allow_negative_numbers = true)]
    pub seed: u64,
    // The sampler sheared as --shear and --shear-mode say (4D integrands on xu and yv only): the
    // prediction is made in the unsheared pattern's frame, for the integrand pulled back through the
    // shear, sampled on a grid of 4K (at most 4096) per side, so K is at most 1024. (clap shows no
    // doc comment of a flattened field: the command's long help in main.rs, --res and --cones say it.)
    #[command(flatten)]
    pub shear: ShearArgs,
    /// Write the table as CSV: n, variance, stderr, grid (the sum over the grid), tail, then cone_c and
    /// cone_c_stderr per cone (variances, in squared integrand units, not shares).
    #[arg(short = 'o', long)]
    pub output: Option<PathBuf>,
}

/// Runs the prediction and prints it.
pub fn run(args: &VarianceArgs) -> Result<()> {
    crate::cli::increasing_counts(&args.n)?;
    if let Some(out) = &args.output {
        crate::cli::require_extension(out, "-o", "csv", "the prediction as a CSV table")?;
        let mut inputs = samplers::input_files(&args.sampler);
        inputs.extend(crate::integrands::spec::input_files(&args.integrand));
        crate::output::check_outputs(&[out], &inputs)?;
    }
    let f = parse(&args.integrand)?;
    let sampler = sampler_with_shear(&args.sampler, f.dims(), &args.shear)?;
    let method = crate::cli::fourier_method(args.exact, args.eps)?;
    let cfg = VarianceConfig {
        res: args.res,
        res_per_n: args.res_per_n,
        realizations: args.realizations,
        cones: args.cones,
        seed: args.seed,
        method,
    };
    let bar = crate::progress::bar(
        // Saturating: a count above the limit is refused inside, after the bar is made.
        args.n.len().saturating_mul(args.realizations) as u64,
        "variance realizations",
    );
    let pred = predict_with_progress(sampler.as_ref(), f.as_ref(), &args.n, &cfg, &bar)?;
    bar.finish_and_clear();
    let grid = match args.res_per_n {
        Some(m) => format!("max({}, {m}·N)", args.res),
        None => args.res.to_string(),
    };
    outln!(
        "sampler {} on {} (planes {}, K = {grid}, R = {})",
        pred.sampler,
        pred.integrand,
        pred.planes
            .iter()
            .map(|p| p.name())
            .collect::<Vec<_>>()
            .join(", "),
        args.realizations
    );
    out!(
        "{:>7} {:>12} {:>10} {:>11}",
        "N",
        "variance",
        "stderr",
        "tail"
    );
    for c in 0..args.cones {
        out!(" {:>8}", format!("cone{c}%"));
    }
    outln!();
    for p in &pred.points {
        out!(
            "{:>7} {:>12.4e} {:>10.2e} {:>11.3e}",
            p.n,
            p.variance,
            p.stderr,
            p.tail
        );
        for (c, rounding) in p.cones.iter().zip(&p.cone_rounding) {
            if p.grid > 0.0 && c > rounding {
                out!(" {:>8.1}", 100.0 * c / p.grid);
            } else {
                // Zero within rounding: no share to print.
                out!(" {:>8}", "—");
            }
        }
        outln!();
    }
    let at_rounding: Vec<String> = pred
        .points
        .iter()
        .filter(|p| p.is_rounding())
        .map(|p| format!("{} (error bound {:.1e})", p.n, p.rounding))
        .collect();
    // With the NUFFT the bound holds its error at --eps; with --exact, f64 rounding's alone.
    let (bound, zero_spectrum) = match method {
        crate::spectrum::Method::Nufft { .. } => (
            "what f64 rounding and the NUFFT's error at --eps can put into it",
            "the sampler's spectrum is 0, or below the NUFFT's error at --eps, wherever the integrand has energy (a lattice on a smooth integrand); --exact or a smaller --eps tells the two apart",
        ),
        crate::spectrum::Method::Exact => (
            "what f64 rounding can put into it",
            "the sampler's spectrum is 0 wherever the integrand has energy (a lattice on a smooth integrand)",
        ),
    };
    match &pred.fit {
        Some(fit) => match fit.interval() {
            Some((lo, hi)) => outln!(
                "predicted slope {:.3} (95% CI {lo:.3} .. {hi:.3})",
                fit.slope
            ),
            None => outln!(
                "predicted slope {:.3} (95% CI —: at one or more N the realizations differ by no more than the spectrum method's own error (--eps, or f64 rounding with --exact), as for a set whose spectrum is the same for every shift (e.g. a lattice); no interval)",
                fit.slope
            ),
        },
        None if !at_rounding.is_empty() => outln!(
            "no predicted slope: at N = {} the predicted variance is not above {bound}, so its digits are not a value: {}",
            at_rounding.join(", "),
            // Only here (a rare case) is Var(f) computed, by quadrature where it has no closed form.
            if crate::integrands::variance_reference(f.as_ref()).value > 0.0 {
                zero_spectrum
            } else {
                "the integrand has no energy to integrate (Var f = 0 in f64: it is constant, or its feature is too small for f64), so every sampler integrates it exactly"
            }
        ),
        None => outln!(
            "no predicted slope (a log-log fit needs two or more distinct N and a positive variance at each)"
        ),
    }
    for (c, fit) in pred.cone_fits.iter().enumerate() {
        if let Some(fit) = fit {
            let angle = c as f64 * 180.0 / args.cones as f64;
            if fit.errors_defined {
                outln!(
                    "  cone {c} ({angle:.0}°) slope {:.3} ± {:.3}",
                    fit.slope,
                    fit.stderr
                );
            } else {
                outln!("  cone {c} ({angle:.0}°) slope {:.3} ± —", fit.slope);
            }
        }
    }
    warn_dominant_tail(&pred, args.shear.shear.is_some());
    if let Some(out) = &args.output {
        write_csv(out, &pred)?;
    }
    Ok(())
}

/// Warns on stderr, in one line, at every `N` whose tail is more than [`TAIL_WARNING_SHARE`] of the
/// prediction: its share, its grid, the `P = 1` assumption behind it and the flags that push it out
/// (within K = 1024 for a sheared sampler, whose pulled-back integrand allows no more).
fn warn_dominant_tail(pred: &VariancePrediction, sheared: bool) {
    let dominated: Vec<String> = pred
        .points
        .iter()
        .filter_map(|p| {
            p.tail_share()
                .filter(|&s| s > TAIL_WARNING_SHARE)
                .map(|s| format!("N = {} (tail {:.0} %, K = {})", p.n, 100.0 * s, p.res))
        })
        .collect();
    if dominated.is_empty() {
        return;
    }
    let fix = if sheared {
        format!(
            "raise --res or --res-per-n (K = max(--res, M·N)) to push the tail out, up to K = {} with --shear; past it, measure with `anisospec converge`",
            crate::variance::MAX_PULLBACK_SAMPLES / 4
        )
    } else {
        "raise --res-per-n (K = max(--res, M·N)) or --res to push the tail out".to_string()
    };
    crate::eprintln_best_effort!(
        "warning: the white-noise tail is more than {:.0} % of the predicted variance at {}: it assumes the sampler's spectrum is white (P = 1) beyond the frequency grid, which overstates the variance of a sampler whose spectrum is still below 1 there (jittered or N-rooks past a grid of a few N) and understates it where the spectrum has peaks there (a lattice's P = N); {fix}",
        100.0 * TAIL_WARNING_SHARE,
        dominated.join(", ")
    );
}
