//! The compare report folder: `report.md` with tables, convergence and speed-against-error plots, a
//! spectra gallery per sampler, and CSV / npy of every number.

use super::config::CompareConfig;
use super::tables::TableCache;
use super::{instantiate, usable_n, Outcome, SamplerSpec, Study, SubjectInfo};
use crate::converge::{plot, Convergence};
use crate::error::Result;
use crate::output::plot::{write_loglog_png, LogLogPlot, Series};
use crate::output::sheet::{write_sheet, Panel};
use crate::output::{write_atomic, write_npy};
use crate::points::Projection;
use crate::spectrum::expected::of_sampler;
use crate::spectrum::Method;
use std::io::Write;
use std::path::Path;

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

/// Writes the whole report under `out`.
pub fn write(
    outcome: &Outcome,
    specs: &[SamplerSpec],
    tables: &TableCache,
    out: &Path,
) -> Result<()> {
    write_numbers(outcome, specs, out)?;
    let mut plots = Vec::new();
    for SubjectInfo { label, .. } in &outcome.subjects {
        let studies: Vec<&Study> = outcome
            .studies
            .iter()
            .filter(|s| &s.subject == label)
            .collect();
        let conv = format!("plots/convergence_{}.png", slug(label));
        let speed = format!("plots/speed_{}.png", slug(label));
        write_convergence_plot(
            &out.join(&conv),
            label,
            &studies,
            outcome.config.realizations,
        )?;
        write_speed_plot(&out.join(&speed), label, &studies, &outcome.config)?;
        plots.push((conv, speed));
    }
    let gallery = write_gallery(outcome, specs, tables, out)?;
    write_markdown(outcome, &plots, &gallery, out)
}

