"""The Rust port of Pendulum-v1 (pbcs::envs::pendulum, the task our learners are checked on against
Stable-Baselines3) steps exactly as gymnasium's own, for the same states and actions."""

import gymnasium as gym
import numpy as np

from pbcs import _pbcs


def test_pendulum_port_steps_equal_gymnasiums():
    env = gym.make("Pendulum-v1").unwrapped
    rng = np.random.default_rng(0)
    env.reset(seed=0)
    for i in range(3000):
        if i % 200 == 0:  # a fresh start now and then, otherwise follow the trajectory
            env.state = np.array([rng.uniform(-10, 10), rng.uniform(-8, 8)])
        th, thdot = env.state
        u = np.array([rng.uniform(-3, 3)], dtype=np.float32)  # beyond ±2: clipped
        (th2, thdot2), reward, obs = _pbcs.pendulum_step(float(th), float(thdot), float(u[0]))
        gym_obs, gym_reward, terminated, truncated, _ = env.step(u)
        assert (th2, thdot2) == tuple(env.state), f"step {i}"
        assert np.float32(gym_reward) == np.float32(reward), f"step {i}"
        assert np.array(obs, dtype=np.float32).tobytes() == gym_obs.tobytes(), f"step {i}"
        assert not terminated and not truncated
