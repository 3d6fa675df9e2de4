"""What the adapter costs per env step over the env's own Python step (issue 80, point 5), on
gymnasium-robotics' PointMaze_UMaze-v3 (or ``--env``), through ``gym.make`` (its wrappers in
both): the median over ``--repeats`` of ``--steps`` steps with one fixed list of random
actions, of

* ``env.step`` alone;
* ``pbcs.Adapter.step`` (the env's step, the observation put position first, success read,
  the whole state read back with ``mj_getState``);
* the core stepping it: phase 1 (``pbcs.explore(env=...)``, the fast preset, returns to
  archived states through ``set_state``) on ``--env`` until its target, env steps per second.

Prints one line per measure, and the ratios. Needs gymnasium-robotics and mujoco.

    python python/benches/adapter_cost.py --steps 5000 --repeats 5
"""

import argparse
import statistics
import time

import gymnasium as gym
import numpy as np

import pbcs


def per_step(step, actions):
    t = time.perf_counter()
    for a in actions:
        step(a)
    return (time.perf_counter() - t) / len(actions)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--env", default="PointMaze_UMaze-v3")
    p.add_argument("--steps", type=int, default=5000)
    p.add_argument("--repeats", type=int, default=5)
    args = p.parse_args()
    if not (1 <= args.steps <= 10**6 and 1 <= args.repeats <= 100):
        p.error("--steps in 1..1e6, --repeats in 1..100")
    import gymnasium_robotics

    gym.register_envs(gymnasium_robotics)
    env = gym.make(args.env, continuing_task=False)
    adapter = pbcs.Adapter(env, slice(0, 2), observation_key="observation")
    actions = np.random.default_rng(0).uniform(-1, 1, (args.steps, 2)).astype(np.float32)
    raw, wrapped = [], []
    for _ in range(args.repeats):
        env.reset(seed=0)
        raw.append(per_step(env.step, actions))
        adapter.set_state(adapter.start_state)
        wrapped.append(per_step(adapter.step, actions))
    raw, wrapped = statistics.median(raw), statistics.median(wrapped)
    core = []
    for _ in range(args.repeats):
        # The same adapter each time (built and checked above, outside the clock).
        t = time.perf_counter()
        found = pbcs.explore(env=adapter, seed=0)
        core.append((time.perf_counter() - t) / found["env_steps"])
    core = statistics.median(core)
    print(f"env.step        {raw * 1e6:8.1f} us per step")
    print(f"Adapter.step    {wrapped * 1e6:8.1f} us per step  ({wrapped / raw:.3f} x env.step)")
    print(f"phase 1 (core)  {core * 1e6:8.1f} us per step  ({core / raw:.3f} x env.step; "
          f"{found['env_steps']} steps)")


if __name__ == "__main__":
    main()
