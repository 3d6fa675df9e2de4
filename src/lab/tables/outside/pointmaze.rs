//! PointMaze's learner baselines (issues 35 and 48) as one table, `outside.pointmaze.csv`: our
//! DDPG and TD3 alone on PBCS's PointMaze task (the experiment
//! `experiments/pointmaze_vanilla.toml`), our SAC and TD3 with HER on gymnasium-robotics' own
//! task by SB3's protocol (`experiments/pointmaze_her.toml`), their raw rows checked as every
//! sweep's, with each run's `s<seed>.evals.csv`,
//! and Stable-Baselines3's SAC+HER in gymnasium-robotics' own PointMaze
//! (`python/benches/sb3_pointmaze.py`: `<results>/pointmaze/sb3/sac_her-pointmaze_<map>/`,
//! `s<seed>.evals.csv` as the run goes, `s<seed>.csv` once it ended). An SB3 run stopped before
//! its end counts with the evaluations it made (one stopped before its first is left out), and
//! the table says how many runs ended and how many of SB3's were resumed from a checkpoint.

use super::{seed_files, seed_rows, seeds_text};
use crate::envs::EnvName;
use crate::error::{Error, Result};
use crate::experiment::run_file;
use crate::experiment::{Cell, Experiment, Method, RawRow};
use crate::vanilla::EvalRow;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// One evaluation of an SB3 run (`s<seed>.evals.csv`): 100 episodes from the env's own resets.
/// It solves the map by the package's one rule ([`crate::stats::solved`]: 95 of 100).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sb3Eval {
    /// Environment steps of training before it.
    pub env_steps: u64,
    /// Episodes that ended in `info["success"]`.
    pub successes: u64,
    /// Episodes played.
    pub episodes: u64,
    /// Wall clock since training started (not deterministic).
    pub wall_seconds: f64,
}

/// Whose runs a line counts (`outside.pointmaze.csv`; the cost table's `pbcs` and
/// `sb3-<version>`).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    PartialOrd,
    Ord,
    Serialize,
    Deserialize,
    strum::IntoStaticStr,
    strum::Display,
)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum Library {
    /// Ours (this package's learners).
    Ours,
    /// Stable-Baselines3's.
    Sb3,
}

impl Library {
    /// The library a version string names: `sb3-<version>` (or `sb3`) is SB3's, any other
    /// (`pbcs`) ours.
    pub fn of_version(version: &str) -> Library {
        if version.starts_with("sb3") {
            Library::Sb3
        } else {
            Library::Ours
        }
    }
}

impl Sb3Eval {
    /// Whether this evaluation solved the map: at least [`crate::stats::least_successes`] of
    /// its episodes.
    pub fn solves(&self) -> bool {
        self.successes >= crate::stats::least_successes(self.episodes)
    }
}

/// One line of `outside.pointmaze.csv`: one learner on one map.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PointMazeBaseline {
    /// `ddpg`, `td3`, `sac_her`, `td3_her` (ours) or `sac_her` (SB3).
    pub method: Method,
    /// `ours` or `sb3`.
    pub library: Library,
    /// The registry's name of the task (`pointmaze_umaze`; `pointmaze_umaze_goals` for ours
    /// with the env's own resets; SB3's runs, named by their map, play those resets too).
    pub env: EnvName,
    /// Runs with rows.
    pub runs: u64,
    /// Of them, ended (their budget spent, or SB3's stopped at a solving evaluation).
    pub ended: u64,
    /// SB3's: of them, resumed from a checkpoint at least once (its `s<seed>.resumes.csv`;
    /// a resumed SB3 run is not the uninterrupted one). Empty for ours: a resumed run of ours
    /// gives the bytes of the uncut run, and its row does not record whether it was cut.
    pub resumed: Option<u64>,
    /// The most environment steps a run trained.
    pub steps_max: u64,
    /// Runs whose policy solves the map: ours alone on PBCS's task, a final greedy episode
    /// from the start that reaches the goal; SB3 and ours by its protocol
    /// (`train.stop_at_successes`), an evaluation that solves it
    /// ([`crate::stats::least_successes`]: 95 of 100).
    pub solved: u64,
    /// By SB3's protocol: the fewest environment steps at which a run solved it (ours alone on
    /// PBCS's task: never set).
    pub solved_at_min: Option<u64>,
    /// By SB3's protocol: the median of those steps over the solved runs (the mean of the two
    /// middle ones for an even count, rounded down).
    pub solved_at_median: Option<u64>,
    /// By SB3's protocol: the best evaluation of the runs that did not solve it (fraction of
    /// its episodes), none where every run did.
    pub best_unsolved: Option<f64>,
    /// Runs with at least one successful evaluation episode.
    pub reached: u64,
    /// The best evaluation of any run: success fraction (ours: 0 or 1; SB3: successes / 100).
    pub best: f64,
    /// The steps of that evaluation (the earliest among ties); none where no evaluation
    /// succeeded.
    pub best_at: Option<u64>,
    /// The seeds, space-separated.
    pub seeds: String,
}

