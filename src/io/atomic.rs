//! Atomic output: write to a temporary file in the destination directory, then rename.
//!
//! A failed or interrupted run never leaves a half-written file that `make` would treat as up to
//! date. `-` means standard output. A destination that exists and is not a regular file (a
//! device such as `/dev/null`, a FIFO, `/dev/stdout`, a shell's `>(…)`) is written in place:
//! renaming over it would replace the device node with a file, or fail outright.

use super::IoError;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Where an output goes: a file path or standard output (`-`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Output {
    /// Standard output.
    Stdout,
    /// A file, written atomically.
    File(PathBuf),
}

impl Output {
    /// `-` is stdout; anything else a path.
    pub fn parse(s: &str) -> Output {
        if s == "-" {
            Output::Stdout
        } else {
            Output::File(PathBuf::from(s))
        }
    }

    /// Writes `bytes` to this output (atomically for files).
    pub fn write(&self, bytes: &[u8]) -> Result<(), IoError> {
        match self {
            Output::Stdout => write_stdout(bytes),
            Output::File(path) => write_atomic(path, bytes),
        }
    }

    /// A printable name for messages.
    pub fn display(&self) -> String {
        match self {
            Output::Stdout => "<stdout>".to_string(),
            Output::File(p) => p.display().to_string(),
        }
    }

    /// Fails fast, before any long work starts, when the destination directory does not exist
    /// or cannot be written (a temporary file is created there and removed).
    pub fn check_writable(&self) -> Result<(), IoError> {
        let Output::File(path) = self else { return Ok(()) };
        if is_special(path) {
            return Ok(());
        }
        refuse_directory(path)?;
        let dir = parent_dir(path);
        if !dir.is_dir() {
            return Err(IoError::os(
                path,
                std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    format!("directory {} does not exist", dir.display()),
                ),
            ));
        }
        // Under the pending lock: an interruption waits until the probe file is gone again.
        let _list = pending();
        temp_file_in(dir).map(drop).map_err(|e| IoError::os(path, e))
    }
}

fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Temporary files written but not yet renamed into place, and directories created for outputs
/// not yet committed, removed by [`remove_pending_and_hold`] when the process is interrupted.
/// Held locked while a set of outputs is renamed, so an interruption waits until all of them are
/// in place: outputs appear all together or not at all.
static PENDING: Mutex<Pending> = Mutex::new(Pending { files: Vec::new(), dirs: Vec::new() });

struct Pending {
    /// Temporary files.
    files: Vec<PathBuf>,
    /// Directories created for outputs, in order of creation.
    dirs: Vec<PathBuf>,
}

fn pending() -> std::sync::MutexGuard<'static, Pending> {
    PENDING.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Removes every temporary output file not yet renamed into place, then the directories created
/// for outputs not yet committed (those left empty), and keeps the list locked for the rest of
/// the process: for a signal handler, just before the process exits. An interrupted run leaves
/// no partial or temporary file, and no directory it made.
///
/// Every temporary file is created under this lock, so holding it until the exit is what makes
/// the cleanup final: released, it would let a thread waiting to stage its next output create a
/// temporary file that the exit then leaves behind (this happened, about once in 20 runs, to
/// `encode-normals` interrupted between its outputs).
pub fn remove_pending_and_hold() {
    let mut list = pending();
    for path in list.files.drain(..) {
        let _ = std::fs::remove_file(path);
    }
    // Innermost first; `remove_dir` leaves a directory that holds anything.
    for dir in list.dirs.drain(..).rev() {
        let _ = std::fs::remove_dir(dir);
    }
    std::mem::forget(list);
}

fn temp_file_in(dir: &Path) -> std::io::Result<tempfile::NamedTempFile> {
    tempfile::Builder::new().prefix(".prtkit-").suffix(".tmp").tempfile_in(dir)
}

/// The outputs of one run, written all or none: [`OutputSet::add`] writes each file's bytes to
/// a temporary file beside it, [`OutputSet::commit`] writes standard output and then renames the
/// files into place. Dropped without a commit (an error part-way), it removes its temporary files
/// and the directories it created, and no destination is touched.
#[derive(Default)]
pub struct OutputSet {
    staged: Vec<Staged>,
    /// Directories this set created, removed again (when empty) if it is dropped uncommitted.
    created_dirs: Vec<PathBuf>,
}

