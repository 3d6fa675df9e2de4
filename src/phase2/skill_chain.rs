//! The result of phase 2: a chain of skills — policies π_i with activation balls
//! A_i = B_ε(τ_{K_i}) — its execution (π_0 until the state enters A_1, then π_1, ...) and its
//! persistence (`manifest.toml` and one safetensors file per policy).

use super::goal::Inputs;
use super::goal::{weighted_dist, BallMetric};
use crate::env::Env;
use crate::error::{Error, Result};
use crate::nn::kernel::Kernel;
use crate::nn::Mlp;
use crate::rng::{Seeds, Stream};
use crate::rollout::{lockstep, Agent, Verdict};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A closed ball in observation space.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Ball {
    /// Centre.
    pub center: Vec<f32>,
    /// Radius.
    pub radius: f32,
    /// Weights of the distance ([`weighted_dist`]; empty: all 1, a ball in position;
    /// [`super::goal::BallMetric::weights`] with velocity).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub weights: Vec<f32>,
}

impl Ball {
    /// The ball of `radius` around `center`, in position (unit weights).
    pub fn new(center: Vec<f32>, radius: f32) -> Self {
        Ball {
            center,
            radius,
            weights: Vec::new(),
        }
    }

    /// The ball of `radius` around the observation `obs` of `env`, measured by `metric`.
    pub fn around<E: Env>(env: &E, obs: &[f32], radius: f32, metric: BallMetric) -> Self {
        Ball {
            center: metric.center(env, obs),
            radius,
            weights: metric.weights(env),
        }
    }

    /// Whether `obs` is in the ball (d ≤ radius, d in the ball's metric).
    pub fn contains(&self, obs: &[f32]) -> bool {
        weighted_dist(obs, &self.center, &self.weights) <= self.radius
    }
}

/// A skill: a policy and its activation set.
#[derive(Debug, Clone, PartialEq)]
pub struct Skill {
    /// π_i.
    pub policy: Mlp,
    /// A_i = B_ε(τ_{K_i}).
    pub activation: Ball,
    /// K_i: the index on τ of the ball's centre.
    pub start_index: usize,
    /// The index on τ of the skill's target (the next skill's K, or N for the last one).
    pub target_index: usize,
    /// What π_i sees and emits (goal-relative observations, actions in [−1, 1]ᵈ).
    pub inputs: Inputs,
}

/// A chain of skills in execution order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SkillChain {
    /// π_0 … π_n with A_0 … A_n.
    pub skills: Vec<Skill>,
    /// The layer kernel the policies run on (not saved: [`SkillChain::load`] is told it).
    pub kernel: Kernel,
}

/// One execution of a chain.
#[derive(Debug, Clone, PartialEq)]
pub struct Rollout<S> {
    /// Visited states, start included.
    pub states: Vec<S>,
    /// Index of the skill that chose each action (one per step).
    pub skill_used: Vec<usize>,
    /// Whether the environment's reward was reached.
    pub success: bool,
}

/// `manifest.toml`. Since issue 48 it says what belongs to the chain: the number of skills,
/// each policy file's SHA-256 and, for a chain saved by `pbcs run`, the job file beside it and
/// its SHA-256; [`SkillChain::load`] refuses a folder whose files do not match. A manifest
/// written before has none of them and loads as it did, its files unchecked.
#[derive(Serialize, Deserialize)]
pub(crate) struct Manifest {
    /// The number of skills (`[[skills]]` tables): a manifest cut short is refused.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    skill_count: Option<usize>,
    /// The job file in the chain's folder (`run.toml`), for a chain saved with its job.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    job_file: Option<String>,
    /// That file's SHA-256.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    job_sha256: Option<String>,
    skills: Vec<ManifestSkill>,
}

