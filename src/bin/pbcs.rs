//! The `pbcs` command line, a thin layer over the library: `explore` (phase 1), `train`
//! (vanilla DDPG / TD3 baselines), `run` (PBCS), `eval` (re-run a saved chain), `table` (one
//! PBCS preset or config on sizes × seeds, as a one-method experiment), `exp` (experiment
//! grids: run, list, check), `aggregate` (with the `polars` feature) and `figures`. A run
//! subcommand loads an optional TOML config, applies the flags over it, validates the result
//! and calls `pbcs::runs`; the others call `pbcs::experiment`, `pbcs::tables`,
//! `pbcs::aggregate`, `pbcs::figures` and `pbcs::report`.

use anyhow::Context;
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use pbcs::config::{self, Check, ExploreJob, MazeConfig, Preset, RunJob, TrainJob};
use pbcs::learner::{ActorUpdate, Algo};
use pbcs::nn::kernel::Kernel;
use serde::de::DeserializeOwned;
use std::io::IsTerminal;
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
    /// TOML config; the flags override its fields [default: the built-in defaults (`run`: the
    /// preset); the run folder's config.toml lists every value used].
    #[arg(long)]
    config: Option<PathBuf>,
    /// Maze size N (2..=100); overrides `maze.size` [default: the config's, else 5].
    #[arg(long, allow_negative_numbers = true, value_parser = parse_maze_size)]
    maze: Option<usize>,
    /// Maze layout seed; overrides `maze.seed` [default: the config's, else 0].
    #[arg(long, allow_negative_numbers = true)]
    maze_seed: Option<u64>,
    /// Run seed; overrides `seed` [default: the config's, else 0].
    #[arg(long, allow_negative_numbers = true)]
    seed: Option<u64>,
    /// Output folder [default: out/explore/maze<N>-m<maze seed>-s<seed>,
    /// out/train/maze…-<algo>[-am], out/run/<preset or config file stem>/maze…[-nochain][-exact]].
    /// A folder that holds another run (another config.toml) is refused, before any work.
    #[arg(long)]
    out: Option<PathBuf>,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

impl RunArgs {
    /// The config file (or the defaults) with the maze and seed flags applied.
    fn load<T: DeserializeOwned + Check + Default + serde::Serialize>(
        &self,
        parts: impl FnOnce(&mut T) -> (&mut MazeConfig, &mut u64),
    ) -> anyhow::Result<T> {
        self.load_or(|| Ok(T::default()), parts)
    }

