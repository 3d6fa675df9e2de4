//! Result files, written atomically.
//!
//! Every file is written to a temporary file in the destination folder and renamed into place
//! only when complete, so an interrupted run never leaves a half-written CSV behind: a file
//! either exists whole or not at all.

use crate::error::{Error, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

mod lock;
pub use lock::{inside_rows, FolderLock, WorkLock};

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

/// The name of the temporary file that becomes `path` starts with `.tmp-<its name>.`, so that
/// whoever owns `path` knows what a killed writer left ([`remove_orphans`]).
fn temp_prefix(path: &Path) -> String {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
    format!(".tmp-{}.", name.unwrap_or_default())
}

/// Removes from `dir` what a writer killed mid-write left for files whose names start with
/// `stem`: the temporary files ([`write_atomic`]) of such files, and, when `stem` is empty,
/// every temporary file and staging folder (`.writing-*`, [`write_run_folder`]). The caller
/// must own those names (a run's lock): a live writer's temporary file would go too. Returns
/// how many it removed; a failure to remove one is an error naming it.
///
/// ```
/// let dir = tempfile::tempdir().unwrap();
/// let d = dir.path();
/// std::fs::write(d.join(".tmp-s1.csv.x7Yq"), "half").unwrap();
/// std::fs::write(d.join(".tmp-s10.csv.x7Yq"), "another run's").unwrap();
/// assert_eq!(pbcs::record::remove_orphans(d, "s1.").unwrap(), 1);
/// assert!(d.join(".tmp-s10.csv.x7Yq").exists());
/// ```
pub fn remove_orphans(dir: &Path, stem: &str) -> Result<usize> {
    let entries = match std::fs::read_dir(dir) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(0),
        Err(e) => return Err(Error::io(dir, e)),
    };
    let tmp = format!(".tmp-{stem}");
    let mut removed = 0;
    for entry in entries {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let path = entry.path();
        let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
        if !is_dir && name.starts_with(&tmp) {
            std::fs::remove_file(&path).map_err(|e| Error::io(&path, e))?;
        } else if is_dir && stem.is_empty() && name.starts_with(".writing-") {
            std::fs::remove_dir_all(&path).map_err(|e| Error::io(&path, e))?;
        } else {
            continue;
        }
        removed += 1;
    }
    Ok(removed)
}

/// Creates the folder `dir` and its parents ([`std::fs::create_dir_all`]); where `dir` or one
/// of its parents is a file, the error names that path and says so (not `File exists`).
///
/// ```
/// let dir = tempfile::tempdir().unwrap();
/// let file = dir.path().join("f");
/// std::fs::write(&file, "").unwrap();
/// let e = pbcs::record::create_folder(&file.join("out")).unwrap_err().to_string();
/// assert!(e.contains("f: exists and is not a folder"), "{e}");
/// pbcs::record::create_folder(&dir.path().join("a/b")).unwrap();
/// ```
pub fn create_folder(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| {
        let file = dir
            .ancestors()
            .find(|a| std::fs::metadata(a).is_ok_and(|m| !m.is_dir()));
        match file {
            Some(file) => Error::io(
                file,
                std::io::Error::other("exists and is not a folder; choose another folder"),
            ),
            None => Error::io(dir, e),
        }
    })
}

/// The SHA-256 of `bytes` in lower-case hex (a registered preset, a chain's files).
///
/// ```
/// assert_eq!(
///     pbcs::record::sha256_hex(b"abc"),
///     "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
/// );
/// ```
pub fn sha256_hex(bytes: &[u8]) -> String {
    sha256_hex_of(&[bytes])
}

