//! Sampling patterns: classical 2D and 4D constructions behind one [`Sampler`] trait, and a registry
//! that builds them by name.
//!
//! Every sampler draws a set from the generator it is handed, so a set is a function of the seed and
//! the set's index only ([`generate_sets`]), whatever the thread count.

pub mod compose;
pub mod disk;
pub mod grid;
pub mod lattice;
pub mod lowdisc;
pub mod oa;
pub mod pmj;
pub mod table;

pub use compose::{Paired, Pairing, Sheared};

use crate::error::{Error, Result};
use crate::points::{coordinate_count, PointSets};
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

    /// An error, naming the parameter or file at fault and a fix, if the construction exists for `n`
    /// (it passed [`Sampler::check_n`]) but cannot make sets there: a usage error for parameters
    /// that make a degenerate set (a lattice whose generating vector shares a factor with `n`), an
    /// input error for a table file of that `N` that cannot be read or holds other sets. Most
    /// samplers have neither.
    fn check_parameters(&self, _n: usize) -> Result<()> {
        Ok(())
    }

    /// One set of `n` points, `[n, dims]` row-major, in `[0,1)^dims`. `n` has passed [`Sampler::check_n`]
    /// and [`Sampler::check_parameters`].
    fn generate(&self, n: usize, rng: &mut Rng) -> Vec<f64>;

    /// One set moved by the Cranley–Patterson rotation `shift` (one entry per dimension, in `[0,1)`),
    /// as an unbiased estimator needs. The default shifts the generated set mod 1. A sampler whose sets
    /// are not periodic on the torus (the seam-free shear) shifts its underlying pattern instead, before
    /// transforming it: shifting afterwards would wrap the transformed set and cut a seam through it.
    fn generate_shifted(&self, n: usize, rng: &mut Rng, shift: &[f64]) -> Vec<f64> {
        let mut set = self.generate(n, rng);
        crate::points::toroidal_shift(&mut set, shift);
        set
    }

    /// For a sampler that shears the sets of another ([`Sheared`]): that sampler and the shear. The
    /// random shift moves the unsheared pattern, so the variance of DESIGN §4 holds in the pattern's
    /// frame, for the integrand pulled back through the shear ([`crate::variance::predict`]). `None`
    /// for every other sampler, and for a shear of 0, which moves no point.
    fn shear_frame(&self) -> Option<ShearFrame<'_>> {
        None
    }
}

/// The frame of a sheared sampler (see [`Sampler::shear_frame`]).
pub struct ShearFrame<'a> {
    /// The sampler whose sets are sheared.
    pub pattern: &'a dyn Sampler,
    /// Shear in `xu` (`x + sx u` carries the pattern's `x`).
    pub sx: f64,
    /// Shear in `yv`.
    pub sy: f64,
    /// How the shear is applied.
    pub mode: crate::points::shear::ShearMode,
}

/// Checks `n` for `sampler`, with a message naming the nearest valid `n`, and its parameters at `n`.
/// One set of `n` points must fit under [`crate::points::MAX_COORDINATES`]; the commands check every
/// N here before drawing.
pub fn validate_n(sampler: &dyn Sampler, n: usize) -> Result<()> {
    validate_n_of_sets(sampler, n, 1)
}

