//! TD3/DDPG: TD targets, target smoothing, learning on the 1-D toy, determinism, bad input.

use pbcs::config::Check;
use pbcs::envs::toy::Toy1D;
use pbcs::learner::replay::Batch;
use pbcs::learner::td3::{ActorUpdate, Td3, Td3Config};
use pbcs::learner::{Learner, LearnerConfig};

/// The TD3 learner inside a trained outcome.
fn td3(l: &mut Box<dyn Learner>) -> &mut Td3 {
    l.as_any_mut().downcast_mut::<Td3>().expect("a TD3 learner")
}
use pbcs::rng::Seeds;
use pbcs::vanilla::{train_vanilla, TrainConfig};

fn batch_of_two(done: [f32; 2]) -> Batch {
    Batch {
        len: 2,
        obs: vec![0.3, 0.4, 0.3, 0.4],
        act: vec![0.05, -0.02, 0.05, -0.02],
        rew: vec![1.0, 1.0],
        next_obs: vec![0.35, 0.38, 0.35, 0.38],
        done: done.to_vec(),
    }
}

#[test]
fn terminal_transitions_stop_bootstrapping() {
    for cfg in [Td3Config::ddpg(), Td3Config::td3()] {
        let mut l = Td3::new(
            &cfg,
            2,
            &[0.1, 0.1],
            &Seeds::new(0),
            pbcs::nn::kernel::Kernel::detect(),
        )
        .unwrap();
        let y = l.td_targets(&batch_of_two([1.0, 0.0]));
        assert_eq!(y[0], 1.0, "terminal: y = r exactly");
        assert!(
            (y[1] - 1.0).abs() > 1e-6,
            "non-terminal: y = r + γ·Q'(s', π'(s'))"
        );
    }
}

#[test]
fn time_limit_truncation_is_not_terminal() {
    // Episodes of at most 5 steps on the toy: most end by truncation. Only the transitions
    // that reach x = 0 are stored as terminal, and every ended episode is one or the other.
    let train = TrainConfig {
        steps: 2_000,
        max_episode_steps: 5,
        learning_starts: 2_000,
        eval_every: 2_000,
        ..TrainConfig::default()
    };
    let out = train_vanilla(
        &Toy1D,
        &LearnerConfig::from(Td3Config::ddpg()),
        &train,
        &Seeds::new(1),
        pbcs::nn::kernel::Kernel::detect(),
        |_, _| {},
    )
    .unwrap();
    assert!(out.truncated_episodes > 100, "{}", out.truncated_episodes);
    assert!(out.terminal_transitions > 0);
    let ended = out.episodes - 1; // the last episode is still running
    assert_eq!(out.terminal_transitions + out.truncated_episodes, ended);
}

#[test]
fn target_smoothing_noise_is_clipped() {
    let next_obs: Vec<f32> = (0..200).map(|i| (i % 17) as f32 * 0.1).collect();
    let n = 100;
    let plain = {
        let mut ddpg = Td3::new(
            &Td3Config::ddpg(),
            2,
            &[0.1, 0.3],
            &Seeds::new(2),
            pbcs::nn::kernel::Kernel::detect(),
        )
        .unwrap();
        ddpg.smoothed_target_actions(&next_obs, n).to_vec()
    };
    // Same weights (same seed), TD3 with a huge σ: every sample is clipped to ±c·bound.
    let cfg = Td3Config {
        n_critics: Some(1),
        target_noise: Some(10.0),
        target_noise_clip: Some(0.5),
        ..Td3Config::td3()
    };
    let mut td3 = Td3::new(
        &cfg,
        2,
        &[0.1, 0.3],
        &Seeds::new(2),
        pbcs::nn::kernel::Kernel::detect(),
    )
    .unwrap();
    let noisy = td3.smoothed_target_actions(&next_obs, n).to_vec();
    let mut moved = 0;
    for (i, (x, p)) in noisy.iter().zip(&plain).enumerate() {
        let bound = [0.1f32, 0.3][i % 2];
        assert!(x.abs() <= bound, "outside the action bounds: {x}");
        assert!(
            (x - p).abs() <= 0.5 * bound + 1e-6,
            "noise not clipped: {x} vs {p}"
        );
        moved += usize::from((x - p).abs() > 1e-4);
    }
    assert!(moved > 150, "the noise is there: {moved} of 200 moved");
}

