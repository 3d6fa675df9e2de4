//! A run folder is written completely or marked incomplete (issue 33, probe 11): before, a
//! full disk in the middle of `pbcs run` left `record.csv` saying "solved" beside a chain
//! without its manifest, and nothing marked the folder. `write_run_folder` (what `pbcs run`,
//! `explore`, `train` and `pbcs.run(out=...)` write through) fills a temporary folder, then
//! moves its files into place under an `INCOMPLETE` marker removed last.

use pbcs::record::{check_complete, write_run_folder, INCOMPLETE};
use std::path::Path;

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// A run's files: `record.csv` and `chain/manifest.toml` holding `text`.
fn fill(dir: &Path, text: &str) {
    std::fs::write(dir.join("record.csv"), text).unwrap();
    std::fs::create_dir(dir.join("chain")).unwrap();
    std::fs::write(dir.join("chain").join("manifest.toml"), text).unwrap();
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap()
}

#[test]
fn a_run_folder_is_written_whole_or_marked_incomplete() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    write_run_folder(&out, |d| {
        fill(d, "old");
        Ok(())
    })
    .unwrap();
    assert_eq!(names(&out), ["chain", "record.csv"]);
    check_complete(&out).unwrap();

    // A failure while the files are written (a full disk, say) leaves the folder as it was:
    // the earlier finished run stays whole, and no temporary folder is left behind.
    let err = write_run_folder(&out, |d| {
        std::fs::write(d.join("record.csv"), "new").unwrap();
        Err(pbcs::Error::io(
            d.join("chain"),
            std::io::Error::other("No space left on device"),
        ))
    })
    .unwrap_err();
    assert!(err.to_string().contains("No space left"), "{err}");
    assert_eq!(names(&out), ["chain", "record.csv"]);
    assert_eq!(read(&out.join("record.csv")), "old");
    assert_eq!(read(&out.join("chain").join("manifest.toml")), "old");
    check_complete(&out).unwrap();

    // A complete write replaces the earlier run, its chain folder included.
    write_run_folder(&out, |d| {
        fill(d, "new");
        Ok(())
    })
    .unwrap();
    assert_eq!(names(&out), ["chain", "record.csv"]);
    assert_eq!(read(&out.join("record.csv")), "new");
    assert_eq!(read(&out.join("chain").join("manifest.toml")), "new");

    // Something in the way of one file when the files move into place: the error names the
    // file, the folder is marked incomplete and readers refuse it.
    std::fs::create_dir_all(out.join("run.png").join("in-the-way")).unwrap();
    let err = write_run_folder(&out, |d| {
        fill(d, "newer");
        std::fs::write(d.join("run.png"), "png").unwrap();
        Ok(())
    })
    .unwrap_err()
    .to_string();
    assert!(err.contains("run.png"), "{err}");
    assert!(out.join(INCOMPLETE).exists(), "{:?}", names(&out));
    let refused = check_complete(&out).unwrap_err().to_string();
    assert!(
        refused.contains("incomplete") && refused.contains(out.to_str().unwrap()),
        "{refused}"
    );
    assert!(!names(&out).iter().any(|n| n.starts_with(".writing")));
    // The obstacle gone, a complete write removes the mark.
    std::fs::remove_dir_all(out.join("run.png")).unwrap();
    write_run_folder(&out, |d| {
        fill(d, "newest");
        Ok(())
    })
    .unwrap();
    check_complete(&out).unwrap();
    assert_eq!(names(&out), ["chain", "record.csv"]);
}
