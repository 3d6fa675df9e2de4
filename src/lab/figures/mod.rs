//! The paper's figures, drawn with plotters from the aggregated tables and the raw picture
//! data (no training): the results grid, the enlarged results, the γ study with Wilson error
//! bars, the reset-in-unseen-states contrast and the vanilla learning curves.
//!
//! Every figure is written as PNG and SVG with the bundled font (see [`crate::plot`]).

mod bars;
mod columns;
mod curves;
mod grid;
mod routes;
mod scaling;

pub use bars::{ChainSpread, Profile, SuccessBars};
pub use curves::Curves;
pub use grid::{Panels, ResultsGrid};
pub use routes::Routes;
pub use scaling::Scaling;

use crate::error::{Error, Result};
use crate::experiment::{picture_file, Cell, CellKey, Experiment, FigureSpec, Method, Site};
use crate::fmt::human_steps;
use crate::picture::PictureData;
use crate::plot::render_figure;
use crate::tables::curves::{curves_path, read_curves};
use crate::tables::scaling::{read_paths_and_fit, ScalingData};
use crate::tables::CellStats;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

type DrawResult<DB> =
    std::result::Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

const GREEN_BG: RGBColor = RGBColor(46, 160, 67);

const RED_BG: RGBColor = RGBColor(200, 50, 50);

/// Colours of methods in bar charts and curves (colour-blind-safe Okabe–Ito).
const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(230, 159, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(86, 180, 233),
    RGBColor(213, 94, 0),
    RGBColor(120, 120, 120),
    RGBColor(40, 40, 40),
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

/// The picture data of a cell's first picture seed: none while that seed has no row yet; an
/// error naming the file where its row exists and its picture data does not (a figure never
/// draws "no runs yet" over runs that exist).
fn cell_picture(exp: &Experiment, results: &Path, cell: &Cell) -> Result<Option<PictureData>> {
    let Some(&seed) = exp.picture_seeds.first() else {
        return Ok(None);
    };
    let path = picture_file(exp, results, cell, seed);
    if !path.exists() {
        let row = crate::experiment::run_file(&exp.cell_dir(results, cell), seed, ".csv");
        if row.exists() {
            return Err(Error::parse(
                &path,
                format!(
                    "missing: seed {seed} of cell {} has its row ({}) but not the picture data \
                     its figures draw (restore the file, or remove the row and run the seed \
                     again)",
                    cell.id,
                    row.display()
                ),
            ));
        }
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

/// `text` centred in `area` at `size` pixels, or smaller (down to 8) where it would not fit
/// its width (a long row label, `three_rooms`, beside a grid's narrow left margin).
fn centred_text<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    text: &str,
    size: u32,
    colour: &RGBColor,
) -> DrawResult<DB> {
    let (w, h) = area.dim_in_pixel();
    let fits = |size: u32| {
        let style = TextStyle::from(("sans-serif", size).into_font());
        area.estimate_text_size(text, &style)
            .is_ok_and(|(tw, _)| tw + 4 <= w)
    };
    let size = (8..=size).rev().find(|&s| fits(s)).unwrap_or(size.min(8));
    let style = TextStyle::from(("sans-serif", size).into_font())
        .color(colour)
        .pos(plotters::style::text_anchor::Pos::new(
            plotters::style::text_anchor::HPos::Center,
            plotters::style::text_anchor::VPos::Center,
        ));
    area.draw_text(text, &style, (w as i32 / 2, h as i32 / 2))
}

/// The whole powers of ten around [lo, hi] (a log axis over whole decades gets labels).
fn decades(lo: f64, hi: f64) -> std::ops::Range<f64> {
    let lo = 10f64.powf(lo.max(1e-9).log10().floor());
    let hi = 10f64.powf(hi.max(lo).log10().ceil()).max(lo * 10.0);
    lo..hi
}

/// Draws every figure `exp` declares ([`FigureSpec`]) into `out` from its table `stats`, the
/// raw picture and evaluation files under `results` and the tables beside `stats` (chains,
/// routes; for a scaling figure, `<exp>.paths.csv` and the fit `<exp>.scaling_fit.csv`, which
/// must be there and agree with `stats`); returns the files written. A figure whose data is
/// missing (no picture kept, no vanilla method for curves, no chains or routes table) is
/// skipped.
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
                files.extend(maze_pictures(exp, results, stats, out, name, *method)?);
            }
            FigureSpec::Curves { .. } => {
                let path = curves_path(results, exp.name);
                if path.exists() {
                    if let Some(curves) = Curves::new(exp, &read_curves(&path)?) {
                        files.extend(render_figure(&curves, &stem)?);
                    }
                }
            }
            FigureSpec::Bars { baselines, .. } => {
                let mut bars = SuccessBars::new(exp, stats);
                // Each is put first: the last listed goes in first, so they end in their order.
                for b in baselines.iter().rev() {
                    let path = crate::tables::table_path(results, b.experiment);
                    if path.exists() {
                        bars = bars.with_baseline(b, &crate::tables::read_table(&path)?);
                    }
                }
                files.extend(render_figure(&bars, &stem)?);
            }
            FigureSpec::Chains { .. } => {
                let path = crate::criteria::chains_path(results, exp.name);
                if path.exists() {
                    let chains = ChainSpread::new(exp, &crate::criteria::read_chains(&path)?);
                    files.extend(render_figure(&chains, &stem)?);
                }
            }
            FigureSpec::Profile { .. } => {
                let path = crate::criteria::chains_path(results, exp.name);
                if path.exists() {
                    let runs = crate::criteria::read_chains(&path)?;
                    files.extend(render_figure(&Profile::new(exp, &runs), &stem)?);
                }
            }
            FigureSpec::Routes { .. } => {
                let path = crate::tables::routes::routes_path(results, exp.name);
                if path.exists() {
                    let routes = crate::tables::routes::read_routes(&path)?;
                    files.extend(render_figure(&Routes::new(exp, &routes), &stem)?);
                }
            }
            FigureSpec::Scaling { .. } => {
                let (paths, fit) = read_paths_and_fit(results, exp.name)?;
                let data = ScalingData::new(exp, stats, &paths, fit)?;
                files.extend(render_figure(&Scaling::new(exp, data), &stem)?);
            }
            FigureSpec::Panels { methods, .. } => {
                if let Some(panels) = panels(exp, results, stats, methods)? {
                    files.extend(render_figure(&panels, &stem)?);
                }
            }
        }
    }
    Ok(files)
}

