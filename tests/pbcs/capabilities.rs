//! A setting that needs a hook the environment does not offer is refused, naming the setting
//! and the hook (before: ball starts became exact starts, `stop_at_failure` never stopped,
//! `shorten` returned τ unchanged, all silently). [`super::Plane`] offers none of the hooks;
//! [`TwoRooms`] and the maze offer all three.

use super::Plane;
use pbcs::config::{MazeConfig, Preset};
use pbcs::env::{evaluation_starts, Env};
use pbcs::envs::maze::Maze;
use pbcs::envs::rooms::TwoRooms;
use pbcs::error::Error;
use pbcs::learner::LearnerConfig;
use pbcs::nn::kernel::Kernel;
use pbcs::phase1::Trajectory;
use pbcs::phase2::{chain_skills, phase2_trajectory, Phase2Config, Phase2Inputs, StartMode};
use pbcs::rng::Seeds;

/// The error `config` gets on the plane before phase 2 runs ([`Phase2Config::ready`], which
/// `chain_skills` needs).
fn refusal(config: &Phase2Config) -> Error {
    config.ready(&Plane).map(|_| ()).expect_err("refused")
}

fn says(e: &Error, setting: &str, hook: &str) {
    let text = e.to_string();
    assert!(
        matches!(e, Error::Capability { .. }) && text.contains(setting) && text.contains(hook),
        "{text}"
    );
}

#[test]
fn each_setting_that_needs_a_missing_hook_is_refused_naming_both() {
    // The fast preset asks for every hook; each is refused in turn as the one before is
    // turned off.
    let mut c = Preset::Fast.job().unwrap().phase2;
    says(&refusal(&c), "phase2.start = \"ball\"", "Env::ball_starts");
    c.start = StartMode::Exact;
    says(
        &refusal(&c),
        "phase2.chain_verify_episodes",
        "Env::ball_starts",
    );
    c.ideas.chain_check = None;
    says(&refusal(&c), "phase2.stop_at_failure", "Env::clear_balls");
    c.ideas.stop_at_failure = false;
    says(&refusal(&c), "phase2.retargets", "Env::clear_balls");
    c.ideas.dead_walk = None;
    says(&refusal(&c), "phase2.shorten", "Env::connector");
    c.ideas.shorten = false;
    // Issue 47: path limits need a step's reach, and the last skill aiming at the success
    // region needs one (before, the smallest action bound and τ_N stood in for them).
    says(&refusal(&c), "phase2.test_path_limit", "Env::step_reach");
    c.ideas.episode_limit = Some(pbcs::phase2::EpisodeLimit::Every(2.0));
    says(&refusal(&c), "phase2.path_limit", "Env::step_reach");
    c.ideas.episode_limit = None;
    says(
        &refusal(&c),
        "phase2.last_goal = \"success_region\"",
        "Env::success_region",
    );
    c.last_goal = pbcs::phase2::LastGoal::Ball;
    c.require_hooks(&Plane).unwrap();
    // `shorten` itself, called on τ.
    let tau = Trajectory {
        states: vec![[0.0, 0.0], [0.1, 0.0]],
        actions: vec![vec![0.1, 0.0]],
    };
    let mut s = c.clone();
    s.ideas.shorten = true;
    says(
        &phase2_trajectory(&Plane, &tau, &s).unwrap_err(),
        "phase2.shorten",
        "Env::connector",
    );
    assert_eq!(phase2_trajectory(&Plane, &tau, &c).unwrap(), tau);
    // The evaluation protocol's ball.
    says(
        &evaluation_starts(&Plane, 0.1, 3, &Seeds::new(0)).unwrap_err(),
        "evaluation ball",
        "Env::ball_starts",
    );
    let at_start = evaluation_starts(&Plane, 0.0, 3, &Seeds::new(0)).unwrap();
    assert_eq!(at_start, vec![Plane.start(); 3]);
}

