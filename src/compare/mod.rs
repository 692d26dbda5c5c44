//! `anisospec compare`: optimized, sheared and classical samplers side by side on analytic integrands
//! and on renderer pixels picked by the oracle's classes, with variance, slope and time — the answer to
//! "which sampler, for which pixels, how much it gains, and what it costs".
//!
//! Every sampler goes through the same convergence engine ([`crate::converge::measure`]): each
//! estimate is an independent set with a random toroidal shift, its error taken against the
//! integrand's exact integral or cached reference.

pub mod config;
pub mod report;
pub mod tables;

use crate::converge::{fit_points, measure, ConvergeConfig, ConvergePoint, SlopeFit};
use crate::error::{Error, Result};
use crate::integrands::{self, Integrand};
use crate::points::shear::ShearMode;
use crate::render::oracle::{oracle_image, PixelClass};
use crate::render::pixel::PixelIntegrand;
use crate::render::scene::Scene;
pub use crate::samplers::usable_n;
use crate::samplers::{self, Sampler, Sheared};
use config::CompareConfig;
use report::REPORT_MARKER;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// One integrand of the study, with what the oracle says of it.
pub struct Subject {
    /// Name in the report.
    pub label: String,
    /// `analytic`, or the pixel class (`in-focus`, `hairline`, `double-wedge`).
    pub class: String,
    /// The integrand.
    pub integrand: Arc<dyn Integrand>,
    /// The shear `(sx, sy)` the sheared samplers use and the tables are moved by (the robustness study
    /// scales it): an analytic integrand's configured shear; a pixel's oracle shear at its centre,
    /// or for a double-wedge pixel the midpoint of its shear range on both axes.
    pub shear: (f64, f64),
    /// The range of shears the integrand holds.
    pub shear_range: (f64, f64),
    /// A pixel's oracle output `(sx, sy)`: the shear at the depth seen through the pixel centre and
    /// the lens centre (`anisospec oracle`); `None` for an analytic integrand.
    pub oracle_shear: Option<(f64, f64)>,
}

/// What the report says of a subject.
#[derive(Clone, Debug, PartialEq)]
pub struct SubjectInfo {
    /// Name in the report.
    pub label: String,
    /// The integrand's own name, its definition (`sheared:s=0.5,c=0.7@xu`, `pixel:px=33,py=32`).
    pub definition: String,
    /// `analytic`, or the pixel class.
    pub class: String,
    /// The shear `(sx, sy)` the samplers use ([`Subject::shear`]).
    pub shear: (f64, f64),
    /// The range of shears the integrand holds.
    pub shear_range: (f64, f64),
    /// A pixel's oracle output `(sx, sy)` at its centre ([`Subject::oracle_shear`]).
    pub oracle_shear: Option<(f64, f64)>,
    /// The integral the errors are measured against (its exact value, or a pixel's high-count
    /// reference), in the integrand's units (radiance for a pixel).
    pub integral: f64,
    /// The standard error of `integral`: 0 for an exact value; for a pixel's reference, whose error
    /// adds its square (on average) to every MSE measured against it.
    pub integral_stderr: f64,
}

/// How a sampler of the study is made for a subject.
#[derive(Clone, Debug, PartialEq)]
pub enum SamplerSpec {
    /// A registry sampler, used as it is.
    Classical(String),
    /// A registry sampler sheared by the subject's shear ([`Subject::shear`]).
    Sheared(String, ShearMode),
    /// An optimized table built from a target file.
    Table(PathBuf),
}

impl SamplerSpec {
    /// The name in the report.
    pub fn label(&self) -> String {
        match self {
            Self::Classical(n) => n.clone(),
            Self::Sheared(n, ShearMode::Transported) => format!("{n} sheared (transported)"),
            Self::Sheared(n, ShearMode::Wrap) => format!("{n} sheared (wrap)"),
            Self::Table(p) => format!("optimized {}", stem(p)),
        }
    }

    /// `classical`, `sheared` or `optimized`.
    pub fn family(&self) -> &'static str {
        match self {
            Self::Classical(_) => "classical",
            Self::Sheared(..) => "sheared",
            Self::Table(_) => "optimized",
        }
    }
}

