//! Experiment files: every file parses under every profile with unique cells, bad files are
//! rejected with the field named, and the smoke profile runs end to end to tables and figures,
//! deterministically and resumably.

use pbcs::experiment::{experiment_files, plan, read_raw, sweep, Event, Experiment};
use std::collections::BTreeSet;
use std::path::Path;
use std::sync::Mutex;

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
