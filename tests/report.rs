//! `anisospec compare` end to end: a tiny study (one analytic edge and one renderer pixel; a classical,
//! a sheared and an optimized sampler) run through the binary, and its report folder checked against
//! itself (every link, every PNG, the CSV against the npy arrays and report.md) and against further runs
//! on the warm cache (tables reused, the same numbers).

use anisospec::compare::tables::start_sampler;
use anisospec::converge::rounding_floor;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::SystemTime;

/// The study's samplers in report order (classical, sheared, optimized), with their family.
const SAMPLERS: [(&str, &str); 3] = [
    ("padded-jittered", "classical"),
    ("padded-mj sheared (transported)", "sheared"),
    ("optimized hairline", "optimized"),
];
/// The analytic integrand's label.
const EDGE: &str = "hairline edge in xu";
/// The robustness study's shear errors: the exact oracle, then the config's `oracle_errors`.
const SHEAR_ERRORS: [f64; 2] = [0.0, 0.1];
/// Realizations per N.
const REALIZATIONS: usize = 8;
/// Points and grid side K of the spectra gallery.
const SPECTRA_N: usize = 64;
const SPECTRA_RES: usize = 16;

/// The study over the sizes `ns`: a hairline edge and the default scene's hairline pixel, one
/// sampler of each family, a 2-set optimized hairline table. Under a second per run on 2 cores in
/// the (optimized) test profile, about 7 s unoptimized.
fn study(ns: &[usize]) -> String {
    let target = Path::new(env!("CARGO_MANIFEST_DIR")).join("targets/hairline.toml");
    format!(
        r#"ns = {ns:?}
realizations = {REALIZATIONS}
seed = {SEED}
classical = ["padded-jittered"]
sheared = ["padded-mj"]
shear_modes = ["transported"]
tables = ['{}']
table_sets = 2
table_seconds = 600.0
pixel_classes = ["hairline"]
pixel_reference_count = 4096
oracle_errors = [0.1]
spectra_n = {SPECTRA_N}
spectra_res = {SPECTRA_RES}
spectra_realizations = 2

[[analytic]]
label = "{EDGE}"
spec = "sheared:s=0.5,c=0.7@xu"
shear = [0.5, 0.5]
shear_range = [0.5, 0.5]
"#,
        target.display()
    )
}

fn anisospec(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_anisospec"))
        .args(args)
        .output()
        .expect("the binary runs")
}

