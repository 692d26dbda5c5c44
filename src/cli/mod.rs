//! Subcommands of the `anisospec` binary: each has its clap arguments and a `run` function.

pub mod oracle;
pub mod pixel_spectrum;
