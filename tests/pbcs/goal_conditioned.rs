//! The goal-conditioned chain (`phase2.chain = "goal_conditioned"`): value chaining's target
//! on hand-made transitions, the sub-goals cut from τ, its settings, and runs on maze 2 (solved,
//! the same bytes twice, a saved chain sharing one policy file that loads back equal).

use pbcs::config::{PbcsJob, Preset};
use pbcs::env::Env;
use pbcs::envs::maze::Maze;
use pbcs::learner::her::{GoalTransition, HerConfig, HerReplay};
use pbcs::learner::replay::Batch;
use pbcs::learner::td3::{Td3, Td3Config};
use pbcs::nn::kernel::Kernel;
use pbcs::phase2::goal_conditioned::{
    goal_minus_position, shape_rewards, GoalConditioned, GoalReward, SubGoals, MIN_SCALE,
};
use pbcs::phase2::{ChainStrategy, SkillChain};
use pbcs::rng::{Seeds, Stream};

/// One transition on a line (observation = position = goal, 1-D) from 0.5 to 1.0, which
/// reaches sub-goal g_1 = 1.0: with value chaining its own row bootstraps through g_2 = 2.0
/// (not done, reward 1); a relabelled copy keeps the ordinary target of its own goal.
#[test]
fn value_chaining_bootstraps_through_the_next_sub_goal() {
    let (g1, g2) = ([1.0f32], [2.0f32]);
    // n_sampled_goal = 1: the first half of a batch is real, the second relabelled.
    let her_config = HerConfig {
        n_sampled_goal: 1,
        ..HerConfig::default()
    };
    let mut her = HerReplay::new(10, 1, 1, 1, her_config);
    her.push(GoalTransition {
        obs: &[0.5],
        act: &[1.0],
        rew: 1.0,
        next_obs: &[1.0],
        done: false,
        desired: &g1,
        achieved_next: &[1.0],
        rest: 0.0,
        chained: Some(&g2),
    });
    her.end_episode();
    let mut batch = Batch::default();
    let reached = |a: &[f32], g: &[f32]| (a[0] - g[0]).abs() <= 0.1;
    let mut rng = Seeds::new(0).stream(Stream::Replay);
    assert!(her.sample_reaching(2, &mut rng, &reached, &mut batch));
    goal_minus_position(&mut batch, 1, 1);
    // The real row: s = (0.5, g_1 − 0.5), s′ = (1.0, g_2 − 1.0), reward 1, not done.
    assert_eq!(batch.obs[..2], [0.5, 0.5]);
    assert_eq!(batch.next_obs[..2], [1.0, 1.0]);
    assert_eq!((batch.rew[0], batch.done[0]), (1.0, 0.0));
    // The relabelled row: its goal is the one achieved (1.0): reached, reward 1, done.
    assert_eq!(batch.next_obs[2..], [1.0, 0.0]);
    assert_eq!((batch.rew[1], batch.done[1]), (1.0, 1.0));

    // The critic's target on them: y = 1 + γ·Q′(s′, π′(s′)) with s′ seeing g_2 for the real
    // row, y = 1 for the relabelled one.
    let config = Td3Config::ddpg();
    let mut td3 = Td3::new(&config, 2, &[1.0], &Seeds::new(0), Kernel::detect()).unwrap();
    let y = td3.td_targets(&batch);
    assert_eq!(y[1], 1.0);
    let alone = |next: [f32; 2], done: f32| Batch {
        obs: vec![0.5, 0.5],
        act: vec![1.0],
        rew: vec![1.0],
        next_obs: next.to_vec(),
        done: vec![done],
        len: 1,
    };
    let mut td3_again = Td3::new(&config, 2, &[1.0], &Seeds::new(0), Kernel::detect()).unwrap();
    let through_g2 = td3_again.td_targets(&alone([1.0, 1.0], 0.0))[0];
    let through_g1 = td3_again.td_targets(&alone([1.0, 0.0], 0.0))[0];
    assert_eq!(y[0], through_g2);
    assert_ne!(y[0], through_g1);
    assert_ne!(y[0], 1.0);
}

