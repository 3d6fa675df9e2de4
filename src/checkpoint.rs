//! A run's checkpoint: one file, one envelope, for every kind of run that saves itself (a
//! vanilla run, [`crate::vanilla::resume`]; a PBCS run between two steps of phase 2 — learning
//! problems, verifications of the chain, tests of its goal-conditioned chain —,
//! [`crate::runs::pbcs_resume`]), so that a run cut short (a session's end, a cluster job's
//! limit, a killed process) goes on where it was saved and ends with the bytes of a run never
//! cut.
//!
//! The file is postcard-encoded: the run's format and version, the job it belongs to, the
//! wall-clock seconds and env steps so far (the head, which [`Checkpoint::peek`] reads alone),
//! then the SHA-256 of the run's state and the state, whose encoding is the run's own. It is
//! written atomically; a file of another format or version, another job, cut short or damaged
//! is refused with what to do, and left as it is: nothing is lost.
//!
//! ```
//! use pbcs::checkpoint::Checkpoint;
//! let dir = tempfile::tempdir().unwrap();
//! let checkpoint = Checkpoint::new(dir.path().join("s0.resume"), "toy, seed 0");
//! assert!(checkpoint.read("my run, version 1").unwrap().is_none(), "no file yet");
//! checkpoint.write("my run, version 1", 200, 1.5, b"the state").unwrap();
//! let saved = checkpoint.read("my run, version 1").unwrap().unwrap();
//! assert_eq!((saved.body.as_slice(), saved.steps, saved.seconds), (&b"the state"[..], 200, 1.5));
//! // Another version of the run, or another job, is refused.
//! let err = checkpoint.read("my run, version 2").unwrap_err();
//! assert!(err.to_string().contains("another version"), "{err}");
//! let other = Checkpoint::new(checkpoint.path.clone(), "toy, seed 1");
//! assert!(other.read("my run, version 1").unwrap_err().to_string().contains("another job"));
//! ```

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// How often `pbcs exp run` saves a run: at the first evaluation (a vanilla run) or learning
/// problem (PBCS) ten minutes or more after the run (re)started or was last saved.
pub const EVERY: Duration = Duration::from_secs(600);

/// The format of a vanilla run's checkpoint ([`crate::vanilla::resume`]): a file of another
/// format or version is refused by it. Bump the version with any change to what a vanilla run
/// computes or to its state's layout (version 2: the learner's and the run's states in one
/// body; 3: each HER row holds the goal its target bootstraps through, for value chaining).
pub const VANILLA: &str = "pbcs vanilla run checkpoint, version 3";

/// The format of a PBCS run's checkpoint ([`crate::runs::pbcs_resume`]). Bump the version with
/// any change to what a PBCS run computes or to its saved state's layout (version 2: the
/// chain's verification and repairs are saved too, a repair under way included).
pub const PBCS: &str = "pbcs PBCS run checkpoint, version 2";

/// The format of a PBCS run's checkpoint whose phase 2 is the goal-conditioned chain
/// ([`crate::runs::pbcs_resume`], saved between two of its tests). Bump the version with any
/// change to what such a run computes or to its saved state's layout.
pub const PBCS_GOAL_CONDITIONED: &str = "pbcs goal-conditioned PBCS run checkpoint, version 1";

/// What the messages refusing a file end with.
const AFRESH: &str = "delete it to start the run afresh";

/// Where a run saves its state, for which job, and how often.
#[derive(Debug, Clone, PartialEq)]
pub struct Checkpoint {
    /// The file (an experiment's run: `s<seed>.resume` beside its row).
    pub path: PathBuf,
    /// What identifies the run (an experiment's run: its job's TOML and its kernel): a
    /// checkpoint is resumed only by a run of the same job.
    pub job: String,
    /// Saved at the first evaluation this long after the run (re)started or was last saved.
    pub every: Duration,
    /// A deadline (`pbcs exp run --stop-after`): at the first save point at or past it the run
    /// is saved and stops, unfinished.
    pub stop_at: Option<Instant>,
}

/// What a checkpoint file holds.
#[derive(Serialize, Deserialize)]
struct Envelope {
    format: String,
    job: String,
    /// Wall-clock seconds of the run so far.
    seconds: f64,
    /// Environment steps so far.
    steps: u64,
    /// SHA-256 of `body`.
    sha256: String,
    body: Vec<u8>,
}

/// [`Envelope`] as written, its strings and body borrowed.
#[derive(Serialize)]
struct WrittenEnvelope<'a> {
    format: &'a str,
    job: &'a str,
    seconds: f64,
    steps: u64,
    sha256: String,
    body: &'a [u8],
}

/// The head of a checkpoint file: [`Envelope`]'s first fields, which postcard writes first.
#[derive(Deserialize)]
struct Head {
    format: String,
    job: String,
    seconds: f64,
    steps: u64,
}

/// How far a saved run got ([`Checkpoint::peek`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Saved {
    /// Environment steps taken.
    pub steps: u64,
    /// Wall-clock seconds of the run up to the save.
    pub seconds: f64,
}

/// A checkpoint read back ([`Checkpoint::read`]): the run's state as it encoded it, and how far
/// it got.
#[derive(Debug, Clone, PartialEq)]
pub struct Opened {
    /// The state, as the run encoded it.
    pub body: Vec<u8>,
    /// Environment steps taken.
    pub steps: u64,
    /// Wall-clock seconds of the run up to the save.
    pub seconds: f64,
}

impl Checkpoint {
    /// The checkpoint at `path` of the run of `job`, saved every [`EVERY`], without a
    /// deadline.
    pub fn new(path: impl Into<PathBuf>, job: impl Into<String>) -> Self {
        Checkpoint {
            path: path.into(),
            job: job.into(),
            every: EVERY,
            stop_at: None,
        }
    }

