//! One-dimensional views of a 2D spectrum (DESIGN §3): radial mean, anisotropy, directional cones.
//!
//! Grids follow the layout of [`crate::spectrum`]: entry `i * K + j` holds `k1 = j − K/2` and
//! `k2 = i − K/2` (see [`super::frequency`]).

use super::expected::ExpectedSpectrum;
use super::{frequency, Method};
use crate::error::{Error, Result};
use crate::output::{csv_number, write_atomic};
use std::f64::consts::PI;
use std::io::Write;
use std::path::Path;

/// The radial annulus of a frequency: `r` such that `r − ½ ≤ |k| < r + ½`.
pub fn annulus(k1: i64, k2: i64) -> usize {
    (((k1 * k1 + k2 * k2) as f64).sqrt() + 0.5).floor() as usize
}

/// The most directional cones a profile or a variance prediction splits the half-turn into: cones of
/// half a degree. At the default grid (`--res 128`) the outermost annulus, `r = 63`, holds about
/// `2π·63 ≈ 400` frequencies over the folded half-turn, so 360 cones is about the finest split that still
/// puts one frequency in each; a finer one leaves most cones empty at every radius of that grid, and
/// its output grows with the count (one CSV column, or one running sum per realization, per cone).
pub const MAX_CONES: usize = 360;

/// Checks a cone count (the flag `--cones`) against [`MAX_CONES`]. Whether 0 is allowed is the
/// caller's (a radial CSV takes 0 as no cones).
pub fn check_cones(cones: usize) -> Result<()> {
    if cones > MAX_CONES {
        return Err(Error::Usage(format!(
            "--cones {cones} is above the largest cone count, {MAX_CONES} (cones of half a degree; finer ones hold no frequency at most radii of the grid); lower it, e.g. --cones 8"
        )));
    }
    Ok(())
}

/// The directional cone of a frequency among `cones` sectors of the folded angle
/// `θ = atan2(k2, k1) mod π`. Cone `c` is centred on `θ = c π / cones`, so cone 0 holds the `k1` axis and,
/// for an even count, cone `cones / 2` holds the `k2` axis. Cones are half-open, `[c − ½, c + ½)` in
/// units of `π / cones`: a frequency on an edge goes to the cone above it. `k = 0` is put in cone 0.
pub fn cone_index(k1: i64, k2: i64, cones: usize) -> usize {
    // An integer frequency can lie on an edge only along an axis or a diagonal (the only directions
    // q π/4 whose tangent is rational, Niven's theorem), where rounding may put θ / width a hair
    // below the edge (the k2 axis with 25 cones went to cone 12): their cone is found in integers,
    // floor(q cones / 4 + 1/2) = (q cones + 2) / 4.
    let quarter = match (k1, k2) {
        (0, 0) => return 0,
        (_, 0) => Some(0),
        (0, _) => Some(2),
        _ if k1 == k2 => Some(1),
        _ if k1 == -k2 => Some(3),
        _ => None,
    };
    if let Some(q) = quarter {
        return (q * cones + 2) / 4 % cones;
    }
    let theta = (k2 as f64).atan2(k1 as f64).rem_euclid(PI);
    let width = PI / cones as f64;
    ((theta / width + 0.5).floor() as usize) % cones
}

/// One annulus of a radial profile.
#[derive(Clone, Debug, PartialEq)]
pub struct RadialBin {
    /// Integer radius `r` (frequency units of the unit torus).
    pub r: usize,
    /// `r / sqrt(N)`: the normalized frequency at which profiles of different `N` overlay.
    pub r_normalized: f64,
    /// Mean of `E[P]` over the annulus.
    pub mean: f64,
    /// Standard error of `mean`; `None` from a single realization, whose spread is unknown. Each bin
    /// `k` of the annulus has its mirror `−k` in it with the same `P` (real points), so the bins are
    /// combined in mirror pairs, the pairs taken as independent: `sqrt(2 Σ se²) / count` (combining
    /// the bins themselves as independent understated it by `1/sqrt(2)`).
    pub stderr: Option<f64>,
    /// `10 log10(var / mean²)` of `E[P]` within the annulus, in dB; `None` where the annulus is dark
    /// or flat within the error of the method that computed `P` ([`precision`]), where the ratio would
    /// be one of errors.
    pub anisotropy_db: Option<f64>,
    /// Mean of `E[P]` in each directional cone of the annulus (`None` where a cone has no bin).
    pub cones: Vec<Option<f64>>,
}

