//! What `anisospec compare` runs: samplers, integrands, sizes and realizations. Built-in presets
//! (a small default and a paper-scale `--full`) or a strict TOML file, in which every key is optional
//! (a key left out takes the default suite's value) and an unknown key is refused.

use crate::error::{number, Error, Result};
use crate::points::shear::{ShearMode, MAX_SHEAR};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The largest `table_seconds`, a safety net of about 11 days per set.
pub const MAX_TABLE_SECONDS: f64 = 1e6;

/// The largest relative oracle error of the robustness study (+10000 %).
pub const MAX_ORACLE_ERROR: f64 = 100.0;

/// The shear range of the spectra gallery's sheared and optimized samplers (at shear 0.5).
pub const GALLERY_SHEAR_RANGE: (f64, f64) = (0.3, 0.7);

/// An analytic 4D integrand of the suite.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnalyticEntry {
    /// Name in the report, e.g. `hairline edge`.
    pub label: String,
    /// Integrand spec (see `anisospec integrands`), 4D, e.g. `sheared:s=0.5@xu*sheared:s=0.5@yv`.
    pub spec: String,
    /// The shear `(sx, sy)` an exact oracle gives for it (the centre of its shear range for a fan;
    /// with a double-wedge table listed, `[c, c]` for the range's centre `c`, unless the range holds
    /// 0).
    #[serde(deserialize_with = "crate::exact_array::exactly")]
    pub shear: [f64; 2],
    /// The range of shears it holds, `[s_min, s_max]` (equal for a single edge); a double-wedge table
    /// is built for this range.
    #[serde(deserialize_with = "crate::exact_array::exactly")]
    pub shear_range: [f64; 2],
}

/// The whole study.
///
/// In a TOML file every key is optional: a key left out takes its value in
/// [`CompareConfig::default_suite`] (so `ns = [16, 64]` alone is the default study at two sizes). A
/// key given replaces the default's whole value; `analytic`, for one, replaces the default's
/// integrands rather than adding to them, and each of its entries needs all four keys. An unknown
/// (say, misspelt) key is refused.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default = "CompareConfig::default_suite")]
pub struct CompareConfig {
    /// Points per pixel / estimate.
    pub ns: Vec<usize>,
    /// Realizations per N (each an independent set with a random toroidal shift).
    pub realizations: usize,
    /// Seed of every random choice.
    pub seed: u64,
    /// Classical 4D samplers, used as they are (see `anisospec samplers`); the best of them is what
    /// every gain is against, so tables (`table:PATH`) go in `sheared`, not here.
    pub classical: Vec<String>,
    /// 4D samplers sheared by each integrand's shear ([`super::Subject::shear`]), once per mode in
    /// `shear_modes`.
    pub sheared: Vec<String>,
    /// How the oracle's shear is applied to `sheared`.
    pub shear_modes: Vec<ShearMode>,
    /// Optimized tables: target files (relative to the folder compare runs in; a shipped
    /// `targets/NAME.toml` with no file there is read from the binary), built for each N when
    /// missing from the cache.
    pub tables: Vec<PathBuf>,
    /// Sets per optimized table (each use picks one and shifts it at random).
    pub table_sets: usize,
    /// Optimizer time limit per set, seconds: only a safety net. The iteration budget
    /// ([`crate::compare::tables::TABLE_ITERATIONS`]) is meant to stop every set, so that a table is
    /// the same on every machine; a set stopped by this limit is reported on stderr and in the
    /// table's sidecar.
    pub table_seconds: f64,
    /// Analytic integrands.
    pub analytic: Vec<AnalyticEntry>,
    /// Renderer pixel classes to include, one pixel each: any of `in-focus`, `hairline`,
    /// `double-wedge`.
    pub pixel_classes: Vec<String>,
    /// Rays per pixel reference.
    pub pixel_reference_count: usize,
    /// Relative errors put on the oracle's shear for the robustness study (the sweep), e.g. -0.25, 0.1;
    /// the default runs from -0.25 to 0.25 in steps of 0.025.
    pub oracle_errors: Vec<f64>,
    /// Spectra gallery: points, grid side and realizations.
    pub spectra_n: usize,
    /// Frequency grid side K of the gallery.
    pub spectra_res: usize,
    /// Realizations of each gallery spectrum.
    pub spectra_realizations: usize,
}

