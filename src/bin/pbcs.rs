//! The `pbcs` command line: `pbcs explore ...` (phase 1) and `pbcs train ...` (vanilla
//! DDPG / TD3 baselines). Each subcommand loads an optional TOML config, applies the flags
//! over it, validates the result and runs the matching job of `pbcs::jobs`.

use anyhow::Context;
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use pbcs::config::{self, Check, ExploreJob, MazeConfig, RunJob, TrainJob};
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

/// Learner flags shared by `train` and `run`.
#[derive(Args)]
struct LearnerArgs {
    /// Learner preset; overrides `learner.algo`.
    #[arg(long, value_parser = ["ddpg", "td3"])]
    algo: Option<String>,
    /// Actor update; overrides `learner.actor_update`.
    #[arg(long, value_parser = ["gradient", "argmax"])]
    actor: Option<String>,
}

impl LearnerArgs {
    fn apply(&self, l: &mut pbcs::learner::LearnerConfig) {
        match self.algo.as_deref() {
            Some("ddpg") => l.algo = Algo::Ddpg,
            Some("td3") => l.algo = Algo::Td3,
            _ => {}
        }
        match self.actor.as_deref() {
            Some("gradient") => l.actor_update = ActorUpdate::Gradient,
            Some("argmax") => l.actor_update = ActorUpdate::Argmax,
            _ => {}
        }
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
        #[command(flatten)]
        learner: LearnerArgs,
        /// Environment steps; overrides `train.steps`.
        #[arg(long)]
        steps: Option<u64>,
    },
    /// PBCS: phase 1, then phase 2 (Backplay, shaped training, skill chaining); evaluate the
    /// chain; write the record, the chain and a picture.
    Run {
        #[command(flatten)]
        run: RunArgs,
        #[command(flatten)]
        learner: LearnerArgs,
        /// PBCS without skill chaining (fail when a second skill would be needed).
        #[arg(long)]
        no_chaining: bool,
        /// Start Backplay's episodes exactly at τ_K instead of in B_ε(τ_K).
        #[arg(long)]
        exact_starts: bool,
        /// Discount γ; overrides `learner.gamma`.
        #[arg(long)]
        gamma: Option<f32>,
    },
    /// The PBCS results table: `pbcs run` for every maze size × seed (resumable: finished runs
    /// are read back, not re-run), then solved counts and step statistics beside the paper's.
    Table {
        /// TOML config of the runs (a `RunJob`, e.g. experiments/pbcs_faithful.toml).
        #[arg(long)]
        config: Option<PathBuf>,
        /// Maze sizes.
        #[arg(long, value_delimiter = ',', default_value = "2,5,7,10,15")]
        sizes: Vec<usize>,
        /// Number of seeds: runs seeds 0..SEEDS.
        #[arg(long, default_value_t = 10)]
        seeds: u64,
        /// Runs at a time (one thread each).
        #[arg(long, default_value_t = 2)]
        jobs: usize,
        /// Output folder [default: out/table/<config file stem or "default">].
        #[arg(long)]
        out: Option<PathBuf>,
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
            learner,
            steps,
        } => train(&run, &learner, steps),
        Command::Run {
            run,
            learner,
            no_chaining,
            exact_starts,
            gamma,
        } => {
            let mut job: RunJob = run.load(|j: &mut RunJob| (&mut j.maze, &mut j.seed))?;
            learner.apply(&mut job.learner);
            if no_chaining {
                job.phase2.chaining = false;
            }
            if exact_starts {
                job.phase2.start = pbcs::pbcs::StartMode::Exact;
            }
            if let Some(g) = gamma {
                job.learner.gamma = g;
            }
            pbcs_run(&run, &job)
        }
        Command::Table {
            config,
            sizes,
            seeds,
            jobs,
            out,
        } => table(config.as_deref(), &sizes, seeds, jobs, out),
    }
}