/// [`validate_n`] for `sets` sets of `n` points drawn together: the N a refusal names keeps all of
/// them under [`crate::points::MAX_COORDINATES`].
fn validate_n_of_sets(sampler: &dyn Sampler, n: usize, sets: usize) -> Result<()> {
    if n == 0 {
        return Err(Error::Usage(format!(
            "N = 0 asks for no points; {} needs at least one (e.g. N = {})",
            sampler.name(),
            usable_n(sampler, 1)
        )));
    }
    coordinate_count(1, n, sampler.dims()).map_err(Error::Usage)?;
    sampler.check_n(n).map_err(|nearest| {
        let largest = crate::points::MAX_COORDINATES / (sampler.dims() * sets.max(1));
        let nearest = if nearest > largest {
            // The nearest is past the coordinate limit: name the largest allowed within it.
            allowed_at_most(sampler, largest).map_or_else(
                || format!("{nearest}, past the limit of {largest} points"),
                |m| format!("{m} (the nearer {nearest} is past the limit of {largest} points)"),
            )
        } else {
            nearest.to_string()
        };
        Error::Usage(format!(
            "{} cannot make {n} point{}; the nearest N it allows is {nearest}",
            sampler.name(),
            if n == 1 { "" } else { "s" }
        ))
    })?;
    sampler.check_parameters(n)
}

/// The largest N at most `limit` that `sampler` allows, if any: from `limit` down, each step
/// mirrors the nearest allowed N above the current guess to below it, so the next nearest is the
/// allowed N below.
fn allowed_at_most(sampler: &dyn Sampler, limit: usize) -> Option<usize> {
    let mut guess = limit;
    while guess > 0 {
        match sampler.check_n(guess) {
            Ok(()) => return Some(guess),
            Err(nearest) if nearest <= limit => return Some(nearest),
            Err(nearest) => guess = guess.checked_sub(nearest.saturating_sub(guess) + 1)?,
        }
    }
    None
}

/// The first sampler of `built` that repeats an earlier one (the same built name: one sampler given
/// twice, or two spellings of it), described from `names`, the names as given, in order:
/// `'mj' twice`, or `'lattice:1:3' and 'lattice:01:3', both the sampler lattice:1:3`. A list of
/// samplers to compare names each once: a repeat would be measured twice and reported twice.
pub fn repeated(names: &[String], built: &[Box<dyn Sampler>]) -> Option<String> {
    built.iter().enumerate().find_map(|(j, b)| {
        let i = built[..j].iter().position(|a| a.name() == b.name())?;
        let (first, again) = (names[i].trim(), names[j].trim());
        Some(if first == again {
            format!("'{first}' twice")
        } else {
            format!("'{first}' and '{again}', both the sampler {}", b.name())
        })
    })
}

/// `n` if the sampler allows it, else its nearest valid N within the coordinate limit of one set.
pub fn usable_n(sampler: &dyn Sampler, n: usize) -> usize {
    let largest = crate::points::MAX_COORDINATES / sampler.dims();
    match sampler.check_n(n) {
        Ok(()) => n,
        Err(nearest) if nearest > largest => allowed_at_most(sampler, largest).unwrap_or(nearest),
        Err(nearest) => nearest,
    }
}

/// Draws `sets` independent sets of `n` points. Set `s` uses stream `s` of `seed`: the result does not
/// depend on the number of threads. All sets together must fit under
/// [`crate::points::MAX_COORDINATES`], checked before any is drawn.
pub fn generate_sets(sampler: &dyn Sampler, n: usize, sets: usize, seed: u64) -> Result<PointSets> {
    if sets == 0 {
        return Err(Error::Usage(
            "--sets 0 asks for nothing; give at least one set".into(),
        ));
    }
    coordinate_count(sets, n, sampler.dims()).map_err(Error::Usage)?;
    validate_n_of_sets(sampler, n, sets)?;
    let all: Vec<Vec<f64>> = (0..sets)
        .into_par_iter()
        .map(|s| sampler.generate(n, &mut rng::stream(seed, s as u64)))
        .collect();
    PointSets::from_sets(sampler.dims(), all)
}

/// The valid count nearest to `n` (at least 1) according to `valid`; ties go to the smaller count.
///
/// The search steps outwards one count at a time, so callers keep `n` under the coordinate limit
/// ([`crate::points::coordinate_count`]) first; it never steps past `usize::MAX`. Every caller's
/// `valid` accepts some count in `[1, usize::MAX]` (each sampler makes at least one size).
pub(crate) fn nearest_valid(n: usize, valid: impl Fn(usize) -> bool) -> usize {
    (0..=usize::MAX)
        .find_map(|d| {
            let below = n.checked_sub(d).filter(|&c| c >= 1 && valid(c));
            below.or_else(|| n.checked_add(d).filter(|&c| valid(c)))
        })
        .expect("some count is valid")
}

