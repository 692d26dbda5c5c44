//! Optimized tables for the compare study: built for each target, shear range and N when missing,
//! cached when present.
//!
//! Shape tables are designed in the frame of their *frame shear* (see [`frame_shear`]) — a widened
//! hairline around the `k1` axis, a double wedge over the subject's shear range taken relative to it —
//! and moved at use by the subject's shear ([`super::Subject::shear`]: the oracle's, or a double-wedge
//! pixel's range midpoint) with the seam-free (transported) shear, which carries a
//! pattern direction of slope `a` to slope `s + a`. One table then serves every depth, and the pattern
//! never wraps across the pixel boundary (the seam that defeats the wrap-around shear, DESIGN §5). A
//! variance table is designed for the integrand family and shear its file names, built once per N,
//! and moved by each subject's shear (see [`moved`]).

use super::config::CompareConfig;
use crate::error::{Error, Result};
use crate::optimize::{
    lattice_design, optimize_sets, Limits, Setup, Strata, DEFAULT_ANNULAR_WEIGHT, DEFAULT_REPULSION,
};
use crate::points::io::write_points;
use crate::points::shear::ShearMode;
use crate::points::PointSets;
use crate::samplers::table::Table;
use crate::samplers::{Sampler, Sheared};
use crate::spectrum::Method;
use crate::targets::variance::Design;
use crate::targets::Target;
use std::path::{Path, PathBuf};

/// The narrowest double wedge a table is built for: half-width 0.05 in slope, for subjects whose shear
/// range is (nearly) a single shear.
pub const MIN_WEDGE_HALF_WIDTH: f64 = 0.05;

/// Optimizer iterations per set: the binding limit, so a table does not depend on machine speed.
pub const TABLE_ITERATIONS: u64 = 300;

/// Where tables are cached and how they are built.
pub struct TableCache {
    dir: PathBuf,
    sets: usize,
    seconds: f64,
    seed: u64,
    /// Cached tables already warned about (sets stopped at the time limit), so that the warning
    /// comes once per table however often the study uses it.
    warned: std::sync::Mutex<Vec<PathBuf>>,
}

/// The shear whose frame a table for a subject with shears `range` is designed in: 0 when the range
/// holds an in-focus layer (a sharp edge in x and y alone, which only a held, unsheared (0,2)-net in
/// xy integrates at the in-focus rate), else the range's centre. Measured on the default scene's
/// double-wedge pixel (shears -0.71 to 0, 99 % of its xu energy on the in-focus edge's k1 axis) at
/// N = 1024: MSE 2.1e-6 in the frame of 0, 4.5e-6 in the frame of the centre.
pub fn frame_shear(range: (f64, f64)) -> f64 {
    if range.0 <= 0.0 && 0.0 <= range.1 {
        0.0
    } else {
        0.5 * (range.0 + range.1)
    }
}

/// Whether a table of `target` for a subject whose shears span `range` is moved by the oracle's
/// shear at use: a variance target always (it is designed for the shear it names, which stands for
/// the oracle's), a shape target unless its frame shear is 0 (an in-focus layer).
pub fn moved(target: &Target, range: (f64, f64)) -> bool {
    matches!(target, Target::Variance(_)) || frame_shear(range) != 0.0
}

/// The target in the file `target` (or built in: see [`Target::load`]) moved into the frame of
/// [`frame_shear`] for a subject whose shears span `range` (see [`table_frame`]): what a table of it
/// is designed for.
pub fn framed_target(target: &Path, range: (f64, f64)) -> Result<Target> {
    Ok(table_frame(Target::load(target)?, range))
}

/// The target moved into the frame of [`frame_shear`] for a subject whose shears span `range`: a
/// hairline becomes unsheared, a double wedge spans `range` minus the frame shear (at least
/// [`MIN_WEDGE_HALF_WIDTH`] either side of its middle).
pub fn table_frame(target: Target, range: (f64, f64)) -> Target {
    match target {
        Target::Hairline(mut h) => {
            h.shear = 0.0;
            Target::Hairline(h)
        }
        Target::DoubleWedge(mut w) => {
            let frame = frame_shear(range);
            let middle = 0.5 * (range.0 + range.1) - frame;
            let half = (0.5 * (range.1 - range.0)).max(MIN_WEDGE_HALF_WIDTH);
            w.s0 = middle - half;
            w.s1 = middle + half;
            Target::DoubleWedge(w)
        }
        other => other,
    }
}

