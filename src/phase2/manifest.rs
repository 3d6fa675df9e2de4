//! A chain's persistence: `manifest.toml` and one safetensors file per policy
//! ([`SkillChain::save`], [`SkillChain::load`]), every value of the manifest checked before a
//! weight is read, and the files checked to be the ones the chain was saved with.

use super::goal::Inputs;
use super::skill_chain::{Ball, Skill, SkillChain};
use crate::error::{Error, Result};
use crate::learner::load_policy;
use crate::nn::kernel::Kernel;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The file in a saved chain's folder that holds the job that built it (what `pbcs eval` and
/// `pbcs.load_chain` read, and the only job file a manifest may name).
pub const CHAIN_JOB: &str = "run.toml";

/// `manifest.toml`. Since issue 48 it says what belongs to the chain: the number of skills,
/// each policy file's SHA-256 and, for a chain saved by `pbcs run`, the job file beside it and
/// its SHA-256; [`SkillChain::load`] refuses a folder whose files do not match. A manifest
/// written before has none of them and loads as it did, its files unchecked.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
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
    /// The length of the τ phase 2 chained along (shortened, where it was): the last skill
    /// ends at its last state, the target (absent before issue 77: unchecked).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    trajectory_len: Option<usize>,
    /// Where the chain starts along τ: 0 for a complete chain, past it for one phase 2 left
    /// incomplete (saved since issue 77): a manifest cut at its first skill is refused.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    chain_start: Option<usize>,
    skills: Vec<ManifestSkill>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ManifestSkill {
    file: String,
    /// The policy's kind ([`Policy::kind`], read back by [`load_policy`]; absent in manifests
    /// written before issue 48, whose policies are all `mlp`).
    #[serde(default = "mlp_kind")]
    policy: String,
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
    /// [`Inputs::episode_goal`] (absent: `false`, as in every manifest before it).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    episode_goal: bool,
    /// [`Inputs::goal`] (absent: empty, a skill that sees the observation alone).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    goal: Vec<f32>,
    /// [`Inputs::scale`] (absent: empty, observations seen unscaled).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    scale: Vec<f32>,
}

fn mlp_kind() -> String {
    "mlp".to_string()
}

impl SkillChain {
    /// Saves the chain into `dir`: `skill{i}.safetensors` per policy and `manifest.toml`
    /// (activation balls, trajectory indices, network shapes, the number of skills and each
    /// policy file's SHA-256), written last.
    pub fn save(&self, dir: &Path) -> Result<()> {
        self.save_with_job(dir, None, None)
    }

