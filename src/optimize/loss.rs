//! The optimizer's objective: the spectral loss of DESIGN §6 summed over weighted projections, plus a
//! short-range toroidal repulsion, with exact gradients.
//!
//! For one projection with grid target `T` and weights `W`:
//!
//! ```text
//! L = Σ_k W(k) (P(k) − T(k))²,   P = |F|² / N,   F(k) = Σ_j exp(−2πi k·x_j)
//! ∂L/∂x_j = (4/N) Re Σ_k W (P − T) conj(F) (−2πi k) exp(−2πi k·x_j)
//! ```
//!
//! Both coordinates come out of one type-2 transform: with `W`, `T` symmetric in `k` (the unpaired
//! row and column `−K/2` carry `W = 0`), `G = Σ_k W (P − T) F(k) 2πi (k1 + i k2) exp(+2πi k·x_j)` has
//! `Re G = Σ … k1 …` and `Im G = Σ … k2 …`, both real sums; the gradient is `(4/N) (Re G, Im G)`.
//!
//! A variance target's grid ([`crate::targets::variance`]) makes the term linear: `L = Σ_k W(k) P(k)`,
//! the predicted variance, whose gradient is the same transform with `W` in place of `2 W (P − T)`.
//!
//! Annular means (per term, optional): the fit criterion ([`super::metrics::Fit`]) compares the
//! means of `P` and of `T` over the non-dark cells of each annulus `round(|k|) = r`
//! ([`TargetGrid::annulus`]). The loss can add `λ_a / A · Σ_r m_r²`, `m_r` the mean residual `P − T`
//! over annulus `r` and `A` the number of annuli; its derivative `2 λ_a m_r / (A n_r)` joins
//! `2 W (P − T)` in the same type-2 transform. Without it the energy pushed out of a large dark region
//! piles up in the annuli nearby, a bias the per-cell term barely sees under the periodogram's
//! per-cell noise.
//!
//! Repulsion (per constrained projection, on the torus): `E = (λ / N) Σ_{pairs, d < r} (1 − d²/r²)²`
//! with `r = radius / sqrt(N)`; smooth (`C¹`), zero beyond `r`, found with kiddo periodic radius queries.

use crate::points::{wrap, Projection};
use crate::spectrum::{self, frequency, Method};
use crate::targets::TargetGrid;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use rustfft::num_complex::Complex64;
use std::f64::consts::TAU;

/// One projection's share of the loss: its target grid and weight.
#[derive(Clone, Debug)]
pub struct Term {
    /// The pair of dimensions the target applies to.
    pub proj: Projection,
    /// The target, weights and dark mask on the frequency grid.
    pub grid: TargetGrid,
    /// Multiplies the projection's loss (`≥ 0`).
    pub weight: f64,
}

/// The short-range repulsion term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Repulsion {
    /// Interaction radius in units of the mean spacing `1 / sqrt(N)`.
    pub radius: f64,
    /// Strength `λ` (0 switches the term off).
    pub weight: f64,
}

/// The objective for sets of `n` points in `dims` dimensions.
#[derive(Clone, Debug)]
pub struct Objective {
    /// Points per set.
    pub n: usize,
    /// Dimensions (2 or 4).
    pub dims: usize,
    /// The projections the loss constrains.
    pub terms: Vec<Term>,
    /// Repulsion within each constrained projection.
    pub repulsion: Repulsion,
    /// Weight `λ_a` of the annular-mean term (0 switches it off); see the module doc.
    pub annular_weight: f64,
    /// How the Fourier sums are computed.
    pub method: Method,
}

/// The loss and its gradient at one point set.
#[derive(Clone, Debug, PartialEq)]
pub struct Evaluation {
    /// Total loss: spectral plus repulsion.
    pub loss: f64,
    /// The spectral part, `Σ_terms weight · (Σ_k W (P − T)² + the annular term)`.
    pub spectral: f64,
    /// The repulsion part.
    pub repulsion: f64,
    /// `∂loss/∂x`, `[n, dims]` row-major like the set.
    pub gradient: Vec<f64>,
}

