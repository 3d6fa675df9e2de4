//! A saved chain's manifest is checked value by value when it is loaded (issue 33, probe 11):
//! before, `center = [nan, nan]`, `origin = [nan, inf]`, `action_scale = [1e30, -1e30]` and
//! `skills = []` loaded, and `pbcs eval` reported a success rate with exit 0. Each bad value
//! is now an error naming `manifest.toml` and the field; a freshly saved chain still loads.

use super::constant_policy;
use pbcs::nn::kernel::Kernel;
use pbcs::nn::{Head, Mlp};
use pbcs::phase2::goal::Inputs;
use pbcs::phase2::{Ball, Skill, SkillChain};
use pbcs::rng::{Seeds, Stream};
use std::path::Path;

/// A one-skill chain saved into a fresh folder, with the manifest's text.
fn saved() -> (tempfile::TempDir, String) {
    let chain = SkillChain {
        skills: vec![Skill {
            policy: Box::new(constant_policy([1.0, 0.0])),
            activation: Ball::new(vec![0.5, 0.5], 0.1),
            start_index: 0,
            target_index: 3,
            inputs: Inputs::new(vec![0.5, 0.5], vec![1.0, 1.0]),
        }],
        kernel: Kernel::detect(),
    };
    let dir = tempfile::tempdir().unwrap();
    chain.save(dir.path()).unwrap();
    let text = std::fs::read_to_string(dir.path().join("manifest.toml")).unwrap();
    (dir, text)
}

/// The error of loading the chain in `dir` once `from` is replaced by `to` in its manifest.
fn load_error(dir: &Path, text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "{from} not in {text}");
    std::fs::write(dir.join("manifest.toml"), text.replacen(from, to, 1)).unwrap();
    SkillChain::load(dir, Kernel::detect())
        .map(|c| format!("loaded {} skills", c.skills.len()))
        .expect_err("a manifest with a bad value must not load")
        .to_string()
}

fn assert_names(err: &str, field: &str) {
    assert!(
        err.contains("manifest.toml") && err.contains(field),
        "the error should name manifest.toml and {field}: {err}"
    );
}

#[test]
fn a_nan_center_is_refused_naming_the_field() {
    let (dir, text) = saved();
    let err = load_error(
        dir.path(),
        &text,
        "center = [0.5, 0.5]",
        "center = [nan, nan]",
    );
    assert_names(&err, "skills[0].center");
    assert!(err.contains("finite"), "{err}");
}

#[test]
fn a_non_finite_origin_is_refused_naming_the_field() {
    let (dir, text) = saved();
    let err = load_error(
        dir.path(),
        &text,
        "origin = [0.5, 0.5]",
        "origin = [nan, inf]",
    );
    assert_names(&err, "skills[0].origin");
    assert!(err.contains("finite"), "{err}");
}

#[test]
fn a_negative_action_scale_is_refused_naming_the_field() {
    let (dir, text) = saved();
    let err = load_error(
        dir.path(),
        &text,
        "action_scale = [1.0, 1.0]",
        "action_scale = [1e30, -1e30]",
    );
    assert_names(&err, "skills[0].action_scale");
    assert!(err.contains("positive"), "{err}");
    for bad in ["[inf, 1.0]", "[0.0, 1.0]"] {
        let err = load_error(
            dir.path(),
            &text,
            "action_scale = [1.0, 1.0]",
            &format!("action_scale = {bad}"),
        );
        assert_names(&err, "skills[0].action_scale");
    }
}

#[test]
fn an_empty_chain_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("manifest.toml"), "skills = []\n").unwrap();
    let err = SkillChain::load(dir.path(), Kernel::detect())
        .map(|c| format!("loaded {} skills", c.skills.len()))
        .unwrap_err()
        .to_string();
    assert_names(&err, "skills");
    assert!(err.contains("no skill"), "{err}");
}

