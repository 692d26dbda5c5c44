//! Command-line subcommands of the analysis: integrands, variance, converge.
