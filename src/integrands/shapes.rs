//! The 2D integrand families: periodic Gaussian, disc, half-plane steps (oriented or sheared) and the
//! fan of sheared edges. Coordinates are `(x1, x2)` of `[0,1)²`; placed on a 4D projection by
//! [`super::compose::Embed`], `(x1, x2)` become e.g. `(x, u)`.

use super::polygon;
use super::{Integrand, Reference};
use crate::error::{number, Error, Result};
use crate::points::shear::MAX_SHEAR;
use crate::points::wrap;
use crate::quad;
use crate::rng::Rng;
use rand::Rng as _;
use rustfft::num_complex::Complex64;
use std::f64::consts::PI;

fn finite(name: &str, key: &str, v: f64) -> Result<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::Usage(format!(
            "{name}: {key}={v} is not a finite number"
        )))
    }
}

/// `v` if it is a shear of magnitude at most [`MAX_SHEAR`] (beyond it the edges' integrals lose
/// their precision).
fn shear(name: &str, key: &str, v: f64) -> Result<f64> {
    if finite(name, key, v)?.abs() <= MAX_SHEAR {
        Ok(v)
    } else {
        Err(Error::Usage(format!(
            "{name}: {key}={} is beyond the largest shear, {MAX_SHEAR:e}; give a shear of magnitude at most that",
            number(v)
        )))
    }
}

/// `exp(−2πi k·c)`, with `k·c` reduced mod 1 first.
fn phase(k: [i64; 2], c: [f64; 2]) -> Complex64 {
    crate::spectrum::exact::turn(k[0] as f64 * c[0] + k[1] as f64 * c[1])
}

fn k2(k: &[i64]) -> [i64; 2] {
    [k[0], k[1]]
}

/// A Gaussian bump of width `sigma`, centred at `centre` and made periodic on the torus (the sum of its
/// images), so that it is smooth on the torus: `f(x) = Σ_m exp(−|x − c − m|² / (2σ²))`. Each image
/// peaks at 1; for a wide `sigma` the images overlap and the sum exceeds 1.
///
/// Integral `2πσ²`; `f̂(k) = 2πσ² exp(−2π²σ²|k|²) exp(−2πi k·c)`: both exact.
#[derive(Clone, Debug)]
pub struct Gaussian {
    sigma: f64,
    centre: [f64; 2],
    images: i64,
}

impl Gaussian {
    /// `sigma` in `(0, 1]` (units of the domain), `centre` in `[0, 1]²`.
    pub fn new(sigma: f64, centre: [f64; 2]) -> Result<Self> {
        finite("gaussian", "sigma", sigma)?;
        if sigma <= 0.0 || sigma > 1.0 {
            return Err(Error::Usage(format!(
                "gaussian: sigma={} is not a width in (0, 1]; give a positive sigma no wider than the domain, e.g. sigma=0.15",
                number(sigma)
            )));
        }
        for (key, c) in [("cx", centre[0]), ("cy", centre[1])] {
            if !(0.0..=1.0).contains(&finite("gaussian", key, c)?) {
                return Err(Error::Usage(format!(
                    "gaussian: {key}={} puts the centre outside the unit square; use a value in [0, 1]",
                    number(c)
                )));
            }
        }
        // Images farther than M − ½ contribute below exp(−40) of the peak.
        let images = (0.5 + sigma * 80f64.sqrt()).ceil() as i64;
        Ok(Self {
            sigma,
            centre,
            images,
        })
    }

    /// The periodic 1D factor at offset `d` from the centre.
    fn factor(&self, d: f64) -> f64 {
        let mut d = wrap(d);
        if d >= 0.5 {
            d -= 1.0;
        }
        let s2 = 2.0 * self.sigma * self.sigma;
        // Terms beyond |t|² = 40·s2 are below exp(−40) of the peak: skip them.
        let cut = 40.0 * s2;
        (-self.images..=self.images)
            .map(|m| d + m as f64)
            .filter(|t| t * t < cut)
            .map(|t| (-t * t / s2).exp())
            .sum()
    }

    /// `Σ_{k ∈ Z} exp(−4π²σ²k²)`, by the Poisson dual `Σ_m exp(−m²/(4σ²)) / (2σ√π)` when σ is small.
    fn theta_sum(&self) -> f64 {
        let s = self.sigma;
        if s < 0.25 {
            let terms = (s * 2.0 * 50f64.sqrt()).ceil() as i64 + 1;
            // The m = 0 term is 1 exactly; written out, it stays 1 when σ² underflows to 0 (0 / 0).
            (-terms..=terms)
                .map(|m| match m {
                    0 => 1.0,
                    _ => (-((m * m) as f64) / (4.0 * s * s)).exp(),
                })
                .sum::<f64>()
                / (2.0 * s * PI.sqrt())
        } else {
            1.0 + self.theta_excess()
        }
    }

    /// `Σ_{k≠0} exp(−4π²σ²k²) = 2 Σ_{k≥1} exp(−4π²σ²k²)`, summed directly: for σ ≥ 1/4, where
    /// [`Gaussian::theta_sum`] is `1 +` this (the terms past the last are below `exp(−50)`).
    fn theta_excess(&self) -> f64 {
        let s = self.sigma;
        let terms = (50f64.sqrt() / (2.0 * PI * s)).ceil() as i64 + 1;
        2.0 * (1..=terms)
            .map(|k| (-4.0 * PI * PI * s * s * (k * k) as f64).exp())
            .sum::<f64>()
    }
}

