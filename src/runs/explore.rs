//! `pbcs explore`: phase 1 alone, its trajectory, archive and picture.

use super::folder::{claim, write_timing};
use crate::config::{ExploreJob, Located};
use crate::env::Env;
use crate::env::Planar;
use crate::envs::EnvName;
use crate::error::Result;
use crate::phase1::{explore, Exploration, NO_PARENT};
use crate::picture::{Draw, PictureData, RunPicture};
use crate::record::{write_csv, write_record};
use crate::rng::{Seeds, Stream};
use crate::validate::Valid;
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// The one-row summary of a phase-1 run (`summary.csv`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExploreSummary {
    /// Maze size N (empty for another environment).
    pub maze: Option<usize>,
    /// Maze layout seed (empty for another environment).
    pub maze_seed: Option<u64>,
    /// Run seed.
    pub seed: u64,
    /// Environment steps phase 1 used.
    pub env_steps: u64,
    /// Number of states of τ (N + 1).
    pub trajectory_len: usize,
    /// States in the archive when the target was reached.
    pub archive_states: usize,
    /// Non-empty bins of the archive.
    pub archive_bins: usize,
    /// The environment ([`EnvName`]; the last column, so the others keep their places).
    pub env: EnvName,
}

/// One phase-1 run's outcome ([`ExploreRun::compute`]): the summary row, everything
/// exploration found and the wall-clock seconds; [`ExploreRun::write`] writes it.
#[derive(Debug, Clone)]
pub struct ExploreRun<E: Planar> {
    /// The environment explored.
    pub env: E,
    /// The one-row summary.
    pub summary: ExploreSummary,
    /// τ and the archive.
    pub found: Exploration<E::State>,
    /// Wall-clock seconds of the run (not deterministic).
    pub seconds: f64,
}

impl<E: Planar> ExploreRun<E> {
    /// Runs phase 1 of `job` on `env` (the environment `job` names: [`run_explore`] makes it
    /// from the name); `progress(steps, archive_len)` is called during the run. Writes
    /// nothing.
    pub fn compute(
        env: E,
        job: &Valid<ExploreJob>,
        progress: impl FnMut(u64, usize),
    ) -> Result<ExploreRun<E>> {
        let mut rng = Seeds::new(job.seed).stream(Stream::Explore);
        let clock = Instant::now();
        let found = explore(&env, &job.explore, &mut rng, progress)?;
        let seconds = clock.elapsed().as_secs_f64();
        let (maze, maze_seed) = job.env_spec().maze_columns();
        let summary = ExploreSummary {
            maze,
            maze_seed,
            seed: job.seed,
            env_steps: found.env_steps,
            trajectory_len: found.trajectory.len(),
            archive_states: found.archive.len(),
            archive_bins: found.archive.bins(),
            env: job.env,
        };
        Ok(ExploreRun {
            env,
            summary,
            found,
            seconds,
        })
    }

    /// Writes into `out`: `summary.csv`, `trajectory.csv`, `archive.csv`, `timing.toml` and
    /// what `draw` draws of the archive and τ (`explore.png`, `explore.svg` with
    /// [`crate::plot::draw_run`]), all of them or none ([`crate::record::write_run_folder`]: a
    /// failure leaves `out` as it was, or marked incomplete).
    pub fn write(&self, job: &ExploreJob, out: &Path, draw: Draw) -> Result<()> {
        crate::record::write_run_folder(out, |dir| self.write_files(job, dir, draw))
    }

    fn write_files(&self, job: &ExploreJob, out: &Path, draw: Draw) -> Result<()> {
        let (env, found) = (&self.env, &self.found);
        write_record(&out.join("summary.csv"), &self.summary)?;
        write_trajectory_csv(env, found, &out.join("trajectory.csv"))?;
        write_archive_csv(env, found, &out.join("archive.csv"))?;
        draw_exploration(env, found, job, out, draw)?;
        write_timing(
            &out.join("timing.toml"),
            self.seconds,
            found.env_steps,
            None,
        )
    }
}

