//! The compare report folder: `report.md` with tables, convergence and speed-against-error plots, a
//! spectra gallery per sampler, and CSV / npy of every number.

use super::config::{CompareConfig, GALLERY_SHEAR_RANGE};
use super::tables::{framed_target, moved, start_sampler, TableCache, TABLE_ITERATIONS};
use super::{instantiate, usable_n, Outcome, Robustness, SamplerSpec, Study, SubjectInfo};
use crate::converge::{plot, ConvergePoint, Convergence};
use crate::error::Result;
use crate::output::plot::{write_loglog_png, LogLogPlot, Series, XScale};
use crate::output::sheet::{write_sheet, Panel};
use crate::output::{csv_number, write_atomic, write_npy, ReportMarker};
use crate::points::shear::ShearMode;
use crate::points::Projection;
use crate::spectrum::expected::of_sampler;
use crate::spectrum::Method;
use crate::targets::variance::Design;
use crate::targets::Target;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The report's main file and its first line; a folder holding it holds an earlier report, which a new
/// one replaces.
pub const REPORT_MARKER: ReportMarker = ReportMarker {
    file: "report.md",
    first_line: "# anisospec compare",
};

/// A file-name-safe version of a label.
pub fn slug(label: &str) -> String {
    let s: String = label
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '_'
            }
        })
        .collect();
    s.split('_')
        .filter(|p| !p.is_empty())
        .collect::<Vec<_>>()
        .join("_")
}

/// The report's files named the same in every study (besides [`REPORT_MARKER`]'s and the manifest).
const NUMBER_FILES: [&str; 8] = [
    "convergence.csv",
    "robustness.csv",
    "mse.npy",
    "mse_stderr.npy",
    "n.npy",
    "seconds_per_estimate.npy",
    "setup_seconds.npy",
    "axes.json",
];

/// The plot of one kind (`convergence`, `speed`, `robustness`) for the integrand `label`.
fn plot_file(kind: &str, label: &str) -> String {
    format!("plots/{kind}_{}.png", slug(label))
}

/// The spectra gallery's file of the sampler `label`, with extension `ext` (`png`, `npy`).
fn spectra_file(label: &str, ext: &str) -> String {
    format!("spectra/{}.{ext}", slug(label))
}

/// Every place the report may write for these integrands and samplers, relative to its folder, with
/// whether it is a folder: a superset (a plot the report leaves out is listed), for checking before
/// any work that none is taken ([`crate::output::check_report_places`]).
pub fn places(subject_labels: &[String], sampler_labels: &[String]) -> Vec<(PathBuf, bool)> {
    let files = std::iter::once(REPORT_MARKER.file.to_string())
        .chain(NUMBER_FILES.map(String::from))
        .chain(subject_labels.iter().flat_map(|label| {
            ["convergence", "speed", "robustness"].map(|kind| plot_file(kind, label))
        }))
        .chain(
            sampler_labels
                .iter()
                .flat_map(|label| ["png", "npy"].map(|ext| spectra_file(label, ext))),
        );
    ["plots", "spectra"]
        .map(|folder| (folder.into(), true))
        .into_iter()
        .chain(files.map(|f| (f.into(), false)))
        .collect()
}

/// Writes the whole report under `out`; `started` is when the run began (the report states the time
/// of the whole run, its spectra gallery included).
pub fn write(
    outcome: &Outcome,
    specs: &[SamplerSpec],
    tables: &TableCache,
    out: &Path,
    started: std::time::Instant,
) -> Result<()> {
    write_numbers(outcome, specs, out)?;
    let mut plots = Vec::new();
    for SubjectInfo { label, .. } in &outcome.subjects {
        let studies: Vec<&Study> = outcome
            .studies
            .iter()
            .filter(|s| &s.subject == label)
            .collect();
        // A log axis has no place for an MSE of 0: an integrand every sampler integrates exactly
        // gets its tables and a line saying so, and no plot.
        if !studies
            .iter()
            .any(|s| s.points.iter().any(|p| drawable(p.mse)))
        {
            plots.push(None);
            continue;
        }
        let conv = plot_file("convergence", label);
        let speed = plot_file("speed", label);
        write_convergence_plot(
            &out.join(&conv),
            label,
            &studies,
            outcome.config.realizations,
        )?;
        write_speed_plot(&out.join(&speed), label, &studies, &outcome.config)?;
        plots.push(Some((conv, speed)));
    }
    let mut robustness_plots = Vec::new();
    for SubjectInfo { label, .. } in &outcome.subjects {
        let file = plot_file("robustness", label);
        if write_robustness_plot(&out.join(&file), outcome, label)? {
            robustness_plots.push((label.clone(), file));
        }
    }
    let gallery = write_gallery(outcome, specs, tables, out)?;
    let whole_seconds = started.elapsed().as_secs_f64();
    write_markdown(
        outcome,
        specs,
        &plots,
        &robustness_plots,
        &gallery,
        whole_seconds,
        out,
    )
}

/// Whether an MSE can be drawn on a log axis: finite and above 0.
pub(crate) fn drawable(mse: f64) -> bool {
    mse.is_finite() && mse > 0.0
}

fn write_numbers(outcome: &Outcome, specs: &[SamplerSpec], out: &Path) -> Result<()> {
    let r = outcome.config.realizations;
    write_atomic(&out.join("convergence.csv"), |w| {
        writeln!(
            w,
            "subject,class,integral,integral_stderr,sampler,family,n,realizations,mse,mse_stderr,seconds_per_estimate,setup_seconds,slope,slope_ci_low,slope_ci_high"
        )?;
        for s in &outcome.studies {
            let subject = outcome
                .subjects
                .iter()
                .find(|i| i.label == s.subject)
                .expect("every study's subject is in the outcome");
            let (integral, integral_stderr) = (subject.integral, subject.integral_stderr);
            let (slope, lo, hi) =
                s.fit
                    .map_or((String::new(), String::new(), String::new()), |f| {
                        let (lo, hi) = f.interval().map_or((String::new(), String::new()), |i| {
                            (csv_number(i.0), csv_number(i.1))
                        });
                        (csv_number(f.slope), lo, hi)
                    });
            for (p, setup) in s.points.iter().zip(&s.setup_seconds) {
                writeln!(
                    w,
                    "\"{}\",{},{},{},\"{}\",{},{},{r},{},{},{},{},{slope},{lo},{hi}",
                    s.subject,
                    s.class,
                    csv_number(integral),
                    csv_number(integral_stderr),
                    s.sampler,
                    s.family,
                    p.n,
                    csv_number(p.mse),
                    csv_number(p.mse_stderr),
                    csv_number(p.median_seconds),
                    csv_number(*setup)
                )?;
            }
        }
        Ok(())
    })?;
    write_atomic(&out.join("robustness.csv"), |w| {
        writeln!(
            w,
            "subject,sampler,shear_error,n,realizations,mse,mse_stderr,moved_by_oracle"
        )?;
        for row in &outcome.robustness {
            writeln!(
                w,
                "\"{}\",\"{}\",{},{},{r},{},{},{}",
                row.subject,
                row.sampler,
                csv_number(row.error),
                row.point.n,
                csv_number(row.point.mse),
                csv_number(row.point.mse_stderr),
                row.moved
            )?;
        }
        Ok(())
    })?;
    let shape = [outcome.subjects.len(), specs.len(), outcome.config.ns.len()];
    let collect = |f: &dyn Fn(&ConvergePoint) -> f64| -> Vec<f64> {
        outcome
            .studies
            .iter()
            .flat_map(|s| s.points.iter().map(f))
            .collect()
    };
    write_npy(&out.join("mse.npy"), &shape, &collect(&|p| p.mse))?;
    write_npy(
        &out.join("mse_stderr.npy"),
        &shape,
        &collect(&|p| p.mse_stderr),
    )?;
    write_npy(&out.join("n.npy"), &shape, &collect(&|p| p.n as f64))?;
    let setup: Vec<f64> = outcome
        .studies
        .iter()
        .flat_map(|s| s.setup_seconds.iter().copied())
        .collect();
    write_npy(&out.join("setup_seconds.npy"), &shape, &setup)?;
    // What each index of the arrays' axes stands for, so that they load labelled; and the spectra's.
    let k = outcome.config.spectra_res;
    let axes = serde_json::json!({
        "axes": ["integrand", "sampler", "n"],
        "integrand": outcome.subjects.iter().map(|s| &s.label).collect::<Vec<_>>(),
        "sampler": specs.iter().map(|s| s.label()).collect::<Vec<_>>(),
        "n": outcome.config.ns,
        "realizations": r,
        "spectra": {
            "axes": ["projection", "k2 + K/2", "k1 + K/2"],
            "projection": ["xy", "uv", "xu", "yv"],
            "K": k,
            "n": outcome.config.spectra_n,
            "realizations": outcome.config.spectra_realizations,
        },
    });
    write_atomic(&out.join("axes.json"), |w| writeln!(w, "{axes:#}"))?;
    write_npy(
        &out.join("seconds_per_estimate.npy"),
        &shape,
        &collect(&|p| p.median_seconds),
    )
}

