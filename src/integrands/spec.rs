//! The command-line form of an integrand, `NAME:key=value,...`, and the table of families.
//!
//! Grammar: `spec := term ('+' term)*`, `term := atom ('*' atom)*`,
//! `atom := NAME [':' key=value (',' key=value)*] ['@' projection]`.
//! An atom is a 2D integrand; `@xu` (any two of `x, y, u, v`) places it on that projection of 4D.
//! Examples: `step:theta=30`, `disc:r=0.25,cx=0.4`, `sheared:s=0.5@xu+sheared:s=0.5@yv`,
//! `gaussian:sigma=0.1@xy*fan:s0=0.3,s1=0.7@uv`.

use super::compose::{Embed, Product, Sum};
use super::shapes::{Disc, Fan, Gaussian, HalfPlane};
use super::Integrand;
use crate::error::{Error, Result};
use crate::points::Projection;
use std::path::PathBuf;
use std::sync::Arc;

/// The `key=value` parameters of one atom, checked against its family's keys.
#[derive(Clone, Debug, PartialEq)]
pub struct Params {
    values: Vec<(String, f64)>,
}

impl Params {
    /// The value of `key`, if given.
    pub fn get(&self, key: &str) -> Option<f64> {
        self.values.iter().find(|(k, _)| k == key).map(|(_, v)| *v)
    }

    /// The value of `key`, or `default`.
    pub fn get_or(&self, key: &str, default: f64) -> f64 {
        self.get(key).unwrap_or(default)
    }
}

/// One integrand family: its name, what it is, its keys, and how to build it from parameters.
///
/// To add an analytic family, add one entry to [`FAMILIES`]: the parser, the error messages and
/// `anisospec integrands` all follow from the table. (The renderer's `pixel:px=..,py=..[,scene=FILE]`
/// takes a file path, not only numbers, so [`parse`] hands it to `render::pixel::parse_pixel_spec`.)
pub struct Family {
    /// Name as written on the command line.
    pub name: &'static str,
    /// One line on what the integrand is.
    pub summary: &'static str,
    /// `(key, meaning and default)` for every accepted key.
    pub keys: &'static [(&'static str, &'static str)],
    /// Builds the integrand from checked parameters (only keys listed in `keys` reach it).
    pub build: fn(&Params) -> Result<Box<dyn Integrand>>,
}

fn build_gaussian(p: &Params) -> Result<Box<dyn Integrand>> {
    Ok(Box::new(Gaussian::new(
        p.get_or("sigma", 0.15),
        [p.get_or("cx", 0.5), p.get_or("cy", 0.5)],
    )?))
}

fn build_disc(p: &Params) -> Result<Box<dyn Integrand>> {
    Ok(Box::new(Disc::new(
        p.get_or("r", 0.3),
        [p.get_or("cx", 0.5), p.get_or("cy", 0.5)],
    )?))
}

fn build_step(p: &Params) -> Result<Box<dyn Integrand>> {
    Ok(Box::new(HalfPlane::oriented(
        p.get_or("theta", 0.0),
        p.get("c"),
    )?))
}

fn build_sheared(p: &Params) -> Result<Box<dyn Integrand>> {
    Ok(Box::new(HalfPlane::sheared(
        p.get_or("s", 0.5),
        p.get("c"),
    )?))
}

fn build_fan(p: &Params) -> Result<Box<dyn Integrand>> {
    Ok(Box::new(Fan::new(
        p.get_or("s0", 0.3),
        p.get_or("s1", 0.7),
        p.get("c"),
    )?))
}

