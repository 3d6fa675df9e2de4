//! Absurd values in an experiment file (issue 47, found by probing ~150 bad inputs): each is a
//! clear error naming its field — never a panic ("capacity overflow"), an abort (an 800 GB
//! allocation) or a sweep of nothing that exits 0.

use pbcs::config::{load, PbcsJob, TrainJob};
use pbcs::experiment::Experiment;

#[test]
fn absurd_values_are_refused_naming_their_field() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy("experiments/pbcs_paper.toml", dir.path().join("base.toml")).unwrap();
    std::fs::copy("experiments/baseline.toml", dir.path().join("vanilla.toml")).unwrap();
    let head = "title = \"t\"\nseeds = 2\nmazes = [2]\n";
    let method = |name: &str, set: &str| {
        format!("[[method]]\nname = \"{name}\"\nkind = \"pbcs\"\nbase = \"base.toml\"\nset = {{ {set} }}\n")
    };
    let cases = [
        // Absurd values (issue 47): each a clear error naming its field, never a panic, an
        // abort or a silent sweep of nothing.
        (
            format!(
                "title = \"t\"\nseeds = 18446744073709551615\nmazes = [2]\n{}",
                method("a", "")
            ),
            "invalid `seeds`: 18446744073709551615: needs 1 to 100000 seeds",
        ),
        (
            format!(
                "title = \"t\"\nseeds = 100000000000\nmazes = [2]\n{}",
                method("a", "")
            ),
            "needs 1 to 100000 seeds",
        ),
        (
            format!(
                "first_seed = 18446744073709551615\n{head}{}",
                method("a", "")
            ),
            "invalid `first_seed`: 18446744073709551615 + 2 seeds passes the largest seed",
        ),
        (
            format!("picture_seeds = [50]\n{head}{}", method("a", "")),
            "invalid `picture_seeds`: 50 is not one of the grid's seeds 0..=1",
        ),
        (
            format!("{head}{}", method("a", "learner.argmax_samples = 0")),
            "learner.argmax_samples",
        ),
        (
            format!(
                "{head}[[method]]\nname = \"v\"\nkind = \"vanilla\"\nbase = \"vanilla.toml\"\n\
                 set = {{ train.steps = 5000, train.learning_starts = 6000 }}\n"
            ),
            "invalid `train.learning_starts`: 6000 of train.steps = 5000: the learner would never update",
        ),
        // A map of one's own set by a method rather than the file's [pointmaze], a site
        // `pointmaze` without a map, and a map with no such site (issue 47).
        (
            format!("{head}{}", method("a", "pointmaze.time_limit = 500")),
            "invalid `pointmaze`: method `a`: sets [pointmaze]",
        ),
        (
            format!("title = \"t\"\nseeds = 2\nenvs = [\"pointmaze\"]\n{}", method("a", "")),
            "invalid `pointmaze`: the sites `pointmaze` and `antmaze` run a map of one's own",
        ),
        (
            format!("{head}[pointmaze]\nmap = [\"1111\", \"1001\", \"1111\"]\n{}", method("a", "")),
            "nor `antmaze` is one of the file's `envs`",
        ),
    ];
    for (i, (text, needle)) in cases.iter().enumerate() {
        let path = dir.path().join(format!("bad{i}.toml"));
        std::fs::write(&path, text).unwrap();
        let err = Experiment::load(&path, None).unwrap_err().to_string();
        assert!(
            err.contains(needle),
            "case {i}: `{err}` does not name `{needle}`"
        );
    }
    // A profile's seeds are held to the same bounds, named as the profile's.
    let path = dir.path().join("profiled.toml");
    std::fs::write(
        &path,
        format!("{head}{}[profile.p]\nseeds = 0\n", method("a", "")),
    )
    .unwrap();
    let err = Experiment::load(&path, Some("p")).unwrap_err().to_string();
    assert!(
        err.contains("invalid `profile.p.seeds`: 0: needs 1 to"),
        "{err}"
    );
    // A registered preset that no method runs, or beside a method of its kind on another base.
    std::fs::copy("experiments/pbcs_fast.toml", dir.path().join("other.toml")).unwrap();
    let registered =
        "[registered]\npreset = \"base.toml\"\nsha256 = \"00\"\ndate = \"2026-12-01\"\n";
    let other = |name: &str| method(name, "").replace("base.toml", "other.toml");
    for (text, needle) in [
        (
            format!("{head}{registered}{}", other("a")),
            "registered.preset: base.toml is the base of no method",
        ),
        (
            format!("{head}{registered}{}{}", method("a", ""), other("b")),
            "method `b`: runs on other.toml, but the grid is registered for base.toml",
        ),
    ] {
        std::fs::write(&path, text).unwrap();
        let err = Experiment::load(&path, None).unwrap_err().to_string();
        assert!(err.contains(needle), "`{err}` does not name `{needle}`");
    }
    // The pictures a profile inherits from the file are among the profile's seeds too: seed 1
    // of a grid of 2, under a profile of one seed, would never be drawn.
    std::fs::write(
        &path,
        format!(
            "picture_seeds = [1]\n{head}{}[profile.p]\nseeds = 1\n",
            method("a", "")
        ),
    )
    .unwrap();
    let err = Experiment::load(&path, Some("p")).unwrap_err().to_string();
    assert!(
        err.contains("invalid `picture_seeds`: 1 is not one of the grid's seeds 0..=0"),
        "{err}"
    );
    Experiment::load(&path, None).unwrap();
}

