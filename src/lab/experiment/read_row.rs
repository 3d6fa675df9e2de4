//! Reading a raw row back: every value in range, and, for a row of an experiment's run, the
//! row that run wrote (its cell, seed and what the cell's job fixes).

use super::row::{layout_seed, KindRow, PbcsRow, RawRow, VanillaRow};
use super::{plan, run_file, Cell, Experiment, Job, Kind};
use crate::env::EvalEpisode;
use crate::error::{Error, Result};
use crate::phase2::StartMode;
use std::path::Path;

/// The finished raw row of (cell, seed) of `exp` in `dir` (the cell's folder), if there is
/// one. A finished run of another config is an error: results of two configs are never mixed.
/// Configs are compared by value, so a setting added later, absent from an older stored
/// config, takes its default (the behaviour the older run had). The row itself must be this
/// run's and hold one record of values in range ([`read_run_row`]), else an error names the
/// file, the line and the column: a resumed sweep, `pbcs aggregate` and `pbcs exp list` read
/// rows through here alike.
pub fn read_finished(
    exp: &Experiment,
    cell: &Cell,
    seed: u64,
    dir: &Path,
) -> Result<Option<RawRow>> {
    let path = run_file(dir, seed, ".csv");
    if !path.exists() {
        return Ok(None);
    }
    let config_path = run_file(dir, seed, ".toml");
    let stored = std::fs::read_to_string(&config_path).map_err(|e| Error::io(&config_path, e))?;
    if !cell.job.with_seed(seed).same_as(&stored) {
        let profile = match &exp.profile {
            None => "; rows of a profile's grid (`make smoke` writes results-smoke/) are read \
                     with that profile (--profile smoke)"
                .to_string(),
            Some(p) => format!("; this read the grid of the profile `{p}`"),
        };
        return Err(Error::parse(
            &config_path,
            format!(
                "this finished run used another config than the experiment now gives (its \
                 file, or `pbcs table`'s preset or config); remove the cell's folder to re-run \
                 it, restore the file, or choose another results folder (--results, \
                 --out){profile}"
            ),
        ));
    }
    read_run_row(exp, cell, seed, &path).map(Some)
}

/// All finished raw rows of the experiment under `results`, in (cell, seed) order; missing
/// runs are left out (and counted by the caller through `n`).
pub fn read_raw(exp: &Experiment, results: &Path) -> Result<Vec<RawRow>> {
    let mut rows = Vec::new();
    for p in plan(exp, None, None)? {
        if let Some(r) = read_finished(exp, p.cell, p.seed, &exp.cell_dir(results, p.cell))? {
            rows.push(r);
        }
    }
    Ok(rows)
}

/// Reads one raw row file: a header and exactly one record, every value in range (a rate in
/// [0, 1], no NaN or infinity, `solved` as the rate and the failure give it, the columns of the
/// other kind empty or 0, the step counts adding up). An error names the file, the line and
/// the column. [`read_run_row`] also checks the row against its place in an experiment.
pub fn read_row(path: &Path) -> Result<RawRow> {
    let (row, line) = read_row_at(path)?;
    check_values(&row, path, line).map(|()| row)
}

