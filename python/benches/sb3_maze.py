"""The outside check of our learners (issue 25): Stable-Baselines3's DDPG and TD3 on our 2×2
maze through the Python package, with the settings of our baselines, and the update cost per
environment step of SB3 and of ours measured on this machine.

Settings (experiments/baseline.toml): networks 64×64 (ReLU), learning rates 1e-3 for actor
and critic, γ = 0.99, τ = 0.005, batch 64, replay 1M, Gaussian action noise σ = 0.1 in the
learner's [−1, 1] action space, 10 000 uniformly random warm-up steps, one gradient step per
environment step, episodes of at most 1000 steps. SB3's actions live in [−1, 1]; the maze's
are [−0.1, 0.1] (RescaleAction), exactly as our learners scale them. TD3: two critics, policy
delay 2, target smoothing 0.2 clipped at 0.5 (SB3's defaults and ours).

Each run is judged as our table judges its vanilla runs at the same step count: one greedy
episode from s_0 (success = the target reached within 1000 steps); and, beside it, PBCS's
protocol (100 greedy episodes from the start states of `pbcs.evaluation_starts` for the run
seed, solved at >= 95 %). One torch thread per run (ours are single-threaded too).

    python python/benches/sb3_maze.py --algo ddpg --seeds 0-9 --steps 300000 --out results/outside/sb3
    python python/benches/sb3_maze.py --timing        # update cost per step: SB3 and ours,
                                                      # into results/outside/update_cost.csv

Needs stable-baselines3 (and torch) beside this package; not part of CI. Each run writes
`<out>/<algo>-maze2/s<seed>.csv` (atomically: a finished run is skipped on re-run) and its
wall clock beside it in `s<seed>.timing.toml`.
"""

import argparse
import os
import platform
import subprocess
import tempfile
import time
from pathlib import Path

from common import write_atomic
import gymnasium as gym
import numpy as np

import pbcs

SETTINGS = dict(
    learning_rate=1e-3,
    buffer_size=1_000_000,
    learning_starts=10_000,
    batch_size=64,
    tau=0.005,
    gamma=0.99,
    train_freq=1,
    gradient_steps=1,
)


def make_env(seed):
    env = gym.make("pbcs/ContinuousMaze-v0", size=2, max_episode_steps=None)
    env = gym.wrappers.RescaleAction(env, -1.0, 1.0)
    env.reset(seed=seed)
    return env


def make_model(algo, seed):
    import torch
    from stable_baselines3 import DDPG, TD3
    from stable_baselines3.common.noise import NormalActionNoise

    torch.set_num_threads(1)
    noise = NormalActionNoise(mean=np.zeros(2), sigma=0.1 * np.ones(2))
    cls = {"ddpg": DDPG, "td3": TD3}[algo]
    return cls(
        "MlpPolicy",
        make_env(seed),
        action_noise=noise,
        policy_kwargs=dict(net_arch=[64, 64]),
        seed=seed,
        device="cpu",
        verbose=0,
        **SETTINGS,
    )


def greedy(model, start=None, max_steps=1000):
    """One deterministic episode of the trained policy; True if it reaches the target."""
    env = pbcs.ContinuousMaze(size=2, max_episode_steps=max_steps)
    obs, _ = env.reset(options=None if start is None else {"state": tuple(start)})
    for _ in range(max_steps):
        action, _ = model.predict(obs, deterministic=True)
        obs, reward, terminated, truncated, _ = env.step(np.asarray(action) * 0.1)
        if terminated:
            return reward > 0
        if truncated:
            return False
    return False




def run(algo, seed, steps, out):
    import stable_baselines3
    import torch

    row = out / f"{algo}-maze2" / f"s{seed}.csv"
    if row.exists():
        return row.read_text()
    model = make_model(algo, seed)
    clock = time.perf_counter()
    model.learn(total_timesteps=steps)
    seconds = time.perf_counter() - clock
    solved_s0 = greedy(model)
    starts = pbcs.evaluation_starts(2, seed=seed, episodes=100)
    wins = sum(greedy(model, s, max_steps=5000) for s in starts)
    text = (
        "library,algo,seed,steps,solved_s0,protocol_successes,protocol_episodes\n"
        f"sb3-{stable_baselines3.__version__},{algo},{seed},{steps},"
        f"{str(bool(solved_s0)).lower()},{wins},{len(starts)}\n"
    )
    write_atomic(
        row.with_suffix(".timing.toml"),
        f"# wall clock of model.learn (not deterministic)\nwall_seconds = {seconds:.3f}\n"
        f"steps_per_second = {steps / seconds:.0f}\ntorch = \"{torch.__version__}\"\n"
        f"torch_threads = {torch.get_num_threads()}\n",
    )
    write_atomic(row, text)
    return text


def machine():
    """This machine in words, as the Rust core's `record::machine` writes it."""
    model = platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{model}, {os.cpu_count()} cores"


def timing(steps, pbcs_bin, out):
    """Update cost per environment step after warm-up: SB3 (this process) and ours (`pbcs
    train`: a run of 10 000 + `steps` steps less a run of the 10 000 warm-up steps), the same
    steps on the same machine. Writes `<out>/update_cost.csv` (wall clock)."""
    import stable_baselines3

    lines = ["algo,library,us_per_step,steps,machine"]
    for algo in ("ddpg", "td3"):
        model = make_model(algo, 0)
        model.learn(total_timesteps=10_000)  # warm-up: random actions, no update
        clock = time.perf_counter()
        model.learn(total_timesteps=steps, reset_num_timesteps=False)
        sb3 = (time.perf_counter() - clock) / steps
        with tempfile.TemporaryDirectory() as tmp:
            for total in (10_000, 10_000 + steps):
                clock = time.perf_counter()
                subprocess.run(
                    [pbcs_bin, "train", "--maze", "2", "--seed", "0", "--algo", algo,
                     "--steps", str(total), "--quiet", "--out", f"{tmp}/{total}"],
                    check=True, capture_output=True,
                )
                if total == 10_000:
                    base = time.perf_counter() - clock
                else:
                    ours = (time.perf_counter() - clock - base) / steps
        print(f"{algo}: SB3 {sb3 * 1e6:.0f} us per step (one update each), ours {ours * 1e6:.0f} us "
              f"per step: {sb3 / ours:.1f}x")
        lines.append(f'{algo},sb3-{stable_baselines3.__version__},{sb3 * 1e6:.1f},{steps},"{machine()}"')
        lines.append(f'{algo},pbcs,{ours * 1e6:.1f},{steps},"{machine()}"')
    write_atomic(out / "update_cost.csv", "\n".join(lines) + "\n")


def seeds_of(text):
    a, _, b = text.partition("-")
    return range(int(a), int(b or a) + 1)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--algo", choices=["ddpg", "td3"], default="ddpg")
    p.add_argument("--seeds", default="0-9", help="a seed or a range, e.g. 0-9")
    p.add_argument("--steps", type=int, default=300_000)
    p.add_argument("--out", type=Path, default=Path("results/outside/sb3"))
    p.add_argument("--timing", action="store_true", help="measure the update cost per step only")
    p.add_argument("--timing-steps", type=int, default=5_000)
    p.add_argument("--pbcs", default="target/release/pbcs", help="the pbcs command (for --timing)")
    args = p.parse_args()
    if args.timing:
        timing(args.timing_steps, args.pbcs, args.out.parent)
        return
    for seed in seeds_of(args.seeds):
        print(run(args.algo, seed, args.steps, args.out).splitlines()[1], flush=True)


if __name__ == "__main__":
    main()
