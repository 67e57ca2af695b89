//! Atomic output: write to a temporary file in the destination directory, then rename.
//!
//! A failed or interrupted run never leaves a half-written file that `make` would treat as up to
//! date. `-` means standard output. A destination that exists and is not a regular file (a
//! device such as `/dev/null`, a FIFO, `/dev/stdout`, a shell's `>(…)`) is written in place:
//! renaming over it would replace the device node with a file, or fail outright.

use super::IoError;
use std::io::Write;
use std::path::{Path, PathBuf};

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
            Output::Stdout => {
                let mut out = std::io::stdout().lock();
                out.write_all(bytes).and_then(|_| out.flush()).map_err(|e| IoError::os(Path::new("<stdout>"), e))
            }
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

    /// Fails fast when the destination directory does not exist, before any long work starts.
    pub fn check_writable(&self) -> Result<(), IoError> {
        match self {
            Output::Stdout => Ok(()),
            Output::File(path) => {
                let dir = parent_dir(path);
                if dir.is_dir() {
                    Ok(())
                } else {
                    Err(IoError::os(
                        path,
                        std::io::Error::new(
                            std::io::ErrorKind::NotFound,
                            format!("directory {} does not exist", dir.display()),
                        ),
                    ))
                }
            }
        }
    }
}

fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    if is_special(path) {
        let mut file = std::fs::OpenOptions::new().write(true).open(path).map_err(|e| IoError::os(path, e))?;
        return file.write_all(bytes).and_then(|_| file.flush()).map_err(|e| IoError::os(path, e));
    }
    let dir = parent_dir(path);
    let mut tmp = tempfile::Builder::new()
        .prefix(".prtkit-")
        .suffix(".tmp")
        .tempfile_in(dir)
        .map_err(|e| IoError::os(path, e))?;
    tmp.write_all(bytes).map_err(|e| IoError::os(path, e))?;
    tmp.as_file().sync_data().map_err(|e| IoError::os(path, e))?;
    // Temporary files are created 0600; an output keeps the mode of the file it replaces, or gets
    // the usual 0644, so other users and tools can read it.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(path).map(|m| m.permissions().mode() & 0o7777).unwrap_or(0o644);
        tmp.as_file().set_permissions(std::fs::Permissions::from_mode(mode)).map_err(|e| IoError::os(path, e))?;
    }
    tmp.persist(path).map_err(|e| IoError::os(path, e.error))?;
    Ok(())
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
