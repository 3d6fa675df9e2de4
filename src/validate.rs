//! Validation and TOML loading: the leaf every configuration builds on.
//!
//! Each config struct implements [`Check`], which names the offending field in its error
//! (`invalid \`maze.size\`: ...`); [`load`] is the one way a TOML file becomes a validated
//! config, and [`read_toml`]/[`parse_toml`]/[`to_toml`] are the one way any other TOML file
//! (manifests, timings, experiment and claim files) is read or written, with errors that name
//! the file.
//!
//! ```
//! use pbcs::validate::{parse_toml, Check};
//! use pbcs::config::ExploreJob;
//! use std::path::Path;
//!
//! let job: ExploreJob = parse_toml("seed = 3\n[maze]\nsize = 7\n", Path::new("job.toml")).unwrap();
//! job.check().unwrap();
//! let err = parse_toml::<ExploreJob>("[maze]\nsiz = 7\n", Path::new("job.toml")).unwrap_err();
//! assert!(err.to_string().contains("job.toml"));
//! ```

use crate::error::{Error, Result};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::path::Path;

/// An unset number (a penalty, a scale whose 0 turns it off), left out of written files so
/// that files written before its setting existed keep their bytes.
pub fn is_zero(x: &f32) -> bool {
    *x == 0.0
}

/// A validated configuration.
pub trait Check {
    /// Ok if every field is in range; otherwise an [`Error::Invalid`] naming the field.
    fn check(&self) -> Result<()>;

    /// The value, checked once ([`Valid`]): what a run takes, so that the run need not check
    /// it again.
    fn valid(self) -> Result<Valid<Self>>
    where
        Self: Sized,
    {
        self.check()?;
        Ok(Valid(self))
    }
}

/// A value whose [`Check`] passed (linfa's checked parameters): made only by [`Check::valid`],
/// so a function that takes one knows its fields are in range without checking them again
/// (library functions that also take unchecked parts, `Learner::new` or `train_vanilla`, still
/// check those).
/// It reads as the value ([`std::ops::Deref`]) and serialises as it.
///
/// ```
/// use pbcs::config::TrainJob;
/// use pbcs::validate::Check;
/// let mut job = TrainJob::default();
/// job.train.steps = 0;
/// let e = job.clone().valid().unwrap_err().to_string();
/// assert!(e.contains("train.steps"), "{e}");
/// job.train.steps = 20_000;
/// assert_eq!(job.valid().unwrap().train.steps, 20_000);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(transparent)]
pub struct Valid<T>(T);

impl<T> Valid<T> {
    /// The value, to change it (and check it again to run it).
    pub fn into_inner(self) -> T {
        self.0
    }
}

impl<T> std::ops::Deref for Valid<T> {
    type Target = T;
    fn deref(&self) -> &T {
        &self.0
    }
}

/// Parses `text` (the contents of `path`) as TOML; a syntax error or an unknown key is an
/// [`Error::Parse`] naming `path` and the key.
pub fn parse_toml<T: DeserializeOwned>(text: &str, path: &Path) -> Result<T> {
    toml::from_str(text).map_err(|e| Error::parse(path, toml_message(text, &e)))
}

/// The longest line of a TOML error's message that is quoted whole: the parser echoes the
/// line it stopped on, which a hostile file makes 100 KB long.
const ECHO_CHARS: usize = 160;

/// `e`'s message for a user: each echoed line cut to [`ECHO_CHARS`]; for the deserializer's
/// `recursion limit`, which names no place, the line with the deepest dotted key.
///
/// ```
/// use pbcs::validate::parse_toml;
/// let deep = format!("seed = 1\nmaze = {}{}", "[".repeat(20_000), "]".repeat(20_000));
/// let e = parse_toml::<toml::Table>(&deep, "deep.toml".as_ref()).unwrap_err().to_string();
/// assert!(e.contains("line 2") && e.len() < 1_000, "{e}");
/// for dotted in ["{} = 1", "[{}]", "[[{}]]", "set = { {} = 1 }"] {
///     let text = format!("seed = 1\n{}", dotted.replace("{}", &vec!["a"; 5_000].join(".")));
///     let e = parse_toml::<toml::Table>(&text, "dot.toml".as_ref()).unwrap_err().to_string();
///     assert!(e.contains("line 2") && e.contains("5000 parts"), "{dotted}: {e}");
/// }
/// ```
fn toml_message(text: &str, e: &toml::de::Error) -> String {
    let cut = |line: &str| match line.char_indices().nth(ECHO_CHARS) {
        Some((at, _)) => format!("{}… ({} characters)", &line[..at], line.chars().count()),
        None => line.to_string(),
    };
    let message: Vec<String> = e.to_string().lines().map(cut).collect();
    let message = message.join("\n");
    if e.span().is_some() || !message.contains("recursion limit") {
        return message;
    }
    // The deepest dotted word of a line: a key (`a.b.c = 1`), a header (`[a.b.c]`), a key of
    // an inline table (`set = { a.b.c = 1 }`).
    let parts = |line: &str| {
        let words = line.split(|c: char| c.is_whitespace() || "=[]{},".contains(c));
        words.map(|w| w.split('.').count()).max().unwrap_or(0)
    };
    match text.lines().enumerate().max_by_key(|(_, l)| parts(l)) {
        Some((i, line)) if parts(line) > 1 => format!(
            "{message}: line {}, a key of {} parts (dotted keys nested deeper than the parser \
             allows; no config nests more than a few)",
            i + 1,
            parts(line)
        ),
        _ => message,
    }
}

