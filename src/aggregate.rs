//! Aggregation of raw results with polars (cargo feature `polars`): raw rows → per-cell
//! statistics ([`CellStats`]): n, successes, Wilson 95 % interval, median and quartiles of
//! environment steps, and the paper's figure beside ours.
//!
//! polars does the grouping, the order statistics and the Wilson interval (written there a
//! second time, [`wilson_exprs`]). Every number is then checked against the plain-Rust computation of
//! [`crate::tables::cell_stats`], and a disagreement is an error: the two implementations keep
//! each other honest every time `make figures` runs.

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
        "skills" => rows.iter().map(|r| r.skills as f64).collect::<Vec<_>>(),
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
            col("solved")
                .eq(lit(1.0))
                .and(steps().lt_eq(col("paper_steps")))
                .cast(DataType::Float64)
                .sum()
                .alias("solved_within_paper"),
            col("skills").median().alias("skills_median"),
            col("success_rate").median().alias("success_rate_median"),
            col("budget").first().alias("budget"),
        ])
        .with_columns(wilson_exprs())
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

/// Aggregates `rows` of `exp` with polars into one [`CellStats`] per cell with runs, in the
/// experiment's cell order, and checks every number against the plain-Rust computation.
pub fn aggregate(exp: &Experiment, rows: &[RawRow]) -> Result<Vec<CellStats>> {
    let grouped = raw_frame(exp, rows)
        .and_then(group_cells)
        .map_err(|e| err(exp, e))?;
    let cells = grouped
        .column("cell")
        .and_then(|c| c.u32().cloned())
        .map_err(|e| err(exp, e))?;
    let num = |name: &str, i: usize| -> Result<Option<f64>> {
        grouped
            .column(name)
            .and_then(|c| c.f64().map(|c| c.get(i)))
            .map_err(|e| err(exp, e))
    };
    let mut out = Vec::new();
    for (index, c) in exp.cells.iter().enumerate() {
        let Some(i) = (0..grouped.height()).find(|&i| cells.get(i) == Some(index as u32)) else {
            continue;
        };
        let get = |name: &str| -> Result<f64> {
            num(name, i)?.ok_or_else(|| err(exp, format!("{}: no `{name}`", c.id)))
        };
        let (n, k) = (get("n")? as u64, get("successes")? as u64);
        // Every declared statistic polars computes, by its column's name (polars' own Wilson
        // interval among them: `same` checks it against the plain one).
        let mut stats = CellStats::counted(exp, c, k, n);
        for stat in STATISTICS {
            if grouped.column(stat.column).is_ok() {
                (stat.set)(&mut stats, num(stat.column, i)?);
            }
        }
        // Null paper steps count nothing; the paper's figure decides whether there is one.
        if c.paper_steps.is_none() {
            stats.solved_within_paper = None;
        }
        out.push(stats);
    }
    let plain = cell_stats(exp, rows);
    if !same(&out, &plain) {
        return Err(err(
            exp,
            format!("polars and the plain computation disagree:\n{out:?}\n{plain:?}"),
        ));
    }
    Ok(out)
}

/// Equal cell by cell in every declared statistic
/// ([`crate::tables::statistics::STATISTICS`]), up to floating-point noise (relative 1e-9).
fn same(a: &[CellStats], b: &[CellStats]) -> bool {
    let close = |x: f64, y: f64| (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1.0);
    a.len() == b.len()
        && a.iter().zip(b).all(|(x, y)| {
            x.cell == y.cell
                && STATISTICS
                    .iter()
                    .all(|stat| match ((stat.value)(x), (stat.value)(y)) {
                        (Some(p), Some(q)) => close(p, q),
                        (None, None) => true,
                        _ => false,
                    })
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// polars' aggregation of the committed table's rows agrees with the plain computation,
    /// and the comparison sees a difference in any declared statistic (here the first
    /// quartile, a missing median of solved runs, the paper's figure).
    #[test]
    fn polars_agrees_with_the_plain_computation_and_the_check_sees_a_difference() {
        let exp = Experiment::load(std::path::Path::new("experiments/table.toml"), None).unwrap();
        let rows = crate::experiment::read_raw(&exp, std::path::Path::new("results")).unwrap();
        let ours = aggregate(&exp, &rows).unwrap();
        let plain = cell_stats(&exp, &rows);
        assert!(same(&ours, &plain));
        let changed: [fn(&mut CellStats); 3] = [
            |s| s.steps_q1 += 1.0,
            |s| s.solved_steps_median = None,
            |s| s.paper_steps = s.paper_steps.map(|p| p + 1).or(Some(1)),
        ];
        for change in changed {
            let mut other = plain.clone();
            let cell = other
                .iter_mut()
                .find(|s| s.solved_steps_median.is_some())
                .unwrap();
            change(cell);
            assert!(!same(&ours, &other));
        }
    }
}
