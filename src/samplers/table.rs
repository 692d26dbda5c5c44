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

/// Tabulated point sets, one table per `N`.
#[derive(Debug, Clone)]
pub struct Table {
    pattern: String,
    dims: usize,
    tables: Vec<PointSets>,
}

impl Table {
    /// Loads the table(s) named by `pattern` for `dims`-dimensional use.
    pub fn load(pattern: &str, dims: usize) -> Result<Self> {
        let mut tables = Vec::new();
        for (f, named_n) in &files(pattern)? {
            let t = read_points(f)?;
            if let Some(named) = named_n.filter(|&named| named != t.n()) {
                return Err(Error::Input(format!(
                    "table {} is named for N = {named} but holds N = {}; rename it (table:{pattern} finds each N by its name)",
                    f.display(),
                    t.n()
                )));
            }
            if t.dims() != dims {
                return Err(Error::Usage(format!(
                    "table {} holds {}D points but {dims}D are asked here; use it for {}D sets (--dims {} in sample and spectrum, a {}D integrand in variance and converge)",
                    f.display(),
                    t.dims(),
                    t.dims(),
                    t.dims(),
                    t.dims()
                )));
            }
            if tables.iter().any(|o: &PointSets| o.n() == t.n()) {
                return Err(Error::Input(format!(
                    "two tables of table:{pattern} hold N = {}; keep one per N",
                    t.n()
                )));
            }
            tables.push(t);
        }
        tables.sort_by_key(PointSets::n);
        Ok(Self {
            pattern: pattern.into(),
            dims,
            tables,
        })
    }
}

impl Sampler for Table {
    fn name(&self) -> String {
        format!("table:{}", self.pattern)
    }

    fn dims(&self) -> usize {
        self.dims
    }

    fn check_n(&self, n: usize) -> std::result::Result<(), usize> {
        if self.tables.iter().any(|t| t.n() == n) {
            return Ok(());
        }
        let nearest = self
            .tables
            .iter()
            .map(PointSets::n)
            .min_by_key(|&m| (m.abs_diff(n), m))
            .expect("at least one table");
        Err(nearest)
    }

    fn generate(&self, n: usize, rng: &mut Rng) -> Vec<f64> {
        let table = self
            .tables
            .iter()
            .find(|t| t.n() == n)
            .expect("n passed check_n");
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
        assert!(Table::load(&pattern, 4).is_err());
        assert!(Table::load(&format!("{}/none-{{n}}.npy", dir.path().display()), 2).is_err());
        // A file whose name gives another N than it holds is refused, not used for the wrong N.
        let data: Vec<f64> = (0..2 * 17).map(|i| (i as f64 * 0.137) % 1.0).collect();
        let p = PointSets::new(1, 17, 2, data).unwrap();
        write_points(&dir.path().join("t-18.npy"), &p).unwrap();
        let e = Table::load(&pattern, 2).unwrap_err().to_string();
        assert!(e.contains("named for N = 18 but holds N = 17"), "{e}");
    }
}