/// Every analytic integrand family the parser knows (the renderer's `pixel:` is parsed apart, see
/// [`Family`]).
pub const FAMILIES: &[Family] = &[
    Family {
        name: "gaussian",
        summary: "smooth: a periodic Gaussian bump, the sum of the images of exp(-|x-c|²/2σ²) (peak about 1 for small σ)",
        keys: &[
            ("sigma", "width σ in (0, 1] (default 0.15)"),
            ("cx", "centre, first coordinate (default 0.5)"),
            ("cy", "centre, second coordinate (default 0.5)"),
        ],
        build: build_gaussian,
    },
    Family {
        name: "disc",
        summary: "discontinuous: the indicator of a disc inside the unit square",
        keys: &[
            ("r", "radius in (0, 0.5] (default 0.3)"),
            ("cx", "centre, first coordinate, in [r, 1-r] (default 0.5)"),
            ("cy", "centre, second coordinate, in [r, 1-r] (default 0.5)"),
        ],
        build: build_disc,
    },
    Family {
        name: "step",
        summary: "oriented step: 1 where cos(θ)·x1 + sin(θ)·x2 < c; θ = 0 is an edge aligned with an axis",
        keys: &[
            ("theta", "angle of the edge normal from the first axis, degrees (default 0)"),
            ("c", "offset of the edge (default: through the centre)"),
        ],
        build: build_step,
    },
    Family {
        name: "sheared",
        summary: "sheared step: 1 where x + s·u < c (on a projection such as xu)",
        keys: &[
            ("s", "shear (default 0.5)"),
            ("c", "offset (default (1+s)/2: through the centre)"),
        ],
        build: build_sheared,
    },
    Family {
        name: "fan",
        summary: "fan of sheared edges x + s·u = c, s uniform in [s0, s1]: a double-wedge spectrum",
        keys: &[
            ("s0", "smallest shear (default 0.3)"),
            ("s1", "largest shear, > s0 (default 0.7)"),
            ("c", "offset (default (1+(s0+s1)/2)/2: mean edge through the centre)"),
        ],
        build: build_fan,
    },
];

/// What a pixel written as a term of a larger spec is told.
const PIXEL_STANDS_ALONE: &str =
    "pixel needs its position and stands alone: write pixel:px=COLUMN,py=ROW (no @proj, + or *)";

/// Whether `spec` names a pixel of the scene (`pixel:...`), an integrand whose integral is a
/// rendered reference with a standard error rather than a closed form.
pub fn names_a_pixel(spec: &str) -> bool {
    spec.trim().starts_with("pixel:")
}

/// The files an integrand `spec` reads: the scene file of a pixel (`pixel:...,scene=FILE`), else
/// none. Commands refuse an output that is one of them (outputs never clobber inputs).
pub fn input_files(spec: &str) -> Vec<PathBuf> {
    spec.trim()
        .strip_prefix("pixel:")
        .into_iter()
        .flat_map(|body| body.split(','))
        .filter_map(|kv| kv.split_once('='))
        .filter(|(k, _)| k.trim() == "scene")
        .map(|(_, v)| PathBuf::from(v.trim()))
        .collect()
}

/// The family called `name`.
pub fn family(name: &str) -> Result<&'static Family> {
    if name == "pixel" {
        return Err(Error::Usage(PIXEL_STANDS_ALONE.into()));
    }
    FAMILIES.iter().find(|f| f.name == name).ok_or_else(|| {
        let names: Vec<&str> = FAMILIES.iter().map(|f| f.name).collect();
        Error::Usage(format!(
            "unknown integrand '{name}'; the integrands are {}, and pixel (run `anisospec integrands` for their keys)",
            names.join(", ")
        ))
    })
}

/// Parses `NAME:key=value,...[@proj]` terms joined by `*` and `+` into an integrand; a pixel's
/// reference is cached in [`crate::render::pixel::default_cache_dir`].
pub fn parse(spec: &str) -> Result<Box<dyn Integrand>> {
    parse_with_cache(spec, None)
}

/// [`parse`], with a pixel's reference cached in `cache` when given (a `--cache` flag); other
/// integrands have no reference and ignore it.
pub fn parse_with_cache(spec: &str, cache: Option<&std::path::Path>) -> Result<Box<dyn Integrand>> {
    let spec = spec.trim();
    if spec.is_empty() {
        return Err(Error::Usage(
            "empty integrand; write NAME:key=value,..., e.g. step:theta=30 (see `anisospec integrands`)".into(),
        ));
    }
    if let Some(pixel) = spec.strip_prefix("pixel:") {
        // The renderer's pixel integrand is 4D on its own: it takes no placement and no combination.
        // A scene path may hold these characters; the other keys' values may not.
        let joined = pixel
            .split(',')
            .any(|kv| !kv.trim().starts_with("scene=") && kv.contains(['@', '+', '*']));
        if joined {
            return Err(Error::Usage(PIXEL_STANDS_ALONE.into()));
        }
        return crate::render::pixel::parse_pixel_spec(pixel, cache);
    }
    let mut terms: Vec<Box<dyn Integrand>> = Vec::new();
    for term in split_plus(spec) {
        let mut factors = term
            .split('*')
            .map(|atom| parse_atom(atom.trim()))
            .collect::<Result<Vec<_>>>()?;
        terms.push(if factors.len() == 1 {
            factors.pop().expect("one factor")
        } else {
            Box::new(Product::new(factors.into_iter().map(Arc::from).collect())?)
        });
    }
    if terms.len() == 1 {
        return Ok(terms.pop().expect("one term"));
    }
    Ok(Box::new(Sum::new(
        terms.into_iter().map(Arc::from).collect(),
    )?))
}

