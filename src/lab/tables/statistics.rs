//! Each statistic of a cell declared once, in [`statistics!`]'s list below: its column in
//! `results/tables/<experiment>.csv` (a field of [`CellStats`], in the table's order), its
//! field in the report's `\res{<experiment>:<cell>:<field>}`, how the report prints it, and
//! how it is computed from the cell's runs ([`Runs`]). From that one list come the row type
//! [`CellStats`], its computation [`CellStats::of`], and [`STATISTICS`], which
//! `numbers.tex` ([`crate::report::numbers_tex`]), polars' check
//! ([`crate::aggregate`]) and the claims' tests read.
//!
//! Adding a statistic is one entry: its doc line, `name: type`, `res`, `print` and `of`. polars
//! checks the statistics it has an expression for (`aggregate::group_cells`, by column name);
//! its test `polars_checks_every_statistic_but_the_papers_verdict` lists the one it does not,
//! so a new statistic is checked by polars or named there.

use crate::experiment::{Cell, CellKey, Experiment, ExperimentName, Method, RawRow, Site};
use crate::fmt::human_steps;
use crate::stats::{median, quantile, wilson, Z95};
use serde::{Deserialize, Serialize};

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
    /// Its value as a number (none where a cell has none): what polars' check compares.
    pub value: fn(&CellStats) -> Option<f64>,
}

/// What a statistic is computed from: one cell and its finished runs (at least one).
pub struct Runs<'a> {
    /// The cell.
    pub cell: &'a Cell,
    /// Its runs' rows.
    pub rows: Vec<&'a RawRow>,
}

impl<'a> Runs<'a> {
    /// The runs of `cell` among `rows`; none without any.
    pub fn of(cell: &'a Cell, rows: &'a [RawRow]) -> Option<Runs<'a>> {
        let rows: Vec<&RawRow> = rows.iter().filter(|r| r.cell == cell.id).collect();
        (!rows.is_empty()).then_some(Runs { cell, rows })
    }

    /// Runs.
    pub fn n(&self) -> u64 {
        self.rows.len() as u64
    }

    /// Runs solved.
    pub fn solved(&self) -> u64 {
        self.rows.iter().filter(|r| r.solved).count() as u64
    }

    /// `f` of each run.
    pub fn each(&self, f: impl Fn(&RawRow) -> f64) -> Vec<f64> {
        self.rows.iter().map(|r| f(r)).collect()
    }

    /// Environment steps of each run.
    pub fn steps(&self) -> Vec<f64> {
        self.each(|r| r.env_steps as f64)
    }

    /// Environment steps of each solved run.
    pub fn solved_steps(&self) -> Vec<f64> {
        let solved = self.rows.iter().filter(|r| r.solved);
        solved.map(|r| r.env_steps as f64).collect()
    }

    /// The 95 % Wilson interval of the solved runs.
    pub fn wilson(&self) -> (f64, f64) {
        wilson(self.solved(), self.n(), Z95)
    }
}

/// The median of `v`.
fn median_of(mut v: Vec<f64>) -> f64 {
    median(&mut v)
}

/// The `q` quantile of `v` (linear interpolation).
fn quantile_of(mut v: Vec<f64>, q: f64) -> f64 {
    quantile(&mut v, q)
}

/// A statistic's value as a number, whatever its type.
trait AsNumber {
    fn number(&self) -> Option<f64>;
}

impl AsNumber for f64 {
    fn number(&self) -> Option<f64> {
        Some(*self)
    }
}

impl AsNumber for u64 {
    fn number(&self) -> Option<f64> {
        Some(*self as f64)
    }
}

impl AsNumber for bool {
    fn number(&self) -> Option<f64> {
        Some(f64::from(u8::from(*self)))
    }
}

impl<T: AsNumber> AsNumber for Option<T> {
    fn number(&self) -> Option<f64> {
        self.as_ref().and_then(AsNumber::number)
    }
}

