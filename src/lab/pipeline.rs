//! The one-way pipeline after the runs: raw rows → [`aggregate`] → `results/tables/*`
//! ([`write_tables`], the one writer of that folder) → [`render`]: figures and the report's
//! LaTeX, which read the tables only (and the per-run picture data they draw).
//!
//! `pbcs aggregate` and `pbcs figures` (`make figures`) are thin calls of [`aggregate`] and
//! [`render`]; the default folders live here so that the CLI, the Makefile and a script agree.

use crate::claims::Claim;
use crate::error::Result;
use crate::experiment::{experiment_files, Experiment, ExperimentName, FigureSpec, RawRow};
use crate::record::{write_atomic, write_records};
use crate::report;
use crate::tables::curves::curves_path;
use crate::tables::routes::routes_path;
use crate::tables::scaling::{paths_path, read_paths_and_fit, scaling_fit_path};
use crate::tables::CellStats;
use std::path::{Path, PathBuf};

/// The results folder: `results` if given, else `results` for the committed grid and
/// `results-<profile>` for a profile (so a smoke run never mixes with the committed rows).
pub fn results_dir(results: Option<&Path>, profile: Option<&str>) -> PathBuf {
    results
        .map(Path::to_path_buf)
        .unwrap_or_else(|| match profile {
            None => PathBuf::from("results"),
            Some(p) => PathBuf::from(format!("results-{p}")),
        })
}

/// The folder of the generated LaTeX: `tex` if given, else `paper/generated` for the
/// committed grid in its own folder (no profile, `results` the default results folder), and
/// `<results>/tex` for anything else (a profile, or another results folder): the report's
/// committed LaTeX is written from the committed results only.
pub fn tex_dir(tex: Option<&Path>, profile: Option<&str>, results: &Path) -> PathBuf {
    match (tex, profile) {
        (Some(tex), _) => tex.to_path_buf(),
        (None, None) if same_folder(results, &results_dir(None, None)) => {
            PathBuf::from("paper/generated")
        }
        _ => results.join("tex"),
    }
}

/// Whether `a` and `b` name one folder (the same path, or the same folder once resolved).
fn same_folder(a: &Path, b: &Path) -> bool {
    a == b || matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
}

/// Refuses a results folder that does not exist (or is not a folder), naming it: `aggregate`
/// `figures` and `exp check` read what is there and never invent an empty result.
pub fn existing_results(results: &Path) -> Result<()> {
    let why = if !results.exists() {
        "no such results folder"
    } else if !results.is_dir() {
        "is not a folder"
    } else {
        return Ok(());
    };
    Err(crate::Error::io(
        results,
        std::io::Error::other(format!(
            "{why}: give the folder that holds the runs (--results; `pbcs exp run` writes \
             their rows into <results>/raw/)"
        )),
    ))
}

/// Every experiment's finished raw rows under `results` ([`crate::experiment::read_raw`]),
/// refusing a results folder that does not exist or holds no row of any experiment.
fn read_all_raw(exps: &[Experiment], results: &Path) -> Result<Vec<Vec<RawRow>>> {
    existing_results(results)?;
    let rows = exps
        .iter()
        .map(|exp| crate::experiment::read_raw(exp, results))
        .collect::<Result<Vec<_>>>()?;
    if rows.iter().all(Vec::is_empty) {
        let names: Vec<&str> = exps.iter().map(|e| e.name.as_str()).collect();
        return Err(crate::Error::io(
            results,
            std::io::Error::other(format!(
                "holds no raw row of any experiment ({}: <results>/raw/<experiment>/<cell>/\
                 s<seed>.csv, written by `pbcs exp run`): nothing to aggregate; give the folder \
                 that holds them (--results, and --profile for a profile's runs)",
                names.join(", ")
            )),
        ));
    }
    Ok(rows)
}

/// Every experiment file of the folder `dir` ([`experiment_files`]), resolved under `profile`.
pub fn load_experiments(dir: &Path, profile: Option<&str>) -> Result<Vec<Experiment>> {
    experiment_files(dir)?
        .iter()
        .map(|f| Experiment::load(f, profile))
        .collect()
}