/// The paper's shaped reward on a hand-made HER batch (1-D, position = observation = goal):
/// a real step from 3.0 to 2.0 toward g_1 = 0.0 is paid Φ(s′) − Φ(s) = 1/2 − 1/3 and a
/// failure's penalty on top; the value-chained step reaching g_1 is paid 10 (not the jump of
/// Φ toward g_2, which its next observation sees); a relabelled copy that reaches the goal it
/// was given is paid 10 too.
#[test]
fn shaped_rewards_follow_each_rows_own_goal() {
    let (g1, g2) = ([0.0f32], [5.0f32]);
    let her_config = HerConfig {
        n_sampled_goal: 1,
        ..HerConfig::default()
    };
    let mut her = HerReplay::new(10, 1, 1, 1, her_config);
    let step = |obs, next, rew, rest, chained| GoalTransition {
        obs,
        act: &[1.0],
        rew,
        next_obs: next,
        done: false,
        desired: &g1,
        achieved_next: next,
        rest,
        chained,
    };
    her.push(step(&[3.0], &[2.0], -0.5, -0.5, None));
    her.push(step(&[0.2], &[0.05], 1.0, 0.0, Some(&g2)));
    her.end_episode();
    let reached = |a: &[f32], g: &[f32]| (a[0] - g[0]).abs() <= 0.1;
    let mut rng = Seeds::new(3).stream(Stream::Replay);
    let mut batch = Batch::default();
    let (mut far, mut chained, mut relabelled) = (0, 0, 0);
    for _ in 0..20 {
        assert!(her.sample_reaching(8, &mut rng, &reached, &mut batch));
        let sparse = batch.clone();
        shape_rewards(&mut batch, 1, 1, 0.1);
        for k in 0..batch.len {
            let (s, goal, s2) = (
                sparse.obs[2 * k],
                sparse.obs[2 * k + 1],
                sparse.next_obs[2 * k],
            );
            let rew = batch.rew[k];
            if sparse.rew[k] == 1.0 {
                assert_eq!(rew, 10.0, "row {k}");
                if goal == g1[0] && sparse.done[k] == 0.0 {
                    chained += 1;
                    assert_eq!(sparse.next_obs[2 * k + 1], g2[0]);
                } else {
                    relabelled += 1;
                }
            } else {
                let phi = |x: f32| 1.0 / (x - goal).abs().max(0.1);
                assert_eq!(rew, sparse.rew[k] + phi(s2) - phi(s), "row {k}");
                if (s, goal) == (3.0, 0.0) {
                    far += 1;
                    assert_eq!(rew, -0.5 + (1.0 / 2.0 - 1.0 / 3.0));
                }
            }
        }
    }
    assert!(
        far > 0 && chained > 0 && relabelled > 0,
        "{far} {chained} {relabelled}"
    );
}

/// The sub-goals of a maze-10 τ: increasing indices ending at τ's end, each at least `spacing`
/// from the one before (the first from τ_0), the last one cut kept only where it lies at least
/// spacing / 2 from τ's end.
#[test]
fn sub_goals_are_spaced_along_tau_and_end_at_its_end() {
    let job = maze_job(10, 0);
    let maze = Maze::new(&job.maze).unwrap();
    let found = pbcs::phase1::explore(
        &maze,
        &job.explore,
        &mut Seeds::new(0).stream(Stream::Explore),
        |_, _| {},
    )
    .unwrap();
    let tau = &found.trajectory.states;
    for spacing in [0.3, 0.5, 1.0] {
        let cut = SubGoals::cut(&maze, maze.goals().unwrap(), tau, spacing).unwrap();
        assert_eq!(*cut.at.last().unwrap(), tau.len() - 1);
        assert!(cut.at.windows(2).all(|w| w[0] < w[1]));
        let obs = pbcs::env::observations(&maze, tau);
        let mut last = &obs[0];
        for (&k, p) in cut.at.iter().zip(&cut.points) {
            assert_eq!(p, &obs[k]);
            let d = pbcs::phase2::goal::dist(p, last);
            let at_end = k == tau.len() - 1;
            assert!(
                d >= if at_end { spacing / 2.0 } else { spacing },
                "{spacing}: {d}"
            );
            last = &obs[k];
        }
        assert!(
            cut.len() > 5,
            "a maze-10 τ is long: {} sub-goals",
            cut.len()
        );
    }
}