enum Staged {
    /// A temporary file to rename over `dest`.
    Renamed { temp: tempfile::TempPath, dest: PathBuf },
    /// A device, FIFO or `/dev/stdout`-like destination, written in place at commit.
    InPlace { dest: PathBuf, bytes: Vec<u8> },
    /// Standard output, written last.
    Stdout(Vec<u8>),
}

impl OutputSet {
    /// An empty set.
    pub fn new() -> Self {
        OutputSet::default()
    }

    /// Creates directory `dir` for outputs to go into, unless it exists; its parent must exist
    /// (a run creates the directory it is given, never the path to it). Dropped without a
    /// commit, the set removes the directory it created, if it is still empty.
    pub fn create_dir(&mut self, dir: &Path) -> Result<(), IoError> {
        if dir.is_dir() {
            return Ok(());
        }
        // Created and registered under one lock, as temporary files are: an interruption in
        // between would leave it behind.
        let mut list = pending();
        std::fs::create_dir(dir).map_err(|e| IoError::os(dir, e))?;
        list.dirs.push(dir.to_path_buf());
        self.created_dirs.push(dir.to_path_buf());
        Ok(())
    }

    /// Stages `bytes` for `output`. Files are written to a temporary file now (so a full disk
    /// or a bad directory fails here, before anything is replaced).
    pub fn add(&mut self, output: &Output, bytes: Vec<u8>) -> Result<(), IoError> {
        match output {
            Output::Stdout => self.staged.push(Staged::Stdout(bytes)),
            Output::File(path) if is_special(path) => self.staged.push(Staged::InPlace { dest: path.clone(), bytes }),
            Output::File(path) => {
                if self.staged.iter().any(|s| matches!(s, Staged::Renamed { dest, .. } if dest == path)) {
                    return Err(IoError::os(
                        path,
                        std::io::Error::new(std::io::ErrorKind::AlreadyExists, "given twice as an output"),
                    ));
                }
                // Checked here, not left to the rename: a rename failing at commit would come
                // after the other outputs of the set were already in place.
                refuse_directory(path)?;
                let temp = stage_file(path, &bytes)?;
                self.staged.push(Staged::Renamed { temp, dest: path.clone() });
            }
        }
        Ok(())
    }

    /// Writes the in-place destinations (devices, FIFOs: a full disk fails here, before any
    /// file is replaced), then standard output, then renames every staged file into place. An
    /// interruption during the renames waits for them to finish.
    ///
    /// Standard output comes before the renames so that a failure to write it (`/dev/full`, an
    /// I/O error) leaves every file output untouched: all or nothing includes stdout. A reader of
    /// stdout that needs the files waits for the process to exit. A broken pipe is not such a
    /// failure: the reader chose to stop reading (`head`), the outputs are complete, so the
    /// files are put in place and the broken pipe returned after, for the CLI to end quietly.
    pub fn commit(mut self) -> Result<(), IoError> {
        for item in &self.staged {
            if let Staged::InPlace { dest, bytes } = item {
                let mut file = std::fs::OpenOptions::new().write(true).open(dest).map_err(|e| IoError::os(dest, e))?;
                file.write_all(bytes).and_then(|_| file.flush()).map_err(|e| IoError::os(dest, e))?;
            }
        }
        let mut broken_pipe = None;
        for item in &self.staged {
            if let Staged::Stdout(bytes) = item {
                match write_stdout(bytes) {
                    Err(IoError::Os { error, path }) if error.kind() == std::io::ErrorKind::BrokenPipe => {
                        broken_pipe = Some(IoError::Os { error, path });
                        break;
                    }
                    result => result?,
                }
            }
        }
        let staged = std::mem::take(&mut self.staged);
        {
            let mut list = pending();
            // From here on the outputs are in place: directories made for them stay.
            let created = std::mem::take(&mut self.created_dirs);
            list.dirs.retain(|d| !created.contains(d));
            for item in staged {
                if let Staged::Renamed { temp, dest } = item {
                    let path: PathBuf = temp.to_path_buf();
                    list.files.retain(|p| *p != path);
                    temp.persist(&dest).map_err(|e| IoError::os(&dest, e.error))?;
                }
            }
        }
        broken_pipe.map_or(Ok(()), Err)
    }
}

