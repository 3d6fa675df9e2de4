//! Bad input is rejected with a message that names the field or file, never a panic.

use pbcs::config::{load, ExploreJob, PbcsJob, TrainJob};
use std::path::PathBuf;
use std::process::Command;

fn write(text: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("job.toml");
    std::fs::write(&path, text).unwrap();
    (dir, path)
}

fn load_err(text: &str) -> String {
    let (_dir, path) = write(text);
    load::<ExploreJob>(&path).unwrap_err().to_string()
}

#[test]
fn maze_size_out_of_range_names_the_field() {
    for size in [0, 1, 101, 1_000_000] {
        let msg = load_err(&format!("[maze]\nsize = {size}\n"));
        assert!(
            msg.contains("maze.size") && msg.contains(&size.to_string()),
            "{msg}"
        );
    }
}

#[test]
fn negative_or_zero_radius_thickness_action_bin_are_rejected() {
    for (text, field) in [
        ("[maze]\ntarget_radius = -0.2\n", "maze.target_radius"),
        ("[maze]\nwall_thickness = 0.0\n", "maze.wall_thickness"),
        ("[maze]\nmax_action = nan\n", "maze.max_action"),
        ("[explore]\nbin_side = -0.05\n", "explore.bin_side"),
        ("[explore]\nbudget = 0\n", "explore.budget"),
        // The old name is still read (stored configs), and checked the same way.
        ("[explore]\nmax_steps = 0\n", "explore.budget"),
    ] {
        let msg = load_err(text);
        assert!(msg.contains(field), "{text:?}: {msg}");
    }
}

#[test]
fn unknown_keys_are_rejected() {
    let msg = load_err("[maze]\nsize = 5\ncolour = 3\n");
    assert!(
        msg.contains("unknown field") && msg.contains("colour"),
        "{msg}"
    );
    let msg = load_err("sed = 3\n");
    assert!(
        msg.contains("unknown field") && msg.contains("sed"),
        "{msg}"
    );
}

#[test]
fn negative_seed_and_bad_syntax_are_parse_errors_naming_the_file() {
    let msg = load_err("seed = -1\n");
    assert!(msg.contains("job.toml") && msg.contains("seed"), "{msg}");
    let msg = load_err("[maze\nsize = 5\n");
    assert!(msg.contains("job.toml"), "{msg}");
}

#[test]
fn unreadable_file_names_the_path() {
    let msg = load::<ExploreJob>(std::path::Path::new("/nonexistent/job.toml"))
        .unwrap_err()
        .to_string();
    assert!(msg.contains("/nonexistent/job.toml"), "{msg}");
}

fn pbcs(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_pbcs"))
        .args(args)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "panic on {args:?}: {stderr}");
    (out.status.code().unwrap_or(-1), stderr)
}

#[test]
fn the_command_line_rejects_bad_input_with_a_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let (code, err) = pbcs(&["explore", "--maze", "1", "--seed", "0", "--out", out]);
    assert!(code != 0 && err.contains("maze.size"), "{code} {err}");
    let (code, err) = pbcs(&["explore", "--maze", "5", "--seed", "-1", "--out", out]);
    assert!(code != 0 && err.contains("--seed"), "{code} {err}");
    let (code, err) = pbcs(&["explore", "--config", "/nonexistent.toml", "--out", out]);
    assert!(
        code != 0 && err.contains("/nonexistent.toml"),
        "{code} {err}"
    );
    let (_tmp, path) = write("[maze]\nsize = 5\nbogus = 1\n");
    let (code, err) = pbcs(&["explore", "--config", path.to_str().unwrap(), "--out", out]);
    assert!(code != 0 && err.contains("bogus"), "{code} {err}");
    // Nothing was written by the failed runs.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn the_command_line_runs_a_small_maze() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let (code, err) = pbcs(&[
        "explore",
        "--maze",
        "3",
        "--seed",
        "4",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    for f in [
        "summary.csv",
        "trajectory.csv",
        "archive.csv",
        "explore.png",
        "explore.svg",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
}

