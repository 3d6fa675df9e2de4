//! The Pendulum-v1 outside checks as tables: our TD3 on the Rust port against SB3's on
//! gymnasium's ([`pendulum_rows`], `outside.pendulum.csv`), our SAC against SB3's
//! ([`pendulum_sac_rows`], `outside.pendulum_sac.csv`), each with RL-Zoo's published agent of
//! that learner beside them.

use super::{outside_dir, seed_rows};
use crate::error::{Error, Result};
use crate::learner::LearnerName;
use crate::stats::{mean_sd, t_interval, welch};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// One Pendulum-v1 run (`cargo run --example pendulum`, `python/benches/sb3_pendulum.py`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PendulumRun {
    /// `pbcs` or `sb3-<version>`.
    pub library: String,
    /// The learner (`td3`, `sac`).
    pub algo: LearnerName,
    /// The run's seed.
    pub seed: u64,
    /// Environment steps of training.
    pub steps: u64,
    /// Greedy episodes of the final evaluation.
    pub eval_episodes: u64,
    /// Their mean return.
    pub mean_return: f64,
}

/// A published figure to set beside the runs (`results/outside/pendulum/published.toml`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Published {
    /// Where it is published (a file and commit a reader can open).
    pub source: String,
    /// The learner.
    pub algo: LearnerName,
    /// Environment steps of training.
    pub steps: u64,
    /// Episodes its evaluation averaged.
    pub eval_episodes: u64,
    /// Mean return.
    pub mean: f64,
    /// Standard deviation of the return over those episodes (one trained agent).
    pub std: f64,
}

/// Whose final mean returns a line of `outside.pendulum.csv` holds.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, strum::IntoStaticStr, strum::Display,
)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum Source {
    /// Our runs.
    Ours,
    /// Stable-Baselines3's runs.
    Sb3,
    /// A published figure ([`Published`]).
    Published,
}

/// One line of `outside.pendulum.csv`: one source of final mean returns.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PendulumRow {
    /// `ours`, `sb3` or `published`.
    pub source: Source,
    /// The library (or the publication for `published`).
    pub library: String,
    /// Runs (seeds); 1 for a published agent.
    pub n: u64,
    /// Environment steps of training.
    pub steps: u64,
    /// Greedy episodes each run's return averages (the published evaluation's episodes for
    /// `published`).
    pub eval_episodes: u64,
    /// Mean over runs of the final mean return (the published mean for `published`).
    pub mean: f64,
    /// Standard deviation over runs (over the published evaluation's episodes for
    /// `published`).
    pub sd: f64,
    /// The worst run's return (empty for `published`).
    pub min: Option<f64>,
    /// The best run's return.
    pub max: Option<f64>,
    /// Student's t 95 % interval of the mean, lower end.
    pub ci_lo: Option<f64>,
    /// Upper end.
    pub ci_hi: Option<f64>,
    /// Welch's test of ours against this source: mean(ours) − mean(this).
    pub diff_vs_ours: Option<f64>,
    /// Its t.
    pub welch_t: Option<f64>,
    /// Its degrees of freedom.
    pub welch_df: Option<f64>,
    /// Its two-sided p-value.
    pub welch_p: Option<f64>,
    /// Runs whose return lies within one standard deviation of the published mean (empty
    /// without a published figure, and for `published`).
    pub within_published: Option<u64>,
}

/// The TD3 lines: `ours` (`pendulum/ours/`), `sb3` (`pendulum/sb3/`, with Welch's test of
/// ours against it) and `published` (`pendulum/published.toml`, if present); empty without
/// the folder.
pub fn pendulum_rows(results: &Path) -> Result<Vec<PendulumRow>> {
    rows_of(results, ["ours", "sb3", "published.toml"])
}

/// The SAC lines, the same way: `pendulum/ours_sac/`, `pendulum/sb3_sac/`,
/// `pendulum/published_sac.toml`; empty without `ours_sac/`.
pub fn pendulum_sac_rows(results: &Path) -> Result<Vec<PendulumRow>> {
    rows_of(results, ["ours_sac", "sb3_sac", "published_sac.toml"])
}

