//! The Makefile runs every experiment file: `make results` (EXPERIMENTS) every one, skipping in a
//! build without MuJoCo exactly those `make pointmaze` (MUJOCO_EXPERIMENTS) runs, and the skip
//! message names that target. Both lists are read from the files by make; this holds them to
//! what the library says each grid is and needs.

use super::files;
use pbcs::experiment::{Experiment, MUJOCO_TARGET};
use std::collections::BTreeSet;

/// What `make -s <target>` prints, as a set of words.
fn make_words(target: &str) -> BTreeSet<String> {
    let out = std::process::Command::new("make")
        .args(["-s", "--no-print-directory", target])
        .output()
        .expect("make runs");
    assert!(out.status.success(), "make {target}: {out:?}");
    String::from_utf8(out.stdout)
        .unwrap()
        .split_whitespace()
        .map(String::from)
        .collect()
}

#[test]
fn every_experiment_file_is_run_by_a_make_target_and_the_skip_names_it() {
    let all = make_words("experiments");
    let mujoco = make_words("mujoco-experiments");
    let makefile = std::fs::read_to_string("Makefile").unwrap();
    // Each target loops over its list.
    assert!(makefile.contains("for e in $(EXPERIMENTS); do $(PBCS) exp run experiments/$$e.toml"));
    assert!(makefile.contains(&format!("{MUJOCO_TARGET}: mujoco python")));
    assert!(makefile
        .contains("for e in $(MUJOCO_EXPERIMENTS); do $(PBCS) exp run experiments/$$e.toml"));
    let mut seen = BTreeSet::new();
    for path in files() {
        let exp = Experiment::load(&path, None).unwrap();
        let name = exp.name.to_string();
        assert!(all.contains(&name), "{name} is in no make target's list");
        let needs = exp.features().contains(&"mujoco");
        assert_eq!(mujoco.contains(&name), needs, "{name}: MUJOCO_EXPERIMENTS");
        if needs && !cfg!(feature = "mujoco") {
            let why = exp
                .unavailable()
                .expect("a MuJoCo grid is unavailable here");
            assert!(why.contains(&format!("`make {MUJOCO_TARGET}`")), "{why}");
        }
        seen.insert(name);
    }
    assert_eq!(all, seen, "EXPERIMENTS lists exactly the experiment files");
    // The committed grids that need MuJoCo, among them the two the list once missed.
    for name in ["pointmaze", "pointmaze_her", "sac_skills"] {
        assert!(mujoco.contains(name), "{name}");
    }
}
