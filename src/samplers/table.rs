//! `table:PATH`: optimized sets written by `anisospec optimize`, used as a sampler.
//!
//! `PATH` is an npy (or text) table `[sets, N, D]`, or a family of tables at several `N` named by a
//! pattern holding `{n}`, e.g. `table:out/wedge-{n}.npy` (every file of that folder matching the
//! pattern with a whole number in place of `{n}`). Each draw picks one set of the table for `N` at
//! random and applies a random toroidal shift; shear it with the usual `--shear` (transported by
//! default) when the table was made in the pattern frame (see `targets/*.toml`).

use super::Sampler;
use crate::error::{Error, Result};
use crate::points::io::read_points;
use crate::points::{toroidal_shift, PointSets};
use crate::rng::Rng;
use rand::Rng as _;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Tabulated point sets, one table per `N`.
#[derive(Debug, Clone)]
pub struct Table {
    pattern: String,
    dims: usize,
    members: Vec<Member>,
}

/// One file of a table: the `N` its name gives (a single file's, the `N` it holds) and its sets,
/// read when that `N` is first asked for, so a file for an `N` no one asks for is never read.
#[derive(Debug, Clone)]
struct Member {
    path: PathBuf,
    n: usize,
    sets: OnceLock<PointSets>,
}

impl Table {
    /// Loads the table(s) named by `pattern` for `dims`-dimensional use: a single file is read now,
    /// a family's files (one per `N`, by name) when their `N` is checked
    /// ([`Sampler::check_parameters`]).
    pub fn load(pattern: &str, dims: usize) -> Result<Self> {
        let mut members: Vec<Member> = Vec::new();
        for (path, named_n) in files(pattern)? {
            let member = match named_n {
                None => {
                    let sets = read_table(&path, None, dims, pattern)?;
                    Member {
                        path,
                        n: sets.n(),
                        sets: OnceLock::from(sets),
                    }
                }
                Some(n) => Member {
                    path,
                    n,
                    sets: OnceLock::new(),
                },
            };
            if let Some(other) = members.iter().find(|o| o.n == member.n) {
                return Err(Error::Input(format!(
                    "table:{pattern} names two files for N = {}, {} and {}; keep one per N",
                    member.n,
                    other.path.display(),
                    member.path.display()
                )));
            }
            members.push(member);
        }
        members.sort_by_key(|m| m.n);
        Ok(Self {
            pattern: pattern.into(),
            dims,
            members,
        })
    }

    /// How many sets the table holds for `n` (which passed [`Sampler::check_n`]), read on first use.
    pub fn set_count(&self, n: usize) -> Result<usize> {
        Ok(self.sets(n)?.sets())
    }

    /// The sets for `n` (which passed [`Sampler::check_n`]), read on first use.
    fn sets(&self, n: usize) -> Result<&PointSets> {
        let member = self
            .members
            .iter()
            .find(|m| m.n == n)
            .expect("n passed check_n");
        if let Some(sets) = member.sets.get() {
            return Ok(sets);
        }
        let sets = read_table(&member.path, Some(n), self.dims, &self.pattern)?;
        Ok(member.sets.get_or_init(|| sets))
    }
}

/// Reads one table file, refusing one that holds another `N` than its name gives (`named`) or points
/// of another dimension than `dims`.
fn read_table(path: &Path, named: Option<usize>, dims: usize, pattern: &str) -> Result<PointSets> {
    let t = read_points(path)?;
    if let Some(named) = named.filter(|&named| named != t.n()) {
        return Err(Error::Input(format!(
            "table {} is named for N = {named} but holds N = {}; rename it (table:{pattern} finds each N by its name)",
            path.display(),
            t.n()
        )));
    }
    if t.dims() != dims {
        return Err(Error::Usage(format!(
            "table {} holds {}D points but {dims}D are asked here; use it for {}D sets (--dims {} in sample and spectrum, a {}D integrand in variance and converge)",
            path.display(),
            t.dims(),
            t.dims(),
            t.dims(),
            t.dims()
        )));
    }
    Ok(t)
}

impl Sampler for Table {
    fn name(&self) -> String {
        format!("table:{}", self.pattern)
    }

    fn dims(&self) -> usize {
        self.dims
    }

    fn check_n(&self, n: usize) -> std::result::Result<(), usize> {
        if self.members.iter().any(|m| m.n == n) {
            return Ok(());
        }
        let nearest = self
            .members
            .iter()
            .map(|m| m.n)
            .min_by_key(|&m| (m.abs_diff(n), m))
            .expect("at least one table");
        Err(nearest)
    }

    /// Reads the table for `n` if not yet read: a file that cannot be read, holds another `N` than
    /// its name, or points of another dimension is an error here, before any work.
    fn check_parameters(&self, n: usize) -> Result<()> {
        self.sets(n).map(|_| ())
    }