impl CompareConfig {
    /// The built-in default: small enough for a few minutes on 2 cores.
    pub fn default_suite() -> Self {
        Self {
            ns: vec![16, 64, 256, 1024],
            realizations: 256,
            seed: 1,
            classical: [
                "padded-jittered",
                "padded-mj",
                "sobol",
                "padded-pmj02",
                "oa",
                "lattice",
            ]
            .map(String::from)
            .to_vec(),
            sheared: vec!["padded-mj".into(), "sobol".into(), "lattice".into()],
            shear_modes: vec![ShearMode::Transported, ShearMode::Wrap],
            tables: vec![
                PathBuf::from("targets/hairline.toml"),
                PathBuf::from("targets/widened-hairline.toml"),
                PathBuf::from("targets/double-wedge.toml"),
                PathBuf::from("targets/fan-variance.toml"),
                PathBuf::from("targets/fan-lattice.toml"),
            ],
            table_sets: 16,
            table_seconds: 600.0,
            // Edges off the centre (c = 0.7, not the default (1 + s)/2): through the transported
            // shear an edge x + 0.5 u = 0.75 becomes the pattern's line a = 1/2, a stratum boundary for
            // every even N, which a sampler with centred strata integrates exactly. Off the centre the
            // comparison is the generic one.
            analytic: vec![
                AnalyticEntry {
                    label: "hairline edge in xu".into(),
                    spec: "sheared:s=0.5,c=0.7@xu".into(),
                    shear: [0.5, 0.5],
                    shear_range: [0.5, 0.5],
                },
                AnalyticEntry {
                    label: "double-wedge fan in xu".into(),
                    spec: "fan:s0=0.3,s1=0.7,c=0.7@xu".into(),
                    shear: [0.5, 0.5],
                    shear_range: [0.3, 0.7],
                },
                AnalyticEntry {
                    label: "hairline edges in xu and yv".into(),
                    spec: "sheared:s=0.5,c=0.7@xu*sheared:s=0.5,c=0.7@yv".into(),
                    shear: [0.5, 0.5],
                    shear_range: [0.5, 0.5],
                },
            ],
            pixel_classes: ["in-focus", "hairline", "double-wedge"]
                .map(String::from)
                .to_vec(),
            // 0.4 s a pixel; its reference's standard error (8.8e-6 on the back-wall pixel, against
            // 6.3e-5 from 2^18 rays) puts a floor of 8e-11 under the pixel's MSEs, 0.06 % of the
            // lowest at N = 1024 (2^18 rays: 3.9e-9, about 3 %).
            pixel_reference_count: 1 << 22,
            // −25 % to +25 % in steps of 2.5 %: a rank-1 lattice's MSE has spikes a few per cent wide
            // (where the erred edge meets a dual point), which ±10 % and ±25 % alone can miss.
            oracle_errors: (-10..=10)
                .filter(|&i| i != 0)
                .map(|i| f64::from(i) / 40.0)
                .collect(),
            spectra_n: 256,
            spectra_res: 64,
            spectra_realizations: 32,
        }
    }

    /// The paper-scale study: N from 16 to 4096 and more realizations.
    pub fn full_suite() -> Self {
        Self {
            ns: vec![16, 64, 256, 1024, 4096],
            realizations: 1000,
            table_sets: 64,
            table_seconds: 600.0,
            // The most rays a reference takes (1.5 s a pixel, standard error 4.7e-6 on the back-wall
            // pixel): MSEs at N = 4096 reach 1e-8.
            pixel_reference_count: 1 << 24,
            spectra_n: 1024,
            spectra_res: 128,
            spectra_realizations: 128,
            ..Self::default_suite()
        }
    }

    /// Reads a TOML config. A key left out takes the default suite's value; unknown keys and bad
    /// values are input errors.
    pub fn load(path: &Path) -> Result<Self> {
        let text = crate::input::read_text(path, "compare config")?;
        let config: Self = toml::from_str(&text).map_err(|e| {
            let message = e.to_string();
            let hint = misplaced_key_hint(&message).unwrap_or_default();
            Error::Input(format!("{}: {}{hint}", path.display(), message.trim_end()))
        })?;
        config.validate().map_err(|e| match e {
            Error::Usage(m) | Error::Input(m) => Error::Input(format!("{}: {m}", path.display())),
            other => other,
        })?;
        Ok(config)
    }

    /// The study as TOML text that [`CompareConfig::load`] reads back to the same config, every key
    /// written out. Fails only on a table path that is not UTF-8, which TOML cannot hold (a config
    /// read from TOML has none).
    pub fn to_toml(&self) -> Result<String> {
        toml::to_string(self)
            .map_err(|e| Error::Usage(format!("the study cannot be written as TOML: {e}")))
    }

