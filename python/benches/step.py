"""Step cost of the Python maze (issue 25's targets: one `step` call <= 2 us; the vectorised
maze >= 10M maze steps per second at N = 1024 on one core), beside a plain numpy
implementation of the same maze (`python/tests/reference_maze.py`: every wall tested for every
env, no grid), whose transitions are also compared with the compiled ones. Prints its numbers; run it with the
package installed: `python python/benches/step.py [--size 15]`."""

import argparse
import sys
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

import pbcs

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from reference_maze import NumpyMaze  # noqa: E402  (the tests' plain numpy maze)


def per_call(fn, calls):
    t = time.perf_counter()
    for _ in range(calls):
        fn()
    return (time.perf_counter() - t) / calls


def main():
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--size", type=int, default=15)
    p.add_argument("--calls", type=int, default=200_000)
    p.add_argument("--num-envs", type=int, default=1024)
    args = p.parse_args()
    rng = np.random.default_rng(0)
    action = np.array([0.03, 0.05], dtype=np.float32)

    env = pbcs.ContinuousMaze(size=args.size, max_episode_steps=10**9)
    env.reset()
    best = min(per_call(lambda: env.step(action), args.calls) for _ in range(3))
    print(f"ContinuousMaze.step (maze {args.size}, numpy action): {best * 1e6:.2f} us per call")

    core = env.maze
    core.reset(None)
    best = min(per_call(lambda: core.step(action), args.calls) for _ in range(3))
    print(f"  the compiled core's step alone: {best * 1e6:.2f} us per call")

    made = gym.make("pbcs/ContinuousMaze-v0", size=args.size, max_episode_steps=None)
    made.reset()
    best = min(per_call(lambda: made.step(action), args.calls // 4) for _ in range(3))
    print(f"  through gym.make's wrappers (order enforcing, env checker): {best * 1e6:.2f} us per call")

    n = args.num_envs
    envs = pbcs.ContinuousMazeVec(n, size=args.size, max_episode_steps=1000)
    envs.reset(seed=0)
    actions = rng.uniform(-0.1, 0.1, size=(n, 2)).astype(np.float32)
    calls = max(1, 4_000_000 // n)
    best = min(per_call(lambda: envs.step(actions), calls) for _ in range(3))
    print(f"ContinuousMazeVec.step, N = {n}: {best * 1e6:.1f} us per call, "
          f"{n / best / 1e6:.1f}M maze steps per second")

    ref = NumpyMaze(env.maze)
    states = rng.uniform(0, args.size, size=(n, 2)).astype(np.float32)
    calls = 50
    numpy_best = min(per_call(lambda: ref.step(states, actions), calls) for _ in range(3))
    print(f"  a plain numpy maze (every wall tested), N = {n}: {numpy_best * 1e6:.0f} us per call, "
          f"{n / numpy_best / 1e6:.2f}M maze steps per second ({numpy_best / best:.0f}x slower)")

    # The same transitions from both: random states and actions (beyond the bound too).
    samples = 20_000
    states = rng.uniform(0, args.size, size=(samples, 2)).astype(np.float32)
    acts = rng.uniform(-0.15, 0.15, size=(samples, 2)).astype(np.float32)
    ours_states, ours_rewards = np.empty_like(states), np.empty(samples, dtype=np.float32)
    for i in range(samples):
        env.reset(options={"state": tuple(states[i])})
        obs, reward, *_ = env.step(acts[i])
        ours_states[i], ours_rewards[i] = obs, reward
    ref_states, ref_rewards, _ = ref.step(states, acts)
    same = (ours_states == ref_states).all(1) & (ours_rewards == ref_rewards)
    print(f"  transitions equal to the compiled maze's: {same.sum()} of {samples} "
          f"(walls hit in {(ours_rewards < 0).sum()})")


if __name__ == "__main__":
    main()
