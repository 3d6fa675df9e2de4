//! A registered paired comparison: an experiment file whose `[registered]` table says
//! `paired = [baseline, variant]` ran two methods on the same sites and seeds (the baseline's
//! rows those of another experiment where it says `baseline_from = "<experiment>"`), and its
//! registered outcome is, per site and over all sites pooled, the seeds where the variant used
//! fewer env steps (phase 1 included) than the baseline, with the two-sided exact sign test
//! ([`crate::stats::sign_test`], ties dropped). `pbcs aggregate` writes it to
//! `results/tables/<experiment>.paired.csv`; `pbcs figures` writes its numbers
//! (`\res{<experiment>:paired:<site>:<field>}`, the pooled row's site being `all`).

use super::scope::Scope;
use crate::experiment::{CellKey, Experiment, ExperimentName, Method, RawRow, Site};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The comparison on one site, or on all of them pooled.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PairedSite {
    /// The site (`pointmaze_medium`), or all of them pooled (written `all`).
    pub site: Scope<Site>,
    /// The experiment whose rows the baseline's are (the file's own, or its `baseline_from`).
    pub baseline_from: ExperimentName,
    /// The baseline method.
    pub baseline: Method,
    /// The variant method.
    pub variant: Method,
    /// Seeds with a row in both methods' cells.
    pub pairs: u64,
    /// Pairs where the variant used fewer env steps.
    pub fewer: u64,
    /// Pairs where it used more.
    pub more: u64,
    /// Pairs with the same env steps (dropped by the test).
    pub ties: u64,
    /// The two-sided exact sign test of `fewer` against `more`.
    pub p_value: f64,
}

/// `results/tables/<experiment>.paired.csv`.
pub fn paired_path(results: &Path, experiment: ExperimentName) -> PathBuf {
    results
        .join("tables")
        .join(format!("{experiment}.paired.csv"))
}

/// The registered comparison of `exp`, its variant's steps from `rows` and its baseline's
/// from `baseline_rows` (`rows` again, or the rows of the experiment its `baseline_from`
/// names), per site (in the file's order, sites without a pair left out) and pooled; none
/// when `exp` registers no paired comparison.
///
/// ```
/// use pbcs::experiment::Experiment;
/// // Without `[registered] paired`, no comparison.
/// let exp = Experiment::load(std::path::Path::new("experiments/pointmaze.toml"), None).unwrap();
/// assert!(pbcs::tables::paired::paired_sites(&exp, &[], &[]).is_empty());
/// ```
pub fn paired_sites(
    exp: &Experiment,
    rows: &[RawRow],
    baseline_rows: &[RawRow],
) -> Vec<PairedSite> {
    let Some(registered) = exp.registered.as_ref() else {
        return Vec::new();
    };
    let Some([baseline, variant]) = registered.paired else {
        return Vec::new();
    };
    let baseline_from = registered.baseline_from.unwrap_or(exp.name);
    let steps = |rows: &[RawRow], method, site, seed| {
        let cell = CellKey::new(method, site);
        rows.iter()
            .find(|r| r.cell == cell && r.seed == seed)
            .map(|r| r.env_steps)
    };
    let row = |site: Scope<Site>, diffs: &[std::cmp::Ordering]| {
        let count = |o| diffs.iter().filter(|&&d| d == o).count() as u64;
        let (fewer, more) = (
            count(std::cmp::Ordering::Less),
            count(std::cmp::Ordering::Greater),
        );
        PairedSite {
            site,
            baseline_from,
            baseline,
            variant,
            pairs: diffs.len() as u64,
            fewer,
            more,
            ties: count(std::cmp::Ordering::Equal),
            p_value: crate::stats::sign_test(fewer, more),
        }
    };
    let mut out = Vec::new();
    let mut all = Vec::new();
    for &site in &exp.sites {
        let diffs: Vec<_> = exp
            .seeds()
            .into_iter()
            .filter_map(|s| {
                let ours = steps(rows, variant, site, s)?;
                Some(ours.cmp(&steps(baseline_rows, baseline, site, s)?))
            })
            .collect();
        if !diffs.is_empty() {
            all.extend_from_slice(&diffs);
            out.push(row(Scope::One(site), &diffs));
        }
    }
    if !all.is_empty() {
        out.push(row(Scope::Pooled, &all));
    }
    out
}

/// `\res{<experiment>:paired:<site>:<field>}` (`pairs`, `fewer`, `more`, `ties`, `p`: the
/// p-value to two significant digits) from the paired table, where it exists.
pub fn paired_numbers(
    name: ExperimentName,
    results: &Path,
) -> crate::Result<Vec<(String, String)>> {
    super::table_numbers(&paired_path(results, name), |s: &PairedSite| {
        let fields = [
            ("pairs", s.pairs.to_string()),
            ("fewer", s.fewer.to_string()),
            ("more", s.more.to_string()),
            ("ties", s.ties.to_string()),
            ("p", two_digits(s.p_value)),
        ];
        (format!("paired:{}", s.site), fields)
    })
}

