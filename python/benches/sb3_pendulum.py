"""Stable-Baselines3's TD3 or SAC on gymnasium's Pendulum-v1 with RL-Zoo's tuned settings, the
outside anchor for our learners (issues 25 and 48); ours is `cargo run --release --example
pendulum -- [td3|sac]` on the Rust port of the same task (its steps equal gymnasium's:
python/tests/test_pendulum.py).

RL-Zoo's TD3 for Pendulum-v1: 20 000 steps, γ = 0.98, replay 200 000, 10 000 warm-up steps,
learning rate 1e-3, networks [400, 300], Gaussian noise σ = 0.1, train_freq [1, "episode"],
gradient_steps −1 (SB3's defaults otherwise: batch 256, τ = 0.005, policy delay 2, target
smoothing 0.2 / 0.5). Each seed's final deterministic policy: mean return over 10 episodes
(RL-Zoo's benchmark, one agent over 750 episodes: −151.9 ± 90.2,
results/outside/pendulum/published.toml). One torch thread per run.

    python python/benches/sb3_pendulum.py --seeds 0-9 --out results/outside/pendulum/sb3
    python python/benches/sb3_pendulum.py --algo sac --seeds 0-9 --out results/outside/pendulum/sb3_sac

RL-Zoo's SAC for Pendulum-v1 (hyperparams/sac.yml): 20 000 steps, learning rate 1e-3, SB3's SAC
defaults otherwise ([256, 256], γ = 0.99, τ = 0.005, batch 256, replay 10⁶, 100 warm-up steps,
one update per step, ent_coef "auto"). Judged as TD3: the final deterministic policy's mean
return over 10 episodes.

Needs stable-baselines3 (not part of CI). A finished seed's row is skipped on re-run.
"""

import argparse
import time
from pathlib import Path

from common import write_atomic
import gymnasium as gym
import numpy as np




def run(seed, out, algo="td3"):
    import stable_baselines3
    import torch
    from stable_baselines3 import SAC

    row = out / f"s{seed}.csv"
    if row.exists():
        return row.read_text()
    torch.set_num_threads(1)
    env = gym.make("Pendulum-v1")
    if algo == "sac":
        model = SAC("MlpPolicy", env, learning_rate=1e-3, seed=seed, device="cpu", verbose=0)
    else:
        model = td3(env, seed)
    return finish(model, seed, row, algo, stable_baselines3, torch)


def td3(env, seed):
    from stable_baselines3 import TD3
    from stable_baselines3.common.noise import NormalActionNoise

    return TD3(
        "MlpPolicy",
        env,
        learning_rate=1e-3,
        buffer_size=200_000,
        learning_starts=10_000,
        gamma=0.98,
        train_freq=(1, "episode"),
        gradient_steps=-1,
        action_noise=NormalActionNoise(mean=np.zeros(1), sigma=0.1 * np.ones(1)),
        policy_kwargs=dict(net_arch=[400, 300]),
        seed=seed,
        device="cpu",
        verbose=0,
    )


def finish(model, seed, row, algo, stable_baselines3, torch):
    from stable_baselines3.common.evaluation import evaluate_policy

    clock = time.perf_counter()
    model.learn(total_timesteps=20_000)
    seconds = time.perf_counter() - clock
    eval_env = gym.make("Pendulum-v1")
    eval_env.reset(seed=10_000 + seed)
    mean, std = evaluate_policy(model, eval_env, n_eval_episodes=10, deterministic=True)
    text = (
        "library,algo,seed,steps,eval_episodes,mean_return\n"
        f"sb3-{stable_baselines3.__version__},{algo},{seed},20000,10,{mean:.5f}\n"
    )
    write_atomic(
        row.with_suffix(".timing.toml"),
        f"# wall clock of model.learn (not deterministic)\nwall_seconds = {seconds:.3f}\n"
        f"torch = \"{torch.__version__}\"\ntorch_threads = {torch.get_num_threads()}\n",
    )
    write_atomic(row, text)
    return text


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--seeds", default="0-9", help="a seed or a range, e.g. 0-9")
    p.add_argument("--algo", choices=["td3", "sac"], default="td3")
    p.add_argument("--out", type=Path, help="default: results/outside/pendulum/sb3 (td3), sb3_sac (sac)")
    args = p.parse_args()
    out = args.out or Path("results/outside/pendulum/" + ("sb3_sac" if args.algo == "sac" else "sb3"))
    a, _, b = args.seeds.partition("-")
    for seed in range(int(a), int(b or a) + 1):
        print(run(seed, out, args.algo).splitlines()[1], flush=True)


if __name__ == "__main__":
    main()
