//! Locks on work and on results folders: OS advisory locks that the operating system releases
//! when the process ends, however it ends.

use crate::error::{Error, Result};
use std::io::Write;
use std::path::Path;

/// An exclusive claim on one piece of work (a run of a sweep): an OS advisory lock
/// ([`std::fs::File::try_lock`]: `flock` on Unix, `LockFileEx` on Windows) on the file
/// `path`, held while the guard lives. A second claim of the same path fails with a message
/// naming the file and its holder, so two sweeps into one results folder never do the same run
/// twice or replace each other's rows. The operating system releases the lock when the process
/// ends, however it ends, so a file left behind by an interrupted run blocks nothing: the
/// interrupted sweep resumes by being started again. The file names its holder (`pid`,
/// `host`) for that message and is removed when the guard is dropped.
#[derive(Debug)]
pub struct WorkLock {
    path: std::path::PathBuf,
    /// Holds the lock: closing it releases it.
    _file: std::fs::File,
}

/// Whether the open `file` is the file `path` names now (a holder that finished may have
/// removed the file after we opened it: a lock on the removed file claims nothing).
fn names_file(path: &Path, file: &std::fs::File) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (std::fs::metadata(path), file.metadata()) {
            (Ok(a), Ok(b)) => (a.dev(), a.ino()) == (b.dev(), b.ino()),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = file;
        path.exists()
    }
}

impl WorkLock {
    /// Takes the lock `path` (its folder is created), or says who holds it.
    pub fn acquire(path: &Path) -> Result<WorkLock> {
        if let Some(dir) = path.parent() {
            crate::record::create_folder(dir)?;
        }
        loop {
            let mut file = std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(path)
                .map_err(|e| Error::io(path, e))?;
            match file.try_lock() {
                Ok(()) => {}
                Err(std::fs::TryLockError::WouldBlock) => {
                    let holder = std::fs::read_to_string(path).unwrap_or_default();
                    return Err(Error::io(
                        path,
                        std::io::Error::other(format!(
                            "another process is doing this run ({}); wait for it",
                            holder.trim()
                        )),
                    ));
                }
                Err(std::fs::TryLockError::Error(e)) => return Err(Error::io(path, e)),
            }
            if !names_file(path, &file) {
                continue;
            }
            let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
                .map(|h| h.trim().to_string())
                .or_else(|_| std::env::var("HOSTNAME"))
                .unwrap_or_default();
            file.set_len(0)
                .and_then(|()| writeln!(file, "pid = {}\nhost = \"{host}\"", std::process::id()))
                .map_err(|e| Error::io(path, e))?;
            return Ok(WorkLock {
                path: path.to_path_buf(),
                _file: file,
            });
        }
    }
}

impl Drop for WorkLock {
    /// Removes the file, then (closing it) releases the lock.
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// The `raw/` folder of a results folder (one that holds [`FolderLock::path`]) that `dir` is or
/// lies inside, if any: no run's files and no other results folder belong there.
///
/// ```
/// let dir = tempfile::tempdir().unwrap();
/// std::fs::write(dir.path().join("sweep.lock"), "").unwrap();
/// let raw = dir.path().join("raw");
/// assert_eq!(pbcs::record::inside_rows(&raw.join("table/cell")), Some(raw.clone()));
/// assert_eq!(pbcs::record::inside_rows(dir.path()), None);
/// assert_eq!(pbcs::record::inside_rows(&dir.path().join("dev/issue1")), None);
/// ```
pub fn inside_rows(dir: &Path) -> Option<std::path::PathBuf> {
    let dir = std::path::absolute(dir).ok()?;
    dir.ancestors()
        .find(|a| {
            a.file_name().is_some_and(|n| n == "raw")
                && a.parent().is_some_and(|r| FolderLock::path(r).exists())
        })
        .map(Path::to_path_buf)
}

/// A sweep's claim on a whole results folder: an OS advisory lock
/// ([`std::fs::File::try_lock`], `flock` on Unix) on `<results>/sweep.lock`, held while the
/// guard lives and released by the operating system when the process ends, however it ends.
/// A sweep of several runs takes it exclusively before it reads what is finished and plans the
/// rest, so a second sweep on the same folder is refused at its start, naming the folder,
/// instead of taking a run the first one planned and making it stop between two runs. A
/// process of one run (`pbcs exp run --cell C --seed S`, as `pbcs exp list --make` and
/// `--slurm` start them side by side) takes it shared: such processes run together (each
/// run's own [`WorkLock`] keeps two of them off one run), and none runs beside a sweep of
/// several. The file stays (removing it could hand a new holder another file than the one a
/// shared holder still locks); it holds nothing.
#[derive(Debug)]
pub struct FolderLock {
    /// Holds the lock: closing it releases it.
    _file: std::fs::File,
}

impl FolderLock {
    /// The lock file of the results folder `results`.
    pub fn path(results: &Path) -> std::path::PathBuf {
        results.join("sweep.lock")
    }

    /// Takes the lock of the results folder `results` (created if needed): exclusively, or
    /// `shared` with other holders that take it shared; refused, naming the folder, while
    /// another process holds it in the other mode (or exclusively).
    pub fn acquire(results: &Path, shared: bool) -> Result<FolderLock> {
        if let Some(raw) = inside_rows(results) {
            return Err(Error::io(
                results,
                std::io::Error::other(format!(
                    "lies inside {}, the raw rows of a results folder: a sweep's rows would mix \
                     with its cells; choose another results folder",
                    raw.display()
                )),
            ));
        }
        crate::record::create_folder(results)?;
        let path = FolderLock::path(results);
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(|e| Error::io(&path, e))?;
        let taken = if shared {
            file.try_lock_shared()
        } else {
            file.try_lock()
        };
        match taken {
            Ok(()) => Ok(FolderLock { _file: file }),
            Err(std::fs::TryLockError::WouldBlock) => Err(Error::io(
                results,
                std::io::Error::other(format!(
                    "results folder in use: another sweep is running on it (it holds {}); wait \
                     for it to finish, or give this sweep another results folder (--results, \
                     --out)",
                    path.display()
                )),
            )),
            Err(std::fs::TryLockError::Error(e)) => Err(Error::io(&path, e)),
        }
    }
}
