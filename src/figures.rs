//! The paper's figures, drawn with plotters from the aggregated tables and the raw picture
//! data (no training): the results grid, the enlarged results, the γ study with Wilson error
//! bars, the reset-in-unseen-states contrast and the vanilla learning curves.
//!
//! Every figure is written as PNG and SVG with the bundled font (see [`crate::plot`]).

use crate::error::{Error, Result};
use crate::experiment::{evals_file, picture_file, Cell, Experiment, FigureSpec, Job};
use crate::fmt::human_steps;
use crate::maze::Maze;
use crate::plot::{draw_maze, render_figure, Figure, PictureData};
use crate::tables::CellStats;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

type DrawResult<DB> =
    std::result::Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

const GREEN_BG: RGBColor = RGBColor(46, 160, 67);
const RED_BG: RGBColor = RGBColor(200, 50, 50);
/// Colours of methods in bar charts and curves (colour-blind-safe Okabe–Ito).
const PALETTE: [RGBColor; 7] = [
    RGBColor(0, 114, 178),
    RGBColor(230, 159, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(86, 180, 233),
    RGBColor(213, 94, 0),
    RGBColor(120, 120, 120),
];

/// The x-axis labels of a chart of categories at [i, i + 1): `labels[i]` at the centre of its
/// slot, nothing at the other ticks (ask for `2 · labels.len() + 1` of them).
fn category_label(labels: &[String]) -> impl Fn(&f64) -> String + '_ {
    move |x: &f64| {
        let i = x.floor() as usize;
        if (x - x.floor() - 0.5).abs() < 1e-6 && i < labels.len() {
            labels[i].clone()
        } else {
            String::new()
        }
    }
}

/// The maze of a cell.
pub fn cell_maze(cell: &Cell) -> Result<Maze> {
    Maze::new(match &cell.job {
        Job::Vanilla(j) => &j.maze,
        Job::Pbcs(j) => &j.maze,
    })
}

/// The picture data of a cell's first picture seed, if it was kept.
fn cell_picture(exp: &Experiment, results: &Path, cell: &Cell) -> Result<Option<PictureData>> {
    let Some(&seed) = exp.picture_seeds.first() else {
        return Ok(None);
    };
    let path = picture_file(exp, results, cell, seed);
    if !path.exists() {
        return Ok(None);
    }
    PictureData::read_csv(&path).map(Some)
}

fn stats_of<'a>(stats: &'a [CellStats], cell: &Cell) -> Option<&'a CellStats> {
    stats.iter().find(|s| s.cell == cell.id)
}

/// A cell's one-line summary: `7/10 solved · median 171k`, the median environment steps of
/// the solved seeds. When no seed solved: `0/10 solved · budget 400k` if a run reached the
/// budget (its steps say only that the budget ran out, and Backplay checks it between batches
/// of episodes, so it may pass it by up to one batch), else `0/10 solved · median 329k (all
/// runs)`, the runs having stopped on their own (a complete chain that failed its evaluation,
/// a run without chaining at its first failure, or Backplay failing at K = 0).
pub fn summary(s: &CellStats) -> String {
    match s.solved_steps_median {
        Some(m) if s.successes > 0 => {
            format!("{}/{} solved · median {}", s.successes, s.n, human_steps(m))
        }
        _ if s.steps_max < s.budget as f64 => format!(
            "{}/{} solved · median {} (all runs)",
            s.successes,
            s.n,
            human_steps(s.steps_median)
        ),
        _ => format!(
            "{}/{} solved · budget {}",
            s.successes,
            s.n,
            human_steps(s.budget as f64)
        ),
    }
}

fn centred_text<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    text: &str,
    size: u32,
    colour: &RGBColor,
) -> DrawResult<DB> {
    let (w, h) = area.dim_in_pixel();
    let style = TextStyle::from(("sans-serif", size).into_font())
        .color(colour)
        .pos(plotters::style::text_anchor::Pos::new(
            plotters::style::text_anchor::HPos::Center,
            plotters::style::text_anchor::VPos::Center,
        ));
    area.draw_text(text, &style, (w as i32 / 2, h as i32 / 2))
}

