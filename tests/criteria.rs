//! The success-criterion tables against the committed results: at our threshold they are the
//! tables' "solved"; looser criteria never count fewer runs.

use pbcs::criteria::{criteria, read_chains, Criteria};
use pbcs::tables::read_table;
use std::path::Path;

fn committed(experiment: &str) -> (Vec<Criteria>, Vec<pbcs::tables::CellStats>) {
    let tables = Path::new("results/tables");
    let chains = read_chains(&tables.join(format!("{experiment}.chains.csv"))).unwrap();
    let stats = read_table(&tables.join(format!("{experiment}.csv"))).unwrap();
    (criteria(&chains), stats)
}

#[test]
fn at_our_threshold_the_criteria_are_the_tables_solved_counts() {
    for experiment in ["table", "gamma", "unseen", "beyond", "ablations"] {
        let (criteria, stats) = committed(experiment);
        assert!(!criteria.is_empty(), "{experiment}");
        for c in &criteria {
            let s = stats.iter().find(|s| s.cell == c.cell).unwrap();
            assert_eq!(
                (c.n, c.at_0_95),
                (s.n, s.successes),
                "{experiment} {}",
                c.cell
            );
            // Looser criteria count at least as many runs; a complete chain is the loosest.
            let at = c.at();
            assert!(at.windows(2).all(|w| w[0] >= w[1]), "{}: {at:?}", c.cell);
            assert!(c.complete >= at[0] && c.n >= c.complete, "{}", c.cell);
        }
    }
}

/// What the report says of the table under other criteria: every `paper` chain is complete;
/// at 100 % maze 2 loses one more run; at 50 % maze 15 gains one (a chain at 93 %); `fast`
/// keeps every run at every threshold.
#[test]
fn the_table_under_other_criteria() {
    let (criteria, _) = committed("table");
    let get = |cell: &str| {
        let key: pbcs::experiment::CellKey = cell.parse().unwrap();
        criteria.iter().find(|c| c.cell == key).unwrap()
    };
    for n in [2, 5, 7, 10, 15] {
        let paper = get(&format!("pbcs-maze{n}"));
        assert_eq!(paper.complete, paper.n, "maze {n}");
        let fast = get(&format!("pbcs_fast-maze{n}"));
        assert_eq!(fast.at(), [fast.n; 4], "maze {n}");
    }
    assert_eq!(get("pbcs-maze2").at(), [9, 9, 9, 8]);
    assert_eq!(get("pbcs-maze15").at(), [7, 7, 6, 6]);
}

/// The performance profile at x = 1 is the table's "solved within the paper's steps", pooled
/// over the sizes, and at x = 2 (the budget) its solved count.
#[test]
fn the_profile_at_one_and_two_is_the_tables_solved_within_and_solved() {
    let tables = Path::new("results/tables");
    let runs = read_chains(&tables.join("table.chains.csv")).unwrap();
    let stats = read_table(&tables.join("table.csv")).unwrap();
    for name in ["pbcs", "pbcs_fast", "pbcs_no_chaining"] {
        let method: pbcs::experiment::Method = name.parse().unwrap();
        let own: Vec<_> = runs
            .iter()
            .filter(|r| r.method == method)
            .cloned()
            .collect();
        let cells: Vec<_> = stats.iter().filter(|s| s.method == method).collect();
        let n: u64 = cells.iter().map(|s| s.n).sum();
        let solved: u64 = cells.iter().map(|s| s.successes).sum();
        let p = pbcs::criteria::profile(&own, &[2.0]);
        assert_eq!(p[0], solved as f64 / n as f64, "{method}");
        if name == "pbcs" {
            let within: u64 = cells.iter().map(|s| s.solved_within_paper.unwrap()).sum();
            let p = pbcs::criteria::profile(&own, &[1.0]);
            assert_eq!(p[0], within as f64 / n as f64);
        }
    }
}