/// DDPG and TD3 learn the 1-D toy. Criterion: greedy success ≥ 90 % over 100 random starts
/// after 3 000 environment steps (500 of them random warm-up), for at least 8 of 10 seeds.
/// Confidence: if each seed independently succeeded with probability 0.95, this test would
/// fail with probability P(Binomial(10, 0.95) ≤ 7) ≈ 1.2 %; the seeds are fixed, so the
/// outcome itself is deterministic. Contrast: untrained policies (evaluated at the end of
/// the warm-up) reach 90 % on at most 2 of the same 10 seeds (measured: 1).
#[test]
fn ddpg_and_td3_learn_the_1d_toy() {
    let schedule = |steps| TrainConfig {
        steps,
        max_episode_steps: 50,
        learning_starts: 500,
        eval_every: steps,
        eval_episodes: 100,
        visit_bin: 0.05,
        ..Default::default()
    };
    for cfg in [Td3Config::ddpg(), Td3Config::td3()] {
        let solved = |steps| {
            (0..10)
                .filter(|&seed| {
                    let out = train_vanilla(
                        &Toy1D,
                        &LearnerConfig::from(cfg.clone()),
                        &schedule(steps),
                        &Seeds::new(seed),
                        pbcs::nn::kernel::Kernel::detect(),
                        |_, _| {},
                    )
                    .unwrap();
                    out.evals.last().unwrap().success >= 0.9
                })
                .count()
        };
        let (before, after) = (solved(500), solved(3_000));
        assert!(
            before <= 2,
            "{:?}: {before} seeds succeed untrained",
            cfg.algo
        );
        assert!(
            after >= 8,
            "{:?}: only {after} of 10 seeds learned",
            cfg.algo
        );
    }
}

#[test]
fn the_argmax_actor_learns_the_1d_toy_too() {
    let cfg = Td3Config {
        actor_update: ActorUpdate::Argmax,
        argmax_samples: 16,
        ..Td3Config::ddpg()
    };
    let train = TrainConfig {
        steps: 3_000,
        max_episode_steps: 50,
        learning_starts: 500,
        eval_every: 3_000,
        eval_episodes: 100,
        visit_bin: 0.05,
        ..Default::default()
    };
    let solved = (0..5)
        .filter(|&seed| {
            let out = train_vanilla(
                &Toy1D,
                &LearnerConfig::from(cfg.clone()),
                &train,
                &Seeds::new(seed),
                pbcs::nn::kernel::Kernel::detect(),
                |_, _| {},
            )
            .unwrap();
            out.evals.last().unwrap().success >= 0.9
        })
        .count();
    assert!(solved >= 4, "argmax actor: {solved} of 5 seeds");
}

#[test]
fn same_seed_same_weights_and_evaluations() {
    let train = TrainConfig {
        steps: 1_500,
        max_episode_steps: 50,
        learning_starts: 300,
        eval_every: 500,
        eval_episodes: 10,
        visit_bin: 0.05,
        ..Default::default()
    };
    let run = || {
        train_vanilla(
            &Toy1D,
            &LearnerConfig::from(Td3Config::td3()),
            &train,
            &Seeds::new(7),
            pbcs::nn::kernel::Kernel::detect(),
            |_, _| {},
        )
        .unwrap()
    };
    let (mut a, mut b) = (run(), run());
    assert_eq!(a.evals, b.evals);
    assert_eq!(a.visited, b.visited);
    assert!(a.learner.policy().same(&*b.learner.policy()));
    assert_eq!(
        td3(&mut a.learner).critics[1].params,
        td3(&mut b.learner).critics[1].params
    );
    let c = train_vanilla(
        &Toy1D,
        &LearnerConfig::from(Td3Config::td3()),
        &train,
        &Seeds::new(8),
        pbcs::nn::kernel::Kernel::detect(),
        |_, _| {},
    )
    .unwrap();
    assert!(!a.learner.policy().same(&*c.learner.policy()));
}

