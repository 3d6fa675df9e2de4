//! The committed rows: byte-for-byte round trips, computed from the experiment files as they
//! are, and the numbers derived from them.

use super::*;

/// The committed raw rows read and written back give the same bytes: the row's enums (kind,
/// starts, failure) keep the strings the files hold, empty where they do not apply. Every
/// enum value but two occurs in the committed rows; those two (`budget`: no run at the paper's
/// budgets ran out; `archive` starts: their rows are development rows, in `results/dev/`) are
/// written and read back here, with the others.
#[test]
fn committed_raw_rows_round_trip_byte_for_byte() {
    use pbcs::experiment::{read_row, Kind, KindRow};
    use pbcs::phase2::{Failure, StartMode};
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    let mut stack = vec![root.join("results/raw")];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for e in entries {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            if p.is_dir() {
                stack.push(p);
            } else if name.starts_with('s')
                && name.ends_with(".csv")
                && name.matches('.').count() == 1
            {
                files.push(p);
            }
        }
    }
    assert!(files.len() > 100, "{} raw rows", files.len());
    let tmp = tempfile::tempdir().unwrap();
    let mut seen = BTreeSet::new();
    for f in &files {
        let row = read_row(f).unwrap();
        let back = tmp.path().join("row.csv");
        pbcs::record::write_record(&back, &row).unwrap();
        assert_eq!(
            std::fs::read(&back).unwrap(),
            std::fs::read(f).unwrap(),
            "{}",
            f.display()
        );
        let starts = row.pbcs_row().map(|p| p.starts);
        seen.insert(format!("{:?}", row.kind()));
        seen.insert(format!("{starts:?}"));
        seen.insert(format!("{:?}", row.failure()));
    }
    for want in [
        format!("{:?}", Kind::Vanilla),
        format!("{:?}", Kind::Pbcs),
        format!("{:?}", None::<StartMode>),
        format!("{:?}", Some(StartMode::Ball)),
        format!("{:?}", Some(StartMode::Exact)),
        format!("{:?}", None::<Failure>),
        format!("{:?}", Some(Failure::NoChaining)),
        // No committed run at the paper's budgets ran out of budget (the 400k-step grids'
        // did); `Budget` round-trips below on a written row.
        format!("{:?}", Some(Failure::BackplayFailed)),
    ] {
        assert!(seen.contains(&want), "no committed row has {want}");
    }
    // A PBCS row (a failure is PBCS's only), not solved (a run with a failure never is).
    let mut row = files
        .iter()
        .map(|f| read_row(f).unwrap())
        .find(|r| r.kind() == Kind::Pbcs)
        .unwrap();
    row.solved = false;
    let KindRow::Pbcs(mut pbcs) = row.kind else {
        unreachable!("a PBCS row")
    };
    for f in [
        Failure::BackplayFailed,
        Failure::NoChaining,
        Failure::Budget,
    ] {
        pbcs.failure = Some(f);
        row.kind = KindRow::Pbcs(pbcs);
        let path = tmp.path().join("failure.csv");
        pbcs::record::write_record(&path, &row).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.trim_end().ends_with(&format!(",{}", f.name())),
            "{text}"
        );
        assert_eq!(read_row(&path).unwrap(), row);
    }
    // Consistent again: no failure, solved as its success rate says.
    pbcs.failure = None;
    row.solved = row.success_rate >= 0.95;
    for starts in [StartMode::Ball, StartMode::Exact, StartMode::Archive] {
        pbcs.starts = starts;
        row.kind = KindRow::Pbcs(pbcs);
        let path = tmp.path().join("starts.csv");
        pbcs::record::write_record(&path, &row).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let name = format!("{starts:?}").to_lowercase();
        assert!(text.contains(&format!(",{name},")), "{text}");
        assert_eq!(read_row(&path).unwrap(), row);
    }
}

