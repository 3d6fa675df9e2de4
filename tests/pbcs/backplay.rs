//! Algorithm 2 (Backplay) and Algorithm 1 (skill chaining) on a scripted learner: the
//! control flow of the pseudo-code, checked call by call.

use super::*;
use pbcs::phase2::{DeadWalk, Ideas};

/// A learner whose results are dictated: `tests[k]` is the list of successive test results at
/// K (the last one repeats), `train` the successive training results. The policy is the
/// number of training rounds run so far, so a returned π_s says when it was saved.
#[derive(Default)]
pub struct Scripted {
    pub tests: HashMap<usize, Vec<f32>>,
    pub train: Vec<f32>,
    pub calls: Vec<String>,
    pub rounds: usize,
    /// Verification results by (K, policy); 1 when absent.
    pub verified: HashMap<(usize, usize), f32>,
}

impl Backplayer for Scripted {
    type Policy = usize;
    fn test(&mut self, k: usize) -> f32 {
        let v = self.tests.get_mut(&k).expect("unexpected test");
        let p = if v.len() > 1 { v.remove(0) } else { v[0] };
        self.calls.push(format!("test {k} = {p}"));
        p
    }
    fn train(&mut self, k: usize) -> f32 {
        let p = self.train.get(self.rounds).copied().unwrap_or(0.0);
        self.rounds += 1;
        self.calls.push(format!("train {k} = {p}"));
        p
    }
    fn policy(&self) -> usize {
        self.rounds
    }
    fn verify(&mut self, k: usize, policy: &usize, episodes: usize) -> f32 {
        let p = self.verified.get(&(k, *policy)).copied().unwrap_or(1.0);
        self.calls.push(format!(
            "verify {k} (policy {policy}, {episodes} episodes) = {p}"
        ));
        p
    }
    fn gave_up(&mut self, k: usize) {
        self.calls.push(format!("dead walk at {k}"));
    }
    fn exhausted(&self) -> bool {
        false
    }
    fn ball_is_clear(&self, _k: usize) -> bool {
        false
    }
}

/// Backplay's walk: α, K step, early stop; the paper's fixed step.
pub fn walk(alpha: usize, k_step: usize, early_stop: bool) -> Walk {
    Walk {
        k_walk: KWalk::Fixed { step: k_step },
        stopping: Stopping {
            early_stop,
            max_rounds: None,
        },
        ..Walk::paper(alpha)
    }
}

#[test]
fn always_successful_walks_to_zero_without_training() {
    let mut b = Scripted {
        tests: (0..5).map(|k| (k, vec![1.0])).collect(),
        ..Default::default()
    };
    assert_eq!(backplay(&mut b, 5, &walk(10, 1, false)), Some((0, 0)));
    assert_eq!(
        b.calls,
        [
            "test 4 = 1",
            "test 3 = 1",
            "test 2 = 1",
            "test 1 = 1",
            "test 0 = 1"
        ]
    );
}

/// `max_rounds` = 2 ends the training of the test below (α = 3) after its second round,
/// still improving; K = 2's test then decides as usual.
#[test]
fn training_stops_after_max_rounds_even_while_improving() {
    let mut b = Scripted {
        tests: HashMap::from([(2, vec![0.5]), (1, vec![1.0]), (0, vec![1.0])]),
        train: vec![0.2, 0.5, 0.5, 0.4, 0.3, 0.9],
        ..Default::default()
    };
    let capped = Walk {
        stopping: Stopping {
            early_stop: false,
            max_rounds: Some(2),
        },
        ..walk(3, 1, false)
    };
    assert_eq!(backplay(&mut b, 3, &capped), Some((0, 2)));
    assert_eq!(
        b.calls,
        [
            "test 2 = 0.5",
            "train 2 = 0.2",
            "train 2 = 0.5",
            "test 2 = 0.5",
            "test 1 = 1",
            "test 0 = 1",
        ]
    );
}