/// The other values: indices, bounds, the policy's file, parameter counts, weights.
#[test]
fn indices_bounds_files_and_parameter_counts_are_checked() {
    let (dir, text) = saved();
    for (from, to, field) in [
        (
            "start_index = 0",
            "start_index = 4",
            "skills[0].start_index",
        ),
        ("radius = 0.1", "radius = inf", "skills[0].radius"),
        // A policy kind this build does not know (`pbcs::learner::load_policy`).
        ("policy = \"mlp\"", "policy = \"ppo\"", "skills[0].policy"),
        (
            "action_bounds = [0.1, 0.1]",
            "action_bounds = [0.1, -0.1]",
            "skills[0].action_bounds",
        ),
        (
            "action_bounds = [0.1, 0.1]",
            "action_bounds = [nan, 0.1]",
            "skills[0].action_bounds",
        ),
        (
            "file = \"skill0.safetensors\"",
            "file = \"../skill0.safetensors\"",
            "skills[0].file",
        ),
        // More parameters than the file holds: refused before the network is allocated.
        (
            "sizes = [2, 4, 2]",
            "sizes = [2, 4000000000, 2]",
            "skills[0].sizes",
        ),
        (
            "sizes = [2, 4, 2]",
            "sizes = [2, 9223372036854775807, 2]",
            "skills[0].sizes",
        ),
    ] {
        let err = load_error(dir.path(), &text, from, to);
        assert_names(&err, field);
    }
    // A kind this build knows whose network the manifest's is not (a SAC network gives half
    // its outputs as actions): refused naming the field and the kind.
    let err = load_error(dir.path(), &text, "policy = \"mlp\"", "policy = \"sac\"");
    assert_names(&err, "skills[0].action_scale");
    assert!(err.contains("sac policy"), "{err}");
    // The second skill is named by its index (a copy of the first, moved on along τ to follow
    // it).
    let skills = text[text.find("[[skills]]").unwrap()..]
        .replacen("start_index = 0", "start_index = 3", 1)
        .replacen("target_index = 3", "target_index = 6", 1);
    let two = format!(
        "{}\n{skills}",
        text.replace("skill_count = 1", "skill_count = 2")
    );
    std::fs::write(dir.path().join("manifest.toml"), &two).unwrap();
    SkillChain::load(dir.path(), Kernel::detect()).unwrap();
    let second = two.rfind("center = [0.5, 0.5]").unwrap();
    let bad = format!(
        "{}center = [0.5, nan]{}",
        &two[..second],
        &two[second + 19..]
    );
    std::fs::write(dir.path().join("manifest.toml"), bad).unwrap();
    let err = SkillChain::load(dir.path(), Kernel::detect())
        .unwrap_err()
        .to_string();
    assert_names(&err, "skills[1].center");
    // A non-finite weight, its file's SHA-256 recorded as it is now: an error naming the
    // policy's file.
    let mut policy = constant_policy([1.0, 0.0]);
    policy.params[3] = f32::NAN;
    let file = dir.path().join("skill0.safetensors");
    policy.save(&file).unwrap();
    let new = format!("sha256 = \"{}\"", pbcs::record::file_sha256(&file).unwrap());
    let recorded = text.lines().find(|l| l.starts_with("sha256 = ")).unwrap();
    assert_ne!(recorded, new, "the NaN file is another file");
    let text = text.replace(recorded, &new);
    std::fs::write(dir.path().join("manifest.toml"), &text).unwrap();
    let err = SkillChain::load(dir.path(), Kernel::detect())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("skill0.safetensors") && err.contains("not finite"),
        "{err}"
    );
}