#[test]
fn every_experiment_file_parses_and_checks() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if name.starts_with("explore") && name.ends_with(".toml") {
            load::<ExploreJob>(&path).unwrap_or_else(|e| panic!("{e}"));
            n += 1;
        } else if name.starts_with("pbcs") && name.ends_with(".toml") {
            load::<PbcsJob>(&path).unwrap_or_else(|e| panic!("{e}"));
            n += 1;
        } else if name.starts_with("baseline") && name.ends_with(".toml") {
            load::<TrainJob>(&path).unwrap_or_else(|e| panic!("{e}"));
            n += 1;
        }
    }
    assert!(n >= 4, "experiment files missing in {}", dir.display());
}

#[test]
fn train_rejects_bad_learner_settings_and_runs_a_small_case() {
    let (_tmp, path) = write("[learner]\ngamma = 1.5\n");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = out.to_str().unwrap();
    let (code, err) = pbcs(&["train", "--config", path.to_str().unwrap(), "--out", o]);
    assert!(code != 0 && err.contains("learner.gamma"), "{code} {err}");
    let (code, err) = pbcs(&["train", "--algo", "ppo", "--out", o]);
    assert!(
        code != 0 && err.contains("ppo") && err.contains("sac"),
        "{code} {err}"
    );
    // TD3's actor switch under SAC: refused, naming the flag.
    let (code, err) = pbcs(&["train", "--algo", "sac", "--actor", "argmax", "--out", o]);
    assert!(code != 0 && err.contains("--actor"), "{code} {err}");
    // `--steps` below the config's `train.learning_starts` (10 000 by default) would never
    // update the learner: refused, naming the field.
    let small = [
        "--algo", "td3", "--maze", "2", "--seed", "1", "--steps", "1500", "--quiet",
    ];
    let (code, err) = pbcs(&[&["train"][..], &small, &["--out", o]].concat());
    assert!(
        code != 0 && err.contains("train.learning_starts"),
        "{code} {err}"
    );
    let (_tmp2, starts) = write("[train]\nlearning_starts = 500\n");
    let config = ["--config", starts.to_str().unwrap()];
    let (code, err) = pbcs(&[&["train"][..], &config, &small, &["--out", o]].concat());
    assert_eq!(code, 0, "{err}");
    for f in [
        "summary.csv",
        "evals.csv",
        "visited.csv",
        "actor.safetensors",
        "train.png",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
}

#[test]
fn presets_are_the_experiment_files_and_paper_is_the_library_default() {
    use pbcs::config::Preset;
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments");
    for preset in [Preset::Paper, Preset::Fast] {
        let from_file: PbcsJob = load(&dir.join(preset.file_name())).unwrap();
        assert_eq!(preset.job().unwrap(), from_file, "{preset:?}");
    }
    // The paper preset is PbcsJob::default() (what experiment bases start from), for maze 5.
    let mut default = PbcsJob::default();
    default.maze.size = 5;
    assert_eq!(Preset::Paper.job().unwrap(), default);
    // The paper preset is the paper's procedure: none of our ideas. The fast preset differs
    // only in its ideas (and its budget).
    let paper = Preset::Paper.job().unwrap().phase2;
    assert_eq!(paper.ideas, pbcs::phase2::Ideas::NONE);
    let fast = Preset::Fast.job().unwrap().phase2;
    let i = fast.ideas;
    assert!(i.shorten && i.stopping.early_stop && i.verify_skills.is_some());
    assert!(matches!(
        i.k_walk,
        pbcs::phase2::KWalk::Adaptive { first: 1 }
    ));
    let mut fast_without_ideas = fast.clone();
    fast_without_ideas.ideas = pbcs::phase2::Ideas::NONE;
    fast_without_ideas.inputs = paper.inputs;
    fast_without_ideas.max_env_steps = paper.max_env_steps;
    assert_eq!(fast_without_ideas, paper);
    // --preset and --config exclude each other; an unknown preset is refused by name.
    let (code, err) = pbcs(&["run", "--preset", "paper", "--config", "x.toml"]);
    assert!(code != 0 && err.contains("--config"), "{code} {err}");
    let (code, err) = pbcs(&["run", "--preset", "quick"]);
    assert!(
        code != 0 && err.contains("quick") && err.contains("fast"),
        "{code} {err}"
    );
}

#[test]
fn epsilon_is_a_radius_in_cells() {
    let (_dir, path) = write("[phase2]\nepsilon = 50\n");
    let err = load::<PbcsJob>(&path).unwrap_err().to_string();
    assert!(err.contains("phase2.epsilon"), "{err}");
}

/// Every enum's name (`name()`, from strum's snake_case rule) is its serde name, the one that
/// configs, CSVs and `timing.toml` use: the two derive from the variant by the same rule, and
/// this holds them equal.
/// `gym` names what a run through the Python adapter ran on: a job that names it is refused
/// by the command line, saying where it runs, and `--env` does not offer it.
#[test]
fn a_job_on_a_users_gymnasium_env_runs_from_python_only() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out = out.to_str().unwrap();
    let (_tmp, path) = write("env = \"gym\"\n");
    let (code, err) = pbcs(&["run", "--config", path.to_str().unwrap(), "--out", out]);
    assert!(
        code != 0 && err.contains("runs from Python only"),
        "{code} {err}"
    );
    let (code, err) = pbcs(&["run", "--env", "gym", "--out", out]);
    assert!(
        code != 0 && err.contains("invalid value 'gym'"),
        "{code} {err}"
    );
    assert!(!pbcs::envs::EnvName::all().contains(&pbcs::envs::EnvName::Gym));
    assert!(!dir.path().join("out").exists());
}