/// `beyond` compares two layouts on each size: they must be two different mazes on every size.
/// Layouts 0 and 1 of the 3×3 maze are the same maze (the file once used them).
#[test]
fn the_beyond_experiment_has_two_different_layouts_on_every_size() {
    use pbcs::envs::maze::Layout;
    assert_eq!(Layout::generate(3, 0), Layout::generate(3, 1));
    let exp = Experiment::load(Path::new("experiments/beyond.toml"), None).unwrap();
    for &n in &exp.sites {
        let layouts: Vec<Layout> = exp
            .cells
            .iter()
            .filter(|c| c.site == n)
            .map(|c| {
                pbcs::tables::scaling::cell_maze(c)
                    .unwrap()
                    .layout()
                    .clone()
            })
            .collect();
        assert_eq!(layouts.len(), 2, "maze {n}");
        assert_ne!(layouts[0], layouts[1], "maze {n}");
    }
}

/// Every committed raw row was computed from its experiment file as it is now: each
/// `results/raw/<experiment>/<cell>/s<seed>.toml` is the job the file resolves for that cell
/// and seed, every folder there is a cell of the file, and every cell has all its seeds (a
/// grid `in_progress`: the seeds with rows so far). A
/// changed experiment file (a budget, a preset) without re-run rows fails here, not silently
/// in `make figures`.

#[test]
fn committed_rows_were_computed_from_the_experiment_files_as_they_are() {
    let raw = Path::new("results/raw");
    let mut checked = 0;
    for f in files() {
        let exp = Experiment::load(&f, None).unwrap();
        // Every experiment file's every (cell, seed) is committed; a grid registered
        // before its first row (`in_progress`) may have no folder yet.
        let folder = raw.join(exp.name);
        if exp.in_progress && !folder.exists() {
            continue;
        }
        let entries =
            std::fs::read_dir(&folder).unwrap_or_else(|e| panic!("{}: no rows ({e})", exp.name));
        for e in entries {
            let dir = e.unwrap().path();
            let id = dir.file_name().unwrap().to_string_lossy().into_owned();
            exp.cell(&id).unwrap_or_else(|e| {
                panic!("{}: not a cell of {}: {e}", dir.display(), f.display())
            });
        }
        for cell in &exp.cells {
            for seed in exp.seeds_of(cell) {
                let dir = exp.cell_dir(Path::new("results"), cell);
                // A grid in progress: the runs with rows so far.
                if exp.in_progress && !dir.join(format!("s{seed}.csv")).exists() {
                    continue;
                }
                let path = dir.join(format!("s{seed}.toml"));
                let text = std::fs::read_to_string(&path)
                    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                assert!(
                    cell.job.with_seed(seed).same_as(&text),
                    "{}: not the job {} resolves",
                    path.display(),
                    f.display()
                );
                if !exp.in_progress {
                    checked += 1;
                }
            }
        }
    }
    // Whole grids (a grid in progress, lookahead, adds its rows as they finish): table 250,
    // gamma 80, unseen 40, beyond 100, ablations 100, protocol 20, switches 90, heldout 56,
    // rooms 20, pointmaze 30, pointmaze_heldout 30, pointmaze_velocity 60, pointmaze_vanilla 60,
    // three_rooms 20, pointmaze_own 20, sac_skills 60, pointmaze_her 60, goal_conditioned 50,
    // pointmaze_gc 30, goal_conditioned_strict 50.
    assert_eq!(checked, 1226, "committed jobs");
}

