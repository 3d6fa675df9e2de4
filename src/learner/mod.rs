//! Off-policy learners behind one [`Learner`] trait: TD3 (with DDPG as a preset and the
//! argmax actor as a variant of the same update, [`td3`]) and SAC ([`sac`]).
//!
//! A learner acts (greedily, or with its own exploration), learns from mini-batches of
//! transitions and gives its policy ([`crate::policy::Policy`]) for a chain's skill. The
//! replay buffer stays with the caller: a skill's replay is its learning problem's (a warm
//! start keeps the learner, not the replay), and how transitions are stored (whole episodes
//! for HER) is the caller's to say. [`LearnerConfig`] is a job's `[learner]` table: its `algo`
//! names the family, and each family's settings are its own (TD3's exploration noise is not
//! writable under `algo = "sac"`).
//!
//! The families are named in one place, the `learners!` line below: a new learner is its
//! file (its settings implementing [`Family`], its learner implementing [`Learner`], its
//! policy implementing [`crate::policy::Policy`]) plus one entry there.
//!
//! ```
//! use pbcs::learner::{Learner, LearnerConfig};
//! use pbcs::nn::kernel::Kernel;
//! use pbcs::rng::{Seeds, Stream};
//! let sac: LearnerConfig = toml::from_str("algo = \"sac\"\nhidden = [16, 16]").unwrap();
//! assert_eq!(sac.record_name().as_str(), "sac");
//! let mut learner = sac.build(2, &[0.1, 0.1], &Seeds::new(0), Kernel::detect()).unwrap();
//! learner.begin_episodes(1);
//! let mut rng = Seeds::new(0).stream(Stream::Noise);
//! let a = learner.explore(&[0.5, 0.5], &[0], &mut rng).to_vec();
//! assert!(a.iter().all(|x| x.abs() <= 0.1));
//! // TD3's settings are refused under SAC, by name.
//! let err = toml::from_str::<LearnerConfig>("algo = \"sac\"\nnoise_sigma = 0.2").unwrap_err();
//! assert!(err.to_string().contains("noise_sigma"), "{err}");
//! ```

pub mod her;
pub mod noise;
pub mod replay;

use crate::error::{Error, Result};
use crate::nn::kernel::Kernel;
use crate::policy::Policy;
use crate::rng::{Rng, Seeds};
use crate::validate::Check;
use replay::Batch;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Deserializer, Serialize};
use std::path::Path;

/// Losses of one update (for logging).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Losses {
    /// Mean squared TD error of the first critic.
    pub critic: f32,
    /// Actor loss; `None` on steps that do not update the actor (TD3's delay).
    pub actor: Option<f32>,
}

/// An off-policy learner: acts, learns from mini-batches, gives its policy.
///
/// Actions live in the bounds the learner was made with (`[-b_i, b_i]`); exploration state
/// (TD3's noise processes) is kept per lane, a lane being one of the episodes run in lockstep.
pub trait Learner: std::fmt::Debug + Send {
    /// Its settings.
    fn config(&self) -> LearnerConfig;
    /// Greedy actions for `n` observations (row-major; one forward pass).
    fn act(&mut self, obs: &[f32], n: usize) -> &[f32];
    /// Resets the exploration state of lanes `0..lanes` (new episodes begin).
    fn begin_episodes(&mut self, lanes: usize);
    /// Exploratory actions for the running `lanes` (one observation row each, in order),
    /// drawn from `rng`, within the bounds.
    fn explore(&mut self, obs: &[f32], lanes: &[usize], rng: &mut Rng) -> &[f32];
    /// One update on a mini-batch.
    fn update(&mut self, batch: &Batch) -> Losses;
    /// Its current greedy policy, as a chain's skill holds it.
    fn policy(&self) -> Box<dyn Policy>;
    /// Mini-batch size of [`Learner::update`].
    fn batch_size(&self) -> usize;
    /// Updates done so far.
    fn updates(&self) -> u64;
    /// The kernel of every product, optimiser step and soft update.
    fn kernel(&self) -> Kernel;
    /// Runs every later product, optimiser step and soft update on `kernel`.
    ///
    /// # Panics
    /// If this CPU cannot run `kernel` (see [`Kernel::available`]).
    fn set_kernel(&mut self, kernel: Kernel);
    /// Subnormal values among all Adam moments (0 while the flush works; see
    /// [`crate::nn::Adam`]).
    fn subnormal_moments(&self) -> usize;
    /// A boxed copy.
    fn boxed(&self) -> Box<dyn Learner>;
    /// Its whole state (weights, targets, optimiser moments, the position of its update
    /// stream, its exploration state), as a run's checkpoint holds it ([`crate::vanilla::resume`]).
    fn save_state(&self) -> Result<Vec<u8>>;
    /// Becomes the learner whose [`Learner::save_state`] gave `bytes`; refused, unchanged,
    /// when they are not its family's or were saved with other settings or sizes.
    fn restore_state(&mut self, bytes: &[u8]) -> Result<()>;
    /// As `Any` (tests and benchmarks reach a family's own methods through it).
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any;
}