/// Declares [`CellStats`] (the cell's identity, then each statistic as a field), its
/// computation [`CellStats::of`] and [`STATISTICS`], from one list of statistics.
macro_rules! statistics {
    ($($(#[$doc:meta])* $field:ident: $ty:ty, res $res:expr, print $print:expr, of $of:expr;)*) => {
        /// One cell's statistics over its seeds: a line of `results/tables/<experiment>.csv`.
        #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
        pub struct CellStats {
            /// Experiment name.
            pub experiment: ExperimentName,
            /// The cell.
            pub cell: CellKey,
            /// Its method.
            pub method: Method,
            /// The method's label.
            pub label: String,
            /// Where the cell runs: maze size N or another environment's name (column `maze`).
            #[serde(rename = "maze")]
            pub site: Site,
            $($(#[$doc])* pub $field: $ty,)*
        }

        impl CellStats {
            /// The statistics of `runs`, cell of `exp`.
            pub fn of(exp: &Experiment, runs: &Runs) -> CellStats {
                let c = runs.cell;
                CellStats {
                    experiment: exp.name,
                    cell: c.id,
                    method: c.method,
                    label: c.label.clone(),
                    site: c.site,
                    $($field: ($of as fn(&Runs) -> $ty)(runs),)*
                }
            }

            /// A cell of no runs, every statistic zero or empty (for tests and figures that
            /// make one up, then set what they need).
            pub fn empty(experiment: ExperimentName, cell: CellKey, label: &str) -> CellStats {
                CellStats {
                    experiment,
                    cell,
                    method: cell.method,
                    label: label.to_string(),
                    site: cell.site,
                    $($field: Default::default(),)*
                }
            }
        }

        /// Every statistic of [`CellStats`], in the table's column order.
        pub const STATISTICS: &[Statistic] = &[$(Statistic {
            column: stringify!($field),
            res: $res,
            print: $print,
            value: |s| AsNumber::number(&s.$field),
        },)*];
    };
}

statistics! {
    /// Finished runs (seeds).
    n: u64, res Some("n"), print |s| s.n.to_string(), of |r| r.n();
    /// Runs that solved the task.
    successes: u64, res Some("successes"), print |s| s.successes.to_string(), of |r| r.solved();
    /// successes / n.
    success_rate: f64, res Some("rate"), print |s| format!("{:.2}", s.success_rate),
        of |r| r.solved() as f64 / r.n() as f64;
    /// Wilson 95 % interval, lower end.
    wilson_lo: f64, res Some("lo"), print |s| format!("{:.2}", s.wilson_lo), of |r| r.wilson().0;
    /// Wilson 95 % interval, upper end.
    wilson_hi: f64, res Some("hi"), print |s| format!("{:.2}", s.wilson_hi), of |r| r.wilson().1;
    /// Environment steps: median over runs.
    steps_median: f64, res Some("median"), print |s| human_steps(s.steps_median),
        of |r| median_of(r.steps());
    /// First quartile (linear interpolation).
    steps_q1: f64, res Some("q1"), print |s| human_steps(s.steps_q1),
        of |r| quantile_of(r.steps(), 0.25);
    /// Third quartile.
    steps_q3: f64, res Some("q3"), print |s| human_steps(s.steps_q3),
        of |r| quantile_of(r.steps(), 0.75);
    /// Interquartile range: `steps_q3 − steps_q1`.
    steps_iqr: f64, res Some("iqr"), print |s| human_steps(s.steps_iqr),
        of |r| quantile_of(r.steps(), 0.75) - quantile_of(r.steps(), 0.25);
    /// Fewest.
    steps_min: f64, res None, print |s| human_steps(s.steps_min),
        of |r| quantile_of(r.steps(), 0.0);
    /// Most.
    steps_max: f64, res None, print |s| human_steps(s.steps_max),
        of |r| quantile_of(r.steps(), 1.0);
    /// Median environment steps of the solved runs (empty if none solved).
    solved_steps_median: Option<f64>, res Some("solvedmedian"),
        print |s| s.solved_steps_median.map_or("--".into(), human_steps),
        of |r| Some(r.solved_steps()).filter(|v| !v.is_empty()).map(median_of);
    /// Runs solved within the paper's environment steps for the cell (empty where the paper
    /// gives none): with a budget of twice the paper's steps, how many also fit in 1×.
    solved_within_paper: Option<u64>, res Some("withinpaper"),
        print |s| s.solved_within_paper.map_or("--".into(), |k| k.to_string()),
        of |r| r.cell.paper_steps.map(|p| {
            r.solved_steps().iter().filter(|&&s| s <= p as f64).count() as u64
        });
    /// Median number of skills (PBCS; 0 for vanilla).
    skills_median: f64, res Some("skills"), print |s| s.skills_median.to_string(),
        of |r| median_of(r.each(|r| r.skills() as f64));
    /// Median of the final evaluation's success rate.
    success_rate_median: f64, res Some("evalmedian"),
        print |s| format!("{:.2}", s.success_rate_median),
        of |r| median_of(r.each(|r| f64::from(r.success_rate)));
    /// The step budget of each run.
    budget: u64, res Some("budget"), print |s| human_steps(s.budget as f64),
        of |r| r.rows[0].budget;
    /// The paper's environment steps for this cell (one seed), if reported.
    paper_steps: Option<u64>, res Some("paper"),
        print |s| s.paper_steps.map_or("--".into(), |p| human_steps(p as f64)),
        of |r| r.cell.paper_steps;
    /// Whether the paper's run solved it, if reported.
    paper_solved: Option<bool>, res None,
        print |s| s.paper_solved.map_or("--".into(), |b| b.to_string()),
        of |r| r.cell.paper_solved;
}

impl CellStats {
    /// The same cell with `k` successes out of `n` runs, and the success rate and 95 % Wilson
    /// interval that follow from them.
    pub fn with_counts(self, k: u64, n: u64) -> CellStats {
        let (lo, hi) = wilson(k, n, Z95);
        CellStats {
            n,
            successes: k,
            success_rate: k as f64 / n as f64,
            wilson_lo: lo,
            wilson_hi: hi,
            ..self
        }
    }
}

/// The table's columns that name a cell rather than summarise its runs.
pub const IDENTITY: [&str; 5] = ["experiment", "cell", "method", "label", "maze"];

#[cfg(test)]
mod tests {
    use super::*;

    /// The table's header is the identity and then every declared statistic in order, each
    /// `\res` field is declared once, and a known cell prints as the report quotes it.
    #[test]
    fn the_table_has_the_declared_columns() {
        let exp = Experiment::load(std::path::Path::new("experiments/table.toml"), None).unwrap();
        let c = &exp.cells[0];
        let stats = CellStats::empty(exp.name, c.id, &c.label).with_counts(1, 2);
        let mut w = csv::Writer::from_writer(Vec::new());
        w.serialize(&stats).unwrap();
        let text = String::from_utf8(w.into_inner().unwrap()).unwrap();
        let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
        let declared = IDENTITY
            .iter()
            .copied()
            .chain(STATISTICS.iter().map(|s| s.column));
        assert_eq!(header, declared.collect::<Vec<_>>());
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

    /// Known values: three runs of 100, 200 and 400 steps, two solved, the paper's figure
    /// 250 steps.
    #[test]
    fn each_statistic_of_known_runs() {
        let exp = Experiment::load(std::path::Path::new("experiments/table.toml"), None).unwrap();
        let mut cell = exp.cells[0].clone();
        cell.paper_steps = Some(250);
        let row = |seed, steps, solved, skills| {
            crate::tables::tests::row(&exp, seed, solved, steps, skills)
        };
        let rows = [
            row(0, 100, true, 1),
            row(1, 400, false, 3),
            row(2, 200, true, 2),
        ];
        let s = CellStats::of(&exp, &Runs::of(&cell, &rows).unwrap());
        assert_eq!((s.n, s.successes), (3, 2));
        assert_eq!(
            (s.steps_median, s.steps_min, s.steps_max),
            (200.0, 100.0, 400.0)
        );
        assert_eq!((s.steps_q1, s.steps_q3, s.steps_iqr), (150.0, 300.0, 150.0));
        assert_eq!(s.solved_steps_median, Some(150.0));
        assert_eq!(s.solved_within_paper, Some(2));
        assert_eq!((s.skills_median, s.success_rate_median), (2.0, 1.0));
        let (lo, hi) = wilson(2, 3, Z95);
        assert_eq!((s.wilson_lo, s.wilson_hi), (lo, hi));
    }
}