/// The report quotes the scaling figure's fit from `numbers.tex`: on made-up medians that
/// follow steps = 500 · L^1.5 exactly on `beyond`'s cells, the generated numbers give back the
/// exponent and the factor, and every cell's path length (at least 2(N − 1) moves on N × N).
#[test]
fn the_scaling_fit_in_the_reports_numbers_recovers_a_known_power_law() {
    use pbcs::tables::{read_table, table_path};
    let exp = Experiment::load(Path::new("experiments/beyond.toml"), None).unwrap();
    let paths = pbcs::tables::scaling::path_lengths(&exp).unwrap();
    assert_eq!(paths.len(), exp.cells.len());
    let mut stats =
        read_table(&table_path(Path::new("results"), "beyond".parse().unwrap())).unwrap();
    assert_eq!(stats.len(), exp.cells.len());
    for s in &mut stats {
        let l = &paths.iter().find(|p| p.cell == s.cell).unwrap().path_cells;
        assert!(
            *l >= 2 * (s.site.size().unwrap() - 1),
            "{}: L = {l}",
            s.cell
        );
        s.steps_median = 500.0 * (*l as f64).powf(1.5);
        (s.steps_q1, s.steps_q3) = (s.steps_median, s.steps_median);
    }
    let fit = pbcs::tables::scaling::ScalingFit::of(&exp, &stats, &paths);
    assert_eq!(fit.cells, exp.cells.len() as u64);
    let tex = pbcs::report::scaling_numbers_tex(&exp, &paths, &fit);
    assert!(
        tex.contains("\\csname res:beyond:scaling:exponent\\endcsname{1.50}"),
        "{tex}"
    );
    assert!(
        tex.contains("\\csname res:beyond:scaling:factor\\endcsname{500}"),
        "{tex}"
    );
    let (cell, l) = (&paths[0].cell, paths[0].path_cells);
    assert!(tex.contains(&format!("res:beyond:{cell}:pathlen\\endcsname{{{l}}}")));
    // An experiment without a scaling figure adds nothing.
    let table = Experiment::load(Path::new("experiments/table.toml"), None).unwrap();
    assert_eq!(pbcs::report::scaling_numbers_tex(&table, &[], &fit), "");
    // Nor does a fit without a line (fewer than two distinct path lengths).
    let one = pbcs::tables::scaling::ScalingFit::of(&exp, &stats[..1], &paths);
    assert_eq!((one.cells, one.line()), (1, None));
    let tex = pbcs::report::scaling_numbers_tex(&exp, &paths, &one);
    assert!(
        !tex.contains("exponent") && tex.contains("pathlen"),
        "{tex}"
    );
}

/// The routes table of the committed ablation rows: no chain beats the fewest steps possible
/// (a successful episode takes at least `Maze::fewest_steps`), each run's successful episodes
/// are its row's success rate, and phase 1's τ, recomputed from the seed, is never shorter
/// than the fewest steps either.
#[test]
fn routes_respect_the_fewest_steps_and_agree_with_the_rows() {
    let exp = Experiment::load(Path::new("experiments/ablations.toml"), None).unwrap();
    let rows = read_raw(&exp, Path::new("results")).unwrap();
    let routes = pbcs::tables::routes::routes(&exp, Path::new("results"), &rows).unwrap();
    assert!(routes.len() >= 20, "only {} routes", routes.len());
    for r in &routes {
        let row = rows
            .iter()
            .find(|w| w.cell == r.cell && w.seed == r.seed)
            .unwrap();
        assert_eq!(r.successes as f32, (row.success_rate * 100.0).round());
        if let Some(c) = r.chain_steps {
            assert!(c >= r.fewest_steps as f64, "{} s{}: {c}", r.cell, r.seed);
        }
        assert!(r.tau_steps >= r.fewest_steps && r.phase2_tau_steps <= r.tau_steps);
    }
}