#[derive(Serialize, Deserialize)]
pub(crate) struct ManifestSkill {
    file: String,
    /// The policy file's SHA-256 (absent in manifests written before issue 48).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    sha256: Option<String>,
    center: Vec<f32>,
    radius: f32,
    /// [`Ball::weights`] (absent: a ball in position).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    weights: Vec<f32>,
    start_index: usize,
    target_index: usize,
    sizes: Vec<usize>,
    /// The policy's tanh scale (1 for actions in [−1, 1]).
    action_bounds: Vec<f32>,
    /// [`Inputs::origin`]: subtracted from observations.
    origin: Vec<f32>,
    /// [`Inputs::action_scale`]: multiplies the policy's actions.
    action_scale: Vec<f32>,
}

impl SkillChain {
    /// Executes the chain from `start`: π_0 until the state enters A_1, then π_1, and so on,
    /// until the environment's positive reward or `max_steps` steps. When a state lies in
    /// several later activation balls, the chain switches to the last of them (a skill that
    /// overshoots its goal into a later ball hands over there). Each skill sees its own
    /// [`Inputs`]. An empty chain takes no step.
    pub fn run<E: Env>(&self, env: &E, start: E::State, max_steps: usize) -> Rollout<E::State> {
        self.run_limited(env, start, max_steps, None)
    }

    /// [`SkillChain::run`], and with `per_skill = Some(m)` the episode also ends (a failure)
    /// when one skill has acted `m` times without handing over, or when a step does not move
    /// the state (a greedy chain on a pure step is then stuck for good): the limits of a
    /// skill's own tests, used by the chain's verification.
    pub fn run_limited<E: Env>(
        &self,
        env: &E,
        start: E::State,
        max_steps: usize,
        per_skill: Option<usize>,
    ) -> Rollout<E::State> {
        let mut run = Execution {
            chain: self,
            skill: 0,
            acted: 0,
            per_skill,
            obs: vec![0.0; env.obs_dim()],
            ws: crate::nn::Workspace::with_kernel(self.kernel),
            rollout: Rollout {
                states: vec![start.clone()],
                skill_used: Vec::new(),
                success: false,
            },
        };
        if self.skills.is_empty() || per_skill == Some(0) {
            return run.rollout;
        }
        let tally = lockstep(env, &mut run, vec![start], max_steps, |_| false);
        run.rollout.success = tally.successes == 1;
        run.rollout
    }

    /// The skill that acts at observation `raw` when skill `current` acted last: the last
    /// later skill whose activation ball contains `raw` (a skill that overshoots its goal into
    /// a later ball hands over there), else `current`. Start an execution with `current = 0`.
    ///
    /// ```
    /// use pbcs::phase2::{Ball, SkillChain};
    /// # use pbcs::phase2::{goal::Inputs, Skill};
    /// # use pbcs::nn::{Head, Mlp};
    /// # use pbcs::rng::{Seeds, Stream};
    /// # let skill = |c: [f32; 2]| Skill {
    /// #     policy: Mlp::new(&[2, 2], Head::Linear, &mut Seeds::new(0).stream(Stream::Init)),
    /// #     activation: Ball::new(c.to_vec(), 0.1),
    /// #     start_index: 0, target_index: 1, inputs: Inputs::new(vec![0.0; 2], vec![1.0; 2]),
    /// # };
    /// // Three skills whose balls are centred at x = 0, 1 and 2.
    /// let chain = SkillChain { skills: vec![skill([0.0, 0.0]), skill([1.0, 0.0]), skill([2.0, 0.0])], ..Default::default() };
    /// assert_eq!(chain.active_skill(0, &[0.5, 0.0]), 0); // in no later ball: π_0 goes on
    /// assert_eq!(chain.active_skill(0, &[1.05, 0.0]), 1); // enters A_1
    /// assert_eq!(chain.active_skill(0, &[2.0, 0.0]), 2); // overshoots into A_2
    /// assert_eq!(chain.active_skill(2, &[1.0, 0.0]), 2); // never back to an earlier skill
    /// ```
    pub fn active_skill(&self, current: usize, raw: &[f32]) -> usize {
        (current + 1..self.skills.len())
            .rev()
            .find(|&j| self.skills[j].activation.contains(raw))
            .unwrap_or(current)
    }

