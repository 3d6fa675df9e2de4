//! What a judge's reset draws (gymnasium-robotics' AntMaze: start and goal each ±1 m around its
//! cell's centre): `phase2.last_goal = "drawn"`, the last skill aiming at the goal each episode
//! draws and seeing its position relative to it, and `phase2.first_starts = "drawn"`, the first
//! skill's starts at K = 0 and the chain's verification and evaluation starts drawn as the
//! reset draws them.

use super::{Head, Mlp, Seeds, Stream};
use pbcs::env::{DrawGoals, DrawStarts, Env, Goals, SampleBall, Step};
use pbcs::learner::LearnerConfig;
use pbcs::nn::kernel::Kernel;
use pbcs::phase2::goal::{Goal, GoalKind, Inputs, REACHED_REWARD};
use pbcs::phase2::{
    chain_skills, Ball, FirstStarts, LastGoal, Phase2Config, Phase2Inputs, Skill, SkillChain,
};
use std::cell::Cell;

/// The task's goal: τ ends within [`REACH`] of it.
const GOAL: [f32; 2] = [1.0, 0.0];
/// Success within this distance of the episode's goal.
const REACH: f32 = 0.2;
/// A drawn goal: [`GOAL`] plus a uniform draw in ±this along x, then y.
const NOISE: f32 = 0.6;
/// A drawn start: the origin plus a uniform draw in ±this along x, then y.
const START_NOISE: f32 = 0.3;

/// An open plane whose state holds the episode's goal: (x, y, goal x, goal y); the
/// observation is the position alone, as AntMaze's is the body alone. Steps of at most 0.1
/// per axis; reward 1 and the end within [`REACH`] of the state's goal. Counts the starts it
/// draws.
#[derive(Default)]
struct GoalPlane {
    starts_drawn: Cell<usize>,
}

impl Env for GoalPlane {
    type State = [f32; 4];
    fn obs_dim(&self) -> usize {
        2
    }
    fn action_dim(&self) -> usize {
        2
    }
    fn action_bound(&self, _i: usize) -> f32 {
        0.1
    }
    fn start(&self) -> [f32; 4] {
        [0.0, 0.0, GOAL[0], GOAL[1]]
    }
    fn sample_start(&self, _rng: &mut pbcs::rng::Rng) -> [f32; 4] {
        self.start()
    }
    fn observe(&self, s: &[f32; 4], out: &mut [f32]) {
        out.copy_from_slice(&s[..2]);
    }
    fn step(&self, s: &[f32; 4], a: &[f32]) -> Step<[f32; 4]> {
        let state = [
            s[0] + a[0].clamp(-0.1, 0.1),
            s[1] + a[1].clamp(-0.1, 0.1),
            s[2],
            s[3],
        ];
        let done = (state[0] - s[2]).hypot(state[1] - s[3]) <= REACH;
        Step {
            state,
            reward: f32::from(u8::from(done)),
            terminal: done,
        }
    }
    fn success_region(&self) -> Option<(Vec<f32>, f32)> {
        Some((GOAL.to_vec(), REACH))
    }
    fn ball_starts(&self) -> Option<&dyn SampleBall<[f32; 4]>> {
        Some(self)
    }
    fn goals(&self) -> Option<&dyn Goals<[f32; 4]>> {
        Some(self)
    }
    fn drawn_goals(&self) -> Option<&dyn DrawGoals<[f32; 4]>> {
        Some(self)
    }
    fn drawn_starts(&self) -> Option<&dyn DrawStarts<[f32; 4]>> {
        Some(self)
    }
}

impl DrawStarts<[f32; 4]> for GoalPlane {
    fn drawn_start(&self, like: &[f32; 4], rng: &mut pbcs::rng::Rng) -> [f32; 4] {
        use rand::Rng as _;
        self.starts_drawn.set(self.starts_drawn.get() + 1);
        let mut p = [0.0f32; 2];
        for p in &mut p {
            *p += rng.random_range(-START_NOISE..START_NOISE);
        }
        [p[0], p[1], like[2], like[3]]
    }
}

impl SampleBall<[f32; 4]> for GoalPlane {
    fn sample_ball(&self, c: &[f32; 4], r: f32, rng: &mut pbcs::rng::Rng) -> [f32; 4] {
        use rand::Rng as _;
        let (d, a) = (
            r * rng.random::<f32>().sqrt(),
            rng.random::<f32>() * std::f32::consts::TAU,
        );
        [c[0] + d * a.cos(), c[1] + d * a.sin(), c[2], c[3]]
    }
}