/// The wrapped projection of a set whose coordinates may have left `[0, 1)`.
pub(super) fn projected(set: &[f64], dims: usize, proj: Projection) -> Vec<[f64; 2]> {
    set.chunks_exact(dims)
        .map(|p| [wrap(p[proj.a]), wrap(p[proj.b])])
        .collect()
}

/// Minimum-image difference `a − b` on the unit circle, in `[−½, ½)`.
fn torus_delta(a: f64, b: f64) -> f64 {
    let d = a - b;
    d - (d + 0.5).floor()
}

impl Objective {
    /// The spectral loss of one term and its gradient with respect to the term's two coordinates
    /// (`[n]` each).
    fn term_loss(&self, term: &Term, set: &[f64]) -> (f64, Vec<f64>, Vec<f64>) {
        let pts = projected(set, self.dims, term.proj);
        let g = &term.grid;
        let res = g.res;
        let n = self.n as f64;
        let f = spectrum::fourier_sums(&pts, res, self.method);
        let power: Vec<f64> = f.iter().map(|z| z.norm_sqr() / n).collect();
        // Annular means of the residual over the non-dark cells, and their share of the loss.
        let with_annuli = self.annular_weight > 0.0;
        let mut annular = vec![(0.0, 0usize); g.annuli()];
        if with_annuli {
            for (idx, p) in power.iter().enumerate() {
                if let Some(r) = g.annulus(idx) {
                    annular[r].0 += p - g.target[idx];
                    annular[r].1 += 1;
                }
            }
        }
        let used = annular.iter().filter(|a| a.1 > 0).count().max(1) as f64;
        let wa = self.annular_weight * term.weight / used;
        let mut loss: f64 = annular
            .iter()
            .filter(|a| a.1 > 0)
            .map(|a| wa * (a.0 / a.1 as f64).powi(2))
            .sum();
        // ∂/∂P of the annular part, halved like `w r` below: `wa · mean / cells`.
        let annular_pull: Vec<f64> = annular
            .iter()
            .map(|a| {
                if a.1 > 0 {
                    wa * a.0 / (a.1 * a.1) as f64
                } else {
                    0.0
                }
            })
            .collect();
        let mut coeffs = vec![Complex64::new(0.0, 0.0); res * res];
        for (idx, c) in coeffs.iter_mut().enumerate() {
            let w = g.weight[idx] * term.weight;
            if w == 0.0 {
                continue;
            }
            // `r` is half of ∂(loss)/∂P over w: `P − T` for a shape, ½ for a variance target's `w P`.
            let r = if g.variance {
                loss += w * power[idx];
                0.5
            } else {
                let r = power[idx] - g.target[idx];
                loss += w * r * r;
                r
            };
            let pull = match g.annulus(idx) {
                Some(a) if with_annuli => annular_pull[a],
                _ => 0.0,
            };
            let (k1, k2) = frequency(idx, res);
            let (k1, k2) = (k1 as f64, k2 as f64);
            // 2πi (k1 + i k2) = 2π (−k2 + i k1)
            *c = f[idx] * Complex64::new(-TAU * k2, TAU * k1) * (w * r + pull);
        }
        let gsum = spectrum::type2(&coeffs, &pts, res, self.method);
        let scale = 4.0 / n;
        let ga = gsum.iter().map(|z| scale * z.re).collect();
        let gb = gsum.iter().map(|z| scale * z.im).collect();
        (loss, ga, gb)
    }

