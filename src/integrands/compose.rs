//! Building 4D integrands: a 2D integrand placed on a projection ([`Embed`]), and [`Sum`]s and
//! [`Product`]s of integrands of the same dimension.

use super::{Integrand, Reference};
use crate::error::{Error, Result};
use crate::points::Projection;
use crate::rng::Rng;
use rustfft::num_complex::Complex64;
use std::sync::Arc;

/// A 2D integrand `g` seen as the 4D function `f(x) = g(x_a, x_b)` for the projection `(a, b)`.
///
/// `f̂(k) = ĝ(k_a, k_b)` when the other two components of `k` are 0, and 0 otherwise.
pub struct Embed {
    inner: Arc<dyn Integrand>,
    proj: Projection,
}

impl Embed {
    /// Places the 2D integrand `inner` on the projection `proj` of 4D.
    pub fn new(inner: Arc<dyn Integrand>, proj: Projection) -> Result<Self> {
        if inner.dims() != 2 {
            return Err(Error::Usage(format!(
                "{}@{}: only a 2D integrand can be placed on a projection; this one is already {}D",
                inner.name(),
                proj.name(),
                inner.dims()
            )));
        }
        Projection::parse(&proj.name(), 4)?;
        Ok(Self { inner, proj })
    }
}

impl Integrand for Embed {
    fn name(&self) -> String {
        format!("{}@{}", self.inner.name(), self.proj.name())
    }
    fn dims(&self) -> usize {
        4
    }
    fn eval(&self, x: &[f64]) -> f64 {
        self.inner.eval(&[x[self.proj.a], x[self.proj.b]])
    }
    fn reference(&self) -> Reference {
        self.inner.reference()
    }
    fn fourier(&self, k: &[i64]) -> Option<Complex64> {
        let off_plane = (0..4).any(|d| d != self.proj.a && d != self.proj.b && k[d] != 0);
        let g = self.inner.fourier(&[k[self.proj.a], k[self.proj.b]])?;
        Some(if off_plane {
            Complex64::new(0.0, 0.0)
        } else {
            g
        })
    }
    fn fourier_error(&self) -> f64 {
        self.inner.fourier_error()
    }
    fn mean_square(&self) -> Option<f64> {
        self.inner.mean_square()
    }
    fn variance(&self) -> Option<f64> {
        self.inner.variance()
    }
    fn support(&self) -> Vec<usize> {
        let mut s = vec![self.proj.a, self.proj.b];
        s.sort_unstable();
        s
    }
    fn spectral_planes(&self) -> Option<Vec<Projection>> {
        Some(vec![self.proj])
    }
    fn placed(&self, rng: &mut Rng) -> Option<Box<dyn Integrand>> {
        let inner = self.inner.placed(rng)?;
        Some(Box::new(Embed {
            inner: Arc::from(inner),
            proj: self.proj,
        }))
    }
}

fn same_dims(parts: &[Arc<dyn Integrand>], what: &str) -> Result<usize> {
    let d = parts[0].dims();
    if let Some(p) = parts.iter().find(|p| p.dims() != d) {
        return Err(Error::Usage(format!(
            "a {what} mixes a {d}D integrand ({}) with a {}D one ({}); place 2D terms on a 4D projection with @xy, @uv, @xu, ...",
            parts[0].name(),
            p.dims(),
            p.name()
        )));
    }
    Ok(d)
}

/// Places each part anew (parts with nothing to move are kept); `None` if no part moves.
fn place_all(parts: &[Arc<dyn Integrand>], rng: &mut Rng) -> Option<Vec<Arc<dyn Integrand>>> {
    let mut moved = false;
    let out = parts
        .iter()
        .map(|p| match p.placed(rng) {
            Some(q) => {
                moved = true;
                Arc::from(q)
            }
            None => Arc::clone(p),
        })
        .collect();
    moved.then_some(out)
}