/// `p` to two significant digits (`0.021`, `0.34`, `1.0`).
pub(crate) fn two_digits(p: f64) -> String {
    if p <= 0.0 || !p.is_finite() {
        return p.to_string();
    }
    let decimals = (1 - p.log10().floor() as i32).max(1) as usize;
    format!("{p:.decimals$}")
}

#[cfg(test)]
mod tests {
    #[test]
    fn p_values_print_with_two_significant_digits() {
        for (p, s) in [
            (0.021484375, "0.021"),
            (0.34375, "0.34"),
            (1.0, "1.0"),
            (0.0014309, "0.0014"),
        ] {
            assert_eq!(super::two_digits(p), s);
        }
    }
}

#[cfg(test)]
mod known {
    use super::*;

    /// Known counts: the committed PointMaze grid's rows as both methods of the registered
    /// comparison, the variant's env steps changed seed by seed.
    #[test]
    fn counts_pairs_per_site_and_pooled() {
        let exp = Experiment::load(Path::new("experiments/pointmaze_velocity.toml"), None).unwrap();
        let grid = Experiment::load(Path::new("experiments/pointmaze.toml"), None).unwrap();
        let rows = crate::experiment::read_raw(&grid, Path::new("results")).unwrap();
        let mut ours = Vec::new();
        for r in rows.iter().filter(|r| r.seed < 4) {
            let site = r.site;
            let cell = |m| CellKey::new(Method::new(m).unwrap(), site);
            let (base, var) = (cell("pbcs_pm"), cell("pbcs_pm_velocity"));
            let seed = r.seed + 20;
            ours.push(RawRow {
                cell: base,
                seed,
                ..r.clone()
            });
            // UMaze: seeds 20, 21 fewer, 22 equal, 23 more; other maps: every seed fewer.
            let umaze = Site::Env(crate::envs::EnvName::PointmazeUmaze);
            let delta: i64 = match r.seed {
                2 if site == umaze => 0,
                3 if site == umaze => 1,
                _ => -1,
            };
            let env_steps = r.env_steps.checked_add_signed(delta).unwrap();
            ours.push(RawRow {
                cell: var,
                seed,
                env_steps,
                ..r.clone()
            });
        }
        // Medium's seed 23 has no variant row: not a pair.
        let medium: CellKey = "pbcs_pm_velocity-pointmaze_medium".parse().unwrap();
        ours.retain(|r| !(r.cell == medium && r.seed == 23));
        let got: Vec<_> = paired_sites(&exp, &ours, &ours)
            .into_iter()
            .map(|s| (s.site.to_string(), s.pairs, s.fewer, s.more, s.ties))
            .collect();
        assert_eq!(
            got,
            [
                ("pointmaze_umaze".to_string(), 4, 2, 1, 1),
                ("pointmaze_medium".to_string(), 3, 3, 0, 0),
                ("pointmaze_large".to_string(), 4, 4, 0, 0),
                ("all".to_string(), 11, 9, 1, 1),
            ]
        );
        let all = paired_sites(&exp, &ours, &ours).pop().unwrap();
        assert_eq!(all.p_value, crate::stats::sign_test(9, 1));
    }

    /// Known counts across two experiments: goal_conditioned_strict.toml's variant against the
    /// table's pbcs_fast rows (its `baseline_from`), the variant's steps the baseline's ± 1.
    #[test]
    fn pairs_the_variant_with_another_experiments_baseline() {
        let exp =
            Experiment::load(Path::new("experiments/goal_conditioned_strict.toml"), None).unwrap();
        let table = Experiment::load(Path::new("experiments/table.toml"), None).unwrap();
        let fast = Method::new("pbcs_fast").unwrap();
        let base: Vec<RawRow> = crate::experiment::read_raw(&table, Path::new("results"))
            .unwrap()
            .into_iter()
            .filter(|r| r.cell.method == fast && r.seed < 3)
            .collect();
        let gc100 = Method::new("gc100").unwrap();
        // Maze 2: seed 0 fewer, 1 the same, 2 more; other mazes: every seed fewer.
        let ours: Vec<RawRow> = (base.iter())
            .map(|r| RawRow {
                cell: CellKey::new(gc100, r.site),
                env_steps: match (r.site, r.seed) {
                    (Site::Maze(2), 1) => r.env_steps,
                    (Site::Maze(2), 2) => r.env_steps + 1,
                    _ => r.env_steps - 1,
                },
                ..r.clone()
            })
            .collect();
        // The table's rows as the variant's own: no baseline row, no pair.
        assert!(paired_sites(&exp, &ours, &ours).is_empty());
        let got: Vec<_> = paired_sites(&exp, &ours, &base)
            .into_iter()
            .map(|s| (s.site, s.baseline_from, s.fewer, s.ties, s.more))
            .collect();
        let table = ExperimentName::new("table").unwrap();
        let row = |site: Scope<Site>, fewer, ties, more| (site, table, fewer, ties, more);
        let maze = |n| Scope::One(Site::Maze(n));
        assert_eq!(
            got,
            [
                row(maze(2), 1, 1, 1),
                row(maze(5), 3, 0, 0),
                row(maze(7), 3, 0, 0),
                row(maze(10), 3, 0, 0),
                row(maze(15), 3, 0, 0),
                row(Scope::Pooled, 13, 1, 1),
            ]
        );
    }
}
