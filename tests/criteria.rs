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
    let get = |cell: &str| criteria.iter().find(|c| c.cell == cell).unwrap();
    for n in [2, 5, 7, 10, 15] {
        let paper = get(&format!("pbcs-maze{n}"));
        assert_eq!(paper.complete, paper.n, "maze {n}");
        let fast = get(&format!("pbcs_fast-maze{n}"));
        assert_eq!(fast.at(), [fast.n; 4], "maze {n}");
    }
    assert_eq!(get("pbcs-maze2").at(), [9, 9, 9, 8]);
    assert_eq!(get("pbcs-maze15").at(), [7, 7, 6, 6]);
}