impl Clone for Box<dyn Learner> {
    fn clone(&self) -> Self {
        self.boxed()
    }
}

/// A learner family's settings: what a job's `[learner]` table holds when its `algo` is one
/// of [`Family::ALGOS`].
pub trait Family:
    Check + Clone + std::fmt::Debug + PartialEq + Serialize + DeserializeOwned + Default
{
    /// The `algo` values that select this family (`ddpg`, `td3`; `sac`).
    const ALGOS: &'static [&'static str];
    /// The kind of its policy in a chain's manifest ([`load_policy`]).
    const POLICY: &'static str;
    /// These settings' `algo`.
    fn algo(&self) -> &'static str;
    /// This family's default settings under `algo` (one of [`Family::ALGOS`]).
    fn preset(algo: &str) -> Self;
    /// The learner's name in result rows (`ddpg`, `td3_am`, `sac`).
    fn record_name(&self) -> String;
    /// The discount γ.
    fn gamma(&self) -> f32;
    /// The discount γ, to change.
    fn gamma_mut(&mut self) -> &mut f32;
    /// Replay capacity (transitions).
    fn replay_size(&self) -> usize;
    /// Transitions per update.
    fn batch_size(&self) -> usize;
    /// A fresh learner for observations of `obs_dim` and actions in `[-bounds_i, bounds_i]`;
    /// all its randomness comes from `seeds`.
    fn build(
        &self,
        obs_dim: usize,
        bounds: &[f32],
        seeds: &Seeds,
        kernel: Kernel,
    ) -> Result<Box<dyn Learner>>;
    /// Its policy saved at `path`, of network `sizes` and action `bounds` as the manifest
    /// records them.
    fn load_policy(sizes: &[usize], bounds: &[f32], path: &Path) -> Result<Box<dyn Policy>>;
    /// The actions its policy gives per observation, for a network of `sizes` (at least two
    /// layers): TD3's actor its output, SAC's half of it (μ and ℓ per action).
    fn policy_action_dim(sizes: &[usize]) -> usize;
}

crate::name!(
    /// A learner as result rows name it: its family's record name (`ddpg`, `td3`, `td3_am`,
    /// `sac`), with `_her` for a vanilla run with hindsight experience replay
    /// ([`crate::config::TrainJob::learner_name`]).
    LearnerName,
    field = "learner",
    what = "a learner's name",
    dash = false
);

impl LearnerName {
    /// The name a family gives its learner ([`Family::record_name`]): letters, digits and `_`
    /// by every family's construction, which `every_family_names_its_learner_validly` holds.
    pub(crate) fn of_family(name: &str) -> LearnerName {
        LearnerName::new(name).unwrap_or_else(|e| panic!("a learner family's record name: {e}"))
    }
}

/// [`Learner::save_state`] of a family whose learner is serde's: its postcard bytes.
pub(crate) fn save_whole<L: Serialize>(learner: &L) -> Result<Vec<u8>> {
    postcard::to_stdvec(learner).map_err(|e| Error::invalid("learner state", e.to_string()))
}

/// A family's settings in its learner's saved state, as their TOML text: postcard, which
/// writes the state, cannot read back serde's untagged enums (SAC's `ent_coef`) nor fields
/// skipped when empty (SAC's `target_entropy`); TOML can.
pub(crate) mod settings_as_toml {
    use serde::de::{DeserializeOwned, Error as _};
    use serde::ser::Error as _;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<T: Serialize, S: Serializer>(v: &T, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&toml::to_string(v).map_err(S::Error::custom)?)
    }

    pub fn deserialize<'de, T: DeserializeOwned, D: Deserializer<'de>>(
        d: D,
    ) -> Result<T, D::Error> {
        toml::from_str(&String::deserialize(d)?).map_err(D::Error::custom)
    }
}

