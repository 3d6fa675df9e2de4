//! Whether an AntMaze chain's skills carry the ant when run in turn: a diagnosis for issue 49
//! (`results/dev/issue49/handover/`).
//!
//! ```text
//! cargo run --release --features mujoco --example antmaze_chain -- handover RUN_DIR [EPISODES] [BALL]
//! cargo run --release --features mujoco --example antmaze_chain -- prefix JOB.toml SEED N [EPISODES] [BALL] [ANGLE SPEED]
//! ```
//!
//! `handover` reads a `pbcs run` folder (its `chain/` and the job in it) and makes τ again by
//! phase 1 from the job's seed, as the run made it. `prefix` runs phase 2 of JOB on τ_0 … τ_N
//! alone (the first N + 1 states of the job's τ; the last skill aims at B_ε(τ_N),
//! `phase2.last_goal = "ball"`, and every state keeps the task's goal, which no state near τ_N
//! reaches, so the environment's success never ends an episode), with the job's chain
//! verification and repairs, and then reads the chain it made; there, an episode succeeds when
//! the torso enters B_ε(τ_N), and the chain runs as its verification runs it (an episode also
//! ends when one skill has acted `phase2.max_steps` times without handing over). With ANGLE and SPEED,
//! Backplay's starts are jittered balls ([`Jittered`]: τ_K's whole state, the torso moved up to
//! ε, each hinge angle moved up to ANGLE rad and each hinge velocity up to SPEED rad/s,
//! uniformly) in place of the job's.
//!
//! Both then run the chain EPISODES (20) times from starts in B_ε(τ_0) drawn as training drew
//! its balls, each skill taking over as the chain's execution hands over, and print which
//! skills each episode reached. For each skill some episode entered, the skill alone runs to its
//! target (the next skill's ball, or for the last, the episode's success) within its test's
//! step limit (`phase2.max_steps`): from each state where the chain handed it over
//! (`from_entries`), and from BALL (50) starts of each kind: B_ε(τ_K) as its training drew them
//! (`from_ball`), the same with the ant at rest (`from_ball_at_rest`: velocities and warm start
//! zero), and the same with no action at all (`coasting`: zero torques, τ_K's momentum alone).
//! `joint_gap` and `velocity_gap` are the mean distances of the entries' hinge angles (rad) and
//! hinge velocities (rad/s) from τ_K's; `flipped` counts entries with the torso upside down.
use anyhow::{bail, Context};
use pbcs::config::{Located, PbcsJob};
use pbcs::env::Env;
use pbcs::env::SampleBall;
use pbcs::envs::antmaze::{AntMaze, AntState};
use pbcs::envs::Built;
use pbcs::phase1::{explore, Exploration};
use pbcs::phase2::goal::dist;
use pbcs::phase2::{
    chain_skills, phase2_trajectory, ArchiveStarts, Ball, LastGoal, Phase2Inputs, SkillChain,
    StartMode,
};
use pbcs::rng::{Seeds, Stream};