/// Reads and parses the TOML file `path`, with errors that name it.
pub fn read_toml<T: DeserializeOwned>(path: &Path) -> Result<T> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_toml(&text, path)
}

/// Serialises `value` as TOML for the file `path` (named by the error, if any).
pub fn to_toml<T: Serialize>(value: &T, path: &Path) -> Result<String> {
    toml::to_string(value).map_err(|e| Error::parse(path, e))
}

/// Reads a TOML file into a config and validates it. Unknown keys, syntax errors and
/// unreadable files are errors that name the file (and the key, for parse errors).
pub fn load<T: DeserializeOwned + Check>(path: &Path) -> Result<T> {
    let config: T = read_toml(path)?;
    config.check().map_err(|e| e.in_file(path))?;
    Ok(config)
}

/// The top-level keys of `job` (a config as read from `path`) that the file does not set:
/// their defaults were used. An unreadable file sets nothing.
pub fn unset_keys<T: Serialize>(path: &Path, job: &T) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let given: toml::Table = toml::from_str(&text).unwrap_or_default();
    let Ok(toml::Value::Table(all)) = toml::Value::try_from(job) else {
        return Vec::new();
    };
    all.keys()
        .filter(|k| !given.contains_key(*k))
        .cloned()
        .collect()
}

/// The upper bounds of the counts a job or a command line can set, each checked when it is
/// read: far above what any committed run uses (at most 300 episodes of a test, 1 000 steps of
/// an episode, a replay of 1M, layers of 256), low enough that an allocation or a loop sized by
/// one ends on this machine. More is a typo, as for [`crate::experiment::MAX_SEEDS`].
pub mod bounds {
    /// Episodes of one evaluation, test or verification (β, `eval_episodes`, …).
    pub const EPISODES: u64 = 100_000;
    /// Steps of one episode.
    pub const EPISODE_STEPS: u64 = 1_000_000;
    /// Transitions a replay buffer holds.
    pub const REPLAY: u64 = 100_000_000;
    /// Units of one hidden layer.
    pub const WIDTH: u64 = 16_384;
    /// Hidden layers of a network.
    pub const LAYERS: u64 = 16;
    /// Actions the argmax actor samples per state.
    pub const SAMPLES: u64 = 100_000;
    /// Training rounds, patience and the like: counts of repetitions of a learning step.
    pub const REPEATS: u64 = 1_000_000;
    /// Learner updates per environment step (DCIL-II's is 1.5, SB3's `gradient_steps` a few).
    pub const UPDATES_PER_STEP: u64 = 1_000;
    /// Environment steps of one run's budget (`train.steps`, `phase2.max_env_steps`,
    /// `explore.budget`): the paper's largest is 22M, ours 50M.
    pub const ENV_STEPS: u64 = 1_000_000_000;
}

/// Ok if `value` ≤ `max` (a count that may be 0); otherwise an error naming `field`.
///
/// ```
/// use pbcs::validate::at_most;
/// assert!(at_most("phase2.restarts", 0, 1_000_000).is_ok());
/// let e = at_most("phase2.restarts", u64::MAX, 1_000_000).unwrap_err().to_string();
/// assert!(e.contains("phase2.restarts") && e.contains("at most 1000000"), "{e}");
/// ```
pub fn at_most(field: &str, value: u64, max: u64) -> Result<()> {
    if value > max {
        return Err(Error::invalid(
            field,
            format!("must be at most {max} (more is a typo), got {value}"),
        ));
    }
    Ok(())
}

/// Ok if `value` is in 1 ..= `max`; otherwise an error naming `field` and both ends.
///
/// ```
/// use pbcs::validate::count;
/// assert!(count("phase2.beta", 50, 100_000).is_ok());
/// let e = count("phase2.beta", 0, 100_000).unwrap_err().to_string();
/// assert!(e.contains("phase2.beta") && e.contains("at least 1"), "{e}");
/// let e = count("phase2.beta", u64::MAX, 100_000).unwrap_err().to_string();
/// assert!(e.contains("at most 100000"), "{e}");
/// ```
pub fn count(field: &str, value: u64, max: u64) -> Result<()> {
    if value == 0 {
        return Err(Error::invalid(field, "must be at least 1"));
    }
    if value > max {
        return Err(Error::invalid(
            field,
            format!("must be at most {max} (more is a typo), got {value}"),
        ));
    }
    Ok(())
}

/// Ok if `value` is finite and in (0, `max`]; otherwise an error naming `field`.
pub fn positive_finite(field: &str, value: f32, max: f32) -> Result<()> {
    if !(value.is_finite() && value > 0.0 && value <= max) {
        // A positive value too small for 32 bits (1e-300) is read as 0: say so.
        let read = if value == 0.0 {
            " (a value under 1e-45 reads as 0 in 32 bits)"
        } else {
            ""
        };
        return Err(Error::invalid(
            field,
            format!("must be in (0, {max}], got {value}{read}"),
        ));
    }
    Ok(())
}
