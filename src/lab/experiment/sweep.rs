//! Running an experiment: one (cell, seed) run, and the sweep that runs the plan's runs
//! ([`super::plan`]) in parallel, resumably.

use super::{read_finished, run_file, Cell, Experiment, Job, Pending, RawRow};
use crate::checkpoint::Checkpoint;
use crate::error::{Error, Result};
use crate::nn::kernel::Kernel;
use crate::runs::run_outcome_resumable;
use crate::validate::Check;
use std::path::Path;
use std::time::Instant;

/// Runs (cell, seed) and writes its raw files into `dir` (the CSV row last): the run is
/// computed without writing anything ([`crate::runs::train_outcome`], [`run_outcome`]), then only
/// the raw files the tables and figures need are written: `s<seed>.timing.toml`,
/// `s<seed>.evals.csv` (vanilla), `s<seed>.evaluation.csv` (PBCS, and vanilla runs judged by
/// PBCS's protocol), `s<seed>.picture.csv` (picture seeds), `s<seed>.toml` (the
/// job) and `s<seed>.csv` (the row). The learners run on `kernel`. A run saves itself to
/// `s<seed>.resume` every ten minutes (a vanilla run at an evaluation, a PBCS run between two
/// of phase 2's learning problems) and goes on from there when run again after a cut
/// ([`crate::vanilla::resume`], [`crate::runs::pbcs_resume`]: the same bytes as an uncut
/// run); the file goes once the row is written (a failure to delete it is only reported: the
/// row stands). A vanilla run calls `progress(steps, success)` after each of its evaluations.
///
/// With a deadline `stop_at`, a vanilla run stops at its first evaluation at or past it, a
/// PBCS run at the end of its first learning problem at or past it (phase 2's verification
/// and repairs and the chain's evaluation run to the row), saved to its checkpoint, and
/// `None` is returned (nothing else is written: run it again to go on).
pub fn run_cell_seed(
    exp: &Experiment,
    cell: &Cell,
    seed: u64,
    dir: &Path,
    kernel: Kernel,
    stop_at: Option<Instant>,
    progress: impl FnMut(u64, f32),
) -> Result<Option<RawRow>> {
    let job = cell.job.with_seed(seed);
    let config = job.to_toml();
    let checkpoint = Checkpoint {
        stop_at,
        ..checkpoint(cell, seed, dir)
    };
    let (row, seconds, picture) = match &job {
        Job::Vanilla(j) => {
            let valid = j.clone().valid()?;
            let Some(run) = crate::runs::train_outcome(&valid, kernel, &checkpoint, progress)?
            else {
                return Ok(None);
            };
            crate::record::write_records(&run_file(dir, seed, ".evals.csv"), &run.result.evals)?;
            let final_eval = &run.result.final_eval;
            if !final_eval.is_empty() {
                crate::record::write_records(&run_file(dir, seed, ".evaluation.csv"), final_eval)?;
            }
            let row = RawRow::vanilla(exp, cell, j, &run.summary, final_eval);
            (row, run.seconds, run.picture)
        }
        Job::Pbcs(j) => {
            let valid = j.clone().valid()?;
            let Some(run) = run_outcome_resumable(&valid, kernel, &checkpoint, |_, _| {})? else {
                return Ok(None);
            };
            crate::record::write_records(&run_file(dir, seed, ".evaluation.csv"), &run.evaluation)?;
            let row = RawRow::pbcs(exp, cell, j, run.record);
            (row, run.seconds, run.picture)
        }
    };
    crate::runs::write_timing(
        &run_file(dir, seed, ".timing.toml"),
        seconds,
        row.env_steps,
        Some(kernel),
    )?;
    if exp.picture_seeds.contains(&seed) {
        picture.write_csv(&run_file(dir, seed, ".picture.csv"))?;
    }
    crate::record::write_atomic(&run_file(dir, seed, ".toml"), |w| {
        w.write_all(config.as_bytes())
    })?;
    crate::record::write_record(&run_file(dir, seed, ".csv"), &row)?;
    drop_checkpoint(&checkpoint);
    Ok(Some(row))
}

/// The checkpoint of the run (cell, seed) whose raw files are in `dir`: `s<seed>.resume`, of
/// the job's TOML (a vanilla run's learner state, and a PBCS run's saved state, also name the
/// kernel, which must compute the bytes of the kernel a resumed run is on:
/// [`Kernel::same_bytes`]).
pub fn checkpoint(cell: &Cell, seed: u64, dir: &Path) -> Checkpoint {
    Checkpoint::new(
        run_file(dir, seed, ".resume"),
        cell.job.with_seed(seed).to_toml(),
    )
}

/// Deletes the checkpoint of a run whose row is written; a failure is only reported (the
/// row stands, and the file is ignored where a row exists).
fn drop_checkpoint(checkpoint: &Checkpoint) {
    if let Err(e) = checkpoint.remove() {
        eprintln!("warning: a finished run's checkpoint stays: {e}");
    }
}

