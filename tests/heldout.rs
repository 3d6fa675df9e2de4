//! The held-out grid (`experiments/heldout.toml`) was registered before it ran, for the
//! `fast` preset as it was then: its recorded SHA-256 must still be the preset file's.

use pbcs::experiment::Experiment;
use std::path::Path;

/// A registered grid's `[registered]` table and its preset file's SHA-256 now.
fn registration(exp: &Experiment) -> (pbcs::experiment::Registration, String) {
    let reg = exp
        .registered
        .clone()
        .unwrap_or_else(|| panic!("{} has a [registered] table", exp.name));
    let hash = reg.preset_sha256().unwrap();
    (reg, hash)
}

#[test]
fn the_held_out_grid_runs_the_preset_it_was_registered_for() {
    let exp = Experiment::load(Path::new("experiments/heldout.toml"), None).unwrap();
    let (reg, hash) = registration(&exp);
    assert_eq!(
        hash, reg.sha256,
        "experiments/{} changed since the held-out grid was registered on {}: its rows no longer \
         test the preset as it is. Register a new grid on new layouts (and say so in the report); \
         do not update this hash.",
        reg.preset, reg.date
    );
    // The grid is the one registered: every method runs that preset on a layout of its own.
    for c in &exp.cells {
        let pbcs::experiment::Job::Pbcs(j) = &c.job else {
            panic!("{}: not a PBCS cell", c.id)
        };
        assert!([2611, 2612].contains(&j.maze.seed), "{}", c.id);
    }
    assert_eq!(exp.sites, [8, 16, 24, 32].map(pbcs::experiment::Site::Maze));
    let runs: usize = exp.cells.iter().map(|c| exp.seeds_of(c).len()).sum();
    assert_eq!(runs, 2 * (10 + 10 + 5 + 3));
}

/// Known values: one maze, two methods, one chain below 100 %.
#[test]
fn the_methods_by_maze_table_reads_by_size_and_names_imperfect_chains() {
    let stats = pbcs::tables::read_table(&pbcs::tables::table_path(
        Path::new("results"),
        "heldout".parse().unwrap(),
    ))
    .unwrap();
    let eight: Vec<_> = stats
        .into_iter()
        .filter(|c| c.site.size() == Some(8))
        .collect();
    let run = |cell: &str, label: &str, seed: u64, rate: f32| pbcs::criteria::ChainSuccess {
        experiment: "heldout".parse().unwrap(),
        cell: cell.parse().unwrap(),
        method: cell[..1].parse().unwrap(),
        label: label.into(),
        site: pbcs::experiment::Site::Maze(8),
        seed,
        complete: true,
        success_rate: rate,
        solved: rate >= 0.95,
        env_steps: 1,
        paper_steps: None,
    };
    let md = pbcs::tables::methods_by_maze_markdown(
        &eight,
        &[
            run("a-maze8", "layout 2611", 0, 1.0),
            run("a-maze8", "layout 2611", 1, 0.97),
            run("b-maze8", "layout 2612", 0, 1.0),
        ],
    );
    let lines: Vec<&str> = md.lines().collect();
    assert_eq!(
        lines[0],
        "| size | layout 2611: solved, Wilson 95 %, median steps, chains at 100 % | layout 2612: \
         solved, Wilson 95 %, median steps, chains at 100 % |"
    );
    assert_eq!(lines[1], "| --- | --- | --- |");
    assert_eq!(
        lines[2],
        "| 8 | 10/10, [0.72, 1.00], 296k, 1/2 | 10/10, [0.72, 1.00], 522k, 1/1 |"
    );
    assert_eq!(
        lines[4],
        "Chains below 100 % of their evaluation episodes: layout 2611 size 8 seed 1 (97 %)."
    );
}

/// The held-out PointMaze grid (`experiments/pointmaze_heldout.toml`) was registered before it
/// ran: it runs exactly the PointMaze grid's jobs, map by map, on seeds no PointMaze run had
/// used, for the `fast` preset as it was then.
#[test]
fn the_held_out_pointmaze_grid_runs_the_grids_jobs_on_unused_seeds() {
    let held = Experiment::load(Path::new("experiments/pointmaze_heldout.toml"), None).unwrap();
    let grid = Experiment::load(Path::new("experiments/pointmaze.toml"), None).unwrap();
    let (reg, hash) = registration(&held);
    assert_eq!(
        hash, reg.sha256,
        "experiments/{} changed since the held-out PointMaze grid was registered on {}: \
         register a new one on unused seeds (and say so); do not update this hash.",
        reg.preset, reg.date
    );
    assert_eq!(held.sites, grid.sites);
    assert_eq!(held.cells.len(), grid.cells.len());
    for (h, g) in held.cells.iter().zip(&grid.cells) {
        assert_eq!((&h.id, &h.site), (&g.id, &g.site));
        assert_eq!(h.job, g.job, "{}: not the grid's job", h.id);
        let (hs, gs) = (held.seeds_of(h), grid.seeds_of(g));
        assert_eq!(hs, (10..20).collect::<Vec<u64>>(), "{}", h.id);
        assert!(
            hs.iter().all(|s| !gs.contains(s)),
            "{}: a seed of the grid",
            h.id
        );
    }
}

