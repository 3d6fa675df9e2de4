//! The goal-conditioned chain's training step on AntMaze UMaze beside what it is made of
//! (feature `mujoco`): prints numbers, asserts nothing. Run with
//! `cargo bench --features mujoco --bench goal_conditioned -- [JOB.toml]` (default: the
//! development job `results/dev/issue79/antmaze/td3_64.toml`).
//!
//! Three costs, one thread, in µs per env step (median of three repeats):
//! - **the strategy's step**: a training round of the job's goal-conditioned phase 2
//!   (`GoalConditionedRun::next_test`) on the job's τ, timed from the end of its first test
//!   to the start of its second (training only: every step acts, stores, overshoots and
//!   updates once), over `test_every` steps;
//! - **the physics alone**: `Env::step` of the same ant, uniformly random actions, 100 steps
//!   from each of τ's states in turn (where training starts; contacts make MuJoCo dearer than
//!   the ant at rest, which is printed beside: from the task's start, restarted every 1 000);
//! - **the update alone**: the job's learner built for the strategy's inputs (observation and
//!   sub-goal) updated on one random batch of the job's size, again and again.
//!
//! Issue 79's target: the step within 15 % of physics + update (the rest is sampling the HER
//! replay, the episode's bookkeeping and acting).

use pbcs::config::PbcsJob;
use pbcs::env::{random_action, Env};
use pbcs::envs::antmaze::{AntMaze, AntState};
use pbcs::envs::pointmaze::{MapName, PointMap, Resets};
use pbcs::learner::replay::Batch;
use pbcs::nn::kernel::Kernel;
use pbcs::phase2::goal_conditioned::GoalConditionedRun;
use pbcs::phase2::{ChainStrategy, EventKind, Phase2Inputs};
use pbcs::rng::{Seeds, Stream};
use pbcs::validate::{Check, Valid};
use rand::Rng;
use std::hint::black_box;
use std::time::Instant;

const PHYSICS_STEPS: usize = 20_000;
const UPDATES: usize = 5_000;

/// Median of three values of `f`.
fn median(mut f: impl FnMut(u64) -> f64) -> f64 {
    let mut v: Vec<f64> = (0..3).map(&mut f).collect();
    v.sort_by(f64::total_cmp);
    v[1]
}

/// The job at `path` (its chain goal-conditioned), UMaze's ant of PBCS's task, and τ.
fn setup(path: &str) -> (Valid<PbcsJob>, AntMaze, Vec<AntState>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let job: PbcsJob = toml::from_str(&text).unwrap_or_else(|e| panic!("{path}: {e}"));
    let job = Check::valid(job).unwrap_or_else(|e| panic!("{path}: {e}"));
    let map = PointMap::named(MapName::UMaze);
    let (start, goal) = map.farthest_cells();
    let env = AntMaze::new(map, start, goal, Resets::Fixed)
        .expect("UMaze's model compiles")
        .refusing_flipped();
    let seeds = Seeds::new(job.seed);
    let mut rng = seeds.stream(Stream::Explore);
    let found = pbcs::phase1::explore(&env, &job.explore, &mut rng, |_, _| {})
        .expect("phase 1 reaches the goal");
    let tau = pbcs::phase2::phase2_trajectory(&env, &found.trajectory, &job.phase2)
        .expect("τ")
        .states;
    (job, env, tau)
}

