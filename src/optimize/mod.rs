//! The optimizer (DESIGN §6): moves the points of a set until its spectra in the projections that
//! matter match their targets, then writes tables a renderer can use.
//!
//! - [`loss`]: the spectral loss and its exact gradient (type-1 + type-2 transforms), and a short-range
//!   toroidal repulsion (kiddo periodic queries).
//! - [`solver`]: argmin L-BFGS in rounds, with steepest descent as the fallback; limits on iterations,
//!   time and tolerance; a log of loss against iteration and time.
//! - [`metrics`]: the fit of the expected spectrum to the target.
//! - [`latin`]: holds the first coordinates N-stratified, at their strata's centres (tables used
//!   through the seam-free shear need it).
//! - [`optimize_sets`]: many sets in parallel, set `s` seeded by `rng::stream(seed, s)`.
//!
//! In 2D the target applies to the set's two coordinates. In 4D it applies to `xu` and `yv`, and `xy`
//! and `uv` are kept stratified by a blue-noise dark-disc target.

pub mod latin;
pub mod lattice_design;
pub mod loss;
pub mod metrics;
pub mod solver;

use crate::error::{Error, Result};
use crate::points::{PointSets, Projection};
use crate::rng::{self, Rng};
use crate::spectrum::Method;
use crate::targets::{BlueNoise, Target};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use loss::{Objective, Repulsion, Term};
use rand::Rng as _;
use rayon::prelude::*;
use serde::Serialize;
pub use solver::{Limits, LogRow, DEFAULT_LIMITS};

/// How the 4D `xy` and `uv` projections are kept stratified.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Strata {
    /// Dark-disc radius of the blue-noise target, in units of `sqrt(N)`.
    pub radius: f64,
    /// Weight of each of the two projections' losses.
    pub weight: f64,
}

/// Default stratification of `xy` and `uv`: a dark disc of radius 0.35 `sqrt(N)`, weight 1.
pub const DEFAULT_STRATA: Strata = Strata {
    radius: 0.35,
    weight: 1.0,
};

impl Default for Strata {
    fn default() -> Self {
        DEFAULT_STRATA
    }
}

/// Everything that defines an optimization apart from the seed.
#[derive(Clone, Debug)]
pub struct Setup {
    /// The target for the 2D set, or for `xu` and `yv` in 4D.
    pub target: Target,
    /// Points per set.
    pub n: usize,
    /// 2 or 4.
    pub dims: usize,
    /// 4D only: the `xy` / `uv` stratification target.
    pub strata: Strata,
    /// The repulsion term.
    pub repulsion: Repulsion,
    /// Fourier method for the loss.
    pub method: Method,
    /// Stopping rules.
    pub limits: Limits,
    /// The sampler the starts are drawn from (a name for [`crate::samplers::build`]), or `None` for
    /// uniform random starts. A stratified start (e.g. `mj`) begins with dark axes, which a target
    /// around the `k1` axis keeps and widens; random starts end in poorer local minima.
    pub init: Option<String>,
    /// Hold the first coordinate of each targeted pair (2D: the first coordinate; 4D: `x` and `y`)
    /// where the start put them, N-stratified and centred (see [`latin`]), and move only the others:
    /// the `k1` axis of the target's projections then stays dark up to `N`, far beyond the loss's
    /// grid, and in 4D the `xy` projection keeps the start's structure (a (0,2)-net from a PMJ02
    /// start).
    pub latin: bool,
    /// Weight `λ_a` of the loss's annular-mean term (see [`loss`]); 0 switches it off.
    pub annular_weight: f64,
}

/// Default repulsion: radius 0.25 of the mean spacing, strength 0.1. Stronger or wider repulsion
/// raises a blue-noise peak near `|k| ≈ sqrt(N)` that the flat part of a target does not want
/// (measured: radius 0.4, strength 1 left an annular error of 0.17 at `ν ≈ 0.6` on the double wedge).
pub const DEFAULT_REPULSION: Repulsion = Repulsion {
    radius: 0.25,
    weight: 0.1,
};

/// The largest weight accepted for a loss term.
pub const MAX_WEIGHT: f64 = 1e6;

/// Default weight `λ_a` of the annular-mean term. At 1 the term is as large as the cells' mean
/// squared error when every cell of every annulus is off by the same amount; the cells' own
/// periodogram noise then hides a bias of 0.1. Measured (2D, 8 sets, N = 1024, 3000 iterations): the
/// largest annular error of a widened hairline (opening 0.025, length 2.2) is 0.121 at 0, 0.091 at 1, 0.047 at 10 and 0.008 at
/// 100 (a double wedge with a disc of 0.3: 0.123, 0.067, 0.028, 0.003), with the dark means
/// unchanged (0.011, 0.005).
pub const DEFAULT_ANNULAR_WEIGHT: f64 = 100.0;

