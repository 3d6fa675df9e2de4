//! Unit tests of [`super`]'s private helpers.

use super::*;

/// With `warm_start`, the problem after a saved skill (an earlier target on τ) takes over
/// the last learner; a restart (same target) or a repair of a later section starts from
/// the seeds, as every problem does without the switch.
#[test]
fn warm_start_takes_over_the_last_learner_only_for_the_next_skill() {
    let lc = LearnerConfig::ddpg();
    let seeds = Seeds::new(5);
    let kernel = Kernel::detect();
    let fresh = || lc.build(1, &[1.0], &seeds.skill(0), kernel);
    // A learner unlike any fresh one: the weights of sub-run 99.
    let trained = lc.build(1, &[1.0], &seeds.skill(99), kernel).unwrap();
    let fresh_params = fresh().unwrap().policy();
    assert!(fresh_params != trained.policy());
    for warm in [false, true] {
        // (last target, new target, whether the last learner is taken over when warm)
        for (last_t, t, takes_over) in [(6, 3, true), (6, 6, false), (6, 8, false)] {
            let got = warm_or_fresh(Some((last_t, trained.clone())), warm, t, fresh).unwrap();
            let expected = if warm && takes_over {
                &trained.policy()
            } else {
                &fresh_params
            };
            assert!(
                &got.policy() == expected,
                "warm {warm}, T {last_t} → {t}: took over {}",
                got.policy() == trained.policy()
            );
        }
        // The first problem has no last learner: fresh, warm or not.
        let first = warm_or_fresh(None, warm, 3, fresh).unwrap();
        assert!(
            first.policy().same(fresh_params.as_ref()),
            "warm {warm}, first problem"
        );
    }
}