    /// The repulsion energy of one projection and its gradient (`[n]` per coordinate).
    fn repulsion_loss(&self, proj: Projection, set: &[f64]) -> (f64, Vec<f64>, Vec<f64>) {
        let n = self.n;
        let rep = self.repulsion;
        if rep.weight == 0.0 || rep.radius <= 0.0 || n < 2 {
            return (0.0, vec![0.0; n], vec![0.0; n]);
        }
        let pts = projected(set, self.dims, proj);
        let r = rep.radius / (n as f64).sqrt();
        let r2 = r * r;
        let lam = rep.weight / n as f64;
        let tree: ImmutableKdTree<f64, 2> = ImmutableKdTree::new_from_slice(&pts)
            .expect("a non-empty set of finite points builds a tree");
        let per_point: Vec<(f64, f64, f64)> = pts
            .par_iter()
            .enumerate()
            .map(|(i, p)| {
                let mut near = tree
                    .query(p)
                    .periodic_boundary_condition(&[1.0, 1.0])
                    .within::<SquaredEuclidean<f64>>(r2)
                    .execute();
                near.sort_by_key(|q| q.item);
                let (mut e, mut ga, mut gb) = (0.0, 0.0, 0.0);
                for q in near {
                    let j = q.item as usize;
                    if j == i {
                        continue;
                    }
                    let da = torus_delta(p[0], pts[j][0]);
                    let db = torus_delta(p[1], pts[j][1]);
                    let d2 = da * da + db * db;
                    if d2 >= r2 {
                        continue;
                    }
                    let s = 1.0 - d2 / r2;
                    // Each pair is seen from both ends: half its energy here.
                    e += 0.5 * lam * s * s;
                    let f = -4.0 * lam * s / r2;
                    ga += f * da;
                    gb += f * db;
                }
                (e, ga, gb)
            })
            .collect();
        let energy = per_point.iter().map(|t| t.0).sum();
        (
            energy,
            per_point.iter().map(|t| t.1).collect(),
            per_point.iter().map(|t| t.2).collect(),
        )
    }

    /// The constrained projections, each once, in the terms' order: those repulsion acts in.
    pub(super) fn constrained_projections(&self) -> Vec<Projection> {
        let mut seen: Vec<Projection> = Vec::new();
        for term in &self.terms {
            if !seen.contains(&term.proj) {
                seen.push(term.proj);
            }
        }
        seen
    }

    /// The loss and its gradient at `set` (`[n, dims]`, coordinates taken mod 1).
    pub fn evaluate(&self, set: &[f64]) -> Evaluation {
        self.evaluate_with(set, &Held::default())
    }

    /// The parts of the loss at `set` that depend only on held coordinates: every term, and every
    /// projection's repulsion, whose two coordinates are `held` (`[n, dims]`, as the solver's mask)
    /// at every point. While those coordinates keep their values these parts are constants.
    pub(super) fn held_parts(&self, set: &[f64], held: &[bool]) -> Held {
        let is_held = |proj: Projection| {
            held.chunks_exact(self.dims)
                .all(|point| point[proj.a] && point[proj.b])
        };
        Held {
            terms: self
                .terms
                .iter()
                .map(|t| is_held(t.proj).then(|| self.term_loss(t, set).0))
                .collect(),
            repulsion: self
                .constrained_projections()
                .into_iter()
                .map(|proj| is_held(proj).then(|| self.repulsion_loss(proj, set).0))
                .collect(),
        }
    }

