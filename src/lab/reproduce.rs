//! Re-running committed rows (`make cell`, `pbcs exp check`): the runs of one cell are repeated
//! in a scratch folder and compared with the committed raw rows, byte for byte, and where the
//! bytes differ, statistically: does the new success rate lie inside the committed rows'
//! Wilson 95 % interval? The layer kernels recorded beside the rows explain a byte difference
//! between machines ([`crate::nn::kernel::Kernel`]).

use crate::error::{Error, Result};
use crate::experiment::{
    plan, read_finished, run_file, sweep, CellKey, Event, Experiment, Pending, RawRow,
};
use crate::nn::kernel::Kernel;
use crate::record::Timing;
use crate::stats::wilson;
use crate::stats::Z95;
use std::path::Path;

/// One seed's comparison.
#[derive(Debug, Clone)]
pub struct SeedCheck {
    /// The run seed.
    pub seed: u64,
    /// Whether the fresh row has the committed row's bytes.
    pub identical: bool,
    /// Where they differ: `column: committed → fresh`, one per column (empty when identical;
    /// `header` when the headers differ, `bytes` when the values read the same but the bytes
    /// do not).
    pub differing: Vec<String>,
    /// The committed row.
    pub committed: RawRow,
    /// The fresh row.
    pub fresh: RawRow,
}

/// What re-running a cell found.
#[derive(Debug, Clone)]
pub struct CellCheck {
    /// The cell.
    pub cell: CellKey,
    /// Every seed re-run, in order.
    pub seeds: Vec<SeedCheck>,
    /// The kernels that computed the committed rows (sorted, each once; `matrixmultiply` for
    /// rows written before kernels were recorded).
    pub committed_kernels: Vec<String>,
    /// The kernel that computed the fresh rows.
    pub kernel: String,
}

/// The verdict of a [`CellCheck`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reproduced {
    /// Every row reproduced byte for byte.
    Match,
    /// Some bytes differ, but the new success rate lies inside the committed interval.
    WithinInterval,
    /// The new success rate lies outside the committed interval.
    Outside,
}

impl CellCheck {
    /// Runs.
    pub fn n(&self) -> u64 {
        self.seeds.len() as u64
    }

    /// Rows reproduced byte for byte.
    pub fn identical(&self) -> u64 {
        self.seeds.iter().filter(|s| s.identical).count() as u64
    }

    /// Solved runs among the committed rows.
    pub fn solved_committed(&self) -> u64 {
        self.seeds.iter().filter(|s| s.committed.solved).count() as u64
    }

    /// Solved runs among the fresh rows.
    pub fn solved_now(&self) -> u64 {
        self.seeds.iter().filter(|s| s.fresh.solved).count() as u64
    }

    /// The Wilson 95 % interval of the committed success rate.
    pub fn interval(&self) -> (f64, f64) {
        wilson(self.solved_committed(), self.n(), Z95)
    }

    /// Match, within the committed interval, or outside it.
    pub fn reproduced(&self) -> Reproduced {
        if self.identical() == self.n() {
            return Reproduced::Match;
        }
        let (lo, hi) = self.interval();
        let rate = self.solved_now() as f64 / self.n() as f64;
        if (lo..=hi).contains(&rate) {
            Reproduced::WithinInterval
        } else {
            Reproduced::Outside
        }
    }

    /// Why bytes may differ: the committed rows came from a kernel that sums in another order
    /// than this run's (None when every committed kernel gives this run's bytes).
    pub fn kernel_note(&self) -> Option<String> {
        let same = |k: &str| crate::nn::kernel::Kernel::same_bytes(k, &self.kernel);
        if self.committed_kernels.iter().all(|k| same(k)) {
            return None;
        }
        Some(format!(
            "the committed rows were computed with the {} kernel, this run with {}; kernels sum \
             in different orders, so bytes differ. `PBCS_KERNEL={} make cell ...` compares like \
             with like",
            self.committed_kernels.join(", "),
            self.kernel,
            self.committed_kernels[0]
        ))
    }
}

impl CellCheck {
    /// What `pbcs exp check` prints for cell `cell`: one line per seed (identical or not, the
    /// committed and the fresh row), then the counts and the committed Wilson interval.
    pub fn report(&self, cell: CellKey) -> String {
        let mut s = String::new();
        for c in &self.seeds {
            s.push_str(&format!(
                "seed {}: {} — committed: {}; now: {}\n",
                c.seed,
                if c.identical {
                    "identical bytes".to_string()
                } else {
                    format!("DIFFERENT ({})", c.differing.join(", "))
                },
                c.committed,
                c.fresh
            ));
        }
        let (n, (lo, hi)) = (self.n(), self.interval());
        s.push_str(&format!(
            "cell {cell}: {}/{n} rows identical byte for byte; solved committed {}/{n} \
             (Wilson 95 % [{lo:.3}, {hi:.3}]), now {}/{n}",
            self.identical(),
            self.solved_committed(),
            self.solved_now()
        ));
        s
    }