/// Reads the raw row of (`cell`, `seed`) of `exp` at `path` ([`read_row`]) and checks that it
/// is that run's row: the experiment's name, the cell's id, method, kind, maze size and
/// layout seed, the seed, and what the cell's job fixes (learner, γ, chaining, starts,
/// budget). A row edited or moved into another cell's folder is an error naming the file, the
/// line and the column, never a run of another cell counted here.
pub fn read_run_row(exp: &Experiment, cell: &Cell, seed: u64, path: &Path) -> Result<RawRow> {
    let (row, line) = read_row_at(path)?;
    // A vanilla run stops before its budget only with `train.stop_at_successes`.
    let stops = match &cell.job {
        Job::Vanilla(j) => j.train.stop_at_successes.is_some(),
        Job::Pbcs(_) => true,
    };
    if !stops && row.kind() == Kind::Vanilla && row.env_steps != row.budget {
        return Err(Error::parse(
            path,
            format!(
                "line {line}, column `env_steps`: {} of a budget of {}, but the job of cell \
                 `{}` trains its whole budget (it has no train.stop_at_successes)",
                row.env_steps, row.budget, cell.id
            ),
        ));
    }
    match first_difference(&row, exp, cell, seed) {
        None => {
            check_values(&row, path, line)?;
            check_summary(&row, cell, seed, path, line)?;
            Ok(row)
        }
        Some((column, found, want)) => Err(Error::parse(
            path,
            format!(
                "line {line}, column `{column}`: holds `{found}`, but this file is the row of \
                 experiment `{}`, cell `{}`, seed {seed}, whose {column} is `{want}` (a row \
                 edited or moved from another cell's folder is never counted; restore it, or \
                 remove it and run the cell's seed again)",
                exp.name, cell.id
            ),
        )),
    }
}

/// The first column of `row` that differs from what (`cell`, `seed`) of `exp` fixes (the
/// experiment's name, the cell's id, method, kind, maze size and layout seed, the seed, the
/// job's learner, γ, chaining, starts and budget): (column, found, wanted).
fn first_difference(
    row: &RawRow,
    exp: &Experiment,
    cell: &Cell,
    seed: u64,
) -> Option<(&'static str, String, String)> {
    let starts = |s: Option<StartMode>| s.map_or("", <&str>::from);
    let (kind, maze_seed, learner, gamma, chaining, start, budget) = match &cell.job {
        Job::Vanilla(j) => (
            Kind::Vanilla,
            layout_seed(j),
            j.learner_name(),
            j.learner.gamma(),
            false,
            None,
            j.train.steps,
        ),
        Job::Pbcs(j) => (
            Kind::Pbcs,
            layout_seed(j),
            j.learner.record_name(),
            j.learner.gamma(),
            j.phase2.chaining,
            Some(j.phase2.start),
            j.phase2.max_env_steps,
        ),
    };
    // Each column the job fixes, compared as its type (γ: the job's f32, which the row holds);
    // in words where they differ.
    fn differ<T: PartialEq + std::fmt::Display>(found: T, want: T) -> Option<(String, String)> {
        (found != want).then(|| (found.to_string(), want.to_string()))
    }
    let row_starts = row.pbcs_row().map(|p| p.starts);
    let fields: [(&str, Option<(String, String)>); 12] = [
        ("experiment", differ(row.experiment, exp.name)),
        ("cell", differ(row.cell, cell.id)),
        ("method", differ(row.method, cell.method)),
        ("kind", differ(row.kind().name(), kind.name())),
        ("maze", differ(&row.site, &cell.site)),
        ("maze_seed", differ(row.maze_seed, maze_seed)),
        ("seed", differ(row.seed, seed)),
        ("learner", differ(row.learner, learner)),
        ("gamma", differ(row.gamma, gamma)),
        (
            "chaining",
            differ(row.pbcs_row().is_some_and(|p| p.chaining), chaining),
        ),
        ("starts", differ(starts(row_starts), starts(start))),
        ("budget", differ(row.budget, budget)),
    ];
    fields
        .into_iter()
        .find_map(|(c, d)| d.map(|(found, want)| (c, found, want)))
}

