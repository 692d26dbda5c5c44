//! Writing results: every file is written to a temporary sibling and renamed into place (DESIGN §7),
//! so a failed run leaves no half-written file. A command with several outputs writes them as a group
//! ([`write_group`]), and a report or gallery as a whole folder ([`write_folder`]): a failure while
//! writing leaves none of the new files.

pub mod image;
pub mod interrupt;
pub mod oracle_map;
pub mod plot;
pub mod sheet;

use crate::error::{Error, Result};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// `eprintln!` that cannot panic: a line for standard error (a note, a timing, a warning, the error
/// message itself) that cannot be written there (stderr on a full disk, a closed stream) is dropped,
/// and the run goes on to its own exit status, since its messages are no part of its results.
#[macro_export]
macro_rules! eprintln_best_effort {
    ($($arg:tt)*) => {
        $crate::output::write_stderr_line(format_args!($($arg)*))
    };
}

/// Writes `text` and a newline to standard error, ignoring a failure: see
/// [`crate::eprintln_best_effort!`].
pub fn write_stderr_line(text: std::fmt::Arguments) {
    // A failed write is ignored on purpose: there is nowhere left to report it.
    let _ = writeln!(std::io::stderr().lock(), "{text}");
}

/// FNV-1a, 64 bits, of `bytes`: a stable hash for cache file names and header guards (std's hasher
/// is not stable across releases or platforms).
pub fn stable_hash(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The folder a file `path` goes in: its parent, or `.` for a bare file name.
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Writes `path` atomically: `fill` writes into a temporary file in the same folder, which is renamed
/// onto `path` only if `fill` succeeds; folders made for it go again (while empty) if it does not.
/// The file gets the permissions `File::create` would give it.
pub fn write_atomic<F>(path: &Path, fill: F) -> Result<()>
where
    F: FnOnce(&mut BufWriter<&mut std::fs::File>) -> std::io::Result<()>,
{
    let dir = folder_of(path);
    // Declared before the temporary file, so dropped after it: the folders it made go once empty.
    let mut made = NewFolders::default();
    let mut builder = tempfile::Builder::new();
    builder.prefix(".anisospec-");
    // A temporary file is created owner-only (0600); an output is an ordinary file, 0666 less the
    // umask, as `File::create` makes it (a report folder others can read).
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    // The folders too: one made inside a staging folder an interrupt is removing would stay.
    let (mut tmp, _registered) = interrupt::create(
        || {
            made.make(dir)?;
            builder
                .tempfile_in(dir)
                .map_err(|e| Error::io("create a file in", dir, os_error(&e)))
        },
        |t| t.path(),
    )?;
    {
        let mut w = BufWriter::new(tmp.as_file_mut());
        fill(&mut w)
            .and_then(|_| w.flush())
            .map_err(|e| Error::io("write", path, e))?;
    }
    // An interrupt that came while it was written removes it: the output does not appear after it.
    interrupt::yield_to_interrupt();
    tmp.persist(path)
        .map_err(|e| Error::io("write", path, e.error))?;
    made.keep();
    Ok(())
}

/// Writes several outputs of one command as a group, so that a failure while writing leaves none of
/// them (DESIGN §7): `write` is handed a map from each of `outputs` to a path in a temporary folder
/// beside it, and writes there. Only when it succeeds, and no folder stands where an output goes, are
/// the files it wrote moved into place; an error names the output, not its temporary path. The
/// outputs' folders are created first, as each single write would, and go again (while empty) if
/// the group is not written.
pub fn write_group<T>(
    outputs: &[&Path],
    write: impl FnOnce(&dyn Fn(&Path) -> PathBuf) -> Result<T>,
) -> Result<T> {
    // Declared before the temporary folders, so dropped after them: the folders made go once empty.
    let mut made = NewFolders::default();
    let mut folders: Vec<(PathBuf, Staging)> = Vec::new();
    let mut staged: Vec<(PathBuf, PathBuf)> = Vec::new();
    for out in outputs {
        let dir = folder_of(out).to_path_buf();
        let name = out
            .file_name()
            .ok_or_else(|| Error::Usage(format!("{}: give a file name", out.display())))?;
        staged.push((
            out.to_path_buf(),
            folder_for(&mut folders, &mut made, dir)?.join(name),
        ));
    }
    let staged_path = |out: &Path| -> PathBuf {
        staged
            .iter()
            .find(|(o, _)| o == out)
            .map(|(_, s)| s.clone())
            .unwrap_or_else(|| panic!("{} is not an output of this group", out.display()))
    };
    let value = write(&staged_path).map_err(|e| {
        folders
            .iter()
            .fold(e, |e, (dir, tmp)| e.with_path_replaced(tmp.path(), dir))
    })?;
    let written: Vec<&(PathBuf, PathBuf)> = staged.iter().filter(|(_, t)| t.exists()).collect();
    for (out, _) in &written {
        if out.is_dir() {
            return Err(folder_in_the_way(out));
        }
    }
    commit(&written)?;
    made.keep();
    Ok(value)
}

/// Moves each staged file `(output, staged)` onto its output, all or none. Each existing output is
/// first kept aside, as a hard link (a copy where links are refused) in a temporary folder beside it;
/// then each new file is renamed over its output, replacing it in one step. If a rename fails (an
/// output that cannot be replaced: immutable, or another user's in a sticky folder), the outputs
/// replaced so far get their kept files back and new ones are removed, and the error says that
/// nothing was written. Should putting one back fail too, the kept files stay in their folder and
/// the error names it.
fn commit(written: &[&(PathBuf, PathBuf)]) -> Result<()> {
    let mut asides: Vec<(PathBuf, Staging)> = Vec::new();
    let mut kept: Vec<Option<PathBuf>> = Vec::with_capacity(written.len());
    for (out, _) in written {
        if out.symlink_metadata().is_err() {
            kept.push(None);
            continue;
        }
        // An existing output's folder exists: nothing is made for the kept files but the temporary
        // folder, which goes with `asides`.
        let old = folder_for(
            &mut asides,
            &mut NewFolders::default(),
            folder_of(out).to_path_buf(),
        )?
        .join(out.file_name().expect("an output has a file name"));
        if std::fs::hard_link(out, &old).is_err() {
            std::fs::copy(out, &old).map_err(|e| Error::io("keep a copy of", out, e))?;
        }
        kept.push(Some(old));
    }
    for (i, (out, staged)) in written.iter().enumerate() {
        let Err(e) = move_file(staged, out) else {
            continue;
        };
        let mut restored = true;
        for ((placed, _), old) in written[..i].iter().zip(&kept) {
            restored &= match old {
                Some(old) => std::fs::rename(old, placed).is_ok(),
                None => std::fs::remove_file(placed).is_ok(),
            };
        }
        if !restored {
            let folders: Vec<String> = asides
                .into_iter()
                .map(|(_, tmp)| tmp.keep().display().to_string())
                .collect();
            return Err(Error::Numerical(format!(
                "{e}; the outputs written before it could not all be put back: the earlier files are kept in {}",
                folders.join(", ")
            )));
        }
        let Error::Io { source, .. } = e else {
            return Err(e);
        };
        let unchanged = "no output was written and the existing files are unchanged";
        // Refused by the file's or the folder's permissions: the user's to fix (exit 2), as a
        // folder that takes no new file is before the work; anything else is a failure of the run.
        return Err(if source.kind() == std::io::ErrorKind::PermissionDenied {
            Error::Usage(format!(
                "cannot write {}: {source}; {unchanged}; make the file replaceable (check its owner, the folder's sticky bit, chattr -i) or choose another output name",
                out.display()
            ))
        } else {
            Error::Io {
                context: format!("cannot write {} ({unchanged})", out.display()),
                source,
            }
        });
    }
    Ok(())
}

/// The file in a report folder that lists every file and subfolder the report wrote, one path per
/// line relative to the folder (`/`-separated, a folder ending in `/`), after a header line. The next
/// report written there removes the listed files it does not write again, and nothing else: notes, a
/// study's TOML or a target's image kept in the folder stay.
pub const MANIFEST: &str = "manifest.txt";

/// The first line of every [`MANIFEST`]: a `manifest.txt` without it is not this tool's.
const MANIFEST_HEADER: &str =
    "# Files written by anisospec; the next report in this folder removes those it does not write again.";

/// The main file every report of one kind writes, and the line it starts with: a folder whose file
/// of that name starts with that line holds an earlier report of that kind (a `report.md` of someone
/// else's does not).
#[derive(Clone, Copy, Debug)]
pub struct ReportMarker {
    /// File name, e.g. `report.md`.
    pub file: &'static str,
    /// Its first line, e.g. `# anisospec compare`.
    pub first_line: &'static str,
}

impl ReportMarker {
    /// Whether `dir` holds this marker: the file, starting with the line.
    fn is_in(&self, dir: &Path) -> bool {
        // The first line alone, read from at most 4 KiB (the file may be anything, even a device).
        let mut head = Vec::new();
        std::fs::File::open(dir.join(self.file))
            .and_then(|f| std::io::Read::read_to_end(&mut std::io::Read::take(f, 4096), &mut head))
            .is_ok()
            && String::from_utf8_lossy(&head).lines().next() == Some(self.first_line)
    }
}

/// Checks, before any work, that `dest` (given by `--out`) may take a report marked by `marker`: it is
/// missing, empty, or holds an earlier report (its marker, and a [`MANIFEST`] of this tool if any),
/// and it (or the nearest folder above it that exists) takes new files. A report folder holds one
/// report, so a folder of other files (sources, say) is refused with a usage
/// error naming it and the fix, and nothing in it is touched. Every caller of [`write_folder`] calls
/// this first, before the work that fills the report.
pub fn check_report_folder(dest: &Path, marker: ReportMarker) -> Result<()> {
    check_folder(dest, "--out", "report")?;
    // The folder, or the nearest one above it that exists, must take new files.
    if let Some(existing) = dest.ancestors().find(|a| a.is_dir()) {
        probe_folder(existing)?;
    }
    if !dest.is_dir() {
        return Ok(());
    }
    if marker.is_in(dest) {
        return read_manifest(dest).map(drop);
    }
    let entries = std::fs::read_dir(dest).map_err(|e| Error::io("read the folder", dest, e))?;
    let mut others = Vec::new();
    for entry in entries {
        let name = entry
            .map_err(|e| Error::io("read the folder", dest, e))?
            .file_name();
        if !is_staging(&name) {
            others.push(name.to_string_lossy().into_owned());
        }
    }
    if others.is_empty() {
        return Ok(());
    }
    others.sort();
    let shown = others
        .iter()
        .take(3)
        .cloned()
        .collect::<Vec<_>>()
        .join(", ");
    let more = if others.len() > 3 { ", ..." } else { "" };
    Err(Error::Usage(format!(
        "{} holds other files ({shown}{more}) and no {} of this tool, so it is not an earlier report; \
         give --out a new or empty folder, or the folder of an earlier report",
        dest.display(),
        marker.file
    )))
}

/// Whether `path` is a folder and not a link to one: pruning never reaches through a link into a
/// folder the report does not own.
fn is_real_folder(path: &Path) -> bool {
    std::fs::symlink_metadata(path).is_ok_and(|m| m.is_dir())
}

/// Whether a folder entry is a temporary file or folder of this crate (an atomic write in progress,
/// or one a killed run left behind).
fn is_staging(name: &std::ffi::OsStr) -> bool {
    name.to_string_lossy().starts_with(".anisospec-")
}

/// Writes a report folder as a whole (a compare report, a gallery): `write` fills a temporary folder
/// inside `dest`, and only when it succeeds, and no file of the new set clashes with a folder of the
/// old (or a folder with a file) or with a file that is not the earlier report's, are the files it
/// wrote moved into `dest`. The new report then replaces the old one: the files and subfolders the
/// earlier report's [`MANIFEST`] lists and the new report does not write go, so no stale plot of an
/// earlier study stays beside the new ones; nothing else in `dest` is touched (a file that appeared
/// during the run included), and links are removed, never followed. An earlier report from before the
/// manifest (its `marker` and no manifest) has its files replaced but none pruned. The caller checks
/// `dest` with [`check_report_folder`] before any work. On a failure before the move none of `dest`'s
/// files is touched, `dest` and the ancestors this call created go again (while empty), and an error
/// names the final path, not the temporary one. The manifest lists the earlier and the new files while they move, so
/// a failure while moving or pruning leaves new files beside old ones, all of which the next report
/// can replace.
pub fn write_folder<T>(
    dest: &Path,
    marker: ReportMarker,
    write: impl FnOnce(&Path) -> Result<T>,
) -> Result<T> {
    let mut made = NewFolders::default();
    let result = staging_folder(dest, &mut made).and_then(|staging| {
        let value =
            write(staging.path()).map_err(|e| e.with_path_replaced(staging.path(), dest))?;
        let (earlier, replaceable) = replaceable_by_report(dest, marker)?;
        let incoming = check_tree(staging.path(), dest, replaceable)?;
        write_manifest(dest, earlier.iter().chain(&incoming))?;
        let written = move_tree(staging.path(), dest)?;
        prune_stale(dest, &earlier, &written)?;
        write_manifest(dest, written.iter())?;
        Ok(value)
    });
    if result.is_ok() {
        made.keep();
        warn_left_staging(dest);
    }
    result
}

/// Warns of temporary folders of this crate left in `dest` (this run's own is gone by now): a run
/// that was killed leaves one behind. They are named, not removed, since another run may be
/// writing into one of them right now.
fn warn_left_staging(dest: &Path) {
    for folder in left_staging(dest) {
        crate::eprintln_best_effort!(
            "warning: {} is a temporary folder of a run that stopped before it finished (or of one still running); remove it once no other run writes to {}",
            folder.display(),
            dest.display()
        );
    }
}

/// The temporary folders of this crate in `dest`, sorted.
fn left_staging(dest: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dest) else {
        return Vec::new();
    };
    let mut left: Vec<PathBuf> = entries
        .filter_map(|e| e.ok())
        .filter(|e| is_staging(&e.file_name()) && is_real_folder(&e.path()))
        .map(|e| e.path())
        .collect();
    left.sort();
    left
}

