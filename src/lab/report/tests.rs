//! Tests of the report's generated LaTeX (`super`).

use super::*;
use crate::experiment::Experiment;

/// Three short lines per maze: "k/n (j), median", the interval, the paper's figure; a
/// method without the cell gets dashes.
#[test]
fn the_results_table_puts_counts_interval_and_paper_on_three_lines() {
    let exp = Experiment::of_job("pbcs", &Default::default(), &[2], 10).unwrap();
    let c = &exp.cells[0];
    let cell = CellStats {
        steps_median: 195_000.0,
        solved_within_paper: Some(8),
        paper_steps: c.paper_steps,
        paper_solved: c.paper_solved,
        ..CellStats::empty(exp.name, c.id, &c.label).with_counts(9, 10)
    };
    let methods = [
        ("pbcs".parse().unwrap(), "PBCS".to_string()),
        ("other".parse().unwrap(), "Other".to_string()),
    ];
    let tex = results_table_tex(&[cell], &[crate::experiment::Site::Maze(2)], &methods);
    let lines: Vec<&str> = tex
        .lines()
        .skip_while(|l| !l.starts_with("\\midrule"))
        .collect();
    assert_eq!(lines[1], "$2\\times2$ & 9/10 (8), 195k & -- \\\\");
    assert_eq!(
        lines[2],
        " & \\textcolor{gray}{\\small [0.60, 0.98]} & \\\\"
    );
    assert_eq!(
        lines[3],
        " & \\textit{\\small paper: 321k S} & \\textit{\\small paper: --} \\\\[3pt]"
    );
    assert!(tex.contains("\\begin{tabular}{rcc}") && tex.contains("maze & PBCS & Other"));
}

/// The numbers beside the table of cells: seeds, the settings every cell of a method shares
/// (not the maze size where mazes differ, not the run seed), each run's chain success in
/// percent and each routes cell's fewest steps and share of phase 1's τ.
#[test]
fn the_extra_numbers_give_settings_runs_and_routes() {
    use crate::criteria::ChainSuccess;
    use crate::tables::routes::Route;
    let exp = Experiment::of_job("m", &Default::default(), &[2, 5], 10).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let key = |k: &str, v: &str| format!("\\csname res:m:{k}\\endcsname{{{v}}}");
    let tex = extra_numbers_tex(&exp, dir.path()).unwrap();
    assert!(tex.contains(&key("seeds", "10")), "{tex}");
    assert!(tex.contains(&key("m:cfg:phase2.beta", "50")), "{tex}");
    assert!(
        !tex.contains("cfg:maze.size") && !tex.contains("cfg:seed\\"),
        "{tex}"
    );
    assert!(
        !tex.contains(":chain\\") && !tex.contains(":routes:"),
        "{tex}"
    );
    let run = |seed: u64, rate: f32| ChainSuccess {
        experiment: "m".parse().unwrap(),
        cell: "m-maze5".parse().unwrap(),
        method: "m".parse().unwrap(),
        label: "m".into(),
        site: crate::experiment::Site::Maze(5),
        seed,
        complete: rate > 0.0,
        success_rate: rate,
        solved: rate >= 0.95,
        env_steps: 1000,
        paper_steps: None,
    };
    let chains = [
        run(1, 0.29),
        run(4, 0.0),
        ChainSuccess {
            complete: true,
            ..run(7, 0.0)
        },
    ];
    write_chains(dir.path(), &chains);
    let route = |seed: u64, tau: usize, phase2_tau: usize| Route {
        cell: "m-maze5".parse().unwrap(),
        method: "m".parse().unwrap(),
        site: crate::experiment::Site::Maze(5),
        seed,
        solved: true,
        tau_steps: tau,
        phase2_tau_steps: phase2_tau,
        chain_steps: Some(70.0),
        successes: 100,
        fewest_steps: 62,
    };
    crate::record::write_records(
        &crate::tables::routes::route_cells_path(dir.path(), "m".parse().unwrap()),
        &crate::tables::routes::route_cells(&[
            route(0, 400, 100),
            route(1, 400, 120),
            route(2, 300, 90),
        ]),
    )
    .unwrap();
    let tex = extra_numbers_tex(&exp, dir.path()).unwrap();
    for (k, v) in [
        ("m-maze5:s1:chain", "29"),
        ("m-maze5:s4:chain", "0"),
        ("m-maze5:routes:fewest", "62"),
        ("m-maze5:routes:tauleft", "30"),
        ("m-maze5:unsolved", "3"),
        ("m-maze5:incomplete", "1"),
        ("m-maze5:zerochains", "1"),
    ] {
        assert!(tex.contains(&key(k, v)), "{k}: {tex}");
    }
}

