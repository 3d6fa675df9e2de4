//! Hindsight experience replay: the environments' goal rewards against their own steps, the
//! buffer's sampling (Stable-Baselines3's `HerReplayBuffer` semantics), and training with it.

use pbcs::env::Env;
use pbcs::envs::maze::{Maze, MazeConfig};
use pbcs::envs::rooms::TwoRooms;
use pbcs::envs::three_rooms::ThreeRooms;
use pbcs::envs::toy::Toy1D;
use pbcs::learner::her::{GoalSelection, GoalTransition, HerConfig, HerReplay};
use pbcs::learner::replay::Batch;
use pbcs::learner::LearnerConfig;
use pbcs::nn::kernel::Kernel;
use pbcs::rng::{Seeds, Stream};
use pbcs::vanilla::GoalInputs;
use pbcs::vanilla::{train_vanilla, TrainConfig};
use rand::Rng as _;

/// From random states near and far from the target, with random actions: the goal's part of
/// the step's reward is what `goal_reward` gives for the goal the next observation achieved
/// and the episode's goal, and it is 1 exactly when the step ends the episode (these tasks end
/// on success only); whatever else the reward holds (the maze's −1 on a wall) is not 1.
fn goal_reward_is_the_steps<E: Env>(env: &E, near: impl Fn(&mut pbcs::rng::Rng) -> E::State) {
    let goals = env.goals().expect("offers goals");
    let g = goals.goal_dim();
    let (mut obs, mut achieved, mut desired) =
        (vec![0.0; env.obs_dim()], vec![0.0; g], vec![0.0; g]);
    let mut rng = Seeds::new(3).stream(Stream::Start);
    let mut reached = 0;
    for i in 0..4000 {
        let s = if i % 2 == 0 {
            near(&mut rng)
        } else {
            env.sample_start(&mut rng)
        };
        let a: Vec<f32> = (0..env.action_dim())
            .map(|j| rng.random_range(-1.0..1.0) * env.action_bound(j))
            .collect();
        let step = env.step(&s, &a);
        env.observe(&step.state, &mut obs);
        goals.achieved_goal(&obs, &mut achieved);
        goals.desired_goal(&s, &mut desired);
        let r = goals.goal_reward(&achieved, &desired);
        assert_eq!(r, f32::from(u8::from(step.terminal)), "step {i}: {step:?}");
        assert!(
            step.reward - r != 1.0,
            "step {i}: the rest is not the goal's"
        );
        reached += usize::from(step.terminal);
    }
    assert!(reached > 100, "the target was reached {reached} times");
}

#[test]
fn the_environments_goal_rewards_are_their_steps() {
    let maze = Maze::new(&MazeConfig {
        size: 3,
        ..MazeConfig::default()
    })
    .unwrap();
    let t = maze.target();
    goal_reward_is_the_steps(&maze, |rng| {
        nalgebra::Point2::new(
            t.x + rng.random_range(-0.3..0.3),
            t.y + rng.random_range(-0.3..0.3),
        )
    });
    let near = |target: [f32; 2]| {
        move |rng: &mut pbcs::rng::Rng| {
            [
                target[0] + rng.random_range(-0.3f32..0.3),
                (target[1] + rng.random_range(-0.3f32..0.3)).max(0.0),
            ]
        }
    };
    goal_reward_is_the_steps(&TwoRooms, near(pbcs::envs::rooms::TARGET));
    let three = ThreeRooms.success_region().unwrap().0;
    goal_reward_is_the_steps(&ThreeRooms, near([three[0], three[1]]));
}

/// PointMaze (the MuJoCo build): the same, from rest near the goal and from its start.
#[cfg(feature = "mujoco")]
#[test]
fn pointmaze_goal_rewards_are_its_steps() {
    use pbcs::envs::pointmaze::{MapName, PointMaze};
    let env = PointMaze::named(MapName::UMaze).unwrap();
    let goal = env.goal();
    goal_reward_is_the_steps(&env, |rng| {
        env.at_rest([
            goal[0] + rng.random_range(-0.6..0.6),
            goal[1] + rng.random_range(-0.6..0.6),
        ])
    });
}

/// AntMaze (the MuJoCo build): the same, from its resets (start and goal ±1 m around their
/// cells' centres) and from rest near the episode's goal, legs kicking.
#[cfg(feature = "mujoco")]
#[test]
fn antmaze_goal_rewards_are_its_steps() {
    use pbcs::envs::antmaze::AntMaze;
    use pbcs::envs::pointmaze::MapName;
    let env = AntMaze::named(MapName::UMaze).unwrap();
    goal_reward_is_the_steps(&env, |rng| {
        let s = env.sample_start(rng);
        let near = s.goal.map(|g| g + rng.random_range(-0.6..0.6));
        env.at_rest(near, s.goal)
    });
}