#[test]
fn enum_names_are_their_serde_names() {
    use pbcs::config::Preset;
    use pbcs::learner::td3::{ActorUpdate, Algo};
    use pbcs::phase2::{EventKind, Failure, StartMode, Variant};
    fn serde_name<T: serde::Serialize>(v: &T) -> String {
        #[derive(serde::Serialize)]
        struct Wrap<'a, T> {
            v: &'a T,
        }
        let text = toml::to_string(&Wrap { v }).unwrap();
        text.trim()
            .trim_start_matches("v = ")
            .trim_matches('"')
            .to_string()
    }
    let mut pairs: Vec<(&str, String)> = Vec::new();
    for a in [Algo::Ddpg, Algo::Td3] {
        pairs.push((a.name(), serde_name(&a)));
    }
    for a in [ActorUpdate::Gradient, ActorUpdate::Argmax] {
        pairs.push((a.name(), serde_name(&a)));
    }
    for v in [Variant::Pbcs, Variant::PbcsNoChaining] {
        pairs.push((v.name(), serde_name(&v)));
    }
    for f in [
        Failure::BackplayFailed,
        Failure::NoChaining,
        Failure::Budget,
    ] {
        pairs.push((f.name(), serde_name(&f)));
    }
    for s in [StartMode::Ball, StartMode::Exact, StartMode::Archive] {
        pairs.push((s.into(), serde_name(&s)));
    }
    for k in [
        EventKind::Test,
        EventKind::Train,
        EventKind::Verify,
        EventKind::ChainVerify,
    ] {
        pairs.push((k.name(), serde_name(&k)));
    }
    for p in [Preset::Paper, Preset::Fast] {
        pairs.push((p.name(), serde_name(&p)));
    }
    for (name, serde) in &pairs {
        assert_eq!(name, serde);
    }
    assert!(pairs.iter().any(|(n, _)| *n == "pbcs_no_chaining"));
    // The kernels have no serde form: their names are the documented PBCS_KERNEL spellings.
    let kernels: Vec<&str> = pbcs::nn::kernel::Kernel::ALL
        .iter()
        .map(|k| k.name())
        .collect();
    assert_eq!(kernels, ["portable", "matrixmultiply", "avx2", "avx512"]);
}