/// The report groups rows by cell whatever their order (it grouped with `Vec::dedup`, right
/// only while rows came sorted: rows of two cells interleaved gave each cell's numbers twice).
#[test]
fn the_report_groups_rows_whatever_their_order() {
    use crate::criteria::ChainSuccess;
    use crate::tables::routes::Route;
    let exp = Experiment::of_job("m", &Default::default(), &[2, 5], 10).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let chain = |n: usize, seed: u64| ChainSuccess {
        experiment: "m".parse().unwrap(),
        cell: crate::experiment::CellKey::new(
            "m".parse().unwrap(),
            crate::experiment::Site::Maze(n),
        ),
        method: "m".parse().unwrap(),
        label: "m".into(),
        site: crate::experiment::Site::Maze(n),
        seed,
        complete: true,
        success_rate: 1.0,
        solved: true,
        env_steps: 1000,
        paper_steps: None,
    };
    let route = |n: usize, seed: u64| Route {
        cell: crate::experiment::CellKey::new(
            "m".parse().unwrap(),
            crate::experiment::Site::Maze(n),
        ),
        method: "m".parse().unwrap(),
        site: crate::experiment::Site::Maze(n),
        seed,
        solved: true,
        tau_steps: 400,
        phase2_tau_steps: 100,
        chain_steps: Some(70.0),
        successes: 100,
        fewest_steps: 62,
    };
    let interleaved = [(5, 0), (2, 0), (5, 1), (2, 1)];
    let chains = interleaved.map(|(n, s)| chain(n, s));
    write_chains(dir.path(), &chains);
    crate::record::write_records(
        &crate::tables::routes::route_cells_path(dir.path(), "m".parse().unwrap()),
        &crate::tables::routes::route_cells(&interleaved.map(|(n, s)| route(n, s))),
    )
    .unwrap();
    let tex = extra_numbers_tex(&exp, dir.path()).unwrap();
    for cell in ["m-maze2", "m-maze5"] {
        for field in ["unsolved", "incomplete", "zerochains", "routes:fewest"] {
            let key = format!("res:m:{cell}:{field}\\endcsname");
            assert_eq!(tex.matches(&key).count(), 1, "{key}: {tex}");
        }
    }
}

/// A summary table the report reads is checked before it is trusted: missing beside the runs
/// it summarises (a folder aggregated before it existed) is an error saying to aggregate
/// again, and criteria counts that do not nest are an error naming the cell (the report
/// subtracts them).
#[test]
fn the_report_refuses_a_missing_or_inconsistent_summary() {
    use crate::criteria::{criteria_path, read_criteria};
    let exp = Experiment::of_job("m", &Default::default(), &[2, 5], 10).unwrap();
    let dir = tempfile::tempdir().unwrap();
    // A chains table (its header is enough) without the criteria table beside it.
    std::fs::create_dir_all(dir.path().join("tables")).unwrap();
    std::fs::write(
        crate::criteria::chains_path(dir.path(), "m".parse().unwrap()),
        "experiment,cell,method,label,maze,seed,complete,success_rate,solved,env_steps,paper_steps\n",
    )
    .unwrap();
    let err = extra_numbers_tex(&exp, dir.path()).unwrap_err().to_string();
    assert!(
        err.contains("m.criteria.csv") && err.contains("pbcs aggregate"),
        "{err}"
    );
    let path = criteria_path(dir.path(), "m".parse().unwrap());
    std::fs::write(
        &path,
        "experiment,cell,method,label,maze,n,complete,at_0_50,at_0_90,at_0_95,at_1_00,at_zero\n\
         m,m-maze5,m,m,5,10,10,9,9,12,8,0\n",
    )
    .unwrap();
    let err = read_criteria(&path).unwrap_err().to_string();
    assert!(err.contains("m-maze5") && err.contains("nest"), "{err}");
    assert!(extra_numbers_tex(&exp, dir.path()).is_err());
}

