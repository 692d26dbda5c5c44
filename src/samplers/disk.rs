//! Point sets shaped by distances on the torus: Poisson disk by dart throwing, and blue noise by Lloyd
//! relaxation. Neighbour queries use kiddo's periodic-boundary k-d tree queries.

use super::Sampler;
use crate::error::{Error, Result};
use crate::rng::Rng;
use kiddo::{ImmutableKdTree, MutableKdTree, SquaredEuclidean};
use rand::Rng as _;

/// Period of the unit torus, for kiddo's periodic queries.
const TORUS: [f64; 2] = [1.0, 1.0];

/// Radius of the densest packing of `n` disks on the unit torus (hexagonal): the minimum distance
/// `sqrt(2 / (sqrt(3) n))` of a hexagonal lattice with `n` points per unit area.
pub fn max_packing_radius(n: usize) -> f64 {
    (2.0 / (3f64.sqrt() * n as f64)).sqrt()
}

/// Default Poisson-disk radius relative to [`max_packing_radius`].
pub const DEFAULT_RELATIVE_RADIUS: f64 = 0.75;

/// Darts thrown per requested point at one radius before that radius is given up.
pub const DARTS_PER_POINT: usize = 2000;

/// Factor applied to the radius by [`Sampler::generate`] each time the dart budget runs out.
pub const RADIUS_BACKOFF: f64 = 0.95;

/// Poisson-disk sampling by dart throwing on the torus: uniform darts, each kept if its toroidal
/// distance to every kept point is at least `r = relative_radius · sqrt(2 / (sqrt(3) N))`.
///
/// Dart throwing jams near a relative radius of about 0.78 (random sequential adsorption covers at
/// most ~55 % of the area), so the number of darts is bounded: [`DARTS_PER_POINT`]` · N` per radius.
/// - [`Poisson::try_generate`] keeps the requested radius and returns an [`Error::Numerical`] when
///   the darts run out;
/// - [`Sampler::generate`] keeps the points placed so far, multiplies the radius by
///   [`RADIUS_BACKOFF`] and goes on, so it always returns `N` points whose minimum toroidal distance is
///   at least the last radius used. At the default relative radius 0.75 the first budget suffices.
#[derive(Clone, Debug)]
pub struct Poisson {
    relative_radius: f64,
}

impl Poisson {
    /// A Poisson-disk sampler; `relative_radius` must lie in `(0, 1]` (1 is the hexagonal packing,
    /// which no finite dart throwing reaches).
    pub fn new(relative_radius: f64) -> Result<Self> {
        if !(relative_radius > 0.0 && relative_radius <= 1.0) {
            return Err(Error::Usage(format!(
                "Poisson-disk relative radius {relative_radius} is out of range; give a value in (0, 1] \
                 (1 = hexagonal packing; dart throwing jams near 0.78, default {DEFAULT_RELATIVE_RADIUS})"
            )));
        }
        Ok(Self { relative_radius })
    }

    /// The relative radius (fraction of [`max_packing_radius`]).
    pub fn relative_radius(&self) -> f64 {
        self.relative_radius
    }

    /// The absolute minimum distance requested for `n` points.
    pub fn radius(&self, n: usize) -> f64 {
        self.relative_radius * max_packing_radius(n)
    }

    /// `n` points at the requested radius, or an error if [`DARTS_PER_POINT`]` · n` darts did not
    /// place them all.
    pub fn try_generate(&self, n: usize, rng: &mut Rng) -> Result<Vec<f64>> {
        let r = self.radius(n);
        let mut state = Darts::new(n);
        if state.throw(r, n, rng) {
            Ok(state.points)
        } else {
            Err(Error::Numerical(format!(
                "Poisson disk: dart throwing placed only {} of {n} points at relative radius {} after {} darts; \
                 lower the radius (dart throwing jams near 0.78)",
                state.points.len() / 2,
                self.relative_radius,
                DARTS_PER_POINT * n
            )))
        }
    }
}

impl Poisson {
    /// What [`Sampler::generate`] does, also returning the relative radius finally kept: the
    /// requested one, or a power of [`RADIUS_BACKOFF`] times it if the darts ran out. The minimum
    /// toroidal distance of the set is at least that radius times [`max_packing_radius`]`(n)`.
    pub fn generate_reporting(&self, n: usize, rng: &mut Rng) -> (Vec<f64>, f64) {
        let mut rel = self.relative_radius;
        let mut state = Darts::new(n);
        while !state.throw(rel * max_packing_radius(n), n, rng) {
            rel *= RADIUS_BACKOFF;
        }
        (state.points, rel)
    }
}

impl Default for Poisson {
    fn default() -> Self {
        Self {
            relative_radius: DEFAULT_RELATIVE_RADIUS,
        }
    }
}

/// Points kept so far and their k-d tree.
struct Darts {
    points: Vec<f64>,
    tree: MutableKdTree<f64, 2>,
}

