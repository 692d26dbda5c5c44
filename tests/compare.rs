//! The compare study on renderer pixels: oracle-sheared and optimized samplers against the classical
//! ones, with fixed seeds and tolerances from standard errors.

use anisospec::compare::config::CompareConfig;
use anisospec::compare::{
    instantiate, subjects, tables::TableCache, usable_n, SamplerSpec, Subject,
};
use anisospec::converge::{measure, ConvergeConfig, ConvergePoint};
use anisospec::points::shear::ShearMode;

fn config(classes: &[&str]) -> CompareConfig {
    CompareConfig {
        analytic: vec![],
        pixel_classes: classes.iter().map(|c| c.to_string()).collect(),
        pixel_reference_count: 1 << 20,
        ..CompareConfig::default_suite()
    }
}

fn mse(
    spec: &SamplerSpec,
    s: &Subject,
    n: usize,
    shear_scale: f64,
    tables: &TableCache,
) -> ConvergePoint {
    mse_over(spec, s, n, shear_scale, tables, 256)
}

/// [`mse`] over `realizations` independent estimates.
fn mse_over(
    spec: &SamplerSpec,
    s: &Subject,
    n: usize,
    shear_scale: f64,
    tables: &TableCache,
    realizations: usize,
) -> ConvergePoint {
    let shear = (s.shear.0 * shear_scale, s.shear.1 * shear_scale);
    let range = (s.shear_range.0 * shear_scale, s.shear_range.1 * shear_scale);
    let (sampler, _) = instantiate(spec, shear, range, n, tables).unwrap();
    let n = usable_n(sampler.as_ref(), n);
    let cfg = ConvergeConfig {
        realizations,
        seed: 17,
        random_placement: false,
    };
    measure(sampler.as_ref(), s.integrand.as_ref(), n, &cfg).unwrap()
}

/// The default suite's edge in `xu` (shear 0.5, offset 0.7) and a cache of 8-set tables under `dir`.
fn xu_edge(dir: &std::path::Path) -> (Subject, TableCache) {
    let mut cfg = config(&[]);
    cfg.analytic = CompareConfig::default_suite().analytic[..1].to_vec();
    cfg.table_sets = 8;
    let subject = subjects(&cfg, dir).unwrap().remove(0);
    assert_eq!(subject.label, "hairline edge in xu");
    (subject, TableCache::new(&cfg, dir))
}

/// How many combined standard errors `a` lies below `b`.
fn z_below(a: &ConvergePoint, b: &ConvergePoint) -> f64 {
    (b.mse - a.mse) / (a.mse_stderr.powi(2) + b.mse_stderr.powi(2)).sqrt()
}

const CLASSICAL: [&str; 5] = [
    "padded-jittered",
    "padded-mj",
    "sobol",
    "padded-pmj02",
    "lattice",
];

/// The MSE of the classical sampler `name` on `subject` at N = 256 with the exact oracle.
fn classical_mse(name: &str, subject: &Subject, tables: &TableCache) -> ConvergePoint {
    mse(
        &SamplerSpec::Classical(name.into()),
        subject,
        256,
        1.0,
        tables,
    )
}

/// On a single-depth (hairline) pixel, oracle-sheared padded MJ beats every classical sampler by more
/// than 3 combined standard errors at N = 256; the wrap-around shear does not.
#[test]
fn sheared_sampling_wins_on_the_hairline_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = config(&["hairline"]);
    let subject = &subjects(&cfg, dir.path()).unwrap()[0];
    let tables = TableCache::new(&cfg, dir.path());
    let sheared = mse(
        &SamplerSpec::Sheared("padded-mj".into(), ShearMode::Transported),
        subject,
        256,
        1.0,
        &tables,
    );
    let wrapped = mse(
        &SamplerSpec::Sheared("padded-mj".into(), ShearMode::Wrap),
        subject,
        256,
        1.0,
        &tables,
    );
    let mut best = f64::INFINITY;
    for name in CLASSICAL {
        let c = classical_mse(name, subject, &tables);
        let z = z_below(&sheared, &c);
        assert!(
            z > 3.0,
            "{name}: {:.3e} ± {:.1e} vs sheared {:.3e} ± {:.1e}",
            c.mse,
            c.mse_stderr,
            sheared.mse,
            sheared.mse_stderr
        );
        best = best.min(c.mse);
    }
    assert!(
        z_below(&sheared, &wrapped) > 3.0,
        "wrap {:.3e} ± {:.1e} vs transported {:.3e} ± {:.1e}",
        wrapped.mse,
        wrapped.mse_stderr,
        sheared.mse,
        sheared.mse_stderr
    );
    eprintln!(
        "hairline pixel, N=256: best classical {best:.3e}, sheared {:.3e} ({:.1}x), wrap {:.3e}",
        sheared.mse,
        best / sheared.mse,
        wrapped.mse
    );
}

