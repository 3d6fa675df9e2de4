//! Each statistic of a cell declared once: its column in `results/tables/<experiment>.csv` (a
//! field of [`CellStats`]), its field in the report's `\res{<experiment>:<cell>:<field>}`, how
//! the report prints it and its value, read and set by polars' aggregation. `numbers.tex`
//! ([`crate::report::numbers_tex`]), polars' aggregation (which fills each column it computes by
//! name) and its check against the plain one read this list; a test holds it to the table's
//! columns, so no column is added to the table without its declaration. Adding a statistic:
//! its field in [`CellStats`] (and its zero in [`CellStats::counted`] and in the tests that
//! build a `CellStats` whole), its declaration here, its computation in
//! [`crate::tables::cell_stats`], and polars' expression for it (the second computation, in
//! `aggregate::group_cells`).

use super::CellStats;
use crate::fmt::human_steps;

/// One statistic of a cell.
#[derive(Debug, Clone, Copy)]
pub struct Statistic {
    /// Its column in the table: the [`CellStats`] field's name.
    pub column: &'static str,
    /// Its field in `\res{<experiment>:<cell>:<field>}`; none for a column the report does not
    /// quote.
    pub res: Option<&'static str>,
    /// Its value as the report prints it (`--` where a cell has none).
    pub print: fn(&CellStats) -> String,
    /// Its value as a number (none where a cell has none): what polars' aggregation must
    /// reproduce.
    pub value: fn(&CellStats) -> Option<f64>,
    /// Sets it from a number ([`Statistic::value`]'s inverse): how polars' aggregation fills
    /// the columns it computes, by name.
    pub set: fn(&mut CellStats, Option<f64>),
}

/// Every statistic of [`CellStats`], in the order `numbers.tex` defines them (the columns the
/// report does not quote last).
pub const STATISTICS: &[Statistic] = &[
    Statistic {
        column: "n",
        res: Some("n"),
        print: |s| s.n.to_string(),
        value: |s| Some(s.n as f64),
        set: |s, v| s.n = v.unwrap_or(f64::NAN) as u64,
    },
    Statistic {
        column: "successes",
        res: Some("successes"),
        print: |s| s.successes.to_string(),
        value: |s| Some(s.successes as f64),
        set: |s, v| s.successes = v.unwrap_or(f64::NAN) as u64,
    },
    Statistic {
        column: "success_rate",
        res: Some("rate"),
        print: |s| format!("{:.2}", s.success_rate),
        value: |s| Some(s.success_rate),
        set: |s, v| s.success_rate = v.unwrap_or(f64::NAN),
    },
    Statistic {
        column: "wilson_lo",
        res: Some("lo"),
        print: |s| format!("{:.2}", s.wilson_lo),
        value: |s| Some(s.wilson_lo),
        set: |s, v| s.wilson_lo = v.unwrap_or(f64::NAN),
    },
    Statistic {
        column: "wilson_hi",
        res: Some("hi"),
        print: |s| format!("{:.2}", s.wilson_hi),
        value: |s| Some(s.wilson_hi),
        set: |s, v| s.wilson_hi = v.unwrap_or(f64::NAN),
    },
    Statistic {
        column: "steps_median",
        res: Some("median"),
        print: |s| human_steps(s.steps_median),
        value: |s| Some(s.steps_median),
        set: |s, v| s.steps_median = v.unwrap_or(f64::NAN),
    },
    Statistic {
        column: "steps_q1",
        res: Some("q1"),
        print: |s| human_steps(s.steps_q1),
        value: |s| Some(s.steps_q1),
        set: |s, v| s.steps_q1 = v.unwrap_or(f64::NAN),
    },
    Statistic {
        column: "steps_q3",
        res: Some("q3"),
        print: |s| human_steps(s.steps_q3),
        value: |s| Some(s.steps_q3),
        set: |s, v| s.steps_q3 = v.unwrap_or(f64::NAN),
    },
    Statistic {
        column: "steps_iqr",
        res: Some("iqr"),
        print: |s| human_steps(s.steps_iqr),
        value: |s| Some(s.steps_iqr),
        set: |s, v| s.steps_iqr = v.unwrap_or(f64::NAN),
    },
    Statistic {
        column: "solved_steps_median",
        res: Some("solvedmedian"),
        print: |s| s.solved_steps_median.map_or("--".into(), human_steps),
        value: |s| s.solved_steps_median,
        set: |s, v| s.solved_steps_median = v,
    },
    Statistic {
        column: "skills_median",
        res: Some("skills"),
        print: |s| s.skills_median.to_string(),
        value: |s| Some(s.skills_median),
        set: |s, v| s.skills_median = v.unwrap_or(f64::NAN),
    },
    Statistic {
        column: "success_rate_median",
        res: Some("evalmedian"),
        print: |s| format!("{:.2}", s.success_rate_median),
        value: |s| Some(s.success_rate_median),
        set: |s, v| s.success_rate_median = v.unwrap_or(f64::NAN),
    },
    Statistic {
        column: "solved_within_paper",
        res: Some("withinpaper"),
        print: |s| s.solved_within_paper.map_or("--".into(), |k| k.to_string()),
        value: |s| s.solved_within_paper.map(|k| k as f64),
        set: |s, v| s.solved_within_paper = v.map(|k| k as u64),
    },
    Statistic {
        column: "budget",
        res: Some("budget"),
        print: |s| human_steps(s.budget as f64),
        value: |s| Some(s.budget as f64),
        set: |s, v| s.budget = v.unwrap_or(f64::NAN) as u64,
    },
    Statistic {
        column: "paper_steps",
        res: Some("paper"),
        print: |s| s.paper_steps.map_or("--".into(), |p| human_steps(p as f64)),
        value: |s| s.paper_steps.map(|p| p as f64),
        set: |s, v| s.paper_steps = v.map(|p| p as u64),
    },
    Statistic {
        column: "steps_min",
        res: None,
        print: |s| human_steps(s.steps_min),
        value: |s| Some(s.steps_min),
        set: |s, v| s.steps_min = v.unwrap_or(f64::NAN),
    },
    Statistic {
        column: "steps_max",
        res: None,
        print: |s| human_steps(s.steps_max),
        value: |s| Some(s.steps_max),
        set: |s, v| s.steps_max = v.unwrap_or(f64::NAN),
    },
    Statistic {
        column: "paper_solved",
        res: None,
        print: |s| s.paper_solved.map_or("--".into(), |b| b.to_string()),
        value: |s| s.paper_solved.map(|b| f64::from(u8::from(b))),
        set: |s, v| s.paper_solved = v.map(|b| b != 0.0),
    },
];