/// One entry of the sampler registry.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SamplerInfo {
    /// Registry name (`padded-NAME` and `xuyv-NAME` stand for the families over every 2D `NAME`).
    pub name: &'static str,
    /// Dimensions the name can be built in (`&[2]`, `&[4]` or `&[2, 4]`).
    pub dims: &'static [usize],
    /// One line on what it is.
    pub summary: &'static str,
    /// Which point counts `N` it accepts.
    pub valid_n: &'static str,
}

/// Names of the 2D samplers (each also usable as `padded-NAME` and `xuyv-NAME` in 4D).
pub const NAMES_2D: [&str; 11] = [
    "random", "jittered", "nrooks", "mj", "cmj", "pmj02", "poisson", "blue", "halton", "sobol",
    "lattice",
];

/// Names of the native 4D samplers.
pub const NAMES_4D: [&str; 7] = [
    "random", "jittered", "nrooks", "halton", "sobol", "oa", "lattice",
];

/// Every sampler name with its dimensions, a summary and its valid `N`.
pub fn catalog() -> Vec<SamplerInfo> {
    let e = |name, dims, summary, valid_n| SamplerInfo {
        name,
        dims,
        summary,
        valid_n,
    };
    vec![
        e("random", &[2, 4], "uniform random points (white noise)", "any N"),
        e("jittered", &[2, 4], "one random point per cell of an m^D grid", "N = m^2 (2D), N = m^4 (4D)"),
        e("nrooks", &[2, 4], "N-rooks / Latin hypercube: every 1D projection N-stratified", "any N"),
        e("mj", &[2], "multi-jittered (Chiu, Shirley & Wang 1994): m x n cells and N-rooks", "N = m*n, m = floor(sqrt N) dividing N"),
        e("cmj", &[2], "correlated multi-jittered (Kensler 2013): m x n cells and N-rooks, shared shuffles", "N = m*n, m = floor(sqrt N) dividing N"),
        e("pmj02", &[2], "progressive multi-jittered (0,2) (Christensen et al. 2018); prefixes of 2^m are (0,m,2)-nets", "any N <= 2^20"),
        e("poisson", &[2], "Poisson disk by dart throwing on the torus, radius 0.75 of hexagonal packing", "any N <= 2^18"),
        e("blue", &[2], "blue noise: 20 Lloyd iterations on the torus (32 probes per point)", "any N <= 2^18"),
        e("halton", &[2, 4], "Halton, bases 2,3 (2D) or 2,3,5,7 (4D), random digit permutations", "any N"),
        e("sobol", &[2, 4], "Owen-scrambled Sobol (Burley 2020), f32 resolution", "any N <= 65536"),
        e("lattice", &[2, 4], "rank-1 lattice i z/N mod 1, randomly shifted; z = (1, g) or Korobov (1, a, a^2, a^3) with the longest shortest dual vector (4D: worst 2D projection)", "any N <= 2^20"),
        e("oa", &[4], "orthogonal-array sampling, Bose OA(p^2, p+1, p, 2): 2D projections p x p, 1D N-stratified", "N = p^2, p an odd prime"),
        e("padded-NAME", &[4], "Cook padding: 2D sets of NAME in xy and uv joined by a random permutation", "the N that NAME allows"),
        e("xuyv-NAME", &[4], "2D sets of NAME in xu and yv joined by a random permutation", "the N that NAME allows"),
    ]
}