/// Writes `config` to `dir/name.toml`, runs compare with the report in `dir/name` and the cache
/// `cache`, expects success, and returns the report folder and compare's standard error.
fn compare_logged(dir: &Path, name: &str, config: &str, cache: &Path) -> (PathBuf, String) {
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, config).unwrap();
    let out = dir.join(name);
    let o = anisospec(&[
        "compare",
        "--config",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--cache",
        cache.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(
        o.status.success(),
        "compare exited {:?}: {err}",
        o.status.code()
    );
    (out, err)
}

/// [`compare_logged`]'s report folder.
fn compare(dir: &Path, name: &str, config: &str, cache: &Path) -> PathBuf {
    compare_logged(dir, name, config, cache).0
}

/// Whether `stderr` can be the standard error of a mean `mse` of R = [`REALIZATIONS`] squared
/// errors: at least 0 (0 when every estimate errs alike, as a table's centred strata do on the edge
/// with the exact oracle), and at most `mse · sqrt(R / (R − 1))`, the bound for non-negative samples
/// (Σ(x − m)² ≤ Σx² ≤ (Σx)² = R²m², so s² ≤ R²m²/(R − 1) and s/sqrt(R) ≤ that). Only a necessary
/// condition, which the moments of any non-negative sample meet: the rows [`recomputed`] covers are
/// checked exactly.
fn stderr_fits(mse: f64, stderr: f64) -> bool {
    let r = REALIZATIONS as f64;
    (0.0..=mse * (r / (r - 1.0)).sqrt()).contains(&stderr)
}

/// The seed of every study of this file (see [`study`]).
const SEED: u64 = 7;

/// The MSE and its standard error of `sampler` on `f` at `n` points against `integral`, recomputed
/// from the R = [`REALIZATIONS`] estimates themselves, drawn as `converge::measure` draws them (its
/// module doc: realization `r` at size `N` takes its set from `rng::substream(seed, r, 3N)` and its
/// toroidal shift from `rng::substream(seed, r, 3N + 1)`; no random placement in compare), each
/// estimate the points' sum in order over `N`. The mean of the squared errors and the two-pass
/// sample standard deviation over `sqrt(R)` are taken in the order `measure` takes them, so a
/// correct report holds these bits exactly.
fn recomputed(
    sampler: &dyn anisospec::samplers::Sampler,
    f: &dyn anisospec::integrands::Integrand,
    n: usize,
    integral: f64,
) -> (f64, f64) {
    use rand::Rng as _;
    let dims = sampler.dims();
    let key = 3 * n as u64;
    let squares: Vec<f64> = (0..REALIZATIONS as u64)
        .map(|r| {
            let mut shift_rng = anisospec::rng::substream(SEED, r, key + 1);
            let shift: Vec<f64> = (0..dims).map(|_| shift_rng.random::<f64>()).collect();
            let set =
                sampler.generate_shifted(n, &mut anisospec::rng::substream(SEED, r, key), &shift);
            let sum: f64 = set.chunks_exact(dims).map(|p| f.eval(p)).sum();
            (sum / n as f64 - integral).powi(2)
        })
        .collect();
    let r = REALIZATIONS as f64;
    let mean = squares.iter().sum::<f64>() / r;
    let variance = squares.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (r - 1.0);
    (mean, (variance / r).sqrt())
}

/// The study's sheared sampler, transported padded MJ, sheared by `shear` on both axes.
fn sheared_mj(shear: f64) -> anisospec::samplers::Sheared {
    anisospec::samplers::Sheared::new(
        anisospec::samplers::build("padded-mj", 4).unwrap(),
        shear,
        shear,
        anisospec::points::shear::ShearMode::Transported,
    )
    .unwrap()
}

/// The shear compare gives a hairline pixel's samplers: the oracle's `sx` at the pixel of `label`
/// ("hairline pixel (px,py)") in the default scene.
fn hairline_pixel_shear(label: &str) -> f64 {
    let (px, py) = label
        .strip_prefix("hairline pixel (")
        .and_then(|rest| rest.strip_suffix(')'))
        .and_then(|xy| xy.split_once(','))
        .unwrap_or_else(|| panic!("'{label}' is not a hairline pixel's label"));
    let scene = anisospec::render::Scene::load(None).unwrap();
    anisospec::render::oracle::oracle_pixel(&scene, px.parse().unwrap(), py.parse().unwrap()).sx
}

/// The N a sampler of the study makes when asked for `n` (a table is built for exactly `n`).
fn usable(sampler: &str, n: usize) -> usize {
    match sampler.split(' ').next().unwrap() {
        "optimized" => n,
        name => {
            anisospec::compare::usable_n(anisospec::samplers::build(name, 4).unwrap().as_ref(), n)
        }
    }
}

/// A CSV file as its header and rows of named fields. Fields may be quoted (labels hold commas);
/// every row has as many fields as the header.
fn read_csv(path: &Path) -> (Vec<String>, Vec<BTreeMap<String, String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let split = |line: &str| {
        let (mut fields, mut field, mut quoted) = (Vec::new(), String::new(), false);
        for c in line.chars() {
            match c {
                '"' => quoted = !quoted,
                ',' if !quoted => fields.push(std::mem::take(&mut field)),
                _ => field.push(c),
            }
        }
        assert!(!quoted, "{}: unbalanced quotes in {line}", path.display());
        fields.push(field);
        fields
    };
    let mut lines = text.lines();
    let header = split(lines.next().expect("a header line"));
    let rows = lines
        .map(|line| {
            let fields = split(line);
            assert_eq!(
                fields.len(),
                header.len(),
                "{}: '{line}' against {header:?}",
                path.display()
            );
            header.iter().cloned().zip(fields).collect()
        })
        .collect();
    (header, rows)
}

/// A finite number from a CSV field.
fn num(row: &BTreeMap<String, String>, key: &str) -> f64 {
    let text = &row[key];
    let v: f64 = text
        .parse()
        .unwrap_or_else(|e| panic!("{key} = '{text}': {e}"));
    assert!(v.is_finite(), "{key} = {v} in {row:?}");
    v
}

/// A slope's 95% interval from its CSV fields: finite bounds, or `None` for the empty fields of an
/// undefined interval.
fn interval(row: &BTreeMap<String, String>) -> Option<(f64, f64)> {
    let (lo, hi) = ("slope_ci_low", "slope_ci_high");
    if row[lo].is_empty() && row[hi].is_empty() {
        None
    } else {
        Some((num(row, lo), num(row, hi)))
    }
}

fn read_npy(path: &Path) -> (Vec<u64>, Vec<f64>) {
    let bytes = std::fs::read(path).unwrap();
    let npy = npyz::NpyFile::new(&bytes[..]).unwrap();
    let shape = npy.shape().to_vec();
    (shape, npy.into_vec().unwrap())
}

/// One row of convergence.csv.
#[derive(Clone, Debug, PartialEq)]
struct Point {
    subject: String,
    class: String,
    /// The integral the errors are measured against.
    integral: f64,
    /// Its standard error: 0 for an analytic integral, a pixel reference's own.
    integral_stderr: f64,
    sampler: String,
    n: usize,
    mse: f64,
    mse_stderr: f64,
    seconds_per_estimate: f64,
    setup_seconds: f64,
    slope: f64,
    interval: Option<(f64, f64)>,
}

/// report.md as its level-2 sections: the heading, the rows of its tables (cells trimmed, separator
/// rows dropped) and its links `(text, target)`.
struct Section {
    heading: String,
    rows: Vec<Vec<String>>,
    links: Vec<(String, String)>,
}

fn read_markdown(path: &Path) -> Vec<Section> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut sections: Vec<Section> = Vec::new();
    for line in text.lines() {
        if let Some(heading) = line.strip_prefix("## ") {
            sections.push(Section {
                heading: heading.to_string(),
                rows: Vec::new(),
                links: Vec::new(),
            });
            continue;
        }
        let Some(section) = sections.last_mut() else {
            continue;
        };
        if line.starts_with("|---") {
            continue;
        }
        if line.starts_with('|') {
            let cells = line.trim().trim_matches('|').split('|');
            section
                .rows
                .push(cells.map(|c| c.trim().to_string()).collect());
        }
        let mut rest = line;
        while let Some(start) = rest.find("![") {
            let (text, after) = rest[start + 2..].split_once("](").expect("a link target");
            let (target, after) = after.split_once(')').expect("a closed link");
            section.links.push((text.to_string(), target.to_string()));
            rest = after;
        }
    }
    sections
}

/// Every file under `dir`, relative to it.
fn files_under(dir: &Path) -> BTreeSet<PathBuf> {
    let mut out = BTreeSet::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                out.insert(path.strip_prefix(dir).unwrap().to_path_buf());
            }
        }
    }
    out
}