fn slope_text(s: &Study) -> String {
    s.fit.map_or("no fit".into(), |f| {
        format!("{:.2} {}", f.slope, f.interval_text(2))
    })
}

/// The local slope `ln(MSE_b / MSE_a) / ln(N_b / N_a)` between the two largest N the sampler made
/// (its usable N), where a curve that bends shows its rate at the sizes that matter; `—` with fewer
/// than two sizes or an MSE of 0.
fn local_slope_text(s: &Study) -> String {
    let mut points: Vec<_> = s.points.iter().collect();
    points.sort_by_key(|p| p.n);
    points.dedup_by_key(|p| p.n);
    match points[..] {
        [.., a, b] if a.mse > 0.0 && b.mse > 0.0 => format!(
            "{:.2}",
            (b.mse / a.mse).ln() / (b.n as f64 / a.n as f64).ln()
        ),
        _ => "—".into(),
    }
}

/// The gain `reference / mse` of a sampler over the best classical one, as `1.23×`, with two
/// significant digits below 1 (`0.0034×`); `—` when it is not a finite number (no classical
/// reference, or an MSE of 0).
fn gain_text(reference: f64, mse: f64) -> String {
    let gain = reference / mse;
    if !gain.is_finite() {
        "—".into()
    } else if gain >= 1.0 {
        format!("{gain:.2}×")
    } else if gain > 0.0 {
        // Below 1, two significant digits: 0.0034×, not 0.00×.
        let decimals = (1.0 - gain.log10().floor()).max(2.0) as usize;
        format!("{gain:.decimals$}×")
    } else {
        "0×".into()
    }
}

/// One label for a group of samplers: their labels joined by commas, the first word of the first
/// (e.g. `optimized`) left out of the others that start with it.
fn shared_label(group: &[String]) -> String {
    let first_word = group[0].split(' ').next().unwrap_or_default();
    let rest = group[1..].iter().map(|l| {
        l.strip_prefix(first_word)
            .and_then(|r| r.strip_prefix(' '))
            .unwrap_or(l)
    });
    std::iter::once(group[0].as_str())
        .chain(rest)
        .collect::<Vec<_>>()
        .join(", ")
}

/// MSE against N, one line per sampler with its fitted slope; samplers with the same estimates (see
/// [`identical_groups`]) share one line.
fn write_convergence_plot(path: &Path, label: &str, studies: &[&Study], r: usize) -> Result<()> {
    // Samplers with the same estimates would draw one line over another: one line,
    // named after all of them.
    let groups = identical_groups(studies);
    // Each line keeps its sampler's colour of the other plots: its position among all the samplers.
    let mut colours = Vec::new();
    let curves: Vec<Convergence> = studies
        .iter()
        .enumerate()
        .filter_map(|(i, s)| {
            let sampler = match groups.iter().find(|g| g.contains(&s.sampler)) {
                Some(g) if g[0] != s.sampler => return None,
                Some(g) => format!("{} (identical estimates)", shared_label(g)),
                None => s.sampler.clone(),
            };
            colours.push(i);
            Some(Convergence {
                sampler,
                integrand: s.subject.clone(),
                points: s.points.clone(),
                fit: s.fit,
            })
        })
        .collect();
    plot(
        path,
        &curves,
        Some(&colours),
        &format!("{label}: MSE against N ({r} realizations per point)"),
    )
}

/// MSE against the time per estimate, one solid line per sampler (generation and evaluation); for a
/// table, also a dashed line of the same colour with its one-off optimization spread over the study's
/// R estimates (a renderer that reuses the table spreads it over many more).
fn write_speed_plot(
    path: &Path,
    label: &str,
    studies: &[&Study],
    config: &CompareConfig,
) -> Result<()> {
    let r = config.realizations as f64;
    let mut series = Vec::new();
    for (i, s) in studies.iter().enumerate() {
        let per_estimate = |setup: f64| -> Vec<(f64, f64)> {
            s.points
                .iter()
                .zip(&s.setup_seconds)
                .map(|(p, own)| ((p.median_seconds + setup * own / r) * 1e3, p.mse))
                .collect()
        };
        series.push(Series {
            label: s.sampler.clone(),
            points: per_estimate(0.0),
            errors: None,
            dashed: false,
            colour: Some(i),
        });
        if s.setup_seconds.iter().any(|&t| t > 0.0) {
            series.push(Series {
                label: format!("{}, with set-up / R", s.sampler),
                points: per_estimate(1.0),
                errors: None,
                dashed: true,
                colour: Some(i),
            });
        }
    }
    write_loglog_png(
        path,
        &LogLogPlot {
            title: format!(
                "{label}: MSE against time per estimate (N = {} to {} or the nearest each sampler makes, R = {})",
                config.ns.iter().min().unwrap_or(&0),
                config.ns.iter().max().unwrap_or(&0),
                config.realizations
            ),
            x_label: format!(
                "ms per estimate, one thread: generation + evaluation (dashed: + table optimization / R, R = {})",
                config.realizations
            ),
            y_label: "MSE (squared integrand units)".into(),
            series,
            width: 1000,
            height: 700,
            x_scale: XScale::Log,
        },
    )
}