/// `f = Σ_i f_i`, all of the same dimension: `f̂ = Σ f̂_i`, `∫f = Σ ∫f_i`.
pub struct Sum {
    terms: Vec<Arc<dyn Integrand>>,
}

impl Sum {
    /// At least one term, all of one dimension.
    pub fn new(terms: Vec<Arc<dyn Integrand>>) -> Result<Self> {
        if terms.is_empty() {
            return Err(Error::Usage("an empty sum of integrands".into()));
        }
        same_dims(&terms, "sum")?;
        Ok(Self { terms })
    }
}

impl Integrand for Sum {
    fn name(&self) -> String {
        self.terms
            .iter()
            .map(|t| t.name())
            .collect::<Vec<_>>()
            .join("+")
    }
    fn dims(&self) -> usize {
        self.terms[0].dims()
    }
    fn eval(&self, x: &[f64]) -> f64 {
        self.terms.iter().map(|t| t.eval(x)).sum()
    }
    fn reference(&self) -> Reference {
        let r: Vec<Reference> = self.terms.iter().map(|t| t.reference()).collect();
        Reference {
            value: r.iter().map(|r| r.value).sum(),
            stderr: r.iter().map(|r| r.stderr * r.stderr).sum::<f64>().sqrt(),
        }
    }
    fn fourier(&self, k: &[i64]) -> Option<Complex64> {
        self.terms.iter().map(|t| t.fourier(k)).sum()
    }
    fn fourier_error(&self) -> f64 {
        self.terms.iter().map(|t| t.fourier_error()).sum()
    }
    /// Terms on disjoint dimensions are uncorrelated, so the variance is the sum of the terms' own
    /// (free of the cancellation of `∫f² − (∫f)²`); `None` when terms overlap, as for `∫f²`.
    fn variance(&self) -> Option<f64> {
        self.mean_square()?;
        self.terms.iter().map(|t| t.variance()).sum()
    }
    /// Known when every term's `∫f_i²` is known and every pair of terms depends on disjoint
    /// dimensions (then `∫f_i f_j = ∫f_i ∫f_j`).
    fn mean_square(&self) -> Option<f64> {
        let mut total = 0.0;
        for (i, a) in self.terms.iter().enumerate() {
            total += a.mean_square()?;
            for b in &self.terms[i + 1..] {
                let (sa, sb) = (a.support(), b.support());
                if sa.iter().any(|d| sb.contains(d)) {
                    return None;
                }
                total += 2.0 * a.reference().value * b.reference().value;
            }
        }
        Some(total)
    }
    fn support(&self) -> Vec<usize> {
        let mut s: Vec<usize> = self.terms.iter().flat_map(|t| t.support()).collect();
        s.sort_unstable();
        s.dedup();
        s
    }
    fn spectral_planes(&self) -> Option<Vec<Projection>> {
        let mut planes: Vec<Projection> = Vec::new();
        for t in &self.terms {
            for p in t.spectral_planes()? {
                if !planes.contains(&p) {
                    planes.push(p);
                }
            }
        }
        Some(planes)
    }
    fn placed(&self, rng: &mut Rng) -> Option<Box<dyn Integrand>> {
        Some(Box::new(Sum {
            terms: place_all(&self.terms, rng)?,
        }))
    }
}

/// `f = Π_i f_i` with factors on disjoint dimensions: `f̂(k) = Π f̂_i(k restricted to f_i's
/// dimensions)`, `∫f = Π ∫f_i`, `∫f² = Π ∫f_i²`.
pub struct Product {
    factors: Vec<Arc<dyn Integrand>>,
}

