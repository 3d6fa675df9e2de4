//! The settings table (`experiments/settings.toml` with both presets' values) is complete
//! (`tests/docs.rs` checks that `docs/phase2.md` quotes exactly what it generates).

use pbcs::report::settings::load;
use std::path::Path;

/// Every field of both presets has one entry, and every entry names a field: removing one,
/// doubling one or naming a field that does not exist is an error naming it.
#[test]
fn every_preset_field_has_exactly_one_entry() {
    let rows = load(Path::new("experiments/settings.toml")).unwrap();
    let paper = pbcs::report::settings::preset_values(pbcs::config::Preset::Paper).unwrap();
    assert_eq!(rows.len(), paper.len());
    let beta = rows.iter().find(|(d, _)| d.field == "phase2.beta").unwrap();
    assert_eq!(beta.1, ["50", "50"]);
    let text = std::fs::read_to_string("experiments/settings.toml").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("settings.toml");
    let entry = "[[setting]]\nfield = \"phase2.beta\"\n";
    let at = text.find(entry).unwrap();
    let end = at + text[at..].find("\n\n").unwrap() + 2;
    for (bad, expected) in [
        (format!("{}{}", &text[..at], &text[end..]), "`phase2.beta` has 0 entries"),
        (format!("{text}\n{}", &text[at..end]), "`phase2.beta` has 2 entries"),
        (
            format!(
                "{text}\n[[setting]]\nfield = \"phase2.nothing\"\nsource = \"open\"\nwhat = \"w\"\nevidence = \"e\"\n"
            ),
            "`phase2.nothing` is not a field",
        ),
    ] {
        std::fs::write(&path, bad).unwrap();
        let e = load(&path).unwrap_err().to_string();
        assert!(e.contains(expected), "{e}");
    }
}