/// Checks a row against the files it summarises, beside it (where they exist: rows written
/// before a file existed lack it): a PBCS row's `s<seed>.evaluation.csv` holds the job's
/// `phase2.eval_episodes` episodes and the rate is their wins over them, or is empty for a run
/// that stopped (a failure) or made no skill, whose rate is 0; a vanilla row's rate is that of
/// its `s<seed>.evaluation.csv` (PBCS's protocol after training) or else of the last
/// evaluation of its `s<seed>.evals.csv`. An error names the row's file, line and column.
fn check_summary(r: &RawRow, cell: &Cell, seed: u64, path: &Path, line: u64) -> Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let evaluation_path = run_file(dir, seed, ".evaluation.csv");
    let evaluation: Option<Vec<EvalEpisode>> = evaluation_path
        .exists()
        .then(|| crate::record::read_records(&evaluation_path))
        .transpose()?;
    let file = evaluation_path.display();
    let wrong = match (&cell.job, evaluation) {
        (Job::Pbcs(j), Some(e)) => pbcs_evaluation_error(r, j.phase2.eval_episodes, &e, &file),
        (Job::Vanilla(j), Some(e)) => {
            let (n, wins) = (j.train.final_eval_episodes, wins(&e));
            let wrong = !e.is_empty() && (e.len() != n || r.success_rate != rate(&e));
            let why = || {
                let (rate, len) = (r.success_rate, e.len());
                format!("{rate}, but {file} holds {wins} wins of {len} episodes (the job evaluates {n})")
            };
            if wrong {
                Err(("success_rate", why()))
            } else {
                Ok(())
            }
        }
        // Every run writes its evaluation (a vanilla run, where its job evaluates after
        // training; else its curve); only the committed rows listed as written before that may
        // lack it ([`super::legacy`]).
        (job, None) => {
            let file = match job {
                Job::Vanilla(j) if j.train.final_eval_episodes == 0 => {
                    run_file(dir, seed, ".evals.csv")
                }
                _ => evaluation_path.clone(),
            };
            without_evaluation_error(r, job, &file, path)?
        }
    };
    wrong.map_err(|(column, why)| {
        Error::parse(path, format!("line {line}, column `{column}`: {why}"))
    })
}

/// Of `episodes`, those that reached the goal, and the rate they make.
fn wins(episodes: &[EvalEpisode]) -> usize {
    episodes.iter().filter(|e| e.success).count()
}

fn rate(episodes: &[EvalEpisode]) -> f32 {
    wins(episodes) as f32 / episodes.len() as f32
}

/// What is wrong with a PBCS row beside its evaluation `e` (in `file`) of a job evaluating
/// `n` episodes: the column and why.
fn pbcs_evaluation_error(
    r: &RawRow,
    n: usize,
    e: &[EvalEpisode],
    file: &impl std::fmt::Display,
) -> std::result::Result<(), (&'static str, String)> {
    let rate_is = r.success_rate;
    if e.is_empty() {
        // A run that stopped (a failure) or made no skill is not evaluated: its rate is 0.
        if r.failure().is_none() && r.skills() > 0 {
            let skills = r.skills();
            let why = format!(
                "empty, but {file} holds no evaluation episode: a chain of {skills} skills with \
                 no failure is evaluated"
            );
            return Err(("failure", why));
        }
        if rate_is != 0.0 {
            return Err((
                "success_rate",
                format!("{rate_is}, but {file} holds no evaluation episode"),
            ));
        }
        return Ok(());
    }
    if e.len() != n {
        let len = e.len();
        let why = format!("of {len} episodes in {file}, but the job evaluates {n}");
        return Err(("success_rate", why));
    }
    if let Some(f) = r.failure() {
        let why = format!("{}, but the run's chain was evaluated ({file})", f.name());
        return Err(("failure", why));
    }
    if rate_is != rate(e) {
        let (wins, len) = (wins(e), e.len());
        let why = format!("{rate_is}, but {file} holds {wins} wins of {len} episodes");
        return Err(("success_rate", why));
    }
    Ok(())
}

