//! The rollout engine (`src/rollout.rs`): lockstep episodes end where their verdicts say, in
//! row order, and stop early when asked; the greedy evaluation through it equals the plain
//! one-episode-at-a-time loop it replaced.

use pbcs::config::MazeConfig;
use pbcs::env::{Env, Step};
use pbcs::envs::maze::Maze;
use pbcs::envs::toy::Toy1D;
use pbcs::learner::td3::{Td3, Td3Config};
use pbcs::nn::kernel::Kernel;
use pbcs::rng::{Seeds, Stream};
use pbcs::rollout::{lockstep, Agent, Tally, Verdict};

/// Pushes left at full speed (the toy's target is at 0, steps of at most 0.1) and records
/// which episodes each step ran, in the order `after` saw them.
#[derive(Default)]
struct Left {
    rows: Vec<Vec<usize>>,
}

impl Agent<Toy1D> for Left {
    fn act(&mut self, lanes: &[usize], obs: &[f32], actions: &mut [f32]) {
        assert_eq!((obs.len(), actions.len()), (lanes.len(), lanes.len()));
        actions.fill(-1.0);
        self.rows.push(Vec::new());
    }

    fn after(
        &mut self,
        j: usize,
        lane: usize,
        state: &f32,
        obs: &[f32],
        step: &Step<f32>,
        next_obs: &[f32],
    ) -> Verdict {
        let row = self.rows.last_mut().unwrap();
        assert_eq!(row.len(), j, "rows come in order");
        row.push(lane);
        assert_eq!((obs[0], next_obs[0]), (*state, step.state));
        Verdict::of_terminal(step)
    }
}

#[test]
fn lockstep_runs_each_episode_until_its_verdict_and_counts_them() {
    let env = Toy1D;
    // 0.05 reaches 0 in one step; 0.25 in three; 0.95 needs ten.
    let mut agent = Left::default();
    let tally = lockstep(&env, &mut agent, vec![0.05, 0.25, 0.95], 4, |_| false);
    assert_eq!(
        tally,
        Tally {
            successes: 2,
            failures: 0
        }
    );
    assert_eq!(
        agent.rows,
        [vec![0, 1, 2], vec![1, 2], vec![1, 2], vec![2]],
        "an ended episode leaves the batch"
    );
    // No start, no step; a limit of 0, no step either.
    assert_eq!(
        lockstep(&env, &mut Left::default(), Vec::new(), 9, |_| false),
        Tally::default()
    );
    let mut idle = Left::default();
    assert_eq!(
        lockstep(&env, &mut idle, vec![0.5], 0, |_| false),
        Tally::default()
    );
    assert!(idle.rows.is_empty());
}

#[test]
fn lockstep_stops_when_the_tally_says_so() {
    let env = Toy1D;
    let mut agent = Left::default();
    let tally = lockstep(&env, &mut agent, vec![0.05, 0.5, 0.95], 100, |t| {
        t.successes >= 1
    });
    assert_eq!(tally.successes, 1);
    assert_eq!(agent.rows.len(), 1, "stopped after the first step");
}

/// The loop `train::greedy_episodes` was before the engine: one episode at a time, the
/// learner's action scaled to the bounds, success at a positive terminal reward.
fn plain_greedy(env: &Maze, learner: &mut Td3, start: <Maze as Env>::State) -> (bool, usize) {
    let mut obs = vec![0.0; env.obs_dim()];
    let mut action = vec![0.0; env.action_dim()];
    let mut s = start;
    for steps in 1..=60 {
        env.observe(&s, &mut obs);
        let a = learner.act(&obs, 1);
        for (i, (o, x)) in action.iter_mut().zip(a).enumerate() {
            *o = x * env.action_bound(i);
        }
        let step = env.step(&s, &action);
        s = step.state;
        if step.terminal {
            return (step.reward > 0.0, steps);
        }
    }
    (false, 60)
}

#[test]
fn greedy_episodes_through_the_engine_equal_the_plain_loop() {
    let env = Maze::new(&MazeConfig {
        size: 2,
        ..MazeConfig::default()
    })
    .unwrap();
    let seeds = Seeds::new(3);
    let mut rng = seeds.stream(Stream::Eval);
    let starts: Vec<_> = (0..20).map(|_| env.sample_start(&mut rng)).collect();
    let mut outcomes = Vec::new();
    // Untrained learners of several seeds: some episodes end at the target, most run out.
    for seed in 0..6 {
        let unit = [1.0, 1.0];
        let learner = |s| {
            Td3::new(
                &Td3Config::ddpg(),
                2,
                &unit,
                &Seeds::new(s),
                Kernel::detect(),
            )
            .unwrap()
        };
        let (mut a, mut b) = (learner(seed), learner(seed));
        let engine = pbcs::vanilla::greedy_episodes(
            &env,
            &mut a,
            pbcs::vanilla::GoalInputs::NONE,
            starts.clone(),
            60,
        );
        for (e, s) in engine.iter().zip(&starts) {
            let plain = plain_greedy(&env, &mut b, *s);
            assert_eq!((e.success, e.steps), plain, "seed {seed}, start {s}");
            outcomes.push(plain.0);
        }
    }
    assert!(
        outcomes.contains(&false),
        "every episode succeeded: the test is vacuous"
    );
}