/// On a pixel that sees two depths (an in-focus edge over the blurred back wall), shearing by the
/// centre of the fan undoes the x-stratification the in-focus edge needs: oracle-sheared padded MJ is
/// worse than Owen-scrambled Sobol by more than 3 combined standard errors at N = 256. No hairline
/// sampler fits a double wedge; this is the gap the talk's double-wedge patterns are for.
#[test]
fn shearing_loses_on_the_double_wedge_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = config(&["double-wedge"]);
    let subject = &subjects(&cfg, dir.path()).unwrap()[0];
    assert!(
        subject.shear_range.1 - subject.shear_range.0 > 0.1,
        "{:?}",
        subject.shear_range
    );
    let tables = TableCache::new(&cfg, dir.path());
    let sheared = mse(
        &SamplerSpec::Sheared("padded-mj".into(), ShearMode::Transported),
        subject,
        256,
        1.0,
        &tables,
    );
    let sobol = mse(
        &SamplerSpec::Classical("sobol".into()),
        subject,
        256,
        1.0,
        &tables,
    );
    let z = z_below(&sobol, &sheared);
    assert!(
        z > 3.0,
        "sobol {:.3e} ± {:.1e} vs sheared {:.3e} ± {:.1e}",
        sobol.mse,
        sobol.mse_stderr,
        sheared.mse,
        sheared.mse_stderr
    );
}

/// The oracle-sheared 4D rank-1 lattice on the renderer's pixels at N = 1024 (R = 256). On the hairline
/// pixel it beats every classical sampler and sheared Sobol and MJ by more than 3 combined standard
/// errors: 1.2e-7 against 2.6e-7 for sheared Sobol (z = 4.8). On the double-wedge pixel it beats
/// unsheared Sobol by more than 3: 1.1e-6 against 2.2e-6 (z = 5.0). Reported, not asserted: it is
/// below the unsheared lattice there by z = 2.1 only (1.4e-6), and below the double-wedge and
/// widened-hairline tables (8 sets, built in a run of this test) by z = 2.9 and 4.0. Its gains vary
/// with N: on the double-wedge pixel at N = 256 it is worse than Sobol (1.7e-5 against 1.2e-5 in the
/// default compare).
#[test]
fn sheared_lattice_on_the_pixels() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = config(&["hairline", "double-wedge"]);
    let found = subjects(&cfg, dir.path()).unwrap();
    let (hairline, wedge) = (&found[0], &found[1]);
    let tables = TableCache::new(&cfg, dir.path());
    let n = 1024;
    let lattice = SamplerSpec::Sheared("lattice".into(), ShearMode::Transported);
    let rivals: Vec<SamplerSpec> = CLASSICAL
        .iter()
        .map(|s| SamplerSpec::Classical(s.to_string()))
        .chain(
            ["sobol", "padded-mj"].map(|s| SamplerSpec::Sheared(s.into(), ShearMode::Transported)),
        )
        .collect();
    let t = mse(&lattice, hairline, n, 1.0, &tables);
    for rival in &rivals {
        let c = mse(rival, hairline, n, 1.0, &tables);
        let z = z_below(&t, &c);
        eprintln!(
            "hairline pixel N={n}: sheared lattice {:.3e} ± {:.1e}, {} {:.3e} (z = {z:.1})",
            t.mse,
            t.mse_stderr,
            rival.label(),
            c.mse
        );
        assert!(z > 3.0, "{}", rival.label());
    }
    let t = mse(&lattice, wedge, n, 1.0, &tables);
    let z_against = |name: &str| {
        let c = mse(&SamplerSpec::Classical(name.into()), wedge, n, 1.0, &tables);
        let z = z_below(&t, &c);
        eprintln!(
            "double-wedge pixel N={n}: sheared lattice {:.3e} ± {:.1e}, {name} {:.3e} (z = {z:.1})",
            t.mse, t.mse_stderr, c.mse
        );
        z
    };
    assert!(z_against("sobol") > 3.0);
    // Reported only (z = 2.1 measured).
    z_against("lattice");
}