/// Splits at `+` signs that are not an exponent's sign (`1e+3`).
fn split_plus(spec: &str) -> Vec<&str> {
    let bytes = spec.as_bytes();
    let mut parts = Vec::new();
    let mut start = 0;
    for (i, &b) in bytes.iter().enumerate() {
        let exponent =
            i > 0 && matches!(bytes[i - 1], b'e' | b'E') && i > 1 && bytes[i - 2].is_ascii_digit();
        if b == b'+' && !exponent {
            parts.push(&spec[start..i]);
            start = i + 1;
        }
    }
    parts.push(&spec[start..]);
    parts
}

/// One `NAME[:params][@proj]`.
fn parse_atom(atom: &str) -> Result<Box<dyn Integrand>> {
    let (body, proj) = match atom.split_once('@') {
        Some((b, p)) => (b, Some(p.trim())),
        None => (atom, None),
    };
    let (name, list) = match body.split_once(':') {
        Some((n, l)) => (n.trim(), l.trim()),
        None => (body.trim(), ""),
    };
    if name.is_empty() {
        return Err(Error::Usage(format!(
            "'{atom}' has no integrand name; write NAME:key=value,..., e.g. disc:r=0.3"
        )));
    }
    let fam = family(name)?;
    let params = parse_params(fam, list)?;
    let f = (fam.build)(&params)?;
    match proj {
        None => Ok(f),
        Some(p) => {
            let proj = Projection::parse(p, 4).map_err(|_| {
                Error::Usage(format!(
                    "'{atom}': '@{p}' is not a projection of 4D; write two of x,y,u,v, e.g. @xu"
                ))
            })?;
            Ok(Box::new(Embed::new(Arc::from(f), proj)?))
        }
    }
}

fn parse_params(fam: &Family, list: &str) -> Result<Params> {
    let mut values: Vec<(String, f64)> = Vec::new();
    let known = || fam.keys.iter().map(|k| k.0).collect::<Vec<_>>().join(", ");
    for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let (key, value) = item.split_once('=').ok_or_else(|| {
            Error::Usage(format!(
                "{}: '{item}' is not key=value; the keys of {} are {}",
                fam.name,
                fam.name,
                known()
            ))
        })?;
        let key = key.trim();
        if !fam.keys.iter().any(|k| k.0 == key) {
            return Err(Error::Usage(format!(
                "{}: unknown key '{key}'; the keys of {} are {}",
                fam.name,
                fam.name,
                known()
            )));
        }
        if values.iter().any(|(k, _)| k == key) {
            return Err(Error::Usage(format!(
                "{}: key '{key}' is given twice",
                fam.name
            )));
        }
        let v: f64 = value.trim().parse().map_err(|_| {
            if value.trim().is_empty() {
                // `theta=+30` reaches here as `theta=`: '+' joins integrands into a sum.
                Error::Usage(format!(
                    "{}: {key}= has no value; give {key}=NUMBER (a '+' or '*' joins integrands, so a sign '+' cannot lead a number: write {key}=30, not {key}=+30)",
                    fam.name
                ))
            } else {
                Error::Usage(format!(
                    "{}: {key}={} is not a number",
                    fam.name,
                    value.trim()
                ))
            }
        })?;
        if !v.is_finite() {
            return Err(Error::Usage(format!(
                "{}: {key}={v} is not a finite number",
                fam.name
            )));
        }
        values.push((key.to_string(), v));
    }
    Ok(Params { values })
}

