//! The held-out grid (`experiments/heldout.toml`) was registered before it ran, for the
//! `fast` preset as it was then: its recorded SHA-256 must still be the preset file's.

use pbcs::experiment::Experiment;
use sha2::{Digest, Sha256};
use std::path::Path;

#[test]
fn the_held_out_grid_runs_the_preset_it_was_registered_for() {
    let exp = Experiment::load(Path::new("experiments/heldout.toml"), None).unwrap();
    let reg = exp
        .registered
        .clone()
        .expect("heldout.toml has a [registered] table");
    let preset = std::fs::read(Path::new("experiments").join(&reg.preset)).unwrap();
    let hash: String = Sha256::digest(&preset)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    assert_eq!(
        hash, reg.sha256,
        "experiments/{} changed since the held-out grid was registered on {}: its rows no longer \
         test the preset as it is. Register a new grid on new layouts (and say so in the report); \
         do not update this hash.",
        reg.preset, reg.date
    );
    // The grid is the one registered: every method runs that preset on a layout of its own.
    for c in &exp.cells {
        let pbcs::experiment::Job::Pbcs(j) = &c.job else {
            panic!("{}: not a PBCS cell", c.id)
        };
        assert!([2611, 2612].contains(&j.maze.seed), "{}", c.id);
    }
    assert_eq!(exp.mazes, [8, 16, 24, 32]);
    let runs: usize = exp.cells.iter().map(|c| exp.seeds_of(c).len()).sum();
    assert_eq!(runs, 2 * (10 + 10 + 5 + 3));
}