/// A chain of two maze skills with what each input mode writes: goal-relative (origin the
/// goal, scale the maze's bound 0.1, tanh bound 1) and raw (origin 0, scale 1, tanh bound 0.1).
fn maze_chain() -> SkillChain {
    let policy = |bound: f32| {
        let mut rng = Seeds::new(0).stream(Stream::Init);
        Mlp::new(&[2, 8, 2], Head::Tanh(vec![bound; 2]), &mut rng)
    };
    let skill = |policy: Mlp, center: Vec<f32>, k, inputs| Skill {
        policy: Box::new(policy),
        activation: Ball::new(center, 0.1),
        start_index: k,
        target_index: k + 5,
        inputs,
    };
    SkillChain {
        skills: vec![
            skill(
                policy(1.0),
                vec![0.5, 0.5],
                0,
                Inputs::new(vec![1.0, 0.5], vec![0.1, 0.1]),
            ),
            skill(
                policy(0.1),
                vec![1.0, 0.5],
                5,
                Inputs::new(vec![0.0, 0.0], vec![1.0, 1.0]),
            ),
        ],
        kernel: Kernel::detect(),
    }
}

/// A freshly saved chain loads back equal, alone and as a chain of `pbcs run` (with its job,
/// checked against the maze); policies that do not fit the maze are refused there.
#[test]
fn a_freshly_saved_chain_loads_and_policies_must_fit_the_maze() {
    let chain = maze_chain();
    let dir = tempfile::tempdir().unwrap();
    chain.save(dir.path()).unwrap();
    assert_eq!(
        SkillChain::load(dir.path(), Kernel::detect()).unwrap(),
        chain
    );
    let mut job = pbcs::config::Preset::Fast.job().unwrap();
    job.maze.size = 2;
    let run_toml = dir.path().join(pbcs::runs::CHAIN_JOB);
    let job_text = pbcs::validate::to_toml(&job, &run_toml).unwrap();
    std::fs::write(&run_toml, job_text).unwrap();
    let (_, _, loaded) = pbcs::runs::load_saved_chain(dir.path(), Kernel::detect()).unwrap();
    assert_eq!(loaded, chain);
    let e = pbcs::runs::eval_chain(dir.path(), 3, None, Kernel::detect()).unwrap();
    assert_eq!((e.skills, e.episodes), (2, 3));

    // A policy of 3 inputs on the 2-d maze.
    let mut wrong = maze_chain();
    let mut rng = Seeds::new(0).stream(Stream::Init);
    wrong.skills[1].policy = Box::new(Mlp::new(&[3, 8, 2], Head::Tanh(vec![0.1; 2]), &mut rng));
    wrong.skills[1].activation.center = vec![1.0, 0.5, 0.0];
    wrong.skills[1].inputs = Inputs::new(vec![0.0; 3], vec![1.0, 1.0]);
    wrong.save(dir.path()).unwrap();
    let err = pbcs::runs::load_saved_chain(dir.path(), Kernel::detect())
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert_names(&err, "skills[1].sizes");
    // Actions beyond the maze's bound: a raw policy's bound 0.1 scaled by 1e30.
    let mut wrong = maze_chain();
    wrong.skills[1].inputs.action_scale = vec![1e30, 1.0];
    wrong.save(dir.path()).unwrap();
    let err = pbcs::runs::load_saved_chain(dir.path(), Kernel::detect())
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert_names(&err, "skills[1].action_scale");
}

/// A one-skill chain of PointMaze's shape (networks of 4 inputs, 2 actions) with `activation`.
fn pointmaze_chain(activation: Ball) -> SkillChain {
    let mut rng = Seeds::new(0).stream(Stream::Init);
    SkillChain {
        skills: vec![Skill {
            policy: Box::new(Mlp::new(&[4, 8, 2], Head::Tanh(vec![1.0; 2]), &mut rng)),
            activation,
            start_index: 0,
            target_index: 9,
            inputs: Inputs::new(vec![0.5, 0.5, 0.0, 0.0], vec![1.0, 1.0]),
        }],
        kernel: Kernel::detect(),
    }
}

