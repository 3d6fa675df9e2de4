"""What the judges in gymnasium-robotics share (:mod:`pbcs.pointmaze`, :mod:`pbcs.antmaze`):
the env of a chain's task, reset to its cells, and the episodes played there."""

import numpy as np

import gymnasium as gym


class FixedCells(gym.Wrapper):
    """Every reset asks the maze for the same start and goal cells (with its own noise)."""

    def __init__(self, env, start, goal):
        super().__init__(env)
        self.cells = {"reset_cell": np.array(start), "goal_cell": np.array(goal)}

    def reset(self, *, seed=None, options=None):
        return self.env.reset(seed=seed, options=dict(self.cells))


def task_env(chain, task, module, **kwargs):
    """gymnasium-robotics' env of ``task`` (``(gym_id, start, goal, time_limit)``, a chain's
    ``pointmaze`` or ``antmaze``), ``continuing_task=False``, resetting to its cells; a map of
    one's own made with ``maze_map=`` its rows and ``max_episode_steps=`` the time limit.
    ``module`` names the judge in messages; ``kwargs`` go to ``gym.make``."""
    if task is None:
        raise ValueError(f"a chain of env = {chain.env!r}, not one {module} judges")
    try:
        import gymnasium_robotics
    except ImportError as e:
        raise ImportError(
            f"{module} needs gymnasium-robotics: pip install gymnasium-robotics==1.4.2"
        ) from e
    gym.register_envs(gymnasium_robotics)
    gym_id, start, goal, time_limit = task
    kwargs.setdefault("continuing_task", False)
    own = chain.pointmaze_map
    if own is not None:
        kwargs.setdefault("maze_map", own)
        kwargs.setdefault("max_episode_steps", time_limit)
    return FixedCells(gym.make(gym_id, **kwargs), start, goal)


def evaluate(chain, make_env, time_limit, episodes, seed, env):
    """``episodes`` episodes of ``chain`` in ``env`` (None: ``make_env(chain)``, closed after),
    the first reset seeded with ``seed``, each the chain's one rollout
    (:meth:`pbcs.Chain.rollout`: ``info["success"]`` on the last step), within the env's time
    limit (``time_limit()`` where the env has none). Returns ``successes``, ``episodes`` and
    each episode's ``success`` and ``steps``."""
    if episodes < 1:
        raise ValueError(f"invalid `episodes`: must be at least 1, got {episodes}")
    own = env is None
    if own:
        env = make_env(chain)
    try:
        # The env's own time limit ends each episode (the rollout's cap never comes first).
        spec = getattr(env, "spec", None)
        limit = (spec.max_episode_steps if spec and spec.max_episode_steps else None) or time_limit()
        runs = [chain.rollout(env=env, max_steps=limit, seed=seed if e == 0 else None)
                for e in range(episodes)]
    finally:
        if own:
            env.close()
    success = [r["success"] for r in runs]
    return {
        "successes": int(sum(success)),
        "episodes": episodes,
        "success": np.array(success),
        "steps": np.array([r["steps"] for r in runs]),
    }