/// Robustness to the oracle: off by 25 %, the sheared hairline loses most of its gain on the
/// single-depth pixel (N = 256), yet stays ahead of the classical samplers there by more than 3
/// combined standard errors, but for the lattice, which it is ahead of by only 2.4 (25 % low) and 3.5
/// (25 % high) standard errors (9.5e-6 and 7.8e-6 against 1.3e-5 ± 1.3e-6; sobol 2.0e-5, z ≥ 5.4).
#[test]
fn sheared_hairline_degrades_with_oracle_error() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = config(&["hairline"]);
    let subject = &subjects(&cfg, dir.path()).unwrap()[0];
    let tables = TableCache::new(&cfg, dir.path());
    let spec = SamplerSpec::Sheared("padded-mj".into(), ShearMode::Transported);
    let exact = mse(&spec, subject, 256, 1.0, &tables);
    let classical: Vec<(&str, ConvergePoint)> = CLASSICAL
        .iter()
        .map(|&name| (name, classical_mse(name, subject, &tables)))
        .collect();
    for scale in [0.75, 1.25] {
        let off = mse(&spec, subject, 256, scale, &tables);
        assert!(
            z_below(&exact, &off) > 3.0,
            "x{scale}: {:.3e} ± {:.1e} vs exact {:.3e} ± {:.1e}",
            off.mse,
            off.mse_stderr,
            exact.mse,
            exact.mse_stderr
        );
        // The lattice, the strongest classical sampler here, is not told apart (z = 2.4 and 3.5
        // measured): reported only.
        for (name, c) in &classical {
            let z = z_below(&off, c);
            assert!(
                *name == "lattice" || z > 3.0,
                "x{scale} against {name}: {:.3e} ± {:.1e} vs {:.3e} ± {:.1e}, z = {z:.1}",
                off.mse,
                off.mse_stderr,
                c.mse,
                c.mse_stderr,
            );
        }
    }
}

/// The widened hairline keeps its gain where the sheared hairline loses it: on the xu edge of shear
/// 0.5 with the oracle's shear 10 % too large, the widened-hairline table (targets/
/// widened-hairline.toml, moved by the same wrong shear) has a lower MSE than seam-free sheared padded
/// MJ by more than 3 combined standard errors, and the sheared MJ hairline is itself worse than with
/// the exact shear by more than 3 (its gain is lost). With the oracle 25 % too large, the band itself
/// counts: the widened table beats the optimized hairline table (targets/hairline.toml, the same
/// centred strata without the opening band) by more than 3. Measured (8-set tables, R = 1024):
/// 2.1e-6 ± 1e-7 against 3.6e-6 ± 1.5e-7, z = 8.1.
#[test]
fn widened_hairline_survives_oracle_error() {
    let dir = tempfile::tempdir().unwrap();
    let (subject, tables) = xu_edge(dir.path());
    let subject = &subject;
    let table = SamplerSpec::Table("targets/widened-hairline.toml".into());
    let hairline = SamplerSpec::Sheared("padded-mj".into(), ShearMode::Transported);
    let n = 1024;
    let h_exact = mse(&hairline, subject, n, 1.0, &tables);
    let (t_off, h_off) = (
        mse(&table, subject, n, 1.1, &tables),
        mse(&hairline, subject, n, 1.1, &tables),
    );
    let z = z_below(&t_off, &h_off);
    eprintln!(
        "N={n}: hairline exact {:.3e}; +10 %: table {:.3e} ± {:.1e} / hairline {:.3e} ± {:.1e} (z = {z:.1})",
        h_exact.mse, t_off.mse, t_off.mse_stderr, h_off.mse, h_off.mse_stderr
    );
    assert!(z > 3.0);
    assert!(z_below(&h_exact, &h_off) > 3.0);
    let band = SamplerSpec::Table("targets/hairline.toml".into());
    let (t_far, b_far) = (
        mse_over(&table, subject, n, 1.25, &tables, GAIN_REALIZATIONS),
        mse_over(&band, subject, n, 1.25, &tables, GAIN_REALIZATIONS),
    );
    let z = z_below(&t_far, &b_far);
    eprintln!(
        "N={n}, +25 %: widened {:.3e} ± {:.1e} / hairline table {:.3e} ± {:.1e} (z = {z:.1})",
        t_far.mse, t_far.mse_stderr, b_far.mse, b_far.mse_stderr
    );
    assert!(z > 3.0);
}