    /// [`Objective::evaluate`] with the parts in `held` taken as computed there, not recomputed: the
    /// same loss bits while the held coordinates keep their values, and a gradient that differs only
    /// at the held coordinates (which the solver zeroes). With `--latin` in 4D, `x` and `y` are held,
    /// so the `xy` strata term and its repulsion (about a quarter of the spectral work) are constants.
    pub(super) fn evaluate_with(&self, set: &[f64], held: &Held) -> Evaluation {
        debug_assert_eq!(set.len(), self.n * self.dims);
        debug_assert!(held.terms.is_empty() || held.terms.len() == self.terms.len());
        let mut gradient = vec![0.0; set.len()];
        let (mut spectral, mut repulsion) = (0.0, 0.0);
        let mut add = |proj: Projection, ga: &[f64], gb: &[f64]| {
            for (j, (a, b)) in ga.iter().zip(gb).enumerate() {
                gradient[j * self.dims + proj.a] += a;
                gradient[j * self.dims + proj.b] += b;
            }
        };
        for (i, term) in self.terms.iter().enumerate() {
            if let Some(l) = held.terms.get(i).copied().flatten() {
                spectral += l;
                continue;
            }
            let (l, ga, gb) = self.term_loss(term, set);
            spectral += l;
            add(term.proj, &ga, &gb);
        }
        for (i, proj) in self.constrained_projections().into_iter().enumerate() {
            if let Some(e) = held.repulsion.get(i).copied().flatten() {
                repulsion += e;
                continue;
            }
            let (e, ga, gb) = self.repulsion_loss(proj, set);
            repulsion += e;
            add(proj, &ga, &gb);
        }
        Evaluation {
            loss: spectral + repulsion,
            spectral,
            repulsion,
            gradient,
        }
    }
}

/// Loss parts that depend only on coordinates the solver holds ([`Objective::held_parts`]): per
/// term, and per repelled projection, `Some(value)` to reuse or `None` to compute. The default
/// holds nothing.
#[derive(Clone, Debug, Default)]
pub(super) struct Held {
    terms: Vec<Option<f64>>,
    repulsion: Vec<Option<f64>>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::targets::Target;
    use rand::Rng as _;

    /// With `x` and `y` held, as `--latin` holds them in 4D, the `xy` term and the `xy` repulsion are
    /// taken once from [`Objective::held_parts`], and the evaluation keeps the same loss bits and the
    /// same gradient at every coordinate the solver moves (`u`, `v`).
    #[test]
    fn held_parts_keep_the_loss_bits_and_the_free_gradient() {
        let n = 64;
        let grid = Target::parse("kind = \"blue-noise\"\nradius = 0.5\n")
            .unwrap()
            .grid(n)
            .unwrap();
        let term = |proj, weight| Term {
            proj,
            grid: grid.clone(),
            weight,
        };
        let objective = Objective {
            n,
            dims: 4,
            terms: vec![
                term(Projection::XU, 1.0),
                term(Projection::YV, 1.0),
                term(Projection::XY, 0.3),
                term(Projection::UV, 0.3),
            ],
            repulsion: Repulsion {
                radius: 1.0,
                weight: 1.0,
            },
            annular_weight: 100.0,
            method: crate::spectrum::Method::Exact,
        };
        let mut rng = crate::rng::stream(3, 0);
        let start: Vec<f64> = (0..4 * n).map(|_| rng.random::<f64>()).collect();
        let held = crate::optimize::latin::frozen(n, 4, &[0, 1]);
        let parts = objective.held_parts(&start, &held);
        let is_some = |v: &[Option<f64>]| v.iter().map(Option::is_some).collect::<Vec<_>>();
        assert_eq!(is_some(&parts.terms), [false, false, true, false]);
        assert_eq!(is_some(&parts.repulsion), [false, false, true, false]);
        assert!(parts.repulsion[2].unwrap() > 0.0, "the xy repulsion acts");
        // The solver moves u and v only; x and y keep their values.
        let mut moved = start.clone();
        for (c, h) in moved.iter_mut().zip(&held) {
            if !h {
                *c = crate::points::wrap(*c + 0.01 * (rng.random::<f64>() - 0.5));
            }
        }
        for set in [&start, &moved] {
            let full = objective.evaluate(set);
            let reused = objective.evaluate_with(set, &parts);
            assert_eq!(full.loss.to_bits(), reused.loss.to_bits());
            assert_eq!(full.spectral.to_bits(), reused.spectral.to_bits());
            assert_eq!(full.repulsion.to_bits(), reused.repulsion.to_bits());
            for (i, h) in held.iter().enumerate() {
                if !h {
                    assert_eq!(
                        full.gradient[i].to_bits(),
                        reused.gradient[i].to_bits(),
                        "{i}"
                    );
                }
            }
        }
    }
}
