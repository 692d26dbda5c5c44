//! Reading and writing point sets: npy `float64 [sets, N, D]` and UTK-style text (DESIGN §7).

use super::PointSets;
use crate::error::{Error, Result};
use crate::output::{write_atomic, write_npy};
use std::io::{BufRead, Read, Write};
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

/// The largest npy header read: far beyond any real one (numpy pads them to 64-byte multiples).
const MAX_NPY_HEADER: u64 = 1 << 20;

/// The longest line of a text point file: a point's few coordinates take well under a hundred bytes.
const MAX_LINE_BYTES: u64 = 1 << 16;

/// Reads a point set from `.npy` or text, checking every value (see [`PointSets::new`]). A file
/// holding more than [`super::MAX_COORDINATES`] coordinates is refused before it is read whole: an
/// npy file by its size, a text file as soon as the count passes the limit (or a line runs past
/// 64 KiB).
pub fn read_points(path: &Path) -> Result<PointSets> {
    let format = Format::of(path)?;
    let file = std::fs::File::open(path).map_err(|e| Error::read_input(path, e))?;
    let named = |e: Error| match e {
        Error::Input(m) => Error::Input(format!("{}: {m}", path.display())),
        other => other,
    };
    match format {
        Format::Npy => {
            let len = file
                .metadata()
                .map_err(|e| Error::read_input(path, e))?
                .len();
            let limit = super::MAX_COORDINATES as u64 * 8 + MAX_NPY_HEADER;
            if len > limit {
                return Err(named(Error::Input(format!(
                    "{len} bytes, more than the {} float64 coordinates ({} GiB of data) a point set may hold; split it into several files",
                    super::MAX_COORDINATES,
                    (super::MAX_COORDINATES * 8) >> 30
                ))));
            }
            // Bounded also where the size says nothing (a device, a pipe).
            match crate::input::read_npy_bytes(file, path, limit)? {
                Ok(bytes) => parse_npy(&bytes),
                Err(why) => Err(Error::Input(format!(
                    "not a readable npy point set ({why}); give a float64 npy array [sets, N, D] or \
                     [N, D] (numpy.save, anisospec sample), or name a text point file .txt"
                ))),
            }
        }
        Format::Text => match parse_text(std::io::BufReader::new(file), super::MAX_COORDINATES) {
            // A folder, or a failing disk: the message and exit code of any unreadable input.
            Err(Error::Io { source, .. }) => return Err(Error::read_input(path, source)),
            parsed => parsed,
        },
    }
    .map_err(named)
}

fn parse_npy(bytes: &[u8]) -> Result<PointSets> {
    let bad = |why: String| Error::Input(format!("not a readable npy point set ({why})"));
    let (shape, data) = parse_npy_array(bytes, false).map_err(bad)?;
    let (sets, n, dims) = match shape[..] {
        [sets, n, d] => (sets, n, d),
        [n, d] => (1, n, d),
        _ => {
            return Err(bad(format!(
                "shape {shape:?}; expected [sets, N, D] or [N, D]"
            )))
        }
    };
    PointSets::new(sets, n, dims, data)
}

/// Reads the bytes of an npy file of `float64` (or, with `allow_f32`, also `float32`) values: the shape
/// and the values in C (row-major) order, a Fortran-order array transposed into it.
///
/// The header's shape is checked before any data are read: a product of dimensions that overflows, or
/// data shorter or longer than the shape needs, is an error. Errors give the reason alone, for the
/// caller to name the file and the fix.
pub fn parse_npy_array(
    bytes: &[u8],
    allow_f32: bool,
) -> std::result::Result<(Vec<usize>, Vec<f64>), String> {
    let (shape, data_start) = npy_header_shape(bytes)?;
    // Every partial product of the dimensions (zeros skipped) must fit, as npyz forms them unchecked.
    shape
        .iter()
        .try_fold(1usize, |acc, &d| acc.checked_mul(d.max(1)))
        .ok_or_else(|| format!("shape {shape:?} has more elements than memory can address"))?;
    let count: usize = shape.iter().product();
    let npy = npyz::NpyFile::new(bytes).map_err(|e| e.to_string())?;
    if npy
        .shape()
        .iter()
        .map(|&d| d as usize)
        .ne(shape.iter().copied())
    {
        return Err(format!(
            "the header's shape is ambiguous ({:?} or {shape:?})",
            npy.shape()
        ));
    }
    let wanted = if allow_f32 {
        "float64 or float32"
    } else {
        "float64"
    };
    let item = match npy.dtype().num_bytes() {
        Some(b @ 8) => b,
        Some(b @ 4) if allow_f32 => b,
        _ => {
            return Err(format!(
                "dtype {}; the array must be {wanted}",
                npy.dtype().descr()
            ))
        }
    };
    let held = bytes.len() - data_start;
    if count.checked_mul(item) != Some(held) {
        let why = if count.checked_mul(item).is_some_and(|need| need < held) {
            "the file has bytes after its array (appended to) or its header is wrong"
        } else {
            "the file is cut short or its header is wrong"
        };
        return Err(format!(
            "the header's shape {shape:?} needs {count} values of {item} bytes but the file holds {held} bytes of data; {why}"
        ));
    }
    let fortran = npy.order() == npyz::Order::Fortran;
    let values: Vec<f64> = if item == 4 {
        npy.into_vec::<f32>()
            .map_err(|e| format!("{e}; the array must be {wanted}"))?
            .into_iter()
            .map(f64::from)
            .collect()
    } else {
        npy.into_vec::<f64>()
            .map_err(|e| format!("{e}; the array must be {wanted}"))?
    };
    Ok(if fortran {
        let c_order = fortran_to_c(&shape, &values);
        (shape, c_order)
    } else {
        (shape, values)
    })
}

