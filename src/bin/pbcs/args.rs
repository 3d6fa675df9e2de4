//! The command line's arguments: clap declarations, their help texts, and the few rules that
//! turn flags into a job (a config file or defaults, then the flags over it).

use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use pbcs::config::{self, Check, Located, Place, Preset, MAX_MAZE_SIZE};
use pbcs::envs::pointmaze::PointMazeConfig;
use pbcs::envs::EnvName;
use pbcs::experiment::Experiment;
use pbcs::learner::td3::ActorUpdate;
use pbcs::learner::LearnerConfig;
use serde::{de::DeserializeOwned, Serialize};
use std::path::PathBuf;

/// `pbcs <command> [flags]`.
#[derive(Parser)]
#[command(
    name = "pbcs",
    version,
    about = "PBCS (Matheron, Perrin, Sigaud 2020) reproduced"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// Flags shared by every run.
#[derive(Args)]
pub struct RunArgs {
    /// TOML config; the flags override its fields [default: the built-in defaults (`run`: the
    /// preset); the run folder's config.toml lists every value used].
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// The environment (`pbcs::envs`); overrides `env` [default: the config's, else the maze].
    /// --maze and --maze-seed apply to the maze only.
    #[arg(long, value_enum)]
    pub env: Option<EnvName>,
    /// Maze size N (2..=100); overrides `maze.size` [default: the config's, else 5].
    #[arg(long, allow_negative_numbers = true, value_parser = parse_maze_size)]
    pub maze: Option<usize>,
    /// Maze layout seed; overrides `maze.seed` [default: the config's, else 0].
    #[arg(long, allow_negative_numbers = true)]
    pub maze_seed: Option<u64>,
    /// Run seed; overrides `seed` [default: the config's, else 0].
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u64>,
    /// A map of one's own, for `--env pointmaze` or `--env antmaze`: a file of rows of 0 (free)
    /// and 1 (wall), one row per line, `#` comments; overrides `[pointmaze] map` (the run
    /// folder's config.toml keeps the rows).
    #[arg(long)]
    pub map: Option<PathBuf>,
    /// Output folder [default: out/explore/<where>-s<seed>, out/train/<where>-s<seed>-<algo>[-am],
    /// out/run/<preset or config file stem>/<where>-s<seed>[-nochain][-exact|-archive][-velocity],
    /// where is maze<N>-m<maze seed> for the maze, <env>-<H>x<W>-<8 hex of the rows' SHA-256>
    /// for a map of one's own (pointmaze, antmaze), the environment's name for another].
    /// A folder that holds another run (another config.toml) is refused, before any work.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

impl RunArgs {
    /// The config file (or `default()` without one) with `--env` and the maze and seed flags
    /// applied ([`Place`]).
    pub fn load<T: DeserializeOwned + Check + Serialize + Located>(
        &self,
        default: impl FnOnce() -> pbcs::Result<T>,
    ) -> anyhow::Result<T> {
        let (mut job, unset): (T, _) = match &self.config {
            Some(path) => {
                let job: T = config::load(path)?;
                let unset = pbcs::validate::unset_keys(path, &job);
                (job, Some((path, unset)))
            }
            None => (default()?, None),
        };
        let place = Place {
            env: self.env,
            maze_size: self.maze,
            maze_seed: self.maze_seed,
            seed: self.seed,
            map: match &self.map {
                Some(file) => Some(
                    PointMazeConfig::from_file(file)
                        .map_err(|e| anyhow::anyhow!("--map {}: {e}", file.display()))?
                        .map,
                ),
                None => None,
            },
        };
        place.apply(&mut job)?;
        if let Some((path, mut unset)) = unset {
            // The maze's parameters matter only on the maze.
            if !job.env_spec().name.is_maze() {
                unset.retain(|k| k != "maze");
            }
            if !unset.is_empty() {
                eprintln!(
                    "note: {} does not set {}: the defaults are used (the run folder's \
                     config.toml lists every value)",
                    path.display(),
                    unset.join(", ")
                );
            }
        }
        Ok(job)
    }

    /// `--out`, else the run's default folder (`runs::explore_out`, `train_out`, `run_out`).
    pub fn out_dir(&self, default: impl FnOnce() -> PathBuf) -> PathBuf {
        self.out.clone().unwrap_or_else(default)
    }

