//! The chain's evaluation from B_ε(s_0) (or from the starts the environment's reset draws,
//! `phase2.first_starts = "drawn"`), the one used by `pbcs run`, the sweeps and `pbcs eval` (a
//! saved chain re-run).

use crate::config::{Located, PbcsJob};
use crate::env::Planar;
use crate::env::{evaluation_starts, Env, Scene};
use crate::envs::maze::Maze;
use crate::envs::EnvName;
use crate::error::{Error, Result};
use crate::nn::kernel::Kernel;
use crate::phase2::SkillChain;
use crate::picture::{Draw, PictureData, RunPicture};
use crate::rng::Seeds;
use std::path::Path;

/// Chain rollouts drawn in the picture.
pub const DRAWN_ROLLOUTS: usize = 10;

/// The activation balls of `chain` as drawn over `env` ([`Planar::ball_point`]).
pub(crate) fn ball_circles<E: Planar>(env: &E, chain: &SkillChain) -> Vec<((f32, f32), f32)> {
    chain
        .skills
        .iter()
        .map(|s| (env.ball_point(&s.activation.center), s.activation.radius))
        .collect()
}

pub use crate::env::EvalEpisode;

/// A chain's evaluation episodes and the states (start first) of its first
/// [`DRAWN_ROLLOUTS`] rollouts.
pub type ChainEpisodes<S> = (Vec<EvalEpisode>, Vec<Vec<S>>);

/// The evaluation of a chain built for `job`: `episodes` episodes from starts uniform in
/// B_ε(s_0) (with `phase2.first_starts = "drawn"`, where the environment's reset draws them)
/// drawn from the `Eval` stream of `seed` (for a chain aiming at each episode's own
/// goal, [`SkillChain::needs_goal`], with goals drawn from its `EvalGoal` stream), each at most
/// `phase2.eval_max_steps` steps; the episodes and the first [`DRAWN_ROLLOUTS`] rollouts.
pub fn evaluate_chain<E: Env>(
    env: &E,
    chain: &SkillChain,
    job: &PbcsJob,
    episodes: usize,
    seed: u64,
) -> Result<ChainEpisodes<E::State>> {
    let mut rows = Vec::with_capacity(episodes);
    let mut rollouts = Vec::new();
    let starts = chain_eval_starts(env, job, episodes, seed)?;
    // A chain aiming at each episode's own goal is judged on goals its environment draws.
    let mut goals = Seeds::new(seed).stream(crate::rng::Stream::EvalGoal);
    for start in starts {
        let start = chain.episode_start(env, start, &mut goals);
        let r = chain.run(env, start, job.phase2.eval_max_steps);
        rows.push(EvalEpisode {
            success: r.success,
            steps: r.states.len() - 1,
        });
        if rollouts.len() < DRAWN_ROLLOUTS {
            rollouts.push(r.states);
        }
    }
    Ok((rows, rollouts))
}

/// The starts of a chain's evaluation ([`evaluate_chain`]): `episodes` states uniform in
/// B_ε(s_0) ([`evaluation_starts`]), or with `phase2.first_starts = "drawn"` drawn as the
/// environment's reset draws them, from the `Eval` stream of `seed`.
pub fn chain_eval_starts<E: Env>(
    env: &E,
    job: &PbcsJob,
    episodes: usize,
    seed: u64,
) -> Result<Vec<E::State>> {
    match job.phase2.first_starts(env)? {
        Some(d) => {
            let mut rng = Seeds::new(seed).stream(crate::rng::Stream::Eval);
            let like = env.start();
            Ok((0..episodes)
                .map(|_| d.drawn_start(&like, &mut rng))
                .collect())
        }
        None => evaluation_starts(env, job.phase2.epsilon, episodes, &Seeds::new(seed)),
    }
}

pub use crate::phase2::CHAIN_JOB;

/// What `pbcs eval` measured: a saved chain re-run from its evaluation's starts
/// ([`chain_eval_starts`]: uniform in B_ε(s_0), or drawn with `phase2.first_starts = "drawn"`).
#[derive(Debug, Clone)]
pub struct ChainEval {
    /// The job that built the chain (from the chain folder).
    pub job: PbcsJob,
    /// Skills in the chain.
    pub skills: usize,
    /// The seed of the start states.
    pub seed: u64,
    /// Episodes run.
    pub episodes: usize,
    /// Episodes that reached the target.
    pub successes: usize,
    /// Wilson 95 % interval of the success rate.
    pub interval: (f64, f64),
    /// Each episode: success and steps.
    pub rows: Vec<EvalEpisode>,
    /// The picture: the first rollouts over the environment, with the activation balls.
    pub picture: PictureData,
    scene: Scene,
}

/// A chain saved by `pbcs run` with what it needs to run: the job that built it (`run.toml`
/// beside `manifest.toml`, or `../config.toml` for chains saved before it existed), the maze
/// of that job, and the chain, its policies on `kernel`. A chain in a run folder marked
/// incomplete ([`crate::record::check_complete`]), a folder without the job, a manifest with a
/// bad value ([`SkillChain::load`]) or policies that do not fit the maze
/// ([`SkillChain::check_env`]), or bad weights are errors naming the file.
pub fn load_saved_chain(chain_dir: &Path, kernel: Kernel) -> Result<(PbcsJob, Maze, SkillChain)> {
    let (job, chain) = load_saved_job(chain_dir, kernel)?;
    if !job.env.is_maze() {
        return Err(Error::invalid(
            "env",
            format!(
                "{}: a chain of env = \"{}\", not of the maze (`pbcs eval` runs it)",
                chain_dir.display(),
                job.env.name()
            ),
        ));
    }
    let maze = Maze::new(&job.maze)?;
    chain.check_env(&maze, &chain_dir.join("manifest.toml"))?;
    Ok((job, maze, chain))
}

