//! The paper's maze pictures: the results grid (Figure 3's layout, one maze or other
//! environment per cell with its τ, chain rollouts and activation balls) and side-by-side
//! panels of two methods.

use super::{cell_picture, centred_text, stats_of, summary, DrawResult, GREEN_BG, RED_BG};
use crate::env::Scene;
use crate::error::Result;
use crate::experiment::{CellKey, Experiment};
use crate::picture::PictureData;
use crate::plot::{draw_scene, Figure};
use crate::tables::CellStats;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// The results table as a grid of pictures: rows = sites (maze sizes, environments), columns =
/// methods; each cell
/// shows the first picture seed's run and is labelled with its [`summary`] on a green (more
/// than half the seeds solved) or red background; a legend under the grid says so.
pub struct ResultsGrid {
    cells: Vec<Vec<Option<GridCell>>>,
    rows: Vec<String>,
    columns: Vec<String>,
    /// The legend's lines (see [`ResultsGrid::legend`]), wrapped where the grid is too narrow
    /// for them ([`wrap_legend`]).
    legend: Vec<String>,
    /// The legend's font size where its lines were wrapped; None: each line as large as its
    /// width allows (at most 15).
    legend_font: Option<f64>,
}

/// The smallest font a legend line is drawn in before it is wrapped instead.
const LEGEND_FONT_MIN: f64 = 8.0;

/// The font size of wrapped legend lines.
const LEGEND_FONT_WRAPPED: f64 = 10.0;

/// Where a legend line of `chars` characters starts at `x` in a grid `w` pixels wide: the font
/// size that fits it (sans-serif is about 0.55 em a character).
fn legend_font(w: u32, x: i32, chars: usize) -> f64 {
    (w as f64 - x as f64 - 10.0) / (0.55 * chars.max(1) as f64)
}

/// The x of legend line `i`: the first follows two colour swatches.
fn legend_x(i: usize) -> i32 {
    GRID_LEFT as i32 + if i == 0 { 68 } else { 0 }
}

/// The legend's lines for a grid `w` pixels wide: as they are where each fits at
/// [`LEGEND_FONT_MIN`] or more, else every line broken at spaces to fit at
/// [`LEGEND_FONT_WRAPPED`] (a one-column grid), with that font size.
fn wrap_legend(lines: Vec<String>, w: u32) -> (Vec<String>, Option<f64>) {
    let fits = lines
        .iter()
        .enumerate()
        .all(|(i, l)| legend_font(w, legend_x(i), l.chars().count()) >= LEGEND_FONT_MIN);
    if fits {
        return (lines, None);
    }
    let mut out: Vec<String> = Vec::new();
    for line in lines {
        let mut current = String::new();
        for word in line.split(' ') {
            let longer = if current.is_empty() {
                word.to_string()
            } else {
                format!("{current} {word}")
            };
            let x = legend_x(out.len());
            if !current.is_empty()
                && legend_font(w, x, longer.chars().count()) < LEGEND_FONT_WRAPPED
            {
                out.push(std::mem::take(&mut current));
                current = word.to_string();
            } else {
                current = longer;
            }
        }
        out.push(current);
    }
    (out, Some(LEGEND_FONT_WRAPPED))
}

/// One drawn cell of the grid: its scene, its picture seed's run and its statistics.
pub(crate) type GridCell = (Scene, PictureData, CellStats);

pub(crate) const GRID_CELL: u32 = 280;

pub(crate) const GRID_LABEL: u32 = 26;

/// Height of one legend line under the grid.
pub(crate) const GRID_LEGEND_LINE: u32 = 22;

/// Width of the row labels.
pub(crate) const GRID_LEFT: u32 = 70;

impl ResultsGrid {
    /// Collects the grid of `exp` from its table and picture data.
    pub fn new(exp: &Experiment, results: &Path, stats: &[CellStats]) -> Result<ResultsGrid> {
        let mut cells = Vec::new();
        for &n in &exp.sites {
            let mut row = Vec::new();
            for (m, _) in &exp.methods {
                let cell = exp.cell_at(CellKey::new(*m, n))?;
                row.push(
                    match (stats_of(stats, cell), cell_picture(exp, results, cell)?) {
                        (Some(s), Some(p)) => Some((cell.scene()?, p, s.clone())),
                        _ => None,
                    },
                );
            }
            cells.push(row);
        }
        let width = GRID_LEFT + GRID_CELL * exp.methods.len() as u32;
        let (legend, legend_font) = wrap_legend(ResultsGrid::legend(exp, &cells), width);
        Ok(ResultsGrid {
            cells,
            rows: exp.sites.iter().map(|n| n.axis()).collect(),
            columns: exp.methods.iter().map(|(_, l)| l.clone()).collect(),
            legend,
            legend_font,
        })
    }

    /// What the bands and the pictures show, one line each; the first line follows the two
    /// colour swatches drawn before it.
    pub(super) fn legend(exp: &Experiment, cells: &[Vec<Option<GridCell>>]) -> Vec<String> {
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
            let size = self
                .legend_font
                .unwrap_or_else(|| legend_font(w, x, line.chars().count()));
            footer.draw(&Text::new(
                line.clone(),
                (x, y),
                ("sans-serif", size.clamp(LEGEND_FONT_MIN, 15.0))
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
                Some((scene, data, s)) => {
                    let colour = if 2 * s.successes > s.n {
                        GREEN_BG
                    } else {
                        RED_BG
                    };
                    band.fill(&colour)?;
                    centred_text(&band, &summary(s), 15, &WHITE)?;
                    draw_scene(picture, scene, &data.picture(String::new()))?;
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

/// Pictures side by side, each with a title (the unseen-states contrast).
pub struct Panels {
    /// (scene, its picture data, panel title), left to right.
    pub panels: Vec<(Scene, PictureData, String)>,
}

impl Figure for Panels {
    fn size(&self) -> (u32, u32) {
        (520 * self.panels.len() as u32, 560)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        for (area, (scene, data, title)) in root
            .split_evenly((1, self.panels.len()))
            .iter()
            .zip(&self.panels)
        {
            draw_scene(area.clone(), scene, &data.picture(title.clone()))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines() -> Vec<String> {
        vec![
            "more than half the seeds solved / half or fewer (grey: no runs yet)".to_string(),
            "pictures: seed 0's run — blue dot: start · green disc: target · red: trajectory τ \
             · green: chain rollouts · purple: activation balls"
                .to_string(),
        ]
    }

    #[test]
    fn a_wide_grid_keeps_its_legend_lines_as_they_are() {
        let w = GRID_LEFT + 4 * GRID_CELL;
        assert_eq!(wrap_legend(lines(), w), (lines(), None));
    }

    #[test]
    fn a_one_column_grid_wraps_its_legend_so_that_every_word_is_drawn() {
        let w = GRID_LEFT + GRID_CELL;
        let (wrapped, font) = wrap_legend(lines(), w);
        assert_eq!(font, Some(LEGEND_FONT_WRAPPED));
        assert!(wrapped.len() > lines().len());
        for (i, l) in wrapped.iter().enumerate() {
            let f = legend_font(w, legend_x(i), l.chars().count());
            assert!(f >= LEGEND_FONT_WRAPPED, "line {i} `{l}` needs font {f}");
        }
        // Nothing lost: the same words in the same order.
        let words = |v: &[String]| v.join(" ").split(' ').map(String::from).collect::<Vec<_>>();
        assert_eq!(words(&wrapped), words(&lines()));
    }
}