fn stem(p: &Path) -> String {
    p.file_stem().map_or_else(
        || p.display().to_string(),
        |s| s.to_string_lossy().into_owned(),
    )
}

/// The samplers of a config, in report order.
pub fn sampler_specs(config: &CompareConfig) -> Vec<SamplerSpec> {
    let mut specs: Vec<SamplerSpec> = config
        .classical
        .iter()
        .cloned()
        .map(SamplerSpec::Classical)
        .collect();
    for name in &config.sheared {
        for &mode in &config.shear_modes {
            specs.push(SamplerSpec::Sheared(name.clone(), mode));
        }
    }
    specs.extend(config.tables.iter().cloned().map(SamplerSpec::Table));
    specs
}

/// Builds the sampler `spec` for a subject whose shear ([`Subject::shear`]) is `shear` and whose shears span
/// `range`, at `n` points. Also returns the one-off set-up time in seconds (a table's optimization,
/// as recorded when it was built; 0 for the others).
pub fn instantiate(
    spec: &SamplerSpec,
    shear: (f64, f64),
    range: (f64, f64),
    n: usize,
    tables: &tables::TableCache,
) -> Result<(Box<dyn Sampler>, f64)> {
    match spec {
        SamplerSpec::Classical(name) => Ok((samplers::build(name, 4)?, 0.0)),
        SamplerSpec::Sheared(name, mode) => Ok((
            Box::new(Sheared::new(
                samplers::build(name, 4)?,
                shear.0,
                shear.1,
                *mode,
            )?),
            0.0,
        )),
        SamplerSpec::Table(target) => tables.sampler(target, shear, range, n),
    }
}

/// The measured convergence of one sampler on one subject.
#[derive(Clone, Debug)]
pub struct Study {
    /// Subject label.
    pub subject: String,
    /// Subject class.
    pub class: String,
    /// Sampler label.
    pub sampler: String,
    /// Sampler family.
    pub family: &'static str,
    /// One point per N of the config (N may be the sampler's nearest valid N).
    pub points: Vec<ConvergePoint>,
    /// `MSE ∝ N^slope`.
    pub fit: Option<SlopeFit>,
    /// One-off set-up time (the optimization of the table for that N), seconds, one per point.
    pub setup_seconds: Vec<f64>,
}

/// The robustness of one sampler to an error of the oracle's shear, at the largest N.
#[derive(Clone, Debug)]
pub struct Robustness {
    /// Subject label.
    pub subject: String,
    /// Sampler label.
    pub sampler: String,
    /// Relative error put on the shear (0 = exact oracle).
    pub error: f64,
    /// Whether the oracle's shear moves the sampler on this subject: false for a shape table kept
    /// unsheared (see `tables::moved`), whose rows are one measurement repeated.
    pub moved: bool,
    /// The measurement.
    pub point: ConvergePoint,
}

/// Everything a compare run measured.
pub struct Outcome {
    /// The config that ran.
    pub config: CompareConfig,
    /// Subjects, in order.
    pub subjects: Vec<SubjectInfo>,
    /// Studies, subject-major.
    pub studies: Vec<Study>,
    /// Robustness rows.
    pub robustness: Vec<Robustness>,
    /// Wall time of the measurements (the pixels' references, the studies and the robustness sweep,
    /// with the tables they build), seconds; the report adds its spectra gallery and plots to it.
    pub seconds: f64,
}