/// The results table as a grid of pictures: rows = maze sizes, columns = methods; each cell
/// shows the first picture seed's run and is labelled with its [`summary`] on a green (more
/// than half the seeds solved) or red background; a legend under the grid says so.
pub struct ResultsGrid {
    cells: Vec<Vec<Option<GridCell>>>,
    rows: Vec<String>,
    columns: Vec<String>,
    /// The legend's lines (see [`ResultsGrid::legend`]).
    legend: Vec<String>,
}

/// One drawn cell of the grid: its maze, its picture seed's run and its statistics.
type GridCell = (Maze, PictureData, CellStats);

const GRID_CELL: u32 = 280;
const GRID_LABEL: u32 = 26;
/// Height of one legend line under the grid.
const GRID_LEGEND_LINE: u32 = 22;
/// Width of the row labels.
const GRID_LEFT: u32 = 70;

impl ResultsGrid {
    /// Collects the grid of `exp` from its table and picture data.
    pub fn new(exp: &Experiment, results: &Path, stats: &[CellStats]) -> Result<ResultsGrid> {
        let mut cells = Vec::new();
        for &n in &exp.mazes {
            let mut row = Vec::new();
            for (m, _) in &exp.methods {
                let cell = exp
                    .cells
                    .iter()
                    .find(|c| c.maze == n && &c.method == m)
                    .expect("every maze × method is a cell");
                row.push(
                    match (stats_of(stats, cell), cell_picture(exp, results, cell)?) {
                        (Some(s), Some(p)) => Some((cell_maze(cell)?, p, s.clone())),
                        _ => None,
                    },
                );
            }
            cells.push(row);
        }
        let legend = ResultsGrid::legend(exp, &cells);
        Ok(ResultsGrid {
            cells,
            rows: exp.mazes.iter().map(|n| format!("{n}×{n}")).collect(),
            columns: exp.methods.iter().map(|(_, l)| l.clone()).collect(),
            legend,
        })
    }

    /// What the bands and the pictures show, one line each; the first line follows the two
    /// colour swatches drawn before it.
    fn legend(exp: &Experiment, cells: &[Vec<Option<GridCell>>]) -> Vec<String> {
        let mut lines = vec![
            "more than half the seeds solved / half or fewer (grey: no runs yet)".to_string(),
            "band: seeds solved / seeds · median environment steps of the solved seeds; \
             when none solved, the step budget if a run reached it, else all runs' median"
                .to_string(),
        ];
        // Everything any panel draws, each name once, in the order the panels name them.
        let mut parts: Vec<String> = Vec::new();
        for (_, data, _) in cells.iter().flatten().flatten() {
            for part in crate::plot::legend(&data.picture(String::new())).split(" · ") {
                if !parts.iter().any(|p| p == part) {
                    parts.push(part.to_string());
                }
            }
        }
        if let (Some(seed), false) = (exp.picture_seeds.first(), parts.is_empty()) {
            lines.push(format!(
                "pictures: seed {seed}'s run — {}",
                parts.join(" · ")
            ));
        }
        lines
    }
}