/// One push per step of an episode of `len` transitions along a line: observation t, next
/// observation and achieved goal t + 1, goal `aim`, reward 1 − 1 (a wall) at odd steps.
fn episode(her: &mut HerReplay, from: f32, len: usize, aim: f32) {
    for t in 0..len {
        let (s, s2) = (from + t as f32, from + t as f32 + 1.0);
        let rest = if t % 2 == 1 { -1.0 } else { 0.0 };
        let r = f32::from(u8::from(s2 == aim)) + rest;
        her.push(GoalTransition {
            obs: &[s],
            act: &[0.5],
            rew: r,
            next_obs: &[s2],
            done: s2 == aim,
            desired: &[aim],
            achieved_next: &[s2],
            rest,
            chained: None,
        });
    }
    her.end_episode();
}

fn exact(achieved: &[f32], desired: &[f32]) -> f32 {
    f32::from(u8::from(achieved == desired))
}

/// Real rows keep their goal and reward; relabelled ones (⌊0.8·n⌋ of them with 4 sampled goals,
/// after the real ones) take a goal achieved later in their own episode and the reward for it
/// plus the stored part that is not the goal's; unfinished episodes are never sampled.
#[test]
fn future_goals_come_from_later_in_the_same_episode() {
    let mut her = HerReplay::new(1000, 1, 1, 1, HerConfig::default());
    episode(&mut her, 0.0, 10, 100.0);
    episode(&mut her, 200.0, 5, 100.0);
    // An unfinished episode: never in a batch.
    her.push(GoalTransition {
        obs: &[500.0],
        act: &[0.5],
        rew: 0.0,
        next_obs: &[501.0],
        done: false,
        desired: &[100.0],
        achieved_next: &[501.0],
        rest: 0.0,
        chained: None,
    });
    assert_eq!(her.sampleable(), 15);
    let mut b = Batch::default();
    let mut rng = Seeds::new(1).stream(Stream::Replay);
    let mut relabelled_hits = 0;
    for _ in 0..50 {
        assert!(her.sample(256, &mut rng, &exact, &mut b));
        let real = 256 - 204;
        assert_eq!(HerConfig::default().virtual_count(256), 204);
        for k in 0..256 {
            let (s, goal, s2) = (b.obs[2 * k], b.obs[2 * k + 1], b.next_obs[2 * k]);
            assert!(s < 500.0, "an unfinished episode was sampled");
            assert_eq!(b.next_obs[2 * k + 1], goal);
            assert_eq!(b.act[k], 0.5);
            let rest = if (s as usize % 200) % 2 == 1 {
                -1.0
            } else {
                0.0
            };
            if k < real {
                assert_eq!((goal, b.rew[k]), (100.0, rest));
            } else {
                let end = if s < 200.0 { 10.0 } else { 205.0 };
                assert!(goal >= s2 && goal <= end, "{s} → goal {goal}");
                assert_eq!(b.rew[k], f32::from(u8::from(goal == s2)) + rest);
                relabelled_hits += usize::from(goal == s2);
            }
        }
    }
    assert!(relabelled_hits > 500, "{relabelled_hits}");
}

/// `final` gives every relabelled row its episode's last achieved goal; `episode` any of them.
#[test]
fn final_and_episode_strategies() {
    for (strategy, check) in [
        (
            GoalSelection::Final,
            (|s: f32, g: f32| g == if s < 200.0 { 10.0 } else { 205.0 }) as fn(f32, f32) -> bool,
        ),
        (GoalSelection::Episode, |s: f32, g: f32| {
            if s < 200.0 {
                (1.0..=10.0).contains(&g)
            } else {
                (201.0..=205.0).contains(&g)
            }
        }),
    ] {
        let config = HerConfig {
            n_sampled_goal: 1,
            goal_selection_strategy: strategy,
            ..HerConfig::default()
        };
        let mut her = HerReplay::new(100, 1, 1, 1, config.clone());
        episode(&mut her, 0.0, 10, 100.0);
        episode(&mut her, 200.0, 5, 100.0);
        let mut b = Batch::default();
        let mut rng = Seeds::new(2).stream(Stream::Replay);
        assert!(her.sample(100, &mut rng, &exact, &mut b));
        assert_eq!(config.virtual_count(100), 50);
        let mut earlier = 0;
        for k in 50..100 {
            let (s, g) = (b.obs[2 * k], b.obs[2 * k + 1]);
            assert!(check(s, g), "{strategy:?}: {s} → {g}");
            earlier += usize::from(g <= s);
        }
        assert_eq!(
            earlier > 0,
            strategy == GoalSelection::Episode,
            "{strategy:?}: goals before the transition"
        );
    }
}

