//! The report's AntMaze section: `antmaze_probes.tex`, `antmaze_handover.tex`,
//! `antmaze_reach.tex` (and the goal-conditioned chain's `antmaze_gc.tex`,
//! [`super::antmaze_gc`]) and the numbers `\res{antmaze:…}`, read from the committed development
//! files of PBCS on gymnasium-robotics' AntMaze (`<results>/dev/issue49/`, described by its
//! README). None of those runs is a registered grid; the section says so, and every number it
//! quotes comes from these files.
//!
//! The files read, each checked as it is read (a missing or malformed line is an error naming
//! the file):
//! - `phase1_dev.csv`: phase 1 on the fixed task, one row per run;
//! - `starts/runs/ball30m-s0/record.csv`: the one PBCS run long enough to walk all of τ;
//! - `handover/out/<arm>-s<seed>.txt`: `examples/antmaze_chain.rs`'s readings (`handover` on
//!   that run, `prefix` on τ_0 … τ_40): the run's steps and skills, the chain's episodes from
//!   B_ε(τ_0) that reached the target, and a table per skill;
//! - `phase2/long/record.csv` and `judged.txt`: the longer run of the first development grid,
//!   its chain judged by gymnasium-robotics;
//! - `reach/<arm>-s<seed>.csv`: the reach probe's evaluations (100 greedy episodes each).

use super::{def_res, percent, tex, GENERATED};
use crate::envs::pointmaze::MapName;
use crate::fmt::human_steps;
use crate::{Error, Result};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use strum::IntoEnumIterator as _;

/// The development folder of PBCS on AntMaze, under a results folder.
pub const DEV: &str = "dev/issue49";

/// The readings of `handover/out/` the report's table shows, in its order: (file stem, what
/// the arm changes).
const PROBES: [(&str, &str); 9] = [
    ("verify-s0", "the run's job, no repair"),
    ("verify-s2", "the run's job, no repair"),
    ("repair-s0", "up to 10 chain repairs"),
    ("repair-s2", "up to 10 chain repairs"),
    ("jitter-s2", "legs jittered in the starts"),
    ("archive-s0", "starts from phase 1's archive"),
    ("archive-s2", "starts from phase 1's archive"),
    ("lookahead-s0", "hand-over lookahead 100"),
    ("lookahead-s2", "hand-over lookahead 100"),
];

/// The reach probe's arms, in the table's order: (file stem, learner).
const REACH: [(&str, &str); 5] = [
    ("td3_her64-s0", "TD3+HER 64×64"),
    (
        "td3_her64_body-s0",
        "TD3+HER 64×64, goal in the body's frame",
    ),
    ("sac_her64-s0", "SAC+HER 64×64"),
    ("td3_her256-s0", "TD3+HER 256×256"),
    ("td3_her64_6m-s0", "TD3+HER 64×64, 6M steps"),
];

/// One row of `phase1_dev.csv` (the columns the report reads; the others are allowed).
#[derive(Debug, serde::Deserialize)]
struct Phase1Row {
    /// As the rows write it (`UMaze`; `large` in the rows that hit the time limit).
    #[serde(deserialize_with = "map_name")]
    map: MapName,
    flipped: String,
    bin_side: f64,
    /// States archived, and of them upside down (empty in a row that hit the time limit).
    archived: Option<u64>,
    archived_flipped: Option<u64>,
    /// `true`, `false` (budget spent) or `timeout` (the wall-clock limit).
    solved: String,
    /// Empty in a row that hit the time limit.
    env_steps: Option<u64>,
}

/// A map's name in any case (`UMaze`, `large`).
fn map_name<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<MapName, D::Error> {
    let name = <std::borrow::Cow<str> as serde::Deserialize>::deserialize(d)?;
    MapName::iter()
        .find(|m| <&str>::from(*m).eq_ignore_ascii_case(&name))
        .ok_or_else(|| serde::de::Error::custom(format!("unknown map `{name}`")))
}

