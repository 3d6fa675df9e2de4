//! Unit tests of the claim criteria and verdicts, on made-up tables.

use super::*;
use crate::experiment::CellKey;

/// The method called `name`.
fn m(name: &str) -> Method {
    Method::new(name).unwrap()
}

/// A cell with `k` of `n` seeds solved and its 95 % Wilson interval.
fn cell(method: &str, maze: usize, k: u64, n: u64) -> CellStats {
    let empty = CellStats::empty(
        "t".parse().unwrap(),
        CellKey::new(m(method), Site::Maze(maze)),
        method,
    );
    CellStats {
        steps_median: 1.0,
        steps_q1: 1.0,
        steps_q3: 1.0,
        steps_min: 1.0,
        steps_max: 1.0,
        budget: 1,
        ..empty
    }
    .with_counts(k, n)
}

#[test]
fn pooled_counts_only_the_mazes_both_methods_ran() {
    let spec = ClaimSpec {
        id: "x".into(),
        paper: "p".into(),
        experiment: "t".parse().unwrap(),
        test: ClaimTest::Beats {
            method: m("a"),
            label: "A".into(),
            than: m("b"),
            than_label: "B".into(),
            pooled: true,
            than_experiment: None,
        },
    };
    // `a` also ran maze 5, which `b` did not: its 0/10 must not dilute the comparison.
    let stats = vec![
        cell("a", 2, 9, 10),
        cell("b", 2, 3, 10),
        cell("a", 5, 0, 10),
    ];
    let c = &claims(&[spec], &[("t".parse().unwrap(), stats)]).unwrap()[0];
    assert!(c.ours.contains("pooled: A 9/10"), "{}", c.ours);
    assert_eq!(c.verdict, Verdict::ExactTestOnly);
}

#[test]
fn an_exact_test_speaks_where_intervals_overlap() {
    // 9/10 [0.60, 0.98] against 3/10 [0.11, 0.60]: the intervals touch, Fisher's p is
    // 0.0198 (SciPy). 5/10 against 4/10: p = 1.
    let stats = [
        cell("a", 2, 9, 10),
        cell("b", 2, 3, 10),
        cell("a", 3, 5, 10),
        cell("b", 3, 4, 10),
    ];
    assert!(!beats(&stats[0], &stats[1]) && exact_better(&stats[0], &stats[1]));
    let (parts, verdict) = per_maze(&stats, (m("a"), "A"), (m("b"), "B"));
    assert_eq!(verdict, Verdict::ExactTestOnly);
    assert!(parts[0].ends_with("Fisher p = 0.020"), "{}", parts[0]);
    assert!(parts[1].ends_with("Fisher p = 1.000"), "{}", parts[1]);
    // The other way round the test finds nothing for "b beats a".
    let (_, verdict) = per_maze(&stats, (m("b"), "B"), (m("a"), "A"));
    assert_eq!(verdict, Verdict::Inconclusive);
}

#[test]
fn per_maze_agrees_when_one_maze_separates_and_none_reverses() {
    // 10/10 is [0.72, 1.00], 2/10 is [0.06, 0.51]: disjoint. 0/10 against 0/10: a tie.
    let stats = [
        cell("a", 2, 10, 10),
        cell("b", 2, 2, 10),
        cell("a", 3, 0, 10),
        cell("b", 3, 0, 10),
    ];
    let (parts, verdict) = per_maze(&stats, (m("a"), "A"), (m("b"), "B"));
    assert_eq!(verdict, Verdict::Agrees);
    assert_eq!(parts.len(), 2);
    assert!(parts[0].starts_with("maze 2: A 10/10 [0.72, 1.00] vs B 2/10 [0.06, 0.51]"));
    // Pooled, the same counts overlap (10/20 [0.30, 0.70] against 2/20 [0.03, 0.30] is a
    // near miss), which is why the verdict is per maze.
    let (a, b) = (
        pooled(&stats, m("a")).unwrap(),
        pooled(&stats, m("b")).unwrap(),
    );
    assert!(!beats(&a, &b), "{} vs {}", k_of_n(&a), k_of_n(&b));
}