/// The lines of our runs, SB3's and a published figure, from the folders and file `names`
/// under `<results>/outside/pendulum/`; empty without our folder.
fn rows_of(results: &Path, names: [&str; 3]) -> Result<Vec<PendulumRow>> {
    let [ours_dir, sb3_dir, published_file] = names;
    let root = outside_dir(results).join("pendulum");
    if !root.join(ours_dir).is_dir() {
        return Ok(Vec::new());
    }
    let (ours, sb3) = (read_side(&root, ours_dir)?, read_side(&root, sb3_dir)?);
    if (&ours[0].algo, ours[0].steps, ours[0].eval_episodes)
        != (&sb3[0].algo, sb3[0].steps, sb3[0].eval_episodes)
    {
        return Err(Error::parse(
            root.join(sb3_dir),
            "SB3's runs differ from ours in algo, steps or eval_episodes",
        ));
    }
    let published = read_published(&root.join(published_file), &ours[0])?;
    let band = published.as_ref().map(|p| (p.mean - p.std, p.mean + p.std));
    let ours_returns = returns(&ours);
    let mut out = vec![
        line(&root, Source::Ours, ours_dir, &ours, None, band)?,
        line(&root, Source::Sb3, sb3_dir, &sb3, Some(&ours_returns), band)?,
    ];
    if let Some(p) = published {
        out.push(PendulumRow {
            source: Source::Published,
            library: p.source,
            n: 1,
            steps: p.steps,
            eval_episodes: p.eval_episodes,
            mean: p.mean,
            sd: p.std,
            min: None,
            max: None,
            ci_lo: None,
            ci_hi: None,
            diff_vs_ours: None,
            welch_t: None,
            welch_df: None,
            welch_p: None,
            within_published: None,
        });
    }
    Ok(out)
}

/// The runs of `<root>/<who>/`: at least two, all of the first run's library, algorithm, steps
/// and evaluation, each with a finite mean return.
fn read_side(root: &Path, who: &str) -> Result<Vec<PendulumRun>> {
    let dir = root.join(who);
    let runs: Vec<(PathBuf, PendulumRun)> = seed_rows(&dir, |r: &PendulumRun| r.seed)?;
    let same = |a: &PendulumRun, b: &PendulumRun| {
        (&a.library, &a.algo, a.steps, a.eval_episodes)
            == (&b.library, &b.algo, b.steps, b.eval_episodes)
    };
    for (path, r) in &runs {
        if !same(r, &runs[0].1) || !r.mean_return.is_finite() {
            return Err(Error::parse(
                path,
                "every run of the folder has the first run's library, algo, steps and \
                 eval_episodes, and a finite mean_return",
            ));
        }
    }
    if runs.len() < 2 {
        return Err(Error::parse(&dir, "fewer than two runs (s<seed>.csv)"));
    }
    Ok(runs.into_iter().map(|(_, r)| r).collect())
}

/// The published figure at `published` if present: of our runs' algorithm and steps, a finite
/// mean and a standard deviation of at least 0.
fn read_published(published: &Path, ours: &PendulumRun) -> Result<Option<Published>> {
    if !published.exists() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(published).map_err(|e| Error::io(published, e))?;
    let p: Published = toml::from_str(&text).map_err(|e| Error::parse(published, e))?;
    if p.algo != ours.algo || p.steps != ours.steps || !(p.mean.is_finite() && p.std >= 0.0) {
        return Err(Error::parse(
            published,
            format!(
                "the published figure must be of {} at {} steps, with a finite mean and std >= 0",
                ours.algo, ours.steps
            ),
        ));
    }
    Ok(Some(p))
}

/// The final mean returns of `runs`.
fn returns(runs: &[PendulumRun]) -> Vec<f64> {
    runs.iter().map(|r| r.mean_return).collect()
}

/// The line of `source`'s `runs`: with `ours` (our returns), Welch's test of ours against
/// them; with `band` (the published mean ± std), how many runs lie in it.
fn line(
    root: &Path,
    source: Source,
    dir: &str,
    runs: &[PendulumRun],
    ours: Option<&[f64]>,
    band: Option<(f64, f64)>,
) -> Result<PendulumRow> {
    let r = returns(runs);
    let (mean, sd) = mean_sd(&r)
        .ok_or_else(|| Error::parse(root.join(dir), "fewer than two runs (s<seed>.csv)"))?;
    let (ci_lo, ci_hi) = t_interval(&r).map_or((None, None), |(a, b)| (Some(a), Some(b)));
    let w = ours.and_then(|o| welch(o, &r));
    let ours_mean = ours.and_then(mean_sd).map_or(f64::NAN, |m| m.0);
    Ok(PendulumRow {
        source,
        library: runs[0].library.clone(),
        n: runs.len() as u64,
        steps: runs[0].steps,
        eval_episodes: runs[0].eval_episodes,
        mean,
        sd,
        min: r.iter().copied().reduce(f64::min),
        max: r.iter().copied().reduce(f64::max),
        ci_lo,
        ci_hi,
        diff_vs_ours: w.map(|_| ours_mean - mean),
        welch_t: w.map(|w| w.0),
        welch_df: w.map(|w| w.1),
        welch_p: w.map(|w| w.2),
        within_published: band
            .map(|(lo, hi)| r.iter().filter(|&&x| (lo..=hi).contains(&x)).count() as u64),
    })
}