/// How far `method`'s `P` may be off, for `n` points on a `res × res` grid: `(dark, flat)`, the
/// absolute error of a bin whose true `P` is 0, and the relative error of any bin.
/// - Exact DFT: each of the `N` terms of `F` errs by at most `ρ_F` ([`super::exact::sum_error`]),
///   so `|ΔF| ≤ ρ_F N`, a dark bin holds at most `ρ_F² N` and `P` errs by `2 ρ_F + 2 u` relative.
/// - NUFFT: the contract, `10·eps` relative on `P`; a dark bin holds at most `(10 eps)² N`, the error
///   of `F` being at most `10 eps N` when every point's error adds up (a lattice).
pub fn precision(method: Method, n: usize, res: usize) -> (f64, f64) {
    let points = n as f64;
    match method {
        Method::Exact => {
            let rho = super::exact::sum_error(n, res);
            // 2 u = f64::EPSILON.
            (rho * rho * points, 2.0 * rho + f64::EPSILON)
        }
        Method::Nufft { eps } => ((10.0 * eps).powi(2) * points, 10.0 * eps),
    }
}

/// Radial mean, anisotropy and (with `cones > 0`) per-cone profiles for `r = 1 … K/2 − 1`: the annuli
/// that lie entirely inside the grid. `method` is the one that computed `spec`: it says where the
/// anisotropy is within its error ([`precision`]).
pub fn radial_profile(spec: &ExpectedSpectrum, cones: usize, method: Method) -> Vec<RadialBin> {
    let (dark, flat) = precision(method, spec.n, spec.res);
    let res = spec.res;
    let rmax = res / 2;
    let mut sum = vec![0.0; rmax];
    let mut var_sum = vec![0.0; rmax];
    let mut count = vec![0usize; rmax];
    let mut cone_sum = vec![vec![0.0; cones]; rmax];
    let mut cone_count = vec![vec![0usize; cones]; rmax];
    for i in 0..res {
        for j in 0..res {
            let (k1, k2) = frequency(i * res + j, res);
            let r = annulus(k1, k2);
            if r == 0 || r >= rmax {
                continue;
            }
            let p = spec.mean[i * res + j];
            let se = spec.stderr[i * res + j];
            sum[r] += p;
            var_sum[r] += se * se;
            count[r] += 1;
            if cones > 0 {
                let c = cone_index(k1, k2, cones);
                cone_sum[r][c] += p;
                cone_count[r][c] += 1;
            }
        }
    }
    let mean_of = |r: usize| sum[r] / count[r] as f64;
    // The spread about each annulus's mean, in a second pass: Σp²/c − mean² cancels on a flat annulus.
    let mut spread = vec![0.0; rmax];
    for i in 0..res {
        for j in 0..res {
            let (k1, k2) = frequency(i * res + j, res);
            let r = annulus(k1, k2);
            if r > 0 && r < rmax {
                spread[r] += (spec.mean[i * res + j] - mean_of(r)).powi(2);
            }
        }
    }
    (1..rmax)
        .map(|r| {
            let c = count[r] as f64;
            let mean = mean_of(r);
            let var = spread[r] / c;
            // Undefined on an annulus dark within the method's error (a lattice's exact zeros) or
            // flat within it (identical points: P = N everywhere): a ratio of errors.
            let anisotropy_db = (mean > dark && var.sqrt() > flat * mean)
                .then(|| 10.0 * (var / (mean * mean)).log10());
            RadialBin {
                r,
                r_normalized: r as f64 / (spec.n as f64).sqrt(),
                mean,
                // Every annulus here lies inside the grid, so it holds each bin's mirror.
                stderr: (spec.realizations > 1).then(|| (2.0 * var_sum[r]).sqrt() / c),
                anisotropy_db,
                cones: (0..cones)
                    .map(|k| {
                        (cone_count[r][k] > 0).then(|| cone_sum[r][k] / cone_count[r][k] as f64)
                    })
                    .collect(),
            }
        })
        .collect()
}

/// Largest `(10 eps)² N` at which [`dark_withheld_note`] stays silent: a zero bin's NUFFT error
/// bound below 1e-3 of white noise's `P = 1`, the level below which the accuracy contract stops.
const QUIET_DARK_BOUND: f64 = 1e-3;

