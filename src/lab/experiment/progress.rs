//! A sweep's progress as `pbcs table` and `pbcs exp run` show it ([`SweepProgress`]): a bar of
//! runs, one line per run as it finishes, resumes or stops at the deadline, and environment
//! steps per second.

use super::{Event, Pending};
use indicatif::{ProgressBar, ProgressStyle};
use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// What a sweep's events show ([`SweepProgress::on_event`], the `on_event` of
/// [`super::sweep_until`]). Without a terminal the bar is hidden and drops its lines: a log
/// (nohup, a cluster's job output) still gets them, and a running vanilla run's evaluation at
/// most once a minute.
pub struct SweepProgress {
    bar: ProgressBar,
    /// Environment steps of the runs done now, and how many.
    steps: AtomicU64,
    ran: AtomicUsize,
    clock: Instant,
    /// Per running vanilla run, its first evaluation seen (time, steps), for its rate.
    first_seen: Mutex<HashMap<(super::CellKey, u64), (Instant, u64)>>,
    /// When a hidden bar last logged an evaluation.
    logged: Mutex<Option<Instant>>,
}

impl SweepProgress {
    /// The progress of a sweep of `total` runs (those already finished count as they are read
    /// back).
    pub fn new(total: u64) -> Self {
        let bar = ProgressBar::new(total);
        let style = "{bar:30} {pos}/{len} runs [{elapsed}, eta {eta}] {msg}";
        bar.set_style(ProgressStyle::with_template(style).expect("valid template"));
        SweepProgress {
            bar,
            steps: AtomicU64::new(0),
            ran: AtomicUsize::new(0),
            clock: Instant::now(),
            first_seen: Mutex::new(HashMap::new()),
            logged: Mutex::new(None),
        }
    }

    /// Shows what happened to run `p`.
    pub fn on_event(&self, p: &Pending, event: &Event) {
        let run = format!("{} seed {}", p.cell.id, p.seed);
        match event {
            Event::Evaluated { steps, success } => self.evaluated(p, *steps, *success),
            Event::Ran(row, secs) => {
                self.bar.inc(1);
                self.ran.fetch_add(1, Ordering::SeqCst);
                let total = self.steps.fetch_add(row.env_steps, Ordering::SeqCst) + row.env_steps;
                self.say(format!("{row} ({secs:.0} s)"));
                let rate = total as f64 / self.clock.elapsed().as_secs_f64().max(1e-9);
                self.bar.set_message(format!("{rate:.0} env steps/s"));
            }
            Event::Saved { steps } => {
                self.bar.inc(1);
                self.say(format!(
                    "{run}: stopped at the deadline after {steps} env steps, saved to its \
                     checkpoint"
                ));
            }
            Event::Skipped(_) => self.bar.inc(1),
            Event::Resumes { from, steps } => {
                let at = steps.map_or(String::new(), |s| format!(" ({s} env steps saved)"));
                self.say(format!("{run}: resumes from {}{at}", from.display()));
            }
        }
    }

    /// Clears the bar: how many runs ran now.
    pub fn finish(self) -> usize {
        self.bar.finish_and_clear();
        self.ran.into_inner()
    }

    fn say(&self, line: String) {
        if self.bar.is_hidden() {
            eprintln!("{line}");
        } else {
            self.bar.println(line);
        }
    }

    /// A running vanilla run's evaluation, with its rate from the second evaluation this
    /// process saw on.
    fn evaluated(&self, p: &Pending, steps: u64, success: f32) {
        let (t0, s0) = *self
            .first_seen
            .lock()
            .unwrap()
            .entry((p.cell.id, p.seed))
            .or_insert((Instant::now(), steps));
        let rate = match steps - s0 {
            0 => String::new(),
            n => format!(
                " ({:.0} steps/s)",
                n as f64 / t0.elapsed().as_secs_f64().max(1e-9)
            ),
        };
        let line = format!(
            "{} seed {}: {steps} env steps, greedy success {success:.2}{rate}",
            p.cell.id, p.seed
        );
        let mut last = self.logged.lock().unwrap();
        if !self.bar.is_hidden() {
            self.bar.set_message(line);
        } else if last.is_none_or(|t| t.elapsed().as_secs() >= 60) {
            *last = Some(Instant::now());
            eprintln!("{line}");
        }
    }
}