/// A job file with `text` in a fresh folder.
fn write_job(text: &str) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("job.toml");
    std::fs::write(&path, text).unwrap();
    (dir, path)
}

/// `pbcs ARGS` here: its exit code and its standard error, which holds no panic.
fn pbcs_cli(args: &[&str]) -> (i32, String) {
    super::pbcs_in(std::path::Path::new("."), args)
}

/// Every count a job can set has an upper bound, checked when the file is read: the values a
/// probe found to panic, abort or run without end are each refused naming their field, before
/// any work (none of them reaches an allocation or a loop).
/// Whether error `e` names `table.key`: as the check names a field, or, for a value past
/// TOML's integers (u64::MAX), as the parser does, with the file and the key's line.
fn names(e: &str, table: &str, key: &str) -> bool {
    e.contains(&format!("{table}.{key}")) || (e.contains("job.toml") && e.contains(key))
}

#[test]
fn every_count_has_an_upper_bound_checked_at_load() {
    let huge = ["1000000000000", "18446744073709551615", "100000000000"];
    let pbcs_fields = [
        ("learner", "replay_size"),
        ("learner", "batch_size"),
        ("learner", "argmax_samples"),
        ("phase2", "alpha"),
        ("phase2", "beta"),
        ("phase2", "max_steps"),
        ("phase2", "eval_episodes"),
        ("phase2", "eval_max_steps"),
        ("phase2", "verify_episodes"),
        ("phase2", "chain_verify_episodes"),
        // The re-probe (issue 77): budgets ran on for hours, repeats were unbounded.
        ("phase2", "max_env_steps"),
        ("phase2", "restarts"),
        ("phase2", "retargets"),
        ("phase2", "chain_repairs"),
        ("explore", "budget"),
    ];
    for (table, key) in pbcs_fields {
        for v in huge {
            let (_dir, path) = write_job(&format!("[{table}]\n{key} = {v}\n"));
            let e = load::<PbcsJob>(&path).unwrap_err().to_string();
            assert!(names(&e, table, key), "{table}.{key} = {v}: {e}");
        }
    }
    for (table, key) in [
        ("train", "max_episode_steps"),
        ("train", "eval_episodes"),
        ("train", "final_eval_episodes"),
        ("train", "final_eval_max_steps"),
        ("train", "steps"),
        ("train", "eval_every"),
        ("train.her", "n_sampled_goal"),
    ] {
        for v in huge {
            let (_dir, path) = write_job(&format!("[{table}]\n{key} = {v}\n"));
            let e = load::<TrainJob>(&path).unwrap_err().to_string();
            assert!(names(&e, table, key), "{table}.{key} = {v}: {e}");
        }
    }
    for hidden in [
        "[1000000000, 1000000000]",
        "[64, 64, 64, 64, 64, 64, 64, 64, 64, 64, 64, 64, 64, 64, 64, 64, 64]",
    ] {
        let (_dir, path) = write_job(&format!("[learner]\nhidden = {hidden}\n"));
        let e = load::<PbcsJob>(&path).unwrap_err().to_string();
        assert!(e.contains("learner.hidden"), "{hidden}: {e}");
    }
    // A batch larger than the whole run: the replay never holds one, the learner never updates.
    let (_dir, path) = write_job("[train]\nsteps = 2000\nlearning_starts = 0\n[learner]\nbatch_size = 100000000\nreplay_size = 100000000\n");
    let e = load::<TrainJob>(&path).unwrap_err().to_string();
    assert!(
        e.contains("learner.batch_size") && e.contains("never update"),
        "{e}"
    );
    // The defaults and the bounds themselves are accepted.
    let (_dir, path) = write_job("[phase2]\nbeta = 100000\n[learner]\nhidden = [16384]\n");
    load::<PbcsJob>(&path).unwrap();
    // The command line's counts too: `pbcs eval --episodes` past its bound is refused by the
    // parser, before the chain is read.
    for v in ["18446744073709551615", "100000000000"] {
        let (code, err) = pbcs_cli(&["eval", "--chain", "/nonexistent", "--episodes", v]);
        assert!(code != 0 && err.contains("--episodes"), "{v}: {code} {err}");
    }
}