/// The columns of a PBCS run's `record.csv` the report reads.
#[derive(Debug, serde::Deserialize)]
struct RunRecord {
    total_steps: u64,
    skills: u64,
    trajectory_len: u64,
}

/// One evaluation of the reach probe.
#[derive(Debug, serde::Deserialize)]
struct ReachRow {
    steps: u64,
    success: f64,
}

/// One line of a reading's table of skills.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
pub struct SkillReading {
    /// The skill's index in its chain.
    pub skill: u64,
    /// The index of τ its ball is centred on.
    #[serde(rename = "K")]
    pub k: u64,
    /// The index of τ its target ball is centred on.
    #[serde(rename = "T")]
    pub t: u64,
    /// Episodes of the chain that entered it.
    pub entered: u64,
    /// Of those, the episodes that stopped in it.
    pub stalled: u64,
    /// Of its entries, the share from which the skill alone reached its target.
    pub from_entries: f64,
    /// The share from starts drawn as its training drew them.
    pub from_ball: f64,
    /// Hinge angles at the entries from τ_K's (norm over the 8 hinges, radians; mean).
    pub joint_gap: f64,
    /// Hinge velocities at the entries from τ_K's (rad/s; mean).
    pub velocity_gap: f64,
}

/// What one reading of `examples/antmaze_chain.rs` says.
#[derive(Debug, Clone, PartialEq)]
pub struct ChainReading {
    /// What phase 2 did, where the reading ran it (`prefix`; `handover` reads a saved run).
    pub phase2: Option<Phase2Line>,
    /// The last index of the prefix of τ phase 2 ran on (`τ_0 … τ_40` in its `phase 1:`
    /// line), none for a reading of a whole run.
    pub prefix: Option<u64>,
    /// Episodes from B_ε(τ_0) that reached the target, of how many (none when no chain).
    pub reached: Option<(u64, u64)>,
    /// One line per skill the chain's episodes reached.
    pub table: Vec<SkillReading>,
}

/// A reading's `phase 2:` line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Phase2Line {
    /// Phase 2's env steps, training and tests.
    pub steps: u64,
    /// The skills phase 2 saved.
    pub skills: u64,
    /// How phase 2 ended: `chain` (a complete chain), `backplay failed`, `budget`.
    pub outcome: &'static str,
}

/// Reads one `handover/out/*.txt` file.
pub fn read_chain_reading(path: &Path) -> Result<ChainReading> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let bad = |m: &str| Error::parse(path, m.to_string());
    let mut phase2 = None;
    let mut reached = None;
    let mut prefix = None;
    let mut lines = text.lines();
    let mut table = Vec::new();
    while let Some(line) = lines.next() {
        if let Some(rest) = line.strip_prefix("phase 1: ") {
            if let Some((_, last)) = rest.split_once("τ_0 … τ_") {
                let digits: String = last.chars().take_while(char::is_ascii_digit).collect();
                prefix = Some(digits.parse().map_err(|_| bad("its `phase 1:` line"))?);
            }
        } else if let Some(rest) = line.strip_prefix("phase 2: ") {
            phase2 = Some(parse_phase2(rest).ok_or_else(|| bad("its `phase 2:` line"))?);
        } else if let Some(rest) = line.strip_prefix("chain from B_eps(tau_0): ") {
            reached = Some(parse_reached(rest).ok_or_else(|| bad("its `chain from` line"))?);
        } else if line.starts_with("skill,K,T,") {
            let block: Vec<&str> = std::iter::once(line)
                .chain(lines.by_ref().take_while(|l| !l.trim().is_empty()))
                .collect();
            let block = block.join("\n");
            let mut reader = csv::Reader::from_reader(block.as_bytes());
            for row in reader.deserialize() {
                table.push(row.map_err(|e| Error::csv(path, e))?);
            }
        }
    }
    if phase2.is_none() && prefix.is_some() {
        return Err(bad("a prefix of τ without its `phase 2:` line"));
    }
    if reached.is_some() == table.is_empty() {
        return Err(bad(
            "a chain's episodes without its table of skills, or the reverse",
        ));
    }
    Ok(ChainReading {
        phase2,
        prefix,
        reached,
        table,
    })
}