/// Spectra of every sampler in xy, uv, xu, yv (sheared and optimized ones at the demo shear 0.5):
/// one sheet PNG and one npy `[4, K, K]` per sampler.
fn write_gallery(
    outcome: &Outcome,
    specs: &[SamplerSpec],
    tables: &TableCache,
    out: &Path,
) -> Result<Vec<(String, String)>> {
    let c = &outcome.config;
    let projections = [
        Projection::XY,
        Projection::UV,
        Projection::XU,
        Projection::YV,
    ];
    let mut written = Vec::new();
    for spec in specs {
        let (sampler, _) = instantiate(spec, (0.5, 0.5), GALLERY_SHEAR_RANGE, c.spectra_n, tables)?;
        let n = usable_n(sampler.as_ref(), c.spectra_n);
        let spectra = projections
            .iter()
            .map(|&p| {
                of_sampler(
                    sampler.as_ref(),
                    n,
                    p,
                    c.spectra_res,
                    c.spectra_realizations,
                    c.seed,
                    Method::Nufft { eps: 1e-6 },
                )
            })
            .collect::<Result<Vec<_>>>()?;
        let panels: Vec<Panel> = spectra
            .iter()
            .zip(&projections)
            .map(|(s, p)| Panel {
                label: format!("{} N={n}", p.name()),
                values: &s.mean,
                res: s.res,
            })
            .collect();
        let file = spectra_file(&spec.label(), "png");
        let shear_note = match spec {
            SamplerSpec::Classical(_) => String::new(),
            SamplerSpec::Table(target) => {
                let framed = framed_target(target, GALLERY_SHEAR_RANGE);
                format!(
                    " (designed for {}), sheared by 0.5 (seam-free)",
                    design_text(&framed)
                )
            }
            _ => ", sheared by 0.5".to_string(),
        };
        write_sheet(
            &out.join(&file),
            &format!(
                "{}{shear_note}: expected power spectra, K = {}, {} realizations",
                spec.label(),
                c.spectra_res,
                c.spectra_realizations
            ),
            &panels,
            4,
        )?;
        let all: Vec<f64> = spectra
            .iter()
            .flat_map(|s| s.mean.iter().copied())
            .collect();
        write_npy(
            &out.join(spectra_file(&spec.label(), "npy")),
            &[4, c.spectra_res, c.spectra_res],
            &all,
        )?;
        // A sampler that cannot make spectra_n is shown at its nearest N, as the panels say.
        let label = if n == c.spectra_n {
            spec.label()
        } else {
            format!("{} (N = {n})", spec.label())
        };
        written.push((label, file));
    }
    Ok(written)
}

/// What a table's target, framed for an integrand's shear range ([`framed_target`]), is designed for, in
/// words (the Tables section and the spectra gallery's titles).
fn design_text(framed: &Result<Target>) -> String {
    match framed {
        Ok(Target::DoubleWedge(d)) => {
            format!("double wedge, slopes {:.2} to {:.2}", d.s0, d.s1)
        }
        Ok(Target::Hairline(h)) => format!(
            "hairline band, unsheared: half-width {}{}, length {} (in units of sqrt(N))",
            crate::error::number(h.half_width),
            if h.opening > 0.0 {
                format!(
                    ", opening {0} (a slope within ±{0} stays dark)",
                    crate::error::number(h.opening)
                )
            } else {
                ", no opening".to_string()
            },
            crate::error::number(h.length)
        ),
        Ok(Target::Variance(v)) => format!(
            "variance of {} through shear {}{}",
            v.integrand,
            shear_text(v.shear),
            match v.shear_error() {
                0.0 => String::new(),
                e => format!(" off by up to ±{}%", (e * 1000.0).round() / 10.0),
            }
        ),
        Ok(t) => t.kind().to_string(),
        Err(e) => format!("({e})"),
    }
}

/// The index in `ns` of the largest N (where the robustness rows and the summary are measured).
fn largest_n_index(ns: &[usize]) -> usize {
    ns.iter()
        .enumerate()
        .max_by_key(|&(_, n)| n)
        .map_or(0, |(i, _)| i)
}

/// ` (N=n)` when a sampler measured at `n` instead of the `asked` N (the nearest it makes), else
/// nothing.
fn other_n(n: usize, asked: usize) -> String {
    if n == asked {
        String::new()
    } else {
        format!(" (N={n})")
    }
}

/// The studies of one subject, in report order.
fn studies_of<'a>(outcome: &'a Outcome, subject: &str) -> Vec<&'a Study> {
    outcome
        .studies
        .iter()
        .filter(|s| s.subject == subject)
        .collect()
}

/// The classical study with the lowest MSE at point `at`.
fn best_classical<'a>(studies: &[&'a Study], at: usize) -> Option<&'a Study> {
    studies
        .iter()
        .filter(|s| s.family == "classical")
        .min_by(|a, b| a.points[at].mse.total_cmp(&b.points[at].mse))
        .copied()
}

/// Relative difference below which two samplers' MSEs count as the same number: far above the
/// rounding of the same points reached by different float operations (e.g. tables whose x and y sit
/// at the same stratum centres, moved by the oracle's shear: 1.2e-12 apart at most in the default
/// study), far below any difference of two samplers that differ (2.5e-3 at the least there).
const SAME_ESTIMATES: f64 = 1e-9;

/// Whether two MSEs are the same to [`SAME_ESTIMATES`] (relative).
fn same_number(a: f64, b: f64) -> bool {
    a == b || (a - b).abs() <= SAME_ESTIMATES * a.abs().max(b.abs())
}

/// Whether two points have the same estimates: the same N and MSE, and standard errors the same
/// relative to the MSE (a standard error at rounding level, of realizations that all give the same
/// error, may differ in its first digit between the same points reached by different operations).
fn same_point(p: &ConvergePoint, q: &ConvergePoint) -> bool {
    p.n == q.n
        && same_number(p.mse, q.mse)
        && (p.mse_stderr - q.mse_stderr).abs() <= SAME_ESTIMATES * p.mse.abs().max(q.mse.abs())
}

/// Groups of samplers whose estimates are the same at every N (see [`same_point`]; the integrand
/// only sees coordinates these samplers share): each group of two or more, labels in report order.
/// A group is a connected component of "the same at every N", so it does not depend on the order
/// of `studies` even where A is the same as B and B as C but A and C differ at rounding level.
fn identical_groups(studies: &[&Study]) -> Vec<Vec<String>> {
    let same = |a: &Study, b: &Study| {
        a.points.len() == b.points.len()
            && a.points
                .iter()
                .zip(&b.points)
                .all(|(p, q)| same_point(p, q))
    };
    let mut grouped = vec![false; studies.len()];
    let mut groups = Vec::new();
    for start in 0..studies.len() {
        if grouped[start] {
            continue;
        }
        grouped[start] = true;
        let mut members = vec![start];
        let mut next = 0;
        while next < members.len() {
            let i = members[next];
            next += 1;
            for j in 0..studies.len() {
                if !grouped[j] && same(studies[i], studies[j]) {
                    grouped[j] = true;
                    members.push(j);
                }
            }
        }
        if members.len() > 1 {
            members.sort_unstable();
            groups.push(
                members
                    .iter()
                    .map(|&i| studies[i].sampler.clone())
                    .collect(),
            );
        }
    }
    groups
}

/// Combined standard errors by which a sampler's MSE must lie below the best classical one's to
/// count as beating it in the summary.
const BEATS_BY: f64 = 2.0;

/// The N of the study at which `s` has a lower MSE than the best classical sampler at that N by more
/// than [`BEATS_BY`] combined standard errors, in words: `all`, `none`, or the list (an N the
/// sampler replaced by its nearest valid N marked with it); `—` for a classical sampler, which is not
/// compared with itself.
fn winning_ns(studies: &[&Study], s: &Study, ns: &[usize]) -> String {
    if s.family == "classical" {
        return "— (classical)".into();
    }
    let beats = |p: &ConvergePoint, q: &ConvergePoint| {
        q.mse - p.mse > BEATS_BY * p.mse_stderr.hypot(q.mse_stderr)
    };
    let wins: Vec<usize> = (0..ns.len())
        .filter(|&i| best_classical(studies, i).is_some_and(|c| beats(&s.points[i], &c.points[i])))
        .collect();
    // A sampler measured at a substitute N is marked with it, as in its other cells.
    let substituted = |i: usize| s.points[i].n != ns[i];
    match wins.len() {
        0 => "none".into(),
        k if k == ns.len() && !wins.iter().any(|&i| substituted(i)) => "all".into(),
        _ => wins
            .iter()
            .map(|&i| match substituted(i) {
                true => format!("{} (N={})", ns[i], s.points[i].n),
                false => ns[i].to_string(),
            })
            .collect::<Vec<_>>()
            .join(", "),
    }
}