/// The target, with its dark region shrunk in steps of 10 % in extent until `n` points can reach it
/// (a shipped target is sized for N of a few hundred; at N = 16 its dark area may exceed the N cells
/// that 2N degrees of freedom can darken, DESIGN §6). A lattice design or mixture has no loss grid
/// and is returned as it is.
pub fn within_reach(mut target: Target, n: usize) -> Result<Target> {
    if matches!(&target, Target::Variance(v) if v.design() != Design::Points) {
        return Ok(target);
    }
    for _ in 0..40 {
        match target.grid(n) {
            Ok(_) => return Ok(target),
            Err(e) => match &mut target {
                Target::Hairline(h) => {
                    h.length *= 0.9;
                    h.inner_radius *= 0.9;
                }
                Target::DoubleWedge(w) => {
                    w.radius *= 0.9;
                    w.inner_radius *= 0.9;
                }
                _ => return Err(e),
            },
        }
    }
    target.grid(n).map(|_| target)
}

/// The start of a table's sets: Owen-scrambled Sobol where `n` is a power of two (its xy is a
/// (0,2)-net and its xu and yv keep part of their structure through the optimization: 5-15 % lower
/// MSE than a padded PMJ02 start on the hairline edge with the shear off by 10-25 % at N = 1024, the
/// same on the fan; up to Sobol's largest N), else padded PMJ02 (xy and uv (0,2)-nets) where it
/// allows `n`, else padded MJ.
/// All are N-stratified in every coordinate.
pub fn start_sampler(n: usize) -> &'static str {
    let sobol = crate::samplers::build("sobol", 4).expect("a built-in sampler");
    let pmj = crate::samplers::build("padded-pmj02", 4).expect("a built-in sampler");
    if n.is_power_of_two() && sobol.check_n(n).is_ok() {
        "sobol"
    } else if pmj.check_n(n).is_ok() {
        "padded-pmj02"
    } else {
        "padded-mj"
    }
}

impl TableCache {
    /// Tables of `config.table_sets` sets, cached under `cache_dir/tables`.
    pub fn new(config: &CompareConfig, cache_dir: &Path) -> Self {
        Self {
            dir: cache_dir.join("tables"),
            sets: config.table_sets,
            seconds: config.table_seconds,
            seed: config.seed,
            warned: Default::default(),
        }
    }

    /// The sampler of `target` at `n` points for a subject with shear `shear` ([`super::Subject::shear`]) and shear range
    /// `range`, and the seconds its table took to optimize (when it was built, cached or not). The
    /// table is moved by `shear`, or not at all (see [`moved`]).
    pub fn sampler(
        &self,
        target: &Path,
        shear: (f64, f64),
        range: (f64, f64),
        n: usize,
    ) -> Result<(Box<dyn Sampler>, f64)> {
        let framed = within_reach(framed_target(target, range)?, n)?;
        let (table, seconds) = self.table(target, &framed, n)?;
        let shear = if moved(&framed, range) {
            shear
        } else {
            (0.0, 0.0)
        };
        let sampler = Sheared::new(Box::new(table), shear.0, shear.1, ShearMode::Transported)?;
        Ok((Box::new(sampler), seconds))
    }