impl Figure for ResultsGrid {
    fn size(&self) -> (u32, u32) {
        (
            GRID_LEFT + GRID_CELL * self.columns.len() as u32,
            40 + (GRID_CELL + GRID_LABEL) * self.rows.len() as u32
                + 8
                + GRID_LEGEND_LINE * self.legend.len() as u32,
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let (w, h) = root.dim_in_pixel();
        let (root, footer) =
            root.split_vertically(h - 8 - GRID_LEGEND_LINE * self.legend.len() as u32);
        // The legend: two colour swatches before the first line.
        for (i, line) in self.legend.iter().enumerate() {
            let y = 8 + GRID_LEGEND_LINE as i32 * i as i32;
            let mut x = GRID_LEFT as i32;
            if i == 0 {
                for colour in [GREEN_BG, RED_BG] {
                    footer.draw(&Rectangle::new([(x, y), (x + 28, y + 16)], colour.filled()))?;
                    x += 34;
                }
            }
            let size = (w as f64 - x as f64 - 10.0) / (0.55 * line.chars().count().max(1) as f64);
            footer.draw(&Text::new(
                line.clone(),
                (x, y),
                ("sans-serif", size.clamp(8.0, 15.0))
                    .into_font()
                    .color(&BLACK),
            ))?;
        }
        let (header, body) = root.split_vertically(40);
        let (_, header) = header.split_horizontally(GRID_LEFT);
        for (area, label) in header
            .split_evenly((1, self.columns.len()))
            .iter()
            .zip(&self.columns)
        {
            centred_text(area, label, 18, &BLACK)?;
        }
        let (left, grid) = body.split_horizontally(GRID_LEFT);
        for (area, label) in left
            .split_evenly((self.rows.len(), 1))
            .iter()
            .zip(&self.rows)
        {
            centred_text(area, label, 18, &BLACK)?;
        }
        let areas = grid.split_evenly((self.rows.len(), self.columns.len()));
        for (area, cell) in areas.iter().zip(self.cells.iter().flatten()) {
            let (band, picture) = area.split_vertically(GRID_LABEL);
            match cell {
                Some((maze, data, s)) => {
                    let colour = if 2 * s.successes > s.n {
                        GREEN_BG
                    } else {
                        RED_BG
                    };
                    band.fill(&colour)?;
                    centred_text(&band, &summary(s), 15, &WHITE)?;
                    draw_maze(picture, maze, &data.picture(String::new()))?;
                }
                None => {
                    band.fill(&RGBColor(150, 150, 150))?;
                    centred_text(&band, "no runs yet", 15, &WHITE)?;
                }
            }
        }
        Ok(())
    }
}

/// Bars of success rate per maze and method with Wilson 95 % error bars (the γ study).
pub struct SuccessBars {
    title: String,
    mazes: Vec<usize>,
    methods: Vec<(String, String)>,
    stats: Vec<CellStats>,
}

impl SuccessBars {
    /// The bar chart of `exp`.
    pub fn new(exp: &Experiment, stats: &[CellStats]) -> SuccessBars {
        SuccessBars {
            title: exp.title.clone(),
            mazes: exp.mazes.clone(),
            methods: exp.methods.clone(),
            stats: stats.to_vec(),
        }
    }
}

impl Figure for SuccessBars {
    fn size(&self) -> (u32, u32) {
        ((260 * self.mazes.len() as u32 + 200).max(700), 520)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let groups = self.mazes.len() as f64;
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..groups, 0.0..1.05)?;
        let labels: Vec<String> = self.mazes.iter().map(|n| format!("maze {n}×{n}")).collect();
        let label = category_label(&labels);
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(labels.len() * 2 + 1)
            .x_label_formatter(&label)
            .y_desc("success rate (Wilson 95 % interval)")
            .label_style(("sans-serif", 15))
            .draw()?;
        // Each maze's group holds the methods that ran on it (all of them in a full grid),
        // side by side in the file's order.
        let slots: Vec<Vec<&str>> = self
            .mazes
            .iter()
            .map(|&n| {
                self.methods
                    .iter()
                    .map(|(name, _)| name.as_str())
                    .filter(|name| self.stats.iter().any(|s| s.maze == n && s.method == *name))
                    .collect()
            })
            .collect();
        for (j, (name, label)) in self.methods.iter().enumerate() {
            let colour = PALETTE[j % PALETTE.len()];
            let bars: Vec<(f64, f64, &CellStats)> = self
                .mazes
                .iter()
                .enumerate()
                .filter_map(|(g, &n)| {
                    let rank = slots[g].iter().position(|m| m == name)?;
                    let width = 0.8 / slots[g].len() as f64;
                    self.stats
                        .iter()
                        .find(|s| s.maze == n && &s.method == name)
                        .map(|s| (g as f64 + 0.1 + rank as f64 * width, width, s))
                })
                .collect();
            chart
                .draw_series(bars.iter().map(|&(x, width, s)| {
                    Rectangle::new(
                        [(x + 0.1 * width, 0.0), (x + 0.9 * width, s.success_rate)],
                        colour.filled(),
                    )
                }))?
                .label(label.as_str())
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 6), (x + 14, y + 6)], colour.filled())
                });
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
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .label_font(("sans-serif", 15))
            .draw()?;
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
const PROFILE_RANGE: (f64, f64) = (0.01, 2.0);

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
                    .filter(|r| &r.method == m && r.paper_steps.is_some())
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
type ChainRun = (u64, bool, f32);

