//! The README's headline table: the paper's maze and gymnasium-robotics' PointMaze, each
//! number read from a committed table (`results/tables/`), never typed; and docs/pointmaze.md's
//! table of the goal-conditioned learners. `tests/docs.rs` holds the README's block equal to
//! [`headline_markdown`] and the page's to [`goal_baselines_markdown`].

use super::judged::{judged_path, JudgedCell};
use super::outside::{Library, PointMazeBaseline};
use super::{read_table, table_path, CellStats};
use crate::envs::EnvName;
use crate::error::{Error, Result};
use crate::experiment::{CellKey, ExperimentName, Method, Site};
use crate::fmt::human_steps;
use std::fmt::Write as _;
use std::path::Path;

/// The headline tables in Markdown, from the tables under `results`: per maze size of the
/// `table` experiment, the paper's PBCS steps, our DDPG and TD3, and PBCS with the `paper`
/// and `fast` presets (solved / runs, median environment steps of all runs); per PointMaze
/// map, PBCS's chains as gymnasium-robotics judged them on the grid and the held-out grid,
/// and the learners alone (`outside.pointmaze.csv`; our SAC+HER and TD3+HER by SB3's protocol
/// `–` until their grid has a row there). A missing table or cell is an error naming it.
pub fn headline_markdown(results: &Path) -> Result<String> {
    let table = read_table(&table_path(results, ExperimentName::new("table")?))?;
    let chained = read_table(&table_path(
        results,
        ExperimentName::new("goal_conditioned")?,
    ))?;
    let strict = read_table(&table_path(
        results,
        ExperimentName::new("goal_conditioned_strict")?,
    ))?;
    let mut s = maze_table(&table, &chained, &strict)?;
    s.push('\n');
    s.push_str(&paired_line(results)?);
    s.push('\n');
    s.push_str(&pointmaze_table(results)?);
    Ok(s)
}

/// The registered paired comparisons of the goal-conditioned chains with the table's `fast`,
/// pooled over the mazes (`<experiment>.paired.csv`), as one sentence; `–` for a grid not yet
/// paired.
fn paired_line(results: &Path) -> Result<String> {
    let pooled = |name: &str| -> Result<String> {
        let path = super::paired::paired_path(results, ExperimentName::new(name)?);
        if !path.exists() {
            return Ok("–".into());
        }
        let rows: Vec<super::paired::PairedSite> = crate::record::read_records(&path)?;
        let all = rows
            .iter()
            .find(|r| r.site == super::scope::Scope::Pooled)
            .ok_or_else(|| Error::parse(&path, "no pooled row (`all`)"))?;
        let p = match all.p_value {
            p if p < 1e-3 => format!("{p:.1e}"),
            p => super::paired::two_digits(p),
        };
        Ok(format!(
            "fewer in {} of {} pairs ({} more, {} ties), p = {p}",
            all.fewer, all.pairs, all.more, all.ties
        ))
    };
    Ok(format!(
        "Seed by seed against `fast`'s run of the same maze and seed (env steps, phase 1 \
         included;\ntwo-sided exact sign test, registered before the runs):\n\
         GC chain: {};\nGC, 100 tests: {}.\n",
        pooled("goal_conditioned")?,
        pooled("goal_conditioned_strict")?
    ))
}

/// The cell of `method` at `site` in `stats`, or an error naming both.
fn cell(stats: &[CellStats], method: Method, site: Site) -> Result<&CellStats> {
    let key = CellKey::new(method, site);
    stats.iter().find(|c| c.cell == key).ok_or_else(|| {
        Error::parse(
            Path::new("results/tables"),
            format!("no cell of method `{method}` at {site}"),
        )
    })
}

/// `9/10` (solved of runs).
fn solved(c: &CellStats) -> String {
    format!("{}/{}", c.successes, c.n)
}

/// `9/10, 195k` (solved of runs, median environment steps of all runs).
fn solved_steps(c: &CellStats) -> String {
    format!("{}, {}", solved(c), human_steps(c.steps_median))
}

/// A cell of a grid that may still be running: its solved of runs and median steps, `–` where
/// it has no row yet.
fn solved_steps_so_far(stats: &[CellStats], method: Method, site: Site) -> String {
    let key = CellKey::new(method, site);
    stats
        .iter()
        .find(|c| c.cell == key)
        .map_or("–".into(), solved_steps)
}