/// A chain of PointMaze's shape: networks of 4 inputs (x, y, vx, vy), activation balls in the
/// position (2 values). Such a chain saved by `pbcs run --env pointmaze_umaze` did not load
/// ("center has 2 values, the network needs 4") before the centre was allowed to be the
/// position part; a centre longer than the input, or empty, is still refused.
#[test]
fn a_chain_whose_balls_lie_in_the_position_part_saves_and_loads() {
    let chain = pointmaze_chain(Ball::new(vec![-1.0, 1.0], 0.25));
    let dir = tempfile::tempdir().unwrap();
    chain.save(dir.path()).unwrap();
    assert_eq!(
        SkillChain::load(dir.path(), Kernel::detect()).unwrap(),
        chain
    );
    let text = std::fs::read_to_string(dir.path().join("manifest.toml")).unwrap();
    for bad in ["center = [-1.0, 1.0, 0.0, 0.0, 0.0]", "center = []"] {
        let err = load_error(dir.path(), &text, "center = [-1.0, 1.0]", bad);
        assert_names(&err, "skills[0].center");
        assert!(err.contains("1 to 4"), "{err}");
    }
}

/// Balls in position and velocity (`phase2.velocity_scale`): the centre holds x, y, vx, vy and
/// the ball its weights; both are saved and loaded, and the loaded ball measures as the saved
/// one (a state at the centre's position with a velocity 3/λ off is outside). Weights of
/// another length than the centre, or not positive and finite, are refused naming the field.
#[test]
fn a_ball_in_position_and_velocity_keeps_its_weights() {
    let chain = pointmaze_chain(Ball {
        center: vec![-1.0, 1.0, 2.0, 0.0],
        radius: 0.25,
        weights: vec![1.0, 1.0, 0.1, 0.1],
    });
    let dir = tempfile::tempdir().unwrap();
    chain.save(dir.path()).unwrap();
    let loaded = SkillChain::load(dir.path(), Kernel::detect()).unwrap();
    assert_eq!(loaded, chain);
    let a = &loaded.skills[0].activation;
    // Velocity 2.0 vs 2.0 + 2.4: weighted 0.24 ≤ 0.25, inside; + 2.6: 0.26, outside.
    assert!(a.contains(&[-1.0, 1.0, 4.4, 0.0]));
    assert!(!a.contains(&[-1.0, 1.0, 4.6, 0.0]));
    assert!(!a.contains(&[-1.0, 1.0, 2.0 + 3.0 / 0.1, 0.0]));
    // The same centre without weights: a position ball would hold them all.
    assert!(Ball::new(vec![-1.0, 1.0], 0.25).contains(&[-1.0, 1.0, 32.0, 0.0]));
    let text = std::fs::read_to_string(dir.path().join("manifest.toml")).unwrap();
    assert!(text.contains("weights = [1.0, 1.0, 0.1, 0.1]"), "{text}");
    for (bad, why) in [
        ("weights = [1.0, 1.0, 0.1]", "3 values"),
        ("weights = [1.0, 1.0, 0.1, -0.1]", "positive"),
        ("weights = [1.0, 1.0, 0.1, nan]", "positive"),
    ] {
        let err = load_error(dir.path(), &text, "weights = [1.0, 1.0, 0.1, 0.1]", bad);
        assert_names(&err, "skills[0].weights");
        assert!(err.contains(why), "{bad}: {err}");
    }
}