fn write_numbers(outcome: &Outcome, specs: &[SamplerSpec], out: &Path) -> Result<()> {
    let r = outcome.config.realizations as f64;
    write_atomic(&out.join("convergence.csv"), |w| {
        writeln!(
            w,
            "subject,class,sampler,family,n,mse,mse_stderr,seconds_per_estimate,setup_seconds,slope,slope_ci_low,slope_ci_high"
        )?;
        for s in &outcome.studies {
            let (slope, lo, hi) =
                s.fit
                    .map_or((String::new(), String::new(), String::new()), |f| {
                        (
                            f.slope.to_string(),
                            f.ci95.0.to_string(),
                            f.ci95.1.to_string(),
                        )
                    });
            for (p, setup) in s.points.iter().zip(&s.setup_seconds) {
                writeln!(
                    w,
                    "\"{}\",{},\"{}\",{},{},{},{},{},{},{slope},{lo},{hi}",
                    s.subject,
                    s.class,
                    s.sampler,
                    s.family,
                    p.n,
                    p.mse,
                    p.mse_stderr,
                    p.seconds / r,
                    setup
                )?;
            }
        }
        Ok(())
    })?;
    write_atomic(&out.join("robustness.csv"), |w| {
        writeln!(w, "subject,sampler,shear_error,n,mse,mse_stderr")?;
        for row in &outcome.robustness {
            writeln!(
                w,
                "\"{}\",\"{}\",{},{},{},{}",
                row.subject,
                row.sampler,
                row.error,
                row.point.n,
                row.point.mse,
                row.point.mse_stderr
            )?;
        }
        Ok(())
    })?;
    let shape = [outcome.subjects.len(), specs.len(), outcome.config.ns.len()];
    let collect = |f: &dyn Fn(&super::ConvergePoint) -> f64| -> Vec<f64> {
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
    write_npy(
        &out.join("seconds_per_estimate.npy"),
        &shape,
        &collect(&|p| p.seconds / r),
    )
}

fn slope_text(s: &Study) -> String {
    s.fit.map_or("no fit".into(), |f| {
        format!("{:.2} [{:.2}, {:.2}]", f.slope, f.ci95.0, f.ci95.1)
    })
}

fn write_convergence_plot(path: &Path, label: &str, studies: &[&Study], r: usize) -> Result<()> {
    let curves: Vec<Convergence> = studies
        .iter()
        .map(|s| Convergence {
            sampler: s.sampler.clone(),
            integrand: s.subject.clone(),
            points: s.points.clone(),
            fit: s.fit,
        })
        .collect();
    plot(
        path,
        &curves,
        &format!("{label}: MSE against N ({r} realizations per point)"),
    )
}

fn write_speed_plot(
    path: &Path,
    label: &str,
    studies: &[&Study],
    config: &CompareConfig,
) -> Result<()> {
    let r = config.realizations;
    let series = studies
        .iter()
        .map(|s| Series {
            label: s.sampler.clone(),
            points: s
                .points
                .iter()
                .zip(&s.setup_seconds)
                .map(|(p, setup)| ((p.seconds + setup) / r as f64 * 1e3, p.mse))
                .collect(),
            errors: None,
            dashed: false,
        })
        .collect();
    write_loglog_png(
        path,
        &LogLogPlot {
            title: format!(
                "{label}: MSE against time per estimate (N = {} to {})",
                config.ns.iter().min().unwrap_or(&0),
                config.ns.iter().max().unwrap_or(&0)
            ),
            x_label: "ms per estimate (generation + evaluation + one-off optimization / R)".into(),
            y_label: "MSE (squared integrand units)".into(),
            series,
            width: 1000,
            height: 700,
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
        let (sampler, _) = instantiate(spec, (0.5, 0.5), (0.3, 0.7), c.spectra_n, tables)?;
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
        let file = format!("spectra/{}.png", slug(&spec.label()));
        let shear_note = if spec.family() == "classical" {
            ""
        } else {
            ", at shear 0.5"
        };
        write_sheet(
            &out.join(&file),
            &format!("{}{shear_note}: expected power spectra", spec.label()),
            &panels,
            4,
        )?;
        let all: Vec<f64> = spectra
            .iter()
            .flat_map(|s| s.mean.iter().copied())
            .collect();
        write_npy(
            &out.join(format!("spectra/{}.npy", slug(&spec.label()))),
            &[4, c.spectra_res, c.spectra_res],
            &all,
        )?;
        written.push((spec.label(), file));
    }
    Ok(written)
}

fn write_markdown(
    outcome: &Outcome,
    plots: &[(String, String)],
    gallery: &[(String, String)],
    out: &Path,
) -> Result<()> {
    let c = &outcome.config;
    let r = c.realizations;
    write_atomic(&out.join("report.md"), |w| {
        writeln!(w, "# anisospec compare\n")?;
        writeln!(
            w,
            "Every estimate integrates one 4D integrand (x, y pixel; u, v lens) with N samples from an independent set \
             moved by a random toroidal shift. **MSE** is the mean squared error of one estimate against the exact integral \
             (analytic integrands) or the cached high-count reference (pixels), in squared integrand units, over R = {r} \
             realizations, ± its standard error. **Slope** is the fitted exponent of MSE ∝ N^slope with its 95% interval. \
             **Time** is wall time per estimate (sample generation and integrand evaluation, 2 cores shared by the \
             realizations), in milliseconds; **set-up** is the one-off optimization of the table for that N, in seconds. A sampler that \
             cannot make an N uses its nearest valid N (shown). Seed {}; whole run {:.1} s.\n",
            c.seed, outcome.seconds
        )?;
        writeln!(w, "## Integrands\n")?;
        writeln!(
            w,
            "| integrand | class | oracle shear (sx, sy) | shear range |"
        )?;
        writeln!(w, "|---|---|---|---|")?;
        for SubjectInfo {
            label,
            class,
            shear,
            shear_range: range,
        } in &outcome.subjects
        {
            writeln!(
                w,
                "| {label} | {class} | ({:.3}, {:.3}) | [{:.3}, {:.3}] |",
                shear.0, shear.1, range.0, range.1
            )?;
        }
        for (SubjectInfo { label, .. }, (conv, speed)) in outcome.subjects.iter().zip(plots) {
            let studies: Vec<&Study> = outcome
                .studies
                .iter()
                .filter(|s| &s.subject == label)
                .collect();
            writeln!(w, "\n## {label}\n")?;
            write!(w, "| sampler | family |")?;
            for n in &c.ns {
                write!(w, " MSE at N={n} |")?;
            }
            let nmax = c.ns.last().copied().unwrap_or(0);
            writeln!(w, " slope [95% CI] | ms/estimate at N={nmax} | set-up s at N={nmax} | gain over best classical at N={nmax} |")?;
            writeln!(w, "|---|---|{}---|---|---|---|", "---|".repeat(c.ns.len()))?;
            let best_classical = studies
                .iter()
                .filter(|s| s.family == "classical")
                .filter_map(|s| s.points.last().map(|p| p.mse))
                .fold(f64::INFINITY, f64::min);
            for s in &studies {
                write!(w, "| {} | {} |", s.sampler, s.family)?;
                for (p, n) in s.points.iter().zip(&c.ns) {
                    let shown = if p.n == *n {
                        String::new()
                    } else {
                        format!(" (N={})", p.n)
                    };
                    write!(w, " {:.3e} ± {:.1e}{shown} |", p.mse, p.mse_stderr)?;
                }
                let last = s.points.last().expect("one point per N");
                writeln!(
                    w,
                    " {} | {:.3} | {:.2} | {:.2}× |",
                    slope_text(s),
                    last.seconds / r as f64 * 1e3,
                    s.setup_seconds.last().expect("one set-up time per N"),
                    best_classical / last.mse
                )?;
            }
            writeln!(
                w,
                "\n![convergence]({conv})\n![speed against error]({speed})"
            )?;
        }
        writeln!(w, "\n## Robustness to oracle error\n")?;
        writeln!(
            w,
            "MSE at N = {} when the oracle's shear is scaled by (1 + error); in brackets, the gain over the best classical \
             sampler on that integrand at the same N (best classical MSE / this MSE; above 1 is a gain). Tables keep \
             the shape built for the true shear range; a table for a range that holds an in-focus layer is designed \
             in that layer's frame and not sheared, so the error does not move it.\n",
            c.ns.iter().max().unwrap_or(&0)
        )?;
        let mut errors = vec![0.0];
        errors.extend(c.oracle_errors.iter().copied());
        write!(w, "| integrand | sampler |")?;
        for e in &errors {
            write!(w, " error {:+.0}% |", e * 100.0)?;
        }
        writeln!(w, "\n|---|---|{}", "---|".repeat(errors.len()))?;
        let mut keys: Vec<(&String, &String)> = outcome
            .robustness
            .iter()
            .map(|r| (&r.subject, &r.sampler))
            .collect();
        keys.dedup();
        // The robustness rows are at the largest N, wherever it is in `ns`.
        let at_largest =
            c.ns.iter()
                .enumerate()
                .max_by_key(|&(_, n)| n)
                .map_or(0, |(i, _)| i);
        for (subject, sampler) in keys {
            let best_classical = outcome
                .studies
                .iter()
                .filter(|s| &s.subject == subject && s.family == "classical")
                .filter_map(|s| s.points.get(at_largest).map(|p| p.mse))
                .fold(f64::INFINITY, f64::min);
            let rows: Vec<_> = outcome
                .robustness
                .iter()
                .filter(|r| &r.subject == subject && &r.sampler == sampler)
                .collect();
            write!(w, "| {subject} | {sampler} |")?;
            for row in &rows {
                write!(
                    w,
                    " {:.2e} ({:.2}×) |",
                    row.point.mse,
                    best_classical / row.point.mse
                )?;
            }
            writeln!(w)?;
        }
        writeln!(w, "\n## Spectra\n")?;
        writeln!(
            w,
            "Expected power spectra, N = {}, K = {}, {} realizations; sheared and optimized samplers at shear 0.5 (the double-wedge table made for shears 0.3 to 0.7). \
             log10 P from -2 (black) to 1 (white).\n",
            c.spectra_n, c.spectra_res, c.spectra_realizations
        )?;
        for (label, file) in gallery {
            writeln!(w, "![{label}]({file})\n")?;
        }
        writeln!(w, "## Files\n")?;
        writeln!(
            w,
            "`convergence.csv` and `robustness.csv` hold every number above; `mse.npy`, `mse_stderr.npy`, `n.npy` and \
             `seconds_per_estimate.npy` are arrays [integrand, sampler, N] in the order of the tables; \
             `spectra/*.npy` are [projection (xy, uv, xu, yv), K, K]."
        )
    })
}