/// What [`aggregate`] did for one experiment.
#[derive(Debug, Clone, PartialEq)]
pub struct Aggregated {
    /// Experiment name.
    pub experiment: ExperimentName,
    /// Finished runs read (0: none, nothing written).
    pub runs: usize,
    /// Runs of the full grid (cells × seeds).
    pub expected: u64,
    /// Cells with runs.
    pub cells: usize,
    /// The main table written.
    pub table: PathBuf,
}

impl std::fmt::Display for Aggregated {
    /// What `pbcs aggregate` prints for the experiment: its runs and cells and the table
    /// written, or that it had no rows.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.runs {
            0 => write!(f, "{}: no raw rows, skipped", self.experiment),
            n => write!(
                f,
                "{}: {n} of {} runs in {} cells → {} (polars; checked against the plain \
                 computation)",
                self.experiment,
                self.expected,
                self.cells,
                self.table.display()
            ),
        }
    }
}

/// Aggregates every experiment's raw rows under `results` with polars
/// ([`crate::aggregate::aggregate`], checked against the plain computation) and writes its
/// tables ([`write_tables`]); an experiment without rows is reported and skipped. A build
/// without the `polars` feature says so.
#[cfg(not(feature = "polars"))]
pub fn aggregate(exps: &[Experiment], results: &Path) -> Result<Vec<Aggregated>> {
    read_all_raw(exps, results)?;
    Err(crate::Error::invalid(
        "features",
        "this build has no polars: build with `--features polars` (as `make figures` does), \
         or use the committed tables in results/tables/",
    ))
}

/// Aggregates every experiment's raw rows under `results` with polars
/// ([`crate::aggregate::aggregate`], checked against the plain computation) and writes its
/// tables ([`write_tables`]); an experiment without rows is reported and skipped. A results
/// folder that does not exist or holds no row of any experiment is refused before anything is
/// written.
#[cfg(feature = "polars")]
pub fn aggregate(exps: &[Experiment], results: &Path) -> Result<Vec<Aggregated>> {
    let mut out = Vec::new();
    let all = read_all_raw(exps, results)?;
    for (exp, rows) in exps.iter().zip(&all) {
        let baseline_rows = paired_baseline_rows(exp, exps, &all)?.unwrap_or(rows);
        let table = crate::tables::table_path(results, exp.name);
        let mut done = Aggregated {
            experiment: exp.name,
            runs: rows.len(),
            expected: exp.run_count(),
            cells: 0,
            table,
        };
        if !rows.is_empty() {
            let stats = crate::aggregate::aggregate(exp, rows)?;
            write_tables(exp, results, &stats, rows, baseline_rows)?;
            done.cells = stats.len();
        }
        out.push(done);
    }
    Ok(out)
}

/// The rows of the experiment whose method is `exp`'s registered paired baseline, where its
/// `baseline_from` names another experiment (`rows[i]` being `exps[i]`'s); an error when that
/// experiment is not among `exps` or does not declare the method.
#[cfg(feature = "polars")]
fn paired_baseline_rows<'a>(
    exp: &Experiment,
    exps: &[Experiment],
    rows: &'a [Vec<RawRow>],
) -> Result<Option<&'a [RawRow]>> {
    let Some(reg) = exp.registered.as_ref() else {
        return Ok(None);
    };
    let (Some(from), Some([baseline, _])) = (reg.baseline_from, reg.paired) else {
        return Ok(None);
    };
    let field = format!("registered.baseline_from of {}", exp.name);
    let Some(i) = exps.iter().position(|e| e.name == from) else {
        return Err(crate::Error::invalid(
            field,
            format!("`{from}` is not an experiment of the folder"),
        ));
    };
    if !exps[i].methods.iter().any(|(m, _)| *m == baseline) {
        return Err(crate::Error::invalid(
            field,
            format!("`{from}` has no method `{baseline}`, the registered baseline"),
        ));
    }
    Ok(Some(&rows[i]))
}

