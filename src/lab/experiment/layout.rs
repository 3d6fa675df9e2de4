//! Where a run's raw files live (`<results>/raw/<experiment>/<cell>/s<seed>.*`); reading its
//! row back is [`super::read_row`]'s.

use super::{Cell, Experiment};
use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// The raw file of run `seed` in the cell folder `dir`: `s<seed><suffix>` (`.csv` the row,
/// `.toml` the job, `.timing.toml`, `.evals.csv`, `.evaluation.csv`, `.picture.csv`, `.lock`).
pub fn run_file(dir: &Path, seed: u64, suffix: &str) -> PathBuf {
    dir.join(format!("s{seed}{suffix}"))
}

/// Wall seconds of a finished run, from its timing file (None if absent or unreadable).
pub fn read_wall_seconds(exp: &Experiment, results: &Path, cell: &Cell, seed: u64) -> Option<f64> {
    let path = run_file(&exp.cell_dir(results, cell), seed, ".timing.toml");
    crate::record::Timing::read(&path)
        .ok()
        .flatten()
        .map(|t| t.wall_seconds)
}

/// Path of the picture data of (cell, seed), if it was kept.
pub fn picture_file(exp: &Experiment, results: &Path, cell: &Cell, seed: u64) -> PathBuf {
    run_file(&exp.cell_dir(results, cell), seed, ".picture.csv")
}

/// Path of a PBCS (cell, seed)'s evaluation episodes (success, steps of each).
pub fn evaluation_file(exp: &Experiment, results: &Path, cell: &Cell, seed: u64) -> PathBuf {
    run_file(&exp.cell_dir(results, cell), seed, ".evaluation.csv")
}

/// Path of the learning curve of a vanilla (cell, seed).
pub fn evals_file(exp: &Experiment, results: &Path, cell: &Cell, seed: u64) -> PathBuf {
    run_file(&exp.cell_dir(results, cell), seed, ".evals.csv")
}

/// The experiment files under `dir` (every `*.toml` with a `[[method]]` array), sorted; a
/// TOML file that does not parse is an error naming it.
pub fn experiment_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let path = entry.map_err(|e| Error::io(dir, e))?.path();
        if path.extension().is_some_and(|e| e == "toml") {
            let table: toml::Table = crate::validate::read_toml(&path)?;
            if table.get("method").is_some_and(toml::Value::is_array) {
                files.push(path);
            }
        }
    }
    files.sort();
    Ok(files)
}
