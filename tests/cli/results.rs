//! The commands that read and write results folders and the Makefile around them: a folder
//! without rows is refused before anything is written, a folder another sweep holds is refused
//! at the sweep's start, and `make` runs the binary cargo builds.

use std::path::Path;
use std::process::Command;

use super::{path, pbcs, stderr};

/// The Makefile runs the binary cargo builds (before: a hard-coded `target/release/pbcs`,
/// rc 127 under `CARGO_TARGET_DIR`, and a stale binary never rebuilt), and `make paper`
/// without LaTeX says what to install before building anything. Needs `make` (skipped, with a
/// message, where it is absent).
#[test]
fn the_makefile_uses_cargos_binary_and_checks_latex_first() {
    let make = |args: &[&str], env: &[(&str, &str)]| {
        let mut c = Command::new("make");
        c.args(args).envs(env.iter().copied());
        c.output()
    };
    let Ok(o) = make(
        &["-n", "cell", "EXP=table", "CELL=ddpg-maze2", "SEED=0"],
        &[("CARGO_TARGET_DIR", "/elsewhere/tgt")],
    ) else {
        eprintln!("make is not installed: skipped");
        return;
    };
    let plan = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    // The `bin` prerequisite always asks cargo (which rebuilds a stale binary), then runs the
    // binary where cargo put it.
    assert!(plan.contains("cargo build --release"), "{plan}");
    assert!(
        plan.contains("/elsewhere/tgt/release/pbcs exp check experiments/table.toml --cell ddpg-maze2 --seed 0"),
        "{plan}"
    );
    // `make paper` with no latexmk on PATH (a PATH holding only `make`): a clear message,
    // exit 2, nothing built.
    let which = Command::new("sh")
        .args(["-c", "command -v make"])
        .output()
        .unwrap();
    let make_path = String::from_utf8_lossy(&which.stdout).trim().to_string();
    let bin = tempfile::tempdir().unwrap();
    std::os::unix::fs::symlink(&make_path, bin.path().join("make")).unwrap();
    let o = Command::new(bin.path().join("make"))
        .arg("paper")
        .env("PATH", bin.path())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("needs latexmk") && out.contains("apt install"),
        "{out}"
    );
}

/// Before: `pbcs figures --results <a folder that does not exist>` printed "wrote 2 files",
/// replacing the committed paper/generated/numbers.tex and claims.tex with empty ones (the
/// LaTeX went to paper/generated whatever `--results` held), exit 0; `pbcs aggregate` on a
/// missing or empty folder exited 0 too. Both refuse such a folder, naming it, and write
/// nothing; the LaTeX of another results folder defaults to `<results>/tex`.
#[test]
fn aggregate_and_figures_refuse_a_results_folder_without_rows() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let committed = || {
        ["numbers.tex", "claims.tex"]
            .map(|name| std::fs::read(root.join("paper/generated").join(name)).unwrap())
    };
    let before = committed();
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing");
    let empty = dir.path().join("empty");
    std::fs::create_dir_all(empty.join("raw")).unwrap();
    let figures = dir.path().join("figures");
    for (results, aggregate_says, figures_says) in [
        (&missing, "no such results folder", "no such results folder"),
        (&empty, "holds no raw row", "holds no table"),
    ] {
        let o = pbcs(&["aggregate", "--results", path(results)]);
        assert!(!o.status.success(), "aggregate {}", path(results));
        let e = stderr(&o);
        assert!(
            e.contains(path(results)) && e.contains(aggregate_says),
            "{e}"
        );
        let o = pbcs(&[
            "figures",
            "--results",
            path(results),
            "--figures",
            path(&figures),
        ]);
        assert!(!o.status.success(), "figures {}", path(results));
        let e = stderr(&o);
        assert!(e.contains(path(results)) && e.contains(figures_says), "{e}");
    }
    assert_eq!(committed(), before, "paper/generated was written");
    assert!(!figures.exists() && !missing.exists());
    assert!(!empty.join("tex").exists() && !empty.join("tables").exists());
    // Where the LaTeX goes: paper/generated only for the committed results folder.
    use pbcs::pipeline::tex_dir;
    let generated = Path::new("paper/generated");
    assert_eq!(tex_dir(None, None, Path::new("results")), generated);
    assert_eq!(tex_dir(None, None, &empty), empty.join("tex"));
    let smoke = Path::new("results-smoke");
    assert_eq!(tex_dir(None, Some("smoke"), smoke), smoke.join("tex"));
    let tex = Path::new("elsewhere");
    assert_eq!(tex_dir(Some(tex), None, &empty), tex);
}

/// Before: a second sweep on one results folder took the runs the first had planned, and the
/// first died between two runs. A sweep on a folder another sweep holds is refused at its
/// start, naming the folder, and runs nothing.
#[test]
fn a_sweep_on_a_results_folder_in_use_is_refused_at_its_start() {
    let dir = tempfile::tempdir().unwrap();
    let held = pbcs::record::FolderLock::acquire(dir.path(), false).unwrap();
    let o = pbcs(&[
        "exp",
        "run",
        "experiments/table.toml",
        "--profile",
        "smoke",
        "--results",
        path(dir.path()),
    ]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains(path(dir.path())) && e.contains("in use"), "{e}");
    assert!(!dir.path().join("raw").exists(), "a run went ahead");
    drop(held);
}