/// The code's constants as the report quotes them.
#[test]
fn the_code_constants_are_quoted_in_their_units() {
    let tex = settings::code_tex();
    for (k, v) in [
        ("solved_at_percent", "95"),
        ("confidence_percent", "95"),
        ("exact_test_level", "0.05"),
        ("thresholds:1_percent", "50"),
        ("thresholds:4_percent", "100"),
        ("max_adaptive_step", "16"),
    ] {
        let line = format!("\\csname res:code:{k}\\endcsname{{{v}}}");
        assert!(tex.contains(&line), "{k}: {tex}");
    }
}

/// Known values: two cells; the chains are 1.1 and 1.2 times the fewest steps, τ four and
/// five times the chain; one run without a successful episode counts nowhere.
#[test]
fn the_routes_numbers_give_the_spread_over_cells() {
    use crate::tables::routes::Route;
    let route = |cell: &str, chain: Option<f64>, tau: usize, fewest: usize| Route {
        cell: cell.parse().unwrap(),
        method: "m".parse().unwrap(),
        site: crate::experiment::Site::Maze(5),
        seed: 0,
        solved: chain.is_some(),
        tau_steps: tau,
        phase2_tau_steps: tau,
        chain_steps: chain,
        successes: u64::from(chain.is_some()),
        fewest_steps: fewest,
    };
    let cells = |routes: &[Route]| {
        crate::tables::routes::route_spread(&crate::tables::routes::route_cells(routes))
    };
    let tex = routes_numbers_tex(
        "x".parse().unwrap(),
        &cells(&[
            route("m-maze2", Some(110.0), 440, 100),
            route("m-maze5", Some(120.0), 600, 100),
            route("m-maze5", None, 600, 100),
        ]),
    );
    for (key, value) in [
        ("runs", "2"),
        ("shorter", "2"),
        ("fewestlo", "1.10"),
        ("fewesthi", "1.20"),
        ("taulo", "4.0"),
        ("tauhi", "5.0"),
        ("phase1lo", "4.0"),
        ("phase1hi", "5.0"),
    ] {
        let line = format!("\\csname res:x:routes:{key}\\endcsname{{{value}}}");
        assert!(tex.contains(&line), "{key}: {tex}");
    }
    assert_eq!(
        routes_numbers_tex(
            "x".parse().unwrap(),
            &cells(&[route("m-maze2", None, 1, 1)])
        ),
        ""
    );
    // A shortened τ: phase 2 worked on 440 steps, phase 1's τ had 880.
    let shortened = crate::tables::routes::Route {
        tau_steps: 880,
        ..route("m-maze2", Some(110.0), 440, 100)
    };
    let tex = routes_numbers_tex("x".parse().unwrap(), &cells(&[shortened]));
    assert!(tex.contains("res:x:routes:taulo\\endcsname{4.0}"), "{tex}");
    assert!(
        tex.contains("res:x:routes:phase1lo\\endcsname{8.0}"),
        "{tex}"
    );
}