    /// Checks, before any work, everything in the config that would otherwise fail mid-run, put a
    /// number that is not one in the report, or make two outputs share a file name.
    pub fn validate(&self) -> Result<()> {
        if self.ns.len() < 2 || self.ns.contains(&0) {
            return Err(Error::Usage(
                "ns needs at least two positive sizes for a slope, e.g. ns = [16, 64, 256]".into(),
            ));
        }
        // Before any sampler looks for its nearest valid N: that search steps one count at a time.
        for &n in &self.ns {
            crate::points::coordinate_count(1, n, 4)
                .map_err(|e| Error::Usage(format!("ns: {e}")))?;
        }
        if self.realizations < 2 {
            return Err(Error::Usage(
                "realizations must be at least 2 for a standard error".into(),
            ));
        }
        crate::stats::check_realizations("realizations =", self.realizations)?;
        for c in &self.pixel_classes {
            if !["in-focus", "hairline", "double-wedge"].contains(&c.as_str()) {
                return Err(Error::Usage(format!(
                    "pixel class '{c}' is unknown; use in-focus, hairline or double-wedge"
                )));
            }
        }
        if self
            .oracle_errors
            .iter()
            .any(|e| !(*e > -1.0 && *e <= MAX_ORACLE_ERROR))
        {
            return Err(Error::Usage(format!(
                "oracle_errors are relative errors of the shear, above -1 and at most {MAX_ORACLE_ERROR} (e.g. -0.25, 0.1)"
            )));
        }
        if let Some(n) = first_repeat(&self.ns) {
            return Err(Error::Usage(format!(
                "ns lists N = {n} twice; give each size once, e.g. ns = [16, 64, 256]"
            )));
        }
        if let Some((a, b)) = first_descent(&self.ns) {
            return Err(Error::Usage(format!(
                "ns lists N = {a} before {b}; list the sizes in increasing order, e.g. ns = [16, 64, 256] (the report's columns and plots follow it)"
            )));
        }
        if self.oracle_errors.is_empty() {
            return Err(Error::Usage(
                "oracle_errors is empty; the robustness study needs at least one error of the oracle's shear, e.g. oracle_errors = [-0.1, 0.1]".into(),
            ));
        }
        if self.oracle_errors.contains(&0.0) {
            return Err(Error::Usage(
                "oracle_errors holds 0, the exact oracle, which the robustness study always measures; list only errors, e.g. oracle_errors = [-0.1, 0.1]".into(),
            ));
        }
        if let Some(e) = first_repeat(&self.oracle_errors) {
            return Err(Error::Usage(format!(
                "oracle_errors lists {} twice; give each error once",
                number(*e)
            )));
        }
        // The report gives errors to 0.1 %: one that reads +0% would pass for the exact oracle, and
        // two that read the same could not be told apart in its tables and plots.
        let shown = |e: &f64| super::report::error_text(*e);
        if let Some(e) = self
            .oracle_errors
            .iter()
            .find(|e| (**e * 1000.0).round() == 0.0)
        {
            return Err(Error::Usage(format!(
                "oracle_errors holds {}, which the report (errors to 0.1 %) would show as {}, as the exact oracle; give errors of 0.0005 or more in size",
                number(*e),
                shown(e)
            )));
        }
        for (i, a) in self.oracle_errors.iter().enumerate() {
            if let Some(b) = self.oracle_errors[..i]
                .iter()
                .find(|b| shown(b) == shown(a))
            {
                return Err(Error::Usage(format!(
                    "oracle_errors {} and {} both read {} in the report, which gives errors to 0.1 %; give errors at least 0.001 apart",
                    number(*b),
                    number(*a),
                    shown(a)
                )));
            }
        }
        if self.analytic.is_empty() && self.pixel_classes.is_empty() {
            return Err(Error::Usage(
                "analytic and pixel_classes are both empty, so there is nothing to integrate; add an [[analytic]] entry or a pixel class, e.g. pixel_classes = [\"hairline\"]".into(),
            ));
        }
        if let Some(c) = first_repeat(&self.pixel_classes) {
            return Err(Error::Usage(format!(
                "pixel_classes lists '{c}' twice; give each class once"
            )));
        }
        if !self.pixel_classes.is_empty() {
            crate::render::pixel::check_ref_count(self.pixel_reference_count).map_err(|e| {
                Error::Usage(format!(
                    "pixel_reference_count = {}: {e}",
                    self.pixel_reference_count
                ))
            })?;
        }
        if self.classical.is_empty() {
            return Err(Error::Usage(
                "classical is empty, but every gain in the report is against the best classical sampler; list at least one, e.g. classical = [\"padded-jittered\"]".into(),
            ));
        }
        if let Some(table) = self.classical.iter().find(|s| s.starts_with("table:")) {
            return Err(Error::Usage(format!(
                "classical lists '{table}', a table, but every gain in the report is against the best classical sampler; list the table in sheared = [...] (used through the oracle's shear, as the suite's own tables are), or its target file in tables = [...]"
            )));
        }
        for (key, list) in [("classical", &self.classical), ("sheared", &self.sheared)] {
            let built = list
                .iter()
                .map(|name| crate::samplers::build(name, 4))
                .collect::<Result<Vec<_>>>()?;
            if let Some(which) = crate::samplers::repeated(list, &built) {
                return Err(Error::Usage(format!(
                    "{key} lists {which}; give each sampler once"
                )));
            }
            // Every N a sampler runs at: the study's, and the gallery's (a spectra_n of 0 or
            // beyond the coordinate limit is refused below, with its own message).
            let gallery_checked =
                self.spectra_n > 0 && crate::points::coordinate_count(1, self.spectra_n, 4).is_ok();
            let sizes = self
                .ns
                .iter()
                .map(|&n| ("ns", n))
                .chain(gallery_checked.then_some(("spectra_n", self.spectra_n)));
            for (size_key, n) in sizes {
                for sampler in &built {
                    let n = crate::samplers::usable_n(sampler.as_ref(), n);
                    // A size the sampler cannot make is the study's; a table file that cannot be
                    // read (a family's, read for this N) is the file's, named as it is.
                    crate::samplers::validate_n(sampler.as_ref(), n).map_err(|e| match e {
                        Error::Usage(m) => Error::Usage(format!("{size_key}: {m}")),
                        other => other,
                    })?;
                }
            }
        }
        if self.tables.is_empty() {
            self.validate_ns_made()?;
        }
        if let Some(mode) = first_repeat(&self.shear_modes) {
            return Err(Error::Usage(format!(
                "shear_modes lists '{}' twice; give each mode once",
                format!("{mode:?}").to_lowercase()
            )));
        }
        if !self.sheared.is_empty() && self.shear_modes.is_empty() {
            return Err(Error::Usage(
                "sheared lists samplers but shear_modes is empty, so none would run; give shear_modes = [\"transported\"] (or [\"transported\", \"wrap\"]), or sheared = []".into(),
            ));
        }
        for (i, e) in self.analytic.iter().enumerate() {
            for (key, pair) in [("shear", e.shear), ("shear_range", e.shear_range)] {
                if pair.iter().any(|s| !s.is_finite() || s.abs() > MAX_SHEAR) {
                    return Err(Error::Usage(format!(
                        "{}: {key} = [{}, {}]: shears must be finite and at most {MAX_SHEAR:e} in magnitude (a larger one loses precision in the transported shear), e.g. {key} = [0.5, 0.5]",
                        e.label,
                        number(pair[0]),
                        number(pair[1])
                    )));
                }
            }
            let largest = e.shear[0].abs().max(e.shear[1].abs());
            if let Some(err) = self
                .oracle_errors
                .iter()
                .find(|&&err| largest * (1.0 + err) > MAX_SHEAR)
            {
                return Err(Error::Usage(format!(
                    "{}: shear {} with the oracle error {} is above the largest shear, {MAX_SHEAR:e}; lower oracle_errors or the shear",
                    e.label,
                    number(largest),
                    number(*err)
                )));
            }
            if e.shear_range[0] > e.shear_range[1] {
                return Err(Error::Usage(format!(
                    "{}: shear_range [{}, {}] has s_min > s_max",
                    e.label,
                    number(e.shear_range[0]),
                    number(e.shear_range[1])
                )));
            }
            if crate::integrands::spec::names_a_pixel(&e.spec) {
                return Err(Error::Usage(format!(
                    "{}: spec '{}' is a pixel of the scene, not an analytic integrand (whose integral is exact); list pixels by their oracle class instead, e.g. pixel_classes = [\"hairline\"], which also sets their shears and references",
                    e.label, e.spec
                )));
            }
            let integrand = crate::integrands::parse(&e.spec)
                .map_err(|err| Error::Usage(format!("{}: spec '{}': {err}", e.label, e.spec)))?;
            if integrand.dims() != 4 {
                return Err(Error::Usage(format!(
                    "{}: spec '{}' is {}D; compare integrates 4D integrands, so place a 2D one on a plane, e.g. '{}@xu'",
                    e.label,
                    e.spec,
                    integrand.dims(),
                    e.spec
                )));
            }
            if e.label.is_empty() || e.label.contains(['"', '|', '\n', '\r']) {
                return Err(Error::Usage(format!(
                    "analytic integrand label {:?}: a label must be non-empty and hold no '\"', '|' or line break (it goes into CSV and markdown tables)",
                    e.label
                )));
            }
            if self.analytic[..i].iter().any(|o| o.label == e.label) {
                return Err(Error::Usage(format!(
                    "two analytic integrands are labelled '{}'; labels name the report's rows and plot files, so make them differ",
                    e.label
                )));
            }
        }
        let labels: Vec<String> = self.analytic.iter().map(|e| e.label.clone()).collect();
        check_file_names(&labels, "analytic integrand labels")?;
        self.validate_spectra()?;
        self.validate_tables()?;
        self.validate_sampler_labels()
    }

