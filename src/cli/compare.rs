//! `anisospec compare`: the study of optimized, sheared and classical samplers (the README's main job).

use crate::compare;
use crate::compare::config::CompareConfig;
use crate::error::Result;
use std::path::PathBuf;

/// Compare optimized, sheared and classical samplers on analytic integrands and renderer pixels.
#[derive(Debug, clap::Args)]
pub struct CompareArgs {
    /// A TOML study (keys as in the built-in default: --print-config prints them all). Every key is
    /// optional: one left out takes the built-in default's value; an unknown key is refused.
    /// Without it the built-in default suite runs: a few minutes on 2 cores.
    #[arg(long, conflicts_with = "full")]
    pub config: Option<PathBuf>,
    /// Run the paper-scale preset instead of the default (N up to 4096, 1000 realizations; hours).
    #[arg(long)]
    pub full: bool,
    /// Print the study as TOML on stdout and run nothing (no report, no cache, so --out and --cache are
    /// refused with it): the built-in default, with --full the paper-scale preset, with --config FILE
    /// that file's study with every key it leaves out filled in from the default; --seed sets its
    /// seed. Save it, edit it, and run it with --config.
    #[arg(long, conflicts_with_all = ["out", "cache"])]
    pub print_config: bool,
    /// Report folder, made if missing: report.md, plots/, spectra/, CSV and npy, and manifest.txt
    /// listing them. A new report replaces an earlier one there (the files its manifest lists go; your
    /// own files stay); a folder of other files is refused, and so is a --cache inside it.
    #[arg(long, default_value = "out/compare")]
    pub out: PathBuf,
    /// Cache of pixel references and optimized tables, reused across runs (default $ANISOSPEC_CACHE
    /// or out/cache, as for render).
    #[arg(long)]
    pub cache: Option<PathBuf>,
    /// Override the seed of the study (a whole number from 0 to 2^64 − 1).
    #[arg(long, value_parser = crate::cli::parse_seed, allow_negative_numbers = true)]
    pub seed: Option<u64>,
}

/// Runs `anisospec compare`.
pub fn run(args: &CompareArgs) -> Result<()> {
    let mut config = match (&args.config, args.full) {
        (Some(path), _) => CompareConfig::load(path)?,
        (None, true) => CompareConfig::full_suite(),
        (None, false) => CompareConfig::default_suite(),
    };
    if let Some(seed) = args.seed {
        config.seed = seed;
    }
    if args.print_config {
        out!("{}", config.to_toml()?);
        return Ok(());
    }
    let (cache, cache_source) = crate::render::pixel::cache_dir_and_source(args.cache.as_deref());
    // Checked here too, before `run` checks it as `--cache`, to name $ANISOSPEC_CACHE when it chose.
    crate::output::check_folder(&cache, cache_source, "cache")?;
    let started = std::time::Instant::now();
    let outcome = compare::run(&config, &args.out, &cache)?;
    crate::eprintln_best_effort!(
        "compared {} on {} in {:.1} s (report included); report in {}",
        super::counted(
            outcome.studies.len() / outcome.subjects.len().max(1),
            "sampler"
        ),
        super::counted(outcome.subjects.len(), "integrand"),
        started.elapsed().as_secs_f64(),
        args.out.join("report.md").display()
    );
    Ok(())
}