/// A saved chain's job and chain, of any environment: the checks of [`load_saved_chain`] but
/// the environment's (acting from given observations needs no environment; a chain of
/// PointMaze loads without MuJoCo).
pub fn load_saved_job(chain_dir: &Path, kernel: Kernel) -> Result<(PbcsJob, SkillChain)> {
    let run_dir = match chain_dir.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        Some(_) => std::path::PathBuf::from("."),
        None => chain_dir.join(".."),
    };
    crate::record::check_complete(chain_dir)?;
    crate::record::check_complete(&run_dir)?;
    let own = chain_dir.join(CHAIN_JOB);
    let job_path = if own.exists() {
        own
    } else {
        let parent = chain_dir.join("..").join("config.toml");
        if !parent.exists() {
            return Err(Error::io(
                &own,
                std::io::Error::other(
                    "not found: not a chain saved by `pbcs run` (it writes run.toml beside \
                     manifest.toml)",
                ),
            ));
        }
        parent
    };
    let job: PbcsJob = crate::validate::load(&job_path)?;
    let chain = SkillChain::load(chain_dir, kernel)?;
    Ok((job, chain))
}

/// Re-runs the chain saved in `chain_dir` on the environment its job names: `episodes` episodes
/// from the evaluation's starts ([`chain_eval_starts`]: uniform in B_ε(s_0), or drawn with
/// `phase2.first_starts = "drawn"`), drawn from the `Eval` stream of `seed` (default: the run's
/// own seed, which reproduces the run's evaluation exactly), each at most
/// `phase2.eval_max_steps` steps, the policies on `kernel`. Writes nothing
/// ([`ChainEval::write`] does). A folder without the chain's job (`run.toml`, or
/// `../config.toml` for chains saved before it existed), a malformed manifest or bad weights
/// are errors naming the file.
pub fn eval_chain(
    chain_dir: &Path,
    episodes: usize,
    seed: Option<u64>,
    kernel: Kernel,
) -> Result<ChainEval> {
    if episodes == 0 {
        return Err(Error::invalid("--episodes", "must be at least 1"));
    }
    let (job, chain) = load_saved_job(chain_dir, kernel)?;
    let seed = seed.unwrap_or(job.seed);
    let manifest = chain_dir.join("manifest.toml");
    let (rows, rollout_paths, circles, scene) = crate::with_env!(job.env_spec().build()?, |env| {
        chain.check_env(&env, &manifest)?;
        let (rows, rollouts) = evaluate_chain(&env, &chain, &job, episodes, seed)?;
        let points: Vec<Vec<(f32, f32)>> = rollouts
            .iter()
            .map(|r| r.iter().map(|s| env.point(s)).collect())
            .collect();
        (rows, points, ball_circles(&env, &chain), env.scene())
    });
    let successes = rows.iter().filter(|r| r.success).count();
    let interval = crate::stats::wilson(successes as u64, episodes as u64, crate::stats::Z95);
    let picture = PictureData {
        rollout_paths,
        circles,
        ..PictureData::default()
    };
    Ok(ChainEval {
        skills: chain.skills.len(),
        job,
        seed,
        episodes,
        successes,
        interval,
        rows,
        picture,
        scene,
    })
}

impl ChainEval {
    /// Writes `eval-s<seed>.csv` (one row per episode: success, steps) and
    /// what `draw` draws of the first rollouts over the environment (`eval-s<seed>.png` and
    /// `.svg` with [`crate::plot::draw_run`]) into `out` (`pbcs eval`: the chain folder unless
    /// `--out` says otherwise).
    pub fn write(&self, out: &Path, draw: Draw) -> Result<()> {
        let seed = self.seed;
        crate::record::create_folder(out)?;
        crate::record::write_records(&out.join(format!("eval-s{seed}.csv")), &self.rows)?;
        let title = format!(
            "saved chain, {}, eval seed {seed}: success {}/{}",
            self.job.env_spec().label(),
            self.successes,
            self.episodes
        );
        draw(
            &RunPicture {
                stem: format!("eval-s{seed}"),
                title,
                scene: self.scene.clone(),
                data: &self.picture,
            },
            out,
        )
    }
}

impl ChainEval {
    /// What `pbcs eval` prints for the chain in `chain_dir` evaluated from starts of `seed`.
    pub fn summary(&self, chain_dir: &Path, seed: u64) -> String {
        format!(
            "chain {} ({} skills) on {}, start seed {seed}: success {}/{} = {:.1} % [Wilson 95 \
             % {:.1}, {:.1} %]",
            chain_dir.display(),
            self.skills,
            match self.job.env {
                EnvName::Maze => format!(
                    "maze {} (layout seed {})",
                    self.job.maze.size, self.job.maze.seed
                ),
                other => other.name().to_string(),
            },
            self.successes,
            self.episodes,
            100.0 * self.successes as f64 / self.episodes as f64,
            100.0 * self.interval.0,
            100.0 * self.interval.1
        )
    }
}