/// The analytic subjects and one pixel per requested class of the default scene.
pub fn subjects(config: &CompareConfig, cache_dir: &Path) -> Result<Vec<Subject>> {
    let mut out = Vec::new();
    for a in &config.analytic {
        let f: Arc<dyn Integrand> = Arc::from(integrands::parse(&a.spec)?);
        if f.dims() != 4 {
            return Err(Error::Usage(format!(
                "{}: '{}' is {}D; compare runs 4D integrands (place 2D ones with @xu, @yv, ...)",
                a.label,
                a.spec,
                f.dims()
            )));
        }
        out.push(Subject {
            label: a.label.clone(),
            class: "analytic".into(),
            integrand: f,
            shear: (a.shear[0], a.shear[1]),
            shear_range: (a.shear_range[0], a.shear_range[1]),
            oracle_shear: None,
        });
    }
    if config.pixel_classes.is_empty() {
        return Ok(out);
    }
    let scene = Arc::new(Scene::load(None)?);
    let oracle = oracle_image(&scene, &indicatif::ProgressBar::hidden())?;
    let (w, h) = (scene.width(), scene.height());
    for class in &config.pixel_classes {
        // The pixel of that class nearest the image centre.
        let pick = oracle
            .iter()
            .enumerate()
            .filter(|(_, o)| o.class.name() == class)
            .min_by(|(i, _), (j, _)| {
                let d = |k: usize| {
                    let (x, y) = (
                        (k % w) as f64 - w as f64 / 2.0,
                        (k / w) as f64 - h as f64 / 2.0,
                    );
                    x * x + y * y
                };
                d(*i).total_cmp(&d(*j))
            });
        let Some((i, o)) = pick else {
            return Err(Error::Usage(format!(
                "the default scene has no {class} pixel; drop it from pixel_classes"
            )));
        };
        let (px, py) = (i % w, i / w);
        let f = PixelIntegrand::new(scene.clone(), px, py)?
            .with_ref_count(config.pixel_reference_count)?
            .with_cache_dir(Some(cache_dir.to_path_buf()));
        // A double wedge's shears fan over its range: the samplers take its midpoint, not the
        // shear at the one depth seen through the centres.
        let centre = if o.class == PixelClass::DoubleWedge {
            0.5 * (o.s_min + o.s_max)
        } else {
            o.sx
        };
        out.push(Subject {
            label: format!("{class} pixel ({px},{py})"),
            class: class.clone(),
            integrand: Arc::new(f),
            shear: (centre, centre),
            shear_range: (o.s_min, o.s_max),
            oracle_shear: Some((o.sx, o.sy)),
        });
    }
    Ok(out)
}