    pub fn bar(&self, template: &str, len: Option<u64>) -> ProgressBar {
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
pub struct LearnerArgs {
    /// Learner; overrides `learner.algo` [default: the config's, else ddpg]. Between ddpg and
    /// td3 only `algo` changes; another family starts from its own defaults.
    #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(LearnerConfig::algo_names()))]
    pub algo: Option<String>,
    /// TD3's actor update (ddpg, td3); overrides `learner.actor_update` [default: the config's,
    /// else gradient].
    #[arg(long, value_enum)]
    pub actor: Option<ActorUpdate>,
    /// Discount γ in [0, 1); overrides `learner.gamma` [default: the config's, else 0.9 for
    /// `run`, 0.99 for `train`].
    #[arg(long, allow_negative_numbers = true)]
    pub gamma: Option<f32>,
}

impl LearnerArgs {
    pub fn apply(&self, l: &mut LearnerConfig) -> pbcs::error::Result<()> {
        if let Some(algo) = &self.algo {
            l.switch_to(algo)?;
        }
        if let Some(actor) = self.actor {
            match l {
                LearnerConfig::Td3(c) => c.actor_update = actor,
                other => {
                    return Err(pbcs::error::Error::invalid(
                        "--actor",
                        format!(
                            "is TD3's actor update (ddpg, td3); {} has none",
                            other.algo()
                        ),
                    ))
                }
            }
        }
        if let Some(gamma) = self.gamma {
            l.set_gamma(gamma);
        }
        Ok(())
    }
}

#[derive(Subcommand)]
pub enum Command {
    /// Phase 1: explore an environment (the maze unless --env) until the target is reached;
    /// write the trajectory, the archive and a picture.
    Explore {
        #[command(flatten)]
        run: RunArgs,
    },
    /// A vanilla baseline: DDPG, TD3 (optionally with the argmax actor) or SAC, with HER where
    /// the config has [train.her], on an environment's own reward (the maze unless --env);
    /// write evaluations, visited states, the policy and a picture.
    Train {
        #[command(flatten)]
        run: RunArgs,
        #[command(flatten)]
        learner: LearnerArgs,
        /// Environment steps; overrides `train.steps` [default: the config's, else 1000000].
        #[arg(long)]
        steps: Option<u64>,
    },
    /// Re-run a chain saved by `pbcs run` (its `chain/` folder) on its environment: success rate with
    /// its Wilson interval; writes eval-s<seed>.csv and a picture (into the chain folder by default).
    Eval {
        /// The chain folder (`<run folder>/chain`).
        #[arg(long)]
        chain: PathBuf,
        /// Episodes, each from a start uniform in B_ε(s_0) (with phase2.first_starts = "drawn",
        /// where the environment's reset draws them).
        #[arg(long, default_value_t = 100,
              value_parser = clap::value_parser!(u64).range(1..=pbcs::validate::bounds::EPISODES))]
        episodes: u64,
        /// Seed of the start states [default: the run's seed, which reproduces its evaluation].
        #[arg(long)]
        seed: Option<u64>,
        /// Folder for eval-s<seed>.csv and the picture [default: the chain folder].
        #[arg(long)]
        out: Option<PathBuf>,
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
        /// PBCS without skill chaining (fail when a second skill would be needed); also turns
        /// off `phase2.retargets` and `phase2.chain_repairs`, which act between skills.
        #[arg(long)]
        no_chaining: bool,
        /// Start Backplay's episodes exactly at τ_K instead of in B_ε(τ_K).
        #[arg(long)]
        exact_starts: bool,
        /// A deadline from now (`90s`, `45m`, `3h 50m`): the run stops at the end of its first
        /// learning problem of phase 2 (or verification of the chain) at or past it that leaves
        /// another to make (with `phase2.chain = "goal_conditioned"`, its first test of the chain
        /// that does not pass), saved to <OUT>/run.resume, and exits with status 75
        /// (EX_TEMPFAIL); the same command goes on where it stopped, to the same bytes (phase 1,
        /// the last step of phase 2 and the evaluation are not cut: past them the run finishes).
        /// Without it the run still saves itself every ten minutes and goes on from there when
        /// run again after a cut.
        #[arg(long, value_parser = parse_stop_after)]
        stop_after: Option<std::time::Duration>,
    },
    /// The PBCS results table of one config: every maze size × seed, run by the same sweep as
    /// `pbcs exp run` (resumable: finished runs are read back, not re-run), then solved counts
    /// and step statistics beside the paper's.
    Table {
        /// TOML config of the runs (a `PbcsJob`, e.g. experiments/pbcs_paper.toml).
        #[arg(long)]
        config: Option<PathBuf>,
        /// The procedure, when no --config is given: `fast` (the default) or `paper`.
        #[arg(long, value_enum, conflicts_with = "config")]
        preset: Option<Preset>,
        /// Maze sizes.
        #[arg(long, value_delimiter = ',', default_value = "2,5,7,10,15")]
        sizes: Vec<usize>,
        /// Number of seeds: runs seeds 0..SEEDS (at least 1).
        #[arg(long, default_value_t = 10,
              value_parser = clap::value_parser!(u64).range(1..=pbcs::experiment::MAX_SEEDS))]
        seeds: u64,
        /// Runs at a time (one thread each).
        #[arg(long, default_value_t = 2, value_parser = parse_jobs)]
        jobs: usize,
        /// Results folder: rows in <OUT>/raw/<name>/, statistics in <OUT>/tables/<name>.csv,
        /// where <name> is the config's file stem or the preset's name [default: out/table].
        #[arg(long, default_value = "out/table")]
        out: PathBuf,
    },
    /// Experiments as data (experiments/*.toml): run a grid of (cell, seed) pairs into
    /// results/raw/, list its commands, or re-run one cell and compare with the committed rows.
    Exp {
        #[command(subcommand)]
        command: ExpCommand,
    },
    /// Aggregate every experiment's raw rows with polars into results/tables/ (needs the
    /// `polars` cargo feature: `make figures` turns it on).
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
        /// Folder of the generated LaTeX [default: paper/generated for the committed results
        /// (no profile, results folder `results`), else <results>/tex].
        #[arg(long)]
        tex: Option<PathBuf>,
    },
}

