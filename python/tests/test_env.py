"""The maze environment: Gymnasium's own checker, the Rust trajectories, the paper's MDP."""

import subprocess

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import pbcs


def test_gymnasium_check_env_passes():
    for size in (2, 5):
        # Made through the registry, so that the checker also tests the render modes the
        # spec declares.
        env = gym.make("pbcs/ContinuousMaze-v0", size=size, render_mode="rgb_array")
        check_env(env.unwrapped, skip_render_check=False)


def test_registered_and_made_by_gymnasium():
    env = gym.make("pbcs/ContinuousMaze-v0", size=3, layout=1)
    obs, info = env.reset(seed=3)
    assert obs.dtype == np.float32 and obs.tolist() == [0.5, 0.5]
    assert env.unwrapped.maze.size == 3 and env.unwrapped.maze.layout == 1


def test_spaces_are_the_papers():
    env = pbcs.ContinuousMaze(size=5)
    assert env.observation_space.low.tolist() == [0, 0]
    assert env.observation_space.high.tolist() == [5, 5]
    assert np.allclose(env.action_space.low, -0.1) and np.allclose(env.action_space.high, 0.1)


def test_the_2x2_u_shape_rewards_and_terminates():
    env = pbcs.ContinuousMaze(size=2)
    env.reset()
    # Straight up from s_0 hits the wall between cells (0,0) and (0,1): −1, no move.
    for _ in range(5):
        obs, r, term, trunc, info = env.step([0.0, 0.1])
    assert r == -1.0 and info["hit_wall"] and not term
    assert obs[1] < 1.0
    # Reset-anywhere just below the target (0.5, 1.5): one step enters the disc of radius 0.2.
    env.reset(options={"state": (0.5, 1.25)})
    obs, r, term, trunc, info = env.step(np.array([0.0, 0.1], dtype=np.float32))
    assert (r, term, trunc) == (1.0, True, False)


def test_actions_are_clipped_and_episodes_truncated():
    env = pbcs.ContinuousMaze(size=5, max_episode_steps=3)
    env.reset(options={"state": (2.5, 2.5)})
    obs, *_ = env.step([5.0, -5.0])
    assert np.allclose(obs, [2.6, 2.4])
    env.step([0.0, 0.0])
    _, _, term, trunc, _ = env.step([0.0, 0.0])
    assert trunc and not term


def test_render_returns_an_rgb_array():
    env = pbcs.ContinuousMaze(size=3, render_mode="rgb_array", render_size=128)
    env.reset()
    env.step([0.1, 0.0])
    img = env.render()
    assert img.shape == (128, 128, 3) and img.dtype == np.uint8
    assert (img == 0).all(axis=2).any(), "walls are drawn black"


def _rust_trajectory(pbcs_bin, tmp_path, size, layout, seed):
    """phase 1's τ and its actions as `pbcs explore` writes them (trajectory.csv)."""
    out = tmp_path / "explore"
    subprocess.run(
        [pbcs_bin, "explore", "--maze", str(size),
         "--maze-seed", str(layout), "--seed", str(seed), "--quiet", "--out", str(out)],
        check=True,
    )
    lines = (out / "trajectory.csv").read_text().split()
    assert lines[0] == "t,x,y,a0,a1"
    # The last row has no action (empty fields): NaN. f32's shortest decimal, read as a
    # double, converts back to the same float32.
    return np.array([[float(v) if v else np.nan for v in line.split(",")] for line in lines[1:]])


@pytest.mark.parametrize("size,layout,seed", [(2, 0, 0), (5, 0, 1), (7, 2, 3)])
def test_python_steps_reproduce_the_rust_trajectory_exactly(pbcs_bin, tmp_path, size, layout, seed):
    """The Rust binary's τ (`pbcs explore`), replayed action by action through the Python
    environment, gives the same states bit for bit: one step function."""
    rows = _rust_trajectory(pbcs_bin, tmp_path, size, layout, seed)
    states = rows[:, 1:3].astype(np.float32)
    actions = rows[:-1, 3:5].astype(np.float32)
    env = pbcs.ContinuousMaze(size=size, layout=layout, max_episode_steps=10**9)
    # τ is a chain of archived states, each reached from its parent by one step: replay each
    # transition from its own start (reset-anywhere), as phase 1 took it.
    for i, a in enumerate(actions):
        env.reset(options={"state": states[i]})
        obs, r, term, _, _ = env.step(a)
        assert obs.tobytes() == states[i + 1].tobytes(), f"step {i}: {obs} != {states[i + 1]}"
    assert term and r == 1.0, "τ ends in the target disc"
    # explore() in Python returns the same τ.
    found = pbcs.explore(size, layout=layout, seed=seed)
    assert found["tau"].tobytes() == states.tobytes()


def test_pure_step_equals_the_episode_step():
    env = pbcs.ContinuousMaze(size=5, layout=0)
    rng = np.random.default_rng(0)
    env.reset()
    for _ in range(2000):
        s = env.maze.state
        a = rng.uniform(-0.12, 0.12, size=2).astype(np.float32)
        x, y, r, t = env.maze.step_from(s[0], s[1], float(a[0]), float(a[1]))
        obs, r2, t2, trunc, _ = env.step(a)
        assert (np.float32(x), np.float32(y), r, t) == (obs[0], obs[1], r2, t2)
        if t2 or trunc:
            env.reset()


def test_the_agent_never_leaves_the_maze_or_crosses_a_wall():
    env = pbcs.ContinuousMaze(size=5, layout=0, max_episode_steps=10**6)
    walls = np.array(env.maze.walls)
    rng = np.random.default_rng(1)
    obs, _ = env.reset()
    for _ in range(5000):
        obs, *_ = env.step(rng.uniform(-0.1, 0.1, size=2))
        assert (0 <= obs).all() and (obs <= 5).all()
        inside = (walls[:, 0] < obs[0]) & (obs[0] < walls[:, 2]) & (walls[:, 1] < obs[1]) & (obs[1] < walls[:, 3])
        assert not inside.any(), f"{obs} inside a wall"


def test_the_docstring_examples_hold():
    import doctest

    import pbcs.chain
    import pbcs.envs

    for module in (pbcs, pbcs.envs, pbcs.chain):
        failed, _ = doctest.testmod(module)
        assert failed == 0, module.__name__


def test_hit_wall_is_the_steps_own_wall_test():
    # A target disc wide enough (0.45) to reach the wall between cells (0,0) and (0,1)
    # (y = 1 ± 0.05): from inside it, a step down into the wall is paid 1 − 1 = 0, and is
    # still reported as a wall.
    env = pbcs.ContinuousMaze(size=2, target_radius=0.45)
    env.reset(options={"state": (0.5, 1.1)})
    obs, reward, terminated, _, info = env.step([0.0, -0.1])
    assert info["hit_wall"] and reward == 0.0 and terminated
    assert obs.tobytes() == np.array([0.5, 1.1], dtype=np.float32).tobytes()
    env.reset()
    obs, reward, terminated, _, info = env.step([0.1, 0.0])
    assert not info["hit_wall"] and reward == 0.0
