//! Phase 1 on AntMaze's fixed task (issue 49's development grid): from rest at the start cell's
//! centre until the torso is within 0.45 of the goal cell's centre, the paper's exploration
//! (`phase1::explore`: least-used bin, least-used state, one uniform random action) with bins of
//! `bin_side` metres on the torso's (x, y). `refuse` never archives an ant on its back
//! (`AntMaze::refusing_flipped`); `keep` archives every state.
//!
//! `hold` env steps per random action (1, the paper's, by default; `ExploreConfig::hold`).
//!
//! `antmaze_explore <umaze|open|medium|large> <seed> <keep|refuse> [bin_side 0.5] [budget 2000000]
//! [hold 1]` prints one CSV row: `map,seed,flipped,bin_side,budget,solved,env_steps,archived,bins,
//! archived_flipped,tau_steps,wall_s,hold` (`--header` prints the header).

use anyhow::{bail, Context};
use pbcs::envs::antmaze::AntMaze;
use pbcs::envs::pointmaze::{MapName, PointMap, Resets};
use pbcs::phase1::{explore, ExploreConfig};
use pbcs::rng::{Seeds, Stream};
use strum::IntoEnumIterator;

const HEADER: &str = "map,seed,flipped,bin_side,budget,solved,env_steps,archived,bins,\
                      archived_flipped,tau_steps,wall_s,hold";

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("--header") {
        println!("{HEADER}");
        return Ok(());
    }
    let [map, seed, flipped, rest @ ..] = &args[..] else {
        bail!("usage: antmaze_explore <map> <seed> <keep|refuse> [bin_side] [budget] [hold]");
    };
    let name = MapName::iter()
        .find(|m| <&str>::from(*m).eq_ignore_ascii_case(map))
        .with_context(|| format!("unknown map {map:?}"))?;
    let seed: u64 = seed.parse().context("seed")?;
    let bin_side: f32 = rest
        .first()
        .map_or(Ok(0.5), |b| b.parse())
        .context("bin_side")?;
    let budget: u64 = rest
        .get(1)
        .map_or(Ok(2_000_000), |b| b.parse())
        .context("budget")?;
    let hold: u32 = rest.get(2).map_or(Ok(1), |b| b.parse()).context("hold")?;
    let points = PointMap::named(name);
    let (start, goal) = points.farthest_cells();
    let env = AntMaze::new(points, start, goal, Resets::Fixed)?;
    let env = match flipped.as_str() {
        "keep" => env,
        "refuse" => env.refusing_flipped(),
        other => bail!("flipped: keep or refuse, not {other:?}"),
    };
    let config = ExploreConfig {
        bin_side,
        budget,
        hold,
    };
    pbcs::validate::Check::check(&config)?;
    let mut rng = Seeds::new(seed).stream(Stream::Explore);
    let t = std::time::Instant::now();
    let found = explore(&env, &config, &mut rng, |_, _| {});
    let wall = t.elapsed().as_secs_f64();
    let row = match found {
        Ok(e) => {
            let a = &e.archive;
            let upside_down = (0..a.len() as u32)
                .filter(|&i| a.state(i).up() < 0.0)
                .count();
            let tau = e.trajectory.actions.len();
            format!(
                "true,{},{},{},{upside_down},{tau}",
                e.env_steps,
                a.len(),
                a.bins()
            )
        }
        Err(pbcs::Error::ExplorationBudget { steps }) => format!("false,{steps},,,,"),
        Err(e) => return Err(e.into()),
    };
    println!(
        "{},{seed},{flipped},{bin_side},{budget},{row},{wall:.1},{hold}",
        <&str>::from(name)
    );
    Ok(())
}