/// Largest repulsion radius, in mean spacings `1/sqrt(N)`: just under `sqrt(2/sqrt(3))` = 1.0746, the
/// spacing of a hexagonal packing, the widest at which N points can all stand a radius apart. Beyond
/// it the bounded repulsion lowers its energy by stacking points (measured at N = 256, 300
/// iterations, weight 1e6: nearest neighbours 1.00 spacing on average at radius 1, 0.89 at 1.25 with
/// some points coincident, 0.19 at 1.5; at N = 1024, radius 2 and weight 0.1, 2 % of the points
/// within 0.1 spacing of another).
pub const MAX_REPULSION_RADIUS: f64 = 1.07;

impl Setup {
    /// The objective: the target on `xy` (2D) or on `xu` and `yv` plus the strata on `xy` and `uv`
    /// (4D). Fails for bad dims, N, or a target out of reach.
    pub fn objective(&self) -> Result<Objective> {
        if let Method::Nufft { eps } = self.method {
            Method::nufft(eps)?;
        }
        for (name, v) in [
            ("--repulsion-radius", self.repulsion.radius),
            ("--strat-radius", self.strata.radius),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::Usage(format!(
                    "{name} {}: give a finite radius >= 0",
                    crate::error::number(v)
                )));
            }
        }
        if self.repulsion.radius > MAX_REPULSION_RADIUS {
            return Err(Error::Usage(format!(
                "--repulsion-radius {}: give at most {MAX_REPULSION_RADIUS} mean spacings (the repulsion keeps neighbours apart; N points cannot all stand farther apart than about 1.07 spacings, and a wider repulsion stacks them into clusters)",
                crate::error::number(self.repulsion.radius)
            )));
        }
        for (name, v) in [
            ("--repulsion-weight", self.repulsion.weight),
            ("--strat-weight", self.strata.weight),
            ("--annular-weight", self.annular_weight),
        ] {
            if !(v.is_finite() && (0.0..=MAX_WEIGHT).contains(&v)) {
                return Err(Error::Usage(format!(
                    "{name} {}: give a weight from 0 to {MAX_WEIGHT:e} (the loss's terms are of order 1; larger weights overflow the line search)",
                    crate::error::number(v)
                )));
            }
        }
        let grid = self.target.grid(self.n)?;
        let terms = match self.dims {
            2 => vec![Term {
                proj: Projection::XY,
                grid,
                weight: 1.0,
            }],
            4 => {
                let mut t = vec![
                    Term {
                        proj: Projection::XU,
                        grid: grid.clone(),
                        weight: 1.0,
                    },
                    Term {
                        proj: Projection::YV,
                        grid,
                        weight: 1.0,
                    },
                ];
                if self.strata.weight > 0.0 {
                    let sg = self.strata_grid()?;
                    for proj in [Projection::XY, Projection::UV] {
                        t.push(Term {
                            proj,
                            grid: sg.clone(),
                            weight: self.strata.weight,
                        });
                    }
                }
                t
            }
            d => {
                return Err(Error::Usage(format!(
                    "--dims {d}: the optimizer makes 2D or 4D sets; use --dims 2 or --dims 4"
                )))
            }
        };
        Ok(Objective {
            n: self.n,
            dims: self.dims,
            terms,
            repulsion: self.repulsion,
            annular_weight: self.annular_weight,
            method: self.method,
        })
    }
}

impl Strata {
    /// The blue-noise grid of this 4D strata term on `xy` and `uv` at `n` points; its errors are the
    /// blue-noise target's (e.g. a disc that reaches no frequency cell at a small `n`).
    pub fn grid(&self, n: usize) -> Result<crate::targets::TargetGrid> {
        let strata = Target::BlueNoise(BlueNoise {
            radius: self.radius,
            dark_weight: None,
            falloff: None,
        });
        strata.validate().and_then(|()| strata.grid(n))
    }
}

impl Setup {
    /// The blue-noise grid of the 4D strata term on `xy` and `uv`; its errors name that term and its
    /// flags, since the user gave no blue-noise target.
    fn strata_grid(&self) -> Result<crate::targets::TargetGrid> {
        self.strata.grid(self.n).map_err(|e| match e {
                // A flag's problem, not a target file's: a usage error, its advice in flags.
                Error::Usage(m) | Error::Input(m) => Error::Usage(format!(
                    "the 4D strata term (a blue-noise disc of radius --strat-radius {} on xy and uv): {}; or drop the term with --strat-weight 0",
                    crate::error::number(self.strata.radius),
                    m.replace("lower radius", "lower --strat-radius")
                        .replace("raise radius", "raise --strat-radius")
                )),
                other => other,
            })
    }
}

