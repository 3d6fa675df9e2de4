//! The outside checks of our learners as tables (`results/tables/outside.*.csv`): the runs of
//! Stable-Baselines3 and of our learners committed under `results/outside/` (written by the
//! scripts its README names, never by an experiment sweep) set beside each other with the
//! package's statistics, so that the report quotes generated numbers only.
//!
//! - **Maze** ([`maze_comparisons`]): SB3's DDPG and TD3 on our maze through the Python package
//!   (`results/outside/sb3/<algo>-maze<N>/s<seed>.csv`) against our DDPG and TD3 at the same
//!   step count: the results table's vanilla runs (`experiment` `table`, cell `<algo>-maze<N>`)
//!   judged by their greedy evaluation at that step (`s<seed>.evals.csv`; their training up to
//!   that step is a run of that length). Solved with Wilson 95 % intervals and Fisher's exact
//!   test, per learner and pooled.
//! - **Pendulum** ([`pendulum_rows`]): the final mean return of our TD3 on the Rust port of
//!   Pendulum-v1 (`pendulum/ours/`) and of SB3's TD3 on gymnasium's (`pendulum/sb3/`): mean,
//!   standard deviation, range, Student's t interval and Welch's test; beside them the
//!   published figure of `pendulum/published.toml` (RL-Zoo's benchmark); the same for SAC
//!   ([`pendulum_sac_rows`]: `pendulum/ours_sac/`, `pendulum/sb3_sac/`,
//!   `pendulum/published_sac.toml`).
//! - **Update cost** (`update_cost.csv`, wall clock, copied as `outside.timing.csv`): the time
//!   per environment step of SB3's and our updates measured in the same run on one machine.
//! - **PointMaze** ([`pointmaze_baselines`]): our DDPG and TD3 alone and SB3's SAC+HER on
//!   PBCS's PointMaze tasks (the experiment `pointmaze_vanilla`'s raw rows,
//!   `<results>/pointmaze/sb3/`).

use super::scope::Scope;
use crate::error::{Error, Result};
use crate::experiment::{evals_file, run_file, CellKey, Experiment, ExperimentName, Method, Site};
use crate::learner::td3::Algo;
use crate::learner::LearnerName;
use crate::stats::{fisher_exact, least_successes, wilson, Z95};
use crate::vanilla::EvalRow;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// `<results>/outside`: the committed rows of the outside checks.
pub fn outside_dir(results: &Path) -> PathBuf {
    results.join("outside")
}

/// `<results>/tables/outside.<what>.csv`.
pub fn outside_table(results: &Path, what: &str) -> PathBuf {
    results.join("tables").join(format!("outside.{what}.csv"))
}

/// One Stable-Baselines3 run on the maze (`python/benches/sb3_maze.py`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MazeRun {
    /// `sb3-<version>`.
    pub library: String,
    /// `ddpg` or `td3`.
    pub algo: Algo,
    /// The run's seed.
    pub seed: u64,
    /// Environment steps of training.
    pub steps: u64,
    /// One greedy episode from s_0 reached the target (the table's vanilla judge).
    pub solved_s0: bool,
    /// Of PBCS's protocol (greedy episodes from the evaluation starts in B_ε(s_0)), the
    /// episodes that reached the target.
    pub protocol_successes: u64,
    /// Episodes of that protocol.
    pub protocol_episodes: u64,
}

/// One line of `outside.maze.csv`: ours against SB3 for one learner (or both pooled), at one
/// step count, judged by one greedy episode from s_0.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MazeComparison {
    /// `ddpg`, `td3`, or both learners' runs together (written `pooled`).
    pub algo: Scope<Algo>,
    /// Maze size N.
    pub maze: usize,
    /// Environment steps of training at the judged evaluation.
    pub steps: u64,
    /// Our runs judged.
    pub ours_n: u64,
    /// Of them, solved.
    pub ours_solved: u64,
    /// Wilson 95 % interval, lower end.
    pub ours_lo: f64,
    /// Upper end.
    pub ours_hi: f64,
    /// The solved seeds, space-separated (empty for `pooled`).
    pub ours_seeds: String,
    /// SB3's version (`sb3-<version>`).
    pub sb3_library: String,
    /// SB3 runs judged.
    pub sb3_n: u64,
    /// Of them, solved.
    pub sb3_solved: u64,
    /// Wilson 95 % interval, lower end.
    pub sb3_lo: f64,
    /// Upper end.
    pub sb3_hi: f64,
    /// The solved seeds (empty for `pooled`).
    pub sb3_seeds: String,
    /// SB3 runs solved by PBCS's protocol (≥ 95 % of its episodes).
    pub sb3_protocol_solved: u64,
    /// Two-sided p-value of Fisher's exact test, ours against SB3.
    pub fisher_p: f64,
}