impl Goals<[f32; 4]> for GoalPlane {
    fn goal_dim(&self) -> usize {
        2
    }
    fn achieved_goal(&self, obs: &[f32], out: &mut [f32]) {
        out.copy_from_slice(&obs[..2]);
    }
    fn desired_goal(&self, s: &[f32; 4], out: &mut [f32]) {
        out.copy_from_slice(&s[2..]);
    }
    fn goal_reward(&self, a: &[f32], d: &[f32]) -> f32 {
        f32::from(u8::from((a[0] - d[0]).hypot(a[1] - d[1]) <= REACH))
    }
}

impl DrawGoals<[f32; 4]> for GoalPlane {
    fn with_drawn_goal(&self, s: &[f32; 4], rng: &mut pbcs::rng::Rng) -> [f32; 4] {
        use rand::Rng as _;
        let mut g = GOAL;
        for g in &mut g {
            *g += rng.random_range(-NOISE..NOISE);
        }
        [s[0], s[1], g[0], g[1]]
    }
}

/// τ: from the start straight to [`GOAL`] in steps of 0.1.
fn tau() -> Vec<[f32; 4]> {
    (0..=10)
        .map(|i| [0.1 * i as f32, 0.0, GOAL[0], GOAL[1]])
        .collect()
}

/// A one-skill chain whose policy heads for the origin of what it sees (tanh(−20 x), scaled
/// to ±0.1): the task's goal, or with `episode_goal` the episode's own.
fn homing_chain(episode_goal: bool) -> SkillChain {
    let mut policy = Mlp::new(
        &[2, 2],
        Head::Tanh(vec![1.0, 1.0]),
        &mut Seeds::new(0).stream(Stream::Init),
    );
    policy.params.iter_mut().for_each(|p| *p = 0.0);
    let (w, _) = policy.offsets(0);
    policy.params[w] = -20.0;
    policy.params[w + 3] = -20.0;
    SkillChain {
        skills: vec![Skill {
            policy: Box::new(policy),
            activation: Ball::new(vec![0.0, 0.0], 0.1),
            start_index: 0,
            target_index: 10,
            inputs: Inputs {
                episode_goal,
                ..Inputs::new(GOAL.to_vec(), vec![0.1, 0.1])
            },
        }],
        kernel: Kernel::detect(),
    }
}

/// Episodes of `chain` from τ_N ([`GOAL`]) toward goals drawn from the `EvalGoal` stream of
/// seed 0: (successes, episodes whose goal lies within reach of the task's).
fn judged(chain: &SkillChain, episodes: usize) -> (usize, usize) {
    let env = GoalPlane::default();
    let mut rng = Seeds::new(0).stream(Stream::EvalGoal);
    let at_goal = [GOAL[0], GOAL[1], GOAL[0], GOAL[1]];
    let (mut successes, mut near) = (0, 0);
    for _ in 0..episodes {
        let start = env.with_drawn_goal(&at_goal, &mut rng);
        near += usize::from((start[2] - GOAL[0]).hypot(start[3] - GOAL[1]) <= REACH);
        successes += usize::from(chain.run(&env, start, 200).success);
    }
    (successes, near)
}

#[test]
fn a_skill_told_the_episodes_goal_reaches_every_drawn_goal_and_one_not_told_only_its_own() {
    let told = homing_chain(true);
    assert!(told.needs_goal());
    let (successes, near) = judged(&told, 200);
    assert_eq!(successes, 200);
    // Not told: it stays at the task's goal and succeeds exactly where the drawn goal lies
    // within reach of it.
    let untold = homing_chain(false);
    assert!(!untold.needs_goal());
    assert_eq!(judged(&untold, 200), (near, near));
    assert!(near > 0 && near < 100, "{near}");
    // The flag is saved, and absent when false (manifests before it load unchanged).
    for chain in [told, untold] {
        let dir = tempfile::tempdir().unwrap();
        chain.save(dir.path()).unwrap();
        let text = std::fs::read_to_string(dir.path().join("manifest.toml")).unwrap();
        assert_eq!(text.contains("episode_goal"), chain.needs_goal(), "{text}");
        assert_eq!(
            SkillChain::load(dir.path(), Kernel::detect()).unwrap(),
            chain
        );
    }
}