/// How many of `reports` stopped at their wall-time limit (see [`solver::TIME_LIMIT_STOP`]): those
/// sets depend on the machine's speed.
pub fn time_limited(reports: &[SetReport]) -> usize {
    reports
        .iter()
        .filter(|r| r.stop.starts_with(solver::TIME_LIMIT_STOP))
        .count()
}

/// The outcome for one set.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SetReport {
    /// Index of the set.
    pub set: usize,
    /// Loss at the start (after the nudge off a stationary start, if any: see `nudged`).
    pub initial_loss: f64,
    /// Final loss (spectral plus repulsion).
    pub loss: f64,
    /// Final spectral loss.
    pub spectral: f64,
    /// Final repulsion energy.
    pub repulsion: f64,
    /// Solver iterations.
    pub iterations: u64,
    /// Loss evaluations.
    pub evaluations: u64,
    /// Wall time in seconds.
    pub seconds: f64,
    /// Why it stopped.
    pub stop: String,
    /// Whether the fallback solver ran.
    pub fallback_used: bool,
    /// Points of the start that coincided with another in a constrained projection and were moved
    /// apart by a tiny random step (a duplicate has the same gradient as its twin and never leaves it).
    pub separated: usize,
    /// Whether the start was a stationary point of the loss and every free coordinate was moved by
    /// a tiny random step to leave it (see [`leave_stationary`]).
    pub nudged: bool,
    /// Loss against iteration and time.
    #[serde(skip)]
    pub log: Vec<LogRow>,
}

/// Moves apart points that coincide (within `1e-9 / sqrt(N)`) with a lower-numbered point in any
/// constrained projection, by a uniform step in `±0.5e-3 / sqrt(N)` per coordinate. Returns how many
/// moved.
fn separate_duplicates(objective: &Objective, set: &mut [f64], rng: &mut Rng) -> usize {
    let dims = objective.dims;
    let n = objective.n;
    let close = 1e-9 / (n as f64).sqrt();
    let step = 1e-3 / (n as f64).sqrt();
    let mut moved = vec![false; n];
    for proj in objective.constrained_projections() {
        let pts = loss::projected(set, dims, proj);
        let tree: ImmutableKdTree<f64, 2> =
            ImmutableKdTree::new_from_slice(&pts).expect("finite points build a tree");
        for (i, p) in pts.iter().enumerate() {
            let twins = tree
                .query(p)
                .periodic_boundary_condition(&[1.0, 1.0])
                .within::<SquaredEuclidean<f64>>(close * close)
                .execute();
            if twins.iter().any(|q| (q.item as usize) < i) {
                moved[i] = true;
            }
        }
    }
    for (i, m) in moved.iter().enumerate() {
        if *m {
            for c in &mut set[i * dims..(i + 1) * dims] {
                *c = crate::points::wrap(*c + step * (rng.random::<f64>() - 0.5));
            }
        }
    }
    moved.iter().filter(|&&m| m).count()
}

/// The coordinates a Latin constraint keeps N-stratified: the first of each targeted pair (2D: the
/// first coordinate; 4D: `x` of `xu` and `y` of `yv`).
fn latin_coords(dims: usize) -> Vec<usize> {
    if dims == 4 {
        vec![Projection::XU.a, Projection::YV.a]
    } else {
        vec![0]
    }
}

/// Largest gradient, per unit of a coordinate and relative to the loss, at which a start counts as
/// stationary: a lattice or a line, whose symmetry cancels the gradient, has only rounding (or the
/// NUFFT's error) there. Starts in general position lie far above it: the Sobol and PMJ02 starts of
/// compare's default tables are not nudged (their tables at N = 16 and 64 rebuilt bit for bit).
const STATIONARY_GRADIENT: f64 = 1e-6;

/// Moves `set` off a stationary point of the loss: where no free coordinate (not `frozen`) has a
/// gradient above [`STATIONARY_GRADIENT`] times the loss while the loss is above 0, as at a rank-1
/// lattice or a line of points (the solver would stop there at once, "converged", and hand the start
/// back), each free coordinate moves by a uniform step of up to `1e-3 / sqrt(N)` drawn from `rng`.
/// Returns whether it moved.
fn leave_stationary(
    objective: &Objective,
    set: &mut [f64],
    frozen: Option<&[bool]>,
    rng: &mut Rng,
) -> bool {
    let at = objective.evaluate(set);
    let is_free = |i: usize| frozen.is_none_or(|f| !f[i]);
    let steepest = at
        .gradient
        .iter()
        .enumerate()
        .filter(|&(i, _)| is_free(i))
        .map(|(_, g)| g.abs())
        .fold(0.0, f64::max);
    let any_free = (0..set.len()).any(is_free);
    if !(any_free && at.loss > 0.0 && steepest <= STATIONARY_GRADIENT * at.loss) {
        return false;
    }
    let step = 1e-3 / (objective.n as f64).sqrt();
    for (i, c) in set.iter_mut().enumerate() {
        if is_free(i) {
            *c = crate::points::wrap(*c + step * (2.0 * rng.random::<f64>() - 1.0));
        }
    }
    true
}

