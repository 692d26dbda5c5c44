//! Minimizing an [`Objective`] for one set: argmin's L-BFGS (More–Thuente line search) in rounds,
//! restarted from the best point until a limit is met, with steepest descent and a backtracking
//! (Armijo) line search as the fallback when L-BFGS fails.

use super::loss::{Evaluation, Held, Objective};
use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{
    CostFunction, Error as ArgminError, Executor, Gradient, State, TerminationReason, KV,
};
use argmin::solver::gradientdescent::SteepestDescent;
use argmin::solver::linesearch::condition::ArmijoCondition;
use argmin::solver::linesearch::{BacktrackingLineSearch, MoreThuenteLineSearch};
use argmin::solver::quasinewton::LBFGS;
use serde::Serialize;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// How the stop reason of a run ended by its time limit begins.
pub const TIME_LIMIT_STOP: &str = "time limit";

/// Iterations of one steepest-descent round before L-BFGS is tried again.
const FALLBACK_ITERS: u64 = 50;

/// When to stop.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Limits {
    /// Largest number of solver iterations (all rounds together).
    pub max_iters: u64,
    /// Largest wall time per set, in seconds. A binding time limit makes the result depend on the
    /// machine's speed; the iteration limit does not.
    pub max_seconds: f64,
    /// Stop when a round lowers the loss by less than this fraction.
    pub tol: f64,
}

/// Default stopping rules: 2000 iterations, 60 s per set, a round that gains less than 1e-6.
pub const DEFAULT_LIMITS: Limits = Limits {
    max_iters: 2000,
    max_seconds: 60.0,
    tol: 1e-6,
};

impl Default for Limits {
    fn default() -> Self {
        DEFAULT_LIMITS
    }
}

/// One line of the optimization log.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LogRow {
    /// Iterations done since the start (all rounds): 0 on the first row, the starting set.
    pub iter: u64,
    /// Seconds since the start.
    pub seconds: f64,
    /// Best loss so far.
    pub loss: f64,
    /// `start` (the first row), then `lbfgs` or `steepest-descent`.
    pub solver: &'static str,
}

/// What the solver did.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    /// The best set found, coordinates wrapped to `[0, 1)`.
    pub set: Vec<f64>,
    /// The loss at the start.
    pub initial: Evaluation,
    /// The loss at the best set.
    pub last: Evaluation,
    /// Iterations (all rounds).
    pub iterations: u64,
    /// Loss evaluations.
    pub evaluations: u64,
    /// Seconds spent.
    pub seconds: f64,
    /// Why it stopped, in words.
    pub stop: String,
    /// Whether the fallback solver was used.
    pub fallback_used: bool,
    /// Loss against iteration and time.
    pub log: Vec<LogRow>,
}

/// The objective with some coordinates held fixed: their gradient is zero, so no solver moves them,
/// and the loss parts that depend on them alone are computed once, at `start`.
struct Variables<'a> {
    objective: &'a Objective,
    frozen: Option<&'a [bool]>,
    held: Held,
    start: &'a [f64],
}

impl Variables<'_> {
    fn evaluate(&self, set: &[f64]) -> Evaluation {
        // The held parts stand while every held coordinate keeps its start bits, as the solvers
        // keep them (a zero gradient gives a zero step); should one ever move, the loss is computed
        // in full rather than from stale parts.
        let unmoved = self.frozen.is_none_or(|mask| {
            mask.iter()
                .zip(set.iter().zip(self.start))
                .all(|(&held, (a, b))| !held || a.to_bits() == b.to_bits())
        });
        let mut e = if unmoved {
            self.objective.evaluate_with(set, &self.held)
        } else {
            self.objective.evaluate(set)
        };
        if let Some(mask) = self.frozen {
            for (g, &f) in e.gradient.iter_mut().zip(mask) {
                if f {
                    *g = 0.0;
                }
            }
        }
        e
    }
}

/// The lowest-loss point a round has evaluated, kept outside the solver: a round that fails (a
/// non-finite step) still hands back what it gained.
type BestSeen = Arc<Mutex<Option<(Vec<f64>, f64)>>>;

/// The argmin view of an objective: cost and gradient share one evaluation through a cache.
struct Problem<'a> {
    objective: &'a Variables<'a>,
    cache: Mutex<Option<(Vec<f64>, Evaluation)>>,
    evaluations: Arc<AtomicU64>,
    best_seen: BestSeen,
}

