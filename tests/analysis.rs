//! Issue 3 "Must show": convergence rates, prediction against measurement, directional cones, bad input.

use anisospec::converge::{converge, measure, ConvergeConfig};
use anisospec::integrands::{parse, Integrand};
use anisospec::rng::Rng;
use anisospec::samplers::Sampler;
use anisospec::spectrum::Method;
use anisospec::variance::{predict, VarianceConfig};
use rand::seq::SliceRandom;
use rand::Rng as _;

struct Local(&'static str);
impl Sampler for Local {
    fn name(&self) -> String {
        self.0.into()
    }
    fn dims(&self) -> usize {
        2
    }
    fn check_n(&self, _n: usize) -> Result<(), usize> {
        Ok(())
    }
    fn generate(&self, n: usize, rng: &mut Rng) -> Vec<f64> {
        let mut out = Vec::with_capacity(2 * n);
        match self.0 {
            "random" => (0..2 * n).for_each(|_| out.push(rng.random::<f64>())),
            "jittered" => {
                let m = (n as f64).sqrt() as usize;
                for i in 0..m {
                    for j in 0..m {
                        out.push((j as f64 + rng.random::<f64>()) / m as f64);
                        out.push((i as f64 + rng.random::<f64>()) / m as f64);
                    }
                }
            }
            _ => {
                let mut p: Vec<usize> = (0..n).collect();
                p.shuffle(rng);
                for (j, pj) in p.iter().enumerate() {
                    out.push((*pj as f64 + rng.random::<f64>()) / n as f64);
                    out.push((j as f64 + rng.random::<f64>()) / n as f64);
                }
            }
        }
        out
    }
}

fn sampler(name: &'static str) -> Box<dyn Sampler> {
    Box::new(Local(name))
}

const NS: [usize; 5] = [16, 64, 256, 1024, 4096];

#[test]
fn explore_rates() {
    for f in ["step:theta=0", "step:theta=30", "disc", "gaussian"] {
        let f = parse(f).unwrap();
        for s in ["random", "jittered", "nrooks"] {
            let cfg = ConvergeConfig { realizations: 256, seed: 7, random_placement: false };
            let t = std::time::Instant::now();
            let c = converge(sampler(s).as_ref(), f.as_ref(), &NS, &cfg, |_| {}).unwrap();
            let fit = c.fit.unwrap();
            eprintln!("{:>14} {:>9}: slope {:.3} ± {:.3} chi2 {:.2} ({:.2}s) mse {:?}", f.name(), s, fit.slope, fit.stderr, fit.chi2_per_dof, t.elapsed().as_secs_f64(),
                c.points.iter().map(|p| format!("{:.2e}", p.mse)).collect::<Vec<_>>());
        }
    }
}

#[test]
fn explore_prediction() {
    for f in ["gaussian"] {
        let f = parse(f).unwrap();
        for s in ["jittered"] {
            for (i, &n) in [64usize; 3].iter().enumerate() {
                let vc = VarianceConfig { res: 32, res_per_n: Some(8), realizations: 4000, cones: 4, seed: 11+7*i as u64, method: Method::Exact };
                let t = std::time::Instant::now();
                let p = predict(sampler(s).as_ref(), f.as_ref(), &[n], &vc).unwrap();
                let tp = t.elapsed().as_secs_f64();
                let m = measure(sampler(s).as_ref(), f.as_ref(), n, &ConvergeConfig { realizations: 20000, seed: 12+7*i as u64, random_placement: false }).unwrap();
                let pp = &p.points[0];
                let z = (pp.variance - m.mse) / (pp.stderr.powi(2) + m.mse_stderr.powi(2)).sqrt();
                eprintln!("{:>14} {:>9} N={n}: pred {:.4e} ± {:.1e} (tail {:.2e}) meas {:.4e} ± {:.1e} z={z:.2} ({tp:.2}s)", f.name(), s, pp.variance, pp.stderr, pp.tail.unwrap(), m.mse, m.mse_stderr);
            }
        }
    }
}

#[test]
fn explore_cones() {
    for (f, res, per) in [("step:theta=0", 32, Some(8)), ("step:theta=30", 64, None)] {
        let f = parse(f).unwrap();
        let vc = VarianceConfig { res, res_per_n: per, realizations: 100, cones: 4, seed: 3, method: Method::Exact };
        let t = std::time::Instant::now();
        let p = predict(sampler("nrooks").as_ref(), f.as_ref(), &[16, 64, 256, 1024], &vc).unwrap();
        for pt in &p.points {
            eprintln!("{} N={} var {:.3e} grid {:.3e} tail {:.3e} cones {:?}", f.name(), pt.n, pt.variance, pt.grid, pt.tail.unwrap(), pt.cones.iter().map(|c| format!("{:.2}", c / pt.grid)).collect::<Vec<_>>());
        }
        eprintln!("fits {:?} total {:?} ({:.2}s)", p.cone_fits.iter().map(|f| f.map(|f| (f.slope, f.stderr))).collect::<Vec<_>>(), p.fit.map(|f| f.slope), t.elapsed().as_secs_f64());
    }
}

#[test]
fn explore_measure() {
    let f = parse("gaussian").unwrap();
    let vf = f.mean_square().unwrap() - f.reference().value.powi(2);
    for s in ["random", "jittered"] {
        for seed in [1u64, 2] {
            let m = measure(sampler(s).as_ref(), f.as_ref(), 64, &ConvergeConfig { realizations: 400000, seed, random_placement: false }).unwrap();
            eprintln!("{s} seed {seed}: mse {:.5e} ± {:.1e} mean err {:.2e} (random theory {:.5e})", m.mse, m.mse_stderr, m.mean_error, vf / 64.0);
        }
    }
}