/// Optimizes one set from `start` (`[n, dims]`, in `[0,1)`), with the coordinates of `latin_coords` held (after
/// [`latin::stratify`]) if `latin`. `rng` moves apart duplicate points. Fails with `Error::Numerical` if the start's loss is not finite.
pub fn optimize_set(
    objective: &Objective,
    start: &[f64],
    limits: &Limits,
    latin: bool,
    index: usize,
    rng: &mut Rng,
) -> Result<(Vec<f64>, SetReport)> {
    if start.len() != objective.n * objective.dims {
        return Err(Error::Input(format!(
            "the start set has {} coordinates; {} points in {}D need {}",
            start.len(),
            objective.n,
            objective.dims,
            objective.n * objective.dims
        )));
    }
    if let Some(c) = start.iter().find(|c| !c.is_finite()) {
        return Err(Error::Input(format!(
            "the start set holds the coordinate {c}; every coordinate must be finite"
        )));
    }
    let mut set = start.to_vec();
    let separated = separate_duplicates(objective, &mut set, rng);
    let check = objective.evaluate(&set);
    if !check.loss.is_finite() {
        return Err(Error::Numerical(format!(
            "set {index}: the loss at the start is {}; the optimizer cannot start from it",
            check.loss
        )));
    }
    let frozen = latin.then(|| {
        let (n, dims) = (objective.n, objective.dims);
        let coords = latin_coords(dims);
        latin::stratify(&mut set, n, dims, &coords);
        latin::frozen(n, dims, &coords)
    });
    let nudged =
        limits.max_iters > 0 && leave_stationary(objective, &mut set, frozen.as_deref(), rng);
    let out = solver::minimize(objective, &set, limits, frozen.as_deref());
    let report = SetReport {
        set: index,
        initial_loss: out.initial.loss,
        loss: out.last.loss,
        spectral: out.last.spectral,
        repulsion: out.last.repulsion,
        iterations: out.iterations,
        evaluations: out.evaluations,
        seconds: out.seconds,
        stop: out.stop,
        fallback_used: out.fallback_used,
        separated,
        nudged,
        log: out.log,
    };
    Ok((out.set, report))
}

/// Optimizes `sets` sets in parallel from starts drawn from `setup.init` (uniform random if `None`);
/// set `s` draws its start from `rng::stream(seed, s)`, so the result does not depend on the thread count (as long as the time limit
/// does not bind). `on_done` is called once per finished set (e.g. to advance a progress bar).
pub fn optimize_sets(
    setup: &Setup,
    sets: usize,
    seed: u64,
    on_done: &(dyn Fn(&SetReport) + Sync),
) -> Result<(PointSets, Vec<SetReport>)> {
    if sets == 0 {
        return Err(Error::Usage(
            "--sets 0 asks for nothing; give at least one set".into(),
        ));
    }
    crate::points::coordinate_count(sets, setup.n, setup.dims).map_err(Error::Usage)?;
    let objective = setup.objective()?;
    let init = match &setup.init {
        Some(name) => {
            let sampler = crate::samplers::build(name, setup.dims)?;
            crate::samplers::validate_n(sampler.as_ref(), setup.n).map_err(|e| {
                // The nearest N the sampler allows may be 1, which no optimized set has.
                match (e, sampler.check_n(setup.n)) {
                    (Error::Usage(m), Err(1)) => {
                        match (2..1 << 16).find(|&m| sampler.check_n(m).is_ok()) {
                            Some(m2) => Error::Usage(format!(
                                "{m}, but an optimized set needs at least 2 points: use N = {m2}, the smallest above 1 that {name} makes"
                            )),
                            None => Error::Usage(m),
                        }
                    }
                    (e, _) => e,
                }
            })?;
            Some(sampler)
        }
        None => None,
    };
    let results: Vec<Result<(Vec<f64>, SetReport)>> = (0..sets)
        .into_par_iter()
        .map(|s| {
            let mut rng = rng::stream(seed, s as u64);
            let start: Vec<f64> = match &init {
                Some(sampler) => sampler.generate(setup.n, &mut rng),
                None => (0..setup.n * setup.dims)
                    .map(|_| rng.random::<f64>())
                    .collect(),
            };
            let r = optimize_set(&objective, &start, &setup.limits, setup.latin, s, &mut rng);
            if let Ok((_, rep)) = &r {
                on_done(rep);
            }
            r
        })
        .collect();
    let mut data = Vec::with_capacity(sets);
    let mut reports = Vec::with_capacity(sets);
    for r in results {
        let (set, rep) = r?;
        data.push(set);
        reports.push(rep);
    }
    Ok((PointSets::from_sets(setup.dims, data)?, reports))
}