/// µs per env step of the strategy's training: round 2 (test 1's end to round 2's report).
fn strategy_step(job: &Valid<PbcsJob>, env: &AntMaze, tau: &[AntState], kernel: Kernel) -> f64 {
    let ChainStrategy::GoalConditioned(settings) = &job.phase2.chain else {
        panic!("phase2.chain is not \"goal_conditioned\"");
    };
    let ready = job.phase2.ready(env).expect("the job fits the ant");
    let seeds = Seeds::new(job.seed);
    median(|_| {
        let inputs = Phase2Inputs::new(env, tau, ready, &job.learner, &seeds, kernel);
        let mut run = GoalConditionedRun::start(inputs, settings).expect("the run starts");
        let mut marks = Vec::new();
        let mut report = |_: usize, p: pbcs::phase2::Progress| marks.push((p.kind, Instant::now()));
        for _ in 0..2 {
            let more = run.next_test(&mut report).is_continue();
            assert!(more, "solved in two rounds");
        }
        let (tested, trained) = (marks[1], marks[2]);
        assert_eq!((tested.0, trained.0), (EventKind::Test, EventKind::Train));
        let round = settings.test_every as f64;
        trained.1.duration_since(tested.1).as_secs_f64() * 1e6 / round
    })
}

/// µs per `Env::step`, uniformly random actions: 100 steps from each of τ's states in turn
/// (`from_tau`), or from the task's start, restarted every 1 000 steps.
fn physics(env: &AntMaze, tau: &[AntState], from_tau: bool) -> f64 {
    median(|repeat| {
        let mut rng = Seeds::new(repeat).stream(Stream::Explore);
        let mut action = [0.0f32; 8];
        let mut s = env.start();
        let t = Instant::now();
        for i in 0..PHYSICS_STEPS {
            if i % 100 == 0 {
                s = match from_tau {
                    true => tau[(i / 100) % tau.len()],
                    false if i % 1000 == 0 => env.start(),
                    false => s,
                };
            }
            random_action(env, &mut rng, &mut action);
            s = env.step(&s, &action).state;
        }
        black_box(s);
        t.elapsed().as_secs_f64() * 1e6 / PHYSICS_STEPS as f64
    })
}

/// µs per update of the job's learner built for the strategy's inputs (observation and
/// sub-goal), on one random batch of the job's size.
fn update(job: &Valid<PbcsJob>, env: &AntMaze, kernel: Kernel) -> f64 {
    let goal_dim = env.goals().expect("the ant has goals").goal_dim();
    let (o, d) = (env.obs_dim() + goal_dim, env.action_dim());
    let n = job.learner.batch_size();
    let seeds = Seeds::new(job.seed);
    let mut rng = seeds.stream(Stream::Replay);
    let mut random = |len: usize| (0..len).map(|_| rng.random_range(-1.0..1.0)).collect();
    let batch = Batch {
        len: n,
        obs: random(n * o),
        act: random(n * d),
        rew: random(n),
        next_obs: random(n * o),
        done: vec![0.0; n],
    };
    median(|_| {
        let mut learner = job
            .learner
            .build(o, &vec![1.0; d], &seeds, kernel)
            .expect("the learner builds");
        let t = Instant::now();
        for _ in 0..UPDATES {
            black_box(learner.update(&batch));
        }
        t.elapsed().as_secs_f64() * 1e6 / UPDATES as f64
    })
}

fn main() {
    let path = std::env::args()
        .skip(1)
        .find(|a| a.ends_with(".toml"))
        .unwrap_or_else(|| "results/dev/issue79/antmaze/td3_64.toml".into());
    let (job, env, tau) = setup(&path);
    let kernel = Kernel::detect();
    let step_us = strategy_step(&job, &env, &tau, kernel);
    let (physics_us, from_rest_us) = (physics(&env, &tau, true), physics(&env, &tau, false));
    let update_us = update(&job, &env, kernel);
    let sum = physics_us + update_us;
    println!(
        "{path} ({}, batch {}, kernel {}): strategy step {step_us:.1} µs; physics \
         {physics_us:.1} µs (from τ's states; {from_rest_us:.1} µs from rest) + update \
         {update_us:.1} µs = {sum:.1} µs; step / sum = {:.3} (target ≤ 1.15); {:.0} env steps/s",
        job.learner.algo(),
        job.learner.batch_size(),
        kernel.name(),
        step_us / sum,
        1e6 / step_us
    );
}