/// Decodes a PNG and checks it is a picture: at least 400 x 200 pixels, many colours, and mostly
/// not one flat colour.
fn check_png(path: &Path) {
    let bytes = std::fs::read(path).unwrap();
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert!(
        info.width >= 400 && info.height >= 200,
        "{}: {} x {}",
        path.display(),
        info.width,
        info.height
    );
    assert_eq!(info.bit_depth, png::BitDepth::Eight, "{}", path.display());
    let bpp = info.color_type.samples();
    let mut counts: BTreeMap<&[u8], usize> = BTreeMap::new();
    for px in buf[..info.buffer_size()].chunks_exact(bpp) {
        *counts.entry(px).or_default() += 1;
    }
    let pixels = (info.width * info.height) as usize;
    let flat = counts.values().max().unwrap();
    assert!(
        counts.len() >= 16 && *flat < pixels * 99 / 100,
        "{}: {} colours, the commonest on {flat} of {pixels} pixels",
        path.display(),
        counts.len()
    );
}

/// Checks the report folder `out` of a study over `ns` and returns its convergence rows.
fn check_report(out: &Path, ns: &[usize]) -> Vec<Point> {
    let report = out.join("report.md");
    let text = std::fs::read_to_string(&report).unwrap();
    let sections = read_markdown(&report);
    let section = |heading: &str| {
        sections
            .iter()
            .find(|s| s.heading == heading)
            .unwrap_or_else(|| panic!("report.md has no section '{heading}'"))
    };

    // convergence.csv: one row per (integrand, sampler, N), integrand-major, samplers and N in config
    // order; positive MSE, finite slopes.
    let (_, rows) = read_csv(&out.join("convergence.csv"));
    let points: Vec<Point> = rows
        .iter()
        .map(|r| Point {
            subject: r["subject"].clone(),
            class: r["class"].clone(),
            integral: num(r, "integral"),
            integral_stderr: num(r, "integral_stderr"),
            sampler: r["sampler"].clone(),
            n: r["n"].parse().unwrap(),
            mse: num(r, "mse"),
            mse_stderr: num(r, "mse_stderr"),
            seconds_per_estimate: num(r, "seconds_per_estimate"),
            setup_seconds: num(r, "setup_seconds"),
            slope: num(r, "slope"),
            interval: interval(r),
        })
        .collect();
    // Columns: label, definition, class, ...
    let integrands = &section("Integrands").rows[1..];
    let subjects: Vec<(String, String)> = integrands
        .iter()
        .map(|r| (r[0].clone(), r[2].clone()))
        .collect();
    assert_eq!(integrands[0][1], "`sheared:s=0.5,c=0.7@xu`");
    // The pixel's definition gives the study's reference count, so that converge --integrand with
    // it uses the same reference (it left it out, and converge took the default 1048576 rays).
    assert!(
        integrands[1][1].starts_with("`pixel:px=") && integrands[1][1].ends_with(",refcount=4096`"),
        "{integrands:?}"
    );
    assert_eq!(subjects.len(), 2, "{subjects:?}");
    // axes.json labels the npy arrays' axes: the integrands and samplers in the order of the
    // tables, the study's N.
    // Every file the report wrote is among the places checked before any work.
    let labels = |list: Vec<&String>| list.into_iter().cloned().collect::<Vec<String>>();
    let places = anisospec::compare::report::places(
        &labels(subjects.iter().map(|s| &s.0).collect()),
        &SAMPLERS.map(|s| s.0.to_string()),
    );
    let manifest = std::fs::read_to_string(out.join("manifest.txt")).unwrap();
    for file in manifest.lines().skip(1).filter(|l| !l.ends_with('/')) {
        assert!(
            places.contains(&(PathBuf::from(file), false)),
            "{file} is not among the places checked up front"
        );
    }
    let axes: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("axes.json")).unwrap()).unwrap();
    assert_eq!(
        axes,
        serde_json::json!({
            "axes": ["integrand", "sampler", "n"],
            "integrand": subjects.iter().map(|s| &s.0).collect::<Vec<_>>(),
            "sampler": SAMPLERS.iter().map(|s| s.0).collect::<Vec<_>>(),
            "n": ns,
            "realizations": REALIZATIONS,
            "spectra": {
                "axes": ["projection", "k2 + K/2", "k1 + K/2"],
                "projection": ["xy", "uv", "xu", "yv"],
                "K": SPECTRA_RES,
                "n": SPECTRA_N,
                "realizations": 2,
            },
        })
    );
    assert_eq!(subjects[0], (EDGE.to_string(), "analytic".to_string()));
    assert_eq!(subjects[1].1, "hairline");
    // Each row carries its subject's integral: the edge's exact value, and a pixel's reference (a
    // radiance, positive).
    let edge = anisospec::integrands::parse("sheared:s=0.5,c=0.7@xu").unwrap();
    let pixel = anisospec::integrands::parse(integrands[1][1].trim_matches('`')).unwrap();
    // The samplers' shear of each integrand: the edge's configured 0.5, the pixel's oracle shear.
    let samplers_shear = |subject: &str| {
        if subject == EDGE {
            0.5
        } else {
            hairline_pixel_shear(subject)
        }
    };
    let mut recomputed_rows = 0;
    for p in &points {
        if p.subject == EDGE {
            assert_eq!(p.integral, edge.reference().value, "{p:?}");
            assert_eq!(p.integral_stderr, 0.0, "{p:?}");
        } else {
            assert!(p.integral.is_finite() && p.integral > 0.0, "{p:?}");
            assert!(p.integral_stderr > 0.0, "{p:?}");
        }
    }
    assert_eq!(points.len(), subjects.len() * SAMPLERS.len() * ns.len());
    let studies: Vec<&[Point]> = points.chunks(ns.len()).collect();
    for (i, study) in studies.iter().enumerate() {
        let (subject, class) = &subjects[i / SAMPLERS.len()];
        let (sampler, family) = SAMPLERS[i % SAMPLERS.len()];
        for ((p, row), &n) in study.iter().zip(&rows[i * ns.len()..]).zip(ns) {
            assert_eq!(
                (&p.subject, &p.class, p.sampler.as_str(), p.n),
                (subject, class, sampler, usable(sampler, n)),
            );
            assert_eq!(row["family"], family);
            assert!(p.mse > 0.0 && stderr_fits(p.mse, p.mse_stderr), "{p:?}");
            // The rows whose sampler the test can build (all but a table's, which takes its
            // optimization) are recomputed from their estimates: the MSE and its standard error,
            // bit for bit.
            let sampler_here: Option<Box<dyn anisospec::samplers::Sampler>> = match family {
                "classical" => Some(anisospec::samplers::build("padded-jittered", 4).unwrap()),
                "sheared" => Some(Box::new(sheared_mj(samplers_shear(&p.subject)))),
                _ => None,
            };
            if let Some(sampler_here) = sampler_here {
                let f = if p.subject == EDGE { &edge } else { &pixel };
                let (mse, stderr) = recomputed(sampler_here.as_ref(), f.as_ref(), p.n, p.integral);
                assert_eq!(
                    (p.mse.to_bits(), p.mse_stderr.to_bits()),
                    (mse.to_bits(), stderr.to_bits()),
                    "{p:?}: recomputed MSE {mse:e} ± {stderr:e}"
                );
                recomputed_rows += 1;
            }
            assert!(p.seconds_per_estimate > 0.0, "{p:?}");
            // Only a table has a one-off set-up: its own optimization at that N.
            assert_eq!(p.setup_seconds > 0.0, family == "optimized", "{p:?}");
            assert_eq!(
                (p.slope, p.interval),
                (study[0].slope, study[0].interval),
                "one fit per study"
            );
        }
        // With two N the fit goes through both points, whatever their weights.
        let (a, b) = (&study[0], &study[1]);
        let through = (b.mse / a.mse).ln() / (b.n as f64 / a.n as f64).ln();
        let slope = a.slope;
        assert!((slope - through).abs() < 1e-9, "{slope} vs {through}");
        // The interval is left empty exactly when a point's standard error defines no weight: not
        // above what f64 rounding alone gives an estimator whose error is the same for every shift
        // (e.g. centred strata on an unmoved edge).
        let weightless = study
            .iter()
            .any(|p| p.mse_stderr / p.mse <= rounding_floor(p.n, REALIZATIONS, p.mse, p.integral));
        assert_eq!(a.interval.is_none(), weightless, "{study:?}");
        if let Some((lo, hi)) = a.interval {
            assert!(lo <= slope && slope <= hi, "{slope} outside [{lo}, {hi}]");
        }
    }
    // Padded jittered and the sheared sampler on both integrands: all rows but the table's.
    assert_eq!(recomputed_rows, 4 * ns.len());

    // The arrays [integrand, sampler, N] hold the CSV's numbers bit for bit (the CSV prints the
    // shortest text that reads back as the same f64).
    let shape = [subjects.len(), SAMPLERS.len(), ns.len()].map(|s| s as u64);
    let columns: [(&str, Vec<f64>); 5] = [
        ("mse", points.iter().map(|p| p.mse).collect()),
        ("mse_stderr", points.iter().map(|p| p.mse_stderr).collect()),
        ("n", points.iter().map(|p| p.n as f64).collect()),
        (
            "seconds_per_estimate",
            points.iter().map(|p| p.seconds_per_estimate).collect(),
        ),
        (
            "setup_seconds",
            points.iter().map(|p| p.setup_seconds).collect(),
        ),
    ];
    for (name, column) in columns {
        let (s, values) = read_npy(&out.join(format!("{name}.npy")));
        assert_eq!(s, shape, "{name}.npy");
        let csv: Vec<u64> = column.iter().map(|v| v.to_bits()).collect();
        let npy: Vec<u64> = values.iter().map(|v| v.to_bits()).collect();
        assert_eq!(npy, csv, "{name}.npy against convergence.csv");
    }

    // report.md: per integrand, a header naming every N and a row per sampler printing the CSV's
    // numbers; the columns "at N=" are at the largest N of the config (a gain from a sampler's
    // nearest N names it).
    let best_classical = |subject: &str, at: usize| {
        points
            .chunks(ns.len())
            .filter(|s| s[0].subject == subject && s[0].sampler == SAMPLERS[0].0)
            .map(|s| s[at].mse)
            .fold(f64::INFINITY, f64::min)
    };
    let last = (0..ns.len()).max_by_key(|&i| ns[i]).unwrap();
    let mut plots = Vec::new();
    for (subject, _) in &subjects {
        let section = section(subject);
        let mut header = vec!["sampler".to_string(), "family".to_string()];
        header.extend(ns.iter().map(|n| format!("MSE at N={n}")));
        header.extend([
            "slope [95% CI]".to_string(),
            "local slope".to_string(),
            format!("ms/estimate at N={}", ns[last]),
            format!("set-up s at N={}", ns[last]),
            format!("gain over best classical at N={}", ns[last]),
        ]);
        assert_eq!(section.rows[0], header, "{subject}");
        assert_eq!(section.rows.len(), 1 + SAMPLERS.len(), "{subject}");
        for (row, (sampler, family)) in section.rows[1..].iter().zip(SAMPLERS) {
            let study = studies
                .iter()
                .find(|s| &s[0].subject == subject && s[0].sampler == sampler)
                .unwrap();
            let mut expect = vec![sampler.to_string(), family.to_string()];
            for (p, &n) in study.iter().zip(ns) {
                let shown = if p.n == n {
                    String::new()
                } else {
                    format!(" (N={})", p.n)
                };
                expect.push(format!("{:.3e} ± {:.1e}{shown}", p.mse, p.mse_stderr));
            }
            let slope = study[0].slope;
            let p = &study[last];
            // The local slope: between the two largest N the sampler made.
            let mut made: Vec<_> = study.iter().map(|p| (p.n, p.mse)).collect();
            made.sort_by_key(|&(n, _)| n);
            made.dedup_by_key(|&mut (n, _)| n);
            let local = match made[..] {
                [.., (na, a), (nb, b)] => {
                    format!("{:.2}", (b / a).ln() / (nb as f64 / na as f64).ln())
                }
                _ => "—".into(),
            };
            expect.extend([
                match study[0].interval {
                    Some((lo, hi)) => format!("{slope:.2} [{lo:.2}, {hi:.2}]"),
                    None => format!("{slope:.2} [—]"),
                },
                local,
                format!("{:.3}", p.seconds_per_estimate * 1e3),
                format!("{:.2}", p.setup_seconds),
                format!("{:.2}×", best_classical(subject, last) / p.mse)
                    + &if p.n == ns[last] {
                        String::new()
                    } else {
                        format!(" (N={})", p.n)
                    },
            ]);
            assert_eq!(row, &expect, "{subject}");
        }
        let targets: Vec<&str> = section.links.iter().map(|l| l.1.as_str()).collect();
        assert_eq!(
            targets.len(),
            2,
            "{subject}: a convergence and a speed plot"
        );
        plots.extend(targets);
    }
    assert_eq!(
        plots.iter().collect::<BTreeSet<_>>().len(),
        plots.len(),
        "every integrand has its own plots: {plots:?}"
    );

    // robustness.csv: the sheared and optimized samplers at the largest N on every integrand, per
    // shear error; at error 0 the same measurement as the study's.
    let nmax = *ns.iter().max().unwrap();
    let at_max = ns.iter().position(|&n| n == nmax).unwrap();
    let (_, rows) = read_csv(&out.join("robustness.csv"));
    let followers = &SAMPLERS[1..];
    assert_eq!(
        rows.len(),
        subjects.len() * followers.len() * SHEAR_ERRORS.len()
    );
    let mut rows = rows.iter();
    let robustness_section = section("Robustness to oracle error");
    let robustness = &robustness_section.rows;
    let mut expect_header = [
        "integrand",
        "sampler",
        "exact oracle",
        "worst with the oracle off",
        "mean with the oracle off",
    ]
    .map(String::from)
    .to_vec();
    expect_header.extend(
        SHEAR_ERRORS[1..]
            .iter()
            .map(|e| format!("error {:+}%", (e * 1000.0).round() / 10.0)),
    );
    assert_eq!(robustness[0], expect_header);
    let mut table_rows = robustness[1..].iter();
    let mut recomputed_sweep = 0;
    for (subject, _) in &subjects {
        for (sampler, _) in followers {
            let reference = best_classical(subject, at_max);
            let cell = |mse: f64, stderr: f64| {
                format!("{mse:.2e} ± {stderr:.1e} ({:.2}×)", reference / mse)
            };
            let mut off = Vec::new();
            let mut exact = String::new();
            for e in SHEAR_ERRORS {
                let r = rows.next().unwrap();
                assert_eq!(
                    (&r["subject"], r["sampler"].as_str(), num(r, "shear_error")),
                    (subject, *sampler, e)
                );
                assert_eq!(r["n"], usable(sampler, nmax).to_string());
                assert_eq!(r["realizations"], REALIZATIONS.to_string());
                // Both integrands see one depth off focus: the oracle's shear moves the sheared
                // sampler and the hairline table (designed unsheared) alike.
                assert_eq!(r["moved_by_oracle"], "true", "{r:?}");
                let (mse, stderr) = (num(r, "mse"), num(r, "mse_stderr"));
                assert!(mse > 0.0 && stderr_fits(mse, stderr), "{r:?}");
                // The sheared sampler, its shear scaled by (1 + error) as the sweep scales it:
                // recomputed from its estimates, bit for bit.
                if sampler.starts_with("padded-mj sheared") {
                    let sheared = sheared_mj(samplers_shear(subject) * (1.0 + e));
                    let (f, integral) = if subject == EDGE {
                        (&edge, edge.reference().value)
                    } else {
                        let p = points.iter().find(|p| &p.subject == subject).unwrap();
                        (&pixel, p.integral)
                    };
                    let n = usable(sampler, nmax);
                    let again = recomputed(&sheared, f.as_ref(), n, integral);
                    recomputed_sweep += 1;
                    assert_eq!(
                        (mse.to_bits(), stderr.to_bits()),
                        (again.0.to_bits(), again.1.to_bits()),
                        "{r:?}: recomputed MSE {:e} ± {:e}",
                        again.0,
                        again.1
                    );
                }
                if e == 0.0 {
                    let study = studies
                        .iter()
                        .find(|s| &s[0].subject == subject && s[0].sampler == *sampler)
                        .unwrap();
                    assert_eq!(
                        (mse, stderr),
                        (study[at_max].mse, study[at_max].mse_stderr),
                        "{subject}, {sampler}: the exact oracle's row is the study's point"
                    );
                    exact = cell(mse, stderr);
                } else {
                    off.push((e, mse, stderr));
                }
            }
            // One error off: it is the worst, its MSE the mean, and it has a column of its own.
            let [(e, mse, stderr)] = off[..] else {
                panic!("one error off the oracle")
            };
            let expect = vec![
                subject.clone(),
                sampler.to_string(),
                exact,
                format!(
                    "{} at {:+}%",
                    cell(mse, stderr),
                    (e * 1000.0).round() / 10.0
                ),
                format!("{mse:.2e} ({:.2}×)", reference / mse),
                cell(mse, stderr),
            ];
            assert_eq!(table_rows.next(), Some(&expect));
        }
    }
    assert_eq!(table_rows.next(), None);
    // The sheared sampler's rows on both integrands, at every error.
    assert_eq!(recomputed_sweep, subjects.len() * SHEAR_ERRORS.len());
    let plots: Vec<&str> = robustness_section
        .links
        .iter()
        .map(|l| l.1.as_str())
        .collect();
    assert_eq!(
        plots.len(),
        subjects.len(),
        "a robustness plot per integrand"
    );
    assert!(plots.iter().all(|p| p.starts_with("plots/robustness_")));

    // The summary: per integrand at the largest N, the best classical sampler with its MSE, and the
    // sampler with the lowest MSE (named first among any that tie) with its gain over it.
    let summary = &section("Summary").rows;
    assert_eq!(summary.len(), 1 + subjects.len(), "{summary:?}");
    for (row, (subject, class)) in summary[1..].iter().zip(&subjects) {
        let own: Vec<&[Point]> = studies
            .iter()
            .filter(|s| &s[0].subject == subject)
            .copied()
            .collect();
        let best = own
            .iter()
            .min_by(|a, b| a[at_max].mse.total_cmp(&b[at_max].mse))
            .unwrap();
        let classical = best_classical(subject, at_max);
        // A sampler measured at another N than the largest asked is marked with it.
        let other_n = |p: &Point| {
            if p.n == ns[at_max] {
                String::new()
            } else {
                format!(" (N={})", p.n)
            }
        };
        let jittered = own.iter().find(|s| s[0].sampler == SAMPLERS[0].0).unwrap();
        assert_eq!((&row[0], &row[1]), (subject, class));
        assert_eq!(
            row[2],
            format!(
                "{} ({classical:.3e}){}",
                SAMPLERS[0].0,
                other_n(&jittered[at_max])
            )
        );
        assert!(
            row[3]
                .split(" = ")
                .any(|name| name.split(" (N=").next() == Some(best[0].sampler.as_str())),
            "{subject}: {} is not named best in {row:?}",
            best[0].sampler
        );
        // The others within 2 combined standard errors of it at the largest N.
        let close: Vec<String> = own
            .iter()
            .filter(|s| {
                !row[3]
                    .split(" = ")
                    .any(|name| name.split(" (N=").next() == Some(s[0].sampler.as_str()))
            })
            .filter(|s| {
                let (p, q) = (&best[at_max], &s[at_max]);
                (q.mse - p.mse).abs() <= 2.0 * p.mse_stderr.hypot(q.mse_stderr)
            })
            .map(|s| format!("{}{}", s[0].sampler, other_n(&s[at_max])))
            .collect();
        let close = if close.is_empty() {
            "—".to_string()
        } else {
            close.join(", ")
        };
        assert_eq!(row[4], close, "{subject}: {row:?}");
        assert_eq!(row[5], format!("{:.2}×", classical / best[at_max].mse));
        // The N at which it beats the best classical sampler at that N by more than 2 combined
        // standard errors (the only classical sampler here is padded-jittered).
        let beats = |i: usize| {
            let p = &best[i];
            let c = &jittered[i];
            c.mse - p.mse > 2.0 * p.mse_stderr.hypot(c.mse_stderr)
        };
        // An N the sampler replaced by its nearest valid N is marked with it.
        let wins: Vec<String> = (0..ns.len())
            .filter(|&i| beats(i))
            .map(|i| match best[i].n == ns[i] {
                true => ns[i].to_string(),
                false => format!("{} (N={})", ns[i], best[i].n),
            })
            .collect();
        let wins = if best[0].sampler == SAMPLERS[0].0 {
            "— (classical)".to_string()
        } else if wins.is_empty() {
            "none".to_string()
        } else if wins.len() == ns.len() && (0..ns.len()).all(|i| best[i].n == ns[i]) {
            "all".to_string()
        } else {
            wins.join(", ")
        };
        assert_eq!(row[6], wins, "{subject}: {row:?}");
    }

    // The tables: per integrand, the table's target, the start of its optimization at every N, and
    // its set-up at every N as in the CSV.
    // What each sampler is: a row per sampler in the tables' order, with its family and a line
    // from the sampler catalogue (padded-jittered: Cook padding of jittered sets).
    let glossary = &section("Samplers").rows;
    assert_eq!(glossary.len(), 1 + SAMPLERS.len(), "{glossary:?}");
    for (row, (sampler, family)) in glossary[1..].iter().zip(SAMPLERS) {
        assert_eq!((row[0].as_str(), row[1].as_str()), (sampler, family));
    }
    assert!(
        glossary[1][2].starts_with("Cook padding: 2D sets of jittered"),
        "{glossary:?}"
    );
    assert!(glossary[2][2].contains("seam-free"), "{glossary:?}");
    assert!(
        glossary[3][2].contains("targets/hairline.toml"),
        "{glossary:?}"
    );

    let tables = &section("Tables").rows;
    assert_eq!(tables.len(), 1 + subjects.len(), "{tables:?}");
    for (row, (subject, _)) in tables[1..].iter().zip(&subjects) {
        let study = studies
            .iter()
            .find(|s| &s[0].subject == subject && s[0].sampler == SAMPLERS[2].0)
            .unwrap();
        assert_eq!(row[0], *subject);
        assert!(row[1].ends_with("hairline.toml"), "{row:?}");
        for p in study.iter() {
            let start = start_sampler(p.n);
            assert!(
                row[3].contains(start),
                "{subject}: {start} at N = {}: {row:?}",
                p.n
            );
        }
        let setups: Vec<String> = study
            .iter()
            .map(|p| format!("{:.2}", p.setup_seconds))
            .collect();
        assert_eq!(row[5..], setups[..], "{subject}");
    }

    // The spectra gallery: one sheet per sampler, beside it the npy [projection, K, K] of expected
    // power spectra, P(0) = N in every projection.
    let gallery = &section("Spectra").links;
    let labels: Vec<&str> = gallery.iter().map(|l| l.0.as_str()).collect();
    assert_eq!(labels, SAMPLERS.map(|s| s.0));
    let k = SPECTRA_RES;
    for (label, png) in gallery {
        let (shape, values) = read_npy(&out.join(png).with_extension("npy"));
        assert_eq!(shape, [4, k as u64, k as u64], "{label}");
        assert!(values.iter().all(|v| v.is_finite() && *v >= 0.0), "{label}");
        for projection in values.chunks_exact(k * k) {
            let dc = projection[k / 2 * k + k / 2];
            // The gallery's NUFFT (eps = 1e-6) promises a relative error of P within 10 eps.
            assert!(
                (dc / SPECTRA_N as f64 - 1.0).abs() <= 1e-5,
                "{label}: P(0) = {dc}"
            );
        }
    }

    // Every link leads to a decodable picture; every file is a linked picture, a gallery npy beside
    // one, or a top-level file report.md names; no temporary file is left.
    let linked: BTreeSet<PathBuf> = sections
        .iter()
        .flat_map(|s| s.links.iter().map(|l| PathBuf::from(&l.1)))
        .collect();
    // A convergence, a speed and a robustness plot per integrand, a sheet per sampler.
    assert_eq!(linked.len(), 3 * subjects.len() + SAMPLERS.len());
    for path in &linked {
        check_png(&out.join(path));
    }
    // manifest.txt lists every file of the report.
    let manifest = std::fs::read_to_string(out.join("manifest.txt")).unwrap();
    let listed: BTreeSet<PathBuf> = manifest
        .lines()
        .skip(1)
        .filter(|l| !l.ends_with('/'))
        .map(PathBuf::from)
        .collect();
    let report_files: BTreeSet<PathBuf> = files_under(out)
        .into_iter()
        .filter(|f| f != Path::new("manifest.txt"))
        .collect();
    assert_eq!(listed, report_files, "{manifest}");
    for file in report_files {
        let top_level = file.parent() == Some(Path::new(""));
        let named = top_level && text.contains(&format!("`{}`", file.display()));
        let gallery_npy = file.starts_with("spectra")
            && file.extension().is_some_and(|e| e == "npy")
            && linked.contains(&file.with_extension("png"));
        assert!(
            linked.contains(&file) || named || gallery_npy || file == Path::new("report.md"),
            "{} is in no link and not named in report.md",
            file.display()
        );
    }
    points
}