/// The help text of `anisospec integrands`: one block per family with its keys, then the grammar.
pub fn listing() -> String {
    let mut out = String::new();
    for f in FAMILIES {
        out.push_str(&format!("{:<10} {}\n", f.name, f.summary));
        for (k, meaning) in f.keys {
            out.push_str(&format!("    {k:<7} {meaning}\n"));
        }
    }
    out.push_str(
        "pixel      a depth-of-field pixel of the built-in scene (4D: x, y in the pixel, u, v on the lens)\n\
         \x20   px      column from the left, 0 to width - 1 (0 to 63 in the built-in scene); required\n\
         \x20   py      row from the top, 0 to height - 1 (0 to 63 in the built-in scene); required\n\
         \x20   scene   optional TOML scene file overriding camera, focus and aperture\n\
         \x20   refcount rays of the cached reference, a power of two from 1024 to 16777216 (default 1048576)\n",
    );
    out.push_str(
        "\nWrite NAME:key=value,... (e.g. step:theta=30). Append @PROJ (two of x,y,u,v) to place a 2D\n\
         integrand on a projection of 4D; join with * (factors on disjoint dimensions) and + (sums),\n\
         e.g. sheared:s=0.5@xu*sheared:s=0.5@yv or gaussian@xy+fan:s0=0.3,s1=0.7@xu.\n",
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pixel joined to other terms is told it stands alone, but a scene path holding `+`, `@` or
    /// `*` is a path (here a missing one, so the scene's own error).
    #[test]
    fn a_pixel_stands_alone_but_its_scene_path_is_free() {
        let message = |spec: &str| parse(spec).err().expect("refused").to_string();
        let alone = message("pixel:px=1,py=1,refcount=1024@xu");
        assert!(alone.contains("stands alone"), "{alone}");
        let path = message("pixel:px=1,py=1,scene=/nonexistent/c++/a@b*c.toml");
        assert!(
            !path.contains("stands alone") && path.contains("c++/a@b*c.toml"),
            "{path}"
        );
    }

    #[test]
    fn parses_atoms_sums_and_products() {
        let f = parse("step:theta=30").unwrap();
        assert_eq!(f.dims(), 2);
        assert!((f.reference().value - 0.5).abs() < 1e-15);
        let g = parse("sheared:s=0.5@xu + sheared:s=0.5@yv").unwrap();
        assert_eq!(g.dims(), 4);
        assert_eq!(
            g.spectral_planes().unwrap(),
            vec![Projection::XU, Projection::YV]
        );
        assert!((g.reference().value - 1.0).abs() < 1e-15);
        assert_eq!(g.eval(&[0.1, 0.9, 0.2, 0.9]), 1.0);
        let p = parse("gaussian:sigma=0.1@xy*disc:r=0.2@uv").unwrap();
        let r = p.reference().value;
        assert!(
            (r - 2.0 * std::f64::consts::PI * 0.01 * std::f64::consts::PI * 0.04).abs() < 1e-15
        );
        // f̂ of a product at a 4D frequency is the product of the factors' coefficients.
        let (a, b) = (
            parse("gaussian:sigma=0.1").unwrap(),
            parse("disc:r=0.2").unwrap(),
        );
        let want = a.fourier(&[1, 2]).unwrap() * b.fourier(&[3, -1]).unwrap();
        assert!((p.fourier(&[1, 2, 3, -1]).unwrap() - want).norm() < 1e-15);
        assert!(p.spectral_planes().is_none());
        assert!(parse("disc:r=1e-1").is_ok());
    }

    #[test]
    fn listing_names_every_family_and_key_and_each_parses() {
        let text = listing();
        for f in FAMILIES {
            assert!(text.contains(f.name));
            for (k, _) in f.keys {
                assert!(text.contains(&format!("    {k} ")), "{k}");
            }
            // Defaults build, and the name an integrand reports parses back to the same integrand.
            let g = parse(f.name).unwrap();
            let h = parse(&g.name()).unwrap();
            assert_eq!(g.name(), h.name());
            assert_eq!(g.reference(), h.reference());
        }
    }

    #[test]
    fn bad_specs_say_what_is_wrong() {
        let msg = |s: &str| {
            let e = parse(s).err().unwrap_or_else(|| panic!("{s} should fail"));
            assert_eq!(e.exit_code(), 2);
            e.to_string()
        };
        assert!(msg("blob:r=1").contains("gaussian, disc, step, sheared, fan"));
        assert!(msg("gaussian:sigma=-0.1").contains("sigma"));
        assert!(msg("disc:r=0.3,cx=0.1").contains("outside the domain"));
        assert!(msg("fan:s0=0.7,s1=0.3").contains("s0=0.7 > s1=0.3"));
        assert!(msg("disc:radius=0.3").contains("unknown key 'radius'"));
        assert!(msg("disc:r=abc").contains("not a number"));
        // A leading '+' splits the spec into a sum: the empty value says so.
        assert!(msg("step:theta=+30").contains("step: theta= has no value; give theta=NUMBER"));
        assert!(msg("disc@xq").contains("not a projection"));
        assert!(msg("gaussian*disc").contains("share a dimension"));
        assert!(msg("gaussian+disc@uv").contains("mixes"));
        assert!(msg("").contains("empty"));
        assert!(msg("pixel").contains("pixel:px="));
        assert!(msg("pixel@xu").contains("pixel:px="));
    }
}