/// All experiment files of a folder, one profile, one results folder.
#[derive(Args)]
pub struct SetArgs {
    /// Folder of the experiment files.
    #[arg(long, default_value = "experiments")]
    pub experiments: PathBuf,
    /// Profile (e.g. `smoke`); none: the committed grids.
    #[arg(long)]
    pub profile: Option<String>,
    /// Results folder [default: results, or results-<profile>].
    #[arg(long)]
    pub results: Option<PathBuf>,
}

impl SetArgs {
    pub fn load(&self) -> anyhow::Result<(Vec<Experiment>, PathBuf)> {
        let profile = self.profile.as_deref();
        let exps = pbcs::pipeline::load_experiments(&self.experiments, profile)?;
        Ok((
            exps,
            pbcs::pipeline::results_dir(self.results.as_deref(), profile),
        ))
    }
}

/// Which experiment, which profile, where its results live.
#[derive(Args)]
pub struct ExpArgs {
    /// The experiment file (experiments/table.toml, gamma.toml, unseen.toml, beyond.toml, ...).
    pub file: PathBuf,
    /// A profile of the file (e.g. `smoke`); none: the committed grid.
    #[arg(long)]
    pub profile: Option<String>,
    /// Results folder [default: results, or results-<profile> for a profile].
    #[arg(long)]
    pub results: Option<PathBuf>,
}

impl ExpArgs {
    pub fn load(&self) -> anyhow::Result<(Experiment, PathBuf)> {
        let profile = self.profile.as_deref();
        let exp = Experiment::load(&self.file, profile)?;
        Ok((
            exp,
            pbcs::pipeline::results_dir(self.results.as_deref(), profile),
        ))
    }
}