/// Runs phase 1 for `job` into `out` on the environment it names: claims the folder (writing
/// `config.toml`, the resolved job) before any work, then [`ExploreRun::compute`] and
/// [`ExploreRun::write`] with the drawing step `draw` ([`crate::plot::draw_run`], or
/// [`crate::picture::no_pictures`]). `progress(steps, archive_len)` is called during the run.
pub fn run_explore(
    job: &Valid<ExploreJob>,
    out: &Path,
    draw: Draw,
    progress: impl FnMut(u64, usize),
) -> Result<(ExploreSummary, f64)> {
    let built = job.env_spec().build()?;
    let _lock = claim(job, out)?;
    crate::with_env!(built, |env| {
        let run = ExploreRun::compute(env, job, progress)?;
        run.write(job, out, draw)?;
        Ok((run.summary, run.seconds))
    })
}

/// `trajectory.csv`: `t, x, y, a0, a1`, where `(a0, a1)` led from τ_t to τ_{t+1} (empty on
/// the last row).
pub(crate) fn write_trajectory_csv<E: Env>(
    env: &E,
    found: &Exploration<E::State>,
    path: &Path,
) -> Result<()> {
    let mut header = vec!["t".to_string()];
    header.extend(env.obs_names());
    header.extend((0..env.action_dim()).map(|i| format!("a{i}")));
    let tau = &found.trajectory;
    let mut obs = vec![0.0; env.obs_dim()];
    let rows = tau.states.iter().enumerate().map(|(t, s)| {
        env.observe(s, &mut obs);
        let mut row = vec![t.to_string()];
        row.extend(obs.iter().map(f32::to_string));
        match tau.actions.get(t) {
            Some(a) => row.extend(a.iter().map(f32::to_string)),
            None => row.extend((0..env.action_dim()).map(|_| String::new())),
        }
        row
    });
    write_csv(path, &header, rows)
}

/// `archive.csv`: `id, parent, state_usage, bin_usage` and the state's observation (`x, y`
/// for the maze; parent empty for s_0).
pub(crate) fn write_archive_csv<E: Env>(
    env: &E,
    found: &Exploration<E::State>,
    path: &Path,
) -> Result<()> {
    let mut header: Vec<String> = ["id", "parent", "state_usage", "bin_usage"]
        .map(String::from)
        .to_vec();
    header.extend(env.obs_names());
    let archive = &found.archive;
    let mut obs = vec![0.0; env.obs_dim()];
    let rows = (0..archive.len() as u32).map(|id| {
        let parent = archive.parent(id);
        let (cs, cb) = archive.usage(id);
        let mut row = vec![
            id.to_string(),
            if parent == NO_PARENT {
                String::new()
            } else {
                parent.to_string()
            },
            cs.to_string(),
            cb.to_string(),
        ];
        env.observe(archive.state(id), &mut obs);
        row.extend(obs.iter().map(f32::to_string));
        row
    });
    write_csv(path, &header, rows)
}

/// Hands `draw` phase 1's picture: the archive's states and τ over `env`'s scene.
fn draw_exploration<E: Planar>(
    env: &E,
    found: &Exploration<E::State>,
    job: &ExploreJob,
    out: &Path,
    draw: Draw,
) -> Result<()> {
    let data = PictureData {
        points: (0..found.archive.len() as u32)
            .map(|i| env.point(found.archive.state(i)))
            .collect(),
        tau_paths: vec![found
            .trajectory
            .states
            .iter()
            .map(|s| env.point(s))
            .collect()],
        ..PictureData::default()
    };
    let title = format!(
        "phase 1, {}, seed {}: {} steps, |τ| = {}",
        job.env_spec().label(),
        job.seed,
        found.env_steps,
        found.trajectory.len()
    );
    draw(
        &RunPicture {
            stem: "explore".into(),
            title,
            scene: env.scene(),
            data: &data,
        },
        out,
    )
}

impl ExploreSummary {
    /// What `pbcs explore` prints, with the wall clock `seconds` and the archive's bin side.
    pub fn summary(&self, seconds: f64, bin_side: f32) -> String {
        format!(
            "{}, run seed {}: target reached after {} env steps ({:.3} s, {:.2} M steps/s)\n\
             trajectory τ: {} states; archive: {} states in {} bins of side {}",
            match (self.maze, self.maze_seed) {
                (Some(n), Some(m)) => format!("maze {n} (layout seed {m})"),
                _ => self.env.name().to_string(),
            },
            self.seed,
            self.env_steps,
            seconds,
            self.env_steps as f64 / seconds.max(1e-9) / 1e6,
            self.trajectory_len,
            self.archive_states,
            self.archive_bins,
            bin_side
        )
    }
}