/// [`Learner::restore_state`] of such a family: the learner `bytes` hold, when `same` says it
/// has the settings and sizes of the one it replaces.
pub(crate) fn restore_whole<L: DeserializeOwned>(
    bytes: &[u8],
    same: impl FnOnce(&L) -> bool,
) -> Result<L> {
    let saved: L = postcard::from_bytes(bytes)
        .map_err(|e| Error::invalid("learner state", format!("not this family's learner ({e})")))?;
    if !same(&saved) {
        return Err(Error::invalid(
            "learner state",
            "saved with other settings or sizes than this learner's",
        ));
    }
    Ok(saved)
}

/// Declares the learner families: each entry `Variant(module::Settings)` is a module of this
/// folder whose `Settings` implement [`Family`].
macro_rules! learners {
    ($($family:ident($module:ident::$settings:ident)),+ $(,)?) => {
        $(pub mod $module;)+

        /// A job's `[learner]` table: one family's settings, chosen by `algo` (absent: `ddpg`).
        #[derive(Debug, Clone, PartialEq, Serialize)]
        #[serde(untagged)]
        pub enum LearnerConfig {
            $(
                #[allow(missing_docs)]
                $family($module::$settings),
            )+
        }

        $(impl From<$module::$settings> for LearnerConfig {
            fn from(s: $module::$settings) -> Self {
                LearnerConfig::$family(s)
            }
        })+

        impl LearnerConfig {
            /// Every `algo` value, family by family.
            pub const ALGOS: &'static [&'static [&'static str]] =
                &[$(<$module::$settings as Family>::ALGOS),+];

            /// The default settings of the family `algo` names, under that `algo`.
            pub fn preset(algo: &str) -> Result<Self> {
                $(if <$module::$settings as Family>::ALGOS.contains(&algo) {
                    return Ok(<$module::$settings as Family>::preset(algo).into());
                })+
                Err(unknown_algo(algo))
            }

            /// A `[learner]` table read as the family its `algo` names; a value of the wrong
            /// type is named by its key (`learner.batch_size: invalid value ...`: the table,
            /// read as a whole, loses where it was).
            fn from_table(algo: &str, table: toml::Table) -> std::result::Result<Self, String> {
                $(if <$module::$settings as Family>::ALGOS.contains(&algo) {
                    let read = |t: toml::Table| {
                        toml::Value::Table(t).try_into::<$module::$settings>()
                    };
                    return read(table.clone()).map(LearnerConfig::$family).map_err(|e| {
                        let alone = |k: &String| {
                            let mut t = toml::Table::new();
                            t.insert(k.clone(), table[k].clone());
                            read(t).is_err()
                        };
                        match table.keys().find(|k| alone(k)) {
                            Some(k) => format!("learner.{k}: {}", e.message()),
                            None => e.message().to_string(),
                        }
                    });
                })+
                Err(unknown_algo(algo).to_string())
            }

            /// Whether `other` is of the same family.
            pub fn same_family(&self, other: &LearnerConfig) -> bool {
                std::mem::discriminant(self) == std::mem::discriminant(other)
            }

            /// These settings as their family's (object-safe) methods.
            fn get(&self) -> &dyn Settings {
                match self {
                    $(LearnerConfig::$family(s) => s,)+
                }
            }

            fn get_mut(&mut self) -> &mut dyn Settings {
                match self {
                    $(LearnerConfig::$family(s) => s,)+
                }
            }
        }

        /// The policy of `kind` saved at `path`: the family whose policy it is loads it.
        fn load_policy_of(
            kind: &str,
            sizes: &[usize],
            bounds: &[f32],
            path: &Path,
        ) -> Option<Result<Box<dyn Policy>>> {
            $(if kind == <$module::$settings as Family>::POLICY {
                return Some(<$module::$settings as Family>::load_policy(sizes, bounds, path));
            })+
            None
        }

        /// The actions a policy of `kind` with a network of `sizes` gives, if the kind is known.
        pub(crate) fn policy_action_dim(kind: &str, sizes: &[usize]) -> Option<usize> {
            $(if kind == <$module::$settings as Family>::POLICY {
                return Some(<$module::$settings as Family>::policy_action_dim(sizes));
            })+
            None
        }

        /// Every policy kind, in the families' order.
        const POLICY_KINDS: &[&str] = &[$(<$module::$settings as Family>::POLICY),+];
    };
}

// The one place learner families are named.
learners! {
    Td3(td3::Td3Config),
    Sac(sac::SacConfig),
}

/// The object-safe part of [`Family`].
trait Settings: Check {
    fn algo(&self) -> &'static str;
    fn record_name(&self) -> String;
    fn gamma(&self) -> f32;
    fn gamma_mut(&mut self) -> &mut f32;
    fn replay_size(&self) -> usize;
    fn batch_size(&self) -> usize;
    fn build(
        &self,
        obs_dim: usize,
        bounds: &[f32],
        seeds: &Seeds,
        kernel: Kernel,
    ) -> Result<Box<dyn Learner>>;
}

impl<F: Family> Settings for F {
    fn algo(&self) -> &'static str {
        Family::algo(self)
    }
    fn record_name(&self) -> String {
        Family::record_name(self)
    }
    fn gamma(&self) -> f32 {
        Family::gamma(self)
    }
    fn gamma_mut(&mut self) -> &mut f32 {
        Family::gamma_mut(self)
    }
    fn replay_size(&self) -> usize {
        Family::replay_size(self)
    }
    fn batch_size(&self) -> usize {
        Family::batch_size(self)
    }
    fn build(
        &self,
        obs_dim: usize,
        bounds: &[f32],
        seeds: &Seeds,
        kernel: Kernel,
    ) -> Result<Box<dyn Learner>> {
        Family::build(self, obs_dim, bounds, seeds, kernel)
    }
}