impl Integrand for Gaussian {
    fn name(&self) -> String {
        format!(
            "gaussian:sigma={},cx={},cy={}",
            number(self.sigma),
            number(self.centre[0]),
            number(self.centre[1])
        )
    }
    fn dims(&self) -> usize {
        2
    }
    fn eval(&self, x: &[f64]) -> f64 {
        self.factor(x[0] - self.centre[0]) * self.factor(x[1] - self.centre[1])
    }
    fn reference(&self) -> Reference {
        Reference {
            value: 2.0 * PI * self.sigma * self.sigma,
            stderr: 0.0,
        }
    }
    fn fourier(&self, k: &[i64]) -> Option<Complex64> {
        let kk = (k[0] * k[0] + k[1] * k[1]) as f64;
        let amp = 2.0
            * PI
            * self.sigma
            * self.sigma
            * (-2.0 * PI * PI * self.sigma * self.sigma * kk).exp();
        Some(phase(k2(k), self.centre) * amp)
    }
    fn mean_square(&self) -> Option<f64> {
        let a = 2.0 * PI * self.sigma * self.sigma;
        if a == 0.0 {
            // σ² underflows (σ below about 1e-162): so does ∫f² ≈ πσ², while the theta sum
            // may overflow (σ below about 1e-308), which would give 0 · ∞.
            return Some(0.0);
        }
        Some((a * self.theta_sum()).powi(2))
    }
    /// `Σ_{k≠0} |f̂(k)|² = (2πσ²)² (S − 1)(S + 1)` with `S` = [`Gaussian::theta_sum`]; for σ ≥ 1/4,
    /// where `S − 1` is tiny, it is summed as `2 Σ_{k≥1} exp(−4π²σ²k²)` rather than subtracted.
    fn variance(&self) -> Option<f64> {
        let a = 2.0 * PI * self.sigma * self.sigma;
        if a == 0.0 {
            // As for `mean_square`: the variance, below πσ², underflows too.
            return Some(0.0);
        }
        let theta = self.theta_sum();
        let excess = if self.sigma < 0.25 {
            theta - 1.0
        } else {
            self.theta_excess()
        };
        // (a · excess)(a · (θ + 1)): a² alone underflows for narrow σ (σ = 1e-100: a² = 4e-399).
        Some((a * excess) * (a * (theta + 1.0)))
    }
    /// Centre uniform on the torus.
    fn placed(&self, rng: &mut Rng) -> Option<Box<dyn Integrand>> {
        let mut g = self.clone();
        g.centre = [rng.random::<f64>(), rng.random::<f64>()];
        Some(Box::new(g))
    }
}

/// The indicator of a disc of radius `r` centred at `centre`, wholly inside the unit square.
///
/// Integral `πr²`; `f̂(k) = r J1(2πr|k|) / |k| · exp(−2πi k·c)`: both exact (J1 from `libm`).
#[derive(Clone, Debug)]
pub struct Disc {
    r: f64,
    centre: [f64; 2],
}

impl Disc {
    /// `r > 0` and the disc inside `[0,1]²`: `r ≤ cx ≤ 1 − r`, `r ≤ cy ≤ 1 − r`.
    pub fn new(r: f64, centre: [f64; 2]) -> Result<Self> {
        finite("disc", "r", r)?;
        if r <= 0.0 || r > 0.5 {
            return Err(Error::Usage(format!(
                "disc: r={} is not a radius in (0, 0.5]; a disc inside the unit square has 0 < r <= 0.5",
                number(r)
            )));
        }
        for (key, c) in [("cx", centre[0]), ("cy", centre[1])] {
            finite("disc", key, c)?;
            if c < r || c > 1.0 - r {
                return Err(Error::Usage(format!(
                    "disc: {key}={} with r={r} puts the disc outside the domain [0,1]²; keep {r} <= {key} <= {}",
                    number(c),
                    number(1.0 - r),
                    r = number(r)
                )));
            }
        }
        Ok(Self { r, centre })
    }
}

impl Integrand for Disc {
    fn name(&self) -> String {
        format!(
            "disc:r={},cx={},cy={}",
            number(self.r),
            number(self.centre[0]),
            number(self.centre[1])
        )
    }
    fn dims(&self) -> usize {
        2
    }
    fn eval(&self, x: &[f64]) -> f64 {
        let (dx, dy) = (x[0] - self.centre[0], x[1] - self.centre[1]);
        f64::from(u8::from(dx * dx + dy * dy < self.r * self.r))
    }
    fn reference(&self) -> Reference {
        Reference {
            value: PI * self.r * self.r,
            stderr: 0.0,
        }
    }
    fn fourier(&self, k: &[i64]) -> Option<Complex64> {
        if k[0] == 0 && k[1] == 0 {
            return Some(Complex64::new(PI * self.r * self.r, 0.0));
        }
        let kn = ((k[0] * k[0] + k[1] * k[1]) as f64).sqrt();
        Some(phase(k2(k), self.centre) * (self.r * libm::j1(2.0 * PI * self.r * kn) / kn))
    }
    fn mean_square(&self) -> Option<f64> {
        Some(PI * self.r * self.r)
    }
    /// Centre uniform over the positions that keep the disc inside the square.
    fn placed(&self, rng: &mut Rng) -> Option<Box<dyn Integrand>> {
        let span = 1.0 - 2.0 * self.r;
        let mut d = self.clone();
        d.centre = [
            self.r + span * rng.random::<f64>(),
            self.r + span * rng.random::<f64>(),
        ];
        Some(Box::new(d))
    }
}