/// A chain's files are the ones it was saved with (issue 48's probe: a manifest cut before its
/// second skill evaluated as a one-skill chain, swapped or foreign policy files and another
/// run's `run.toml` ran, all with exit 0). The manifest records the number of skills and the
/// SHA-256 of each policy file and of the job beside it; each mismatch is refused naming the
/// field. A manifest written before it (none of those fields) still loads, unchecked.
#[test]
fn a_chain_whose_files_do_not_match_its_manifest_is_refused() {
    let policy = |seed: u64| {
        let mut rng = Seeds::new(seed).stream(Stream::Init);
        Mlp::new(&[2, 8, 2], Head::Tanh(vec![0.1; 2]), &mut rng)
    };
    let chain = |seeds: [u64; 2]| SkillChain {
        skills: seeds
            .iter()
            .enumerate()
            .map(|(i, &s)| Skill {
                policy: Box::new(policy(s)),
                activation: Ball::new(vec![0.5 + i as f32, 0.5], 0.1),
                start_index: 5 * i,
                target_index: 5 * i + 5,
                inputs: Inputs::new(vec![0.0, 0.0], vec![1.0, 1.0]),
            })
            .collect(),
        kernel: Kernel::detect(),
    };
    let saved = |seeds: [u64; 2], job: &str| {
        let dir = tempfile::tempdir().unwrap();
        chain(seeds)
            .save_with_job(dir.path(), Some(("run.toml", job)), None)
            .unwrap();
        dir
    };
    let load = |dir: &Path| SkillChain::load(dir, Kernel::detect()).map(|c| c.skills.len());
    let (ours, theirs) = (saved([1, 2], "seed = 1\n"), saved([3, 4], "seed = 2\n"));
    assert_eq!(load(ours.path()).unwrap(), 2);
    let manifest = std::fs::read_to_string(ours.path().join("manifest.toml")).unwrap();
    assert!(manifest.starts_with("skill_count = 2\njob_file = \"run.toml\"\njob_sha256 = \""));
    let refused = |edit: &dyn Fn(&Path), field: &str| {
        let dir = saved([1, 2], "seed = 1\n");
        edit(dir.path());
        let err = load(dir.path()).expect_err("a chain whose files do not match must not load");
        assert_names(&err.to_string(), field);
    };
    // The manifest cut just before its second [[skills]].
    refused(
        &|d| {
            let cut = manifest.rfind("[[skills]]").unwrap();
            std::fs::write(d.join("manifest.toml"), &manifest[..cut]).unwrap();
        },
        "skill_count",
    );
    // The two policy files swapped.
    refused(
        &|d| {
            let (a, b) = (d.join("skill0.safetensors"), d.join("skill1.safetensors"));
            let tmp = d.join("tmp");
            std::fs::rename(&a, &tmp).unwrap();
            std::fs::rename(&b, &a).unwrap();
            std::fs::rename(&tmp, &b).unwrap();
        },
        "skills[0].sha256",
    );
    // A policy file copied in from another run's chain.
    refused(
        &|d| {
            let other = theirs.path().join("skill1.safetensors");
            std::fs::copy(other, d.join("skill1.safetensors")).unwrap();
        },
        "skills[1].sha256",
    );
    // Another run's job.
    refused(
        &|d| {
            std::fs::copy(theirs.path().join("run.toml"), d.join("run.toml")).unwrap();
        },
        "job_sha256",
    );
    // A manifest that records its count but not a file's hash (the line deleted).
    refused(
        &|d| {
            let first = manifest
                .lines()
                .find(|l| l.starts_with("sha256 = "))
                .unwrap();
            let cut = manifest.replacen(&format!("{first}\n"), "", 1);
            std::fs::write(d.join("manifest.toml"), cut).unwrap();
        },
        "skills[0].sha256",
    );
    // A job file other than the run.toml `pbcs eval` reads, hashed: refused all the same.
    refused(
        &|d| {
            std::fs::copy(d.join("run.toml"), d.join("other.toml")).unwrap();
            let moved = manifest.replace("job_file = \"run.toml\"", "job_file = \"other.toml\"");
            std::fs::write(d.join("manifest.toml"), moved).unwrap();
        },
        "job_file",
    );
    // A manifest written before issue 48 (no count, no hashes) loads as it did: its files are
    // not checked (swapped here, and loaded).
    let legacy: String = manifest
        .lines()
        .filter(|l| {
            !l.starts_with("skill_count") && !l.starts_with("job_") && !l.starts_with("sha256")
        })
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(ours.path().join("manifest.toml"), legacy).unwrap();
    std::fs::copy(
        theirs.path().join("skill0.safetensors"),
        ours.path().join("skill0.safetensors"),
    )
    .unwrap();
    assert_eq!(load(ours.path()).unwrap(), 2);
}