impl Problem<'_> {
    fn eval(&self, x: &[f64]) -> Result<Evaluation, ArgminError> {
        if let Some((p, e)) = self.cache.lock().expect("cache lock").as_ref() {
            if p.as_slice() == x {
                return Ok(e.clone());
            }
        }
        // L-BFGS on a loss that has stopped changing (e.g. with --tol 0) can divide by a zero
        // curvature and step to NaN: a failed round, not a set the spectrum code must take.
        if x.iter().any(|c| !c.is_finite()) {
            return Err(argmin::core::ArgminError::InvalidParameter {
                text: "the solver stepped to a non-finite coordinate".into(),
            }
            .into());
        }
        let e = self.objective.evaluate(x);
        self.evaluations.fetch_add(1, Ordering::Relaxed);
        if !e.loss.is_finite() || e.gradient.iter().any(|g| !g.is_finite()) {
            return Err(argmin::core::ArgminError::InvalidParameter {
                text: "the loss or its gradient is not finite".into(),
            }
            .into());
        }
        let mut best = self.best_seen.lock().expect("best lock");
        if best.as_ref().is_none_or(|b| e.loss < b.1) {
            *best = Some((x.to_vec(), e.loss));
        }
        drop(best);
        *self.cache.lock().expect("cache lock") = Some((x.to_vec(), e.clone()));
        Ok(e)
    }
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, p: &Vec<f64>) -> Result<f64, ArgminError> {
        Ok(self.eval(p)?.loss)
    }
}

impl Gradient for Problem<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, p: &Vec<f64>) -> Result<Vec<f64>, ArgminError> {
        Ok(self.eval(p)?.gradient)
    }
}

/// Records the best loss at every iteration.
struct Recorder {
    rows: Arc<Mutex<Vec<LogRow>>>,
    start: Instant,
    offset: u64,
    solver: &'static str,
}

impl<I: State<Float = f64>> Observe<I> for Recorder {
    fn observe_iter(&mut self, state: &I, _kv: &KV) -> Result<(), ArgminError> {
        self.rows.lock().expect("log lock").push(LogRow {
            // argmin counts the iteration after observing it: this row follows iteration
            // `get_iter() + 1` of the round.
            iter: self.offset + state.get_iter() + 1,
            seconds: self.start.elapsed().as_secs_f64(),
            loss: state.get_best_cost(),
            solver: self.solver,
        });
        Ok(())
    }
}

/// Result of one round: best point and cost, iterations, and whether the solver failed.
struct Round {
    best: Option<(Vec<f64>, f64)>,
    iters: u64,
    failed: Option<String>,
    reason: String,
    /// The solver gave up (e.g. its line search failed) rather than met a convergence test.
    solver_exit: bool,
}

/// One round of L-BFGS (or, with `fallback`, steepest descent) from `start_set`; L-BFGS stops when
/// the loss changes by less than `tol × 1e-3` (absolute: the caller scales `tol` to the loss).
fn run_round(
    problem: Problem<'_>,
    start_set: &[f64],
    iters: u64,
    time_left: Duration,
    recorder: Recorder,
    fallback: bool,
    tol: f64,
) -> Round {
    let best_seen = Arc::clone(&problem.best_seen);
    let rows = Arc::clone(&recorder.rows);
    let rows_before = rows.lock().expect("log lock").len();
    macro_rules! finish {
        ($res:expr) => {
            match $res {
                Ok(res) => {
                    let state = res.state();
                    Round {
                        best: state
                            .get_best_param()
                            .map(|p| (p.clone(), state.get_best_cost())),
                        iters: state.get_iter(),
                        failed: None,
                        reason: state
                            .get_termination_reason()
                            .map_or_else(|| "stopped".to_string(), |r| r.text().to_string()),
                        solver_exit: matches!(
                            state.get_termination_reason(),
                            Some(TerminationReason::SolverExit(_))
                        ),
                    }
                }
                // The best point evaluated and the iterations logged before the failure.
                Err(e) => Round {
                    best: best_seen.lock().expect("best lock").take(),
                    iters: (rows.lock().expect("log lock").len() - rows_before) as u64,
                    failed: Some(e.to_string()),
                    reason: String::new(),
                    solver_exit: false,
                },
            }
        };
    }
    if fallback {
        let ls = BacktrackingLineSearch::new(ArmijoCondition::new(1e-4).expect("valid constant"));
        let solver = SteepestDescent::new(ls);
        finish!(Executor::new(problem, solver)
            .configure(|s| s.param(start_set.to_vec()).max_iters(iters))
            .add_observer(recorder, ObserverMode::Always)
            .timeout(time_left)
            .run())
    } else {
        let solver = LBFGS::new(MoreThuenteLineSearch::new(), 10)
            .with_tolerance_grad(0.0)
            .and_then(|s| s.with_tolerance_cost(tol * 1e-3));
        let solver = match solver {
            Ok(s) => s,
            Err(e) => {
                return Round {
                    best: None,
                    iters: 0,
                    failed: Some(e.to_string()),
                    reason: String::new(),
                    solver_exit: false,
                }
            }
        };
        finish!(Executor::new(problem, solver)
            .configure(|s| s.param(start_set.to_vec()).max_iters(iters))
            .add_observer(recorder, ObserverMode::Always)
            .timeout(time_left)
            .run())
    }
}

