//! `anisospec integrands`: the integrand families, their keys, and (with `--check`) what a spec parses to.

use crate::error::Result;
use crate::integrands::{estimate_mean_square, parse, spec::listing};

/// List the integrand families and their keys, or check one integrand spec.
#[derive(Debug, clap::Args)]
pub struct IntegrandsArgs {
    /// Parse this integrand (NAME:key=value,...) and print its dimension, exact integral, variance (exact,
    /// or estimated by randomized QMC with its standard error for sums of overlapping terms) and
    /// whether the Fourier prediction can use it, instead of the list.
    #[arg(long, value_name = "SPEC")]
    pub check: Option<String>,
}

/// Prints the list, or the checked integrand.
pub fn run(args: &IntegrandsArgs) -> Result<()> {
    let Some(spec) = &args.check else {
        out!("{}", listing());
        return Ok(());
    };
    let f = parse(spec)?;
    let r = f.reference();
    outln!("integrand  {}", f.name());
    outln!("dims       {}", f.dims());
    outln!("integral   {:.17e} (± {:e})", r.value, r.stderr);
    if let Some(v) = f.variance() {
        outln!("variance   {v:.10e} (of f over the domain)");
    } else if f.spectral_planes().is_none() {
        // A pixel of the scene: each evaluation traces rays; its variance is what converge measures.
        outln!("variance   unknown in closed form (measure it with `anisospec converge`)");
    } else {
        let m = estimate_mean_square(f.as_ref());
        outln!(
            "variance   {:.6e} (± {:.1e}; of f over the domain, with ∫f² by randomized QMC: no closed form for overlapping terms)",
            m.value - r.value * r.value,
            m.stderr.hypot(2.0 * r.value * r.stderr)
        );
    }
    match f.spectral_planes() {
        Some(p) => {
            let names: Vec<String> = p.iter().map(|p| p.name()).collect();
            outln!(
                "spectrum   on the plane(s) {}; Fourier coefficients with error <= {:e}",
                names.join(", "),
                f.fourier_error()
            );
        }
        None => outln!(
            "spectrum   spread over all {}D frequencies: use `anisospec converge`",
            f.dims()
        ),
    }
    Ok(())
}
