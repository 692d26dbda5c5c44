//! Variance targets: the optimizer minimizes the variance a set predicts for a family of integrands
//! (DESIGN §4), instead of matching a spectrum shape.
//!
//! For a set moved by a random toroidal shift and then by the seam-free shear `S` of DESIGN §5, the
//! estimate of `∫ f` has variance `(1/N) Σ_{k≠0} |ĝ(k)|² P(k)` with `g = f ∘ S` on the torus. A variance
//! target holds `|ĝ|²`, averaged over random placements of the integrand family, and the loss is
//! `weight · Σ_k |ĝ(k)|² P(k) / Σ_k |ĝ(k)|²` over the fit radius: the predicted variance relative to
//! random sampling's (1 for white noise), times `weight`. Unlike a shape target, it asks for no `T = 1`
//! outside a dark region, so a set may put its energy in a few peaks where the family has little, as a
//! rank-1 lattice does.
//!
//! `|ĝ|²` comes from sampling `g` at the centres of an `M × M` grid and a 2D FFT (rustfft). A jump in
//! `g` makes the sampled coefficients differ from the true ones by about `|k| / M` relative (aliasing),
//! so `M` is at least 8 times the largest `|k|` used (a unit test holds the sampled spectrum of a fan
//! against its exact coefficients).

use crate::error::{Error, Result};
use crate::integrands::sampled::sampled_power;
use crate::integrands::{spec, Integrand};
use crate::points::shear::{shear_pair, ShearMode, MAX_SHEAR};
use rand::Rng as _;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// Default number of random placements averaged (see [`Variance::placements`]).
pub const DEFAULT_PLACEMENTS: usize = 32;

/// Largest number of placements a target may ask for.
pub const MAX_PLACEMENTS: usize = 1024;

/// Default loss weight (see [`Variance::weight`]). Measured on the fan of edges of
/// `targets/fan-variance.toml` (4D, N = 1024, 8 sets, 300 iterations, R = 1024): with the `xy`/`uv`
/// strata at their default weight 1, the fan's MSE was within 3 % of the MSE with the strata off,
/// where a weight 100 times smaller let the strata double it.
pub const DEFAULT_VARIANCE_WEIGHT: f64 = 5000.0;

/// Largest loss weight: far larger weights overflow the solver's line search.
pub const MAX_VARIANCE_WEIGHT: f64 = 1e8;

/// The version of how `|ĝ|²` is sampled (placement seed, grid size rule): part of compare's table
/// cache key, so change it whenever either changes.
pub const SAMPLING_VERSION: u32 = 1;

/// The seed of the placements' random streams: part of the target's definition, not of the run.
const PLACEMENT_SEED: u64 = 0x7661_7269_616e_6365;

/// Smallest sampling grid side `M`.
const MIN_SAMPLES: usize = 256;

/// Largest sampling grid side `M` (256 MiB of complex samples), so largest loss grid `M / 4`.
pub const MAX_SAMPLES: usize = 4096;

/// Largest number of integrand evaluations, placements × `M²`, one spectrum may take (about a minute
/// on 2 cores).
pub const MAX_EVALUATIONS: usize = 1 << 30;

