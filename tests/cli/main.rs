//! The command line as a user meets it: bad input and unusable output folders are refused
//! before any work, with a message naming what to fix; no run replaces another's folder; a
//! closed pipe is not a panic. Each test spawns the `pbcs` binary.

use std::path::Path;
use std::process::{Command, Output, Stdio};

mod envs;
mod outputs;
mod results;

pub(crate) fn pbcs(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pbcs"))
        .args(args)
        .env_remove("PBCS_KERNEL")
        .output()
        .expect("spawn pbcs")
}

pub(crate) fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub(crate) fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn bad_numbers_get_clear_messages() {
    let o = pbcs(&["run", "--maze", "-3", "--quiet"]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("from 2 to 100") && e.contains("-3"), "{e}");
    assert!(!e.contains("invalid digit"), "{e}");

    // Before: "0/0 NaN [NaN, NaN]".
    let o = pbcs(&["table", "--seeds", "0", "--sizes", "2"]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("--seeds") && !e.contains("NaN"), "{e}");

    // A maze size given twice, or one out of range, is refused before any run.
    let dir = tempfile::tempdir().unwrap();
    for (sizes, says) in [("2,2", "unique"), ("2,1", "maze.size")] {
        let o = pbcs(&[
            "table",
            "--sizes",
            sizes,
            "--seeds",
            "1",
            "--out",
            path(dir.path()),
        ]);
        assert!(!o.status.success(), "{sizes}");
        let e = stderr(&o);
        assert!(e.contains(says), "{sizes}: {e}");
    }
    assert!(!dir.path().join("raw").exists(), "nothing was run");
}

#[test]
fn an_unknown_kernel_is_refused_naming_the_variable() {
    let o = Command::new(env!("CARGO_BIN_EXE_pbcs"))
        .args([
            "explore",
            "--maze",
            "2",
            "--quiet",
            "--out",
            "/nonexistent/never",
        ])
        .env("PBCS_KERNEL", "avx9000")
        .output()
        .unwrap();
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("PBCS_KERNEL") && e.contains("avx9000"), "{e}");
}

/// OS errors were printed twice ("(os error 2): … (os error 2)").
#[test]
fn an_os_error_is_printed_once() {
    let o = pbcs(&["run", "--config", "/nonexistent/x.toml", "--quiet"]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert_eq!(e.matches("os error").count(), 1, "{e}");
}

/// Before: `pbcs exp list … | head -1` panicked with "failed printing to stdout".
#[cfg(unix)]
#[test]
fn a_closed_pipe_is_not_a_panic() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_pbcs"))
        .args(["exp", "list", "experiments/table.toml"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take()); // the reader goes away at once, like `head` after its lines
    let o = child.wait_with_output().unwrap();
    let e = stderr(&o);
    assert!(!e.contains("panicked"), "{e}");
}

/// Before: a run stopped on its budget printed "chain success 0 % over 100000000000
/// episodes" though no episode ran. Its line says the chain was not evaluated.
#[test]
fn a_run_stopped_on_its_budget_says_its_chain_was_not_evaluated() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("budget.toml");
    std::fs::write(
        &config,
        "[phase2]\neval_episodes = 100000\nmax_env_steps = 8000\n",
    )
    .unwrap();
    let out = dir.path().join("run");
    let o = pbcs(
        &["run", "--maze", "2", "--seed", "0", "--quiet"]
            .into_iter()
            .chain(["--config", path(&config), "--out", path(&out)])
            .collect::<Vec<_>>(),
    );
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(said.contains("not solved — chain not evaluated"), "{said}");
    assert!(
        said.contains("stopped: budget") && !said.contains("episodes"),
        "{said}"
    );
}

