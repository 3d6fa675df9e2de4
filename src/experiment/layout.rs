//! Where a run's raw files live (`<results>/raw/<experiment>/<cell>/s<seed>.*`) and reading
//! them back.

use super::{plan, read_run_row, Cell, Experiment, RawRow};
use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// The raw file of run `seed` in the cell folder `dir`: `s<seed><suffix>` (`.csv` the row,
/// `.toml` the job, `.timing.toml`, `.evals.csv`, `.evaluation.csv`, `.picture.csv`, `.lock`).
pub fn run_file(dir: &Path, seed: u64, suffix: &str) -> PathBuf {
    dir.join(format!("s{seed}{suffix}"))
}

/// The finished raw row of (cell, seed) of `exp` in `dir` (the cell's folder), if there is
/// one. A finished run of another config is an error: results of two configs are never mixed.
/// Configs are compared by value, so a setting added later, absent from an older stored
/// config, takes its default (the behaviour the older run had). The row itself must be this
/// run's and hold one record of values in range ([`read_run_row`]), else an error names the
/// file, the line and the column: a resumed sweep, `pbcs aggregate` and `pbcs exp list` read
/// rows through here alike.
pub fn read_finished(
    exp: &Experiment,
    cell: &Cell,
    seed: u64,
    dir: &Path,
) -> Result<Option<RawRow>> {
    let path = run_file(dir, seed, ".csv");
    if !path.exists() {
        return Ok(None);
    }
    let config_path = run_file(dir, seed, ".toml");
    let stored = std::fs::read_to_string(&config_path).map_err(|e| Error::io(&config_path, e))?;
    if !cell.job.with_seed(seed).same_as(&stored) {
        let profile = match &exp.profile {
            None => "; rows of a profile's grid (`make smoke` writes results-smoke/) are read \
                     with that profile (--profile smoke)"
                .to_string(),
            Some(p) => format!("; this read the grid of the profile `{p}`"),
        };
        return Err(Error::parse(
            &config_path,
            format!(
                "this finished run used another config than the experiment now gives (its \
                 file, or `pbcs table`'s preset or config); remove the cell's folder to re-run \
                 it, restore the file, or choose another results folder (--results, \
                 --out){profile}"
            ),
        ));
    }
    read_run_row(exp, cell, seed, &path).map(Some)
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

/// All finished raw rows of the experiment under `results`, in (cell, seed) order; missing
/// runs are left out (and counted by the caller through `n`).
pub fn read_raw(exp: &Experiment, results: &Path) -> Result<Vec<RawRow>> {
    let mut rows = Vec::new();
    for p in plan(exp, None, None)? {
        if let Some(r) = read_finished(exp, p.cell, p.seed, &exp.cell_dir(results, p.cell))? {
            rows.push(r);
        }
    }
    Ok(rows)
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