/// The oracle's error swept from −25 % to +25 % in steps of 2.5 % (compare's default sweep) on the xu
/// edge of shear 0.5 at N = 1024: the widened-hairline table has the lowest worst case of the samplers
/// that follow the oracle, and a sheared rank-1 lattice, best at ±10 % and ±25 %, has a spike between
/// them that the Fourier-domain prediction of DESIGN §4 finds.
///
/// Asserted, with more than 3 combined standard errors each:
/// - the widened table's worst MSE over the sweep is below the worst of the optimized hairline table,
///   of sheared padded MJ, of sheared Owen-scrambled Sobol and of the sheared 4D lattice;
/// - the sheared lattice's MSE at +22.5 % is above 3 times its MSE at +25 %, and not below the
///   variance its dual lattice predicts there from the |ĝ|² of the integrand seen through the erred
///   shear (`lattice_design::dual_sum` over |k| < 512: a lower bound, since every term left out is
///   positive).
///
/// Measured (R = 1024, 8-set tables): worst over the sweep 2.12e-6 ± 1e-7 for the widened table (at
/// +25 %), 3.60e-6 for the hairline table (z = 8.1), 2.04e-5 for sheared MJ, 3.09e-6 for sheared Sobol
/// (z = 5.6), 1.35e-5 for the sheared lattice at +22.5 % (in-grid prediction 1.33e-5; 4.98e-7 at
/// +25 %). The widened table keeps 2.3× of its 30× gain over the best classical sampler (the unsheared
/// lattice, 4.92e-6) in the worst case.
#[test]
fn widened_hairline_has_the_lowest_worst_case_over_the_sweep() {
    use anisospec::optimize::lattice_design::dual_sum;
    use anisospec::samplers::lattice::generating_vector;
    use anisospec::targets::Variance;
    let dir = tempfile::tempdir().unwrap();
    let (subject, tables) = xu_edge(dir.path());
    let subject = &subject;
    let n = 1024;
    let errors: Vec<f64> = (-10..=10)
        .filter(|&i| i != 0)
        .map(|i| f64::from(i) / 40.0)
        .collect();
    let sweep = |spec: &SamplerSpec| -> Vec<(f64, ConvergePoint)> {
        errors
            .iter()
            .map(|&e| {
                (
                    e,
                    mse_over(spec, subject, n, 1.0 + e, &tables, GAIN_REALIZATIONS),
                )
            })
            .collect()
    };
    let worst = |points: &[(f64, ConvergePoint)]| {
        points
            .iter()
            .max_by(|a, b| a.1.mse.total_cmp(&b.1.mse))
            .cloned()
            .unwrap()
    };
    let widened = worst(&sweep(&SamplerSpec::Table(
        "targets/widened-hairline.toml".into(),
    )));
    eprintln!(
        "widened: worst {:.3e} ± {:.1e} at {:+}",
        widened.1.mse, widened.1.mse_stderr, widened.0
    );
    // The sheared lattice last: its sweep also holds the spike checked below.
    let sweeps: Vec<(String, Vec<(f64, ConvergePoint)>)> = [
        SamplerSpec::Table("targets/hairline.toml".into()),
        SamplerSpec::Sheared("padded-mj".into(), ShearMode::Transported),
        SamplerSpec::Sheared("sobol".into(), ShearMode::Transported),
        SamplerSpec::Sheared("lattice".into(), ShearMode::Transported),
    ]
    .iter()
    .map(|spec| (spec.label(), sweep(spec)))
    .collect();
    let mut failures = Vec::new();
    for (label, points) in &sweeps {
        let (e, p) = worst(points);
        let z = z_below(&widened.1, &p);
        eprintln!(
            "{label}: worst {:.3e} ± {:.1e} at {e:+} (z = {z:.1})",
            p.mse, p.mse_stderr,
        );
        if z <= 3.0 {
            failures.push(label.clone());
        }
    }
    assert!(failures.is_empty(), "worst case not beaten: {failures:?}");

    // The sweep's last two errors, +22.5 % and +25 %.
    let lattice = &sweeps.last().expect("four sweeps").1;
    let [(spike_error, spike), (_, beside)] = &lattice[errors.len() - 2..] else {
        unreachable!("the sweep ends at +22.5 %, +25 %")
    };
    let z_spike = (spike.mse - 3.0 * beside.mse)
        / (spike.mse_stderr.powi(2) + 9.0 * beside.mse_stderr.powi(2)).sqrt();
    let seen = Variance {
        integrand: "sheared:s=0.5,c=0.7".into(),
        shear: subject.shear.0 * (1.0 + spike_error),
        placements: Some(0),
        shear_error: None,
        extent: 1.0,
        weight: None,
        design: None,
    };
    let res = 1024;
    let xu_multiplier = generating_vector(n, 4)[2];
    let predicted = dual_sum(&seen.spectrum(res).unwrap(), res, n, xu_multiplier);
    eprintln!(
        "sheared lattice: +22.5 % {:.3e} ± {:.1e} (in-grid prediction {predicted:.3e}), +25 % {:.3e} ± {:.1e}",
        spike.mse, spike.mse_stderr, beside.mse, beside.mse_stderr
    );
    assert!(z_spike > 3.0, "no spike: z = {z_spike:.1}");
    assert!(
        spike.mse + 3.0 * spike.mse_stderr >= predicted,
        "below its lower bound"
    );
}

/// Realizations per MSE in the gain tests: 1024 puts the standard error of a gain near 6 %.
const GAIN_REALIZATIONS: usize = 1024;

/// The ratio `b / a` of two MSEs and its standard error (first-order propagation).
fn gain(a: &ConvergePoint, b: &ConvergePoint) -> (f64, f64) {
    let r = b.mse / a.mse;
    let rel = ((a.mse_stderr / a.mse).powi(2) + (b.mse_stderr / b.mse).powi(2)).sqrt();
    (r, r * rel)
}