    /// The verdict `pbcs exp check` ends with: `MATCH`, or different bytes inside the
    /// committed interval (an error with `exact`), preceded by the kernel note where it
    /// explains a difference; an error when the fresh success rate lies outside the interval.
    pub fn verdict(&self, cell: CellKey, exact: bool) -> crate::error::Result<String> {
        let reproduced = self.reproduced();
        let mut s = match (reproduced == Reproduced::Match, self.kernel_note()) {
            (false, Some(note)) => format!("note: {note}\n"),
            _ => String::new(),
        };
        let (n, differ) = (self.n(), self.n() - self.identical());
        let ((lo, hi), rate) = (self.interval(), self.solved_now() as f64 / n as f64);
        let fail = |why: String| {
            Err(crate::error::Error::NotReproduced {
                cell: cell.to_string(),
                message: format!("{s}{why}"),
            })
        };
        match reproduced {
            Reproduced::Match => s.push_str("MATCH: the committed rows are reproduced exactly"),
            Reproduced::WithinInterval if exact => {
                let which: Vec<String> = self
                    .seeds
                    .iter()
                    .filter(|c| !c.identical)
                    .map(|c| format!("seed {}: {}", c.seed, c.differing.join(", ")))
                    .collect();
                return fail(format!(
                    "--exact: {differ} of {n} rows differ from the committed bytes ({})",
                    which.join("; ")
                ));
            }
            Reproduced::WithinInterval => s.push_str(&format!(
                "DIFFERENT BYTES, but the new success rate {rate:.2} lies inside the committed \
                 interval"
            )),
            Reproduced::Outside => {
                return fail(format!(
                    "the new success rate {rate:.2} lies outside the committed interval \
                     [{lo:.3}, {hi:.3}]"
                ))
            }
        }
        Ok(s)
    }
}
/// Re-runs `cell` of `exp` (every seed, or `seed`) into a scratch folder, `jobs` at a time,
/// and compares with the committed rows under `results`. A missing committed row is an error
/// naming the folder. The re-runs' learners run on `kernel`. `on_event` is called as the
/// sweep goes.
pub fn check_cell(
    exp: &Experiment,
    results: &Path,
    cell: CellKey,
    seed: Option<u64>,
    jobs: usize,
    kernel: Kernel,
    on_event: impl Fn(&Pending, &Event) + Sync,
) -> Result<CellCheck> {
    crate::pipeline::existing_results(results)?;
    let runs = plan(exp, Some(cell), seed)?;
    let c = exp.cell_at(cell)?;
    let committed_dir = exp.cell_dir(results, c);
    let mut committed = Vec::new();
    for p in &runs {
        match read_finished(exp, p.cell, p.seed, &committed_dir)? {
            Some(r) => committed.push(r),
            None => {
                return Err(Error::invalid(
                    "cell",
                    format!(
                        "no committed row for cell {cell} seed {} in {}",
                        p.seed,
                        committed_dir.display()
                    ),
                ))
            }
        }
    }
    let scratch = tempfile::tempdir().map_err(|e| Error::io(std::env::temp_dir(), e))?;
    let fresh = sweep(exp, &runs, scratch.path(), jobs, kernel, on_event)?;
    let fresh_dir = exp.cell_dir(scratch.path(), c);
    let read = |p: &Path| std::fs::read(p).map_err(|e| Error::io(p, e));
    let mut seeds = Vec::new();
    let mut committed_kernels = Vec::new();
    for (p, (old, new)) in runs.iter().zip(committed.into_iter().zip(fresh)) {
        let (was, is) = (
            read(&run_file(&committed_dir, p.seed, ".csv"))?,
            read(&run_file(&fresh_dir, p.seed, ".csv"))?,
        );
        let identical = was == is;
        let differing = if identical {
            Vec::new()
        } else {
            differing_columns(&was, &is)
        };
        let timing = Timing::read(&run_file(&committed_dir, p.seed, ".timing.toml"))
            .ok()
            .flatten();
        committed_kernels
            .push(timing.map_or_else(|| "matrixmultiply".into(), |t| t.kernel_name().to_string()));
        seeds.push(SeedCheck {
            seed: p.seed,
            identical,
            differing,
            committed: old,
            fresh: new,
        });
    }
    committed_kernels.sort();
    committed_kernels.dedup();
    Ok(CellCheck {
        cell,
        seeds,
        committed_kernels,
        kernel: kernel.name().to_string(),
    })
}

