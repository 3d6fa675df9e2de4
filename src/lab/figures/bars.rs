//! Bar and dot charts over cells: success with Wilson 95 % intervals, each run's chain
//! success, and the performance profile against the paper's steps.

use super::columns::RunColumns;
use super::{category_label, DrawResult, PALETTE};
use crate::experiment::{Baseline, Experiment, Site};
use crate::plot::Figure;
use crate::tables::CellStats;
use plotters::coord::Shift;
use plotters::prelude::*;

/// Bars of success rate per site (maze or environment) and method with Wilson 95 % error
/// bars (the γ study).
pub struct SuccessBars {
    title: String,
    mazes: Vec<Site>,
    /// One colour each, in drawing order: a label and its cells (a method's, or a baseline's
    /// from another experiment).
    series: Vec<(String, Vec<CellStats>)>,
}

impl SuccessBars {
    /// The bar chart of `exp`.
    pub fn new(exp: &Experiment, stats: &[CellStats]) -> SuccessBars {
        SuccessBars {
            title: exp.title.clone(),
            mazes: exp.sites.clone(),
            series: exp
                .methods
                .iter()
                .map(|(m, label)| {
                    let cells = stats.iter().filter(|s| s.method == *m).cloned().collect();
                    (label.clone(), cells)
                })
                .collect(),
        }
    }

    /// Draws `baseline`'s cells (from its experiment's table `stats`) first, on this
    /// figure's mazes.
    pub fn with_baseline(mut self, baseline: &Baseline, stats: &[CellStats]) -> SuccessBars {
        let cells = stats
            .iter()
            .filter(|s| s.method == baseline.method && self.mazes.contains(&s.site))
            .cloned()
            .collect();
        self.series.insert(0, (baseline.label.clone(), cells));
        self
    }
}

/// The most width in pixels of the legend beside a bar chart.
const BAR_LEGEND_WIDTH: u32 = 300;

impl SuccessBars {
    /// The legend's width: its longest label's (a swatch, a gap, 15-pixel sans-serif at about
    /// 0.55 em a character, a margin), at most [`BAR_LEGEND_WIDTH`].
    fn legend_width(&self) -> u32 {
        let chars = self.series.iter().map(|(l, _)| l.chars().count()).max();
        let needed = 34.0 + 0.55 * 15.0 * chars.unwrap_or(0) as f64 + 30.0;
        (needed.ceil() as u32).min(BAR_LEGEND_WIDTH)
    }

    /// The legend beside the chart: a colour swatch and a label per method.
    fn draw_legend<DB: DrawingBackend>(&self, side: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        for (j, (label, _)) in self.series.iter().enumerate() {
            let (x, y) = (10, 60 + 26 * j as i32);
            let colour = PALETTE[j % PALETTE.len()];
            side.draw(&Rectangle::new(
                [(x, y - 7), (x + 16, y + 7)],
                colour.filled(),
            ))?;
            side.draw(&Text::new(
                label.as_str(),
                (x + 24, y - 8),
                ("sans-serif", 15).into_font(),
            ))?;
        }
        Ok(())
    }

    /// Each maze's group holds the series that ran on it (all of them in a full grid), side
    /// by side in drawing order: their indices.
    fn slots(&self) -> Vec<Vec<usize>> {
        self.mazes
            .iter()
            .map(|&n| {
                (0..self.series.len())
                    .filter(|&j| self.series[j].1.iter().any(|s| s.site == n))
                    .collect()
            })
            .collect()
    }
}