/// The folders a write made for its outputs: unless [`NewFolders::keep`] is called, they go again
/// when this is dropped (innermost first, and only while empty), so a write that fails leaves no
/// empty folder behind.
#[derive(Default)]
pub(crate) struct NewFolders(Vec<PathBuf>);

impl NewFolders {
    /// Makes `dest` and its missing ancestors, outermost first, and lists the folders this call
    /// made: one that exists already, or that another process makes first, is not listed.
    pub(crate) fn make(&mut self, dest: &Path) -> Result<()> {
        let mut chain: Vec<&Path> = dest
            .ancestors()
            .take_while(|a| !a.as_os_str().is_empty())
            .collect();
        chain.reverse();
        for folder in chain {
            match std::fs::create_dir(folder) {
                Ok(()) => self.0.push(folder.to_path_buf()),
                Err(_) if folder.is_dir() => {}
                Err(e) => return Err(Error::io("create the folder", folder, e)),
            }
        }
        Ok(())
    }

    /// The outputs are in place: the folders stay.
    fn keep(mut self) {
        self.0.clear();
    }
}

impl Drop for NewFolders {
    fn drop(&mut self) {
        // A failure to remove one (not empty, or gone) changes nothing.
        for folder in self.0.iter().rev() {
            let _ = std::fs::remove_dir(folder);
        }
    }
}

