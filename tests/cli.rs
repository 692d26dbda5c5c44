//! The command line: a round trip through files, and bad input (exit code 2, a clear message, no output
//! file, inputs untouched).

use anisospec::compare::config::CompareConfig;
use std::path::{Path, PathBuf};
use std::process::Command;

fn anisospec(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_anisospec"))
        .args(args)
        .output()
        .expect("the binary runs")
}

fn tmp(name: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    (dir, path)
}

/// Runs `args`, expects exit code 2 with a message containing `needle`, and no file at `out`.
fn rejects(args: &[&str], needle: &str, out: &Path) {
    refused(&anisospec(args), args, needle, out);
}

/// The address space, in KiB, [`rejects_in_small_memory`] gives the binary: 256 MiB, far below the
/// gigabytes the refused sizes would take, and several times what a refusal needs.
#[cfg(target_os = "linux")]
const SMALL_MEMORY_KIB: u64 = 256 * 1024;

/// Runs the binary with `args` under `ulimit -v` of [`SMALL_MEMORY_KIB`] (Linux enforces it on every
/// allocation).
#[cfg(target_os = "linux")]
fn anisospec_in_small_memory(args: &[&str]) -> std::process::Output {
    Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v {SMALL_MEMORY_KIB} && exec \"$0\" \"$@\""
        ))
        .arg(env!("CARGO_BIN_EXE_anisospec"))
        .args(args)
        .output()
        .expect("sh runs")
}

/// [`rejects`] in a small address space: a refusal that came only after allocating the refused size
/// would abort on the failed allocation instead of exiting with 2.
#[cfg(target_os = "linux")]
fn rejects_in_small_memory(args: &[&str], needle: &str, out: &Path) {
    refused(&anisospec_in_small_memory(args), args, needle, out);
}

/// Checks that the run `o` of `args` exited with 2 and a message containing `needle`, and left no
/// file at `out`.
fn refused(o: &std::process::Output, args: &[&str], needle: &str, out: &Path) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{args:?} exited {:?}: {err}",
        o.status.code()
    );
    assert!(
        err.to_lowercase().contains(&needle.to_lowercase()),
        "{args:?}: '{err}' lacks '{needle}'"
    );
    assert!(!out.exists(), "{args:?} left {}", out.display());
}

