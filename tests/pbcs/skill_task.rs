use super::{constant_policy, Head, Mlp, Phase2Config, Seeds, Stream};
use parry2d::math::Point;
use pbcs::config::MazeConfig;
use pbcs::config::PbcsJob;
use pbcs::env::Env;
use pbcs::envs::maze::Maze;
use pbcs::learner::td3::{Td3, Td3Config};
use pbcs::phase2::backplay::Backplayer;
use pbcs::phase2::task::SkillTask;
use pbcs::phase2::{EpisodeLimit, FastTests, Ideas, StartMode};

fn setup() -> (Maze, Vec<Point<f32>>, Vec<Vec<f32>>) {
    let maze = Maze::new(&MazeConfig {
        size: 2,
        ..MazeConfig::default()
    })
    .unwrap();
    let mut s = maze.start();
    let mut states = vec![s];
    for _ in 0..10 {
        s = maze.step(&s, &[0.1, 0.0]).state;
        states.push(s);
    }
    let obs = states.iter().map(|p| vec![p.x, p.y]).collect();
    (maze, states, obs)
}

/// Always moves in direction `dir` at full speed in the learner's [−1, 1] space.
fn unit_policy(dir: [f32; 2]) -> Mlp {
    let m = constant_policy(dir);
    let mut unit = Mlp::new(
        m.sizes(),
        Head::Tanh(vec![1.0, 1.0]),
        &mut Seeds::new(0).stream(Stream::Init),
    );
    unit.params = m.params.clone();
    unit
}

/// The task of reaching τ_5 along `states` with a policy moving along +x.
fn task<'a>(
    maze: &'a Maze,
    config: &'a Phase2Config,
    states: &'a [Point<f32>],
    obs: &'a [Vec<f32>],
    budget: u64,
) -> SkillTask<'a, Maze> {
    task_with(
        maze,
        config,
        states,
        obs,
        unit_policy([1.0, 0.0]),
        5,
        budget,
    )
}

fn task_with<'a>(
    maze: &'a Maze,
    config: &'a Phase2Config,
    states: &'a [Point<f32>],
    obs: &'a [Vec<f32>],
    policy: Mlp,
    t: usize,
    budget: u64,
) -> SkillTask<'a, Maze> {
    let seeds = Seeds::new(3);
    let mut learner = Td3::new(
        &Td3Config::ddpg(),
        2,
        &[1.0, 1.0],
        &seeds,
        pbcs::nn::kernel::Kernel::detect(),
    )
    .unwrap();
    learner.actor = policy;
    let rngs = [0, 1, 2].map(|i| seeds.substream(Stream::Start, i));
    let goal = config.goal(maze, obs, t);
    SkillTask::new(
        maze,
        config.ready(maze).unwrap(),
        states,
        goal,
        t,
        Box::new(learner),
        rngs,
    )
    .with_budget(budget)
}

#[test]
fn fast_tests_give_the_same_verdict_for_fewer_steps() {
    // The policy pushes up into the wall at y = 1 and never reaches τ_10.
    let (maze, states, obs) = setup();
    let run = |fast: bool| {
        let config = Phase2Config {
            ideas: Ideas {
                fast_tests: fast.then_some(FastTests::ALL),
                ..Ideas::NONE
            },
            ..Phase2Config::default()
        };
        let up = unit_policy([0.0, 1.0]);
        let mut task = task_with(&maze, &config, &states, &obs, up, 10, 1_000_000);
        (task.test(0), task.steps.test)
    };
    let (slow, fast) = (run(false), run(true));
    assert_eq!(slow.0, 0.0);
    assert_eq!(fast.0, slow.0, "same verdict");
    assert_eq!(slow.1, 50 * 50, "every episode runs its 50 steps");
    assert!(
        fast.1 < slow.1 / 4,
        "stuck episodes end early: {} steps",
        fast.1
    );
}

