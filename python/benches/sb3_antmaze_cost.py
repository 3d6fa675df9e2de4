"""What Stable-Baselines3's SAC+HER costs on gymnasium-robotics' AntMaze (issue 49, point 4:
"what SB3 would cost here, said, not run"): env steps per second of SB3's SAC with
HerReplayBuffer (the defaults python/benches/sb3_pointmaze.py uses: 4 sampled goals, "future",
learning starts 1 000, one gradient step per env step, torch on one CPU thread) on
AntMaze_<Map>-v5 with continuing_task=False and include_cfrc_ext_in_observation=False, reset to
the task's cells. Measures `--steps` env steps after learning starts (the rate of a long run);
prints one line. Needs stable-baselines3, torch, gymnasium-robotics and mujoco==3.17.0.

    python python/benches/sb3_antmaze_cost.py --map UMaze --steps 3000
"""

import argparse
import time

import gymnasium as gym
import gymnasium_robotics
import numpy as np
import torch
from stable_baselines3 import SAC, HerReplayBuffer

gym.register_envs(gymnasium_robotics)


class Cells(gym.Wrapper):
    """Every reset to the task's cells (start and goal each ±1 m around their centres)."""

    def __init__(self, env, start, goal):
        super().__init__(env)
        self.cells = {"reset_cell": np.array(start), "goal_cell": np.array(goal)}

    def reset(self, *, seed=None, options=None):
        return self.env.reset(seed=seed, options=self.cells)


TASKS = {"UMaze": ((1, 1), (3, 1)), "Medium": ((1, 1), (6, 5)), "Large": ((3, 10), (7, 1))}


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--map", default="UMaze", choices=sorted(TASKS))
    p.add_argument("--steps", type=int, default=3000)
    args = p.parse_args()
    torch.set_num_threads(1)
    env = gym.make(f"AntMaze_{args.map}-v5", continuing_task=False, include_cfrc_ext_in_observation=False)
    env = Cells(env, *TASKS[args.map])
    model = SAC(
        "MultiInputPolicy",
        env,
        replay_buffer_class=HerReplayBuffer,
        replay_buffer_kwargs=dict(n_sampled_goal=4, goal_selection_strategy="future"),
        learning_starts=1_000,
        seed=0,
        device="cpu",
        verbose=0,
    )
    model.learn(1_000)
    t = time.perf_counter()
    model.learn(args.steps, reset_num_timesteps=False)
    rate = args.steps / (time.perf_counter() - t)
    print(f"SB3 SAC+HER on AntMaze_{args.map}-v5: {rate:.1f} env steps/s over {args.steps} steps after learning starts")


if __name__ == "__main__":
    main()