    /// Refuses an N of `ns` that no classical or sheared sampler makes (each would use its nearest
    /// valid N instead), when no table runs at it either: the report's columns at that N would hold
    /// only other N.
    fn validate_ns_made(&self) -> Result<()> {
        let samplers = self
            .classical
            .iter()
            .chain(&self.sheared)
            .map(|name| crate::samplers::build(name, 4))
            .collect::<Result<Vec<_>>>()?;
        for &n in &self.ns {
            let used: Vec<usize> = samplers
                .iter()
                .map(|s| crate::samplers::usable_n(s.as_ref(), n))
                .collect();
            if used.iter().all(|&u| u != n) {
                let nearest = *used
                    .iter()
                    .min_by_key(|&&u| u.abs_diff(n))
                    .expect("classical is not empty");
                return Err(Error::Usage(format!(
                    "ns: no sampler of the study makes N = {n} (each would use its nearest valid N, e.g. {nearest}), so the report's columns at N = {n} would hold other N; give an N a sampler makes, e.g. {nearest}"
                )));
            }
        }
        Ok(())
    }

    /// `table_seconds`, `table_sets`, and every table target at every N it is built for (`ns` and
    /// `spectra_n`), for the analytic integrands' shear ranges and the gallery's.
    /// A double-wedge table is built around the centre `c` of an entry's shear range (its frame
    /// shear, unless the range holds 0) and moved by the entry's `shear`: any other shear than
    /// `[c, c]` would put the wedge off the integrand's (`[0.4, 0.4]` for `[0.3, 0.7]` moved a wedge
    /// built for `[-0.2, 0.2]` to `[0.2, 0.6]`).
    fn check_wedge_shears(&self, table: &std::path::Path) -> Result<()> {
        for e in &self.analytic {
            let c = super::tables::frame_shear((e.shear_range[0], e.shear_range[1]));
            let off = |s: f64| (s - c).abs() > 1e-9 * c.abs().max(1.0);
            if c != 0.0 && (off(e.shear[0]) || off(e.shear[1])) {
                return Err(Error::Usage(format!(
                    "{}: shear = [{}, {}] with shear_range [{}, {}]: the double-wedge table {} is built around the range's centre and moved by the shear, so give shear = [{c}, {c}], or leave that table out of tables",
                    e.label,
                    number(e.shear[0]),
                    number(e.shear[1]),
                    number(e.shear_range[0]),
                    number(e.shear_range[1]),
                    table.display(),
                    c = number(c)
                )));
            }
        }
        Ok(())
    }

