//! The vanilla baselines' learning curves, from the curves table
//! ([`crate::tables::curves`]).

use super::{DrawResult, PALETTE};
use crate::experiment::Experiment;
use crate::fmt::human_steps;
use crate::plot::Figure;
use crate::tables::curves::CurvePoint;
use plotters::coord::Shift;
use plotters::prelude::*;

/// One maze's curve: (its site, [(environment steps, fraction of seeds reaching the target, mean
/// greedy return over seeds)]).
pub(crate) type CurveLine = (crate::experiment::Site, Vec<(f64, f64, f64)>);

/// Learning curves of vanilla baselines, one column per method, one line per maze: the
/// fraction of seeds whose greedy policy reaches the target at each evaluation (top), and the
/// mean return of the greedy episode over seeds (bottom: −1 per wall hit, +1 at the target).
pub struct Curves {
    panels: Vec<(String, Vec<CurveLine>)>,
    max_steps: f64,
    returns: (f64, f64),
    seeds: u64,
}

impl Curves {
    /// The curves of the vanilla methods of `exp`, from its curves table (`points`, in cell
    /// then step order); `None` when no vanilla cell has points.
    pub fn new(exp: &Experiment, points: &[CurvePoint]) -> Option<Curves> {
        let mut panels = Vec::new();
        let mut max_steps: f64 = 1.0;
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for (m, label) in &exp.methods {
            let mut lines = Vec::new();
            for c in exp.cells.iter().filter(|c| c.method == *m) {
                let line: Vec<(f64, f64, f64)> = points
                    .iter()
                    .filter(|p| p.cell == c.id)
                    .map(|p| {
                        (
                            p.steps as f64,
                            p.solved as f64 / p.seeds as f64,
                            p.mean_return,
                        )
                    })
                    .collect();
                if line.is_empty() {
                    continue;
                }
                for p in &line {
                    lo = lo.min(p.2);
                    hi = hi.max(p.2);
                }
                max_steps = max_steps.max(line.last().map_or(1.0, |p| p.0));
                lines.push((c.site, line));
            }
            if !lines.is_empty() {
                panels.push((label.clone(), lines));
            }
        }
        let pad = ((hi - lo) * 0.05).max(0.05);
        (!panels.is_empty()).then_some(Curves {
            panels,
            max_steps,
            returns: (lo - pad, hi + pad),
            seeds: exp.seed_count,
        })
    }
}

impl Figure for Curves {
    fn size(&self) -> (u32, u32) {
        (560 * self.panels.len() as u32, 780)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let areas = root.split_evenly((2, self.panels.len()));
        for (row, (y_desc, range)) in [
            ("fraction of seeds reaching the target", (-0.02, 1.02)),
            ("greedy return, mean over seeds", self.returns),
        ]
        .into_iter()
        .enumerate()
        {
            for (col, (label, lines)) in self.panels.iter().enumerate() {
                let area = &areas[row * self.panels.len() + col];
                let mut chart = ChartBuilder::on(area)
                    .caption(format!("{label}, {} seeds", self.seeds), ("sans-serif", 17))
                    .margin(12)
                    .x_label_area_size(40)
                    .y_label_area_size(55)
                    .build_cartesian_2d(0.0..self.max_steps, range.0..range.1)?;
                chart
                    .configure_mesh()
                    .x_desc("environment steps")
                    .y_desc(y_desc)
                    .x_label_formatter(&|x| human_steps(*x))
                    .label_style(("sans-serif", 13))
                    .draw()?;
                for (i, (maze, line)) in lines.iter().enumerate() {
                    let colour = PALETTE[i % PALETTE.len()];
                    let points = line.iter().map(|p| (p.0, if row == 0 { p.1 } else { p.2 }));
                    chart
                        .draw_series(LineSeries::new(points, colour.stroke_width(2)))?
                        .label(maze.title())
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2))
                        });
                }
                chart
                    .configure_series_labels()
                    .position(if row == 0 {
                        SeriesLabelPosition::UpperLeft
                    } else {
                        SeriesLabelPosition::LowerLeft
                    })
                    .background_style(WHITE.mix(0.9))
                    .border_style(BLACK)
                    .label_font(("sans-serif", 13))
                    .draw()?;
            }
        }
        Ok(())
    }
}
