//! Reading and writing point sets: npy `float64 [sets, N, D]` and UTK-style text (DESIGN §7).

use super::PointSets;
use crate::error::{Error, Result};
use crate::output::{write_atomic, write_npy};
use std::io::Write;
use std::path::Path;

/// The file formats a point set can be stored in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// numpy `float64` array `[sets, N, D]` (a 2D `[N, D]` array is read as one set).
    Npy,
    /// One point per line, coordinates separated by spaces, a line `#` between sets.
    Text,
}

impl Format {
    /// The format a path's extension names: `.npy`, or `.txt` / `.dat` / `.pts` for text.
    pub fn of(path: &Path) -> Result<Self> {
        match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase) {
            Some(e) if e == "npy" => Ok(Format::Npy),
            Some(e) if e == "txt" || e == "dat" || e == "pts" => Ok(Format::Text),
            _ => Err(Error::Usage(format!(
                "{} has no point-set extension; name it .npy (numpy) or .txt (one point per line, '#' between sets)",
                path.display()
            ))),
        }
    }
}

/// Reads a point set from `.npy` or text, checking every value (see [`PointSets::new`]).
pub fn read_points(path: &Path) -> Result<PointSets> {
    let format = Format::of(path)?;
    let bytes = std::fs::read(path).map_err(|e| Error::read_input(path, e))?;
    let named = |e: Error| match e {
        Error::Input(m) => Error::Input(format!("{}: {m}", path.display())),
        other => other,
    };
    match format {
        Format::Npy => parse_npy(&bytes),
        Format::Text => parse_text(&String::from_utf8_lossy(&bytes)),
    }
    .map_err(named)
}

fn parse_npy(bytes: &[u8]) -> Result<PointSets> {
    let bad = |why: String| Error::Input(format!("not a readable npy point set ({why})"));
    let npy = npyz::NpyFile::new(bytes).map_err(|e| bad(e.to_string()))?;
    let shape: Vec<usize> = npy.shape().iter().map(|&s| s as usize).collect();
    let (sets, n, dims) = match shape[..] {
        [sets, n, d] => (sets, n, d),
        [n, d] => (1, n, d),
        _ => {
            return Err(bad(format!(
                "shape {shape:?}; expected [sets, N, D] or [N, D]"
            )))
        }
    };
    let data: Vec<f64> = npy
        .into_vec::<f64>()
        .map_err(|e| bad(format!("{e}; the array must be float64")))?;
    PointSets::new(sets, n, dims, data)
}

fn parse_text(text: &str) -> Result<PointSets> {
    let mut sets: Vec<Vec<f64>> = vec![Vec::new()];
    let mut dims: Option<usize> = None;
    for (line_no, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        if line.starts_with('#') {
            if !sets.last().is_some_and(Vec::is_empty) {
                sets.push(Vec::new());
            }
            continue;
        }
        let coords: Vec<f64> = line
            .split_whitespace()
            .map(|t| {
                t.parse::<f64>().map_err(|_| {
                    Error::Input(format!(
                        "line {}: '{t}' is not a number; each line holds one point's coordinates separated by spaces",
                        line_no + 1
                    ))
                })
            })
            .collect::<Result<_>>()?;
        match dims {
            None => dims = Some(coords.len()),
            Some(d) if d != coords.len() => {
                return Err(Error::Input(format!(
                    "line {}: {} coordinates where earlier lines have {d}; every point needs the same number",
                    line_no + 1,
                    coords.len()
                )))
            }
            _ => {}
        }
        sets.last_mut()
            .expect("one set is always open")
            .extend(coords);
    }
    if sets.last().is_some_and(Vec::is_empty) {
        sets.pop();
    }
    let dims = dims.ok_or_else(|| Error::Input("the file holds no points".into()))?;
    PointSets::from_sets(dims, sets)
}

/// Writes a point set as `.npy` or text, chosen by the extension.
pub fn write_points(path: &Path, points: &PointSets) -> Result<()> {
    match Format::of(path)? {
        Format::Npy => write_npy(
            path,
            &[points.sets(), points.n(), points.dims()],
            points.data(),
        ),
        Format::Text => write_atomic(path, |w| {
            for s in 0..points.sets() {
                if s > 0 {
                    writeln!(w, "#")?;
                }
                for p in points.set(s).chunks_exact(points.dims()) {
                    let cells: Vec<String> = p.iter().map(|c| format!("{c}")).collect();
                    writeln!(w, "{}", cells.join(" "))?;
                }
            }
            Ok(())
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_round_trip_with_separators() {
        let p = parse_text("0.1 0.2\n0.3 0.4\n#\n0.5 0.6\n0.7 0.8\n#\n").unwrap();
        assert_eq!((p.sets(), p.n(), p.dims()), (2, 2, 2));
        assert_eq!(p.set(1), &[0.5, 0.6, 0.7, 0.8]);
    }

    #[test]
    fn text_rejects_ragged_and_garbage() {
        assert!(parse_text("0.1 0.2\n0.3\n").is_err());
        assert!(parse_text("0.1 abc\n").is_err());
        assert!(parse_text("\n\n").is_err());
        assert!(parse_text("0.1 0.2\n#\n0.3 0.4\n0.5 0.6\n").is_err());
    }
}