    /// The config file (or `default()` without one) with the maze and seed flags applied.
    fn load_or<T: DeserializeOwned + Check + serde::Serialize>(
        &self,
        default: impl FnOnce() -> anyhow::Result<T>,
        parts: impl FnOnce(&mut T) -> (&mut MazeConfig, &mut u64),
    ) -> anyhow::Result<T> {
        let mut job: T = match &self.config {
            Some(path) => {
                let job: T = config::load(path)?;
                note_defaults(path, &job);
                job
            }
            None => default()?,
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
    /// Learner preset; overrides `learner.algo` [default: the config's, else ddpg].
    #[arg(long, value_parser = ["ddpg", "td3"])]
    algo: Option<String>,
    /// Actor update; overrides `learner.actor_update` [default: the config's, else gradient].
    #[arg(long, value_parser = ["gradient", "argmax"])]
    actor: Option<String>,
    /// Discount γ in [0, 1); overrides `learner.gamma` [default: the config's, else 0.9 for
    /// `run`, 0.99 for `train`].
    #[arg(long)]
    gamma: Option<f32>,
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
        if let Some(g) = self.gamma {
            l.gamma = g;
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
        /// Environment steps; overrides `train.steps` [default: the config's, else 1000000].
        #[arg(long)]
        steps: Option<u64>,
    },
    /// Re-run a chain saved by `pbcs run` (its `chain/` folder) on its maze: success rate with
    /// its Wilson interval; writes eval-s<seed>.csv and a picture into the chain folder.
    Eval {
        /// The chain folder (`<run folder>/chain`).
        #[arg(long)]
        chain: PathBuf,
        /// Episodes, each from a start uniform in B_ε(s_0).
        #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u64).range(1..))]
        episodes: u64,
        /// Seed of the start states [default: the run's seed, which reproduces its evaluation].
        #[arg(long)]
        seed: Option<u64>,
    },
    /// PBCS: phase 1, then phase 2 (Backplay, shaped training, skill chaining); evaluate the
    /// chain; write the record, the chain and a picture.
    Run {
        #[command(flatten)]
        run: RunArgs,
        /// The procedure, when no --config is given: `fast` (ours, the default) or `paper`
        /// (the paper's procedure with our corrections): experiments/pbcs_<preset>.toml.
        #[arg(long, value_enum, conflicts_with = "config")]
        preset: Option<Preset>,
        #[command(flatten)]
        learner: LearnerArgs,
        /// PBCS without skill chaining (fail when a second skill would be needed).
        #[arg(long)]
        no_chaining: bool,
        /// Start Backplay's episodes exactly at τ_K instead of in B_ε(τ_K).
        #[arg(long)]
        exact_starts: bool,
    },
    /// The PBCS results table of one config: every maze size × seed, run by the same sweep as
    /// `pbcs exp run` (resumable: finished runs are read back, not re-run), then solved counts
    /// and step statistics beside the paper's.
    Table {
        /// TOML config of the runs (a `RunJob`, e.g. experiments/pbcs_paper.toml).
        #[arg(long)]
        config: Option<PathBuf>,
        /// The procedure, when no --config is given: `fast` (ours, the default, as for `pbcs
        /// run`) or `paper`.
        #[arg(long, value_enum, conflicts_with = "config")]
        preset: Option<Preset>,
        /// Maze sizes.
        #[arg(long, value_delimiter = ',', default_value = "2,5,7,10,15")]
        sizes: Vec<usize>,
        /// Number of seeds: runs seeds 0..SEEDS (at least 1).
        #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u64).range(1..))]
        seeds: u64,
        /// Runs at a time (one thread each).
        #[arg(long, default_value_t = 2)]
        jobs: usize,
        /// Results folder: rows in <OUT>/raw/<name>/, statistics in <OUT>/tables/<name>.csv,
        /// where <name> is the config's file stem or the preset's name [default: out/table].
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Experiments as data (experiments/*.toml): run a grid of (cell, seed) pairs into
    /// results/raw/, list its commands, or re-run one cell and compare with the committed rows.
    Exp {
        #[command(subcommand)]
        command: ExpCommand,
    },
    /// Aggregate every experiment's raw rows with polars into results/tables/<experiment>.csv
    /// (needs the `polars` cargo feature: `make figures` turns it on).
    Aggregate {
        #[command(flatten)]
        set: SetArgs,
    },
    /// Draw every figure and write the report's LaTeX from results/tables/ and the raw picture
    /// data (trains nothing).
    Figures {
        #[command(flatten)]
        set: SetArgs,
        /// Figure folder [default: <results>/figures].
        #[arg(long)]
        figures: Option<PathBuf>,
        /// Folder of the generated LaTeX [default: paper/generated, or <results>/tex for a
        /// profile].
        #[arg(long)]
        tex: Option<PathBuf>,
    },
}

/// All experiment files of a folder, one profile, one results folder.
#[derive(Args)]
struct SetArgs {
    /// Folder of the experiment files.
    #[arg(long, default_value = "experiments")]
    experiments: PathBuf,
    /// Profile (e.g. `smoke`); none: the committed grids.
    #[arg(long)]
    profile: Option<String>,
    /// Results folder [default: results, or results-<profile>].
    #[arg(long)]
    results: Option<PathBuf>,
}

impl SetArgs {
    fn load(&self) -> anyhow::Result<(Vec<pbcs::experiment::Experiment>, PathBuf)> {
        let profile = self.profile.as_deref();
        let exps = pbcs::pipeline::load_experiments(&self.experiments, profile)?;
        Ok((exps, results_dir(self.results.as_ref(), profile)))
    }
}

fn results_dir(results: Option<&PathBuf>, profile: Option<&str>) -> PathBuf {
    pbcs::pipeline::results_dir(results.map(PathBuf::as_path), profile)
}

/// Which experiment, which profile, where its results live.
#[derive(Args)]
struct ExpArgs {
    /// The experiment file (experiments/table.toml, gamma.toml, unseen.toml, beyond.toml).
    file: PathBuf,
    /// A profile of the file (e.g. `smoke`); none: the committed grid.
    #[arg(long)]
    profile: Option<String>,
    /// Results folder [default: results, or results-<profile> for a profile].
    #[arg(long)]
    results: Option<PathBuf>,
}

impl ExpArgs {
    fn load(&self) -> anyhow::Result<(pbcs::experiment::Experiment, PathBuf)> {
        let exp = pbcs::experiment::Experiment::load(&self.file, self.profile.as_deref())?;
        let results = results_dir(self.results.as_ref(), self.profile.as_deref());
        Ok((exp, results))
    }
}

#[derive(Subcommand)]
enum ExpCommand {
    /// Run every unfinished (cell, seed) pair (or one cell / one seed), `--jobs` at a time.
    Run {
        #[command(flatten)]
        exp: ExpArgs,
        /// Only this cell (`<method>-maze<N>`, see `pbcs exp list`).
        #[arg(long)]
        cell: Option<String>,
        /// Only this seed.
        #[arg(long)]
        seed: Option<u64>,
        /// Runs at a time (one thread each; the bytes written do not depend on it).
        #[arg(long, default_value_t = 2)]
        jobs: usize,
    },
    /// Print one `pbcs exp run` command per (cell, seed) (for `make -j` or a job array), with
    /// `# done` after finished ones.
    List {
        #[command(flatten)]
        exp: ExpArgs,
        /// Print a makefile instead: one rule per (cell, seed) whose target is the raw row, so
        /// `make -f runs.mk -j N` runs N at a time and skips finished ones.
        #[arg(long, conflicts_with = "slurm")]
        make: bool,
        /// Print a SLURM batch script instead: one array task per (cell, seed), each writing
        /// into the same results folder (`pbcs exp list FILE --slurm > runs.sbatch; sbatch
        /// runs.sbatch`).
        #[arg(long)]
        slurm: bool,
    },
    /// Re-run one cell (all its seeds, or one) in a scratch folder and compare with the
    /// committed raw rows: byte for byte, and if they differ, whether the new success rate lies
    /// inside the committed Wilson 95 % interval. Exits with an error if it does not.
    Check {
        #[command(flatten)]
        exp: ExpArgs,
        /// The cell (`<method>-maze<N>`).
        #[arg(long)]
        cell: String,
        /// Only this seed.
        #[arg(long)]
        seed: Option<u64>,
        /// Runs at a time.
        #[arg(long, default_value_t = 2)]
        jobs: usize,
        /// Fail unless every row is reproduced byte for byte (what CI asks of the rows the
        /// current code must reproduce).
        #[arg(long)]
        exact: bool,
    },
}

/// Says which top-level settings a config file leaves to their defaults (an empty file runs
/// the defaults; the user should know it did).
fn note_defaults<T: serde::Serialize>(path: &std::path::Path, job: &T) {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let given: toml::Table = toml::from_str(&text).unwrap_or_default();
    let Ok(toml::Value::Table(all)) = toml::Value::try_from(job) else {
        return;
    };
    let missing: Vec<&str> = all
        .keys()
        .filter(|k| !given.contains_key(*k))
        .map(String::as_str)
        .collect();
    if !missing.is_empty() {
        eprintln!(
            "note: {} does not set {}: the defaults are used (the run folder's config.toml \
             lists every value)",
            path.display(),
            missing.join(", ")
        );
    }
}

/// `--maze`: a whole number from 2 to 100, said so for anything else (a negative number
/// included).
fn parse_maze_size(s: &str) -> Result<usize, String> {
    match s.trim().parse::<i64>() {
        Ok(n) if (2..=100).contains(&n) => Ok(n as usize),
        _ => Err(format!(
            "maze.size is a whole number from 2 to 100, got {s:?}"
        )),
    }
}

fn main() -> ExitCode {
    // `pbcs exp list | head`: a closed pipe ends the program quietly, as for other command-line
    // tools, instead of a panic in println!.
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of SIGPIPE before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
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
    // The layer kernel of every run (PBCS_KERNEL, else the best this CPU runs), read once: a
    // bad name is an error here, before any work.
    let kernel = Kernel::from_env()?;
    match cli.command {
        Command::Explore { run } => explore(&run),
        Command::Train {
            run,
            learner,
            steps,
        } => train(&run, &learner, steps, kernel),
        Command::Run {
            run,
            preset,
            learner,
            no_chaining,
            exact_starts,
        } => {
            let preset = preset.unwrap_or(Preset::Fast);
            let mut job: RunJob = run.load_or(
                || Ok(preset.job()?),
                |j: &mut RunJob| (&mut j.maze, &mut j.seed),
            )?;
            learner.apply(&mut job.learner);
            if no_chaining {
                job.phase2.chaining = false;
            }
            if exact_starts {
                job.phase2.start = pbcs::phase2::StartMode::Exact;
            }
            // The default folder names the procedure, so runs of two presets or configs never
            // meet in one folder.
            let label = match &run.config {
                Some(path) => path
                    .file_stem()
                    .map_or("config".into(), |s| s.to_string_lossy().into_owned()),
                None => preset.name().to_string(),
            };
            pbcs_run(&run, &job, &label, kernel)
        }
        Command::Eval {
            chain,
            episodes,
            seed,
        } => {
            let e = pbcs::runs::eval_chain(&chain, episodes as usize, seed, kernel)?;
            let seed = seed.unwrap_or(e.job.seed);
            println!(
                "chain {} ({} skills) on maze {} (layout seed {}), start seed {seed}: success \
                 {}/{} = {:.1} % [Wilson 95 % {:.1}, {:.1} %]",
                chain.display(),
                e.skills,
                e.job.maze.size,
                e.job.maze.seed,
                e.successes,
                e.episodes,
                100.0 * e.successes as f64 / e.episodes as f64,
                100.0 * e.interval.0,
                100.0 * e.interval.1
            );
            println!("wrote {}/eval-s{seed}.{{csv,png,svg}}", chain.display());
            Ok(())
        }
        Command::Table {
            config,
            preset,
            sizes,
            seeds,
            jobs,
            out,
        } => table(config.as_deref(), preset, &sizes, seeds, jobs, kernel, out),
        Command::Aggregate { set } => aggregate(&set),
        Command::Figures { set, figures, tex } => make_figures(&set, figures, tex),
        Command::Exp { command } => match command {
            ExpCommand::Run {
                exp,
                cell,
                seed,
                jobs,
            } => exp_run(&exp, cell.as_deref(), seed, jobs, kernel),
            ExpCommand::List { exp, make, slurm } => exp_list(&exp, make, slurm),
            ExpCommand::Check {
                exp,
                cell,
                seed,
                jobs,
                exact,
            } => exp_check(&exp, &cell, seed, jobs, kernel, exact),
        },
    }
}

#[cfg(feature = "polars")]
fn aggregate(set: &SetArgs) -> anyhow::Result<()> {
    let (exps, results) = set.load()?;
    for a in pbcs::pipeline::aggregate(&exps, &results)? {
        if a.runs == 0 {
            println!(
                "{}: no raw rows in {}, skipped",
                a.experiment,
                results.display()
            );
        } else {
            println!(
                "{}: {} of {} runs in {} cells → {} (polars; checked against the plain computation)",
                a.experiment,
                a.runs,
                a.expected,
                a.cells,
                a.table.display()
            );
        }
    }
    Ok(())
}

#[cfg(not(feature = "polars"))]
fn aggregate(_: &SetArgs) -> anyhow::Result<()> {
    anyhow::bail!(
        "this build has no polars: build with `--features polars` (as `make figures` does), \
         or use the committed tables in results/tables/"
    )
}

fn make_figures(
    set: &SetArgs,
    figures: Option<PathBuf>,
    tex: Option<PathBuf>,
) -> anyhow::Result<()> {
    let (exps, results) = set.load()?;
    let figures = figures.unwrap_or_else(|| results.join("figures"));
    let tex = pbcs::pipeline::tex_dir(tex.as_deref(), set.profile.as_deref(), &results);
    let claims_file = set.experiments.join("claims.toml");
    let done = pbcs::pipeline::render(exps, &claims_file, &results, &figures, &tex)?;
    for (name, path) in &done.skipped {
        println!("{name}: no table at {}, skipped", path.display());
    }
    for (exp, stats) in &done.tables {
        println!("\n{} — {}", exp.name, exp.title);
        print!("{}", pbcs::tables::markdown(stats));
    }
    println!("\nthe paper's claims against our tables:");
    for c in &done.claims {
        println!(
            "- {} — {}: {}",
            c.id,
            c.verdict.word().to_uppercase(),
            c.ours
        );
    }
    println!(
        "\nwrote {} files into {} and {}",
        done.files.len(),
        figures.display(),
        tex.display()
    );
    Ok(())
}

fn run_bar(total: u64) -> ProgressBar {
    let bar = ProgressBar::new(total);
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} runs [{elapsed}, eta {eta}] {msg}")
            .expect("valid template"),
    );
    bar
}

fn describe(row: &pbcs::experiment::RawRow) -> String {
    format!(
        "{} seed {}: {} (success {:.2}) in {} env steps{}",
        row.cell,
        row.seed,
        if row.solved { "solved" } else { "not solved" },
        row.success_rate,
        row.env_steps,
        row.failure
            .map_or(String::new(), |f| format!(", {}", f.name()))
    )
}

/// Runs `runs` with [`pbcs::experiment::sweep`] behind a progress bar (finished runs are read
/// back): one line per run as it finishes, environment steps per second in the bar. Returns
/// the rows and how many runs ran now.
fn sweep_with_progress(
    exp: &pbcs::experiment::Experiment,
    runs: &[pbcs::experiment::Pending],
    results: &std::path::Path,
    jobs: usize,
    kernel: Kernel,
) -> anyhow::Result<(Vec<pbcs::experiment::RawRow>, usize)> {
    use pbcs::experiment::{sweep, Event};
    use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
    let bar = run_bar(runs.len() as u64);
    let steps = AtomicU64::new(0);
    let ran = AtomicUsize::new(0);
    let clock = std::time::Instant::now();
    let rows = sweep(exp, runs, results, jobs, kernel, |_, event| {
        bar.inc(1);
        if let Event::Ran(row, secs) = event {
            ran.fetch_add(1, Ordering::SeqCst);
            let total = steps.fetch_add(row.env_steps, Ordering::SeqCst) + row.env_steps;
            let line = format!("{} ({secs:.0} s)", describe(row));
            // Without a terminal the bar is hidden and drops its lines: a log (nohup, a
            // cluster's job output) still gets one line per finished run.
            if bar.is_hidden() {
                eprintln!("{line}");
            } else {
                bar.println(line);
            }
            bar.set_message(format!(
                "{:.0} env steps/s",
                total as f64 / clock.elapsed().as_secs_f64().max(1e-9)
            ));
        }
    })?;
    bar.finish_and_clear();
    Ok((rows, ran.into_inner()))
}

fn exp_run(
    args: &ExpArgs,
    cell: Option<&str>,
    seed: Option<u64>,
    jobs: usize,
    kernel: Kernel,
) -> anyhow::Result<()> {
    let (exp, results) = args.load()?;
    let runs = pbcs::experiment::plan(&exp, cell, seed)?;
    let (rows, ran) = sweep_with_progress(&exp, &runs, &results, jobs, kernel)?;
    println!(
        "{} ({}): {} runs, {ran} ran now, {} were finished; raw rows in {}",
        exp.name,
        exp.profile.as_deref().unwrap_or("committed grid"),
        rows.len(),
        rows.len() - ran,
        results.join("raw").join(&exp.name).display()
    );
    print!(
        "{}",
        pbcs::tables::markdown(&pbcs::tables::cell_stats(&exp, &rows))
    );
    Ok(())
}

fn exp_list(args: &ExpArgs, make: bool, slurm: bool) -> anyhow::Result<()> {
    let (exp, results) = args.load()?;
    let launch = pbcs::launch::Launch::new(
        &exp,
        &args.file,
        args.profile.as_deref(),
        args.results.as_deref(),
    );
    if make {
        print!("{}", launch.makefile(&results));
        return Ok(());
    }
    if slurm {
        print!("{}", launch.slurm(&results));
        return Ok(());
    }
    for p in launch.runs() {
        let done =
            pbcs::experiment::read_finished(p.cell, p.seed, &exp.cell_dir(&results, p.cell))?
                .is_some();
        println!(
            "pbcs {}{}",
            launch.args(&p),
            if done { "  # done" } else { "" }
        );
    }
    Ok(())
}

fn exp_check(
    args: &ExpArgs,
    cell: &str,
    seed: Option<u64>,
    jobs: usize,
    kernel: Kernel,
    exact: bool,
) -> anyhow::Result<()> {
    use pbcs::check::{check_cell, Verdict};
    let (exp, results) = args.load()?;
    let runs = pbcs::experiment::plan(&exp, Some(cell), seed)?;
    let bar = run_bar(runs.len() as u64);
    let check = check_cell(&exp, &results, cell, seed, jobs, kernel, |_, _| bar.inc(1))?;
    bar.finish_and_clear();
    for s in &check.seeds {
        println!(
            "seed {}: {} — committed: {}; now: {}",
            s.seed,
            if s.identical {
                "identical bytes"
            } else {
                "DIFFERENT"
            },
            describe(&s.committed),
            describe(&s.fresh)
        );
    }
    let (n, (lo, hi)) = (check.n(), check.interval());
    println!(
        "cell {cell}: {}/{n} rows identical byte for byte; solved committed {}/{n} \
         (Wilson 95 % [{lo:.3}, {hi:.3}]), now {}/{n}",
        check.identical(),
        check.solved_committed(),
        check.solved_now()
    );
    let verdict = check.verdict();
    if verdict != Verdict::Match {
        if let Some(note) = check.kernel_note() {
            println!("note: {note}");
        }
    }
    let rate = check.solved_now() as f64 / n as f64;
    match verdict {
        Verdict::Match => {
            println!("MATCH: the committed rows are reproduced exactly");
            Ok(())
        }
        Verdict::WithinInterval if exact => anyhow::bail!(
            "--exact: {} of {n} rows differ from the committed bytes",
            n - check.identical()
        ),
        Verdict::WithinInterval => {
            println!(
                "DIFFERENT BYTES, but the new success rate {rate:.2} lies inside the committed interval"
            );
            Ok(())
        }
        Verdict::Outside => anyhow::bail!(
            "the new success rate {rate:.2} lies outside the committed interval [{lo:.3}, {hi:.3}]"
        ),
    }
}

/// `pbcs table`: a one-method experiment built from the config ([`Experiment::of_job`]), run
/// by the same sweep as `pbcs exp run` (resumable, one lock per run, atomic rows), then shown
/// per maze beside the paper's steps; the cell statistics go to `<out>/tables/<name>.csv`.
///
/// [`Experiment::of_job`]: pbcs::experiment::Experiment::of_job
fn table(
    config: Option<&std::path::Path>,
    preset: Option<Preset>,
    sizes: &[usize],
    seeds: u64,
    jobs: usize,
    kernel: Kernel,
    out: Option<PathBuf>,
) -> anyhow::Result<()> {
    let preset = preset.unwrap_or(Preset::Fast);
    let job: RunJob = match config {
        Some(p) => config::load(p)?,
        None => preset.job()?,
    };
    // The preset's name or the config's file stem names the method, its folders and its
    // table: letters, digits and `_` (other characters become `_`).
    let name: String = config
        .and_then(|p| p.file_stem())
        .map_or(preset.name().to_string(), |s| {
            s.to_string_lossy().into_owned()
        })
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    let exp = pbcs::experiment::Experiment::of_job(&name, &job, sizes, seeds)?;
    let out = out.unwrap_or_else(|| PathBuf::from("out/table"));
    let runs = pbcs::experiment::plan(&exp, None, None)?;
    let (rows, ran) = sweep_with_progress(&exp, &runs, &out, jobs, kernel)?;
    let stats = pbcs::tables::cell_stats(&exp, &rows);
    let table = pbcs::tables::table_path(&out, &exp.name);
    pbcs::tables::write_table(&table, &stats)?;
    println!(
        "{name} ({}), seeds 0..{seeds}: {ran} ran now, {} were finished; raw rows in {}, \
         statistics in {}",
        job.phase2.variant().name(),
        rows.len() - ran,
        out.join("raw").join(&exp.name).display(),
        table.display()
    );
    print!(
        "{}",
        pbcs::tables::grid_markdown(&stats, &pbcs::tables::cell_timings(&exp, &out, &rows))
    );
    Ok(())
}

fn kind_name(kind: pbcs::phase2::EventKind) -> &'static str {
    match kind {
        pbcs::phase2::EventKind::Test => "test",
        pbcs::phase2::EventKind::Train => "train",
        pbcs::phase2::EventKind::Verify => "verify",
        pbcs::phase2::EventKind::ChainVerify => "chain verify",
    }
}

fn pbcs_run(run: &RunArgs, job: &RunJob, label: &str, kernel: Kernel) -> anyhow::Result<()> {
    job.check()?;
    let mut suffix = String::new();
    if !job.phase2.chaining {
        suffix.push_str("-nochain");
    }
    if job.phase2.start == pbcs::phase2::StartMode::Exact {
        suffix.push_str("-exact");
    }
    let out = run.out_dir(&format!("run/{label}"), &job.maze, job.seed, &suffix);
    let bar = run.bar("{spinner} [{elapsed}] {msg}", None);
    let clock = std::time::Instant::now();
    // Steps of the skills already finished, and the running skill's latest count.
    let (mut finished, mut current, mut current_skill) = (0u64, 0u64, 0usize);
    // Without a terminal (logs, CI, cluster jobs) the bar is hidden: a line per skill found.
    let lines = !run.quiet && !std::io::stderr().is_terminal();
    let (record, seconds) = pbcs::runs::run_pbcs(job, kernel, &out, |skill, p| {
        if skill != current_skill {
            finished += current;
            current_skill = skill;
            if lines {
                eprintln!(
                    "[{:.0} s] {skill} skills found, building skill {}; {finished} phase-2 env \
                     steps so far",
                    clock.elapsed().as_secs_f64(),
                    skill + 1
                );
            }
        }
        current = p.steps.train + p.steps.test;
        let total = finished + current;
        bar.set_message(format!(
            "{skill} skills found; building skill {}: K {} → T {}, {} {:.0} %, {} phase-2 env \
             steps ({:.0} steps/s)",
            skill + 1,
            p.k,
            p.t,
            kind_name(p.kind),
            100.0 * p.success,
            total,
            total as f64 / clock.elapsed().as_secs_f64().max(1e-9)
        ));
        bar.tick();
    })
    .with_context(|| format!("PBCS on maze {} seed {}", job.maze.size, job.seed))?;
    bar.finish_and_clear();
    println!(
        "{} ({}) on maze {} (layout seed {}), run seed {}: {} — chain success {:.0} % over {} \
         episodes, {} skills{}",
        record.variant.name(),
        record.learner,
        record.maze,
        record.maze_seed,
        record.seed,
        if record.solved {
            "SOLVED"
        } else {
            "not solved"
        },
        100.0 * record.success_rate,
        job.phase2.eval_episodes,
        record.skills,
        record
            .failure
            .map_or(String::new(), |f| format!(", stopped: {}", f.name()))
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
        "wrote {}/{{record,skills,trace,trajectory}}.csv, chain/, run.png, run.svg",
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
    let (summary, seconds) = pbcs::runs::run_explore(&job, &out, |steps, states| {
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
    learner: &LearnerArgs,
    steps: Option<u64>,
    kernel: Kernel,
) -> anyhow::Result<()> {
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
    let (summary, seconds) = pbcs::runs::run_train(&job, kernel, &out, |steps, success| {
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