#[test]
fn a_drawn_goal_moves_the_potential_and_the_inputs_to_the_episodes_goal() {
    let env = GoalPlane::default();
    let obs: Vec<Vec<f32>> = tau().iter().map(|s| s[..2].to_vec()).collect();
    let c = Phase2Config {
        last_goal: LastGoal::Drawn,
        ..Default::default()
    };
    let last = c.goal(&env, &obs, 10);
    assert_eq!(last.kind, GoalKind::Drawn);
    assert_eq!((last.center.clone(), last.radius), (GOAL.to_vec(), REACH));
    // Every other skill's goal is B_ε(τ_T), as without it.
    assert_eq!(c.goal(&env, &obs, 5).kind, GoalKind::Ball);
    let inputs = c.inputs(&env, &last);
    assert!(inputs.episode_goal);
    // An episode toward (1.3, −0.2): Φ = 1 / d to it, reached only by the env's success.
    let g = [1.3, -0.2];
    let moved: Goal = last.toward(&g);
    let phi = |p: [f32; 2]| 1.0 / (p[0] - g[0]).hypot(p[1] - g[1]).max(REACH);
    let r = moved.reward(&[1.0, 0.0], &[1.1, 0.0], false);
    assert!(
        (r - (phi([1.1, 0.0]) - phi([1.0, 0.0]))).abs() < 1e-5,
        "{r}"
    );
    assert!(!moved.reached(&[1.3, -0.2], false, 0.0));
    assert!(moved.reached(&[1.3, -0.2], true, 1.0));
    assert_eq!(
        moved.reward(&[1.0, 0.0], &[1.3, -0.2], true),
        REACHED_REWARD
    );
    // The networks see the position from the episode's goal.
    let mut view = [0.0; 2];
    inputs.toward(&g).observation(&[1.0, 0.5], &mut view);
    assert_eq!(view, [1.0 - 1.3, 0.5 + 0.2]);
    let mut seen = Vec::new();
    inputs.observation_toward(&[1.0, 0.5], Some(&g), &mut seen);
    assert_eq!(seen, [1.0 - 1.3, 0.5 + 0.2]);
    inputs.observation_toward(&[1.0, 0.5], None, &mut seen);
    assert_eq!(seen, [0.0, 0.5]);
}

#[test]
fn drawn_goals_and_starts_need_their_hooks_and_goal_relative_inputs() {
    let env = GoalPlane::default();
    let mut bare = Phase2Config::default();
    (bare.last_goal, bare.start) = (LastGoal::Drawn, pbcs::phase2::StartMode::Exact);
    let e = bare.require_hooks(&super::Plane).unwrap_err().to_string();
    assert!(
        e.contains("phase2.last_goal = \"drawn\"") && e.contains("Env::drawn_goals"),
        "{e}"
    );
    bare.require_hooks(&env).unwrap();
    let starts = Phase2Config {
        first_starts: FirstStarts::Drawn,
        last_goal: LastGoal::Ball,
        ..bare.clone()
    };
    let e = starts.require_hooks(&super::Plane).unwrap_err().to_string();
    assert!(
        e.contains("phase2.first_starts = \"drawn\"") && e.contains("Env::drawn_starts"),
        "{e}"
    );
    starts.require_hooks(&env).unwrap();
    // Written only when drawn: files before it keep their bytes.
    let flat = |c: &Phase2Config| {
        toml::to_string(&pbcs::phase2::flat::FlatPhase2::from(c.clone())).unwrap()
    };
    assert!(!flat(&bare).contains("first_starts"));
    assert!(flat(&starts).contains("first_starts = \"drawn\""));
    bare.inputs = pbcs::phase2::InputMode::Raw;
    let e = pbcs::validate::Check::valid(bare).unwrap_err().to_string();
    assert!(
        e.contains("phase2.last_goal") && e.contains("goal_relative"),
        "{e}"
    );
}

/// The `fast` preset's phase 2 without the hooks the plane does not offer, within 300 000 env
/// steps.
fn fast() -> Phase2Config {
    let mut c = pbcs::config::Preset::Fast.job().unwrap().phase2;
    c.max_env_steps = 300_000;
    (c.ideas.stop_at_failure, c.ideas.dead_walk, c.ideas.shorten) = (false, None, false);
    c.ideas.episode_limit = None;
    c
}

/// Phase 2 of seed 0 on `tau` with DDPG and settings `c`.
fn phase2(
    env: &GoalPlane,
    tau: &[[f32; 4]],
    c: &Phase2Config,
    kernel: Kernel,
) -> pbcs::phase2::Phase2Outcome {
    let learner = LearnerConfig::ddpg();
    chain_skills(
        Phase2Inputs::new(
            env,
            tau,
            c.ready(env).unwrap(),
            &learner,
            &Seeds::new(0),
            kernel,
        ),
        |_, _| {},
    )
    .unwrap()
}