#[test]
fn training_stops_after_alpha_non_improvements() {
    // α = 3. Training results 0.2 (best), 0.5 (best), 0.5, 0.4, 0.3 (three misses): 5 rounds.
    let mut b = Scripted {
        tests: HashMap::from([(2, vec![0.5, 1.0]), (1, vec![1.0]), (0, vec![1.0])]),
        train: vec![0.2, 0.5, 0.5, 0.4, 0.3, 0.9],
        ..Default::default()
    };
    assert_eq!(backplay(&mut b, 3, &walk(3, 1, false)), Some((0, 5)));
    assert_eq!(
        b.calls,
        [
            "test 2 = 0.5",
            "train 2 = 0.2",
            "train 2 = 0.5",
            "train 2 = 0.5",
            "train 2 = 0.4",
            "train 2 = 0.3",
            "test 2 = 1",
            "test 1 = 1",
            "test 0 = 1",
        ]
    );
}

#[test]
fn never_successful_returns_the_last_kept_skill() {
    // K = 4 solved without training (π saved after 0 rounds); K = 3 fails even after training:
    // Backplay returns (4, π saved at K = 4), not the later π.
    let mut b = Scripted {
        tests: HashMap::from([(4, vec![1.0]), (3, vec![0.0])]),
        train: vec![0.1; 10],
        ..Default::default()
    };
    assert_eq!(backplay(&mut b, 5, &walk(2, 1, false)), Some((4, 0)));
    assert_eq!(b.calls.last().unwrap(), "test 3 = 0");
}

#[test]
fn sometimes_successful_is_not_kept_and_k_goes_on() {
    // K = 2: 60 % after training → not kept, K moves on; K = 1: 100 % → kept with the π of
    // that moment; K = 0: 0 % → return (1, π).
    let mut b = Scripted {
        tests: HashMap::from([(2, vec![0.6]), (1, vec![1.0]), (0, vec![0.0])]),
        train: vec![0.5, 0.5, 0.0, 0.0],
        ..Default::default()
    };
    assert_eq!(backplay(&mut b, 3, &walk(2, 1, false)), Some((1, 3)));
    assert!(b.calls.contains(&"test 2 = 0.6".to_string()));
}

#[test]
fn never_successful_without_a_kept_skill_goes_on_and_may_fail() {
    let mut b = Scripted {
        tests: (0..3).map(|k| (k, vec![0.0])).collect(),
        train: vec![0.0; 100],
        ..Default::default()
    };
    assert_eq!(backplay(&mut b, 3, &walk(2, 1, false)), None);
    // Every K was tried, each with α = 2 training rounds (0.0 is a first best, then 2 misses).
    assert_eq!(b.calls.iter().filter(|c| c.starts_with("test")).count(), 6);
    assert_eq!(b.calls.iter().filter(|c| c.starts_with("train")).count(), 9);
}

#[test]
fn early_stop_ends_training_at_a_confirmed_100_percent() {
    // Training hits 100 % at its 2nd round; the test right after confirms it, so training
    // stops there (without early stop it would run α = 3 more rounds).
    let script = || Scripted {
        tests: HashMap::from([(1, vec![0.5, 1.0, 1.0]), (0, vec![1.0])]),
        train: vec![0.5, 1.0, 1.0, 1.0, 1.0, 1.0],
        ..Default::default()
    };
    let mut b = script();
    assert_eq!(backplay(&mut b, 2, &walk(3, 1, true)), Some((0, 2)));
    assert_eq!(
        b.calls,
        [
            "test 1 = 0.5",
            "train 1 = 0.5",
            "train 1 = 1",
            "test 1 = 1",
            "test 1 = 1",
            "test 0 = 1"
        ]
    );
    let mut b = script();
    backplay(&mut b, 2, &walk(3, 1, false));
    assert_eq!(b.calls.iter().filter(|c| c.starts_with("train")).count(), 5);
}

#[test]
fn k_step_walks_back_faster_but_still_ends_at_zero() {
    let mut b = Scripted {
        tests: (0..10).map(|k| (k, vec![1.0])).collect(),
        ..Default::default()
    };
    assert_eq!(backplay(&mut b, 10, &walk(10, 4, false)), Some((0, 0)));
    assert_eq!(
        b.calls,
        ["test 9 = 1", "test 5 = 1", "test 1 = 1", "test 0 = 1"]
    );
}