/// Each PBCS run's chain success, one column per cell (methods in the file's order, mazes
/// within each), read from `<experiment>.chains.csv`: a dot per complete chain at its
/// evaluation success, a cross at 0 per run whose chain was never completed, and the 95 %
/// line above which a run counts as solved.
pub struct ChainSpread {
    title: String,
    /// (method index, maze, runs), in drawing order.
    columns: Vec<(usize, usize, Vec<ChainRun>)>,
    methods: Vec<(String, String)>,
}

impl ChainSpread {
    /// The figure of `exp`'s `chains`.
    pub fn new(exp: &Experiment, chains: &[crate::criteria::ChainSuccess]) -> ChainSpread {
        let mut columns = Vec::new();
        let methods: Vec<(String, String)> = exp
            .methods
            .iter()
            .filter(|(m, _)| chains.iter().any(|c| &c.method == m))
            .cloned()
            .collect();
        for (j, (m, _)) in methods.iter().enumerate() {
            for &n in &exp.mazes {
                let runs: Vec<ChainRun> = chains
                    .iter()
                    .filter(|c| &c.method == m && c.maze == n)
                    .map(|c| (c.seed, c.complete, c.success_rate))
                    .collect();
                if !runs.is_empty() {
                    columns.push((j, n, runs));
                }
            }
        }
        ChainSpread {
            title: format!("{}: chain success of each PBCS run", exp.title),
            columns,
            methods,
        }
    }
}