/// The PointMaze grid on a map of one's own (`experiments/pointmaze_own.toml`) was registered
/// before it ran, choosing nothing on that map: its PBCS cell runs the PointMaze grid's job and
/// its DDPG cell the vanilla grid's (Large's episode length, the map's time limit), each with
/// only the environment changed to the map of `experiments/maps/pointmaze_own.txt`.
#[test]
fn the_own_map_grid_runs_the_named_maps_jobs_on_its_map() {
    use pbcs::config::Located;
    use pbcs::envs::{pointmaze::PointMazeConfig, EnvName, EnvSpec};
    use pbcs::experiment::Job;
    let load = |f: &str| Experiment::load(&Path::new("experiments").join(f), None).unwrap();
    let (own, grid, vanilla) = (
        load("pointmaze_own.toml"),
        load("pointmaze.toml"),
        load("pointmaze_vanilla.toml"),
    );
    let (reg, hash) = registration(&own);
    assert_eq!(
        hash, reg.sha256,
        "experiments/{} changed since the own-map PointMaze grid was registered on {}: \
         register a new one (and say so); do not update this hash.",
        reg.preset, reg.date
    );
    let map = PointMazeConfig::from_file(Path::new("experiments/maps/pointmaze_own.txt")).unwrap();
    assert!(map.map.len() >= 10 && map.map[0].len() >= 10);
    let on_map = EnvSpec {
        pointmaze: map,
        ..EnvSpec::named(EnvName::Pointmaze)
    };
    let find = |exp: &Experiment, id: &str| exp.cell(id).unwrap().clone();
    for (mine, theirs) in [
        (
            find(&own, "pbcs_pm-pointmaze"),
            find(&grid, "pbcs_pm-pointmaze_large"),
        ),
        (
            find(&own, "ddpg-pointmaze"),
            find(&vanilla, "ddpg-pointmaze_large"),
        ),
    ] {
        let mut job = theirs.job.clone();
        match &mut job {
            Job::Pbcs(j) => j.set_env_spec(on_map.clone()),
            Job::Vanilla(j) => j.set_env_spec(on_map.clone()),
        }
        assert_eq!(
            mine.job, job,
            "{}: not {}'s job on the map",
            mine.id, theirs.id
        );
        assert_eq!(own.seeds_of(&mine), (0..10).collect::<Vec<u64>>());
    }
    assert_eq!(own.cells.len(), 2);
}

/// The registered comparison of balls in position and in position and velocity
/// (`experiments/pointmaze_velocity.toml`) runs, map by map, the PointMaze grid's job and that
/// job with only `phase2.velocity_scale` set, on seeds no other PointMaze grid used, for the
/// `fast` preset as it was when it was registered.
#[test]
fn the_velocity_comparison_runs_the_grids_jobs_and_one_change_on_unused_seeds() {
    use pbcs::phase2::goal::BallMetric;
    let load = |f: &str| Experiment::load(&Path::new("experiments").join(f), None).unwrap();
    let (cmp, grid, held) = (
        load("pointmaze_velocity.toml"),
        load("pointmaze.toml"),
        load("pointmaze_heldout.toml"),
    );
    let (reg, hash) = registration(&cmp);
    assert_eq!(
        hash, reg.sha256,
        "experiments/{} changed since the velocity comparison was registered on {}: register a \
         new one on unused seeds (and say so); do not update this hash.",
        reg.preset, reg.date
    );
    assert_eq!(cmp.sites, grid.sites);
    let pbcs_job = |j: &pbcs::experiment::Job| match j {
        pbcs::experiment::Job::Pbcs(j) => j.clone(),
        _ => panic!("not a PBCS cell"),
    };
    let used: Vec<u64> = [&grid, &held]
        .iter()
        .flat_map(|e| e.cells.iter().flat_map(|c| e.seeds_of(c)))
        .collect();
    for g in &grid.cells {
        let velocity_id = g.id.to_string().replace("pbcs_pm-", "pbcs_pm_velocity-");
        let cell = |id: &str| cmp.cell(id).unwrap();
        let (same, velocity) = (cell(&g.id.to_string()), cell(&velocity_id));
        assert_eq!(same.job, g.job, "{}: not the grid's job", g.id);
        let mut expected = pbcs_job(&g.job);
        expected.phase2.ball = BallMetric::PositionVelocity { scale: 0.1 };
        assert_eq!(pbcs_job(&velocity.job), expected, "{velocity_id}");
        for c in [same, velocity] {
            let seeds = cmp.seeds_of(c);
            assert_eq!(seeds, (20..30).collect::<Vec<u64>>(), "{}", c.id);
            assert!(seeds.iter().all(|s| !used.contains(s)), "{}", c.id);
        }
    }
    assert_eq!(cmp.cells.len(), 2 * grid.cells.len());
}