/// The SHA-256 of `parts` one after the other ([`sha256_hex`] of their concatenation, without
/// making it: a checkpoint's two states).
pub fn sha256_hex_of(parts: &[&[u8]]) -> String {
    use sha2::{Digest, Sha256};
    let mut hash = Sha256::new();
    for part in parts {
        hash.update(part);
    }
    hash.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// The SHA-256 of the file at `path` ([`sha256_hex`]), an error naming it if unreadable.
pub fn file_sha256(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    Ok(sha256_hex(&bytes))
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
    create_folder(dir)?;
    let tmp = temp_builder(&temp_prefix(path), "")
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
    create_folder(dir)?;
    let suffix = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let tmp = temp_builder(&temp_prefix(path), &suffix)
        .tempfile_in(dir)
        .map_err(|e| Error::io(dir, e))?;
    fill(tmp.path())?;
    tmp.persist(path).map_err(|e| Error::io(path, e.error))?;
    Ok(())
}

/// Claims `dir` as the output folder of the run whose resolved config is `config_text`, before
/// any work: `dir` is created if needed and must be a writable folder, and a folder that
/// already holds another run (a `config.toml` with other contents) is refused, so a run never
/// silently replaces a different run's files and never fails for its folder after the work.
/// The config is written first, so the folder says whose it is from the start; re-running the
/// same config into its own folder is allowed (runs are deterministic). The run holds the
/// returned lock ([`RUN_LOCK`] in `dir`) while it works, so a second process of the same run
/// into the same folder is refused; with it held, the temporary files and staging folders a
/// killed process of this run left in `dir` are removed ([`remove_orphans`]).
pub fn claim_out_dir(dir: &Path, config_text: &str) -> Result<WorkLock> {
    create_folder(dir)?;
    let lock = WorkLock::acquire(&dir.join(RUN_LOCK))?;
    let config = dir.join("config.toml");
    match std::fs::read_to_string(&config) {
        Ok(stored) if stored != config_text => {
            return Err(Error::io(
                dir,
                std::io::Error::other(
                    "holds another run (its config.toml differs from this run's); choose \
                     another output folder or delete this one",
                ),
            ))
        }
        Ok(_) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => return Err(Error::io(&config, e)),
    }
    remove_orphans(dir, "")?;
    write_atomic(&config, |w| w.write_all(config_text.as_bytes()))?;
    Ok(lock)
}

/// The lock file a run holds in its folder while it works ([`claim_out_dir`]).
pub const RUN_LOCK: &str = ".lock";

/// The file that marks a run folder as incomplete: present while [`write_run_folder`] moves a
/// run's files into place, and left behind when that fails. Readers of run folders
/// ([`check_complete`]: `pbcs eval`, `pbcs.Chain`) refuse a folder that holds it.
pub const INCOMPLETE: &str = "INCOMPLETE";

/// What [`INCOMPLETE`] says to whoever opens it.
const INCOMPLETE_TEXT: &str = "This run folder is incomplete: the run that wrote it stopped \
     before all its files were in place (a full disk, an error). Its files are not a finished \
     run, and `pbcs eval` refuses them. Run the same command again to complete it, or delete \
     the folder.\n";

/// Writes the files of one run into the folder `out`, all of them or none: `fill` writes them
/// into a temporary folder inside `out` (`.writing-*`), so a failure there (a full disk, say)
/// leaves `out` as it was (an earlier finished run of the same job stays whole) and the
/// temporary folder is removed. Then [`INCOMPLETE`] is written into `out`, each file and
/// folder is renamed into place (a folder of the same name, such as an earlier run's `chain/`,
/// is replaced), and the marker is removed last. A failure while moving (something in the way
/// of a file) leaves the marker: readers refuse the folder until a run completes it.
pub fn write_run_folder(out: &Path, fill: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    create_folder(out)?;
    let staging = tempfile::Builder::new()
        .prefix(".writing-")
        .tempdir_in(out)
        .map_err(|e| Error::io(out, e))?;
    fill(staging.path())?;
    let listed: std::io::Result<Vec<_>> =
        std::fs::read_dir(staging.path()).and_then(|d| d.map(|e| e.map(|e| e.path())).collect());
    let mut entries = listed.map_err(|e| Error::io(staging.path(), e))?;
    entries.sort();
    // Folders replaced go here, inside the temporary folder, and are removed with it.
    let aside = tempfile::Builder::new()
        .prefix(".replaced-")
        .tempdir_in(staging.path())
        .map_err(|e| Error::io(staging.path(), e))?;
    let marker = out.join(INCOMPLETE);
    write_atomic(&marker, |w| w.write_all(INCOMPLETE_TEXT.as_bytes()))?;
    for from in entries {
        let Some(name) = from.file_name() else {
            continue;
        };
        let to = out.join(name);
        let old_dir = std::fs::symlink_metadata(&to).is_ok_and(|m| m.is_dir());
        if from.is_dir() && old_dir {
            let away = aside.path().join(name);
            std::fs::rename(&to, &away).map_err(|e| Error::io(&to, e))?;
        }
        std::fs::rename(&from, &to).map_err(|e| Error::io(&to, e))?;
    }
    std::fs::remove_file(&marker).map_err(|e| Error::io(&marker, e))
}

/// Writes a set of generated files into the folders `dirs`, all of them or none: `fill` is
/// handed, for each folder, a temporary folder inside it (`.writing-*`) and writes there,
/// returning the files it wrote; only when it succeeds is every file it left there moved to
/// the same name in the real folder. A failure while `fill` draws and writes (missing data, a
/// full disk) leaves every folder's files as they were, never half old and half new (`pbcs
/// figures`: the figures and the report's LaTeX); the moves after it are renames within one
/// file system, each atomic, not atomic as a set. Returns `fill`'s files at their final paths.
///
/// ```
/// use pbcs::record::write_all_or_none;
/// let dir = tempfile::tempdir().unwrap();
/// std::fs::write(dir.path().join("a.txt"), "old").unwrap();
/// let failed = write_all_or_none([dir.path()], |[stage]| {
///     std::fs::write(stage.join("a.txt"), "new").unwrap();
///     Err(pbcs::Error::invalid("data", "missing"))
/// });
/// assert!(failed.is_err());
/// assert_eq!(std::fs::read_to_string(dir.path().join("a.txt")).unwrap(), "old");
/// let files = write_all_or_none([dir.path()], |[stage]| {
///     std::fs::write(stage.join("a.txt"), "new").unwrap();
///     Ok(vec![stage.join("a.txt")])
/// })
/// .unwrap();
/// assert_eq!(files, vec![dir.path().join("a.txt")]);
/// assert_eq!(std::fs::read_to_string(&files[0]).unwrap(), "new");
/// assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1); // no staging folder left
/// ```
pub fn write_all_or_none<const N: usize>(
    dirs: [&Path; N],
    fill: impl FnOnce([&Path; N]) -> Result<Vec<PathBuf>>,
) -> Result<Vec<PathBuf>> {
    let mut stages = Vec::with_capacity(N);
    for dir in dirs {
        create_folder(dir)?;
        let stage = tempfile::Builder::new()
            .prefix(".writing-")
            .tempdir_in(dir)
            .map_err(|e| Error::io(dir, e))?;
        stages.push(stage);
    }
    let staged: [&Path; N] = std::array::from_fn(|i| stages[i].path());
    let written = fill(staged)?;
    // Every file left in a stage moves, whether or not `fill` listed it.
    for (stage, dir) in stages.iter().zip(dirs) {
        let mut files = Vec::new();
        list_files(stage.path(), &mut files)?;
        files.sort();
        for from in files {
            let rel = from.strip_prefix(stage.path()).unwrap_or(&from);
            let to = dir.join(rel);
            if let Some(parent) = to.parent() {
                create_folder(parent)?;
            }
            std::fs::rename(&from, &to).map_err(|e| Error::io(&to, e))?;
        }
    }
    Ok(written
        .into_iter()
        .map(|f| {
            let at = stages.iter().zip(dirs).find_map(|(stage, dir)| {
                f.strip_prefix(stage.path()).ok().map(|rel| dir.join(rel))
            });
            at.unwrap_or(f)
        })
        .collect())
}

/// Every file under `dir`, recursively, into `out`.
fn list_files(dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let path = entry.map_err(|e| Error::io(dir, e))?.path();
        if path.is_dir() {
            list_files(&path, out)?;
        } else {
            out.push(path);
        }
    }
    Ok(())
}