/// What happened to one (cell, seed) of a sweep.
#[derive(Debug, Clone)]
pub enum Event {
    /// It was already finished and was read back.
    Skipped(RawRow),
    /// It goes on from the checkpoint a run cut earlier left (told before any run begins).
    Resumes {
        /// The checkpoint.
        from: std::path::PathBuf,
        /// Environment steps saved, where the file's head says (a file that would be refused
        /// is refused by the run, naming it).
        steps: Option<u64>,
    },
    /// It ran now, in this many wall seconds.
    Ran(RawRow, f64),
    /// It stopped at the sweep's deadline after this many environment steps, saved to its
    /// checkpoint ([`sweep_until`]): run the sweep again to go on.
    Saved {
        /// Environment steps so far.
        steps: u64,
    },
    /// It is running: a vanilla run's evaluation after this many environment steps, with this
    /// greedy success rate.
    Evaluated {
        /// Environment steps so far.
        steps: u64,
        /// The evaluation's success rate.
        success: f32,
    },
}

impl Event {
    /// Whether the (cell, seed) is over for this sweep (read back, run, or saved at the
    /// deadline): a sweep's progress counts these.
    pub fn is_final(&self) -> bool {
        matches!(
            self,
            Event::Skipped(_) | Event::Ran(..) | Event::Saved { .. }
        )
    }
}

/// What a sweep with a deadline ([`sweep_until`]) did.
#[derive(Debug, Clone)]
pub struct Swept {
    /// The finished runs' rows (read back or run now), in the order of the plan.
    pub rows: Vec<RawRow>,
    /// The runs that did not finish: stopped at the deadline and saved, or not begun.
    pub unfinished: usize,
}

/// Runs every (cell, seed) of `runs` that is not finished under `results`, `jobs` at a time
/// (one thread each; each run is single-threaded and deterministic, so the bytes do not
/// depend on `jobs`), every learner on `kernel`. `on_event` is called as each pair finishes.
/// Returns the rows in the order of `runs`; the first error stops handing out new runs and is
/// returned. Before anything else the sweep takes the lock of `results`
/// ([`crate::record::FolderLock`]): exclusively for several runs, shared for one; a folder
/// another sweep holds is refused at once, naming it, and nothing is read or run. A
/// registered grid whose preset file changed is refused first ([`super::Registration::check`]).
pub fn sweep(
    exp: &Experiment,
    runs: &[Pending],
    results: &Path,
    jobs: usize,
    kernel: Kernel,
    on_event: impl Fn(&Pending, &Event) + Sync,
) -> Result<Vec<RawRow>> {
    Ok(sweep_until(exp, runs, results, jobs, kernel, None, on_event)?.rows)
}

/// [`sweep`] with a deadline `stop_at` (a cluster job's time limit): no run begins at or past
/// it, and a run in progress stops at its first evaluation (vanilla) or the end of its first
/// learning problem (PBCS) at or past it, saved to its checkpoint ([`run_cell_seed`],
/// [`Event::Saved`]).
/// Running the sweep again goes on where it stopped, to the same bytes as a sweep never
/// stopped.
pub fn sweep_until(
    exp: &Experiment,
    runs: &[Pending],
    results: &Path,
    jobs: usize,
    kernel: Kernel,
    stop_at: Option<Instant>,
    on_event: impl Fn(&Pending, &Event) + Sync,
) -> Result<Swept> {
    // A registered grid runs only with the preset it was registered for.
    if let Some(registration) = &exp.registered {
        registration.check(exp.name)?;
    }
    let _folder = crate::record::FolderLock::acquire(results, runs.len() <= 1)?;
    // Finished runs first (cheap), so that a config mismatch is reported before any work.
    let mut rows = read_back(exp, runs, results, &on_event)?;
    let todo: Vec<usize> = (0..runs.len()).filter(|&i| rows[i].is_none()).collect();
    let ran = run_parallel(&todo, jobs, |&i| {
        if stop_at.is_some_and(|t| Instant::now() >= t) {
            return Ok(None);
        }
        run_pending(exp, &runs[i], results, kernel, stop_at, &on_event)
    })?;
    for (i, row) in todo.into_iter().zip(ran) {
        rows[i] = row;
    }
    let unfinished = rows.iter().filter(|r| r.is_none()).count();
    Ok(Swept {
        rows: rows.into_iter().flatten().collect(),
        unfinished,
    })
}

