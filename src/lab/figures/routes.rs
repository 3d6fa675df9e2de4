//! Each PBCS run's path against the fewest steps possible: the chain's (median successful
//! evaluation episode, a dot) and phase 1's trajectory τ it was built from (a cross), both
//! divided by the fewest steps from s_0 ([`crate::tables::routes`]), one column per cell.

use super::columns::RunColumns;
use super::{category_label, DrawResult, PALETTE};
use crate::experiment::Experiment;
use crate::plot::Figure;
use crate::tables::routes::Route;
use plotters::coord::Shift;
use plotters::prelude::*;

/// One run in the figure: (seed, chain / fewest, τ / fewest).
type RunRatios = (u64, Option<f64>, f64);

/// The routes figure (`kind = "routes"`).
pub struct Routes {
    title: String,
    /// (method index, maze, its runs), in drawing order.
    runs: RunColumns<RunRatios>,
}

impl Routes {
    /// The figure of `exp`'s routes table.
    pub fn new(exp: &Experiment, routes: &[Route]) -> Routes {
        let runs = RunColumns::new(exp, |m, n| {
            routes
                .iter()
                .filter(|r| r.method == m && r.site == n)
                .map(|r| (r.seed, r.chain_over_fewest(), r.tau_over_fewest()))
                .collect()
        });
        Routes {
            title: format!("{}: path length / fewest steps", exp.title),
            runs,
        }
    }
}

impl Figure for Routes {
    fn size(&self) -> (u32, u32) {
        self.runs.size()
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let width = self.runs.columns.len() as f64;
        let top = self
            .runs
            .columns
            .iter()
            .flat_map(|c| c.2.iter().map(|r| r.2.max(r.1.unwrap_or(1.0))))
            .fold(2.0f64, f64::max)
            * 1.3;
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 18))
            .margin(15)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..width, (0.9..top).log_scale())?;
        let labels = self.runs.labels();
        let label = category_label(&labels);
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(labels.len() * 2 + 1)
            .x_label_formatter(&label)
            .y_desc("steps / fewest steps from s₀ (log)")
            .label_style(("sans-serif", 14))
            .draw()?;
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(0.0, 1.0), (width, 1.0)],
            BLACK.mix(0.6).stroke_width(1),
        )))?;
        for (j, (_, label)) in self.runs.methods.iter().enumerate() {
            let colour = PALETTE[j % PALETTE.len()];
            // Seeds spread across the column so equal values stay visible.
            let spread = |i: usize, seed: u64| i as f64 + 0.2 + 0.06 * (seed % 10) as f64;
            let columns = self
                .runs
                .columns
                .iter()
                .enumerate()
                .filter(|(_, c)| c.0 == j);
            let dots: Vec<(f64, f64)> = columns
                .clone()
                .flat_map(|(i, (_, _, runs))| {
                    runs.iter()
                        .filter_map(move |&(seed, chain, _)| Some((spread(i, seed), chain?)))
                })
                .collect();
            let crosses: Vec<(f64, f64)> = columns
                .flat_map(|(i, (_, _, runs))| {
                    runs.iter()
                        .map(move |&(seed, _, tau)| (spread(i, seed), tau))
                })
                .collect();
            chart
                .draw_series(dots.iter().map(|&p| Circle::new(p, 4, colour.filled())))?
                .label(label.as_str())
                .legend(move |(x, y)| Circle::new((x + 7, y), 4, colour.filled()));
            chart.draw_series(
                crosses
                    .iter()
                    .map(|&p| Cross::new(p, 4, colour.stroke_width(2))),
            )?;
        }
        // One legend entry says what the crosses are; the colours say whose they are.
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
            .label("dot: the chain's path; cross: τ (phase 1)")
            .legend(|(x, y)| Cross::new((x + 7, y), 4, BLACK.stroke_width(2)));
        chart
            .configure_series_labels()
            // The band between the chains (near 1) and τ (4–6 times the fewest) stays empty.
            .position(SeriesLabelPosition::MiddleRight)
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()?;
        Ok(())
    }
}