/// The shape in an npy file's header and where its data start, read without npyz, which multiplies
/// the dimensions unchecked.
fn npy_header_shape(bytes: &[u8]) -> std::result::Result<(Vec<usize>, usize), String> {
    let rest = bytes
        .strip_prefix(b"\x93NUMPY")
        .ok_or("no npy magic \\x93NUMPY at the start")?;
    let cut = || "the header is cut short".to_string();
    let (len, text_start) = match rest.first() {
        Some(1) => {
            let b = rest.get(2..4).ok_or_else(cut)?;
            (usize::from(u16::from_le_bytes([b[0], b[1]])), 10)
        }
        Some(2 | 3) => {
            let b = rest.get(2..6).ok_or_else(cut)?;
            let len = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            (usize::try_from(len).map_err(|_| cut())?, 12)
        }
        Some(v) => return Err(format!("npy format version {v}, not 1, 2 or 3")),
        None => return Err(cut()),
    };
    let data_start = text_start + len;
    let text = bytes.get(text_start..data_start).ok_or_else(cut)?;
    let text = String::from_utf8_lossy(text);
    let no_shape = || "the header has no readable 'shape'".to_string();
    // The key 'shape' is followed by a colon; a field of that name in a structured dtype is not.
    let tuple = ["'shape'", "\"shape\""]
        .iter()
        .flat_map(|key| text.match_indices(key).map(|(at, k)| at + k.len()))
        .find_map(|after| text[after..].trim_start().strip_prefix(':'))
        .and_then(|value| value.trim_start().strip_prefix('('))
        .and_then(|value| value.split_once(')'))
        .ok_or_else(no_shape)?
        .0;
    let shape = tuple
        .split(',')
        .map(str::trim)
        .filter(|d| !d.is_empty())
        .map(|d| d.parse::<usize>().map_err(|_| no_shape()))
        .collect::<std::result::Result<_, _>>()?;
    Ok((shape, data_start))
}

/// The values of a Fortran-order array of `shape` (first index fastest) in C order (last index
/// fastest). The product of `shape` is the length of `values`.
fn fortran_to_c(shape: &[usize], values: &[f64]) -> Vec<f64> {
    let strides: Vec<usize> = shape
        .iter()
        .scan(1, |acc, &d| {
            let stride = *acc;
            *acc *= d;
            Some(stride)
        })
        .collect();
    let mut index = vec![0; shape.len()];
    let mut out = Vec::with_capacity(values.len());
    for _ in 0..values.len() {
        out.push(
            values[index
                .iter()
                .zip(&strides)
                .map(|(i, s)| i * s)
                .sum::<usize>()],
        );
        for (i, &d) in index.iter_mut().zip(shape).rev() {
            *i += 1;
            if *i < d {
                break;
            }
            *i = 0;
        }
    }
    out
}