/// One line of `update_cost.csv` and `outside.timing.csv` (wall clock, not deterministic).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UpdateCost {
    /// `ddpg` or `td3`.
    pub algo: LearnerName,
    /// `pbcs` or `sb3-<version>`.
    pub library: String,
    /// Microseconds per environment step after the warm-up (one update each).
    pub us_per_step: f64,
    /// Steps timed.
    pub steps: u64,
    /// The machine.
    pub machine: String,
}

/// One line of `outside.cost_ratio.csv`, per learner of `outside.timing.csv` ([`cost_ratios`]):
/// the first time per environment step of each library, and SB3's over ours.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CostRatio {
    /// `ddpg` or `td3`.
    pub algo: LearnerName,
    /// SB3's microseconds per step (its first line), empty without one.
    pub sb3_us_per_step: Option<f64>,
    /// Ours (the first line of any other library), empty without one.
    pub ours_us_per_step: Option<f64>,
    /// `sb3_us_per_step / ours_us_per_step`, empty unless both are given and it is finite and
    /// positive.
    pub ratio: Option<f64>,
}

impl CostRatio {
    /// Whether the line's ratio is its times' (given exactly where that is finite and
    /// positive) and its times are finite.
    fn consistent(&self) -> bool {
        let ratio = ratio_of(self.sb3_us_per_step, self.ours_us_per_step);
        let finite = [self.sb3_us_per_step, self.ours_us_per_step]
            .iter()
            .all(|t| t.is_none_or(f64::is_finite));
        finite && ratio == self.ratio
    }
}

/// SB3's time per step over ours, where both are given and it is finite and positive.
fn ratio_of(sb3: Option<f64>, ours: Option<f64>) -> Option<f64> {
    let ratio = sb3? / ours?;
    (ratio.is_finite() && ratio > 0.0).then_some(ratio)
}

/// Per learner of `rows` (in learner order), the first time per step of each library and
/// SB3's over ours, where that ratio is finite and positive.
///
/// ```
/// use pbcs::tables::outside::{cost_ratios, UpdateCost};
/// let line = |library: &str, us_per_step| UpdateCost {
///     algo: "td3".parse().unwrap(),
///     library: library.into(),
///     us_per_step,
///     steps: 5000,
///     machine: "m".into(),
/// };
/// let ratios = cost_ratios(&[line("sb3-2.9.2", 2000.0), line("pbcs", 80.0), line("pbcs", 1.0)]);
/// assert_eq!(ratios.len(), 1);
/// assert_eq!(ratios[0].ours_us_per_step, Some(80.0));
/// assert_eq!(ratios[0].ratio, Some(25.0));
/// // Ours alone, or a time of zero, gives no ratio.
/// assert_eq!(cost_ratios(&[line("pbcs", 80.0)])[0].ratio, None);
/// assert_eq!(cost_ratios(&[line("sb3", 2000.0), line("pbcs", 0.0)])[0].ratio, None);
/// ```
pub fn cost_ratios(rows: &[UpdateCost]) -> Vec<CostRatio> {
    let algos: std::collections::BTreeSet<LearnerName> = rows.iter().map(|r| r.algo).collect();
    let first = |algo, library| {
        rows.iter()
            .find(|r| r.algo == algo && Library::of_version(&r.library) == library)
            .map(|r| r.us_per_step)
    };
    algos
        .into_iter()
        .map(|algo| {
            let (sb3, ours) = (first(algo, Library::Sb3), first(algo, Library::Ours));
            CostRatio {
                algo,
                sb3_us_per_step: sb3,
                ours_us_per_step: ours,
                ratio: ratio_of(sb3, ours),
            }
        })
        .collect()
}

/// Reads `outside.cost_ratio.csv`, each line checked: its ratio is its times' where that is
/// finite and positive, and empty otherwise.
pub fn read_cost_ratios(path: &Path) -> Result<Vec<CostRatio>> {
    let lines: Vec<CostRatio> = crate::record::read_records(path)?;
    match lines.iter().find(|l| !l.consistent()) {
        Some(l) => Err(Error::parse(
            path,
            format!(
                "the line of {} gives a ratio that is not SB3's time over ours: {l:?}",
                l.algo
            ),
        )),
        None => Ok(lines),
    }
}