/// The temporary folder of `folders` inside `dir`, made by [`staging_folder`] the first time `dir`
/// is asked for.
fn folder_for<'a>(
    folders: &'a mut Vec<(PathBuf, Staging)>,
    made: &mut NewFolders,
    dir: PathBuf,
) -> Result<&'a Path> {
    let slot = match folders.iter().position(|(d, _)| *d == dir) {
        Some(i) => i,
        None => {
            let tmp = staging_folder(&dir, made)?;
            folders.push((dir, tmp));
            folders.len() - 1
        }
    };
    Ok(folders[slot].1.path())
}

/// A temporary folder inside `dir` (created if missing, and listed in `made`), on the file system of
/// the outputs.
fn staging_folder(dir: &Path, made: &mut NewFolders) -> Result<Staging> {
    let (folder, registered) = interrupt::create(
        || {
            made.make(dir)?;
            tempfile::Builder::new()
                .prefix(".anisospec-")
                .tempdir_in(dir)
                .map_err(|e| Error::io("create a folder in", dir, os_error(&e)))
        },
        |folder| folder.path(),
    )?;
    Ok(Staging {
        folder,
        _registered: registered,
    })
}

/// A temporary folder of this crate, removed when dropped (as `tempfile::TempDir`) and, while it
/// lives, on an interrupt ([`interrupt`]).
struct Staging {
    folder: tempfile::TempDir,
    // Dropped after the folder: the register never lists a folder already gone.
    _registered: interrupt::Temporary,
}

impl Staging {
    fn path(&self) -> &Path {
        self.folder.path()
    }

    /// Keeps the folder (no longer removed, on drop or on an interrupt) and returns its path.
    fn keep(self) -> PathBuf {
        self.folder.keep()
    }
}

fn folder_in_the_way(out: &Path) -> Error {
    Error::Usage(format!(
        "cannot write {}: a folder stands where the file goes; move it away or choose another output",
        out.display()
    ))
}

/// Calls `visit(path, target, is_folder)` for every entry under `from`, with `target` its place
/// under `to`, a folder before its contents.
fn walk_tree(
    from: &Path,
    to: &Path,
    visit: &mut dyn FnMut(&Path, &Path, bool) -> Result<()>,
) -> Result<()> {
    let entries = std::fs::read_dir(from).map_err(|e| Error::io("read the folder", from, e))?;
    for entry in entries {
        let entry = entry.map_err(|e| Error::io("read the folder", from, e))?;
        let (path, target) = (entry.path(), to.join(entry.file_name()));
        let is_folder = path.is_dir();
        visit(&path, &target, is_folder)?;
        if is_folder {
            walk_tree(&path, &target, visit)?;
        }
    }
    Ok(())
}

/// Checks, before anything moves, that every file under `from` can go to the same place under `to`:
/// no folder where a file goes, no file where a folder goes, and no existing file where a file goes
/// unless `replaceable` (the earlier report's, in the report's own folders). Returns the places under
/// `to`, files and folders.
fn check_tree(from: &Path, to: &Path, replaceable: impl Fn(&Path) -> bool) -> Result<Vec<PathBuf>> {
    let mut targets = Vec::new();
    walk_tree(from, to, &mut |_, target, is_folder| {
        check_place(target, is_folder, &replaceable)?;
        targets.push(target.to_path_buf());
        Ok(())
    })?;
    Ok(targets)
}

/// Checks that a report can put a file (or, with `is_folder`, a folder) at `target`: no folder
/// where a file goes, no file where a folder goes, and no existing file unless `replaceable`.
fn check_place(target: &Path, is_folder: bool, replaceable: &impl Fn(&Path) -> bool) -> Result<()> {
    if is_folder && target.exists() && !target.is_dir() {
        return Err(Error::Usage(format!(
            "cannot write into {}: a file stands where the folder goes; move it away or choose another output folder",
            target.display()
        )));
    }
    if !is_folder && target.is_dir() {
        return Err(folder_in_the_way(target));
    }
    if !is_folder && target.symlink_metadata().is_ok() && !replaceable(target) {
        return Err(Error::Usage(format!(
            "cannot write {}: a file of that name is there and the earlier report did not write it \
             (it is not in {MANIFEST}, or lies in a linked folder); move it away and run again",
            target.display()
        )));
    }
    Ok(())
}

/// The files of the earlier report in `dest` (its [`MANIFEST`]) and which existing files a new
/// report may replace: those the manifest lists, or, for a report from before the manifest (its
/// `marker` and no manifest), every file; in either case only in real folders, not links.
fn replaceable_by_report(
    dest: &Path,
    marker: ReportMarker,
) -> Result<(Vec<PathBuf>, impl Fn(&Path) -> bool + '_)> {
    let earlier = read_manifest(dest)?;
    let before_manifest = earlier.is_none() && marker.is_in(dest);
    let earlier = earlier.unwrap_or_default();
    let listed = earlier.clone();
    Ok((earlier, move |target: &Path| {
        in_real_folders(dest, target) && (before_manifest || listed.iter().any(|e| e == target))
    }))
}

/// Checks, before any work, that a report can put its `places` (paths relative to `dest`, with
/// whether each is a folder) in `dest`, by the rule [`write_folder`] applies when it moves the
/// report in: so a file of the user's where the report puts one stops the run before its work,
/// not after. Names the report may or may not write (a plot it leaves out) may be listed: a
/// superset is checked.
pub fn check_report_places(
    dest: &Path,
    marker: ReportMarker,
    places: &[(PathBuf, bool)],
) -> Result<()> {
    if !dest.is_dir() {
        return Ok(());
    }
    let (_, replaceable) = replaceable_by_report(dest, marker)?;
    for (place, is_folder) in places {
        check_place(&dest.join(place), *is_folder, &replaceable)?;
    }
    Ok(())
}

/// Moves every file under `from` to the same place under `to`, creating subfolders as needed, and
/// returns the paths it wrote under `to`, files and folders.
fn move_tree(from: &Path, to: &Path) -> Result<Vec<PathBuf>> {
    let mut written = Vec::new();
    walk_tree(from, to, &mut |path, target, is_folder| {
        if is_folder {
            std::fs::create_dir_all(target)
                .map_err(|e| Error::io("create the folder", target, e))?;
        } else {
            move_file(path, target)?;
        }
        written.push(target.to_path_buf());
        Ok(())
    })?;
    Ok(written)
}