/// `[registered] paired` names two different methods of its file: otherwise loading the file
/// is an error naming the field.
#[test]
fn a_paired_comparison_names_two_methods_of_its_file() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        "experiments/pbcs_fast.toml",
        dir.path().join("pbcs_fast.toml"),
    )
    .unwrap();
    let text = std::fs::read_to_string("experiments/pointmaze_velocity.toml").unwrap();
    let good = "paired = [\"pbcs_pm\", \"pbcs_pm_velocity\"]";
    assert!(text.contains(good));
    for (bad, why) in [
        ("paired = [\"pbcs_pm\", \"pbcs_pm\"]", "twice"),
        (
            "paired = [\"pbcs_pm\", \"nothing\"]",
            "`nothing` is not a method",
        ),
    ] {
        let path = dir.path().join("cmp.toml");
        std::fs::write(&path, text.replace(good, bad)).unwrap();
        let e = Experiment::load(&path, None).unwrap_err().to_string();
        assert!(e.contains("registered.paired") && e.contains(why), "{e}");
    }
}

/// `baseline_from` names another experiment file of the folder, whose method the baseline is;
/// the file itself, or a file that is not there, is an error naming the field. With it, the
/// baseline need not be a method of the file, and may share the variant's name.
#[test]
fn a_paired_baseline_from_another_experiment_names_a_file_of_the_folder() {
    let dir = tempfile::tempdir().unwrap();
    for f in ["pbcs_fast.toml", "table.toml"] {
        std::fs::copy(Path::new("experiments").join(f), dir.path().join(f)).unwrap();
    }
    let text = std::fs::read_to_string("experiments/goal_conditioned_strict.toml").unwrap();
    let good = "baseline_from = \"table\"";
    assert!(text.contains(good));
    let path = dir.path().join("cmp.toml");
    std::fs::write(&path, &text).unwrap();
    let exp = Experiment::load(&path, None).unwrap();
    let reg = exp.registered.as_ref().unwrap();
    assert_eq!(reg.baseline_from.unwrap().as_str(), "table");
    std::fs::write(
        &path,
        text.replace("[\"pbcs_fast\", \"gc100\"]", "[\"gc100\", \"gc100\"]"),
    )
    .unwrap();
    assert!(
        Experiment::load(&path, None).is_ok(),
        "the same name, another file's method"
    );
    for (bad, why) in [
        (
            "baseline_from = \"cmp\"",
            "`cmp` is not another experiment file",
        ),
        (
            "baseline_from = \"nowhere\"",
            "`nowhere` is not another experiment file",
        ),
    ] {
        std::fs::write(&path, text.replace(good, bad)).unwrap();
        let e = Experiment::load(&path, None).unwrap_err().to_string();
        assert!(
            e.contains("registered.baseline_from") && e.contains(why),
            "{e}"
        );
    }
    let e = text.replace("\"pbcs_fast\", \"gc100\"", "\"pbcs_fast\", \"nothing\"");
    std::fs::write(&path, e).unwrap();
    let e = Experiment::load(&path, None).unwrap_err().to_string();
    assert!(e.contains("`nothing` is not a method"), "{e}");
}