impl Figure for ChainSpread {
    fn size(&self) -> (u32, u32) {
        ((60 * self.columns.len() as u32 + 200).max(700), 560)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let width = self.columns.len() as f64;
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 18))
            .margin(15)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..width, -0.06..1.06)?;
        let labels: Vec<String> = self
            .columns
            .iter()
            .map(|(_, n, _)| format!("{n}×{n}"))
            .collect();
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
        for (j, (_, label)) in self.methods.iter().enumerate() {
            let colour = PALETTE[j % PALETTE.len()];
            // Seeds spread across the column so equal values stay visible.
            let spread = |i: usize, seed: u64| i as f64 + 0.2 + 0.06 * (seed % 10) as f64;
            let columns = self.columns.iter().enumerate().filter(|(_, c)| c.0 == j);
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

/// One cell of the scaling figure: (shortest path in moves, median, first and third quartile
/// of the environment steps, solved k, runs n).
type ScalingPoint = (f64, f64, f64, f64, u64, u64);

/// Environment steps against the length of the maze's shortest path, log–log, one series per
/// method, with the least-squares power law through the cells' medians.
pub struct Scaling {
    title: String,
    series: Vec<(String, Vec<ScalingPoint>)>,
    /// steps ≈ exp(a) · L^b over every cell with runs.
    fit: Option<(f64, f64)>,
}

/// Least-squares line through the points (x, y): (intercept, slope); None with fewer than two
/// distinct x.
pub fn fit_line(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    let n = points.len() as f64;
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (points.len() >= 2 && sxx > 1e-12).then(|| (my - sxy / sxx * mx, sxy / sxx))
}

impl Scaling {
    /// The fitted power law steps ≈ c · L^b as (c, b), over every cell with runs.
    pub fn power_law(&self) -> Option<(f64, f64)> {
        self.fit.map(|(a, b)| (a.exp(), b))
    }

    /// Each cell's shortest path L (moves between cells), by cell id.
    pub fn path_lengths(exp: &Experiment) -> Result<Vec<(String, usize)>> {
        let mut out = Vec::new();
        for c in &exp.cells {
            if let Some(l) = cell_maze(c)?.path_cells() {
                out.push((c.id.clone(), l));
            }
        }
        Ok(out)
    }

    /// The scaling figure of `exp` from its table.
    pub fn new(exp: &Experiment, stats: &[CellStats]) -> Result<Scaling> {
        let paths = Scaling::path_lengths(exp)?;
        let mut series = Vec::new();
        let mut logs = Vec::new();
        for (m, label) in &exp.methods {
            let mut points = Vec::new();
            for c in exp.cells.iter().filter(|c| &c.method == m) {
                let path = paths.iter().find(|(id, _)| id == &c.id);
                let (Some(s), Some(&(_, l))) = (stats_of(stats, c), path) else {
                    continue;
                };
                let l = l.max(1) as f64;
                points.push((l, s.steps_median, s.steps_q1, s.steps_q3, s.successes, s.n));
                logs.push((l.ln(), s.steps_median.max(1.0).ln()));
            }
            series.push((label.clone(), points));
        }
        Ok(Scaling {
            title: exp.title.clone(),
            series,
            fit: fit_line(&logs),
        })
    }
}

/// The whole powers of ten around [lo, hi] (a log axis over whole decades gets labels).
fn decades(lo: f64, hi: f64) -> std::ops::Range<f64> {
    let lo = 10f64.powf(lo.max(1e-9).log10().floor());
    let hi = 10f64.powf(hi.max(lo).log10().ceil()).max(lo * 10.0);
    lo..hi
}

impl Figure for Scaling {
    fn size(&self) -> (u32, u32) {
        (760, 560)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let points = self.series.iter().flat_map(|s| &s.1);
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, 1.0f64, f64::MAX, 1.0f64);
        for p in points {
            (x0, x1) = (x0.min(p.0), x1.max(p.0));
            (y0, y1) = (y0.min(p.2.max(1.0)), y1.max(p.3));
        }
        if x0 > x1 {
            (x0, y0) = (1.0, 1.0);
        }
        let caption = match self.fit {
            Some((_, b)) => format!("{} — fit over the cells: steps ∝ L^{b:.2}", self.title),
            None => self.title.clone(),
        };
        let mut chart = ChartBuilder::on(root)
            .caption(caption, ("sans-serif", 18))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(decades(x0, x1).log_scale(), decades(y0, y1).log_scale())?;
        chart
            .configure_mesh()
            .x_desc("shortest path from start to target, L (moves between cells)")
            .y_desc("environment steps: median, quartiles")
            .x_label_formatter(&|x| format!("{x:.0}"))
            .y_label_formatter(&|y| human_steps(*y))
            .label_style(("sans-serif", 13))
            .draw()?;
        if let Some((a, b)) = self.fit {
            let line = [x0, x1].map(|x| (x, (a + b * x.ln()).exp()));
            chart
                .draw_series(LineSeries::new(line, BLACK.mix(0.5).stroke_width(1)))?
                .label(format!("fit: {:.0} · L^{b:.2}", a.exp()))
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.mix(0.5)));
        }
        for (i, (label, points)) in self.series.iter().enumerate() {
            let colour = PALETTE[i % PALETTE.len()];
            for p in points {
                chart.draw_series(std::iter::once(PathElement::new(
                    vec![(p.0, p.2.max(1.0)), (p.0, p.3)],
                    colour.stroke_width(2),
                )))?;
                if p.4 < p.5 {
                    chart.draw_series(std::iter::once(Text::new(
                        format!("{}/{}", p.4, p.5),
                        (p.0 * 1.04, p.1),
                        ("sans-serif", 12),
                    )))?;
                }
            }
            chart
                .draw_series(
                    points
                        .iter()
                        .map(|p| Circle::new((p.0, p.1), 5, colour.filled())),
                )?
                .label(label.clone())
                .legend(move |(x, y)| Circle::new((x + 8, y), 5, colour.filled()));
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

/// Maze pictures side by side, each with a title (the unseen-states contrast).
pub struct Panels {
    panels: Vec<(Maze, PictureData, String)>,
}

impl Figure for Panels {
    fn size(&self) -> (u32, u32) {
        (520 * self.panels.len() as u32, 560)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        for (area, (maze, data, title)) in root
            .split_evenly((1, self.panels.len()))
            .iter()
            .zip(&self.panels)
        {
            draw_maze(area.clone(), maze, &data.picture(title.clone()))?;
        }
        Ok(())
    }
}

/// One maze's curve: (maze, [(environment steps, fraction of seeds reaching the target, mean
/// greedy return over seeds)]).
type CurveLine = (usize, Vec<(f64, f64, f64)>);

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
    /// The curves of the vanilla methods of `exp`, from each seed's `evals.csv`.
    pub fn new(exp: &Experiment, results: &Path) -> Result<Option<Curves>> {
        let mut panels = Vec::new();
        let mut max_steps: f64 = 1.0;
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for (m, label) in &exp.methods {
            let mut lines = Vec::new();
            for c in exp.cells.iter().filter(|c| &c.method == m) {
                if !matches!(c.job, Job::Vanilla(_)) {
                    continue;
                }
                // steps → (successful seeds, seeds, sum of returns)
                let mut by_step: std::collections::BTreeMap<u64, (u64, u64, f64)> =
                    Default::default();
                for seed in exp.seeds() {
                    let path = evals_file(exp, results, c, seed);
                    if !path.exists() {
                        continue;
                    }
                    let mut reader =
                        csv::Reader::from_path(&path).map_err(|e| Error::csv(&path, e))?;
                    for rec in reader.deserialize::<EvalPoint>() {
                        let e = rec.map_err(|e| Error::csv(&path, e))?;
                        let slot = by_step.entry(e.steps).or_default();
                        slot.0 += u64::from(e.success >= crate::runs::SOLVED_AT);
                        slot.1 += 1;
                        slot.2 += f64::from(e.mean_return);
                    }
                }
                if by_step.is_empty() {
                    continue;
                }
                let line: Vec<(f64, f64, f64)> = by_step
                    .iter()
                    .map(|(&s, &(k, n, r))| (s as f64, k as f64 / n as f64, r / n as f64))
                    .collect();
                for p in &line {
                    lo = lo.min(p.2);
                    hi = hi.max(p.2);
                }
                max_steps = max_steps.max(line.last().map_or(1.0, |p| p.0));
                lines.push((c.maze, line));
            }
            if !lines.is_empty() {
                panels.push((label.clone(), lines));
            }
        }
        let pad = ((hi - lo) * 0.05).max(0.05);
        Ok((!panels.is_empty()).then_some(Curves {
            panels,
            max_steps,
            returns: (lo - pad, hi + pad),
            seeds: exp.seed_count,
        }))
    }
}