/// `None, 8 skills, 838366 training and 652396 test env steps, 817 s` (the failure as Rust's
/// `Debug` of an `Option` wrote it).
fn parse_phase2(rest: &str) -> Option<Phase2Line> {
    let (failure, rest) = rest.split_once(", ")?;
    let outcome = match failure {
        "None" => "chain",
        "Some(BackplayFailed)" => "backplay failed",
        "Some(Budget)" => "budget",
        _ => return None,
    };
    let (skills, rest) = rest.split_once(" skills, ")?;
    let (train, rest) = rest.split_once(" training and ")?;
    let (test, _) = rest.split_once(" test env steps")?;
    let steps = train.parse::<u64>().ok()?.checked_add(test.parse().ok()?)?;
    Some(Phase2Line {
        steps,
        skills: skills.parse().ok()?,
        outcome,
    })
}

/// `4 of 100 episodes reach the target (…)`: (4, 100).
fn parse_reached(rest: &str) -> Option<(u64, u64)> {
    let (k, rest) = rest.split_once(" of ")?;
    let (n, _) = rest.split_once(" episodes")?;
    let (k, n) = (k.parse().ok()?, n.parse().ok()?);
    (k <= n && n > 0).then_some((k, n))
}

/// `successes = 0 of 100` in a judge's `judged.txt`: (successes, episodes).
fn read_judged(path: &Path) -> Result<(u64, u64)> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    text.lines()
        .find_map(|l| parse_reached(&format!("{} episodes", l.strip_prefix("successes = ")?)))
        .ok_or_else(|| Error::parse(path, "no `successes = K of N` line".to_string()))
}

fn one_record<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T> {
    crate::record::read_one_record(path)
}

/// The AntMaze section's tables (written into `tex_dir`, added to `files`) and its numbers,
/// from `<results>/dev/issue49/`; nothing where that folder does not exist (a results folder
/// of the smoke profile).
pub fn render(results: &Path, tex_dir: &Path, files: &mut Vec<PathBuf>) -> Result<String> {
    let dev = results.join(DEV);
    if !dev.is_dir() {
        return Ok(String::new());
    }
    let mut numbers = String::new();
    phase1_numbers(&mut numbers, &dev.join("phase1_dev.csv"))?;
    walk_numbers(&mut numbers, &dev)?;
    for (name, table) in [
        ("antmaze_handover.tex", handover_table(&mut numbers, &dev)?),
        ("antmaze_probes.tex", probes_table(&mut numbers, &dev)?),
        ("antmaze_reach.tex", reach_table(&mut numbers, &dev)?),
    ]
    .into_iter()
    .chain(
        super::antmaze_gc::gc_table(&mut numbers, results)?.map(|table| ("antmaze_gc.tex", table)),
    ) {
        let path = tex_dir.join(name);
        crate::record::write_atomic(&path, |w| w.write_all(table.as_bytes()))?;
        files.push(path);
    }
    Ok(numbers)
}