/// What [`render`] read and wrote.
#[derive(Debug, Clone)]
pub struct Rendered {
    /// Each experiment with a table, and its table.
    pub tables: Vec<(Experiment, Vec<CellStats>)>,
    /// Experiments without a table (name, the missing path): skipped.
    pub skipped: Vec<(ExperimentName, PathBuf)>,
    /// The paper's claims judged against the tables.
    pub claims: Vec<Claim>,
    /// Under a profile, the claims its smaller grid cannot judge (why, per claim); empty for
    /// the committed grids, where such a claim is an error.
    pub unjudged: Vec<String>,
    /// Every file written.
    pub files: Vec<PathBuf>,
}

impl Rendered {
    /// What `pbcs figures` prints: the claims a profile cannot judge, the experiments skipped,
    /// each table as Markdown, the claims' verdicts and the count of files written.
    pub fn summary(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        for why in &self.unjudged {
            let _ = writeln!(s, "{why} (not judged under this profile)");
        }
        for (name, path) in &self.skipped {
            let _ = writeln!(s, "{name}: no table at {}, skipped", path.display());
        }
        for (exp, stats) in &self.tables {
            let table = crate::tables::markdown(stats);
            let _ = write!(s, "\n{} — {}\n{table}", exp.name, exp.title);
        }
        s.push_str("\nthe paper's claims against our tables:\n");
        for c in &self.claims {
            let verdict = c.verdict.word().to_uppercase();
            let _ = writeln!(s, "- {} — {verdict}: {}", c.id, c.ours);
        }
        let _ = write!(s, "\nwrote {} files", self.files.len());
        s
    }
}