/// A note for the user when the NUFFT's tolerance is too loose for `n` points to tell a dark annulus
/// from a bright one: `(10 eps)² N` (the error a bin whose `P` is 0 can hold, [`precision`]) is above
/// 1e-3 and `profile` withholds the anisotropy of some annulus whose mean is below it. It names the
/// count and the fix (the largest `eps` whose bound is at most 1e-3, or `--exact`). `None` otherwise,
/// and always for the exact DFT.
pub fn dark_withheld_note(profile: &[RadialBin], method: Method, n: usize) -> Option<String> {
    let Method::Nufft { eps } = method else {
        return None;
    };
    let (dark, _) = precision(method, n, 0);
    let withheld = profile
        .iter()
        .filter(|b| b.anisotropy_db.is_none() && b.mean <= dark)
        .count();
    if dark <= QUIET_DARK_BOUND || withheld == 0 {
        return None;
    }
    let wanted = (QUIET_DARK_BOUND / n as f64).sqrt() / 10.0;
    let suggested = 10f64
        .powf(wanted.log10().floor())
        .max(super::nufft::EPS_MIN);
    Some(format!(
        "note: at --eps {eps:e} with N = {n}, a bin whose P is 0 can read up to (10 eps)^2 N = {dark:.3} \
         with the NUFFT (when every point's error adds up, as on a lattice), so the radial profile leaves \
         the anisotropy out on {withheld} annuli whose mean is below that; for it, give --eps {suggested:e} \
         or less, or --exact (an annulus that is truly dark, as a lattice's, stays without one)"
    ))
}

