//! Absurd values in an experiment file (issue 47, found by probing ~150 bad inputs): each is a
//! clear error naming its field — never a panic ("capacity overflow"), an abort (an 800 GB
//! allocation) or a sweep of nothing that exits 0.

use pbcs::experiment::Experiment;

#[test]
fn absurd_values_are_refused_naming_their_field() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy("experiments/pbcs_paper.toml", dir.path().join("base.toml")).unwrap();
    std::fs::copy("experiments/baseline.toml", dir.path().join("vanilla.toml")).unwrap();
    let head = "title = \"t\"\nseeds = 2\nmazes = [2]\n";
    let method = |name: &str, set: &str| {
        format!("[[method]]\nname = \"{name}\"\nkind = \"pbcs\"\nbase = \"base.toml\"\nset = {{ {set} }}\n")
    };
    let cases = [
        // Absurd values (issue 47): each a clear error naming its field, never a panic, an
        // abort or a silent sweep of nothing.
        (
            format!(
                "title = \"t\"\nseeds = 18446744073709551615\nmazes = [2]\n{}",
                method("a", "")
            ),
            "invalid `seeds`: 18446744073709551615: needs 1 to 100000 seeds",
        ),
        (
            format!(
                "title = \"t\"\nseeds = 100000000000\nmazes = [2]\n{}",
                method("a", "")
            ),
            "needs 1 to 100000 seeds",
        ),
        (
            format!(
                "first_seed = 18446744073709551615\n{head}{}",
                method("a", "")
            ),
            "invalid `first_seed`: 18446744073709551615 + 2 seeds passes the largest seed",
        ),
        (
            format!("picture_seeds = [50]\n{head}{}", method("a", "")),
            "invalid `picture_seeds`: 50 is not one of the grid's seeds 0..1",
        ),
        (
            format!("{head}{}", method("a", "learner.argmax_samples = 0")),
            "learner.argmax_samples",
        ),
        (
            format!(
                "{head}[[method]]\nname = \"v\"\nkind = \"vanilla\"\nbase = \"vanilla.toml\"\n\
                 set = {{ train.steps = 5000, train.learning_starts = 6000 }}\n"
            ),
            "invalid `train.learning_starts`: 6000 of train.steps = 5000: the learner would never update",
        ),
        // A map of one's own set by a method rather than the file's [pointmaze], a site
        // `pointmaze` without a map, and a map with no such site (issue 47).
        (
            format!("{head}{}", method("a", "pointmaze.time_limit = 500")),
            "invalid `pointmaze`: method `a`: sets [pointmaze]",
        ),
        (
            format!("title = \"t\"\nseeds = 2\nenvs = [\"pointmaze\"]\n{}", method("a", "")),
            "invalid `pointmaze`: the sites `pointmaze` and `antmaze` run a map of one's own",
        ),
        (
            format!("{head}[pointmaze]\nmap = [\"1111\", \"1001\", \"1111\"]\n{}", method("a", "")),
            "nor `antmaze` is one of the file's `envs`",
        ),
    ];
    for (i, (text, needle)) in cases.iter().enumerate() {
        let path = dir.path().join(format!("bad{i}.toml"));
        std::fs::write(&path, text).unwrap();
        let err = Experiment::load(&path, None).unwrap_err().to_string();
        assert!(
            err.contains(needle),
            "case {i}: `{err}` does not name `{needle}`"
        );
    }
    // A profile's seeds are held to the same bounds, named as the profile's.
    let path = dir.path().join("profiled.toml");
    std::fs::write(
        &path,
        format!("{head}{}[profile.p]\nseeds = 0\n", method("a", "")),
    )
    .unwrap();
    let err = Experiment::load(&path, Some("p")).unwrap_err().to_string();
    assert!(
        err.contains("invalid `profile.p.seeds`: 0: needs 1 to"),
        "{err}"
    );
}