impl Product {
    /// At least one factor, all of one dimension, on pairwise disjoint dimensions.
    pub fn new(factors: Vec<Arc<dyn Integrand>>) -> Result<Self> {
        if factors.is_empty() {
            return Err(Error::Usage("an empty product of integrands".into()));
        }
        same_dims(&factors, "product")?;
        for (i, a) in factors.iter().enumerate() {
            for b in &factors[i + 1..] {
                if a.support().iter().any(|d| b.support().contains(d)) {
                    return Err(Error::Usage(format!(
                        "the factors {} and {} share a dimension; a product needs factors on disjoint dimensions (e.g. one @xy and one @uv, or one @xu and one @yv)",
                        a.name(),
                        b.name()
                    )));
                }
            }
        }
        Ok(Self { factors })
    }
}

impl Integrand for Product {
    fn name(&self) -> String {
        self.factors
            .iter()
            .map(|t| t.name())
            .collect::<Vec<_>>()
            .join("*")
    }
    fn dims(&self) -> usize {
        self.factors[0].dims()
    }
    fn eval(&self, x: &[f64]) -> f64 {
        self.factors.iter().map(|t| t.eval(x)).product()
    }
    fn reference(&self) -> Reference {
        let r: Vec<Reference> = self.factors.iter().map(|t| t.reference()).collect();
        let value: f64 = r.iter().map(|r| r.value).product();
        // First-order propagation of independent errors.
        let var: f64 = (0..r.len())
            .map(|i| {
                let others: f64 = r
                    .iter()
                    .enumerate()
                    .filter(|(j, _)| *j != i)
                    .map(|(_, r)| r.value)
                    .product();
                (r[i].stderr * others).powi(2)
            })
            .sum();
        Reference {
            value,
            stderr: var.sqrt(),
        }
    }
    fn fourier(&self, k: &[i64]) -> Option<Complex64> {
        let mut total = Complex64::new(1.0, 0.0);
        for f in &self.factors {
            let support = f.support();
            let masked: Vec<i64> = (0..k.len())
                .map(|d| if support.contains(&d) { k[d] } else { 0 })
                .collect();
            total *= f.fourier(&masked)?;
        }
        Some(total)
    }
    fn fourier_error(&self) -> f64 {
        // |Π a_i − Π b_i| ≤ Σ_i err_i Π_{j≠i} max|a_j|, and |f̂_j| ≤ ∫|f_j| ≤ sqrt(∫f_j²).
        let bounds: Vec<f64> = self
            .factors
            .iter()
            .map(|f| f.mean_square().map_or(1.0, f64::sqrt))
            .collect();
        self.factors
            .iter()
            .enumerate()
            .map(|(i, f)| {
                f.fourier_error()
                    * bounds
                        .iter()
                        .enumerate()
                        .filter(|(j, _)| *j != i)
                        .map(|(_, b)| b)
                        .product::<f64>()
            })
            .sum()
    }
    fn mean_square(&self) -> Option<f64> {
        self.factors.iter().map(|f| f.mean_square()).product()
    }
    /// `Π (v_i + m_i²) − Π m_i²` (`v_i` the factors' variances, `m_i` their integrals) built up factor
    /// by factor as `D ← D (v + m²) + Q v`, `Q ← Q m²`, with no difference of near-equal terms.
    fn variance(&self) -> Option<f64> {
        let (mut d, mut q) = (0.0, 1.0);
        for f in &self.factors {
            let (v, m2) = (f.variance()?, f.reference().value.powi(2));
            d = d * (v + m2) + q * v;
            q *= m2;
        }
        Some(d)
    }
    fn support(&self) -> Vec<usize> {
        let mut s: Vec<usize> = self.factors.iter().flat_map(|t| t.support()).collect();
        s.sort_unstable();
        s
    }
    /// A product over two projections spreads its spectrum over 4D frequency space: `None` (unless it
    /// has a single factor).
    fn spectral_planes(&self) -> Option<Vec<Projection>> {
        match self.factors.as_slice() {
            [one] => one.spectral_planes(),
            _ => None,
        }
    }
    fn placed(&self, rng: &mut Rng) -> Option<Box<dyn Integrand>> {
        Some(Box::new(Product {
            factors: place_all(&self.factors, rng)?,
        }))
    }
}