/// Observation slots of the ant's hinge angles and their velocities (x, y, then qpos[2..], qvel).
const JOINTS: std::ops::Range<usize> = 7..15;
const JOINT_VELOCITIES: std::ops::Range<usize> = 21..29;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let number = |i: usize, default: usize, what: &str| -> anyhow::Result<usize> {
        args.get(i)
            .map_or(Ok(default), |s| s.parse())
            .with_context(|| what.to_string())
    };
    let kernel = pbcs::nn::kernel::Kernel::from_env()?;
    match args.first().map(String::as_str) {
        Some("handover") => {
            let run = std::path::Path::new(args.get(1).context("RUN_DIR")?);
            let (job, chain) = pbcs::runs::load_saved_job(&run.join("chain"), kernel)?;
            let env = ant(&job)?;
            let (found, tau) = trajectory(&env, &job)?;
            println!("phase 1: {} env steps, |τ| = {}", found.env_steps, tau.len());
            let (episodes, ball_n) = (number(2, 20, "EPISODES")?, number(3, 50, "BALL")?);
            read_chain(&env, &job, &tau, &chain, None, episodes, ball_n);
        }
        Some("prefix") => {
            let path = std::path::Path::new(args.get(1).context("JOB.toml")?);
            let mut job: PbcsJob = pbcs::config::load(path)?;
            job.seed = number(2, 0, "SEED")? as u64;
            let n = number(3, 0, "N")?;
            job.phase2.last_goal = LastGoal::Ball;
            let env = ant(&job)?;
            let (found, mut tau) = trajectory(&env, &job)?;
            let steps = found.env_steps;
            if n == 0 || n >= tau.len() {
                bail!("N must lie in 1..{} (τ has {} states)", tau.len() - 1, tau.len());
            }
            tau.truncate(n + 1);
            let end = tau[n].xy();
            println!("phase 1: {steps} env steps; τ_0 … τ_{n}, τ_{n} at ({:.3}, {:.3})", end[0], end[1]);
            let clock = std::time::Instant::now();
            // Backplay's starts from phase 1's archive where the job asks.
            let archived = (job.phase2.start == StartMode::Archive)
                .then(|| ArchiveStarts::new(&env, &found.archive, job.phase2.epsilon));
            let jittered = match (args.get(6), args.get(7)) {
                (Some(a), Some(v)) => Some(Jittered {
                    env: &env,
                    angle: a.parse().context("ANGLE")?,
                    speed: v.parse().context("SPEED")?,
                }),
                _ => None,
            };
            let starts: Option<&dyn SampleBall<AntState>> = match (&jittered, &archived) {
                (Some(j), _) => {
                    // The starts slot is the archive's: the job's start mode must ask for it.
                    job.phase2.start = StartMode::Archive;
                    println!("Backplay's starts: jittered, ±{} rad, ±{} rad/s", j.angle, j.speed);
                    Some(j)
                }
                (None, Some(a)) => Some(a),
                (None, None) => None,
            };
            let seeds = Seeds::new(job.seed);
            let ready = job.phase2.ready(&env)?;
            let inputs = Phase2Inputs::new(&env, &tau, ready, &job.learner, &seeds, kernel)
                .after(steps)
                .with_starts(starts);
            let out = chain_skills(inputs, |n, p| {
                let s = clock.elapsed().as_secs_f64();
                eprintln!(
                    "[{s:.0} s] problem {n} K {} T {} {:?} {:.2} ({} train, {} test)",
                    p.k, p.t, p.kind, p.success, p.steps.train, p.steps.test
                );
            })?;
            println!(
                "phase 2: {:?}, {} skills, {} training and {} test env steps, {:.0} s",
                out.failure,
                out.chain.skills.len(),
                out.steps.train,
                out.steps.test,
                clock.elapsed().as_secs_f64()
            );
            for row in out.trace.iter().filter(|r| r.event.name() == "chain_verify") {
                println!("chain verification: skill {} blamed, success {:.2}", row.skill, row.success);
            }
            if !out.chain.skills.is_empty() {
                let end = Ball::new(end.map(|x| x as f32).to_vec(), job.phase2.epsilon);
                let (episodes, ball_n) = (number(4, 20, "EPISODES")?, number(5, 50, "BALL")?);
                read_chain(&env, &job, &tau, &out.chain, Some(&end), episodes, ball_n);
            }
        }
        _ => bail!("usage: antmaze_chain handover RUN_DIR [EPISODES] [BALL] | prefix JOB.toml SEED N [EPISODES] [BALL] [ANGLE SPEED]"),
    }
    Ok(())
}

/// Ball starts with the legs moved too: [`AntMaze`]'s own ball (τ_K's whole state, the torso
/// moved), then each hinge angle (qpos 7..15) plus U(−angle, angle) rad and each hinge velocity
/// (qvel 6..14) plus U(−speed, speed) rad/s. Torso height, orientation and velocity stay τ_K's.
struct Jittered<'e> {
    env: &'e AntMaze,
    angle: f64,
    speed: f64,
}

impl SampleBall<AntState> for Jittered<'_> {
    fn sample_ball(&self, center: &AntState, radius: f32, rng: &mut pbcs::rng::Rng) -> AntState {
        use rand::Rng as _;
        let ball = self.env.ball_starts().expect("AntMaze samples balls");
        let mut s = ball.sample_ball(center, radius, rng);
        for q in &mut s.qpos[7..15] {
            *q += rng.random_range(-self.angle..=self.angle);
        }
        for v in &mut s.qvel[6..14] {
            *v += rng.random_range(-self.speed..=self.speed);
        }
        s
    }
}

fn ant(job: &PbcsJob) -> anyhow::Result<AntMaze> {
    match job.env_spec().build()? {
        Built::AntMaze(env) => Ok(env),
        _ => bail!("an AntMaze job, not {}", job.env.name()),
    }
}

/// τ as the job's run made it: phase 1 from the job's seed, then phase 2's trajectory.
fn trajectory(
    env: &AntMaze,
    job: &PbcsJob,
) -> anyhow::Result<(Exploration<AntState>, Vec<AntState>)> {
    let seeds = Seeds::new(job.seed);
    let found = explore(
        env,
        &job.explore,
        &mut seeds.stream(Stream::Explore),
        |_, _| {},
    )?;
    let tau = phase2_trajectory(env, &found.trajectory, &job.phase2)?.states;
    Ok((found, tau))
}

