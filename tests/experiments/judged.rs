//! The outside judge's rows (`s<seed>.gym.csv`, gymnasium-robotics' verdict on PBCS's PointMaze
//! chains) are read back checked: the committed ones give each cell's verdict, and a row that
//! contradicts itself, names another seed, judges another run than its row's, has another
//! judge, or is missing for one seed is refused naming the file.

use super::*;
use pbcs::tables::judged::judged_cells;

fn pointmaze() -> Experiment {
    Experiment::load(Path::new("experiments/pointmaze.toml"), None).unwrap()
}

#[test]
fn the_committed_verdicts_are_read_per_cell() {
    let exp = pointmaze();
    let rows = read_raw(&exp, Path::new("results")).unwrap();
    let cells = judged_cells(&exp, Path::new("results"), &rows).unwrap();
    let got: Vec<(&str, usize, usize)> = cells
        .iter()
        .map(|c| (c.gym_id.as_str(), c.seeds, c.solved))
        .collect();
    // Recounted from the rows as text: the `gym_solved` column of each seed, per map.
    let want_solved: Vec<usize> = ["umaze", "medium", "large"]
        .iter()
        .map(|m| {
            (0..10)
                .filter(|s| {
                    let path = format!("results/raw/pointmaze/pbcs_pm-pointmaze_{m}/s{s}.gym.csv");
                    let text = std::fs::read_to_string(path).unwrap();
                    let mut lines = text.lines();
                    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
                    let row: Vec<&str> = lines.next().unwrap().split(',').collect();
                    let i = header.iter().position(|h| *h == "gym_solved").unwrap();
                    row[i] == "true"
                })
                .count()
        })
        .collect();
    assert_eq!(got.len(), 3);
    for ((id, seeds, solved), want) in got.iter().zip(&want_solved) {
        assert!(id.starts_with("PointMaze_") && *seeds == 10, "{id} {seeds}");
        assert_eq!(solved, want, "{id}");
    }
}

/// A copy of the UMaze cell's rows with `edit` applied to seed 3's judged row.
fn refused(edit: impl Fn(&Path)) -> String {
    let tmp = tempfile::tempdir().unwrap();
    let exp = pointmaze();
    let from = Path::new("results/raw/pointmaze/pbcs_pm-pointmaze_umaze");
    let to = tmp.path().join("raw/pointmaze/pbcs_pm-pointmaze_umaze");
    std::fs::create_dir_all(&to).unwrap();
    for s in 0..10 {
        let name = format!("s{s}.gym.csv");
        std::fs::copy(from.join(&name), to.join(&name)).unwrap();
    }
    edit(&to.join("s3.gym.csv"));
    let rows = read_raw(&exp, Path::new("results")).unwrap();
    judged_cells(&exp, tmp.path(), &rows)
        .map(|c| format!("accepted: {c:?}"))
        .unwrap_err()
        .to_string()
}

#[test]
fn a_row_that_contradicts_itself_or_is_missing_is_refused_naming_the_file() {
    let text = std::fs::read_to_string("results/raw/pointmaze/pbcs_pm-pointmaze_umaze/s3.gym.csv")
        .unwrap();
    let row = text.lines().nth(1).unwrap().to_string();
    let fields: Vec<&str> = row.split(',').collect();
    let with = |i: usize, v: &str| {
        let mut f = fields.clone();
        f[i] = v;
        text.replace(&row, &f.join(","))
    };
    // Columns: cell 0, seed 1, gym_id 2, ..., env_steps 6, ..., gym_successes 10,
    // gym_episodes 11, gym_solved 12.
    for (bad, why) in [
        (with(12, "false"), "gym_solved"),
        (with(10, "101"), "successes"),
        (with(1, "4"), "seed 4"),
        (with(6, "1"), "judge the run again"),
        (with(2, "PointMaze_Open-v3"), "one judge per cell"),
    ] {
        let err = refused(|p| std::fs::write(p, &bad).unwrap());
        assert!(
            err.contains("s3.gym.csv") && err.contains(why),
            "{why}: {err}"
        );
    }
    let err = refused(|p| std::fs::remove_file(p).unwrap());
    assert!(
        err.contains("s3.gym.csv") && err.contains("missing"),
        "{err}"
    );
}
