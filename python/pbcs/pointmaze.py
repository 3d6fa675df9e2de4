"""A PBCS chain of PointMaze judged by gymnasium-robotics itself (issue 35's protocol).

The chain (``pbcs run --env pointmaze_<map>``, or ``--env pointmaze --map FILE`` for a map of
one's own, built with ``--features mujoco``) acts in gymnasium-robotics' own
``PointMaze_<Map>-v3`` (a map of one's own: ``PointMaze_UMaze-v3`` with ``maze_map=`` its rows
and ``max_episode_steps=`` the job's ``pointmaze.time_limit``) with ``continuing_task=False``: every episode
starts from the env's own reset for the task's cells (start and goal drawn within ±0.25 of
the cells' centres, at rest) and runs within the env's time limit; success is the env's
``info["success"]`` on the episode's last step. The chain sees ``obs["observation"]`` =
(x, y, vx, vy) and nothing else: it learned one fixed task, whose success region is the one
every goal the reset may draw agrees on (``pbcs run --env pointmaze_<map>``: within 0.45 of
every goal of the square of half-side 0.25 around the goal cell's centre), so it needs no
goal.

Needs ``gymnasium-robotics`` (and ``mujoco``) beside this package; nothing else here does.
"""

import numpy as np

import gymnasium as gym


class FixedCells(gym.Wrapper):
    """Every reset asks PointMaze for the same start and goal cells (with its own ±0.25
    noise)."""

    def __init__(self, env, start, goal):
        super().__init__(env)
        self.cells = {"reset_cell": np.array(start), "goal_cell": np.array(goal)}

    def reset(self, *, seed=None, options=None):
        return self.env.reset(seed=seed, options=dict(self.cells))


def make_env(chain, **kwargs):
    """gymnasium-robotics' PointMaze of ``chain``'s task, ``continuing_task=False``, resetting
    to its cells (``kwargs`` go to ``gym.make``)."""
    task = chain.pointmaze
    if task is None:
        raise ValueError(f"a chain of env = {chain.env!r}, not of PointMaze")
    try:
        import gymnasium_robotics
    except ImportError as e:
        raise ImportError(
            "pbcs.pointmaze needs gymnasium-robotics: pip install gymnasium-robotics==1.4.2"
        ) from e
    gym.register_envs(gymnasium_robotics)
    gym_id, start, goal, time_limit = task
    kwargs.setdefault("continuing_task", False)
    own = chain.pointmaze_map
    if own is not None:
        # A map of one's own: the same env class on those rows, with the job's time limit.
        kwargs.setdefault("maze_map", own)
        kwargs.setdefault("max_episode_steps", time_limit)
    return FixedCells(gym.make(gym_id, **kwargs), start, goal)


def evaluate(chain, episodes=100, seed=0, env=None):
    """``episodes`` episodes of ``chain`` in gymnasium-robotics (:func:`make_env`), the first
    reset seeded with ``seed``, each the chain's one rollout (:meth:`pbcs.Chain.rollout`:
    ``info["success"]`` on the last step, within the env's time limit). Returns
    ``successes``, ``episodes`` and each episode's ``success`` and ``steps``."""
    if episodes < 1:
        raise ValueError(f"invalid `episodes`: must be at least 1, got {episodes}")
    own = env is None
    if own:
        env = make_env(chain)
    # The env's own time limit ends each episode (the rollout's cap never comes first).
    spec = getattr(env, "spec", None)
    limit = (spec.max_episode_steps if spec and spec.max_episode_steps else None) or chain.pointmaze[3]
    runs = [chain.rollout(env=env, max_steps=limit, seed=seed if e == 0 else None)
            for e in range(episodes)]
    success = [r["success"] for r in runs]
    steps = [r["steps"] for r in runs]
    if own:
        env.close()
    return {
        "successes": int(sum(success)),
        "episodes": episodes,
        "success": np.array(success),
        "steps": np.array(steps),
    }