/// The paths under `dest` that the [`MANIFEST`] of an earlier report lists, files and folders, in
/// its order; `None` when there is no manifest. A listed path that leaves `dest` (absolute, or
/// through `..`) is never returned. A `manifest.txt` that is not this tool's (another first line, not
/// text) or cannot be read (a folder, a link loop) is refused with a usage error naming the fix.
fn read_manifest(dest: &Path) -> Result<Option<Vec<PathBuf>>> {
    let path = dest.join(MANIFEST);
    let foreign = |why: &str| {
        Error::Usage(format!(
            "{} {why}, and a report writes its list of files there; move it away",
            path.display()
        ))
    };
    let text = match crate::input::read_text(&path, "list of a report's files") {
        Ok(text) => text,
        Err(_) if std::fs::symlink_metadata(&path).is_err() => return Ok(None),
        Err(Error::Input(m)) if m.contains("UTF-8") => {
            return Err(foreign("was not written by anisospec (it is not text)"))
        }
        Err(e) => return Err(foreign(&format!("cannot be read ({e})"))),
    };
    let mut lines = text.lines();
    if lines.next() != Some(MANIFEST_HEADER) {
        return Err(foreign("was not written by anisospec"));
    }
    Ok(Some(
        lines
            .map(|line| Path::new(line.trim_end_matches('/')))
            .filter(|rel| {
                !rel.as_os_str().is_empty()
                    && rel
                        .components()
                        .all(|c| matches!(c, std::path::Component::Normal(_)))
            })
            .map(|rel| dest.join(rel))
            .collect(),
    ))
}

/// Writes the [`MANIFEST`] listing `paths` (files and folders under `dest`), sorted and each once (the
/// same report gives the same bytes).
fn write_manifest<'a>(dest: &Path, paths: impl Iterator<Item = &'a PathBuf>) -> Result<()> {
    let mut lines: Vec<String> = paths
        .filter_map(|path| {
            let rel = path.strip_prefix(dest).ok()?;
            if rel == Path::new(MANIFEST) {
                return None;
            }
            let parts: Vec<_> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy())
                .collect();
            let slash = if is_real_folder(path) { "/" } else { "" };
            Some(format!("{}{slash}", parts.join("/")))
        })
        .collect();
    lines.sort();
    lines.dedup();
    write_atomic(&dest.join(MANIFEST), |w| {
        writeln!(w, "{MANIFEST_HEADER}")?;
        for line in &lines {
            writeln!(w, "{line}")?;
        }
        Ok(())
    })
}

/// Whether every folder between `dest` and `path` (under it) is a real folder, not a link: the
/// report owns only what lies in its own folders.
fn in_real_folders(dest: &Path, path: &Path) -> bool {
    path.ancestors()
        .skip(1)
        .take_while(|a| *a != dest)
        .all(is_real_folder)
}

/// Removes the stale outputs of an earlier report: each path in `earlier` (its manifest) that the new
/// report did not write. A file goes only when it and every folder between it and `dest` are real
/// (a link is removed, never followed); a folder goes only when it is then empty, deepest first.
fn prune_stale(dest: &Path, earlier: &[PathBuf], written: &[PathBuf]) -> Result<()> {
    let stale = earlier
        .iter()
        .filter(|p| !written.contains(p) && in_real_folders(dest, p));
    let mut folders = Vec::new();
    for path in stale {
        if is_real_folder(path) {
            folders.push(path);
        } else if path.symlink_metadata().is_ok() {
            std::fs::remove_file(path)
                .map_err(|e| Error::io("remove the stale output", path, e))?;
        }
    }
    folders.sort_by_key(|p| std::cmp::Reverse(p.components().count()));
    for folder in folders {
        // A folder that still holds files of someone else's stays.
        let _ = std::fs::remove_dir(folder);
    }
    Ok(())
}

/// Renames `from` onto `to`; where `to` lies on another file system (a linked subfolder), copies it
/// beside `to` first, then renames the copy into place.
fn move_file(from: &Path, to: &Path) -> Result<()> {
    match std::fs::rename(from, to) {
        Err(e) if e.kind() == std::io::ErrorKind::CrossesDevices => {
            let dir = folder_of(to);
            let copy = tempfile::Builder::new()
                .prefix(".anisospec-")
                .tempfile_in(dir)
                .map_err(|e| Error::io("create a file in", dir, os_error(&e)))?;
            std::fs::copy(from, copy.path()).map_err(|e| Error::io("write", to, e))?;
            copy.persist(to)
                .map_err(|e| Error::io("write", to, e.error))?;
            Ok(())
        }
        other => other.map_err(|e| Error::io("write", to, e)),
    }
}

/// Writes an `f64` array of the given shape (C order) as npy.
pub fn write_npy(path: &Path, shape: &[usize], data: &[f64]) -> Result<()> {
    debug_assert_eq!(shape.iter().product::<usize>(), data.len());
    let shape: Vec<u64> = shape.iter().map(|&s| s as u64).collect();
    write_atomic(path, |w| {
        use npyz::WriterBuilder;
        let mut npy = npyz::WriteOptions::new()
            .default_dtype()
            .shape(&shape)
            .writer(w)
            .begin_nd()?;
        npy.extend(data.iter().copied())?;
        npy.finish()
    })
}

/// A number for a CSV cell: the shortest text that reads back to the same bits, in scientific
/// notation below 1e-4 and from 1e16 in size (fixed notation writes 1e-300 as 300 digits and an
/// MSE of 3.3e-7 as 0.00000033...).
pub fn csv_number(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-4..1e16).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// Longest file or folder name, in bytes, that Linux file systems take (ext4, XFS, btrfs). APFS and
/// NTFS count 255 characters instead, so there a longer name of non-ASCII characters is refused too.
const MAX_NAME_BYTES: usize = 255;

/// Checks, before any work, that a command's output files can be written without harm: no output is
/// one of the `inputs` (point files, tables, targets, scenes: outputs never clobber inputs), no two
/// outputs are the same file, no output is a folder, and each output's folder exists (no file stands
/// where it must go, and a missing one is not made: a typo in a path should not grow folders) and
/// takes a new file (probed with a temporary file, removed at once), and no name in the path is longer
/// than file systems take. A usage error names the clash, or the folder and the operating system's
/// reason, and the fix.
pub fn check_outputs(outputs: &[&Path], inputs: &[PathBuf]) -> Result<()> {
    let mut probed: Vec<&Path> = Vec::new();
    for (i, out) in outputs.iter().enumerate() {
        check_file_name(out, &[])?;
        if let Some(input) = inputs.iter().find(|input| same_file(out, input)) {
            return Err(Error::Usage(format!(
                "the output {} is the input file {}; choose another output name",
                out.display(),
                input.display()
            )));
        }
        if let Some(other) = outputs[..i].iter().find(|o| same_file(out, o)) {
            return Err(Error::Usage(format!(
                "{} and {} name the same output file; give each output its own name",
                other.display(),
                out.display()
            )));
        }
        if out.is_dir() {
            return Err(Error::Usage(format!(
                "the output {} is a folder; give a file name",
                out.display()
            )));
        }
        // Most file systems refuse a longer name, and only at the end of the work.
        if let Some(long) = out
            .components()
            .map(|c| c.as_os_str().len())
            .find(|&len| len > MAX_NAME_BYTES)
        {
            return Err(Error::Usage(format!(
                "the output {} has a name of {long} bytes, more than the {MAX_NAME_BYTES} a file system allows; choose a shorter name",
                out.display()
            )));
        }
        if let Some(blocker) = out.parent().and_then(file_in_the_way) {
            return Err(Error::Usage(format!(
                "cannot write {}: {} is {}, not a folder; choose another output path",
                out.display(),
                blocker.display(),
                what_is(blocker)
            )));
        }
        let dir = folder_of(out);
        if !dir.is_dir() {
            return Err(Error::Usage(format!(
                "cannot write {}: folder {} does not exist; create it first or choose another output path",
                out.display(),
                dir.display()
            )));
        }
        if !probed.contains(&dir) {
            probe_folder(dir)?;
            probed.push(dir);
        }
    }
    Ok(())
}

