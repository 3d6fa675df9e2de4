//! The scaling table (`results/tables/<experiment>.paths.csv`): each cell's shortest path in
//! maze cells, the x axis of the scaling figure — and the fit table
//! (`<experiment>.scaling_fit.csv`): the power law steps ≈ c · L^b fitted through the cells'
//! medians, computed here once when the tables are written, drawn by the figure and quoted by
//! the report.

use crate::envs::maze::Maze;
use crate::error::{Error, Result};
use crate::experiment::{Cell, CellKey, Experiment, ExperimentName, Job};
use crate::tables::CellStats;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// One cell's shortest path from the start cell to the target cell.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PathLength {
    /// Cell id.
    pub cell: CellKey,
    /// Maze size N.
    pub maze: usize,
    /// Moves between maze cells on the shortest path ([`Maze::path_cells`]).
    pub path_cells: usize,
}

/// `<results>/tables/<experiment>.paths.csv`.
pub fn paths_path(results: &Path, experiment: ExperimentName) -> PathBuf {
    results
        .join("tables")
        .join(format!("{experiment}.paths.csv"))
}

/// The maze of a cell.
pub fn cell_maze(cell: &Cell) -> Result<Maze> {
    Maze::new(match &cell.job {
        Job::Vanilla(j) => &j.maze,
        Job::Pbcs(j) => &j.maze,
    })
}

/// Each maze cell's shortest path (cells of other environments and cells whose target cannot
/// be reached are left out).
pub fn path_lengths(exp: &Experiment) -> Result<Vec<PathLength>> {
    let mut out = Vec::new();
    for c in &exp.cells {
        let Some(n) = c.site.size() else { continue };
        if let Some(l) = cell_maze(c)?.path_cells() {
            out.push(PathLength {
                cell: c.id,
                maze: n,
                path_cells: l,
            });
        }
    }
    Ok(out)
}

/// Reads a paths table written by [`crate::pipeline::write_tables`].
pub fn read_paths(path: &Path) -> Result<Vec<PathLength>> {
    crate::record::read_records(path)
}

/// One cell of the scaling figure: (shortest path in moves, median, first and third quartile
/// of the environment steps, solved k, runs n).
pub type ScalingPoint = (f64, f64, f64, f64, u64, u64);

/// Environment steps against the shortest path's length, per method, with the power law.
#[derive(Debug, Clone, PartialEq)]
pub struct ScalingData {
    /// (method label, its cells' points), in the experiment's method order.
    pub series: Vec<(String, Vec<ScalingPoint>)>,
    /// The power law through the points, as [`ScalingFit::of`] wrote it.
    pub fit: ScalingFit,
}

impl ScalingData {
    /// The points of every cell of `exp` with statistics in `stats` and a path in `paths`,
    /// with the fit read from `<experiment>.scaling_fit.csv`; refused where the fit went
    /// through another number of cells than the points (a fit written for other tables).
    pub fn new(
        exp: &Experiment,
        stats: &[CellStats],
        paths: &[PathLength],
        fit: ScalingFit,
    ) -> Result<ScalingData> {
        let series = series(exp, stats, paths);
        let points: usize = series.iter().map(|(_, p)| p.len()).sum();
        if fit.cells != points as u64 {
            return Err(Error::invalid(
                format!("{}.scaling_fit.csv", exp.name),
                format!(
                    "the fit went through {} cells, the tables give {points}: run `pbcs \
                     aggregate` again",
                    fit.cells
                ),
            ));
        }
        Ok(ScalingData { series, fit })
    }
}

/// Per method (in the experiment's order, with its label) the points of its cells that have
/// statistics in `stats` and a path in `paths`.
fn series(
    exp: &Experiment,
    stats: &[CellStats],
    paths: &[PathLength],
) -> Vec<(String, Vec<ScalingPoint>)> {
    let mut series = Vec::new();
    for (m, label) in &exp.methods {
        let mut points = Vec::new();
        for c in exp.cells.iter().filter(|c| &c.method == m) {
            let s = stats.iter().find(|s| s.cell == c.id);
            let path = paths.iter().find(|p| p.cell == c.id);
            let (Some(s), Some(p)) = (s, path) else {
                continue;
            };
            let l = p.path_cells.max(1) as f64;
            points.push((l, s.steps_median, s.steps_q1, s.steps_q3, s.successes, s.n));
        }
        series.push((label.clone(), points));
    }
    series
}

