"""A PBCS chain of AntMaze judged by gymnasium-robotics itself (issue 49, point 3).

The chain (``pbcs run --env antmaze_<map>``, or ``--env antmaze --map FILE`` for a map of one's
own, built with ``--features mujoco``) acts in gymnasium-robotics' own ``AntMaze_<Map>-v5``
(a map of one's own: ``AntMaze_UMaze-v5`` with ``maze_map=`` its rows and
``max_episode_steps=`` the job's ``pointmaze.time_limit``) with ``continuing_task=False`` and
``include_cfrc_ext_in_observation=False``: every episode starts from the env's own reset of the
task's cells (start and goal each drawn within ±1 m of its cell's centre, the ant at rest) and
runs within the env's time limit; success is the env's ``info["success"]`` on the episode's last
step. The chain sees what it learned on, the torso's (x, y) (``achieved_goal``) followed by the
env's 27-number ``observation``. A chain built with ``phase2.last_goal = "drawn"`` learned its
last skill toward goals drawn as the reset draws them and is shown the goal the reset drew
(``desired_goal``); any other learned one fixed goal, the goal cell's centre, and is not (the
drawn goal may lie up to 1.4 m from that centre).

Needs ``gymnasium-robotics`` (and ``mujoco``) beside this package; nothing else here does.
"""

import numpy as np

import gymnasium as gym

from . import _judge
from ._judge import task_env

__all__ = ["AntObservation", "make_env", "evaluate"]


class AntObservation(gym.ObservationWrapper):
    """The dict observation with ``observation`` = ``achieved_goal`` ++ ``observation`` (29
    numbers): the torso's (x, y), then the env's 27, as ``pbcs``'s AntMaze observes."""

    def __init__(self, env):
        super().__init__(env)
        spaces = dict(env.observation_space.spaces)
        low = np.concatenate([spaces["achieved_goal"].low, spaces["observation"].low])
        high = np.concatenate([spaces["achieved_goal"].high, spaces["observation"].high])
        spaces["observation"] = gym.spaces.Box(low, high, dtype=np.float64)
        self.observation_space = gym.spaces.Dict(spaces)

    def observation(self, obs):
        obs = dict(obs)
        obs["observation"] = np.concatenate([obs["achieved_goal"], obs["observation"]])
        return obs


def make_env(chain, **kwargs):
    """gymnasium-robotics' AntMaze of ``chain``'s task, ``continuing_task=False`` and the
    27-number observation, resetting to its cells, observed as :class:`AntObservation`
    (``kwargs`` go to ``gym.make``)."""
    kwargs.setdefault("include_cfrc_ext_in_observation", False)
    return AntObservation(task_env(chain, chain.antmaze, "pbcs.antmaze", **kwargs))


def evaluate(chain, episodes=100, seed=0, env=None):
    """``episodes`` episodes of ``chain`` in gymnasium-robotics (:func:`make_env`), the first
    reset seeded with ``seed``, each the chain's one rollout (:meth:`pbcs.Chain.rollout`:
    ``info["success"]`` on the last step, within the env's time limit). Returns
    ``successes``, ``episodes`` and each episode's ``success`` and ``steps``."""
    return _judge.evaluate(chain, make_env, lambda: chain.antmaze[3], episodes, seed, env)