/// The finished rows of `runs` (`None` for a run not finished), each told as
/// [`Event::Skipped`]; a run with a checkpoint and no row is told as [`Event::Resumes`].
fn read_back(
    exp: &Experiment,
    runs: &[Pending],
    results: &Path,
    on_event: &impl Fn(&Pending, &Event),
) -> Result<Vec<Option<RawRow>>> {
    let mut rows = Vec::with_capacity(runs.len());
    for p in runs {
        let dir = exp.cell_dir(results, p.cell);
        let done = read_finished(exp, p.cell, p.seed, &dir)?;
        let saved = checkpoint(p.cell, p.seed, &dir);
        match &done {
            // A checkpoint left by a process stopped between the row and its deletion.
            Some(r) => {
                drop_checkpoint(&saved);
                on_event(p, &Event::Skipped(r.clone()));
            }
            None if saved.path.is_file() => {
                let steps = saved.peek().ok().flatten().map(|s| s.steps);
                let from = saved.path;
                on_event(p, &Event::Resumes { from, steps });
            }
            None => {}
        }
        rows.push(done);
    }
    Ok(rows)
}

/// Runs `p` under its lock ([`run_cell_seed`]; read back where another sweep finished it
/// meanwhile): its row, or `None` where it stopped at `stop_at`, saved. Told as
/// [`Event::Evaluated`] as it goes, then [`Event::Ran`] or [`Event::Saved`].
fn run_pending(
    exp: &Experiment,
    p: &Pending,
    results: &Path,
    kernel: Kernel,
    stop_at: Option<Instant>,
    on_event: &impl Fn(&Pending, &Event),
) -> Result<Option<RawRow>> {
    let clock = Instant::now();
    let dir = exp.cell_dir(results, p.cell);
    let mut last_steps = 0;
    // One process per run: a second sweep into this folder stops here with a message
    // instead of doing the run again and replacing its row.
    let row = crate::record::WorkLock::acquire(&run_file(&dir, p.seed, ".lock"))
        .and_then(|_lock| {
            // What a killed process of this run left mid-write (its checkpoint's
            // temporary file): the lock makes the names s<seed>.* this run's.
            crate::record::remove_orphans(&dir, &format!("s{}.", p.seed))?;
            // Finished by another sweep while this one was planning: read it back.
            match read_finished(exp, p.cell, p.seed, &dir)? {
                Some(row) => Ok(Some(row)),
                None => run_cell_seed(
                    exp,
                    p.cell,
                    p.seed,
                    &dir,
                    kernel,
                    stop_at,
                    |steps, success| {
                        last_steps = steps;
                        on_event(p, &Event::Evaluated { steps, success })
                    },
                ),
            }
        })
        .map_err(|e| Error::Run {
            cell: p.cell.id.to_string(),
            seed: p.seed,
            cause: Box::new(e),
        })?;
    match &row {
        Some(row) => on_event(p, &Event::Ran(row.clone(), clock.elapsed().as_secs_f64())),
        None => {
            // A PBCS run reports no evaluations: its checkpoint's head says how far it got.
            let saved = checkpoint(p.cell, p.seed, &dir).peek().ok().flatten();
            let steps = saved.map_or(last_steps, |s| s.steps);
            on_event(p, &Event::Saved { steps })
        }
    }
    Ok(row)
}

/// `f` on every item, `jobs` at a time (a pool of `jobs` threads, at most one per item), the
/// results in the items'
/// order. Items start in their order (each free thread takes the next one), so an interrupted
/// sweep has finished a prefix of its plan: with the table's plan, whole mazes, smallest first.
/// One item's failure, an error or a panic, does not take the others with it: every item runs
/// (and a run writes its own row), then the first failure in the items' order is returned,
/// with how many failed. Every run is single-threaded and seeded by its own job, so `jobs`
/// changes the wall clock, never a byte.
pub fn run_parallel<T: Sync, R: Send>(
    items: &[T],
    jobs: usize,
    f: impl Fn(&T) -> Result<R> + Sync,
) -> Result<Vec<R>> {
    use rayon::prelude::*;
    // No more threads than items: `--jobs 1000000` on ten runs starts ten.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs.clamp(1, items.len().max(1)))
        .build()
        .map_err(|e| Error::invalid("jobs", e.to_string()))?;
    let mut done: Vec<(usize, Result<R>)> = pool.install(|| {
        items
            .iter()
            .enumerate()
            .par_bridge()
            .map(|(i, item)| (i, caught(|| f(item))))
            .collect()
    });
    done.sort_by_key(|(i, _)| *i);
    let failed = done.iter().filter(|(_, r)| r.is_err()).count();
    let mut out = Vec::with_capacity(done.len());
    for (_, r) in done {
        match r {
            Ok(r) => out.push(r),
            Err(e) if failed == 1 => return Err(e),
            Err(e) => {
                return Err(Error::invalid(
                    "sweep",
                    format!("{failed} of {} runs failed; the first: {e}", items.len()),
                ))
            }
        }
    }
    Ok(out)
}

/// `f()`, with a panic turned into an error that carries its message: a bug met by one run
/// fails that run, not the process and the runs beside it.
fn caught<R>(f: impl FnOnce() -> Result<R>) -> Result<R> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).unwrap_or_else(|payload| {
        let message = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "a panic without a message".to_string());
        Err(Error::invalid("run", format!("panicked: {message}")))
    })
}