/// Issue 5, widened hairline: on the xu edge of shear 0.5 with the oracle's shear off by ±5 % and
/// ±20 %, the widened-hairline table (shipped target, 8 sets, moved by the wrong shear) against
/// jittered sampling (unsheared: padded-jittered, and jittered on the xu plane itself, xuyv-jittered)
/// and the transported-sheared hairlines (padded MJ, MJ on xu, N-rooks on xu) at N = 64, 256, 1024.
///
/// Asserted: the table beats both jittered samplers by more than 3 combined standard errors at every N
/// and error; at N = 1024 it beats every sheared hairline by more than 3 as well, and its gain over
/// jittered on the xu plane at ±5 % exceeds the goal of 5 by more than 2 standard errors of the
/// ratio. Measured (seeds fixed, R = 1024, edge offset c = 0.7, Sobol start): at N = 1024, 9.7–9.8×
/// over xuyv-jittered and 43× over padded-jittered at ±5 % (7.1–7.5× and 32–33× at ±20 %), 2.1–9.2×
/// over the sheared hairlines; at N = 256, 1.4–3.8× over them; at N = 64, where these errors do not
/// break the hairlines yet, 1.23–1.55×, which is not asserted. (The band before, opening for 5 % only,
/// gave 4.1–4.6× and 18–20× at ±20 %.)
///
/// Rates, issue 6's "keeps its gain where the hairline loses it": from N = 256 to 1024 sheared
/// padded MJ falls from its exact-oracle rate (MSE ∝ N^-2.00 ± 0.04) back to random sampling's -1
/// at every error (-0.98 to -1.06 ± 0.04), while the table keeps -1.56 to -1.63 ± 0.05 of its
/// -2.09 ± 0.05: 52-58 % of its rate's gain over -1, the hairline -2 to 6 %. Asserted, by more than 3
/// combined standard errors each, at every error: the hairline's rate is shallower than with the
/// exact oracle, the table's is steeper than the hairline's and steeper than -1. Asymptotically, half
/// is what a set with a smooth spectrum robust to a range of errors can keep (README, "Rates under
/// oracle error"), and the shares vary with the seed by about 5 % (45-66 % and 0-18 % over seeds
/// 1-4), so "most" is not asserted.
///
/// Reported, not asserted: sheared rank-1 lattices, outside the list. They beat the table at
/// nearly every N and error here. The table's gain over the lattice on the xu plane (`xuyv-lattice`) is
/// 0.22–0.44× at N = 1024, 0.31–0.46× at 256 and 0.33–1.00× at 64; over the 4D Korobov lattice
/// (`lattice`), 0.22–0.58×, 0.31–0.42× and 0.49–1.27×. Their dual lattices leave the erred edge's line
/// dark out to about 2 sqrt(N); past that it meets isolated dual points, not a spectrum near 1.
#[test]
fn widened_hairline_gains_under_oracle_error() {
    let dir = tempfile::tempdir().unwrap();
    let (subject, tables) = xu_edge(dir.path());
    let subject = &subject;
    let table = SamplerSpec::Table("targets/widened-hairline.toml".into());
    let jittered = ["padded-jittered", "xuyv-jittered"].map(|s| SamplerSpec::Classical(s.into()));
    let hairlines = ["padded-mj", "xuyv-mj", "xuyv-nrooks"]
        .map(|s| SamplerSpec::Sheared(s.into(), ShearMode::Transported));
    let lattices =
        ["xuyv-lattice", "lattice"].map(|s| SamplerSpec::Sheared(s.into(), ShearMode::Transported));
    let mut failures = Vec::new();
    // The table's and sheared padded MJ's points at N = 256 and 1024, per error (0 for the exact
    // oracle), for their local rates.
    let mut rated: Vec<(usize, f64, ConvergePoint, ConvergePoint)> = Vec::new();
    for n in [256, 1024] {
        rated.push((
            n,
            0.0,
            mse_over(&table, subject, n, 1.0, &tables, GAIN_REALIZATIONS),
            mse_over(&hairlines[0], subject, n, 1.0, &tables, GAIN_REALIZATIONS),
        ));
    }
    for n in [64, 256, 1024] {
        let jit: Vec<ConvergePoint> = jittered
            .iter()
            .map(|j| mse_over(j, subject, n, 1.0, &tables, GAIN_REALIZATIONS))
            .collect();
        for error in [-0.2, -0.05, 0.05, 0.2] {
            let t = mse_over(&table, subject, n, 1.0 + error, &tables, GAIN_REALIZATIONS);
            let mut line = format!(
                "N={n} error {error:+}: table {:.3e} ± {:.1e}",
                t.mse, t.mse_stderr
            );
            for (spec, p) in jittered.iter().zip(&jit) {
                let (g, se) = gain(&t, p);
                line += &format!(" | vs {} {g:.2}±{se:.2}", spec.label());
                if z_below(&t, p) <= 3.0 {
                    failures.push(format!("N={n} error {error:+}: {}", spec.label()));
                }
                if n == 1024
                    && error.abs() == 0.05
                    && spec.label() == "xuyv-jittered"
                    && g - 2.0 * se <= 5.0
                {
                    failures.push(format!("N={n} error {error:+}: 5x over {}", spec.label()));
                }
            }
            for h in &hairlines {
                let p = mse_over(h, subject, n, 1.0 + error, &tables, GAIN_REALIZATIONS);
                if h == &hairlines[0] && n >= 256 {
                    rated.push((n, error, t.clone(), p.clone()));
                }
                let (g, se) = gain(&t, &p);
                line += &format!(" | vs {} {g:.2}±{se:.2}", h.label());
                // Every sheared hairline, as documented above (xuyv-mj was left out here without a
                // word; measured at N = 1024: 2.09–2.79× over it, z ≈ 10 or more).
                if n == 1024 && z_below(&t, &p) <= 3.0 {
                    failures.push(format!("N={n} error {error:+}: {}", h.label()));
                }
            }
            for lattice in &lattices {
                let p = mse_over(lattice, subject, n, 1.0 + error, &tables, GAIN_REALIZATIONS);
                let (g, se) = gain(&t, &p);
                line += &format!(" | (reported) vs {} {g:.2}±{se:.2}", lattice.label());
            }
            eprintln!("{line}");
        }
    }
    // Rates from N = 256 to 1024: the sheared hairline's falls back towards random sampling's -1 at
    // every error, the widened table's stays steeper than the hairline's and than -1.
    let rate = |error: f64, of_table: bool| {
        let at = |n: usize| {
            let (_, _, t, h) = rated.iter().find(|r| r.0 == n && r.1 == error).unwrap();
            if of_table {
                t.clone()
            } else {
                h.clone()
            }
        };
        local_rate(&at(256), &at(1024))
    };
    let (t_exact, h_exact) = (rate(0.0, true), rate(0.0, false));
    eprintln!(
        "rate 256 -> 1024, exact oracle: table {:.2} ± {:.2}, sheared padded MJ {:.2} ± {:.2}",
        t_exact.0, t_exact.1, h_exact.0, h_exact.1
    );
    for error in [-0.2, -0.05, 0.05, 0.2] {
        let (t, h) = (rate(error, true), rate(error, false));
        let kept = |r: (f64, f64), exact: (f64, f64)| (r.0 + 1.0) / (exact.0 + 1.0);
        eprintln!(
            "rate 256 -> 1024, error {error:+}: table {:.2} ± {:.2} (keeps {:.0} % of its rate's \
             gain over -1), sheared padded MJ {:.2} ± {:.2} (keeps {:.0} %)",
            t.0,
            t.1,
            100.0 * kept(t, t_exact),
            h.0,
            h.1,
            100.0 * kept(h, h_exact)
        );
        let z = |a: (f64, f64), b: (f64, f64)| (b.0 - a.0) / a.1.hypot(b.1);
        if z(h_exact, h) <= 3.0 {
            failures.push(format!(
                "error {error:+}: the sheared hairline keeps its rate"
            ));
        }
        if z(t, h) <= 3.0 {
            failures.push(format!(
                "error {error:+}: rate not steeper than the hairline's"
            ));
        }
        if z(t, (-1.0, 0.0)) <= 3.0 {
            failures.push(format!("error {error:+}: rate not steeper than -1"));
        }
    }
    assert!(failures.is_empty(), "not beaten: {failures:?}");
}

