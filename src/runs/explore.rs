//! `pbcs explore`: phase 1 alone, its trajectory, archive and picture.

use super::{claim, write_timing};
use crate::config::ExploreJob;
use crate::env::Env;
use crate::env::Planar;
use crate::error::Result;
use crate::explore::{explore, Exploration, NO_PARENT};
use crate::maze::Maze;
use crate::plot::{render_scene, MazePicture, SVG_MAX_POINTS};
use crate::record::{write_csv, write_record};
use crate::rng::{Seeds, Stream};
use crate::validate::Check;
use parry2d::math::Point;
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// The one-row summary of a phase-1 run (`summary.csv`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExploreSummary {
    /// Maze size N.
    pub maze: usize,
    /// Maze layout seed.
    pub maze_seed: u64,
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
}

/// One phase-1 run's outcome ([`ExploreRun::compute`]): the summary row, everything
/// exploration found and the wall-clock seconds; [`ExploreRun::write`] writes it.
#[derive(Debug, Clone)]
pub struct ExploreRun {
    /// The maze explored.
    pub maze: Maze,
    /// The one-row summary.
    pub summary: ExploreSummary,
    /// τ and the archive.
    pub found: Exploration<Point<f32>>,
    /// Wall-clock seconds of the run (not deterministic).
    pub seconds: f64,
}

impl ExploreRun {
    /// Runs phase 1 for `job`; `progress(steps, archive_len)` is called during the run.
    /// Writes nothing.
    pub fn compute(job: &ExploreJob, progress: impl FnMut(u64, usize)) -> Result<ExploreRun> {
        job.check()?;
        let maze = Maze::new(&job.maze)?;
        let mut rng = Seeds::new(job.seed).stream(Stream::Explore);
        let clock = Instant::now();
        let found = explore(&maze, &job.explore, &mut rng, progress)?;
        let seconds = clock.elapsed().as_secs_f64();
        let summary = ExploreSummary {
            maze: job.maze.size,
            maze_seed: job.maze.seed,
            seed: job.seed,
            env_steps: found.env_steps,
            trajectory_len: found.trajectory.len(),
            archive_states: found.archive.len(),
            archive_bins: found.archive.bins(),
        };
        Ok(ExploreRun {
            maze,
            summary,
            found,
            seconds,
        })
    }

    /// Writes into `out`: `summary.csv`, `trajectory.csv`, `archive.csv`, `explore.png`,
    /// `explore.svg` and `timing.toml`, all of them or none
    /// ([`crate::record::write_run_folder`]: a failure leaves `out` as it was, or marked
    /// incomplete).
    pub fn write(&self, job: &ExploreJob, out: &Path) -> Result<()> {
        crate::record::write_run_folder(out, |dir| self.write_files(job, dir))
    }

    fn write_files(&self, job: &ExploreJob, out: &Path) -> Result<()> {
        let (maze, found) = (&self.maze, &self.found);
        write_record(&out.join("summary.csv"), &self.summary)?;
        write_trajectory_csv(maze, found, &out.join("trajectory.csv"))?;
        write_archive_csv(maze, found, &out.join("archive.csv"))?;
        render_exploration(maze, found, job, out)?;
        write_timing(
            &out.join("timing.toml"),
            self.seconds,
            found.env_steps,
            None,
        )
    }
}

/// Runs phase 1 for `job` into `out`: claims the folder (writing `config.toml`, the resolved
/// job) before any work, then [`ExploreRun::compute`] and [`ExploreRun::write`].
/// `progress(steps, archive_len)` is called during the run.
pub fn run_explore(
    job: &ExploreJob,
    out: &Path,
    progress: impl FnMut(u64, usize),
) -> Result<(ExploreSummary, f64)> {
    job.check()?;
    claim(job, out)?;
    let run = ExploreRun::compute(job, progress)?;
    run.write(job, out)?;
    Ok((run.summary, run.seconds))
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

/// `archive.csv`: `id, parent, state_usage, bin_usage, x, y` (parent empty for s_0).
pub(crate) fn write_archive_csv(
    maze: &Maze,
    found: &Exploration<Point<f32>>,
    path: &Path,
) -> Result<()> {
    let mut header: Vec<String> = ["id", "parent", "state_usage", "bin_usage"]
        .map(String::from)
        .to_vec();
    header.extend(maze.obs_names());
    let archive = &found.archive;
    let rows = (0..archive.len() as u32).map(|id| {
        let s = archive.state(id);
        let parent = archive.parent(id);
        let (cs, cb) = archive.usage(id);
        [
            id.to_string(),
            if parent == NO_PARENT {
                String::new()
            } else {
                parent.to_string()
            },
            cs.to_string(),
            cb.to_string(),
            s.x.to_string(),
            s.y.to_string(),
        ]
    });
    write_csv(path, &header, rows)
}

pub(crate) fn render_exploration(
    maze: &Maze,
    found: &Exploration<Point<f32>>,
    job: &ExploreJob,
    out: &Path,
) -> Result<()> {
    let points: Vec<(f32, f32)> = (0..found.archive.len() as u32)
        .map(|i| {
            let s = found.archive.state(i);
            (s.x, s.y)
        })
        .collect();
    let path: Vec<(f32, f32)> = found.trajectory.states.iter().map(|s| (s.x, s.y)).collect();
    let picture = MazePicture {
        title: format!(
            "phase 1, maze {} (layout {}), seed {}: {} steps, |τ| = {}",
            job.maze.size,
            job.maze.seed,
            job.seed,
            found.env_steps,
            found.trajectory.len()
        ),
        points: &points,
        tau_paths: vec![&path],
        ..MazePicture::default()
    };
    render_scene(
        &maze.scene(),
        &picture,
        &out.join("explore.png"),
        &out.join("explore.svg"),
        SVG_MAX_POINTS,
    )
}

impl ExploreSummary {
    /// What `pbcs explore` prints, with the wall clock `seconds` and the archive's bin side.
    pub fn summary(&self, seconds: f64, bin_side: f32) -> String {
        format!(
            "maze {} (layout seed {}), run seed {}: target reached after {} env steps \
             ({:.3} s, {:.2} M steps/s)\ntrajectory τ: {} states; archive: {} states in {} bins \
             of side {}",
            self.maze,
            self.maze_seed,
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