#[derive(serde::Deserialize)]
struct EvalPoint {
    steps: u64,
    success: f32,
    mean_return: f32,
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
                        .label(format!("maze {maze}×{maze}"))
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

/// Draws every figure `exp` declares ([`FigureSpec`]) into `out` from its table `stats` and
/// the raw picture and evaluation files under `results`; returns the files written. A figure
/// whose data is missing (no picture kept, no vanilla method for curves) is skipped.
pub fn render_experiment(
    exp: &Experiment,
    results: &Path,
    stats: &[CellStats],
    out: &Path,
) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for figure in &exp.figures {
        let stem = out.join(figure.name());
        match figure {
            FigureSpec::Grid { .. } => {
                let grid = ResultsGrid::new(exp, results, stats)?;
                files.extend(render_figure(&grid, &stem)?);
            }
            FigureSpec::Mazes { name, method } => {
                for c in exp.cells.iter().filter(|c| &c.method == method) {
                    let (Some(s), Some(data)) =
                        (stats_of(stats, c), cell_picture(exp, results, c)?)
                    else {
                        continue;
                    };
                    let maze = cell_maze(c)?;
                    let title = format!(
                        "{0}, maze {1}×{1}, seed {2}: phase-1 τ (red), chain rollouts (green), \
                         activation balls (purple) — {3}",
                        c.label,
                        c.maze,
                        exp.picture_seeds[0],
                        summary(s)
                    );
                    let stem = out.join(format!("{name}{}", c.maze));
                    crate::plot::render_maze(
                        &maze,
                        &data.picture(title),
                        &stem.with_extension("png"),
                        &stem.with_extension("svg"),
                        20_000,
                    )?;
                    files.push(stem.with_extension("png"));
                    files.push(stem.with_extension("svg"));
                }
            }
            FigureSpec::Curves { .. } => {
                if let Some(curves) = Curves::new(exp, results)? {
                    files.extend(render_figure(&curves, &stem)?);
                }
            }
            FigureSpec::Bars { .. } => {
                files.extend(render_figure(&SuccessBars::new(exp, stats), &stem)?);
            }
            FigureSpec::Chains { .. } => {
                let path = crate::criteria::chains_path(results, &exp.name);
                if path.exists() {
                    let chains = ChainSpread::new(exp, &crate::criteria::read_chains(&path)?);
                    files.extend(render_figure(&chains, &stem)?);
                }
            }
            FigureSpec::Profile { .. } => {
                let path = crate::criteria::chains_path(results, &exp.name);
                if path.exists() {
                    let runs = crate::criteria::read_chains(&path)?;
                    files.extend(render_figure(&Profile::new(exp, &runs), &stem)?);
                }
            }
            FigureSpec::Scaling { .. } => {
                files.extend(render_figure(&Scaling::new(exp, stats)?, &stem)?);
            }
            FigureSpec::Panels { methods, .. } => {
                let solved = |n: usize, m: &str| {
                    stats
                        .iter()
                        .find(|s| s.maze == n && s.method == m)
                        .map_or(0, |s| s.successes as i64)
                };
                let pick = exp.mazes.iter().copied().max_by_key(|&n| {
                    (
                        (solved(n, &methods[0]) - solved(n, &methods[1])).abs(),
                        -(n as i64),
                    )
                });
                let Some(n) = pick else { continue };
                let mut panels = Vec::new();
                for m in methods {
                    let Some(c) = exp.cells.iter().find(|c| c.maze == n && &c.method == m) else {
                        continue;
                    };
                    if let (Some(s), Some(data)) =
                        (stats_of(stats, c), cell_picture(exp, results, c)?)
                    {
                        let title = format!(
                            "{}, maze {n}×{n}, seed {}: {}",
                            c.label,
                            exp.picture_seeds[0],
                            summary(s)
                        );
                        panels.push((cell_maze(c)?, data, title));
                    }
                }
                if !panels.is_empty() {
                    files.extend(render_figure(&Panels { panels }, &stem)?);
                }
            }
        }
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stats(successes: u64, steps_median: f64, solved: Option<f64>) -> CellStats {
        CellStats {
            experiment: "table".into(),
            cell: "pbcs-maze5".into(),
            method: "pbcs".into(),
            label: "PBCS".into(),
            maze: 5,
            n: 10,
            successes,
            success_rate: successes as f64 / 10.0,
            wilson_lo: 0.0,
            wilson_hi: 1.0,
            steps_median,
            steps_q1: steps_median,
            steps_q3: steps_median,
            steps_min: steps_median,
            steps_max: steps_median,
            solved_steps_median: solved,
            solved_within_paper: None,
            skills_median: 1.0,
            success_rate_median: 0.0,
            budget: 400_000,
            paper_steps: None,
            paper_solved: None,
        }
    }

    #[test]
    fn the_fitted_line_recovers_a_power_law() {
        // steps = 500 · L^1.5 exactly: the log–log fit gives back ln 500 and 1.5.
        let pts: Vec<(f64, f64)> = [3.0f64, 8.0, 20.0, 57.0]
            .iter()
            .map(|&l| (l.ln(), (500.0 * l.powf(1.5)).ln()))
            .collect();
        let (a, b) = fit_line(&pts).unwrap();
        assert!(
            (a - 500f64.ln()).abs() < 1e-9 && (b - 1.5).abs() < 1e-12,
            "{a} {b}"
        );
        // Known small case: (0, 1), (1, 3), (2, 5) → y = 1 + 2x.
        assert_eq!(
            fit_line(&[(0.0, 1.0), (1.0, 3.0), (2.0, 5.0)]),
            Some((1.0, 2.0))
        );
        assert_eq!(fit_line(&[(1.0, 1.0)]), None);
        assert_eq!(fit_line(&[(2.0, 1.0), (2.0, 3.0)]), None);
    }

    #[test]
    fn summary_names_the_median_of_solved_runs_or_of_all_runs_or_the_budget() {
        // Unsolved runs stop at the first check past the budget (401 580 here): the band
        // states the budget, never a step count above it.
        assert_eq!(
            summary(&stats(0, 401_580.0, None)),
            "0/10 solved · budget 400k"
        );
        // Unsolved runs that all stopped before the budget: their own median, so labelled.
        assert_eq!(
            summary(&stats(0, 329_000.0, None)),
            "0/10 solved · median 329k (all runs)"
        );
        // One run at the budget is enough for the budget to be what the band says.
        let mut mixed = stats(0, 329_000.0, None);
        mixed.steps_max = 400_900.0;
        assert_eq!(summary(&mixed), "0/10 solved · budget 400k");
        // Solved: the median of the solved runs, labelled, not the median over all runs.
        assert_eq!(
            summary(&stats(7, 300_000.0, Some(171_000.0))),
            "7/10 solved · median 171k"
        );
        assert_eq!(human_steps(1_573_000.0), "1.57M");
    }

    #[test]
    fn the_printed_cells_table_has_one_row_per_cell() {
        let mut c = stats(7, 300_000.0, Some(171_000.0));
        c.wilson_lo = 0.4;
        c.wilson_hi = 0.89;
        c.paper_steps = Some(5_000_000);
        c.paper_solved = Some(true);
        assert_eq!(
            crate::tables::markdown(&[c]),
            "| cell | solved | Wilson 95 % | env steps median [q1, q3] | paper |\n\
             | --- | --- | --- | --- | --- |\n\
             | pbcs-maze5 | 7/10 | [0.40, 0.89] | 300k [300k, 300k] | 5.00M S |\n"
        );
    }

    #[test]
    fn grid_legend_names_colours_band_and_pictures() {
        let exp = crate::experiment::Experiment::load(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/table.toml"),
            Some("smoke"),
        )
        .unwrap();
        let data = PictureData {
            red_paths: vec![vec![(0.5, 0.5), (1.0, 1.0)]],
            ..PictureData::default()
        };
        let maze = cell_maze(&exp.cells[0]).unwrap();
        let cells = vec![vec![Some((maze, data, stats(1, 1.0, Some(1.0))))]];
        let legend = ResultsGrid::legend(&exp, &cells);
        assert!(legend[0].contains("more than half the seeds solved"));
        assert!(legend[1].contains("median environment steps of the solved seeds"));
        assert!(legend[1].contains("step budget"));
        assert_eq!(
            legend[2],
            format!(
                "pictures: seed {}'s run — blue dot: start · green disc: target · red: trajectory τ",
                exp.picture_seeds[0]
            )
        );
    }
}