/// Creates and at once removes a temporary file in `dir`, so that a folder that takes no new file
/// (read-only, forbidden, a virtual file system) is refused before any work, naming the folder.
fn probe_folder(dir: &Path) -> Result<()> {
    tempfile::Builder::new()
        .prefix(".anisospec-")
        .tempfile_in(dir)
        .map(drop)
        .map_err(|e| {
            Error::Usage(format!(
                "cannot write to {}: {}; choose a writable folder",
                dir.display(),
                os_error(&e)
            ))
        })
}

/// The operating system's own error, without the temporary path the `tempfile` crate adds to its
/// message (`... at path "dir/.anisospec-XXXX"`): a message names the output or its folder, never a
/// file the user did not ask for.
fn os_error(e: &std::io::Error) -> std::io::Error {
    if let Some(code) = e.raw_os_error() {
        return std::io::Error::from_raw_os_error(code);
    }
    let text = e.to_string();
    let text = text.split(" at path ").next().unwrap_or_default();
    std::io::Error::new(e.kind(), text.to_string())
}

/// Whether `path` names no file it could be written to: a folder (`out/`, `out/.`, `..`, `/`: a
/// trailing separator would be dropped by the path's file name, and the run would fail only when it
/// writes), an extension alone (`out/.npy`, which would become a hidden file), or `-`, which
/// commands elsewhere take for standard output, where nothing here writes.
pub fn names_no_file(path: &Path) -> bool {
    if path.as_os_str() == "-" {
        return true;
    }
    let text = path.as_os_str().to_string_lossy();
    let last = text
        .rsplit(std::path::is_separator)
        .next()
        .unwrap_or_default();
    let bare_extension = last.strip_prefix('.').is_some_and(|rest| {
        ["npy", "exr", "png", "txt", "csv", "json"]
            .iter()
            .any(|e| e.eq_ignore_ascii_case(rest))
    });
    path.file_name().is_none() || matches!(last, "" | "." | "..") || bare_extension
}

/// Refuses an output path that names no file ([`names_no_file`]), suggesting a name with the
/// extension it was given (`y.png/`: `out/name.png`) when it is one of `writes` (the extensions the
/// command writes; empty: any), else the first of `writes` (or `.npy`).
pub fn check_file_name(out: &Path, writes: &[&str]) -> Result<()> {
    if !names_no_file(out) {
        return Ok(());
    }
    if out.as_os_str() == "-" {
        return Err(Error::Usage(format!(
            "the output - would be standard output, which no command writes to; give a file path such as out/name.{}",
            writes.first().unwrap_or(&"npy")
        )));
    }
    let text = out.as_os_str().to_string_lossy();
    let last = text
        .trim_end_matches(std::path::is_separator)
        .rsplit(std::path::is_separator)
        .next()
        .unwrap_or_default();
    let ext = last
        .rfind('.')
        .map(|i| &last[i + 1..])
        .filter(|e| !e.is_empty() && e.chars().all(|c| c.is_ascii_alphanumeric()))
        .filter(|e| writes.is_empty() || writes.iter().any(|w| w.eq_ignore_ascii_case(e)))
        .unwrap_or(writes.first().unwrap_or(&"npy"));
    Err(Error::Usage(format!(
        "the output {} has no usable file name (it ends in a folder, or is an extension alone); give a file path such as out/name.{ext}",
        out.display()
    )))
}

/// Refuses a folder `dir` (given by `flag`, holding the `what`) that is, or lies under, an existing
/// file, before any work: the run could not write to it. The message's fix is to give `flag` a
/// folder path.
pub fn check_folder(dir: &Path, flag: &str, what: &str) -> Result<()> {
    check_folder_fixed_by(dir, flag, what, &format!("give {flag} a folder path"))
}

/// [`check_folder`] for a folder chosen by something other than a flag (`name`, e.g. "the cache
/// folder"), with the message's `fix` given by the caller.
pub fn check_folder_fixed_by(dir: &Path, name: &str, what: &str, fix: &str) -> Result<()> {
    match file_in_the_way(dir) {
        Some(file) => {
            let place = if file == dir {
                format!("{} is {}", dir.display(), what_is(file))
            } else {
                format!(
                    "{} lies under {}, {}",
                    dir.display(),
                    file.display(),
                    what_is(file)
                )
            };
            Err(Error::Usage(format!(
                "{name} {place}, not a folder, so no {what} folder can be written there; {fix}"
            )))
        }
        None => Ok(()),
    }
}

/// What a path that stands in the way of a folder is: a file, or a link that leads nowhere.
fn what_is(path: &Path) -> &'static str {
    let link = path
        .symlink_metadata()
        .is_ok_and(|m| m.file_type().is_symlink());
    if link && !path.exists() {
        "a link to nothing (a dangling symbolic link)"
    } else {
        "a file"
    }
}

/// The existing file, if any, that stands where the folder `dir` (or one of its ancestors) must go: the
/// nearest ancestor that exists, when it is not a folder (a file, or a link that leads to no folder).
pub fn file_in_the_way(dir: &Path) -> Option<&Path> {
    dir.ancestors()
        .find(|a| a.symlink_metadata().is_ok())
        .filter(|a| !a.is_dir())
}

/// The absolute path of `path`, whether it exists or not: links and `..` resolved in the part that
/// exists, `.` and `..` taken literally in the rest.
pub fn resolved(path: &Path) -> Result<PathBuf> {
    let absolute = std::path::absolute(path).map_err(|e| Error::io("resolve", path, e))?;
    let existing = absolute
        .ancestors()
        .find(|a| a.exists())
        .unwrap_or(Path::new("/"));
    let mut out = existing
        .canonicalize()
        .map_err(|e| Error::io("resolve", existing, e))?;
    let rest = absolute.strip_prefix(existing).unwrap_or(Path::new(""));
    for part in rest.components() {
        match part {
            std::path::Component::ParentDir => {
                out.pop();
            }
            std::path::Component::Normal(name) => out.push(name),
            _ => {}
        }
    }
    Ok(out)
}

