//! Phase 2: Backplay's control flow on a scripted learner, skill chaining, chain execution,
//! saving and loading chains, and PBCS end to end on maze 2.

use pbcs::env::{Env, Step};
use pbcs::nn::{Head, Mlp};
use pbcs::phase2::backplay::{backplay, backplay_candidates, Backplayer, KWalk, Stopping, Walk};
use pbcs::phase2::goal::Inputs;
use pbcs::phase2::{Ball, Between, Failure, Made, Phase2Config, Skill, SkillChain};
use pbcs::rng::{Seeds, Stream};
use std::collections::HashMap;

/// Algorithm 1 run to its end ([`Between::step`] until it breaks) on the problems `next(n, T)`
/// makes and `finished` takes back: the skills in execution order and why it stopped early.
#[allow(clippy::type_complexity)]
fn skill_chaining<B: Backplayer>(
    n: usize,
    config: &Phase2Config,
    next: impl FnMut(usize, usize) -> pbcs::error::Result<B>,
    finished: impl FnMut(B),
) -> pbcs::error::Result<(Vec<(usize, usize, B::Policy)>, Option<Failure>)> {
    let mut problems = Made::new(next, finished);
    let mut at = Between::start(n);
    loop {
        if let std::ops::ControlFlow::Break(failure) = at.step(config, &mut problems)? {
            return Ok((at.into_skills(), failure));
        }
    }
}

mod backplay;
mod capabilities;
mod drawn;
mod goal_conditioned;
mod patience;
use backplay::{walk, Scripted};

/// An open plane: no walls, actions clipped to ±0.1, reward 1 when x ≥ 3.
struct Plane;

impl Env for Plane {
    type State = [f32; 2];
    fn obs_dim(&self) -> usize {
        2
    }
    fn action_dim(&self) -> usize {
        2
    }
    fn action_bound(&self, _i: usize) -> f32 {
        0.1
    }
    fn start(&self) -> [f32; 2] {
        [0.0, 0.0]
    }
    fn sample_start(&self, _rng: &mut pbcs::rng::Rng) -> [f32; 2] {
        self.start()
    }
    fn observe(&self, s: &[f32; 2], out: &mut [f32]) {
        out.copy_from_slice(s);
    }
    fn step(&self, s: &[f32; 2], a: &[f32]) -> Step<[f32; 2]> {
        let n = [s[0] + a[0].clamp(-0.1, 0.1), s[1] + a[1].clamp(-0.1, 0.1)];
        let done = n[0] >= 3.0;
        Step {
            state: n,
            reward: f32::from(u8::from(done)),
            terminal: done,
        }
    }
}

/// A policy that always outputs `dir` (±0.1 per component): zero weights, saturated bias.
fn constant_policy(dir: [f32; 2]) -> Mlp {
    let mut rng = Seeds::new(0).stream(Stream::Init);
    let mut m = Mlp::new(&[2, 4, 2], Head::Tanh(vec![0.1, 0.1]), &mut rng);
    m.params.iter_mut().for_each(|p| *p = 0.0);
    let (_, b) = m.offsets(1);
    m.params[b] = 20.0 * dir[0].signum() * f32::from(u8::from(dir[0] != 0.0));
    m.params[b + 1] = 20.0 * dir[1].signum() * f32::from(u8::from(dir[1] != 0.0));
    m
}

fn two_skill_chain() -> SkillChain {
    let skill = |dir, center: Vec<f32>, k| Skill {
        policy: Box::new(constant_policy(dir)),
        activation: Ball::new(center, 0.25),
        start_index: k,
        target_index: k + 1,
        inputs: Inputs::new(vec![0.0, 0.0], vec![1.0, 1.0]),
    };
    SkillChain {
        skills: vec![
            skill([1.0, 0.0], vec![0.0, 0.0], 0),
            skill([1.0, 1.0], vec![1.0, 0.0], 1),
        ],
        kernel: pbcs::nn::kernel::Kernel::detect(),
    }
}

#[test]
fn chain_execution_switches_exactly_on_entering_the_next_ball() {
    let chain = two_skill_chain();
    let r = chain.run(&Plane, Plane.start(), 100);
    // π_0 moves along +x: x = 0.1, 0.2, ... The first state within 0.25 of (1, 0) is x ≈ 0.8.
    let first_inside = r
        .states
        .iter()
        .position(|s| ((s[0] - 1.0).powi(2) + s[1].powi(2)).sqrt() <= 0.25)
        .unwrap();
    assert!((r.states[first_inside][0] - 0.8).abs() < 1e-4);
    for (i, &used) in r.skill_used.iter().enumerate() {
        assert_eq!(used, usize::from(i >= first_inside), "step {i}");
    }
    // After the switch π_1 moves diagonally.
    let s = r.states[first_inside + 1];
    assert!((s[1] - 0.1).abs() < 1e-6, "{s:?}");
    assert!(r.success);
}

#[test]
fn a_saved_chain_loads_and_runs_the_same() {
    let chain = two_skill_chain();
    let dir = tempfile::tempdir().unwrap();
    chain.save(dir.path()).unwrap();
    let loaded = SkillChain::load(dir.path(), pbcs::nn::kernel::Kernel::detect()).unwrap();
    assert_eq!(loaded, chain);
    assert_eq!(
        loaded.run(&Plane, [0.0, 0.0], 50),
        chain.run(&Plane, [0.0, 0.0], 50)
    );
    let err = SkillChain::load(
        &dir.path().join("missing"),
        pbcs::nn::kernel::Kernel::detect(),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("manifest.toml"), "{err}");
}