#[test]
fn sample_then_spectrum_round_trip() {
    let (dir, pts) = tmp("mj.npy");
    let o = anisospec(&[
        "sample",
        "--sampler",
        "mj",
        "-n",
        "64",
        "--sets",
        "8",
        "--seed",
        "3",
        "-o",
        pts.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let txt = dir.path().join("mj.txt");
    let o = anisospec(&[
        "sample",
        "--sampler",
        "mj",
        "-n",
        "64",
        "--sets",
        "8",
        "--seed",
        "3",
        "-o",
        txt.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    let a = anisospec::points::io::read_points(&pts).unwrap();
    let b = anisospec::points::io::read_points(&txt).unwrap();
    assert_eq!(a, b, "npy and text hold the same numbers");
    let spec = dir.path().join("s.npy");
    let png = dir.path().join("s.png");
    let radial = dir.path().join("r.csv");
    let o = anisospec(&[
        "spectrum",
        "--input",
        pts.to_str().unwrap(),
        "--res",
        "16",
        "--exact",
        "-o",
        &format!("{},{}", spec.display(), png.display()),
        "--radial",
        radial.to_str().unwrap(),
        "--cones",
        "4",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(png.exists() && radial.exists());
    let bytes = std::fs::read(&spec).unwrap();
    let npy = npyz::NpyFile::new(&bytes[..]).unwrap();
    assert_eq!(npy.shape(), &[16, 16]);
    let values: Vec<f64> = npy.into_vec().unwrap();
    // P(0) = N.
    assert!((values[8 * 16 + 8] - 64.0).abs() < 1e-9);
}

#[test]
fn bad_sampler_and_n_are_rejected() {
    let (_d, out) = tmp("x.npy");
    let o = out.to_str().unwrap();
    rejects(
        &["sample", "--sampler", "nosuch", "-n", "16", "-o", o],
        "nosuch",
        &out,
    );
    rejects(
        &["sample", "--sampler", "jittered", "-n", "50", "-o", o],
        "49",
        &out,
    );
    rejects(
        &["spectrum", "--sampler", "jittered", "-n", "50", "-o", o],
        "49",
        &out,
    );
    // Dart throwing and Lloyd relaxation cost more than linearly in N: capped, not left to run for hours.
    let above = (anisospec::samplers::disk::DISK_MAX_N + 1).to_string();
    for name in ["poisson", "blue", "padded-blue"] {
        rejects(
            &[
                "sample",
                "--sampler",
                name,
                "--dims",
                if name.starts_with("padded") { "4" } else { "2" },
                "-n",
                &above,
                "-o",
                o,
            ],
            &anisospec::samplers::disk::DISK_MAX_N.to_string(),
            &out,
        );
    }
}

#[test]
fn bad_resolution_is_rejected() {
    let (_d, out) = tmp("x.npy");
    let o = out.to_str().unwrap();
    rejects(
        &[
            "spectrum",
            "--sampler",
            "random",
            "-n",
            "16",
            "--res",
            "15",
            "-o",
            o,
        ],
        "even",
        &out,
    );
    rejects(
        &[
            "spectrum",
            "--sampler",
            "random",
            "-n",
            "16",
            "--res",
            "0",
            "-o",
            o,
        ],
        "even",
        &out,
    );
}

/// The scene file a pixel integrand names (`pixel:...,scene=FILE`) is an input too: converge's CSV or
/// plot, or variance's CSV, of that name is refused with exit 2 and the scene left as it was.
#[test]
fn a_pixel_scene_file_is_never_an_output() {
    let (dir, csv) = tmp("scene.csv");
    std::fs::write(&csv, "aperture = 0.05\n").unwrap();
    let png = dir.path().join("scene.png");
    std::fs::write(&png, "aperture = 0.05\n").unwrap();
    for scene in [&csv, &png] {
        let s = scene.to_str().unwrap();
        let pixel = format!("pixel:px=20,py=20,scene={s},refcount=64");
        let out_flag = if scene == &csv { "-o" } else { "--plot" };
        for args in [
            vec![
                "converge",
                "--sampler",
                "sobol",
                "--integrand",
                &pixel,
                "-n",
                "16",
                "--realizations",
                "2",
                out_flag,
                s,
            ],
            vec![
                "variance",
                "--sampler",
                "sobol",
                "--integrand",
                &pixel,
                "-n",
                "16",
                "-o",
                s,
            ],
        ] {
            if args[0] == "variance" && scene == &png {
                continue;
            }
            let o = anisospec(&args);
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
            assert!(err.contains("is the input file"), "{args:?}: {err}");
            assert_eq!(std::fs::read_to_string(scene).unwrap(), "aperture = 0.05\n");
        }
    }
}

/// Outputs are checked against every input and against each other before any work: a table used as a
/// sampler or as the optimizer's start, two outputs with one name, a file where a folder must go.
#[test]
fn outputs_never_clobber_tables_or_each_other() {
    let (dir, table) = tmp("p.npy");
    let t = table.to_str().unwrap();
    let o = anisospec(&["sample", "--sampler", "random", "-n", "16", "-o", t]);
    assert!(o.status.success());
    let before = std::fs::read(&table).unwrap();
    let sampler = format!("table:{t}");
    for args in [
        vec!["sample", "--sampler", &sampler, "-n", "16", "-o", t],
        vec![
            "spectrum",
            "--sampler",
            &sampler,
            "-n",
            "16",
            "--res",
            "8",
            "-o",
            t,
        ],
        vec![
            "optimize",
            "--target",
            "targets/blue-noise.toml",
            "-n",
            "16",
            "--init",
            &sampler,
            "-o",
            t,
        ],
    ] {
        let o = anisospec(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("is the input file"), "{args:?}: {err}");
        assert_eq!(
            std::fs::read(&table).unwrap(),
            before,
            "{args:?} changed the table"
        );
    }
    let twice = dir.path().join("a.npy");
    let twice = twice.to_str().unwrap();
    rejects(
        &[
            "spectrum", "--input", t, "--res", "8", "-o", twice, "--stderr", twice,
        ],
        "name the same output file",
        Path::new(twice),
    );
    let first = dir.path().join("ok.npy");
    let blocked = format!("{t}/x.png");
    rejects(
        &[
            "spectrum",
            "--input",
            t,
            "--res",
            "8",
            "-o",
            &format!("{},{blocked}", first.display()),
        ],
        "is a file, not a folder",
        &first,
    );
    assert_eq!(std::fs::read(&table).unwrap(), before);
}

/// Values so large they would exhaust memory, lose all precision or overflow a solver end in exit 2
/// and a message naming the limit.
#[test]
fn extreme_values_are_refused() {
    let (dir, out) = tmp("x.npy");
    let o = out.to_str().unwrap();
    let long = dir.path().join("long.toml");
    std::fs::write(
        &long,
        "kind = \"hairline\"\nshear = 0.0\nhalf_width = 0.0\nlength = 1024\ninner_radius = 0.0\n",
    )
    .unwrap();
    let huge = dir.path().join("huge.toml");
    std::fs::write(
        &huge,
        "kind = \"hairline\"\nshear = 0.0\nhalf_width = 0.0\nlength = 1e300\ninner_radius = 0.0\n",
    )
    .unwrap();
    let cases: [(Vec<&str>, &str); 7] = [
        (
            vec![
                "spectrum",
                "--sampler",
                "random",
                "-n",
                "16",
                "--res",
                "1000000",
                "-o",
                o,
            ],
            "above the largest grid",
        ),
        (
            vec![
                "sample",
                "--sampler",
                "random",
                "--dims",
                "4",
                "-n",
                "16",
                "--shear",
                "1e17,1e17",
                "-o",
                o,
            ],
            "magnitude at most",
        ),
        (
            vec![
                "converge",
                "--sampler",
                "padded-mj",
                "--integrand",
                "fan:s0=-1e16,s1=1e16@xu",
                "-n",
                "16,64",
            ],
            "beyond the largest shear",
        ),
        (
            vec![
                "optimize",
                "--target",
                "targets/blue-noise.toml",
                "-n",
                "16",
                "--max-seconds",
                "1e20",
                "-o",
                o,
            ],
            "at most",
        ),
        (
            vec![
                "optimize",
                "--target",
                "targets/blue-noise.toml",
                "-n",
                "16",
                "--repulsion-weight",
                "1e300",
                "-o",
                o,
            ],
            "give a weight from 0",
        ),
        (
            vec![
                "optimize",
                "--target",
                long.to_str().unwrap(),
                "-n",
                "16",
                "-o",
                o,
            ],
            "beyond the largest grid",
        ),
        (
            vec![
                "optimize",
                "--target",
                huge.to_str().unwrap(),
                "-n",
                "16",
                "-o",
                o,
            ],
            "'length' is 1e300; it is a width or radius in units of sqrt(N) and must lie in [0, 1024]",
        ),
    ];
    for (args, needle) in &cases {
        rejects(args, needle, &out);
    }
}

/// A number the user gave is echoed in short form: a shear of 1e-300 in the sampler's label, an eps
/// of 1e-300 in the refusal, not as 300 digits.
#[test]
fn tiny_numbers_are_echoed_in_short_form() {
    let (_dir, out) = tmp("s.npy");
    let o = out.to_str().unwrap();
    let run = anisospec(&[
        "sample",
        "--sampler",
        "padded-mj",
        "--dims",
        "4",
        "-n",
        "16",
        "--shear",
        "1e-300,0.5",
        "-o",
        o,
    ]);
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{err}");
    assert!(
        err.contains("padded-mj+shear(1e-300,0.5,transported)"),
        "{err}"
    );
    let (_dir2, png) = tmp("s.png");
    rejects(
        &[
            "spectrum",
            "--sampler",
            "random",
            "-n",
            "16",
            "--eps",
            "1e-300",
            "-o",
            png.to_str().unwrap(),
        ],
        "NUFFT tolerance 1e-300 is out of range",
        &png,
    );
    // An integrand's messages and its name: a fan of one tiny shear, and an edge sheared by one.
    let fan = anisospec(&[
        "converge",
        "--sampler",
        "random",
        "--integrand",
        "fan:s0=1e-300,s1=1e-300@xu",
        "-n",
        "16",
    ]);
    let err = String::from_utf8_lossy(&fan.stderr);
    assert_eq!(fan.status.code(), Some(2), "{err}");
    assert!(err.contains("s0 = s1 = 1e-300 is a single edge"), "{err}");
    let edge = anisospec(&[
        "converge",
        "--sampler",
        "random",
        "--integrand",
        "sheared:s=1e-300,c=0.5@xu",
        "-n",
        "16",
        "--realizations",
        "4",
    ]);
    let text = String::from_utf8_lossy(&edge.stdout);
    assert!(edge.status.success(), "{text}");
    assert!(
        text.contains("integrand sheared:s=1e-300,c=0.5@xu"),
        "{text}"
    );
}

/// converge's CSV quotes sampler names, which hold commas once sheared: every row has the header's
/// eleven fields.
#[test]
fn converge_csv_quotes_sheared_sampler_names() {
    let (_dir, csv) = tmp("c.csv");
    let o = anisospec(&[
        "converge",
        "--sampler",
        "padded-mj",
        "--integrand",
        "sheared:s=0.5@xu",
        "-n",
        "16,64",
        "--realizations",
        "8",
        "--shear",
        "0.5,0.5",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&csv).unwrap();
    for line in text.lines().skip(1) {
        let mut fields = 0;
        let mut quoted = false;
        for c in line.chars() {
            match c {
                '"' => quoted = !quoted,
                ',' if !quoted => fields += 1,
                _ => {}
            }
        }
        assert_eq!(fields + 1, 11, "{line}");
    }
}

#[test]
fn projection_must_fit_dimensions() {
    let (_d, out) = tmp("x.npy");
    let o = out.to_str().unwrap();
    // xu does not fit 2D; -1,2 is no projection (taken for a flag by clap before, 'unexpected
    // argument').
    for (proj, needle) in [
        ("xu", "--proj"),
        ("-1,2", "--proj '-1,2' is not a projection"),
    ] {
        rejects(
            &[
                "spectrum",
                "--sampler",
                "random",
                "-n",
                "16",
                "--proj",
                proj,
                "-o",
                o,
            ],
            needle,
            &out,
        );
    }
}

#[test]
fn bad_point_files_are_rejected_and_left_untouched() {
    let cases: [(&str, &str, &str); 7] = [
        ("empty.txt", "", "no points"),
        ("garbage.txt", "0.1 0.2\n0.3 oops\n", "not a number"),
        ("ragged.txt", "0.1 0.2\n0.3\n", "coordinates"),
        ("nan.txt", "0.1 0.2\nNaN 0.5\n", "finite"),
        ("inf.txt", "0.1 0.2\n-inf 0.5\n", "is -inf"),
        (
            "huge.txt",
            "0.1 0.2\n0.5 1e400\n",
            "line 2: '1e400' is beyond the range",
        ),
        ("range.txt", "0.1 0.2\n1.5 0.5\n", "[0, 1)"),
    ];
    for (name, content, needle) in cases {
        let (dir, input) = tmp(name);
        std::fs::write(&input, content).unwrap();
        let out = dir.path().join("spec.npy");
        rejects(
            &[
                "spectrum",
                "--input",
                input.to_str().unwrap(),
                "--res",
                "8",
                "-o",
                out.to_str().unwrap(),
            ],
            needle,
            &out,
        );
        assert_eq!(
            std::fs::read_to_string(&input).unwrap(),
            content,
            "{name} was modified"
        );
    }
    // A truncated npy file.
    let (dir, input) = tmp("cut.npy");
    std::fs::write(&input, b"\x93NUMPY\x01\x00").unwrap();
    let out = dir.path().join("spec.npy");
    rejects(
        &[
            "spectrum",
            "--input",
            input.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ],
        "npy",
        &out,
    );
}

/// A version-1 npy file of `<f8` values: the header's `shape` text, its order flag, the values.
fn npy_bytes(shape: &str, fortran: bool, values: &[f64]) -> Vec<u8> {
    let order = if fortran { "True" } else { "False" };
    let mut header = format!("{{'descr': '<f8', 'fortran_order': {order}, 'shape': {shape}, }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend(u16::try_from(header.len()).unwrap().to_le_bytes());
    bytes.extend(header.as_bytes());
    bytes.extend(values.iter().flat_map(|v| v.to_le_bytes()));
    bytes
}

#[test]
fn fortran_order_npy_gives_the_same_points_and_spectrum() {
    let (sets, n, dims) = (3, 20, 2);
    // Distinct values in [0, 1): any mix-up of the axes changes the points.
    let c: Vec<f64> = (0..sets * n * dims)
        .map(|i| ((i * 37) % 120) as f64 / 120.0)
        .collect();
    let mut f = vec![0.0; c.len()];
    for s in 0..sets {
        for j in 0..n {
            for d in 0..dims {
                f[s + sets * (j + n * d)] = c[(s * n + j) * dims + d];
            }
        }
    }
    let (dir, c_file) = tmp("c.npy");
    let f_file = dir.path().join("f.npy");
    std::fs::write(&c_file, npy_bytes("(3, 20, 2)", false, &c)).unwrap();
    std::fs::write(&f_file, npy_bytes("(3, 20, 2)", true, &f)).unwrap();
    let a = anisospec::points::io::read_points(&c_file).unwrap();
    let b = anisospec::points::io::read_points(&f_file).unwrap();
    assert_eq!(a.data(), &c[..]);
    assert_eq!(a, b);
    let mut spectra = Vec::new();
    for (input, name) in [(&c_file, "sc.npy"), (&f_file, "sf.npy")] {
        let out = dir.path().join(name);
        let o = anisospec(&[
            "spectrum",
            "--input",
            input.to_str().unwrap(),
            "--res",
            "8",
            "--exact",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        spectra.push(std::fs::read(&out).unwrap());
    }
    assert_eq!(spectra[0], spectra[1]);
}

#[test]
fn npy_headers_that_overflow_or_lie_are_rejected() {
    // 2^62 x 2^62 x 4 elements wrap to 0 unchecked; then the empty data matched and spectrum hung.
    let cases = [
        (
            "(4611686018427387904, 4611686018427387904, 4)",
            0,
            "more elements",
        ),
        ("(1, 16, 2)", 30, "cut short"),
        ("(1, 16, 2)", 34, "header is wrong"),
    ];
    for (shape, values, needle) in cases {
        let (dir, input) = tmp("crafted.npy");
        let bytes = npy_bytes(shape, false, &vec![0.5; values]);
        std::fs::write(&input, &bytes).unwrap();
        let out = dir.path().join("spec.npy");
        rejects(
            &[
                "spectrum",
                "--input",
                input.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
            ],
            needle,
            &out,
        );
        assert_eq!(std::fs::read(&input).unwrap(), bytes);
    }
}

/// Sizes above the coordinate limit are refused before their points are allocated: each refusal runs
/// in an address space far smaller than the refused size, where an allocation first would abort
/// (Linux only: it relies on `ulimit -v` being enforced).
#[cfg(target_os = "linux")]
#[test]
fn sizes_above_the_coordinate_limit_are_refused_at_once() {
    let (dir, out) = tmp("big.npy");
    let o = out.to_str().unwrap();
    // The limit bites: a size within the coordinate limit (2^26 coordinates, 512 MiB) that the small
    // address space cannot hold fails, with no refusal and no file.
    let big =
        anisospec_in_small_memory(&["sample", "--sampler", "random", "-n", "33554432", "-o", o]);
    assert!(
        !big.status.success() && big.status.code() != Some(2),
        "{:?}: {}",
        big.status,
        String::from_utf8_lossy(&big.stderr)
    );
    assert!(!out.exists());
    rejects_in_small_memory(
        &["sample", "--sampler", "random", "-n", "1000000000", "-o", o],
        "2000000000 coordinates (14.9 GiB) is above the limit",
        &out,
    );
    let csv = dir.path().join("big.csv");
    let huge = [
        ("sample --sampler random -n 18446744073709551615", &out),
        (
            "sample --sampler random -n 4611686018427387904 --sets 4",
            &out,
        ),
        // Each set fits, all eight together do not.
        ("sample --sampler random -n 67108864 --sets 8", &out),
        ("spectrum --sampler random -n 1000000000", &out),
        ("spectrum --sampler random -n 1000000000 --dims 4", &out),
        (
            "variance --sampler random --integrand disc -n 16,1000000000",
            &csv,
        ),
        (
            "converge --sampler random --integrand disc -n 16,1000000000",
            &csv,
        ),
    ];
    for (command, file) in huge {
        let mut args: Vec<&str> = command.split_whitespace().collect();
        args.extend(["-o", file.to_str().unwrap()]);
        rejects_in_small_memory(&args, "use a smaller N", file);
    }
}

#[test]
fn missing_input_files_are_input_errors() {
    let (dir, out) = tmp("out.npy");
    let o = out.to_str().unwrap();
    let missing = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let (points, table, folder) = (
        missing("nonexist.npy"),
        missing("missing.npy"),
        missing("nodir"),
    );
    rejects(
        &["spectrum", "--input", &points, "-o", o],
        "nonexist.npy",
        &out,
    );
    for sampler in [
        format!("table:{table}"),
        format!("table:{folder}/t{{n}}.npy"),
    ] {
        rejects(
            &["spectrum", "--sampler", &sampler, "-n", "16", "-o", o],
            "check the path",
            &out,
        );
    }
    let target = missing("missing.toml");
    rejects(
        &["optimize", "--target", &target, "-n", "16", "-o", o],
        "missing.toml",
        &out,
    );
    // A target whose image is missing: the message names the target, then its image.
    let image_target = dir.path().join("image.toml");
    std::fs::write(
        &image_target,
        "kind = \"image\"\nfile = \"no-image.npy\"\nextent = 1.0\n",
    )
    .unwrap();
    rejects(
        &[
            "optimize",
            "--target",
            image_target.to_str().unwrap(),
            "-n",
            "16",
            "-o",
            o,
        ],
        &format!(
            "{}: its image: {}: the target image does not exist; check the 'file' key",
            image_target.display(),
            dir.path().join("no-image.npy").display()
        ),
        &out,
    );
    let report = dir.path().join("report");
    rejects(
        &[
            "compare",
            "--config",
            &missing("study.toml"),
            "--out",
            report.to_str().unwrap(),
        ],
        "check the path",
        &report,
    );
}

#[test]
fn output_never_clobbers_input() {
    let (_dir, input) = tmp("pts.npy");
    let o = anisospec(&[
        "sample",
        "--sampler",
        "random",
        "-n",
        "16",
        "-o",
        input.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    let before = std::fs::read(&input).unwrap();
    let o = anisospec(&[
        "spectrum",
        "--input",
        input.to_str().unwrap(),
        "--res",
        "8",
        "-o",
        input.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(std::fs::read(&input).unwrap(), before);
}

#[test]
fn compare_rejects_a_bad_config_before_any_work() {
    let (dir, config) = tmp("study.toml");
    let out = dir.path().join("report");
    std::fs::write(&config, "ns = [16, 64]\nrealisations = 10\n").unwrap();
    let o = out.to_str().unwrap();
    let c = config.to_str().unwrap();
    rejects(
        &["compare", "--config", c, "--out", o],
        "realisations",
        &out,
    );
    std::fs::write(&config, "ns = [16]\n").unwrap();
    rejects(&["compare", "--config", c, "--out", o], "study.toml", &out);
    // A whole config with one bad name, caught before any sampler runs.
    type Mend = fn(&mut CompareConfig);
    let cases: [(Mend, &str); 6] = [
        (|c| c.sheared.push("padded-nosuch".into()), "padded-nosuch"),
        (
            |c| c.tables.push("targets/missing.toml".into()),
            "missing.toml",
        ),
        (
            |c| c.analytic[0].spec = "fan:s0=0.3,s1=0.7".into(),
            "place a 2D one",
        ),
        (|c| c.ns = vec![16, 64, 16], "N = 16 twice"),
        (
            |c| c.analytic[1].label = c.analytic[0].label.clone(),
            "labelled",
        ),
        (|c| c.analytic[0].label = "a | b".into(), "markdown"),
    ];
    for (mend, needle) in cases {
        let mut study = CompareConfig::default_suite();
        mend(&mut study);
        std::fs::write(&config, toml::to_string(&study).unwrap()).unwrap();
        rejects(&["compare", "--config", c, "--out", o], needle, &out);
    }
}

/// A compare config may leave keys out: each takes the built-in default's value. An `[[analytic]]`
/// entry is one integrand and still needs all its keys; an unknown key is still refused.
#[test]
fn compare_config_fills_left_out_keys_from_the_default() {
    let (_dir, config) = tmp("study.toml");
    std::fs::write(&config, "ns = [16, 64]\nrealizations = 8\n").unwrap();
    let expected = CompareConfig {
        ns: vec![16, 64],
        realizations: 8,
        ..CompareConfig::default_suite()
    };
    assert_eq!(CompareConfig::load(&config).unwrap(), expected);

    let entry = "[[analytic]]\nlabel = \"edge\"\nspec = \"sheared:s=0.5@xu\"\nshear = [0.5, 0.5]\n";
    std::fs::write(&config, format!("{entry}shear_range = [0.5, 0.5]\n")).unwrap();
    let study = CompareConfig::load(&config).unwrap();
    assert_eq!(
        study.analytic.len(),
        1,
        "analytic replaces the default's list"
    );
    assert_eq!(study.analytic[0].label, "edge");
    assert_eq!(study.ns, CompareConfig::default_suite().ns);

    for (text, needle) in [
        (entry.to_string(), "shear_range"),
        (
            format!("{entry}shear_range = [0.5, 0.5]\nwidth = 2\n"),
            "width",
        ),
        ("realizations = 8\nseeds = 3\n".to_string(), "seeds"),
    ] {
        std::fs::write(&config, &text).unwrap();
        let err = CompareConfig::load(&config).unwrap_err();
        assert_eq!(err.exit_code(), 2, "{text}");
        assert!(
            err.to_string().contains(needle),
            "{text}: '{err}' lacks '{needle}'"
        );
    }
}

/// `compare --print-config` prints the study it would run as TOML that loads back to the same config,
/// runs nothing and writes no file; with `--config` it prints the file's study, defaults filled in.
#[test]
fn compare_print_config_prints_the_study_as_toml() {
    let dir = tempfile::tempdir().unwrap();
    let print = |args: &[&str], cwd: &Path| {
        let o = Command::new(env!("CARGO_BIN_EXE_anisospec"))
            .args(["compare", "--print-config"])
            .args(args)
            .current_dir(cwd)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{args:?}: {err}");
        assert!(err.is_empty(), "{args:?} wrote to stderr: {err}");
        toml::from_str::<CompareConfig>(&String::from_utf8(o.stdout).unwrap()).unwrap()
    };
    assert_eq!(print(&[], dir.path()), CompareConfig::default_suite());
    assert_eq!(print(&["--full"], dir.path()), CompareConfig::full_suite());
    assert_eq!(
        print(&["--seed", "7"], dir.path()),
        CompareConfig {
            seed: 7,
            ..CompareConfig::default_suite()
        }
    );
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "a file was written"
    );

    // A partial file, read where its default table targets are found (the crate's root).
    let config = dir.path().join("study.toml");
    std::fs::write(&config, "ns = [16, 64]\nrealizations = 8\n").unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    assert_eq!(
        print(&["--config", config.to_str().unwrap()], root),
        CompareConfig {
            ns: vec![16, 64],
            realizations: 8,
            ..CompareConfig::default_suite()
        }
    );

    // Nothing is written, so --out and --cache would be ignored: refused.
    let out = dir.path().join("report");
    for flag in ["--out", "--cache"] {
        rejects(
            &["compare", "--print-config", flag, out.to_str().unwrap()],
            "--print-config",
            &out,
        );
    }
}

/// Numbers and names in a compare config that would fail late, panic, write a number that is not one,
/// or overwrite one output with another are refused up front: exit 2, a message naming the config key
/// (not a command-line flag), and no report folder.
#[test]
fn compare_rejects_bad_numbers_and_clashing_names_before_any_work() {
    let (dir, config) = tmp("study.toml");
    let out = dir.path().join("report");
    let o = out.to_str().unwrap();
    let c = config.to_str().unwrap();
    type Mend = fn(&mut CompareConfig);
    let cases: Vec<(Mend, &str)> = vec![
        (|c| c.table_seconds = f64::NAN, "table_seconds = NaN"),
        (
            |c| {
                c.ns = vec![16, 1_000_000];
                c.classical = vec!["sobol".into()];
                c.sheared = vec!["sobol".into()];
                c.tables.clear();
            },
            "no sampler of the study makes N = 1000000",
        ),
        (|c| c.table_seconds = 1e20, "at most 1e6"),
        (|c| c.table_seconds = -1.0, "table_seconds = -1"),
        (
            |c| c.analytic[0].shear = [f64::NAN; 2],
            "shear = [NaN, NaN]",
        ),
        (
            |c| c.analytic[1].shear_range = [f64::NAN; 2],
            "shear_range = [NaN, NaN]",
        ),
        (
            |c| c.analytic[1].shear_range = [0.3, 1e7],
            "at most 1e6 in magnitude",
        ),
        (|c| c.oracle_errors = vec![0.1, 1e3], "at most 100"),
        (
            |c| c.analytic[0].shear = [9e5, 0.5],
            "above the largest shear",
        ),
        (|c| c.spectra_res = 7, "spectra_res = 7"),
        (|c| c.spectra_res = 0, "spectra_res = 0"),
        (
            |c| c.spectra_res = 100_000,
            "spectra_res = 100000 is above the largest grid",
        ),
        (|c| c.spectra_n = 0, "spectra_n = 0"),
        (|c| c.spectra_realizations = 0, "spectra_realizations = 0"),
        (|c| c.classical.clear(), "classical is empty"),
        (|c| c.ns = vec![16, 1 << 40], "ns: "),
        (
            |c| c.oracle_errors = vec![-0.1, 0.0],
            "oracle_errors holds 0",
        ),
        (|c| c.oracle_errors.clear(), "oracle_errors is empty"),
        (
            |c| c.oracle_errors = vec![0.1, -0.1, 0.1],
            "oracle_errors lists 0.1 twice",
        ),
        (
            |c| c.shear_modes.clear(),
            "shear_modes is empty, so none would run",
        ),
        (|c| c.table_sets = 0, "table_sets = 0"),
        (
            |c| c.ns = vec![1, 16],
            "cannot be built at N = 1 (from ns): a 4D table keeps its xy and uv stratified by a blue-noise disc of radius 0.35 sqrt(N), which reaches a frequency cell from N = 9 on",
        ),
        (
            |c| c.spectra_n = 1,
            "cannot be built at N = 1 (from spectra_n)",
        ),
        (
            |c| {
                c.analytic[0].label = "edge a".into();
                c.analytic[1].label = "edge-a".into();
            },
            "'edge a' and 'edge-a' both make the file name 'edge_a'",
        ),
        (
            |c| c.analytic[0].label = "!!!".into(),
            "'!!!' has no ASCII letter or digit",
        ),
        (
            |c| c.analytic[0].label = "a".repeat(300),
            "makes a file name part of 300 characters",
        ),
        (
            |c| c.classical = vec!["random".into(), "random".into()],
            "classical lists 'random' twice",
        ),
        (
            |c| c.shear_modes.push(c.shear_modes[0]),
            "shear_modes lists 'transported' twice",
        ),
        (
            |c| c.tables.push("./targets/hairline.toml".into()),
            "both would be 'optimized hairline'",
        ),
        (
            |c| {
                c.analytic.clear();
                c.pixel_classes.clear();
            },
            "nothing to integrate",
        ),
        (
            |c| c.pixel_classes.push("hairline".into()),
            "pixel_classes lists 'hairline' twice",
        ),
        (|c| c.pixel_reference_count = 1000, "pixel_reference_count"),
    ];
    for (mend, needle) in cases {
        let mut study = CompareConfig::default_suite();
        mend(&mut study);
        std::fs::write(&config, toml::to_string(&study).unwrap()).unwrap();
        let args = ["compare", "--config", c, "--out", o];
        rejects(&args, needle, &out);
        let err = String::from_utf8_lossy(&anisospec(&args).stderr).into_owned();
        assert!(
            !err.contains(" --") && !err.contains(" -n "),
            "{needle}: '{err}' names a flag"
        );
    }
}

/// An analytic label that makes the same file name as a pixel's (known only once the oracle has
/// picked the pixel) is refused before anything is measured or written.
#[test]
fn compare_rejects_a_label_clashing_with_a_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let mut study = CompareConfig {
        pixel_classes: vec!["hairline".into()],
        pixel_reference_count: 1 << 10,
        ..CompareConfig::default_suite()
    };
    let pixel = anisospec::compare::subjects(&study, dir.path()).unwrap()[3]
        .label
        .clone();
    study.analytic[0].label = pixel.replace(' ', "-").to_uppercase();
    let config = dir.path().join("study.toml");
    std::fs::write(&config, toml::to_string(&study).unwrap()).unwrap();
    let out = dir.path().join("report");
    rejects(
        &[
            "compare",
            "--config",
            config.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--cache",
            dir.path().join("cache").to_str().unwrap(),
        ],
        &format!(
            "'{}' and '{pixel}' both make the file name",
            study.analytic[0].label
        ),
        &out,
    );
}

/// A report folder (or a cache folder) that is, or lies under, an existing file is refused before
/// any work, and the file is left as it was.
#[test]
fn compare_refuses_an_output_folder_that_is_a_file() {
    let (dir, file) = tmp("taken");
    std::fs::write(&file, "mine").unwrap();
    let f = file.to_str().unwrap();
    let under = file.join("report");
    let report = dir.path().join("report");
    let cases = [
        (vec!["--out", f], "--out"),
        (vec!["--out", under.to_str().unwrap()], "lies under"),
        (
            vec!["--out", report.to_str().unwrap(), "--cache", f],
            "--cache",
        ),
    ];
    for (flags, needle) in cases {
        let mut args = vec!["compare"];
        args.extend(&flags);
        let o = anisospec(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains(needle) && err.contains("not a folder"),
            "{args:?}: '{err}' lacks '{needle}'"
        );
        assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");
        assert!(!report.exists());
    }
}

/// A report folder that holds other files (not an earlier report, which a new one replaces) is refused
/// before any work, naming a file, and so is a cache inside the report folder; nothing is written and
/// the files stay as they were.
#[test]
fn compare_refuses_a_folder_of_other_files_and_a_cache_inside_the_report() {
    let dir = tempfile::tempdir().unwrap();
    let sources = dir.path().join("sources");
    std::fs::create_dir_all(&sources).unwrap();
    std::fs::write(sources.join("hairline.toml"), "mine").unwrap();
    let cache = dir.path().join("cache");
    let o = anisospec(&[
        "compare",
        "--out",
        sources.to_str().unwrap(),
        "--cache",
        cache.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("hairline.toml") && err.contains("no report.md"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_to_string(sources.join("hairline.toml")).unwrap(),
        "mine"
    );
    assert_eq!(std::fs::read_dir(&sources).unwrap().count(), 1);
    assert!(!cache.exists());

    let report = dir.path().join("report");
    for inside in [report.join("cache"), report.clone()] {
        rejects(
            &[
                "compare",
                "--out",
                report.to_str().unwrap(),
                "--cache",
                inside.to_str().unwrap(),
            ],
            "inside the report folder",
            &report,
        );
    }
}

/// `anisospec gallery`: an index row per sampler (11 in 2D, 9 in 4D), each linking a PNG and a radial
/// CSV that exist, beside an npy spectrum with `P(0) = N` (the N the index gives); and the two contact
/// sheets.
#[test]
fn gallery_writes_every_sampler() {
    let dir = tempfile::tempdir().unwrap();
    let o = anisospec(&[
        "gallery",
        "--out",
        dir.path().to_str().unwrap(),
        "-n",
        "64",
        "--res",
        "16",
        "--realizations",
        "4",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let gallery = dir.path().join("gallery");
    let index = std::fs::read_to_string(gallery.join("index.md")).unwrap();
    let rows: Vec<&str> = index
        .lines()
        .filter(|l| l.starts_with("| ") && l.contains(".png"))
        .collect();
    assert_eq!(rows.len(), 20, "{index}");
    for name in ["2d_lattice_xy", "4d_lattice_xu"] {
        assert!(index.contains(&format!("({name}.png)")), "{name} missing");
    }
    for row in &rows {
        let stem = row
            .split("](")
            .nth(1)
            .unwrap()
            .split(".png")
            .next()
            .unwrap();
        assert!(gallery.join(format!("{stem}.png")).exists(), "{stem}.png");
        assert!(
            gallery.join(format!("{stem}_radial.csv")).exists(),
            "{stem} csv"
        );
        let bytes = std::fs::read(gallery.join(format!("{stem}.npy"))).unwrap();
        let npy = npyz::NpyFile::new(&bytes[..]).unwrap();
        assert_eq!(npy.shape(), &[16, 16], "{stem}");
        let values: Vec<f64> = npy.into_vec().unwrap();
        // The N the sampler made (its nearest valid N to 64), from the row's N column.
        let n: f64 = row.split('|').nth(4).unwrap().trim().parse().unwrap();
        // The gallery's NUFFT (eps = 1e-6) keeps P within 10 eps relative.
        assert!(
            (values[8 * 16 + 8] - n).abs() < 1e-5 * n,
            "{stem}: P(0) = {}",
            values[136]
        );
    }
    for sheet in ["sheet_2d_xy.png", "sheet_4d_xu.png"] {
        assert!(gallery.join(sheet).exists(), "{sheet}");
    }
    // A file of yours where the next gallery writes one (not in the earlier gallery's manifest) is
    // refused before any spectrum is computed, and kept.
    let mine = gallery.join("2d_random_xy_radial.csv");
    std::fs::write(&mine, "mine").unwrap();
    let manifest = gallery.join("manifest.txt");
    let listed = std::fs::read_to_string(&manifest).unwrap();
    let unlisted: String = listed
        .lines()
        .filter(|l| !l.ends_with("2d_random_xy_radial.csv"))
        .map(|l| format!("{l}\n"))
        .collect();
    assert_ne!(unlisted, listed, "the manifest lists the radial CSV");
    std::fs::write(&manifest, unlisted).unwrap();
    let o = anisospec(&[
        "gallery",
        "--out",
        dir.path().to_str().unwrap(),
        "-n",
        "64",
        "--res",
        "16",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("2d_random_xy_radial.csv"), "{err}");
    assert!(
        !err.contains(": N = "),
        "spectra computed before the check: {err}"
    );
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), "mine");
}

/// `gallery --out` on a file (or under one) is a usage error naming the flag, before any work.
#[test]
fn gallery_refuses_a_file_as_its_folder() {
    let (dir, file) = tmp("ok.txt");
    std::fs::write(&file, "keep").unwrap();
    let f = file.to_str().unwrap();
    rejects(
        &["gallery", "--out", f, "-n", "16", "--res", "8"],
        "is a file, not a folder",
        &file.join("gallery"),
    );
    let under = file.join("sub");
    rejects(
        &["gallery", "--out", under.to_str().unwrap(), "--res", "8"],
        "give --out a folder path",
        &under,
    );
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "keep");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

/// `gallery` checks its realizations and every sampler's N before it makes a folder: bad input leaves
/// no folder behind, nested or not, and an N too large for memory is told to shrink (gallery has no
/// --sets to lower).
#[test]
fn gallery_checks_before_it_makes_a_folder() {
    let dir = tempfile::tempdir().unwrap();
    let nested = dir.path().join("g/x/y");
    let out = nested.to_str().unwrap();
    rejects(
        &["gallery", "--out", out, "-n", "16", "--realizations", "0"],
        "--realizations 0 averages nothing",
        &dir.path().join("g"),
    );
    let huge = ["gallery", "--out", out, "-n", "999999999", "--res", "16"];
    let o = anisospec(&huge);
    refused(&o, &huge, "use a smaller N", &dir.path().join("g"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("sets"), "{err}");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

/// Sampler names that are empty, a `table:` without a path, and a 4D pairing asked in 2D each get a
/// message saying so (not "no point-set extension" or a guess at the closest 2D name).
#[test]
fn sampler_name_messages() {
    let (_dir, out) = tmp("a.npy");
    let o = out.to_str().unwrap();
    rejects(
        &["sample", "--sampler", "table:", "-n", "16", "-o", o],
        "names no table",
        &out,
    );
    rejects(
        &["sample", "--sampler", "padded-nosuch", "-n", "16", "-o", o],
        "--dims 4",
        &out,
    );
    rejects(
        &["sample", "--sampler", "", "-n", "16", "-o", o],
        "the sampler name is empty",
        &out,
    );
}

/// A scene whose camera can put a shear beyond the crate's largest on some depth (a tiny fov) is
/// refused before any work, by `oracle` and `render --shear` alike, naming the keys.
#[test]
fn scenes_with_unbounded_shear_are_refused() {
    let (dir, out) = tmp("o.npy");
    let scene = dir.path().join("s.toml");
    std::fs::write(&scene, "fov = 1e-300\n").unwrap();
    let sc = scene.to_str().unwrap();
    rejects(
        &["oracle", "--scene", sc, "-o", out.to_str().unwrap()],
        "widen fov",
        &out,
    );
    assert!(!dir.path().join("o.exr").exists());
    let img = dir.path().join("r.exr");
    rejects(
        &[
            "render",
            "--scene",
            sc,
            "--sampler",
            "mj",
            "--shear",
            "-o",
            img.to_str().unwrap(),
        ],
        "beyond the largest supported shear",
        &img,
    );
}

/// A variance target with `design = "lattice"`: `optimize` writes the searched lattice as every set
/// (each coordinate at its strata's centres) and names its generating vector and predicted variance in
/// the sidecar (a shape target with the key is refused: tests/optimize.rs, `target_files_are_strict`).
#[test]
fn lattice_designs_are_written_as_tables() {
    let (dir, out) = tmp("fan.npy");
    let target = dir.path().join("fan.toml");
    std::fs::write(
        &target,
        "kind = \"variance\"\nintegrand = \"fan:s0=0.3,s1=0.7\"\nshear = 0.5\nplacements = 2\nextent = 2.0\ndesign = \"lattice\"\n",
    )
    .unwrap();
    let o = anisospec(&[
        "optimize",
        "--target",
        target.to_str().unwrap(),
        "--dims",
        "4",
        "-n",
        "64",
        "--sets",
        "3",
        "-o",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("lattice z = ["), "{err}");
    let sidecar: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.with_extension("json")).unwrap())
            .unwrap();
    let z: Vec<usize> = sidecar["lattice"]["generator"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect();
    assert_eq!((z.len(), z[0]), (4, 1), "{z:?}");
    let ratio = sidecar["lattice"]["variance_ratio"].as_f64().unwrap();
    assert!(ratio > 0.0 && ratio < 1.0, "{ratio}");
    let table = anisospec::points::io::read_points(&out).unwrap();
    assert_eq!(table.sets(), 3);
    for s in 0..3 {
        for (i, p) in table.set(s).chunks_exact(4).enumerate() {
            for (c, zd) in p.iter().zip(&z) {
                assert_eq!(*c, ((i * zd % 64) as f64 + 0.5) / 64.0);
            }
        }
    }
}

/// An output file whose folder does not exist is refused (exit 2, naming the folder), and the folder is
/// not made; the other outputs of the command are not written either.
#[test]
fn missing_output_folders_are_refused_not_made() {
    let (dir, input) = tmp("pts.npy");
    let i = input.to_str().unwrap();
    let o = anisospec(&["sample", "--sampler", "random", "-n", "16", "-o", i]);
    assert!(o.status.success());
    let missing = dir.path().join("nodir");
    let deep = missing.join("deeper/a.png");
    let deep_npy = missing.join("deeper/a.npy");
    let fine = dir.path().join("fine.npy");
    let radial = missing.join("r.csv");
    let cases: [(Vec<&str>, &Path); 3] = [
        (
            vec![
                "spectrum",
                "--input",
                i,
                "--res",
                "8",
                "-o",
                deep.to_str().unwrap(),
            ],
            &deep,
        ),
        (
            vec![
                "spectrum",
                "--input",
                i,
                "--res",
                "8",
                "-o",
                fine.to_str().unwrap(),
                "--radial",
                radial.to_str().unwrap(),
            ],
            &fine,
        ),
        (
            vec![
                "sample",
                "--sampler",
                "random",
                "-n",
                "16",
                "-o",
                deep_npy.to_str().unwrap(),
            ],
            &deep_npy,
        ),
    ];
    for (args, out) in &cases {
        rejects(args, "does not exist; create it first", out);
        let err = String::from_utf8_lossy(&anisospec(args).stderr).into_owned();
        assert!(
            err.contains(&format!("folder {}", missing.display())),
            "{args:?}: {err}"
        );
        assert!(!missing.exists(), "{args:?} made {}", missing.display());
    }
}

/// An output in a folder that takes no file is refused before any work with exit 2, naming the folder
/// and the operating system's reason, never the temporary file the check made.
#[cfg(target_os = "linux")]
#[test]
fn unwritable_output_folders_are_named() {
    for args in [
        vec![
            "sample",
            "--sampler",
            "random",
            "-n",
            "16",
            "-o",
            "/proc/z.npy",
        ],
        vec![
            "spectrum",
            "--sampler",
            "random",
            "-n",
            "16",
            "--res",
            "8",
            "-o",
            "/proc/z.png",
        ],
    ] {
        let o = anisospec(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("cannot write to /proc: ") && err.contains("choose a writable folder"),
            "{args:?}: {err}"
        );
        assert!(!err.contains(".anisospec-"), "{args:?}: {err}");
    }
}

/// Flags that a command would ignore are refused at parse time (exit 2, naming them): the sampler's
/// flags with a point file, the shear's mode without a shear, the sampler's flags with render's
/// reference, the oracle shear's options without --shear, optimize's NUFFT tolerance with --exact.
/// Nothing is written.
#[test]
fn flags_that_would_be_ignored_are_refused() {
    let (dir, input) = tmp("pts.npy");
    let i = input.to_str().unwrap();
    let o = anisospec(&["sample", "--sampler", "random", "-n", "16", "-o", i]);
    assert!(o.status.success());
    let out = dir.path().join("out.npy");
    let img = dir.path().join("img.exr");
    let (o, im) = (out.to_str().unwrap(), img.to_str().unwrap());
    let spectrum = |flags: &[&'static str]| {
        let mut v = vec!["spectrum", "--input", i, "--res", "8", "-o", o];
        v.extend(flags);
        v
    };
    let cases: Vec<(Vec<&str>, &str, &Path)> = vec![
        (
            spectrum(&["-n", "16"]),
            "'--input <INPUT>' cannot be used with '--n",
            &out,
        ),
        (
            spectrum(&["--seed", "3"]),
            "cannot be used with '--seed",
            &out,
        ),
        (
            spectrum(&["--dims", "4"]),
            "cannot be used with '--dims",
            &out,
        ),
        (
            spectrum(&["--sampler", "mj"]),
            "cannot be used with '--sampler",
            &out,
        ),
        (
            spectrum(&["--shear", "0.5,0.5"]),
            "cannot be used with '--shear",
            &out,
        ),
        (
            spectrum(&["--shear-mode", "wrap"]),
            "cannot be used with '--shear-mode",
            &out,
        ),
        (
            vec![
                "sample",
                "--sampler",
                "random",
                "-n",
                "16",
                "--shear-mode",
                "wrap",
                "-o",
                o,
            ],
            "--shear-mode wrap needs --shear sx,sy:",
            &out,
        ),
        (
            vec![
                "variance",
                "--sampler",
                "padded-mj",
                "-n",
                "16",
                "--integrand",
                "sheared:s=0.5@xu",
                "--shear-mode",
                "wrap",
            ],
            "--shear-mode wrap needs --shear sx,sy:",
            &out,
        ),
        (
            vec![
                "spectrum",
                "--sampler",
                "random",
                "-n",
                "16",
                "--cones",
                "8",
                "-o",
                o,
            ],
            "--cones 8 needs --radial FILE.csv:",
            &out,
        ),
        (
            vec!["render", "--reference", "--sampler", "padded-mj", "-o", im],
            "'--reference' cannot be used with '--sampler",
            &img,
        ),
        (
            vec!["render", "--reference", "--spp", "16", "-o", im],
            "'--reference' cannot be used with '--spp",
            &img,
        ),
        (
            vec!["render", "--reference", "--shear", "-o", im],
            "'--reference' cannot be used with '--shear",
            &img,
        ),
        (
            vec![
                "render",
                "--sampler",
                "padded-mj",
                "--wedge-shear",
                "none",
                "-o",
                im,
            ],
            "--wedge-shear none needs --shear:",
            &img,
        ),
        (
            vec![
                "render",
                "--sampler",
                "padded-mj",
                "--shear-mode",
                "wrap",
                "-o",
                im,
            ],
            "--shear-mode wrap needs --shear:",
            &img,
        ),
        (
            vec![
                "optimize",
                "--target",
                "targets/hairline.toml",
                "-n",
                "16",
                "--exact",
                "--eps",
                "1e-3",
                "-o",
                o,
            ],
            "'--exact' cannot be used with '--eps",
            &out,
        ),
    ];
    for (args, needle, file) in &cases {
        rejects(args, needle, file);
    }
}

/// `spectrum --stderr` over one realization would write an all-zero standard error: refused, whether
/// the one realization is asked for or is all the point file holds; `--realizations 0` names the flag.
#[test]
fn spectrum_stderr_needs_two_realizations() {
    let (dir, one) = tmp("one.npy");
    let i = one.to_str().unwrap();
    let o = anisospec(&["sample", "--sampler", "random", "-n", "16", "-o", i]);
    assert!(o.status.success());
    let out = dir.path().join("s.npy");
    let se = dir.path().join("se.npy");
    let (o, s) = (out.to_str().unwrap(), se.to_str().unwrap());
    let sampler = ["spectrum", "--sampler", "random", "-n", "16", "--res", "8"];
    let mut asked = sampler.to_vec();
    asked.extend(["--realizations", "1", "--stderr", s, "-o", o]);
    rejects(&asked, "--stderr needs 2 or more realizations", &out);
    rejects(
        &[
            "spectrum", "--input", i, "--res", "8", "--stderr", s, "-o", o,
        ],
        "one.npy holds one set",
        &out,
    );
    assert!(!se.exists());
    for source in [&sampler[..], &["spectrum", "--input", i, "--res", "8"]] {
        let mut args = source.to_vec();
        args.extend(["--realizations", "0", "-o", o]);
        rejects(&args, "--realizations 0 averages nothing", &out);
    }
    // Two realizations give a standard error that is positive at every bin off k = 0 (the middle
    // bin of the 8 × 8 grid): a half-plane left out of the mirrored layout would show as zeros.
    let mut two = sampler.to_vec();
    two.extend(["--realizations", "2", "--stderr", s, "-o", o]);
    let run = anisospec(&two);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let bytes = std::fs::read(&se).unwrap();
    let values: Vec<f64> = npyz::NpyFile::new(&bytes[..]).unwrap().into_vec().unwrap();
    let dc = 4 * 8 + 4;
    assert_eq!(values.len(), 64);
    assert!(
        values.iter().enumerate().all(|(i, &v)| i == dc || v > 0.0),
        "{values:?}"
    );
}

/// Commands that write a fixed set of files beside `-o` (render, oracle, pixel-spectrum) refuse an
/// extension they would not write, naming the files they do write, before any work; the one-format
/// outputs of the other commands name the extension to use.
#[test]
fn output_names_must_match_what_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let at = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let (csv_o, txt, npy, csv) = (at("o.csv"), at("p.txt"), at("r.npy"), at("c.txt"));
    let cases: Vec<(Vec<&str>, String, String)> = vec![
        (
            vec!["oracle", "-o", &csv_o],
            format!(
                "the outputs are {}, {} and {}, not a .csv",
                at("o.exr"),
                at("o.npy"),
                at("o.png")
            ),
            at("o.exr"),
        ),
        (
            vec!["pixel-spectrum", "--pixel", "20,20", "-o", &txt],
            format!("{}, {} and {}", at("p.npy"), at("p.exr"), at("p.png")),
            at("p.npy"),
        ),
        (
            vec!["render", "--sampler", "padded-mj", "-o", &npy],
            "name -o with .exr or .png, or with no extension".into(),
            at("r.exr"),
        ),
        (
            vec!["oracle", "-o", "/"],
            "has no usable file name".into(),
            at("o.npy"),
        ),
        (
            vec![
                "converge",
                "--sampler",
                "mj",
                "--integrand",
                "disc",
                "-n",
                "16,64",
                "-o",
                &csv,
            ],
            "name it .csv (-o writes a CSV table)".into(),
            csv.clone(),
        ),
        (
            vec![
                "variance",
                "--sampler",
                "mj",
                "--integrand",
                "disc",
                "-n",
                "16",
                "-o",
                &csv,
            ],
            "name it .csv".into(),
            csv.clone(),
        ),
    ];
    for (args, needle, file) in &cases {
        rejects(args, needle, Path::new(file));
    }
    // Without an extension, or with one of its own, the oracle writes all three files.
    for (given, stem) in [
        ("plain", "plain"),
        ("named.npy", "named"),
        ("seen.png", "seen"),
    ] {
        let o = anisospec(&["oracle", "-o", &at(given)]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        for ext in ["exr", "npy", "png"] {
            assert!(
                dir.path().join(format!("{stem}.{ext}")).exists(),
                "{stem}.{ext}"
            );
        }
    }
}

/// `oracle` checks its outputs before it computes anything: with a scene the oracle cannot be made
/// for (a pinhole camera) and an output it cannot write, the output is what is reported.
#[test]
fn oracle_checks_outputs_before_the_oracle() {
    let (dir, scene) = tmp("pinhole.toml");
    std::fs::write(&scene, "aperture = 0.0\n").unwrap();
    let s = scene.to_str().unwrap();
    let out = dir.path().join("nodir/o.exr");
    rejects(
        &["oracle", "--scene", s, "-o", out.to_str().unwrap()],
        "does not exist",
        &out,
    );
    let here = dir.path().join("o.exr");
    rejects(
        &["oracle", "--scene", s, "-o", here.to_str().unwrap()],
        "aperture",
        &here,
    );
}

/// `optimize --sets 0` is refused up front, naming the flag, also for a lattice design (whose search
/// would otherwise run first).
#[test]
fn optimize_refuses_no_sets_before_any_work() {
    let (dir, out) = tmp("t.npy");
    let target = dir.path().join("fan.toml");
    std::fs::write(
        &target,
        "kind = \"variance\"\nintegrand = \"fan:s0=0.3,s1=0.7\"\nshear = 0.5\nplacements = 2\nextent = 2.0\ndesign = \"lattice\"\n",
    )
    .unwrap();
    for t in [target.to_str().unwrap(), "targets/blue-noise.toml"] {
        let args = [
            "optimize",
            "--target",
            t,
            "--dims",
            "4",
            "-n",
            "64",
            "--sets",
            "0",
            "-o",
            out.to_str().unwrap(),
        ];
        rejects(&args, "--sets 0 asks for nothing", &out);
        let err = String::from_utf8_lossy(&anisospec(&args).stderr).into_owned();
        assert!(!err.contains("searching"), "{t}: {err}");
    }
}

/// `--tol 0` runs until the loss stops changing; there L-BFGS divided by a zero curvature and stepped to
/// NaN coordinates, which panicked in the spectrum code. The run now ends with a table, no NaN, and
/// the reason it stopped.
#[test]
fn optimize_with_tol_zero_stops_cleanly() {
    let (dir, out) = tmp("t.npy");
    let o = anisospec(&[
        "optimize",
        "--target",
        "targets/blue-noise.toml",
        "-n",
        "64",
        "--tol",
        "0",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(dir.path().join("t.txt")).unwrap();
    assert!(!text.to_lowercase().contains("nan"), "{text}");
    let json = std::fs::read_to_string(dir.path().join("t.json")).unwrap();
    assert!(json.contains("\"stop\": \"stopped:"), "{json}");
}

/// The C header's first line is the whole command: run again by a shell, it makes the same table, bit
/// for bit, with the flags that change a table (--init, --latin, --max-iters, a loss weight, --eps)
/// given away from their defaults and a path that needs quoting.
#[test]
fn c_header_names_the_command_that_makes_the_table() {
    let dir = tempfile::tempdir().unwrap();
    // A space and a quote in the path: the command quotes them for the shell.
    let table = dir.path().join("it's a table.npy");
    let o = anisospec(&[
        "optimize",
        "--target",
        "targets/blue-noise.toml",
        "-n",
        "16",
        "--seed",
        "3",
        "--init",
        "mj",
        "--latin",
        "--max-iters",
        "4",
        "--annular-weight",
        "0.5",
        "--eps",
        "1e-6",
        "-o",
        table.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let first = std::fs::read(&table).unwrap();
    let header = std::fs::read_to_string(table.with_extension("h")).unwrap();
    let line = header.lines().next().unwrap();
    let command = line
        .strip_prefix("/* anisospec ")
        .and_then(|l| l.strip_suffix(" */"))
        .unwrap_or_else(|| panic!("not a command: {line}"));
    for flag in [
        "--init=mj",
        "--latin",
        "--max-iters 4",
        "--annular-weight 0.5",
        "--eps 1e-6",
    ] {
        assert!(command.contains(flag), "{flag} missing from {command}");
    }
    // Run as written, by a POSIX shell, from the same folder: it writes the same table again.
    std::fs::remove_file(&table).unwrap();
    let o = Command::new("sh")
        .arg("-c")
        .arg(format!("\"$0\" {command}"))
        .arg(env!("CARGO_BIN_EXE_anisospec"))
        .output()
        .expect("sh runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(first, std::fs::read(&table).unwrap());
}

/// `variance` on a pixel of the scene (no Fourier coefficients) is refused before any work on the
/// pixel: its reference is not rendered, and no cache folder appears.
#[test]
fn variance_refuses_a_pixel_before_rendering_it() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let o = Command::new(env!("CARGO_BIN_EXE_anisospec"))
        .args([
            "variance",
            "--sampler",
            "padded-mj",
            "--integrand",
            "pixel:px=20,py=20",
            "-n",
            "16",
        ])
        .env("ANISOSPEC_CACHE", &cache)
        .output()
        .expect("the binary runs");
    refused(&o, &["variance"], "anisospec converge", &cache);
}

/// Two optimized tables' C headers can be included in one C file (and each twice): the include guard,
/// the macros and the array are named after the file, `anisospec_` and its stem as a C identifier.
/// Two tables whose names give the same identifier (`Fan-A`, `fan_a`) do not compile together: the
/// guard carries a hash of the numbers, so the second is not silently skipped. A name with no ASCII
/// letter or digit, which would give the bare prefix, is refused.
#[test]
fn c_headers_of_two_tables_live_in_one_file() {
    let dir = tempfile::tempdir().unwrap();
    let bare = dir.path().join("ü.npy");
    rejects(
        &[
            "optimize",
            "--target",
            "targets/blue-noise.toml",
            "-n",
            "16",
            "-o",
            bare.to_str().unwrap(),
        ],
        "no ASCII letter or digit",
        &bare,
    );
    for (file, sets) in [
        ("Fan-A.npy", "2"),
        ("2nd table.npy", "1"),
        ("fan_a.npy", "1"),
    ] {
        let o = anisospec(&[
            "optimize",
            "--target",
            "targets/blue-noise.toml",
            "-n",
            "16",
            "--sets",
            sets,
            "--max-iters",
            "3",
            "-o",
            dir.path().join(file).to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let a = std::fs::read_to_string(dir.path().join("Fan-A.h")).unwrap();
    let b = std::fs::read_to_string(dir.path().join("2nd table.h")).unwrap();
    for (text, name, sets) in [(&a, "anisospec_fan_a", 2), (&b, "anisospec_2nd_table", 1)] {
        let upper = name.to_uppercase();
        let guard = text.lines().find(|l| l.starts_with("#ifndef ")).unwrap();
        let hash = guard
            .strip_prefix(&format!("#ifndef {upper}_H_"))
            .unwrap_or_else(|| panic!("{name}: guard '{guard}'"));
        assert!(
            hash.len() == 16 && hash.chars().all(|c| c.is_ascii_hexdigit()),
            "{guard}"
        );
        for line in [
            format!("#define {upper}_SETS {sets}"),
            format!("#define {upper}_N 16"),
            format!("#define {upper}_DIMS 2"),
            format!("static const double {name}[{sets}][16][2] = {{"),
        ] {
            assert!(
                text.lines().any(|l| l == line),
                "{name}: no '{line}' in\n{text}"
            );
        }
    }
    let Ok(cc) = Command::new("cc").arg("--version").output() else {
        return; // No C compiler here: the names above are what it would see.
    };
    assert!(cc.status.success());
    let c = dir.path().join("both.c");
    std::fs::write(
        &c,
        "#include \"Fan-A.h\"\n#include \"2nd table.h\"\n#include \"Fan-A.h\"\n\
         _Static_assert(sizeof anisospec_fan_a == ANISOSPEC_FAN_A_SETS * ANISOSPEC_FAN_A_N * ANISOSPEC_FAN_A_DIMS * sizeof(double), \"a\");\n\
         _Static_assert(ANISOSPEC_2ND_TABLE_SETS == 1 && ANISOSPEC_FAN_A_SETS == 2, \"sets\");\n\
         double corner(void) { return anisospec_fan_a[1][15][1] + anisospec_2nd_table[0][0][0]; }\n",
    )
    .unwrap();
    let o = Command::new("cc")
        .current_dir(dir.path())
        .args(["-std=c11", "-c", "both.c", "-o", "both.o"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // fan_a.h declares the same names with other numbers: a compile error, not a skipped header.
    std::fs::write(
        dir.path().join("clash.c"),
        "#include \"Fan-A.h\"\n#include \"fan_a.h\"\n",
    )
    .unwrap();
    let o = Command::new("cc")
        .current_dir(dir.path())
        .args(["-std=c11", "-c", "clash.c", "-o", "clash.o"])
        .output()
        .unwrap();
    assert!(!o.status.success(), "Fan-A.h and fan_a.h compiled together");
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("anisospec_fan_a"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// An output's extension is matched in any case, and the file is written at exactly the path given:
/// `-o T.NPY` writes `T.NPY` (with its companions beside it), never `T.npy`.
#[test]
fn outputs_keep_the_case_of_their_extension() {
    let dir = tempfile::tempdir().unwrap();
    let names_in = |sub: &str| {
        let mut names: Vec<String> = std::fs::read_dir(dir.path().join(sub))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    };
    let cases: [(&str, Vec<&str>, Vec<&str>); 3] = [
        (
            "optimize",
            vec![
                "optimize",
                "--target",
                "targets/blue-noise.toml",
                "-n",
                "16",
                "--max-iters",
                "3",
            ],
            vec!["T.NPY", "T.h", "T.json", "T.log.csv", "T.txt"],
        ),
        (
            "sample",
            vec!["sample", "--sampler", "mj", "-n", "16"],
            vec!["T.NPY"],
        ),
        ("oracle", vec!["oracle"], vec!["T.NPY", "T.exr", "T.png"]),
    ];
    for (sub, mut args, written) in cases {
        std::fs::create_dir(dir.path().join(sub)).unwrap();
        let out = dir.path().join(sub).join("T.NPY");
        args.extend(["-o", out.to_str().unwrap()]);
        let o = anisospec(&args);
        assert!(
            o.status.success(),
            "{sub}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert_eq!(names_in(sub), written, "{sub}");
    }
    let table = anisospec::points::io::read_points(&dir.path().join("optimize/T.NPY")).unwrap();
    assert_eq!((table.sets(), table.n(), table.dims()), (1, 16, 2));
}

/// A count of one is spoken in the singular: "1 set", "1 realization", not "1 sets".
#[test]
fn counts_of_one_are_singular() {
    let (dir, pts) = tmp("one.npy");
    let p = pts.to_str().unwrap();
    let o = anisospec(&["sample", "--sampler", "mj", "-n", "16", "-o", p]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("wrote 1 set of 16 2D points"), "{err}");
    let spec = dir.path().join("s.npy");
    let s = spec.to_str().unwrap();
    let o = anisospec(&["spectrum", "--input", p, "--res", "8", "-o", s]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("spectrum of 1 realization of 16 points"),
        "{err}"
    );
    std::fs::remove_file(&spec).unwrap();
    rejects(
        &["spectrum", "--input", p, "--realizations", "2", "-o", s],
        "holds 1 set; ask for at most 1",
        &spec,
    );
}

/// `optimize` without --seed uses seed 1, as every other command: the same table as --seed 1, another
/// than --seed 0, and the sidecar says 1.
#[test]
fn optimize_seeds_with_1_by_default() {
    let dir = tempfile::tempdir().unwrap();
    let table = |name: &str, seed: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec![
            "optimize",
            "--target",
            "targets/blue-noise.toml",
            "-n",
            "16",
            "--max-iters",
            "3",
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend(seed);
        let o = anisospec(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        std::fs::read(&out).unwrap()
    };
    let default = table("default.npy", &[]);
    assert_eq!(default, table("one.npy", &["--seed", "1"]));
    assert_ne!(default, table("zero.npy", &["--seed", "0"]));
    let sidecar: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("default.json")).unwrap())
            .unwrap();
    assert_eq!(sidecar["parameters"]["seed"], 1);
}

/// A rank-1 lattice whose generating vector shares a factor with N (0 included) would repeat points or
/// values in a coordinate: refused in every command, naming the entry and a coprime one. An entry
/// past u64 is named as too large, not as "not a whole number".
#[test]
fn degenerate_lattice_generators_are_refused() {
    let (_dir, out) = tmp("l.npy");
    let o = out.to_str().unwrap();
    let cases: [(Vec<&str>, &str); 5] = [
        (
            vec![
                "sample",
                "--sampler",
                "lattice:18446744073709551617:3",
                "-n",
                "8",
                "-o",
                o,
            ],
            "'18446744073709551617' is above the largest entry, 18446744073709551615",
        ),
        (
            vec!["sample", "--sampler", "lattice:0:0", "-n", "8", "-o", o],
            "the entry 0 for x shares the factor 8 with N = 8",
        ),
        (
            vec!["sample", "--sampler", "lattice:1:4", "-n", "8", "-o", o],
            "so y takes only 2 distinct values; give an entry coprime to 8 instead, e.g. 3",
        ),
        (
            vec![
                "spectrum",
                "--sampler",
                "lattice:1:163:271:141",
                "--dims",
                "4",
                "--shear",
                "0.5,0.5",
                "-n",
                "9",
                "--res",
                "8",
                "-o",
                o,
            ],
            "the entry 141 for v shares the factor 3",
        ),
        (
            vec![
                "converge",
                "--sampler",
                "lattice:1:3,lattice:1:2",
                "--integrand",
                "disc",
                "-n",
                "16,64",
            ],
            "the entry 2 for y shares the factor 2 with N = 16",
        ),
    ];
    for (args, needle) in &cases {
        rejects(args, needle, &out);
    }
    let ok = anisospec(&["sample", "--sampler", "lattice:1:34", "-n", "89", "-o", o]);
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
}

/// converge measures each sampler once: a sampler listed twice, in one list or in two flags, is
/// refused before any work (no table printed, no CSV).
#[test]
fn converge_refuses_a_sampler_listed_twice() {
    let (_dir, csv) = tmp("c.csv");
    let c = csv.to_str().unwrap();
    for samplers in [
        vec!["--sampler", "mj,mj"],
        vec!["--sampler", "jittered,mj, mj"],
        vec!["--sampler", "mj", "--sampler", "mj"],
    ] {
        let mut args = vec!["converge", "--integrand", "disc", "-n", "16,64", "-o", c];
        args.extend(&samplers);
        rejects(
            &args,
            "--sampler lists 'mj' twice; give each sampler once",
            &csv,
        );
        assert!(
            anisospec(&args).stdout.is_empty(),
            "{args:?} printed a table"
        );
    }
}

/// A point count that is not a positive integer is named as such (not taken for an unknown flag), in
/// every command that takes one; a list of N that repeats one is refused; a count the sampler cannot
/// make names the flag that set it.
#[test]
fn counts_must_be_positive_and_distinct() {
    let (_dir, out) = tmp("x.npy");
    let o = out.to_str().unwrap();
    let csv = out.with_extension("csv");
    let c = csv.to_str().unwrap();
    let exr = out.with_extension("exr");
    let cases: [(Vec<&str>, &str, &Path); 11] = [
        (
            vec!["sample", "--sampler", "mj", "-n", "-5", "-o", o],
            "a point count must be a positive integer (1 or more), not -5",
            &out,
        ),
        (
            vec![
                "sample",
                "--sampler",
                "mj",
                "-n",
                "16",
                "--seed",
                "-1",
                "-o",
                o,
            ],
            "a seed is a whole number from 0 to 18446744073709551615, not -1",
            &out,
        ),
        (
            vec!["sample", "--sampler", "mj", "-n", "0", "-o", o],
            "a point count must be a positive integer",
            &out,
        ),
        (
            vec!["spectrum", "--sampler", "mj", "-n", "-16", "-o", o],
            "a point count must be a positive integer",
            &out,
        ),
        (
            vec![
                "converge",
                "--sampler",
                "mj",
                "--integrand",
                "disc",
                "-n",
                "16,-64",
                "-o",
                c,
            ],
            "not -64",
            &csv,
        ),
        (
            vec!["render", "--sampler", "padded-mj", "--spp", "-4", "-o", o],
            "a point count must be a positive integer",
            &out,
        ),
        (
            vec![
                "render",
                "--sampler",
                "jittered",
                "-o",
                exr.to_str().unwrap(),
            ],
            "--spp 64: jittered cannot make 64 points; the nearest N it allows is 81",
            &exr,
        ),
        (
            vec![
                "converge",
                "--sampler",
                "mj",
                "--integrand",
                "disc",
                "-n",
                "16,16",
                "-o",
                c,
            ],
            "-n lists 16 twice",
            &csv,
        ),
        (
            vec![
                "variance",
                "--sampler",
                "mj",
                "--integrand",
                "disc",
                "-n",
                "16,64,16",
                "-o",
                c,
            ],
            "-n lists 16 twice",
            &csv,
        ),
        (
            vec![
                "converge",
                "--sampler",
                "mj",
                "--integrand",
                "disc",
                "-n",
                "36,9,16",
                "-o",
                c,
            ],
            "-n lists 36 before 9; list N in increasing order",
            &csv,
        ),
        (
            vec![
                "variance",
                "--sampler",
                "mj",
                "--integrand",
                "disc",
                "-n",
                "16",
                "--res-per-n",
                "0",
                "-o",
                c,
            ],
            "--res-per-n 0 grows no grid",
            &csv,
        ),
    ];
    for (args, needle, file) in &cases {
        rejects(args, needle, file);
    }
}

/// converge's table: through two N no chi2/dof is printed (no degree of freedom is left), through three
/// it is; the time column says it covers all R realizations.
#[test]
fn converge_prints_no_chi2_without_degrees_of_freedom() {
    let run = |ns: &str| {
        let o = anisospec(&[
            "converge",
            "--sampler",
            "random",
            "--integrand",
            "disc",
            "-n",
            ns,
            "--realizations",
            "8",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let two = run("16,64");
    assert!(two.contains("chi2/dof —"), "{two}");
    assert!(!two.contains("chi2/dof 0.00"), "{two}");
    let three = run("16,64,256");
    let chi2: f64 = three
        .split("chi2/dof ")
        .nth(1)
        .and_then(|rest| rest.split(')').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no chi2/dof number in {three}"));
    assert!(chi2.is_finite() && chi2 >= 0.0, "{three}");
    for table in [&two, &three] {
        assert!(
            table.contains("seconds(R)") && table.contains("all R realizations"),
            "{table}"
        );
    }
}

/// variance warns on stderr at every N whose white-noise tail is more than
/// `TAIL_WARNING_SHARE` of the prediction, judged from the tail and variance columns the command
/// prints: N-rooks on an aligned step at N = 256 with K = 128 is dominated by its tail, and not once the
/// grid grows with N (`--res-per-n 4`), which the warning names.
#[test]
fn variance_warns_when_the_tail_dominates() {
    use anisospec::cli::variance::TAIL_WARNING_SHARE;
    let run = |extra: &[&str]| {
        let mut args = vec![
            "variance",
            "--sampler",
            "nrooks",
            "--integrand",
            "step:theta=0",
            "-n",
            "16,256",
            "--realizations",
            "20",
        ];
        args.extend_from_slice(extra);
        let o = anisospec(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let out = String::from_utf8_lossy(&o.stdout).into_owned();
        // Rows of the table: N, variance, stderr, tail, cone shares.
        let shares: Vec<(usize, f64)> = out
            .lines()
            .filter_map(|l| {
                let t: Vec<&str> = l.split_whitespace().collect();
                let n = t.first()?.parse().ok()?;
                let variance: f64 = t.get(1)?.parse().ok()?;
                let tail: f64 = t.get(3)?.parse().ok()?;
                Some((n, tail / variance))
            })
            .collect();
        assert_eq!(shares.len(), 2, "{out}");
        (shares, String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let mut dominated_somewhere = false;
    let mut dominated_nowhere = false;
    for extra in [&[][..], &["--res-per-n", "4"][..]] {
        let (shares, err) = run(extra);
        let over: Vec<usize> = shares
            .iter()
            .filter(|s| s.1 > TAIL_WARNING_SHARE)
            .map(|s| s.0)
            .collect();
        dominated_somewhere |= !over.is_empty();
        dominated_nowhere |= over.is_empty();
        assert_eq!(
            err.contains("warning: the white-noise tail"),
            !over.is_empty(),
            "{extra:?}: shares {shares:?}, stderr '{err}'"
        );
        for (n, share) in &shares {
            let named = format!("N = {n} (tail ");
            let printed = err.split(&named).nth(1).map(|rest| {
                rest.split(' ')
                    .next()
                    .and_then(|v| v.parse::<f64>().ok())
                    .unwrap_or_else(|| panic!("no share after '{named}' in '{err}'"))
            });
            assert_eq!(
                printed.is_some(),
                *share > TAIL_WARNING_SHARE,
                "{extra:?}: '{named}' in '{err}'"
            );
            // The warning rounds the share to a whole percent; the table's tail (4 digits) and variance
            // (5 digits) put at most 6e-4 of relative error on the share computed here.
            if let Some(pct) = printed {
                let tol = 0.5 + 6e-4 * 100.0 * share;
                assert!(
                    (pct - 100.0 * share).abs() <= tol,
                    "{extra:?}: warning says {pct} %, the table {:.2} %",
                    100.0 * share
                );
            }
        }
        if !over.is_empty() {
            for needed in ["P = 1", "--res-per-n", "--res "] {
                assert!(err.contains(needed), "'{err}' lacks '{needed}'");
            }
        }
    }
    assert!(
        dominated_somewhere && dominated_nowhere,
        "the two cases no longer straddle the threshold"
    );
}

/// Realization counts, cone counts, table sets and `--average` above their limits are refused with
/// exit code 2, naming the limit, before any work and without output (they used to panic with
/// "capacity overflow", abort on an allocation, or run for days).
#[test]
fn counts_above_their_limits_are_refused() {
    let (dir, out) = tmp("a.npy");
    let o = out.to_str().unwrap();
    let radial = dir.path().join("r.csv");
    let r = radial.to_str().unwrap();
    let max = "18446744073709551615";
    let above_realizations = (anisospec::stats::MAX_REALIZATIONS + 1).to_string();
    let above_cones = (anisospec::spectrum::profiles::MAX_CONES + 1).to_string();
    for count in [max, above_cones.as_str()] {
        rejects(
            &[
                "spectrum",
                "--sampler",
                "random",
                "-n",
                "16",
                "--res",
                "8",
                "--cones",
                count,
                "--radial",
                r,
                "-o",
                o,
            ],
            "largest cone count, 360",
            &out,
        );
        assert!(!radial.exists());
        rejects(
            &[
                "variance",
                "--sampler",
                "nrooks",
                "--integrand",
                "step:theta=0",
                "-n",
                "16",
                "--cones",
                count,
            ],
            "largest cone count, 360",
            &out,
        );
    }
    for count in [max, above_realizations.as_str()] {
        rejects(
            &[
                "spectrum",
                "--sampler",
                "random",
                "-n",
                "16",
                "--res",
                "8",
                "--realizations",
                count,
                "-o",
                o,
            ],
            "largest realization count, 1000000",
            &out,
        );
        for cmd in ["converge", "variance"] {
            rejects(
                &[
                    cmd,
                    "--sampler",
                    "random",
                    "--integrand",
                    "disc",
                    "-n",
                    "4,16",
                    "--realizations",
                    count,
                ],
                "largest realization count, 1000000",
                &out,
            );
        }
    }
    let gallery = dir.path().join("g");
    rejects(
        &[
            "gallery",
            "--out",
            gallery.to_str().unwrap(),
            "--realizations",
            &above_realizations,
        ],
        "largest realization count, 1000000",
        &gallery,
    );
    let png = dir.path().join("p.png");
    for count in [max, "257"] {
        rejects(
            &[
                "pixel-spectrum",
                "--pixel",
                "33,30",
                "--res",
                "4",
                "--average",
                count,
                "-o",
                png.to_str().unwrap(),
            ],
            "--average",
            &png,
        );
    }
    // Each flag within its own limit, the two together far above the limit of their product: refused
    // before the scene is read or a ray cast (the refusal returns; the work would take days).
    let casts = anisospec::cli::pixel_spectrum::MAX_RAY_CASTS.to_string();
    for (res, average) in [("8192", "256"), ("8192", "8"), ("2048", "32")] {
        rejects(
            &[
                "pixel-spectrum",
                "--pixel",
                "33,30",
                "--res",
                res,
                "--average",
                average,
                "-o",
                png.to_str().unwrap(),
            ],
            &format!("ray casts, above the limit of {casts}"),
            &png,
        );
    }
    // A point file of more sets than the realization limit is not averaged whole.
    let many = dir.path().join("many.npy");
    let sets = anisospec::stats::MAX_REALIZATIONS + 1;
    let bytes = npy_bytes(&format!("({sets}, 1, 2)"), false, &vec![0.25; 2 * sets]);
    std::fs::write(&many, &bytes).unwrap();
    let m = many.to_str().unwrap();
    rejects(
        &["spectrum", "--input", m, "--res", "8", "-o", o],
        &format!("holds {sets} sets, above the largest realization count, 1000000; average its first 1000000 with --realizations 1000000"),
        &out,
    );
    let run = anisospec(&[
        "spectrum",
        "--input",
        m,
        "--res",
        "8",
        "--realizations",
        "2",
        "-o",
        o,
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert_eq!(
        std::fs::read(&many).unwrap(),
        bytes,
        "the input is untouched"
    );
}

/// The same limits in a compare config, caught by `validate()` before any work.
#[test]
fn compare_config_counts_above_their_limits_are_refused() {
    let (dir, config) = tmp("study.toml");
    let out = dir.path().join("report");
    let (c, o) = (config.to_str().unwrap(), out.to_str().unwrap());
    let max = usize::MAX;
    for (text, needle) in [
        (
            format!("realizations = {max}\n"),
            "realizations = 18446744073709551615 is above",
        ),
        (
            format!("spectra_realizations = {max}\n"),
            "largest realization count",
        ),
        (
            format!("table_sets = {max}\n"),
            "table_sets = 18446744073709551615",
        ),
    ] {
        std::fs::write(&config, text).unwrap();
        rejects(&["compare", "--config", c, "--out", o], needle, &out);
    }
}

/// Each bounded flag's `--help` states its limit, the value of the constant that enforces it.
#[test]
fn bounded_flags_state_their_limits_in_help() {
    let realizations = anisospec::stats::MAX_REALIZATIONS.to_string();
    let cones = anisospec::spectrum::profiles::MAX_CONES.to_string();
    let average = anisospec::cli::pixel_spectrum::MAX_AVERAGE.to_string();
    let casts = anisospec::cli::pixel_spectrum::MAX_RAY_CASTS.to_string();
    for (cmd, limits) in [
        ("spectrum", vec![&realizations, &cones]),
        ("converge", vec![&realizations]),
        ("variance", vec![&realizations, &cones]),
        ("pixel-spectrum", vec![&average, &casts]),
        ("gallery", vec![&realizations]),
    ] {
        let o = anisospec(&[cmd, "--help"]);
        let help = String::from_utf8_lossy(&o.stdout);
        for limit in limits {
            assert!(help.contains(limit.as_str()), "{cmd} --help lacks {limit}");
        }
    }
}

/// A fan over the widest shear range is predicted in well under a second (its coefficients' cost used
/// to grow with the range: ±1e6 wrote nothing after minutes), with a finite variance.
#[test]
fn variance_of_a_wide_fan_finishes_finite() {
    let (_dir, csv) = tmp("fan.csv");
    let o = anisospec(&[
        "variance",
        "--sampler",
        "random",
        "--integrand",
        "fan:s0=-1e6,s1=1e6@xu",
        "-n",
        "4",
        "--realizations",
        "4",
        "--res",
        "16",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&csv).unwrap();
    let row = text.lines().nth(1).unwrap();
    let variance: f64 = row.split(',').nth(1).unwrap().parse().unwrap();
    assert!(variance.is_finite() && variance > 0.0, "{row}");
}

/// An N of `ns` near `usize::MAX` is refused by the coordinate limit before any sampler looks for its
/// nearest valid N (a search one count at a time that used to spin for many minutes, and wrap).
#[test]
fn compare_refuses_an_n_near_usize_max_before_searching() {
    let (dir, config) = tmp("study.toml");
    let out = dir.path().join("report");
    let (c, o) = (config.to_str().unwrap(), out.to_str().unwrap());
    for ns in ["[16, 18446744073709551615]", "[18446744073709551615, 16]"] {
        std::fs::write(&config, format!("ns = {ns}\n")).unwrap();
        rejects(
            &["compare", "--config", c, "--out", o],
            "ns: N × D = 18446744073709551615 × 4",
            &out,
        );
    }
    std::fs::write(&config, "spectra_n = 18446744073709551615\n").unwrap();
    rejects(
        &["compare", "--config", c, "--out", o],
        "spectra_n = 18446744073709551615: N × D",
        &out,
    );
}

/// A negative count for a flag other than `-n` is answered by that flag, not taken for an unknown
/// flag: exit 2, the flag named, and no output.
#[test]
fn negative_counts_are_named_by_their_flag() {
    let (_dir, out) = tmp("s.png");
    let o = out.to_str().unwrap();
    for (flag, extra) in [
        ("--res", vec!["spectrum", "--sampler", "random", "-n", "16"]),
        (
            "--realizations",
            vec!["spectrum", "--sampler", "random", "-n", "16"],
        ),
        ("--sets", vec!["sample", "--sampler", "random", "-n", "16"]),
        (
            "--max-iters",
            vec![
                "optimize",
                "--target",
                "targets/blue-noise.toml",
                "-n",
                "16",
            ],
        ),
    ] {
        let mut args = extra.clone();
        args.extend([flag, "-2", "-o", o]);
        rejects(&args, &format!("'{flag} <"), &out);
        rejects(&args, "a count is a whole number, 0 or more, not -2", &out);
    }
}

/// A negative value for a real-valued flag reaches the flag's own check (exit 2, the flag and the
/// value named, no output) instead of being taken for an unknown flag.
#[test]
fn negative_reals_reach_their_flags_check() {
    let (_dir, out) = tmp("t.npy");
    let o = out.to_str().unwrap();
    let spectrum = ["spectrum", "--sampler", "random", "-n", "16", "--eps", "-1"];
    let mut args = spectrum.to_vec();
    args.extend(["-o", o]);
    rejects(&args, "NUFFT tolerance -1 is out of range", &out);
    for (flag, message) in [
        (
            "--strat-radius",
            "--strat-radius -1: give a finite radius >= 0",
        ),
        (
            "--repulsion-weight",
            "--repulsion-weight -1: give a weight from 0",
        ),
        ("--tol", "--tol -1: give a finite number >= 0"),
        (
            "--max-seconds",
            "--max-seconds -1: give a positive number of seconds",
        ),
    ] {
        let args = [
            "optimize",
            "--target",
            "targets/blue-noise.toml",
            "--dims",
            "4",
            "-n",
            "16",
            flag,
            "-1",
            "-o",
            o,
        ];
        rejects(&args, message, &out);
    }
    // A repulsion wider than a hexagonal packing's spacing stacks points into clusters: refused.
    for (radius, shown) in [("1e9", "1000000000"), ("1.25", "1.25")] {
        let args = [
            "optimize",
            "--target",
            "targets/blue-noise.toml",
            "-n",
            "16",
            "--repulsion-radius",
            radius,
            "-o",
            o,
        ];
        rejects(
            &args,
            &format!("--repulsion-radius {shown}: give at most 1.07 mean"),
            &out,
        );
    }
}

/// `optimize --target TARGET -n 16 FLAGS` is refused with `needle`, and writes nothing.
fn optimize_rejects(target: &str, flags: &[&str], needle: &str) {
    let (_dir, out) = tmp("t.npy");
    let mut args = vec!["optimize", "--target", target, "-n", "16"];
    args.extend(flags);
    args.extend(["-o", out.to_str().unwrap()]);
    rejects(&args, needle, &out);
}

/// A 2D table has no xy and uv strata: `--strat-radius` and `--strat-weight` are refused by name there,
/// not recorded in the sidecar and the header's command as if they had been used.
#[test]
fn two_d_tables_refuse_the_strata_flags() {
    let blue = "targets/blue-noise.toml";
    optimize_rejects(
        blue,
        &["--strat-weight", "3"],
        "--strat-weight sets the 4D loss",
    );
    optimize_rejects(
        blue,
        &["--strat-radius", "0.2", "--strat-weight", "3"],
        "--strat-radius and --strat-weight set the 4D loss",
    );
}

/// A flag for a loss term that another flag or the target switches off would be ignored: it is
/// refused by name. Before, a weight with its radius 0 and an annular weight on a variance target
/// (whose grid has no annuli) gave a table identical to one without them.
#[test]
fn a_flag_without_its_term_is_refused() {
    let (blue, fan) = ("targets/blue-noise.toml", "targets/fan-variance.toml");
    for (target, flags, needle) in [
        (
            blue,
            &["--repulsion-radius", "0.5", "--repulsion-weight", "0"][..],
            "--repulsion-radius has no effect with --repulsion-weight 0",
        ),
        (
            blue,
            &[
                "--dims",
                "4",
                "--strat-radius",
                "0.2",
                "--strat-weight",
                "0",
            ],
            "--strat-radius has no effect with --strat-weight 0",
        ),
        (
            blue,
            &["--repulsion-radius", "0", "--repulsion-weight", "5"],
            "--repulsion-weight has no effect with --repulsion-radius 0",
        ),
        (
            blue,
            &["--dims", "4", "--strat-radius", "0", "--strat-weight", "5"],
            "--strat-weight has no effect with --strat-radius 0",
        ),
        (
            fan,
            &["--annular-weight", "3"],
            "--annular-weight has no effect here: targets/fan-variance.toml is a variance target",
        ),
        (
            fan,
            &[
                "--dims",
                "4",
                "--strat-weight",
                "0",
                "--annular-weight",
                "3",
            ],
            "and --strat-weight 0 switches off the strata term",
        ),
        (
            "targets/fan-lattice.toml",
            &["--seed", "3"],
            "so --seed would not apply",
        ),
    ] {
        optimize_rejects(target, flags, needle);
    }
}

/// A start sampler whose nearest N is 1 is refused with the smallest N above 1 it makes (an optimized
/// set needs 2 points; "the nearest N it allows is 1" alone named an N optimize refuses).
#[test]
fn a_start_of_one_point_names_the_n_that_works() {
    let (_dir, out) = tmp("t.npy");
    rejects(
        &[
            "optimize",
            "--target",
            "targets/widened-hairline.toml",
            "--init",
            "jittered",
            "-n",
            "2",
            "-o",
            out.to_str().unwrap(),
        ],
        "the nearest N it allows is 1, but an optimized set needs at least 2 points: use N = 4, the smallest above 1 that jittered makes",
        &out,
    );
}

/// A lattice search whose integrand sampling is too large is refused before any work, by its file,
/// with the placements that would fit (it samples 4096 x 4096 points whatever the extent).
#[test]
fn a_lattice_search_too_large_is_refused_at_once() {
    let (dir, target) = tmp("big.toml");
    std::fs::write(
        &target,
        "kind = \"variance\"\nintegrand = \"fan:s0=0.3,s1=0.7\"\nshear = 0.5\nplacements = 1024\nextent = 2\ndesign = \"lattice\"\n",
    )
    .unwrap();
    let out = dir.path().join("t.npy");
    let args = [
        "optimize",
        "--target",
        target.to_str().unwrap(),
        "-n",
        "64",
        "-o",
        out.to_str().unwrap(),
    ];
    let o = anisospec(&args);
    refused(
        &o,
        &args,
        "big.toml: the variance target would evaluate its integrand 1.718e10 times (1024 placements on 4096 x 4096 points), more than 1.074e9; lower its placements to at most 64",
        &out,
    );
    // Before, it was refused only after the search had started (3.9 to 9.5 s in).
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("searching"), "{err}");
}

/// A run stopped by `--max-seconds` depends on the machine's speed: it says so on stderr and in the C
/// header, under the command that would not remake it; the sidecar records the shape's weights in
/// use (the defaults, which the target file leaves out).
#[test]
fn optimize_says_when_the_time_limit_stopped_it() {
    let (dir, out) = tmp("t.npy");
    let o = anisospec(&[
        "optimize",
        "--target",
        "targets/blue-noise.toml",
        "-n",
        "256",
        "--sets",
        "2",
        "--max-seconds",
        "1e-9",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("warning: 2 of 2 sets stopped at --max-seconds (1e-9 s)"),
        "{err}"
    );
    let header = std::fs::read_to_string(dir.path().join("t.h")).unwrap();
    let second = header.lines().nth(1).unwrap();
    assert!(
        second.starts_with("/* 2 of 2 sets stopped at --max-seconds"),
        "{second}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("t.json")).unwrap()).unwrap();
    assert_eq!(json["parameters"]["dark_weight"], 8.0);
    assert_eq!(json["parameters"]["falloff"], 0.0);
}

/// A lattice design searches lattices and moves no points: the flags of the point optimizer (a start,
/// held strata, the solver's limits, the loss's weights) are refused by name before any work, not
/// ignored.
#[test]
fn lattice_designs_refuse_the_optimizers_flags() {
    let (dir, out) = tmp("fan.npy");
    let target = dir.path().join("fan.toml");
    std::fs::write(
        &target,
        "kind = \"variance\"\nintegrand = \"fan:s0=0.3,s1=0.7\"\nshear = 0.5\nplacements = 2\nextent = 2.0\ndesign = \"lattice\"\n",
    )
    .unwrap();
    let (t, o) = (target.to_str().unwrap(), out.to_str().unwrap());
    for (flags, needle) in [
        (
            vec!["--init", "sobol", "--latin"],
            "so --init and --latin would not apply",
        ),
        (vec!["--max-iters", "5"], "so --max-iters would not apply"),
        (
            vec!["--annular-weight", "3"],
            "so --annular-weight would not apply",
        ),
        (vec!["--exact"], "so --exact would not apply"),
        (
            vec!["--strat-radius", "0.2", "--strat-weight", "0"],
            "so --strat-radius and --strat-weight would not apply",
        ),
    ] {
        let mut args = vec!["optimize", "--target", t, "--dims", "4", "-n", "16"];
        args.extend(flags);
        args.extend(["-o", o]);
        rejects(&args, needle, &out);
    }
}

/// `variance --shear` predicts in the sheared pattern's frame, which needs the integrand on the xu and
/// yv planes (the planes the shear moves within) and a grid it can sample; either refusal names the
/// fix, and nothing is written.
#[test]
fn variance_with_a_shear_refuses_what_it_cannot_pull_back() {
    let (_dir, out) = tmp("v.csv");
    let o = out.to_str().unwrap();
    let base = [
        "variance",
        "--sampler",
        "padded-mj",
        "-n",
        "16",
        "--shear",
        "0.5,0.5",
    ];
    let with = |extra: &[&'static str]| {
        let mut a = base.to_vec();
        a.extend_from_slice(extra);
        a.extend(["-o", o]);
        a
    };
    rejects(
        &with(&["--integrand", "gaussian@xy"]),
        "needs an integrand on the xu and yv planes",
        &out,
    );
    rejects(
        &with(&["--integrand", "sheared:s=0.5@xu", "--res", "2048"]),
        "so that K is at most 1024",
        &out,
    );
    // A grid that grows with N past the limit only at the last N is refused before the first N's
    // million realizations (minutes of work before the check ran per N), sheared or not.
    let growing = |sheared: bool| {
        let ns = if sheared { "16,576" } else { "16,65536" };
        let mut a = vec!["variance", "--sampler", "padded-mj", "-n", ns];
        a.extend(["--integrand", "sheared:s=0.5@xu", "--res-per-n", "4"]);
        a.extend(["--realizations", "1000000", "-o", o]);
        if sheared {
            a.extend(["--shear", "0.5,0.5"]);
        }
        a
    };
    rejects(&growing(true), "so that K is at most 1024", &out);
    rejects(
        &growing(false),
        "coefficients the prediction evaluates",
        &out,
    );
    let run = anisospec(&with(&["--integrand", "sheared:s=0.5@xu", "--res", "64"]));
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(String::from_utf8_lossy(&run.stdout).contains("padded-mj+shear(0.5,0.5,transported)"));
}

/// `variance --shear` says, in its help and in its tail warning, that K stops at 1024 (the
/// pulled-back integrand's sampling grid) and that the cones are the pattern's directions: the flat
/// advice to raise --res or --res-per-n would lead past it to a refusal. (The flattened ShearArgs
/// field's doc comment is not shown by clap, so the help says it elsewhere.)
#[test]
fn variance_with_a_shear_says_where_its_grid_stops() {
    let help = anisospec(&["variance", "--help"]);
    let text = String::from_utf8_lossy(&help.stdout);
    assert!(text.contains("with --shear at most 1024"), "{text}");
    assert!(text.contains("unsheared pattern's frame"), "{text}");
    assert!(
        text.contains("the directions are the unsheared pattern's"),
        "{text}"
    );
    // The exact shear puts the edge on the pattern's k1 axis, dark up to N: the tail dominates.
    let run = anisospec(&[
        "variance",
        "--sampler",
        "padded-mj",
        "--integrand",
        "sheared:s=0.5,c=0.7@xu",
        "-n",
        "256",
        "--res",
        "64",
        "--realizations",
        "8",
        "--shear",
        "0.5,0.5",
    ]);
    assert!(run.status.success());
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("white-noise tail"), "{err}");
    assert!(err.contains("up to K = 1024 with --shear"), "{err}");
}

/// At N = 2 the 4D strata term's blue-noise disc reaches no frequency cell. The user gave no
/// blue-noise target, so the refusal of a double-wedge table names the strata term and its flags;
/// without the term it runs. A lattice design has no strata term at all.
#[test]
fn a_strata_term_out_of_reach_is_named_as_such() {
    let (dir, out) = tmp("wedge.npy");
    let o = out.to_str().unwrap();
    let args = [
        "optimize",
        "--target",
        "targets/double-wedge.toml",
        "--dims",
        "4",
        "-n",
        "2",
        "--max-iters",
        "2",
        "-o",
        o,
    ];
    rejects(&args, "the 4D strata term", &out);
    rejects(&args, "--strat-weight 0", &out);
    let mut without = args.to_vec();
    without.extend(["--strat-weight", "0"]);
    let run = anisospec(&without);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(out.is_file());
    // A lattice design keeps no strata term: at N = 2 it runs as it is, and --strat-weight is one
    // of the loss flags it refuses.
    let target = dir.path().join("fan.toml");
    std::fs::write(
        &target,
        "kind = \"variance\"\nintegrand = \"fan:s0=0.3,s1=0.7\"\nshear = 0.5\nplacements = 0\nextent = 2.0\ndesign = \"lattice\"\n",
    )
    .unwrap();
    let lattice_out = dir.path().join("fan.npy");
    let t = target.to_str().unwrap();
    let args = [
        "optimize",
        "--target",
        t,
        "--dims",
        "4",
        "-n",
        "2",
        "-o",
        lattice_out.to_str().unwrap(),
    ];
    let run = anisospec(&args);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    std::fs::remove_file(&lattice_out).unwrap();
    let mut with_weight = args.to_vec();
    with_weight.extend(["--strat-weight", "0"]);
    rejects(&with_weight, "--strat-weight would not apply", &lattice_out);
}

/// A radial profile holds the annuli r = 1 … K/2 − 1; at K = 2 there is none, so `spectrum --radial`
/// and `gallery` (which writes one per spectrum) refuse --res 2 instead of writing header-only CSVs.
#[test]
fn radial_profiles_need_a_grid_of_4() {
    let (dir, csv) = tmp("r.csv");
    let spec = dir.path().join("s.npy");
    let (c, s) = (csv.to_str().unwrap(), spec.to_str().unwrap());
    let args = [
        "spectrum",
        "--sampler",
        "random",
        "-n",
        "16",
        "--res",
        "2",
        "--radial",
        c,
        "-o",
        s,
    ];
    rejects(&args, "--radial needs --res 4 or more", &csv);
    assert!(!spec.exists());
    let o = anisospec(&[
        "spectrum",
        "--sampler",
        "random",
        "-n",
        "16",
        "--res",
        "4",
        "--radial",
        c,
        "-o",
        s,
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(std::fs::read_to_string(&csv).unwrap().lines().count(), 2);
    let gallery = dir.path().join("g");
    // Odd or tiny, --res is told what the gallery takes (before, --res 1 was told "e.g. --res 2").
    for res in ["2", "1"] {
        rejects(
            &["gallery", "--res", res, "--out", gallery.to_str().unwrap()],
            "give --res 4 or more",
            &gallery,
        );
    }
    // The gallery has no --exact: a tolerance out of range is not pointed at one.
    let o = anisospec(&["gallery", "--eps", "0", "--out", gallery.to_str().unwrap()]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("choose eps in") && !e.contains("exact"), "{e}");
    // A file where the gallery's own folder goes is named as that folder.
    std::fs::create_dir(&gallery).unwrap();
    std::fs::write(gallery.join("gallery"), "").unwrap();
    rejects(
        &["gallery", "--out", gallery.to_str().unwrap()],
        "the gallery folder",
        &gallery.join("gallery/index.md"),
    );
}

/// compare's closing line counts its samplers and integrands in the singular when there is one.
#[test]
fn compare_counts_one_integrand_in_the_singular() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("one.toml");
    std::fs::write(
        &config,
        "ns = [4, 16]\nrealizations = 2\nclassical = [\"random\"]\nsheared = []\ntables = []\npixel_classes = []\nspectra_n = 4\nspectra_res = 4\nspectra_realizations = 2\n\n[[analytic]]\nlabel = \"edge\"\nspec = \"sheared:s=0.5,c=0.7@xu\"\nshear = [0.5, 0.5]\nshear_range = [0.5, 0.5]\n",
    )
    .unwrap();
    let (out, cache) = (dir.path().join("report"), dir.path().join("cache"));
    let o = anisospec(&[
        "compare",
        "--config",
        config.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--cache",
        cache.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("compared 1 sampler on 1 integrand in "),
        "{err}"
    );
}

/// A negative pixel reaches `--pixel`'s own check (exit 2, the value and the fix named) instead of
/// being taken for an unknown flag.
#[test]
fn a_negative_pixel_is_named_by_its_flag() {
    let (_dir, out) = tmp("p.npy");
    rejects(
        &[
            "pixel-spectrum",
            "--pixel",
            "-1,2",
            "-o",
            out.to_str().unwrap(),
        ],
        "--pixel '-1,2' is not COLUMN,ROW; give two non-negative integers",
        &out,
    );
}

/// A Gaussian narrower than about 1e-162 has σ² = 0 in f64: its variance is 0, not NaN (the Poisson
/// sum's m = 0 term was 0 / 0).
#[test]
fn a_gaussian_whose_width_underflows_has_a_variance_of_0() {
    let o = anisospec(&["integrands", "--check", "gaussian:sigma=1e-200"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.contains("variance   0.0000000000e0"), "{out}");
    assert!(!out.to_lowercase().contains("nan"), "{out}");
}

/// A prediction at rounding level names its cause: an integrand with no variance in f64 (a disc of
/// radius 1e-300) is integrated exactly by any sampler; a lattice on a smooth Gaussian has a spectrum
/// that is 0 wherever the integrand has energy.
#[test]
fn variance_at_rounding_level_names_its_cause() {
    let predict = |sampler: &str, integrand: &str| {
        let o = anisospec(&[
            "variance",
            "--sampler",
            sampler,
            "--integrand",
            integrand,
            "-n",
            "16,64",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let out = predict("jittered", "disc:r=1e-300");
    assert!(out.contains("no predicted slope"), "{out}");
    assert!(
        out.contains("the integrand has no energy to integrate"),
        "{out}"
    );
    let out = predict("lattice", "gaussian:sigma=0.15");
    assert!(out.contains("no predicted slope"), "{out}");
    assert!(
        out.contains("the sampler's spectrum is 0, or below the NUFFT's error at --eps, wherever the integrand has energy"),
        "{out}"
    );
}

/// Samplers that integrate the integrand exactly at every N (a lattice on an edge along its strata)
/// have every MSE 0, which a log axis cannot show: converge writes its CSV, leaves out the plot and
/// says so, as compare's report does (it used to fail with exit code 1 after the run, writing
/// nothing).
#[test]
fn converge_with_every_mse_0_writes_its_csv_and_no_plot() {
    let (dir, csv) = tmp("c.csv");
    let png = dir.path().join("c.png");
    let o = anisospec(&[
        "converge",
        "--sampler",
        "lattice",
        "--integrand",
        "step:theta=0",
        "-n",
        "2,4,16",
        "--realizations",
        "4",
        "-o",
        csv.to_str().unwrap(),
        "--plot",
        png.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(csv.is_file());
    assert!(!png.exists());
    assert!(
        err.contains("no plot written to") && err.contains("every MSE is 0"),
        "{err}"
    );
}

/// A `--cache` that is a file is refused before the reference is computed (about 45 s on the
/// built-in scene), with exit code 2; it used to fail with exit code 1 once the reference was done.
#[test]
fn render_refuses_a_cache_that_is_a_file_before_any_work() {
    let (dir, out) = tmp("r.exr");
    let cache = dir.path().join("cache");
    std::fs::write(&cache, "mine").unwrap();
    for extra in [&[][..], &["--sampler", "sobol", "--spp", "4"][..]] {
        let mut args = vec![
            "render",
            "--cache",
            cache.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ];
        if extra.is_empty() {
            args.push("--reference");
        }
        args.extend_from_slice(extra);
        rejects(&args, "is a file, not a folder", &out);
    }
    assert_eq!(std::fs::read_to_string(&cache).unwrap(), "mine");
}

/// Extreme numbers in a scene file and in `--strat-radius` are echoed in short form (`1e300`), not
/// as 300 digits.
#[test]
fn extreme_scene_and_strata_numbers_are_echoed_in_short_form() {
    let (dir, out) = tmp("o.exr");
    for (line, needle) in [
        ("aperture = 1e300", "aperture = 1e300 is out of range"),
        ("focus = 1e-300", "focus = 1e-300 is out of range"),
        ("fov = 1e-300", "(fov = 1e-300, aperture = 0.04, focus = 3,"),
    ] {
        let scene = dir.path().join("scene.toml");
        std::fs::write(&scene, format!("width = 8\nheight = 8\n{line}\n")).unwrap();
        let args = [
            "oracle",
            "--scene",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ];
        rejects(&args, needle, &out);
        let err = String::from_utf8_lossy(&anisospec(&args).stderr).to_string();
        assert!(!err.contains("0000000000"), "{err}");
    }
    let (_dir, table) = tmp("t.npy");
    rejects(
        &[
            "optimize",
            "--target",
            "targets/double-wedge.toml",
            "--dims",
            "4",
            "-n",
            "64",
            "--strat-radius",
            "1e300",
            "-o",
            table.to_str().unwrap(),
        ],
        "radius --strat-radius 1e300 on xy and uv",
        &table,
    );
}

/// A cached reference image that holds a negative radiance is computed again, with a warning naming
/// the file, and the cache then holds the same numbers as before it was spoiled; a cache that cannot
/// be written costs only a warning, after the reference is shown.
#[test]
fn spoiled_or_unwritable_reference_caches_are_recomputed_or_warned_of() {
    let (dir, out) = tmp("r.exr");
    let scene = dir.path().join("scene.toml");
    std::fs::write(&scene, "width = 4\nheight = 4\n").unwrap();
    let cache = dir.path().join("cache");
    let args = [
        "render",
        "--reference",
        "--ref-count",
        "1024",
        "--scene",
        scene.to_str().unwrap(),
        "--cache",
        cache.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ];
    let o = anisospec(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let cached: Vec<PathBuf> = std::fs::read_dir(&cache)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    let [file] = &cached[..] else {
        panic!("one cached image: {cached:?}")
    };
    let good = std::fs::read(file).unwrap();
    // The first value of the data (after the npy header) is the first pixel's radiance.
    let mut spoiled = good.clone();
    let data = spoiled.len() - 4 * 4 * 2 * 8;
    spoiled[data..data + 8].copy_from_slice(&(-1.0f64).to_le_bytes());
    std::fs::write(file, &spoiled).unwrap();
    let o = anisospec(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("computing it again") && err.contains(&file.display().to_string()),
        "{err}"
    );
    assert_eq!(std::fs::read(file).unwrap(), good);

    let unwritable = "/proc/anisospec-test-cache";
    let mut args = args.to_vec();
    args[7] = unwritable;
    let o = anisospec(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("computed but not cached"), "{err}");
}

/// `--random-placement` on an integrand with nothing to move (a pixel) is refused, not ignored;
/// `compare` refuses a pixel among its analytic integrands, pointing to `pixel_classes`.
#[test]
fn pixels_refuse_what_only_analytic_integrands_take() {
    let (dir, out) = tmp("c.csv");
    rejects(
        &[
            "converge",
            "--sampler",
            "sobol",
            "--integrand",
            "pixel:px=1,py=1,refcount=1024",
            "-n",
            "16,64",
            "--realizations",
            "4",
            "--random-placement",
            "-o",
            out.to_str().unwrap(),
        ],
        "has nothing to move",
        &out,
    );
    let config = dir.path().join("study.toml");
    std::fs::write(
        &config,
        "[[analytic]]\nlabel = \"p\"\nspec = \"pixel:px=3,py=3\"\nshear = [0.5, 0.5]\nshear_range = [0.5, 0.5]\n",
    )
    .unwrap();
    let report = dir.path().join("report");
    rejects(
        &[
            "compare",
            "--config",
            config.to_str().unwrap(),
            "--out",
            report.to_str().unwrap(),
        ],
        "pixel_classes",
        &report,
    );
}

/// Results written to a standard output that cannot take them end in an error naming standard
/// output (exit 1), not a panic; a reader that closes the pipe early stops the run quietly with the
/// status of SIGPIPE (141).
#[cfg(target_os = "linux")]
#[test]
fn an_unwritable_standard_output_is_an_error_not_a_panic() {
    for args in [
        &["samplers"][..],
        &["integrands"],
        &["integrands", "--check", "step"],
        &["compare", "--print-config"],
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_anisospec"))
            .args(args)
            .stdout(std::fs::File::create("/dev/full").unwrap())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.contains("cannot write the results to standard output")
                && !err.contains("panicked"),
            "{args:?}: {err}"
        );
    }
    // 1500 lines of results into a pipe closed after the first byte.
    let ns: Vec<String> = (1..=1500).map(|n| n.to_string()).collect();
    let o = Command::new("bash")
        .arg("-c")
        .arg(format!(
            "\"$0\" variance --sampler random --integrand step -n {} --res 8 --realizations 2 --cones 1 | head -c 1 >/dev/null; echo \"${{PIPESTATUS[0]}}\"",
            ns.join(",")
        ))
        .arg(env!("CARGO_BIN_EXE_anisospec"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(String::from_utf8_lossy(&o.stdout).trim(), "141", "{err}");
    assert!(err.is_empty(), "{err}");
}

/// A render or reference beyond 2^34 rays, or with a reference count it cannot draw, is refused
/// before any work, naming the flag to lower or the counts allowed.
#[test]
fn a_render_beyond_the_ray_budget_is_refused_at_once() {
    let (dir, out) = tmp("big.exr");
    let scene = dir.path().join("big.toml");
    std::fs::write(&scene, "width = 4096\nheight = 4096\n").unwrap();
    let scene = scene.to_str().unwrap();
    let out_s = out.to_str().unwrap();
    rejects(
        &["render", "--scene", scene, "--reference", "-o", out_s],
        "lower --ref-count",
        &out,
    );
    rejects(
        &[
            "render",
            "--scene",
            scene,
            "--ref-count",
            "1024",
            "--sampler",
            "random",
            "--spp",
            "2048",
            "-o",
            out_s,
        ],
        "lower --spp",
        &out,
    );
    // A reference count that is not a power of two, with the oracle's shear: refused before the
    // oracle of 16.8 million pixels (minutes of work) is built.
    rejects(
        &[
            "render",
            "--scene",
            scene,
            "--ref-count",
            "1000",
            "--sampler",
            "random",
            "--spp",
            "1",
            "--shear",
            "-o",
            out_s,
        ],
        "must be a power of two",
        &out,
    );
}

/// An interrupt (SIGINT, as Ctrl-C sends) while a write is under way removes its hidden temporary
/// file, which a stopped run left behind before (173 MB for 60 million points), leaves no output,
/// and exits with status 130. On a loaded machine the write (about 2 s) can end before the handler
/// runs: the run then leaves its whole output, and is tried again with a larger one (it failed CI
/// once so, with the message "interrupted" alone).
#[cfg(unix)]
#[test]
fn an_interrupted_write_leaves_nothing_behind() {
    for n in ["4000000", "8000000", "16000000"] {
        let dir = tempfile::tempdir().unwrap();
        let mut child = Command::new(env!("CARGO_BIN_EXE_anisospec"))
            .args(["sample", "--sampler", "random", "-n", n, "-o"])
            .arg(dir.path().join("big.txt"))
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let temporary = || {
            std::fs::read_dir(dir.path())
                .unwrap()
                .filter_map(|e| e.ok())
                .find(|e| e.file_name().to_string_lossy().starts_with(".anisospec-"))
        };
        let started = std::time::Instant::now();
        while temporary().is_none() {
            assert!(
                child.try_wait().unwrap().is_none(),
                "the write ended before its temporary file was seen"
            );
            assert!(started.elapsed().as_secs() < 120, "no temporary file");
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        let sent = Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status()
            .unwrap();
        assert!(sent.success());
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        let left: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        if left == [std::ffi::OsString::from("big.txt")] {
            // The write was done first: its whole output is in place; no temporary is left.
            eprintln!("N = {n}: the write ended before the interrupt ({err}); trying a larger one");
            continue;
        }
        assert_eq!(out.status.code(), Some(130), "{err}");
        assert!(
            err.contains("interrupted: removed 1 unfinished output"),
            "{err}"
        );
        assert!(left.is_empty(), "{left:?}");
        return;
    }
    panic!("every write ended before its interrupt");
}

/// The shipped targets that need no image are built in: run from a folder with no `targets/`, a
/// shipped path is read from the binary (compare's default suite names its tables so), while the
/// image target, which needs its npy beside it, is still refused as missing, and a file of the user's
/// at a shipped path is read instead of the built-in copy.
#[test]
fn shipped_targets_are_built_in() {
    let dir = tempfile::tempdir().unwrap();
    let optimize = |target: &str| {
        Command::new(env!("CARGO_BIN_EXE_anisospec"))
            .args([
                "optimize",
                "--target",
                target,
                "-n",
                "16",
                "--max-iters",
                "1",
            ])
            .args(["-o", "t.npy"])
            .current_dir(dir.path())
            .output()
            .unwrap()
    };
    for target in ["targets/hairline.toml", "./targets/fan-variance.toml"] {
        let o = optimize(target);
        assert!(
            o.status.success(),
            "{target}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    let o = optimize("targets/image-ellipse.toml");
    assert_eq!(o.status.code(), Some(2));
    std::fs::create_dir(dir.path().join("targets")).unwrap();
    std::fs::write(
        dir.path().join("targets/hairline.toml"),
        "kind = \"mine\"\n",
    )
    .unwrap();
    let o = optimize("targets/hairline.toml");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.code() == Some(2) && err.contains("mine"), "{err}");
}

/// Interrupts a gallery (many files staged in a folder, written one after another) at 20 moments
/// spread over its run: every run exits with 130 and leaves no temporary file or folder behind,
/// whether the signal comes before, during or after its writes (before the temporaries were made
/// and registered as one step, 19 of 196 interrupted runs left a staging folder, emptied or refilled
/// while it was removed). The gallery takes about 0.2 s on 2 cores, so the latest moments can come
/// after a run has ended (exit 0): that run is tried again with 4 times the realizations, up to 128,
/// and a run that still ends first fails the test. The earliest moments can come before the handler
/// is installed on a loaded machine: a run killed by the signal itself (it has made nothing yet) is
/// allowed within the first 50 ms only. On Linux every other run writes its messages to a full
/// disk, which the handler's "interrupted" must not turn into a panic.
#[cfg(unix)]
#[test]
fn an_interrupted_gallery_leaves_no_temporary() {
    use std::os::unix::process::ExitStatusExt as _;
    for i in 0..20u64 {
        let delay = std::time::Duration::from_millis(5 + 10 * i);
        let mut realizations = 2;
        loop {
            let dir = tempfile::tempdir().unwrap();
            let stderr = if cfg!(target_os = "linux") && i % 2 == 1 {
                full_disk()
            } else {
                std::process::Stdio::null()
            };
            let child = Command::new(env!("CARGO_BIN_EXE_anisospec"))
                .args(["gallery", "-n", "64", "--res", "16", "--realizations"])
                .arg(realizations.to_string())
                .arg("--out")
                .arg(dir.path())
                .stderr(stderr)
                .spawn()
                .unwrap();
            std::thread::sleep(delay);
            let _ = Command::new("kill")
                .args(["-INT", &child.id().to_string()])
                .status();
            let out = child.wait_with_output().unwrap();
            let mut left = Vec::new();
            let mut folders = vec![dir.path().to_path_buf()];
            while let Some(folder) = folders.pop() {
                for entry in std::fs::read_dir(&folder).unwrap() {
                    let path = entry.unwrap().path();
                    if path
                        .file_name()
                        .unwrap()
                        .to_string_lossy()
                        .starts_with(".anisospec-")
                    {
                        left.push(path.clone());
                    }
                    if path.is_dir() {
                        folders.push(path);
                    }
                }
            }
            assert!(
                left.is_empty(),
                "interrupted after {delay:?} (R = {realizations}): {left:?}"
            );
            if out.status.code() == Some(0) && realizations < 128 {
                // The run ended before the interrupt: the same moment, in a longer run.
                eprintln!("R = {realizations}: the gallery ended before the interrupt after {delay:?}; trying 4 times the realizations");
                realizations *= 4;
                continue;
            }
            if out.status.signal() == Some(2) && delay.as_millis() < 50 {
                // Interrupted before the handler was installed: nothing was made to leave behind.
                break;
            }
            assert_eq!(
                out.status.code(),
                Some(130),
                "interrupted after {delay:?} (R = {realizations}): {:?}",
                out.status
            );
            break;
        }
    }
}

/// A converge run on a pixel whose reference takes a moment (1024 rays), short of its output flag.
const TINY_PIXEL_CONVERGE: &[&str] = &[
    "converge",
    "--sampler",
    "random",
    "--integrand",
    "pixel:px=1,py=1,refcount=1024",
    "-n",
    "16",
    "--realizations",
    "4",
];

/// A cache folder chosen by `$ANISOSPEC_CACHE` that is a file is refused before any work, naming the
/// variable (not a `--cache` flag the user never gave), by every command that caches a reference:
/// render, compare, and converge on a pixel (which only warned after the work before).
#[test]
fn a_cache_variable_that_names_a_file_is_refused_by_name() {
    let (dir, exr) = tmp("out.exr");
    let file = dir.path().join("not-a-folder");
    std::fs::write(&file, "x").unwrap();
    let csv = dir.path().join("out.csv");
    let report = dir.path().join("report");
    let render = ["render", "--sampler", "sobol", "--ref-count", "1024", "-o"];
    let converge = [TINY_PIXEL_CONVERGE, &["--output"]].concat();
    for (args, out) in [
        (&render[..], &exr),
        (&converge[..], &csv),
        (&["compare", "--out"][..], &report),
    ] {
        let mut args = args.to_vec();
        args.push(out.to_str().unwrap());
        let o = Command::new(env!("CARGO_BIN_EXE_anisospec"))
            .args(&args)
            .env("ANISOSPEC_CACHE", &file)
            .output()
            .unwrap();
        refused(&o, &args, "give $ANISOSPEC_CACHE a folder path", out);
        assert_eq!(std::fs::read_to_string(&file).unwrap(), "x");
    }
    // Without the variable, converge names the default folder and its --cache flag, as compare does.
    std::fs::create_dir(dir.path().join("out")).unwrap();
    std::fs::write(dir.path().join("out/cache"), "x").unwrap();
    let mut args = converge.to_vec();
    args.push(csv.to_str().unwrap());
    let o = Command::new(env!("CARGO_BIN_EXE_anisospec"))
        .args(&args)
        .current_dir(dir.path())
        .env_remove("ANISOSPEC_CACHE")
        .output()
        .unwrap();
    refused(
        &o,
        &args,
        "--cache out/cache is a file, not a folder, so no cache folder can be written there; give --cache a folder path",
        &csv,
    );
}

/// An output path that ends in a folder separator, or is an extension alone, names no file: refused
/// before any work with exit 2 (before, `y.npy/` passed the checks, the whole job ran, and writing
/// failed with exit 1).
#[test]
fn outputs_that_name_no_file_are_refused_before_the_work() {
    let (dir, _) = tmp("unused");
    let at = |name: &str| format!("{}/{name}", dir.path().display());
    let (slash, csv_slash, bare, spectrum) = (at("y.npy/"), at("r.csv/"), at(".npy"), at("s.npy"));
    let target = "targets/blue-noise.toml";
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["sample", "--sampler", "sobol", "-n", "64", "-o", &slash],
            "has no usable file name",
        ),
        (
            vec!["optimize", "--target", target, "-n", "64", "-o", &slash],
            "has no usable file name",
        ),
        (
            vec!["optimize", "--target", target, "-n", "64", "-o", &bare],
            "has no usable file name",
        ),
        (
            vec!["spectrum", "--sampler", "sobol", "-n", "64", "-o", &slash],
            "has no usable file name",
        ),
        (
            vec![
                "spectrum",
                "--sampler",
                "sobol",
                "-n",
                "64",
                "-o",
                &spectrum,
                "--radial",
                &csv_slash,
            ],
            "--radial",
        ),
    ];
    for (args, needle) in &cases {
        rejects(args, needle, &dir.path().join("y.npy"));
    }
    // The name suggested has an extension the command writes: the one given if it can, else its
    // first. And "-", standard output elsewhere, is no file here (render and oracle wrote -.exr).
    let png_slash = at("a.png/");
    let more: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["sample", "--sampler", "mj", "-n", "16", "-o", &png_slash],
            "out/name.npy",
        ),
        (
            vec!["spectrum", "--sampler", "mj", "-n", "16", "-o", &png_slash],
            "out/name.png",
        ),
        (
            vec!["sample", "--sampler", "mj", "-n", "16", "-o", "-"],
            "standard output",
        ),
        (
            vec!["render", "--sampler", "mj", "-o", "-"],
            "standard output",
        ),
        (vec!["oracle", "-o", "-"], "standard output"),
    ];
    for (args, needle) in &more {
        rejects(args, needle, Path::new("-.exr"));
    }
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "nothing written"
    );
}

/// The scale of a target's loss does not decide how far the optimizer goes: the same variance target
/// with weight 5000 (the default) and 1e-6 (losses about 1e-8) reaches about the same predicted
/// variance. Before, L-BFGS's absolute cost tolerance (1e-9) stopped every round of the small one at
/// once: 1.63e-2 of random sampling's against 6.41e-4 (25 times); now 7.78e-4 (1.2 times). Fixed
/// seed, so the figures are exact; the bound of 2 separates the two behaviours.
#[test]
fn a_variance_target_reaches_the_same_level_whatever_its_weight() {
    let dir = tempfile::tempdir().unwrap();
    let reached = |weight: &str| {
        let target = dir.path().join(format!("fan_{weight}.toml"));
        std::fs::write(
            &target,
            format!(
                "kind = \"variance\"\nintegrand = \"fan:s0=0.3,s1=0.7\"\nshear = 0.5\nplacements = 0\nextent = 2.0\nweight = {weight}\n"
            ),
        )
        .unwrap();
        let out = dir.path().join(format!("fan_{weight}.npy"));
        let o = anisospec(&[
            "optimize",
            "--target",
            target.to_str().unwrap(),
            "-n",
            "256",
            "--max-iters",
            "200",
            "-o",
            out.to_str().unwrap(),
        ]);
        let text =
            String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{text}");
        text.split("predicted variance ")
            .nth(1)
            .and_then(|rest| rest.split_whitespace().next())
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or_else(|| panic!("no predicted variance in: {text}"))
    };
    let (default, tiny) = (reached("5000"), reached("1e-6"));
    assert!(
        tiny < 2.0 * default && default < 2.0 * tiny,
        "weight 5000: {default:e}, weight 1e-6: {tiny:e}"
    );
}

/// `/dev/full` (Linux) as a child's stream: every write to it fails (ENOSPC), as on a full disk.
#[cfg(unix)]
fn full_disk() -> std::process::Stdio {
    std::process::Stdio::from(
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap(),
    )
}

/// Runs `args` with stderr on `/dev/full`, where every write fails (ENOSPC).
#[cfg(target_os = "linux")]
fn anisospec_with_full_stderr(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_anisospec"))
        .args(args)
        .stderr(full_disk())
        .output()
        .unwrap()
}

/// A standard error that cannot be written (a full disk) costs the run only its messages: the job
/// is done and the run exits with its own status, 0 with its files written, 2 on bad input (before,
/// the first message panicked, exit 101, on either path).
#[cfg(target_os = "linux")]
#[test]
fn a_full_standard_error_keeps_the_work_and_the_exit_status() {
    let dir = tempfile::tempdir().unwrap();
    let pts = dir.path().join("pts.npy");
    let pts_s = pts.to_str().unwrap();
    let o = anisospec_with_full_stderr(&[
        "sample",
        "--sampler",
        "jittered",
        "-n",
        "16",
        "--sets",
        "2",
        "-o",
        pts_s,
    ]);
    assert_eq!(o.status.code(), Some(0), "{:?}", o.status);
    assert_eq!(anisospec::points::io::read_points(&pts).unwrap().sets(), 2);
    // spectrum's messages come after its files are written (and its note of a dark annulus).
    let spec = dir.path().join("s.npy");
    let o = anisospec_with_full_stderr(&[
        "spectrum",
        "--input",
        pts_s,
        "--res",
        "8",
        "-o",
        spec.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{:?}", o.status);
    let bytes = std::fs::read(&spec).unwrap();
    assert_eq!(npyz::NpyFile::new(&bytes[..]).unwrap().shape(), &[8, 8]);
    // An input error (a missing file) and a usage error: exit 2 and no output, the message lost.
    let out = dir.path().join("never.npy");
    let out_s = out.to_str().unwrap();
    let missing = dir.path().join("missing.npy");
    for args in [
        &[
            "spectrum",
            "--input",
            missing.to_str().unwrap(),
            "-o",
            out_s,
        ][..],
        &["sample", "--sampler", "nosuch", "-n", "16", "-o", out_s],
    ] {
        let o = anisospec_with_full_stderr(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {:?}", o.status);
        assert!(!out.exists(), "{args:?}");
    }
}

/// `converge --cache DIR` keeps a pixel's reference in DIR, ahead of `$ANISOSPEC_CACHE` (which then
/// stays empty), as compare's and render's --cache do; without the flag the variable chooses, and an
/// empty variable counts as unset (out/cache under the working folder); a --cache with an analytic
/// integrand, which has no reference to cache, is refused.
#[test]
fn converge_caches_a_pixel_reference_in_its_cache_flag() {
    let dir = tempfile::tempdir().unwrap();
    let (given, variable) = (dir.path().join("given"), dir.path().join("variable"));
    std::fs::create_dir(&variable).unwrap();
    let csv = dir.path().join("c.csv");
    let converge = |cache: Option<&Path>, variable: &Path| {
        let mut args = [TINY_PIXEL_CONVERGE, &["-o", csv.to_str().unwrap()]].concat();
        if let Some(c) = cache {
            args.extend(["--cache", c.to_str().unwrap()]);
        }
        let o = Command::new(env!("CARGO_BIN_EXE_anisospec"))
            .args(&args)
            .env("ANISOSPEC_CACHE", variable)
            .current_dir(dir.path())
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    let entries = |d: &Path| std::fs::read_dir(d).map_or(0, |e| e.count());
    converge(Some(&given), &variable);
    assert_eq!(entries(&given), 1, "the reference is cached in --cache");
    assert_eq!(
        entries(&variable),
        0,
        "--cache takes precedence over $ANISOSPEC_CACHE"
    );
    // Without the flag the variable chooses, as before; an empty one is unset.
    converge(None, &variable);
    assert_eq!(entries(&variable), 1);
    converge(None, Path::new(""));
    assert_eq!(
        entries(&dir.path().join("out/cache")),
        1,
        "an empty variable"
    );
    let args = [
        "converge",
        "--sampler",
        "random",
        "--integrand",
        "disc:r=0.3",
        "-n",
        "16",
        "--cache",
        given.to_str().unwrap(),
        "-o",
        csv.to_str().unwrap(),
    ];
    std::fs::remove_file(&csv).unwrap();
    rejects(
        &args,
        "--cache has no effect with --integrand disc:r=0.3",
        &csv,
    );
}

/// A spectrum command's files hold what the library computes: the npy is the mean of the exact
/// `spectrum::power` of each set's xu projection, in DESIGN §3's layout, and the radial CSV is
/// `radial_profile` of that mean; the NUFFT's meets its contract against it.
#[test]
fn spectrum_outputs_equal_the_librarys_recomputation() {
    use anisospec::spectrum::{expected::ExpectedSpectrum, profiles, Method};
    use rand::Rng as _;
    let (sets, n, res, cones) = (3, 40, 32, 4);
    let mut rng = anisospec::rng::stream(17, 0);
    let values: Vec<f64> = (0..sets * n * 4).map(|_| rng.random::<f64>()).collect();
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("pts.npy");
    std::fs::write(&input, npy_bytes("(3, 40, 4)", false, &values)).unwrap();
    let run = |method: &[&str], npy: &str, csv: &str| -> (Vec<f64>, Vec<Vec<String>>) {
        let (npy, csv) = (dir.path().join(npy), dir.path().join(csv));
        let mut args = vec![
            "spectrum",
            "--input",
            input.to_str().unwrap(),
            "--proj",
            "xu",
            "--res",
            "32",
            "-o",
            npy.to_str().unwrap(),
            "--radial",
            csv.to_str().unwrap(),
            "--cones",
            "4",
        ];
        args.extend(method);
        let o = anisospec(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let bytes = std::fs::read(&npy).unwrap();
        let file = npyz::NpyFile::new(&bytes[..]).unwrap();
        assert_eq!(file.shape(), &[32, 32]);
        let rows = std::fs::read_to_string(&csv)
            .unwrap()
            .lines()
            .map(|l| l.split(',').map(str::to_string).collect())
            .collect();
        (file.into_vec().unwrap(), rows)
    };
    // x and u are dimensions 0 and 2: k1 goes with x, k2 with u.
    let projected: Vec<Vec<[f64; 2]>> = (0..sets)
        .map(|s| {
            (0..n)
                .map(|j| [values[(s * n + j) * 4], values[(s * n + j) * 4 + 2]])
                .collect()
        })
        .collect();
    let powers: Vec<Vec<f64>> = projected
        .iter()
        .map(|p| anisospec::spectrum::power(p, res, Method::Exact))
        .collect();
    let r = sets as f64;
    let mean: Vec<f64> = (0..res * res)
        .map(|b| powers.iter().map(|p| p[b]).sum::<f64>() / r)
        .collect();
    // Two-pass standard error per bin.
    let stderr: Vec<f64> = (0..res * res)
        .map(|b| {
            let var = powers.iter().map(|p| (p[b] - mean[b]).powi(2)).sum::<f64>() / (r - 1.0);
            (var / r).sqrt()
        })
        .collect();
    // The layout, against a direct sum written here: P[i, j] holds k1 = j - K/2, k2 = i - K/2. Each
    // sum errs by at most the library's bound of an exact P (`profiles::precision`: relative
    // 2 ρ_F + 2u, absolute ρ_F² N in a dark bin), so the two differ by twice that.
    let (dark, flat) = profiles::precision(Method::Exact, n, res);
    for i in 0..res {
        for j in 0..res {
            let (k1, k2) = (j as i64 - 16, i as i64 - 16);
            let direct = projected
                .iter()
                .map(|p| {
                    let f: rustfft::num_complex::Complex64 = p
                        .iter()
                        .map(|q| {
                            anisospec::spectrum::exact::turn(k1 as f64 * q[0] + k2 as f64 * q[1])
                        })
                        .sum();
                    f.norm_sqr() / n as f64
                })
                .sum::<f64>()
                / r;
            let tol = 2.0 * (flat * direct + dark);
            assert!(
                (mean[i * res + j] - direct).abs() <= tol,
                "k = ({k1}, {k2}): {} vs the direct sum {direct}",
                mean[i * res + j]
            );
        }
    }
    let (exact_npy, exact_csv) = run(&["--exact"], "exact.npy", "exact.csv");
    // The library sums the sets' P in set order and divides by R (PowerSums::mean_and_stderr: "the
    // bits of summing power's output set by set in the same order"): the same bits.
    for (b, (got, want)) in exact_npy.iter().zip(&mean).enumerate() {
        assert_eq!(got.to_bits(), want.to_bits(), "bin {b}: {got} vs {want}");
    }
    let spec = ExpectedSpectrum {
        res,
        n,
        realizations: sets,
        mean: mean.clone(),
        stderr: stderr.clone(),
    };
    let profile = profiles::radial_profile(&spec, cones, Method::Exact);
    assert_eq!(
        exact_csv[0].join(","),
        "r,r_normalized,mean,stderr,anisotropy_db,cone0_0.0deg,cone1_45.0deg,cone2_90.0deg,cone3_135.0deg"
    );
    assert_eq!(
        exact_csv.len(),
        1 + res / 2 - 1,
        "one row per annulus r = 1 .. K/2 - 1"
    );
    let number = |s: &str| {
        s.parse::<f64>()
            .unwrap_or_else(|_| panic!("'{s}' is no number"))
    };
    for (row, bin) in exact_csv[1..].iter().zip(&profile) {
        assert_eq!(row.len(), 5 + cones);
        assert_eq!(row[0], bin.r.to_string());
        // The CSV's numbers read back exactly (shortest round-trip form), and every column but the
        // standard error is computed from the same mean bits.
        assert_eq!(number(&row[1]), bin.r_normalized);
        assert_eq!(number(&row[2]), bin.mean, "r = {}", bin.r);
        assert_eq!(
            row[4].parse::<f64>().ok(),
            bin.anisotropy_db,
            "r = {}",
            bin.r
        );
        for (cell, cone) in row[5..].iter().zip(&bin.cones) {
            assert_eq!(cell.parse::<f64>().ok(), *cone, "r = {}", bin.r);
        }
        // The library's standard error takes the sums of P and of (P - P_first)² in one pass; the
        // two-pass one here differs by rounding alone: each variance of R values of at most
        // P_max errs by at most (R + 4) u (2 P_max)² R / (R - 1) (u = 2^-53), so the annulus's
        // sqrt(2 Σ se²) / c errs by at most 2 Σ that / R over c (sqrt a + sqrt b).
        let u = f64::EPSILON / 2.0;
        let (mut bound, mut count) = (0.0, 0.0);
        for b in 0..res * res {
            let (k1, k2) = anisospec::spectrum::frequency(b, res);
            if profiles::annulus(k1, k2) == bin.r {
                let p_max = powers.iter().map(|p| p[b]).fold(0.0, f64::max);
                bound += 2.0 * (r + 4.0) * u * (2.0 * p_max).powi(2) * r / (r - 1.0) / r;
                count += 1.0;
            }
        }
        let (got, want) = (number(&row[3]), bin.stderr.unwrap());
        // Plus each side's rounding of Σ se² over the c bins and of the root: (c + 4) u relative.
        let tol = 2.0 * bound / (count * count * (got + want)) + (count + 4.0) * u * (got + want);
        assert!(
            (got - want).abs() <= tol,
            "r = {}: stderr {got} vs {want} (bound {tol:e})",
            bin.r
        );
    }
    // The NUFFT at eps = 1e-9: within its contract (10 eps relative in every bin above 1e-3 of the
    // mean) against the exact mean, and so are the profile's means, means of such bins.
    let eps = 1e-9;
    let (nufft_npy, nufft_csv) = run(&["--eps", "1e-9"], "nufft.npy", "nufft.csv");
    let err = anisospec::spectrum::nufft::contract_error(&nufft_npy, &mean);
    assert!(err <= 10.0 * eps, "NUFFT error {err:e}");
    let grid_mean = mean.iter().sum::<f64>() / mean.len() as f64;
    assert!(
        mean.iter().all(|&p| p >= 1e-3 * grid_mean),
        "every bin is under the contract"
    );
    for (row, bin) in nufft_csv[1..].iter().zip(&profile) {
        let close = |got: f64, want: f64| (got - want).abs() <= 10.0 * eps * want;
        assert!(
            close(number(&row[2]), bin.mean),
            "r = {}: {}",
            bin.r,
            row[2]
        );
        for (cell, cone) in row[5..].iter().zip(&bin.cones) {
            assert!(close(number(cell), cone.unwrap()), "r = {}: {cell}", bin.r);
        }
    }
}