/// One picture per cell of `method` (its first picture seed's τ, chain rollouts and balls),
/// `<name><N>.{png,svg}` in `out`; cells without a picture or a table row are skipped.
fn maze_pictures(
    exp: &Experiment,
    results: &Path,
    stats: &[CellStats],
    out: &Path,
    name: &str,
    method: Method,
) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for c in exp.cells.iter().filter(|c| c.method == method) {
        let (Some(s), Some(data)) = (stats_of(stats, c), cell_picture(exp, results, c)?) else {
            continue;
        };
        let title = format!(
            "{}, {}, seed {}: phase-1 τ (red), chain rollouts (green), activation balls \
             (purple) — {}",
            c.label,
            c.site.title(),
            exp.picture_seeds[0],
            summary(s)
        );
        let stem = out.join(format!("{name}{}", c.site));
        crate::plot::render_scene(
            &c.scene()?,
            &data.picture(title),
            &stem.with_extension("png"),
            &stem.with_extension("svg"),
            crate::plot::SVG_MAX_POINTS,
        )?;
        files.push(stem.with_extension("png"));
        files.push(stem.with_extension("svg"));
    }
    Ok(files)
}

/// Side-by-side pictures of `methods` on the site where the first two differ most in solved
/// runs (the first such site: the smallest maze); `None` when no cell has a picture.
fn panels(
    exp: &Experiment,
    results: &Path,
    stats: &[CellStats],
    methods: &[Method],
) -> Result<Option<Panels>> {
    let solved = |n: Site, m: Method| {
        stats
            .iter()
            .find(|s| s.site == n && s.method == m)
            .map_or(0, |s| s.successes as i64)
    };
    let pick = exp.sites.iter().copied().max_by_key(|&n| {
        (
            (solved(n, methods[0]) - solved(n, methods[1])).abs(),
            std::cmp::Reverse(n),
        )
    });
    let Some(n) = pick else { return Ok(None) };
    let mut panels = Vec::new();
    for &m in methods {
        let Ok(c) = exp.cell_at(CellKey::new(m, n)) else {
            continue;
        };
        if let (Some(s), Some(data)) = (stats_of(stats, c), cell_picture(exp, results, c)?) {
            let title = format!(
                "{}, {}, seed {}: {}",
                c.label,
                n.title(),
                exp.picture_seeds[0],
                summary(s)
            );
            panels.push((c.scene()?, data, title));
        }
    }
    Ok((!panels.is_empty()).then_some(Panels { panels }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stats(successes: u64, steps_median: f64, solved: Option<f64>) -> CellStats {
        let empty = CellStats::empty(
            "table".parse().unwrap(),
            "pbcs-maze5".parse().unwrap(),
            "PBCS",
        );
        CellStats {
            steps_median,
            steps_q1: steps_median,
            steps_q3: steps_median,
            steps_min: steps_median,
            steps_max: steps_median,
            solved_steps_median: solved,
            skills_median: 1.0,
            budget: 400_000,
            ..empty.with_counts(successes, 10)
        }
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
            tau_paths: vec![vec![(0.5, 0.5), (1.0, 1.0)]],
            ..PictureData::default()
        };
        let scene = exp.cells[0].scene().unwrap();
        let cells = vec![vec![Some((scene, data, stats(1, 1.0, Some(1.0))))]];
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