/// The range `(lo, hi)` of `n·x` over the unit square's corners: the offsets `c` for which the edge
/// `n·x = c` crosses the square.
fn corner_range(n: [f64; 2]) -> (f64, f64) {
    let v = [0.0, n[0], n[1], n[0] + n[1]];
    (
        v.iter().copied().fold(f64::INFINITY, f64::min),
        v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    )
}

/// What a [`HalfPlane`] is called and how it was parametrized, for its name.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EdgeKind {
    /// `step:theta=θ`: normal `(cos θ, sin θ)`, θ in degrees; θ = 0 is an edge aligned with the `x2` axis.
    Oriented {
        /// Angle of the edge normal from the `x1` axis, degrees.
        theta_deg: f64,
    },
    /// `sheared:s=s`: the edge `x1 + s x2 = c` (in a projection `xu`: `x + s u = c`).
    Sheared {
        /// The shear `s`.
        s: f64,
    },
}

/// A step: 1 on the part of the unit square where `n·x < c`, 0 elsewhere (a polygon; on the torus the
/// square's sides are edges too).
///
/// Integral = the polygon's area; `f̂` by the polygon formula: both exact.
#[derive(Clone, Debug)]
pub struct HalfPlane {
    kind: EdgeKind,
    normal: [f64; 2],
    c: f64,
    poly: polygon::Polygon,
}

impl HalfPlane {
    /// An oriented step `n·x < c` with unit normal `n = (cos θ, sin θ)`: `θ = theta_deg` is the angle of
    /// the normal (not the edge) from the `x1` axis towards `x2`, in degrees. `c` is the offset along
    /// `n` (`None`: the edge through the centre `(½, ½)`, `c = (cos θ + sin θ)/2`).
    pub fn oriented(theta_deg: f64, c: Option<f64>) -> Result<Self> {
        let t = finite("step", "theta", theta_deg)?.to_radians();
        Self::build(
            EdgeKind::Oriented { theta_deg },
            [t.cos(), t.sin()],
            c,
            "step",
        )
    }

    /// The sheared step `x1 + s x2 < c` (`None`: the edge through the centre, `c = (1 + s)/2`).
    pub fn sheared(s: f64, c: Option<f64>) -> Result<Self> {
        shear("sheared", "s", s)?;
        Self::build(EdgeKind::Sheared { s }, [1.0, s], c, "sheared")
    }

    fn build(kind: EdgeKind, normal: [f64; 2], c: Option<f64>, family: &str) -> Result<Self> {
        let (lo, hi) = corner_range(normal);
        let c = match c {
            Some(c) => finite(family, "c", c)?,
            None => 0.5 * (normal[0] + normal[1]),
        };
        if c <= lo || c >= hi {
            return Err(Error::Usage(format!(
                "{family}: the edge at c={} misses the unit square (it crosses it for {} < c < {}); choose c in that range",
                number(c),
                number(lo),
                number(hi)
            )));
        }
        Ok(Self {
            kind,
            normal,
            c,
            poly: polygon::clip_square(normal, c),
        })
    }
}

impl Integrand for HalfPlane {
    fn name(&self) -> String {
        match self.kind {
            EdgeKind::Oriented { theta_deg } => {
                format!("step:theta={},c={}", number(theta_deg), number(self.c))
            }
            EdgeKind::Sheared { s } => format!("sheared:s={},c={}", number(s), number(self.c)),
        }
    }
    fn dims(&self) -> usize {
        2
    }
    fn eval(&self, x: &[f64]) -> f64 {
        f64::from(u8::from(
            self.normal[0] * x[0] + self.normal[1] * x[1] < self.c,
        ))
    }
    fn reference(&self) -> Reference {
        Reference {
            value: polygon::area(self.poly.vertices()),
            stderr: 0.0,
        }
    }
    fn fourier(&self, k: &[i64]) -> Option<Complex64> {
        Some(polygon::fourier(&self.poly, k2(k)))
    }
    fn mean_square(&self) -> Option<f64> {
        Some(polygon::area(self.poly.vertices()))
    }
    /// Offset `c` uniform over the range where the edge crosses the square.
    fn placed(&self, rng: &mut Rng) -> Option<Box<dyn Integrand>> {
        let (lo, hi) = corner_range(self.normal);
        let mut c = lo + (hi - lo) * rng.random::<f64>();
        if c <= lo {
            c = 0.5 * (lo + hi);
        }
        let mut h = self.clone();
        h.c = c;
        h.poly = polygon::clip_square(self.normal, c);
        Some(Box::new(h))
    }
}

/// A fan of sheared edges: the mean over shears `s` uniform on `[s0, s1]` of the steps
/// `H(c − x1 − s x2)`. For `x2 > 0` it is the clamped ramp `clamp((c − s0 x2 − x1) / ((s1 − s0) x2), 0, 1)`;
/// its spectrum fills the double wedge between the lines of slopes `s0` and `s1`.
///
/// Evaluation is exact. The integral and `∫f²` come from Gauss–Legendre quadrature in `x2` of an exact
/// inner integral, cut at every kink (error near machine precision); `f̂(k)` is the quadrature in `s` of
/// the exact step coefficients, with absolute error below [`FAN_FOURIER_ERROR`] (checked in the tests
/// against a rule with four times the panels).
#[derive(Clone, Debug)]
pub struct Fan {
    s0: f64,
    s1: f64,
    c: f64,
    integral: f64,
    square: f64,
}