/// Phase 2 on τ with DDPG: with `last_goal = "drawn"` the chain reaches the goals the env
/// draws; with the success region, only those its path to the task's goal passes (about a
/// fifth of the square by area). On each kernel this CPU runs, since their bytes differ.
#[test]
fn phase2_with_drawn_goals_learns_to_reach_the_goal_each_episode_draws() {
    let env = GoalPlane::default();
    let tau = tau();
    let run = |last_goal: LastGoal, kernel: Kernel| {
        let mut c = fast();
        c.last_goal = last_goal;
        let out = phase2(&env, &tau, &c, kernel);
        assert_eq!(out.failure, None, "{last_goal:?} {kernel:?}");
        let mut rng = Seeds::new(0).stream(Stream::EvalGoal);
        let successes = (0..100)
            .filter(|_| {
                // The same drawn goals for both chains.
                let start = env.with_drawn_goal(&env.start(), &mut rng);
                out.chain.run(&env, start, 200).success
            })
            .count();
        (successes, out.chain)
    };
    let kernels = [Kernel::Avx512, Kernel::Avx2, Kernel::Portable];
    for kernel in kernels.into_iter().filter(|k| k.available()) {
        let (drawn, chain) = run(LastGoal::Drawn, kernel);
        assert!(chain.needs_goal() && chain.skills.last().unwrap().inputs.episode_goal);
        let (region, fixed) = run(LastGoal::SuccessRegion, kernel);
        assert!(!fixed.needs_goal());
        eprintln!("{kernel:?}: drawn {drawn}, success region {region}");
        assert!(
            drawn >= 90 && region <= 50,
            "{kernel:?}: drawn {drawn}, success region {region}"
        );
    }
}

/// `first_starts = "drawn"`: phase 2 draws the first skill's starts at K = 0 (and its chain
/// verification's) as the reset draws them and none elsewhere; the chain, also aiming at drawn
/// goals, goes from drawn starts to drawn goals; `pbcs eval`'s protocol starts it there.
#[test]
fn phase2_with_drawn_starts_covers_the_starts_the_reset_draws() {
    let tau = tau();
    let run = |first_starts: FirstStarts| {
        let env = GoalPlane::default();
        let mut c = fast();
        (c.first_starts, c.last_goal) = (first_starts, LastGoal::Drawn);
        let out = phase2(&env, &tau, &c, Kernel::detect());
        assert_eq!(out.failure, None, "{first_starts:?}");
        (out.chain, env.starts_drawn.get(), c)
    };
    let (_, drawn, _) = run(FirstStarts::Ball);
    assert_eq!(drawn, 0);
    let (chain, drawn, c) = run(FirstStarts::Drawn);
    // Every K = 0 test and training round draws β starts, the chain verification its own.
    let verification = c.ideas.chain_check.unwrap().episodes;
    assert!(drawn >= c.beta + verification, "{drawn}");
    let job = pbcs::config::PbcsJob {
        phase2: c,
        ..Default::default()
    };
    let env = GoalPlane::default();
    let (rows, rollouts) = pbcs::runs::evaluate_chain(&env, &chain, &job, 100, 0).unwrap();
    assert_eq!(env.starts_drawn.get(), 100);
    // Starts over the whole square, not B_ε(s_0) alone; drawn goals too.
    let far = rollouts
        .iter()
        .filter(|r| r[0][0].hypot(r[0][1]) > job.phase2.epsilon)
        .count();
    assert!(far > rollouts.len() / 2, "{far} of {}", rollouts.len());
    assert!(rollouts
        .iter()
        .any(|r| (r[0][2], r[0][3]) != (GOAL[0], GOAL[1])));
    let successes = rows.iter().filter(|r| r.success).count();
    eprintln!("from drawn starts to drawn goals: {successes} of 100");
    assert!(successes >= 90, "{successes}");
}

/// A chain repair learns a section τ_lo … τ_T again: its K = 0 is τ_lo, where
/// `first_starts = "drawn"` draws nothing (`SkillTask::at_offset`); a section from τ_0 draws
/// every start of its K = 0 tests.
#[test]
fn drawn_starts_are_the_chains_start_only() {
    use pbcs::phase2::backplay::Backplayer;
    use pbcs::phase2::task::SkillTask;
    let tau = tau();
    let mut c = fast();
    c.first_starts = FirstStarts::Drawn;
    let obs: Vec<Vec<f32>> = tau.iter().map(|s| s[..2].to_vec()).collect();
    for lo in [0, 3] {
        let env = GoalPlane::default();
        let seeds = Seeds::new(0);
        let learner = LearnerConfig::ddpg()
            .build(2, &c.learner_bounds(&env), &seeds, Kernel::detect())
            .unwrap();
        let rngs = [0, 1, 2].map(|i| seeds.substream(Stream::Start, i));
        let goal = c.goal(&env, &obs, 6);
        let mut task = SkillTask::new(
            &env,
            c.ready(&env).unwrap(),
            &tau[lo..=6],
            goal,
            6 - lo,
            learner,
            rngs,
        )
        .with_budget(1_000_000)
        .at_offset(lo);
        task.test(0);
        let drawn = env.starts_drawn.get();
        match lo {
            0 => assert_eq!(drawn, c.beta),
            _ => assert_eq!(drawn, 0),
        }
        task.test(1);
        assert_eq!(env.starts_drawn.get(), drawn, "K = 1 is a ball");
    }
}