fn unknown_algo(algo: &str) -> Error {
    Error::invalid(
        "learner.algo",
        format!(
            "`{algo}` is not a learner (one of: {})",
            LearnerConfig::algo_names().join(", ")
        ),
    )
}

impl Default for LearnerConfig {
    /// DDPG.
    fn default() -> Self {
        td3::Td3Config::ddpg().into()
    }
}

impl<'de> Deserialize<'de> for LearnerConfig {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        let table = toml::Table::deserialize(d)?;
        let algo = match table.get("algo") {
            None => "ddpg".to_string(),
            Some(toml::Value::String(s)) => s.clone(),
            Some(other) => {
                return Err(D::Error::custom(format!(
                    "learner.algo must be a string, got {other}"
                )))
            }
        };
        LearnerConfig::from_table(&algo, table).map_err(D::Error::custom)
    }
}

impl LearnerConfig {
    /// The DDPG preset.
    pub fn ddpg() -> Self {
        td3::Td3Config::ddpg().into()
    }

    /// The TD3 preset.
    pub fn td3() -> Self {
        td3::Td3Config::td3().into()
    }

    /// The SAC preset (Stable-Baselines3's defaults).
    pub fn sac() -> Self {
        sac::SacConfig::default().into()
    }

    /// The `algo` value: `ddpg`, `td3`, `sac`.
    pub fn algo(&self) -> &'static str {
        self.get().algo()
    }

    /// The learner's name in result rows: `ddpg` or `td3`, with `_am` for the argmax actor;
    /// `sac`.
    pub fn record_name(&self) -> LearnerName {
        LearnerName::of_family(&self.get().record_name())
    }

    /// The discount γ.
    pub fn gamma(&self) -> f32 {
        self.get().gamma()
    }

    /// Sets the discount γ.
    pub fn set_gamma(&mut self, gamma: f32) {
        *self.get_mut().gamma_mut() = gamma;
    }

    /// Every `algo` value.
    pub fn algo_names() -> Vec<&'static str> {
        LearnerConfig::ALGOS
            .iter()
            .flat_map(|a| a.iter().copied())
            .collect()
    }

    /// Replay capacity (transitions).
    pub fn replay_size(&self) -> usize {
        self.get().replay_size()
    }

    /// Transitions per update.
    pub fn batch_size(&self) -> usize {
        self.get().batch_size()
    }

    /// The TD3 family's settings, if these are.
    pub fn as_td3(&self) -> Option<&td3::Td3Config> {
        match self {
            LearnerConfig::Td3(c) => Some(c),
            _ => None,
        }
    }

    /// Switches to `algo`: within a family only `algo` changes (DDPG ↔ TD3 keep every other
    /// setting); another family's learner starts from that family's defaults (a family's
    /// settings do not carry over to another's).
    pub fn switch_to(&mut self, algo: &str) -> Result<()> {
        let preset = LearnerConfig::preset(algo)?;
        match (self, preset) {
            (LearnerConfig::Td3(c), LearnerConfig::Td3(p)) => c.algo = p.algo,
            (me, preset) if me.same_family(&preset) => {}
            (me, preset) => *me = preset,
        }
        Ok(())
    }

    /// A fresh learner for observations of `obs_dim` and actions in `[-bounds_i, bounds_i]`,
    /// whose layer arithmetic runs on `kernel` (an input of the run like the seed: kernels
    /// other than AVX2/AVX-512 give other bytes). All its randomness comes from `seeds`.
    pub fn build(
        &self,
        obs_dim: usize,
        bounds: &[f32],
        seeds: &Seeds,
        kernel: Kernel,
    ) -> Result<Box<dyn Learner>> {
        self.check()?;
        self.get().build(obs_dim, bounds, seeds, kernel)
    }
}