/// When the ring overwrites an old episode's first transition, the rest of that episode is
/// never sampled again.
#[test]
fn an_overwritten_episode_is_not_sampled() {
    let mut her = HerReplay::new(12, 1, 1, 1, HerConfig::default());
    episode(&mut her, 0.0, 8, 100.0);
    episode(&mut her, 200.0, 4, 100.0);
    assert_eq!(her.sampleable(), 12);
    // A new episode writes over the first one's first transitions.
    episode(&mut her, 400.0, 2, 100.0);
    assert_eq!(her.sampleable(), 4 + 2);
    let mut b = Batch::default();
    let mut rng = Seeds::new(3).stream(Stream::Replay);
    for _ in 0..20 {
        assert!(her.sample(64, &mut rng, &exact, &mut b));
        assert!(b.obs.chunks(2).all(|r| r[0] >= 200.0), "{:?}", b.obs);
    }
    // Nothing finished: no batch.
    let mut empty = HerReplay::new(10, 1, 1, 1, HerConfig::default());
    assert!(!empty.sample(4, &mut rng, &exact, &mut b));
}

/// Training with HER is deterministic, its policy sees the goal, and an environment without
/// goals, or a replay smaller than an episode, is refused naming the setting.
#[test]
fn training_with_her_is_deterministic_and_refused_where_it_cannot_run() {
    let maze = Maze::new(&MazeConfig {
        size: 2,
        ..MazeConfig::default()
    })
    .unwrap();
    let train = TrainConfig {
        steps: 3_000,
        max_episode_steps: 200,
        learning_starts: 1_000,
        eval_every: 1_000,
        eval_episodes: 2,
        her: Some(HerConfig::default()),
        ..TrainConfig::default()
    };
    for learner in [LearnerConfig::td3(), small_sac()] {
        let run = || {
            train_vanilla(
                &maze,
                &learner,
                &train,
                &Seeds::new(4),
                Kernel::detect(),
                |_, _| {},
            )
            .unwrap()
        };
        let (a, b) = (run(), run());
        assert_eq!(a.evals, b.evals);
        assert!(a.learner.policy().same(&*b.learner.policy()));
        // Observation (2) then goal (2).
        assert_eq!(a.learner.policy().obs_dim(), 4);
    }
    let err = train_vanilla(
        &Toy1D,
        &LearnerConfig::td3(),
        &train,
        &Seeds::new(0),
        Kernel::detect(),
        |_, _| {},
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("train.her") && err.contains("Env::goals"),
        "{err}"
    );
    let err = train_vanilla(
        &maze,
        &toml::from_str("algo = \"td3\"\nbatch_size = 10\nreplay_size = 100").unwrap(),
        &train,
        &Seeds::new(0),
        Kernel::detect(),
        |_, _| {},
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("learner.replay_size"), "{err}");
    // A frame given to the evaluations rewrites every input the policy acts on: one call per
    // step taken ([`pbcs::env::Goals::body_frame`]'s place in `evaluate` and
    // `greedy_episodes`).
    let mut trained = train_vanilla(
        &maze,
        &LearnerConfig::td3(),
        &train,
        &Seeds::new(4),
        Kernel::detect(),
        |_, _| {},
    )
    .unwrap();
    thread_local!(static CALLS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) });
    fn count(input: &mut [f32]) {
        assert_eq!(input.len(), 4);
        CALLS.with(|c| c.set(c.get() + 1));
    }
    let goals = maze.goals();
    let (_, _, length) = pbcs::vanilla::evaluate(
        &maze,
        trained.learner.as_mut(),
        GoalInputs {
            goals,
            frame: Some(count),
        },
        3,
        40,
        &Seeds::new(0),
        0,
    );
    assert_eq!(CALLS.with(|c| c.take()), (length * 3.0).round() as usize);
    let mut rng = Seeds::new(1).stream(Stream::Eval);
    let starts = (0..3).map(|_| maze.sample_start(&mut rng)).collect();
    let episodes = pbcs::vanilla::greedy_episodes(
        &maze,
        trained.learner.as_mut(),
        GoalInputs {
            goals,
            frame: Some(count),
        },
        starts,
        40,
    );
    let steps: usize = episodes.iter().map(|e| e.steps).sum();
    assert!(steps > 0);
    assert_eq!(CALLS.with(|c| c.take()), steps);
    // The goal seen from a body, on an environment without one.
    let body: TrainConfig = toml::from_str("[her]\ngoal_frame = \"body\"").unwrap();
    let err = train_vanilla(
        &maze,
        &LearnerConfig::td3(),
        &TrainConfig {
            her: body.her,
            ..train.clone()
        },
        &Seeds::new(0),
        Kernel::detect(),
        |_, _| {},
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("train.her.goal_frame"), "{err}");
    // Stable-Baselines3's frame, the default, is not written: written jobs keep their bytes.
    let written = toml::to_string(&HerConfig::default()).unwrap();
    assert!(!written.contains("goal_frame"), "{written}");
    let bad: Result<TrainConfig, _> = toml::from_str("[her]\nn_sampled_goal = 0");
    let err = pbcs::config::Check::check(&bad.unwrap()).unwrap_err();
    assert!(
        err.to_string().contains("train.her.n_sampled_goal"),
        "{err}"
    );
}