/// An environment of the registry goes through an experiment as a maze size does:
/// `rooms.toml`'s cells are `<method>-rooms`, its rows hold `rooms` where a maze row holds its
/// size (and layout seed 0), its table is the plain computation of those rows, its figures
/// exist, and no maze-only table (routes against the maze's fewest steps, shortest paths) is
/// made up for it.
#[test]
fn the_rooms_grid_goes_through_rows_tables_and_figures_like_a_maze() {
    use pbcs::envs::EnvName;
    use pbcs::experiment::Site;
    let results = Path::new("results");
    let exp = Experiment::load(Path::new("experiments/rooms.toml"), None).unwrap();
    let rooms = Site::Env(EnvName::Rooms);
    assert_eq!(exp.sites, [rooms]);
    let ids: Vec<String> = exp.cells.iter().map(|c| c.id.to_string()).collect();
    assert_eq!(ids, ["pbcs-rooms", "pbcs_fast-rooms"]);
    for c in &exp.cells {
        let pbcs::experiment::Job::Pbcs(j) = &c.job else {
            panic!("{}: not a PBCS cell", c.id)
        };
        assert_eq!(j.env, EnvName::Rooms, "{}", c.id);
    }
    let rows = read_raw(&exp, results).unwrap();
    assert_eq!(rows.len(), 20);
    assert!(rows.iter().all(|r| r.site == rooms && r.maze_seed == 0));
    let table =
        pbcs::tables::read_table(&pbcs::tables::table_path(results, "rooms".parse().unwrap()))
            .unwrap();
    let plain = pbcs::tables::cell_stats(&exp, &rows);
    assert_eq!(table.len(), plain.len());
    for (t, p) in table.iter().zip(&plain) {
        assert_eq!(
            (&t.cell, t.site, t.n, t.successes, t.steps_median),
            (&p.cell, p.site, p.n, p.successes, p.steps_median)
        );
        assert_eq!(t.paper_steps, None, "{}", t.cell);
    }
    assert!(pbcs::tables::routes::routes(&exp, results, &rows)
        .unwrap()
        .is_empty());
    assert!(pbcs::tables::scaling::path_lengths(&exp)
        .unwrap()
        .is_empty());
    for f in [
        "rooms_grid.png",
        "rooms_grid.svg",
        "rooms_bars.png",
        "rooms_bars.svg",
    ] {
        assert!(results.join("figures").join(f).exists(), "{f}");
    }
}

/// The SAC-skill comparison's DDPG arm runs the committed grids' jobs
/// (`tests/heldout.rs`), so its rows are theirs: byte for byte past the experiment, cell and
/// method names, and the same evaluation episodes, seed by seed.
#[test]
fn the_sac_comparisons_ddpg_arm_reproduces_the_committed_grids() {
    let raw = Path::new("results/raw");
    let past_names = |path: &Path| -> String {
        let text =
            std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        text.lines()
            .map(|l| l.splitn(4, ',').nth(3).unwrap_or("").to_string())
            .collect::<Vec<_>>()
            .join("\n")
    };
    for (site, theirs) in [
        ("maze5", "table/pbcs_fast-maze5"),
        ("maze10", "table/pbcs_fast-maze10"),
        ("pointmaze_medium", "pointmaze/pbcs_pm-pointmaze_medium"),
    ] {
        let ours = raw.join(format!("sac_skills/ddpg_skills-{site}"));
        for seed in 0..10 {
            let (a, b) = (
                ours.join(format!("s{seed}.csv")),
                raw.join(theirs).join(format!("s{seed}.csv")),
            );
            assert_eq!(past_names(&a), past_names(&b), "{}", a.display());
            let eval = |d: &Path| std::fs::read(d.join(format!("s{seed}.evaluation.csv"))).unwrap();
            assert_eq!(eval(&ours), eval(&raw.join(theirs)), "{site} seed {seed}");
        }
    }
}

/// The committed criteria tables count what the chains tables hold, and their count at 95 %
/// is the solved rule's (`Criteria::unsolved`, which the report quotes, subtracts it from n).
#[test]
fn the_criteria_tables_agree_with_the_chains_and_the_solved_rule() {
    use pbcs::criteria::{chains_path, criteria, criteria_path, read_chains, read_criteria};
    let mut checked = 0;
    for entry in std::fs::read_dir("results/tables").unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let Some(exp) = name.strip_suffix(".chains.csv") else {
            continue;
        };
        let exp: pbcs::experiment::ExperimentName = exp.parse().unwrap();
        let results = Path::new("results");
        let chains = read_chains(&chains_path(results, exp)).unwrap();
        let committed = read_criteria(&criteria_path(results, exp)).unwrap();
        assert_eq!(committed, criteria(&chains), "{exp}");
        for c in &committed {
            let unsolved = chains
                .iter()
                .filter(|r| r.cell == c.cell && !r.solved)
                .count();
            assert_eq!(c.unsolved(), unsolved as u64, "{exp} {}", c.cell);
        }
        checked += 1;
    }
    assert!(checked >= 10, "{checked} chains tables");
}

