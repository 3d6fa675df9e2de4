//! Environment steps against the shortest path's length, log–log, with the fitted power law
//! ([`crate::tables::scaling`] holds the data and the fit).

use super::{decades, DrawResult, PALETTE};
use crate::experiment::Experiment;
use crate::fmt::human_steps;
use crate::plot::Figure;
use crate::tables::scaling::ScalingData;
use plotters::coord::Shift;
use plotters::prelude::*;

/// Environment steps against the length of the maze's shortest path, log–log, one series per
/// method, with the least-squares power law through the cells' medians (the data and the fit:
/// [`ScalingData`], from the tables).
pub struct Scaling {
    title: String,
    data: ScalingData,
}

impl Scaling {
    /// The scaling figure of `exp` from its scaling data.
    pub fn new(exp: &Experiment, data: ScalingData) -> Scaling {
        Scaling {
            title: exp.title.clone(),
            data,
        }
    }
}

impl Figure for Scaling {
    fn size(&self) -> (u32, u32) {
        (760, 560)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let points = self.data.series.iter().flat_map(|s| &s.1);
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, 1.0f64, f64::MAX, 1.0f64);
        for p in points {
            (x0, x1) = (x0.min(p.0), x1.max(p.0));
            (y0, y1) = (y0.min(p.2.max(1.0)), y1.max(p.3));
        }
        if x0 > x1 {
            (x0, y0) = (1.0, 1.0);
        }
        let caption = match self.data.fit.line() {
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
        if let Some((a, b)) = self.data.fit.line() {
            let line = [x0, x1].map(|x| (x, (a + b * x.ln()).exp()));
            chart
                .draw_series(LineSeries::new(line, BLACK.mix(0.5).stroke_width(1)))?
                .label(format!("fit: {:.0} · L^{b:.2}", a.exp()))
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.mix(0.5)));
        }
        for (i, (label, points)) in self.data.series.iter().enumerate() {
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