/// Bound on the absolute error of [`Fan`]'s Fourier coefficients.
pub const FAN_FOURIER_ERROR: f64 = 1e-11;

/// Gauss–Legendre points per panel for the fan's quadratures.
const FAN_RULE: usize = 16;

/// The [`FAN_RULE`]-point Gauss–Legendre rule, computed once: `f̂` is evaluated at every frequency of
/// a grid, and recomputing the rule each time took 4 % of a prediction.
fn fan_rule() -> &'static [(f64, f64)] {
    static RULE: std::sync::OnceLock<Vec<(f64, f64)>> = std::sync::OnceLock::new();
    RULE.get_or_init(|| quad::gauss_legendre(FAN_RULE))
}

impl Fan {
    /// Shears `s0 < s1`, offset `c` (`None`: the mean edge through the centre, `c = (1 + (s0+s1)/2)/2`).
    pub fn new(s0: f64, s1: f64, c: Option<f64>) -> Result<Self> {
        shear("fan", "s0", s0)?;
        shear("fan", "s1", s1)?;
        if s0 > s1 {
            return Err(Error::Usage(format!(
                "fan: s0={a} > s1={b}; the shears run from s0 up to s1, so swap them (fan:s0={b},s1={a})",
                a = number(s0),
                b = number(s1)
            )));
        }
        if s0 == s1 {
            return Err(Error::Usage(format!(
                "fan: s0 = s1 = {a} is a single edge, not a fan; use sheared:s={a} or widen [s0, s1]",
                a = number(s0)
            )));
        }
        let c = match c {
            Some(c) => finite("fan", "c", c)?,
            None => 0.5 * (1.0 + 0.5 * (s0 + s1)),
        };
        let (lo, hi) = (s0.min(0.0), 1.0 + s1.max(0.0));
        if c <= lo || c >= hi {
            return Err(Error::Usage(format!(
                "fan: the edges at c={} miss the unit square (they cross it for {} < c < {}); choose c in that range",
                number(c),
                number(lo),
                number(hi)
            )));
        }
        let mut fan = Self {
            s0,
            s1,
            c,
            integral: 0.0,
            square: 0.0,
        };
        fan.integral = fan.moment(1);
        fan.square = fan.moment(2);
        Ok(fan)
    }

    /// `∫_0^1 f(x1, u)^p dx1` for `p` = 1 or 2, exact.
    fn inner(&self, u: f64, p: i32) -> f64 {
        let w = (self.s1 - self.s0) * u;
        if w <= 0.0 {
            return self.c.clamp(0.0, 1.0);
        }
        let a = self.c - self.s0 * u; // f = 0 from here on
        let b = a - w; // f = 1 up to here
        let mut total = b.clamp(0.0, 1.0);
        let (xl, xr) = (b.max(0.0), a.min(1.0));
        if xr > xl {
            // ∫_xl^xr ((a − x)/w)^p dx = (A^{p+1} − B^{p+1}) / ((p + 1) w^p) with A = a − xl,
            // B = a − xr, written as (A − B) Σ A^{p−i} B^i: on a wide ramp A and B nearly agree and
            // their powers' difference would cancel.
            let (big, small) = ((a - xl) / w, (a - xr) / w);
            let powers: f64 = (0..=p).map(|i| big.powi(p - i) * small.powi(i)).sum();
            total += (xr - xl) * powers / f64::from(p + 1);
        }
        total
    }

    /// `∫ f^p` over the square: quadrature in `u` cut where the ramp's ends cross `x1 = 0` or `x1 = 1`,
    /// and at `u = 2^j / (s1 − s0)`, where the ramp's width `(s1 − s0) u` doubles past 1: beyond it
    /// the square sees only a piece of the ramp, and `∫f^p dx1` departs from its value at the ramp's
    /// middle by terms in `1/u` and `1/u²`, which four panels on one piece cannot follow (a fan of
    /// range 2000 lost 13 % of its variance).
    fn moment(&self, p: i32) -> f64 {
        let mut breaks = Vec::new();
        for s in [self.s0, self.s1] {
            if s != 0.0 {
                breaks.push(self.c / s);
                breaks.push((self.c - 1.0) / s);
            }
        }
        let mut u = 1.0 / (self.s1 - self.s0);
        while u < 1.0 {
            breaks.push(u);
            u *= 2.0;
        }
        quad::integrate(fan_rule(), 0.0, 1.0, &breaks, 4, |u| self.inner(u, p))
    }