/// A run whose checkpoint is not one (here: a few bytes where `s0.resume` belongs) is announced
/// as resuming, then refused with the file named and what to do; the file is left as it was and
/// no row is written. Deleted, the run goes afresh and logs its evaluations.
#[test]
fn a_sweep_refuses_a_bad_checkpoint_naming_it_and_keeps_it() {
    let dir = tempfile::tempdir().unwrap();
    let args = [
        "exp",
        "run",
        "experiments/table.toml",
        "--profile",
        "smoke",
        "--cell",
        "td3-maze2",
        "--results",
        path(dir.path()),
    ];
    let cell = dir.path().join("raw/table/td3-maze2");
    std::fs::create_dir_all(&cell).unwrap();
    let bad = cell.join("s0.resume");
    std::fs::write(&bad, b"half a checkpoint").unwrap();
    let o = pbcs(&args);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("td3-maze2 seed 0: resumes from"), "{e}");
    assert!(
        e.contains(path(&bad)) && e.contains("delete it to start the run afresh"),
        "{e}"
    );
    assert_eq!(std::fs::read(&bad).unwrap(), b"half a checkpoint");
    assert!(!cell.join("s0.csv").exists(), "a row was written");
    // Deleted as it says, the run starts afresh and ends with its row, and no checkpoint; the
    // log (no terminal) shows the run's evaluations as it goes (at most one line a minute).
    std::fs::remove_file(&bad).unwrap();
    let o = pbcs(&args);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(cell.join("s0.csv").exists() && !bad.exists());
    assert!(
        e.contains("td3-maze2 seed 0: ") && e.contains("env steps, greedy success"),
        "{e}"
    );
}

/// `--stop-after`: a deadline already past begins no run; the exit status is 75 (EX_TEMPFAIL)
/// with what to do, and nothing is written. A duration that is not one, or one past what the
/// clock holds, is refused by name.
/// Run again with a deadline an hour ahead, the sweep runs.
#[test]
fn a_sweep_past_its_deadline_begins_nothing_and_exits_75() {
    let dir = tempfile::tempdir().unwrap();
    let mut args = vec![
        "exp",
        "run",
        "experiments/table.toml",
        "--profile",
        "smoke",
        "--cell",
        "td3-maze2",
        "--results",
        path(dir.path()),
    ];
    let o = pbcs(&[&args[..], &["--stop-after", "0s"]].concat());
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(75), "{e}");
    assert!(
        e.contains("stopped at the deadline") && e.contains("run the same command again"),
        "{e}"
    );
    let cell = dir.path().join("raw/table/td3-maze2");
    assert!(!cell.join("s0.csv").exists() && !cell.join("s0.resume").exists());
    let o = pbcs(&[&args[..], &["--stop-after", "soon"]].concat());
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("--stop-after"), "{e}");
    // A deadline past what the clock can hold is refused, not a panic: since issue 77 by the
    // parser, as anything past a year is.
    let o = pbcs(&[&args[..], &["--stop-after", "500000000000y"]].concat());
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("--stop-after") && e.contains("more than a year"),
        "{e}"
    );
    args.extend(["--stop-after", "1h"]);
    let o = pbcs(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(cell.join("s0.csv").exists() && !cell.join("s0.resume").exists());
}

/// `pbcs run --stop-after`: a deadline already past stops the run at the end of its first
/// learning problem, saved to <OUT>/run.resume, with exit status 75 and no record; the same
/// command without it goes on and writes the record, trace, skills and chain of a run never
/// stopped, byte for byte, and the checkpoint goes.
#[test]
fn pbcs_run_stopped_at_its_deadline_goes_on_to_the_same_files() {
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let args = |out: &Path| {
        let out = path(out).to_string();
        let run = ["run", "--maze", "3", "--seed", "1", "--quiet", "--out"];
        run.iter()
            .map(|s| s.to_string())
            .chain([out])
            .collect::<Vec<_>>()
    };
    let strs = |v: &[String]| v.iter().map(String::as_str).collect::<Vec<_>>().join(" ");
    let call = |v: Vec<String>| {
        let v: Vec<&str> = v.iter().map(String::as_str).collect();
        pbcs(&v)
    };
    let o = call(args(a.path()));
    assert!(o.status.success(), "{}", stderr(&o));
    let mut stopped = args(b.path());
    stopped.extend(["--stop-after".into(), "0s".into()]);
    let o = call(stopped.clone());
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(75), "{}: {e}", strs(&stopped));
    assert!(e.contains("run the same command again"), "{e}");
    assert!(b.path().join("run.resume").exists() && !b.path().join("record.csv").exists());
    let o = call(args(b.path()));
    assert!(o.status.success(), "{}", stderr(&o));
    for file in [
        "record.csv",
        "trace.csv",
        "skills.csv",
        "chain/manifest.toml",
    ] {
        let read = |dir: &Path| std::fs::read(dir.join(file)).unwrap();
        assert_eq!(read(a.path()), read(b.path()), "{file}");
    }
    assert!(!b.path().join("run.resume").exists());
}
