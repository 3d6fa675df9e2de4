//! What the committed rows cost in wall clock: per experiment, the sums of its cells' timing
//! table (`results/tables/<experiment>.timing.csv`, [`super::CellTiming`]), and the learners
//! run outside the sweeps on PointMaze (`results/pointmaze/{vanilla,sb3}/*/s<seed>.timing.toml`).
//! `docs/experiments.md` quotes [`cost_markdown`] between markers; `tests/docs.rs` holds the
//! two equal, so no cost there is typed.

use super::CellTiming;
use crate::error::{Error, Result};
use crate::experiment::{Experiment, ExperimentName};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// `results/tables/<experiment>.timing.csv`.
pub fn timing_path(results: &Path, experiment: ExperimentName) -> PathBuf {
    results
        .join("tables")
        .join(format!("{experiment}.timing.csv"))
}

/// The wall clock of a run written by a script outside the sweeps (`wall_seconds`; other keys
/// are the script's own).
#[derive(serde::Deserialize)]
struct Wall {
    wall_seconds: f64,
}

/// Runs and total wall seconds of the `s<seed>.timing.toml` files in the folders of `root`
/// (none without `root`).
fn outside_walls(root: &Path) -> Result<(u64, f64)> {
    let (mut runs, mut seconds) = (0, 0.0);
    if !root.is_dir() {
        return Ok((runs, seconds));
    }
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(root)
        .map_err(|e| Error::io(root, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    dirs.sort();
    for dir in dirs {
        for entry in std::fs::read_dir(&dir).map_err(|e| Error::io(&dir, e))? {
            let path = entry.map_err(|e| Error::io(&dir, e))?.path();
            let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
            if name.starts_with('s') && name.ends_with(".timing.toml") {
                let wall: Wall = crate::validate::read_toml(&path)?;
                if !(wall.wall_seconds.is_finite() && wall.wall_seconds >= 0.0) {
                    return Err(Error::parse(&path, "wall_seconds must be finite and ≥ 0"));
                }
                runs += 1;
                seconds += wall.wall_seconds;
            }
        }
    }
    Ok((runs, seconds))
}

/// Hours with one decimal.
fn hours(seconds: f64) -> String {
    format!("{:.1}", seconds / 3600.0)
}

/// The cost table in Markdown: per experiment of `exps` with a timing table under `results`,
/// its runs, the sum of their wall clocks in core-hours (one core per run) and that over two
/// cores (`JOBS=2`); their total; then Stable-Baselines3's SAC+HER on PointMaze (Python,
/// which `make results` does not run).
pub fn cost_markdown(exps: &[Experiment], results: &Path) -> Result<String> {
    let mut s = String::from(
        "| experiment | runs | core-hours | hours on 2 cores (`JOBS=2`) |\n\
         | --- | --- | --- | --- |\n",
    );
    let (mut runs, mut seconds) = (0, 0.0);
    for exp in exps {
        let path = timing_path(results, exp.name);
        if !path.exists() {
            continue;
        }
        let cells: Vec<CellTiming> = crate::record::read_records(&path)?;
        let n: u64 = cells.iter().map(|c| c.n).sum();
        let total: f64 = cells.iter().map(|c| c.wall_total_s).sum();
        let _ = writeln!(
            s,
            "| `{}` | {n} | {} | {} |",
            exp.name,
            hours(total),
            hours(total / 2.0)
        );
        runs += n;
        seconds += total;
    }
    let _ = writeln!(
        s,
        "| every experiment above | {runs} | {} | {} |",
        hours(seconds),
        hours(seconds / 2.0)
    );
    let (n, total) = outside_walls(&results.join("pointmaze").join("sb3"))?;
    let _ = writeln!(
        s,
        "| PointMaze: SB3's SAC+HER (`python/benches/sb3_pointmaze.py`, one torch thread) | {n} \
         | {} | {} |",
        hours(total),
        hours(total / 2.0)
    );
    Ok(s)
}
