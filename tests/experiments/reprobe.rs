//! What issue 77's re-probe (`scripts/probe-hostile.py`, 1018 hostile inputs) found still
//! accepted or vaguely refused: each is now refused before any work, naming its field or flag.

use super::*;

#[test]
fn counts_of_the_command_line_are_bounded_and_flags_take_negative_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let grid = std::fs::canonicalize("experiments/table.toml").unwrap();
    let grid = grid.to_str().unwrap();
    let smoke = [
        "exp",
        "run",
        grid,
        "--profile",
        "smoke",
        "--cell",
        "ddpg-maze2",
    ];
    let cases: Vec<(Vec<&str>, &str)> = vec![
        ([&smoke[..], &["--jobs", "100000"]].concat(), "--jobs"),
        (
            [&smoke[..], &["--jobs", "18446744073709551615"]].concat(),
            "--jobs",
        ),
        (
            [&smoke[..], &["--stop-after", "99999999999h"]].concat(),
            "--stop-after",
        ),
        (
            vec!["run", "--maze", "2", "--stop-after", "99999999999h"],
            "--stop-after",
        ),
        (
            vec!["run", "--maze", "2", "--quiet", "--gamma", "-0.1"],
            "gamma",
        ),
        (
            vec!["train", "--maze", "2", "--quiet", "--gamma", "-0.1"],
            "gamma",
        ),
    ];
    for (args, needle) in cases {
        let (code, err) = pbcs_in(dir.path(), &args);
        assert!(code != 0 && err.contains(needle), "{args:?}: {code} {err}");
    }
    assert!(!dir.path().join("results-smoke").exists(), "nothing ran");
}

#[test]
fn a_grid_refuses_what_it_would_silently_replace_or_cannot_name() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy("experiments/pbcs_paper.toml", dir.path().join("base.toml")).unwrap();
    let head = "title = \"t\"\nseeds = 2\nmazes = [2]\n";
    let method = |name: &str, base: &str, set: &str| {
        format!("[[method]]\nname = \"{name}\"\nkind = \"pbcs\"\nbase = \"{base}\"\nset = {{ {set} }}\n")
    };
    let long = "x".repeat(5000);
    let cases = [
        (
            method("a", "base.toml", "maze.size = 100000"),
            "invalid `maze.size`: method `a` sets it",
        ),
        (
            method("a", "base.toml", "seed = 3"),
            "invalid `seed`: method `a` sets it",
        ),
        (method(&long, "base.toml", ""), "(5000 characters)"),
        (
            method("a", "", ""),
            "invalid `base`: method `a`: \"\" is not a file",
        ),
        (
            format!(
                "{}[by_maze.2.pbcs]\nmaze.size = 7\n",
                method("a", "base.toml", "")
            ),
            "by_maze.2 sets it",
        ),
    ];
    for (i, (methods, needle)) in cases.iter().enumerate() {
        let path = dir.path().join(format!("grid{i}.toml"));
        std::fs::write(&path, format!("{head}{methods}")).unwrap();
        let err = Experiment::load(&path, None)
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(
            err.contains(needle) && err.contains(&format!("grid{i}.toml")) && err.len() < 1000,
            "case {i}: {err}"
        );
    }
}
