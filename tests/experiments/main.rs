//! Experiment files: every file parses under every profile with unique cells, bad files are
//! rejected with the field named, and the smoke profile runs end to end to tables and figures,
//! deterministically and resumably.

use pbcs::experiment::{experiment_files, plan, read_raw, sweep, Event, Experiment};
use std::collections::BTreeSet;
use std::path::Path;
use std::sync::Mutex;

/// `pbcs ARGS` in `dir`: its exit code and standard error, which holds no panic.
pub(crate) fn pbcs_in(dir: &Path, args: &[&str]) -> (i32, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_pbcs"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "panic on {args:?}: {stderr}");
    (out.status.code().unwrap_or(-1), stderr)
}

fn files() -> Vec<std::path::PathBuf> {
    experiment_files(Path::new("experiments")).unwrap()
}

mod absurd;
mod baselines;
mod committed;
#[path = "../common/cut_run.rs"]
mod cut_run;
mod files;
mod judged;
mod legacy;
mod locks;
mod make_targets;
mod reprobe;
mod rows;
mod sweeps;
mod tables_read;