/// The maze table: the `table` experiment's cells, and the goal-conditioned chain's
/// (`goal_conditioned`, `chained`; tested on 100 episodes, `goal_conditioned_strict`,
/// `strict`).
fn maze_table(stats: &[CellStats], chained: &[CellStats], strict: &[CellStats]) -> Result<String> {
    let sizes = super::distinct(stats.iter().map(|c| c.site));
    let (gc, gc100) = (Method::new("gc")?, Method::new("gc100")?);
    let mut s = String::from(
        "| maze | paper, 1 run | DDPG, 1M | TD3, 1M | PBCS `paper` | PBCS `fast` | GC chain | \
         GC, 100 tests |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    let [pbcs, ddpg, td3, fast] = ["pbcs", "ddpg", "td3", "pbcs_fast"].map(Method::new);
    let (pbcs, ddpg, td3, fast) = (pbcs?, ddpg?, td3?, fast?);
    for &site in &sizes {
        let pbcs = cell(stats, pbcs, site)?;
        // The paper's round figures as it writes them: 5M, not 5.00M.
        let paper = pbcs.paper_steps.map_or("–".into(), |p| {
            let h = human_steps(p as f64);
            h.replace(".00M", "M")
        });
        let label = site.size().map_or(site.to_string(), |n| format!("{n}×{n}"));
        let _ = writeln!(
            s,
            "| {label} | {paper} | {} | {} | {} | **{}** | {} | {} |",
            solved(cell(stats, ddpg, site)?),
            solved(cell(stats, td3, site)?),
            solved_steps(pbcs),
            solved_steps(cell(stats, fast, site)?),
            solved_steps_so_far(chained, gc, site),
            solved_steps_so_far(strict, gc100, site),
        );
    }
    Ok(s)
}

fn pointmaze_table(results: &Path) -> Result<String> {
    let [ddpg, td3, sac_her, td3_her] = ["ddpg", "td3", "sac_her", "td3_her"].map(Method::new);
    let (ddpg, td3, sac_her, td3_her) = (ddpg?, td3?, sac_her?, td3_her?);
    let [grid_name, held_name] = ["pointmaze", "pointmaze_heldout"].map(ExperimentName::new);
    let (grid_name, held_name) = (grid_name?, held_name?);
    let grid = read_table(&table_path(results, grid_name))?;
    let held = read_table(&table_path(results, held_name))?;
    let judged = |name| -> Result<Vec<JudgedCell>> {
        crate::record::read_records(&judged_path(results, name))
    };
    let (grid_judged, held_judged) = (judged(grid_name)?, judged(held_name)?);
    // The goal-conditioned chain's grid: judged where its judge has run.
    let gc_name = ExperimentName::new("pointmaze_gc")?;
    let gc = read_table(&table_path(results, gc_name))?;
    let gc_judged = match judged_path(results, gc_name) {
        p if p.exists() => crate::record::read_records(&p)?,
        _ => Vec::new(),
    };
    let gc_method = Method::new("gc_pm")?;
    let mut chained = String::from(
        "| map | GC chain, in our env | GC chain, judged by gymnasium-robotics |\n\
         | --- | --- | --- |\n",
    );
    let baselines: Vec<PointMazeBaseline> =
        crate::record::read_records(&super::outside::outside_table(results, "pointmaze"))?;
    let mut s = String::from(
        "| map | PBCS, seeds 0–9 | PBCS, held out | DDPG | TD3 | SB3 SAC+HER | SAC+HER | TD3+HER |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    for c in &grid {
        let Site::Env(env) = c.site else { continue };
        let map = env.point_map().map_or(env.into(), <&str>::from);
        let (m, site) = (c.method, c.site);
        let _ = writeln!(
            s,
            "| {map} | **{}** | {} | {} | {} | {} | {} | {} |",
            judged_text(&grid_judged, &grid, m, site)?,
            judged_text(&held_judged, &held, m, site)?,
            baseline_text(&baselines, ddpg, env)?,
            baseline_text(&baselines, td3, env)?,
            baseline_text(&baselines, sac_her, env)?,
            ours_text(&baselines, sac_her, env),
            ours_text(&baselines, td3_her, env),
        );
        let _ = writeln!(
            chained,
            "| {map} | {} | {} |",
            solved_steps_so_far(&gc, gc_method, site),
            judged_so_far(&gc_judged, &gc, gc_method, site),
        );
    }
    s.push('\n');
    s.push_str(&chained);
    Ok(s)
}

/// A judged cell of PointMaze's table: seeds solved by gymnasium-robotics' judge of those run,
/// and the cell's median steps.
fn judged_text(
    cells: &[JudgedCell],
    stats: &[CellStats],
    method: Method,
    site: Site,
) -> Result<String> {
    let stats = cell(stats, method, site)?;
    let j = cells.iter().find(|j| j.cell == stats.cell).ok_or_else(|| {
        Error::parse(
            Path::new("results/tables"),
            format!("{}: not judged", stats.cell),
        )
    })?;
    Ok(format!(
        "{}/{}, {}",
        j.solved,
        j.seeds,
        human_steps(stats.steps_median)
    ))
}

/// A judged cell of a grid that may still be running or unjudged: `–` until its judge has run.
fn judged_so_far(cells: &[JudgedCell], stats: &[CellStats], method: Method, site: Site) -> String {
    judged_text(cells, stats, method, site).unwrap_or_else(|_| "–".into())
}

/// An outside baseline's cell: runs solved, and from how many steps the first was.
fn baseline_text(baselines: &[PointMazeBaseline], method: Method, env: EnvName) -> Result<String> {
    let name: &str = env.into();
    let b = baselines
        .iter()
        .find(|b| b.method == method && b.env == env)
        .ok_or_else(|| {
            Error::parse(
                Path::new("results/tables/outside.pointmaze.csv"),
                format!("no line for {method} on {name}"),
            )
        })?;
    Ok(match b.solved_at_min {
        Some(at) => format!("{}/{} (from {})", b.solved, b.runs, human_steps(at as f64)),
        None => format!("{}/{}", b.solved, b.runs),
    })
}

/// Ours by SB3's protocol, on the env's reset law (`<name>_goals`): runs solved of those with
/// rows (the grid may still be running: `–` where none has a row yet), and the median steps of
/// the solved ones (over as many runs as were solved: the legend says so, and the docs' table
/// names the count; the README's line has no room).
fn ours_text(baselines: &[PointMazeBaseline], method: Method, env: EnvName) -> String {
    let goals = env.goals_task();
    let line = baselines
        .iter()
        .find(|b| b.library == Library::Ours && b.method == method && Some(b.env) == goals);
    match line {
        None => "–".to_string(),
        Some(b) => match b.solved_at_median {
            Some(m) => format!("{}/{}, {}", b.solved, b.runs, human_steps(m as f64)),
            None => format!("{}/{}", b.solved, b.runs),
        },
    }
}

/// `40k (median of 2)`: a median of the steps to solve with the number of runs it is over
/// (`30k` for one run: its own steps).
fn median_of(median: u64, runs: u64) -> String {
    match runs {
        1 => human_steps(median as f64),
        n => format!("{} (median of {n})", human_steps(median as f64)),
    }
}

/// The learners by SB3's protocol on gymnasium-robotics' own resets, from the lines of
/// `outside.pointmaze.csv` in Markdown: per map, SB3's SAC+HER, then ours (`<name>_goals`), each
/// with its runs, the most steps a run trained, the runs solved (an evaluation with 95 of 100),
/// the fewest and the median steps of the solved ones and the best evaluation of the others
/// (`–` where there is none). Our learners alone on PBCS's task are not in it.
pub fn goal_baselines_markdown(lines: &[PointMazeBaseline]) -> String {
    let mut by_protocol: Vec<&PointMazeBaseline> = lines
        .iter()
        .filter(|b| b.library == Library::Sb3 || b.env.goal_resets())
        .collect();
    by_protocol.sort_by_key(|b| (b.env.point_map(), b.library == Library::Ours));
    let mut s = String::from(
        "| map | learner | runs | steps at most | solved | fewest steps to solve | \
         median steps to solve | best evaluation of the others |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    let steps = |at: Option<u64>| at.map_or("–".into(), |at| human_steps(at as f64));
    for b in by_protocol {
        let name: &str = b.env.into();
        let map = b.env.point_map().map_or(name, <&str>::from);
        let learner = b.method.as_str().to_uppercase().replace('_', "+");
        let learner = match b.library {
            Library::Sb3 => format!("SB3's {learner}"),
            Library::Ours => learner,
        };
        let best = b
            .best_unsolved
            .map_or("–".into(), |f| format!("{:.0} %", 100.0 * f));
        let _ = writeln!(
            s,
            "| {map} | {learner} | {} | {} | {} | {} | {} | {best} |",
            b.runs,
            human_steps(b.steps_max as f64),
            b.solved,
            steps(b.solved_at_min),
            b.solved_at_median
                .map_or("–".into(), |m| median_of(m, b.solved)),
        );
    }
    s
}