/// `\res{antmaze:phase1:…}`: `runs`, `solved` (runs that refused flipped states, and of them
/// those that reached the goal), per map `<map>:median` (median env steps refusing flipped
/// states, bins of 0.5 m), and `keep:large:runs` / `keep:large:unfinished` (Large keeping
/// them: runs, and runs that hit the time limit).
fn phase1_numbers(s: &mut String, path: &Path) -> Result<()> {
    let rows: Vec<Phase1Row> = crate::record::read_records(path)?;
    let refuse: Vec<&Phase1Row> = rows.iter().filter(|r| r.flipped == "refuse").collect();
    let solved = refuse.iter().filter(|r| r.solved == "true").count();
    def_res(s, "antmaze", "phase1:runs", &refuse.len().to_string());
    def_res(s, "antmaze", "phase1:solved", &solved.to_string());
    for map in MapName::iter() {
        let mut steps = Vec::new();
        for r in &refuse {
            if r.map == map && r.bin_side == 0.5 && r.solved == "true" {
                let why = format!("a solved run on {map:?} without its env steps");
                steps.push(r.env_steps.ok_or_else(|| Error::parse(path, why))? as f64);
            }
        }
        if steps.is_empty() {
            return Err(Error::parse(
                path,
                format!("no solved run on {map:?} at 0.5 m"),
            ));
        }
        let median = crate::stats::median(&mut steps);
        let key = format!("phase1:{}:median", <&str>::from(map).to_lowercase());
        def_res(s, "antmaze", &key, &human_steps(median));
    }
    let large: Vec<&Phase1Row> = rows
        .iter()
        .filter(|r| r.flipped == "keep" && r.map == MapName::Large)
        .collect();
    let unfinished = large.iter().filter(|r| r.solved == "timeout").count();
    // The share of each finished archive that is upside down, keeping flipped states.
    let mut shares = Vec::new();
    for r in rows
        .iter()
        .filter(|r| r.flipped == "keep" && r.solved == "true")
    {
        match (r.archived, r.archived_flipped) {
            (Some(all), Some(flipped)) if flipped <= all && all > 0 => {
                shares.push(flipped as f64 / all as f64)
            }
            _ => {
                return Err(Error::parse(
                    path,
                    "a finished run without its archive's counts",
                ))
            }
        }
    }
    let lo = shares.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = shares.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if shares.is_empty() {
        return Err(Error::parse(path, "no finished run keeping flipped states"));
    }
    def_res(s, "antmaze", "phase1:keep:flippedlo", &percent(lo));
    def_res(s, "antmaze", "phase1:keep:flippedhi", &percent(hi));
    def_res(
        s,
        "antmaze",
        "phase1:keep:large:runs",
        &large.len().to_string(),
    );
    def_res(
        s,
        "antmaze",
        "phase1:keep:large:unfinished",
        &unfinished.to_string(),
    );
    Ok(())
}

/// The two long runs: `\res{antmaze:ball30m:…}` (`steps`, `skills`, `tau`: env steps, skills
/// saved, τ's length) and `\res{antmaze:long:…}` (the same, and `judged` / `judgedn`:
/// gymnasium-robotics' successes of its episodes).
fn walk_numbers(s: &mut String, dev: &Path) -> Result<()> {
    for (key, dir) in [
        ("ball30m", "starts/runs/ball30m-s0"),
        ("long", "phase2/long"),
    ] {
        let r: RunRecord = one_record(&dev.join(dir).join("record.csv"))?;
        def_res(
            s,
            "antmaze",
            &format!("{key}:steps"),
            &human_steps(r.total_steps as f64),
        );
        def_res(
            s,
            "antmaze",
            &format!("{key}:skills"),
            &r.skills.to_string(),
        );
        def_res(
            s,
            "antmaze",
            &format!("{key}:tau"),
            &r.trajectory_len.to_string(),
        );
    }
    let (k, n) = read_judged(&dev.join("phase2/long/judged.txt"))?;
    def_res(s, "antmaze", "long:judged", &k.to_string());
    def_res(s, "antmaze", "long:judgedn", &n.to_string());
    Ok(())
}