/// The files `s<seed><suffix>` of `dir` (`suffix` `.csv`, `.evals.csv`) with their seeds, in
/// seed order (a file of another name, such as `s01.csv`, is ignored).
fn seed_files(dir: &Path, suffix: &str) -> Result<Vec<(u64, PathBuf)>> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let path = entry.map_err(|e| Error::io(dir, e))?.path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let seed = name
            .strip_prefix('s')
            .and_then(|n| n.strip_suffix(suffix))
            .and_then(|n| n.parse::<u64>().ok())
            .filter(|&seed| path == run_file(dir, seed, suffix));
        out.extend(seed.map(|seed| (seed, path)));
    }
    out.sort();
    Ok(out)
}

/// The rows `s<seed>.csv` of `dir` with their files, in seed order: each file one row whose
/// seed (`seed_of`) is the file's ([`seed_files`]).
fn seed_rows<T: serde::de::DeserializeOwned>(
    dir: &Path,
    seed_of: impl Fn(&T) -> u64,
) -> Result<Vec<(PathBuf, T)>> {
    let mut out = Vec::new();
    for (seed, path) in seed_files(dir, ".csv")? {
        let mut rows: Vec<T> = crate::record::read_records(&path)?;
        let row = match (rows.pop(), rows.is_empty()) {
            (Some(row), true) => row,
            _ => {
                return Err(Error::parse(
                    &path,
                    "an outside run's file holds exactly one row",
                ))
            }
        };
        if seed_of(&row) != seed {
            let message = format!(
                "the row's seed is {}, the file's name says {seed}",
                seed_of(&row)
            );
            return Err(Error::parse(&path, message));
        }
        out.push((path, row));
    }
    Ok(out)
}

fn seeds_text(seeds: impl IntoIterator<Item = u64>) -> String {
    seeds
        .into_iter()
        .map(|s| s.to_string())
        .collect::<Vec<_>>()
        .join(" ")
}

/// Our side of one maze comparison: for each seed of `table`'s cell `<algo>-maze<maze>` with
/// an evaluation at `steps`, whether its greedy episode reached the target
/// ([`crate::runs::SOLVED_AT`]); a seed whose evaluations stop before `steps` is an error.
fn ours_at(
    table: &Experiment,
    results: &Path,
    algo: Algo,
    maze: usize,
    steps: u64,
) -> Result<Vec<(u64, bool)>> {
    let cell = table.cell_at(CellKey::new(Method::new(algo.name())?, Site::Maze(maze)))?;
    let mut out = Vec::new();
    for seed in table.seeds() {
        let path = evals_file(table, results, cell, seed);
        if !path.exists() {
            continue;
        }
        let evals: Vec<EvalRow> = crate::record::read_records(&path)?;
        let at = evals
            .iter()
            .find(|e| e.steps == steps)
            .ok_or_else(|| Error::parse(&path, format!("no greedy evaluation at step {steps}")))?;
        out.push((seed, crate::stats::solved(false, at.success)));
    }
    if out.is_empty() {
        return Err(Error::parse(
            table.cell_dir(results, cell),
            "no run of ours to compare with (no s<seed>.evals.csv)",
        ));
    }
    Ok(out)
}

/// The maze comparisons of every `<results>/outside/sb3/<algo>-maze<N>/` folder against
/// `table` (the results table's experiment), one line per learner then one `pooled` line per
/// maze; empty without SB3 rows. Every SB3 run of a folder must have the same steps.
pub fn maze_comparisons(table: &Experiment, results: &Path) -> Result<Vec<MazeComparison>> {
    let root = outside_dir(results).join("sb3");
    if !root.is_dir() {
        return Ok(Vec::new());
    }
    let folders = sb3_folders(&root)?;
    let mut out: Vec<MazeComparison> = Vec::new();
    for (maze, algo, dir) in &folders {
        let runs: Vec<(PathBuf, MazeRun)> = seed_rows(dir, |r: &MazeRun| r.seed)?;
        let Some((_, first)) = runs.first() else {
            continue;
        };
        let (steps, library) = (first.steps, first.library.clone());
        check_sb3_runs(&runs, *algo, steps, &library)?;
        let ours = ours_at(table, results, *algo, *maze, steps)?;
        let solved = |v: &[(u64, bool)]| {
            v.iter()
                .filter(|(_, s)| *s)
                .map(|(seed, _)| *seed)
                .collect::<Vec<u64>>()
        };
        let sb3: Vec<(u64, bool)> = runs.iter().map(|(_, r)| (r.seed, r.solved_s0)).collect();
        let protocol = runs
            .iter()
            .filter(|(_, r)| r.protocol_successes >= least_successes(r.protocol_episodes))
            .count() as u64;
        let (ours_seeds, sb3_seeds) = (solved(&ours), solved(&sb3));
        let mut line = comparison(
            Scope::One(*algo),
            *maze,
            steps,
            &library,
            [ours.len() as u64, ours_seeds.len() as u64],
            [sb3.len() as u64, sb3_seeds.len() as u64],
            protocol,
        );
        line.ours_seeds = seeds_text(ours_seeds);
        line.sb3_seeds = seeds_text(sb3_seeds);
        out.push(line);
    }
    let pooled = pooled_comparisons(&out)?;
    out.extend(pooled);
    Ok(out)
}

