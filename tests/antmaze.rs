//! AntMaze (feature `mujoco`): the registry's names, the pure step, the resets. The equality
//! test against gymnasium-robotics' own env is `python/tests/test_antmaze.py`.

use pbcs::env::{Env, Planar};
use pbcs::envs::antmaze::{AntMaze, AntState, NQ, NV};
use pbcs::envs::pointmaze::{MapName, Resets};
use pbcs::envs::{EnvName, EnvSpec};
use pbcs::rng::{Seeds, Stream};
use rand::Rng as _;
use strum::IntoEnumIterator;

/// The eight names build the four maps' tasks: 29 numbers observed (the torso's x, y, then
/// the env's 27), 8 actions in [−1, 1], goals offered; the scene drawn without MuJoCo is the
/// env's. `antmaze_<map>` is the fixed task (from rest at the start cell's centre, success
/// within 0.45 of the goal cell's centre, an ant on its back never archived), which PBCS runs;
/// `antmaze_<map>_goals` has gymnasium-robotics' resets, no fixed success region, and PBCS
/// is refused there, pointed to the fixed name.
#[test]
fn the_registry_builds_the_four_maps_both_ways() {
    let names: Vec<EnvName> = EnvName::all()
        .iter()
        .copied()
        .filter(|e| e.ant_map().is_some())
        .collect();
    assert_eq!(names.len(), 8);
    let maps: Vec<MapName> = MapName::iter().chain(MapName::iter()).collect();
    for (name, map) in names.into_iter().zip(maps) {
        assert_eq!(name.ant_map(), Some(map));
        let spec = EnvSpec::named(name);
        let drawn = spec.scene().unwrap();
        let goals = name.goal_resets();
        assert_eq!(goals, name.name().ends_with("_goals"), "{name:?}");
        let pbcs::envs::Built::AntMaze(env) = spec.build().unwrap() else {
            panic!("{name:?} built another environment");
        };
        assert_eq!(
            (env.obs_dim(), env.action_dim(), env.action_bound(3)),
            (29, 8, 1.0)
        );
        assert_eq!(env.obs_names().len(), 29);
        assert!(env.goals().is_some());
        assert_eq!(env.success_region().is_none(), goals, "{name:?}");
        assert_eq!(env.scene(), drawn, "{name:?}");
        let mut flipped = env.start();
        flipped.qpos[3..7].copy_from_slice(&[0.0, 1.0, 0.0, 0.0]);
        assert_eq!(env.archivable(&flipped), goals, "{name:?}");
        assert!(env.archivable(&env.start()));
        if goals {
            let err = name.check_fixed_task("PBCS").unwrap_err().to_string();
            assert!(err.contains("draws each episode's goal") && err.contains("[train.her]"));
            assert!(err.contains(name.fixed_name()) && !name.fixed_name().ends_with("_goals"));
            assert!(spec.label().ends_with("(goals drawn per episode)"));
        } else {
            name.check_fixed_task("PBCS").unwrap();
            assert_eq!(name.fixed_name(), name.name());
        }
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
    // `phase2.last_goal = "drawn"`: a goal drawn into any state, fixed task or not, is the
    // reset's (the reset draws the goal first, from the same stream), the rest of the state
    // kept.
    let mut a = Seeds::new(4).stream(Stream::Start);
    let mut b = Seeds::new(4).stream(Stream::Start);
    for task in [&env, &fixed] {
        let drawn = task.drawn_goals().unwrap();
        for _ in 0..50 {
            let reset = env.sample_start(&mut a);
            let moved = drawn.with_drawn_goal(&near, &mut b);
            assert_eq!(moved.goal, reset.goal);
            assert_eq!(
                AntState {
                    goal: near.goal,
                    ..moved
                },
                near
            );
            // Keep the streams in step: the reset drew the start too.
            let _ = drawn.with_drawn_goal(&near, &mut b);
        }
    }
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

/// Backplay's starts in B_ε(τ_K) for a body: the torso moved in the plane, within ε of the
/// centre's position and farther than the ant's reach from every wall, everything else the
/// centre's; where no draw is clear, the centre itself. A ball is clear when no wall lies
/// within ε plus the reach.
#[test]
fn ball_starts_move_the_body_clear_of_the_walls() {
    use pbcs::envs::antmaze::model::{cell_xy, clearance, REACH};
    let env = AntMaze::named(MapName::UMaze).unwrap();
    let mut rng = Seeds::new(3).stream(Stream::Start);
    let mut centre = random_state(&env, &mut rng);
    let xy = cell_xy(env.map(), env.cells().0);
    centre.qpos[..2].copy_from_slice(&xy);
    let (balls, clear) = (env.ball_starts().unwrap(), env.clear_balls().unwrap());
    let mut moved = 0;
    for _ in 0..200 {
        let s = balls.sample_ball(&centre, 1.0, &mut rng);
        let d = (s.qpos[0] - xy[0]).hypot(s.qpos[1] - xy[1]);
        assert!(d <= 1.0 && clearance(env.map(), s.xy()) >= REACH, "{s:?}");
        assert_eq!(
            (&s.qpos[2..], s.qvel, s.warmstart, s.goal),
            (
                &centre.qpos[2..],
                centre.qvel,
                centre.warmstart,
                centre.goal
            )
        );
        moved += usize::from(s != centre);
    }
    assert!(moved > 150, "{moved}");
    // The cell's centre is 2 m from its walls.
    assert!(clear.ball_is_clear(&centre, 0.75) && !clear.ball_is_clear(&centre, 0.8));
    // 0.3 m from a wall: every draw within 0.1 m is too close, so the centre comes back.
    let mut near = centre;
    near.qpos[0] = xy[0] - 1.7;
    for _ in 0..20 {
        assert_eq!(balls.sample_ball(&near, 0.1, &mut rng), near);
    }
}

/// The body at rest where a state stands (`rest_starts`): the reset's pose and zero velocity
/// and warm start, at the state's (x, y) and toward its goal; the same state as a reset at
/// that position leaves.
#[test]
fn a_state_at_rest_keeps_the_position_and_the_task_alone() {
    let env = AntMaze::named(MapName::UMaze).unwrap();
    let mut rng = Seeds::new(4).stream(Stream::Start);
    let s = random_state(&env, &mut rng);
    let rest = env.drawn_starts().unwrap().at_rest_like(&s).unwrap();
    assert_eq!(rest, env.at_rest(s.xy(), s.goal));
    assert_eq!((&rest.qpos[..2], rest.goal), (&s.qpos[..2], s.goal));
    assert_eq!((rest.qvel, rest.warmstart), ([0.0; NV], [0.0; NV]));
    assert_eq!(&rest.qpos[2..], &env.start().qpos[2..]);
    assert_ne!(rest.qpos, s.qpos);
}

/// PBCS runs on the fixed task through the registry: phase 1 finds the goal cell (τ ends within
/// 0.45 of its centre, no state of τ upside down), phase 2 runs Backplay from the archive's
/// states until its budget, and the run writes its record.
#[test]
fn pbcs_runs_on_the_fixed_task() {
    let text = std::fs::read_to_string("results/dev/issue49/phase2/ddpg64_e1.toml").unwrap();
    let mut job: pbcs::config::PbcsJob = toml::from_str(&text).unwrap();
    job.env = EnvName::AntmazeUmaze;
    // The budget counts phase 1 too (38 696 env steps here): phase 2 gets the rest.
    job.phase2.max_env_steps = 60_000;
    job.phase2.eval_episodes = 2;
    let dir = tempfile::tempdir().unwrap();
    let kernel = pbcs::nn::kernel::Kernel::detect();
    let valid = pbcs::validate::Check::valid(job).unwrap();
    let (record, _) = pbcs::runs::run_pbcs(
        &valid,
        kernel,
        dir.path(),
        &pbcs::picture::no_pictures,
        |_, _| {},
    )
    .unwrap();
    assert!(!record.solved);
    // Phase 2 ran Backplay from the archive's states until the budget stopped it.
    assert_eq!(
        record.failure,
        Some(pbcs::phase2::Failure::Budget),
        "{record:?}"
    );
    assert!(
        record.train_steps > 0 && record.test_steps > 0,
        "{record:?}"
    );
    let trace = std::fs::read_to_string(dir.path().join("trace.csv")).unwrap();
    assert!(trace.lines().count() > 1, "{trace}");
    let goal = AntMaze::named(MapName::UMaze).unwrap().goal();
    let tau: Vec<Vec<f64>> = csv::Reader::from_path(dir.path().join("trajectory.csv"))
        .unwrap()
        .records()
        .map(|r| {
            r.unwrap()
                .iter()
                .skip(1)
                .take(7)
                .map(|v| v.parse().unwrap())
                .collect()
        })
        .collect();
    let last = tau.last().unwrap();
    assert!(
        (last[0] - goal[0]).hypot(last[1] - goal[1]) <= 0.45,
        "{last:?}"
    );
    for p in &tau {
        assert!(1.0 - 2.0 * (p[4] * p[4] + p[5] * p[5]) >= 0.0, "{p:?}");
    }
}

/// `antmaze` runs the fixed task on a map of one's own, given as `pointmaze`'s (`[pointmaze]`
/// rows, `--map`): the ant in the map's cells of 4 m between its two free cells farthest apart,
/// named and foldered after its rows; without rows it is refused, and a named AntMaze refuses
/// rows.
#[test]
fn antmaze_runs_a_map_of_ones_own() {
    use pbcs::envs::pointmaze::{PointMap, PointMazeConfig};
    let own = PointMazeConfig::from_file("experiments/maps/pointmaze_own.txt".as_ref()).unwrap();
    let spec = EnvSpec {
        name: EnvName::Antmaze,
        pointmaze: own.clone(),
        ..EnvSpec::default()
    };
    spec.check().unwrap();
    assert_eq!(spec.label(), "AntMaze (own map, 10×10)");
    assert!(spec.folder_name().starts_with("antmaze-10x10-"));
    let pbcs::envs::Built::AntMaze(env) = spec.build().unwrap() else {
        panic!("antmaze built another environment");
    };
    let map = PointMap::from_config(&own).unwrap();
    assert_eq!(env.cells(), map.farthest_cells());
    assert_eq!(env.cells(), ((1, 3), (8, 7)));
    assert_eq!(env.resets(), Resets::Fixed);
    let goal = pbcs::envs::antmaze::model::cell_xy(&map, (8, 7));
    assert_eq!(
        env.success_region(),
        Some((goal.map(|g| g as f32).to_vec(), 0.45))
    );
    assert_eq!(env.scene(), spec.scene().unwrap());
    assert!(!EnvName::Antmaze.goal_resets() && EnvName::Antmaze.takes_map());
    let err = EnvSpec::named(EnvName::Antmaze)
        .check()
        .unwrap_err()
        .to_string();
    assert!(err.contains("map of one's own"), "{err}");
    let named = EnvSpec {
        name: EnvName::AntmazeUmaze,
        pointmaze: own,
        ..EnvSpec::default()
    };
    let err = named.check().unwrap_err().to_string();
    assert!(err.contains("\"antmaze\""), "{err}");
}

/// `[train.her] goal_frame = "body"` on AntMaze: training and its evaluations see the goal
/// from the ant (the run differs from one in the world's frame, and is deterministic).
#[test]
fn a_her_run_can_see_the_goal_from_the_ant() {
    use pbcs::learner::LearnerConfig;
    use pbcs::nn::kernel::Kernel;
    use pbcs::vanilla::{train_vanilla, TrainConfig};
    let env = AntMaze::named(MapName::UMaze).unwrap();
    let learner: LearnerConfig =
        toml::from_str("algo = \"td3\"\nhidden = [16, 16]\nbatch_size = 16").unwrap();
    let run = |frame: &str| {
        let train: TrainConfig = toml::from_str(&format!(
            "steps = 600\nmax_episode_steps = 100\nlearning_starts = 200\neval_every = 300\n\
             eval_episodes = 2\n[her]\ngoal_frame = \"{frame}\""
        ))
        .unwrap();
        let out = train_vanilla(
            &env,
            &learner,
            &train,
            &Seeds::new(1),
            Kernel::detect(),
            |_, _| {},
        )
        .unwrap();
        (out.evals, out.learner.policy())
    };
    let (body, again, world) = (run("body"), run("body"), run("world"));
    assert_eq!(body.0, again.0);
    assert!(body.1.same(&*again.1));
    assert!(!body.1.same(&*world.1));
}