/// `antmaze_handover.tex`, `ball30m`'s skills read one by one (`handover/out/ball30m-s0.txt`),
/// and `\res{antmaze:handover:…}`: `reached` / `episodes` (the chain's episodes from B_ε(τ_0)
/// that reached the goal), `skills` (skills its episodes entered), `fromball` (the least
/// success of a skill from its own training ball, %), and over the skills after the first
/// (whose entries are hand-overs, not the episodes' starts) `entrieslo`/`entrieshi` (% from
/// their entries, skills entered more than twice), `jointlo`/`jointhi` (rad) and
/// `velocitylo`/`velocityhi` (rad/s).
fn handover_table(s: &mut String, dev: &Path) -> Result<String> {
    let path = dev.join("handover/out/ball30m-s0.txt");
    let reading = read_chain_reading(&path)?;
    let (k, n) = reading
        .reached
        .ok_or_else(|| Error::parse(&path, "no chain's episodes".to_string()))?;
    let later: Vec<&SkillReading> = reading.table.iter().filter(|r| r.skill > 0).collect();
    let many: Vec<&&SkillReading> = later.iter().filter(|r| r.entered > 2).collect();
    if many.is_empty() {
        return Err(Error::parse(
            &path,
            "no hand-over entered more than twice".to_string(),
        ));
    }
    let lo_hi = |v: &mut dyn Iterator<Item = f64>| {
        v.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        })
    };
    let fromball = lo_hi(&mut reading.table.iter().map(|r| r.from_ball)).0;
    let entries = lo_hi(&mut many.iter().map(|r| r.from_entries));
    let joint = lo_hi(&mut later.iter().map(|r| r.joint_gap));
    let velocity = lo_hi(&mut later.iter().map(|r| r.velocity_gap));
    for (f, v) in [
        ("reached", k.to_string()),
        ("episodes", n.to_string()),
        ("skills", reading.table.len().to_string()),
        ("fromball", percent(fromball)),
        ("entrieslo", percent(entries.0)),
        ("entrieshi", percent(entries.1)),
        ("jointlo", format!("{:.1}", joint.0)),
        ("jointhi", format!("{:.1}", joint.1)),
        ("velocitylo", format!("{:.0}", velocity.0)),
        ("velocityhi", format!("{:.0}", velocity.1)),
    ] {
        def_res(s, "antmaze", &format!("handover:{f}"), &v);
    }
    let mut t = String::from(GENERATED);
    t.push_str("\\begin{tabular}{rrrrrrr}\n\\toprule\n");
    t.push_str(
        "skill & $K\\to T$ & entered & from entries & from its ball & angle gap (rad) & \
         velocity gap (rad/s) \\\\\n\\midrule\n",
    );
    for r in &reading.table {
        // Few entries read as counts, not as a percentage.
        let entries = if r.entered > 2 {
            format!("{} %", percent(r.from_entries))
        } else {
            let hits = (r.from_entries * r.entered as f64).round() as u64;
            format!("{hits} of {}", r.entered)
        };
        let _ = writeln!(
            t,
            "{} & {}$\\to${} & {} & {} & {} & {:.2} & {:.1} \\\\",
            r.skill,
            r.k,
            r.t,
            r.entered,
            tex(&entries),
            tex(&format!("{} %", percent(r.from_ball))),
            r.joint_gap,
            r.velocity_gap
        );
    }
    t.push_str("\\bottomrule\n\\end{tabular}\n");
    Ok(t)
}