#[test]
fn the_rooms_and_the_maze_offer_every_hook_the_presets_use() {
    let maze = Maze::new(&MazeConfig::default()).unwrap();
    for preset in [Preset::Paper, Preset::Fast] {
        let c = preset.job().unwrap().phase2;
        c.require_hooks(&TwoRooms).unwrap();
        c.require_hooks(&maze).unwrap();
    }
}

/// The rooms' hooks agree with their step: a ball start is within the radius and reachable
/// from the centre, a clear ball is one no start of which is across the wall, a connected
/// path is made of steps that move as asked and end at the target state.
#[test]
fn the_rooms_hooks_agree_with_the_step() {
    use pbcs::env::{BallIsClear, Connect, SampleBall};
    use rand::Rng as _;
    let rooms = TwoRooms;
    let mut rng = Seeds::new(7).stream(pbcs::rng::Stream::Eval);
    let mut clear = 0;
    for _ in 0..2000 {
        let c = [rng.random_range(0.0..2.0f32), rng.random_range(0.0..1.0f32)];
        let r = rng.random_range(0.01..0.3f32);
        let p = rooms.sample_ball(&c, r, &mut rng);
        assert!((p[0] - c[0]).hypot(p[1] - c[1]) <= r + 1e-6, "{c:?} {p:?}");
        assert!(!TwoRooms::blocked(&c, &p), "{c:?} → {p:?} crosses the wall");
        if rooms.ball_is_clear(&c, r) {
            clear += 1;
            // Clear: the ball stays in the rooms and off the wall below the door.
            assert!(c[0] - r >= 0.0 && c[0] + r <= 2.0 && c[1] - r >= 0.0 && c[1] + r <= 1.0);
            assert!(c[1] >= 0.8 || (c[0] - 1.0).abs() >= r, "{c:?} {r}");
        }
        let to = [rng.random_range(0.0..2.0f32), rng.random_range(0.0..1.0f32)];
        if let Some(path) = rooms.connect(&c, &to, 0.05) {
            assert!(!TwoRooms::blocked(&c, &to));
            let mut s = c;
            for a in &path {
                let n = rooms.step(&s, a).state;
                assert!((n[0] - s[0] - a[0]).abs() < 1e-5 && (n[1] - s[1] - a[1]).abs() < 1e-5);
                s = n;
            }
            assert!(
                (s[0] - to[0]).abs() < 1e-4 && (s[1] - to[1]).abs() < 1e-4,
                "{s:?} {to:?}"
            );
        }
    }
    assert!(clear > 500, "{clear} clear balls of 2000");
    // Known values: the start's ball is clear, one on the wall is not, the door joins the
    // rooms only through its middle with a clearance of 0.1.
    assert!(rooms.ball_is_clear(&rooms.start(), 0.1));
    assert!(!rooms.ball_is_clear(&[1.05, 0.4], 0.1));
    assert!(rooms.connect(&[0.5, 0.5], &[1.5, 0.5], 0.01).is_none());
    assert!(rooms.connect(&[0.7, 0.9], &[1.3, 0.9], 0.09).is_some());
    assert!(rooms.connect(&[0.7, 0.9], &[1.3, 0.9], 0.11).is_none());
}

/// Archive starts (`phase2.start = "archive"`): refused without the archive or without the
/// environment's ball (its fallback), naming the setting.
#[test]
fn archive_starts_need_the_archive_and_the_ball() {
    let mut c = Preset::Fast.job().unwrap().phase2;
    c.start = StartMode::Archive;
    says(
        &refusal(&c),
        "phase2.start = \"archive\"",
        "Env::ball_starts",
    );
    let maze = Maze::new(&MazeConfig::default()).unwrap();
    let tau: Vec<_> = (0..5).map(|_| maze.start()).collect();
    let e = chain_skills(
        Phase2Inputs::new(
            &maze,
            &tau,
            c.ready(&maze).unwrap(),
            &LearnerConfig::ddpg(),
            &Seeds::new(0),
            Kernel::detect(),
        ),
        |_, _| {},
    )
    .expect_err("refused without the archive");
    assert!(
        matches!(e, Error::Invalid { .. }) && e.to_string().contains("phase2.start"),
        "{e}"
    );
}

