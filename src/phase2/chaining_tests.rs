//! Unit tests of [`super`] that read the chainer's private state.

use super::*;
use crate::toy::Toy1D;

/// With `warm_start`, the problem after a saved skill (an earlier target on τ) takes over
/// the last learner; a restart (same target) or a repair of a later section starts from
/// the seeds, as every problem does without the switch.
#[test]
fn warm_start_takes_over_the_last_learner_only_for_the_next_skill() {
    let tau: Vec<f32> = (0..=10).map(|i| 0.9 - 0.08 * i as f32).collect();
    let lc = LearnerConfig::ddpg();
    let seeds = Seeds::new(5);
    let kernel = Kernel::detect();
    let fresh = |n: u32| {
        Learner::new(&lc, 1, &[1.0], &seeds.skill(n), kernel)
            .unwrap()
            .actor
            .params
    };
    // A learner unlike any fresh one: the weights of sub-run 99.
    let trained = Learner::new(&lc, 1, &[1.0], &seeds.skill(99), kernel).unwrap();
    for warm in [false, true] {
        // The toy makes no ball starts: exact starts (the test reads learners only).
        let config = Phase2Config {
            warm_start: warm,
            start: super::super::StartMode::Exact,
            ..Phase2Config::default()
        };
        let mut progress = |_: usize, _: Progress| {};
        let c = Chainer::new(&Toy1D, &tau, &lc, &config, &seeds, 0, kernel, &mut progress);
        // (last target, new target, expected: warm?)
        for (n, (last_t, t, takes_over)) in [(6, 3, true), (6, 6, false), (6, 8, false)]
            .into_iter()
            .enumerate()
        {
            *c.last.borrow_mut() = Some((last_t, trained.clone()));
            let task = c.task(&tau, 0, t, &[]).unwrap();
            let expected = if warm && takes_over {
                trained.actor.params.clone()
            } else {
                fresh(n as u32)
            };
            let got = &task.learner.actor.params;
            assert!(
                got == &expected,
                "warm {warm}, T {last_t} → {t}: {} params, first {:?}; expected {} params, \
                 first {:?}",
                got.len(),
                &got[..3],
                expected.len(),
                &expected[..3]
            );
        }
    }
}