#[test]
fn invalid_hyper_parameters_are_rejected_with_the_field() {
    let cases: Vec<(Td3Config, &str)> = vec![
        (
            Td3Config {
                actor_lr: -1e-3,
                ..Default::default()
            },
            "learner.actor_lr",
        ),
        (
            Td3Config {
                critic_lr: 0.0,
                ..Default::default()
            },
            "learner.critic_lr",
        ),
        (
            Td3Config {
                gamma: 1.0,
                ..Default::default()
            },
            "learner.gamma",
        ),
        (
            Td3Config {
                gamma: -0.1,
                ..Default::default()
            },
            "learner.gamma",
        ),
        (
            Td3Config {
                batch_size: 0,
                ..Default::default()
            },
            "learner.batch_size",
        ),
        (
            Td3Config {
                tau: 0.0,
                ..Default::default()
            },
            "learner.tau",
        ),
        (
            Td3Config {
                hidden: vec![64, 0],
                ..Default::default()
            },
            "learner.hidden",
        ),
        (
            Td3Config {
                n_critics: Some(3),
                ..Default::default()
            },
            "learner.n_critics",
        ),
        (
            Td3Config {
                action_l2: -1.0,
                ..Default::default()
            },
            "learner.action_l2",
        ),
        (
            Td3Config {
                actor_update: ActorUpdate::Argmax,
                argmax_samples: 0,
                ..Default::default()
            },
            "learner.argmax_samples",
        ),
    ];
    for (cfg, field) in cases {
        let msg = cfg.check().unwrap_err().to_string();
        assert!(msg.contains(field), "{field}: {msg}");
        let err = Td3::new(
            &cfg,
            2,
            &[0.1, 0.1],
            &Seeds::new(0),
            pbcs::nn::kernel::Kernel::detect(),
        )
        .unwrap_err();
        assert!(err.to_string().contains(field));
    }
}

/// Sampled rows are whole transitions (s, a, r, s', terminal stay together), and a full ring
/// keeps only the newest `capacity` of them.
#[test]
fn replay_samples_whole_transitions_from_the_newest() {
    use pbcs::learner::replay::{Batch, Replay};
    let mut replay = Replay::new(10, 2, 2);
    for i in 0..25 {
        let f = i as f32;
        replay.push(
            &[f, -f],
            &[0.5 * f, 1.0],
            f,
            &[f + 1.0, -f - 1.0],
            i % 3 == 0,
        );
    }
    assert_eq!(replay.len(), 10);
    let mut rng = pbcs::rng::Seeds::new(0).stream(pbcs::rng::Stream::Replay);
    let mut b = Batch::default();
    replay.sample(200, &mut rng, &mut b);
    assert_eq!(
        (b.len, b.obs.len(), b.act.len(), b.rew.len()),
        (200, 400, 400, 200)
    );
    for k in 0..200 {
        let f = b.rew[k];
        assert!(
            (15.0..25.0).contains(&f),
            "an overwritten transition came back: {f}"
        );
        assert_eq!(&b.obs[2 * k..2 * k + 2], &[f, -f]);
        assert_eq!(&b.act[2 * k..2 * k + 2], &[0.5 * f, 1.0]);
        assert_eq!(&b.next_obs[2 * k..2 * k + 2], &[f + 1.0, -f - 1.0]);
        assert_eq!(
            b.done[k],
            f32::from(u8::from((f as usize).is_multiple_of(3)))
        );
    }
}