    /// [`SkillChain::save`], with the job that built the chain written beside it first
    /// (`job` = (file name, its text): `run.toml`), its SHA-256 in the manifest, so that a job
    /// file copied in from another run is refused when the chain is loaded; and the length of
    /// the τ it chained along, `trajectory_len`, so that a last skill that does not end at τ's
    /// end is refused too.
    pub fn save_with_job(
        &self,
        dir: &Path,
        job: Option<(&str, &str)>,
        trajectory_len: Option<usize>,
    ) -> Result<()> {
        let mut manifest = Manifest {
            skill_count: Some(self.skills.len()),
            job_file: None,
            job_sha256: None,
            trajectory_len,
            chain_start: trajectory_len
                .and(self.skills.first())
                .map(|s| s.start_index),
            skills: Vec::new(),
        };
        if let Some((name, text)) = job {
            crate::record::write_atomic(&dir.join(name), |w| w.write_all(text.as_bytes()))?;
            manifest.job_file = Some(name.to_string());
            manifest.job_sha256 = Some(crate::record::sha256_hex(text.as_bytes()));
        }
        for (i, skill) in self.skills.iter().enumerate() {
            // Skills that share one policy (a goal-conditioned chain's) share its file.
            let earlier = self.skills[..i]
                .iter()
                .position(|e| e.policy.same(skill.policy.as_ref()));
            let (file, sha256) = match earlier {
                Some(j) => (
                    manifest.skills[j].file.clone(),
                    manifest.skills[j].sha256.clone(),
                ),
                None => {
                    let file = format!("skill{i}.safetensors");
                    skill.policy.save(&dir.join(&file))?;
                    let sha256 = Some(crate::record::file_sha256(&dir.join(&file))?);
                    (file, sha256)
                }
            };
            manifest.skills.push(ManifestSkill {
                file,
                policy: skill.policy.kind().to_string(),
                sha256,
                center: skill.activation.center.clone(),
                radius: skill.activation.radius,
                weights: skill.activation.weights.clone(),
                start_index: skill.start_index,
                target_index: skill.target_index,
                sizes: skill.policy.sizes().to_vec(),
                action_bounds: skill.policy.action_bounds().to_vec(),
                origin: skill.inputs.origin.clone(),
                action_scale: skill.inputs.action_scale.clone(),
                episode_goal: skill.inputs.episode_goal,
                goal: skill.inputs.goal.clone(),
                scale: skill.inputs.scale.clone(),
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
    /// scales of agreeing lengths; `start_index < target_index`, each skill starting where the one
    /// before it ends, the first where the chain starts (`chain_start`) and the last at τ's end
    /// (`trajectory_len`), where the manifest records them; a policy file inside the
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
        let mut skills: Vec<Skill> = Vec::new();
        let files: Vec<String> = manifest.skills.iter().map(|m| m.file.clone()).collect();
        for (i, m) in manifest.skills.into_iter().enumerate() {
            // A policy file shared by skills (a goal-conditioned chain's) is read once.
            if let Some(j) = files[..i].iter().position(|f| *f == m.file) {
                let shared = m;
                let policy = skills[j].policy.clone();
                let same = policy.kind() == shared.policy
                    && policy.sizes() == shared.sizes.as_slice()
                    && policy.action_bounds() == shared.action_bounds.as_slice();
                if !same {
                    return Err(Error::parse(
                        &path,
                        format!(
                            "skills[{i}].file: {} is skills[{j}]'s, whose policy is a {} of \
                             sizes {:?} (and its action bounds), not a {} of sizes {:?}",
                            shared.file,
                            policy.kind(),
                            policy.sizes(),
                            shared.policy,
                            shared.sizes
                        ),
                    ));
                }
                skills.push(shared.into_skill(policy));
                continue;
            }
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
            // An unknown kind is the manifest's error; bad weights name their file.
            let policy = load_policy(&m.policy, &m.sizes, &m.action_bounds, &weights).map_err(
                |e| match e {
                    Error::Invalid { .. } => {
                        Error::parse(&path, format!("skills[{i}].policy: {e}"))
                    }
                    other => other,
                },
            )?;
            skills.push(m.into_skill(policy));
        }
        Ok(SkillChain { skills, kernel })
    }
}

impl ManifestSkill {
    /// The skill this entry describes, acting by `policy` (its file, read).
    fn into_skill(self, policy: Box<dyn crate::policy::Policy>) -> Skill {
        Skill {
            policy,
            activation: Ball {
                center: self.center,
                radius: self.radius,
                weights: self.weights,
            },
            start_index: self.start_index,
            target_index: self.target_index,
            inputs: Inputs {
                episode_goal: self.episode_goal,
                goal: self.goal,
                scale: self.scale,
                ..Inputs::new(self.origin, self.action_scale)
            },
        }
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
                if file != CHAIN_JOB {
                    return Err(Error::parse(
                        path,
                        format!(
                            "job_file: must be {:?}, the job `pbcs eval` reads, got {file:?}",
                            CHAIN_JOB
                        ),
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
            let field = format!("skills[{i}].sha256");
            match (&s.sha256, self.skill_count) {
                (Some(want), _) => check_sha256(path, &field, &dir.join(&s.file), want)?,
                // A manifest that records its count records every file's hash.
                (None, Some(_)) => {
                    return Err(Error::parse(
                        path,
                        format!("{field}: missing (the manifest records skill_count)"),
                    ))
                }
                (None, None) => {}
            }
        }
        Ok(())
    }

    /// Checks every value of the manifest read from `path` before a file it names is read:
    /// at least one skill, each skill's values ([`ManifestSkill::check`]), and the skills a
    /// chain along τ: each from an index of τ to a later one, each starting where the one
    /// before it ends (a manifest cut inside, reordered or with a skill repeated is refused; a
    /// chain phase 2 left incomplete starts past τ_0, as it was saved). An error names `path`
    /// and the field.
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
        for (i, pair) in self.skills.windows(2).enumerate() {
            if pair[1].start_index != pair[0].target_index {
                return Err(Error::parse(
                    path,
                    format!(
                        "skills[{}].start_index: {}, but skills[{i}] ends at τ_{}: the chain's \
                         skills must follow each other along τ (a manifest cut, reordered or \
                         with a skill repeated)",
                        i + 1,
                        pair[1].start_index,
                        pair[0].target_index
                    ),
                ));
            }
        }
        if let Some(k) = self
            .chain_start
            .filter(|&k| k != self.skills[0].start_index)
        {
            return Err(Error::parse(
                path,
                format!(
                    "skills[0].start_index: {}, but the chain starts at τ_{k} (chain_start): a \
                     manifest cut at its first skill",
                    self.skills[0].start_index
                ),
            ));
        }
        let last = self.skills.len() - 1;
        match self.trajectory_len {
            Some(n) if self.skills[last].target_index.checked_add(1) != Some(n) => {
                Err(Error::parse(
                    path,
                    format!(
                        "skills[{last}].target_index: {}, but τ (trajectory_len = {n}) ends at \
                         τ_{}: the last skill ends at τ's end, the target",
                        self.skills[last].target_index,
                        n.saturating_sub(1)
                    ),
                ))
            }
            _ => Ok(()),
        }
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

    /// How many of the network's inputs are the observation: all but a goal-conditioned
    /// skill's sub-goal, which follows it (refused when it leaves none, or is not finite).
    fn observation_inputs(&self) -> std::result::Result<usize, (&'static str, String)> {
        if self.goal.len() >= self.sizes[0] {
            return Err((
                "goal",
                format!(
                    "has {} values, more than the network's {} inputs leave the observation",
                    self.goal.len(),
                    self.sizes[0]
                ),
            ));
        }
        if self.goal.iter().any(|v| !v.is_finite()) {
            return Err((
                "goal",
                format!("must be finite numbers, got {:?}", self.goal),
            ));
        }
        Ok(self.sizes[0] - self.goal.len())
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
        // The policy's actions per observation: its kind says how its network gives them (an
        // unknown kind is refused when the policy loads, naming the field).
        let input = self.observation_inputs()?;
        let output = crate::learner::policy_action_dim(&self.policy, &self.sizes)
            .unwrap_or(self.sizes[self.sizes.len() - 1]);
        let bounds = (!self.action_bounds.is_empty()).then_some(&self.action_bounds);
        let scale = (!self.scale.is_empty()).then_some(&self.scale);
        self.check_center(input)?;
        for (field, values, want, positive) in [
            ("center", Some(&self.center), self.center.len(), false),
            ("origin", Some(&self.origin), input, false),
            ("scale", scale, self.origin.len(), true),
            ("action_scale", Some(&self.action_scale), output, true),
            ("action_bounds", bounds, output, true),
        ] {
            let Some(values) = values else { continue };
            if values.len() != want {
                return Err((
                    field,
                    format!(
                        "has {} values, the {} policy (sizes {:?}) needs {want}",
                        values.len(),
                        self.policy,
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
        if self.start_index >= self.target_index {
            return Err((
                "start_index",
                format!(
                    "{} is not before the skill's target_index {} (a skill goes forward along τ)",
                    self.start_index, self.target_index
                ),
            ));
        }
        Ok(())
    }
}
