//! Whole-file writes that never leave a truncated file behind.

use std::io::Write;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

use super::OutputError;

/// Distinguishes temporary files of concurrent writers in one process.
static COUNTER: AtomicU64 = AtomicU64::new(0);

/// Whether `file_name` is the temporary of a [`write_atomic`]
/// (`.NAME.tmp-PID-N`), which a process killed while writing leaves behind.
pub fn is_atomic_temporary(file_name: &str) -> bool {
    file_name.starts_with('.') && file_name.contains(".tmp-")
}

/// Removes the temporaries of killed [`write_atomic`]s from `dir`.
pub fn remove_atomic_temporaries(dir: &Path) -> Result<(), OutputError> {
    let Ok(list) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    for e in list.flatten() {
        if is_atomic_temporary(&e.file_name().to_string_lossy()) {
            let p = e.path();
            std::fs::remove_file(&p).map_err(|err| OutputError::io(&p, err))?;
        }
    }
    Ok(())
}

/// Writes `bytes` to `path` as a whole: first to a temporary file in the same
/// directory (`.NAME.tmp-PID-N`), synced to disk, then renamed over `path`.
///
/// A reader, or a run that crashes half-way, sees either the previous
/// content of `path` or the new one, never a mix or a truncated file. The
/// parent directory must exist. On failure the temporary file is removed.
///
/// ```
/// let path = std::env::temp_dir().join(format!("pfem-doc-atomic-{}.txt", std::process::id()));
/// pfem_io::output::write_atomic(&path, b"hello")?;
/// assert_eq!(std::fs::read(&path).unwrap(), b"hello");
/// # std::fs::remove_file(&path).ok();
/// # Ok::<(), pfem_io::output::OutputError>(())
/// ```
pub fn write_atomic(path: impl AsRef<Path>, bytes: &[u8]) -> Result<(), OutputError> {
    let path = path.as_ref();
    let file_name = path.file_name().ok_or_else(|| {
        OutputError::io(
            path,
            std::io::Error::new(std::io::ErrorKind::InvalidInput, "path has no file name"),
        )
    })?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(file_name);
    tmp_name.push(format!(
        ".tmp-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let tmp = path.with_file_name(tmp_name);

    let result = (|| {
        let mut file = std::fs::File::create(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        drop(file);
        std::fs::rename(&tmp, path)
    })();
    result.map_err(|source| {
        // Best effort: the temporary may not even exist.
        let _ = std::fs::remove_file(&tmp);
        OutputError::io(path, source)
    })
}