/// Every file under `dir` with its contents and modification time.
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, (Vec<u8>, SystemTime)> {
    files_under(dir)
        .into_iter()
        .map(|f| {
            let path = dir.join(&f);
            let modified = std::fs::metadata(&path).unwrap().modified().unwrap();
            (f, (std::fs::read(&path).unwrap(), modified))
        })
        .collect()
}

/// The numbers of a run that do not depend on the machine's speed: the rows without their timing.
fn measured(points: &[Point]) -> Vec<Point> {
    points
        .iter()
        .map(|p| Point {
            seconds_per_estimate: 0.0,
            ..p.clone()
        })
        .collect()
}

/// A study runs, writes a consistent report, and runs again on its cache without rebuilding a table
/// or changing a number; the same study with its sizes reordered and one a sampler cannot make,
/// written over the first report, reports the same measurements.
#[test]
fn compare_writes_a_consistent_report_and_reuses_its_cache() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let ns = [16, 64];
    let first = compare(dir.path(), "first", &study(&ns), &cache);
    let points = check_report(&first, &ns);
    let tables = files_under(&cache.join("tables"));
    assert_eq!(
        tables
            .iter()
            .filter(|f| f.extension().unwrap() == "npy")
            .count(),
        ns.len(),
        "one table per N: {tables:?}"
    );

    // Again on the warm cache: no cache file rewritten, the same numbers (and the same set-up times,
    // read back from the tables' sidecars); only the timings differ.
    let before = snapshot(&cache);
    let second = compare(dir.path(), "second", &study(&ns), &cache);
    assert!(
        before == snapshot(&cache),
        "the second run rewrote the cache"
    );
    let again = check_report(&second, &ns);
    assert_eq!(measured(&again), measured(&points));
    for file in ["robustness.csv", "mse.npy", "mse_stderr.npy", "n.npy"]
        .map(PathBuf::from)
        .into_iter()
        .chain(
            files_under(&first.join("spectra"))
                .into_iter()
                .filter(|f| f.extension().unwrap() == "npy")
                .map(|f| Path::new("spectra").join(f)),
        )
    {
        assert_eq!(
            std::fs::read(first.join(&file)).unwrap(),
            std::fs::read(second.join(&file)).unwrap(),
            "{}",
            file.display()
        );
    }

    // Sizes with one (15) not a square, which padded jittered replaces by 16: the report shows the
    // N used, and every measurement both runs made is the same. It replaces the first report
    // (check_report: its manifest lists exactly the files in the folder). (Sizes out of order are
    // refused: the plots' lines would run back along N.)
    let odd = [15, 64];
    let before = snapshot(&cache);
    let third = compare(dir.path(), "first", &study(&odd), &cache);
    let shuffled = check_report(&third, &odd);
    // (It adds the table for N = 15 and touches none of the others.)
    let after = snapshot(&cache);
    assert!(
        before.iter().all(|(f, v)| after.get(f) == Some(v)),
        "the third run changed the cache"
    );
    let key = |p: &Point| (p.subject.clone(), p.sampler.clone(), p.n);
    let earlier: BTreeMap<_, _> = points.iter().map(|p| (key(p), p)).collect();
    let mut shared = 0;
    for p in &shuffled {
        if let Some(q) = earlier.get(&key(p)) {
            assert_eq!(
                (p.mse.to_bits(), p.mse_stderr.to_bits()),
                (q.mse.to_bits(), q.mse_stderr.to_bits()),
                "{p:?} vs {q:?}"
            );
            shared += 1;
        }
    }
    // Every sampler at 64 and padded jittered at 16, on both integrands.
    assert_eq!(shared, 2 * (SAMPLERS.len() + 1));

    // A file of the user's where the report puts one (here a plot the manifest no longer lists)
    // stops the next run before any work, with a usage error naming it, and nothing changes.
    let manifest = third.join("manifest.txt");
    let listed = std::fs::read_to_string(&manifest).unwrap();
    let plot = format!("plots/speed_{}.png", anisospec::compare::report::slug(EDGE));
    assert!(listed.lines().any(|l| l == plot), "{listed}");
    let without: String = listed
        .lines()
        .filter(|l| *l != plot)
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(&manifest, &without).unwrap();
    let before = snapshot(&third);
    let config = dir.path().join("clash.toml");
    std::fs::write(&config, study(&odd)).unwrap();
    let o = anisospec(&[
        "compare",
        "--config",
        config.to_str().unwrap(),
        "--out",
        third.to_str().unwrap(),
        "--cache",
        cache.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&plot) && err.contains("did not write it"),
        "{err}"
    );
    assert!(
        before == snapshot(&third),
        "the refused run changed the folder"
    );
}