    /// Skill `i`'s action at observation `raw`, in the environment's units, into `action`
    /// (`obs` is scratch space of the observation's length): π_i on what it sees
    /// ([`Inputs::observation`]), scaled back by [`Inputs::env_action`].
    pub fn act(
        &self,
        i: usize,
        raw: &[f32],
        obs: &mut [f32],
        action: &mut [f32],
        ws: &mut crate::nn::Workspace,
    ) {
        let skill = &self.skills[i];
        skill.inputs.observation(raw, obs);
        let a = skill.policy.forward(obs, 1, ws);
        skill.inputs.env_action(a, action);
    }

    /// Saves the chain into `dir`: `skill{i}.safetensors` per policy and `manifest.toml`
    /// (activation balls, trajectory indices, network shapes, the number of skills and each
    /// policy file's SHA-256), written last.
    pub fn save(&self, dir: &Path) -> Result<()> {
        self.save_with_job(dir, None)
    }

    /// [`SkillChain::save`], with the job that built the chain written beside it first
    /// (`job` = (file name, its text): `run.toml`), its SHA-256 in the manifest, so that a job
    /// file copied in from another run is refused when the chain is loaded.
    pub fn save_with_job(&self, dir: &Path, job: Option<(&str, &str)>) -> Result<()> {
        let mut manifest = Manifest {
            skill_count: Some(self.skills.len()),
            job_file: None,
            job_sha256: None,
            skills: Vec::new(),
        };
        if let Some((name, text)) = job {
            crate::record::write_atomic(&dir.join(name), |w| w.write_all(text.as_bytes()))?;
            manifest.job_file = Some(name.to_string());
            manifest.job_sha256 = Some(crate::record::sha256_hex(text.as_bytes()));
        }
        for (i, skill) in self.skills.iter().enumerate() {
            let file = format!("skill{i}.safetensors");
            skill.policy.save(&dir.join(&file))?;
            let sha256 = Some(crate::record::file_sha256(&dir.join(&file))?);
            let bounds = match skill.policy.head() {
                crate::nn::Head::Tanh(b) => b.clone(),
                crate::nn::Head::Linear => Vec::new(),
            };
            manifest.skills.push(ManifestSkill {
                file,
                sha256,
                center: skill.activation.center.clone(),
                radius: skill.activation.radius,
                weights: skill.activation.weights.clone(),
                start_index: skill.start_index,
                target_index: skill.target_index,
                sizes: skill.policy.sizes().to_vec(),
                action_bounds: bounds,
                origin: skill.inputs.origin.clone(),
                action_scale: skill.inputs.action_scale.clone(),
            });
        }
        let text = crate::validate::to_toml(&manifest, &dir.join("manifest.toml"))?;
        crate::record::write_atomic(&dir.join("manifest.toml"), |w| w.write_all(text.as_bytes()))?;
        // A chain saved here before may have had more skills: its extra policy files go, so the
        // folder holds exactly what the manifest lists.
        for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
            let path = entry.map_err(|e| Error::io(dir, e))?.path();
            let name = path.file_name().unwrap_or_default().to_string_lossy();
            let listed = manifest.skills.iter().any(|s| s.file == name);
            if name.starts_with("skill") && name.ends_with(".safetensors") && !listed {
                std::fs::remove_file(&path).map_err(|e| Error::io(&path, e))?;
            }
        }
        Ok(())
    }

    /// Loads a chain saved by [`SkillChain::save`], its policies to run on `kernel`. Every
    /// value of the manifest is checked before a weight is read: at least one skill; finite
    /// numbers; radius, action scales and action bounds positive; sizes, centre, origin and
    /// scales of agreeing lengths; `start_index <= target_index`; a policy file inside the
    /// folder holding at least the parameters its sizes say. Then what belongs to the chain
    /// (where the manifest says it, as every manifest since issue 48 does): as many skills as
    /// `skill_count`, each policy file and the job file with the SHA-256 recorded, so that a
    /// manifest cut short, policy files swapped or copied in from another run, or another
    /// run's job are refused. Then the weights (their shapes, all finite). An error names
    /// `manifest.toml` (or the file) and the field (`skills[2].center`).
    pub fn load(dir: &Path, kernel: Kernel) -> Result<Self> {
        let path = dir.join("manifest.toml");
        let manifest: Manifest = crate::validate::read_toml(&path)?;
        manifest.check(&path)?;
        manifest.check_files(dir, &path)?;
        let mut skills = Vec::new();
        for (i, m) in manifest.skills.into_iter().enumerate() {
            // Sizes that promise more parameters than the file holds are refused before the
            // network is allocated (a typo in `sizes` must not exhaust the memory).
            let weights = dir.join(&m.file);
            let bytes = std::fs::metadata(&weights)
                .map_err(|e| Error::io(&weights, e))?
                .len();
            let params = parameters(&m.sizes).unwrap_or(usize::MAX);
            if (params as u64).saturating_mul(4) > bytes {
                return Err(Error::parse(
                    &path,
                    format!(
                        "skills[{i}].sizes: {:?} means {params} parameters, more than {} holds \
                         ({bytes} bytes)",
                        m.sizes, m.file
                    ),
                ));
            }
            let mut rng = Seeds::new(0).stream(Stream::Init);
            let head = if m.action_bounds.is_empty() {
                crate::nn::Head::Linear
            } else {
                crate::nn::Head::Tanh(m.action_bounds.clone())
            };
            let mut policy = Mlp::new(&m.sizes, head, &mut rng);
            policy.load(&weights)?;
            skills.push(Skill {
                policy,
                activation: Ball {
                    center: m.center,
                    radius: m.radius,
                    weights: m.weights,
                },
                start_index: m.start_index,
                target_index: m.target_index,
                inputs: Inputs::new(m.origin, m.action_scale),
            });
        }
        Ok(SkillChain { skills, kernel })
    }

    /// Checks that the chain fits `env` (its manifest at `path`, named in errors): every
    /// policy takes the environment's observations and gives its actions, and a tanh policy's
    /// largest action (its bound times the skill's action scale) stays within the
    /// environment's bound (what training wrote: scale b with bound 1, or scale 1 with bound b).
    pub fn check_env<E: Env>(&self, env: &E, path: &Path) -> Result<()> {
        for (i, s) in self.skills.iter().enumerate() {
            let sizes = s.policy.sizes();
            let (input, output) = (sizes[0], sizes[sizes.len() - 1]);
            if input != env.obs_dim() || output != env.action_dim() {
                return Err(Error::parse(
                    path,
                    format!(
                        "skills[{i}].sizes: {sizes:?} takes {input} inputs and gives {output} \
                         actions, the environment has {} observations and {} actions",
                        env.obs_dim(),
                        env.action_dim()
                    ),
                ));
            }
            // A weighted ball measures the velocity too (BallMetric::PositionVelocity).
            let (velocity, what) = if s.activation.weights.is_empty() {
                (0, "position")
            } else {
                let dims = env.velocity_balls().map_or(0, |v| v.velocity_dims());
                (dims, "position and velocity")
            };
            let want = env.position_dims() + velocity;
            if s.activation.center.len() != want {
                return Err(Error::parse(
                    path,
                    format!(
                        "skills[{i}].center: has {} values, the environment's {what} {want}",
                        s.activation.center.len(),
                    ),
                ));
            }
            if let crate::nn::Head::Tanh(bounds) = s.policy.head() {
                for (j, (scale, bound)) in s.inputs.action_scale.iter().zip(bounds).enumerate() {
                    let (reach, limit) = (scale * bound, env.action_bound(j));
                    if reach > limit * (1.0 + 1e-4) {
                        return Err(Error::parse(
                            path,
                            format!(
                                "skills[{i}].action_scale: {scale} times the policy's bound \
                                 {bound} gives actions up to {reach}, beyond the environment's \
                                 bound {limit}"
                            ),
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}

/// The parameter count of an MLP of layer sizes `sizes` (None if it overflows).
fn parameters(sizes: &[usize]) -> Option<usize> {
    sizes.windows(2).try_fold(0usize, |n, w| {
        w[0].checked_mul(w[1])?.checked_add(w[1])?.checked_add(n)
    })
}

/// Refuses `file` (named `what` in the manifest at `manifest`) unless its SHA-256 is `want`.
fn check_sha256(manifest: &Path, what: &str, file: &Path, want: &str) -> Result<()> {
    let got = crate::record::file_sha256(file)?;
    if got == want {
        return Ok(());
    }
    Err(Error::parse(
        manifest,
        format!(
            "{what}: {} has SHA-256 {got}, the manifest records {want}: not the file this \
             chain was saved with (swapped, edited, or copied from another run)",
            file.display()
        ),
    ))
}

impl Manifest {
    /// The files of a chain saved since issue 48 are the ones it was saved with: as many
    /// skills as `skill_count`, the job file and each policy file with the SHA-256 recorded.
    /// (An older manifest records none of them: nothing to check.)
    fn check_files(&self, dir: &Path, path: &Path) -> Result<()> {
        if let Some(n) = self.skill_count {
            if n != self.skills.len() {
                return Err(Error::parse(
                    path,
                    format!(
                        "skill_count: {n} skills recorded, {} [[skills]] tables found (a \
                         manifest cut short or added to)",
                        self.skills.len()
                    ),
                ));
            }
        }
        match (&self.job_file, &self.job_sha256) {
            (Some(file), Some(want)) => {
                let plain = Path::new(file).file_name() == Some(std::ffi::OsStr::new(file));
                if !plain {
                    return Err(Error::parse(
                        path,
                        format!("job_file: must name a file in the chain's folder, got {file:?}"),
                    ));
                }
                check_sha256(path, "job_sha256", &dir.join(file), want)?;
            }
            (None, None) => {}
            _ => {
                return Err(Error::parse(
                    path,
                    "job_file and job_sha256: one without the other",
                ))
            }
        }
        for (i, s) in self.skills.iter().enumerate() {
            if let Some(want) = &s.sha256 {
                check_sha256(
                    path,
                    &format!("skills[{i}].sha256"),
                    &dir.join(&s.file),
                    want,
                )?;
            }
        }
        Ok(())
    }

    /// Checks every value of the manifest read from `path` before a file it names is read:
    /// at least one skill, and each skill's values ([`ManifestSkill::check`]). An error names
    /// `path` and the field.
    fn check(&self, path: &Path) -> Result<()> {
        if self.skills.is_empty() {
            return Err(Error::parse(
                path,
                "skills: the chain has no skill (a saved chain has at least one)",
            ));
        }
        for (i, skill) in self.skills.iter().enumerate() {
            skill.check().map_err(|(field, why)| {
                Error::parse(path, format!("skills[{i}].{field}: {why}"))
            })?;
        }
        Ok(())
    }
}

impl ManifestSkill {
    /// The activation ball lies in the position part of the observation (its first
    /// `Env::position_dims` values: all of the maze's, x and y of PointMaze's), or, with
    /// weights (balls in position and velocity), in the position and the velocity after it:
    /// 1 to `input` values, and weights, if any, one per value, positive and finite.
    fn check_center(&self, input: usize) -> std::result::Result<(), (&'static str, String)> {
        if self.center.is_empty() || self.center.len() > input {
            return Err((
                "center",
                format!(
                    "has {} values, the network (sizes {:?}) needs 1 to {input} (the \
                     observation's position part, and with weights its velocity)",
                    self.center.len(),
                    self.sizes
                ),
            ));
        }
        let n = self.center.len();
        if !(self.weights.is_empty() || self.weights.len() == n) {
            return Err((
                "weights",
                format!(
                    "has {} values, the centre {n} (or none: a ball in position)",
                    self.weights.len()
                ),
            ));
        }
        if self.weights.iter().any(|w| !(w.is_finite() && *w > 0.0)) {
            return Err((
                "weights",
                format!("must be positive and finite, got {:?}", self.weights),
            ));
        }
        Ok(())
    }

    /// The first bad value of the skill, as (field, why).
    fn check(&self) -> std::result::Result<(), (&'static str, String)> {
        let plain = Path::new(&self.file).file_name() == Some(std::ffi::OsStr::new(&self.file));
        if !plain {
            return Err((
                "file",
                format!(
                    "must name a file in the chain's folder, got {:?}",
                    self.file
                ),
            ));
        }
        if self.sizes.len() < 2 || self.sizes.contains(&0) {
            return Err((
                "sizes",
                format!(
                    "needs an input, an output and no empty layer, got {:?}",
                    self.sizes
                ),
            ));
        }
        if parameters(&self.sizes).is_none() {
            return Err((
                "sizes",
                format!("{:?} has more parameters than can be counted", self.sizes),
            ));
        }
        let (input, output) = (self.sizes[0], self.sizes[self.sizes.len() - 1]);
        let bounds = (!self.action_bounds.is_empty()).then_some(&self.action_bounds);
        self.check_center(input)?;
        for (field, values, want, positive) in [
            ("center", Some(&self.center), self.center.len(), false),
            ("origin", Some(&self.origin), input, false),
            ("action_scale", Some(&self.action_scale), output, true),
            ("action_bounds", bounds, output, true),
        ] {
            let Some(values) = values else { continue };
            if values.len() != want {
                return Err((
                    field,
                    format!(
                        "has {} values, the network (sizes {:?}) needs {want}",
                        values.len(),
                        self.sizes
                    ),
                ));
            }
            if values.iter().any(|v| !v.is_finite()) {
                return Err((field, format!("must be finite numbers, got {values:?}")));
            }
            if positive && values.iter().any(|&v| v <= 0.0) {
                return Err((field, format!("must be positive, got {values:?}")));
            }
        }
        if !(self.radius.is_finite() && self.radius > 0.0) {
            return Err((
                "radius",
                format!("must be positive and finite, got {}", self.radius),
            ));
        }
        if self.start_index > self.target_index {
            return Err((
                "start_index",
                format!(
                    "{} lies after the skill's target_index {}",
                    self.start_index, self.target_index
                ),
            ));
        }
        Ok(())
    }
}

/// One execution of a chain ([`SkillChain::run_limited`]) as an agent: the active skill acts,
/// a later skill whose ball the state enters takes over, and the states and the skill of each
/// step are recorded.
struct Execution<'c, S> {
    chain: &'c SkillChain,
    /// The skill acting, and how many times it has acted since it took over.
    skill: usize,
    acted: usize,
    per_skill: Option<usize>,
    /// The acting skill's view of the observation.
    obs: Vec<f32>,
    ws: crate::nn::Workspace,
    rollout: Rollout<S>,
}

impl<E: Env> Agent<E> for Execution<'_, E::State> {
    fn act(&mut self, _lanes: &[usize], raw: &[f32], action: &mut [f32]) {
        let j = self.chain.active_skill(self.skill, raw);
        if j != self.skill {
            self.skill = j;
            self.acted = 0;
        }
        self.acted += 1;
        self.chain
            .act(self.skill, raw, &mut self.obs, action, &mut self.ws);
    }

    fn after(
        &mut self,
        _: usize,
        _: usize,
        state: &E::State,
        _: &[f32],
        step: &crate::env::Step<E::State>,
        next_raw: &[f32],
    ) -> Verdict {
        self.rollout.skill_used.push(self.skill);
        self.rollout.states.push(step.state.clone());
        if step.reward > 0.0 && step.terminal {
            return Verdict::Success;
        }
        let Some(m) = self.per_skill else {
            return Verdict::Running;
        };
        // With a per-skill limit, a step that does not move ends the episode (a greedy chain
        // on a pure step is stuck for good), and so does a skill about to act an m + 1-th
        // time without handing over.
        let stuck = step.state == *state;
        let spent = self.acted >= m && self.chain.active_skill(self.skill, next_raw) == self.skill;
        if stuck || spent {
            Verdict::Failure
        } else {
            Verdict::Running
        }
    }
}