/// The lines of `outside.pointmaze.csv`: our learners from the raw rows of each of `vanilla`
/// (the experiments `pointmaze_vanilla` and `pointmaze_her`, those given) under `results`,
/// then SB3's from `<results>/pointmaze/sb3/` (none without that folder); each experiment's
/// lines sorted by `<method>-<env>`.
pub fn pointmaze_baselines(
    vanilla: &[&Experiment],
    results: &Path,
) -> Result<Vec<PointMazeBaseline>> {
    let mut out = Vec::new();
    for &exp in vanilla {
        let rows = crate::experiment::read_raw(exp, results)?;
        let mut cells: Vec<&Cell> = exp.cells.iter().collect();
        cells.sort_by_key(|a| a.id);
        for cell in cells {
            let runs: Vec<&RawRow> = rows.iter().filter(|r| r.cell == cell.id).collect();
            if !runs.is_empty() {
                out.push(vanilla_line(exp, cell, &runs, results)?);
            }
        }
    }
    for f in folders(
        &results.join("pointmaze").join("sb3"),
        &[Method::new("sac_her")?],
    )? {
        out.push(sb3_line(&f)?);
    }
    Ok(out)
}

/// One learner's folder `<method>-<env>`.
struct Folder {
    method: Method,
    env: EnvName,
    dir: PathBuf,
}

/// The folders `<method>-<env>` of `root` (none without `root`), sorted by name: every folder
/// there must name one of `methods` and a PointMaze map of the registry; files are left alone.
fn folders(root: &Path, methods: &[Method]) -> Result<Vec<Folder>> {
    if !root.is_dir() {
        return Ok(Vec::new());
    }
    let mut found = Vec::new();
    for entry in std::fs::read_dir(root).map_err(|e| Error::io(root, e))? {
        let dir = entry.map_err(|e| Error::io(root, e))?.path();
        if !dir.is_dir() {
            continue;
        }
        let name = dir.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let parsed = name.split_once('-').and_then(|(m, env)| {
            let (m, env) = (m.parse::<Method>().ok()?, env.parse::<EnvName>().ok()?);
            (methods.contains(&m) && env.point_map().is_some()).then_some((m, env))
        });
        let Some((method, env)) = parsed else {
            let why = format!(
                "not a folder <method>-pointmaze_<map> with a method of {methods:?} and a map \
                 of the registry"
            );
            return Err(Error::parse(&dir, why));
        };
        found.push(Folder {
            method,
            env,
            dir: dir.clone(),
        });
    }
    found.sort_by(|a, b| a.dir.cmp(&b.dir));
    Ok(found)
}

/// An error naming a learner's folder that holds no run.
fn no_runs(dir: &Path) -> Error {
    Error::parse(
        dir,
        "holds no run (remove the folder, or run a seed into it)",
    )
}

