//! Tests of the AntMaze section's readers ([`super`]).

use super::*;

const READING: &str = "phase 1: 38696 env steps; τ_0 … τ_40\n\
    phase 2: None, 2 skills, 100 training and 50 test env steps, 8 s\n\
    episode 0: failure in 5000 steps\n\
    chain from B_eps(tau_0): 4 of 100 episodes reach the target (2 of them upright there)\n\
    skill,K,T,entered,stalled,flipped,from_entries,from_ball,from_ball_at_rest,coasting,joint_gap,velocity_gap\n\
    0,0,1,5,5,0,0.00,0.98,0.96,0.96,0.00,0.00\n\
    1,1,3,18,1,0,0.78,1.00,1.00,0.96,0.81,16.54\n";

fn write(text: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("r.txt");
    std::fs::write(&path, text).unwrap();
    (dir, path)
}

#[test]
fn a_reading_gives_its_steps_its_episodes_and_its_table() {
    let (_d, path) = write(READING);
    let r = read_chain_reading(&path).unwrap();
    let p = r.phase2.unwrap();
    assert_eq!((p.steps, p.skills, p.outcome), (150, 2, "chain"));
    assert_eq!(r.prefix, Some(40));
    assert_eq!(r.reached, Some((4, 100)));
    assert_eq!(r.table.len(), 2);
    assert_eq!((r.table[1].k, r.table[1].t, r.table[1].entered), (1, 3, 18));
    assert_eq!(r.table[1].velocity_gap, 16.54);
}

#[test]
fn a_reading_without_a_chain_has_no_episodes_and_no_table() {
    let text = "phase 2: Some(BackplayFailed), 0 skills, 7 training and 3 test env steps, 1 s\n";
    let (_d, path) = write(text);
    let r = read_chain_reading(&path).unwrap();
    let p = r.phase2.unwrap();
    assert_eq!(
        (p.steps, p.outcome, r.reached),
        (10, "backplay failed", None)
    );
}

#[test]
fn a_damaged_reading_is_refused_naming_its_file() {
    for text in [
        // A prefix without its phase-2 line.
        &READING.replace("phase 2: ", "phase two: "),
        // More successes than episodes.
        &READING.replace("4 of 100", "140 of 100"),
        // An unknown outcome.
        &READING.replace("None,", "Some(Other),"),
        // Episodes without their table.
        &READING[..READING.find("skill,K").unwrap()],
        // A cell that is not a number.
        &READING.replace("16.54", "fast"),
    ] {
        let (_d, path) = write(text);
        let err = read_chain_reading(&path).unwrap_err().to_string();
        assert!(err.contains("r.txt"), "{err}");
    }
}

#[test]
fn the_judged_line_is_read_and_checked() {
    let (_d, path) = write("# a comment\nsuccesses = 3 of 100\n");
    assert_eq!(read_judged(&path).unwrap(), (3, 100));
    let (_d, path) = write("successes = 300 of 100\n");
    assert!(read_judged(&path).is_err());
}

#[test]
fn the_committed_files_give_the_sections_numbers() {
    let results = Path::new(env!("CARGO_MANIFEST_DIR")).join("results");
    let tex = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    let numbers = render(&results, tex.path(), &mut files).unwrap();
    assert_eq!(files.len(), 4);
    // Known values of the committed files (their READMEs' tables).
    for (key, value) in [
        ("phase1:solved", "60"),
        ("phase1:runs", "60"),
        ("handover:reached", "0"),
        ("handover:episodes", "20"),
        ("ball30m:skills", "73"),
        ("probe:verify-s0:reached", "4"),
        ("probe:repair-s0:reached", "7"),
        ("probe:best", "7"),
        ("reach:td3_her256-s0:best", "83"),
        ("long:judged", "0"),
        ("prefix", "40"),
        ("phase1:keep:flippedhi", "69"),
    ] {
        let def = format!("\\csname res:antmaze:{key}\\endcsname{{{value}}}");
        assert!(numbers.contains(&def), "{key}: {numbers}");
    }
}
