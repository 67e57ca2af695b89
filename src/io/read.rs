//! The one way prtkit reads input bytes: files, devices and standard input (`-`) alike, each
//! within a ceiling from [`crate::limits`] (`docs/limits.md`). Reading stops at ceiling + 1
//! bytes, so `/dev/zero`, an endless pipe or a file one byte too large costs at most the ceiling
//! in memory and time, and the error names the input and the ceiling.

use super::IoError;
use crate::limits::{human_bytes, LimitError};
use std::io::Read;
use std::path::{Path, PathBuf};

/// The name that means standard input wherever a stage reads a file.
pub const STDIN: &str = "-";

/// Whether `path` is `-`, standard input.
pub fn is_stdin(path: &Path) -> bool {
    path.as_os_str() == STDIN
}

/// The input's name in messages and documents: `<stdin>` for `-`, else the path.
pub fn display_path(path: &Path) -> PathBuf {
    if is_stdin(path) {
        PathBuf::from("<stdin>")
    } else {
        path.to_path_buf()
    }
}

/// Reads the input at `path` (`-`: standard input) whole, refusing it once it exceeds `ceiling`
/// bytes. `format` names the expected format in the messages; `check_start` sees the first bytes
/// (up to 64) before the rest is read, so an input of the wrong kind is refused at once.
pub fn read_bytes(
    path: &Path,
    format: &'static str,
    ceiling: u64,
    check_start: impl FnOnce(&[u8]) -> Result<(), String>,
) -> Result<Vec<u8>, IoError> {
    let name = display_path(path);
    let os = |e| IoError::os(&name, e);
    if is_stdin(path) {
        return read_within(std::io::stdin().lock(), 0, &name, format, ceiling, check_start);
    }
    let file = std::fs::File::open(path).map_err(os)?;
    // A regular file's size on disk refuses it before a byte is read when it is too large, and
    // sizes the buffer otherwise (devices and pipes say 0 and are bounded as they are read).
    let size = file.metadata().ok().filter(|m| m.is_file()).map_or(0, |m| m.len());
    if size > ceiling {
        return Err(too_large(&name, format, format!("{} ({size} bytes)", human_bytes(size as u128)), ceiling));
    }
    read_within(file, size, &name, format, ceiling, check_start)
}

/// The error for an input above `ceiling` bytes (`value`: its size, as far as it is known).
fn too_large(name: &Path, format: &'static str, value: String, ceiling: u64) -> IoError {
    let e = LimitError {
        what: "the file".into(),
        value,
        ceiling: human_bytes(ceiling as u128),
        reason: "files are read whole into memory",
    };
    IoError::invalid(name, format, e.to_string())
}

fn read_within(
    mut input: impl Read,
    hint: u64,
    name: &Path,
    format: &'static str,
    ceiling: u64,
    check_start: impl FnOnce(&[u8]) -> Result<(), String>,
) -> Result<Vec<u8>, IoError> {
    let os = |e| IoError::os(name, e);
    let mut bytes = Vec::with_capacity(hint as usize + 1);
    (&mut input).take(64.min(ceiling.saturating_add(1))).read_to_end(&mut bytes).map_err(os)?;
    check_start(&bytes).map_err(|reason| IoError::invalid(name, format, reason))?;
    // Read straight into a buffer that grows by doubling but never past ceiling + 1 bytes
    // (`read_to_end` alone would double to twice that): the most any input costs is its ceiling.
    // Each read is limited to the spare capacity, so `read_to_end` never grows the buffer itself.
    let limit = ceiling.saturating_add(1);
    while (bytes.len() as u64) < limit {
        if bytes.len() == bytes.capacity() {
            let grown = (bytes.capacity() as u64 * 2).max(bytes.len() as u64 + (64 << 10)).min(limit);
            bytes.reserve_exact(grown as usize - bytes.len());
        }
        let want = ((bytes.capacity() - bytes.len()) as u64).min(limit - bytes.len() as u64);
        if (&mut input).take(want).read_to_end(&mut bytes).map_err(os)? == 0 {
            break;
        }
    }
    if bytes.len() as u64 > ceiling {
        return Err(too_large(name, format, format!("more than {}", human_bytes(ceiling as u128)), ceiling));
    }
    Ok(bytes)
}

/// [`read_bytes`] for text: bytes that are not UTF-8 are an error at their line and column.
pub fn read_text(
    path: &Path,
    format: &'static str,
    ceiling: u64,
    check_start: impl FnOnce(&[u8]) -> Result<(), String>,
) -> Result<String, IoError> {
    String::from_utf8(read_bytes(path, format, ceiling, check_start)?).map_err(|e| {
        let before = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
        let column =
            before.rsplit(|&b| b == b'\n').next().map_or(0, |l| String::from_utf8_lossy(l).chars().count()) + 1;
        IoError::invalid(&display_path(path), format, format!("line {line}, column {column}: not UTF-8 text"))
    })
}

/// Refuses `-` for a document that names other files beside it (an SHRM's EXR, a factor file,
/// an `ibl.json`'s textures): read from standard input it has no directory to find them in.
pub fn refuse_stdin(path: &Path, what: &str) -> Result<(), IoError> {
    if is_stdin(path) {
        return Err(IoError::os(
            &display_path(path),
            std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!("{what} names files beside it, so it is read from a file, not standard input"),
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn read_bytes_stops_at_the_ceiling_and_checks_the_start_first() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f.bin");
        std::fs::write(&p, vec![7u8; 1000]).unwrap();
        assert_eq!(read_bytes(&p, "test", 1000, |_| Ok(())).unwrap().len(), 1000);
        let e = read_bytes(&p, "test", 999, |_| Ok(())).unwrap_err().to_string();
        assert!(e.contains("f.bin") && e.contains("ceiling of 999 bytes"), "{e}");
        let e = read_bytes(&p, "test", 1000, |b| Err(format!("starts with {}", b[0]))).unwrap_err().to_string();
        assert!(e.contains("starts with 7"), "{e}");
        // A ceiling below the 64 bytes of the start check still bounds the read.
        let e = read_bytes(&p, "test", 10, |b| if b.len() <= 11 { Ok(()) } else { Err("read too much".into()) });
        assert!(e.unwrap_err().to_string().contains("ceiling of 10 bytes"));
        std::fs::write(&p, b"ok\nab\xffc").unwrap();
        let e = read_text(&p, "test", 100, |_| Ok(())).unwrap_err().to_string();
        assert!(e.contains("line 2, column 3: not UTF-8"), "{e}");
        // An endless file is read only up to the ceiling.
        if Path::new("/dev/zero").exists() {
            let e = read_bytes(Path::new("/dev/zero"), "test", 1 << 20, |_| Ok(())).unwrap_err().to_string();
            assert!(e.contains("/dev/zero") && e.contains("1.0 MiB"), "{e}");
        }
    }

    #[test]
    fn standard_input_is_named_and_refused_where_a_document_names_files() {
        assert_eq!(display_path(Path::new("-")), PathBuf::from("<stdin>"));
        assert_eq!(display_path(Path::new("./-")), PathBuf::from("./-"));
        let e = refuse_stdin(Path::new("-"), "an SHRM document").unwrap_err().to_string();
        assert!(e.starts_with("<stdin>: an SHRM document names files beside it"), "{e}");
        assert!(refuse_stdin(Path::new("a.json"), "x").is_ok());
    }
}
