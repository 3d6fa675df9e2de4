//! The `pbcs` command line, a thin layer over the library: it parses arguments, calls
//! `pbcs::runs` (`explore`, `train`, `run`, `eval`), `pbcs::experiment` (`table`, `exp`) and
//! `pbcs::pipeline` (`aggregate`, `figures`), and shows progress.

mod args;

use anyhow::Context;
use args::{Cli, Command, ExpArgs, ExpCommand, LearnerArgs, RunArgs, SetArgs};
use clap::Parser;
use pbcs::config::{self, Check, ExploreJob, Located, PbcsJob, Preset, TrainJob};
use pbcs::experiment::{Experiment, Pending, SweepProgress, Swept};
use pbcs::nn::kernel::Kernel;
use pbcs::runs;
use pbcs::validate::Valid;
use std::io::IsTerminal;
use std::path::Path;
use std::process::ExitCode;

fn main() -> ExitCode {
    // `pbcs exp list | head`: a closed pipe ends the program quietly, as for other command-line
    // tools, instead of a panic in println!.
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of SIGPIPE before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    // One thread per process (use cores for seeds): pin candle's thread pool before any candle
    // call, unless the user chose otherwise. Our own kernels are single-threaded.
    for var in ["RAYON_NUM_THREADS", "CANDLE_NUM_THREADS"] {
        if std::env::var_os(var).is_none() {
            std::env::set_var(var, "1");
        }
    }
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        // Not a failure: the work so far is saved, and the same command goes on (sysexits.h's
        // EX_TEMPFAIL, "try again later", for a cluster script to requeue on).
        Err(e) if e.is::<pbcs::error::Unfinished>() => {
            eprintln!("{e}");
            ExitCode::from(pbcs::error::Unfinished::EXIT)
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    // The layer kernel of every run (PBCS_KERNEL, else the best this CPU runs), read once: a
    // bad name is an error here, before any work.
    let kernel = Kernel::from_env()?;
    match cli.command {
        Command::Explore { run } => explore(&run),
        Command::Train {
            run,
            learner,
            steps,
        } => train(&run, &learner, steps, kernel),
        Command::Run {
            run,
            preset,
            learner,
            no_chaining,
            exact_starts,
            stop_after,
        } => {
            let stop_at = pbcs::checkpoint::deadline(stop_after)?;
            let preset = preset.unwrap_or(Preset::Fast);
            let mut job = run.load(|| preset.job())?;
            learner.apply(&mut job.learner)?;
            if no_chaining {
                for field in job.without_chaining() {
                    eprintln!("--no-chaining: {field} = 0 (it acts between skills)");
                }
            }
            if exact_starts {
                job.phase2.start = pbcs::phase2::StartMode::Exact;
            }
            // The default folder names the procedure, so runs of two presets or configs never
            // meet in one folder.
            let label = runs::method_name(run.config.as_deref(), preset);
            pbcs_run(&run, job.valid()?, &label, stop_at, kernel)
        }
        Command::Eval {
            chain,
            episodes,
            seed,
            out,
        } => eval(&chain, episodes as usize, seed, out, kernel),
        Command::Table {
            config,
            preset,
            sizes,
            seeds,
            jobs,
            out,
        } => table(
            config.as_deref(),
            preset.unwrap_or(Preset::Fast),
            &sizes,
            seeds,
            jobs,
            &out,
            kernel,
        ),
        Command::Aggregate { set } => aggregate(&set),
        Command::Figures { set, figures, tex } => render(&set, figures, tex),
        Command::Exp { command } => exp(command, kernel),
    }
}

/// `pbcs exp run`, `list` and `check`.
fn exp(command: ExpCommand, kernel: Kernel) -> anyhow::Result<()> {
    match command {
        ExpCommand::Run {
            exp: args,
            cell,
            seed,
            jobs,
            skip_unavailable,
            stop_after,
        } => {
            let stop_at = pbcs::checkpoint::deadline(stop_after)?;
            exp_run(&args, (cell, seed), jobs, skip_unavailable, stop_at, kernel)
        }
        ExpCommand::List {
            exp: args,
            make,
            slurm,
            skip_unavailable,
        } => exp_list(&args, make, slurm, skip_unavailable),
        ExpCommand::Check {
            exp: args,
            cell,
            seed,
            jobs,
            exact,
        } => exp_check(&args, cell, seed, jobs, kernel, exact),
    }
}

/// `pbcs eval`: a saved chain from its folder, into `out` (default: the chain's folder).
fn eval(
    chain: &Path,
    episodes: usize,
    seed: Option<u64>,
    out: Option<std::path::PathBuf>,
    kernel: Kernel,
) -> anyhow::Result<()> {
    let e = runs::eval_chain(chain, episodes, seed, kernel)?;
    let out = out.unwrap_or_else(|| chain.to_path_buf());
    e.write(&out, &pbcs::plot::draw_run)?;
    println!("{}", e.summary(chain, e.seed));
    println!("wrote {}/eval-s{}.{{csv,png,svg}}", out.display(), e.seed);
    Ok(())
}

/// `pbcs table`: one procedure over maze sizes × seeds, swept into `out`, its table printed.
fn table(
    config: Option<&Path>,
    preset: Preset,
    sizes: &[usize],
    seeds: u64,
    jobs: usize,
    out: &Path,
    kernel: Kernel,
) -> anyhow::Result<()> {
    let job: PbcsJob = match config {
        Some(p) => config::load(p)?,
        None => preset.job()?,
    };
    let name = runs::method_name(config, preset);
    let exp = Experiment::of_job(&name, &job, sizes, seeds)?;
    let plan = pbcs::experiment::plan(&exp, None, None)?;
    let (swept, ran) = sweep(&exp, &plan, out, jobs, None, kernel)?;
    let rows = swept.rows;
    let stats = pbcs::tables::cell_stats(&exp, &rows);
    let table = pbcs::tables::table_path(out, exp.name);
    pbcs::tables::write_table(&table, &stats)?;
    println!(
        "{name} ({}), seeds 0..{seeds}: {ran} ran now, {} were finished; raw rows in {}, \
         statistics in {}",
        job.phase2.variant().name(),
        rows.len() - ran,
        out.join("raw").join(exp.name).display(),
        table.display()
    );
    let timings = pbcs::tables::cell_timings(&exp, out, &rows);
    print!("{}", pbcs::tables::grid_markdown(&stats, &timings));
    Ok(())
}

/// `pbcs figures`: every figure, the claims and the report's LaTeX from the tables.
fn render(
    set: &SetArgs,
    figures: Option<std::path::PathBuf>,
    tex: Option<std::path::PathBuf>,
) -> anyhow::Result<()> {
    let (exps, results) = set.load()?;
    let figures = figures.unwrap_or_else(|| results.join("figures"));
    let tex = pbcs::pipeline::tex_dir(tex.as_deref(), set.profile.as_deref(), &results);
    let claims = set.experiments.join("claims.toml");
    let done = pbcs::pipeline::render(exps, &claims, &results, &figures, &tex)?;
    let (f, t) = (figures.display(), tex.display());
    println!("{} into {f} and {t}", done.summary());
    Ok(())
}

/// `pbcs exp run`: an experiment's planned runs (or one cell, one seed), resuming. An
/// experiment this build cannot run is refused before any work, or skipped with one line.
fn exp_run(
    args: &ExpArgs,
    (cell, seed): (Option<pbcs::experiment::CellKey>, Option<u64>),
    jobs: usize,
    skip_unavailable: bool,
    stop_at: Option<std::time::Instant>,
    kernel: Kernel,
) -> anyhow::Result<()> {
    let (exp, results) = args.load()?;
    if let Some(why) = exp.unavailable() {
        anyhow::ensure!(skip_unavailable, "{why}");
        println!("skipped {why}");
        return Ok(());
    }
    let plan = pbcs::experiment::plan(&exp, cell, seed)?;
    let (swept, ran) = sweep(&exp, &plan, &results, jobs, stop_at, kernel)?;
    if swept.unfinished > 0 {
        return Err(pbcs::error::Unfinished(swept.unfinished).into());
    }
    let rows = swept.rows;
    println!(
        "{} ({}): {} runs, {ran} ran now, {} were finished; raw rows in {}",
        exp.name,
        exp.profile.as_deref().unwrap_or("committed grid"),
        rows.len(),
        rows.len() - ran,
        results.join("raw").join(exp.name).display()
    );
    print!(
        "{}",
        pbcs::tables::markdown(&pbcs::tables::cell_stats(&exp, &rows))
    );
    Ok(())
}

/// `pbcs exp list`: the runs as commands, a Makefile or a SLURM array. An experiment this
/// build cannot run is refused, or listed as one comment line.
fn exp_list(args: &ExpArgs, make: bool, slurm: bool, skip_unavailable: bool) -> anyhow::Result<()> {
    let (exp, results) = args.load()?;
    if let Some(why) = exp.unavailable() {
        anyhow::ensure!(skip_unavailable, "{why}");
        println!(
            "# skipped {why}{}",
            if make { "\n.PHONY: all\nall:" } else { "" }
        );
        return Ok(());
    }
    // The commands would be refused by the sweep they run: say so now, once.
    if let Some(Err(e)) = exp.registered.as_ref().map(|r| r.check(exp.name)) {
        eprintln!("warning: every run listed will be refused: {e}");
    }
    let profile = args.profile.as_deref();
    let launch = pbcs::launch::Launch::new(&exp, &args.file, profile, args.results.as_deref());
    match (make, slurm) {
        (true, _) => print!("{}", launch.makefile(&results)?),
        (_, true) => print!("{}", launch.slurm(&results)),
        _ => print!("{}", launch.commands(&results)?),
    }
    Ok(())
}

fn aggregate(set: &SetArgs) -> anyhow::Result<()> {
    let (exps, results) = set.load()?;
    println!("reading raw rows in {}", results.display());
    for a in pbcs::pipeline::aggregate(&exps, &results)? {
        println!("{a}");
    }
    for file in pbcs::pipeline::aggregate_outside(&exps, &results)? {
        println!("outside checks → {}", file.display());
    }
    Ok(())
}

/// Runs `runs` with [`pbcs::experiment::sweep_until`] behind a progress bar (finished runs are
/// read back; [`SweepProgress`]). Returns what the sweep did and how many runs ran now.
fn sweep(
    exp: &Experiment,
    runs: &[Pending],
    results: &Path,
    jobs: usize,
    stop_at: Option<std::time::Instant>,
    kernel: Kernel,
) -> anyhow::Result<(Swept, usize)> {
    let progress = SweepProgress::new(runs.len() as u64);
    let on_event = |p: &Pending, e: &_| progress.on_event(p, e);
    let swept = pbcs::experiment::sweep_until(exp, runs, results, jobs, kernel, stop_at, on_event)?;
    Ok((swept, progress.finish()))
}

fn exp_check(
    args: &ExpArgs,
    cell: pbcs::experiment::CellKey,
    seed: Option<u64>,
    jobs: usize,
    kernel: Kernel,
    exact: bool,
) -> anyhow::Result<()> {
    use pbcs::reproduce::check_cell;
    let (exp, results) = args.load()?;
    let progress = SweepProgress::new(pbcs::experiment::plan(&exp, Some(cell), seed)?.len() as u64);
    let check = check_cell(&exp, &results, cell, seed, jobs, kernel, |p, e| {
        progress.on_event(p, e)
    })?;
    progress.finish();
    println!("{}", check.report(cell));
    println!("{}", check.verdict(cell, exact)?);
    Ok(())
}

fn pbcs_run(
    run: &RunArgs,
    job: Valid<PbcsJob>,
    label: &str,
    stop_at: Option<std::time::Instant>,
    kernel: Kernel,
) -> anyhow::Result<()> {
    let out = run.out_dir(|| runs::run_out(&job, label));
    let bar = run.bar("{spinner} [{elapsed}] {msg}", None);
    let lines = !run.quiet && !std::io::stderr().is_terminal();
    let mut progress = runs::Phase2Progress::new(bar, lines);
    let done = runs::run_pbcs_until(
        &job,
        kernel,
        &out,
        &pbcs::plot::draw_run,
        stop_at,
        |skill, p| progress.report(skill, p),
    )
    .with_context(|| format!("PBCS on {} seed {}", job.env_spec().label(), job.seed))?;
    progress.finish();
    let Some((record, seconds)) = done else {
        return Err(pbcs::error::Unfinished(1).into());
    };
    println!("{}", record.summary(job.phase2.eval_episodes, seconds));
    let wrote = "{record,skills,trace,trajectory}.csv, chain/, run.png, run.svg";
    println!("wrote {}/{wrote}", out.display());
    Ok(())
}

fn explore(run: &RunArgs) -> anyhow::Result<()> {
    let job = run.load(|| Ok(ExploreJob::default()))?.valid()?;
    let out = run.out_dir(|| runs::explore_out(&job));
    let template = "{spinner} phase 1: {human_pos} env steps ({per_sec}), {msg} [{elapsed}]";
    let bar = run.bar(template, None);
    let (summary, seconds) =
        runs::run_explore(&job, &out, &pbcs::plot::draw_run, |steps, states| {
            bar.set_position(steps);
            bar.set_message(format!("{states} archived states"));
        })
        .with_context(|| format!("explore {} seed {}", job.env_spec().label(), job.seed))?;
    bar.finish_and_clear();
    println!("{}", summary.summary(seconds, job.explore.bin_side));
    let wrote = "{summary,trajectory,archive}.csv, explore.png, explore.svg";
    println!("wrote {}/{wrote}", out.display());
    Ok(())
}

fn train(
    run: &RunArgs,
    learner: &LearnerArgs,
    steps: Option<u64>,
    kernel: Kernel,
) -> anyhow::Result<()> {
    let mut job = run.load(|| Ok(TrainJob::default()))?;
    learner.apply(&mut job.learner)?;
    job.train.steps = steps.unwrap_or(job.train.steps);
    let job = job.valid()?;
    let out = run.out_dir(|| runs::train_out(&job));
    let template = "{bar:30} {human_pos}/{human_len} env steps ({per_sec}, eta {eta}), {msg}";
    let bar = run.bar(template, Some(job.train.steps));
    let (summary, seconds) = runs::run_train(
        &job,
        kernel,
        &out,
        &pbcs::plot::draw_run,
        |steps, success| {
            bar.set_position(steps);
            bar.set_message(format!("greedy success {success}"));
        },
    )
    .with_context(|| format!("train on {} seed {}", job.env_spec().label(), job.seed))?;
    bar.finish_and_clear();
    println!("{}", summary.summary(seconds, job.train.visit_bin));
    let wrote = "{summary,evals,visited}.csv, actor.safetensors, train.png, train.svg";
    println!("wrote {}/{wrote}", out.display());
    Ok(())
}
