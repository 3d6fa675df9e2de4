//! Launching an experiment's runs outside `pbcs exp run`'s own threads: one command line per
//! (cell, seed), a makefile for `make -j`, or a SLURM job array. Every form runs the same
//! deterministic `pbcs exp run FILE --cell C --seed S --jobs 1` into the same results folder,
//! so the rows are the same bytes however the grid was launched, finished runs are skipped
//! (re-submitting resumes) and a run in progress is protected by its lock file.
//!
//! ```
//! use pbcs::experiment::Experiment;
//! use pbcs::launch::Launch;
//! use std::path::Path;
//!
//! let exp = Experiment::load(Path::new("experiments/unseen.toml"), Some("smoke")).unwrap();
//! let launch = Launch::new(&exp, Path::new("experiments/unseen.toml"), Some("smoke"), None);
//! let script = launch.slurm(Path::new("results-smoke"));
//! assert!(script.contains("#SBATCH --array=0-1")); // two cells × one seed
//! ```

use crate::experiment::{Experiment, Pending};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// How to launch the runs of one experiment: the file, the profile and the results folder as
/// they appear on each command line.
pub struct Launch<'a> {
    exp: &'a Experiment,
    file: PathBuf,
    /// ` --profile P` or empty.
    profile_flag: String,
    /// ` --results DIR` or empty.
    results_flag: String,
}

impl<'a> Launch<'a> {
    /// The launch of `exp` (read from `file` under `profile`), writing into `results` (None:
    /// the default results folder of the profile).
    pub fn new(
        exp: &'a Experiment,
        file: &Path,
        profile: Option<&str>,
        results: Option<&Path>,
    ) -> Launch<'a> {
        Launch {
            exp,
            file: file.to_path_buf(),
            profile_flag: profile.map_or(String::new(), |p| format!(" --profile {}", quote(p))),
            results_flag: results.map_or(String::new(), |r| {
                format!(" --results {}", quote(&r.to_string_lossy()))
            }),
        }
    }

    /// The experiment file as a shell word.
    fn file_word(&self) -> String {
        quote(&self.file.to_string_lossy())
    }

    /// Every (cell, seed) of the grid, cell-major.
    pub fn runs(&self) -> Vec<Pending<'a>> {
        let exp = self.exp;
        exp.cells
            .iter()
            .flat_map(|cell| {
                exp.seeds_of(cell)
                    .into_iter()
                    .map(move |seed| Pending { cell, seed })
            })
            .collect()
    }

    /// The arguments after `pbcs` that run one (cell, seed).
    pub fn args(&self, p: &Pending) -> String {
        format!(
            "exp run {}{}{} --cell {} --seed {} --jobs 1",
            self.file_word(),
            self.profile_flag,
            self.results_flag,
            p.cell.id,
            p.seed
        )
    }

    /// One `pbcs exp run` command per (cell, seed), with `  # done` after those whose raw row
    /// is in `results`, and `  # saved at N env steps` after runs in progress whose
    /// checkpoint is there (`# its checkpoint would be refused` where it is another job's or
    /// format's) (`pbcs exp list`).
    pub fn commands(&self, results: &Path) -> crate::Result<String> {
        let mut out = String::new();
        for p in self.runs() {
            let dir = self.exp.cell_dir(results, p.cell);
            let done = crate::experiment::read_finished(self.exp, p.cell, p.seed, &dir)?.is_some();
            let note = if done {
                "  # done".to_string()
            } else {
                match crate::experiment::checkpoint(p.cell, p.seed, &dir).peek() {
                    Ok(None) => String::new(),
                    Ok(Some(saved)) => format!("  # saved at {} env steps", saved.steps),
                    Err(_) => "  # its checkpoint would be refused".to_string(),
                }
            };
            out.push_str(&format!("pbcs {}{note}\n", self.args(&p)));
        }
        Ok(out)
    }

    /// A makefile with one rule per (cell, seed) whose target is the run's raw row in
    /// `results`: `make -f runs.mk -j N` runs N at a time and skips finished runs. A results
    /// folder whose path make cannot name as a target (a space, `#`, `:`, `%`, `$`, …) is
    /// refused naming it; the commands' words are quoted for the shell and `$` doubled for make.
    pub fn makefile(&self, results: &Path) -> crate::Result<String> {
        let runs = self.runs();
        let target = |p: &Pending| {
            crate::experiment::run_file(&self.exp.cell_dir(results, p.cell), p.seed, ".csv")
        };
        let plain = |c: char| c.is_ascii_alphanumeric() || "/._-+=,@~".contains(c);
        for p in [results, &self.file] {
            if !p.to_string_lossy().chars().all(plain) {
                return Err(crate::Error::invalid(
                    "--make",
                    format!(
                        "make cannot name a target in {} (a space or one of #:%$\\ and the \
                         like); use --slurm or the plain commands, or a plainer path",
                        p.display()
                    ),
                ));
            }
        }
        let mut out = format!(
            "# generated by `pbcs exp list --make {}`\nPBCS ?= target/release/pbcs\n",
            self.file.display()
        );
        let _ = writeln!(
            out,
            ".PHONY: all\nall:{}",
            runs.iter()
                .map(|p| format!(" \\\n  {}", target(p).display()))
                .collect::<String>()
        );
        for p in &runs {
            let _ = writeln!(
                out,
                "{}:\n\t$(PBCS) {} >/dev/null",
                target(p).display(),
                self.args(p).replace('$', "$$")
            );
        }
        Ok(out)
    }

    /// A SLURM batch script: one array task per (cell, seed), each running one run into
    /// `results` (the same files `pbcs exp run` writes), submitted from the repository root
    /// with `sbatch FILE` (add `--time`, `--partition`, … on the command line, or `%N` to the
    /// array to run at most N at once).
    pub fn slurm(&self, results: &Path) -> String {
        let runs = self.runs();
        // A comment ends at a newline: one in a path (quoted in the commands) would start a
        // line of the script there, so the comment shows each control character as `?`.
        let comment = |text: String| text.replace(|c: char| c.is_control(), "?");
        let flags = format!(
            "{}{}{}",
            self.file_word(),
            self.profile_flag,
            self.results_flag
        );
        let tasks: String = runs
            .iter()
            .map(|p| format!("  \"{} {}\"\n", p.cell.id, p.seed))
            .collect();
        let fields = [
            ("list_flags", comment(flags.clone())),
            ("results", comment(results.display().to_string())),
            ("name", self.exp.name.to_string()),
            ("count", runs.len().to_string()),
            ("last", runs.len().saturating_sub(1).to_string()),
            ("tasks", tasks),
            ("flags", flags),
        ];
        fill(SLURM_SCRIPT, &fields)
    }
}

