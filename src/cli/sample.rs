//! `anisospec sample`: draw point sets and write them as npy or text.

use super::{sampler_with_shear, ShearArgs};
use crate::error::Result;
use crate::output::check_outputs;
use crate::points::io::{write_points, Format};
use crate::samplers::{self, generate_sets};
use std::path::PathBuf;

/// Draw point sets from a sampler.
#[derive(Debug, clap::Args)]
pub struct SampleArgs {
    /// Sampler name (see `anisospec samplers`), e.g. mj, sobol, padded-cmj, oa, or table:PATH
    /// (optimized sets), or lattice:Z1:Z2 (2D) or lattice:Z1:Z2:Z3:Z4 (4D) (a rank-1 lattice with
    /// that generating vector).
    #[arg(long)]
    pub sampler: String,
    /// Dimensions of each point: 2 (x,y) or 4 (x,y,u,v).
    #[arg(long, default_value_t = 2)]
    pub dims: usize,
    /// Points per set, N (N × sets × D at most 2^28 coordinates). Samplers with a construction
    /// constraint (e.g. jittered needs a square) name the nearest valid N if this one is not.
    #[arg(short = 'n', long = "n", value_parser = super::parse_count, allow_negative_numbers = true)]
    pub n: usize,
    /// Number of independent sets to draw (N × sets × D at most 2^28 = 268435456 coordinates).
    #[arg(long, default_value_t = 1, value_parser = crate::cli::parse_whole, allow_negative_numbers = true)]
    pub sets: usize,
    /// Random seed; set s uses stream s of this seed, so the same seed gives the same bits on any
    /// number of threads.
    #[arg(long, default_value_t = 1, value_parser = crate::cli::parse_seed, allow_negative_numbers = true)]
    pub seed: u64,
    #[command(flatten)]
    pub shear: ShearArgs,
    /// Output file: .npy (float64 [sets, N, D]) or .txt (one point per line, '#' between sets).
    #[arg(short = 'o', long)]
    pub output: PathBuf,
}

/// Runs `anisospec sample`.
pub fn run(args: &SampleArgs) -> Result<()> {
    // A name that is no file first (-o .txt has no extension to tell), then the format, then the
    // path's folders.
    crate::output::check_file_name(&args.output, &["npy", "txt"])?;
    Format::of(&args.output)?;
    check_outputs(&[&args.output], &samplers::input_files(&args.sampler))?;
    let sampler = sampler_with_shear(&args.sampler, args.dims, &args.shear)?;
    let sets = generate_sets(sampler.as_ref(), args.n, args.sets, args.seed)?;
    write_points(&args.output, &sets)?;
    crate::eprintln_best_effort!(
        "wrote {} of {} {}D {} from {} to {}",
        super::counted(sets.sets(), "set"),
        sets.n(),
        sets.dims(),
        if sets.n() == 1 { "point" } else { "points" },
        sampler.name(),
        args.output.display()
    );
    Ok(())
}
