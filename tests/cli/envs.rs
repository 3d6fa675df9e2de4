//! Environments by name on the command line: `pbcs run --env rooms` runs PBCS on the two
//! rooms (`src/envs/rooms.rs`) and `pbcs eval` re-runs its chain, both knowing the environment from
//! the job alone; `pbcs explore --env rooms` runs phase 1 there; maze settings given to
//! another environment are refused.

use super::{path, pbcs, stderr};

/// The value of `column` in a one-row CSV.
fn field(csv: &str, column: &str) -> String {
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let row: Vec<&str> = csv.lines().nth(1).unwrap().split(',').collect();
    let i = header.iter().position(|h| *h == column).unwrap();
    row[i].to_string()
}

/// `pbcs run --env rooms --seed 0` into `out`, which succeeds; its standard output.
fn run_rooms(out: &std::path::Path) -> String {
    let o = pbcs(&[
        "run",
        "--env",
        "rooms",
        "--seed",
        "0",
        "--quiet",
        "--out",
        path(out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn pbcs_run_env_rooms_runs_and_its_chain_is_evaluated_from_its_folder() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rooms");
    let stdout = run_rooms(&out);
    assert!(stdout.contains("on rooms, run seed 0"), "{stdout}");
    let record = std::fs::read_to_string(out.join("record.csv")).unwrap();
    assert_eq!(field(&record, "env"), "rooms");
    assert_eq!(
        (field(&record, "maze"), field(&record, "maze_seed")),
        ("".into(), "".into())
    );
    assert_eq!(field(&record, "solved"), "true", "{record}");
    // The job written names the environment; the picture is the rooms' 2 × 1 frame.
    let config = std::fs::read_to_string(out.join("config.toml")).unwrap();
    assert!(config.contains("env = \"rooms\""), "{config}");
    let png = std::fs::read(out.join("run.png")).unwrap();
    let (w, h) = (
        u32::from_be_bytes(png[16..20].try_into().unwrap()),
        u32::from_be_bytes(png[20..24].try_into().unwrap()),
    );
    assert!(w > h, "{w} × {h}");
    // `pbcs eval` finds the environment in the chain's job: the run's own evaluation again.
    let o = pbcs(&["eval", "--chain", path(&out.join("chain"))]);
    assert!(o.status.success(), "{}", stderr(&o));
    let eval = std::fs::read_to_string(out.join("chain").join("eval-s0.csv")).unwrap();
    let run = std::fs::read_to_string(out.join("evaluation.csv")).unwrap();
    assert_eq!(eval, run);
    // The same command gives the same bytes.
    let again = dir.path().join("again");
    run_rooms(&again);
    for f in [
        "record.csv",
        "trace.csv",
        "trajectory.csv",
        "evaluation.csv",
    ] {
        assert_eq!(
            std::fs::read(out.join(f)).unwrap(),
            std::fs::read(again.join(f)).unwrap(),
            "{f}"
        );
    }
}

#[test]
fn maze_settings_for_another_environment_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x");
    let o = pbcs(&["run", "--env", "rooms", "--maze", "7", "--out", path(&out)]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("--maze") && stderr(&o).contains("rooms"),
        "{}",
        stderr(&o)
    );
    let config = dir.path().join("rooms.toml");
    std::fs::write(&config, "env = \"rooms\"\n[maze]\nsize = 7\n").unwrap();
    let o = pbcs(&["run", "--config", path(&config), "--out", path(&out)]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("`maze`") && e.contains("env = \"rooms\""), "{e}");
    assert!(!out.exists(), "a refused run wrote its folder");
    let o = pbcs(&["run", "--env", "hall", "--out", path(&out)]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("maze") && stderr(&o).contains("rooms"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn pbcs_explore_env_rooms_explores_the_rooms() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("explore");
    let o = pbcs(&[
        "explore",
        "--env",
        "rooms",
        "--seed",
        "0",
        "--quiet",
        "--out",
        path(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).starts_with("rooms, run seed 0: target reached"));
    let summary = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    assert_eq!(field(&summary, "env"), "rooms");
    assert_eq!(field(&summary, "maze"), "");
    // The archive holds the rooms' observations, inside their 2 × 1 frame.
    let archive = std::fs::read_to_string(out.join("archive.csv")).unwrap();
    assert!(archive.starts_with("id,parent,state_usage,bin_usage,x,y\n"));
    for line in archive.lines().skip(1) {
        let v: Vec<f32> = line
            .rsplit(',')
            .take(2)
            .map(|x| x.parse().unwrap())
            .collect();
        let (y, x) = (v[0], v[1]);
        assert!(
            (0.0..=2.0).contains(&x) && (0.0..=1.0).contains(&y),
            "{line}"
        );
    }
    assert!(std::fs::read_to_string(out.join("config.toml"))
        .unwrap()
        .contains("env = \"rooms\""));
    let o = pbcs(&[
        "explore",
        "--env",
        "rooms",
        "--maze-seed",
        "3",
        "--out",
        path(&dir.path().join("x")),
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("--maze-seed") || stderr(&o).contains("--maze"),
        "{}",
        stderr(&o)
    );
}

/// `make results` runs every experiment file: one whose environments this build cannot run
/// (PointMaze without `--features mujoco`) is refused before any work by `pbcs exp run`,
/// saying how to build it, and skipped with that line under `--skip-unavailable`. With the
/// feature, neither applies.
#[test]
fn an_experiment_this_build_cannot_run_is_refused_or_skipped_before_any_work() {
    if cfg!(feature = "mujoco") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let results = dir.path().join("results");
    let args = [
        "exp",
        "run",
        "experiments/pointmaze.toml",
        "--profile",
        "smoke",
        "--results",
        super::path(&results),
    ];
    let o = super::pbcs(&args);
    assert!(!o.status.success());
    let e = super::stderr(&o);
    for needle in ["pointmaze_umaze", "--features mujoco", "make mujoco"] {
        assert!(e.contains(needle), "{needle} not in: {e}");
    }
    let o = super::pbcs(&[&args[..], &["--skip-unavailable"]].concat());
    assert!(o.status.success(), "{}", super::stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.starts_with("skipped pointmaze: ") && out.lines().count() == 1,
        "{out}"
    );
    assert!(!results.exists(), "nothing was written");
}