#[test]
fn adaptive_walk_doubles_its_step_after_successes() {
    let mut b = Scripted {
        tests: (0..40).map(|k| (k, vec![1.0])).collect(),
        ..Default::default()
    };
    let adaptive = Walk {
        k_walk: KWalk::Adaptive { first: 1 },
        ..walk(10, 1, false)
    };
    assert_eq!(backplay(&mut b, 40, &adaptive), Some((0, 0)));
    // Steps 2, 4, 8, 16 (MAX_ADAPTIVE_STEP), 16, floored at K = 0.
    assert_eq!(
        b.calls,
        [
            "test 39 = 1",
            "test 37 = 1",
            "test 33 = 1",
            "test 25 = 1",
            "test 9 = 1",
            "test 0 = 1"
        ]
    );
}

#[test]
fn adaptive_walk_bisects_a_failed_jump_without_training_it() {
    // K ≥ 30 always succeeds, K < 30 never does, even after training.
    let mut b = Scripted {
        tests: (0..40)
            .map(|k| (k, vec![if k >= 30 { 1.0 } else { 0.0 }]))
            .collect(),
        train: vec![0.0; 100],
        ..Default::default()
    };
    let adaptive = Walk {
        k_walk: KWalk::Adaptive { first: 1 },
        ..walk(2, 1, false)
    };
    // The paper's answer: the last K that holds.
    assert_eq!(backplay(&mut b, 40, &adaptive), Some((30, 0)));
    let trained: Vec<&String> = b.calls.iter().filter(|c| c.starts_with("train")).collect();
    // Only K = 29, reached at step 1, is trained (α = 2: three rounds).
    assert_eq!(trained, ["train 29 = 0", "train 29 = 0", "train 29 = 0"]);
    let tested: Vec<&str> = b
        .calls
        .iter()
        .filter_map(|c| c.strip_prefix("test "))
        .collect();
    assert_eq!(
        tested,
        [
            "39 = 1", "37 = 1", "33 = 1", // steps 2, 4, 8: the jump to 25 fails
            "25 = 0", "29 = 0", "31 = 1", // halved to 4 (from 33), then 2: 31 holds
            "27 = 0", "29 = 0", "30 = 1", // step 4 fails, 2 fails, 1 holds
            "28 = 0", "29 = 0", // step 2 fails; at step 1, K = 29 is trained
            "29 = 0"  // and still fails: return the last saved (30, π)
        ]
    );
}

#[test]
fn candidates_are_every_saved_skill_in_order() {
    let mut b = Scripted {
        tests: HashMap::from([
            (3, vec![1.0]),
            (2, vec![0.5]),
            (1, vec![1.0]),
            (0, vec![0.0]),
        ]),
        train: vec![0.1; 100],
        ..Default::default()
    };
    let found: Vec<usize> = backplay_candidates(&mut b, 4, &walk(2, 1, false))
        .into_iter()
        .map(|(k, _)| k)
        .collect();
    assert_eq!(found, [3, 1]);
}

#[test]
fn verification_falls_back_to_a_shorter_reach() {
    use pbcs::phase2::verified;
    // Saved (K, π): (3, 0), (2, 0), (1, 3). The farthest (1, π 3) fails its verification,
    // (2, π 0) passes: it is kept, and its verification used the requested episodes.
    let mut b = Scripted {
        verified: HashMap::from([((1, 3), 0.98)]),
        ..Default::default()
    };
    let found = verified(&mut b, vec![(3, 0), (2, 0), (1, 3)], Some(500));
    assert_eq!(found, Some((2, 0)));
    assert_eq!(
        b.calls,
        [
            "verify 1 (policy 3, 500 episodes) = 0.98",
            "verify 2 (policy 0, 500 episodes) = 1"
        ]
    );
    // Without verification: the paper's (K_s, π_s), the last saved, untested.
    let mut b = Scripted::default();
    assert_eq!(verified(&mut b, vec![(3, 0), (1, 3)], None), Some((1, 3)));
    assert!(b.calls.is_empty());
    // None passes: the best verified success, the farthest reach among ties.
    let mut b = Scripted {
        verified: HashMap::from([((3, 0), 0.9), ((2, 0), 0.99), ((1, 3), 0.99)]),
        ..Default::default()
    };
    assert_eq!(
        verified(&mut b, vec![(3, 0), (2, 0), (1, 3)], Some(100)),
        Some((1, 3))
    );
}

/// A learner that can solve any K within `reach` of T and nothing farther.
struct Reach {
    t: usize,
    reach: usize,
}

