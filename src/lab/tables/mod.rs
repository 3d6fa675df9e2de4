//! Per-cell statistics of an experiment (`results/tables/<experiment>.csv`): what every table,
//! figure and statistical claim is computed from.
//!
//! The tables are produced by `pbcs aggregate` with polars (the `polars` cargo feature, see
//! [`crate::aggregate`]); this module holds their row type, reads and writes them, and
//! computes the same statistics in plain Rust, which the aggregation checks polars against
//! and `pbcs table` (one method, no polars) writes directly.

pub mod cost;
pub mod curves;
pub mod headline;
pub mod judged;
pub mod outside;
pub mod paired;
pub mod phases;
pub mod routes;
pub mod scaling;
pub mod scope;
pub mod statistics;

use crate::error::{Error, Result};
use crate::experiment::{CellKey, Experiment, ExperimentName, Method, RawRow, Site};
use crate::stats::median;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

pub use statistics::{CellStats, Runs};

/// The `\res` numbers of a table written beside an experiment's (`judged`, `paired`,
/// `phases`), where it exists: `fields(row)` gives a row's key prefix and its fields, each
/// becoming the key `<prefix>:<field>`.
pub(crate) fn table_numbers<T: serde::de::DeserializeOwned, const N: usize>(
    path: &Path,
    fields: impl Fn(&T) -> (String, [(&'static str, String); N]),
) -> Result<Vec<(String, String)>> {
    if !path.exists() {
        return Ok(Vec::new());
    }
    let rows: Vec<T> = crate::record::read_records(path)?;
    Ok(rows
        .iter()
        .flat_map(|r| {
            let (prefix, fields) = fields(r);
            fields.map(|(f, v)| (format!("{prefix}:{f}"), v))
        })
        .collect())
}

/// The distinct items of `items` in the order they first appear: a grouping that does not
/// depend on rows coming sorted (`Vec::dedup` merges only neighbours).
///
/// ```
/// use pbcs::tables::distinct;
/// assert_eq!(distinct(["b", "a", "b", "c", "a"]), ["b", "a", "c"]);
/// ```
pub fn distinct<T: PartialEq>(items: impl IntoIterator<Item = T>) -> Vec<T> {
    let mut out = Vec::new();
    for item in items {
        if !out.contains(&item) {
            out.push(item);
        }
    }
    out
}

/// Where an experiment's table lives under `results`.
pub fn table_path(results: &Path, experiment: ExperimentName) -> PathBuf {
    results.join("tables").join(format!("{experiment}.csv"))
}

/// Reads a table written by [`write_table`].
pub fn read_table(path: &Path) -> Result<Vec<CellStats>> {
    let mut reader = csv::Reader::from_path(path).map_err(|e| {
        Error::parse(
            path,
            format!("{e} (run `make figures` to aggregate the raw results)"),
        )
    })?;
    let header = reader.headers().map_err(|e| Error::csv(path, e))?.clone();
    let cells: Vec<CellStats> = reader
        .deserialize()
        .collect::<std::result::Result<Vec<_>, _>>()
        .map_err(|e| Error::csv_in(path, e, &header))?;
    for (i, c) in cells.iter().enumerate() {
        check_counts(c).map_err(|why| Error::parse(path, format!("line {}: {why}", i + 2)))?;
    }
    Ok(cells)
}

/// A cell's counts as aggregation writes them: at least one run, no more successes than runs,
/// the rate their quotient and the Wilson interval theirs, the steps finite and not negative.
fn check_counts(c: &CellStats) -> std::result::Result<(), String> {
    if c.n == 0 || c.successes > c.n {
        return Err(format!("{} successes of {} runs", c.successes, c.n));
    }
    let (lo, hi) = crate::stats::wilson(c.successes, c.n, crate::stats::Z95);
    let rate = c.successes as f64 / c.n as f64;
    for (column, got, want) in [
        ("success_rate", c.success_rate, rate),
        ("wilson_lo", c.wilson_lo, lo),
        ("wilson_hi", c.wilson_hi, hi),
    ] {
        if (got - want).abs().is_nan() || (got - want).abs() > 1e-9 {
            return Err(format!(
                "{column} is {got}, but {} successes of {} runs give {want}",
                c.successes, c.n
            ));
        }
    }
    let steps = [
        c.steps_median,
        c.steps_q1,
        c.steps_q3,
        c.steps_min,
        c.steps_max,
    ];
    if steps.iter().any(|s| !(s.is_finite() && *s >= 0.0)) {
        return Err(format!("steps not finite and non-negative: {steps:?}"));
    }
    Ok(())
}

/// The table of `exp` is its raw rows' under `results`: what [`cell_stats`] computes from them,
/// cell for cell and column for column (as written: a table is `pbcs aggregate`'s output of the
/// plain computation). A table left from rows since removed or edited, a row of the table
/// edited, duplicated or dropped, is an error naming the first cell and column that differ,
/// not figures drawn over a grid that says otherwise.
pub fn check_against_rows(
    exp: &crate::experiment::Experiment,
    results: &Path,
    stats: &[CellStats],
) -> Result<()> {
    let rows = crate::experiment::read_raw(exp, results)?;
    let path = table_path(results, exp.name);
    let want = cell_stats(exp, &rows);
    let text = |cells: &[CellStats]| -> Vec<Vec<String>> {
        let mut w = csv::Writer::from_writer(Vec::new());
        for c in cells {
            // A CellStats always serialises (its fields are plain values).
            let _ = w.serialize(c);
        }
        let bytes = w.into_inner().unwrap_or_default();
        let mut r = csv::Reader::from_reader(bytes.as_slice());
        let header: Vec<String> = r
            .headers()
            .map_or(Vec::new(), |h| h.iter().map(String::from).collect());
        let mut lines = vec![header];
        lines.extend(
            r.records()
                .flatten()
                .map(|rec| rec.iter().map(String::from).collect()),
        );
        lines
    };
    let (got, want_text) = (text(stats), text(&want));
    if got == want_text {
        return Ok(());
    }
    let header = want_text.first().cloned().unwrap_or_default();
    let why = match (1..got.len().max(want_text.len())).find(|&i| got.get(i) != want_text.get(i)) {
        Some(i) => match (got.get(i), want_text.get(i)) {
            (Some(g), Some(w)) => {
                let k = (0..g.len()).find(|&k| g.get(k) != w.get(k)).unwrap_or(0);
                format!(
                    "line {}: {} {} is {}, its raw rows give {}",
                    i + 1,
                    w.get(1).map_or("", String::as_str),
                    header.get(k).map_or("?", String::as_str),
                    g.get(k).map_or("", String::as_str),
                    w.get(k).map_or("", String::as_str)
                )
            }
            (Some(g), None) => format!(
                "line {}: {} has no raw rows (a row the table holds that the rows do not)",
                i + 1,
                g.get(1).map_or("", String::as_str)
            ),
            _ => format!(
                "the table has {} cells, its raw rows give {}",
                stats.len(),
                want.len()
            ),
        },
        None => "its columns are not the ones written".to_string(),
    };
    Err(Error::parse(
        &path,
        format!("{why}: run `pbcs aggregate` (`make figures` does) so that the table is the rows'"),
    ))
}

/// The cells as a markdown table: solved k/n, Wilson interval, median and quartile steps, the
/// paper's figure (S solved, F failed). What `pbcs figures` prints.
pub fn markdown(stats: &[CellStats]) -> String {
    use crate::fmt::human_steps;
    let mut s = String::from(
        "| cell | solved | Wilson 95 % | env steps median [q1, q3] | paper |\n\
         | --- | --- | --- | --- | --- |\n",
    );
    for c in stats {
        let paper = c.paper_steps.map_or("-".into(), |p| {
            format!(
                "{} {}",
                human_steps(p as f64),
                if c.paper_solved == Some(true) {
                    "S"
                } else {
                    "F"
                }
            )
        });
        s.push_str(&format!(
            "| {} | {}/{} | [{:.2}, {:.2}] | {} [{}, {}] | {paper} |\n",
            c.cell,
            c.successes,
            c.n,
            c.wilson_lo,
            c.wilson_hi,
            human_steps(c.steps_median),
            human_steps(c.steps_q1),
            human_steps(c.steps_q3),
        ));
    }
    s
}

/// A one-method grid (`pbcs table`) as a markdown table, one row per maze: solved k/n and its
/// Wilson interval, environment steps median [min, max], the paper's PBCS steps and the
/// ratio of our median to them, median skills and median wall seconds (from `timings`,
/// `-` where a cell has none).
pub fn grid_markdown(stats: &[CellStats], timings: &[CellTiming]) -> String {
    use crate::fmt::human_steps;
    let mut s = String::from(
        "| maze | solved | Wilson 95 % | env steps median [min, max] | paper | median / paper | skills, median | wall s, median |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    for c in stats {
        let wall = timings
            .iter()
            .find(|t| t.cell == c.cell)
            .map_or("-".into(), |t| format!("{:.0}", t.wall_median_s));
        s.push_str(&format!(
            "| {} | {}/{} | [{:.2}, {:.2}] | {} [{}, {}] | {} | {} | {} | {wall} |\n",
            c.site,
            c.successes,
            c.n,
            c.wilson_lo,
            c.wilson_hi,
            human_steps(c.steps_median),
            human_steps(c.steps_min),
            human_steps(c.steps_max),
            c.paper_steps.map_or("-".into(), |p| human_steps(p as f64)),
            c.paper_steps
                .map_or("-".into(), |p| format!("{:.2}", c.steps_median / p as f64)),
            c.skills_median,
        ));
    }
    s
}

/// An experiment's cells as a markdown table with one row per maze and one column per method
/// (its label): solved k/n with the Wilson interval, the median environment steps, and how
/// many of the cell's chains reached the target in every evaluation episode (from the
/// experiment's `chains.csv` rows, `runs`); then one line naming each run whose chain did not
/// (its success in percent), or saying that none did. What `docs/results.md` quotes for the
/// held-out grid (`tests/docs.rs` holds the two equal).
pub fn methods_by_maze_markdown(
    stats: &[CellStats],
    runs: &[crate::criteria::ChainSuccess],
) -> String {
    use crate::fmt::human_steps;
    let mut labels: Vec<(Method, &str)> = Vec::new();
    let mut mazes: Vec<Site> = Vec::new();
    for c in stats {
        if !labels.iter().any(|(m, _)| *m == c.method) {
            labels.push((c.method, &c.label));
        }
        if !mazes.contains(&c.site) {
            mazes.push(c.site);
        }
    }
    let mut s = String::from("| size |");
    for (_, label) in &labels {
        s.push_str(&format!(
            " {label}: solved, Wilson 95 %, median steps, chains at 100 % |"
        ));
    }
    s.push_str("\n| --- |");
    s.push_str(&" --- |".repeat(labels.len()));
    s.push('\n');
    for maze in &mazes {
        s.push_str(&format!("| {maze} |"));
        for (method, _) in &labels {
            match stats
                .iter()
                .find(|c| c.site == *maze && c.method == *method)
            {
                Some(c) => {
                    let cell: Vec<_> = runs.iter().filter(|r| r.cell == c.cell).collect();
                    let perfect = cell.iter().filter(|r| r.success_rate >= 1.0).count();
                    s.push_str(&format!(
                        " {}/{}, [{:.2}, {:.2}], {}, {perfect}/{} |",
                        c.successes,
                        c.n,
                        c.wilson_lo,
                        c.wilson_hi,
                        human_steps(c.steps_median),
                        cell.len()
                    ));
                }
                None => s.push_str(" - |"),
            }
        }
        s.push('\n');
    }
    let below: Vec<String> = runs
        .iter()
        .filter(|r| r.success_rate < 1.0)
        .map(|r| {
            format!(
                "{} size {} seed {} ({:.0} %)",
                r.label,
                r.site,
                r.seed,
                f64::from(r.success_rate) * 100.0
            )
        })
        .collect();
    if below.is_empty() {
        s.push_str("\nEvery chain reached the target in every evaluation episode.\n");
    } else {
        s.push_str(&format!(
            "\nChains below 100 % of their evaluation episodes: {}.\n",
            below.join("; ")
        ));
    }
    s
}

/// Writes a table atomically.
pub fn write_table(path: &Path, rows: &[CellStats]) -> Result<()> {
    crate::record::write_records(path, rows)
}

/// The statistics of each cell of `exp` that has finished runs, in the experiment's cell
/// order, computed in plain Rust from the raw rows ([`CellStats::of`]).
pub fn cell_stats(exp: &Experiment, rows: &[RawRow]) -> Vec<CellStats> {
    exp.cells
        .iter()
        .filter_map(|c| Runs::of(c, rows))
        .map(|runs| CellStats::of(exp, &runs))
        .collect()
}

/// Wall-clock statistics of a cell (beside the table, not in it: not deterministic).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CellTiming {
    /// Cell id.
    pub cell: CellKey,
    /// Runs with a timing file.
    pub n: u64,
    /// Median wall seconds per run.
    pub wall_median_s: f64,
    /// Total wall seconds of the cell's runs.
    pub wall_total_s: f64,
    /// Environment steps per wall second over the cell's runs.
    pub steps_per_s: f64,
}

/// The wall-clock statistics of each cell with timing files.
pub fn cell_timings(exp: &Experiment, results: &Path, rows: &[RawRow]) -> Vec<CellTiming> {
    exp.cells
        .iter()
        .filter_map(|c| {
            let runs: Vec<(f64, u64)> = rows
                .iter()
                .filter(|r| r.cell == c.id)
                .filter_map(|r| {
                    crate::experiment::read_wall_seconds(exp, results, c, r.seed)
                        .map(|s| (s, r.env_steps))
                })
                .collect();
            if runs.is_empty() {
                return None;
            }
            let mut secs: Vec<f64> = runs.iter().map(|r| r.0).collect();
            let total: f64 = secs.iter().sum();
            let steps: u64 = runs.iter().map(|r| r.1).sum();
            Some(CellTiming {
                cell: c.id,
                n: runs.len() as u64,
                wall_median_s: median(&mut secs),
                wall_total_s: total,
                steps_per_s: steps as f64 / total.max(1e-9),
            })
        })
        .collect()
}

/// Refuses a table (`rows`) without the summary written beside it (`summary`): a results
/// folder aggregated before the summary existed would otherwise lose the report's numbers
/// without a word (`\res` prints nothing for an undefined name).
pub(crate) fn summary_beside(
    rows: &std::path::Path,
    summary: &std::path::Path,
) -> crate::Result<()> {
    if rows.exists() && !summary.exists() {
        return Err(crate::Error::parse(
            summary,
            format!(
                "missing beside {}: the report and the figures read it; run `pbcs aggregate` \
                 again to write it",
                rows.display()
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::config::PbcsJob;
    use crate::experiment::{KindRow, PbcsRow};

    /// A made-up PBCS row of the first cell of `exp`.
    pub(crate) fn row(
        exp: &Experiment,
        seed: u64,
        solved: bool,
        steps: u64,
        skills: usize,
    ) -> RawRow {
        let c = &exp.cells[0];
        RawRow {
            experiment: exp.name,
            cell: c.id,
            method: c.method,
            site: c.site,
            maze_seed: 0,
            seed,
            learner: "ddpg".parse().unwrap(),
            gamma: 0.9,
            solved,
            success_rate: if solved { 1.0 } else { 0.0 },
            env_steps: steps,
            budget: 1_000_000,
            kind: KindRow::Pbcs(PbcsRow {
                chaining: true,
                starts: crate::phase2::StartMode::Ball,
                phase1_steps: 0,
                train_steps: steps,
                test_steps: 0,
                skills,
                failure: None,
            }),
        }
    }

    #[test]
    fn the_grid_table_gives_median_extremes_and_the_papers_ratio() {
        let exp = Experiment::of_job("mine", &PbcsJob::default(), &[2], 3).unwrap();
        let rows = [
            row(&exp, 0, true, 300_000, 2),
            row(&exp, 1, false, 100_000, 3),
            row(&exp, 2, true, 200_000, 2),
        ];
        let stats = cell_stats(&exp, &rows);
        let timings = [CellTiming {
            cell: "mine-maze2".parse().unwrap(),
            n: 3,
            wall_median_s: 20.0,
            wall_total_s: 60.0,
            steps_per_s: 10_000.0,
        }];
        let table = grid_markdown(&stats, &timings);
        // 2 of 3: Wilson 95 % [0.21, 0.94]; the paper's 321k steps on maze 2.
        assert_eq!(
            table.lines().nth(2).unwrap(),
            "| 2 | 2/3 | [0.21, 0.94] | 200k [100k, 300k] | 321k | 0.62 | 2 | 20 |"
        );
        assert!(grid_markdown(&stats, &[])
            .lines()
            .nth(2)
            .unwrap()
            .ends_with("| 2 | - |"));
    }
}