/// The local rate from `a` to `b` (`MSE ∝ N^rate` between their N) and its standard error, from the
/// MSEs' relative standard errors (first order; the two sets of realizations are independent).
fn local_rate(a: &ConvergePoint, b: &ConvergePoint) -> (f64, f64) {
    let steps = (b.n as f64 / a.n as f64).ln();
    let rate = (b.mse / a.mse).ln() / steps;
    let se = (a.mse_stderr / a.mse).hypot(b.mse_stderr / b.mse) / steps;
    (rate, se)
}

/// Issue 5, double wedge: on the fan of edges with shears in [0.3, 0.7] (its double wedge is the
/// target's), two tables of 8 sets moved by the middle shear 0.5 — the double-wedge shape
/// (`targets/double-wedge.toml`) and the fans' predicted variance (`targets/fan-variance.toml`, fans
/// at random offsets) — against the classical samplers: jittered, Owen-scrambled Sobol and PMJ02
/// (padded, 4D, and on the xu plane itself), and transported-sheared MJ, Sobol and PMJ02, at N = 64,
/// 256, 1024.
///
/// The same family as a lattice design (`targets/fan-lattice.toml`: the rank-1 lattice whose dual
/// carries the least of the fans' energy) is the third table.
///
/// Asserted: at N = 256 and 1024 all three tables beat every one of them by more than 3 combined
/// standard errors, at N = 1024 the variance table's gain over the list (jittered, Sobol,
/// PMJ02, sheared MJ) is above 3 by more than 2 standard errors, and the lattice design beats the
/// lattices below by more than 3. Measured for the lattice design: 1.43e-7 at N = 1024, 4.74 ± 0.29×
/// over sheared MJ, 2.57× and 2.69× over sheared Sobol and PMJ02, 1.61× and 1.98× over the 4D lattice
/// unsheared and sheared (N = 256: 2.24e-6, 3.56×, 2.39×, 2.24×, 1.60×, 1.06×). Measured for the
/// other two (R = 1024, fan offset c = 0.7, Sobol start): the variance table 1.88e-7, 3.61 ± 0.23× over sheared MJ on the xu plane (the best
/// of the list), 4.2–6.0× over unsheared Sobol (4D and on the xu plane) and PMJ02 on the xu
/// plane (193× over padded PMJ02); 1.95× and 2.04× over sheared Sobol and PMJ02 on the xu plane,
/// stronger baselines than the issue asks for (N = 256: 2.96×, 1.99×, 1.87×; N = 64: 2.46×, 2.09×,
/// 2.28×). The double-wedge shape table: 2.53 ± 0.16× over sheared MJ,
/// 1.37× and 1.43× over sheared Sobol and PMJ02 (N = 256: 2.37×, 1.59×, 1.50×).
///
/// Reported, not asserted: rank-1 lattices, outside the list. The shape table's gain over the
/// lattice on the xu plane (`xuyv-lattice`) is 1.50/1.44/1.67× unsheared and 0.64/0.82/1.17× sheared
/// at N = 64, 256, 1024; over the 4D Korobov lattice (`lattice`), 4.85/1.07/0.86× unsheared and
/// 0.66/0.71/1.06× sheared. The variance table's: 2.14/1.80/2.38× and 0.91/1.03/1.68× over the 2D
/// lattice, 6.92/1.33/1.23× and 0.94/0.88/1.51× over the 4D one. A lattice's spectrum is 0 off its
/// dual lattice, whose nearest points lie about sqrt(N) out, so it darkens far more of the wedge than
/// a spectrum held near 1 outside its dark region can; how much depends on how the dual lattice sits
/// against the wedge, which varies with N. The variance target asks for no flat part and lets the
/// sets put their energy where the fans have little.
#[test]
fn double_wedge_gains_on_the_fan() {
    let dir = tempfile::tempdir().unwrap();
    let mut cfg = config(&[]);
    cfg.analytic = CompareConfig::default_suite().analytic[1..2].to_vec();
    cfg.table_sets = 8;
    let subject = &subjects(&cfg, dir.path()).unwrap()[0];
    assert_eq!(subject.label, "double-wedge fan in xu");
    let tables = TableCache::new(&cfg, dir.path());
    let table = SamplerSpec::Table("targets/double-wedge.toml".into());
    let mut classical: Vec<SamplerSpec> = [
        "padded-jittered",
        "xuyv-jittered",
        "sobol",
        "xuyv-sobol",
        "padded-pmj02",
        "xuyv-pmj02",
    ]
    .map(|s| SamplerSpec::Classical(s.into()))
    .to_vec();
    classical.extend(
        ["padded-mj", "xuyv-mj", "xuyv-sobol", "xuyv-pmj02"]
            .map(|s| SamplerSpec::Sheared(s.into(), ShearMode::Transported)),
    );
    let reported = [
        SamplerSpec::Classical("xuyv-lattice".into()),
        SamplerSpec::Sheared("xuyv-lattice".into(), ShearMode::Transported),
        SamplerSpec::Classical("lattice".into()),
        SamplerSpec::Sheared("lattice".into(), ShearMode::Transported),
    ];
    let variance = SamplerSpec::Table("targets/fan-variance.toml".into());
    let lattice_design = SamplerSpec::Table("targets/fan-lattice.toml".into());
    for n in [64, 256, 1024] {
        let t = mse_over(&table, subject, n, 1.0, &tables, GAIN_REALIZATIONS);
        let v = mse_over(&variance, subject, n, 1.0, &tables, GAIN_REALIZATIONS);
        let l = mse_over(&lattice_design, subject, n, 1.0, &tables, GAIN_REALIZATIONS);
        let mut line = format!(
            "N={n}: table {:.3e} ± {:.1e}, variance table {:.3e} ± {:.1e}, lattice design {:.3e} ± {:.1e}",
            t.mse, t.mse_stderr, v.mse, v.mse_stderr, l.mse, l.mse_stderr
        );
        let mut failures = Vec::new();
        for c in &classical {
            let p = mse_over(c, subject, n, 1.0, &tables, GAIN_REALIZATIONS);
            let (g, se) = gain(&t, &p);
            let (gv, sev) = gain(&v, &p);
            line += &format!(
                " | vs {} {g:.2}±{se:.2} (variance table {gv:.2}±{sev:.2})",
                c.label()
            );
            if n >= 256 && z_below(&t, &p) <= 3.0 {
                failures.push(c.label());
            }
            if n >= 256 && z_below(&v, &p) <= 3.0 {
                failures.push(format!("variance table vs {}", c.label()));
            }
            let stronger = matches!(c, SamplerSpec::Sheared(name, _) if name != "padded-mj" && name != "xuyv-mj");
            if n == 1024 && !stronger && gv - 2.0 * sev <= 3.0 {
                failures.push(format!("variance table 3x over {}", c.label()));
            }
            let (gl, sel) = gain(&l, &p);
            line += &format!(" (lattice design {gl:.2}±{sel:.2})");
            if n >= 256 && z_below(&l, &p) <= 3.0 {
                failures.push(format!("lattice design vs {}", c.label()));
            }
        }
        for c in &reported {
            let p = mse_over(c, subject, n, 1.0, &tables, GAIN_REALIZATIONS);
            let (g, se) = gain(&t, &p);
            let (gv, sev) = gain(&v, &p);
            let (gl, sel) = gain(&l, &p);
            line += &format!(
                " | (reported) vs {} {g:.2}±{se:.2} (variance table {gv:.2}±{sev:.2}, lattice design {gl:.2}±{sel:.2})",
                c.label()
            );
            if n == 1024 && z_below(&l, &p) <= 3.0 {
                failures.push(format!("lattice design vs {}", c.label()));
            }
        }
        eprintln!("{line}");
        assert!(failures.is_empty(), "{line}: not beaten: {failures:?}");
    }
}