impl Backplayer for Reach {
    type Policy = (usize, usize);
    fn test(&mut self, k: usize) -> f32 {
        if self.t - k <= self.reach {
            1.0
        } else {
            0.0
        }
    }
    fn train(&mut self, _k: usize) -> f32 {
        0.0
    }
    fn policy(&self) -> (usize, usize) {
        (self.t, self.reach)
    }
    fn verify(&mut self, k: usize, _policy: &(usize, usize), _episodes: usize) -> f32 {
        self.test(k)
    }
    fn exhausted(&self) -> bool {
        false
    }
    fn ball_is_clear(&self, _k: usize) -> bool {
        false
    }
}

#[test]
fn skill_chaining_follows_tau_backwards_then_reverses() {
    let mut made = Vec::new();
    let config = Phase2Config {
        alpha: 2,
        ..Phase2Config::default()
    };
    let (skills, failure) = skill_chaining(
        35,
        &config,
        |n, t| {
            made.push((n, t));
            Ok(Reach { t, reach: 10 })
        },
        |_| {},
    )
    .unwrap();
    assert_eq!(failure, None);
    // Built backwards: T = 35 → K = 25, 25 → 15, 15 → 5, 5 → 0; returned in execution order.
    assert_eq!(made, [(0, 35), (1, 25), (2, 15), (3, 5)]);
    let spans: Vec<(usize, usize)> = skills.iter().map(|(k, t, _)| (*k, *t)).collect();
    assert_eq!(spans, [(0, 5), (5, 15), (15, 25), (25, 35)]);
    // Each skill's target is the next skill's activation centre.
    for w in skills.windows(2) {
        assert_eq!(w[0].1, w[1].0);
    }
}

#[test]
fn without_chaining_a_second_skill_is_a_failure() {
    let config = Phase2Config {
        alpha: 2,
        chaining: false,
        ..Phase2Config::default()
    };
    let (skills, failure) =
        skill_chaining(35, &config, |_, t| Ok(Reach { t, reach: 10 }), |_| {}).unwrap();
    assert_eq!(failure, Some(Failure::NoChaining));
    assert_eq!(skills.len(), 1);
    let (skills, failure) =
        skill_chaining(8, &config, |_, t| Ok(Reach { t, reach: 10 }), |_| {}).unwrap();
    assert_eq!(
        (skills.len(), failure),
        (1, None),
        "one skill covers τ: success"
    );
}

/// A walk that finds no success anywhere ends `dead_walk` Ks below T (the paper's walks on to
/// K = 0: `never_successful_without_a_kept_skill_goes_on_and_may_fail`); one success, in a
/// test or a training round, lifts the bound.
#[test]
fn a_dead_walk_gives_up_at_its_bound_unless_something_succeeded() {
    let bounded = Walk {
        dead_walk: Some(3),
        ..walk(2, 1, false)
    };
    let mut b = Scripted {
        tests: (0..10).map(|k| (k, vec![0.0])).collect(),
        train: vec![0.0; 100],
        ..Default::default()
    };
    assert_eq!(backplay(&mut b, 10, &bounded), None);
    let tested: Vec<&String> = b.calls.iter().filter(|c| c.starts_with("test")).collect();
    // K = 9, 8, 7: a test before and after training each, then T − K = 3.
    assert_eq!(tested.len(), 6);
    assert_eq!(tested.last().unwrap().as_str(), "test 7 = 0");
    // ... and says so, once, at the K where it stopped (a `dead_walk` trace row).
    assert_eq!(b.calls.last().unwrap().as_str(), "dead walk at 7");
    assert_eq!(b.calls.iter().filter(|c| c.starts_with("dead")).count(), 1);
    // One training round at 2 % (nothing saved): the walk is alive and goes on to K = 0.
    let mut b = Scripted {
        tests: (0..10).map(|k| (k, vec![0.0])).collect(),
        train: [vec![0.02], vec![0.0; 100]].concat(),
        ..Default::default()
    };
    assert_eq!(backplay(&mut b, 10, &bounded), None);
    assert!(b.calls.iter().any(|c| c == "test 0 = 0"), "{:?}", b.calls);
    assert!(
        !b.calls.iter().any(|c| c.starts_with("dead")),
        "{:?}",
        b.calls
    );
}

