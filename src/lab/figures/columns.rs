//! The shared layout of the per-run figures ([`super::bars::ChainSpread`],
//! [`super::routes::Routes`]): one column per method and maze, each holding that cell's runs
//! as dots, the methods that have no run left out.

use crate::experiment::{Experiment, Method, Site};

/// The columns of a per-run figure: `(method index, site, runs)` in the order of the
/// experiment's methods, then its mazes; empty columns left out.
pub(crate) struct RunColumns<R> {
    /// The methods (name, label) with at least one run, in the experiment's order.
    pub methods: Vec<(Method, String)>,
    /// One column per method and maze that has runs.
    pub columns: Vec<(usize, Site, Vec<R>)>,
}

impl<R> RunColumns<R> {
    /// The columns of `exp` from `runs(method, maze)`, the runs of one cell.
    pub fn new(exp: &Experiment, runs: impl Fn(Method, Site) -> Vec<R>) -> RunColumns<R> {
        let mut methods = Vec::new();
        let mut columns = Vec::new();
        for (m, label) in &exp.methods {
            let j = methods.len();
            let before = columns.len();
            for &n in &exp.sites {
                let cell = runs(*m, n);
                if !cell.is_empty() {
                    columns.push((j, n, cell));
                }
            }
            if columns.len() > before {
                methods.push((*m, label.clone()));
            }
        }
        RunColumns { methods, columns }
    }

    /// The figure's pixel size: 60 px a column and room for the axis, at least 700 wide.
    pub fn size(&self) -> (u32, u32) {
        ((60 * self.columns.len() as u32 + 200).max(700), 560)
    }

    /// The x labels, one per column (`N×N`, or an environment's name).
    pub fn labels(&self) -> Vec<String> {
        self.columns.iter().map(|(_, n, _)| n.axis()).collect()
    }
}
