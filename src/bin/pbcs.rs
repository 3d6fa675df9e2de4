//! The `pbcs` command line: `pbcs explore ...` (more subcommands come with phase 2).

use anyhow::Context;
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use pbcs::config::{self, ExploreJob};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "pbcs",
    version,
    about = "PBCS (Matheron, Perrin, Sigaud 2020) reproduced"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Phase 1: explore a maze until the target is reached; write the trajectory, the archive
    /// and a picture.
    Explore {
        /// TOML config (an `ExploreJob`); flags below override its fields.
        #[arg(long)]
        config: Option<PathBuf>,
        /// Maze size N (2..=100); overrides `maze.size`.
        #[arg(long, allow_negative_numbers = true)]
        maze: Option<usize>,
        /// Maze layout seed; overrides `maze.seed`.
        #[arg(long, allow_negative_numbers = true)]
        maze_seed: Option<u64>,
        /// Run seed; overrides `seed`.
        #[arg(long, allow_negative_numbers = true)]
        seed: Option<u64>,
        /// Output folder [default: out/explore/maze<N>-m<maze seed>-s<seed>].
        #[arg(long)]
        out: Option<PathBuf>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Explore {
            config,
            maze,
            maze_seed,
            seed,
            out,
            quiet,
        } => {
            let mut job: ExploreJob = match &config {
                Some(path) => config::load(path)?,
                None => ExploreJob::default(),
            };
            if let Some(n) = maze {
                job.maze.size = n;
            }
            if let Some(m) = maze_seed {
                job.maze.seed = m;
            }
            if let Some(s) = seed {
                job.seed = s;
            }
            pbcs::config::Check::check(&job)?;
            let out = out.unwrap_or_else(|| {
                PathBuf::from(format!(
                    "out/explore/maze{}-m{}-s{}",
                    job.maze.size, job.maze.seed, job.seed
                ))
            });
            let bar = if quiet {
                ProgressBar::hidden()
            } else {
                ProgressBar::new_spinner()
            };
            bar.set_style(
                ProgressStyle::with_template(
                    "{spinner} phase 1: {human_pos} env steps ({per_sec}), {msg} [{elapsed}]",
                )
                .expect("valid template"),
            );
            let (summary, seconds) = pbcs::jobs::run_explore(&job, &out, |steps, states| {
                bar.set_position(steps);
                bar.set_message(format!("{states} archived states"));
            })
            .with_context(|| format!("explore maze {} seed {}", job.maze.size, job.seed))?;
            bar.finish_and_clear();
            println!(
                "maze {} (layout seed {}), run seed {}: target reached after {} env steps \
                 ({:.3} s, {:.2} M steps/s)",
                summary.maze,
                summary.maze_seed,
                summary.seed,
                summary.env_steps,
                seconds,
                summary.env_steps as f64 / seconds.max(1e-9) / 1e6
            );
            println!(
                "trajectory τ: {} states; archive: {} states in {} bins of side {}",
                summary.trajectory_len,
                summary.archive_states,
                summary.archive_bins,
                job.explore.bin_side
            );
            println!(
                "wrote {}/{{summary,trajectory,archive}}.csv, explore.png, explore.svg",
                out.display()
            );
            Ok(())
        }
    }
}