/// `phase2.test_lanes`: a fast test run in groups of 5 episodes side by side stops after the
/// group where it first has a success and a failure, instead of when every one of its β
/// episodes has had its chance: the same verdict (here between 0 and 100 %) in fewer steps.
/// On a test that all episodes pass, or none, the groups run every episode as before, with
/// the same steps. Without fast tests the setting is refused, naming both.
#[test]
fn fast_tests_in_groups_give_the_same_verdict_for_fewer_steps() {
    let (maze, states, obs) = setup();
    let run_for = |max_steps: usize, lanes: Option<usize>, dir: [f32; 2], t: usize| {
        let config = Phase2Config {
            max_steps,
            ideas: Ideas {
                fast_tests: Some(FastTests { lanes }),
                ..Ideas::NONE
            },
            ..Phase2Config::default()
        };
        let mut task = task_with(&maze, &config, &states, &obs, unit_policy(dir), t, 1 << 20);
        let test = (task.test(0), task.steps.test);
        // A saved policy's verification runs every episode at once, whatever the lanes.
        let policy: Box<dyn pbcs::policy::Policy> = Box::new(unit_policy(dir));
        let verified = task.verify(0, &policy, 50);
        (test, (verified, task.steps.test - test.1))
    };
    let run = |lanes, dir, t| run_for(Phase2Config::default().max_steps, lanes, dir, t).0;
    // Moving along +y from B_ε(τ_0): only the starts that pass by τ_1 reach its ball; the
    // others end stuck at the wall (failures), or, with 3 steps an episode, run out of steps
    // (failures too, which a group counts once it has run).
    for max_steps in [Phase2Config::default().max_steps, 3] {
        let ((all, all_verified), (grouped, grouped_verified)) = (
            run_for(max_steps, None, [0.0, 1.0], 1),
            run_for(max_steps, Some(5), [0.0, 1.0], 1),
        );
        assert_eq!(
            grouped_verified, all_verified,
            "{max_steps} steps: a verification"
        );
        assert!(all.0 > 0.0 && all.0 < 1.0, "not a mixed test: {all:?}");
        assert!(
            grouped.0 > 0.0 && grouped.0 < 1.0,
            "the verdict changed: {grouped:?}"
        );
        assert!(
            grouped.1 < all.1,
            "{max_steps} steps: {grouped:?} against {all:?}"
        );
    }
    // Every episode passes (along +x to τ_5), or none does (along −x): the same steps.
    for (dir, p) in [([1.0, 0.0], 1.0), ([-1.0, 0.0], 0.0)] {
        let (all, grouped) = (run(None, dir, 5), run(Some(5), dir, 5));
        assert_eq!((all.0, grouped), (p, all), "{dir:?}");
    }
    let refused: Result<PbcsJob, _> =
        toml::from_str("[phase2]\nfast_tests = false\ntest_lanes = 5\n");
    // Groups of no episode cannot be written in the typed form either.
    let zero = Phase2Config {
        ideas: Ideas {
            fast_tests: Some(FastTests { lanes: Some(0) }),
            ..Ideas::NONE
        },
        ..Phase2Config::default()
    };
    let e = pbcs::validate::Check::check(&zero).unwrap_err().to_string();
    assert!(e.contains("phase2.test_lanes"), "{e}");
    let msg = refused.unwrap_err().to_string();
    assert!(
        msg.contains("phase2.test_lanes") && msg.contains("phase2.fast_tests"),
        "{msg}"
    );
}

/// `path_limit` = 1.5 on τ spaced 0.1 apart towards τ_5: an episode from τ_0 may take
/// ⌈1.5 (0.5 + 2ε) / 0.1⌉ = 11 steps, one from τ_4 ⌈1.5 (0.1 + 2ε) / 0.1⌉ = 5 (not 50); a
/// policy that goes to the goal still passes. `test_path_limit` does the same for greedy
/// episodes alone.
#[test]
fn path_limits_shorten_episodes_near_the_goal() {
    let (maze, states, obs) = setup();
    let limited = |limit| Phase2Config {
        ideas: Ideas {
            episode_limit: Some(limit),
            ..Ideas::NONE
        },
        ..Phase2Config::default()
    };
    let config = limited(EpisodeLimit::Every(1.5));
    // Moving along −x, away from τ_5 (slow tests: no episode ends before its limit).
    let away = unit_policy([-1.0, 0.0]);
    let mut t = task_with(&maze, &config, &states, &obs, away, 5, 1_000_000);
    assert_eq!(t.test(0), 0.0);
    assert_eq!(t.steps.test, 50 * 11);
    assert_eq!(t.test(4), 0.0);
    assert_eq!(t.steps.test, 50 * 11 + 50 * 5);
    let mut t = task(&maze, &config, &states, &obs, 1_000_000);
    assert_eq!(t.test(0), 1.0);
    // `test_path_limit` limits greedy episodes the same way. Both at once cannot be written
    // (one `EpisodeLimit`); in a file they are refused naming both.
    let both: Result<PbcsJob, _> =
        toml::from_str("[phase2]\npath_limit = 3.0\ntest_path_limit = 1.5\n");
    let msg = both.unwrap_err().to_string();
    assert!(msg.contains("phase2.test_path_limit") && msg.contains("phase2.path_limit"));
    let config = limited(EpisodeLimit::Greedy(1.5));
    let away = unit_policy([-1.0, 0.0]);
    let mut t = task_with(&maze, &config, &states, &obs, away, 5, 1_000_000);
    assert_eq!(t.test(0), 0.0);
    assert_eq!(t.steps.test, 50 * 11, "test_path_limit 1.5");
    let bad = limited(EpisodeLimit::Greedy(f32::NAN));
    let err = pbcs::validate::Check::check(&bad).unwrap_err().to_string();
    assert!(err.contains("phase2.test_path_limit"), "{err}");
    let bad = limited(EpisodeLimit::Every(0.0));
    let err = pbcs::validate::Check::check(&bad).unwrap_err().to_string();
    assert!(err.contains("phase2.path_limit"), "{err}");
    let bad: Result<PbcsJob, _> = toml::from_str("[phase2]\npath_limit = -1.0\n");
    assert!(bad.unwrap_err().to_string().contains("phase2.path_limit"));
}