#[test]
fn fails_everywhere_weighs_runs_at_the_papers_budget() {
    let with_budget = |mut c: CellStats, b: u64| {
        c.budget = b;
        c
    };
    let table = [
        with_budget(cell("ddpg", 2, 0, 10), 100_000),
        with_budget(cell("ddpg", 5, 0, 10), 100_000),
    ];
    let verdict = |longer: &[CellStats]| {
        fails_everywhere("x", "", &table, longer, m("ddpg"))
            .unwrap()
            .verdict
    };
    // No longer runs, or longer runs that never succeed: the 10-seed failures decide.
    assert_eq!(verdict(&[]), Verdict::Agrees);
    assert_eq!(
        verdict(&[with_budget(cell("ddpg", 2, 0, 3), 1_000_000)]),
        Verdict::Agrees
    );
    // 2 of 3 at the paper's budget: reached, not reliably. 10 of 10: the claim is wrong.
    assert_eq!(
        verdict(&[with_budget(cell("ddpg", 2, 2, 3), 1_000_000)]),
        Verdict::Inconclusive
    );
    assert_eq!(
        verdict(&[with_budget(cell("ddpg", 5, 10, 10), 1_000_000)]),
        Verdict::Disagrees
    );
    // A "longer" cell with no larger budget is not evidence about a larger budget.
    assert_eq!(
        verdict(&[with_budget(cell("ddpg", 2, 2, 3), 100_000)]),
        Verdict::Agrees
    );
    let claim = fails_everywhere(
        "x",
        "",
        &table,
        &[with_budget(cell("ddpg", 2, 2, 3), 1_000_000)],
        m("ddpg"),
    )
    .unwrap();
    assert!(
        claim.ours.starts_with(
            "maze 2: 0/10 [0.00, 0.28] solved within 100k steps, 2/3 [0.21, 0.94] within 1.00M"
        ),
        "{}",
        claim.ours
    );
}

#[test]
fn per_maze_disagrees_when_any_maze_reverses_and_is_inconclusive_on_overlaps() {
    let reversed = [
        cell("a", 2, 10, 10),
        cell("b", 2, 0, 10),
        cell("a", 5, 0, 10),
        cell("b", 5, 10, 10),
    ];
    assert_eq!(
        per_maze(&reversed, (m("a"), "A"), (m("b"), "B")).1,
        Verdict::Disagrees
    );
    // 6/10 [0.31, 0.83] against 3/10 [0.11, 0.60]: overlapping.
    let close = [cell("a", 2, 6, 10), cell("b", 2, 3, 10)];
    assert_eq!(
        per_maze(&close, (m("a"), "A"), (m("b"), "B")).1,
        Verdict::Inconclusive
    );
    // A maze only one method has is not compared.
    let alone = [cell("a", 2, 10, 10)];
    let (parts, verdict) = per_maze(&alone, (m("a"), "A"), (m("b"), "B"));
    assert!(parts.is_empty());
    assert_eq!(verdict, Verdict::Inconclusive);
}

