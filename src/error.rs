//! One error type for the whole crate.
//!
//! Every error that comes from user input names the offending field or file, so a bad
//! config or command line is answered with a message that says what to fix.

use std::path::PathBuf;

/// Errors of the library. Input errors name the field (`maze.size`) or the file.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A configuration value is outside its valid range.
    #[error("invalid `{field}`: {reason}")]
    Invalid {
        /// Dotted path of the field, as written in the TOML config (`maze.size`).
        field: String,
        /// What is wrong and what is accepted.
        reason: String,
    },
    /// A file could not be read or written. (The OS error is part of the message, not a
    /// `source`, so that error chains print it once.)
    #[error("{path}: {cause}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        cause: std::io::Error,
    },
    /// A file was read but could not be parsed (syntax, unknown key, wrong type).
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// The parser's message, which locates the problem in the file.
        message: String,
    },
    /// Phase 1 used its whole step budget without reaching a reward.
    #[error(
        "exploration used its budget of {steps} environment steps without reaching the target \
         (raise `explore.budget`)"
    )]
    ExplorationBudget {
        /// Environment steps performed.
        steps: u64,
    },
    /// Reading or writing a CSV file failed (its path named).
    #[error("{path}: {cause}")]
    Csv {
        /// The file.
        path: PathBuf,
        /// The CSV reader's or writer's error (it locates the record).
        cause: csv::Error,
    },
    /// One run of a sweep failed: which cell and seed, and why.
    #[error("cell {cell} seed {seed}: {cause}")]
    Run {
        /// The cell (its key, written: errors sit below every module).
        cell: String,
        /// The run seed.
        seed: u64,
        /// Why it failed.
        cause: Box<Error>,
    },
    /// Aggregating results failed (polars), or its numbers disagreed with the plain check.
    #[error("aggregate {experiment}: {message}")]
    Aggregate {
        /// The experiment.
        experiment: String,
        /// What went wrong.
        message: String,
    },
    /// A claim of `experiments/claims.toml` could not be judged: its table, or the cells it
    /// compares, are missing.
    #[error("claim {id}: {message}")]
    Claim {
        /// The claim's id.
        id: String,
        /// What is missing.
        message: String,
    },
    /// A setting asks for a hook the environment does not offer (see [`crate::env::Capability`]):
    /// refused instead of run without it.
    #[error(
        "`{setting}` needs the environment's {hook}, which this environment does not offer \
         (implement it, or change the setting)"
    )]
    Capability {
        /// The setting that needs it, as written in a config (`phase2.start = "ball"`).
        setting: String,
        /// The hook (`Env::ball_starts (SampleBall)`).
        hook: &'static str,
    },
    /// `pbcs exp check`: a cell's fresh rows differ from the committed ones beyond what was
    /// asked for (bytes with `--exact`, else the committed success interval).
    #[error("cell {cell} not reproduced: {message}")]
    NotReproduced {
        /// The cell id.
        cell: String,
        /// How they differ.
        message: String,
    },
    /// Rendering a picture failed.
    #[error("plot {path}: {message}")]
    Plot {
        /// The picture being written.
        path: PathBuf,
        /// The backend's message.
        message: String,
    },
}

/// `Result` with the crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// Shorthand for [`Error::Invalid`].
    pub fn invalid(field: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::Invalid {
            field: field.into(),
            reason: reason.into(),
        }
    }

    /// An [`Error::Invalid`] found in the file `path` as an [`Error::Parse`] naming it (and
    /// still the field); other errors name their file already and stay as they are.
    ///
    /// ```
    /// use pbcs::Error;
    /// let e = Error::invalid("maze.size", "must be at least 2").in_file("run.toml");
    /// assert_eq!(e.to_string(), "run.toml: invalid `maze.size`: must be at least 2");
    /// ```
    pub fn in_file(self, path: impl Into<PathBuf>) -> Self {
        match self {
            Error::Invalid { .. } => Error::parse(path, self.to_string()),
            other => other,
        }
    }

    /// Shorthand for [`Error::Parse`]: `path` could not be read as what it should hold.
    pub fn parse(path: impl Into<PathBuf>, message: impl std::fmt::Display) -> Self {
        Error::Parse {
            path: path.into(),
            message: message.to_string(),
        }
    }

    /// Shorthand for [`Error::Csv`].
    pub fn csv(path: impl Into<PathBuf>, cause: csv::Error) -> Self {
        Error::Csv {
            path: path.into(),
            cause,
        }
    }

    /// [`Error::csv`], where a value could not be read, naming its column from `header` (the
    /// CSV reader names the field by its number) and the line.
    pub fn csv_in(path: impl Into<PathBuf>, cause: csv::Error, header: &csv::StringRecord) -> Self {
        if let csv::ErrorKind::Deserialize { pos, err } = cause.kind() {
            if let Some(name) = err.field().and_then(|k| header.get(k as usize)) {
                let line = pos.as_ref().map_or(0, csv::Position::line);
                return Error::parse(
                    path,
                    format!("line {line}: column `{name}`: {}", err.kind()),
                );
            }
        }
        Error::csv(path, cause)
    }

    /// Shorthand for [`Error::Io`].
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            cause: source,
        }
    }
}

/// Work stopped at its deadline (`--stop-after`, [`crate::checkpoint::Checkpoint::stop_at`])
/// with this many runs unfinished, those in progress saved: the same command goes on.
#[derive(Debug)]
pub struct Unfinished(pub usize);

impl Unfinished {
    /// The exit status of a command that stopped so: 75, sysexits.h's EX_TEMPFAIL ("try again
    /// later", for a cluster script to requeue on).
    pub const EXIT: u8 = 75;
}

impl std::fmt::Display for Unfinished {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "stopped at the deadline (--stop-after) with {} unfinished, the runs in \
             progress saved; run the same command again to go on (exit status {})",
            match self.0 {
                1 => "1 run".to_string(),
                n => format!("{n} runs"),
            },
            Self::EXIT
        )
    }
}

impl std::error::Error for Unfinished {}