/// A shear to 3 decimals, with no minus sign on a value that rounds to zero.
fn shear_text(s: f64) -> String {
    let t = format!("{s:.3}");
    if t == "-0.000" {
        "0.000".into()
    } else {
        t
    }
}

fn write_markdown(
    outcome: &Outcome,
    specs: &[SamplerSpec],
    plots: &[Option<(String, String)>],
    robustness_plots: &[(String, String)],
    gallery: &[(String, String)],
    whole_seconds: f64,
    out: &Path,
) -> Result<()> {
    let c = &outcome.config;
    let r = c.realizations;
    write_atomic(&out.join(REPORT_MARKER.file), |w| {
        writeln!(w, "{}\n", REPORT_MARKER.first_line)?;
        writeln!(
            w,
            "Every estimate integrates one 4D integrand (x, y pixel; u, v lens) with N samples from an independent set \
             moved by a random toroidal shift. **MSE** is the mean squared error of one estimate against the exact integral \
             (analytic integrands) or the cached high-count reference (pixels), in squared integrand units, over R = {r} \
             realizations, ± its standard error. **Slope** is the fitted exponent of MSE ∝ N^slope with its 95% interval; the **local slope** is the \
             exponent between the two largest N alone. \
             **Time** is the median time of one estimate on one thread (generating its set, then evaluating the \
             integrand), in milliseconds, taken while the realizations run on every core: it drifts with the machine's load \
             (two runs of the default study on a loaded 2-core machine gave the same sampler at N = 1024 times a median \
             1.2× apart, up to 1.6×), so only larger differences tell samplers apart. **set-up** is the one-off optimization of the table for that N, in seconds \
             of wall time with every core working (see Tables). A sampler that \
             cannot make an N uses its nearest valid N (shown). Seed {}; measurements {:.1} s, whole run {:.1} s \
             (with the spectra gallery, whose tables at N = {} are built when missing, and the plots).\n",
            c.seed, outcome.seconds, whole_seconds, c.spectra_n
        )?;
        write_summary(w, outcome)?;
        writeln!(w, "## Integrands\n")?;
        writeln!(
            w,
            "**Definition** is the integrand as `anisospec integrands` writes it (`converge --integrand` takes it as \
             it is). Shears are in pixels per lens width. **Shear range** is the range of shears the integrand holds (for a \
             pixel, the oracle's smallest and largest shear over its footprint and the lens). **Samplers' shear** is \
             the one shear every sheared sampler of this report is sheared by and the tables are moved by (the \
             robustness study scales it): an analytic integrand's configured shear; an in-focus or hairline pixel's \
             oracle shear; for a double-wedge pixel, whose shears fan over its range, the range's midpoint on both \
             axes. **Oracle at the pixel centre** is what `anisospec oracle` gives for the pixel (sx, sy): the shear \
             at the depth seen through the pixel centre and the lens centre, one depth of the fan for a double \
             wedge, so it differs from the samplers' shear there (— for an analytic integrand, which has no \
             oracle). A pixel's **integral** is its reference ({} rays) ± its standard error, whose square \
             (**reference floor**) adds to every MSE of the pixel on average; an analytic integral is exact.\n",
            c.pixel_reference_count
        )?;
        writeln!(
            w,
            "| integrand | definition | class | integral | reference floor | shear range | samplers' shear (sx, sy) | oracle at the pixel centre (sx, sy) |"
        )?;
        writeln!(w, "|---|---|---|---|---|---|---|---|")?;
        for SubjectInfo {
            label,
            definition,
            class,
            shear,
            shear_range: range,
            oracle_shear,
            integral,
            integral_stderr,
        } in &outcome.subjects
        {
            let (integral, floor) = if *integral_stderr > 0.0 {
                (
                    format!("{integral:.4e} ± {integral_stderr:.1e}"),
                    format!("{:.1e}", integral_stderr * integral_stderr),
                )
            } else {
                (format!("{integral:.4e}"), "—".to_string())
            };
            let midpoint = if class == "double-wedge" {
                " (range midpoint)"
            } else {
                ""
            };
            let oracle = oracle_shear.map_or("—".to_string(), |(sx, sy)| {
                format!("({}, {})", shear_text(sx), shear_text(sy))
            });
            writeln!(
                w,
                "| {label} | `{definition}` | {class} | {integral} | {floor} | [{}, {}] | ({}, {}){midpoint} | {oracle} |",
                shear_text(range.0),
                shear_text(range.1),
                shear_text(shear.0),
                shear_text(shear.1),
            )?;
        }
        write_samplers(w, specs)?;
        for (SubjectInfo { label, .. }, files) in outcome.subjects.iter().zip(plots) {
            write_subject(w, outcome, label)?;
            match files {
                Some((conv, speed)) => writeln!(
                    w,
                    "\n![convergence]({conv})\n![speed against error]({speed})\n\nSpeed against error: one point per N, the \
                     smallest N at the top left of each line (the MSE falls as N grows); a dashed line is a table's solid one with \
                     its optimization spread over the R estimates."
                )?,
                None => writeln!(
                    w,
                    "\nNo convergence or speed plot: every MSE of this integrand is 0, which a log axis cannot show."
                )?,
            }
        }
        write_robustness(w, outcome, robustness_plots)?;
        write_tables(w, outcome, specs)?;
        writeln!(w, "\n## Spectra\n")?;
        let (lo, hi) = GALLERY_SHEAR_RANGE;
        writeln!(
            w,
            "Expected power spectra, N = {} (a sampler that cannot make it at its nearest N, marked), K = {}, {} realizations; whatever the integrands' shears, the sheared samplers and the tables are shown at the gallery's own shear 0.5, the tables framed for shears {lo} to {hi}. \
             log10 P from -2 (black) to 1 (white).\n",
            c.spectra_n, c.spectra_res, c.spectra_realizations
        )?;
        for (label, file) in gallery {
            writeln!(w, "![{label}]({file})\n")?;
        }
        writeln!(w, "## Files\n")?;
        writeln!(
            w,
            "`convergence.csv` and `robustness.csv` hold every measured number above (gains and local slopes are ratios of them); `mse.npy`, `mse_stderr.npy`, `n.npy` and \
             `seconds_per_estimate.npy` and `setup_seconds.npy` are arrays [integrand, sampler, N] in the order of the tables, \
             whose labels `axes.json` lists (N there is the study's; `n.npy` holds the N each sampler made); \
             `spectra/*.npy` are [projection (xy, uv, xu, yv), k2 + K/2, k1 + K/2], so that k = 0 is at index K/2, \
             where P = N (also in `axes.json`). `{}` lists the files of this \
             report: the next report written to this folder removes those it does not write again, \
             and nothing else.",
            crate::output::MANIFEST
        )
    })
}