/// `antmaze_probes.tex`, phase 2 on τ_0 … τ_40 ([`PROBES`]), and per reading
/// `\res{antmaze:probe:<arm>-s<seed>:…}`: `skills`, `steps` (phase 2's env steps), `reached`
/// and `episodes` (`--` without a chain); `\res{antmaze:probe:best}` (the most episodes of
/// any) and `\res{antmaze:prefix}` (the prefix's last index, the same in every reading).
fn probes_table(s: &mut String, dev: &Path) -> Result<String> {
    let mut t = String::from(GENERATED);
    t.push_str("\\begin{tabular}{llrrrl}\n\\toprule\n");
    t.push_str(
        "starts and switches & seed & skills & env steps & into $B_\\varepsilon(\\tau_{40})$ & \
         phase~2 ended \\\\\n\\midrule\n",
    );
    let mut best = 0;
    let mut prefix = None;
    for (stem, arm) in PROBES {
        let path = dev.join(format!("handover/out/{stem}.txt"));
        let r = read_chain_reading(&path)?;
        let phase2 = r
            .phase2
            .ok_or_else(|| Error::parse(&path, "no `phase 2:` line"))?;
        match (prefix, r.prefix) {
            (_, None) => return Err(Error::parse(&path, "no prefix of τ in its `phase 1:` line")),
            (Some(p), Some(q)) if p != q => {
                return Err(Error::parse(
                    &path,
                    format!("a prefix to τ_{q}, the others' τ_{p}"),
                ))
            }
            (_, q) => prefix = q,
        }
        let seed = stem.rsplit_once("-s").map_or("", |(_, s)| s);
        let (reached, episodes) = match r.reached {
            Some((k, n)) => {
                best = best.max(k);
                (k.to_string(), n.to_string())
            }
            None => ("--".to_string(), "--".to_string()),
        };
        let into = match r.reached {
            Some(_) => format!("{reached} of {episodes}"),
            None => "no chain".to_string(),
        };
        let _ = writeln!(
            t,
            "{} & {} & {} & {} & {} & {} \\\\",
            tex(arm),
            seed,
            phase2.skills,
            human_steps(phase2.steps as f64),
            tex(&into),
            phase2.outcome
        );
        for (f, v) in [
            ("skills", phase2.skills.to_string()),
            ("steps", human_steps(phase2.steps as f64)),
            ("reached", reached),
            ("episodes", episodes),
        ] {
            def_res(s, "antmaze", &format!("probe:{stem}:{f}"), &v);
        }
    }
    def_res(s, "antmaze", "probe:best", &best.to_string());
    if let Some(p) = prefix {
        def_res(s, "antmaze", "prefix", &p.to_string());
    }
    t.push_str("\\bottomrule\n\\end{tabular}\n");
    Ok(t)
}

/// `antmaze_reach.tex`, the reach probe ([`REACH`]), and per arm
/// `\res{antmaze:reach:<arm>-s<seed>:…}`: `steps`, `best` (%), `bestat`, `lastthree` (mean
/// of the last three evaluations, %); and `\res{antmaze:reach:best}` (the best of any, %).
fn reach_table(s: &mut String, dev: &Path) -> Result<String> {
    let mut t = String::from(GENERATED);
    t.push_str("\\begin{tabular}{lrrrr}\n\\toprule\n");
    t.push_str("learner & env steps & best & at & mean of the last 3 \\\\\n\\midrule\n");
    let mut overall: f64 = 0.0;
    for (stem, arm) in REACH {
        let path = dev.join(format!("reach/{stem}.csv"));
        let rows: Vec<ReachRow> = crate::record::read_records(&path)?;
        if rows.len() < 3 || rows.iter().any(|r| !(0.0..=1.0).contains(&r.success)) {
            return Err(Error::parse(
                &path,
                "fewer than 3 evaluations, or a success outside [0, 1]".to_string(),
            ));
        }
        let best = rows
            .iter()
            .fold(&rows[0], |b, r| if r.success > b.success { r } else { b });
        let last: f64 = rows[rows.len() - 3..]
            .iter()
            .map(|r| r.success)
            .sum::<f64>()
            / 3.0;
        let steps = rows.iter().map(|r| r.steps).max().unwrap_or(0);
        overall = overall.max(best.success);
        let fields = [
            ("steps", human_steps(steps as f64)),
            ("best", percent(best.success)),
            ("bestat", human_steps(best.steps as f64)),
            ("lastthree", percent(last)),
        ];
        let _ = writeln!(
            t,
            "{} & {} & {} & {} & {} \\\\",
            tex(arm),
            fields[0].1,
            tex(&format!("{} %", fields[1].1)),
            fields[2].1,
            tex(&format!("{} %", fields[3].1))
        );
        for (f, v) in fields {
            def_res(s, "antmaze", &format!("reach:{stem}:{f}"), &v);
        }
    }
    def_res(s, "antmaze", "reach:best", &percent(overall));
    t.push_str("\\bottomrule\n\\end{tabular}\n");
    Ok(t)
}

#[cfg(test)]
#[path = "antmaze_tests.rs"]
mod tests;