impl Figure for SuccessBars {
    fn size(&self) -> (u32, u32) {
        (
            (260 * self.mazes.len() as u32 + 200).max(700) + self.legend_width(),
            520,
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let groups = self.mazes.len() as f64;
        // The legend stands beside the chart, never over a bar or an interval.
        let (w, _) = root.dim_in_pixel();
        let (root, side) = root.split_horizontally(w - self.legend_width());
        self.draw_legend(&side)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(&self.title, ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..groups, 0.0..1.05)?;
        let labels: Vec<String> = self.mazes.iter().map(|n| n.title()).collect();
        let label = category_label(&labels);
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(labels.len() * 2 + 1)
            .x_label_formatter(&label)
            .y_desc("success rate (Wilson 95 % interval)")
            .label_style(("sans-serif", 15))
            .draw()?;
        let slots = self.slots();
        for (j, (_, cells)) in self.series.iter().enumerate() {
            let colour = PALETTE[j % PALETTE.len()];
            let bars: Vec<(f64, f64, &CellStats)> = self
                .mazes
                .iter()
                .enumerate()
                .filter_map(|(g, &n)| {
                    let rank = slots[g].iter().position(|&i| i == j)?;
                    let width = 0.8 / slots[g].len() as f64;
                    cells
                        .iter()
                        .find(|s| s.site == n)
                        .map(|s| (g as f64 + 0.1 + rank as f64 * width, width, s))
                })
                .collect();
            chart.draw_series(bars.iter().map(|&(x, width, s)| {
                Rectangle::new(
                    [(x + 0.1 * width, 0.0), (x + 0.9 * width, s.success_rate)],
                    colour.filled(),
                )
            }))?;
            for &(x, width, s) in &bars {
                let c = x + 0.5 * width;
                let cap = 0.15 * width;
                for seg in [
                    [(c, s.wilson_lo), (c, s.wilson_hi)],
                    [(c - cap, s.wilson_lo), (c + cap, s.wilson_lo)],
                    [(c - cap, s.wilson_hi), (c + cap, s.wilson_hi)],
                ] {
                    chart.draw_series(std::iter::once(PathElement::new(
                        seg.to_vec(),
                        BLACK.stroke_width(2),
                    )))?;
                }
                // The count above the bar (the text hangs below its anchor), or, for a bar
                // reaching the top, inside it in white, clear of the interval's cap.
                let (y, ink) = if s.success_rate > 0.9 {
                    (s.success_rate - 0.03, WHITE)
                } else {
                    (s.success_rate + 0.03, BLACK)
                };
                chart.draw_series(std::iter::once(Text::new(
                    format!("{}/{}", s.successes, s.n),
                    (x + 0.2 * width, y),
                    ("sans-serif", 13).into_font().color(&ink),
                )))?;
            }
        }
        Ok(())
    }
}

/// The performance profile of each PBCS method of an experiment
/// ([`crate::criteria::profile`]): the fraction of its runs solved within x times the paper's
/// steps, x from 1/100 to 2 on a log axis.
pub struct Profile {
    title: String,
    /// (label, runs counted, fraction at each of `ratios`).
    series: Vec<(String, usize, Vec<f64>)>,
    ratios: Vec<f64>,
}

/// The range of x of the performance profile: 1/100 to twice the paper's steps (the budgets).
pub(crate) const PROFILE_RANGE: (f64, f64) = (0.01, 2.0);

impl Profile {
    /// The profile of `exp`'s PBCS `runs`.
    pub fn new(exp: &Experiment, runs: &[crate::criteria::ChainSuccess]) -> Profile {
        let (lo, hi) = PROFILE_RANGE;
        let ratios: Vec<f64> = (0..=400)
            .map(|i| lo * (hi / lo).powf(i as f64 / 400.0))
            .collect();
        let series = exp
            .methods
            .iter()
            .filter_map(|(m, label)| {
                let own: Vec<_> = runs
                    .iter()
                    .filter(|r| r.method == *m && r.paper_steps.is_some())
                    .cloned()
                    .collect();
                (!own.is_empty()).then(|| {
                    let y = crate::criteria::profile(&own, &ratios);
                    (label.clone(), own.len(), y)
                })
            })
            .collect();
        Profile {
            title: format!(
                "{}: runs solved within x times the paper's steps",
                exp.title
            ),
            series,
            ratios,
        }
    }
}

impl Figure for Profile {
    fn size(&self) -> (u32, u32) {
        (800, 520)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let (lo, hi) = PROFILE_RANGE;
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 18))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d((lo..hi).log_scale(), 0.0..1.05)?;
        chart
            .configure_mesh()
            .x_desc("x: environment steps / the paper's PBCS steps for the maze (log)")
            .y_desc("fraction of runs solved within x")
            .label_style(("sans-serif", 14))
            .draw()?;
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(1.0, 0.0), (1.0, 1.05)],
            BLACK.mix(0.5).stroke_width(1),
        )))?;
        for (j, (label, n, y)) in self.series.iter().enumerate() {
            let colour = PALETTE[j % PALETTE.len()];
            chart
                .draw_series(LineSeries::new(
                    self.ratios.iter().copied().zip(y.iter().copied()),
                    colour.stroke_width(3),
                ))?
                .label(format!("{label} ({n} runs)"))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(3))
                });
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()?;
        Ok(())
    }
}

/// One run of [`ChainSpread`]: seed, chain complete, chain success.
pub(crate) type ChainRun = (u64, bool, f32);

/// Each PBCS run's chain success, one column per cell (methods in the file's order, mazes
/// within each), read from `<experiment>.chains.csv`: a dot per complete chain at its
/// evaluation success, a cross at 0 per run whose chain was never completed, and the 95 %
/// line above which a run counts as solved.
pub struct ChainSpread {
    title: String,
    /// (method index, maze, runs), in drawing order.
    runs: RunColumns<ChainRun>,
}

impl ChainSpread {
    /// The figure of `exp`'s `chains`.
    pub fn new(exp: &Experiment, chains: &[crate::criteria::ChainSuccess]) -> ChainSpread {
        let runs = RunColumns::new(exp, |m, n| {
            chains
                .iter()
                .filter(|c| c.method == m && c.site == n)
                .map(|c| (c.seed, c.complete, c.success_rate))
                .collect()
        });
        ChainSpread {
            title: format!("{}: chain success of each PBCS run", exp.title),
            runs,
        }
    }
}

impl Figure for ChainSpread {
    fn size(&self) -> (u32, u32) {
        self.runs.size()
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let width = self.runs.columns.len() as f64;
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 18))
            .margin(15)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..width, -0.06..1.06)?;
        let labels = self.runs.labels();
        let label = category_label(&labels);
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(labels.len() * 2 + 1)
            .x_label_formatter(&label)
            .y_desc("chain success (evaluation episodes from B_ε(s₀))")
            .label_style(("sans-serif", 14))
            .draw()?;
        chart.draw_series(std::iter::once(PathElement::new(
            vec![
                (0.0, crate::runs::SOLVED_AT as f64),
                (width, crate::runs::SOLVED_AT as f64),
            ],
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
                        .filter(|r| r.1)
                        .map(move |&(seed, _, p)| (spread(i, seed), p as f64))
                })
                .collect();
            let crosses: Vec<(f64, f64)> = columns
                .flat_map(|(i, (_, _, runs))| {
                    runs.iter()
                        .filter(|r| !r.1)
                        .map(move |&(seed, _, _)| (spread(i, seed), -0.03))
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
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()?;
        Ok(())
    }
}