    /// Saves `body`, the state of a run of `format` after `steps` env steps and `seconds` of
    /// wall clock, replacing the file at once and whole.
    pub fn write(&self, format: &str, steps: u64, seconds: f64, body: &[u8]) -> Result<()> {
        // The body borrowed, not copied (a goal-conditioned run's holds its replay): serde
        // writes a slice as it writes a Vec, so the file is `Envelope`'s.
        let envelope = WrittenEnvelope {
            format,
            job: &self.job,
            seconds,
            steps,
            sha256: crate::record::sha256_hex(body),
            body,
        };
        crate::record::write_atomic(&self.path, |w| {
            postcard::to_io(&envelope, w)
                .map(|_| ())
                .map_err(std::io::Error::other)
        })
    }

    /// The state saved at [`Checkpoint::path`] by a run of `format`, or `None` where there is
    /// no file. A file that does not decode, is of another format or version, is damaged or is
    /// another job's is refused, naming it; it is left as it is.
    pub fn read(&self, format: &str) -> Result<Option<Opened>> {
        let bytes = match std::fs::read(&self.path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(Error::io(&self.path, e)),
        };
        let envelope = postcard::from_bytes::<Envelope>(&bytes)
            .ok()
            .filter(|e| e.format == format)
            .ok_or_else(|| {
                self.refused(format!(
                    "is not a {format} (another version, another file, or cut short)"
                ))
            })?;
        if envelope.sha256 != crate::record::sha256_hex(&envelope.body) {
            return Err(self.refused("is damaged: its checksum does not match"));
        }
        if envelope.job != self.job {
            return Err(self.refused(format!(
                "was saved by another job, not this one (its job:\n{}\n)",
                envelope.job
            )));
        }
        Ok(Some(Opened {
            body: envelope.body,
            steps: envelope.steps,
            seconds: envelope.seconds,
        }))
    }

    /// How far the run saved at [`Checkpoint::path`] got (a vanilla run's or a PBCS run's), read
    /// from the file's head without the state: `None` where there is no file; an error where
    /// the head does not decode or belongs to another format, version or job (the file would
    /// be refused; the run says why). Its state is not checked.
    pub fn peek(&self) -> Result<Option<Saved>> {
        let file = match std::fs::File::open(&self.path) {
            Ok(f) => f,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(Error::io(&self.path, e)),
        };
        // Room for the format and the job's TOML (a job's is a few kilobytes), read in place.
        let mut scratch = vec![0u8; 1 << 20];
        let head: Option<Head> = postcard::from_io((std::io::BufReader::new(file), &mut scratch))
            .ok()
            .map(|(h, _)| h);
        match head {
            Some(h)
                if [VANILLA, PBCS, PBCS_GOAL_CONDITIONED].contains(&h.format.as_str())
                    && h.job == self.job =>
            {
                Ok(Some(Saved {
                    steps: h.steps,
                    seconds: h.seconds,
                }))
            }
            _ => Err(self.refused("would be refused (run it to see why)")),
        }
    }

    /// Deletes the file (once the run's results are written); no file is not an error.
    pub fn remove(&self) -> Result<()> {
        match std::fs::remove_file(&self.path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(Error::io(&self.path, e)),
            _ => Ok(()),
        }
    }

    /// The error refusing this file: "this checkpoint {message}; delete it to start the run
    /// afresh".
    pub fn refused(&self, message: impl std::fmt::Display) -> Error {
        Error::parse(&self.path, format!("this checkpoint {message}; {AFRESH}"))
    }

    /// When a run saves itself to this checkpoint, from now on ([`Saves::due`]).
    pub fn saves(&self) -> Saves<'_> {
        Saves {
            checkpoint: self,
            last: Instant::now(),
        }
    }
}

/// When a run saves itself ([`Checkpoint::saves`]): at a save point [`Checkpoint::every`] or more
/// after the last save (or the start), and at the first one at or past the deadline, where the
/// run stops.
pub struct Saves<'c> {
    checkpoint: &'c Checkpoint,
    last: Instant,
}

impl Saves<'_> {
    /// At a save point: saves with `save` where one is due and says whether the run stops here
    /// (saved). A save that fails is reported on standard error and the run goes on, the older
    /// file kept (`at` says where, in the warning); at the deadline it is an error (stopping
    /// unsaved would lose the work since the last save).
    pub fn due(&mut self, at: &str, save: impl FnOnce() -> Result<()>) -> Result<bool> {
        let now = Instant::now();
        let stop = self.checkpoint.stop_at.is_some_and(|t| now >= t);
        if !stop && now.duration_since(self.last) < self.checkpoint.every {
            return Ok(false);
        }
        match save() {
            Err(e) if stop => return Err(e),
            // The next try after another `every`: a full disk is not retried at every point.
            Err(e) => eprintln!("warning: the run goes on unsaved{at}: {e}"),
            Ok(()) => {}
        }
        self.last = now;
        Ok(stop)
    }
}

/// The instant `after` from now (`--stop-after`, counted from the start of the command), for
/// [`Checkpoint::stop_at`]; one too far ahead to be an instant is refused.
pub fn deadline(after: Option<Duration>) -> Result<Option<Instant>> {
    let Some(d) = after else {
        return Ok(None);
    };
    let at = Instant::now().checked_add(d).ok_or_else(|| {
        let d = humantime::format_duration(d);
        Error::invalid("--stop-after", format!("{d}: too far ahead"))
    })?;
    Ok(Some(at))
}