/// A profile's grid is no shelter for a bad committed grid: `exp list FILE --profile smoke`
/// (what CI checks) validates the whole file too.
#[test]
fn a_profile_validates_the_whole_grid_too() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy("experiments/pbcs_paper.toml", dir.path().join("base.toml")).unwrap();
    let method = "[[method]]\nname = \"a\"\nkind = \"pbcs\"\nbase = \"base.toml\"\n";
    for (grid, needle) in [("mazes = [100000]", "maze"), ("mazes = [2, 2]", "unique")] {
        let text = format!(
            "title = \"t\"\nseeds = 2\n{method}{grid}\n[profile.smoke]\nmazes = [2]\nseeds = 1\n"
        );
        let text = text.replacen(
            &format!("{method}{grid}\n"),
            &format!("{grid}\n{method}"),
            1,
        );
        let path = dir.path().join("grid.toml");
        std::fs::write(&path, &text).unwrap();
        let whole = Experiment::load(&path, None)
            .map(|_| ())
            .unwrap_err()
            .to_string();
        let smoke = Experiment::load(&path, Some("smoke"))
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert_eq!(whole, smoke, "{grid}");
        assert!(whole.contains(needle), "{grid}: {whole}");
    }
}

/// `pbcs run --out` a sweep's results folder or one of its cell folders is refused before any
/// work, the folder left as it was.
#[test]
fn a_run_into_a_sweeps_results_is_refused() {
    for plant in ["sweep.lock", "raw/", "s3.csv"] {
        let dir = tempfile::tempdir().unwrap();
        match plant.strip_suffix('/') {
            Some(folder) => std::fs::create_dir_all(dir.path().join(folder)).unwrap(),
            None => std::fs::write(dir.path().join(plant), "").unwrap(),
        }
        let before = std::fs::read_dir(dir.path()).unwrap().count();
        let out = dir.path().to_str().unwrap();
        let (code, err) = pbcs_cli(&["run", "--maze", "2", "--seed", "0", "--quiet", "--out", out]);
        assert!(
            code != 0 && err.contains("holds a sweep's results"),
            "{plant}: {code} {err}"
        );
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            before,
            "{plant}"
        );
    }
    // Inside a results folder's raw rows (its raw/ folder, a cell's), into a saved chain, or a
    // sweep's results folder there: refused too, nothing made.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("sweep.lock"), "").unwrap();
    let chain = dir.path().join("run/chain");
    std::fs::create_dir_all(&chain).unwrap();
    std::fs::write(chain.join("manifest.toml"), "").unwrap();
    let raw = dir.path().join("raw");
    for (out, needle) in [
        (raw.clone(), "lies inside"),
        (raw.join("table/ddpg-maze2"), "lies inside"),
        (chain.clone(), "holds a saved chain"),
    ] {
        let o = out.to_str().unwrap();
        let (code, err) = pbcs_cli(&["run", "--maze", "2", "--seed", "0", "--quiet", "--out", o]);
        assert!(code != 0 && err.contains(needle), "{o}: {code} {err}");
    }
    let o = raw.join("table");
    let args = [
        "table",
        "--sizes",
        "2",
        "--seeds",
        "1",
        "--out",
        o.to_str().unwrap(),
    ];
    let (code, err) = pbcs_cli(&args);
    assert!(code != 0 && err.contains("lies inside"), "{code} {err}");
    assert!(!raw.exists(), "nothing was made");
}
