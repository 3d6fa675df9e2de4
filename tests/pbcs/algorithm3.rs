use super::{constant_policy, Plane};
use pbcs::config::MazeConfig;
use pbcs::env::Env;
use pbcs::envs::maze::Maze;
use pbcs::nn::{Head, Mlp};
use pbcs::phase2::goal::{BallMetric, Goal, GoalKind, Inputs, REACHED_REWARD};
use pbcs::phase2::{Ball, Skill, SkillChain};
use pbcs::rng::{Seeds, Stream};

fn maze2() -> Maze {
    Maze::new(&MazeConfig {
        size: 2,
        ..MazeConfig::default()
    })
    .unwrap()
}

#[test]
fn shaped_reward_is_ten_in_the_ball_else_the_potential_difference() {
    let g = Goal::ball(vec![1.0, 1.0], 0.1);
    // Φ = 1/d: from d = 0.5 to d = 0.25 earns 4 − 2; going back costs as much.
    assert!((g.reward(&[1.5, 1.0], &[1.25, 1.0], false) - 2.0).abs() < 1e-5);
    assert!((g.reward(&[1.25, 1.0], &[1.5, 1.0], false) + 2.0).abs() < 1e-5);
    // Entering the closed ball reaches it and pays 10.
    assert!(g.reached(&[1.0, 1.0999], false, 0.0));
    assert!(!g.reached(&[1.0, 1.1001], false, 0.0));
    assert_eq!(g.reward(&[1.5, 1.0], &[1.1, 1.0], true), REACHED_REWARD);
    // The environment's success reaches any goal; a terminal failure does not.
    assert!(g.reached(&[5.0, 5.0], true, 1.0));
    assert!(!g.reached(&[5.0, 5.0], true, -1.0));
    assert!(g.terminal(false, true) && g.terminal(true, false) && !g.terminal(false, false));
    // Φ is bounded by 1/ε, also at the centre.
    assert_eq!(g.potential(&[1.0, 1.0]), 10.0);
}

#[test]
fn the_last_skill_aims_at_the_environments_target_disc() {
    let maze = maze2();
    // τ_N: the first state found inside the 0.2 target disc, here at its rim.
    let tau_n = [0.5, 1.5 - 0.19];
    let g = Goal::last(&maze, &tau_n, 0.1);
    assert_eq!(g.kind, GoalKind::EnvSuccess);
    assert_eq!((g.center.clone(), g.radius), (vec![0.5, 1.5], 0.2));
    // A point of B_ε(τ_N) outside the disc: not the goal, whatever d(s, τ_N) says.
    let outside = [0.5, 1.5 - 0.28];
    assert!((outside[1] - tau_n[1]).abs() <= 0.1);
    let mut s = maze.start();
    s.x = outside[0];
    s.y = outside[1];
    let step = maze.step(&s, &[0.0, 0.0]);
    assert!(!step.terminal);
    assert!(!g.reached(&outside, step.terminal, step.reward));
    // Stepping into the disc is the environment's success, and the goal's.
    let step = maze.step(&s, &[0.0, 0.1]);
    assert!(step.terminal && step.reward > 0.0);
    assert!(g.reached(&[0.5, 1.32], step.terminal, step.reward));
    // A goal for T < N is B_ε(τ_T).
    let obs = vec![vec![0.5, 0.5], vec![0.6, 0.5], tau_n.to_vec()];
    let mid = Goal::for_target(&maze, &obs, 1, 0.1, BallMetric::Position);
    assert_eq!(mid, Goal::ball(vec![0.6, 0.5], 0.1));
    assert_eq!(
        Goal::for_target(&maze, &obs, 2, 0.1, BallMetric::Position),
        g
    );
}

#[test]
fn hovering_earns_nothing_anywhere() {
    // The defect this goal fixes: 10 per step for staying in B_ε(τ_N) outside the disc.
    let maze = maze2();
    let g = Goal::last(&maze, &[0.5, 1.31], 0.1);
    for i in 0..=40 {
        for j in 0..=40 {
            let p = [0.3 + 0.01 * i as f32, 1.1 + 0.01 * j as f32];
            if !g.reached(&p, false, 0.0) {
                assert_eq!(g.reward(&p, &p, false), 0.0, "{p:?}");
            }
        }
    }
    // An environment without a success region: Φ to τ_N, reached only on its reward.
    let g = Goal::last(&Plane, &[3.0, 0.0], 0.1);
    assert_eq!(g.kind, GoalKind::EnvSuccess);
    assert!(!g.reached(&[3.0, 0.0], false, 0.0));
    assert_eq!(g.reward(&[3.0, 0.05], &[3.0, 0.05], false), 0.0);
}