/// The SB3 folders `<algo>-maze<N>` under `root`, sorted by maze, then algorithm; a folder so
/// named whose `<algo>` is not a learner of ours is an error naming it.
fn sb3_folders(root: &Path) -> Result<Vec<(usize, Algo, PathBuf)>> {
    let mut folders: Vec<(usize, Algo, PathBuf)> = Vec::new();
    for entry in std::fs::read_dir(root).map_err(|e| Error::io(root, e))? {
        let path = entry.map_err(|e| Error::io(root, e))?.path();
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or("")
            .to_string();
        let parsed = name
            .split_once("-maze")
            .and_then(|(a, m)| m.parse::<usize>().ok().map(|m| (m, a)));
        if let Some((maze, algo)) = parsed.filter(|_| path.is_dir()) {
            let algo = algo.parse::<Algo>().map_err(|_| {
                Error::parse(
                    &path,
                    format!("`{algo}` is not a learner of ours (`ddpg` or `td3`)"),
                )
            })?;
            folders.push((maze, algo, path));
        }
    }
    folders.sort();
    Ok(folders)
}

/// Every run of one SB3 folder has a valid protocol count and the first run's steps,
/// algorithm and library.
fn check_sb3_runs(
    runs: &[(PathBuf, MazeRun)],
    algo: Algo,
    steps: u64,
    library: &str,
) -> Result<()> {
    for (path, r) in runs {
        if r.protocol_episodes == 0 || r.protocol_successes > r.protocol_episodes {
            return Err(Error::parse(
                path,
                format!(
                    "protocol_successes {} of protocol_episodes {}: need 0 <= successes \
                     <= episodes, episodes > 0",
                    r.protocol_successes, r.protocol_episodes
                ),
            ));
        }
        if r.steps != steps || r.algo != algo || r.library != library {
            return Err(Error::parse(
                path,
                format!("every run of the folder must be {library} {algo} at {steps} steps"),
            ));
        }
    }
    Ok(())
}

/// One pooled line per maze with more than one learner in `lines`.
fn pooled_comparisons(lines_in: &[MazeComparison]) -> Result<Vec<MazeComparison>> {
    let mut out = Vec::new();
    let mazes: std::collections::BTreeSet<usize> = lines_in.iter().map(|c| c.maze).collect();
    for maze in mazes {
        let lines: Vec<&MazeComparison> = lines_in.iter().filter(|c| c.maze == maze).collect();
        if lines.len() < 2 {
            continue;
        }
        if lines
            .iter()
            .any(|c| c.steps != lines[0].steps || c.sb3_library != lines[0].sb3_library)
        {
            return Err(Error::invalid(
                "outside",
                format!(
                    "results/outside/sb3/*-maze{maze}: the learners' runs differ in steps or \
                     library, so they cannot be pooled"
                ),
            ));
        }
        let sum = |f: fn(&MazeComparison) -> u64| lines.iter().map(|c| f(c)).sum::<u64>();
        let pooled = comparison(
            Scope::Pooled,
            maze,
            lines[0].steps,
            &lines[0].sb3_library.clone(),
            [sum(|c| c.ours_n), sum(|c| c.ours_solved)],
            [sum(|c| c.sb3_n), sum(|c| c.sb3_solved)],
            sum(|c| c.sb3_protocol_solved),
        );
        out.push(pooled);
    }
    Ok(out)
}