/// What is wrong with a row of `job` that has no evaluation file: the file it should have
/// (`file`) missing, unless the committed row at `path` is listed as written before it
/// ([`super::legacy`]); a vanilla row's rate not its curve's last evaluation.
fn without_evaluation_error(
    r: &RawRow,
    job: &Job,
    file: &Path,
    path: &Path,
) -> Result<std::result::Result<(), (&'static str, String)>> {
    if !file.exists() && !super::legacy::may_lack_evaluation(path)? {
        let why = format!("{}, but {} is missing", r.success_rate, file.display());
        return Ok(Err(("success_rate", why)));
    }
    if let (Job::Vanilla(_), true) = (job, file.exists()) {
        let evals: Vec<crate::vanilla::EvalRow> = crate::record::read_records(file)?;
        if let Some(last) = evals.last().filter(|e| e.success != r.success_rate) {
            let (steps, success) = (last.steps, last.success);
            let why = format!(
                "{}, but the last evaluation of {} (at {steps} steps) has success {success}",
                r.success_rate,
                file.display()
            );
            return Ok(Err(("success_rate", why)));
        }
    }
    Ok(Ok(()))
}

/// The row of `path` (one record under the header, its values not yet checked) and the line
/// its record starts on.
fn read_row_at(path: &Path) -> Result<(RawRow, u64)> {
    let mut reader = csv::Reader::from_path(path).map_err(|e| Error::csv(path, e))?;
    let headers = reader.headers().map_err(|e| row_error(path, e))?.clone();
    let mut record = csv::StringRecord::new();
    if !reader
        .read_record(&mut record)
        .map_err(|e| row_error(path, e))?
    {
        return Err(Error::parse(
            path,
            "holds no record under its header (a raw row file holds exactly one)",
        ));
    }
    let line = record.position().map_or(2, csv::Position::line);
    let row: RawRow = record
        .deserialize(Some(&headers))
        .map_err(|e| match e.kind() {
            csv::ErrorKind::Deserialize { err, .. } => {
                let message = err.kind().to_string();
                // The reader's own errors (a number that does not parse) name the field's
                // index; serde's (an unknown enum value) quote the value, found here.
                let index = err.field().map(|i| i as usize).or_else(|| {
                    let quoted = message.split('`').nth(1)?;
                    let mut hits = (0..record.len()).filter(|&i| &record[i] == quoted);
                    hits.next().filter(|_| hits.next().is_none())
                });
                let column = index
                    .and_then(|i| Some((headers.get(i)?, record.get(i)?)))
                    .map_or(String::new(), |(name, value)| {
                        format!(", column `{name}` (`{value}`)")
                    });
                Error::parse(path, format!("line {line}{column}: {message}"))
            }
            _ => row_error(path, e),
        })?;
    let mut next = csv::StringRecord::new();
    if reader
        .read_record(&mut next)
        .map_err(|e| row_error(path, e))?
    {
        let at = next.position().map_or(line + 1, csv::Position::line);
        return Err(Error::parse(
            path,
            format!(
                "line {at}: a second record (a raw row file holds exactly one run's row, on \
                 line {line})"
            ),
        ));
    }
    Ok((row, line))
}

/// A CSV reader's error on a raw row file, said by line: a record of the wrong length names
/// its line and both lengths; anything else is the reader's own message (which locates it).
fn row_error(path: &Path, e: csv::Error) -> Error {
    match e.kind() {
        csv::ErrorKind::UnequalLengths {
            pos,
            expected_len,
            len,
        } => Error::parse(
            path,
            format!(
                "line {}: {len} fields, but the header has {expected_len}",
                pos.as_ref().map_or(0, csv::Position::line)
            ),
        ),
        _ => Error::csv(path, e),
    }
}

/// The checks of one row's own values ([`read_row`]), the row of `path` on `line`: an error
/// names the column and what is wrong.
fn check_values(r: &RawRow, path: &Path, line: u64) -> Result<()> {
    value_error(r).map_err(|(column, message)| {
        Error::parse(path, format!("line {line}, column `{column}`: {message}"))
    })
}