mod end_to_end;

/// Algorithm 3's goal and inputs: one region decides reached, reward and potential.
mod algorithm3;

#[test]
fn stop_at_failure_ends_the_walk_at_a_partial_failure_from_a_clear_ball() {
    // K = 3 solved; K = 2 fails partly after training; K = 1 would succeed again.
    let script = || Scripted {
        tests: HashMap::from([
            (3, vec![1.0]),
            (2, vec![0.5]),
            (1, vec![1.0]),
            (0, vec![0.0]),
        ]),
        train: vec![0.1; 100],
        ..Default::default()
    };
    let stop = Walk {
        stop_at_failure: true,
        ..walk(2, 1, false)
    };
    // The paper (and this option when the ball is not known to be clear) goes on to K = 1.
    let mut b = script();
    assert_eq!(
        backplay(&mut b, 4, &walk(2, 1, false)).map(|(k, _)| k),
        Some(1)
    );
    let mut b = script();
    assert_eq!(backplay(&mut b, 4, &stop).map(|(k, _)| k), Some(1));
    // A clear ball at K = 2: the failure is the policy's, the walk ends with (3, π).
    let mut b = Clear(script());
    assert_eq!(backplay(&mut b, 4, &stop), Some((3, 0)));
    assert!(!b.0.calls.iter().any(|c| c.starts_with("test 1")));
}

/// [`Scripted`] with every ball clear of obstacles.
struct Clear(Scripted);

impl Backplayer for Clear {
    type Policy = usize;
    fn test(&mut self, k: usize) -> f32 {
        self.0.test(k)
    }
    fn train(&mut self, k: usize) -> f32 {
        self.0.train(k)
    }
    fn policy(&self) -> usize {
        self.0.policy()
    }
    fn verify(&mut self, k: usize, policy: &usize, episodes: usize) -> f32 {
        self.0.verify(k, policy, episodes)
    }
    fn ball_is_clear(&self, _k: usize) -> bool {
        true
    }
    fn exhausted(&self) -> bool {
        false
    }
}

/// A [`SkillTask`] on maze 2 along a straight τ to the right, with a policy pushing up.
mod skill_task;

/// A learner that collapses (0 % everywhere) in its first `dead` problems, then reaches 10.
struct Collapsing {
    t: usize,
    dead: bool,
}

impl Backplayer for Collapsing {
    type Policy = usize;
    fn test(&mut self, k: usize) -> f32 {
        f32::from(u8::from(!self.dead && self.t - k <= 10))
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
    fn exhausted(&self) -> bool {
        false
    }
    fn ball_is_clear(&self, _k: usize) -> bool {
        false
    }
}

#[test]
fn a_collapsed_skill_restarts_with_a_fresh_learner_while_restarts_are_left() {
    let run = |restarts: usize| {
        let config = Phase2Config {
            alpha: 1,
            ideas: pbcs::phase2::Ideas {
                restarts,
                ..pbcs::phase2::Ideas::NONE
            },
            ..Phase2Config::default()
        };
        let mut made = Vec::new();
        let out = skill_chaining(
            15,
            &config,
            |n, t| {
                made.push((n, t));
                // Problems 0 and 1 collapse; later ones learn.
                Ok(Collapsing { t, dead: n < 2 })
            },
            |_| {},
        )
        .unwrap();
        (out, made)
    };
    // The paper (no restarts): the collapsed learner walks K down to 0 and fails.
    let ((skills, failure), made) = run(0);
    assert_eq!(
        (skills.len(), failure, made),
        (0, Some(Failure::BackplayFailed), vec![(0, 15)])
    );
    // One restart is not enough; two are: problem 2 solves T = 15, problem 3 T = 5.
    let ((_, failure), _) = run(1);
    assert_eq!(failure, Some(Failure::BackplayFailed));
    let ((skills, failure), made) = run(2);
    assert_eq!(failure, None);
    assert_eq!(made, [(0, 15), (1, 15), (2, 15), (3, 5)]);
    let spans: Vec<(usize, usize)> = skills.iter().map(|(k, t, _)| (*k, *t)).collect();
    assert_eq!(spans, [(0, 5), (5, 15)]);
}

#[test]
fn a_limited_chain_run_stops_a_stuck_or_slow_skill() {
    // A skill pushing into nothing forever: on the plane a zero action never moves, so the
    // limited run stops after one step (stuck); the plain run spends its whole budget.
    let mut chain = two_skill_chain();
    chain.skills[0].policy = Box::new(constant_policy([0.0, 0.0]));
    let plain = chain.run(&Plane, [0.0, 0.0], 40);
    assert_eq!(plain.skill_used.len(), 40);
    let limited = chain.run_limited(&Plane, [0.0, 0.0], 40, Some(1000));
    assert_eq!(limited.skill_used.len(), 1);
    assert!(!limited.success);
    // A moving skill that needs 8 steps to hand over fails under a limit of 5 actions per
    // skill, and succeeds under 50 exactly as the plain run does.
    let chain = two_skill_chain();
    let slow = chain.run_limited(&Plane, [0.0, 0.0], 100, Some(5));
    assert_eq!((slow.skill_used.len(), slow.success), (5, false));
    assert_eq!(
        chain.run_limited(&Plane, [0.0, 0.0], 100, Some(50)),
        chain.run(&Plane, [0.0, 0.0], 100)
    );
}

mod switches;

/// A saved chain's manifest is checked value by value when it is loaded.
mod manifest;

/// A run folder is written completely or marked incomplete.
mod resume;
mod run_folder;