/// A variance target: the loss is the predicted variance of `integrand` (see the module doc).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Variance {
    /// A 2D integrand (the syntax of `anisospec integrands`, without `@proj`), e.g.
    /// `fan:s0=0.3,s1=0.7`. In 4D it stands in both `xu` and `yv`.
    pub integrand: String,
    /// The seam-free shear the set is moved by at use (the oracle's shear; 0 for none). A 4D table
    /// is moved by it in `xu` and `yv` (`--shear`, compare); a 2D set is not sheared by anisospec at
    /// use, so a 2D design with a shear is for a renderer that applies
    /// [`crate::points::shear::shear_pair`] itself.
    #[serde(default)]
    pub shear: f64,
    /// Random placements of the family (the integrand's own random placement, e.g. a fan's offset)
    /// averaged into `|ĝ|²` (default [`DEFAULT_PLACEMENTS`]); 0 takes the integrand as written.
    #[serde(default)]
    pub placements: Option<usize>,
    /// The relative error of `shear` the design should tolerate (the oracle's error): each placement
    /// is also moved by `shear · (1 + e)` instead of `shear`, with `e` uniform in
    /// `[−shear_error, shear_error]` drawn from the placement's stream, so `|ĝ|²` is the mean over
    /// the errors as well (default 0: every placement moved by `shear`). At least 0 and below 1; needs
    /// a nonzero `shear` and at least one placement.
    #[serde(default)]
    pub shear_error: Option<f64>,
    /// Fit radius in normalized frequency `|k| / sqrt(N)` (at least 4 frequency cells).
    pub extent: f64,
    /// Loss weight against the repulsion and the 4D strata (default [`DEFAULT_VARIANCE_WEIGHT`], at
    /// most [`MAX_VARIANCE_WEIGHT`]).
    #[serde(default)]
    pub weight: Option<f64>,
    /// How a table is made for this target (default [`Design::Points`]).
    #[serde(default)]
    pub design: Option<Design>,
}

/// How a table is made for a variance target.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Design {
    /// The optimizer moves the points of each set to lower the loss (the other keys above).
    #[default]
    Points,
    /// A search over the rank-1 lattices of N points for the generating vector whose predicted
    /// variance is lowest ([`crate::optimize::lattice_design`]); `extent` then sets only the radius
    /// the fit is reported over, and `weight` does not apply.
    Lattice,
    /// Sets that are rank-1 lattices of several generating vectors, mixed so that the worst
    /// predicted variance over the shear's errors in `[−shear_error, shear_error]` is lowest
    /// ([`crate::optimize::lattice_design::mixture`]): written `design = "lattice-mixture"`. Needs a
    /// nonzero `shear` and `shear_error`; each error's family is averaged over `placements` (0: the
    /// integrand as written), at most [`MAX_MIXTURE_PLACEMENTS`].
    #[serde(rename = "lattice-mixture")]
    LatticeMixture,
}

/// Most placements a lattice mixture's family may average per error: its spectrum is computed at
/// every error of the mixture's grid, so the cost is that many times a single target's.
pub const MAX_MIXTURE_PLACEMENTS: usize = 4;