#[derive(Subcommand)]
pub enum ExpCommand {
    /// Run every unfinished (cell, seed) pair (or one cell / one seed), `--jobs` at a time.
    Run {
        #[command(flatten)]
        exp: ExpArgs,
        /// Only this cell (`<method>-maze<N>`, `<method>-rooms`, see `pbcs exp list`).
        #[arg(long)]
        cell: Option<pbcs::experiment::CellKey>,
        /// Only this seed.
        #[arg(long)]
        seed: Option<u64>,
        /// Runs at a time (one thread each; the bytes written do not depend on it).
        #[arg(long, default_value_t = 2, value_parser = parse_jobs)]
        jobs: usize,
        /// An experiment whose environments this build cannot run (PointMaze without
        /// `--features mujoco`) is skipped with one line saying how to run it, instead of
        /// refused (`make results`).
        #[arg(long)]
        skip_unavailable: bool,
        /// A deadline from now (`90s`, `45m`, `3h 50m`): no run begins at or past it, and a
        /// vanilla run in progress stops at its first evaluation at or past it, and a PBCS run
        /// in progress at the end of its first step of phase 2 at or past it (a learning
        /// problem, a verification of the chain; goal-conditioned: a test of the chain that does
        /// not pass), each saved to its checkpoint. With runs unfinished the exit status is 75
        /// (EX_TEMPFAIL); the same command goes on where it stopped, to the same bytes. Under a
        /// cluster's time limit, leave the time of an evaluation interval's training, the
        /// evaluation and the save (for a PBCS run, of a learning problem and the save) to
        /// spare.
        #[arg(long, value_parser = parse_stop_after)]
        stop_after: Option<std::time::Duration>,
    },
    /// Print one `pbcs exp run` command per (cell, seed) (for `make -j` or a job array), with
    /// `# done` after finished ones, `# saved at N env steps` after vanilla runs in progress
    /// with a checkpoint (`# its checkpoint would be refused` where it is another job's).
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
        /// An experiment whose environments this build cannot run is listed as one comment
        /// line saying how to run it (with `--make`, a makefile with nothing to do).
        #[arg(long)]
        skip_unavailable: bool,
    },
    /// Re-run one cell (all its seeds, or one) in a scratch folder and compare with the
    /// committed raw rows: byte for byte, and if they differ, whether the new success rate lies
    /// inside the committed Wilson 95 % interval. Exits with an error if it does not.
    Check {
        #[command(flatten)]
        exp: ExpArgs,
        /// The cell (`<method>-maze<N>`, `<method>-rooms`).
        #[arg(long)]
        cell: pbcs::experiment::CellKey,
        /// Only this seed.
        #[arg(long)]
        seed: Option<u64>,
        /// Runs at a time.
        #[arg(long, default_value_t = 2, value_parser = parse_jobs)]
        jobs: usize,
        /// Fail unless every row is reproduced byte for byte (what CI asks of the rows the
        /// current code must reproduce).
        #[arg(long)]
        exact: bool,
    },
}

/// The most runs at a time `--jobs` takes (one thread each; more is a typo).
const MAX_JOBS: usize = 1024;

/// `--jobs`: a whole number from 1 to [`MAX_JOBS`] (before: 0 silently ran as 1).
fn parse_jobs(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if (1..=MAX_JOBS).contains(&n) => Ok(n),
        _ => Err(format!(
            "--jobs (runs at a time, one thread each) is a whole number of at least 1 and at \
             most {MAX_JOBS}, got {s:?}"
        )),
    }
}

/// The furthest deadline `--stop-after` takes: a year (more is a typo).
const MAX_STOP_AFTER: std::time::Duration = std::time::Duration::from_secs(366 * 24 * 3600);

/// `--stop-after`: a duration (`90s`, `45m`, `3h 50m`) of at most [`MAX_STOP_AFTER`].
fn parse_stop_after(s: &str) -> Result<std::time::Duration, String> {
    let d = humantime::parse_duration(s).map_err(|e| format!("{s:?}: {e}"))?;
    if d > MAX_STOP_AFTER {
        return Err(format!(
            "{s:?} is more than a year ahead (at most 366 days; more is a typo)"
        ));
    }
    Ok(d)
}

/// `--maze`: a whole number from 2 to [`MAX_MAZE_SIZE`], said so for anything else (a
/// negative number included).
fn parse_maze_size(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if (2..=MAX_MAZE_SIZE).contains(&n) => Ok(n),
        _ => Err(format!(
            "maze.size is a whole number from 2 to {MAX_MAZE_SIZE}, got {s:?}"
        )),
    }
}