/// A cached table whose file is unreadable is rebuilt, with a warning naming it, as the pixel
/// references are: the run succeeds, the rebuilt file is the table the first run built, and the
/// measurements are the same.
#[test]
fn compare_rebuilds_a_corrupted_cached_table() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let ns = [16, 64];
    let first = compare(dir.path(), "first", &study(&ns), &cache);
    let points = check_report(&first, &ns);
    let table = files_under(&cache.join("tables"))
        .into_iter()
        .find(|f| f.extension().unwrap() == "npy")
        .map(|f| cache.join("tables").join(f))
        .expect("a cached table");
    let built = std::fs::read(&table).unwrap();
    std::fs::write(&table, b"not an npy file").unwrap();

    let (second, err) = compare_logged(dir.path(), "second", &study(&ns), &cache);
    assert!(
        err.contains("rebuilding") && err.contains(table.file_name().unwrap().to_str().unwrap()),
        "{err}"
    );
    assert_eq!(
        std::fs::read(&table).unwrap(),
        built,
        "the rebuilt table differs"
    );
    // The same numbers but the set-up times: the rebuilt table's is the rebuild's.
    let untimed = |p: &[Point]| -> Vec<Point> {
        measured(p)
            .into_iter()
            .map(|p| Point {
                setup_seconds: 0.0,
                ..p
            })
            .collect()
    };
    assert_eq!(untimed(&check_report(&second, &ns)), untimed(&points));

    // A readable table with fewer sets than table_sets (one of its 2) is rebuilt too: it was reused,
    // and the report said "a table of 2 sets".
    let whole = anisospec::points::io::read_points(&table).unwrap();
    let one = anisospec::points::PointSets::from_sets(4, vec![whole.set(0).to_vec()]).unwrap();
    anisospec::points::io::write_points(&table, &one).unwrap();
    let (third, err) = compare_logged(dir.path(), "third", &study(&ns), &cache);
    assert!(
        err.contains("holds 1 set, not the 2 of table_sets"),
        "{err}"
    );
    assert_eq!(std::fs::read(&table).unwrap(), built);
    assert_eq!(untimed(&check_report(&third, &ns)), untimed(&points));
}

