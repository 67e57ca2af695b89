//! Atomic output: write to a temporary file in the destination directory, then rename.
//!
//! A failed or interrupted run never leaves a half-written file that `make` would treat as up to
//! date. `-` means standard output.

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
}