/// The registered comparison of SAC and DDPG skills (`experiments/sac_skills.toml`) runs, site
/// by site, the committed grids' jobs (table.toml's `fast` cells on mazes 5 and 10,
/// pointmaze.toml's Medium cell) and those jobs with only `[learner]` changed to SAC's, for
/// the `fast` preset as it was when it was registered.
#[test]
fn the_sac_skill_comparison_runs_the_grids_jobs_with_only_the_learner_changed() {
    use pbcs::experiment::Job;
    let load = |f: &str| Experiment::load(&Path::new("experiments").join(f), None).unwrap();
    let (cmp, table, grid) = (
        load("sac_skills.toml"),
        load("table.toml"),
        load("pointmaze.toml"),
    );
    let (reg, hash) = registration(&cmp);
    assert_eq!(
        hash, reg.sha256,
        "experiments/{} changed since the SAC-skill comparison was registered on {}: register \
         a new one (and say so); do not update this hash.",
        reg.preset, reg.date
    );
    let find = |exp: &Experiment, id: &str| exp.cell(id).unwrap().clone();
    let pbcs_job = |j: &Job| match j {
        Job::Pbcs(j) => j.clone(),
        _ => panic!("not a PBCS cell"),
    };
    for (site, exp, theirs) in [
        ("maze5", &table, "pbcs_fast-maze5"),
        ("maze10", &table, "pbcs_fast-maze10"),
        ("pointmaze_medium", &grid, "pbcs_pm-pointmaze_medium"),
    ] {
        let committed = find(exp, theirs);
        let ddpg = find(&cmp, &format!("ddpg_skills-{site}"));
        let sac = find(&cmp, &format!("sac_skills-{site}"));
        assert_eq!(ddpg.job, committed.job, "{site}: not {theirs}'s job");
        let (mut a, b) = (pbcs_job(&sac.job), pbcs_job(&committed.job));
        assert_eq!(a.learner.algo(), "sac", "{site}");
        assert_eq!(
            a.learner.gamma(),
            b.learner.gamma(),
            "{site}: the preset's γ"
        );
        a.learner = b.learner.clone();
        assert_eq!(a, b, "{site}: more than the learner differs");
        for c in [&ddpg, &sac] {
            assert_eq!(
                cmp.seeds_of(c),
                exp.seeds_of(&committed),
                "{site}: paired seeds"
            );
        }
    }
    assert_eq!(cmp.cells.len(), 6);
}

/// The registered goal-conditioned grid (`experiments/pointmaze_her.toml`) runs its base job
/// (`her_baseline.toml`, as it was when registered) on gymnasium-robotics' own PointMaze tasks
/// by SB3's protocol, with SAC and with TD3, the two differing only in `[learner]`; each map
/// with its time limit.
#[test]
fn the_her_grid_runs_its_base_job_by_sb3s_protocol_with_two_learners() {
    use pbcs::envs::EnvName;
    use pbcs::experiment::Job;
    let exp = Experiment::load(Path::new("experiments/pointmaze_her.toml"), None).unwrap();
    let (reg, hash) = registration(&exp);
    assert_eq!(
        hash, reg.sha256,
        "experiments/{} changed since the HER grid was registered on {}: register a new one \
         (and say so); do not update this hash.",
        reg.preset, reg.date
    );
    let job = |id: &str| match &exp.cell(id).unwrap().job {
        Job::Vanilla(j) => j.clone(),
        _ => panic!("{id}: not a vanilla cell"),
    };
    for (env, limit) in [
        (EnvName::PointmazeUmazeGoals, 300),
        (EnvName::PointmazeMediumGoals, 600),
        (EnvName::PointmazeLargeGoals, 800),
    ] {
        assert!(env.goal_resets());
        let (sac, mut td3) = (
            job(&format!("sac_her-{}", env.name())),
            job(&format!("td3_her-{}", env.name())),
        );
        let t = &sac.train;
        assert_eq!(sac.env, env);
        assert_eq!(
            (t.steps, t.eval_every, t.eval_episodes, t.stop_at_successes),
            (1_000_000, 10_000, 100, Some(95))
        );
        assert_eq!((t.max_episode_steps, t.learning_starts), (limit, 1_000));
        assert_eq!(t.her, Some(pbcs::learner::her::HerConfig::default()));
        assert_eq!(
            sac.learner,
            pbcs::learner::LearnerConfig::preset("sac").unwrap()
        );
        let td3_learner = td3.learner.as_td3().unwrap().clone();
        assert_eq!(td3.learner.algo(), "td3");
        assert_eq!(
            (
                td3_learner.hidden.as_slice(),
                td3_learner.batch_size,
                td3_learner.noise_sigma
            ),
            (&[256, 256][..], 256, 0.1)
        );
        td3.learner = sac.learner.clone();
        assert_eq!(td3, sac, "{}: more than the learner differs", env.name());
    }
    assert_eq!(exp.cells.len(), 6);
    assert_eq!(
        reg.paired,
        Some(["sac_her".parse().unwrap(), "td3_her".parse().unwrap()])
    );
}