    /// `f̂(k)` with `refine` times the default number of panels.
    ///
    /// The step `H(c − x1 − s x2)` clipped to the square has its moving vertices where the edge meets
    /// a side: `x1 = c − s` on `x2 = 1`, `x2 = c/s` on `x1 = 0` and `x2 = (c − 1)/s` on `x1 = 1`. Each is
    /// monotone in `s` on either side of 0 and stays in `[0, 1]`, so over any piece of the range its
    /// path is the difference of its clamped ends, and over the whole real line at most a few units: a
    /// wide fan turns the phase no more than a narrow one, most of its range moving the vertices as
    /// `1/s²`. The range is cut at the kinks (`c`, `c − 1`), at 0 and at `±2^j` (so the coefficient,
    /// which decays like `1/s`, and the vertices' speed change by a bounded factor within a piece), and
    /// each piece gets
    /// one 16-point panel per two turns of its vertices' phase (and two more): the cost is bounded
    /// whatever `s1 − s0`. Half a turn per panel, the rule until 2026-11-26, gave the same values to
    /// 1e-17 at four times the cost (`fan_coefficients_hold_at_high_frequencies`).
    fn fourier_refined(&self, k: [i64; 2], refine: usize) -> Complex64 {
        let c = self.c;
        let sum: Complex64 = self
            .pieces(k, refine)
            .into_iter()
            .map(|(a, b, panels)| {
                quad::integrate(fan_rule(), a, b, &[], panels, |s| {
                    polygon::fourier(&polygon::clip_square([1.0, s], c), k)
                })
            })
            .sum();
        sum / (self.s1 - self.s0)
    }

    /// The quadrature pieces `(a, b, panels)` of [`Fan::fourier_refined`] at `k`: the range cut as its
    /// doc says, each piece with `refine · (2 + ⌈|k|₁ · path / 2⌉)` panels, `path` the distance its
    /// vertices move over it (the phase `2π k·x` of a vertex turns at most `|k|₁ · path` times).
    fn pieces(&self, k: [i64; 2], refine: usize) -> Vec<(f64, f64, usize)> {
        let c = self.c;
        let k1 = (k[0].unsigned_abs() + k[1].unsigned_abs()) as f64;
        let mut cuts = vec![c, c - 1.0, 0.0];
        // Below min(|c|, |c − 1|) both `c/s` and `(c − 1)/s` are off the square: no octave needed.
        let smallest = 0.5 * c.abs().min((c - 1.0).abs());
        for j in -FAN_OCTAVES..=FAN_OCTAVES {
            let t = 2f64.powi(j);
            if t >= smallest {
                cuts.extend([t, -t]);
            }
        }
        cuts.retain(|&t| t > self.s0 && t < self.s1);
        cuts.extend([self.s0, self.s1]);
        cuts.sort_by(f64::total_cmp);
        cuts.dedup();
        let clamp = |x: f64| x.clamp(0.0, 1.0);
        // Where a vertex is at `s`, clamped to the square (a vertex off the square stays put at a
        // corner); `c/s` and `(c − 1)/s` are taken at a piece's ends, which never straddle 0.
        let vertices = |s: f64| {
            let v = clamp(c - s);
            if s == 0.0 {
                return [v, 0.0, 0.0];
            }
            [v, clamp(c / s), clamp((c - 1.0) / s)]
        };
        cuts.windows(2)
            .map(|w| {
                let (a, b) = (w[0], w[1]);
                // Nudge the ends off 0 so that `c/s` takes the piece's side.
                let side = |s: f64| if s == 0.0 { 0.5 * (a + b) * 1e-12 } else { s };
                let (va, vb) = (vertices(side(a)), vertices(side(b)));
                let path: f64 = va.iter().zip(&vb).map(|(p, q)| (p - q).abs()).sum();
                (a, b, refine * (2 + (0.5 * k1 * path).ceil() as usize))
            })
            .collect()
    }
}

/// Octaves `±2^j`, `|j| ≤ FAN_OCTAVES`, at which a fan's shear range is cut for the quadrature of `f̂`
/// (those above half of `min(|c|, |c − 1|)`): `2^20` is past [`crate::points::shear::MAX_SHEAR`], the
/// largest shear a fan may have. An offset `c` within `2^−20` of a corner leaves the innermost piece
/// uncut, which costs nothing: there the vertices move by at most about `|c|`.
const FAN_OCTAVES: i32 = 20;