/// One line on what the sampler `name` is: its [`catalog`] summary; for `padded-NAME` and
/// `xuyv-NAME`, the family's with `NAME`'s own. `None` for a name the catalog does not hold
/// (`table:` and `lattice:` sets, whose summaries depend on the file or vector).
pub fn summary(name: &str) -> Option<String> {
    let entries = catalog();
    let of = |n: &str| entries.iter().find(|e| e.name == n).map(|e| e.summary);
    for (prefix, family) in [("padded-", "padded-NAME"), ("xuyv-", "xuyv-NAME")] {
        if let Some(inner) = name.strip_prefix(prefix) {
            return Some(format!(
                "{}; {inner}: {}",
                of(family)?.replace("NAME", inner),
                of(inner)?
            ));
        }
    }
    of(name).map(String::from)
}

/// A 2D sampler by name.
fn build_2d(name: &str) -> Option<Box<dyn Sampler>> {
    Some(match name {
        "random" => Box::new(grid::Random { dims: 2 }),
        "jittered" => Box::new(grid::Jittered { dims: 2 }),
        "nrooks" => Box::new(grid::NRooks { dims: 2 }),
        "mj" => Box::new(grid::MultiJittered),
        "cmj" => Box::new(grid::CorrelatedMultiJittered),
        "pmj02" => Box::new(pmj::Pmj02),
        "poisson" => Box::new(disk::Poisson::default()),
        "blue" => Box::new(disk::Blue),
        "halton" => Box::new(lowdisc::Halton { dims: 2 }),
        "sobol" => Box::new(lowdisc::Sobol { dims: 2 }),
        "lattice" => Box::new(lattice::Lattice { dims: 2 }),
        _ => return None,
    })
}

/// A native 4D sampler by name.
fn build_4d(name: &str) -> Option<Box<dyn Sampler>> {
    Some(match name {
        "random" => Box::new(grid::Random { dims: 4 }),
        "jittered" => Box::new(grid::Jittered { dims: 4 }),
        "nrooks" => Box::new(grid::NRooks { dims: 4 }),
        "halton" => Box::new(lowdisc::Halton { dims: 4 }),
        "sobol" => Box::new(lowdisc::Sobol { dims: 4 }),
        "oa" => Box::new(oa::OrthogonalArray),
        "lattice" => Box::new(lattice::Lattice { dims: 4 }),
        _ => return None,
    })
}

/// Edit distance with adjacent transpositions (optimal string alignment), for suggesting the closest
/// name: `cjm` is one step from `cmj`.
fn edit_distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    let w = b.len() + 1;
    let mut d = vec![0usize; (a.len() + 1) * w];
    for i in 0..=a.len() {
        for j in 0..=b.len() {
            d[i * w + j] = if i == 0 || j == 0 {
                i + j
            } else {
                let sub = d[(i - 1) * w + j - 1] + usize::from(a[i - 1] != b[j - 1]);
                let mut best = sub.min(d[(i - 1) * w + j] + 1).min(d[i * w + j - 1] + 1);
                if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                    best = best.min(d[(i - 2) * w + j - 2] + 1);
                }
                best
            };
        }
    }
    d[a.len() * w + b.len()]
}

/// A pairing name's prefix and inner 2D name: `padded-mj` → `("padded", "mj")`, whether or not the
/// inner name exists.
fn pairing_parts(name: &str) -> Option<(&'static str, &str)> {
    [Pairing::Padded, Pairing::Xuyv].into_iter().find_map(|p| {
        Some((
            p.prefix(),
            name.strip_prefix(p.prefix())?.strip_prefix('-')?,
        ))
    })
}

/// For the 2D name inside `padded-NAME` / `xuyv-NAME`: empty if it is a 2D sampler, else a clause
/// saying it is not one: a pairing itself (pairings do not nest), or with the closest 2D name and
/// the list.
fn unknown_inner(inner: &str) -> String {
    if build_2d(inner).is_some() {
        return String::new();
    }
    if pairing_parts(inner).is_some() {
        return format!(
            "; and '{inner}' is already a 4D pairing, which does not nest: write '{inner}' alone"
        );
    }
    let closest = NAMES_2D
        .iter()
        .min_by_key(|n| edit_distance(inner, n))
        .expect("names exist");
    format!(
        "; and '{inner}' is not a 2D sampler (did you mean '{closest}'?); 2D names: {}",
        NAMES_2D.join(", ")
    )
}