    /// The cached table, optimized and written first if missing or unreadable, and its optimization
    /// time. An unreadable cache file is rebuilt, with a warning, as the pixel references are.
    fn table(&self, source: &Path, target: &Target, n: usize) -> Result<(Table, f64)> {
        // A variance target's Debug text holds its resolved defaults; how it is sampled has a version,
        // and a lattice design the grid it searched over.
        let sampling = match target {
            Target::Variance(v) => format!(
                "|sampling=v{}{}",
                crate::targets::variance::SAMPLING_VERSION,
                match v.design() {
                    Design::Lattice => format!("|lattice-search={}", lattice_design::SEARCH_RES),
                    Design::LatticeMixture => format!(
                        "|lattice-mixture={},{}",
                        lattice_design::SEARCH_RES,
                        lattice_design::MIXTURE_ERRORS
                    ),
                    Design::Points => String::new(),
                }
            ),
            _ => String::new(),
        };
        // Everything the optimizer is given (its Debug text: target, strata, repulsion, Fourier
        // method, iteration budget, start, Latin hold) but the time limit, a safety net whose stops
        // are warned about, so that a longer limit reuses the tables (unless their sets stopped at
        // a shorter one: see below).
        let key = format!(
            "{:?}|sets={}|seed={}|v8{sampling}",
            table_setup(target.clone(), n, 0.0),
            self.sets,
            self.seed
        );
        // At most 100 bytes of the target's name (the hash tells tables apart), so that the cache
        // file's name stays within a file system's 255 bytes whatever the target is called.
        let stem: String = source
            .file_stem()
            .map_or_else(|| "table".into(), |s| s.to_string_lossy().into_owned())
            .chars()
            .scan(0, |bytes, c| {
                *bytes += c.len_utf8();
                (*bytes <= 100).then_some(c)
            })
            .collect();
        let path = self.dir.join(format!(
            "{stem}_n{n}_{:016x}.npy",
            crate::output::stable_hash(key.as_bytes())
        ));
        let meta = path.with_extension("json");
        if let (true, Ok(text)) = (path.is_file(), std::fs::read_to_string(&meta)) {
            if let Ok(m) = serde_json::from_str::<serde_json::Value>(&text) {
                // A sidecar without its set-up time is as good as missing: rebuild. So is a table
                // whose sets stopped at a time limit shorter than this run's (or unrecorded): this
                // run would let them go further.
                let stopped = m["sets_stopped_by_time_limit"].as_u64().unwrap_or(0);
                let limit = m["table_seconds"].as_f64();
                let cut_short = stopped > 0 && limit.is_none_or(|l| l < self.seconds);
                if let (true, Some(seconds)) = (m["key"] == key, m["seconds"].as_f64()) {
                    if cut_short {
                        crate::eprintln_best_effort!(
                            "note: rebuilding the cached {} table at N = {n}: {stopped} of its sets stopped at the time limit ({}), and table_seconds is now {} s",
                            source.display(),
                            limit.map_or("not recorded".into(), |l| format!("{l} s")),
                            self.seconds
                        );
                    } else {
                        match load_table(&path, n, self.sets) {
                            Ok(table) => {
                                let mut warned = self.warned.lock().expect("warned lock");
                                if stopped > 0 && !warned.contains(&path) {
                                    warned.push(path.clone());
                                    crate::eprintln_best_effort!(
                                        "warning: the cached {} table at N = {n} has {stopped} sets that stopped at the time limit ({} s); raise table_seconds to rebuild it further",
                                        source.display(),
                                        limit.unwrap_or(self.seconds)
                                    );
                                }
                                return Ok((table, seconds));
                            }
                            Err(e) => {
                                crate::eprintln_best_effort!(
                                    "warning: rebuilding an unreadable cached table: {e}"
                                )
                            }
                        }
                    }
                }
            }
        }
        let (points, timed_out, seconds) = match target {
            Target::Variance(v) if v.design() == Design::Lattice => {
                // The search grid's spectrum is computed once per process and shared by every N:
                // each table is charged its full computation time, as a run at that N alone pays.
                let (_, spectrum_seconds) = v.spectrum_timed(lattice_design::SEARCH_RES)?;
                let started = std::time::Instant::now();
                let design = lattice_design::design(v, n, 4)?;
                let sets = PointSets::from_sets(4, vec![design.points(); self.sets])?;
                (sets, 0, spectrum_seconds + started.elapsed().as_secs_f64())
            }
            Target::Variance(v) if v.design() == Design::LatticeMixture => {
                // Each error's spectrum is computed once per process and shared by every N; each
                // table is charged their whole computation, as a run at that N alone pays.
                let mix = lattice_design::mixture(v, n, self.sets)?;
                let sets = PointSets::new(self.sets, n, 4, mix.points())?;
                (sets, 0, mix.seconds)
            }
            _ => {
                let started = std::time::Instant::now();
                let (sets, timed_out) = self.optimized(source, target, n)?;
                (sets, timed_out, started.elapsed().as_secs_f64())
            }
        };
        if timed_out > 0 {
            // Warned about as it was built.
            self.warned.lock().expect("warned lock").push(path.clone());
        }
        let sidecar = serde_json::json!({
            "key": key, "seconds": seconds, "target": source.display().to_string(),
            "sets_stopped_by_time_limit": timed_out, "table_seconds": self.seconds,
        });
        // The table and its sidecar together, or neither.
        crate::output::write_group(&[&path, &meta], |staged| {
            write_points(&staged(&path), &points)?;
            crate::output::write_atomic(&staged(&meta), |w| {
                use std::io::Write;
                writeln!(w, "{sidecar:#}")
            })
        })?;
        Ok((load_table(&path, n, self.sets)?, seconds))
    }

