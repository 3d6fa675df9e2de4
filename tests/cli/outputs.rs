//! Output folders: a path that is a file, a folder of another run, the same job again. Each
//! is refused before any work (or, for the same job, gives the same bytes).

use super::{path, pbcs, stderr};

/// Before: `pbcs run --out FILE` trained for the whole run, then failed with "File exists".
#[test]
fn an_output_path_that_is_a_file_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("f");
    std::fs::write(&file, "x").unwrap();
    for command in ["run", "explore", "train"] {
        let o = pbcs(&[
            command,
            "--maze",
            "2",
            "--seed",
            "0",
            "--quiet",
            "--out",
            path(&file),
        ]);
        assert!(!o.status.success(), "{command}");
        let e = stderr(&o);
        assert!(
            e.contains("not a folder") && e.contains(path(&file)),
            "{command}: {e}"
        );
        assert!(!e.contains("PBCS on") || e.contains("not a folder"), "{e}");
        assert_eq!(
            std::fs::read_to_string(&file).unwrap(),
            "x",
            "the file is untouched"
        );
    }
}

/// Before: `eval`, `table`, `exp run` and `figures` given a file for a folder said only `File
/// exists (os error 17)`. Each names the path and says it is not a folder, before any work.
#[test]
fn every_command_names_an_output_folder_that_is_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("f");
    std::fs::write(&file, "x").unwrap();
    let run = dir.path().join("run");
    let o = pbcs(&[
        "run",
        "--maze",
        "2",
        "--seed",
        "0",
        "--quiet",
        "--out",
        path(&run),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let chain = run.join("chain");
    let under = file.join("sub");
    let commands: Vec<Vec<&str>> = vec![
        vec![
            "eval",
            "--chain",
            path(&chain),
            "--episodes",
            "2",
            "--out",
            path(&file),
        ],
        vec![
            "eval",
            "--chain",
            path(&chain),
            "--episodes",
            "2",
            "--out",
            path(&under),
        ],
        vec![
            "table",
            "--sizes",
            "2",
            "--seeds",
            "1",
            "--out",
            path(&file),
        ],
        vec![
            "exp",
            "run",
            "experiments/table.toml",
            "--profile",
            "smoke",
            "--cell",
        ]
        .into_iter()
        .chain(["ddpg-maze2", "--results", path(&file)])
        .collect(),
        vec![
            "figures",
            "--results",
            "results",
            "--figures",
            path(&file),
            "--tex",
            path(&run),
        ],
        vec![
            "figures",
            "--results",
            "results",
            "--figures",
            path(&run),
            "--tex",
            path(&file),
        ],
    ];
    for args in commands {
        let o = pbcs(&args);
        let e = stderr(&o);
        assert!(!o.status.success(), "{args:?}");
        assert!(
            e.contains(&format!("{}: exists and is not a folder", path(&file))),
            "{args:?}: {e}"
        );
        assert_eq!(std::fs::read_to_string(&file).unwrap(), "x", "{args:?}");
    }
}

/// Before: a run with another config silently replaced a solved run in the default folder.
#[test]
fn a_folder_holding_another_run_is_refused_and_left_intact() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("config.toml"), "seed = 99\n").unwrap();
    std::fs::write(out.join("record.csv"), "precious\n").unwrap();
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
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("holds another run"), "{e}");
    assert_eq!(
        std::fs::read_to_string(out.join("record.csv")).unwrap(),
        "precious\n"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("config.toml")).unwrap(),
        "seed = 99\n"
    );
}

/// The same job into its own folder again is allowed (runs are deterministic) and gives the
/// same bytes.
#[test]
fn rerunning_the_same_job_into_its_folder_gives_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("explore");
    let args = [
        "explore",
        "--maze",
        "3",
        "--seed",
        "1",
        "--quiet",
        "--out",
        path(&out),
    ];
    assert!(pbcs(&args).status.success());
    let first = std::fs::read(out.join("trajectory.csv")).unwrap();
    let o = pbcs(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read(out.join("trajectory.csv")).unwrap(), first);
}