/// A table whose sets stopped at the time limit is cached with that limit: a run with the same
/// limit reuses it and warns once, a run with a longer limit rebuilds it (its sets then run their
/// iterations), and the sidecar records what stopped them.
#[test]
fn a_table_cut_short_by_the_time_limit_is_rebuilt_under_a_longer_one() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let ns = [16, 64];
    let short = study(&ns).replace("table_seconds = 600.0", "table_seconds = 1e-9");
    // The sidecars of the cached tables, one per N.
    let sidecars = || -> Vec<serde_json::Value> {
        let found: Vec<serde_json::Value> = files_under(&cache.join("tables"))
            .into_iter()
            .filter(|f| f.extension().unwrap() == "json")
            .map(|f| {
                let text = std::fs::read_to_string(cache.join("tables").join(f)).unwrap();
                serde_json::from_str(&text).unwrap()
            })
            .collect();
        assert_eq!(found.len(), ns.len());
        found
    };
    let run = |name: &str, config: &str| compare_logged(dir.path(), name, config, &cache).1;
    run("short", &short);
    for s in sidecars() {
        assert_eq!(s["sets_stopped_by_time_limit"], 2);
        assert_eq!(s["table_seconds"], 1e-9);
    }
    let again = run("again", &short);
    assert_eq!(
        again.matches("stopped at the time limit").count(),
        ns.len(),
        "{again}"
    );
    assert!(!again.contains("rebuilding"), "{again}");
    let longer = run("longer", &study(&ns));
    assert_eq!(
        longer.matches("note: rebuilding the cached").count(),
        ns.len(),
        "{longer}"
    );
    for s in sidecars() {
        assert_eq!(s["sets_stopped_by_time_limit"], 0);
        assert_eq!(s["table_seconds"], 600.0);
    }
}