/// Whether two paths name the same file: the same absolute path, or the same file once links are
/// resolved (when both exist).
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => matches!(
            (std::path::absolute(a), std::path::absolute(b)),
            (Ok(a), Ok(b)) if a == b
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_numbers_read_back_exactly_and_stay_short() {
        for (v, text) in [
            (1e-300, "1e-300"),
            (3.3e-7, "3.3e-7"),
            (0.5, "0.5"),
            (0.0, "0"),
            (1e-4, "0.0001"),
            (12345.5, "12345.5"),
            (1e16, "1e16"),
            (-2.5e-9, "-2.5e-9"),
        ] {
            assert_eq!(csv_number(v), text);
            assert_eq!(text.parse::<f64>().unwrap().to_bits(), v.to_bits());
        }
        for v in [std::f64::consts::PI * 1e-200, 1.0 / 3.0, 0.1 + 0.2, 7e300] {
            assert_eq!(csv_number(v).parse::<f64>().unwrap().to_bits(), v.to_bits());
        }
    }

    /// Test reports: a main file `a.md` or `report.md` starting with `# a report`.
    const MARK: ReportMarker = ReportMarker {
        file: "a.md",
        first_line: "# a report",
    };
    const REPORT: ReportMarker = ReportMarker {
        file: "report.md",
        first_line: "# a report",
    };

    fn leftovers(dir: &Path) -> Vec<String> {
        std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with(".anisospec-"))
            .collect()
    }

    fn read_to(dir: &Path, file: &str) -> String {
        std::fs::read_to_string(dir.join(file)).unwrap()
    }

    /// A group whose second write fails leaves neither output, keeps an existing output's old bytes,
    /// and leaves no temporary folder nor the folder it made; a group that succeeds writes both, in
    /// two folders.
    #[test]
    fn a_failed_group_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.csv"), dir.path().join("sub/b.txt"));
        std::fs::write(&a, "old").unwrap();
        let failed = write_group(&[&a, &b], |staged| {
            write_atomic(&staged(&a), |w| writeln!(w, "new"))?;
            Err::<(), _>(Error::Numerical("the second output failed".into()))
        });
        assert!(failed.is_err());
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "old");
        assert!(!b.exists());
        assert!(leftovers(dir.path()).is_empty());
        assert!(
            !dir.path().join("sub").exists(),
            "the folder made for b goes"
        );

        write_group(&[&a, &b], |staged| {
            write_atomic(&staged(&a), |w| writeln!(w, "new a"))?;
            write_atomic(&staged(&b), |w| writeln!(w, "new b"))
        })
        .unwrap();
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "new a\n");
        assert_eq!(std::fs::read_to_string(&b).unwrap(), "new b\n");
        assert!(leftovers(dir.path()).is_empty());
    }

    /// A single write that fails leaves neither the file nor the folders made for it, and keeps a
    /// folder that was there before (with a file of the user's in it).
    #[test]
    fn a_failed_write_leaves_no_folder_it_made() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("new/deeper/a.npy");
        let failed = write_atomic(&out, |_| Err(std::io::Error::other("the data failed")));
        assert!(failed.is_err());
        assert!(!dir.path().join("new").exists());
        std::fs::create_dir(dir.path().join("mine")).unwrap();
        let out = dir.path().join("mine/b.npy");
        assert!(write_atomic(&out, |_| Err(std::io::Error::other("failed"))).is_err());
        assert!(dir.path().join("mine").is_dir() && !out.exists());
        write_atomic(&dir.path().join("new/deeper/a.npy"), |w| writeln!(w, "ok")).unwrap();
        assert_eq!(read_to(&dir.path().join("new/deeper"), "a.npy"), "ok\n");
    }

    #[test]
    fn a_commit_that_fails_midway_restores_every_output() {
        // The second staged file is missing, so its move fails after the first output was replaced
        // (as a rename onto an immutable file would): both outputs must end as they were.
        let dir = tempfile::tempdir().unwrap();
        let stage = tempfile::tempdir().unwrap();
        let csv = |d: &Path| ["a", "b", "c"].map(|n| d.join(format!("{n}.csv")));
        let ([a, b, c], [sa, sb, sc]) = (csv(dir.path()), csv(stage.path()));
        std::fs::write(&a, "old a").unwrap();
        std::fs::write(&b, "old b").unwrap();
        std::fs::write(&sa, "new a").unwrap();
        std::fs::write(&sc, "new c").unwrap();
        let (wa, wc, wb) = ((a.clone(), sa), (c.clone(), sc), (b.clone(), sb));
        let e = commit(&[&wa, &wc, &wb]).unwrap_err().to_string();
        assert!(e.contains("no output was written"), "{e}");
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "old a");
        assert_eq!(std::fs::read_to_string(&b).unwrap(), "old b");
        assert!(
            !c.exists(),
            "a new output placed before the failure is removed"
        );
        assert!(leftovers(dir.path()).is_empty());
        // With every staged file there, all are replaced and nothing is kept aside.
        std::fs::write(&wb.1, "new b").unwrap();
        std::fs::write(&wc.1, "new c").unwrap();
        std::fs::write(&wa.1, "new a").unwrap();
        commit(&[&wa, &wc, &wb]).unwrap();
        for (path, text) in [(&a, "new a"), (&b, "new b"), (&c, "new c")] {
            assert_eq!(std::fs::read_to_string(path).unwrap(), text);
        }
        assert!(leftovers(dir.path()).is_empty());
    }

    #[test]
    fn a_name_too_long_for_the_file_system_is_refused_before_the_work() {
        let dir = tempfile::tempdir().unwrap();
        let long = dir.path().join(format!("{}.npy", "a".repeat(252)));
        let e = check_outputs(&[&long], &[]).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("a name of 256 bytes"), "{e}");
        let fits = dir.path().join(format!("{}.npy", "a".repeat(251)));
        check_outputs(&[&fits], &[]).unwrap();
        std::fs::write(&fits, "").unwrap();
    }

    /// A folder whose writing fails keeps its old files and gets no new one, and goes if the call
    /// created it; one that succeeds gets every file, subfolders merged.
    #[test]
    fn a_failed_folder_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let report = dir.path().join("report");
        let failed = write_folder(&report, MARK, |stage| {
            write_atomic(&stage.join("a.md"), |w| writeln!(w, "a"))?;
            Err::<(), _>(Error::Numerical("the plot failed".into()))
        });
        assert!(failed.is_err());
        assert!(
            !report.exists(),
            "a folder this call created is left behind"
        );
        // Its missing ancestors go too.
        let nested = dir.path().join("a/b/report");
        let failed = write_folder(&nested, MARK, |_| {
            Err::<(), _>(Error::Numerical("the plot failed".into()))
        });
        assert!(failed.is_err());
        assert!(!dir.path().join("a").exists(), "an ancestor is left behind");

        std::fs::create_dir_all(report.join("plots")).unwrap();
        std::fs::write(report.join("a.md"), "# a report").unwrap();
        std::fs::write(report.join("plots/keep.png"), "kept").unwrap();
        let failed = write_folder(&report, MARK, |stage| {
            write_atomic(&stage.join("a.md"), |w| writeln!(w, "new"))?;
            Err::<(), _>(Error::Numerical("the plot failed".into()))
        });
        assert!(failed.is_err());
        assert_eq!(
            std::fs::read_to_string(report.join("a.md")).unwrap(),
            "# a report"
        );
        assert!(leftovers(&report).is_empty());

        write_folder(&report, MARK, |stage| {
            write_atomic(&stage.join("a.md"), |w| writeln!(w, "new"))?;
            write_atomic(&stage.join("plots/b.png"), |w| writeln!(w, "b"))
        })
        .unwrap();
        assert_eq!(
            std::fs::read_to_string(report.join("a.md")).unwrap(),
            "new\n"
        );
        assert_eq!(
            std::fs::read_to_string(report.join("plots/b.png")).unwrap(),
            "b\n"
        );
        assert_eq!(
            std::fs::read_to_string(report.join("plots/keep.png")).unwrap(),
            "kept",
            "a file no manifest lists is not the report's"
        );
        assert!(leftovers(&report).is_empty());
        // A killed run's staging folder stays (another run may be writing there) and is named once
        // a run into the folder succeeds; this run's own is gone by then.
        assert!(left_staging(&report).is_empty());
        let killed = report.join(".anisospec-killed");
        std::fs::create_dir(&killed).unwrap();
        write_folder(&report, MARK, |stage| {
            write_atomic(&stage.join("a.md"), |w| writeln!(w, "again"))
        })
        .unwrap();
        assert_eq!(left_staging(&report), vec![killed]);
    }

    /// A new report replaces the earlier one: the files and folders its manifest lists and the new one
    /// does not write go; the user's files (notes, a target's image, a cache, a picture of their own
    /// beside the plots) stay, and a listed link is removed, its target left alone.
    #[cfg(unix)]
    #[test]
    fn a_new_report_replaces_the_old_one() {
        let dir = tempfile::tempdir().unwrap();
        let report = dir.path().join("report");
        let outside = dir.path().join("outside");
        std::fs::create_dir_all(&outside).unwrap();
        write_folder(&report, REPORT, |stage| {
            for file in [
                "report.md",
                "old.csv",
                "plots/old.png",
                "plots/kept.png",
                "gone/x.npy",
                "linked.npy",
            ] {
                write_atomic(&stage.join(file), |w| writeln!(w, "# a report"))?;
            }
            Ok(())
        })
        .unwrap();
        let manifest = std::fs::read_to_string(report.join(MANIFEST)).unwrap();
        assert!(
            manifest.starts_with(MANIFEST_HEADER)
                && manifest.lines().any(|l| l == "plots/old.png")
                && manifest.lines().any(|l| l == "gone/"),
            "{manifest}"
        );
        std::fs::create_dir_all(report.join("cache")).unwrap();
        for (file, text) in [
            ("notes.txt", "mine"),
            ("target.npy", "mine"),
            ("plots/mine.png", "mine"),
            ("cache/table.npy", "cached"),
        ] {
            std::fs::write(report.join(file), text).unwrap();
        }
        std::fs::write(outside.join("data.npy"), "theirs").unwrap();
        std::fs::remove_file(report.join("linked.npy")).unwrap();
        std::os::unix::fs::symlink(outside.join("data.npy"), report.join("linked.npy")).unwrap();
        write_folder(&report, REPORT, |stage| {
            write_atomic(&stage.join("report.md"), |w| writeln!(w, "# a report"))?;
            write_atomic(&stage.join("plots/kept.png"), |w| writeln!(w, "new"))
        })
        .unwrap();
        let read = |f: &str| std::fs::read_to_string(report.join(f)).ok();
        assert_eq!(read("plots/kept.png").as_deref(), Some("new\n"));
        assert_eq!(read("old.csv"), None);
        assert_eq!(read("plots/old.png"), None);
        assert!(!report.join("gone").exists(), "an emptied folder stays");
        for (file, text) in [
            ("notes.txt", "mine"),
            ("target.npy", "mine"),
            ("plots/mine.png", "mine"),
            ("cache/table.npy", "cached"),
        ] {
            assert_eq!(read(file).as_deref(), Some(text), "{file}");
        }
        assert!(report.join("linked.npy").symlink_metadata().is_err());
        assert_eq!(
            std::fs::read_to_string(outside.join("data.npy")).unwrap(),
            "theirs"
        );
        let manifest = read(MANIFEST).unwrap();
        let listed: Vec<&str> = manifest.lines().skip(1).collect();
        let mut expected = vec!["report.md", "plots/", "plots/kept.png"];
        expected.sort();
        let mut listed_sorted = listed.clone();
        listed_sorted.sort();
        assert_eq!(listed_sorted, expected, "{manifest}");
        assert!(leftovers(&report).is_empty());
    }

    /// A `manifest.txt` that is not this tool's (other text, or a folder) is refused before any work;
    /// a file the earlier report did not write (one that appeared during the run, or one of the user's
    /// where the new report puts a plot) is never replaced; one that does not clash stays beside the
    /// report. A report from before the manifest has its files replaced and none pruned.
    #[test]
    fn foreign_files_are_never_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let report = dir.path().join("report");
        std::fs::create_dir_all(&report).unwrap();
        std::fs::write(report.join("report.md"), "# a report").unwrap();
        std::fs::write(report.join(MANIFEST), "plots/a.png").unwrap();
        let e = check_report_folder(&report, REPORT).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("not written by anisospec"), "{e}");
        assert_eq!(read_to(&report, MANIFEST), "plots/a.png");
        std::fs::remove_file(report.join(MANIFEST)).unwrap();
        std::fs::create_dir(report.join(MANIFEST)).unwrap();
        let e = check_report_folder(&report, REPORT).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("cannot be read"), "{e}");

        // Before the manifest: the earlier report's files are replaced, nothing is pruned.
        let legacy = dir.path().join("legacy");
        std::fs::create_dir_all(&legacy).unwrap();
        std::fs::write(legacy.join("report.md"), "# a report").unwrap();
        std::fs::write(legacy.join("old.png"), "old").unwrap();
        write_folder(&legacy, REPORT, |stage| {
            write_atomic(&stage.join("report.md"), |w| writeln!(w, "# a report"))
        })
        .unwrap();
        assert_eq!(read_to(&legacy, "report.md"), "# a report\n");
        assert_eq!(read_to(&legacy, "old.png"), "old");
        // With the manifest: the user's picture where the new report puts one stops the move.
        std::fs::write(legacy.join("new.png"), "mine").unwrap();
        let e = write_folder(&legacy, REPORT, |stage| {
            write_atomic(&stage.join("report.md"), |w| writeln!(w, "# a report"))?;
            write_atomic(&stage.join("new.png"), |w| writeln!(w, "plot"))
        })
        .unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(
            e.to_string()
                .contains("the earlier report did not write it"),
            "{e}"
        );
        assert_eq!(read_to(&legacy, "new.png"), "mine");
        assert!(leftovers(&legacy).is_empty());

        let empty = dir.path().join("empty");
        let e = write_folder(&empty, REPORT, |stage| {
            std::fs::write(empty.join("report.md"), "theirs").unwrap();
            write_atomic(&stage.join("report.md"), |w| writeln!(w, "# a report"))
        })
        .unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(
            e.to_string()
                .contains("the earlier report did not write it"),
            "{e}"
        );
        assert_eq!(read_to(&empty, "report.md"), "theirs");
        assert!(leftovers(&empty).is_empty());

        let fresh = dir.path().join("fresh");
        write_folder(&fresh, REPORT, |stage| {
            std::fs::write(fresh.join("notes.txt"), "mine").unwrap();
            write_atomic(&stage.join("report.md"), |w| writeln!(w, "# a report"))
        })
        .unwrap();
        assert_eq!(read_to(&fresh, "notes.txt"), "mine");
        assert_eq!(read_to(&fresh, "report.md"), "# a report\n");
    }

    /// Pruning never reaches through a link into a folder the report does not own: a `plots` that the
    /// earlier report wrote, since replaced by a link, keeps the pictures the manifest lists, and takes
    /// the new one.
    #[cfg(unix)]
    #[test]
    fn pruning_leaves_a_linked_folders_files_alone() {
        let dir = tempfile::tempdir().unwrap();
        let report = dir.path().join("report");
        let shared = dir.path().join("shared");
        std::fs::create_dir_all(&report).unwrap();
        std::fs::create_dir_all(&shared).unwrap();
        std::fs::write(report.join("report.md"), "# a report").unwrap();
        std::fs::write(
            report.join(MANIFEST),
            format!("{MANIFEST_HEADER}\nplots/\nplots/theirs.png\nreport.md\n"),
        )
        .unwrap();
        std::fs::write(shared.join("theirs.png"), "theirs").unwrap();
        std::os::unix::fs::symlink(&shared, report.join("plots")).unwrap();
        write_folder(&report, REPORT, |stage| {
            write_atomic(&stage.join("report.md"), |w| writeln!(w, "# a report"))?;
            write_atomic(&stage.join("plots/new.png"), |w| writeln!(w, "new"))
        })
        .unwrap();
        assert_eq!(
            std::fs::read_to_string(shared.join("theirs.png")).unwrap(),
            "theirs"
        );
        assert_eq!(
            std::fs::read_to_string(shared.join("new.png")).unwrap(),
            "new\n"
        );
    }

    /// A folder of other files (no earlier report in it) is refused with a usage error naming it, and
    /// nothing in it changes; an empty folder, or one holding only a killed run's temporary folder,
    /// takes a report.
    #[test]
    fn a_folder_of_other_files_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let folder = dir.path().join("sources");
        std::fs::create_dir_all(&folder).unwrap();
        std::fs::write(folder.join("data.npy"), "mine").unwrap();
        let e = check_report_folder(&folder, REPORT).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        let text = e.to_string();
        assert!(
            text.contains("data.npy") && text.contains("no report.md") && text.contains("--out"),
            "{text}"
        );
        assert_eq!(
            std::fs::read_to_string(folder.join("data.npy")).unwrap(),
            "mine"
        );
        // A report.md that is not this tool's (another first line) marks no earlier report; and a
        // report in the folder would not replace it.
        std::fs::write(folder.join("report.md"), "# Our quarterly report").unwrap();
        let e = check_report_folder(&folder, REPORT).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        let e = write_folder(&folder, REPORT, |stage| {
            write_atomic(&stage.join("report.md"), |w| writeln!(w, "# a report"))
        })
        .unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert_eq!(
            std::fs::read_to_string(folder.join("report.md")).unwrap(),
            "# Our quarterly report"
        );
        assert!(leftovers(&folder).is_empty());

        let empty = dir.path().join("empty");
        std::fs::create_dir_all(empty.join(".anisospec-killed")).unwrap();
        check_report_folder(&empty, REPORT).unwrap();
        write_folder(&empty, REPORT, |stage| {
            write_atomic(&stage.join("report.md"), |w| writeln!(w, "new"))
        })
        .unwrap();
        assert!(empty.join("report.md").is_file());
    }

    /// A file that the earlier report listed but that now lies behind a link (its folder replaced by
    /// a link to someone else's) is never replaced: the move stops first, and the file keeps its bytes.
    /// A dangling link where the report folder goes, and a manifest that is a link loop, are usage
    /// errors before any work.
    #[cfg(unix)]
    #[test]
    fn files_behind_links_are_never_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let report = dir.path().join("report");
        let theirs = dir.path().join("theirs");
        let write = |stage: &Path| {
            write_atomic(&stage.join("report.md"), |w| writeln!(w, "# a report"))?;
            write_atomic(&stage.join("spectra/x.npy"), |w| writeln!(w, "new"))
        };
        write_folder(&report, REPORT, write).unwrap();
        std::fs::create_dir_all(&theirs).unwrap();
        std::fs::write(theirs.join("x.npy"), "theirs").unwrap();
        std::fs::remove_dir_all(report.join("spectra")).unwrap();
        std::os::unix::fs::symlink(&theirs, report.join("spectra")).unwrap();
        check_report_folder(&report, REPORT).unwrap();
        let e = write_folder(&report, REPORT, write).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("lies in a linked folder"), "{e}");
        assert_eq!(read_to(&theirs, "x.npy"), "theirs");
        assert!(leftovers(&report).is_empty());

        let dangling = dir.path().join("dangling");
        std::os::unix::fs::symlink(dir.path().join("nowhere"), &dangling).unwrap();
        let e = check_report_folder(&dangling, REPORT).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("not a folder"), "{e}");

        std::fs::remove_file(report.join(MANIFEST)).unwrap();
        std::os::unix::fs::symlink(report.join(MANIFEST), report.join(MANIFEST)).unwrap();
        let e = check_report_folder(&report, REPORT).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("cannot be read"), "{e}");
    }

    /// A path resolves through its existing part (links, `..`) and literally beyond it.
    #[test]
    fn paths_resolve_beyond_what_exists() {
        let dir = tempfile::tempdir().unwrap();
        let base = dir.path().canonicalize().unwrap();
        std::fs::create_dir_all(base.join("a")).unwrap();
        assert_eq!(
            resolved(&base.join("a/../b/c/../d")).unwrap(),
            base.join("b/d")
        );
        assert_eq!(resolved(&base.join("a/./e")).unwrap(), base.join("a/e"));
    }

    /// A folder standing where a new file goes stops the move before any file moves, with a usage
    /// error naming it; an error while writing names the output, not its temporary path.
    #[test]
    fn clashes_are_refused_before_anything_moves() {
        let dir = tempfile::tempdir().unwrap();
        let report = dir.path().join("report");
        std::fs::create_dir_all(report.join("z.md")).unwrap();
        std::fs::write(report.join("a.md"), "# a report").unwrap();
        let e = write_folder(&report, MARK, |stage| {
            write_atomic(&stage.join("a.md"), |w| writeln!(w, "a"))?;
            write_atomic(&stage.join("z.md"), |w| writeln!(w, "z"))
        })
        .unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(
            e.to_string()
                .contains("a folder stands where the file goes"),
            "{e}"
        );
        assert_eq!(
            std::fs::read_to_string(report.join("a.md")).unwrap(),
            "# a report"
        );
        assert!(leftovers(&report).is_empty());

        let a = dir.path().join("a.csv");
        let e = write_group(&[&a], |staged| {
            Err::<(), _>(Error::io(
                "write",
                &staged(&a),
                std::io::Error::other("disk full"),
            ))
        })
        .unwrap_err()
        .to_string();
        assert!(
            e.contains(&format!("cannot write {}: disk full", a.display())),
            "{e}"
        );
        assert!(!e.contains(".anisospec-"), "{e}");
    }

    /// A report folder whose subfolder links to another file system (here /dev/shm, a tmpfs, where
    /// the machine has one on another device) is still written: the file is copied across, then
    /// renamed into place.
    #[cfg(unix)]
    #[test]
    fn a_linked_subfolder_on_another_file_system_is_written() {
        use std::os::unix::fs::MetadataExt;
        let shm = Path::new("/dev/shm");
        let dir = tempfile::tempdir().unwrap();
        let Ok(meta) = std::fs::metadata(shm) else {
            return;
        };
        if meta.dev() == std::fs::metadata(dir.path()).unwrap().dev() {
            return;
        }
        let elsewhere = tempfile::tempdir_in(shm).unwrap();
        let report = dir.path().join("report");
        std::fs::create_dir_all(&report).unwrap();
        std::os::unix::fs::symlink(elsewhere.path(), report.join("plots")).unwrap();
        std::fs::write(report.join("a.md"), "# a report").unwrap();
        write_folder(&report, MARK, |stage| {
            write_atomic(&stage.join("plots/a.png"), |w| writeln!(w, "a"))
        })
        .unwrap();
        assert_eq!(
            std::fs::read_to_string(elsewhere.path().join("a.png")).unwrap(),
            "a\n"
        );
        assert!(leftovers(elsewhere.path()).is_empty());
    }

    /// An atomically written file, alone or in a group, has the mode a plain `File::create` gives (0666
    /// less the umask), not the owner-only mode of the temporary file or folder it started in.
    #[cfg(unix)]
    #[test]
    fn atomic_writes_get_ordinary_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let plain = dir.path().join("plain.txt");
        std::fs::File::create(&plain).unwrap();
        let atomic = dir.path().join("atomic.txt");
        write_atomic(&atomic, |w| writeln!(w, "x")).unwrap();
        let grouped = dir.path().join("grouped.txt");
        write_group(&[&grouped], |staged| {
            write_atomic(&staged(&grouped), |w| writeln!(w, "x"))
        })
        .unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        for written in [&atomic, &grouped] {
            assert_eq!(
                mode(written),
                mode(&plain),
                "{}: mode {:o}, File::create gives {:o}",
                written.display(),
                mode(written),
                mode(&plain)
            );
        }
    }
}
