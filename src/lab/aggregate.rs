//! The check of the per-cell statistics ([`CellStats`]) by polars (cargo feature `polars`):
//! the table is the plain-Rust computation declared in [`crate::tables::statistics`], and
//! polars computes the statistics again from the raw rows, its own way (grouping, order
//! statistics, the Wilson interval written a second time, [`wilson_exprs`]). Every statistic
//! it has an expression for, matched by column name, must agree, and a disagreement is an
//! error naming the cell and the column: the two implementations keep each other honest every
//! time `make figures` runs.

use crate::error::{Error, Result};
use crate::experiment::{Experiment, RawRow};
use crate::tables::statistics::STATISTICS;
use crate::tables::{cell_stats, CellStats};
use polars::prelude::*;

fn err(exp: &Experiment, e: impl std::fmt::Display) -> Error {
    Error::Aggregate {
        experiment: exp.name.to_string(),
        message: e.to_string(),
    }
}

/// The raw rows as a polars DataFrame (one row per run): the run's cell as its index in the
/// experiment's cells (null for a row of no cell of `exp`), and the paper's steps for that
/// cell (null where the paper gives none).
pub fn raw_frame(exp: &Experiment, rows: &[RawRow]) -> PolarsResult<DataFrame> {
    let index = |r: &RawRow| exp.cells.iter().position(|c| c.id == r.cell);
    let paper = |r: &RawRow| {
        index(r)
            .and_then(|i| exp.cells[i].paper_steps)
            .map(|p| p as f64)
    };
    df!(
        "cell" => rows.iter().map(|r| index(r).map(|i| i as u32)).collect::<Vec<_>>(),
        "paper_steps" => rows.iter().map(paper).collect::<Vec<_>>(),
        "seed" => rows.iter().map(|r| r.seed).collect::<Vec<_>>(),
        "solved" => rows.iter().map(|r| f64::from(u8::from(r.solved))).collect::<Vec<_>>(),
        "env_steps" => rows.iter().map(|r| r.env_steps as f64).collect::<Vec<_>>(),
        "skills" => rows.iter().map(|r| r.skills() as f64).collect::<Vec<_>>(),
        "success_rate" => rows.iter().map(|r| f64::from(r.success_rate)).collect::<Vec<_>>(),
        "budget" => rows.iter().map(|r| r.budget as f64).collect::<Vec<_>>(),
    )
}

/// Per-cell aggregates of the raw frame, one row per cell (sorted by cell index).
pub fn group_cells(frame: DataFrame) -> PolarsResult<DataFrame> {
    let steps = || col("env_steps");
    frame
        .lazy()
        .group_by([col("cell")])
        .agg([
            len().cast(DataType::Float64).alias("n"),
            col("solved").sum().alias("successes"),
            steps().median().alias("steps_median"),
            steps()
                .quantile(lit(0.25), QuantileMethod::Linear)
                .alias("steps_q1"),
            steps()
                .quantile(lit(0.75), QuantileMethod::Linear)
                .alias("steps_q3"),
            (steps().quantile(lit(0.75), QuantileMethod::Linear)
                - steps().quantile(lit(0.25), QuantileMethod::Linear))
            .alias("steps_iqr"),
            steps().min().alias("steps_min"),
            steps().max().alias("steps_max"),
            steps()
                .filter(col("solved").eq(lit(1.0)))
                .median()
                .alias("solved_steps_median"),
            // Empty where the cell has no paper figure, as the plain statistic.
            when(col("paper_steps").first().is_null())
                .then(lit(NULL).cast(DataType::Float64))
                .otherwise(
                    col("solved")
                        .eq(lit(1.0))
                        .and(steps().lt_eq(col("paper_steps")))
                        .cast(DataType::Float64)
                        .sum(),
                )
                .alias("solved_within_paper"),
            col("skills").median().alias("skills_median"),
            col("success_rate").median().alias("success_rate_median"),
            col("budget").first().alias("budget"),
            col("paper_steps").first().alias("paper_steps"),
        ])
        .with_columns(wilson_exprs())
        .with_columns([(col("successes") / col("n")).alias("success_rate")])
        .sort(["cell"], SortMultipleOptions::default())
        .collect()
}

/// The 95 % Wilson score interval of `successes` of `n` as polars expressions (`wilson_lo`,
/// `wilson_hi`): the interval written a second time, so that the plain check, which uses
/// [`crate::stats::wilson`], compares both ends against a second computation (the formula
/// itself is checked against reference values and a bisection of the score test in
/// `tests/stats.rs`).
fn wilson_exprs() -> [Expr; 2] {
    let z = crate::stats::Z95;
    let z2 = z * z;
    let (k, n) = (col("successes"), col("n"));
    let p = k.clone() / n.clone();
    let denom = lit(1.0) + lit(z2) / n.clone();
    // The same operations in the same order as the plain one, so the two agree to the bit.
    let centre = (p.clone() + lit(z2) / (lit(2.0) * n.clone())) / denom.clone();
    let half = lit(z)
        * (p.clone() * (lit(1.0) - p) / n.clone() + lit(z2) / (lit(4.0) * n.clone() * n.clone()))
            .sqrt()
        / denom;
    let (lo, hi) = (centre.clone() - half.clone(), centre + half);
    [
        // Exactly 0 with no success and 1 with no failure; clipped to [0, 1] otherwise.
        when(k.clone().eq(lit(0.0)).or(lo.clone().lt(lit(0.0))))
            .then(lit(0.0))
            .otherwise(lo)
            .alias("wilson_lo"),
        when(k.eq(n).or(hi.clone().gt(lit(1.0))))
            .then(lit(1.0))
            .otherwise(hi)
            .alias("wilson_hi"),
    ]
}

