//! Backplay's walk with `patience` (ours) on the scripted learner of `backplay.rs`.

use super::*;

/// `patience` (ours): once a K is saved, the walk ends after that many Ks in a row trained
/// without another save; a save starts the count again. The paper's walk goes on until a test
/// after training reads 0 % (here at K = 4), keeping nothing more.
#[test]
fn a_patient_walk_ends_after_its_patience_of_unsaved_ks() {
    let script = || Scripted {
        tests: HashMap::from([
            (9, vec![1.0]),
            (8, vec![0.5]),
            (7, vec![0.5, 1.0]),
            (6, vec![0.5]),
            (5, vec![0.5]),
            (4, vec![0.0]),
        ]),
        train: vec![0.5; 20],
        ..Default::default()
    };
    // α = 1: two rounds per trained K (an improvement, then a miss).
    let patient = Walk {
        patience: Some(2),
        ..walk(1, 1, false)
    };
    let mut b = script();
    let kept = backplay_candidates(&mut b, 10, &patient);
    assert_eq!(kept, [(9, 0), (7, 4)]);
    assert_eq!(b.calls.last().unwrap(), "test 5 = 0.5");
    assert!(!b.calls.iter().any(|c| c.starts_with("test 4")));
    let mut paper = script();
    let kept = backplay_candidates(&mut paper, 10, &walk(1, 1, false));
    assert_eq!(kept, [(9, 0), (7, 4)]);
    assert_eq!(paper.calls.last().unwrap(), "test 4 = 0");
    // Patience 3 would have let K = 4 be trained too.
    let mut b = script();
    let three = Walk {
        patience: Some(3),
        ..walk(1, 1, false)
    };
    backplay_candidates(&mut b, 10, &three);
    assert_eq!(b.calls, paper.calls);
}

/// Patience counts only after a save: a walk that has saved nothing yet goes on past P unsaved
/// Ks (here 2) and saves at K = 6, then ends 2 trained Ks later.
#[test]
fn patience_waits_for_a_first_save() {
    let mut b = Scripted {
        tests: HashMap::from([
            (9, vec![0.5]),
            (8, vec![0.5]),
            (7, vec![0.5]),
            (6, vec![0.5, 1.0]),
            (5, vec![0.5]),
            (4, vec![0.5]),
        ]),
        train: vec![0.5; 20],
        ..Default::default()
    };
    let patient = Walk {
        patience: Some(2),
        ..walk(1, 1, false)
    };
    assert_eq!(backplay_candidates(&mut b, 10, &patient), [(6, 8)]);
    assert_eq!(b.calls.last().unwrap(), "test 4 = 0.5");
}
