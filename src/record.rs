//! Result files, written atomically.
//!
//! Every file is written to a temporary file in the destination folder and renamed into place
//! only when complete, so an interrupted run never leaves a half-written CSV behind: a file
//! either exists whole or not at all.

use crate::error::{Error, Result};
use std::io::Write;
use std::path::Path;

/// Temporary files become result files: give them ordinary read permissions (tempfile's
/// default, 0600, would make results unreadable to other users).
fn temp_builder<'a>(prefix: &'a str, suffix: &'a str) -> tempfile::Builder<'a, 'a> {
    let mut b = tempfile::Builder::new();
    b.prefix(prefix).suffix(suffix);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        b.permissions(std::fs::Permissions::from_mode(0o644));
    }
    b
}

/// Writes `path` atomically: `fill` writes the content into a buffered temporary file in the
/// same folder, which then replaces `path`. Parent folders are created.
pub fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let tmp = temp_builder(".tmp-", "")
        .tempfile_in(dir)
        .map_err(|e| Error::io(dir, e))?;
    {
        let mut out = std::io::BufWriter::new(tmp.as_file());
        fill(&mut out).map_err(|e| Error::io(path, e))?;
        out.flush().map_err(|e| Error::io(path, e))?;
    }
    tmp.persist(path).map_err(|e| Error::io(path, e.error))?;
    Ok(())
}

/// Writes `path` atomically through a writer that needs a file path (an image encoder, say):
/// `fill` writes to a temporary path in the same folder with the same extension, which then
/// replaces `path`.
pub fn write_atomic_via_path(path: &Path, fill: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let suffix = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let tmp = temp_builder(".tmp-", &suffix)
        .tempfile_in(dir)
        .map_err(|e| Error::io(dir, e))?;
    fill(tmp.path())?;
    tmp.persist(path).map_err(|e| Error::io(path, e.error))?;
    Ok(())
}

/// Writes a CSV file atomically: a header and rows of already-formatted fields.
pub fn write_csv<R, I>(path: &Path, header: &[String], rows: I) -> Result<()>
where
    I: IntoIterator<Item = R>,
    R: IntoIterator,
    R::Item: AsRef<[u8]>,
{
    write_atomic(path, |out| {
        let mut w = csv::Writer::from_writer(out);
        w.write_record(header)?;
        for row in rows {
            w.write_record(row)?;
        }
        w.flush()?;
        Ok(())
    })
}

/// Writes one serde record (with its header) as a CSV file, atomically.
pub fn write_record<T: serde::Serialize>(path: &Path, record: &T) -> Result<()> {
    write_atomic(path, |out| {
        let mut w = csv::Writer::from_writer(out);
        w.serialize(record)?;
        w.flush()?;
        Ok(())
    })
}

/// Writes serde records (header from the first) as a CSV file, atomically.
pub fn write_records<T: serde::Serialize>(path: &Path, records: &[T]) -> Result<()> {
    write_atomic(path, |out| {
        let mut w = csv::Writer::from_writer(out);
        for r in records {
            w.serialize(r)?;
        }
        w.flush()?;
        Ok(())
    })
}