/// Writes a radial profile as CSV: `r, r_normalized, mean, stderr, anisotropy_db` and one `cone_c` column
/// per cone, headed with the cone's centre angle in degrees (an empty cell where a cone has no bin, in
/// `stderr` from a single realization, and in `anisotropy_db` where it is undefined).
pub fn write_radial_csv(path: &Path, profile: &[RadialBin]) -> Result<()> {
    let cones = profile.first().map_or(0, |b| b.cones.len());
    write_atomic(path, |w| {
        write!(w, "r,r_normalized,mean,stderr,anisotropy_db")?;
        for c in 0..cones {
            write!(w, ",cone{c}_{:.1}deg", c as f64 * 180.0 / cones as f64)?;
        }
        writeln!(w)?;
        for b in profile {
            let stderr = b.stderr.map_or(String::new(), csv_number);
            let anisotropy = b.anisotropy_db.map_or(String::new(), csv_number);
            write!(
                w,
                "{},{},{},{stderr},{anisotropy}",
                b.r,
                csv_number(b.r_normalized),
                csv_number(b.mean)
            )?;
            for c in &b.cones {
                match c {
                    Some(v) => write!(w, ",{}", csv_number(*v))?,
                    None => write!(w, ",")?,
                }
            }
            writeln!(w)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cones_are_centred_on_axes() {
        assert_eq!(cone_index(5, 0, 4), 0);
        assert_eq!(cone_index(-5, 0, 4), 0);
        assert_eq!(cone_index(0, 5, 4), 2);
        assert_eq!(cone_index(0, -5, 4), 2);
        assert_eq!(cone_index(3, 3, 4), 1);
        assert_eq!(cone_index(-3, 3, 4), 3);
        assert_eq!(cone_index(3, -3, 4), 3);
    }

    /// The axes and diagonals, the directions that can lie on a cone's edge, go to the cone whose
    /// half-open range `[c − ½, c + ½)` (units of π / cones) holds them, in exact arithmetic, for
    /// every cone count: θ = q π/4 is in cone c when 4c − 2 <= q cones < 4c + 2 (mod 4 cones). The
    /// float formula put the k2 axis into the cone below its edge for 18 counts from 1 to 360 (25,
    /// 41, 42, 50, ...). Off those directions the float formula holds: its cone holds θ.
    #[test]
    fn frequencies_on_a_cone_edge_go_to_the_cone_above() {
        for cones in 1..=MAX_CONES {
            for (q, k) in [(0, (7, 0)), (1, (4, 4)), (2, (0, -9)), (3, (-2, 2))] {
                let c = cone_index(k.0, k.1, cones);
                let (lo, hi) = (4 * c as i64 - 2, 4 * c as i64 + 2);
                let at = (q * cones) as i64;
                let wrapped = lo + (at - lo).rem_euclid(4 * cones as i64);
                assert!(
                    (lo..hi).contains(&wrapped) && c < cones,
                    "cones={cones} q={q}: cone {c}"
                );
            }
            for (k1, k2) in [(3, 1), (-5, 2), (1, -7), (12, 5)] {
                let theta = (k2 as f64).atan2(k1 as f64).rem_euclid(PI) / PI * cones as f64;
                let c = cone_index(k1, k2, cones) as f64;
                let theta = c - 0.5 + (theta - (c - 0.5)).rem_euclid(cones as f64);
                assert!(
                    c - 0.5 <= theta && theta < c + 0.5,
                    "cones={cones} k=({k1}, {k2})"
                );
            }
        }
    }

    /// A 16 × 16 lattice's spectrum is 0 (within the method's error) off its dual lattice, which
    /// starts at |k| = 16: the annuli inside are dark and get no anisotropy; the one through the dual
    /// point (16, 0) mixes P = 256 with zeros and gets a finite one. Identical points (P = N
    /// everywhere) get none. A random set's annuli all get one. With the exact DFT and with the NUFFT
    /// at eps = 1e-6 (whose dark bins are far above the exact DFT's rounding).
    #[test]
    fn anisotropy_is_reported_only_where_it_means_something() {
        use rand::Rng as _;
        let res = 64;
        let mut rng = crate::rng::stream(1, 0);
        let random: Vec<[f64; 2]> = (0..256)
            .map(|_| [rng.random::<f64>(), rng.random::<f64>()])
            .collect();
        let lattice: Vec<[f64; 2]> = (0..256)
            .map(|i| [(i % 16) as f64 / 16.0, (i / 16) as f64 / 16.0])
            .collect();
        for method in [Method::Exact, Method::Nufft { eps: 1e-6 }] {
            let of = |pts: &[[f64; 2]]| {
                radial_profile(
                    &ExpectedSpectrum {
                        res,
                        n: pts.len(),
                        realizations: 1,
                        mean: crate::spectrum::power(pts, res, method),
                        stderr: vec![0.0; res * res],
                    },
                    0,
                    method,
                )
            };
            let prof = of(&lattice);
            assert!(
                prof[..15].iter().all(|b| b.anisotropy_db.is_none()),
                "{method:?}: {prof:?}"
            );
            assert!(
                prof[15].anisotropy_db.is_some_and(f64::is_finite),
                "{method:?}: {:?}",
                prof[15]
            );
            assert!(of(&[[0.3, 0.6]; 64])
                .iter()
                .all(|b| b.anisotropy_db.is_none()));
            assert!(of(&random)
                .iter()
                .all(|b| b.anisotropy_db.is_some_and(f64::is_finite)));
        }
    }

    /// With the NUFFT at a tolerance too loose for N, every annulus of a spectrum near 1 is below the
    /// error bound of a zero bin, `(10 eps)² N` (41 at eps = 1e-2, N = 4096): the anisotropy is
    /// withheld and the note names the count and the largest eps that brings the bound to 1e-3
    /// (1e-5: (1e-4)² · 4096 = 4.1e-5). A tolerance that fits N, and the exact DFT, give no note.
    #[test]
    fn a_loose_tolerance_is_noted_where_it_withholds_anisotropy() {
        let (res, n) = (16, 4096);
        let spec = ExpectedSpectrum {
            res,
            n,
            realizations: 8,
            mean: (0..res * res)
                .map(|i| 1.0 + 0.1 * (i as f64).sin())
                .collect(),
            stderr: vec![0.1; res * res],
        };
        let loose = Method::Nufft { eps: 1e-2 };
        let profile = radial_profile(&spec, 0, loose);
        assert!(profile.iter().all(|b| b.anisotropy_db.is_none()));
        let note = dark_withheld_note(&profile, loose, n).expect("a note");
        assert!(
            note.contains("on 7 annuli") && note.contains("--eps 1e-5 or less"),
            "{note}"
        );
        for method in [Method::Nufft { eps: 1e-5 }, Method::Exact] {
            let profile = radial_profile(&spec, 0, method);
            assert!(profile.iter().all(|b| b.anisotropy_db.is_some()));
            assert_eq!(dark_withheld_note(&profile, method, n), None);
        }
    }

    #[test]
    fn white_spectrum_profile_is_flat() {
        let res = 16;
        let spec = ExpectedSpectrum {
            res,
            n: 64,
            realizations: 4,
            mean: vec![1.0; res * res],
            stderr: vec![0.5; res * res],
        };
        let prof = radial_profile(&spec, 4, Method::Exact);
        assert_eq!(prof.len(), 7);
        for b in prof {
            assert_eq!(b.mean, 1.0);
            assert!(b.cones.iter().flatten().all(|&c| c == 1.0));
            // Bins of standard error 0.5 in mirror pairs: the annulus mean's is sqrt(2 c 0.25) / c
            // over its c bins, to rounding.
            let c = (0..res * res)
                .filter(|&i| {
                    let (k1, k2) = frequency(i, res);
                    annulus(k1, k2) == b.r
                })
                .count() as f64;
            let want = (2.0 * c * 0.25).sqrt() / c;
            assert!(
                b.stderr.is_some_and(|se| (se - want).abs() < 1e-15),
                "{b:?}, want {want}"
            );
        }
        // A flat annulus has no anisotropy to report (its variance is 0), rather than a floor in dB.
        assert!(radial_profile(&spec, 0, Method::Exact)
            .iter()
            .all(|b| b.anisotropy_db.is_none()));
        // One realization has no spread to estimate: no standard error, not a zero one.
        let one = ExpectedSpectrum {
            realizations: 1,
            stderr: vec![0.0; res * res],
            ..spec
        };
        assert!(radial_profile(&one, 0, Method::Exact)
            .iter()
            .all(|b| b.stderr.is_none()));
    }
}