/// [`ArchiveStarts`] against a brute-force scan, on the plane (positions on both sides of 0):
/// the states it finds in a ball are exactly the archived states within the radius, every draw
/// is one of them, and a ball with none gives the centre (the plane makes no ball); on the
/// rooms, a ball with none gives the rooms' own ball sample.
#[test]
fn archive_starts_find_exactly_the_archived_states_in_the_ball() {
    use pbcs::env::SampleBall;
    use pbcs::phase1::Archive;
    use pbcs::phase2::ArchiveStarts;
    use rand::Rng as _;
    let mut rng = Seeds::new(3).stream(pbcs::rng::Stream::Eval);
    let mut archive = Archive::new([-0.2f32, 0.2], &[-0.2, 0.2], 2, 0.05);
    for i in 0..400 {
        // Points in x < 0 only, so that balls far into x > 0 find none.
        let p = [
            rng.random_range(-1.0..-0.1f32),
            rng.random_range(-1.0..1.0f32),
        ];
        archive.insert(p, &p, i, &[0.0, 0.0]);
    }
    let starts = ArchiveStarts::new(&Plane, &archive, 0.1);
    let (mut empty, mut full) = (0, 0);
    for _ in 0..500 {
        let c = [
            rng.random_range(-1.2..1.2f32),
            rng.random_range(-1.2..1.2f32),
        ];
        let r = rng.random_range(0.01..0.3f32);
        let mut found = starts.in_ball(&c, r);
        found.sort_unstable();
        let brute: Vec<u32> = (0..archive.len() as u32)
            .filter(|&id| {
                let p = archive.state(id);
                (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) <= r * r
            })
            .collect();
        assert_eq!(found, brute, "ball {c:?} {r}");
        let s = starts.sample_ball(&c, r, &mut rng);
        if brute.is_empty() {
            empty += 1;
            assert_eq!(s, c, "no archived state in the ball: the centre");
        } else {
            full += 1;
            assert!(
                (s[0] - c[0]).hypot(s[1] - c[1]) <= r + 1e-6,
                "{c:?} {r} {s:?}"
            );
            assert!(
                archive.states().contains(&s),
                "{s:?} is not an archived state"
            );
        }
    }
    assert!(
        empty > 50 && full > 50,
        "{empty} empty balls, {full} with states"
    );
    // The rooms make ball states: an empty ball draws the rooms' own sample.
    let rooms_starts = ArchiveStarts::new(&TwoRooms, &archive, 0.1);
    let c = [1.5f32, 0.5];
    let mut again = rng.clone();
    assert_eq!(
        rooms_starts.sample_ball(&c, 0.2, &mut rng),
        TwoRooms.sample_ball(&c, 0.2, &mut again)
    );
}