#[test]
fn pooled_beats_decides_only_where_no_maze_does_and_pooled_shows_counts_without_a_verdict() {
    let spec = |test: ClaimTest| ClaimSpec {
        id: "x".into(),
        paper: "p".into(),
        experiment: "t".parse().unwrap(),
        test,
    };
    let beats = |pooled: bool| {
        spec(ClaimTest::Beats {
            method: m("a"),
            label: "A".into(),
            than: m("b"),
            than_label: "B".into(),
            pooled,
            than_experiment: None,
        })
    };
    // 7/10 against 2/10 on two mazes: each overlaps ([0.40, 0.89] and [0.06, 0.51]),
    // pooled 14/20 [0.48, 0.85] against 4/20 [0.08, 0.42] does not.
    let stats = vec![
        cell("a", 2, 7, 10),
        cell("b", 2, 2, 10),
        cell("a", 3, 7, 10),
        cell("b", 3, 2, 10),
    ];
    let tables = [("t".parse().unwrap(), stats)];
    let verdict = |s: ClaimSpec| claims(&[s], &tables).unwrap()[0].verdict;
    assert_eq!(verdict(beats(false)), Verdict::Inconclusive);
    assert_eq!(verdict(beats(true)), Verdict::Agrees);
    // `than` from another experiment's table: the same comparison.
    let (own, other): (Vec<_>, Vec<_>) = tables[0]
        .1
        .iter()
        .cloned()
        .partition(|c| c.method == m("a"));
    let split = [("t".parse().unwrap(), own), ("u".parse().unwrap(), other)];
    let mut across = beats(true);
    if let ClaimTest::Beats {
        than_experiment, ..
    } = &mut across.test
    {
        *than_experiment = Some("u".parse().unwrap());
    }
    let c = &claims(&[across], &split).unwrap()[0];
    assert_eq!(c.verdict, Verdict::Agrees);
    assert_eq!(c.ours, claims(&[beats(true)], &tables).unwrap()[0].ours);
    let shown = claims(
        &[spec(ClaimTest::Pooled {
            methods: vec![(m("a"), "A".into()), (m("b"), "B".into())],
        })],
        &tables,
    )
    .unwrap();
    assert_eq!(shown[0].verdict, Verdict::NoClaim);
    assert_eq!(
        shown[0].ours,
        "pooled over mazes: A 14/20 [0.48, 0.85] vs B 4/20 [0.08, 0.42]"
    );
}

/// A claim whose table is missing, or whose table lacks the method's cells, is an error that
/// names the claim and what is missing, never a silent skip.
#[test]
fn a_claim_without_its_table_or_cells_is_an_error() {
    let spec = |test: ClaimTest| ClaimSpec {
        id: "x".into(),
        paper: "p".into(),
        experiment: "t".parse().unwrap(),
        test,
    };
    let beats = |than_experiment: Option<&str>| {
        spec(ClaimTest::Beats {
            method: m("a"),
            label: "A".into(),
            than: m("b"),
            than_label: "B".into(),
            pooled: false,
            than_experiment: than_experiment.map(|n: &str| n.parse().unwrap()),
        })
    };
    let tables = [(
        "t".parse().unwrap(),
        vec![cell("a", 2, 7, 10), cell("b", 2, 2, 10)],
    )];
    assert!(claims(&[beats(None)], &tables).is_ok());
    // The claim's own table missing.
    let e = claims(&[beats(None)], &[]).unwrap_err().to_string();
    assert!(e.contains("no table of experiment `t`"), "{e}");
    // The other table missing.
    let e = claims(&[beats(Some("u"))], &tables)
        .unwrap_err()
        .to_string();
    assert!(e.contains("no table of experiment `u`"), "{e}");
    // The cells missing: `b` ran no maze that `a` ran.
    let apart = [(
        "t".parse().unwrap(),
        vec![cell("a", 2, 7, 10), cell("b", 3, 2, 10)],
    )];
    let e = claims(&[beats(None)], &apart).unwrap_err().to_string();
    assert!(e.contains("no maze where both `a` and `b`"), "{e}");
    for test in [
        ClaimTest::SolvesEverywhere { method: m("c") },
        ClaimTest::FailsEverywhere {
            method: m("c"),
            longer: None,
        },
        ClaimTest::StepsBelowPaper { method: m("c") },
        ClaimTest::Pooled {
            methods: vec![(m("a"), "A".into()), (m("c"), "C".into())],
        },
    ] {
        let e = claims(&[spec(test)], &tables).unwrap_err().to_string();
        assert!(e.contains("no cell of method `c`"), "{e}");
    }
}
