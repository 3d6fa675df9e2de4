//! The plan of an experiment: its (cell, seed) runs, in order.

use super::{Cell, Experiment};
use crate::error::{Error, Result};

/// A (cell, seed) pair of a sweep.
#[derive(Debug, Clone)]
pub struct Pending<'a> {
    /// The cell.
    pub cell: &'a Cell,
    /// The run seed.
    pub seed: u64,
}

/// Every (cell, seed) of the experiment (each cell with the seeds of its maze), or of one
/// cell, or one seed.
pub fn plan<'a>(
    exp: &'a Experiment,
    cell: Option<super::CellKey>,
    seed: Option<u64>,
) -> Result<Vec<Pending<'a>>> {
    let cells: Vec<&Cell> = match cell {
        Some(key) => vec![exp.cell_at(key)?],
        None => exp.cells.iter().collect(),
    };
    let seeds = match seed {
        Some(s) => {
            if !exp.seeds().contains(&s) {
                return Err(Error::invalid(
                    "seed",
                    format!(
                        "{s} is outside the experiment's seeds {}..={}",
                        exp.first_seed,
                        exp.first_seed + (exp.seed_count - 1)
                    ),
                ));
            }
            vec![s]
        }
        None => exp.seeds(),
    };
    // A cell runs the seeds of its maze ([`Experiment::seeds_of`]).
    Ok(cells
        .into_iter()
        .flat_map(|c| {
            let own = exp.seeds_of(c);
            seeds
                .iter()
                .filter(move |s| own.contains(s))
                .map(move |&s| Pending { cell: c, seed: s })
        })
        .collect())
}