/// Switches that mean nothing together are refused when a job is loaded, the message naming
/// both fields: each pair on top of a preset that is valid alone.
#[test]
fn switches_that_cannot_combine_are_refused_naming_both_fields() {
    for (base, set, field, other) in [
        (
            "pbcs_fast.toml",
            "chaining = false\nretargets = 3\nchain_repairs = 0\n",
            "phase2.retargets",
            "phase2.chaining",
        ),
        (
            "pbcs_fast.toml",
            "chaining = false\nretargets = 0\n",
            "phase2.chain_repairs",
            "phase2.chaining",
        ),
        (
            "pbcs_fast.toml",
            "inputs = \"raw\"\n",
            "phase2.warm_start",
            "phase2.inputs",
        ),
        (
            "pbcs_fast.toml",
            "path_limit = 2.0\n",
            "phase2.test_path_limit",
            "phase2.path_limit",
        ),
        (
            "pbcs_fast.toml",
            "dead_walk = 0\n",
            "phase2.retargets",
            "phase2.dead_walk",
        ),
        (
            "pbcs_paper.toml",
            "chain_repairs = 2\n",
            "phase2.chain_repairs",
            "phase2.chain_verify_episodes",
        ),
    ] {
        let preset = std::fs::read_to_string(format!("experiments/{base}")).unwrap();
        // The preset's own [phase2] table, with the pair's fields replaced.
        let mut text = String::new();
        let fields: Vec<&str> = set
            .lines()
            .map(|l| l.split(" = ").next().unwrap())
            .collect();
        for line in preset.lines() {
            let key = line.split(" = ").next().unwrap_or("").trim();
            if !fields.contains(&key) {
                text.push_str(line);
                text.push('\n');
            }
            if line.trim() == "[phase2]" {
                text.push_str(set);
            }
        }
        let (_dir, path) = write(&text);
        let msg = load::<PbcsJob>(&path).unwrap_err().to_string();
        assert!(
            msg.contains(field) && msg.contains(other),
            "{base} with {set:?}: {msg}"
        );
    }
}

/// The typed phase-2 procedure is read from, and written back to, the flat `[phase2]` table
/// field for field: every committed file that holds one (presets, experiment bases, run
/// folders, 1 000 and more) converts to `Phase2Config` and back to the very table it held, so
/// committed bytes and the jobs compared against them stay as they were.
#[test]
fn every_committed_phase2_table_reads_into_the_procedure_and_back_unchanged() {
    use pbcs::phase2::{flat::FlatPhase2, Phase2Config};
    let files = std::process::Command::new("git")
        .args(["ls-files", "*.toml"])
        .output()
        .unwrap();
    let mut checked = 0;
    for path in String::from_utf8(files.stdout).unwrap().lines() {
        let text = std::fs::read_to_string(path).unwrap();
        let value: toml::Table = toml::from_str(&text).unwrap();
        let Some(table) = value.get("phase2").and_then(|v| v.as_table()) else {
            continue;
        };
        let flat: FlatPhase2 = table.clone().try_into().unwrap();
        let typed = Phase2Config::try_from(flat.clone()).unwrap_or_else(|e| panic!("{path}: {e}"));
        assert_eq!(FlatPhase2::from(typed.clone()), flat, "{path}");
        // And through serde, as jobs are read and written.
        let back: Phase2Config = toml::from_str(&toml::to_string(&typed).unwrap()).unwrap();
        assert_eq!(back, typed, "{path}");
        checked += 1;
    }
    assert!(checked > 1000, "{checked} tables");
}