/// The SLURM batch script of [`Launch::slurm`]: `{name}` the experiment, `{count}` its runs
/// (`{last}` the last task's index, `{tasks}` one `"<cell> <seed>"` line each), `{flags}` the
/// experiment file, profile and results flags (`{list_flags}` and `{results}` as a comment shows
/// them).
const SLURM_SCRIPT: &str = r#"#!/bin/bash
# generated by `pbcs exp list --slurm {list_flags}`: one array task per (cell, seed) of
# experiment `{name}` ({count} runs, results in {results}). Submit from the repository root with
# `sbatch FILE`; re-submitting skips finished runs, so it resumes.
#SBATCH --job-name=pbcs-{name}
#SBATCH --array=0-{last}
#SBATCH --ntasks=1
#SBATCH --cpus-per-task=1
#SBATCH --output=slurm-%A_%a.out
set -euo pipefail
# The binary: build it once with `cargo build --release` (or set PBCS).
PBCS="${PBCS:-target/release/pbcs}"
runs=(
{tasks})
read -r cell seed <<< "${runs[$SLURM_ARRAY_TASK_ID]}"
# With PBCS_STOP_AFTER (`sbatch --time=4:00:00 --export=ALL,PBCS_STOP_AFTER=3h50m`), a
# vanilla run stops before the time limit, saved, exit status 75; re-submit to go on.
exec "$PBCS" exp run {flags} --cell "$cell" --seed "$seed" --jobs 1 ${PBCS_STOP_AFTER:+--stop-after "$PBCS_STOP_AFTER"}
"#;