/// The table is read and written back; set without the strategy it is refused, and so are
/// bad values, each by its field; the per-skill default writes no new key.
#[test]
fn goal_conditioned_settings_round_trip_and_refuse_by_field() {
    let text = "chain = \"goal_conditioned\"\n[goal_conditioned]\nspacing = 0.4\ncurriculum = \"backplay\"\n";
    let c: pbcs::phase2::Phase2Config = toml::from_str(text).unwrap();
    let ChainStrategy::GoalConditioned(s) = &c.chain else {
        panic!("{:?}", c.chain)
    };
    assert_eq!(s.spacing, 0.4);
    let again: pbcs::phase2::Phase2Config = toml::from_str(&toml::to_string(&c).unwrap()).unwrap();
    assert_eq!(again, c);
    let plain = toml::to_string(&pbcs::phase2::Phase2Config::default()).unwrap();
    assert!(
        !plain.contains("chain =") && !plain.contains("goal_conditioned"),
        "{plain}"
    );
    for (bad, field) in [
        (
            "[goal_conditioned]\nspacing = 0.4\n",
            "phase2.goal_conditioned",
        ),
        (
            "chain = \"goal_conditioned\"\n[goal_conditioned]\nradius = 0.6\n",
            "radius",
        ),
        (
            "chain = \"goal_conditioned\"\n[goal_conditioned]\nspacing = -1.0\n",
            "spacing",
        ),
        (
            "chain = \"goal_conditioned\"\n[goal_conditioned]\nsteps_per_goal = 0\n",
            "steps_per_goal",
        ),
        (
            "chain = \"goal_conditioned\"\n[goal_conditioned]\nadvance_at = 1.5\n",
            "advance_at",
        ),
        (
            "chain = \"goal_conditioned\"\n[goal_conditioned]\nwindow = 1000000000\n",
            "window",
        ),
        (
            "chain = \"goal_conditioned\"\n[goal_conditioned]\nspeed = 1\n",
            "speed",
        ),
        (
            "chain = \"goal_conditioned\"\n[goal_conditioned]\nupdates_per_step = 0\n",
            "updates_per_step",
        ),
        (
            "chain = \"goal_conditioned\"\n[goal_conditioned]\nupdates_per_step = 1000000\n",
            "updates_per_step",
        ),
        (
            "chain = \"goal_conditioned\"\n[goal_conditioned]\novershoot = false\ncurriculum = \"backplay\"\n",
            "overshoot",
        ),
        (
            "chain = \"goal_conditioned\"\n[goal_conditioned.her]\ngoal_frame = \"body\"\n",
            "her.goal_frame",
        ),
        (
            "chain = \"goal_conditioned\"\n[goal_conditioned]\nfailure_reward = 1.0\n",
            "failure_reward",
        ),
        (
            "chain = \"goal_conditioned\"\n[goal_conditioned]\nreward = \"dense\"\n",
            "dense",
        ),
        ("chain = \"sideways\"\n", "sideways"),
    ] {
        let e = toml::from_str::<pbcs::phase2::Phase2Config>(bad)
            .unwrap_err()
            .to_string();
        assert!(e.contains(field), "{bad}: {e}");
    }
}

/// The ablations' switches at their defaults are not written (files written before them keep
/// their bytes); set, they are, and read back.
#[test]
fn the_ablations_switches_are_written_only_when_set() {
    let text = "chain = \"goal_conditioned\"\n[goal_conditioned]\nspacing = 0.4\n";
    let c: pbcs::phase2::Phase2Config = toml::from_str(text).unwrap();
    let written = toml::to_string(&c).unwrap();
    for key in [
        "overshoot",
        "end_on_failure",
        "failure_reward",
        "reward",
        "normalise",
        "rest_starts",
        "updates_per_step",
    ] {
        assert!(!written.contains(key), "{written}");
    }
    let switched = "chain = \"goal_conditioned\"\n[goal_conditioned]\novershoot = false\n\
                    end_on_failure = false\nupdates_per_step = 2\nreward = \"shaped\"\n";
    let c: pbcs::phase2::Phase2Config = toml::from_str(switched).unwrap();
    let ChainStrategy::GoalConditioned(s) = &c.chain else {
        panic!("{:?}", c.chain)
    };
    assert_eq!(
        (s.overshoot, s.end_on_failure, s.updates_per_step, s.reward),
        (false, false, 2, GoalReward::Shaped)
    );
    let again: pbcs::phase2::Phase2Config = toml::from_str(&toml::to_string(&c).unwrap()).unwrap();
    assert_eq!(again, c);
}

/// The `fast` preset with the goal-conditioned chain on maze `size`, run seed `seed`.
fn maze_job(size: usize, seed: u64) -> PbcsJob {
    maze_job_with(size, seed, GoalConditioned::default())
}

/// [`maze_job`] with the chain's `settings`.
fn maze_job_with(size: usize, seed: u64, settings: GoalConditioned) -> PbcsJob {
    let mut job = Preset::Fast.job().unwrap();
    (job.maze.size, job.seed) = (size, seed);
    job.phase2.chain = ChainStrategy::GoalConditioned(Box::new(settings));
    job
}

/// How many of `n` episodes from `job`'s evaluation starts of run seed `seed` `chain` brings
/// to the goal on `maze`.
fn wins(chain: &SkillChain, maze: &Maze, job: &PbcsJob, seed: u64, n: usize) -> usize {
    let starts =
        pbcs::env::evaluation_starts(maze, job.phase2.epsilon, n, &Seeds::new(seed)).unwrap();
    starts
        .into_iter()
        .filter(|s| chain.run(maze, *s, job.phase2.eval_max_steps).success)
        .count()
}