    fn validate_tables(&self) -> Result<()> {
        if !(self.table_seconds.is_finite()
            && self.table_seconds > 0.0
            && self.table_seconds <= MAX_TABLE_SECONDS)
        {
            return Err(Error::Usage(format!(
                "table_seconds = {} is not a time limit; give a finite number of seconds above 0 and at most {MAX_TABLE_SECONDS:e}, e.g. table_seconds = 600",
                number(self.table_seconds)
            )));
        }
        if self.tables.is_empty() {
            return Ok(());
        }
        if self.table_sets == 0 {
            return Err(Error::Usage(
                "table_sets = 0 builds tables of no set; give at least 1, e.g. table_sets = 16"
                    .into(),
            ));
        }
        let sizes = self
            .ns
            .iter()
            .map(|&n| ("ns", n))
            .chain([("spectra_n", self.spectra_n)]);
        // Too small an N is refused by each table's own check below, which names the N it builds
        // from (N = 9 for a table with strata, where "2 or more" was named before).
        for (key, n) in sizes.clone() {
            crate::points::coordinate_count(self.table_sets, n, 4).map_err(|e| {
                Error::Usage(format!(
                    "table_sets = {} at N = {n} (from {key}): {e}, e.g. table_sets = 16",
                    self.table_sets
                ))
            })?;
        }
        let ranges: Vec<(f64, f64)> = self
            .analytic
            .iter()
            .map(|e| (e.shear_range[0], e.shear_range[1]))
            .chain([GALLERY_SHEAR_RANGE])
            .collect();
        for path in &self.tables {
            let target = crate::targets::Target::load(path).map_err(|e| {
                // A missing file gets the list's own rule; any other error names the file itself.
                if std::fs::symlink_metadata(path).is_err() {
                    Error::Usage(format!(
                        "table target {}: {e}; tables = [...] lists target files, relative to the folder compare runs in (the shipped targets/*.toml that need no image are also built in, read from the binary where no such file exists); give files that exist",
                        path.display()
                    ))
                } else {
                    Error::Usage(format!("table target: {e}"))
                }
            })?;
            if matches!(target, crate::targets::Target::DoubleWedge(_)) {
                self.check_wedge_shears(path)?;
            }
            for (key, n) in sizes.clone() {
                for &range in &ranges {
                    super::tables::check_buildable(target.clone(), range, n).map_err(|e| {
                        Error::Usage(format!(
                            "table target {} cannot be built at N = {n} (from {key}): {e}",
                            path.display()
                        ))
                    })?;
                }
            }
        }
        for (i, a) in self.tables.iter().enumerate() {
            if let Some(b) = self.tables[..i]
                .iter()
                .find(|b| b.file_stem() == a.file_stem())
            {
                return Err(Error::Usage(format!(
                    "tables lists {} and {}, which share the file name stem, so both would be '{}' in the report; give each target once, or copy one to a file of another name",
                    b.display(),
                    a.display(),
                    super::SamplerSpec::Table(a.clone()).label()
                )));
            }
        }
        Ok(())
    }