/// Our learner's line from one cell's raw rows `runs` (read and checked as every sweep's),
/// each checked against its own evaluations: in order, successes in [0, 1], the last at the
/// run's last step with the row's success rate; by SB3's protocol (the cell's
/// `train.stop_at_successes`), none solving before the last.
fn vanilla_line(
    exp: &Experiment,
    cell: &Cell,
    runs: &[&RawRow],
    results: &Path,
) -> Result<PointMazeBaseline> {
    let protocol = match &cell.job {
        crate::experiment::Job::Vanilla(j) => j.train.stop_at_successes.is_some(),
        crate::experiment::Job::Pbcs(_) => false,
    };
    let (mut best, mut reached) = ((0.0f32, u64::MAX), 0);
    let mut solved_at = Vec::new();
    let mut best_unsolved: Option<f32> = None;
    for r in runs {
        let path = crate::experiment::evals_file(exp, results, cell, r.seed);
        let evals: Vec<EvalRow> = crate::record::read_records(&path)?;
        let in_order = evals.windows(2).all(|w| w[0].steps < w[1].steps)
            && evals.iter().all(|e| (0.0..=1.0).contains(&e.success));
        let stops_at_solving = !protocol
            || evals[..evals.len().saturating_sub(1)]
                .iter()
                .all(|e| !crate::stats::solved(false, e.success));
        let agrees = in_order
            && stops_at_solving
            && evals
                .last()
                .is_some_and(|e| e.steps == r.env_steps && e.success == r.success_rate);
        if !agrees {
            let why = format!(
                "does not agree with its row (in order, successes in [0, 1]; the last at {} \
                 steps with success {}; by SB3's protocol, none solving before it)",
                r.env_steps, r.success_rate
            );
            return Err(Error::parse(&path, why));
        }
        let run_best = evals.iter().map(|e| e.success).fold(0.0, f32::max);
        if protocol && r.solved {
            solved_at.push(r.env_steps);
        } else if protocol {
            best_unsolved = Some(best_unsolved.map_or(run_best, |b| b.max(run_best)));
        }
        reached += u64::from(run_best > 0.0);
        let at = evals
            .iter()
            .find(|e| e.success == run_best)
            .map_or(u64::MAX, |e| e.steps);
        if run_best > best.0 || (run_best == best.0 && at < best.1) {
            best = (run_best, at);
        }
    }
    Ok(PointMazeBaseline {
        method: cell.method,
        library: Library::Ours,
        env: cell.site.env(),
        runs: runs.len() as u64,
        ended: runs.len() as u64,
        resumed: None,
        steps_max: runs.iter().map(|r| r.env_steps).max().unwrap_or(0),
        solved: if protocol {
            solved_at.len() as u64
        } else {
            runs.iter().filter(|r| r.success_rate >= 1.0).count() as u64
        },
        solved_at_min: solved_at.iter().copied().min(),
        solved_at_median: median_steps(&mut solved_at),
        best_unsolved: best_unsolved.map(decimal),
        reached,
        best: decimal(best.0),
        best_at: (best.0 > 0.0).then_some(best.1),
        seeds: seeds_text(runs.iter().map(|r| r.seed)),
    })
}

/// A success fraction of the evaluations (an `f32`) as the decimal it prints as: 0.57, not
/// 0.5699999928474426.
fn decimal(x: f32) -> f64 {
    x.to_string().parse().unwrap_or(f64::from(x))
}

/// The median of `steps` (the mean of the two middle ones for an even count, rounded down);
/// none when empty.
fn median_steps(steps: &mut [u64]) -> Option<u64> {
    steps.sort_unstable();
    let n = steps.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(steps[n / 2]),
        _ => Some((steps[n / 2 - 1] + steps[n / 2]) / 2),
    }
}

/// The seeds of the files `s<seed>.evals.csv` of `dir`, sorted.
fn evals_seeds(dir: &Path) -> Result<Vec<u64>> {
    Ok(seed_files(dir, ".evals.csv")?
        .into_iter()
        .map(|(seed, _)| seed)
        .collect())
}

/// One SB3 run's evaluations, checked: 100 episodes each, successes within them, every 10 000
/// steps in order, none after one that solved (the run stops there).
fn sb3_evals(dir: &Path, seed: u64) -> Result<Vec<Sb3Eval>> {
    let path = run_file(dir, seed, ".evals.csv");
    let evals: Vec<Sb3Eval> = crate::record::read_records(&path)?;
    for (i, e) in evals.iter().enumerate() {
        let after_solved = i > 0 && evals[i - 1].solves();
        if e.episodes != 100
            || e.successes > e.episodes
            || e.env_steps != 10_000 * (i as u64 + 1)
            || after_solved
        {
            let why = format!(
                "evaluation {} ({} successes of {} episodes at {} steps): 100 episodes every \
                 10 000 steps expected, and none after one with {} successes (it solved the map)",
                i + 1,
                e.successes,
                e.episodes,
                e.env_steps,
                crate::stats::least_successes(100)
            );
            return Err(Error::parse(&path, why));
        }
    }
    Ok(evals)
}