/// Refuses the run folder `dir` if it is marked [`INCOMPLETE`] (its run failed while writing
/// it), with an error naming the folder and saying what to do.
pub fn check_complete(dir: &Path) -> Result<()> {
    if dir.join(INCOMPLETE).exists() {
        return Err(Error::io(
            dir,
            std::io::Error::other(format!(
                "is marked incomplete (it holds {INCOMPLETE}): the run writing it stopped before \
                 all its files were in place; run the same command again to complete it, or \
                 delete the folder"
            )),
        ));
    }
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

/// Reads a CSV file of serde records (the inverse of [`write_records`]); an error names the
/// file and the line.
pub fn read_records<T: serde::de::DeserializeOwned>(path: &Path) -> Result<Vec<T>> {
    let mut reader = csv::Reader::from_path(path).map_err(|e| Error::csv(path, e))?;
    let header = reader.headers().map_err(|e| Error::csv(path, e))?.clone();
    reader
        .deserialize()
        .collect::<std::result::Result<Vec<T>, _>>()
        .map_err(|e| Error::csv_in(path, e, &header))
}

/// Reads a CSV file that holds exactly one serde record (a summary line); any other count is
/// an error naming the file.
pub fn read_one_record<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T> {
    let mut lines: Vec<T> = read_records(path)?;
    match lines.len() {
        1 => Ok(lines.remove(0)),
        n => Err(Error::parse(path, format!("holds {n} lines, one expected"))),
    }
}

/// A run's `timing.toml`: the wall clock, which is not deterministic and so never goes into a
/// CSV, and the layer kernel that ran (`PBCS_KERNEL`; every kernel but `matrixmultiply` gives
/// the same bytes, so a byte difference between machines can be told apart). Files of runs
/// with networks written before the kernel was recorded lack it: those rows were computed
/// with `matrixmultiply`; phase-1 runs (no networks) record none.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Timing {
    /// Wall-clock seconds of the run.
    pub wall_seconds: f64,
    /// Environment steps per wall-clock second (rounded).
    pub steps_per_second: u64,
    /// The layer kernel's name, if recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kernel: Option<String>,
    /// The machine that ran it: CPU model and logical cores, if recorded (rows computed on
    /// another machine say so here).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub machine: Option<String>,
}