/// What each sampler of the study is, a line each, in the order of the tables.
fn write_samplers(w: &mut impl Write, specs: &[SamplerSpec]) -> std::io::Result<()> {
    writeln!(w, "\n## Samplers\n")?;
    writeln!(w, "| sampler | family | what it is |")?;
    writeln!(w, "|---|---|---|")?;
    for spec in specs {
        let what = match spec {
            SamplerSpec::Classical(name) => {
                crate::samplers::summary(name).unwrap_or_else(|| name.clone())
            }
            SamplerSpec::Sheared(name, ShearMode::Transported) => format!(
                "{name} moved by the samplers' shear seam-free (transported): the sheared coordinate x + s·u is drawn \
                 through its marginal, so the pattern's stratification lies along the integrand's sheared axis, with no seam"
            ),
            SamplerSpec::Sheared(name, ShearMode::Wrap) => format!(
                "{name} moved by the samplers' shear with wrap-around (x moved by s·u, mod 1): the pattern keeps its \
                 structure, but the wrap's seam is a discontinuity of its own on an integrand that is not periodic in x"
            ),
            SamplerSpec::Table(path) => format!(
                "sets optimized for the target `{}` (see Tables), one at random per estimate",
                path.display()
            ),
        };
        writeln!(w, "| {} | {} | {what} |", spec.label(), spec.family())?;
    }
    Ok(())
}

/// The answer first: per integrand, at the largest N, the best classical sampler and the sampler with
/// the lowest MSE, its gain, its cost, and its worst gain when the samplers' shear is off.
fn write_summary(w: &mut impl Write, outcome: &Outcome) -> std::io::Result<()> {
    let c = &outcome.config;
    let at = largest_n_index(&c.ns);
    let nmax = c.ns.get(at).copied().unwrap_or(0);
    let errors = errors_text(&c.oracle_errors);
    writeln!(w, "## Summary\n")?;
    writeln!(
        w,
        "At N = {nmax}: the classical sampler with the lowest MSE, and the sampler with the lowest MSE of all \
         (samplers with the same estimates are named together, the one most robust to oracle error first), the other samplers whose MSE at N = {nmax} is within {BEATS_BY} combined standard errors of it (not told apart from it by this study), its gain over that classical sampler (its MSE \
         divided by this one's), the N of this study at which it beats the best classical sampler at that N by more than \
         {BEATS_BY} standard errors (a sampler that wins at N = {nmax} alone may lose at the N you use: see its table), its time per estimate and its one-off set-up, and its lowest gain when the \
         samplers' shear (the oracle's; see Integrands) is off by {errors}, with the error where it falls (for the first named; — when the oracle does not move it \
         here). (N=…) marks a sampler that cannot make N = {nmax} and was measured at its nearest N.\n"
    )?;
    writeln!(
        w,
        "| integrand | class | best classical (MSE) | best sampler | within {BEATS_BY} standard errors of it | gain | beats the best classical at N | ms/estimate | set-up s | lowest gain with the oracle off |"
    )?;
    writeln!(w, "|---|---|---|---|---|---|---|---|---|---|")?;
    for subject in &outcome.subjects {
        let studies = studies_of(outcome, &subject.label);
        let (Some(classical), Some(best)) = (
            best_classical(&studies, at),
            studies
                .iter()
                .min_by(|a, b| a.points[at].mse.total_cmp(&b.points[at].mse)),
        ) else {
            continue;
        };
        let reference = classical.points[at].mse;
        let lowest_gain = |sampler: &str| {
            off_rows(outcome, &subject.label, sampler)
                .iter()
                .filter(|row| row.moved)
                .map(|row| (reference / row.point.mse, row.error))
                .filter(|(g, _)| g.is_finite())
                .min_by(|a, b| a.0.total_cmp(&b.0))
        };
        // Samplers that tie with the exact oracle may part when it is off: the most robust first.
        let mut tied: Vec<(String, Option<(f64, f64)>)> = identical_groups(&studies)
            .into_iter()
            .find(|g| g.contains(&best.sampler))
            .unwrap_or_else(|| vec![best.sampler.clone()])
            .into_iter()
            .map(|label| {
                let g = lowest_gain(&label);
                (label, g)
            })
            .collect();
        tied.sort_by(|a, b| {
            let gain = |t: &(String, Option<(f64, f64)>)| t.1.map_or(f64::NEG_INFINITY, |g| g.0);
            gain(b).total_cmp(&gain(a))
        });
        let names: Vec<&str> = tied.iter().map(|t| t.0.as_str()).collect();
        let lowest = tied[0].1.map_or("—".to_string(), |(g, e)| {
            format!("{g:.2}× at {}", error_text(e))
        });
        let first = studies
            .iter()
            .find(|s| s.sampler == tied[0].0)
            .expect("a tied sampler is a study of this subject");
        let p = &first.points[at];
        let close: Vec<String> = studies
            .iter()
            .filter(|s| !names.contains(&s.sampler.as_str()))
            .filter(|s| {
                let q = &s.points[at];
                (q.mse - p.mse).abs() <= BEATS_BY * p.mse_stderr.hypot(q.mse_stderr)
            })
            .map(|s| format!("{}{}", s.sampler, other_n(s.points[at].n, nmax)))
            .collect();
        let close = if close.is_empty() {
            "—".to_string()
        } else {
            close.join(", ")
        };
        writeln!(
            w,
            "| {} | {} | {} ({:.3e}){} | {}{}{} | {close} | {} | {} | {:.3} | {:.2} | {lowest} |",
            subject.label,
            subject.class,
            classical.sampler,
            reference,
            other_n(classical.points[at].n, nmax),
            names[0],
            other_n(p.n, nmax),
            names[1..]
                .iter()
                .map(|n| format!(" = {n}"))
                .collect::<String>(),
            gain_text(reference, p.mse),
            winning_ns(&studies, first, &c.ns),
            p.median_seconds * 1e3,
            first.setup_seconds[at],
        )?;
    }
    writeln!(w)
}

/// One integrand's table: MSE at every N, slope, time, set-up and gain, then which classical sampler
/// the gains are against and which rows are identical.
fn write_subject(w: &mut impl Write, outcome: &Outcome, label: &str) -> std::io::Result<()> {
    let c = &outcome.config;
    let studies = studies_of(outcome, label);
    writeln!(w, "\n## {label}\n")?;
    write!(w, "| sampler | family |")?;
    for n in &c.ns {
        write!(w, " MSE at N={n} |")?;
    }
    let last = largest_n_index(&c.ns);
    let nmax = c.ns.get(last).copied().unwrap_or(0);
    writeln!(w, " slope [95% CI] | local slope | ms/estimate at N={nmax} | set-up s at N={nmax} | gain over best classical at N={nmax} |")?;
    writeln!(
        w,
        "|---|---|{}---|---|---|---|---|",
        "---|".repeat(c.ns.len())
    )?;
    let classical = best_classical(&studies, last);
    let reference = classical.map_or(f64::INFINITY, |s| s.points[last].mse);
    for s in &studies {
        write!(w, "| {} | {} |", s.sampler, s.family)?;
        for (p, n) in s.points.iter().zip(&c.ns) {
            let shown = other_n(p.n, *n);
            write!(w, " {:.3e} ± {:.1e}{shown} |", p.mse, p.mse_stderr)?;
        }
        let p = &s.points[last];
        let shown = other_n(p.n, nmax);
        writeln!(
            w,
            " {} | {} | {:.3}{shown} | {:.2}{shown} | {}{shown} |",
            slope_text(s),
            local_slope_text(s),
            p.median_seconds * 1e3,
            s.setup_seconds[last],
            gain_text(reference, p.mse)
        )?;
    }
    if let Some(classical) = classical {
        writeln!(
            w,
            "\nGains are against {}, the classical sampler with the lowest MSE at N={nmax}.",
            classical.sampler
        )?;
    }
    let unsheared = outcome
        .subjects
        .iter()
        .any(|s| s.label == label && s.shear == (0.0, 0.0));
    for group in identical_groups(&studies) {
        // Why these samplers agree, from what they are: the reasons that apply to this group.
        let family_of = |l: &String| studies.iter().find(|s| &s.sampler == l).map(|s| s.family);
        let has = |f: &str| group.iter().any(|l| family_of(l) == Some(f));
        let mut reasons = Vec::new();
        if has("sheared") && unsheared {
            reasons.push("the samplers' shear of 0 leaves a sheared sampler as it is");
        }
        if has("optimized") {
            reasons.push(
                "every table holds x (and y) at the same stratum centres, and where the integrand sees nothing else of them (the exact shear) they give the same estimates",
            );
        }
        let why = if reasons.is_empty() {
            String::new()
        } else {
            format!(" ({})", reasons.join("; "))
        };
        writeln!(
            w,
            "\nIdentical estimates at every N (bit for bit, or apart by rounding alone: to 9 digits): {}. These samplers put the same points where this \
             integrand looks{why}.",
            group.join(", ")
        )?;
    }
    Ok(())
}