/// PBCS with the goal-conditioned chain solves maze 2 (seeds 0 and 1), the same bytes twice;
/// its saved chain's skills share one policy file, and the chain loads back equal to the one
/// evaluated, succeeding from B_ε(s_0) as the record says.
#[test]
fn the_goal_conditioned_chain_solves_maze_2_to_the_same_bytes() {
    for seed in [0, 1] {
        let job = pbcs::validate::Check::valid(maze_job(2, seed)).unwrap();
        let run = |dir: &std::path::Path| {
            let (record, _) =
                pbcs::runs::run_pbcs(&job, Kernel::detect(), dir, &|_, _| Ok(()), |_, _| {})
                    .unwrap();
            record
        };
        let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
        let (ra, rb) = (run(a.path()), run(b.path()));
        assert!(ra.solved && ra.success_rate >= 0.95, "seed {seed}: {ra:?}");
        assert_eq!(format!("{ra:?}"), format!("{rb:?}"));
        for file in [
            "record.csv",
            "trace.csv",
            "chain/manifest.toml",
            "chain/skill0.safetensors",
        ] {
            let read = |d: &tempfile::TempDir| std::fs::read(d.path().join(file)).unwrap();
            assert_eq!(read(&a), read(&b), "seed {seed}: {file}");
        }
        let files: Vec<_> = std::fs::read_dir(a.path().join("chain"))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
            .filter(|n| n.ends_with(".safetensors"))
            .collect();
        assert_eq!(files, ["skill0.safetensors"], "one policy for every skill");
        let chain = SkillChain::load(&a.path().join("chain"), Kernel::detect()).unwrap();
        assert_eq!(chain.skills.len(), ra.skills);
        assert!(chain
            .skills
            .iter()
            .all(|s| s.policy.same(chain.skills[0].policy.as_ref())));
        assert!(chain.skills.iter().all(|s| s.inputs.goal.len() == 2));
        let maze = Maze::new(&job.maze).unwrap();
        let wins = wins(&chain, &maze, &job, seed, 20);
        assert!(wins >= 19, "seed {seed}: {wins} of 20");
    }
}

/// With `normalise`, the saved chain's skills see the observation shifted and scaled as
/// training saw it (one μ and σ for all, σ at least `MIN_SCALE`, μ τ's mean, not the origin
/// 0), and the chain loaded back succeeds where the record says the evaluated one did.
#[test]
fn a_normalised_chain_saves_its_view_and_acts_as_evaluated() {
    let normalise = GoalConditioned {
        normalise: true,
        ..GoalConditioned::default()
    };
    let job = pbcs::validate::Check::valid(maze_job_with(2, 0, normalise)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (record, _) = pbcs::runs::run_pbcs(
        &job,
        Kernel::detect(),
        dir.path(),
        &|_, _| Ok(()),
        |_, _| {},
    )
    .unwrap();
    let manifest = std::fs::read_to_string(dir.path().join("chain/manifest.toml")).unwrap();
    assert!(manifest.contains("scale = ["), "{manifest}");
    let chain = SkillChain::load(&dir.path().join("chain"), Kernel::detect()).unwrap();
    let maze = Maze::new(&job.maze).unwrap();
    let first = &chain.skills[0].inputs;
    assert_eq!(first.scale.len(), maze.obs_dim());
    assert!(first.scale.iter().all(|&s| s >= MIN_SCALE), "{first:?}");
    assert!(first.origin.iter().any(|&m| m != 0.0), "{first:?}");
    for skill in &chain.skills {
        assert_eq!(
            (&skill.inputs.origin, &skill.inputs.scale),
            (&first.origin, &first.scale)
        );
    }
    assert!(record.solved, "{record:?}");
    let wins = wins(&chain, &maze, &job, 0, 20);
    assert!(wins >= 19, "{wins} of 20");
}

/// `rest_starts` on an environment without a state at rest (the maze) is refused before any
/// work, naming the setting.
#[test]
fn rest_starts_without_a_state_at_rest_are_refused() {
    let rest = GoalConditioned {
        rest_starts: true,
        ..GoalConditioned::default()
    };
    let job = maze_job_with(2, 0, rest);
    let maze = Maze::new(&job.maze).unwrap();
    let e = job.phase2.ready(&maze).expect_err("refused").to_string();
    assert!(
        e.contains("rest_starts") && e.contains("at_rest_like"),
        "{e}"
    );
}

/// An environment without goals (the plane of these tests) is refused before any work,
/// naming the setting and the hook.
#[test]
fn an_environment_without_goals_is_refused() {
    let job = maze_job(2, 0);
    let e = job
        .phase2
        .ready(&super::Plane)
        .err()
        .expect("refused")
        .to_string();
    assert!(
        e.contains("goal_conditioned") && e.contains("Env::goals"),
        "{e}"
    );
}