/// This machine in words: the CPU model (`/proc/cpuinfo`, where there is one; else the
/// architecture) and the number of logical cores.
pub fn machine() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, m)| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!("{model}, {cores} cores")
}

impl Timing {
    /// The timing of a run that took `seconds` for `env_steps` steps on the kernel named
    /// `kernel` (`None` for runs without networks, such as phase 1 alone).
    pub fn now(seconds: f64, env_steps: u64, kernel: Option<&str>) -> Timing {
        Timing {
            wall_seconds: (seconds * 1e6).round() / 1e6,
            steps_per_second: (env_steps as f64 / seconds.max(1e-9)).round() as u64,
            kernel: kernel.map(str::to_string),
            machine: Some(machine()),
        }
    }

    /// Writes `path` atomically, with a comment line saying why it is not in the CSVs.
    pub fn write(&self, path: &Path) -> Result<()> {
        let body = crate::validate::to_toml(self, path)?;
        let text = format!(
            "# wall-clock time of the run (not deterministic, hence not in the CSVs)\n{body}"
        );
        write_atomic(path, |w| w.write_all(text.as_bytes()))
    }

    /// Reads `path`: `Ok(None)` if there is no such file, an error naming it if it is malformed.
    pub fn read(path: &Path) -> Result<Option<Timing>> {
        match std::fs::read_to_string(path) {
            Ok(text) => crate::validate::parse_toml(&text, path).map(Some),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(e) => Err(Error::io(path, e)),
        }
    }

    /// The kernel that computed the run: as recorded, else `matrixmultiply`.
    pub fn kernel_name(&self) -> &str {
        self.kernel.as_deref().unwrap_or("matrixmultiply")
    }
}

#[cfg(test)]
mod timing_tests {
    use super::Timing;

    #[test]
    fn timing_files_old_and_new_read_back() {
        let dir = tempfile::tempdir().unwrap();
        // A file written before the kernel was recorded (committed rows hold such files).
        let old = dir.path().join("old.timing.toml");
        std::fs::write(
            &old,
            "# wall-clock time of the run (not deterministic, hence not in the CSVs)\n\
             wall_seconds = 205.050875\nsteps_per_second = 4877\n",
        )
        .unwrap();
        let t = Timing::read(&old).unwrap().unwrap();
        assert_eq!(t.wall_seconds, 205.050875);
        assert_eq!(t.steps_per_second, 4877);
        assert_eq!(t.kernel_name(), "matrixmultiply");
        assert_eq!(t.machine, None);
        // Written and read back.
        let new = dir.path().join("new.timing.toml");
        let t = Timing {
            wall_seconds: 1.5,
            steps_per_second: 200,
            kernel: Some("avx2".into()),
            machine: Some(super::machine()),
        };
        assert!(t.machine.as_deref().unwrap().ends_with(" cores"));
        assert_eq!(t.machine, Timing::now(1.0, 1, None).machine);
        t.write(&new).unwrap();
        assert_eq!(Timing::read(&new).unwrap(), Some(t));
        assert!(std::fs::read_to_string(&new)
            .unwrap()
            .starts_with("# wall-clock time"));
        // Absent: None; malformed: an error naming the file.
        assert_eq!(Timing::read(&dir.path().join("none.toml")).unwrap(), None);
        std::fs::write(&old, "wall_seconds = \"soon\"\n").unwrap();
        let e = Timing::read(&old).unwrap_err().to_string();
        assert!(e.contains("old.timing.toml"), "{e}");
    }
}
