//! A run's folder: claimed before any work ([`claim`]), named by default from its job
//! ([`explore_out`], [`train_out`], [`run_out`], [`method_name`]), and its wall clock beside the results ([`write_timing`]).

use crate::config::{ExploreJob, Located, PbcsJob, Preset, TrainJob};
use crate::error::Result;
use crate::nn::kernel::Kernel;
use crate::phase2::goal::BallMetric;
use crate::phase2::StartMode;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Claims `out` for `job` before any work ([`crate::record::claim_out_dir`]): writes the
/// resolved job as `config.toml` (so that `--config` re-runs exactly this job), refusing a
/// path that is not a writable folder, a folder of another run, or a sweep's results folder or
/// cell folder ([`holds_sweep_results`]), whose rows a run's files would mix with. The run
/// holds the returned lock while it works.
pub(super) fn claim<T: Serialize>(job: &T, out: &Path) -> Result<crate::record::WorkLock> {
    if let Some(what) = holds_sweep_results(out) {
        return Err(crate::Error::io(
            out,
            std::io::Error::other(format!(
                "{what}: a run's files would mix with them; choose another output folder"
            )),
        ));
    }
    let text = crate::validate::to_toml(job, &out.join("config.toml"))?;
    crate::record::claim_out_dir(out, &text)
}

/// What in `dir` says it is a results folder of sweeps, lies inside one's raw rows
/// ([`crate::record::inside_rows`]) or is a cell folder of one: its lock
/// ([`crate::record::FolderLock::path`]), its `raw/` folder, or a raw row (`s<seed>.csv`); or
/// that it is a saved chain (`manifest.toml`).
fn holds_sweep_results(dir: &Path) -> Option<String> {
    if crate::record::FolderLock::path(dir).exists() || dir.join("raw").is_dir() {
        return Some("holds a sweep's results (its lock or its raw/ folder)".to_string());
    }
    if let Some(raw) = crate::record::inside_rows(dir) {
        return Some(format!("lies inside {}, a sweep's raw rows", raw.display()));
    }
    if dir.join("manifest.toml").exists() {
        return Some("holds a saved chain (manifest.toml)".to_string());
    }
    let row = |name: &str| {
        let seed = name.strip_prefix('s').and_then(|n| n.strip_suffix(".csv"));
        seed.is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
    };
    std::fs::read_dir(dir).ok()?.flatten().find_map(|e| {
        let name = e.file_name().to_string_lossy().into_owned();
        row(&name).then_some(format!("holds a sweep's results (the row {name})"))
    })
}

/// Writes a run's `timing.toml` at `path` ([`crate::record::Timing`]): its wall clock and the
/// layer kernel it ran on (`None` for phase 1, which has no networks).
pub fn write_timing(
    path: &Path,
    seconds: f64,
    env_steps: u64,
    kernel: Option<Kernel>,
) -> Result<()> {
    crate::record::Timing::now(seconds, env_steps, kernel.map(Kernel::name)).write(path)
}

/// The default output folder of `pbcs explore` without `--out`:
/// `out/explore/<where>-s<seed>`, where is [`crate::envs::EnvSpec::folder_name`] (`maze4-m1`, `rooms`).
/// With [`train_out`] and [`run_out`], the one place run folders are named.
///
/// ```
/// use pbcs::config::{ExploreJob, PbcsJob};
/// use pbcs::envs::{EnvName, EnvSpec};
/// use pbcs::phase2::StartMode;
/// use pbcs::runs::{explore_out, run_out};
/// let mut job = PbcsJob::default();
/// (job.maze.size, job.maze.seed, job.seed) = (4, 1, 2);
/// job.phase2.start = StartMode::Exact;
/// assert_eq!(run_out(&job, "fast"), std::path::Path::new("out/run/fast/maze4-m1-s2-exact"));
/// let rooms = ExploreJob { env: EnvName::Rooms, ..ExploreJob::default() };
/// assert_eq!(explore_out(&rooms), std::path::Path::new("out/explore/rooms-s0"));
/// ```
pub fn explore_out(job: &ExploreJob) -> PathBuf {
    folder("explore", job, "")
}

/// The default output folder of `pbcs train` without `--out`:
/// `out/train/<where>-s<seed>-<learner>` ([`explore_out`]; the learner as [`train_suffix`]).
pub fn train_out(job: &TrainJob) -> PathBuf {
    folder("train", job, &train_suffix(job))
}

/// The default output folder of `pbcs run` without `--out`, for the procedure named `name`
/// ([`method_name`]): `out/run/<name>/<where>-s<seed><departures>` ([`explore_out`]; the
/// departures from the preset as [`pbcs_suffix`]).
pub fn run_out(job: &PbcsJob, name: &str) -> PathBuf {
    folder(&format!("run/{name}"), job, &pbcs_suffix(job))
}

fn folder(command: &str, job: &impl Located, suffix: &str) -> PathBuf {
    let (env, seed) = (job.env_spec(), job.seed());
    PathBuf::from(format!(
        "out/{command}/{}-s{seed}{suffix}",
        env.folder_name()
    ))
}

/// The part of a PBCS run's default folder that names its departures from the preset:
/// `-nochain` without chaining, `-exact` with exact starts, `-archive` with archive starts,
/// `-velocity` with balls in position and velocity.
fn pbcs_suffix(job: &PbcsJob) -> String {
    let mut suffix = String::new();
    if !job.phase2.chaining {
        suffix.push_str("-nochain");
    }
    match job.phase2.start {
        StartMode::Exact => suffix.push_str("-exact"),
        StartMode::Archive => suffix.push_str("-archive"),
        StartMode::Ball => {}
    }
    if job.phase2.ball != BallMetric::Position {
        suffix.push_str("-velocity");
    }
    suffix
}

/// The part of a vanilla run's default folder that names its learner: `-ddpg`, `-td3`, with
/// `-am` for the argmax actor; `-sac`; then `-her` with hindsight experience replay.
fn train_suffix(job: &TrainJob) -> String {
    format!("-{}", job.learner_name().as_str().replace('_', "-"))
}

/// The name of a procedure given as a config file or a preset (`pbcs run`'s folder,
/// `pbcs table`'s method): the file's stem or the preset's name, with every character but
/// ASCII letters, digits and `_` replaced by `_`.
///
/// ```
/// use pbcs::config::Preset;
/// use pbcs::runs::method_name;
/// use std::path::Path;
/// assert_eq!(method_name(None, Preset::Paper), "paper");
/// assert_eq!(method_name(Some(Path::new("exp/my-run.v2.toml")), Preset::Fast), "my_run_v2");
/// ```
pub fn method_name(config: Option<&Path>, preset: Preset) -> String {
    config
        .and_then(Path::file_stem)
        .map_or(preset.name().to_string(), |s| {
            s.to_string_lossy().into_owned()
        })
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}