/// `template` with each `{key}` of `fields` replaced by its value, in one pass (a value holding
/// `{key}` stays as it is); any other `{` is kept.
fn fill(template: &str, fields: &[(&str, String)]) -> String {
    let mut out = String::with_capacity(template.len());
    let mut rest = template;
    while let Some(i) = rest.find('{') {
        out.push_str(&rest[..i]);
        rest = &rest[i..];
        let field = fields.iter().find(|(k, _)| {
            rest[1..]
                .strip_prefix(k)
                .is_some_and(|r| r.starts_with('}'))
        });
        match field {
            Some((k, v)) => {
                out.push_str(v);
                rest = &rest[k.len() + 2..];
            }
            None => {
                out.push('{');
                rest = &rest[1..];
            }
        }
    }
    out.push_str(rest);
    out
}

/// `word` as one POSIX shell word: unchanged when it needs no quoting, else single-quoted
/// (`shlex`); a NUL byte, which no shell word holds, becomes a space.
fn quote(word: &str) -> String {
    let word = word.replace('\0', " ");
    shlex::try_quote(&word).map_or(word.clone(), |q| q.into_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn launch<'a>(exp: &'a Experiment, results: &Path) -> Launch<'a> {
        Launch::new(
            exp,
            Path::new("experiments/unseen.toml"),
            Some("smoke"),
            Some(results),
        )
    }

    fn exp() -> Experiment {
        Experiment::load(Path::new("experiments/unseen.toml"), Some("smoke")).unwrap()
    }

    #[test]
    fn a_results_folder_with_a_space_or_a_command_stays_one_shell_word() {
        let exp = exp();
        for results in ["r space", "r;touch x", "r$(touch x)", "it's"] {
            let l = launch(&exp, Path::new(results));
            let script = l.slurm(Path::new(results));
            let exec = script.lines().find(|l| l.starts_with("exec ")).unwrap();
            let words = shlex::split(exec).unwrap();
            let i = words.iter().position(|w| w == "--results").unwrap();
            assert_eq!(words[i + 1], results, "{exec}");
            let commands = l.commands(Path::new(results)).unwrap();
            let words = shlex::split(commands.lines().next().unwrap()).unwrap();
            let i = words.iter().position(|w| w == "--results").unwrap();
            assert_eq!(words[i + 1], results, "{commands}");
        }
    }

    /// A newline in a path (the re-probe's `r\ntouch x #`) stays inside the comment: every
    /// line of the header is a comment, and the exec line still holds the path as one word.
    #[test]
    fn a_newline_in_a_path_does_not_end_the_scripts_comment() {
        let exp = exp();
        let results = "r\ntouch x #";
        let script = launch(&exp, Path::new(results)).slurm(Path::new(results));
        let header = script.lines().take_while(|l| !l.starts_with("#SBATCH"));
        for line in header {
            assert!(line.starts_with('#'), "{line:?} in\n{script}");
        }
        let exec = &script[script.find("exec ").unwrap()..];
        let words = shlex::split(exec.trim_end()).unwrap();
        let i = words.iter().position(|w| w == "--results").unwrap();
        assert_eq!(words[i + 1], results);
    }

    /// The script is filled in one pass: a path holding a placeholder's name stays as it is.
    #[test]
    fn a_path_holding_a_placeholder_stays_as_it_is() {
        let exp = exp();
        let results = "r{name}{tasks}";
        let script = launch(&exp, Path::new(results)).slurm(Path::new(results));
        assert!(script.contains("results in r{name}{tasks})"), "{script}");
        assert_eq!(script.matches("r{name}{tasks}").count(), 3, "{script}");
    }

    #[test]
    fn a_makefile_refuses_a_path_make_cannot_name() {
        let exp = exp();
        for results in ["r space", "r;x", "r:x", "r$x", "r#x"] {
            let e = launch(&exp, Path::new(results))
                .makefile(Path::new(results))
                .unwrap_err()
                .to_string();
            assert!(e.contains("--make") && e.contains(results), "{e}");
        }
        let mk = launch(&exp, Path::new("results-smoke"))
            .makefile(Path::new("results-smoke"))
            .unwrap();
        assert!(mk.contains("--results results-smoke"), "{mk}");
    }
}