/// `phase2.start = "archive"` reaches Backplay: every start of a short phase 2 on the rooms is
/// drawn by the starts given, and with `"ball"` none is, the run being the same as
/// `chain_skills`'s (archive starts leave ball runs as they were).
#[test]
fn archive_starts_are_the_ones_backplay_draws() {
    use pbcs::env::SampleBall;
    use pbcs::phase2::Phase2Outcome;
    use std::cell::Cell;
    struct Counting(Cell<usize>);
    impl SampleBall<[f32; 2]> for Counting {
        fn sample_ball(&self, c: &[f32; 2], r: f32, rng: &mut pbcs::rng::Rng) -> [f32; 2] {
            self.0.set(self.0.get() + 1);
            TwoRooms.sample_ball(c, r, rng)
        }
    }
    let tau: Vec<[f32; 2]> = (0..6)
        .map(|i| [TwoRooms.start()[0] + 0.05 * i as f32, TwoRooms.start()[1]])
        .collect();
    let learner = LearnerConfig::ddpg();
    let mut c = Preset::Fast.job().unwrap().phase2;
    c.max_env_steps = 3000;
    let run = |c: &Phase2Config, counting: Option<&Counting>| -> Phase2Outcome {
        let starts = counting.map(|k| k as &dyn SampleBall<[f32; 2]>);
        let seeds = Seeds::new(1);
        chain_skills(
            Phase2Inputs::new(
                &TwoRooms,
                &tau,
                c.ready(&TwoRooms).unwrap(),
                &learner,
                &seeds,
                Kernel::detect(),
            )
            .with_starts(starts),
            |_, _| {},
        )
        .unwrap()
    };
    let counting = Counting(Cell::new(0));
    let ball = run(&c, Some(&counting));
    assert_eq!(counting.0.get(), 0, "ball starts drew from the archive's");
    let plain = chain_skills(
        Phase2Inputs::new(
            &TwoRooms,
            &tau,
            c.ready(&TwoRooms).unwrap(),
            &learner,
            &Seeds::new(1),
            Kernel::detect(),
        ),
        |_, _| {},
    )
    .unwrap();
    let rows = |o: &Phase2Outcome| -> Vec<(usize, usize, u64)> {
        o.trace
            .iter()
            .map(|r| (r.skill, r.k, r.env_steps))
            .collect()
    };
    assert!(!plain.trace.is_empty());
    assert_eq!(rows(&ball), rows(&plain));
    c.start = StartMode::Archive;
    let archived = run(&c, Some(&counting));
    let drawn = counting.0.get();
    assert!(
        drawn > 0 && !archived.trace.is_empty(),
        "{drawn} archive starts drawn"
    );
}

/// Balls in position and velocity (`phase2.velocity_scale` > 0): refused on an environment
/// without [`pbcs::env::VelocityBalls`] (the maze, the rooms), naming the setting and the
/// hook; a λ that is not positive and finite, and archive starts (looked up by position), are
/// refused naming the field, in the typed form and in the file's.
#[test]
fn velocity_balls_need_the_hook_and_ball_starts() {
    use pbcs::phase2::goal::BallMetric;
    let maze = Maze::new(&MazeConfig::default()).unwrap();
    let mut c = Preset::Fast.job().unwrap().phase2;
    c.ball = BallMetric::PositionVelocity { scale: 0.1 };
    for e in [
        c.require_hooks(&maze).unwrap_err(),
        c.require_hooks(&TwoRooms).unwrap_err(),
    ] {
        says(&e, "phase2.velocity_scale", "Env::velocity_balls");
    }
    c.ball = BallMetric::Position;
    c.require_hooks(&maze).unwrap();
    use pbcs::validate::Check;
    for (scale, start) in [
        (-0.1, StartMode::Ball),
        (f32::NAN, StartMode::Ball),
        (f32::INFINITY, StartMode::Ball),
        (0.1, StartMode::Archive),
    ] {
        c.ball = BallMetric::PositionVelocity { scale };
        c.start = start;
        let e = c.check().unwrap_err();
        assert!(
            matches!(e, Error::Invalid { .. }) && e.to_string().contains("phase2.velocity_scale"),
            "{scale} {start:?}: {e}"
        );
    }
    // The file's form: 0 is the position (and is not written), a λ is written and read back.
    let fast = Preset::Fast.job().unwrap().phase2;
    let text = |c: &Phase2Config| toml::to_string(c).unwrap();
    assert!(!text(&fast).contains("velocity_scale"));
    let mut v = fast.clone();
    v.ball = BallMetric::PositionVelocity { scale: 0.25 };
    assert!(text(&v).contains("velocity_scale = 0.25"), "{}", text(&v));
    assert_eq!(toml::from_str::<Phase2Config>(&text(&v)).unwrap(), v);
    for bad in ["-0.25", "nan"] {
        let e = toml::from_str::<Phase2Config>(
            &text(&v).replace("velocity_scale = 0.25", &format!("velocity_scale = {bad}")),
        )
        .unwrap_err();
        assert!(
            e.to_string().contains("phase2.velocity_scale"),
            "{bad}: {e}"
        );
    }
}

