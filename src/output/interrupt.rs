//! Temporary files and folders of this run that an interrupt (Ctrl-C, SIGTERM, SIGHUP) removes: an
//! atomic write stages its output beside the final path, and a run stopped while it writes would
//! otherwise leave the hidden `.anisospec-*` entry behind (173 MB for a 60-million-point text file).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Duration;

/// The exit status of a run stopped by an interrupt: `128 + SIGINT`, as a shell reports one.
pub const INTERRUPTED: i32 = 130;

/// This run's temporary files and folders still in place, in the order they were made.
static TEMPORARY: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Set once an interrupt has come: no temporary is made from then on.
static STOPPING: AtomicBool = AtomicBool::new(false);

/// Temporaries being made and not yet registered ([`create`]): an interrupt waits for them.
static PENDING: AtomicUsize = AtomicUsize::new(0);

/// Removal passes an interrupt makes at most, [`PASS_PAUSE`] apart, until one finds nothing left: a
/// thread still writing into a staging folder can refill it between passes (until it makes its
/// next temporary, which stops it).
const PASSES: usize = 100;

/// The pause between two removal passes.
const PASS_PAUSE: Duration = Duration::from_millis(10);

/// A temporary file or folder registered for removal on an interrupt while this guard lives; it
/// leaves the register when dropped (its owner has by then moved or removed it).
#[derive(Debug)]
pub struct Temporary(PathBuf);

/// Makes a temporary file or folder with `make` (and any folders it needs first) and registers the
/// path `path_of` gives, as one step that an interrupt cannot split: an interrupt before it means
/// nothing is made, one during it waits for the registration and then removes the temporary. After
/// an interrupt the calling thread stops for good (the process is about to exit).
pub fn create<T, E>(
    make: impl FnOnce() -> Result<T, E>,
    path_of: impl Fn(&T) -> &Path,
) -> Result<(T, Temporary), E> {
    PENDING.fetch_add(1, Ordering::SeqCst);
    if STOPPING.load(Ordering::SeqCst) {
        PENDING.fetch_sub(1, Ordering::SeqCst);
        stop_here();
    }
    let made = make().map(|t| {
        let path = path_of(&t).to_path_buf();
        lock().push(path.clone());
        (t, Temporary(path))
    });
    PENDING.fetch_sub(1, Ordering::SeqCst);
    if STOPPING.load(Ordering::SeqCst) {
        if let Ok((_, Temporary(path))) = &made {
            remove(std::slice::from_ref(path));
        }
        stop_here();
    }
    made
}

/// Stops the calling thread for good when an interrupt has come: an error of a run whose files the
/// interrupt is removing (a write into a staging folder already gone) is the interrupt's doing, and
/// the handler's exit, with [`INTERRUPTED`], is the one to report it.
pub fn yield_to_interrupt() {
    if STOPPING.load(Ordering::SeqCst) {
        stop_here();
    }
}

/// Parks the calling thread until the process exits.
fn stop_here() -> ! {
    loop {
        std::thread::park();
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
        STOPPING.store(true, Ordering::SeqCst);
        let mut removed = 0;
        for _ in 0..PASSES {
            // A temporary being made is registered (or given up) before long.
            while PENDING.load(Ordering::SeqCst) > 0 {
                std::thread::sleep(Duration::from_millis(1));
            }
            let registered = lock().clone();
            removed += remove(&registered);
            if registered
                .iter()
                .all(|p| std::fs::symlink_metadata(p).is_err())
            {
                break;
            }
            std::thread::sleep(PASS_PAUSE);
        }
        if removed > 0 {
            crate::eprintln_best_effort!("\ninterrupted: removed {removed} unfinished output(s)");
        } else {
            crate::eprintln_best_effort!("\ninterrupted");
        }
        std::process::exit(INTERRUPTED);
    });
    if let Err(e) = installed {
        crate::eprintln_best_effort!("warning: cannot watch for Ctrl-C ({e}); an interrupted write may leave a .anisospec-* file behind");
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
        let register = |path: &PathBuf| {
            create(|| Ok::<_, ()>(path.clone()), |p| p.as_path())
                .unwrap()
                .1
        };
        let guards = [register(&file), register(&folder)];
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