/// Minimizes `objective` from `start` (`[n, dims]`) within `limits`.
///
/// L-BFGS runs in rounds; each round restarts from the best set so far, and the run stops when a round
/// gains less than `limits.tol` (relative), when a round whose line search gave up (argmin ends such
/// a round as a solver exit, not an error) gained nothing, or at the iteration or time limit. A
/// round in which L-BFGS fails (a non-finite loss or gradient outside its line search) is redone
/// with steepest descent. The returned loss is always finite: a start whose loss is not finite is
/// an error for the caller.
///
/// Coordinates where `frozen` (`[n, dims]`) is `true` keep their start values.
pub fn minimize(
    objective: &Objective,
    start: &[f64],
    limits: &Limits,
    frozen: Option<&[bool]>,
) -> Outcome {
    let t0 = Instant::now();
    let rows = Arc::new(Mutex::new(Vec::new()));
    let held = frozen.map_or_else(Held::default, |mask| objective.held_parts(start, mask));
    let objective = &Variables {
        objective,
        frozen,
        held,
        start,
    };
    let initial = objective.evaluate(start);
    rows.lock().expect("log lock").push(LogRow {
        iter: 0,
        seconds: t0.elapsed().as_secs_f64(),
        loss: initial.loss,
        solver: "start",
    });
    let mut best = (start.to_vec(), initial.clone());
    let mut iterations = 0u64;
    let counter = Arc::new(AtomicU64::new(1));
    let mut fallback_used = false;
    let mut use_fallback = false;
    let stop = loop {
        let elapsed = t0.elapsed().as_secs_f64();
        if iterations >= limits.max_iters {
            break format!("iteration limit ({}) reached", limits.max_iters);
        }
        if elapsed >= limits.max_seconds {
            break format!("{TIME_LIMIT_STOP} ({} s) reached", limits.max_seconds);
        }
        let problem = Problem {
            objective,
            cache: Mutex::new(Some((best.0.clone(), best.1.clone()))),
            evaluations: Arc::clone(&counter),
            best_seen: Arc::new(Mutex::new(None)),
        };
        let solver_name = if use_fallback {
            "steepest-descent"
        } else {
            "lbfgs"
        };
        let recorder = Recorder {
            rows: Arc::clone(&rows),
            start: t0,
            offset: iterations,
            solver: solver_name,
        };
        let budget = limits.max_iters - iterations;
        let round = run_round(
            problem,
            &best.0,
            if use_fallback {
                budget.min(FALLBACK_ITERS)
            } else {
                budget
            },
            Duration::try_from_secs_f64((limits.max_seconds - elapsed).max(0.0))
                .unwrap_or(Duration::MAX),
            recorder,
            use_fallback,
            // L-BFGS's stop within a round is an absolute change of the loss: scaled by the loss
            // where it is below 1, so that a target's scale does not decide how far a round goes
            // (a variance target with weight 1e-6, losses about 1e-8, stopped every round at once:
            // 25 times the predicted variance of the same target with weight 5000). Losses of 1
            // and above keep the tolerance as it was (the default tables are the same bits).
            limits.tol * best.1.loss.abs().min(1.0),
        );
        iterations += round.iters.max(1);
        let previous = best.1.loss;
        if let Some((p, _)) = round.best {
            let e = objective.evaluate(&p);
            counter.fetch_add(1, Ordering::Relaxed);
            if e.loss.is_finite() && e.loss < best.1.loss {
                best = (p, e);
            }
        }
        // A round that failed before argmin observed an iteration counts as one but logged none:
        // its row, so that the log always ends at the iterations done.
        {
            let mut log = rows.lock().expect("log lock");
            if log.last().is_none_or(|r| r.iter < iterations) {
                log.push(LogRow {
                    iter: iterations,
                    seconds: t0.elapsed().as_secs_f64(),
                    loss: best.1.loss,
                    solver: solver_name,
                });
            }
        }
        let gain = (previous - best.1.loss) / previous.abs().max(f64::MIN_POSITIVE);
        match (round.failed, use_fallback) {
            (Some(why), true) => break format!("both solvers failed; last: {why}"),
            (Some(_), false) => {
                // L-BFGS failed (a non-finite value outside its line search): a round of steepest
                // descent.
                use_fallback = true;
                fallback_used = true;
            }
            (None, true) if gain < limits.tol => {
                break format!("converged (steepest descent gained {gain:.1e} < tol)")
            }
            (None, true) if gain <= 0.0 => {
                break "stopped: a round of steepest descent made no progress".to_string()
            }
            (None, false) if gain <= 0.0 && round.solver_exit => {
                break format!(
                    "stopped: an L-BFGS round made no progress and gave up ({})",
                    round.reason
                )
            }
            (None, false) if gain < limits.tol => {
                break format!(
                    "converged (L-BFGS round gained {gain:.1e} < tol; {})",
                    round.reason
                )
            }
            (None, _) => use_fallback = false,
        }
    };
    let mut set = best.0;
    set.iter_mut().for_each(|c| *c = crate::points::wrap(*c));
    let log = rows.lock().expect("log lock").clone();
    Outcome {
        set,
        initial,
        last: best.1,
        iterations,
        evaluations: counter.load(Ordering::Relaxed),
        seconds: t0.elapsed().as_secs_f64(),
        stop,
        fallback_used,
        log,
    }
}
