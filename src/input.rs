//! Reading the files a user names, bounded: a device that never ends (a link to `/dev/zero`, say)
//! is refused after a limit, or by its first bytes, not read until memory runs out. (A named pipe
//! with no writer is waited on, as any program reading it would.)

use crate::error::{Error, Result};
use std::io::Read;
use std::path::Path;

/// Largest text file read whole (a target, a compare config, a scene): 4 MiB, far above any real one.
pub const MAX_TEXT_BYTES: u64 = 4 << 20;

/// The first bytes of every npy file.
const NPY_MAGIC: &[u8; 6] = b"\x93NUMPY";

/// The UTF-8 text of the file `path`, a `what` (e.g. "target file"): refused past
/// [`MAX_TEXT_BYTES`], and missing, forbidden, folder and non-UTF-8 paths as [`Error::read_input`]
/// says.
pub fn read_text(path: &Path, what: &str) -> Result<String> {
    let bytes = read_at_most(path, MAX_TEXT_BYTES, || {
        format!(
            "more than {} MiB, far larger than any {what}; check the path",
            MAX_TEXT_BYTES >> 20
        )
    })?;
    String::from_utf8(bytes).map_err(|e| {
        Error::read_input(
            path,
            std::io::Error::new(std::io::ErrorKind::InvalidData, e.utf8_error()),
        )
    })
}

/// The bytes of the npy file `file` (opened from `path`), at most `limit` of them. The outer error is
/// a failure to read (naming `path`, see [`Error::read_input`]); the inner one the reason the bytes are
/// not an npy file's, for the caller to word: a file that does not start with the npy magic is
/// refused by its first 6 bytes, one longer than `limit` after `limit` bytes.
pub fn read_npy_bytes(
    mut file: std::fs::File,
    path: &Path,
    limit: u64,
) -> Result<std::result::Result<Vec<u8>, String>> {
    let mut magic = [0u8; 6];
    let mut got = 0;
    while got < magic.len() {
        match file.read(&mut magic[got..]) {
            Ok(0) => break,
            Ok(k) => got += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(Error::read_input(path, e)),
        }
    }
    if &magic[..got] != NPY_MAGIC {
        return Ok(Err(if got == 0 {
            "the file is empty".to_string()
        } else {
            "no npy magic \\x93NUMPY at the start".to_string()
        }));
    }
    let mut bytes = magic.to_vec();
    file.take(limit.saturating_sub(6) + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::read_input(path, e))?;
    if bytes.len() as u64 > limit {
        return Ok(Err(format!(
            "more than {limit} bytes, larger than any array it may hold"
        )));
    }
    Ok(Ok(bytes))
}

/// Refuses a path that exists but is not a regular file (a device such as `/dev/zero`, a socket),
/// for readers that would not stop on their own (e.g. the EXR decoder); a folder or a missing path is
/// left to the reader's own message.
pub fn check_regular(path: &Path) -> Result<()> {
    match std::fs::metadata(path) {
        Ok(m) if !m.is_file() && !m.is_dir() => Err(Error::Input(format!(
            "{} is not a regular file (a device, a pipe or a socket); give a file",
            path.display()
        ))),
        _ => Ok(()),
    }
}

/// The bytes of `path`, or the refusal `too_long` once more than `limit` have been read.
fn read_at_most(path: &Path, limit: u64, too_long: impl Fn() -> String) -> Result<Vec<u8>> {
    let file = std::fs::File::open(path).map_err(|e| Error::read_input(path, e))?;
    let mut bytes = Vec::new();
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::read_input(path, e))?;
    if bytes.len() as u64 > limit {
        return Err(Error::Input(format!("{}: {}", path.display(), too_long())));
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A device that never ends is refused by its first bytes (npy) or after the text limit, in
    /// bounded memory.
    #[cfg(target_os = "linux")]
    #[test]
    fn endless_inputs_are_refused_not_read_whole() {
        let zero = Path::new("/dev/zero");
        let file = std::fs::File::open(zero).unwrap();
        let why = read_npy_bytes(file, zero, 1 << 30).unwrap().unwrap_err();
        assert_eq!(why, "no npy magic \\x93NUMPY at the start");
        let e = read_text(zero, "target file").unwrap_err();
        assert!(e.to_string().contains("more than 4 MiB"), "{e}");
        assert_eq!(e.exit_code(), 2);
        let e = check_regular(zero).unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");
        assert_eq!(e.exit_code(), 2);
    }

    #[test]
    fn files_within_their_limits_are_read() {
        let dir = tempfile::tempdir().unwrap();
        let text = dir.path().join("t.toml");
        std::fs::write(&text, "kind = \"blue-noise\"\n").unwrap();
        assert_eq!(
            read_text(&text, "target file").unwrap(),
            "kind = \"blue-noise\"\n"
        );
        std::fs::write(&text, [0xff, 0xfe]).unwrap();
        let e = read_text(&text, "target file").unwrap_err();
        assert!(e.to_string().contains("UTF-8"), "{e}");
        let npy = dir.path().join("a.npy");
        let read = |contents: &[u8], limit: u64| {
            std::fs::write(&npy, contents).unwrap();
            read_npy_bytes(std::fs::File::open(&npy).unwrap(), &npy, limit).unwrap()
        };
        assert_eq!(read(b"\x93NUMPY rest", 100).unwrap(), b"\x93NUMPY rest");
        assert_eq!(
            read(b"\x93NUMPY rest", 8).unwrap_err(),
            "more than 8 bytes, larger than any array it may hold"
        );
        assert_eq!(read(b"", 100).unwrap_err(), "the file is empty");
        assert_eq!(
            read(b"\x93NU", 100).unwrap_err(),
            "no npy magic \\x93NUMPY at the start"
        );
        check_regular(&npy).unwrap();
        check_regular(dir.path()).unwrap();
    }
}