impl Drop for OutputSet {
    fn drop(&mut self) {
        // Dropping a TempPath removes its file; only then is it taken off the pending list, so an
        // interruption in between still finds it.
        let temps: Vec<PathBuf> = self
            .staged
            .drain(..)
            .filter_map(|item| match item {
                Staged::Renamed { temp, .. } => {
                    let path = temp.to_path_buf();
                    drop(temp);
                    Some(path)
                }
                _ => None,
            })
            .collect();
        let mut list = pending();
        list.files.retain(|p| !temps.contains(p));
        for dir in self.created_dirs.iter().rev() {
            let _ = std::fs::remove_dir(dir);
        }
        list.dirs.retain(|d| !self.created_dirs.contains(d));
    }
}

/// A file output cannot replace a directory.
fn refuse_directory(path: &Path) -> Result<(), IoError> {
    if path.is_dir() {
        return Err(IoError::os(path, std::io::Error::new(std::io::ErrorKind::IsADirectory, "is a directory")));
    }
    Ok(())
}

/// Writes `bytes` to a registered temporary file beside `dest`, with the mode `dest` will have.
fn stage_file(dest: &Path, bytes: &[u8]) -> Result<tempfile::TempPath, IoError> {
    // Created and registered under one lock: an interruption in between would find the file on
    // disk but not on the list, and leave it behind.
    let mut tmp = {
        let mut list = pending();
        let tmp = temp_file_in(parent_dir(dest)).map_err(|e| IoError::os(dest, e))?;
        list.files.push(tmp.path().to_path_buf());
        tmp
    };
    let temp = (|| {
        tmp.write_all(bytes)?;
        tmp.as_file().sync_data()?;
        // Temporary files are created 0600; an output keeps the mode of the file it replaces,
        // or gets the usual 0644, so other users and tools can read it.
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(dest).map(|m| m.permissions().mode() & 0o7777).unwrap_or(0o644);
            tmp.as_file().set_permissions(std::fs::Permissions::from_mode(mode))?;
        }
        Ok(())
    })();
    let path = tmp.path().to_path_buf();
    match temp {
        Ok(()) => Ok(tmp.into_temp_path()),
        Err(e) => {
            // Removed before it leaves the list, for the same reason.
            drop(tmp);
            pending().files.retain(|p| *p != path);
            Err(IoError::os(dest, e))
        }
    }
}

fn write_stdout(bytes: &[u8]) -> Result<(), IoError> {
    let mut out = std::io::stdout().lock();
    out.write_all(bytes).and_then(|_| out.flush()).map_err(|e| IoError::os(Path::new("<stdout>"), e))
}

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename (an
/// [`OutputSet`] of one).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    let mut set = OutputSet::new();
    set.add(&Output::File(path.to_path_buf()), bytes.to_vec())?;
    set.commit()
}