/// Parses the text format, refusing more than `limit` coordinates as soon as the count passes it, and
/// lines longer than [`MAX_LINE_BYTES`]. Bytes that are not UTF-8 are read as replacement characters
/// (and then fail as numbers). A failure of the reader is an [`Error::Io`].
fn parse_text(mut reader: impl BufRead, limit: usize) -> Result<PointSets> {
    let mut sets: Vec<Vec<f64>> = vec![Vec::new()];
    let mut dims: Option<usize> = None;
    let mut count = 0usize;
    let mut raw = Vec::new();
    for line_no in 0.. {
        raw.clear();
        let read = reader
            .by_ref()
            .take(MAX_LINE_BYTES + 1)
            .read_until(b'\n', &mut raw)
            .map_err(|source| Error::Io {
                context: format!("cannot read line {}", line_no + 1),
                source,
            })?;
        if read == 0 {
            break;
        }
        let text = String::from_utf8_lossy(&raw);
        // A carriage return inside a line: the file ends its lines with CR alone (classic Mac OS),
        // and read by \n it would run its points together. CR LF endings are trimmed below.
        if text.trim_end().contains('\r') {
            return Err(Error::Input(format!(
                "line {} holds a carriage return inside the line: the file ends its lines with CR alone; convert them to LF (e.g. tr '\\r' '\\n' < in.txt > out.txt)",
                line_no + 1
            )));
        }
        if raw.len() as u64 > MAX_LINE_BYTES {
            return Err(Error::Input(format!(
                "line {} is longer than {MAX_LINE_BYTES} bytes; each line holds one point's coordinates",
                line_no + 1
            )));
        }
        // A byte-order mark before the first line (some editors write one) is not part of a number.
        let text = if line_no == 0 {
            text.strip_prefix('\u{feff}').unwrap_or(&text)
        } else {
            &text
        };
        let line = text.trim();
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
                let c = t.parse::<f64>().map_err(|_| {
                    Error::Input(format!(
                        "line {}: '{t}' is not a number; each line holds one point's coordinates separated by spaces",
                        line_no + 1
                    ))
                })?;
                // A finite spelling such as 1e400 that overflows (an explicit inf is left to the
                // range check, which names the point). The spelling is looked at only for an
                // infinite value, so ordinary coordinates cost one comparison.
                let spelt_infinite = || {
                    let digits = t.trim_start_matches(['+', '-']);
                    digits.get(..3).is_some_and(|p| p.eq_ignore_ascii_case("inf"))
                };
                if c.is_infinite() && !spelt_infinite() {
                    return Err(Error::Input(format!(
                        "line {}: '{t}' is beyond the range of a 64-bit float (it reads as infinity); coordinates lie in [0, 1)",
                        line_no + 1
                    )));
                }
                Ok(c)
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
        count += coords.len();
        if count > limit {
            return Err(Error::Input(format!(
                "line {}: more than the {limit} coordinates a point set may hold; split it into several files",
                line_no + 1
            )));
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
        let p = parse_text(
            "0.1 0.2\n0.3 0.4\n#\n0.5 0.6\n0.7 0.8\n#\n".as_bytes(),
            crate::points::MAX_COORDINATES,
        )
        .unwrap();
        assert_eq!((p.sets(), p.n(), p.dims()), (2, 2, 2));
        assert_eq!(p.set(1), &[0.5, 0.6, 0.7, 0.8]);
    }

    /// A version-1 npy file: dtype `descr`, the header's `shape` text, the raw data bytes.
    fn npy(descr: &str, fortran: bool, shape: &str, data: &[u8]) -> Vec<u8> {
        let order = if fortran { "True" } else { "False" };
        let mut header =
            format!("{{'descr': '{descr}', 'fortran_order': {order}, 'shape': {shape}, }}");
        while (10 + header.len() + 1) % 64 != 0 {
            header.push(' ');
        }
        header.push('\n');
        let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
        bytes.extend(u16::try_from(header.len()).unwrap().to_le_bytes());
        bytes.extend(header.as_bytes());
        bytes.extend(data);
        bytes
    }

    fn f8(values: &[f64]) -> Vec<u8> {
        values.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    #[test]
    fn fortran_order_reads_as_the_same_array() {
        // [2 sets, 3 points, 2 dims]; Fortran order stores (s, j, d) at s + 2 (j + 3 d).
        let c: Vec<f64> = (0..12).map(|i| f64::from(i) / 12.0).collect();
        let mut f = vec![0.0; 12];
        for s in 0..2 {
            for j in 0..3 {
                for d in 0..2 {
                    f[s + 2 * (j + 3 * d)] = c[(s * 3 + j) * 2 + d];
                }
            }
        }
        let a = parse_npy(&npy("<f8", false, "(2, 3, 2)", &f8(&c))).unwrap();
        let b = parse_npy(&npy("<f8", true, "(2, 3, 2)", &f8(&f))).unwrap();
        assert_eq!(a.data(), &c[..]);
        assert_eq!(a, b);
        // A 2 x 3 float32 image, as target images are read: (r, c) at r + 2 c in Fortran order.
        let f4: Vec<u8> = [0.0f32, 3.0, 1.0, 4.0, 2.0, 5.0]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let (shape, pixels) = parse_npy_array(&npy("<f4", true, "(2, 3)", &f4), true).unwrap();
        assert_eq!(shape, [2, 3]);
        assert_eq!(pixels, [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
        // Points must be float64.
        assert!(parse_npy(&npy("<f4", false, "(3, 2)", &f4)).is_err());
    }

    #[test]
    fn shapes_that_overflow_or_disagree_with_the_data_are_rejected() {
        let message = |bytes: Vec<u8>| parse_npy(&bytes).unwrap_err().to_string();
        // 2^62 x 2^62 x 4 wraps to 0 elements unchecked, and 0 bytes of data would then match it.
        let e = message(npy(
            "<f8",
            false,
            "(4611686018427387904, 4611686018427387904, 4)",
            &[],
        ));
        assert!(e.contains("more elements"), "{e}");
        // The same with zero data in front, and in Fortran order, where npyz forms 2^62 x 2^62 first.
        let e = message(npy(
            "<f8",
            true,
            "(4611686018427387904, 4611686018427387904, 0)",
            &[],
        ));
        assert!(e.contains("more elements"), "{e}");
        for (shape, values, why) in [
            ("(1, 4, 2)", 6, "cut short or its header is wrong"),
            (
                "(1, 2, 2)",
                6,
                "bytes after its array (appended to) or its header is wrong",
            ),
            ("(1, 134217728, 4)", 0, "cut short or its header is wrong"),
        ] {
            let e = message(npy("<f8", false, shape, &f8(&vec![0.5; values])));
            assert!(e.contains(why), "{shape}: {e}");
        }
        assert!(parse_npy(&npy("<f8", false, "(1, 2, 2)", &f8(&[0.5; 4]))).is_ok());
    }

    #[test]
    fn text_rejects_ragged_and_garbage() {
        let parse = |text: &str| parse_text(text.as_bytes(), crate::points::MAX_COORDINATES);
        assert!(parse("0.1 0.2\n0.3\n").is_err());
        assert!(parse("0.1 abc\n").is_err());
        assert!(parse("\n\n").is_err());
        assert!(parse("0.1 0.2\n#\n0.3 0.4\n0.5 0.6\n").is_err());
        // Lines ended by CR alone would run together into one point of twice the dimensions.
        let e = parse("0.1 0.2\r0.3 0.4\r").unwrap_err().to_string();
        assert!(e.contains("line 1") && e.contains("CR alone"), "{e}");
        // CR LF endings and a byte-order mark are read as plain text.
        let p = parse("\u{feff}0.1 0.2\r\n0.3 0.4\r\n").unwrap();
        assert_eq!((p.sets(), p.n(), p.dims()), (1, 2, 2));
    }

    #[test]
    fn oversized_files_are_refused_before_they_are_read() {
        // Text: the count is checked line by line against the limit.
        let two_sets = "0.1 0.2\n0.3 0.4\n#\n0.5 0.6\n0.7 0.8\n";
        assert!(parse_text(two_sets.as_bytes(), 8).is_ok());
        let e = parse_text(two_sets.as_bytes(), 7).unwrap_err().to_string();
        assert!(
            e.contains("line 5") && e.contains("more than the 7 coordinates"),
            "{e}"
        );
        // npy: by the file's size alone (a sparse file, never read).
        let dir = tempfile::tempdir().unwrap();
        let big = dir.path().join("big.npy");
        let size = crate::points::MAX_COORDINATES as u64 * 8 + MAX_NPY_HEADER + 1;
        std::fs::File::create(&big).unwrap().set_len(size).unwrap();
        let e = read_points(&big).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("split it into several files"), "{e}");
        // A text file with no line breaks is refused at its first line's limit, not read whole.
        let endless = std::io::repeat(b'1').take(1 << 30);
        let e = parse_text(std::io::BufReader::new(endless), 100)
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 1 is longer than"), "{e}");
        // A folder named like a point file keeps the message of any unreadable input.
        let folder = dir.path().join("pts.txt");
        std::fs::create_dir(&folder).unwrap();
        let e = read_points(&folder).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("name a file, not a folder"), "{e}");
    }
}