/// The table's columns that name a cell rather than summarise its runs.
pub const IDENTITY: [&str; 5] = ["experiment", "cell", "method", "label", "maze"];

#[cfg(test)]
mod tests {
    use super::*;

    /// The declarations and the table's columns are the same set: a column added to
    /// [`CellStats`] without its declaration (or a declaration without its column) fails here.
    #[test]
    fn every_column_of_the_table_is_declared_once() {
        let mut w = csv::Writer::from_writer(Vec::new());
        let exp = crate::experiment::Experiment::load(
            std::path::Path::new("experiments/table.toml"),
            None,
        )
        .unwrap();
        let stats = CellStats::counted(&exp, &exp.cells[0], 1, 2);
        w.serialize(&stats).unwrap();
        let text = String::from_utf8(w.into_inner().unwrap()).unwrap();
        let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
        let mut columns: Vec<&str> = header
            .iter()
            .copied()
            .filter(|c| !IDENTITY.contains(c))
            .collect();
        let mut declared: Vec<&str> = STATISTICS.iter().map(|s| s.column).collect();
        columns.sort();
        declared.sort();
        assert_eq!(declared, columns);
        let mut res: Vec<&str> = STATISTICS.iter().filter_map(|s| s.res).collect();
        let n = res.len();
        res.sort();
        res.dedup();
        assert_eq!(res.len(), n, "a \\res field declared twice");
        // A known cell prints as the report quotes it: 1 of 2 runs, Wilson's interval.
        let printed = |column: &str| {
            let s = STATISTICS.iter().find(|s| s.column == column).unwrap();
            (s.print)(&stats)
        };
        assert_eq!(
            (printed("n"), printed("success_rate"), printed("wilson_lo")),
            ("2".to_string(), "0.50".to_string(), "0.09".to_string())
        );
    }
}