    /// At least one sampler, and sampler labels that are distinct, safe in CSV and markdown, and
    /// distinct as file names.
    fn validate_sampler_labels(&self) -> Result<()> {
        let labels: Vec<String> = super::sampler_specs(self)
            .iter()
            .map(super::SamplerSpec::label)
            .collect();
        if let Some(l) = labels.iter().find(|l| l.contains(['"', '|', '\n', '\r'])) {
            return Err(Error::Usage(format!(
                "sampler {l:?}: a sampler's name (or a table target's file stem) must hold no '\"', '|' or line break (it goes into CSV and markdown tables)"
            )));
        }
        check_file_names(&labels, "samplers")
    }

    /// The spectra gallery's size, grid side and realizations.
    fn validate_spectra(&self) -> Result<()> {
        if self.spectra_n == 0 {
            return Err(Error::Usage(
                "spectra_n = 0 asks for no points; give at least 1, e.g. spectra_n = 256".into(),
            ));
        }
        crate::points::coordinate_count(1, self.spectra_n, 4)
            .map_err(|e| Error::Usage(format!("spectra_n = {}: {e}", self.spectra_n)))?;
        crate::spectrum::check_res_named("spectra_res =", self.spectra_res)?;
        if self.spectra_realizations == 0 {
            return Err(Error::Usage(
                "spectra_realizations = 0 averages nothing; give at least 1, e.g. spectra_realizations = 32".into(),
            ));
        }
        crate::stats::check_realizations("spectra_realizations =", self.spectra_realizations)?;
        Ok(())
    }
}

/// The first item of `list` that appears in it again.
pub(crate) fn first_repeat<T: PartialEq>(list: &[T]) -> Option<&T> {
    list.iter()
        .enumerate()
        .find(|&(i, x)| list[..i].contains(x))
        .map(|(_, x)| x)
}

/// The first neighbours `(a, b)` of `list` with `b < a`: `None` for a list in increasing order.
pub(crate) fn first_descent(list: &[usize]) -> Option<(usize, usize)> {
    list.windows(2).find(|w| w[1] < w[0]).map(|w| (w[0], w[1]))
}

/// For a TOML error "unknown field `key`" where `key` is a key of the study itself: a hint that it
/// stands inside an `[[analytic]]` entry (TOML puts every key after an `[[analytic]]` line into that
/// entry, so a key appended to a printed config lands there).
fn misplaced_key_hint(message: &str) -> Option<String> {
    let key = message.split("unknown field `").nth(1)?.split('`').next()?;
    let study = toml::Table::try_from(CompareConfig::default_suite()).ok()?;
    (key != "analytic" && study.contains_key(key)).then(|| {
        format!(
            "\n`{key}` is a key of the study, not of an [[analytic]] entry: put it above the first [[analytic]] line (every key after that line belongs to the entry)"
        )
    })
}

/// Longest file-name part a label may make ([`super::report::slug`], bytes): the report's longest
/// file name adds `convergence_` and `.png`, and a file name may have 255 bytes. (A table's cache
/// file keeps at most 100 bytes of its target's name.)
const MAX_FILE_LABEL: usize = 200;