/// The errors the robustness table gives columns of their own when the sweep holds them, ±10 % and
/// ±25 % (robustness.csv and the plots hold every error of the sweep).
const TABLED_ERRORS: [f64; 4] = [-0.25, -0.1, 0.1, 0.25];

/// A relative error as a signed percentage with at most one decimal, e.g. `+10%`, `-2.5%`.
pub(super) fn error_text(e: f64) -> String {
    format!("{:+}%", (e * 1000.0).round() / 10.0)
}

/// The config's oracle errors in words: each one when there are few, else their count and range,
/// with their step when they (and 0, the exact shear, which the sweep leaves out) are evenly spaced.
fn errors_text(errors: &[f64]) -> String {
    let mut sorted = errors.to_vec();
    sorted.sort_by(f64::total_cmp);
    let mut with_exact = sorted.clone();
    if !with_exact.contains(&0.0) {
        with_exact.push(0.0);
        with_exact.sort_by(f64::total_cmp);
    }
    let steps: Vec<f64> = with_exact.windows(2).map(|w| w[1] - w[0]).collect();
    let even = steps
        .first()
        .filter(|&&d| d > 0.0 && steps.iter().all(|s| (s - d).abs() <= 1e-9))
        .map(|&d| format!(" in steps of {}%", (d * 1000.0).round() / 10.0))
        .unwrap_or_default();
    match (sorted.first(), sorted.last()) {
        (Some(lo), Some(hi)) if sorted.len() > 6 => format!(
            "any of {} errors from {} to {}{even}",
            sorted.len(),
            error_text(*lo),
            error_text(*hi)
        ),
        _ => sorted
            .iter()
            .map(|&e| error_text(e))
            .collect::<Vec<_>>()
            .join(", "),
    }
}

/// The robustness rows of one subject and sampler with the oracle off (error ≠ 0), by error.
fn off_rows<'a>(outcome: &'a Outcome, subject: &str, sampler: &str) -> Vec<&'a Robustness> {
    let mut rows: Vec<&Robustness> = outcome
        .robustness
        .iter()
        .filter(|r| r.subject == subject && r.sampler == sampler && r.error != 0.0)
        .collect();
    rows.sort_by(|a, b| a.error.total_cmp(&b.error));
    rows
}

/// The robustness table: at the largest N, per subject and sampler that uses the oracle, the MSE with
/// the exact oracle, the worst and the mean over the sweep of errors, and the MSE at the errors of
/// [`TABLED_ERRORS`] the sweep holds, each with its gain over the best classical sampler; then the
/// plots.
fn write_robustness(
    w: &mut impl Write,
    outcome: &Outcome,
    plots: &[(String, String)],
) -> std::io::Result<()> {
    let c = &outcome.config;
    let at = largest_n_index(&c.ns);
    writeln!(w, "\n## Robustness to oracle error\n")?;
    if outcome.robustness.is_empty() {
        return writeln!(
            w,
            "Nothing to sweep: the sweep covers the samplers moved by the seam-free shear (transported sheared samplers and tables) on integrands whose shear is not 0 (not in focus), and this study has none."
        );
    }
    writeln!(
        w,
        "At N = {}, the samplers' shear (see Integrands) is scaled by (1 + error) for {} (the sweep). Each cell is the MSE ± its standard \
         error and, in brackets, the gain over the best classical sampler on that integrand at the same N (best classical \
         MSE / this MSE; above 1 is a gain). **Worst** is the highest MSE over the sweep, at the error named; **mean** is \
         the mean MSE over the sweep (the errors share their random streams, so it has no standard error of its own). The plots below show every error. A rank-1 lattice has P = N on its dual lattice, so \
         at some errors the erred edge's spectrum meets a dual point near the origin: a narrow spike that only a fine sweep \
         finds. Tables keep the shape built for the true shear range; a table for a range that holds an in-focus layer is \
         designed in that layer's frame and not sheared, so the error does not move it. The sweep covers the samplers \
         moved by the seam-free shear (transported sheared samplers and tables; the wrap-around shear is left out) on \
         integrands whose shear is not 0: an in-focus pixel, which no error of a shear of 0 moves, has no rows. For an \
         analytic integrand the oracle is its configured shear, and the error is that shear's.\n",
        c.ns.get(at).unwrap_or(&0),
        errors_text(&c.oracle_errors)
    )?;
    let tabled: Vec<f64> = TABLED_ERRORS
        .into_iter()
        .filter(|e| outcome.robustness.iter().any(|r| r.error == *e))
        .collect();
    write!(
        w,
        "| integrand | sampler | exact oracle | worst with the oracle off | mean with the oracle off |"
    )?;
    for e in &tabled {
        write!(w, " error {} |", error_text(*e))?;
    }
    writeln!(w, "\n|---|---|---|---|---|{}", "---|".repeat(tabled.len()))?;
    let mut keys: Vec<(&String, &String)> = outcome
        .robustness
        .iter()
        .map(|r| (&r.subject, &r.sampler))
        .collect();
    keys.dedup();
    for (subject, sampler) in keys {
        let reference = best_classical(&studies_of(outcome, subject), at)
            .map_or(f64::INFINITY, |s| s.points[at].mse);
        let cell =
            |mse: f64, se: f64| format!("{mse:.2e} ± {se:.1e} ({})", gain_text(reference, mse));
        let exact = outcome
            .robustness
            .iter()
            .find(|r| &r.subject == subject && &r.sampler == sampler && r.error == 0.0)
            .map_or("—".to_string(), |r| cell(r.point.mse, r.point.mse_stderr));
        let off = off_rows(outcome, subject, sampler);
        // A table designed in an in-focus layer's frame is not moved: every error gives its MSE
        // with the exact oracle, and there is no worst error to name.
        let unmoved = off.first().is_some_and(|r| !r.moved);
        // The first of equal worst MSEs, as the summary's lowest gain picks it.
        let worst = if unmoved {
            "— (not moved by the oracle here)".to_string()
        } else {
            off.iter()
                .min_by(|a, b| b.point.mse.total_cmp(&a.point.mse))
                .map_or("—".to_string(), |r| {
                    format!(
                        "{} at {}",
                        cell(r.point.mse, r.point.mse_stderr),
                        error_text(r.error)
                    )
                })
        };
        // The errors share their random streams, so the points are correlated and the mean gets no
        // standard error of its own.
        let mean = if off.is_empty() {
            "—".to_string()
        } else {
            let mse = off.iter().map(|r| r.point.mse).sum::<f64>() / off.len() as f64;
            format!("{mse:.2e} ({})", gain_text(reference, mse))
        };
        write!(w, "| {subject} | {sampler} | {exact} | {worst} | {mean} |")?;
        for e in &tabled {
            match off.iter().find(|r| r.error == *e) {
                Some(r) => write!(w, " {} |", cell(r.point.mse, r.point.mse_stderr))?,
                None => write!(w, " — |")?,
            }
        }
        writeln!(w)?;
    }
    for (label, file) in plots {
        writeln!(w, "\n![robustness: {label}]({file})")?;
    }
    Ok(())
}

