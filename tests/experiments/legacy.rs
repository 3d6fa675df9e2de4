//! The committed rows that may lack their evaluation, and every other row that may not.

use super::*;
use pbcs::experiment::{read_run_row, run_file};

/// A row without the file it summarises is refused, PBCS's (its evaluation) and vanilla's
/// (its curve), unless it is one of the committed rows listed as written before runs wrote
/// that file (`results/raw/legacy_without_evaluation.txt`), each of which exists and lacks it.
#[test]
fn a_row_without_its_evaluation_is_refused_unless_listed_as_written_before_it() {
    for (file, cell_id, seed, ext) in [
        (
            "experiments/ablations.toml",
            "as_written-maze5",
            0,
            ".evaluation.csv",
        ),
        ("experiments/table.toml", "ddpg-maze2", 0, ".evals.csv"),
    ] {
        let exp = Experiment::load(Path::new(file), None).unwrap();
        let cell = exp.cell(cell_id).unwrap();
        let from = exp.cell_dir(Path::new("results"), cell);
        let tmp = tempfile::tempdir().unwrap();
        let to = exp.cell_dir(&tmp.path().join("results"), cell);
        std::fs::create_dir_all(&to).unwrap();
        for ext in [".csv", ".toml", ".timing.toml"] {
            let name = format!("s{seed}{ext}");
            std::fs::copy(from.join(&name), to.join(&name)).unwrap();
        }
        let path = run_file(&to, seed, ".csv");
        let err = read_run_row(&exp, cell, seed, &path)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains(&format!("s{seed}{ext} is missing")) && err.contains("success_rate"),
            "{cell_id}: {err}"
        );
    }
    // Every listed row exists, is a PBCS row, and lacks its evaluation; and it is read.
    let list = std::fs::read_to_string("results/raw/legacy_without_evaluation.txt").unwrap();
    let rows: Vec<&str> = list.lines().filter(|l| !l.starts_with('#')).collect();
    assert!(!rows.is_empty());
    for row in rows {
        let path = Path::new("results/raw").join(row);
        assert!(path.is_file(), "{row}");
        let evaluation = path.with_extension("evaluation.csv");
        assert!(
            !evaluation.exists(),
            "{row} has its evaluation: its line should go"
        );
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.lines().nth(1).unwrap().contains(",pbcs,"), "{row}");
    }
}