impl Variance {
    /// Checks the parameters: a 2D integrand that parses, a finite shear within
    /// [`MAX_SHEAR`], `0 < extent`, at most [`MAX_PLACEMENTS`] placements,
    /// `0 < weight ≤` [`MAX_VARIANCE_WEIGHT`].
    pub fn validate(&self) -> Result<()> {
        let f = self.parsed()?;
        if f.dims() != 2 {
            return Err(Error::Input(format!(
                "target integrand '{}' is {}D; give a 2D integrand without @proj: the target applies to each projection the optimizer constrains (xy in 2D, xu and yv in 4D)",
                self.integrand,
                f.dims()
            )));
        }
        if !(self.shear.is_finite() && self.shear.abs() <= MAX_SHEAR) {
            return Err(Error::Input(format!(
                "target parameter 'shear' is {}; give a finite shear of magnitude at most {MAX_SHEAR:e}",
                crate::error::number(self.shear)
            )));
        }
        if !(self.extent.is_finite() && self.extent > 0.0) {
            return Err(Error::Input(format!(
                "target parameter 'extent' is {}; it is the fit radius in units of sqrt(N) and must be a finite number > 0",
                crate::error::number(self.extent)
            )));
        }
        let e = self.shear_error();
        if !(e.is_finite() && (0.0..1.0).contains(&e)) {
            return Err(Error::Input(format!(
                "target parameter 'shear_error' is {}; give the relative error of the shear to tolerate, at least 0 and below 1 (0.25 for ±25 %)",
                crate::error::number(e)
            )));
        }
        if self.design() == Design::LatticeMixture {
            if self.shear == 0.0 || e == 0.0 || self.placements() > MAX_MIXTURE_PLACEMENTS {
                return Err(Error::Input(format!(
                    "design = \"lattice-mixture\" with shear {}, shear_error {e} and {} placements: a mixture is designed for the worst error of a nonzero shear, so give a nonzero 'shear' and 'shear_error', and at most {MAX_MIXTURE_PLACEMENTS} placements (0: the integrand as written)",
                    self.shear,
                    self.placements()
                )));
            }
        } else if e > 0.0 && (self.shear == 0.0 || self.placements() == 0) {
            return Err(Error::Input(format!(
                "target parameter 'shear_error' is {e} with shear {} and {} placements; an error of the shear needs a nonzero 'shear' to scale and at least one placement to draw it in (or leave 'shear_error' out)",
                self.shear,
                self.placements()
            )));
        }
        if self.placements() > MAX_PLACEMENTS {
            return Err(Error::Input(format!(
                "target parameter 'placements' is {}; give at most {MAX_PLACEMENTS}",
                self.placements()
            )));
        }
        let w = self.weight();
        if !(w.is_finite() && w > 0.0 && w <= MAX_VARIANCE_WEIGHT) {
            return Err(Error::Input(format!(
                "target parameter 'weight' is {}; give a number > 0 and at most {MAX_VARIANCE_WEIGHT:e} (larger weights overflow the solver's line search)",
                crate::error::number(w)
            )));
        }
        Ok(())
    }

    /// The same target with every default written out (placements, shear error, weight and
    /// design), so that its
    /// `Debug` text, which keys compare's table cache, and its JSON name what was used.
    pub fn resolved(mut self) -> Self {
        self.placements = Some(self.placements());
        self.shear_error = Some(self.shear_error());
        self.weight = Some(self.weight());
        self.design = Some(self.design());
        self
    }

    /// How a table is made for this target.
    pub fn design(&self) -> Design {
        self.design.unwrap_or_default()
    }

    /// Placements averaged (0: the integrand as written).
    pub fn placements(&self) -> usize {
        self.placements.unwrap_or(DEFAULT_PLACEMENTS)
    }

    /// The relative shear error tolerated (0: none).
    pub fn shear_error(&self) -> f64 {
        self.shear_error.unwrap_or(0.0)
    }

    /// The loss weight.
    pub fn weight(&self) -> f64 {
        self.weight.unwrap_or(DEFAULT_VARIANCE_WEIGHT)
    }

    fn parsed(&self) -> Result<Box<dyn Integrand>> {
        spec::parse(&self.integrand).map_err(|e| {
            Error::Input(format!(
                "target parameter 'integrand': {}",
                match e {
                    Error::Usage(m) | Error::Input(m) => m,
                    other => other.to_string(),
                }
            ))
        })
    }

    /// `|ĝ(k)|²` averaged over the placements, on the `res × res` grid of DESIGN §3 (`[i * res + j]`,
    /// `k1 = j − res/2`, `k2 = i − res/2`), sampled on an `M × M` grid with `M` the smallest power of two
    /// at least `max(256, 4 res)`. Fails with `Error::Input` when `M` would exceed [`MAX_SAMPLES`] or
    /// the placements' evaluations [`MAX_EVALUATIONS`]. Computed once per process for each target
    /// and `res`, then shared.
    pub fn spectrum(&self, res: usize) -> Result<Arc<Vec<f64>>> {
        Ok(self.spectrum_timed(res)?.0)
    }