/// SB3's line from one folder: every run's evaluations; a run ended where its `s<seed>.csv`
/// exists, and then it must agree with them (its best, and its stop at a solving evaluation).
fn sb3_line(f: &Folder) -> Result<PointMazeBaseline> {
    let (method, env, dir) = (f.method, f.env, f.dir.as_path());
    let ended: Vec<(PathBuf, Sb3Row)> = seed_rows(dir, |r: &Sb3Row| r.seed)?;
    if let Some((path, _)) = ended.iter().find(|(_, r)| r.algo != method || r.map != env) {
        return Err(Error::parse(
            path,
            format!("not a run of {method} on {}", env.name()),
        ));
    }
    let mut runs = Vec::new();
    for seed in evals_seeds(dir)? {
        let evals = sb3_evals(dir, seed)?;
        let row = ended.iter().find(|(_, r)| r.seed == seed);
        // A run stopped before its first evaluation has nothing to say yet: left out.
        if evals.is_empty() && row.is_none() {
            continue;
        }
        runs.push(sb3_run(seed, &evals, row)?);
    }
    if let Some((path, _)) = ended
        .iter()
        .find(|(_, r)| !runs.iter().any(|s| s.seed == r.seed))
    {
        return Err(Error::parse(path, "an ended run without its evaluations"));
    }
    if runs.is_empty() {
        return Err(no_runs(dir));
    }
    let best = runs
        .iter()
        .map(|r| (r.top, r.top_at))
        .max_by_key(|&(top, at)| (top, std::cmp::Reverse(at)))
        .unwrap_or((0, 0));
    Ok(PointMazeBaseline {
        method,
        library: Library::Sb3,
        env,
        runs: runs.len() as u64,
        ended: ended.len() as u64,
        resumed: Some(
            runs.iter()
                .filter(|r| run_file(dir, r.seed, ".resumes.csv").exists())
                .count() as u64,
        ),
        steps_max: runs.iter().map(|r| r.steps).max().unwrap_or(0),
        solved: runs.iter().filter(|r| r.solved_at.is_some()).count() as u64,
        solved_at_min: runs.iter().filter_map(|r| r.solved_at).min(),
        solved_at_median: median_steps(
            &mut runs.iter().filter_map(|r| r.solved_at).collect::<Vec<_>>(),
        ),
        best_unsolved: runs
            .iter()
            .filter(|r| r.solved_at.is_none())
            .map(|r| r.top as f64 / 100.0)
            .reduce(f64::max),
        reached: runs.iter().filter(|r| r.top > 0).count() as u64,
        best: best.0 as f64 / 100.0,
        best_at: (best.0 > 0).then_some(best.1),
        seeds: seeds_text(runs.iter().map(|r| r.seed)),
    })
}

/// One SB3 run's evaluations summed up.
struct Sb3Run {
    seed: u64,
    /// The steps of its last evaluation.
    steps: u64,
    /// Its best successes, and the steps of their first evaluation (0 when none succeeded:
    /// the script's own convention).
    top: u64,
    top_at: u64,
    /// The steps of its first evaluation that solved the map ([`Sb3Eval::solves`]).
    solved_at: Option<u64>,
}

/// Sums up one run's `evals`; its ended row, if any, must agree with them.
fn sb3_run(seed: u64, evals: &[Sb3Eval], row: Option<&(PathBuf, Sb3Row)>) -> Result<Sb3Run> {
    let top = evals.iter().map(|e| e.successes).max().unwrap_or(0);
    let top_at = evals
        .iter()
        .find(|e| top > 0 && e.successes == top)
        .map_or(0, |e| e.env_steps);
    let run = Sb3Run {
        seed,
        steps: evals.last().map_or(0, |e| e.env_steps),
        top,
        top_at,
        solved_at: evals.iter().find(|e| e.solves()).map(|e| e.env_steps),
    };
    if let Some((path, r)) = row {
        let agrees = r.library.starts_with("sb3-")
            && r.best_successes == top
            && r.best_at_steps == top_at
            && r.solved == run.solved_at.is_some()
            && r.env_steps == run.steps;
        if !agrees {
            let why = format!(
                "does not agree with s{seed}.evals.csv (best {top} at {top_at}, last at {})",
                run.steps
            );
            return Err(Error::parse(path, why));
        }
    }
    Ok(run)
}