fn small_sac() -> LearnerConfig {
    toml::from_str("algo = \"sac\"\nhidden = [32, 32]\nbatch_size = 64").unwrap()
}

/// A vanilla run's checkpoint (postcard: fields in order, no names) saves the buffer's
/// relabelling settings in the layout `HerConfig` had before `goal_frame`, so that runs saved
/// before it resume.
#[test]
fn a_her_checkpoint_keeps_the_layout_of_runs_saved_before_goal_frame() {
    #[derive(serde::Serialize)]
    struct Before {
        n_sampled_goal: usize,
        goal_selection_strategy: GoalSelection,
    }
    let config = HerConfig {
        n_sampled_goal: 3,
        goal_selection_strategy: GoalSelection::Final,
        goal_frame: pbcs::learner::her::GoalFrame::Body,
    };
    let saved = postcard::to_stdvec(&HerReplay::new(10, 1, 1, 1, config)).unwrap();
    let before = postcard::to_stdvec(&Before {
        n_sampled_goal: 3,
        goal_selection_strategy: GoalSelection::Final,
    })
    .unwrap();
    // Those settings, then the capacity (10, one varint byte): nothing between them.
    assert_eq!(&saved[..before.len()], &before[..]);
    assert_eq!(saved[before.len()], 10);
    let back: HerReplay = postcard::from_bytes(&saved).unwrap();
    assert_eq!(postcard::to_stdvec(&back).unwrap(), saved);
}

/// The goal-conditioned chain's sampler keeps a failure's penalty (`rest`) on a row that does
/// not reach its goal and pays 1 to one that does: one transition from 0 to 1 that fell (reward
/// −1, terminal), sampled as stored (goal 5) or relabelled to the goal it achieved (1).
#[test]
fn sampling_to_reach_keeps_a_failures_penalty_where_the_goal_is_not_reached() {
    let mut her = HerReplay::new(10, 1, 1, 1, HerConfig::default());
    her.push(GoalTransition {
        obs: &[0.0],
        act: &[1.0],
        rew: -1.0,
        next_obs: &[1.0],
        done: true,
        desired: &[5.0],
        achieved_next: &[1.0],
        rest: -1.0,
        chained: None,
    });
    her.end_episode();
    let reached = |a: &[f32], g: &[f32]| (a[0] - g[0]).abs() <= 0.1;
    let mut rng = Seeds::new(0).stream(Stream::Replay);
    let mut batch = Batch::default();
    assert!(her.sample_reaching(64, &mut rng, &reached, &mut batch));
    // Each row: its goal (the next observation's second number), its reward, its end.
    let rows: Vec<(f32, f32, f32)> = (0..64)
        .map(|i| (batch.next_obs[2 * i + 1], batch.rew[i], batch.done[i]))
        .collect();
    let reaching = rows.iter().filter(|&&r| r == (1.0, 1.0, 1.0)).count();
    let penalised = rows.iter().filter(|&&r| r == (5.0, -1.0, 1.0)).count();
    assert_eq!(reaching + penalised, 64, "{rows:?}");
    assert!(reaching > 0 && penalised > 0, "{rows:?}");
}