impl Integrand for Fan {
    fn name(&self) -> String {
        format!(
            "fan:s0={},s1={},c={}",
            number(self.s0),
            number(self.s1),
            number(self.c)
        )
    }
    fn dims(&self) -> usize {
        2
    }
    fn eval(&self, x: &[f64]) -> f64 {
        let w = (self.s1 - self.s0) * x[1];
        if w <= 0.0 {
            return f64::from(u8::from(x[0] < self.c));
        }
        ((self.c - self.s0 * x[1] - x[0]) / w).clamp(0.0, 1.0)
    }
    fn reference(&self) -> Reference {
        Reference {
            value: self.integral,
            stderr: 0.0,
        }
    }
    fn fourier(&self, k: &[i64]) -> Option<Complex64> {
        if k[0] == 0 && k[1] == 0 {
            return Some(Complex64::new(self.integral, 0.0));
        }
        Some(self.fourier_refined(k2(k), 1))
    }
    fn fourier_error(&self) -> f64 {
        FAN_FOURIER_ERROR
    }
    fn mean_square(&self) -> Option<f64> {
        Some(self.square)
    }
    /// Offset `c` uniform over the range where the fan crosses the square.
    fn placed(&self, rng: &mut Rng) -> Option<Box<dyn Integrand>> {
        let (lo, hi) = (self.s0.min(0.0), 1.0 + self.s1.max(0.0));
        let mut c = lo + (hi - lo) * rng.random::<f64>();
        if c <= lo {
            c = 0.5 * (lo + hi);
        }
        Fan::new(self.s0, self.s1, Some(c))
            .ok()
            .map(|f| Box::new(f) as Box<dyn Integrand>)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_messages_echo_numbers_compactly() {
        let g = Gaussian::new(1e-300, [1e-300, 0.25]).unwrap();
        assert_eq!(g.name(), "gaussian:sigma=1e-300,cx=1e-300,cy=0.25");
        let d = Disc::new(1e-300, [0.5, 1e-300]).unwrap();
        assert_eq!(d.name(), "disc:r=1e-300,cx=0.5,cy=1e-300");
        let e = Disc::new(1e-300, [0.5, 0.0]).unwrap_err().to_string();
        assert!(e.contains("keep 1e-300 <= cy <= 1"), "{e}");
        for (s, range) in [(-1e-5, "-1e-5 < c < 1"), (123456.789, "0 < c < 123457.789")] {
            let e = HalfPlane::sheared(s, Some(-5.0)).unwrap_err().to_string();
            assert!(e.contains(range), "{e}");
        }
        let e = Fan::new(-1e-5, 0.5, Some(5.0)).unwrap_err().to_string();
        assert!(e.contains("-1e-5 < c < 1.5"), "{e}");
    }

    /// Midpoint rule over an `m × m` grid.
    fn grid_integral(f: &dyn Integrand, m: usize, g: impl Fn(f64) -> f64) -> f64 {
        let h = 1.0 / m as f64;
        let mut s = 0.0;
        for i in 0..m {
            for j in 0..m {
                s += g(f.eval(&[(j as f64 + 0.5) * h, (i as f64 + 0.5) * h]));
            }
        }
        s * h * h
    }

    #[test]
    fn gaussian_integral_spectrum_and_parseval() {
        let g = Gaussian::new(0.2, [0.3, 0.9]).unwrap();
        // Smooth periodic: the midpoint rule is spectrally accurate.
        assert!((grid_integral(&g, 200, |v| v) - g.reference().value).abs() < 1e-13);
        assert!((grid_integral(&g, 200, |v| v * v) - g.mean_square().unwrap()).abs() < 1e-13);
        // f̂ by the same rule.
        let m = 200;
        let h = 1.0 / m as f64;
        for k in [[1i64, 0], [2, -1], [3, 3]] {
            let mut s = Complex64::new(0.0, 0.0);
            for i in 0..m {
                for j in 0..m {
                    let x = [(j as f64 + 0.5) * h, (i as f64 + 0.5) * h];
                    s += phase(k, x) * g.eval(&x);
                }
            }
            assert!((s * h * h - g.fourier(&k).unwrap()).norm() < 1e-13);
        }
        // Both branches of the theta sum, on both sides of the switch at σ = 0.25, against both
        // series at the same σ: the direct Σ_k exp(−4π²σ²k²) and its Poisson dual
        // Σ_m exp(−m²/(4σ²)) / (2σ√π) are the same number. (This compared σ = 0.2499 with σ = 0.25
        // within 1e-3: the sum itself moves 3.3e-4 over that step, so a branch off by 6e-4 passed.)
        // Here each sum runs to |k|, |m| ≤ 20, where the terms left out are below e^−630; 41 terms
        // of at most 2 ulp each (exp, product) round to under 100 ulp ≈ 2.2e-14 relative, and 1e-13
        // leaves ×4 for the library's own term counts and summation order.
        for sigma in [0.2, 0.2499, 0.25, 0.3] {
            let direct: f64 = (-20..=20i64)
                .map(|k| (-4.0 * PI * PI * sigma * sigma * (k * k) as f64).exp())
                .sum();
            let dual: f64 = (-20..=20i64)
                .map(|m| (-((m * m) as f64) / (4.0 * sigma * sigma)).exp())
                .sum::<f64>()
                / (2.0 * sigma * PI.sqrt());
            let t = Gaussian::new(sigma, [0.5; 2]).unwrap().theta_sum();
            for (name, want) in [("direct", direct), ("dual", dual)] {
                assert!(
                    (t - want).abs() < 1e-13 * want,
                    "σ = {sigma}: theta sum {t} vs {name} series {want}"
                );
            }
        }
    }

    /// A broad Gaussian's variance, far below its squared mean, is its Fourier coefficients' sum
    /// (to 1e-13 relative), where `∫f² − (∫f)²` loses it to cancellation (σ = 1: 1.1e-15 against
    /// (∫f)² = 39); so are a product's and a sum's (of two broad Gaussians in xy and uv).
    #[test]
    fn broad_gaussians_keep_their_variance() {
        let coefficient_sum = |f: &dyn Integrand, dims: usize| {
            let kmax = 8i64;
            let mut total = 0.0;
            let mut k = vec![-kmax; dims];
            loop {
                if k.iter().any(|&c| c != 0) {
                    total += f.fourier(&k).unwrap().norm_sqr();
                }
                let Some(d) = (0..dims).find(|&d| k[d] < kmax) else {
                    break total;
                };
                k[d] += 1;
                k[..d].iter_mut().for_each(|c| *c = -kmax);
            }
        };
        for sigma in [0.15, 0.4, 0.9, 0.95, 1.0] {
            let g = Gaussian::new(sigma, [0.3, 0.6]).unwrap();
            let (v, want) = (g.variance().unwrap(), coefficient_sum(&g, 2));
            assert!(
                (v - want).abs() <= 1e-13 * want,
                "σ = {sigma}: {v} vs {want}"
            );
        }
        for spec in [
            "gaussian:sigma=0.9@xy*gaussian:sigma=0.95@uv",
            "gaussian:sigma=1@xy+gaussian:sigma=0.99@uv",
        ] {
            let f = crate::integrands::parse(spec).unwrap();
            let (v, want) = (f.variance().unwrap(), coefficient_sum(f.as_ref(), 4));
            assert!((v - want).abs() <= 1e-13 * want, "{spec}: {v} vs {want}");
        }
        // A narrow bump keeps its variance πσ² (less the squared mean (2πσ²)², 4e-399) though a²
        // underflows; where σ² itself underflows the variance is 0, not 0 · ∞ = NaN (σ = 1e-310:
        // the theta sum is ∞).
        let narrow = Gaussian::new(1e-100, [0.5; 2]).unwrap();
        let v = narrow.variance().unwrap();
        let want = PI * 1e-100 * 1e-100;
        assert!((v / want - 1.0).abs() < 1e-12, "{v} vs {want}");
        let vanishing = Gaussian::new(1e-310, [0.5; 2]).unwrap();
        assert_eq!(vanishing.variance(), Some(0.0));
        assert_eq!(vanishing.mean_square(), Some(0.0));
    }

    #[test]
    fn disc_spectrum_sums_to_its_variance() {
        let d = Disc::new(0.3, [0.45, 0.5]).unwrap();
        let mut s = 0.0;
        let kmax = 400i64;
        for k1 in -kmax..=kmax {
            for k2 in -kmax..=kmax {
                if (k1, k2) != (0, 0) {
                    s += d.fourier(&[k1, k2]).unwrap().norm_sqr();
                }
            }
        }
        let var = d.variance().unwrap();
        // The tail outside the square |k1|, |k2| ≤ K = 400: J1(z)² averages 1/(πz), so
        // |f̂|² ≈ r / (2π² |k|³), and its integral outside the square is
        // r / (2π² K) ∫ max(|cos θ|, |sin θ|) dθ = r · 2√2 / (π² K) = 2.149e-4. The next terms (J1's
        // asymptotic form, O(1/(2π r K)) = 0.13 %, and the sum against the integral, O(1/K) =
        // 0.25 %) add to below the 0.5 % allowed here (measured: 0.12 %).
        let tail = 0.3 * 2.0 * std::f64::consts::SQRT_2 / (PI * PI * kmax as f64);
        assert!(
            ((var - s) / tail - 1.0).abs() < 0.005,
            "{var} - {s} = {} vs the tail {tail}",
            var - s
        );
    }

    /// An off-centre disc's coefficients, phase included, against the transform
    /// `∫ f(x) exp(−2πi k·x) dx` by the midpoint rule on a 2000² grid (its error, from the cells the
    /// circle cuts, is about 1e-5 here; a wrong sign of the phase would be off by up to 2 |f̂|, 0.1).
    #[test]
    fn an_off_centre_disc_has_the_phase_of_its_centre() {
        let (r, c) = (0.2, [0.3, 0.65]);
        let d = Disc::new(r, c).unwrap();
        let m = 2000;
        let h = 1.0 / m as f64;
        let inside: Vec<[f64; 2]> = (0..m * m)
            .map(|i| [(i % m) as f64 * h + 0.5 * h, (i / m) as f64 * h + 0.5 * h])
            .filter(|x| (x[0] - c[0]).hypot(x[1] - c[1]) < r)
            .collect();
        for k in [[1, 0], [0, 1], [2, -3], [5, 1], [-4, 7]] {
            let quadrature: Complex64 = inside
                .iter()
                .map(|x| {
                    let phase = -2.0 * PI * (k[0] as f64 * x[0] + k[1] as f64 * x[1]);
                    Complex64::from_polar(h * h, phase)
                })
                .sum();
            let exact = d.fourier(&k).unwrap();
            assert!(
                (exact - quadrature).norm() < 1e-4,
                "k = {k:?}: {exact} against {quadrature}"
            );
        }
    }

    #[test]
    fn step_integral_and_spectrum() {
        let h = HalfPlane::oriented(30.0, None).unwrap();
        assert!((h.reference().value - 0.5).abs() < 1e-15);
        let aligned = HalfPlane::oriented(0.0, Some(0.3)).unwrap();
        assert!((aligned.reference().value - 0.3).abs() < 1e-15);
        assert!(aligned.fourier(&[0, 3]).unwrap().norm() < 1e-16);
        assert!(HalfPlane::sheared(0.5, Some(2.0)).is_err());
    }

    /// A fan over the widest shear range: its coefficients take a bounded number of panels (they follow
    /// how far the step's vertices move, not the range's width, which used to make a ±1e6 fan's
    /// prediction run for hours), agree with four times the panels, and obey Bessel's inequality
    /// against `Var(f)`.
    #[test]
    fn a_wide_fan_has_cheap_accurate_coefficients() {
        let fan = Fan::new(-MAX_SHEAR, MAX_SHEAR, None).unwrap();
        // At most 3 + 2 + 2·(2·FAN_OCTAVES + 1) cuts make the pieces, each with 2 panels plus
        // ⌈|k|₁ · path / 2⌉; each of the 3 vertices is monotone on either side of 0 and stays in [0, 1],
        // so the paths sum to at most 6.
        let k: [i64; 2] = [8, 8];
        let pieces = fan.pieces(k, 1);
        let panels: usize = pieces.iter().map(|p| p.2).sum();
        let bound = 3 * pieces.len() + 16 * 6 / 2;
        assert!(pieces.len() <= 5 + 2 * (2 * FAN_OCTAVES as usize + 1));
        assert!(panels <= bound, "{panels} panels > {bound}");
        let mut s = 0.0;
        for k1 in -8i64..8 {
            for k2 in -8i64..8 {
                if (k1, k2) == (0, 0) {
                    continue;
                }
                let a = fan.fourier(&[k1, k2]).unwrap();
                assert!(a.re.is_finite() && a.im.is_finite());
                let b = fan.fourier_refined([k1, k2], 4);
                assert!((a - b).norm() < FAN_FOURIER_ERROR, "k = ({k1}, {k2})");
                s += a.norm_sqr();
            }
        }
        let var = fan.mean_square().unwrap() - fan.reference().value.powi(2);
        assert!(s <= var * (1.0 + 1e-9), "{s} > {var}");
    }

    /// Two turns of the vertices' phase per 16-point panel: against four times the panels, at
    /// frequencies up to |k| = 200 (sampled) and for fans narrow, crossing 0 and wide (with octave
    /// cuts), the coefficients agree far inside [`FAN_FOURIER_ERROR`] (measured: at most 1.2e-17).
    #[test]
    fn fan_coefficients_hold_at_high_frequencies() {
        for fan in [
            Fan::new(0.3, 0.7, None).unwrap(),
            Fan::new(-0.7, 0.0, Some(0.4)).unwrap(),
            Fan::new(-3.0, 5.0, Some(0.2)).unwrap(),
        ] {
            let mut worst: f64 = 0.0;
            for k1 in (-200i64..=200).step_by(23) {
                for k2 in (-200i64..=200).step_by(29) {
                    let a = fan.fourier_refined([k1, k2], 1);
                    let b = fan.fourier_refined([k1, k2], 4);
                    worst = worst.max((a - b).norm());
                }
            }
            assert!(worst < FAN_FOURIER_ERROR, "{}: {worst:e}", fan.name());
        }
    }

    #[test]
    fn fan_matches_mean_of_steps() {
        let fan = Fan::new(0.3, 0.7, None).unwrap();
        // ∫f = mean over s of the step areas.
        let rule = quad::gauss_legendre(16);
        let mean_area: f64 = quad::integrate(&rule, 0.3, 0.7, &[fan.c, fan.c - 1.0], 8, |s| {
            polygon::area(polygon::clip_square([1.0, s], fan.c).vertices())
        }) / 0.4;
        assert!((fan.reference().value - mean_area).abs() < 1e-14);
        assert!((grid_integral(&fan, 1000, |v| v) - mean_area).abs() < 2e-4);
        assert!((grid_integral(&fan, 1000, |v| v * v) - fan.mean_square().unwrap()).abs() < 2e-4);
        // Quadrature error of f̂: against four times the panels, over a grid of frequencies.
        let mut worst: f64 = 0.0;
        for k1 in -24i64..=24 {
            for k2 in -24i64..=24 {
                let a = fan.fourier_refined([k1, k2], 1);
                let b = fan.fourier_refined([k1, k2], 4);
                worst = worst.max((a - b).norm());
            }
        }
        assert!(
            worst < FAN_FOURIER_ERROR,
            "fan f̂ quadrature error {worst:e}"
        );
        // Parseval: Σ|f̂|² ≤ ∫f² − (∫f)².
        let mut s = 0.0;
        for k1 in -24i64..=24 {
            for k2 in -24i64..=24 {
                if (k1, k2) != (0, 0) {
                    s += fan.fourier(&[k1, k2]).unwrap().norm_sqr();
                }
            }
        }
        let var = fan.mean_square().unwrap() - fan.reference().value.powi(2);
        assert!(s < var && s > 0.9 * var, "{s} vs {var}");
    }

    /// A fan through the centre of a symmetric range `s0 = −s1`, of width `W = s1 − s0 > 1`, has
    /// `∫f dx1 = 1/2` at every `u`, `∫f² dx1 = 1/2 − W u / 6` while its ramp fits in the square
    /// (`W u ≤ 1`) and `1/4 + 1/(12 W² u²)` after, so `∫f = 1/2` and `Var(f) = 1/(4W) − 1/(12W²)`
    /// (1.2497917e-4 at W = 2000). The quadrature meets both within rounding: `∫f²` sums about
    /// 1400 terms near 1/4, each within a few ulps, so 1e-14 absolute (reached: 2e-16 to 1.5e-15).
    /// Before the cuts at `2^j / W` a range of 2000 lost 13 % of its variance.
    #[test]
    fn wide_fans_have_exact_moments() {
        for w in [2.0, 2e3, 2e6] {
            let fan = Fan::new(-w / 2.0, w / 2.0, None).unwrap();
            let var = fan.square - fan.integral.powi(2);
            let exact = 1.0 / (4.0 * w) - 1.0 / (12.0 * w * w);
            eprintln!("W = {w}: var {var:e} vs {exact:e}");
            assert!(
                (fan.integral - 0.5).abs() < 1e-14,
                "W = {w}: {}",
                fan.integral
            );
            assert!((var - exact).abs() < 1e-14, "W = {w}: {var} vs {exact}");
        }
    }

    #[test]
    fn bad_parameters_are_usage_errors() {
        assert_eq!(Gaussian::new(-0.1, [0.5; 2]).unwrap_err().exit_code(), 2);
        assert_eq!(Disc::new(0.3, [0.2, 0.5]).unwrap_err().exit_code(), 2);
        assert_eq!(Fan::new(0.7, 0.3, None).unwrap_err().exit_code(), 2);
    }
}
