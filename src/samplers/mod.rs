//! Sampling patterns: classical 2D and 4D constructions behind one [`Sampler`] trait, and a registry
//! that builds them by name.
//!
//! Every sampler draws a set from the generator it is handed, so a set is a function of the seed and
//! the set's index only ([`generate_sets`]), whatever the thread count.

use crate::error::{Error, Result};
use crate::points::PointSets;
use crate::rng::{self, Rng};
use rayon::prelude::*;

/// A construction of `N`-point sets on the unit torus.
pub trait Sampler: Send + Sync {
    /// The registry name, e.g. `mj` or `padded-cmj`.
    fn name(&self) -> String;

    /// Dimensions of the points (2 or 4).
    fn dims(&self) -> usize;

    /// `Ok(())` if the construction exists for `n` points, else `Err(nearest)` with the nearest `n` for
    /// which it does.
    fn check_n(&self, n: usize) -> std::result::Result<(), usize>;

    /// One set of `n` points, `[n, dims]` row-major, in `[0,1)^dims`. `n` has passed [`Sampler::check_n`].
    fn generate(&self, n: usize, rng: &mut Rng) -> Vec<f64>;
}

/// Checks `n` for `sampler`, with a message naming the nearest valid `n`.
pub fn validate_n(sampler: &dyn Sampler, n: usize) -> Result<()> {
    if n == 0 {
        return Err(Error::Usage(format!(
            "-n 0 asks for no points; {} needs at least one (try -n {})",
            sampler.name(),
            nearest_or_one(sampler, 1)
        )));
    }
    sampler.check_n(n).map_err(|nearest| {
        Error::Usage(format!(
            "{} cannot make {n} points; the nearest N it allows is {nearest}",
            sampler.name()
        ))
    })
}

fn nearest_or_one(sampler: &dyn Sampler, n: usize) -> usize {
    sampler.check_n(n).map_or_else(|m| m, |_| n)
}

/// Draws `sets` independent sets of `n` points. Set `s` uses stream `s` of `seed`: the result does not
/// depend on the number of threads.
pub fn generate_sets(sampler: &dyn Sampler, n: usize, sets: usize, seed: u64) -> Result<PointSets> {
    validate_n(sampler, n)?;
    if sets == 0 {
        return Err(Error::Usage(
            "--sets 0 asks for nothing; give at least one set".into(),
        ));
    }
    let all: Vec<Vec<f64>> = (0..sets)
        .into_par_iter()
        .map(|s| sampler.generate(n, &mut rng::stream(seed, s as u64)))
        .collect();
    PointSets::from_sets(sampler.dims(), all)
}