/// The chain from B_ε(τ_0), and each entered skill alone (the module's doc).
///
/// `end`: a prefix's target, B_ε(τ_N) (`None`: the environment's success, as `pbcs eval`).
fn read_chain(
    env: &AntMaze,
    job: &PbcsJob,
    tau: &[AntState],
    chain: &SkillChain,
    end: Option<&Ball>,
    episodes: usize,
    ball_n: usize,
) {
    let obs = |s: &AntState| {
        let mut o = vec![0.0; env.obs_dim()];
        env.observe(s, &mut o);
        o
    };
    let eps = job.phase2.epsilon;
    let ball = env.ball_starts().expect("AntMaze samples balls");
    let mut rng = Seeds::new(job.seed).stream(Stream::ChainVerify);
    let n = chain.skills.len();
    let mut entries: Vec<Vec<AntState>> = vec![Vec::new(); n];
    let mut stalled = vec![0usize; n];
    let limit = job.phase2.max_steps;
    // The step where a rollout first reaches the target: the environment's success (its last
    // state), or entering `end`.
    let reached = |states: &[AntState], success: bool| -> Option<usize> {
        match end {
            Some(b) => states.iter().position(|s| b.contains(&obs(s))),
            None => success.then(|| states.len() - 1),
        }
    };
    let (mut successes, mut upright) = (0, 0);
    for e in 0..episodes {
        let start = ball.sample_ball(&tau[0], eps, &mut rng);
        let r = match end {
            None => chain.run(env, start, job.phase2.eval_max_steps),
            Some(_) => chain.run_limited(env, start, job.phase2.eval_max_steps, Some(limit)),
        };
        let done = reached(&r.states, r.success);
        let acted = done.unwrap_or(r.skill_used.len());
        let mut seq = Vec::new();
        let mut cur = None;
        for (j, &i) in r.skill_used[..acted].iter().enumerate() {
            if cur != Some(i) {
                entries[i].push(r.states[j]);
                seq.push(format!("{i}@{j}"));
                cur = Some(i);
            }
        }
        let last = &r.states[acted];
        match (done, cur) {
            (Some(_), _) => {
                successes += 1;
                upright += usize::from(last.up() >= 0.0);
            }
            (None, Some(i)) => stalled[i] += 1,
            (None, None) => {}
        }
        let o = obs(last);
        println!(
            "episode {e}: {} in {acted} steps, ends at ({:.2}, {:.2}) up {:.2}; skills {}",
            if done.is_some() { "success" } else { "failure" },
            o[0],
            o[1],
            last.up(),
            seq.join(" ")
        );
    }
    println!(
        "chain from B_eps(tau_0): {successes} of {episodes} episodes reach the target \
         ({upright} of them upright there)"
    );
    println!(
        "skill,K,T,entered,stalled,flipped,from_entries,from_ball,from_ball_at_rest,coasting,\
         joint_gap,velocity_gap"
    );
    for i in (0..n).filter(|&i| !entries[i].is_empty()) {
        // Skill i alone (with the next skill's ball as its target) reaches its target.
        let alone = SkillChain {
            skills: chain.skills[i..(i + 2).min(n)].to_vec(),
            kernel: chain.kernel,
        };
        // Reached: the next skill's ball, or the chain's own target on the way.
        let reaches = |start: AntState| -> bool {
            let r = alone.run_limited(env, start, limit + 1, Some(limit));
            reached(&r.states, r.success).is_some() || (i + 1 < n && r.skill_used.contains(&1))
        };
        let arrived = |o: &[f32], reward: f32| {
            reward > 0.0
                || end.is_some_and(|b| b.contains(o))
                || chain
                    .skills
                    .get(i + 1)
                    .is_some_and(|next| next.activation.contains(o))
        };
        let k = chain.skills[i].start_index;
        let centre = obs(&tau[k]);
        let share = |count: usize, of: usize| count as f32 / of as f32;
        let from_entries = entries[i].iter().filter(|s| reaches(**s)).count();
        let from_ball = (0..ball_n)
            .filter(|_| reaches(ball.sample_ball(&tau[k], eps, &mut rng)))
            .count();
        let at_rest = (0..ball_n)
            .filter(|_| {
                let mut s = ball.sample_ball(&tau[k], eps, &mut rng);
                s.qvel = [0.0; 14];
                s.warmstart = [0.0; 14];
                reaches(s)
            })
            .count();
        let coasting = (0..ball_n)
            .filter(|_| {
                let mut s = ball.sample_ball(&tau[k], eps, &mut rng);
                (0..limit).any(|_| {
                    let step = env.step(&s, &[0.0; 8]);
                    s = step.state;
                    arrived(&obs(&s), step.reward)
                })
            })
            .count();
        let flipped = entries[i].iter().filter(|s| s.up() < 0.0).count();
        let gap = |r: std::ops::Range<usize>| {
            entries[i]
                .iter()
                .map(|s| dist(&obs(s)[r.clone()], &centre[r.clone()]))
                .sum::<f32>()
                / entries[i].len() as f32
        };
        println!(
            "{i},{k},{},{},{},{flipped},{:.2},{:.2},{:.2},{:.2},{:.2},{:.2}",
            chain.skills[i].target_index,
            entries[i].len(),
            stalled[i],
            share(from_entries, entries[i].len()),
            share(from_ball, ball_n),
            share(at_rest, ball_n),
            share(coasting, ball_n),
            gap(JOINTS),
            gap(JOINT_VELOCITIES)
        );
    }
}
