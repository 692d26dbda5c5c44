//! Temporary files and folders of this run that an interrupt (Ctrl-C, SIGTERM, SIGHUP) removes: an
//! atomic write stages its output beside the final path, and a run stopped while it writes would
//! otherwise leave the hidden `.anisospec-*` entry behind (173 MB for a 60-million-point text file).

use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The exit status of a run stopped by an interrupt: `128 + SIGINT`, as a shell reports one.
pub const INTERRUPTED: i32 = 130;

/// This run's temporary files and folders still in place, in the order they were made.
static TEMPORARY: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// A temporary file or folder registered for removal on an interrupt while this guard lives; it
/// leaves the register when dropped (its owner has by then moved or removed it).
#[derive(Debug)]
pub struct Temporary(PathBuf);

impl Temporary {
    /// Registers `path`.
    pub fn new(path: &Path) -> Self {
        lock().push(path.to_path_buf());
        Temporary(path.to_path_buf())
    }
}

impl Drop for Temporary {
    fn drop(&mut self) {
        let mut registered = lock();
        if let Some(i) = registered.iter().rposition(|p| p == &self.0) {
            registered.remove(i);
        }
    }
}

fn lock() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    // A panic while the lock was held leaves the list itself intact.
    TEMPORARY.lock().unwrap_or_else(|e| e.into_inner())
}

/// Removes `paths` (files, and folders with what they hold; links are removed, never followed) and
/// returns how many were removed; one already gone is skipped.
fn remove(paths: &[PathBuf]) -> usize {
    paths
        .iter()
        .filter(|p| match std::fs::symlink_metadata(p) {
            Ok(m) if m.is_dir() => std::fs::remove_dir_all(p).is_ok(),
            Ok(_) => std::fs::remove_file(p).is_ok(),
            Err(_) => false,
        })
        .count()
}

/// Installs the handler: on an interrupt, remove this run's temporaries, say so, and exit with
/// [`INTERRUPTED`]. Outputs already in place stay; a report folder being moved into place may hold
/// new files beside old ones, which its manifest lets the next run replace.
pub fn remove_temporaries_on_interrupt() {
    let installed = ctrlc::set_handler(|| {
        // Held until the process exits: no new temporary appears meanwhile.
        let registered = lock();
        let removed = remove(&registered);
        if removed > 0 {
            eprintln!("\ninterrupted: removed {removed} unfinished output(s)");
        } else {
            eprintln!("\ninterrupted");
        }
        std::process::exit(INTERRUPTED);
    });
    if let Err(e) = installed {
        eprintln!("warning: cannot watch for Ctrl-C ({e}); an interrupted write may leave a .anisospec-* file behind");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A registered file and folder (with a file inside) are listed while their guards live, and
    /// removal takes both; a guard dropped afterwards leaves the register without a trace. Other
    /// tests' temporaries are never removed here: [`remove`] gets only this test's paths.
    #[test]
    fn registered_temporaries_are_removed() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join(".anisospec-file");
        let folder = dir.path().join(".anisospec-folder");
        std::fs::write(&file, "partial").unwrap();
        std::fs::create_dir(&folder).unwrap();
        std::fs::write(folder.join("staged.png"), "partial").unwrap();
        let guards = [Temporary::new(&file), Temporary::new(&folder)];
        assert!(lock().contains(&file) && lock().contains(&folder));
        assert_eq!(remove(&[file.clone(), folder.clone()]), 2);
        assert!(!file.exists() && !folder.exists());
        assert_eq!(
            remove(std::slice::from_ref(&file)),
            0,
            "a path already gone is skipped"
        );
        drop(guards);
        assert!(!lock().contains(&file) && !lock().contains(&folder));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