    /// Panics if the table for `n` cannot be read: callers check `n` first
    /// ([`crate::samplers::validate_n`]).
    fn generate(&self, n: usize, rng: &mut Rng) -> Vec<f64> {
        let table = self
            .sets(n)
            .unwrap_or_else(|e| panic!("table for N = {n} used before it was checked: {e}"));
        let mut set = table.set(rng.random_range(0..table.sets())).to_vec();
        let shift: Vec<f64> = (0..self.dims).map(|_| rng.random::<f64>()).collect();
        toroidal_shift(&mut set, &shift);
        set
    }
}

/// The files a `table:` pattern names, each with the N its name gives: the path itself (no N), or
/// every file of its folder that matches a pattern holding `{n}` with a whole number in its place,
/// sorted. None is a usage error.
pub fn files(pattern: &str) -> Result<Vec<(PathBuf, Option<usize>)>> {
    if pattern.trim().is_empty() {
        return Err(Error::Usage(
            "sampler 'table:' names no table: give the point-set file after the colon, e.g. \
             table:sets.npy, or table:dir/n{n}.npy for one file per N"
                .into(),
        ));
    }
    let files = match pattern.split_once("{n}") {
        None => vec![(pattern.into(), None)],
        Some((head, tail)) => {
            let path = Path::new(head);
            let (dir, prefix) = if head.ends_with('/') || head.is_empty() {
                (Path::new(if head.is_empty() { "." } else { head }), "")
            } else {
                let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
                let prefix = path.file_name().and_then(|f| f.to_str()).unwrap_or("");
                (dir.unwrap_or(Path::new(".")), prefix)
            };
            let entries = std::fs::read_dir(dir).map_err(|e| Error::read_input(dir, e))?;
            let mut found: Vec<(PathBuf, Option<usize>)> = entries
                .filter_map(|e| e.ok())
                .filter_map(|e| {
                    let name = e.file_name();
                    let n = name
                        .to_str()?
                        .strip_prefix(prefix)?
                        .strip_suffix(tail)
                        .filter(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))?
                        .parse()
                        .ok()?;
                    Some((e.path(), Some(n)))
                })
                .collect();
            found.sort();
            found
        }
    };
    if files.is_empty() {
        return Err(Error::Usage(format!(
            "table:{pattern} matches no file; write tables with `anisospec optimize -o NAME.npy`, one per N, and name them with {{n}} in place of N"
        )));
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::points::io::write_points;

    #[test]
    fn family_by_n_with_shift() {
        let dir = tempfile::tempdir().unwrap();
        for n in [4usize, 16] {
            let data: Vec<f64> = (0..2 * n * 2).map(|i| (i as f64 * 0.137) % 1.0).collect();
            let p = PointSets::new(2, n, 2, data).unwrap();
            write_points(&dir.path().join(format!("t-{n}.npy")), &p).unwrap();
        }
        let pattern = format!("{}/t-{{n}}.npy", dir.path().display());
        let t = Table::load(&pattern, 2).unwrap();
        assert_eq!(t.check_n(16), Ok(()));
        assert_eq!(t.check_n(12), Err(16));
        let mut rng = crate::rng::stream(1, 0);
        let set = t.generate(4, &mut rng);
        assert_eq!(set.len(), 8);
        assert!(set.iter().all(|c| (0.0..1.0).contains(c)));
        let e = Table::load(&pattern, 4)
            .unwrap()
            .check_parameters(4)
            .unwrap_err();
        assert!(e.to_string().contains("holds 2D points"), "{e}");
        assert!(Table::load(&format!("{}/none-{{n}}.npy", dir.path().display()), 2).is_err());
        // A file whose name gives another N than it holds is refused, not used for the wrong N, but
        // only where that N is asked for: the others stay usable.
        let data: Vec<f64> = (0..2 * 17).map(|i| (i as f64 * 0.137) % 1.0).collect();
        let p = PointSets::new(1, 17, 2, data).unwrap();
        write_points(&dir.path().join("t-18.npy"), &p).unwrap();
        let t = Table::load(&pattern, 2).unwrap();
        assert_eq!(t.check_n(18), Ok(()));
        let e = t.check_parameters(18).unwrap_err().to_string();
        assert!(e.contains("named for N = 18 but holds N = 17"), "{e}");
        t.check_parameters(16).unwrap();
        // Two files named for one N are refused at once.
        write_points(&dir.path().join("t-016.npy"), &p).unwrap();
        let e = Table::load(&pattern, 2).unwrap_err().to_string();
        assert!(e.contains("names two files for N = 16"), "{e}");
    }
}
