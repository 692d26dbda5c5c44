//! `anisospec integrands`: the integrand families, their keys, and (with `--check`) what a spec parses to.

use crate::error::Result;
use crate::integrands::spec::{listing, names_a_pixel};
use crate::integrands::{estimate_variance, parse};

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
    } else if names_a_pixel(spec) {
        // A pixel of the scene: each evaluation traces rays; its variance is what converge measures.
        outln!("variance   unknown in closed form (measure it with `anisospec converge`)");
    } else {
        let v = estimate_variance(f.as_ref());
        outln!(
            "variance   {:.6e} (± {:.1e}; of f over the domain, by randomized QMC: no closed form for overlapping terms)",
            v.value, v.stderr
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