/// The departures table sets the committed file's formulas as math (no literal `_` or braces
/// of a subscript), in ragged-right columns whose widths and gaps fit the text width, with
/// file paths that may break.
#[test]
fn the_departures_table_sets_math_as_math_and_fits() {
    let departures =
        settings::load_departures(std::path::Path::new("experiments/departures.toml")).unwrap();
    let tex = settings::departures_tex(&departures);
    for expected in [
        "$(K_s, \\pi_s)$",
        "$d(s', \\tau_T) \\le \\varepsilon$",
        "$B_\\varepsilon(\\tau_N)$",
        "$\\Phi(s) = 1 / d(s, A_i)$",
        "$\\pi_i$ until the state enters $A_{i+1}$",
        "\\path{experiments/ablations.toml}, mazes 2 and 5",
        ">{\\raggedright\\arraybackslash}p{0.14\\textwidth}",
    ] {
        assert!(tex.contains(expected), "{expected}: {tex}");
    }
    // No subscript or group of a formula is printed as text: the one `\_` is a code name's.
    assert_eq!(tex.matches("\\_").count(), 1, "{tex}");
    assert!(tex.contains("\\texttt{backplay\\_failed}"), "{tex}");
    assert!(!tex.contains("\\{"), "{tex}");
    assert!(tex.is_ascii(), "{tex}");
}

/// A math span left open in a departure, a setting or a claim is an error when the file is
/// read, naming the file, the entry and the field.
#[test]
fn an_unbalanced_dollar_is_an_error_naming_the_entry_and_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("departures.toml");
    std::fs::write(
        &path,
        "[[departure]]\nplace = \"a place\"\npaper = \"$d(s′, τ_T) ≤ ε\"\nours = \"o\"\n\
         why = \"w\"\nmeasured = \"no\"\n",
    )
    .unwrap();
    let e = settings::load_departures(&path).unwrap_err().to_string();
    assert!(
        e.contains("departures.toml")
            && e.contains("departure[0] (a place), paper: unbalanced `$`"),
        "{e}"
    );

    let text = std::fs::read_to_string("experiments/settings.toml").unwrap();
    let bad = text.replacen("what = \"$β$: episodes", "what = \"$β: episodes", 1);
    assert_ne!(bad, text);
    let path = dir.path().join("settings.toml");
    std::fs::write(&path, bad).unwrap();
    let e = settings::load(&path).unwrap_err().to_string();
    assert!(
        e.contains("settings.toml") && e.contains("setting `phase2.beta`, what: unbalanced `$`"),
        "{e}"
    );

    let path = dir.path().join("claims.toml");
    std::fs::write(
        &path,
        "[[claim]]\nid = \"x\"\npaper = \"in $B_ε(τ_K)\"\nexperiment = \"table\"\n\
         test = { kind = \"solves_everywhere\", method = \"a\" }\n",
    )
    .unwrap();
    let e = crate::claims::load_claims(&path).unwrap_err().to_string();
    assert!(
        e.contains("claims.toml") && e.contains("claim[0] (x), paper: unbalanced `$`"),
        "{e}"
    );
}

/// The Markdown table (`docs/phase2.md`) shows a setting's text without its math spans'
/// dollars, and the report's table sets it as math.
#[test]
fn settings_texts_are_plain_in_markdown_and_math_in_latex() {
    let rows = settings::load(std::path::Path::new("experiments/settings.toml")).unwrap();
    let start = rows
        .iter()
        .find(|(d, _)| d.field == "phase2.start")
        .unwrap();
    assert!(start.0.what.contains("$B_ε(τ_K)$"), "{}", start.0.what);
    let markdown = settings::settings_markdown(&rows);
    assert!(
        markdown.contains("uniform in B_ε(τ_K), exactly τ_K,"),
        "{markdown}"
    );
    assert!(!markdown.contains('$'));
    let tex = settings::presets_tex(&rows);
    assert!(
        tex.contains("uniform in $B_\\varepsilon(\\tau_K)$, exactly $\\tau_K$,"),
        "{tex}"
    );
    assert!(tex.contains("\\texttt{phase2.\\allowbreak{}chain\\_\\allowbreak{}verify\\_"));
}

/// Writes experiment `m`'s chains table under `results` and the criteria table beside it, as
/// `pbcs aggregate` does.
fn write_chains(results: &std::path::Path, chains: &[crate::criteria::ChainSuccess]) {
    let m = "m".parse().unwrap();
    crate::record::write_records(&crate::criteria::chains_path(results, m), chains).unwrap();
    let criteria = crate::criteria::criteria(chains);
    crate::record::write_records(&crate::criteria::criteria_path(results, m), &criteria).unwrap();
}
