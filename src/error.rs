//! One error type for the library and the CLI, with the exit code each kind of failure maps to.

use std::path::Path;

/// Everything that can go wrong, sorted by whose fault it is.
///
/// `Usage` and `Input` are the user's to fix (exit code 2); `Io` and `Numerical` are failures of the
/// run itself (exit code 1). Every message names the problem and, where there is one, the fix.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A flag, name or parameter that cannot be used as given.
    #[error("{0}")]
    Usage(String),
    /// An input file or value that is malformed, empty, non-finite or out of range.
    #[error("{0}")]
    Input(String),
    /// The operating system refused a read or a write.
    #[error("{context}: {source}")]
    Io {
        /// What was being done, e.g. "cannot write out/spectrum.npy".
        context: String,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A computation that cannot produce a finite, meaningful answer.
    #[error("{0}")]
    Numerical(String),
}

impl Error {
    /// Process exit code: 2 for usage and input errors, 1 otherwise.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Usage(_) | Error::Input(_) => 2,
            Error::Io { .. } | Error::Numerical(_) => 1,
        }
    }

    /// An I/O error whose reader closed the pipe (`anisospec ... | head`).
    pub fn is_broken_pipe(&self) -> bool {
        matches!(self, Error::Io { source, .. } if source.kind() == std::io::ErrorKind::BrokenPipe)
    }

    /// Wraps an I/O error with the path it concerns.
    pub fn io(what: &str, path: &Path, source: std::io::Error) -> Self {
        Error::Io {
            context: format!("cannot {what} {}", path.display()),
            source,
        }
    }

    /// Wraps the failure to read a file the user named (a point set, a target, a config): a missing,
    /// forbidden or non-file path, or text that is not UTF-8, is an input error naming the path and the
    /// fix; anything else (the disk failing) stays an I/O error.
    pub fn read_input(path: &Path, source: std::io::Error) -> Self {
        use std::io::ErrorKind;
        let fix = match source.kind() {
            ErrorKind::NotFound | ErrorKind::NotADirectory => "check the path",
            ErrorKind::PermissionDenied => "check the file's permissions",
            ErrorKind::IsADirectory => "name a file, not a folder",
            ErrorKind::InvalidData => "the file must be UTF-8 text",
            _ => return Error::io("read", path, source),
        };
        Error::Input(format!("cannot read {}: {source}; {fix}", path.display()))
    }
}

impl Error {
    /// The same error with every mention of the path `from` replaced by `to`: a failure while writing a
    /// staged output names the output, not the temporary folder it was written in.
    pub fn with_path_replaced(self, from: &Path, to: &Path) -> Self {
        let (from, to) = (from.display().to_string(), to.display().to_string());
        let fix = |m: String| m.replace(&from, &to);
        match self {
            Error::Usage(m) => Error::Usage(fix(m)),
            Error::Input(m) => Error::Input(fix(m)),
            Error::Io { context, source } => Error::Io {
                context: fix(context),
                source,
            },
            Error::Numerical(m) => Error::Numerical(fix(m)),
        }
    }
}

/// Result with the crate's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

/// `v` as a message or a label shows a number the user gave: Rust's shortest form that reads back as
/// the same `f64` (`0.5`, `-3`, `inf`), in scientific notation (`1e-300`, `2.5e20`) where the plain
/// form would run to many zeros, below 1e-4 or from 1e16 in magnitude (where `{:?}` switches too).
pub fn number(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-4..1e16).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

#[cfg(test)]
mod tests {
    use super::number;

    #[test]
    fn numbers_are_short_and_read_back_exactly() {
        for (v, text) in [
            (0.5, "0.5"),
            (-3.0, "-3"),
            (0.0, "0"),
            (1e-4, "0.0001"),
            (1e-300, "1e-300"),
            (-2.5e20, "-2.5e20"),
            (f64::INFINITY, "inf"),
        ] {
            assert_eq!(number(v), text);
        }
        for v in [
            0.1 + 0.2,
            1e-5 / 3.0,
            1e300 / 7.0,
            f64::MIN_POSITIVE,
            -f64::MAX,
        ] {
            assert!(number(v).len() <= 24, "{v:e}: {}", number(v));
            assert_eq!(number(v).parse::<f64>().unwrap(), v);
        }
    }
}