/// The first of a row's values out of range or at odds with the others: its column and what is
/// wrong. Each check holds for every row a run writes ([`RawRow::vanilla`], [`RawRow::pbcs`]).
fn value_error(r: &RawRow) -> std::result::Result<(), (&'static str, String)> {
    let fail = |column, message: String| Err((column, message));
    if !(r.success_rate.is_finite() && (0.0..=1.0).contains(&r.success_rate)) {
        return fail(
            "success_rate",
            format!("{} is not a rate in [0, 1]", r.success_rate),
        );
    }
    if !(r.gamma.is_finite() && (0.0..1.0).contains(&r.gamma)) {
        return fail("gamma", format!("{} is not a discount in [0, 1)", r.gamma));
    }
    if r.budget == 0 {
        return fail("budget", "0: a run's step budget is at least 1".into());
    }
    match &r.kind {
        KindRow::Vanilla(v) => vanilla_value_error(r, v)?,
        KindRow::Pbcs(p) => pbcs_value_error(r, p)?,
    }
    let solved = crate::stats::solved(r.failure().is_some(), r.success_rate);
    if r.solved != solved {
        return fail(
            "solved",
            format!(
                "{}, but a run with success_rate {} and {} is {}solved (solved: no failure and \
                 a success rate of at least {})",
                r.solved,
                r.success_rate,
                r.failure().map_or("no failure".to_string(), |f| format!(
                    "failure {}",
                    f.name()
                )),
                if solved { "" } else { "not " },
                crate::runs::SOLVED_AT
            ),
        );
    }
    Ok(())
}

/// [`value_error`] of a vanilla row: the whole budget trained, or stopped where it solved.
/// (That PBCS's columns are empty was checked when the row was read, [`super::row::RowRecord`].)
fn vanilla_value_error(
    r: &RawRow,
    v: &VanillaRow,
) -> std::result::Result<(), (&'static str, String)> {
    let fail = |column, message: String| Err((column, message));
    // A run trains its whole budget, or stops earlier at an evaluation that solved it
    // (`train.stop_at_successes`; whether its job has that stop is checked against the cell,
    // [`read_run_row`]).
    if r.env_steps > r.budget || (r.env_steps < r.budget && !r.solved) {
        return fail(
            "env_steps",
            format!(
                "{} in a vanilla row of budget {}{}: a run trains its whole budget, or stops \
                 earlier at an evaluation that solved it",
                r.env_steps,
                r.budget,
                if r.solved { "" } else { " not solved" }
            ),
        );
    }
    if let Some(first) = v.first_success_steps.filter(|&s| s > r.env_steps) {
        return fail(
            "first_success_steps",
            format!("{first}, after the run's {} env steps", r.env_steps),
        );
    }
    Ok(())
}

/// [`value_error`] of a PBCS row: its steps summing up.
fn pbcs_value_error(r: &RawRow, p: &PbcsRow) -> std::result::Result<(), (&'static str, String)> {
    let sum = [p.phase1_steps, p.train_steps, p.test_steps]
        .into_iter()
        .try_fold(0u64, u64::checked_add);
    if sum != Some(r.env_steps) {
        return Err((
            "env_steps",
            format!(
                "{}, but phase1_steps + train_steps + test_steps = {} + {} + {}",
                r.env_steps, p.phase1_steps, p.train_steps, p.test_steps
            ),
        ));
    }
    Ok(())
}

/// One line per run, as sweeps print it: `pbcs-maze2 seed 3: solved (success 1.00) in 160484
/// env steps`, with the failure where phase 2 stopped.
impl std::fmt::Display for RawRow {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} seed {}: {} (success {:.2}) in {} env steps",
            self.cell,
            self.seed,
            if self.solved { "solved" } else { "not solved" },
            self.success_rate,
            self.env_steps
        )?;
        match self.failure() {
            Some(failure) => write!(f, ", {}", failure.name()),
            None => Ok(()),
        }
    }
}