/// The committed routes summaries are what the routes tables give: each cell's line of
/// `<exp>.route_cells.csv`, and the spread over cells of `<exp>.route_spread.csv` (what the
/// report quotes).
#[test]
fn the_route_summaries_agree_with_the_routes() {
    use pbcs::tables::routes::{
        read_routes, route_cells, route_cells_path, route_spread, route_spread_path, RouteCell,
        RouteSpread,
    };
    let mut checked = 0;
    for entry in std::fs::read_dir("results/tables").unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let Some(exp) = name.strip_suffix(".routes.csv") else {
            continue;
        };
        let exp: pbcs::experiment::ExperimentName = exp.parse().unwrap();
        let results = Path::new("results");
        let cells = route_cells(&read_routes(&path).unwrap());
        let committed: Vec<RouteCell> =
            pbcs::record::read_records(&route_cells_path(results, exp)).unwrap();
        assert_eq!(committed, cells, "{exp}");
        let spread: Vec<RouteSpread> =
            pbcs::record::read_records(&route_spread_path(results, exp)).unwrap();
        assert_eq!(spread, [route_spread(&cells)], "{exp}");
        checked += 1;
    }
    assert!(checked >= 6, "{checked} routes tables");
}

/// The committed scaling fits and the outside cost ratios are what their inputs give: each
/// `<exp>.scaling_fit.csv` is the fit through its experiment's committed table and paths, and
/// `outside.cost_ratio.csv` the ratios of `outside.timing.csv` (what the report quotes and the
/// scaling figure draws).
#[test]
fn the_fits_and_cost_ratios_agree_with_their_tables() {
    use pbcs::tables::scaling::{
        paths_path, read_paths, read_scaling_fit, scaling_fit_path, ScalingFit,
    };
    let results = Path::new("results");
    let mut checked = 0;
    for file in files() {
        let exp = Experiment::load(&file, None).unwrap();
        let paths = paths_path(results, exp.name);
        if !paths.exists() {
            continue;
        }
        let stats = pbcs::tables::read_table(&pbcs::tables::table_path(results, exp.name)).unwrap();
        let fit = ScalingFit::of(&exp, &stats, &read_paths(&paths).unwrap());
        let committed = read_scaling_fit(&scaling_fit_path(results, exp.name)).unwrap();
        assert_eq!(committed, fit, "{}", exp.name);
        assert!(
            fit.line().is_some() && fit.cells >= 2,
            "{}: {fit:?}",
            exp.name
        );
        checked += 1;
    }
    assert!(checked >= 1, "{checked} scaling fits");
    use pbcs::tables::outside::{cost_ratios, outside_table, read_cost_ratios, UpdateCost};
    let timing: Vec<UpdateCost> =
        pbcs::record::read_records(&outside_table(results, "timing")).unwrap();
    let path = outside_table(results, "cost_ratio");
    let ratios = read_cost_ratios(&path).unwrap();
    assert_eq!(ratios, cost_ratios(&timing));
    assert_eq!(ratios.len(), 2, "ddpg and td3");
    assert!(ratios.iter().all(|r| r.ratio.is_some()), "{ratios:?}");
    // The report quotes the times and the ratio from that table.
    let tex = pbcs::report::outside::outside_cost_numbers(&ratios);
    assert_eq!(tex.lines().count(), 6, "{tex}");
    let ours = "\\csname res:outside:cost:td3:ours\\endcsname{72 \\textmu{}s}";
    assert!(tex.contains(ours), "{tex}");
    // A line whose ratio is not its times' is refused, naming the learner.
    let text = std::fs::read_to_string(&path).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let edited = dir.path().join("outside.cost_ratio.csv");
    std::fs::write(&edited, text.replacen(",71.5,", ",70.5,", 1)).unwrap();
    let err = read_cost_ratios(&edited).unwrap_err().to_string();
    assert!(
        err.contains("td3") && err.contains("not SB3's time over ours"),
        "{err}"
    );
}