/// Skill chaining where no walk towards τ_`dead` finds anything, and the skill found last (its
/// target `t`) reaches its goal from any ball at or after `from`. Balls of odd indices touch a
/// wall.
pub(crate) struct DeadTarget {
    pub t: usize,
    pub dead: usize,
    pub from: usize,
    pub calls: std::rc::Rc<std::cell::RefCell<Vec<String>>>,
}

impl Backplayer for DeadTarget {
    type Policy = usize;
    fn test(&mut self, k: usize) -> f32 {
        f32::from(u8::from(self.t != self.dead && self.t - k <= 10))
    }
    fn train(&mut self, _k: usize) -> f32 {
        0.0
    }
    fn policy(&self) -> usize {
        self.t
    }
    fn verify(&mut self, k: usize, _policy: &usize, _episodes: usize) -> f32 {
        self.test(k)
    }
    fn verify_handover(&mut self, k: usize, policy: &usize, episodes: usize) -> f32 {
        assert_eq!(*policy, self.t, "the last skill's policy, on its own goal");
        let p = f32::from(u8::from(k >= self.from));
        self.calls
            .borrow_mut()
            .push(format!("handover {k} → {} ({episodes}) = {p}", self.t));
        p
    }
    fn ball_is_clear(&self, k: usize) -> bool {
        k.is_multiple_of(2)
    }
    fn exhausted(&self) -> bool {
        false
    }
}

/// After a dead walk with no restart left, the skill found last (25 → 35) is verified from
/// the later balls, clear ones first, nearest first; the first that passes becomes its start
/// and the next skill's target. Without `retargets` (the paper) the run fails there.
#[test]
fn a_dead_walk_moves_the_hand_over_to_a_later_clear_ball() {
    let config = Phase2Config {
        alpha: 2,
        ideas: Ideas {
            dead_walk: Some(DeadWalk {
                after: 5,
                retargets: 1,
            }),
            verify_skills: Some(100),
            ..Ideas::NONE
        },
        ..Phase2Config::default()
    };
    let calls = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
    let mut made = Vec::new();
    let (skills, failure) = skill_chaining(
        35,
        &config,
        |n, t| {
            made.push((n, t));
            Ok(DeadTarget {
                t,
                dead: 25,
                from: 29,
                calls: calls.clone(),
            })
        },
        |_| {},
    )
    .unwrap();
    assert_eq!(failure, None);
    // 35 → 25; 25 is dead: the skill ending at 35 is tried from 26, 28, 30 (clear), passes at
    // 30; then 30 → 20, 20 → 10, 10 → 0.
    assert_eq!(
        *calls.borrow(),
        [
            "handover 26 → 35 (100) = 0",
            "handover 28 → 35 (100) = 0",
            "handover 30 → 35 (100) = 1"
        ]
    );
    assert_eq!(made, [(0, 35), (1, 25), (2, 35), (3, 30), (4, 20), (5, 10)]);
    let spans: Vec<(usize, usize)> = skills.iter().map(|(k, t, _)| (*k, *t)).collect();
    assert_eq!(spans, [(0, 10), (10, 20), (20, 30), (30, 35)]);
    // The paper: no move, the run fails at the dead target.
    let mut paper = config.clone();
    paper.ideas.dead_walk = Some(DeadWalk {
        after: 5,
        retargets: 0,
    });
    let (skills, failure) = skill_chaining(
        35,
        &paper,
        |_, t| {
            Ok(DeadTarget {
                t,
                dead: 25,
                from: 29,
                calls: calls.clone(),
            })
        },
        |_| {},
    )
    .unwrap();
    assert_eq!((skills.len(), failure), (1, Some(Failure::BackplayFailed)));
    // No ball within reach passes: the run fails after MAX_HANDOVER_TRIES tries.
    calls.borrow_mut().clear();
    let (_, failure) = skill_chaining(
        35,
        &config,
        |_, t| {
            Ok(DeadTarget {
                t,
                dead: 25,
                from: 34,
                calls: calls.clone(),
            })
        },
        |_| {},
    )
    .unwrap();
    assert_eq!(failure, Some(Failure::BackplayFailed));
    assert_eq!(calls.borrow().len(), pbcs::phase2::MAX_HANDOVER_TRIES);
}