/// PBCS's protocol after training (`train.final_eval_episodes`) reads only the Eval stream:
/// the run trains the same bytes as without it, then runs the greedy policy from exactly the
/// start states a chain of the same seed is evaluated from.
#[test]
fn the_final_protocol_evaluation_changes_no_training_byte() {
    use pbcs::env::{evaluation_starts, Env as _};
    use pbcs::envs::maze::{Maze, MazeConfig};
    let maze = Maze::new(&MazeConfig {
        size: 2,
        ..Default::default()
    })
    .unwrap();
    let plain = TrainConfig {
        steps: 2_000,
        learning_starts: 500,
        eval_every: 1_000,
        ..TrainConfig::default()
    };
    let protocol = TrainConfig {
        final_eval_episodes: 20,
        final_eval_max_steps: 30,
        ..plain.clone()
    };
    let run = |train: &TrainConfig| {
        train_vanilla(
            &maze,
            &LearnerConfig::from(Td3Config::ddpg()),
            train,
            &Seeds::new(3),
            pbcs::nn::kernel::Kernel::detect(),
            |_, _| {},
        )
        .unwrap()
    };
    let (mut a, b) = (run(&plain), run(&protocol));
    assert!(a.final_eval.is_empty());
    assert_eq!(a.evals, b.evals);
    assert_eq!(a.visited, b.visited);
    assert!(a.learner.policy().same(&*b.learner.policy()));
    assert_eq!(b.final_eval.len(), 20);
    // The same episodes, replayed by hand from the protocol's starts.
    let starts = evaluation_starts(&maze, 0.1, 20, &Seeds::new(3)).unwrap();
    assert!(starts
        .iter()
        .all(|s| (s - maze.start()).norm() <= 0.1 + 1e-6));
    let again = pbcs::vanilla::greedy_episodes(
        &maze,
        a.learner.as_mut(),
        pbcs::vanilla::GoalInputs::NONE,
        starts,
        30,
    );
    assert_eq!(again, b.final_eval);
    for e in &b.final_eval {
        assert!(e.steps >= 1 && e.steps <= 30);
        // 11 steps is the fewest from B_ε(s_0) on 2×2 for starts at s_0; a success never
        // comes sooner than the straight-line bound from the ball.
        assert!(!e.success || e.steps >= 9, "{e:?}");
    }
}

/// `train.updates = "episode"` (RL-Zoo's schedule for the Pendulum check): no update inside an
/// episode, then as many as the episode had steps; the same total as one per step over the
/// episodes that ended after the warm-up.
#[test]
fn episode_updates_come_at_episode_ends_as_many_as_steps() {
    use pbcs::vanilla::Updates;
    let schedule = |updates| TrainConfig {
        steps: 1_000,
        max_episode_steps: 100,
        learning_starts: 300,
        eval_every: 1_000,
        updates,
        ..TrainConfig::default()
    };
    let run = |updates| {
        train_vanilla(
            &pbcs::envs::pendulum::Pendulum,
            &LearnerConfig::from(Td3Config {
                batch_size: 32,
                ..Td3Config::td3()
            }),
            &schedule(updates),
            &Seeds::new(1),
            pbcs::nn::kernel::Kernel::detect(),
            |_, _| {},
        )
        .unwrap()
    };
    let (step, episode) = (run(Updates::Step), run(Updates::Episode));
    // Pendulum never terminates: 10 episodes of 100 steps; one update per step after step 300.
    assert_eq!(step.learner.updates(), 700);
    // Episodes ending at steps 400, 500, …, 1000 are past the warm-up: 7 × 100 updates.
    assert_eq!(episode.learner.updates(), 700);
    assert!(!step.learner.policy().same(&*episode.learner.policy()));
}