/// The statistics of `rows` of `exp`, one [`CellStats`] per cell with runs in the
/// experiment's cell order ([`cell_stats`]), once polars has computed every statistic it has
/// an expression for and agreed with each (an error names the cell, the column and both
/// values).
pub fn aggregate(exp: &Experiment, rows: &[RawRow]) -> Result<Vec<CellStats>> {
    let grouped = raw_frame(exp, rows)
        .and_then(group_cells)
        .map_err(|e| err(exp, e))?;
    let plain = cell_stats(exp, rows);
    match disagreement(exp, &grouped, &plain).map_err(|e| err(exp, e))? {
        None => Ok(plain),
        Some(why) => Err(err(
            exp,
            format!("polars and the plain computation disagree: {why}"),
        )),
    }
}

/// Where polars' per-cell numbers (`grouped`) and the plain statistics `plain` of `exp`
/// differ, if anywhere: a cell one has and the other not, or a declared statistic
/// ([`STATISTICS`]) polars computes whose values differ beyond floating-point noise
/// (relative 1e-9), or where one is empty and the other not.
fn disagreement(
    exp: &Experiment,
    grouped: &DataFrame,
    plain: &[CellStats],
) -> PolarsResult<Option<String>> {
    let close = |x: f64, y: f64| (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1.0);
    let cells = grouped.column("cell")?.u32()?.clone();
    if cells.len() != plain.len() {
        return Ok(Some(format!(
            "{} cells against {}",
            cells.len(),
            plain.len()
        )));
    }
    for s in plain {
        let index = exp
            .cells
            .iter()
            .position(|c| c.id == s.cell)
            .map(|i| i as u32);
        let Some(i) = (0..cells.len()).find(|&i| cells.get(i) == index) else {
            return Ok(Some(format!("{}: no cell in polars' grouping", s.cell)));
        };
        for stat in STATISTICS {
            let Ok(column) = grouped.column(stat.column) else {
                continue;
            };
            let (ours, theirs) = ((stat.value)(s), column.f64()?.get(i));
            let agree = match (ours, theirs) {
                (Some(p), Some(q)) => close(p, q),
                (None, None) => true,
                _ => false,
            };
            if !agree {
                return Ok(Some(format!(
                    "{}, column `{}`: {ours:?} (plain) against {theirs:?} (polars)",
                    s.cell, stat.column
                )));
            }
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// polars computes every declared statistic but the paper's verdict (which the cell's
    /// declaration gives, not its runs): a statistic added without its polars expression fails
    /// here until it is written, or named here as unchecked.
    #[test]
    fn polars_checks_every_statistic_but_the_papers_verdict() {
        let exp = Experiment::load(std::path::Path::new("experiments/table.toml"), None).unwrap();
        let rows = crate::experiment::read_raw(&exp, std::path::Path::new("results")).unwrap();
        let grouped = raw_frame(&exp, &rows).and_then(group_cells).unwrap();
        let unchecked: Vec<&str> = STATISTICS
            .iter()
            .map(|s| s.column)
            .filter(|c| grouped.column(c).is_err())
            .collect();
        assert_eq!(unchecked, ["paper_solved"]);
    }

    /// polars' aggregation of the committed table's rows agrees with the plain computation,
    /// and the check sees a difference in a statistic polars computes (here the first
    /// quartile, a missing median of solved runs, the paper's figure, the interquartile
    /// range), naming the column.
    #[test]
    fn polars_agrees_with_the_plain_computation_and_the_check_sees_a_difference() {
        let exp = Experiment::load(std::path::Path::new("experiments/table.toml"), None).unwrap();
        let rows = crate::experiment::read_raw(&exp, std::path::Path::new("results")).unwrap();
        let grouped = raw_frame(&exp, &rows).and_then(group_cells).unwrap();
        let plain = cell_stats(&exp, &rows);
        assert_eq!(disagreement(&exp, &grouped, &plain).unwrap(), None);
        assert_eq!(aggregate(&exp, &rows).unwrap(), plain);
        type Change = (&'static str, fn(&mut CellStats));
        let changed: [Change; 4] = [
            ("steps_q1", |s| s.steps_q1 += 1.0),
            ("solved_steps_median", |s| s.solved_steps_median = None),
            ("paper_steps", |s| {
                s.paper_steps = s.paper_steps.map(|p| p + 1).or(Some(1))
            }),
            ("steps_iqr", |s| s.steps_iqr *= 2.0),
        ];
        for (column, change) in changed {
            let mut other = plain.clone();
            let cell = other
                .iter_mut()
                .find(|s| s.solved_steps_median.is_some() && s.steps_iqr > 0.0)
                .unwrap();
            change(cell);
            let why = disagreement(&exp, &grouped, &other).unwrap().unwrap();
            assert!(why.contains(&format!("`{column}`")), "{column}: {why}");
        }
    }
}