/// A PointMaze map of one's own (`env = "pointmaze"`, `[pointmaze]`, `--map FILE`): every bad
/// map or misplaced map gets an error naming its field, in any build (the map is checked
/// before MuJoCo is needed).
#[test]
fn a_map_of_ones_own_is_checked_naming_its_field() {
    use pbcs::config::Check;
    let job = |text: &str| -> Result<ExploreJob, String> {
        let (_dir, path) = write(text);
        let job: ExploreJob = load(&path).map_err(|e| e.to_string())?;
        job.check().map_err(|e| e.to_string())?;
        Ok(job)
    };
    let ok = "env = \"pointmaze\"\n[pointmaze]\nmap = [\"11111\", \"10001\", \"11111\"]\n";
    let good = job(ok).unwrap();
    assert_eq!(good.pointmaze.map.len(), 3);
    for (text, says) in [
        ("env = \"pointmaze\"\n", "pointmaze.map"),
        (
            "env = \"pointmaze\"\n[pointmaze]\nmap = [\"111\", \"121\", \"111\"]\n",
            "row 1",
        ),
        (
            "env = \"pointmaze\"\n[pointmaze]\nmap = [\"111\", \"10\", \"111\"]\n",
            "row 1 has 2",
        ),
        (
            "env = \"pointmaze\"\n[pointmaze]\nmap = [\"111\", \"001\", \"111\"]\n",
            "border",
        ),
        (
            "env = \"pointmaze\"\n[pointmaze]\nmap = [\"111\", \"101\", \"111\"]\n",
            "one free cell",
        ),
        // Free cells, but no two connected.
        (
            "env = \"pointmaze\"\n[pointmaze]\nmap = [\"11111\", \"10101\", \"11111\"]\n",
            "no two connected",
        ),
        (
            "env = \"pointmaze\"\n[pointmaze]\nmap = [\"111\", \"111\", \"111\"]\n",
            "no free cell",
        ),
        (&format!("{ok}time_limit = 0\n"), "pointmaze.time_limit"),
        (&format!("{ok}colour = 1\n"), "colour"),
        (
            "env = \"pointmaze\"\n[pointmaze]\nmap_file = \"/nonexistent/map.txt\"\n",
            "/nonexistent/map.txt",
        ),
        (
            "env = \"pointmaze\"\n[pointmaze]\nmap = [\"111\"]\nmap_file = \"m.txt\"\n",
            "not both",
        ),
        (
            "env = \"rooms\"\n[pointmaze]\nmap = [\"11111\", \"10001\", \"11111\"]\n",
            "env = \"rooms\"",
        ),
        (
            "[pointmaze]\nmap = [\"11111\", \"10001\", \"11111\"]\n",
            "env = \"maze\"",
        ),
    ] {
        let err = job(text).unwrap_err();
        assert!(err.contains(says), "{text:?}: {err}");
    }
    let side = pbcs::envs::pointmaze::MAX_MAP_SIDE + 1;
    let wide: Vec<String> = (0..3)
        .map(|i| match i {
            1 => format!("1{}1", "0".repeat(side - 2)),
            _ => "1".repeat(side),
        })
        .collect();
    let err = job(&format!(
        "env = \"pointmaze\"\n[pointmaze]\nmap = {wide:?}\n"
    ))
    .unwrap_err();
    assert!(err.contains("at most"), "{err}");
    // A file of rows: comments, spaces between cells; a bad character names its line.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("map.txt");
    std::fs::write(&file, "# mine\n1 1 1 1\n1 0 0 1\n\n1 1 1 1  # end\n").unwrap();
    let from_file = job(&format!(
        "env = \"pointmaze\"\n[pointmaze]\nmap_file = {:?}\ntime_limit = 50\n",
        file.to_str().unwrap()
    ))
    .unwrap();
    assert_eq!(from_file.pointmaze.map, ["1111", "1001", "1111"]);
    assert_eq!(from_file.pointmaze.time_limit, 50);
    // Written back, the job holds the rows, not the file.
    let written = toml::to_string(&from_file).unwrap();
    assert!(
        written.contains("map = [") && !written.contains("map_file"),
        "{written}"
    );
    std::fs::write(&file, "1111\n1x01\n1111\n").unwrap();
    let err = job(&format!(
        "env = \"pointmaze\"\n[pointmaze]\nmap_file = {:?}\n",
        file.to_str().unwrap()
    ))
    .unwrap_err();
    assert!(err.contains("line 2") && err.contains("'x'"), "{err}");
    // On the command line: --map with another environment is refused before any work.
    std::fs::write(&file, "1111\n1001\n1111\n").unwrap();
    let out = dir.path().join("out");
    let (code, err) = pbcs(&[
        "explore",
        "--env",
        "rooms",
        "--map",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        code != 0 && err.contains("is for env `pointmaze`"),
        "{code} {err}"
    );
    assert!(!out.exists());
}

/// Every learner's name in result rows, each family and variant with and without HER, is a
/// valid [`pbcs::learner::LearnerName`] (a family's name that were not would panic here) and
/// the one the rows have always carried.
#[test]
fn every_family_names_its_learner_validly() {
    use pbcs::learner::LearnerConfig;
    let mut names = Vec::new();
    for learner in [
        "algo = \"ddpg\"",
        "algo = \"td3\"",
        "algo = \"ddpg\"\nactor_update = \"argmax\"",
        "algo = \"td3\"\nactor_update = \"argmax\"",
        "algo = \"sac\"",
    ] {
        let learner: LearnerConfig = toml::from_str(learner).unwrap();
        for her in [false, true] {
            let mut job = pbcs::config::TrainJob {
                learner: learner.clone(),
                ..Default::default()
            };
            job.train.her = her.then(Default::default);
            names.push(job.learner_name().to_string());
        }
    }
    assert_eq!(
        names,
        [
            "ddpg",
            "ddpg_her",
            "td3",
            "td3_her",
            "ddpg_am",
            "ddpg_am_her",
            "td3_am",
            "td3_am_her",
            "sac",
            "sac_her"
        ]
    );
}