/// `pbcs eval --chain DIR` re-runs a saved chain from its folder alone: with the run's own
/// seed it reproduces the run's evaluation (the reloaded chain acts as the trained one).
#[test]
fn a_saved_chain_is_evaluated_from_its_folder_alone() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = pbcs(&[
        "run",
        "--maze",
        "2",
        "--seed",
        "0",
        "--quiet",
        "--out",
        path(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // The run's line gives the chain's success as a percentage (before: "chain success 1").
    assert!(
        String::from_utf8_lossy(&o.stdout)
            .contains("SOLVED — chain success 100 % over 100 episodes"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    let record = std::fs::read_to_string(out.join("record.csv")).unwrap();
    let header: Vec<&str> = record.lines().next().unwrap().split(',').collect();
    let row: Vec<&str> = record.lines().nth(1).unwrap().split(',').collect();
    let rate: f64 = row[header.iter().position(|h| *h == "success_rate").unwrap()]
        .parse()
        .unwrap();
    // Moved elsewhere: the chain folder is all `eval` needs.
    let moved = dir.path().join("moved");
    std::fs::rename(out.join("chain"), &moved).unwrap();
    let o = pbcs(&["eval", "--chain", path(&moved)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(moved.join("eval-s0.csv")).unwrap();
    let wins = csv
        .lines()
        .skip(1)
        .filter(|l| l.starts_with("true"))
        .count();
    assert_eq!(csv.lines().count(), 101);
    assert_eq!(wins as f64 / 100.0, rate);
    assert!(String::from_utf8_lossy(&o.stdout).contains("Wilson 95 %"));
    assert!(moved.join("eval-s0.png").exists());

    // Broken weights: an error naming the file, no panic.
    std::fs::write(moved.join("skill0.safetensors"), b"not a tensor file").unwrap();
    let o = pbcs(&["eval", "--chain", path(&moved)]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("skill0.safetensors") && !e.contains("panicked"),
        "{e}"
    );

    // Not a chain folder at all.
    let o = pbcs(&["eval", "--chain", path(dir.path())]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("run.toml"), "{}", stderr(&o));
}

/// Before: an empty config silently ran maze 5 with a 50M-step budget.
#[test]
fn a_config_that_leaves_settings_out_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("empty.toml");
    std::fs::write(&config, "").unwrap();
    let o = pbcs(&[
        "explore",
        "--config",
        path(&config),
        "--maze",
        "2",
        "--quiet",
        "--out",
        path(&dir.path().join("e")),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains("does not set") && e.contains("maze") && e.contains("defaults"),
        "{e}"
    );
}

/// Without a terminal (logs, CI, cluster jobs) a long run says what it is doing: a line per
/// skill found (before: nothing until the end). Also the smaller probes: `--help` names where
/// defaults come from, `train` takes `--gamma`, a grid of 0 seeds is refused.
#[test]
fn without_a_terminal_a_run_prints_a_line_per_skill() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    // stderr is a pipe here, not a terminal; maze 2 seed 0 (fast preset) builds 2 skills.
    let o = pbcs(&["run", "--maze", "2", "--seed", "0", "--out", path(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    let lines: Vec<&str> = e.lines().filter(|l| l.contains("attempts done")).collect();
    assert!(
        lines
            .iter()
            .any(|l| l.contains("1 skill attempts done, attempt 2 starts")),
        "{e}"
    );

    let help = String::from_utf8_lossy(&pbcs(&["run", "--help"]).stdout).into_owned();
    assert!(help.contains("default"), "{help}");
    let help = String::from_utf8_lossy(&pbcs(&["train", "--help"]).stdout).into_owned();
    assert!(help.contains("--gamma"), "{help}");
    let o = pbcs(&["table", "--seeds", "0"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--seeds"), "{}", stderr(&o));

    // A sweep's log (no terminal) gets one line per finished run.
    let results = dir.path().join("results");
    let o = pbcs(&[
        "exp",
        "run",
        "experiments/gamma.toml",
        "--profile",
        "smoke",
        "--cell",
        "g090-maze2",
        "--results",
        path(&results),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("g090-maze2 seed 0: "), "{}", stderr(&o));
}

/// Before: `--jobs 0` silently ran one run at a time. Every command with `--jobs` refuses it
/// in the argument parser, before any work.
#[test]
fn jobs_zero_is_refused_by_every_command_that_takes_it() {
    let dir = tempfile::tempdir().unwrap();
    let results = path(dir.path());
    let exp = |command| {
        vec![
            "exp",
            command,
            "experiments/gamma.toml",
            "--profile",
            "smoke",
            "--cell",
            "g090-maze2",
            "--seed",
            "0",
            "--results",
            results,
            "--jobs",
            "0",
        ]
    };
    let table = vec![
        "table", "--sizes", "2", "--seeds", "1", "--out", results, "--jobs", "0",
    ];
    for args in [table, exp("run"), exp("check")] {
        let o = pbcs(&args);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: a usage error: {e}");
        assert!(
            e.contains("--jobs") && e.contains("at least 1") && e.contains("\"0\""),
            "{args:?}: {e}"
        );
    }
    assert!(
        std::fs::read_dir(dir.path()).unwrap().next().is_none(),
        "nothing ran"
    );
}

/// Replaces the first line of `text` that starts with `key = ` by `key = value`.
fn set_first(text: &str, key: &str, value: &str) -> String {
    let prefix = format!("{key} = ");
    let line = text
        .lines()
        .find(|l| l.starts_with(&prefix))
        .unwrap_or_else(|| panic!("no {key} in {text}"));
    text.replacen(line, &format!("{prefix}{value}"), 1)
}

/// Before: `pbcs eval` ran a chain whose manifest said `center = [nan, nan]`,
/// `origin = [nan, inf]`, `action_scale = [1e30, -1e30]` or `skills = []` and reported a
/// success rate with exit 0. Each is now refused, naming the file and the field; the chain as
/// `pbcs run` saved it is evaluated.
#[test]
fn eval_refuses_a_manifest_with_a_bad_value_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = pbcs(&[
        "run",
        "--maze",
        "2",
        "--seed",
        "0",
        "--quiet",
        "--out",
        path(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let chain = out.join("chain");
    let manifest = chain.join("manifest.toml");
    let text = std::fs::read_to_string(&manifest).unwrap();
    let eval = || pbcs(&["eval", "--chain", path(&chain), "--episodes", "5"]);
    let o = eval();
    assert!(o.status.success(), "as saved: {}", stderr(&o));
    for (key, value, field) in [
        ("center", "[nan, nan]", "skills[0].center"),
        ("origin", "[nan, inf]", "skills[0].origin"),
        ("action_scale", "[1e30, -1e30]", "skills[0].action_scale"),
    ] {
        std::fs::write(&manifest, set_first(&text, key, value)).unwrap();
        let o = eval();
        let e = stderr(&o);
        assert!(
            !o.status.success(),
            "{key} = {value}: {}",
            String::from_utf8_lossy(&o.stdout)
        );
        assert!(
            e.contains("manifest.toml") && e.contains(field) && !e.contains("panicked"),
            "{key} = {value}: {e}"
        );
    }
    std::fs::write(&manifest, "skills = []\n").unwrap();
    let o = eval();
    let e = stderr(&o);
    assert!(
        !o.status.success(),
        "skills = []: {}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert!(e.contains("manifest.toml") && e.contains("no skill"), "{e}");
    std::fs::write(&manifest, &text).unwrap();
    assert!(eval().status.success());
}

/// Before: when a file of `pbcs run` could not be written (a full disk; here a folder in the
/// way of `run.png`), the run failed naming the file but left `record.csv` saying "solved"
/// beside the chain, nothing marked the folder, and `pbcs eval` used it. Now the folder is
/// marked incomplete and refused until a run completes it.
#[test]
fn a_run_that_cannot_write_all_its_files_leaves_its_folder_marked_incomplete() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    std::fs::create_dir_all(out.join("run.png").join("in-the-way")).unwrap();
    let args = [
        "run",
        "--maze",
        "2",
        "--seed",
        "0",
        "--quiet",
        "--out",
        path(&out),
    ];
    let o = pbcs(&args);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("run.png"), "{}", stderr(&o));
    assert!(
        out.join("INCOMPLETE").exists(),
        "the folder is not marked incomplete: {:?}",
        std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect::<Vec<_>>()
    );
    let o = pbcs(&["eval", "--chain", path(&out.join("chain"))]);
    assert!(!o.status.success(), "eval used an incomplete run's chain");
    assert!(stderr(&o).contains("incomplete"), "{}", stderr(&o));
    // The obstacle gone, the same command completes the folder.
    std::fs::remove_dir_all(out.join("run.png")).unwrap();
    let o = pbcs(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!out.join("INCOMPLETE").exists());
    assert!(out.join("run.png").is_file());
    let o = pbcs(&[
        "eval",
        "--chain",
        path(&out.join("chain")),
        "--episodes",
        "5",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// `pbcs run --no-chaining` on the default preset runs PBCS without chaining: the switches
/// that act between skills (moved hand-overs, chain repairs) are turned off with it, and the
/// command says so.
#[test]
fn no_chaining_on_the_default_preset_turns_off_what_acts_between_skills() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = pbcs(&[
        "run",
        "--maze",
        "2",
        "--seed",
        "0",
        "--quiet",
        "--no-chaining",
        "--out",
        path(&out),
    ]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("phase2.retargets") && err.contains("phase2.chain_repairs"),
        "{err}"
    );
    let config = std::fs::read_to_string(out.join("config.toml")).unwrap();
    let job: pbcs::config::PbcsJob = toml::from_str(&config).unwrap();
    let ideas = job.phase2.ideas;
    assert!(!job.phase2.chaining);
    assert!(ideas.dead_walk.is_some_and(|d| d.retargets == 0));
    assert!(ideas.chain_check.is_some_and(|c| c.repairs == 0));
}
