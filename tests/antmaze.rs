//! AntMaze (feature `mujoco`): the registry's names, the pure step, the resets. The equality
//! test against gymnasium-robotics' own env is `python/tests/test_antmaze.py`.

use pbcs::env::{Env, Planar};
use pbcs::envs::antmaze::{AntMaze, AntState, NQ, NV};
use pbcs::envs::pointmaze::{MapName, Resets};
use pbcs::envs::{EnvName, EnvSpec};
use pbcs::rng::{Seeds, Stream};
use rand::Rng as _;
use strum::IntoEnumIterator;

/// The four names build the four maps' tasks with gymnasium-robotics' resets: 29 numbers
/// observed (the torso's x, y, then the env's 27), 8 actions in [−1, 1], goals offered, no
/// fixed success region; the scene drawn without MuJoCo is the env's; PBCS is refused.
#[test]
fn the_registry_builds_the_four_maps() {
    let names: Vec<EnvName> = EnvName::all()
        .iter()
        .copied()
        .filter(|e| e.ant_map().is_some())
        .collect();
    assert_eq!(names.len(), 4);
    for (name, map) in names.into_iter().zip(MapName::iter()) {
        assert_eq!(name.ant_map(), Some(map));
        assert!(name.goal_resets());
        let spec = EnvSpec::named(name);
        let drawn = spec.scene().unwrap();
        pbcs::with_env!(spec.build().unwrap(), |env| {
            assert_eq!(
                (env.obs_dim(), env.action_dim(), env.action_bound(3)),
                (29, 8, 1.0)
            );
            assert_eq!(env.obs_names().len(), 29);
            assert!(env.goals().is_some() && env.success_region().is_none());
            assert_eq!(env.scene(), drawn, "{name:?}");
        });
        let err = name.check_fixed_task("PBCS").unwrap_err().to_string();
        assert!(err.contains("draws each episode's goal") && err.contains("[train.her]"));
        assert!(spec.label().starts_with("AntMaze "));
    }
}

/// A random whole state over a free cell: any orientation, joints and velocities random.
fn random_state(env: &AntMaze, rng: &mut pbcs::rng::Rng) -> AntState {
    let mut s = env.sample_start(rng);
    s.qpos[2] = rng.random_range(0.3..1.2);
    let q: [f64; 4] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
    let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    for (k, v) in q.iter().enumerate() {
        s.qpos[3 + k] = v / n;
    }
    for v in &mut s.qpos[7..] {
        *v = rng.random_range(-1.0..1.0);
    }
    for v in &mut s.qvel {
        *v = rng.random_range(-3.0..3.0);
    }
    s
}

/// The step is a function of the state and the action alone: the same step taken again,
/// after steps from other states in between, gives the same bits; and it moves the ant.
#[test]
fn the_step_is_pure() {
    let env = AntMaze::named(MapName::Medium).unwrap();
    let mut rng = Seeds::new(5).stream(Stream::Start);
    let states: Vec<AntState> = (0..20).map(|_| random_state(&env, &mut rng)).collect();
    let actions: Vec<Vec<f32>> = (0..20)
        .map(|_| (0..8).map(|_| rng.random_range(-1.0..1.0)).collect())
        .collect();
    let first: Vec<AntState> = states
        .iter()
        .zip(&actions)
        .map(|(s, a)| env.step(s, a).state)
        .collect();
    for (k, (s, a)) in states.iter().zip(&actions).enumerate().rev() {
        let again = env.step(s, a).state;
        assert_eq!(again, first[k]);
        assert_ne!(again.qpos, s.qpos);
        assert_eq!(again.goal, s.goal);
    }
    let mut obs = vec![0.0; 29];
    env.observe(&first[0], &mut obs);
    let whole: Vec<f32> = first[0]
        .qpos
        .iter()
        .chain(&first[0].qvel)
        .map(|&v| v as f32)
        .collect();
    assert_eq!(obs, whole);
    assert_eq!((NQ, NV), (15, 14));
}

/// Resets: the ant at rest, level, at `ant.xml`'s height, its joints at 0, start and goal
/// within ±1 m of their cells' centres and spread over the whole square; the fixed task starts
/// at the centre. Reward and termination only within 0.45 of the episode's goal.
#[test]
fn resets_draw_the_squares_and_success_is_the_goals() {
    let env = AntMaze::named(MapName::UMaze).unwrap();
    assert_eq!(env.resets(), Resets::Gym);
    let (start, goal) = env.cells();
    let centre = |c| pbcs::envs::antmaze::model::cell_xy(env.map(), c);
    let mut rng = Seeds::new(0).stream(Stream::Start);
    let (mut lo, mut hi) = ([f64::MAX; 4], [f64::MIN; 4]);
    for _ in 0..2000 {
        let s = env.sample_start(&mut rng);
        assert_eq!(s.qpos[2..7], [0.75, 1.0, 0.0, 0.0, 0.0]);
        assert!(s.qpos[7..]
            .iter()
            .chain(&s.qvel)
            .chain(&s.warmstart)
            .all(|&v| v == 0.0));
        let off = [
            s.qpos[0] - centre(start)[0],
            s.qpos[1] - centre(start)[1],
            s.goal[0] - centre(goal)[0],
            s.goal[1] - centre(goal)[1],
        ];
        for k in 0..4 {
            assert!(off[k].abs() <= 1.0, "{off:?}");
            lo[k] = lo[k].min(off[k]);
            hi[k] = hi[k].max(off[k]);
        }
    }
    assert!(lo.iter().all(|&l| l < -0.99) && hi.iter().all(|&h| h > 0.99));
    let fixed = AntMaze::new(env.map().clone(), start, goal, Resets::Fixed).unwrap();
    assert_eq!(fixed.sample_start(&mut rng), fixed.start());
    assert_eq!(fixed.start().xy(), centre(start));
    assert_eq!(
        fixed.success_region().unwrap().0,
        centre(goal).map(|v| v as f32).to_vec()
    );
    // Success within 0.45 of the goal: the state's own goal, not the task's.
    let mut s = env.at_rest(centre(goal), [centre(goal)[0] + 0.44, centre(goal)[1]]);
    assert!(env.success(&s));
    s.goal[0] += 0.02;
    assert!(!env.success(&s));
    let near = env.at_rest(centre(goal), centre(goal));
    let step = env.step(&near, &[0.0; 8]);
    assert!(step.terminal && step.reward == 1.0);
    assert!(env.point(&near) == env.scene().target.0);
}

/// Walls hold: thrown at 6 m/s at the wall below the start cell, the torso stays in the maze.
#[test]
fn the_walls_hold_the_ant() {
    let env = AntMaze::named(MapName::UMaze).unwrap();
    let mut s = env.start();
    s.qvel[1] = -6.0;
    let floor = pbcs::envs::antmaze::model::cell_xy(env.map(), env.cells().0)[1] - 2.0;
    let mut lowest = f64::MAX;
    for _ in 0..100 {
        s = env.step(&s, &[0.0; 8]).state;
        lowest = lowest.min(s.qpos[1]);
    }
    assert!(lowest > floor, "{lowest} past the wall at {floor}");
    assert!(lowest < floor + 1.0, "it never reached the wall: {lowest}");
}
