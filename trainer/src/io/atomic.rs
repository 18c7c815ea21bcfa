//! Atomic file output: write to a temporary file beside the target, then rename over it, so a
//! failure never leaves a half-written file or destroys the previous one.

use std::io::Write;
use std::path::Path;

use crate::error::{Error, Result};

/// Writes `bytes` to `path` atomically.
///
/// # Errors
/// [`Error::InvalidInput`] naming `path` when its folder does not exist; [`Error::Io`] naming
/// `path` when the folder is not writable or the rename fails. The previous content of
/// `path`, if any, is then untouched.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// The folder `path` is written into.
fn folder(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Checks that `path` can be an output before any work is done for it: its folder exists and
/// it is not itself a folder. Commands call it first, so that a typo costs no training.
///
/// # Errors
/// [`Error::InvalidInput`] naming `path` and what to change.
pub fn check_output(path: &Path) -> Result<()> {
    let dir = folder(path);
    if dir.is_file() {
        return Err(Error::invalid(format!(
            "{}: {} is a file, not a folder; write somewhere else",
            path.display(),
            dir.display()
        )));
    }
    if !dir.is_dir() {
        return Err(Error::invalid(format!(
            "{}: the folder {} does not exist; create it or write somewhere else",
            path.display(),
            dir.display()
        )));
    }
    if path.is_dir() {
        return Err(Error::invalid(format!(
            "{} is a folder; name a file to write",
            path.display()
        )));
    }
    Ok(())
}

/// Streams output into `path` atomically: `fill` writes into a buffered temporary file.
///
/// # Errors
/// As [`write_atomic`], plus any error `fill` returns.
pub fn write_atomic_with(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    check_output(path)?;
    let dir = folder(path);
    let io = |e| Error::io(path, e);
    let mut builder = tempfile::Builder::new();
    builder.prefix(".neurosurf-").suffix(".tmp");
    // A temporary file is private (0600); the output is an ordinary file, readable as the
    // umask allows, like any other the user writes.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let mut tmp = builder.tempfile_in(dir).map_err(io)?;
    {
        let mut writer = std::io::BufWriter::new(tmp.as_file_mut());
        fill(&mut writer).map_err(io)?;
        writer.flush().map_err(io)?;
    }
    tmp.as_file().sync_all().map_err(io)?;
    tmp.persist(path).map_err(|e| io(e.error))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_that_cannot_be_written_are_named_before_any_work() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("file");
        std::fs::write(&file, b"x").unwrap();
        check_output(&dir.path().join("new.nsb")).unwrap();
        check_output(&file).unwrap();
        let folder = check_output(dir.path()).unwrap_err().to_string();
        assert!(folder.contains("is a folder"), "{folder}");
        let under = check_output(&file.join("x.nsb")).unwrap_err().to_string();
        assert!(under.contains("is a file, not a folder"), "{under}");
        let missing = check_output(&dir.path().join("no/x.nsb"))
            .unwrap_err()
            .to_string();
        assert!(missing.contains("does not exist"), "{missing}");
    }

    #[cfg(unix)]
    #[test]
    fn the_output_has_an_ordinary_files_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let ordinary = dir.path().join("ordinary");
        std::fs::write(&ordinary, b"x").unwrap();
        let written = dir.path().join("written");
        write_atomic(&written, b"x").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&written), mode(&ordinary));
    }

    #[test]
    fn a_missing_folder_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("no such folder").join("out.bin");
        let message = write_atomic(&path, b"x").unwrap_err().to_string();
        assert!(
            message.contains("no such folder") && message.contains("does not exist"),
            "{message}"
        );
    }

    #[test]
    fn replaces_content_and_leaves_no_temporaries() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.bin");
        write_atomic(&path, b"first").unwrap();
        write_atomic(&path, b"second").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"second");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn failed_fill_keeps_previous_content() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.bin");
        write_atomic(&path, b"kept").unwrap();
        let err = write_atomic_with(&path, |_| Err(std::io::Error::other("boom")));
        assert!(err.is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"kept");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn missing_directory_is_a_clear_error() {
        let err = write_atomic(Path::new("/nonexistent-dir/x.bin"), b"x").unwrap_err();
        assert!(err.to_string().contains("/nonexistent-dir/x.bin"), "{err}");
    }
}