/// `train.stop_at_successes`: a run stops after the first evaluation with that many successful
/// episodes, and is the same run as one without the stop up to there (the stop reads nothing
/// and draws nothing); `steps` says how far it trained. Out-of-range values are refused.
#[test]
fn a_run_stops_at_its_first_solving_evaluation() {
    let schedule = |stop| TrainConfig {
        steps: 3_000,
        max_episode_steps: 50,
        learning_starts: 500,
        eval_every: 250,
        eval_episodes: 20,
        stop_at_successes: stop,
        ..Default::default()
    };
    let run = |stop| {
        train_vanilla(
            &Toy1D,
            &LearnerConfig::from(Td3Config::ddpg()),
            &schedule(stop),
            &Seeds::new(2),
            pbcs::nn::kernel::Kernel::detect(),
            |_, _| {},
        )
        .unwrap()
    };
    let (whole, stopped) = (run(None), run(Some(19)));
    assert_eq!(whole.steps, 3_000);
    let first = whole
        .evals
        .iter()
        .position(|e| e.success >= 0.95)
        .expect("seed 2 learns the toy within 3 000 steps");
    assert!(first + 1 < whole.evals.len(), "solved only at the end");
    assert_eq!(stopped.evals, whole.evals[..=first]);
    assert_eq!(stopped.steps, whole.evals[first].steps);
    for bad in [Some(0), Some(21)] {
        let err = Check::check(&schedule(bad)).unwrap_err().to_string();
        assert!(err.contains("train.stop_at_successes"), "{err}");
    }
}

/// The action penalty (`learner.action_l2`, λ): the actor's loss is Q's plus
/// λ · mean (π(s)_i / b_i)² exactly (the critic's step is the same with or without it, so the
/// two losses differ by the penalty at the π(s) the update saw), it is not written at 0, and
/// many updates with it keep π(s) nearer 0 than without.
#[test]
fn the_action_penalty_adds_its_known_value_and_pulls_actions_in() {
    let bounds = [0.5f32, 2.0];
    let n = 16;
    let obs: Vec<f32> = (0..n * 3)
        .map(|i| ((i * 7919) % 97) as f32 / 97.0 - 0.5)
        .collect();
    let batch = Batch {
        len: n,
        obs: obs.clone(),
        act: (0..n * 2)
            .map(|i| ((i * 31) % 11) as f32 / 11.0 - 0.5)
            .collect(),
        rew: (0..n).map(|i| (i % 3) as f32).collect(),
        next_obs: obs.iter().map(|x| x * 0.9).collect(),
        done: vec![0.0; n],
    };
    let learner = |lambda: f32| {
        let cfg = Td3Config {
            action_l2: lambda,
            ..Td3Config::ddpg()
        };
        Td3::new(
            &cfg,
            3,
            &bounds,
            &Seeds::new(4),
            pbcs::nn::kernel::Kernel::detect(),
        )
        .unwrap()
    };
    let (mut plain, mut penalised) = (learner(0.0), learner(0.5));
    let pi = plain.act(&batch.obs, n).to_vec();
    let penalty: f32 = pi
        .chunks(2)
        .flat_map(|row| row.iter().zip(&bounds).map(|(p, b)| (p / b) * (p / b)))
        .sum::<f32>()
        / (2 * n) as f32;
    let a = plain.update(&batch).actor.unwrap();
    let b = penalised.update(&batch).actor.unwrap();
    assert!(
        (b - a - 0.5 * penalty).abs() <= 1e-5 * (1.0 + a.abs()),
        "{a} {b} {penalty}"
    );
    assert!(penalty > 0.0);
    for _ in 0..300 {
        plain.update(&batch);
        penalised.update(&batch);
    }
    let size = |l: &mut Td3| -> f32 {
        l.act(&batch.obs, n)
            .chunks(2)
            .flat_map(|row| row.iter().zip(&bounds).map(|(p, b)| (p / b).abs()))
            .sum()
    };
    assert!(size(&mut penalised) < size(&mut plain));
    let written = toml::to_string(&Td3Config::td3()).unwrap();
    assert!(!written.contains("action_l2"), "{written}");
}