/// Reads each experiment's table under `results`, judges the claims of `claims_file` against
/// them, draws every declared figure into `figures` and writes the report's LaTeX into `tex`.
/// The claims file is read first: a bad one stops before any work; so does a results folder
/// that does not exist or holds no table of any experiment (nothing is written).
pub fn render(
    exps: Vec<Experiment>,
    claims_file: &Path,
    results: &Path,
    figures: &Path,
    tex: &Path,
) -> Result<Rendered> {
    let specs = crate::claims::load_claims(claims_file)?;
    existing_results(results)?;
    let mut tables = Vec::new();
    let mut skipped = Vec::new();
    for exp in exps {
        let path = crate::tables::table_path(results, exp.name);
        if path.exists() {
            let stats = crate::tables::read_table(&path)?;
            crate::tables::check_against_rows(&exp, results, &stats)?;
            tables.push((exp, stats));
        } else {
            skipped.push((exp.name, path));
        }
    }
    if tables.is_empty() {
        return Err(crate::Error::io(
            results,
            std::io::Error::other(format!(
                "holds no table of any experiment (<results>/tables/<experiment>.csv: {}): \
                 nothing to draw; run `pbcs aggregate` on it first, or give the folder that \
                 holds the tables (--results)",
                skipped
                    .iter()
                    .map(|(name, _)| name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
        ));
    }
    let named: Vec<(ExperimentName, Vec<CellStats>)> =
        tables.iter().map(|(e, s)| (e.name, s.clone())).collect();
    // The committed grids judge every claim (one that cannot be judged is an error); a
    // profile's smaller grid judges those it can.
    let (claims, unjudged) = if tables.iter().any(|(e, _)| e.profile.is_some()) {
        let (judged, errors) = crate::claims::claims_partial(&specs, &named);
        (judged, errors.iter().map(ToString::to_string).collect())
    } else {
        (crate::claims::claims(&specs, &named)?, Vec::new())
    };
    // Every figure and LaTeX file is drawn first and then moved into place: a failure while
    // drawing (a missing picture file, say) leaves both folders' files as they were.
    let files = crate::record::write_all_or_none([figures, tex], |[figures, tex]| {
        let mut files = render_all(&tables, &claims, results, figures, tex)?;
        files.extend(render_settings(
            claims_file.parent().unwrap_or(Path::new(".")),
            tex,
        )?);
        Ok(files)
    })?;
    remove_stale(&[figures, tex], &files)?;
    Ok(Rendered {
        tables,
        skipped,
        claims,
        unjudged,
        files,
    })
}

/// What `figures` made before and no longer makes goes (an output a step no longer makes is
/// removed by that step): in each folder, every figure or LaTeX file (`.png`, `.svg`, `.tex`)
/// that is not one of `written`, and a staging folder (`.writing-*`) a killed run left.
fn remove_stale(dirs: &[&Path], written: &[PathBuf]) -> Result<()> {
    for dir in dirs {
        for entry in std::fs::read_dir(dir).map_err(|e| crate::Error::io(dir, e))? {
            let path = entry.map_err(|e| crate::Error::io(dir, e))?.path();
            let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
            let drawn = path
                .extension()
                .is_some_and(|e| ["png", "svg", "tex"].iter().any(|x| e == *x));
            let gone = if path.is_dir() {
                name.is_some_and(|n| n.starts_with(".writing-"))
                    && std::fs::remove_dir_all(&path).is_ok()
            } else {
                drawn && !written.contains(&path) && std::fs::remove_file(&path).is_ok()
            };
            if gone {
                eprintln!("removed {}, which figures no longer makes", path.display());
            }
        }
    }
    Ok(())
}

/// Writes every table of an experiment under `<results>/tables/` (the one writer of that
/// folder): `<name>.csv` (`stats`), `<name>.chains.csv` and `<name>.criteria.csv` (PBCS runs'
/// chain success and the table under other success criteria), `<name>.curves.csv` (with a
/// curves figure: the vanilla learning curves), `<name>.paths.csv` and
/// `<name>.scaling_fit.csv` (with a scaling figure: each cell's shortest path, and the power
/// law fitted through the cells' medians), `<name>.routes.csv` (PBCS runs with evaluation
/// episodes: the chain's path beside |τ| and the fewest steps) and `<name>.route_cells.csv`
/// (their medians per cell, what the report quotes), `<name>.judged.csv` (chains judged by an
/// outside environment), `<name>.paired.csv` (a registered paired comparison),
/// `<name>.phases.csv` (PBCS cells: env steps by phase) and the wall-clock companion
/// `<name>.timing.csv`.
pub fn write_tables(
    exp: &Experiment,
    results: &Path,
    stats: &[CellStats],
    rows: &[RawRow],
    baseline_rows: &[RawRow],
) -> Result<()> {
    crate::tables::write_table(&crate::tables::table_path(results, exp.name), stats)?;
    let chains = crate::criteria::chain_successes(exp, rows);
    if !chains.is_empty() {
        write_records(&crate::criteria::chains_path(results, exp.name), &chains)?;
        write_records(
            &crate::criteria::criteria_path(results, exp.name),
            &crate::criteria::criteria(&chains),
        )?;
    }
    for figure in &exp.figures {
        match figure {
            FigureSpec::Curves { .. } => {
                let points = crate::tables::curves::curve_points(exp, results)?;
                write_records(&curves_path(results, exp.name), &points)?;
            }
            FigureSpec::Scaling { .. } => {
                let paths = crate::tables::scaling::path_lengths(exp)?;
                write_records(&paths_path(results, exp.name), &paths)?;
                let fit = crate::tables::scaling::ScalingFit::of(exp, stats, &paths);
                write_records(&scaling_fit_path(results, exp.name), &[fit])?;
            }
            _ => {}
        }
    }
    let name = exp.name;
    let routes = crate::tables::routes::routes(exp, results, rows)?;
    write_nonempty(&routes_path(results, name), &routes)?;
    let route_cells = crate::tables::routes::route_cells(&routes);
    write_nonempty(
        &crate::tables::routes::route_cells_path(results, name),
        &route_cells,
    )?;
    if !routes.is_empty() {
        let spread = crate::tables::routes::route_spread(&route_cells);
        write_records(
            &crate::tables::routes::route_spread_path(results, name),
            &[spread],
        )?;
    }
    let judged = crate::tables::judged::judged_cells(exp, results, rows)?;
    write_nonempty(&crate::tables::judged::judged_path(results, name), &judged)?;
    let paired = crate::tables::paired::paired_sites(exp, rows, baseline_rows);
    write_nonempty(&crate::tables::paired::paired_path(results, name), &paired)?;
    let phases = crate::tables::phases::cell_phases(exp, rows);
    write_nonempty(&crate::tables::phases::phases_path(results, name), &phases)?;
    let timing = crate::tables::cell_timings(exp, results, rows);
    write_records(
        &results
            .join("tables")
            .join(format!("{}.timing.csv", exp.name)),
        &timing,
    )
}

/// Writes `rows` to `path` where there are any (a table with no row is not written).
fn write_nonempty<T: serde::Serialize>(path: &Path, rows: &[T]) -> Result<()> {
    if rows.is_empty() {
        return Ok(());
    }
    write_records(path, rows)
}

/// Renders every figure of every experiment into `figures` and writes the report's generated
/// LaTeX into `tex`: `numbers.tex`, `<experiment>_cells.tex`, `table.tex` (the results table)
/// and `claims.tex`. Returns every file written.
pub fn render_all(
    experiments: &[(Experiment, Vec<CellStats>)],
    claims: &[Claim],
    results: &Path,
    figures: &Path,
    tex_dir: &Path,
) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for (exp, stats) in experiments {
        files.extend(crate::figures::render_experiment(
            exp, results, stats, figures,
        )?);
        let path = tex_dir.join(format!("{}_cells.tex", exp.name));
        let text = report::cells_table_tex(stats);
        write_atomic(&path, |w| w.write_all(text.as_bytes()))?;
        files.push(path);
        let criteria = crate::criteria::criteria_path(results, exp.name);
        if criteria.exists() {
            let criteria = crate::criteria::read_criteria(&criteria)?;
            let path = tex_dir.join(format!("{}_criteria.tex", exp.name));
            let text = report::criteria_tex(&criteria);
            write_atomic(&path, |w| w.write_all(text.as_bytes()))?;
            files.push(path);
        }
        let mut extra = Vec::new();
        if exp.report.results_table {
            extra.push((
                "table.tex",
                report::results_table_tex(stats, &exp.sites, &exp.methods),
            ));
        }
        if let Some(settings) = &exp.report.settings {
            extra.push(("settings.tex", report::settings_tex(exp, settings)));
        }
        for (name, text) in extra {
            let path = tex_dir.join(name);
            write_atomic(&path, |w| w.write_all(text.as_bytes()))?;
            files.push(path);
        }
    }
    let tables: Vec<(ExperimentName, Vec<CellStats>)> = experiments
        .iter()
        .map(|(e, s)| (e.name, s.clone()))
        .collect();
    let mut numbers = report::numbers_tex(&tables);
    for (exp, _) in experiments {
        if paths_path(results, exp.name).exists() {
            let (paths, fit) = read_paths_and_fit(results, exp.name)?;
            numbers.push_str(&report::scaling_numbers_tex(exp, &paths, &fit));
        }
        let spread = crate::tables::routes::route_spread_path(results, exp.name);
        crate::tables::summary_beside(
            &crate::tables::routes::routes_path(results, exp.name),
            &spread,
        )?;
        if spread.exists() {
            let spread: crate::tables::routes::RouteSpread =
                crate::record::read_one_record(&spread)?;
            numbers.push_str(&report::routes_numbers_tex(exp.name, &spread));
        }
        numbers.push_str(&report::extra_numbers_tex(exp, results)?);
    }
    numbers.push_str(&render_outside(results, tex_dir, &mut files)?);
    numbers.push_str(&report::antmaze::render(results, tex_dir, &mut files)?);
    for (name, text) in [
        ("numbers.tex", numbers),
        ("claims.tex", report::claims_tex(claims)),
    ] {
        let path = tex_dir.join(name);
        write_atomic(&path, |w| w.write_all(text.as_bytes()))?;
        files.push(path);
    }
    Ok(files)
}

/// The report's settings and departures tables from the files beside the claims file
/// (`settings.toml` with the presets' values, `departures.toml`): `presets.tex` and
/// `departures.tex` into `tex_dir`.
fn render_settings(experiments: &Path, tex_dir: &Path) -> Result<Vec<PathBuf>> {
    use crate::report::settings;
    let rows = settings::load(&experiments.join("settings.toml"))?;
    let departures = settings::load_departures(&experiments.join("departures.toml"))?;
    let mut files = Vec::new();
    for (name, text) in [
        ("presets.tex", settings::presets_tex(&rows)),
        ("departures.tex", settings::departures_tex(&departures)),
    ] {
        let path = tex_dir.join(name);
        write_atomic(&path, |w| w.write_all(text.as_bytes()))?;
        files.push(path);
    }
    Ok(files)
}

/// The report's LaTeX of the outside checks from `<results>/tables/outside.*.csv` (each only
/// where its table exists; `outside.timing.csv` without `outside.cost_ratio.csv` beside it is
/// refused): `outside_maze.tex`, `outside_pendulum.tex` and `outside_pendulum_sac.tex` into
/// `tex_dir` (added to `files`), and their numbers for `numbers.tex` (returned).
fn render_outside(results: &Path, tex_dir: &Path, files: &mut Vec<PathBuf>) -> Result<String> {
    use crate::record::read_records;
    use crate::tables::outside::outside_table;
    let mut numbers = String::new();
    let mut put = |name: &str, (table, n): (String, String)| -> Result<()> {
        let path = tex_dir.join(name);
        write_atomic(&path, |w| w.write_all(table.as_bytes()))?;
        files.push(path);
        numbers.push_str(&n);
        Ok(())
    };
    let maze = outside_table(results, "maze");
    if maze.exists() {
        put(
            "outside_maze.tex",
            report::outside::outside_maze_tex(&read_records(&maze)?),
        )?;
    }
    let pendulum = outside_table(results, "pendulum");
    if pendulum.exists() {
        put(
            "outside_pendulum.tex",
            report::outside::outside_pendulum_tex(&read_records(&pendulum)?, "pendulum"),
        )?;
    }
    let pendulum_sac = outside_table(results, "pendulum_sac");
    if pendulum_sac.exists() {
        put(
            "outside_pendulum_sac.tex",
            report::outside::outside_pendulum_tex(&read_records(&pendulum_sac)?, "pendulumsac"),
        )?;
    }
    let cost = outside_table(results, "timing");
    if cost.exists() {
        let ratios = outside_table(results, "cost_ratio");
        crate::tables::summary_beside(&cost, &ratios)?;
        numbers.push_str(&report::outside::outside_cost_numbers(
            &crate::tables::outside::read_cost_ratios(&ratios)?,
        ));
    }
    let pointmaze = outside_table(results, "pointmaze");
    if pointmaze.exists() {
        numbers.push_str(&report::outside::outside_pointmaze_numbers(&read_records(
            &pointmaze,
        )?));
    }
    let against_sb3 = outside_table(results, "pointmaze_sb3");
    if against_sb3.exists() {
        numbers.push_str(&report::outside::outside_pointmaze_sb3_numbers(
            &read_records(&against_sb3)?,
        ));
    }
    Ok(numbers)
}

/// Writes the outside checks' tables (`results/tables/outside.*.csv`,
/// [`crate::tables::outside::write_outside_tables`]) from the rows under `<results>/outside/`,
/// our maze side read from the experiment of the results table (`report.results_table`).
/// Returns the files written: none without that experiment or without outside rows.
pub fn aggregate_outside(exps: &[Experiment], results: &Path) -> Result<Vec<PathBuf>> {
    match exps.iter().find(|e| e.report.results_table) {
        Some(table) if crate::tables::outside::outside_dir(results).is_dir() => {
            let names = ["pointmaze_vanilla", "pointmaze_her"].map(ExperimentName::new);
            let mut pointmaze: Vec<&Experiment> = Vec::new();
            for name in names {
                let name = name?;
                pointmaze.extend(exps.iter().find(|e| e.name == name));
            }
            crate::tables::outside::write_outside_tables(table, &pointmaze, results)
        }
        _ => Ok(Vec::new()),
    }
}