    /// The table's sets moved by the optimizer, and how many stopped at the time limit (with a
    /// warning).
    fn optimized(&self, source: &Path, target: &Target, n: usize) -> Result<(PointSets, usize)> {
        let setup = table_setup(target.clone(), n, self.seconds);
        let (points, reports) = optimize_sets(&setup, self.sets, self.seed, &|_| {})?;
        let timed_out = crate::optimize::time_limited(&reports);
        if timed_out > 0 {
            crate::eprintln_best_effort!(
                "warning: {timed_out} of {} sets of the {} table at N = {n} stopped at the time limit \
                 ({} s) before {TABLE_ITERATIONS} iterations; the table depends on this machine's \
                 speed. Raise table_seconds in the compare config",
                self.sets,
                source.display(),
                self.seconds
            );
        }
        Ok((points, timed_out))
    }
}

/// Checks, before any work, that tables can be written into `cache_dir/tables` (made for the check
/// if missing, and removed again): a folder that cannot be made or written in is a usage error
/// naming it and the fix (a table is the study's set-up, and one that cannot be kept would be built
/// again by every run).
pub fn check_writable(cache_dir: &Path) -> Result<()> {
    let dir = cache_dir.join("tables");
    let refused = |e: std::io::Error| {
        Error::Usage(format!(
            "cannot write the optimized tables into the cache folder {}: {e}; give a folder you can write with --cache (or $ANISOSPEC_CACHE)",
            dir.display()
        ))
    };
    // The folders this check makes go again when `made` drops (innermost first, while empty):
    // the tables written later make them for good.
    let mut made = crate::output::NewFolders::default();
    made.make(&dir).map_err(|e| match e {
        Error::Io { source, .. } => refused(source),
        other => other,
    })?;
    tempfile::Builder::new()
        .prefix(".anisospec-")
        .tempfile_in(&dir)
        .map(drop)
        .map_err(refused)
}

/// What a table of `target` at `n` points is optimized with, stopping after `seconds` per set at
/// the latest.
fn table_setup(target: Target, n: usize, seconds: f64) -> Setup {
    Setup {
        target,
        n,
        dims: 4,
        strata: Strata::default(),
        repulsion: DEFAULT_REPULSION,
        method: Method::Nufft { eps: 1e-8 },
        limits: Limits {
            max_iters: TABLE_ITERATIONS,
            max_seconds: seconds,
            tol: 1e-6,
        },
        // x and y are held where the start puts them (Latin): a Sobol or PMJ02 start keeps its
        // (0,2)-net in xy, what a pixel seen through the oracle's shear depends on most.
        init: Some(start_sampler(n).to_string()),
        latin: true,
        annular_weight: DEFAULT_ANNULAR_WEIGHT,
    }
}

/// The table file `path`, which must hold `sets` sets of `n` 4D points.
fn load_table(path: &Path, n: usize, sets: usize) -> Result<Table> {
    let table = Table::load(&path.to_string_lossy(), 4)?;
    if let Err(m) = table.check_n(n) {
        return Err(Error::Input(format!(
            "{} holds sets of {m} points, not {n}",
            path.display()
        )));
    }
    let held = table.set_count(n)?;
    if held != sets {
        return Err(Error::Input(format!(
            "{} holds {held} set{}, not the {sets} of table_sets",
            path.display(),
            if held == 1 { "" } else { "s" }
        )));
    }
    Ok(table)
}

