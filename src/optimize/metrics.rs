//! How well sets meet their target: the expected spectrum over the sets against `T` (issue 5's fit
//! criteria).

use crate::points::{PointSets, Projection};
use crate::spectrum::Method;
use crate::targets::TargetGrid;
use serde::Serialize;

/// Annuli with fewer non-dark cells than this are left out of the annular comparison.
pub const MIN_ANNULUS_CELLS: usize = 8;

/// The fit of one projection's expected spectrum to its target.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Fit {
    /// Projection name, e.g. `xu`.
    pub proj: String,
    /// Sets the expectation was taken over.
    pub sets: usize,
    /// Number of dark cells (`T ≤` [`crate::targets::DARK_LEVEL`]) inside the fit radius.
    pub dark_cells: usize,
    /// Mean expected `P` over the dark cells (goal: `≤ 0.1`); 0 when there are none.
    pub dark_mean: f64,
    /// Largest `|mean P − mean T|` over the annuli `r − ½ ≤ |k| < r + ½` that lie wholly inside the fit
    /// radius, over their non-dark cells (at least [`MIN_ANNULUS_CELLS`] of them) (goal: `≤ 0.1`).
    pub annular_max_error: f64,
    /// The annulus with the largest error, as `|k| / sqrt(N)`; 0 when no annulus is compared
    /// (`annuli == 0`: the annulus `|k| < ½` holds one cell, so a compared annulus is never at 0).
    pub worst_radius: f64,
    /// Root mean square of the same annular errors.
    pub annular_rms_error: f64,
    /// Number of annuli compared.
    pub annuli: usize,
    /// A variance target's predicted variance relative to random sampling's over the fit radius,
    /// `Σ W P / Σ W` (1 for white noise; see [`crate::targets::variance`]); `None` for shape targets.
    pub variance_ratio: Option<f64>,
}

/// The fit of `points`' expected spectrum in `proj` to `grid` (see [`Fit`]).
pub fn fit(points: &PointSets, proj: Projection, grid: &TargetGrid, method: Method) -> Fit {
    let res = grid.res;
    // The grid's resolution is valid and a PointSets holds at least one set.
    let p = crate::spectrum::expected::of_sets(points, proj, res, method)
        .expect("a target grid's resolution and a non-empty PointSets")
        .mean;
    let dark_sum: f64 = p
        .iter()
        .zip(&grid.dark)
        .filter(|(_, &d)| d)
        .map(|(v, _)| v)
        .sum();
    let dark_mean = if grid.dark_cells > 0 {
        dark_sum / grid.dark_cells as f64
    } else {
        0.0
    };
    let mut acc = vec![(0.0f64, 0.0f64, 0usize); grid.annuli()];
    for (idx, pk) in p.iter().enumerate() {
        if let Some(r) = grid.annulus(idx) {
            acc[r].0 += pk;
            acc[r].1 += grid.target[idx];
            acc[r].2 += 1;
        }
    }
    let errors: Vec<(usize, f64)> = acc
        .iter()
        .enumerate()
        .filter(|(_, a)| a.2 >= MIN_ANNULUS_CELLS)
        .map(|(r, a)| (r, ((a.0 - a.1) / a.2 as f64).abs()))
        .collect();
    let variance_ratio = grid.variance.then(|| {
        let (wp, w) = p
            .iter()
            .zip(&grid.weight)
            .fold((0.0, 0.0), |(wp, w), (pk, wk)| (wp + wk * pk, w + wk));
        wp / w
    });
    let annuli = errors.len();
    let (worst, annular_max_error) =
        errors
            .iter()
            .copied()
            .fold((0, 0.0), |m, e| if e.1 > m.1 { e } else { m });
    let errors: Vec<f64> = errors.into_iter().map(|e| e.1).collect();
    let annular_rms_error = if annuli > 0 {
        (errors.iter().map(|e| e * e).sum::<f64>() / annuli as f64).sqrt()
    } else {
        0.0
    };
    Fit {
        proj: proj.name(),
        sets: points.sets(),
        dark_cells: grid.dark_cells,
        dark_mean,
        annular_max_error,
        worst_radius: worst as f64 / (points.n() as f64).sqrt(),
        annular_rms_error,
        annuli,
        variance_ratio,
    }
}