#[test]
fn a_policy_that_goes_to_the_goal_passes_and_actions_are_scaled_to_the_bounds() {
    let (maze, states, obs) = setup();
    let config = Phase2Config::default();
    let mut t = task(&maze, &config, &states, &obs, 1_000_000);
    // From B_ε(τ_0) = B_0.1((0.5, 0.5)), +0.1 per step reaches B_ε(τ_5) within 7 steps:
    // at +1 unscaled it would jump over walls; scaled, each step is exactly 0.1.
    assert_eq!(t.test(0), 1.0);
    assert!(t.steps.test <= 50 * 7, "{}", t.steps.test);
    assert!(t.steps.test >= 50 * 3, "{}", t.steps.test);
}

#[test]
fn exact_starts_are_all_tau_k() {
    let (maze, states, obs) = setup();
    let config = Phase2Config {
        start: StartMode::Exact,
        ..Phase2Config::default()
    };
    let mut t = task(&maze, &config, &states, &obs, 1_000_000);
    assert_eq!(t.test(0), 1.0);
    // τ_0 → B_ε(τ_5) at 0.1 per step: the same 4 or 5 steps (d(τ_4, τ_5) is 0.1 give or
    // take f32 rounding) for each of the β = 50 identical episodes.
    assert!([50 * 4, 50 * 5].contains(&t.steps.test), "{}", t.steps.test);
}

#[test]
fn a_spent_budget_stops_every_test_and_round() {
    let (maze, states, obs) = setup();
    let config = Phase2Config::default();
    let mut t = task(&maze, &config, &states, &obs, 100);
    assert!(!t.exhausted());
    t.test(0); // 50 episodes of ≥ 3 steps: over the budget
    let spent = t.steps;
    assert!(t.exhausted());
    assert_eq!((t.test(0), t.train(0)), (0.0, 0.0));
    assert_eq!(t.steps, spent, "no step after the budget");
    let _ = maze.start();
}

/// `phase2.lookahead` (ours): the goal ball B_ε(τ_5) counts as reached only where the skill
/// found after this one carries the entry on to its own target, B_ε(τ_10). A next skill that
/// walks on along +x does, and the test still passes, its steps counted with the test's; one
/// that walks back never does, and the same policy that reaches B_ε(τ_5) in every episode now
/// passes none.
#[test]
fn a_lookahead_counts_a_goal_only_where_the_next_skill_carries_it_on() {
    use pbcs::phase2::lookahead::Lookahead;
    use pbcs::phase2::{goal::BallMetric, Ball, Skill, SkillChain};
    let (maze, states, obs) = setup();
    let config = Phase2Config::default();
    let next = |dir: [f32; 2]| {
        // τ_10 is τ's last state, whose goal would be the maze's own: a ball instead.
        let goal = pbcs::phase2::goal::Goal::ball(obs[10].clone(), config.epsilon);
        Lookahead {
            chain: SkillChain {
                skills: vec![Skill {
                    policy: Box::new(unit_policy(dir)),
                    activation: Ball::around(&maze, &obs[5], config.epsilon, BallMetric::Position),
                    start_index: 5,
                    target_index: 10,
                    inputs: config.inputs(&maze, &goal),
                }],
                ..Default::default()
            },
            target: goal,
            per_skill: config.max_steps,
        }
    };
    let mut alone = task(&maze, &config, &states, &obs, 1_000_000);
    assert_eq!(alone.test(0), 1.0);
    let mut on =
        task(&maze, &config, &states, &obs, 1_000_000).with_lookahead(Some(next([1.0, 0.0])));
    assert_eq!(on.test(0), 1.0);
    // Each of the 50 episodes then walked about 5 more steps (τ_5 to B_ε(τ_10)).
    let more = on.steps.test - alone.steps.test;
    assert!((50 * 3..=50 * 7).contains(&more), "{more}");
    let mut back =
        task(&maze, &config, &states, &obs, 1_000_000).with_lookahead(Some(next([-1.0, 0.0])));
    assert_eq!(back.test(0), 0.0);
    // Its steps count too: from each entry it walks back to the wall at x = 0 (at least 4
    // steps of 0.1 from B_ε(τ_5)), where a stuck greedy chain ends.
    let more = back.steps.test - alone.steps.test;
    assert!((50 * 4..50 * 20).contains(&more), "{more}");
    // No lookahead is no change.
    let mut none = task(&maze, &config, &states, &obs, 1_000_000).with_lookahead(None);
    assert_eq!((none.test(0), none.steps), (1.0, alone.steps));
}