impl Check for LearnerConfig {
    fn check(&self) -> Result<()> {
        self.get().check()
    }
}

/// The policy of kind `kind` saved at `path` (a skill's weights file), of network `sizes` and
/// action `bounds` as the manifest records them: the learner family whose policy it is loads
/// it. An unknown kind, or weights that do not fit, are errors naming the kind or the file.
pub fn load_policy(
    kind: &str,
    sizes: &[usize],
    bounds: &[f32],
    path: &Path,
) -> Result<Box<dyn Policy>> {
    load_policy_of(kind, sizes, bounds, path).unwrap_or_else(|| {
        Err(Error::invalid(
            "policy",
            format!(
                "`{kind}` is not a policy kind this build knows ({})",
                POLICY_KINDS.join(", ")
            ),
        ))
    })
}

/// Concatenates row-major `x` (n × dx) and `y` (n × dy) into `out` (n × (dx + dy)).
pub(crate) fn concat_rows(x: &[f32], dx: usize, y: &[f32], dy: usize, out: &mut Vec<f32>) {
    out.clear();
    for (xr, yr) in x.chunks_exact(dx).zip(y.chunks_exact(dy)) {
        out.extend(xr.iter().chain(yr).copied());
    }
}

/// Checks shared by the families: positive learning rates, γ ∈ [0, 1), τ ∈ (0, 1], a batch, a
/// replay that holds one, and layers.
pub(crate) fn check_common(
    rates: &[(&str, f32)],
    gamma: f32,
    tau: f32,
    batch_size: usize,
    replay_size: usize,
    hidden: &[usize],
) -> Result<()> {
    for &(field, v) in rates {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::invalid(field, format!("must be positive, got {v}")));
        }
    }
    if !(0.0..1.0).contains(&gamma) {
        return Err(Error::invalid(
            "learner.gamma",
            format!("must be in [0, 1), got {gamma}"),
        ));
    }
    if !(tau > 0.0 && tau <= 1.0) {
        return Err(Error::invalid(
            "learner.tau",
            format!("must be in (0, 1], got {tau}"),
        ));
    }
    use crate::validate::{bounds, count};
    count("learner.replay_size", replay_size as u64, bounds::REPLAY)?;
    count("learner.batch_size", batch_size as u64, bounds::REPLAY)?;
    if replay_size < batch_size {
        return Err(Error::invalid(
            "learner.replay_size",
            "must be at least learner.batch_size",
        ));
    }
    if hidden.is_empty() || hidden.contains(&0) {
        return Err(Error::invalid(
            "learner.hidden",
            "needs at least one layer, all widths positive",
        ));
    }
    count("learner.hidden", hidden.len() as u64, bounds::LAYERS).map_err(|_| {
        Error::invalid(
            "learner.hidden",
            format!("at most {} layers", bounds::LAYERS),
        )
    })?;
    for &w in hidden {
        count("learner.hidden", w as u64, bounds::WIDTH)?;
    }
    Ok(())
}
