//! The scaling table (`results/tables/<experiment>.paths.csv`): each cell's shortest path in
//! maze cells, the x axis of the scaling figure, and the power law steps ≈ c · L^b fitted
//! through the cells' medians — computed here once, drawn by the figure and quoted by the
//! report.

use crate::envs::maze::Maze;
use crate::error::Result;
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
    /// ln steps ≈ a + b · ln L over every cell with runs, as (a, b).
    pub fit: Option<(f64, f64)>,
}

impl ScalingData {
    /// The points of every cell of `exp` with statistics in `stats` and a path in `paths`.
    pub fn new(exp: &Experiment, stats: &[CellStats], paths: &[PathLength]) -> ScalingData {
        let mut series = Vec::new();
        let mut logs = Vec::new();
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
                logs.push((l.ln(), s.steps_median.max(1.0).ln()));
            }
            series.push((label.clone(), points));
        }
        ScalingData {
            series,
            fit: crate::stats::fit_line(&logs),
        }
    }

    /// The fitted power law steps ≈ c · L^b as (c, b), over every cell with runs.
    pub fn power_law(&self) -> Option<(f64, f64)> {
        self.fit.map(|(a, b)| (a.exp(), b))
    }
}