/// Every name valid in `dims` dimensions, families expanded.
fn names_in(dims: usize) -> Vec<String> {
    if dims == 2 {
        NAMES_2D.iter().map(|s| s.to_string()).collect()
    } else {
        let mut v: Vec<String> = NAMES_4D.iter().map(|s| s.to_string()).collect();
        for prefix in ["padded", "xuyv"] {
            v.extend(NAMES_2D.iter().map(|s| format!("{prefix}-{s}")));
        }
        v
    }
}

/// The files a sampler name reads (the tables of `table:PATH`), so that commands can refuse to write
/// over them; empty for the built-in samplers and for a pattern that matches nothing (building the
/// sampler reports that).
pub fn input_files(name: &str) -> Vec<std::path::PathBuf> {
    name.strip_prefix("table:")
        .and_then(|pattern| table::files(pattern).ok())
        .map(|files| files.into_iter().map(|(path, _)| path).collect())
        .unwrap_or_default()
}

/// Builds the sampler `name` in `dims` (2 or 4) dimensions.
///
/// 2D: the names of [`NAMES_2D`]. 4D: [`NAMES_4D`], and `padded-NAME` / `xuyv-NAME` for every 2D
/// `NAME`. An unknown name, a 2D-only name asked in 4D, or a 4D-only name asked in 2D is an
/// `Error::Usage` that lists the valid names and suggests the closest.
pub fn build(name: &str, dims: usize) -> Result<Box<dyn Sampler>> {
    if dims != 2 && dims != 4 {
        return Err(Error::Usage(format!(
            "--dims {dims} is not supported; samplers make 2D (x,y) or 4D (x,y,u,v) sets"
        )));
    }
    if name.trim().is_empty() {
        return Err(Error::Usage(
            "the sampler name is empty; give a sampler's name (`anisospec samplers` lists them)"
                .into(),
        ));
    }
    if let Some(pattern) = name.strip_prefix("table:") {
        return Ok(Box::new(table::Table::load(pattern, dims)?));
    }
    if let Some(z) = name.strip_prefix("lattice:") {
        return Ok(Box::new(lattice::GivenLattice::parse(z, dims)?));
    }
    if dims == 2 {
        if let Some(s) = build_2d(name) {
            return Ok(s);
        }
        // A pairing family is 4D whatever its 2D name; say so first, then whether the name exists.
        if let Some((prefix, inner)) = pairing_parts(name) {
            return Err(Error::Usage(format!(
                "sampler '{name}' makes 4D sets ({prefix}-NAME pairs two 2D sets), but 2D sets are asked here; ask for 4D (--dims 4 in sample, spectrum and optimize, a 4D integrand in variance and converge){}",
                unknown_inner(inner)
            )));
        }
        if names_in(4).iter().any(|n| n == name) {
            return Err(Error::Usage(format!(
                "sampler '{name}' makes 4D sets, but 2D sets are asked here; ask for 4D (--dims 4 in sample, spectrum and optimize, a 4D integrand in variance and converge) or use one of the 2D samplers: {}",
                NAMES_2D.join(", ")
            )));
        }
    } else {
        if let Some(s) = build_4d(name) {
            return Ok(s);
        }
        for pairing in [Pairing::Padded, Pairing::Xuyv] {
            if let Some(inner) = name
                .strip_prefix(pairing.prefix())
                .and_then(|rest| rest.strip_prefix('-'))
                .and_then(build_2d)
            {
                return Ok(Box::new(Paired::new(inner, pairing)?));
            }
        }
        if build_2d(name).is_some() {
            return Err(Error::Usage(format!(
                "sampler '{name}' is 2D only; in 4D use padded-{name} (xy and uv) or xuyv-{name} (xu and yv)"
            )));
        }
        if let Some((prefix, inner)) = pairing_parts(name) {
            return Err(Error::Usage(format!(
                "sampler '{name}': {prefix}-NAME needs a 2D sampler NAME{}",
                unknown_inner(inner)
            )));
        }
    }
    let valid = names_in(dims);
    let closest = valid
        .iter()
        .min_by_key(|n| edit_distance(name, n))
        .expect("names exist");
    Err(Error::Usage(format!(
        "unknown {dims}D sampler '{name}' (did you mean '{closest}'?); valid names: {}",
        valid.join(", ")
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An empty name, an empty table path and a 4D pairing asked in 2D each get their own message.
    #[test]
    fn name_messages_say_what_is_wrong() {
        let msg = |name: &str, dims: usize| {
            let e = build(name, dims).err().expect("refused");
            assert_eq!(e.exit_code(), 2, "{name}: {e}");
            e.to_string()
        };
        for dims in [2, 4] {
            let m = msg("", dims);
            assert!(
                m.contains("name is empty") && m.contains("anisospec samplers"),
                "{m}"
            );
            let m = msg("table:", dims);
            assert!(
                m.contains("names no table") && m.contains("table:sets.npy"),
                "{m}"
            );
        }
        let m = msg("padded-nosuch", 2);
        assert!(m.contains("4D") && m.contains("--dims 4"), "{m}");
        assert!(m.contains("'nosuch' is not a 2D sampler"), "{m}");
        let m = msg("xuyv-mj", 2);
        assert!(
            m.contains("--dims 4") && !m.contains("not a 2D sampler"),
            "{m}"
        );
        let m = msg("padded-nosuch", 4);
        assert!(m.contains("padded-NAME needs a 2D sampler"), "{m}");
        let m = msg("padded-xuyv-mj", 4);
        assert!(m.contains("write 'xuyv-mj' alone"), "{m}");
        assert!(build("padded-mj", 4).is_ok());
    }

    #[test]
    fn edit_distance_counts_transpositions() {
        assert_eq!(edit_distance("cjm", "cmj"), 1);
        assert_eq!(edit_distance("sobol", "sobol"), 0);
        assert_eq!(edit_distance("", "oa"), 2);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
    }

    #[test]
    fn sizes_above_the_limit_are_refused_before_drawing() {
        let random = grid::Random { dims: 2 };
        for (n, sets) in [(usize::MAX, 1), (1 << 62, 4), (1 << 28, 1), (1 << 26, 8)] {
            let e = generate_sets(&random, n, sets, 0).unwrap_err();
            assert_eq!(e.exit_code(), 2);
            assert!(
                e.to_string().contains("above the limit"),
                "{n} x {sets}: {e}"
            );
        }
        assert!(validate_n(&random, 1 << 27).is_ok());
        assert!(validate_n(&grid::Random { dims: 4 }, 1 << 27).is_err());
    }

    #[test]
    fn nearest_valid_prefers_smaller_on_ties() {
        assert_eq!(nearest_valid(50, |c| c == 49 || c == 51), 49);
        assert_eq!(nearest_valid(3, |c| c == 1 || c == 5), 1);
        assert_eq!(nearest_valid(1, |c| c == 9), 9);
        // Near the top of usize the upward search stops at usize::MAX: a wrapped step would reach
        // 1 (two counts away) before usize::MAX − 5.
        let top = |c| c == 1 || c == usize::MAX - 5;
        assert_eq!(nearest_valid(usize::MAX, top), usize::MAX - 5);
        assert_eq!(
            nearest_valid(usize::MAX - 1, |c| c == usize::MAX),
            usize::MAX
        );
    }
}
