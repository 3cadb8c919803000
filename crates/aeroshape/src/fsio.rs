//! Safe file output: every file is written to a temporary name in its destination folder
//! and renamed into place only when complete, so an interrupted or failed run never leaves
//! a half-written file and never touches an input.

use std::fs;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// An error while writing an output file; carries the path.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {source}")]
pub struct WriteError {
    /// The destination that could not be written.
    pub path: PathBuf,
    /// What went wrong.
    #[source]
    pub source: io::Error,
}

/// Writes `path` atomically: `fill` writes the content into a buffered temporary file in the
/// same folder, which is flushed, synced and renamed to `path` only if `fill` succeeds.
///
/// ```
/// use std::io::Write;
/// let dir = tempfile::tempdir().unwrap();
/// let path = dir.path().join("out.txt");
/// aeroshape::fsio::write_atomic(&path, |w| writeln!(w, "hello")).unwrap();
/// assert_eq!(std::fs::read_to_string(&path).unwrap(), "hello\n");
/// // A failing writer leaves nothing behind.
/// let bad = dir.path().join("bad.txt");
/// let r = aeroshape::fsio::write_atomic(&bad, |_| Err(std::io::Error::other("boom")));
/// assert!(r.is_err() && !bad.exists());
/// ```
pub fn write_atomic<F>(path: &Path, fill: F) -> Result<(), WriteError>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    let wrap = |source| WriteError {
        path: path.to_path_buf(),
        source,
    };
    let tmp = temp_beside(path).map_err(wrap)?;
    {
        let mut w = BufWriter::new(tmp.as_file());
        fill(&mut w).map_err(wrap)?;
        w.flush().map_err(wrap)?;
    }
    tmp.as_file().sync_all().map_err(wrap)?;
    tmp.persist(path).map_err(|e| wrap(e.error))?;
    Ok(())
}

/// A new temporary file beside `path` (same folder, so the final rename stays on one file
/// system; hidden name `.<name>.<random>.part.<ext>`), created with the permissions of a normally
/// created file (0666 less the umask on Unix; tempfile's default 0600 would leave outputs
/// unreadable to the rest of a team).
pub fn temp_beside(path: &Path) -> io::Result<tempfile::NamedTempFile> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    // Keep the extension last: some writers (image encoders) choose the format from it.
    let suffix = match path.extension() {
        Some(e) => format!(".part.{}", e.to_string_lossy()),
        None => ".part".to_string(),
    };
    let prefix = format!(".{name}.");
    let mut b = tempfile::Builder::new();
    b.prefix(&prefix).suffix(&suffix);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        b.permissions(std::fs::Permissions::from_mode(0o666));
    }
    b.tempfile_in(&dir)
}

/// Refuses an output path that names one of the inputs (inputs are never modified).
pub fn ensure_not_input(output: &Path, inputs: &[&Path]) -> Result<(), String> {
    let canon = |p: &Path| fs::canonicalize(p).ok();
    if let Some(out) = canon(output) {
        for input in inputs {
            if canon(input).as_deref() == Some(out.as_path()) {
                return Err(format!(
                    "{}: output would overwrite an input; choose another output name",
                    output.display()
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_to_overwrite_input() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("in.su2");
        fs::write(&p, "x").unwrap();
        assert!(ensure_not_input(&p, &[&p]).is_err());
        assert!(ensure_not_input(&dir.path().join("other"), &[&p]).is_ok());
    }

    #[test]
    fn replaces_existing_file_whole() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("o.txt");
        fs::write(&p, "old").unwrap();
        write_atomic(&p, |w| w.write_all(b"new")).unwrap();
        assert_eq!(fs::read_to_string(&p).unwrap(), "new");
        let r = write_atomic(&p, |w| {
            w.write_all(b"partial")?;
            Err(io::Error::other("fail"))
        });
        assert!(r.is_err());
        assert_eq!(fs::read_to_string(&p).unwrap(), "new");
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[cfg(unix)]
    #[test]
    fn outputs_get_the_permissions_of_a_normally_created_file() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let plain = dir.path().join("plain.txt");
        fs::write(&plain, "x").unwrap();
        let atomic = dir.path().join("atomic.txt");
        write_atomic(&atomic, |w| w.write_all(b"x")).unwrap();
        let mode = |p: &Path| fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&atomic), mode(&plain));
    }
}