/// Checks, without optimizing, that a table of `target` can be built at `n` points for a subject
/// whose shears span `range`: the error [`TableCache::sampler`] would meet before its first iteration.
pub fn check_buildable(target: Target, range: (f64, f64), n: usize) -> Result<()> {
    // A lattice design or mixture has no start and no loss: its size limit, and the integrand's
    // sampling at the search's grid.
    if let Target::Variance(v) = &target {
        if v.design() != Design::Points {
            v.sampling_side(lattice_design::SEARCH_RES)?;
            return lattice_design::check_n(n);
        }
    }
    // The strata term's radius is fixed here (optimize's flags for it are not compare's): a failure
    // is the N's, and the fix a larger one.
    let strata = Strata::default();
    if strata.grid(n).is_err() {
        // The disc grows as sqrt(N): a few steps up, not more (N = 9 at the default radius).
        let smallest = (n + 1..n + 1024)
            .find(|&m| strata.grid(m).is_ok())
            .unwrap_or(n + 1024);
        return Err(Error::Usage(format!(
            "a 4D table keeps its xy and uv stratified by a blue-noise disc of radius {} sqrt(N), which reaches a frequency cell from N = {smallest} on; use N >= {smallest}, or leave the table out",
            strata.radius
        )));
    }
    let framed = within_reach(table_frame(target, range), n)?;
    table_setup(framed, n, 1.0).objective()?;
    crate::samplers::validate_n(crate::samplers::build(start_sampler(n), 4)?.as_ref(), n)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cache whose `tables` cannot be a folder is refused as a usage error naming it and the fix;
    /// a fresh one passes and is left as it was, and a probe leaves no file.
    #[test]
    fn a_cache_that_cannot_hold_tables_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let blocked = dir.path().join("blocked");
        std::fs::create_dir(&blocked).unwrap();
        std::fs::write(blocked.join("tables"), "a file").unwrap();
        let e = check_writable(&blocked).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        let m = e.to_string();
        assert!(m.contains("blocked/tables") && m.contains("--cache"), "{m}");
        let fresh = dir.path().join("fresh");
        check_writable(&fresh).unwrap();
        assert!(!fresh.exists(), "the folders the check made go again");
        std::fs::create_dir_all(fresh.join("tables")).unwrap();
        check_writable(&fresh).unwrap();
        assert_eq!(std::fs::read_dir(fresh.join("tables")).unwrap().count(), 0);
    }

    /// Above Sobol's largest N a power of two starts from padded PMJ02, so the table can be built; a
    /// lattice design is checked against its own limit, not a start it does not use.
    #[test]
    fn tables_are_checked_with_what_builds_them() {
        assert_eq!(start_sampler(1024), "sobol");
        assert_eq!(start_sampler(1 << 17), "padded-pmj02");
        let hairline = Target::load(Path::new("targets/hairline.toml")).unwrap();
        check_buildable(hairline.clone(), (0.5, 0.5), 1 << 17).unwrap();
        // Too few points for the strata term compare keeps: the fix is a larger N, named.
        for n in [2, 4, 8] {
            let m = check_buildable(hairline.clone(), (0.5, 0.5), n)
                .unwrap_err()
                .to_string();
            assert!(m.contains("use N >= 9, or leave the table out"), "{m}");
            assert!(!m.contains("--strat"), "{m}");
        }
        check_buildable(hairline.clone(), (0.5, 0.5), 9).unwrap();
        let lattice = Target::load(Path::new("targets/fan-lattice.toml")).unwrap();
        check_buildable(lattice.clone(), (0.3, 0.7), 1 << 20).unwrap();
        let m = check_buildable(lattice, (0.3, 0.7), (1 << 20) + 1)
            .unwrap_err()
            .to_string();
        assert!(
            m.contains("a lattice design needs 2 to 1048576 points"),
            "{m}"
        );
    }

    fn wedge(range: (f64, f64)) -> (f64, f64) {
        let shipped = Target::load(Path::new("targets/double-wedge.toml")).unwrap();
        match table_frame(shipped, range) {
            Target::DoubleWedge(w) => (w.s0, w.s1),
            other => panic!("not a double wedge: {other:?}"),
        }
    }

    #[test]
    fn double_wedges_span_the_range_in_the_frame_shear() {
        // A fan off the focus: centred on its middle shear, symmetric.
        assert_eq!(frame_shear((0.3, 0.7)), 0.5);
        let (s0, s1) = wedge((0.3, 0.7));
        assert!(
            (s0 + 0.2).abs() < 1e-12 && (s1 - 0.2).abs() < 1e-12,
            "{s0} {s1}"
        );
        // A range holding an in-focus layer: the frame of shear 0, the wedge where the range is.
        assert_eq!(frame_shear((-0.7, 0.0)), 0.0);
        assert_eq!(wedge((-0.7, 0.0)), (-0.7, 0.0));
        // A single shear: the narrowest wedge around it.
        let (s0, s1) = wedge((0.5, 0.5));
        assert!(
            (s0 + MIN_WEDGE_HALF_WIDTH).abs() < 1e-12 && (s1 - MIN_WEDGE_HALF_WIDTH).abs() < 1e-12
        );
    }
}