/// The row an SB3 run writes when it ends (`s<seed>.csv`), the fields checked here.
#[derive(Debug, Clone, Deserialize)]
struct Sb3Row {
    library: String,
    algo: Method,
    map: EnvName,
    seed: u64,
    env_steps: u64,
    solved: bool,
    best_successes: u64,
    best_at_steps: u64,
}

/// SB3's budget on PointMaze (`python/benches/sb3_pointmaze.py --steps`): our runs by its
/// protocol are compared with its runs as they stood at this many steps.
pub const SB3_BUDGET: u64 = 500_000;

/// One line of `outside.pointmaze_sb3.csv`: our learner by SB3's protocol against SB3's
/// SAC+HER on one map, runs solved within [`SB3_BUDGET`] steps (issue 48, point 4).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PointMazeSb3Comparison {
    /// Our method (`sac_her`).
    pub method: Method,
    /// Our task (`pointmaze_umaze_goals`).
    pub env: EnvName,
    /// SB3's map folder (`pointmaze_umaze`).
    pub sb3_env: EnvName,
    /// The steps both are judged at.
    pub budget: u64,
    /// Our runs with rows.
    pub ours_n: u64,
    /// Of them, solved (an evaluation with 95 of 100) within the budget.
    pub ours_solved: u64,
    /// Their seeds, space-separated.
    pub ours_seeds: String,
    /// SB3's runs (every one ended at its budget or solving).
    pub sb3_n: u64,
    /// Of them, solved.
    pub sb3_solved: u64,
    /// Two-sided p-value of Fisher's exact test, ours against SB3.
    pub fisher_p: f64,
}

/// The lines of `outside.pointmaze_sb3.csv`: for each method of ours that SB3 also ran
/// (`sac_her`), on each of our `_goals` tasks whose map SB3 ran, from `lines` (the lines of
/// [`pointmaze_baselines`]) and our raw rows under `results` (`her`: the experiment
/// `pointmaze_her`). A map where an SB3 run has not ended is left out; a run beyond
/// [`SB3_BUDGET`] steps is an error. (The registered comparison is UMaze's; the other maps'
/// lines are reported as not registered.)
pub fn sb3_comparisons(
    her: &Experiment,
    lines: &[PointMazeBaseline],
    results: &Path,
) -> Result<Vec<PointMazeSb3Comparison>> {
    let rows = crate::experiment::read_raw(her, results)?;
    let mut out = Vec::new();
    for ours in lines.iter().filter(|l| l.library == Library::Ours) {
        if !ours.env.goal_resets() {
            continue;
        }
        let map = ours.env.fixed_task();
        let Some(sb3) = lines
            .iter()
            .find(|l| l.library == Library::Sb3 && l.method == ours.method && l.env == map)
        else {
            continue;
        };
        if sb3.steps_max > SB3_BUDGET {
            let why = format!(
                "SB3's {} on {}: a run of {} steps, beyond the protocol's {SB3_BUDGET}",
                sb3.method,
                map.name(),
                sb3.steps_max
            );
            return Err(Error::parse(results.join("pointmaze").join("sb3"), why));
        }
        // While an SB3 run of the map is still going, its outcome is not known: no comparison
        // there yet (its evaluations so far show in `outside.pointmaze.csv`).
        if sb3.ended != sb3.runs {
            continue;
        }
        let runs: Vec<&RawRow> = rows
            .iter()
            .filter(|r| r.method == ours.method && r.site.env() == ours.env)
            .collect();
        let solved: Vec<&&RawRow> = runs
            .iter()
            .filter(|r| r.solved && r.env_steps <= SB3_BUDGET)
            .collect();
        let (k1, n1, k2, n2) = (solved.len() as u64, runs.len() as u64, sb3.solved, sb3.runs);
        out.push(PointMazeSb3Comparison {
            method: ours.method,
            env: ours.env,
            sb3_env: map,
            budget: SB3_BUDGET,
            ours_n: n1,
            ours_solved: k1,
            ours_seeds: seeds_text(solved.iter().map(|r| r.seed)),
            sb3_n: n2,
            sb3_solved: k2,
            fisher_p: if n1 > 0 && n2 > 0 {
                crate::stats::fisher_exact(k1, n1, k2, n2)
            } else {
                f64::NAN
            },
        });
    }
    Ok(out)
}