fn table(
    config: Option<&std::path::Path>,
    sizes: &[usize],
    seeds: u64,
    jobs: usize,
    out: Option<PathBuf>,
) -> anyhow::Result<()> {
    let job: RunJob = match config {
        Some(p) => config::load(p)?,
        None => RunJob::default(),
    };
    for &n in sizes {
        let mut j = job.clone();
        j.maze.size = n;
        j.check()?;
    }
    let name = config
        .and_then(|p| p.file_stem())
        .map_or("default".to_string(), |s| s.to_string_lossy().into_owned());
    let out = out.unwrap_or_else(|| PathBuf::from(format!("out/table/{name}")));
    let seed_list: Vec<u64> = (0..seeds).collect();
    let total = (sizes.len() * seed_list.len()) as u64;
    let bar = ProgressBar::new(total);
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} runs [{elapsed}, eta {eta}] {msg}")
            .expect("valid template"),
    );
    let results = pbcs::jobs::run_grid(&job, sizes, &seed_list, &out, jobs, |r, secs| {
        bar.inc(1);
        bar.set_message(format!(
            "maze {} seed {}: {} in {} steps ({secs:.0} s)",
            r.maze,
            r.seed,
            if r.solved { "solved" } else { "not solved" },
            r.total_steps
        ));
    })?;
    bar.finish_and_clear();
    let records: Vec<_> = results.iter().map(|(r, _)| r.clone()).collect();
    pbcs::record::write_records(&out.join("records.csv"), &records)?;
    println!(
        "{} ({}), seeds 0..{seeds}; runs in {}",
        name,
        records.first().map_or("", |r| r.variant.as_str()),
        out.display()
    );
    println!("| maze | solved | env steps, median [min, max] | paper | median / paper | skills, median | wall s, median |");
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for &n in sizes {
        let rows: Vec<&(pbcs::jobs::RunRecord, f64)> =
            results.iter().filter(|(r, _)| r.maze == n).collect();
        let mut steps: Vec<f64> = rows.iter().map(|(r, _)| r.total_steps as f64).collect();
        let mut skills: Vec<f64> = rows.iter().map(|(r, _)| r.skills as f64).collect();
        let mut secs: Vec<f64> = rows.iter().map(|(_, s)| *s).collect();
        let med = |v: &mut Vec<f64>| pbcs::stats::median(v);
        let solved = rows.iter().filter(|(r, _)| r.solved).count();
        let paper = pbcs::jobs::paper_pbcs_steps(n);
        let m = med(&mut steps);
        println!(
            "| {n} | {solved}/{} | {:.0} [{:.0}, {:.0}] | {} | {} | {:.0} | {:.0} |",
            rows.len(),
            m,
            steps.first().copied().unwrap_or(f64::NAN),
            steps.last().copied().unwrap_or(f64::NAN),
            paper.map_or("-".into(), |p| p.to_string()),
            paper.map_or("-".into(), |p| format!("{:.2}", m / p as f64)),
            med(&mut skills),
            med(&mut secs),
        );
    }
    Ok(())
}

fn pbcs_run(run: &RunArgs, job: &RunJob) -> anyhow::Result<()> {
    job.check()?;
    let mut suffix = String::new();
    if !job.phase2.chaining {
        suffix.push_str("-nochain");
    }
    if job.phase2.start == pbcs::pbcs::StartMode::Exact {
        suffix.push_str("-exact");
    }
    let out = run.out_dir("run", &job.maze, job.seed, &suffix);
    let bar = run.bar("{spinner} [{elapsed}] {msg}", None);
    let clock = std::time::Instant::now();
    // Steps of the skills already finished, and the running skill's latest count.
    let (mut finished, mut current, mut current_skill) = (0u64, 0u64, 0usize);
    let (record, seconds) = pbcs::jobs::run_pbcs(job, &out, |skill, p| {
        if skill != current_skill {
            finished += current;
            current_skill = skill;
        }
        current = p.steps.train + p.steps.test;
        let total = finished + current;
        bar.set_message(format!(
            "skill {skill}: K {} → T {}, {} {:.0} %, {} phase-2 env steps ({:.0} steps/s)",
            p.k,
            p.t,
            if p.test { "test" } else { "train" },
            100.0 * p.success,
            total,
            total as f64 / clock.elapsed().as_secs_f64().max(1e-9)
        ));
        bar.tick();
    })
    .with_context(|| format!("PBCS on maze {} seed {}", job.maze.size, job.seed))?;
    bar.finish_and_clear();
    println!(
        "{} ({}) on maze {} (layout seed {}), run seed {}: {} — chain success {} over {} \
         episodes, {} skills{}",
        record.variant,
        record.learner,
        record.maze,
        record.maze_seed,
        record.seed,
        if record.solved {
            "SOLVED"
        } else {
            "not solved"
        },
        record.success_rate,
        job.phase2.eval_episodes,
        record.skills,
        if record.failure.is_empty() {
            String::new()
        } else {
            format!(", stopped: {}", record.failure)
        }
    );
    println!(
        "env steps: phase 1 {}, training {}, tests {}, total {}; |τ| = {}; {:.1} s",
        record.phase1_steps,
        record.train_steps,
        record.test_steps,
        record.total_steps,
        record.trajectory_len,
        seconds
    );
    println!(
        "wrote {}/{{record,skills,trajectory}}.csv, chain/, run.png, run.svg",
        out.display()
    );
    Ok(())
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

fn train(run: &RunArgs, learner: &LearnerArgs, steps: Option<u64>) -> anyhow::Result<()> {
    let mut job: TrainJob = run.load(|j: &mut TrainJob| (&mut j.maze, &mut j.seed))?;
    learner.apply(&mut job.learner);
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
