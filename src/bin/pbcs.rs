//! The `pbcs` command line: `pbcs explore ...` (phase 1) and `pbcs train ...` (vanilla
//! DDPG / TD3 baselines). Each subcommand loads an optional TOML config, applies the flags
//! over it, validates the result and runs the matching job of `pbcs::jobs`.

use anyhow::Context;
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use pbcs::config::{self, Check, ExploreJob, MazeConfig, TrainJob};
use pbcs::learner::{ActorUpdate, Algo};
use serde::de::DeserializeOwned;
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

/// Flags shared by every run.
#[derive(Args)]
struct RunArgs {
    /// TOML config; the flags override its fields.
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
    /// Output folder [default: out/<command>/maze<N>-m<maze seed>-s<seed>[-<algo>]].
    #[arg(long)]
    out: Option<PathBuf>,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

impl RunArgs {
    /// The config file (or the defaults) with the maze and seed flags applied.
    fn load<T: DeserializeOwned + Check + Default>(
        &self,
        parts: impl FnOnce(&mut T) -> (&mut MazeConfig, &mut u64),
    ) -> anyhow::Result<T> {
        let mut job: T = match &self.config {
            Some(path) => config::load(path)?,
            None => T::default(),
        };
        let (maze, seed) = parts(&mut job);
        if let Some(n) = self.maze {
            maze.size = n;
        }
        if let Some(m) = self.maze_seed {
            maze.seed = m;
        }
        if let Some(s) = self.seed {
            *seed = s;
        }
        Ok(job)
    }

    fn out_dir(&self, command: &str, maze: &MazeConfig, seed: u64, suffix: &str) -> PathBuf {
        self.out.clone().unwrap_or_else(|| {
            PathBuf::from(format!(
                "out/{command}/maze{}-m{}-s{seed}{suffix}",
                maze.size, maze.seed
            ))
        })
    }

    fn bar(&self, template: &str, len: Option<u64>) -> ProgressBar {
        let bar = match (self.quiet, len) {
            (true, _) => return ProgressBar::hidden(),
            (false, Some(n)) => ProgressBar::new(n),
            (false, None) => ProgressBar::new_spinner(),
        };
        bar.set_style(ProgressStyle::with_template(template).expect("valid template"));
        bar
    }
}

#[derive(Subcommand)]
enum Command {
    /// Phase 1: explore a maze until the target is reached; write the trajectory, the archive
    /// and a picture.
    Explore {
        #[command(flatten)]
        run: RunArgs,
    },
    /// A vanilla baseline: DDPG or TD3 (optionally with the argmax actor) on the maze's own
    /// reward; write evaluations, visited states, the actor and a picture.
    Train {
        #[command(flatten)]
        run: RunArgs,
        /// Learner preset; overrides `learner.algo`.
        #[arg(long, value_parser = ["ddpg", "td3"])]
        algo: Option<String>,
        /// Actor update; overrides `learner.actor_update`.
        #[arg(long, value_parser = ["gradient", "argmax"])]
        actor: Option<String>,
        /// Environment steps; overrides `train.steps`.
        #[arg(long)]
        steps: Option<u64>,
    },
}

fn main() -> ExitCode {
    // One thread per process (use cores for seeds): pin candle's thread pool before any candle
    // call, unless the user chose otherwise. Our own kernels are single-threaded.
    for var in ["RAYON_NUM_THREADS", "CANDLE_NUM_THREADS"] {
        if std::env::var_os(var).is_none() {
            std::env::set_var(var, "1");
        }
    }
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
        Command::Explore { run } => explore(&run),
        Command::Train {
            run,
            algo,
            actor,
            steps,
        } => train(&run, algo.as_deref(), actor.as_deref(), steps),
    }
}

fn explore(run: &RunArgs) -> anyhow::Result<()> {
    let job: ExploreJob = run.load(|j: &mut ExploreJob| (&mut j.maze, &mut j.seed))?;
    job.check()?;
    let out = run.out_dir("explore", &job.maze, job.seed, "");
    let bar = run.bar(
        "{spinner} phase 1: {human_pos} env steps ({per_sec}), {msg} [{elapsed}]",
        None,
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
        summary.trajectory_len, summary.archive_states, summary.archive_bins, job.explore.bin_side
    );
    println!(
        "wrote {}/{{summary,trajectory,archive}}.csv, explore.png, explore.svg",
        out.display()
    );
    Ok(())
}

fn train(
    run: &RunArgs,
    algo: Option<&str>,
    actor: Option<&str>,
    steps: Option<u64>,
) -> anyhow::Result<()> {
    let mut job: TrainJob = run.load(|j: &mut TrainJob| (&mut j.maze, &mut j.seed))?;
    match algo {
        Some("ddpg") => job.learner.algo = Algo::Ddpg,
        Some("td3") => job.learner.algo = Algo::Td3,
        _ => {}
    }
    match actor {
        Some("gradient") => job.learner.actor_update = ActorUpdate::Gradient,
        Some("argmax") => job.learner.actor_update = ActorUpdate::Argmax,
        _ => {}
    }
    if let Some(s) = steps {
        job.train.steps = s;
    }
    job.check()?;
    let mut suffix = format!("-{}", job.learner.algo.name());
    if job.learner.actor_update == ActorUpdate::Argmax {
        suffix.push_str("-am");
    }
    let out = run.out_dir("train", &job.maze, job.seed, &suffix);
    let bar = run.bar(
        "{bar:30} {human_pos}/{human_len} env steps ({per_sec}, eta {eta}), {msg}",
        Some(job.train.steps),
    );
    let (summary, seconds) = pbcs::jobs::run_train(&job, &out, |steps, success| {
        bar.set_position(steps);
        bar.set_message(format!("greedy success {success}"));
    })
    .with_context(|| format!("train on maze {} seed {}", job.maze.size, job.seed))?;
    bar.finish_and_clear();
    println!(
        "{} ({} actor) on maze {} (layout seed {}), run seed {}: {} env steps, {} episodes, \
         {:.1} s ({:.0} steps/s)",
        summary.algo,
        summary.actor_update,
        summary.maze,
        summary.maze_seed,
        summary.seed,
        summary.env_steps,
        summary.episodes,
        seconds,
        summary.env_steps as f64 / seconds.max(1e-9)
    );
    println!(
        "greedy success: final {}, best {}; visited {} bins of side {}",
        summary.final_success, summary.best_success, summary.visited_bins, job.train.visit_bin
    );
    println!(
        "wrote {}/{{summary,evals,visited}}.csv, actor.safetensors, train.png, train.svg",
        out.display()
    );
    Ok(())
}