/// One comparison line from the counts `[n, solved]` of each side (solved seeds left empty).
fn comparison(
    algo: Scope<Algo>,
    maze: usize,
    steps: u64,
    library: &str,
    [on, ok]: [u64; 2],
    [sn, sk]: [u64; 2],
    sb3_protocol_solved: u64,
) -> MazeComparison {
    let interval = |k: u64, n: u64| {
        if n == 0 {
            (f64::NAN, f64::NAN)
        } else {
            wilson(k, n, Z95)
        }
    };
    let ((olo, ohi), (slo, shi)) = (interval(ok, on), interval(sk, sn));
    MazeComparison {
        algo,
        maze,
        steps,
        ours_n: on,
        ours_solved: ok,
        ours_lo: olo,
        ours_hi: ohi,
        ours_seeds: String::new(),
        sb3_library: library.to_string(),
        sb3_n: sn,
        sb3_solved: sk,
        sb3_lo: slo,
        sb3_hi: shi,
        sb3_seeds: String::new(),
        sb3_protocol_solved,
        fisher_p: if on > 0 && sn > 0 {
            fisher_exact(ok, on, sk, sn)
        } else {
            f64::NAN
        },
    }
}

/// The update-cost lines of `<results>/outside/update_cost.csv` (empty without it).
pub fn update_costs(results: &Path) -> Result<Vec<UpdateCost>> {
    let path = outside_dir(results).join("update_cost.csv");
    if path.exists() {
        crate::record::read_records(&path)
    } else {
        Ok(Vec::new())
    }
}

/// Writes `records` to `path` (added to `files`), or removes a table left from earlier rows
/// when there are none.
fn put_or_remove<T: Serialize>(path: &Path, records: &[T], files: &mut Vec<PathBuf>) -> Result<()> {
    if records.is_empty() {
        if path.exists() {
            std::fs::remove_file(path).map_err(|e| Error::io(path, e))?;
        }
        return Ok(());
    }
    crate::record::write_records(path, records)?;
    files.push(path.to_path_buf());
    Ok(())
}

/// Writes `outside.maze.csv`, `outside.pendulum.csv`, `outside.pendulum_sac.csv`,
/// `outside.timing.csv`, `outside.cost_ratio.csv` ([`cost_ratios`]), `outside.pointmaze.csv`
/// and `outside.pointmaze_sb3.csv`
/// ([`sb3_comparisons`]) under `<results>/tables/` from the rows under `<results>/outside/`
/// (PointMaze's: the raw rows of `pointmaze_vanilla`, `pointmaze_her` and `<results>/pointmaze/sb3/`,
/// [`pointmaze_baselines`]) (each only where it has rows; a table without rows any more is
/// removed); `table` is the experiment of our maze side.
/// Returns the files written.
pub fn write_outside_tables(
    table: &Experiment,
    pointmaze_vanilla: &[&Experiment],
    results: &Path,
) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let maze = maze_comparisons(table, results)?;
    put_or_remove(&outside_table(results, "maze"), &maze, &mut files)?;
    let pendulum = pendulum_rows(results)?;
    put_or_remove(&outside_table(results, "pendulum"), &pendulum, &mut files)?;
    let pendulum_sac = pendulum_sac_rows(results)?;
    put_or_remove(
        &outside_table(results, "pendulum_sac"),
        &pendulum_sac,
        &mut files,
    )?;
    let cost = update_costs(results)?;
    put_or_remove(&outside_table(results, "timing"), &cost, &mut files)?;
    put_or_remove(
        &outside_table(results, "cost_ratio"),
        &cost_ratios(&cost),
        &mut files,
    )?;
    let pointmaze = pointmaze_baselines(pointmaze_vanilla, results)?;
    let her = ExperimentName::new("pointmaze_her")?;
    let against_sb3 = match pointmaze_vanilla.iter().find(|e| e.name == her) {
        Some(her) => sb3_comparisons(her, &pointmaze, results)?,
        None => Vec::new(),
    };
    put_or_remove(&outside_table(results, "pointmaze"), &pointmaze, &mut files)?;
    put_or_remove(
        &outside_table(results, "pointmaze_sb3"),
        &against_sb3,
        &mut files,
    )?;
    Ok(files)
}

mod pendulum;
pub use pendulum::{pendulum_rows, pendulum_sac_rows, PendulumRow, PendulumRun, Published, Source};
mod pointmaze;
pub use pointmaze::{
    pointmaze_baselines, sb3_comparisons, Library, PointMazeBaseline, PointMazeSb3Comparison,
    Sb3Eval, SB3_BUDGET,
};

#[cfg(test)]
mod tests;
