//! Phase 2: Backplay's control flow on a scripted learner, skill chaining, chain execution,
//! saving and loading chains, and PBCS end to end on maze 2.

use pbcs::env::{Env, Step};
use pbcs::nn::{Head, Mlp};
use pbcs::pbcs::backplay::{backplay, Backplayer};
use pbcs::pbcs::{skill_chaining, Ball, Failure, Phase2Config, Skill, SkillChain};
use pbcs::rng::{Seeds, Stream};
use std::collections::HashMap;

/// A learner whose results are dictated: `tests[k]` is the list of successive test results at
/// K (the last one repeats), `train` the successive training results. The policy is the
/// number of training rounds run so far, so a returned π_s says when it was saved.
#[derive(Default)]
struct Scripted {
    tests: HashMap<usize, Vec<f32>>,
    train: Vec<f32>,
    calls: Vec<String>,
    rounds: usize,
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
}

#[test]
fn always_successful_walks_to_zero_without_training() {
    let mut b = Scripted {
        tests: (0..5).map(|k| (k, vec![1.0])).collect(),
        ..Default::default()
    };
    assert_eq!(backplay(&mut b, 5, 10, 1, false), Some((0, 0)));
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

#[test]
fn training_stops_after_alpha_non_improvements() {
    // α = 3. Training results 0.2 (best), 0.5 (best), 0.5, 0.4, 0.3 (three misses): 5 rounds.
    let mut b = Scripted {
        tests: HashMap::from([(2, vec![0.5, 1.0]), (1, vec![1.0]), (0, vec![1.0])]),
        train: vec![0.2, 0.5, 0.5, 0.4, 0.3, 0.9],
        ..Default::default()
    };
    assert_eq!(backplay(&mut b, 3, 3, 1, false), Some((0, 5)));
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
    assert_eq!(backplay(&mut b, 5, 2, 1, false), Some((4, 0)));
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
    assert_eq!(backplay(&mut b, 3, 2, 1, false), Some((1, 3)));
    assert!(b.calls.contains(&"test 2 = 0.6".to_string()));
}

#[test]
fn never_successful_without_a_kept_skill_goes_on_and_may_fail() {
    let mut b = Scripted {
        tests: (0..3).map(|k| (k, vec![0.0])).collect(),
        train: vec![0.0; 100],
        ..Default::default()
    };
    assert_eq!(backplay(&mut b, 3, 2, 1, false), None);
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
    assert_eq!(backplay(&mut b, 2, 3, 1, true), Some((0, 2)));
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
    backplay(&mut b, 2, 3, 1, false);
    assert_eq!(b.calls.iter().filter(|c| c.starts_with("train")).count(), 5);
}

#[test]
fn k_step_walks_back_faster_but_still_ends_at_zero() {
    let mut b = Scripted {
        tests: (0..10).map(|k| (k, vec![1.0])).collect(),
        ..Default::default()
    };
    assert_eq!(backplay(&mut b, 10, 10, 4, false), Some((0, 0)));
    assert_eq!(
        b.calls,
        ["test 9 = 1", "test 5 = 1", "test 1 = 1", "test 0 = 1"]
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
        policy: constant_policy(dir),
        activation: Ball {
            center,
            radius: 0.25,
        },
        start_index: k,
        target_index: k + 1,
    };
    SkillChain {
        skills: vec![
            skill([1.0, 0.0], vec![0.0, 0.0], 0),
            skill([1.0, 1.0], vec![1.0, 0.0], 1),
        ],
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
    let loaded = SkillChain::load(dir.path()).unwrap();
    assert_eq!(loaded, chain);
    assert_eq!(
        loaded.run(&Plane, [0.0, 0.0], 50),
        chain.run(&Plane, [0.0, 0.0], 50)
    );
    let err = SkillChain::load(&dir.path().join("missing"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("manifest.toml"), "{err}");
}

mod end_to_end {
    use pbcs::config::RunJob;
    use pbcs::jobs::run_pbcs;

    fn job(seed: u64) -> RunJob {
        let mut job = RunJob::default();
        job.maze.size = 2;
        job.seed = seed;
        job
    }

    /// The default (faithful) preset solves the 2×2 maze: at least 2 of seeds 0, 1, 2 within a
    /// budget of 1M environment steps (the paper used 321k on its one seed).
    #[test]
    fn pbcs_solves_maze_2_for_most_seeds() {
        let mut solved = 0;
        let mut report = Vec::new();
        for seed in 0..3 {
            let mut j = job(seed);
            j.phase2.max_env_steps = 1_000_000;
            let dir = tempfile::tempdir().unwrap();
            let (r, _) = run_pbcs(&j, dir.path(), |_, _| {}).unwrap();
            report.push(format!(
                "seed {seed}: solved {} success {} steps {} skills {} failure '{}'",
                r.solved, r.success_rate, r.total_steps, r.skills, r.failure
            ));
            solved += usize::from(r.solved);
        }
        assert!(solved >= 2, "{report:#?}");
    }

    /// A grid resumes: finished cells are read back (same records), and a folder of another
    /// config is refused rather than mixed in.
    #[test]
    fn grid_resumes_and_refuses_another_config() {
        let mut j = job(0);
        j.phase2.max_env_steps = 5_000;
        let dir = tempfile::tempdir().unwrap();
        let first = pbcs::jobs::run_grid(&j, &[2], &[0, 1], dir.path(), 2, |_, _| {}).unwrap();
        assert_eq!(first.len(), 2);
        let again = pbcs::jobs::run_grid(&j, &[2], &[0, 1], dir.path(), 1, |_, _| {}).unwrap();
        let records = |v: &[(pbcs::jobs::RunRecord, f64)]| {
            v.iter().map(|(r, _)| r.clone()).collect::<Vec<_>>()
        };
        assert_eq!(records(&first), records(&again));
        j.phase2.epsilon = 0.15;
        let err = pbcs::jobs::run_grid(&j, &[2], &[0], dir.path(), 1, |_, _| {}).unwrap_err();
        assert!(err.to_string().contains("another config"), "{err}");
    }

    /// Same seed, same bytes: the whole pipeline (phase 1, phase 2, evaluation, files). A small
    /// budget keeps it quick; the budget failure is itself deterministic.
    #[test]
    fn pbcs_run_is_byte_identical_per_seed() {
        let mut j = job(5);
        j.phase2.max_env_steps = 30_000;
        let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
        let (ra, _) = run_pbcs(&j, a.path(), |_, _| {}).unwrap();
        run_pbcs(&j, b.path(), |_, _| {}).unwrap();
        assert!(ra.total_steps > 0);
        for f in [
            "record.csv",
            "skills.csv",
            "trajectory.csv",
            "config.toml",
            "run.png",
            "run.svg",
            "chain/manifest.toml",
        ] {
            let (x, y) = (
                std::fs::read(a.path().join(f)).unwrap(),
                std::fs::read(b.path().join(f)).unwrap(),
            );
            assert!(x == y, "{f} differs between two runs of one seed");
        }
    }
}