/// The preset's comment gives the range of wall-clock hours an unsolved `pointmaze_her` run
/// took ("took 0.7 to 5.4 hours"): it must be the shortest and longest of the timing files
/// beside the unsolved rows, to a tenth of an hour, as more rows land.
#[test]
fn the_her_presets_hours_are_those_of_its_timing_files() {
    let path = Path::new("experiments/pointmaze_her.toml");
    let exp = Experiment::load(path, None).unwrap();
    let results = Path::new("results");
    let rows = read_raw(&exp, results).unwrap();
    let hours: Vec<f64> = rows
        .iter()
        .filter(|r| !r.solved)
        .map(|r| {
            let cell = exp.cells.iter().find(|c| c.id == r.cell).unwrap();
            pbcs::experiment::read_wall_seconds(&exp, results, cell, r.seed)
                .unwrap_or_else(|| panic!("{} seed {}: no timing file", r.cell, r.seed))
                / 3600.0
        })
        .collect();
    assert!(!hours.is_empty(), "unsolved rows are read");
    let low = hours.iter().cloned().fold(f64::INFINITY, f64::min);
    let high = hours.iter().cloned().fold(0.0, f64::max);
    let want = format!("took {low:.1} to {high:.1} hours");
    let text = std::fs::read_to_string(path).unwrap();
    let text = text
        .lines()
        .map(|l| l.trim_start_matches('#').trim())
        .collect::<Vec<_>>()
        .join(" ");
    assert!(
        text.contains(&want),
        "experiments/pointmaze_her.toml's comment should say \"{want}\" ({} unsolved rows)",
        hours.len()
    );
}

/// The report's section on the goal-conditioned baselines says in words which cells of
/// `pointmaze_her` have no finished row yet, and on which maps the rows are "so far": true only
/// while it is (the sentence must change with the first such row, or the last).
#[test]
fn the_her_section_says_which_cells_have_no_run_only_while_true() {
    // The words as LaTeX reads them, whatever the line breaks.
    let report = std::fs::read_to_string("paper/report.tex").unwrap();
    let report = report.split_whitespace().collect::<Vec<_>>().join(" ");
    let exp = Experiment::load(Path::new("experiments/pointmaze_her.toml"), None).unwrap();
    let rows = read_raw(&exp, Path::new("results")).unwrap();
    let on = |method: &str, map: &str| {
        rows.iter()
            .filter(|r| {
                r.site.to_string() == format!("pointmaze_{map}_goals")
                    && r.method.as_str() == method
            })
            .count()
    };
    assert!(on("sac_her", "umaze") > 0, "the grid's UMaze rows are read");
    assert!(
        on("td3_her", "medium") > 0,
        "TD3+HER's Medium rows are read"
    );
    assert!(
        on("sac_her", "medium") > 0,
        "SAC+HER's Medium rows are read"
    );
    // "so far" on a map whose cells have every run, or its absence on one that has not, is
    // a sentence that stopped being true.
    // (On Large only once it has a row: until then, the sentence below says so.)
    for (map, words) in [
        ("umaze", "On UMaze so far"),
        ("medium", "On Medium so far"),
        ("large", "On Large so far"),
    ] {
        let some = on("sac_her", map) + on("td3_her", map) > 0;
        let whole = ["sac_her", "td3_her"]
            .iter()
            .all(|m| on(m, map) as u64 == exp.seed_count);
        assert_eq!(
            report.contains(words),
            some && !whole,
            "{map}: SAC+HER {} and TD3+HER {} of {} runs: update paper/report.tex's \"{words}\"",
            on("sac_her", map),
            on("td3_her", map),
            exp.seed_count
        );
    }
    let says = report.contains("No Large run has finished");
    let none = on("sac_her", "large") + on("td3_her", "large");
    assert_eq!(
        says,
        none == 0,
        "Large rows: SAC+HER {}, TD3+HER {}: update paper/report.tex's sentence",
        on("sac_her", "large"),
        on("td3_her", "large")
    );
    // Once one learner has a Large row, the report names the one that has none, if any.
    for (method, label) in [("sac_her", "SAC+HER"), ("td3_her", "TD3+HER")] {
        let words = format!("no {label} run on Large has finished");
        assert_eq!(
            report.to_lowercase().contains(&words.to_lowercase()),
            none > 0 && on(method, "large") == 0,
            "Large rows: {label} {} of {none}: update paper/report.tex's \"{words}\"",
            on(method, "large")
        );
    }
}