/// The power law steps ≈ c · L^b, fitted by least squares through (ln L, ln median steps) of
/// every point of the scaling figure (a median under 1 counts as 1): the one line of
/// `<experiment>.scaling_fit.csv`, which the figure draws and the report quotes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ScalingFit {
    /// Cells the line is fitted through.
    pub cells: u64,
    /// ln c, the intercept; empty where there is no line (fewer than two distinct L).
    pub ln_factor: Option<f64>,
    /// b, the slope; empty exactly where `ln_factor` is.
    pub exponent: Option<f64>,
}

impl ScalingFit {
    /// The fit through the cells of `exp` with statistics in `stats` and a path in `paths`.
    pub fn of(exp: &Experiment, stats: &[CellStats], paths: &[PathLength]) -> ScalingFit {
        let logs: Vec<(f64, f64)> = series(exp, stats, paths)
            .iter()
            .flat_map(|(_, points)| points.iter().map(|p| (p.0.ln(), p.1.max(1.0).ln())))
            .collect();
        let line = crate::stats::fit_line(&logs);
        ScalingFit {
            cells: logs.len() as u64,
            ln_factor: line.map(|l| l.0),
            exponent: line.map(|l| l.1),
        }
    }

    /// ln steps ≈ a + b · ln L as (a, b), where there is a line.
    pub fn line(&self) -> Option<(f64, f64)> {
        self.ln_factor.zip(self.exponent)
    }

    /// The fitted power law steps ≈ c · L^b as (c, b), where there is a line.
    pub fn power_law(&self) -> Option<(f64, f64)> {
        self.line().map(|(a, b)| (a.exp(), b))
    }
}

/// `<results>/tables/<experiment>.scaling_fit.csv`.
pub fn scaling_fit_path(results: &Path, experiment: ExperimentName) -> PathBuf {
    results
        .join("tables")
        .join(format!("{experiment}.scaling_fit.csv"))
}

/// Reads a fit written by [`crate::pipeline::write_tables`]: exactly one line, its intercept
/// and slope both given or both empty.
pub fn read_scaling_fit(path: &Path) -> Result<ScalingFit> {
    let fit: ScalingFit = crate::record::read_one_record(path)?;
    if fit.ln_factor.is_some() != fit.exponent.is_some() {
        return Err(Error::parse(
            path,
            "gives one of ln_factor and exponent without the other",
        ));
    }
    if fit
        .line()
        .is_some_and(|(a, b)| !a.is_finite() || !b.is_finite())
    {
        return Err(Error::parse(path, "gives a line that is not finite"));
    }
    Ok(fit)
}

/// The paths table of `experiment` and the fit written beside it, each checked: a paths
/// table without its fit (aggregated before the fit was a table) is refused.
pub fn read_paths_and_fit(
    results: &Path,
    experiment: ExperimentName,
) -> Result<(Vec<PathLength>, ScalingFit)> {
    let (paths, fit) = (
        paths_path(results, experiment),
        scaling_fit_path(results, experiment),
    );
    super::summary_beside(&paths, &fit)?;
    Ok((read_paths(&paths)?, read_scaling_fit(&fit)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fit file is checked before it is trusted: one line, intercept and slope together.
    #[test]
    fn a_fit_file_holds_one_whole_line() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.scaling_fit.csv");
        let read = |text: &str| {
            std::fs::write(&path, text).unwrap();
            read_scaling_fit(&path).map_err(|e| e.to_string())
        };
        let fit = read("cells,ln_factor,exponent\n3,2.0,1.5\n").unwrap();
        assert_eq!(fit.power_law(), Some((2f64.exp(), 1.5)));
        assert_eq!(
            read("cells,ln_factor,exponent\n1,,\n").unwrap().line(),
            None
        );
        let half = read("cells,ln_factor,exponent\n3,2.0,\n").unwrap_err();
        assert!(half.contains("without the other"), "{half}");
        let two = read("cells,ln_factor,exponent\n3,2.0,1.5\n3,2.0,1.5\n").unwrap_err();
        assert!(two.contains("holds 2 lines, one expected"), "{two}");
        let none = read("cells,ln_factor,exponent\n").unwrap_err();
        assert!(none.contains("holds 0 lines"), "{none}");
        let nan = read("cells,ln_factor,exponent\n3,NaN,1.5\n").unwrap_err();
        assert!(nan.contains("not finite"), "{nan}");
    }
}