/// Refuses two of `labels` (`what`, e.g. `samplers`) that are equal or that make the same file name
/// in the report (which keeps only letters and digits: `edge a` and `edge-a` are both `edge_a`),
/// naming both, and a label whose file name would be too long ([`MAX_FILE_LABEL`]).
pub fn check_file_names(labels: &[String], what: &str) -> Result<()> {
    for (i, a) in labels.iter().enumerate() {
        let slug = super::report::slug(a);
        if slug.is_empty() {
            return Err(Error::Usage(format!(
                "{what}: '{a}' has no ASCII letter or digit, and the report names its files after them keeping only those (plots/convergence_.png); give it a label with an ASCII letter or digit"
            )));
        }
        if slug.len() > MAX_FILE_LABEL {
            return Err(Error::Usage(format!(
                "{what}: '{a}' makes a file name part of {} characters, and the report names files after it, which file systems cap at 255 bytes; shorten it (for a table, its target file's name) to at most {MAX_FILE_LABEL} characters",
                slug.len()
            )));
        }
        if let Some(b) = labels[..i].iter().find(|b| super::report::slug(b) == slug) {
            return Err(if a == b {
                Error::Usage(format!(
                    "{what}: '{a}' appears twice; the report names rows and files after it, so give each once"
                ))
            } else {
                Error::Usage(format!(
                    "{what}: '{b}' and '{a}' both make the file name '{slug}' in the report (which keeps only letters and digits); make them differ in a letter or digit"
                ))
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Writes `text` to a temporary `study.toml` and loads it.
    fn load_text(text: &str) -> Result<CompareConfig> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("study.toml");
        std::fs::write(&path, text).unwrap();
        CompareConfig::load(&path)
    }

    #[test]
    fn printed_configs_load_back_unchanged() {
        let largest_seed = CompareConfig {
            seed: u64::MAX,
            ..CompareConfig::default_suite()
        };
        for preset in [
            CompareConfig::default_suite(),
            CompareConfig::full_suite(),
            largest_seed,
        ] {
            let text = preset.to_toml().unwrap();
            assert_eq!(load_text(&text).unwrap(), preset, "{text}");
        }
    }

    /// A study key appended after an [[analytic]] entry (as to a printed config) is refused with a
    /// hint that says where it goes; an unknown key gets no such hint.
    #[test]
    fn a_study_key_inside_an_entry_gets_a_hint() {
        let printed = CompareConfig::default_suite().to_toml().unwrap();
        let e = load_text(&format!("{printed}spectra_n = 64\n")).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        let m = e.to_string();
        assert!(
            m.contains("`spectra_n` is a key of the study")
                && m.contains("above the first [[analytic]]"),
            "{m}"
        );
        let m = load_text("bogus = 1\n").unwrap_err().to_string();
        assert!(
            m.contains("unknown field `bogus`") && !m.contains("key of the study"),
            "{m}"
        );
    }

    #[test]
    fn an_empty_file_is_the_default_suite() {
        assert_eq!(load_text("").unwrap(), CompareConfig::default_suite());
    }

    #[test]
    fn numbers_in_messages_are_compact() {
        let refused = |mend: fn(&mut CompareConfig)| {
            let mut study = CompareConfig::default_suite();
            mend(&mut study);
            let e = study.validate().unwrap_err();
            assert_eq!(e.exit_code(), 2, "{e}");
            e.to_string()
        };
        let m = refused(|c| c.analytic[0].shear = [1e300, 0.5]);
        assert!(
            m.contains("shear = [1e300, 0.5]: shears must be finite"),
            "{m}"
        );
        // A table built around 0.5 and moved by 0.4 would miss the fan's upper 0.1 (code review).
        let m = refused(|c| c.analytic[1].shear = [0.4, 0.4]);
        assert!(
            m.contains("shear = [0.4, 0.4] with shear_range [0.3, 0.7]")
                && m.contains("give shear = [0.5, 0.5]"),
            "{m}"
        );
        let m = refused(|c| c.analytic[0].shear = [0.5, 0.3]);
        assert!(m.contains("give shear = [0.5, 0.5]"), "{m}");
        // Only a double-wedge table needs it, and a centre off by rounding passes.
        let mut c = CompareConfig::default_suite();
        c.tables.retain(|t| !t.ends_with("double-wedge.toml"));
        c.analytic[1].shear = [0.4, 0.4];
        c.validate().unwrap();
        let mut c = CompareConfig::default_suite();
        c.analytic[1].shear_range = [0.1, 0.2];
        c.analytic[1].shear = [0.15, 0.15];
        c.validate().unwrap();
        let m = refused(|c| c.analytic[0].shear_range = [0.7, 1e-300]);
        assert!(
            m.contains("shear_range [0.7, 1e-300] has s_min > s_max"),
            "{m}"
        );
        let m = refused(|c| c.table_seconds = 1e300);
        assert!(
            m.contains("table_seconds = 1e300 is not a time limit"),
            "{m}"
        );
        let m = refused(|c| c.ns = vec![32, 9, 16]);
        assert!(m.contains("ns lists N = 32 before 9"), "{m}");
        assert!(m.contains("increasing order"), "{m}");
        let m = refused(|c| c.oracle_errors = vec![1e-300, 1e-300]);
        assert!(m.contains("oracle_errors lists 1e-300 twice"), "{m}");
        // Errors the report (to 0.1 %) would show as the exact oracle, or as one another.
        let m = refused(|c| c.oracle_errors = vec![0.1, 1e-300]);
        assert!(m.contains("holds 1e-300, which the report"), "{m}");
        assert!(m.contains("show as +0%"), "{m}");
        let m = refused(|c| c.oracle_errors = vec![0.1001, 0.1002]);
        assert!(m.contains("0.1001 and 0.1002 both read +10%"), "{m}");
        let m = refused(|c| c.oracle_errors = vec![-0.0004, 0.25]);
        assert!(m.contains("show as -0%"), "{m}");
    }

    #[test]
    fn a_sampler_listed_twice_is_refused_naming_it() {
        let twice = |key: &str, list: &[&str]| {
            let list: Vec<String> = list.iter().map(|s| s.to_string()).collect();
            let mut study = CompareConfig::default_suite();
            if key == "classical" {
                study.classical = list;
            } else {
                study.sheared = list;
            }
            let e = study.validate().unwrap_err();
            assert_eq!(e.exit_code(), 2, "{e}");
            e.to_string()
        };
        let m = twice("classical", &["lattice:1:3:5:7", "lattice:01:3:5:7"]);
        assert!(
            m.contains("classical lists 'lattice:1:3:5:7' and 'lattice:01:3:5:7'")
                && m.contains("give each sampler once"),
            "{m}"
        );
        let m = twice("sheared", &["sobol", "padded-mj", "sobol"]);
        assert!(
            m.contains("sheared lists 'sobol' twice; give each sampler once"),
            "{m}"
        );
        // A table is no classical sampler: every gain is against the best of those.
        let m = twice("classical", &["sobol", "table:t.npy"]);
        assert!(
            m.contains("classical lists 'table:t.npy', a table") && m.contains("sheared = [...]"),
            "{m}"
        );
        // One sampler both classical and sheared is two different rows, and allowed.
        let study = CompareConfig {
            classical: vec!["sobol".into()],
            sheared: vec!["sobol".into()],
            ..CompareConfig::default_suite()
        };
        assert!(study.validate().is_ok());
    }

    /// The gallery's N is checked against every sampler before any work, naming its key (it failed
    /// after the whole study was measured, naming none).
    #[test]
    fn a_gallery_size_a_sampler_cannot_make_is_refused_naming_spectra_n() {
        let study = CompareConfig {
            classical: vec!["lattice:1:3:5:7".into()],
            spectra_n: 7,
            ..CompareConfig::default_suite()
        };
        let e = study.validate().unwrap_err();
        assert_eq!(e.exit_code(), 2, "{e}");
        assert!(
            e.to_string().starts_with("spectra_n: lattice:1:3:5:7"),
            "{e}"
        );
        let fine = CompareConfig {
            spectra_n: 64,
            ..study
        };
        assert!(fine.validate().is_ok());
    }

    /// A study N too small for its tables names the N they build from, and that N passes (before,
    /// N = 1 was told "2 or more", and N = 2 was then refused again).
    #[test]
    fn a_table_size_too_small_names_the_n_it_builds_from() {
        for spectra_n in [1, 2] {
            let study = CompareConfig {
                spectra_n,
                ..CompareConfig::default_suite()
            };
            let e = study.validate().unwrap_err().to_string();
            assert!(
                e.contains(&format!("at N = {spectra_n} (from spectra_n)"))
                    && e.contains("from N = 9 on; use N >= 9"),
                "{e}"
            );
        }
        let fine = CompareConfig {
            spectra_n: 9,
            ..CompareConfig::default_suite()
        };
        fine.validate().unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_table_path_that_is_not_utf8_is_a_usage_error() {
        use std::os::unix::ffi::OsStrExt;
        let study = CompareConfig {
            tables: vec![PathBuf::from(std::ffi::OsStr::from_bytes(
                b"targets/\xff.toml",
            ))],
            ..CompareConfig::default_suite()
        };
        assert!(matches!(study.to_toml(), Err(Error::Usage(_))));
    }
}