/// A chain of constant skills with these (start_index, target_index) along τ.
fn chain_along(indices: &[(usize, usize)]) -> SkillChain {
    SkillChain {
        skills: indices
            .iter()
            .map(|&(start_index, target_index)| Skill {
                policy: Box::new(constant_policy([1.0, 0.0])),
                activation: Ball::new(vec![0.5, 0.5], 0.1),
                start_index,
                target_index,
                inputs: Inputs::new(vec![0.5, 0.5], vec![1.0, 1.0]),
            })
            .collect(),
        kernel: Kernel::detect(),
    }
}

/// The skills of a manifest follow each other along τ: one whose second skill does not start
/// where the first ends (a manifest cut at a skill boundary and recounted, its skills
/// reordered, a skill repeated, a skill of no length) is refused naming the field.
#[test]
fn a_chain_whose_skills_do_not_follow_each_other_along_tau_is_refused() {
    let load = |indices: &[(usize, usize)]| {
        let dir = tempfile::tempdir().unwrap();
        chain_along(indices).save(dir.path()).unwrap();
        SkillChain::load(dir.path(), Kernel::detect()).map(|c| c.skills.len())
    };
    assert_eq!(load(&[(0, 4), (4, 9), (9, 12)]).unwrap(), 3);
    // Phase 2 left incomplete: the chain starts past τ_0, as it was saved.
    assert_eq!(load(&[(17, 19), (19, 37)]).unwrap(), 2);
    for (indices, field) in [
        (&[(4, 9), (0, 4)][..], "skills[1].start_index"),
        (&[(0, 4), (0, 4)][..], "skills[1].start_index"),
        (&[(0, 4), (5, 9)][..], "skills[1].start_index"),
        (&[(0, 4), (4, 4)][..], "skills[1].start_index"),
    ] {
        let err = load(indices).expect_err("a chain out of order must not load");
        assert_names(&err.to_string(), field);
    }
}

/// The last skill ends at τ's end, the target: a manifest that records the length of the τ
/// its chain followed (`trajectory_len`, since issue 77) and whose last `target_index` is not
/// its last index (past it, `u64::MAX`, short of it) is refused naming the field.
#[test]
fn a_chain_whose_last_skill_does_not_end_at_the_target_is_refused() {
    let chain = chain_along(&[(0, 4), (4, 12)]);
    let dir = tempfile::tempdir().unwrap();
    chain.save_with_job(dir.path(), None, Some(13)).unwrap();
    let load = || SkillChain::load(dir.path(), Kernel::detect()).map(|c| c.skills.len());
    assert_eq!(load().unwrap(), 2);
    let manifest = std::fs::read_to_string(dir.path().join("manifest.toml")).unwrap();
    assert!(manifest.contains("trajectory_len = 13\n"), "{manifest}");
    for (from, to) in [
        ("target_index = 12", "target_index = 18446744073709551615"),
        ("target_index = 12", "target_index = 30"),
        ("target_index = 12", "target_index = 11"),
        ("trajectory_len = 13", "trajectory_len = 40"),
    ] {
        let err = load_error(dir.path(), &manifest, from, to);
        assert_names(&err, "skills[1].target_index");
    }
    // Cut at its first skill, its count fixed: where the chain starts is recorded too.
    let first = manifest.find("[[skills]]").unwrap();
    let second = first + 1 + manifest[first + 1..].find("[[skills]]").unwrap();
    let cut = format!("{}{}", &manifest[..first], &manifest[second..]);
    let err = load_error(dir.path(), &cut, "skill_count = 2", "skill_count = 1");
    assert_names(&err, "skills[0].start_index");
    // A key no manifest has (a typo, a line pasted in) is refused, not ignored.
    let err = load_error(
        dir.path(),
        &manifest,
        "skill_count = 2",
        "skill_count = 2\nfoo = 1",
    );
    assert_names(&err, "foo");
}