/// MSE against the oracle's error at the largest N, one line per sampler that uses the oracle (with
/// its standard errors), and the best classical sampler, which does not, as a dashed level. Returns
/// false, writing nothing, when the subject has no robustness rows or none with an MSE above 0.
fn write_robustness_plot(path: &Path, outcome: &Outcome, label: &str) -> Result<bool> {
    let c = &outcome.config;
    let at = largest_n_index(&c.ns);
    let mut samplers: Vec<&String> = outcome
        .robustness
        .iter()
        .filter(|r| r.subject == label)
        .map(|r| &r.sampler)
        .collect();
    samplers.dedup();
    if !outcome
        .robustness
        .iter()
        .any(|r| r.subject == label && drawable(r.point.mse))
    {
        return Ok(false);
    }
    // Each sampler keeps the colour of its line in the convergence and speed plots: its position
    // among the subject's studies.
    let studies = studies_of(outcome, label);
    let colour = |sampler: &str| studies.iter().position(|s| s.sampler == sampler);
    let shear = outcome
        .subjects
        .iter()
        .find(|s| s.label == label)
        .map_or((0.0, 0.0), |s| s.shear);
    let mut series = Vec::new();
    let mut span = (f64::INFINITY, f64::NEG_INFINITY);
    for sampler in samplers {
        let mut rows: Vec<&Robustness> = outcome
            .robustness
            .iter()
            .filter(|r| r.subject == label && &r.sampler == sampler)
            .collect();
        rows.sort_by(|a, b| a.error.total_cmp(&b.error));
        for r in &rows {
            span = (span.0.min(r.error), span.1.max(r.error));
        }
        // A sampler the oracle does not move here (a table kept unsheared on this integrand) draws
        // a flat line that is not robustness.
        let unmoved = rows.first().is_some_and(|r| !r.moved);
        series.push(Series {
            label: if unmoved {
                format!("{sampler} (not moved by the oracle here)")
            } else {
                sampler.clone()
            },
            points: rows
                .iter()
                .map(|r| (r.error * 100.0, r.point.mse))
                .collect(),
            errors: Some(rows.iter().map(|r| r.point.mse_stderr).collect()),
            dashed: false,
            colour: colour(sampler),
        });
    }
    if let Some(classical) = best_classical(&studies, at) {
        let mse = classical.points[at].mse;
        series.push(Series {
            label: format!("{} (best classical, no oracle)", classical.sampler),
            points: vec![(span.0 * 100.0, mse), (span.1 * 100.0, mse)],
            errors: None,
            dashed: true,
            colour: colour(&classical.sampler),
        });
    }
    write_loglog_png(
        path,
        &LogLogPlot {
            title: format!(
                "{label}: MSE against the oracle's error (N = {}, R = {})",
                c.ns.get(at).unwrap_or(&0),
                c.realizations
            ),
            x_label: format!(
                "error of the samplers' shear, % (they shear by it × (1 + error); 0 % is (sx, sy) = ({}, {}))",
                shear_text(shear.0),
                shear_text(shear.1)
            ),
            y_label: "MSE (squared integrand units; bars: ±1 standard error, within the marker where shorter)".into(),
            series,
            width: 1000,
            height: 700,
            x_scale: XScale::Linear,
        },
    )?;
    Ok(true)
}