/// `phase2.velocity_scale` reaches Backplay: on the rooms seen as x = position, y = velocity
/// (an environment whose [`pbcs::env::VelocityBalls`] counts its draws), a short phase 2 with
/// balls in position and velocity draws its starts there, one with balls in position never.
#[test]
fn velocity_balls_draw_backplays_starts() {
    use pbcs::env::{SampleBall, Step, VelocityBalls};
    use pbcs::phase2::goal::BallMetric;
    use std::cell::Cell;
    struct Moving(Cell<usize>);
    impl Env for Moving {
        type State = [f32; 2];
        fn obs_dim(&self) -> usize {
            2
        }
        fn action_dim(&self) -> usize {
            2
        }
        fn action_bound(&self, i: usize) -> f32 {
            TwoRooms.action_bound(i)
        }
        fn start(&self) -> [f32; 2] {
            TwoRooms.start()
        }
        fn sample_start(&self, rng: &mut pbcs::rng::Rng) -> [f32; 2] {
            TwoRooms.sample_start(rng)
        }
        fn success_region(&self) -> Option<(Vec<f32>, f32)> {
            TwoRooms.success_region()
        }
        fn step_reach(&self) -> Option<f32> {
            TwoRooms.step_reach()
        }
        fn observe(&self, s: &[f32; 2], out: &mut [f32]) {
            TwoRooms.observe(s, out)
        }
        fn step(&self, s: &[f32; 2], a: &[f32]) -> Step<[f32; 2]> {
            TwoRooms.step(s, a)
        }
        fn position_dims(&self) -> usize {
            1
        }
        fn ball_starts(&self) -> Option<&dyn SampleBall<[f32; 2]>> {
            TwoRooms
                .ball_starts()
                .map(|_| &TwoRooms as &dyn SampleBall<[f32; 2]>)
        }
        fn velocity_balls(&self) -> Option<&dyn VelocityBalls<[f32; 2]>> {
            Some(self)
        }
    }
    impl VelocityBalls<[f32; 2]> for Moving {
        fn velocity_dims(&self) -> usize {
            1
        }
        fn sample_velocity_ball(
            &self,
            c: &[f32; 2],
            r: f32,
            _scale: f32,
            rng: &mut pbcs::rng::Rng,
        ) -> [f32; 2] {
            self.0.set(self.0.get() + 1);
            TwoRooms.sample_ball(c, r, rng)
        }
    }
    let tau: Vec<[f32; 2]> = (0..6)
        .map(|i| [TwoRooms.start()[0] + 0.05 * i as f32, TwoRooms.start()[1]])
        .collect();
    let mut c = Preset::Fast.job().unwrap().phase2;
    (c.max_env_steps, c.ideas.stop_at_failure, c.ideas.shorten) = (3000, false, false);
    c.ideas.dead_walk = None;
    let run = |c: &Phase2Config, env: &Moving| {
        chain_skills(
            Phase2Inputs::new(
                env,
                &tau,
                c.ready(env).unwrap(),
                &LearnerConfig::ddpg(),
                &Seeds::new(1),
                Kernel::detect(),
            ),
            |_, _| {},
        )
        .unwrap()
    };
    let env = Moving(Cell::new(0));
    assert!(!run(&c, &env).trace.is_empty());
    assert_eq!(env.0.get(), 0, "balls in position drew velocity starts");
    c.ball = BallMetric::PositionVelocity { scale: 0.5 };
    let out = run(&c, &env);
    assert!(env.0.get() > 0 && !out.trace.is_empty(), "{}", env.0.get());
}