/// Optimized tables on the renderer's pixels (N = 256, tables of 8 sets): on the hairline pixel the
/// widened-hairline table beats every classical sampler by more than 3 combined standard errors, and
/// with the oracle's shear 25 % too small it still beats them all. On the double-wedge pixel (shears
/// -0.71 to 0: an in-focus edge over the blurred wall) the double-wedge table, designed in the frame of
/// the in-focus layer (`tables::frame_shear`), beats the sheared MJ hairline by more than 3 and is not
/// worse than unsheared Sobol, the best of the classical samplers there (the 4D lattice is 1.3×
/// lower still), by more than 3. Measured in the default
/// compare run at N = 1024: 0.92× Sobol's MSE, where a table moved by the range's centre gave 0.43×.
#[test]
fn optimized_tables_on_the_renderer_pixels() {
    let dir = tempfile::tempdir().unwrap();
    let mut cfg = config(&["hairline", "double-wedge"]);
    cfg.table_sets = 8;
    let found = subjects(&cfg, dir.path()).unwrap();
    let (hairline, wedge) = (&found[0], &found[1]);
    let tables = TableCache::new(&cfg, dir.path());
    let n = 256;
    let widened = SamplerSpec::Table("targets/widened-hairline.toml".into());
    for scale in [1.0, 0.75] {
        let t = mse(&widened, hairline, n, scale, &tables);
        for name in CLASSICAL {
            let c = mse(
                &SamplerSpec::Classical(name.into()),
                hairline,
                n,
                1.0,
                &tables,
            );
            let z = z_below(&t, &c);
            eprintln!(
                "hairline pixel N={n}, shear x{scale}: table {:.3e} ± {:.1e}, {name} {:.3e} (z = {z:.1})",
                t.mse, t.mse_stderr, c.mse
            );
            assert!(z > 3.0);
        }
    }
    let table = mse(
        &SamplerSpec::Table("targets/double-wedge.toml".into()),
        wedge,
        n,
        1.0,
        &tables,
    );
    let sheared = mse(
        &SamplerSpec::Sheared("padded-mj".into(), ShearMode::Transported),
        wedge,
        n,
        1.0,
        &tables,
    );
    let sobol = mse(
        &SamplerSpec::Classical("sobol".into()),
        wedge,
        n,
        1.0,
        &tables,
    );
    let (z, z_sobol) = (z_below(&table, &sheared), z_below(&table, &sobol));
    eprintln!(
        "double-wedge pixel N={n}: table {:.3e} ± {:.1e}, sheared MJ {:.3e} ± {:.1e} (z = {z:.1}), \
         sobol {:.3e} ± {:.1e} (z = {z_sobol:.1})",
        table.mse, table.mse_stderr, sheared.mse, sheared.mse_stderr, sobol.mse, sobol.mse_stderr
    );
    assert!(z > 3.0);
    assert!(z_sobol > -3.0);
}

/// The studies shipped in `targets/studies/` (the README's figures that the default suite does not
/// make) load and pass every check compare makes before any work, their tables included, when run
/// from the repository's root as their comments say.
#[test]
fn shipped_studies_load() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut loaded = Vec::new();
    for entry in std::fs::read_dir(root.join("targets/studies")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let study = CompareConfig::load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(!study.tables.is_empty(), "{}", path.display());
            loaded.push(path);
        }
    }
    assert_eq!(loaded.len(), 3, "{loaded:?}");
}