/// True when `path` (after symlinks) exists and is neither a regular file nor a directory.
fn is_special(path: &Path) -> bool {
    std::fs::metadata(path).map(|m| !m.is_file() && !m.is_dir()).unwrap_or(false)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_whole_file_and_leaves_no_temporaries() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.txt");
        write_atomic(&path, b"hello").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"hello");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&path).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode, 0o644, "outputs must be readable by others");
        }
    }

    #[test]
    fn a_set_that_fails_part_way_replaces_nothing_and_leaves_no_temporaries() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.txt"), dir.path().join("b.txt"));
        std::fs::write(&a, b"old").unwrap();
        let mut set = OutputSet::new();
        set.add(&Output::File(a.clone()), b"new".to_vec()).unwrap();
        assert_eq!(pending().files.iter().filter(|p| p.starts_with(dir.path())).count(), 1);
        let bad = Output::File(dir.path().join("missing-dir/c.txt"));
        assert!(set.add(&bad, b"x".to_vec()).is_err());
        drop(set);
        assert_eq!(std::fs::read(&a).unwrap(), b"old");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, vec![std::ffi::OsString::from("a.txt")]);
        assert!(pending().files.iter().all(|p| !p.starts_with(dir.path())));

        let mut set = OutputSet::new();
        set.add(&Output::File(a.clone()), b"new".to_vec()).unwrap();
        set.add(&Output::File(b.clone()), b"too".to_vec()).unwrap();
        assert!(set.add(&Output::File(b.clone()), b"twice".to_vec()).is_err());
        set.commit().unwrap();
        assert_eq!((std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap()), (b"new".to_vec(), b"too".to_vec()));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }

    #[test]
    fn a_directory_in_the_way_fails_before_anything_is_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.txt"), dir.path().join("b"));
        std::fs::write(&a, b"old").unwrap();
        std::fs::create_dir(&b).unwrap();
        let err = Output::File(b.clone()).check_writable().unwrap_err().to_string();
        assert!(err.contains("is a directory"), "{err}");
        let mut set = OutputSet::new();
        set.add(&Output::File(a.clone()), b"new".to_vec()).unwrap();
        assert!(set.add(&Output::File(b.clone()), b"x".to_vec()).is_err());
        drop(set);
        assert_eq!(std::fs::read(&a).unwrap(), b"old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2, "no temporary file left");
    }

    #[test]
    fn directories_made_for_a_set_that_fails_are_removed_and_kept_when_it_commits() {
        let dir = tempfile::tempdir().unwrap();
        let maps = dir.path().join("maps");
        let err = OutputSet::new().create_dir(&maps.join("k8")).unwrap_err().to_string();
        assert!(err.contains("maps/k8"), "the path to a directory is never created: {err}");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);

        let mut set = OutputSet::new();
        set.create_dir(&maps).unwrap();
        assert!(pending().dirs.contains(&maps), "an interruption would remove it");
        set.add(&Output::File(maps.join("a.exr")), b"a".to_vec()).unwrap();
        drop(set);
        assert!(!pending().dirs.contains(&maps));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "maps/ is removed");

        let mut set = OutputSet::new();
        set.create_dir(&maps).unwrap();
        set.add(&Output::File(maps.join("a.exr")), b"a".to_vec()).unwrap();
        set.commit().unwrap();
        assert_eq!(std::fs::read(maps.join("a.exr")).unwrap(), b"a");
        assert!(!pending().dirs.contains(&maps), "committed: an interruption now leaves it");
    }

    #[cfg(unix)]
    #[test]
    fn a_read_only_directory_is_reported_before_work() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        std::fs::set_permissions(dir.path(), std::fs::Permissions::from_mode(0o555)).unwrap();
        let probe = dir.path().join("probe");
        let root = std::fs::write(&probe, b"").is_ok();
        let _ = std::fs::remove_file(&probe);
        let result = Output::File(dir.path().join("x.json")).check_writable();
        std::fs::set_permissions(dir.path(), std::fs::Permissions::from_mode(0o755)).unwrap();
        if root {
            eprintln!("skipping: running as root, directory permissions are not enforced");
            return;
        }
        assert!(result.is_err());
    }

    #[test]
    fn missing_directory_is_reported_before_work() {
        let out = Output::parse("/nonexistent-dir-prtkit/x.json");
        let err = out.check_writable().unwrap_err().to_string();
        assert!(err.contains("/nonexistent-dir-prtkit"), "{err}");
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_destination_is_written_in_place_not_replaced() {
        use std::os::unix::fs::FileTypeExt;
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("pipe");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if !matches!(made, Ok(s) if s.success()) {
            eprintln!("skipping: mkfifo is not available");
            return;
        }
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || std::fs::read(fifo).unwrap())
        };
        write_atomic(&fifo, b"through the pipe").unwrap();
        assert_eq!(reader.join().unwrap(), b"through the pipe");
        assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo(), "the FIFO must survive");
    }
}