impl Darts {
    fn new(n: usize) -> Self {
        Self {
            points: Vec::with_capacity(2 * n),
            tree: MutableKdTree::default(),
        }
    }

    /// Throws up to `DARTS_PER_POINT * n` darts at radius `r`; true once `n` points are kept.
    fn throw(&mut self, r: f64, n: usize, rng: &mut Rng) -> bool {
        let r2 = r * r;
        for _ in 0..DARTS_PER_POINT * n {
            if self.points.len() >= 2 * n {
                return true;
            }
            let p = [rng.random::<f64>(), rng.random::<f64>()];
            let ok = self.points.is_empty()
                || self
                    .tree
                    .query(&p)
                    .periodic_boundary_condition(&TORUS)
                    .nearest_one::<SquaredEuclidean<f64>>()
                    .execute()
                    .distance
                    >= r2;
            if ok {
                self.tree
                    .add(&p, (self.points.len() / 2) as u32)
                    .expect("k-d tree insertion");
                self.points.extend_from_slice(&p);
            }
        }
        self.points.len() >= 2 * n
    }
}

/// Largest `N` of [`Poisson`] and [`Blue`], whose cost grows faster than `N` (one set of 2^18
/// points: 81 s for `blue`, 8 s for `poisson`, on the 2-core development machine);
/// larger sets would run for hours with nothing to show. Sobol, PMJ02 and the lattice go further.
pub const DISK_MAX_N: usize = 1 << 18;

/// Any `n` up to [`DISK_MAX_N`], else that limit as the nearest valid `n`.
fn check_disk_n(n: usize) -> std::result::Result<(), usize> {
    if n <= DISK_MAX_N {
        Ok(())
    } else {
        Err(DISK_MAX_N)
    }
}

impl Sampler for Poisson {
    fn name(&self) -> String {
        "poisson".into()
    }
    fn dims(&self) -> usize {
        2
    }
    fn check_n(&self, n: usize) -> std::result::Result<(), usize> {
        check_disk_n(n)
    }
    fn generate(&self, n: usize, rng: &mut Rng) -> Vec<f64> {
        self.generate_reporting(n, rng).0
    }
}

/// Lloyd iterations of [`Blue`].
pub const LLOYD_ITERATIONS: usize = 20;

/// Uniform probes per point in each Lloyd iteration of [`Blue`].
pub const PROBES_PER_POINT: usize = 32;

/// Relaxed blue noise: `N` uniform random points moved by [`LLOYD_ITERATIONS`] Lloyd iterations on
/// the torus. Each iteration throws [`PROBES_PER_POINT`]` · N` fresh uniform probes, assigns each to
/// its nearest point (kiddo periodic nearest-neighbour query) and moves every point to the toroidal
/// centroid of its probes (the mean of the wrapped probe-to-point offsets). Any `N` up to 2^18.
#[derive(Clone, Debug)]
pub struct Blue;

impl Sampler for Blue {
    fn name(&self) -> String {
        "blue".into()
    }
    fn dims(&self) -> usize {
        2
    }
    fn check_n(&self, n: usize) -> std::result::Result<(), usize> {
        check_disk_n(n)
    }
    fn generate(&self, n: usize, rng: &mut Rng) -> Vec<f64> {
        let mut sites: Vec<[f64; 2]> = (0..n)
            .map(|_| [rng.random::<f64>(), rng.random::<f64>()])
            .collect();
        let mut sum = vec![[0.0f64; 2]; n];
        let mut count = vec![0usize; n];
        for _ in 0..LLOYD_ITERATIONS {
            let tree: ImmutableKdTree<f64, 2> =
                ImmutableKdTree::new_from_slice(&sites).expect("k-d tree construction");
            sum.iter_mut().for_each(|s| *s = [0.0; 2]);
            count.iter_mut().for_each(|c| *c = 0);
            for _ in 0..PROBES_PER_POINT * n {
                let p = [rng.random::<f64>(), rng.random::<f64>()];
                let near = tree
                    .query(&p)
                    .periodic_boundary_condition(&TORUS)
                    .nearest_one::<SquaredEuclidean<f64>>()
                    .execute()
                    .item as usize;
                for d in 0..2 {
                    // Offset to the probe's nearest periodic image, in [-1/2, 1/2).
                    sum[near][d] += (p[d] - sites[near][d] + 0.5).rem_euclid(1.0) - 0.5;
                }
                count[near] += 1;
            }
            for ((s, t), &c) in sites.iter_mut().zip(&sum).zip(&count) {
                if c > 0 {
                    for d in 0..2 {
                        s[d] = crate::points::wrap(s[d] + t[d] / c as f64)
                            .min(crate::points::BELOW_ONE);
                    }
                }
            }
        }
        sites.into_iter().flatten().collect()
    }
}