    /// The side `M` of the grid [`Variance::spectrum`] samples the integrand on for a `res × res`
    /// loss grid, checked without sampling: `Error::Input` when `M` would exceed [`MAX_SAMPLES`] or
    /// the placements' evaluations [`MAX_EVALUATIONS`].
    pub fn sampling_side(&self, res: usize) -> Result<usize> {
        let samples = (4 * res).max(MIN_SAMPLES).next_power_of_two();
        if samples > MAX_SAMPLES {
            return Err(Error::Input(format!(
                "the variance target's loss grid of {res} x {res} frequencies needs the integrand sampled on {samples} x {samples} points, more than the largest, {MAX_SAMPLES} x {MAX_SAMPLES}; lower its extent ({}) or N so that extent * sqrt(N) is at most {}",
                self.extent,
                MAX_SAMPLES / 8 - 1
            )));
        }
        let evaluations = self.placements().max(1).saturating_mul(samples * samples);
        if evaluations > MAX_EVALUATIONS {
            return Err(Error::Input(format!(
                "the variance target would evaluate its integrand {evaluations:.3e} times ({} placements on {samples} x {samples} points), more than {MAX_EVALUATIONS:.3e}; lower its placements to at most {}",
                self.placements(),
                MAX_EVALUATIONS / (samples * samples)
            )));
        }
        Ok(samples)
    }

    /// [`Variance::spectrum`] and the seconds its computation took, the first time this process
    /// asked for it (the same figure on every later call, which reuses it): a set-up cost that every
    /// design from this spectrum shares.
    pub fn spectrum_timed(&self, res: usize) -> Result<(Arc<Vec<f64>>, f64)> {
        let samples = self.sampling_side(res)?;
        type Memo = Mutex<HashMap<String, (Arc<Vec<f64>>, f64)>>;
        static MEMO: OnceLock<Memo> = OnceLock::new();
        let key = format!("{self:?}|{res}");
        let memo = MEMO.get_or_init(|| Mutex::new(HashMap::new()));
        if let Some((found, seconds)) = memo.lock().expect("memo lock").get(&key) {
            return Ok((Arc::clone(found), *seconds));
        }
        let started = std::time::Instant::now();
        let base = self.parsed()?;
        let spectrum = Arc::new(self.spectrum_sampled(base.as_ref(), res, samples)?);
        let seconds = started.elapsed().as_secs_f64();
        memo.lock()
            .expect("memo lock")
            .insert(key, (Arc::clone(&spectrum), seconds));
        Ok((spectrum, seconds))
    }

    fn spectrum_sampled(&self, base: &dyn Integrand, res: usize, m: usize) -> Result<Vec<f64>> {
        let count = self.placements();
        // Each placement's stream places the integrand, then draws the shear's error.
        let placed: Vec<(Option<Box<dyn Integrand>>, f64)> = (0..count as u64)
            .map(|p| {
                let mut rng = crate::rng::stream(PLACEMENT_SEED, p);
                let f = base.placed(&mut rng);
                let e = self.shear_error();
                let shear = if e > 0.0 {
                    self.shear * (1.0 + rng.random_range(-e..=e))
                } else {
                    self.shear
                };
                (f, shear)
            })
            .collect();
        // A family with nothing to move is its one integrand, whatever `placements` says: once when
        // every placement sees it through the same shear, else through each placement's shear.
        let unplaced = placed.iter().any(|(f, _)| f.is_none());
        let members: Vec<(&dyn Integrand, f64)> =
            if count == 0 || (unplaced && self.shear_error() == 0.0) {
                vec![(base, self.shear)]
            } else {
                placed
                    .iter()
                    .map(|(f, shear)| match f {
                        Some(f) if !unplaced => (f.as_ref(), *shear),
                        _ => (base, *shear),
                    })
                    .collect()
            };
        let mut total = vec![0.0; res * res];
        for (f, shear) in &members {
            for (t, v) in total.iter_mut().zip(self.power(*f, *shear, res, m)) {
                *t += v / members.len() as f64;
            }
        }
        if total.iter().any(|v| !v.is_finite()) {
            return Err(Error::Input(format!(
                "target integrand '{}' has a non-finite value in the unit square, so its spectrum is undefined; give an integrand that is finite everywhere",
                self.integrand
            )));
        }
        Ok(total)
    }