/// The optimized tables behind each integrand's rows: the target in the frame the table was designed
/// in, how it is moved at use, and its optimization time at every N.
fn write_tables(
    w: &mut impl Write,
    outcome: &Outcome,
    specs: &[SamplerSpec],
) -> std::io::Result<()> {
    let c = &outcome.config;
    let targets: Vec<&Path> = specs
        .iter()
        .filter_map(|s| match s {
            SamplerSpec::Table(p) => Some(p.as_path()),
            _ => None,
        })
        .collect();
    if targets.is_empty() {
        return Ok(());
    }
    writeln!(w, "\n## Tables\n")?;
    writeln!(
        w,
        "Each optimized sampler is a table of {} sets per N, built from the target file ({TABLE_ITERATIONS} \
         iterations from the start named, x and y held at the centres of its strata) and cached; each estimate \
         uses one set with a random toroidal shift. A shape table is designed in a frame set by the integrand's \
         shear range: for a range that holds 0, the in-focus layer's, and the table is not moved; for any other, the \
         range's centre, and the table is moved by the samplers' shear (seam-free; see Integrands). A hairline band \
         is the same in every frame (unsheared), so one table serves every integrand; a double wedge spans the \
         range less the frame's shear, so each range has its own table under the one name. A variance table is \
         built once, for the integrand family and shear its file names, and moved by each integrand's samplers' \
         shear (by (0.000, 0.000), i.e. left as it is, on an in-focus pixel); with `design = \"lattice\"` its \
         sets are the rank-1 lattice of lowest predicted variance, found by a search instead of the optimizer; \
         with `design = \"lattice-mixture\"` they are rank-1 lattices in the proportions whose worst predicted \
         variance over the oracle's errors is lowest (a linear program). \
         Set-up is the optimization (or search) time recorded when the table was built (wall time, with every \
         core working), also when it is read back from the cache; a search's includes the whole computation of the spectra it searches over, which \
         one run computes once for every N.\n",
        c.table_sets
    )?;
    write!(w, "| integrand | table | designed for | start | moved by |")?;
    for n in &c.ns {
        write!(w, " set-up s at N={n} |")?;
    }
    writeln!(w, "\n|---|---|---|---|---|{}", "---|".repeat(c.ns.len()))?;
    for subject in &outcome.subjects {
        for &target in &targets {
            let label = SamplerSpec::Table(target.to_path_buf()).label();
            let Some(study) = outcome
                .studies
                .iter()
                .find(|s| s.subject == subject.label && s.sampler == label)
            else {
                continue;
            };
            let range = subject.shear_range;
            let framed = framed_target(target, range);
            let design = design_text(&framed);
            // The start at each N, named once when it does not change with N.
            let starts: Vec<(usize, &str)> = c.ns.iter().map(|&n| (n, start_sampler(n))).collect();
            let start = if starts.windows(2).all(|p| p[0].1 == p[1].1) {
                starts.first().map_or("", |s| s.1).to_string()
            } else {
                let each: Vec<String> = starts.iter().map(|(n, s)| format!("N={n}: {s}")).collect();
                each.join(", ")
            };
            let start = match &framed {
                Ok(Target::Variance(v)) if v.design() == Design::Lattice => {
                    "rank-1 lattice search".to_string()
                }
                Ok(Target::Variance(v)) if v.design() == Design::LatticeMixture => {
                    "mixture of rank-1 lattices".to_string()
                }
                _ => start,
            };
            let is_moved = framed.as_ref().is_ok_and(|t| moved(t, range));
            let moved_by = if !is_moved {
                "not moved".to_string()
            } else {
                format!(
                    "({}, {})",
                    shear_text(subject.shear.0),
                    shear_text(subject.shear.1)
                )
            };
            write!(
                w,
                "| {} | {} | {design} | {start} | {moved_by} |",
                subject.label,
                target.display()
            )?;
            for t in &study.setup_seconds {
                write!(w, " {t:.2} |")?;
            }
            writeln!(w)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A group's one legend entry names every member, the shared first word once.
    #[test]
    fn a_group_shares_one_label() {
        let group = [
            "optimized hairline",
            "optimized double-wedge",
            "lattice sheared (wrap)",
        ]
        .map(String::from);
        assert_eq!(
            shared_label(&group),
            "optimized hairline, double-wedge, lattice sheared (wrap)"
        );
    }

    fn study(mses: &[f64]) -> Study {
        Study {
            subject: "edge".into(),
            class: "analytic".into(),
            sampler: "random".into(),
            family: "classical",
            points: mses
                .iter()
                .enumerate()
                .map(|(i, &mse)| ConvergePoint {
                    n: 16 << (2 * i),
                    mse,
                    mse_stderr: 0.0,
                    mean_error: 0.0,
                    seconds: 0.0,
                    median_seconds: 0.0,
                    evaluations: 0,
                })
                .collect(),
            fit: None,
            setup_seconds: vec![0.0; mses.len()],
        }
    }

    /// An MSE of 0 (an integrand a sampler integrates exactly) reads as "—", never as inf or NaN.
    #[test]
    fn an_mse_of_zero_prints_no_infinite_gain_or_slope() {
        assert_eq!(gain_text(2e-6, 1e-6), "2.00×");
        assert_eq!(gain_text(2.372e-7, 7.057e-5), "0.0034×");
        assert_eq!(gain_text(4.916e-6, 5.981e-5), "0.082×");
        assert_eq!(gain_text(0.5e-6, 1e-6), "0.50×");
        assert_eq!(gain_text(2e-6, 0.0), "—");
        assert_eq!(gain_text(0.0, 0.0), "—");
        assert_eq!(local_slope_text(&study(&[1e-3, 1e-4])), "-1.66");
        assert_eq!(local_slope_text(&study(&[1e-3, 0.0])), "—");
        assert_eq!(local_slope_text(&study(&[0.0, 0.0])), "—");
        assert!(!drawable(0.0) && !drawable(f64::NAN) && drawable(1e-300));
    }

    fn named(sampler: &str, family: &'static str, mses: &[f64]) -> Study {
        Study {
            sampler: sampler.into(),
            family,
            ..study(mses)
        }
    }

    /// Estimates apart by rounding alone (1e-12 relative) are one group, with standard errors at
    /// rounding level that differ in their first digit; estimates apart in the seventh digit are not.
    #[test]
    fn estimates_apart_by_rounding_alone_share_a_group() {
        let a = named("a", "table", &[1e-3, 1e-4]);
        let mut b = named("b", "table", &[1e-3 * (1.0 + 1e-12), 1e-4]);
        b.points[0].mse_stderr = 3e-16;
        let c = named("c", "table", &[1e-3 * (1.0 + 1e-6), 1e-4]);
        assert_eq!(
            identical_groups(&[&a, &c, &b]),
            vec![vec!["a".to_string(), "b".to_string()]]
        );
        assert!(identical_groups(&[&a, &c]).is_empty());
        b.points[0].mse_stderr = 1e-5;
        assert!(identical_groups(&[&a, &b]).is_empty());
    }

    /// Many errors read as their count, range and step (0, the exact shear, counted in the step).
    #[test]
    fn oracle_errors_in_words() {
        let sweep: Vec<f64> = (-10..=10)
            .filter(|&i| i != 0)
            .map(|i| f64::from(i) * 0.025)
            .collect();
        assert_eq!(
            errors_text(&sweep),
            "any of 20 errors from -25% to +25% in steps of 2.5%"
        );
        let uneven = [-0.25, -0.2, -0.1, -0.05, 0.05, 0.1, 0.25];
        assert_eq!(errors_text(&uneven), "any of 7 errors from -25% to +25%");
        assert_eq!(errors_text(&[-0.1, 0.1]), "-10%, +10%");
    }

    /// A chain a ≈ b ≈ c whose ends differ (by 1.6e-9 relative, past the 1e-9 of one step) is one
    /// group in whatever order the samplers come, labels in that order.
    #[test]
    fn a_chain_of_same_estimates_is_one_group_in_any_order() {
        let a = named("a", "table", &[1e-3, 1e-4]);
        let b = named("b", "table", &[1e-3 * (1.0 + 0.8e-9), 1e-4]);
        let c = named("c", "table", &[1e-3 * (1.0 + 1.6e-9), 1e-4]);
        assert!(identical_groups(&[&a, &c]).is_empty());
        let label = |s: &[&str]| vec![s.iter().map(|l| l.to_string()).collect::<Vec<_>>()];
        assert_eq!(identical_groups(&[&a, &c, &b]), label(&["a", "c", "b"]));
        assert_eq!(identical_groups(&[&b, &a, &c]), label(&["b", "a", "c"]));
        assert_eq!(identical_groups(&[&c, &a, &b]), label(&["c", "a", "b"]));
    }

    /// The N at which a sampler beats the best classical sampler at that N by more than 2 standard
    /// errors: all, none, or a list; a classical sampler is not compared with itself.
    #[test]
    fn winning_ns_names_the_sizes_a_sampler_wins_at() {
        let ns = [16, 64, 256];
        let slow = named("slow", "classical", &[1e-2, 1e-3, 1e-4]);
        let fast = named("fast", "classical", &[2e-2, 1e-3, 1e-5]);
        let table = named("table", "table", &[1.5e-2, 5e-4, 1e-4]);
        let classical = [&slow, &fast];
        let all = [&slow, &fast, &table];
        assert_eq!(winning_ns(&all, &table, &ns), "64");
        assert_eq!(winning_ns(&all, &fast, &ns), "— (classical)");
        let t = |mses: &[f64]| named("t", "table", mses);
        assert_eq!(
            winning_ns(&classical, &t(&[5e-3, 5e-4, 5e-4]), &ns),
            "16, 64"
        );
        assert_eq!(winning_ns(&classical, &t(&[1e-9; 3]), &ns), "all");
        assert_eq!(winning_ns(&classical, &t(&[1.0; 3]), &ns), "none");
        // 5e-4 below 1e-3 is a win with standard errors of 1e-4 each (3.5 of them), not with 2e-4.
        let mut near = t(&[1.0, 5e-4, 1.0]);
        let mut reference = fast.clone();
        near.points[1].mse_stderr = 1e-4;
        reference.points[1].mse_stderr = 1e-4;
        assert_eq!(winning_ns(&[&reference, &near], &near, &ns), "64");
        near.points[1].mse_stderr = 2e-4;
        reference.points[1].mse_stderr = 2e-4;
        assert_eq!(winning_ns(&[&reference, &near], &near, &ns), "none");
        // Measured at a substitute N (as oa at 961 for 1024): marked with it, never "all".
        let mut substitute = t(&[1e-9; 3]);
        substitute.points[2].n = 225;
        assert_eq!(
            winning_ns(&classical, &substitute, &ns),
            "16, 64, 256 (N=225)"
        );
    }
}