/// The columns where two raw row files differ, each `column: committed → fresh` in the
/// header's order; `header` when the headers differ; `bytes` when every value reads the same
/// (line endings, quoting).
pub fn differing_columns(committed: &[u8], fresh: &[u8]) -> Vec<String> {
    let records = |bytes: &[u8]| {
        let mut r = csv::Reader::from_reader(bytes);
        let header = r.headers().ok().cloned().unwrap_or_default();
        let rows: Vec<csv::StringRecord> = r.records().filter_map(|x| x.ok()).collect();
        (header, rows)
    };
    let ((h1, r1), (h2, r2)) = (records(committed), records(fresh));
    if h1 != h2 {
        return vec!["header".into()];
    }
    let empty = csv::StringRecord::new();
    let (a, b) = (r1.first().unwrap_or(&empty), r2.first().unwrap_or(&empty));
    let mut out: Vec<String> = h1
        .iter()
        .enumerate()
        .filter_map(|(i, name)| {
            let (x, y) = (a.get(i).unwrap_or(""), b.get(i).unwrap_or(""));
            (x != y).then(|| format!("{name}: {x} → {y}"))
        })
        .collect();
    if r1.len() != r2.len() {
        out.push(format!("records: {} → {}", r1.len(), r2.len()));
    }
    if out.is_empty() {
        out.push("bytes".into());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_difference_is_named_by_its_columns() {
        let head = "cell,seed,skills,env_steps\n";
        let was = format!("{head}pbcs-maze2,0,2,160484\n");
        let is = format!("{head}pbcs-maze2,0,3,170000\n");
        assert_eq!(
            differing_columns(was.as_bytes(), is.as_bytes()),
            ["skills: 2 → 3", "env_steps: 160484 → 170000"]
        );
        let crlf = was.replace('\n', "\r\n");
        assert_eq!(
            differing_columns(was.as_bytes(), crlf.as_bytes()),
            ["bytes"]
        );
        let other = "cell,seed,skills\npbcs-maze2,0,2\n";
        assert_eq!(
            differing_columns(was.as_bytes(), other.as_bytes()),
            ["header"]
        );
    }

    fn row(solved: bool) -> RawRow {
        let csv = format!(
            "experiment,cell,method,kind,maze,maze_seed,seed,learner,gamma,chaining,starts,solved,\
             success_rate,env_steps,budget,first_success_steps,phase1_steps,train_steps,\
             test_steps,skills,failure\n\
             table,pbcs-maze2,pbcs,pbcs,2,0,0,ddpg,0.9,true,ball,{solved},1.0,1,400000,,1,0,0,1,\n"
        );
        csv::Reader::from_reader(csv.as_bytes())
            .deserialize()
            .next()
            .unwrap()
            .unwrap()
    }

    /// `solved` committed / fresh per seed, and whether the bytes matched.
    fn check(seeds: &[(bool, bool, bool)], committed: &[&str], now: &str) -> CellCheck {
        CellCheck {
            cell: "pbcs-maze2".parse().unwrap(),
            seeds: seeds
                .iter()
                .enumerate()
                .map(|(i, &(identical, old, new))| SeedCheck {
                    seed: i as u64,
                    identical,
                    differing: Vec::new(),
                    committed: row(old),
                    fresh: row(new),
                })
                .collect(),
            committed_kernels: committed.iter().map(|s| s.to_string()).collect(),
            kernel: now.into(),
        }
    }

    #[test]
    fn verdicts_follow_bytes_then_the_wilson_interval() {
        let all = |x: (bool, bool, bool)| vec![x; 10];
        assert_eq!(
            check(&all((true, true, true)), &["avx2"], "avx2").reproduced(),
            Reproduced::Match
        );
        // 10/10 committed: Wilson 95 % [0.72, 1]; 8/10 now lies inside, 5/10 outside.
        let mut s = all((false, true, true));
        for x in &mut s[..2] {
            x.2 = false;
        }
        assert_eq!(
            check(&s, &["avx2"], "avx2").reproduced(),
            Reproduced::WithinInterval
        );
        for x in &mut s[..5] {
            x.2 = false;
        }
        assert_eq!(
            check(&s, &["avx2"], "avx2").reproduced(),
            Reproduced::Outside
        );
    }

    #[test]
    fn a_kernel_difference_is_explained_unless_the_kernels_agree() {
        let s = [(false, true, true)];
        assert!(check(&s, &["avx512"], "avx2").kernel_note().is_none());
        let note = check(&s, &["matrixmultiply"], "avx2")
            .kernel_note()
            .unwrap();
        assert!(note.contains("PBCS_KERNEL=matrixmultiply"), "{note}");
    }
}
