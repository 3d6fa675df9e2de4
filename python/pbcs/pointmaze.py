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

from . import _judge
from ._judge import FixedCells, task_env

__all__ = ["FixedCells", "make_env", "evaluate"]


def make_env(chain, **kwargs):
    """gymnasium-robotics' PointMaze of ``chain``'s task, ``continuing_task=False``, resetting
    to its cells (``kwargs`` go to ``gym.make``)."""
    return task_env(chain, chain.pointmaze, "pbcs.pointmaze", **kwargs)


def evaluate(chain, episodes=100, seed=0, env=None):
    """``episodes`` episodes of ``chain`` in gymnasium-robotics (:func:`make_env`), the first
    reset seeded with ``seed``, each the chain's one rollout (:meth:`pbcs.Chain.rollout`:
    ``info["success"]`` on the last step, within the env's time limit). Returns
    ``successes``, ``episodes`` and each episode's ``success`` and ``steps``."""
    return _judge.evaluate(chain, make_env, lambda: chain.pointmaze[3], episodes, seed, env)