/// Runs the study and writes the report folder `out`, replacing an earlier report there. A bad config,
/// an `out` or `cache_dir` that is (or lies under) a file, an `out` holding other files than an
/// earlier report, a `cache_dir` inside `out`, and one where tables cannot be written (when the study
/// builds tables) are refused before any work.
pub fn run(config: &CompareConfig, out: &Path, cache_dir: &Path) -> Result<Outcome> {
    config.validate()?;
    crate::output::check_report_folder(out, REPORT_MARKER)?;
    check_cache_outside(cache_dir, out)?;
    crate::output::check_folder(cache_dir, "--cache", "cache")?;
    if !config.tables.is_empty() {
        tables::check_writable(cache_dir)?;
    }
    let started = Instant::now();
    let subjects = subjects(config, cache_dir)?;
    let labels: Vec<String> = subjects.iter().map(|s| s.label.clone()).collect();
    config::check_file_names(&labels, "integrands (analytic labels and pixels)")?;
    let specs = sampler_specs(config);
    // A file of the user's where the report puts one stops the run now, not after the measurements.
    let sampler_labels: Vec<String> = specs.iter().map(SamplerSpec::label).collect();
    let places = report::places(&labels, &sampler_labels);
    crate::output::check_report_places(out, REPORT_MARKER, &places)?;
    let tables = tables::TableCache::new(config, cache_dir);
    let cfg = ConvergeConfig {
        realizations: config.realizations,
        seed: config.seed,
        random_placement: false,
    };
    let bar = crate::progress::bar((subjects.len() * specs.len()) as u64, "compare");
    let mut studies = Vec::new();
    for s in &subjects {
        for spec in &specs {
            let mut points = Vec::new();
            let mut setup = Vec::new();
            for &n in &config.ns {
                let (sampler, seconds) = instantiate(spec, s.shear, s.shear_range, n, &tables)?;
                setup.push(seconds);
                let n = usable_n(sampler.as_ref(), n);
                // Requested N beyond a sampler's reach fall back on one N: measured once.
                let point = match points.iter().find(|p: &&ConvergePoint| p.n == n) {
                    Some(p) => p.clone(),
                    None => measure(sampler.as_ref(), s.integrand.as_ref(), n, &cfg)?,
                };
                points.push(point);
            }
            studies.push(Study {
                subject: s.label.clone(),
                class: s.class.clone(),
                sampler: spec.label(),
                family: spec.family(),
                fit: fit_points(&points, cfg.realizations, s.integrand.reference().value),
                points,
                setup_seconds: setup,
            });
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    let robustness = robustness(config, &subjects, &specs, &tables, &cfg)?;
    let outcome = Outcome {
        config: config.clone(),
        subjects: subjects
            .iter()
            .map(|s| SubjectInfo {
                label: s.label.clone(),
                definition: s.integrand.name(),
                class: s.class.clone(),
                shear: s.shear,
                shear_range: s.shear_range,
                oracle_shear: s.oracle_shear,
                integral: s.integrand.reference().value,
                integral_stderr: s.integrand.reference().stderr,
            })
            .collect(),
        studies,
        robustness,
        seconds: started.elapsed().as_secs_f64(),
    };
    // The whole folder or nothing: a failure while writing it leaves an earlier report as it was.
    crate::output::write_folder(out, REPORT_MARKER, |staging| {
        report::write(&outcome, &specs, &tables, staging, started)
    })?;
    Ok(outcome)
}

/// Refuses a cache folder inside the report folder `out` (or the same folder), before any work: a
/// cache is no part of a report, and a run stopped before it writes its report would leave the folder
/// holding the cache and no report, which the next run refuses.
fn check_cache_outside(cache_dir: &Path, out: &Path) -> Result<()> {
    use crate::output::resolved;
    if resolved(cache_dir)?.starts_with(resolved(out)?) {
        return Err(Error::Usage(format!(
            "--cache {} lies inside the report folder --out {}; keep the cache beside the report \
             (the default is out/cache beside out/compare)",
            cache_dir.display(),
            out.display()
        )));
    }
    Ok(())
}

/// The samplers that follow the oracle (sheared and optimized), on the subjects that have a shear,
/// with their shear ([`Subject::shear`]) scaled by `1 + e` for every error `e` (and `e = 0`), at the largest N.
/// Tables keep the shape built for the subject's true shear range; the error moves them.
fn robustness(
    config: &CompareConfig,
    subjects: &[Subject],
    specs: &[SamplerSpec],
    tables: &tables::TableCache,
    cfg: &ConvergeConfig,
) -> Result<Vec<Robustness>> {
    let n = *config.ns.iter().max().expect("validated: ns is not empty");
    let mut errors = vec![0.0];
    errors.extend(config.oracle_errors.iter().copied());
    let mut rows = Vec::new();
    // An in-focus pixel's oracle shear is 0 up to rounding, so an error of it changes nothing.
    for s in subjects
        .iter()
        .filter(|s| s.class != "in-focus" && s.shear.0.abs() + s.shear.1.abs() > 0.0)
    {
        for spec in specs.iter().filter(|sp| sp.family() != "classical") {
            if matches!(spec, SamplerSpec::Sheared(_, ShearMode::Wrap)) {
                continue;
            }
            // A shape table designed in the frame of an in-focus layer is never moved (see
            // `tables::moved`): every error gives the same sampler, so it is measured once (the rows
            // are the same bits as measuring each; 20 of 21 ray-traced studies saved per table).
            let unmoved = match spec {
                SamplerSpec::Table(target) => !tables::moved(
                    &tables::framed_target(target, s.shear_range)?,
                    s.shear_range,
                ),
                _ => false,
            };
            let mut exact: Option<ConvergePoint> = None;
            for &e in &errors {
                let point = match &exact {
                    Some(p) if unmoved => p.clone(),
                    _ => {
                        let shear = (s.shear.0 * (1.0 + e), s.shear.1 * (1.0 + e));
                        // A table keeps the shape built for the true range; only the shear moving
                        // it is wrong.
                        let (sampler, _) = instantiate(spec, shear, s.shear_range, n, tables)?;
                        let n = usable_n(sampler.as_ref(), n);
                        measure(sampler.as_ref(), s.integrand.as_ref(), n, cfg)?
                    }
                };
                exact.get_or_insert_with(|| point.clone());
                rows.push(Robustness {
                    subject: s.label.clone(),
                    sampler: spec.label(),
                    error: e,
                    moved: !unmoved,
                    point,
                });
            }
        }
    }
    Ok(rows)
}