/// A goal in position and velocity ([`BallMetric::PositionVelocity`], λ = 0.5 s): reached, and
/// Φ measured, with the velocity difference weighed by λ; the networks still see the position
/// relative to the goal's and the velocity as it is.
#[test]
fn a_goal_in_position_and_velocity_weighs_the_velocity_by_lambda() {
    let g = Goal {
        weights: vec![1.0, 1.0, 0.5, 0.5],
        ..Goal::ball(vec![1.0, 1.0, 2.0, 0.0], 0.1)
    };
    // At the centre's position: reached with a velocity within ε/λ = 0.2 of the centre's.
    assert!(g.reached(&[1.0, 1.0, 2.19, 0.0], false, 0.0));
    assert!(!g.reached(&[1.0, 1.0, 2.21, 0.0], false, 0.0));
    assert!(!g.reached(&[1.0, 1.0, 2.0, 0.21], false, 0.0));
    // d² = 0.06² + (0.5 · 0.16)² = 0.1²: on the rim.
    assert!(g.reached(&[1.06, 1.0, 2.16, 0.0], false, 0.0));
    assert!((g.distance(&[1.06, 1.0, 2.16, 0.0]) - 0.1).abs() < 1e-6);
    // Φ = 1/d with that d: from a velocity 1.0 off to 0.5 off earns 1/0.25 − 1/0.5 = 2.
    let r = g.reward(&[1.0, 1.0, 3.0, 0.0], &[1.0, 1.0, 2.5, 0.0], false);
    assert!((r - 2.0).abs() < 1e-5, "{r}");
    // The environment's success reaches it at any velocity.
    assert!(g.reached(&[1.0, 1.0, 9.0, 0.0], true, 1.0));
    // An environment without velocity balls: the metric measures the position only, and its
    // balls are written as balls in position (no weights).
    let maze = maze2();
    let m = BallMetric::PositionVelocity { scale: 0.5 };
    assert_eq!(m.center(&maze, &[0.6, 0.5]), vec![0.6, 0.5]);
    assert!(m.weights(&maze).is_empty());
    assert!(BallMetric::Position.weights(&maze).is_empty());
}

#[test]
fn inputs_are_goal_relative_with_unit_actions() {
    let maze = maze2();
    let g = Goal::ball(vec![1.5, 0.5], 0.1);
    let inputs = Inputs::for_goal(&maze, &g);
    assert_eq!(inputs, Inputs::new(vec![1.5, 0.5], vec![0.1, 0.1]));
    let mut o = [0.0; 2];
    inputs.observation(&[0.5, 0.5], &mut o);
    assert_eq!(o, [-1.0, 0.0]);
    let mut a = [0.0; 2];
    inputs.env_action(&[1.0, -1.0], &mut a);
    assert_eq!(a, [0.1, -0.1]);
}

/// a_0 = tanh(−20·x): steers its first observation towards 0 (in its own frame).
fn homing_policy() -> Mlp {
    let mut rng = Seeds::new(0).stream(Stream::Init);
    let mut m = Mlp::new(&[2, 2, 2], Head::Tanh(vec![1.0, 1.0]), &mut rng);
    m.params.iter_mut().for_each(|p| *p = 0.0);
    // Layer 0 (2 × 2, row-major, then bias): h_0 = relu(−x), h_1 = relu(x).
    m.params[0] = -1.0;
    m.params[1] = 1.0;
    // Layer 1: out_0 = 20·h_0 − 20·h_1.
    let (w, _) = m.offsets(1);
    m.params[w] = 20.0;
    m.params[w + 2] = -20.0;
    m
}

#[test]
fn a_chain_feeds_each_skill_its_own_inputs_also_after_reloading() {
    let skill = Skill {
        policy: Box::new(homing_policy()),
        activation: Ball::new(vec![0.0, 0.0], 0.1),
        start_index: 0,
        target_index: 1,
        inputs: Inputs::new(vec![1.0, 0.0], vec![0.1, 0.1]),
    };
    let chain = SkillChain {
        skills: vec![skill],
        kernel: pbcs::nn::kernel::Kernel::detect(),
    };
    // Seen from its origin (1, 0), the policy homes on x = 1, not on x = 0.
    let r = chain.run(&Plane, [0.0, 0.0], 40);
    let last = r.states.last().unwrap();
    assert!((last[0] - 1.0).abs() <= 0.1, "{last:?}");
    let dir = tempfile::tempdir().unwrap();
    chain.save(dir.path()).unwrap();
    let loaded = SkillChain::load(dir.path(), pbcs::nn::kernel::Kernel::detect()).unwrap();
    assert_eq!(loaded, chain);
    assert_eq!(loaded.run(&Plane, [0.0, 0.0], 40), r);
}

#[test]
fn a_malformed_manifest_is_an_error_naming_the_field() {
    let chain = SkillChain {
        skills: vec![Skill {
            policy: Box::new(constant_policy([1.0, 0.0])),
            activation: Ball::new(vec![0.0, 0.0], 0.1),
            start_index: 0,
            target_index: 1,
            inputs: Inputs::new(vec![0.0, 0.0], vec![1.0, 1.0]),
        }],
        kernel: pbcs::nn::kernel::Kernel::detect(),
    };
    let dir = tempfile::tempdir().unwrap();
    chain.save(dir.path()).unwrap();
    let manifest = dir.path().join("manifest.toml");
    let text = std::fs::read_to_string(&manifest).unwrap();
    for (from, to, field) in [
        ("sizes = [2, 4, 2]", "sizes = [2]", "sizes"),
        (
            "action_bounds = [0.1, 0.1]",
            "action_bounds = [0.1]",
            "action_bounds",
        ),
        ("origin = [0.0, 0.0]", "origin = [0.0]", "origin"),
        (
            "action_scale = [1.0, 1.0]",
            "action_scale = []",
            "action_scale",
        ),
        ("radius = 0.1", "radius = -1.0", "radius"),
    ] {
        assert!(text.contains(from), "{from} not in {text}");
        std::fs::write(&manifest, text.replace(from, to)).unwrap();
        let err = SkillChain::load(dir.path(), pbcs::nn::kernel::Kernel::detect())
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("manifest.toml") && err.contains(&format!("skills[0].{field}")),
            "{err}"
        );
    }
    // An empty chain takes no step instead of panicking.
    let r = SkillChain::default().run(&Plane, [0.0, 0.0], 10);
    assert!(r.skill_used.is_empty() && !r.success);
}