    /// `|ĝ|²` of one integrand: `f ∘ S` for the seam-free shear `S` by `shear`, sampled on an
    /// `m × m` grid ([`crate::integrands::sampled::sampled_power`]).
    fn power(&self, f: &dyn Integrand, shear: f64, res: usize, m: usize) -> Vec<f64> {
        sampled_power(
            |a, b| {
                let (x, u) = shear_pair(a, b, shear, ShearMode::Transported);
                f.eval(&[x, u])
            },
            res,
            m,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn target(integrand: &str, shear: f64, placements: usize) -> Variance {
        Variance {
            integrand: integrand.into(),
            shear,
            placements: Some(placements),
            shear_error: None,
            extent: 1.0,
            weight: None,
            design: None,
        }
    }

    /// A lattice mixture needs a shear and a shear error to design for, and few placements.
    #[test]
    fn a_lattice_mixture_needs_a_shear_error_and_few_placements() {
        let mixture = |shear: f64, error: f64, placements: usize| Variance {
            shear,
            shear_error: Some(error),
            design: Some(Design::LatticeMixture),
            ..target("sheared:s=0.5", 0.0, placements)
        };
        mixture(0.5, 0.25, 0).validate().unwrap();
        for bad in [
            mixture(0.0, 0.25, 0),
            mixture(0.5, 0.0, 0),
            mixture(0.5, 0.25, 5),
        ] {
            let e = bad.validate().unwrap_err();
            assert_eq!(e.exit_code(), 2);
            assert!(e.to_string().contains("lattice-mixture"), "{e}");
        }
    }

    /// Unsheared and unplaced, the sampled spectrum is the fan's exact `|f̂|²` (from its own Fourier
    /// coefficients) up to aliasing: over `|k1|, |k2| ≤ 8` (where `|f̂|² > 1e-6`) the worst relative
    /// error is below `8 / M`, the module doc's `max |k| / M` with `|k|` measured along an axis, at
    /// `M` = 256 and 1024 (measured 0.35 % and 0.04 %), and falls as `M` grows.
    #[test]
    fn sampled_spectrum_matches_exact_coefficients() {
        let spec_text = "fan:s0=0.3,s1=0.7,c=0.7";
        let t = target(spec_text, 0.0, 0);
        let f = spec::parse(spec_text).unwrap();
        let res = 18;
        let worst = |m: usize| {
            let p = t.spectrum_sampled(f.as_ref(), res, m).unwrap();
            let mut worst: f64 = 0.0;
            for i in 1..res {
                for j in 1..res {
                    let (k1, k2) = crate::spectrum::frequency(i * res + j, res);
                    if (k1, k2) == (0, 0) {
                        continue;
                    }
                    let exact = f.fourier(&[k1, k2]).unwrap().norm_sqr();
                    if exact > 1e-6 {
                        worst = worst.max((p[i * res + j] - exact).abs() / exact);
                    }
                }
            }
            worst
        };
        let (coarse, fine) = (worst(256), worst(1024));
        assert!(
            coarse < 8.0 / 256.0 && fine < 8.0 / 1024.0 && fine < coarse,
            "{coarse} {fine}"
        );
    }

    /// Averaging over placements is averaging the placed integrands' spectra, and the same target
    /// gives the same bits on every call.
    #[test]
    fn placements_average_the_family() {
        let t = target("fan:s0=0.3,s1=0.7", 0.5, 4);
        let base = spec::parse(&t.integrand).unwrap();
        let res = 16;
        let mean = t.spectrum_sampled(base.as_ref(), res, 256).unwrap();
        let mut by_hand = vec![0.0; res * res];
        for p in 0..4 {
            let f = base
                .placed(&mut crate::rng::stream(PLACEMENT_SEED, p))
                .unwrap();
            for (a, v) in by_hand
                .iter_mut()
                .zip(t.power(f.as_ref(), t.shear, res, 256))
            {
                *a += v / 4.0;
            }
        }
        assert_eq!(mean, by_hand);
        assert_eq!(mean, t.spectrum_sampled(base.as_ref(), res, 256).unwrap());
    }

    /// With a shear error, each placement is seen through its own shear `shear · (1 + e)`, `e` drawn
    /// after the placement from its stream and within the range; the mean is over those pairs.
    #[test]
    fn shear_errors_average_over_the_drawn_shears() {
        let mut t = target("sheared:s=0.5", 0.5, 4);
        t.shear_error = Some(0.25);
        t.validate().unwrap();
        let base = spec::parse(&t.integrand).unwrap();
        let res = 16;
        let mean = t.spectrum_sampled(base.as_ref(), res, 256).unwrap();
        let mut by_hand = vec![0.0; res * res];
        let mut shears = Vec::new();
        for p in 0..4 {
            let mut rng = crate::rng::stream(PLACEMENT_SEED, p);
            let f = base.placed(&mut rng).unwrap();
            let shear = 0.5 * (1.0 + rng.random_range(-0.25..=0.25));
            shears.push(shear);
            for (a, v) in by_hand.iter_mut().zip(t.power(f.as_ref(), shear, res, 256)) {
                *a += v / 4.0;
            }
        }
        assert_eq!(mean, by_hand);
        assert!(
            shears.iter().all(|s| (0.375..=0.625).contains(s)),
            "{shears:?}"
        );
        assert!(shears.iter().any(|&s| s != 0.5), "{shears:?}");
        // Without the error the same placements give another spectrum (the shears differ).
        t.shear_error = None;
        assert_ne!(mean, t.spectrum_sampled(base.as_ref(), res, 256).unwrap());
    }

    #[test]
    fn bad_parameters_are_named() {
        let message = |t: Variance| t.validate().unwrap_err().to_string();
        assert!(message(target("fan:s0=0.3,s1=0.7@xu", 0.0, 0)).contains("2D integrand"));
        assert!(message(target("nosuch:a=1", 0.0, 0)).contains("'integrand'"));
        assert!(message(target("fan:s0=0.3,s1=0.7", f64::NAN, 0)).contains("'shear'"));
        assert!(message(target("fan:s0=0.3,s1=0.7", 0.0, 5000)).contains("'placements'"));
        for (shear, placements, error) in [
            (0.5, 4, 1.0),
            (0.5, 4, -0.1),
            (0.5, 4, f64::NAN),
            (0.0, 4, 0.1),
            (0.5, 0, 0.1),
        ] {
            let mut t = target("sheared:s=0.5", shear, placements);
            t.shear_error = Some(error);
            assert!(
                message(t).contains("'shear_error'"),
                "{shear} {placements} {error}"
            );
        }
        let mut t = target("fan:s0=0.3,s1=0.7", 0.0, 0);
        t.extent = 0.0;
        assert!(message(t.clone()).contains("'extent'"));
        t.extent = 1.0;
        t.weight = Some(-1.0);
        assert!(message(t.clone()).contains("'weight'"));
        // A loss grid too fine to sample is refused before any sampling.
        t.weight = None;
        let e = t.spectrum(MAX_SAMPLES / 4 + 2).unwrap_err();
        assert!(e.to_string().contains("lower its extent"), "{e}");
        assert_eq!(e.exit_code(), 2);
        // So is one that would take too many evaluations.
        t.placements = Some(MAX_PLACEMENTS);
        let e = t.spectrum(MAX_SAMPLES / 4).unwrap_err();
        assert!(e.to_string().contains("lower its placements"), "{e}");
        t.placements = Some(0);
        t.weight = Some(1e300);
        assert!(message(t).contains("'weight'"));
    }
}
