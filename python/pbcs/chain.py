"""A chain of skills saved by ``pbcs run``, as a policy: for the Python maze, or for any
environment's observations (:mod:`pbcs.pointmaze` runs a PointMaze chain in
gymnasium-robotics)."""

import numpy as np

from . import _pbcs
from .envs import ContinuousMaze, RegisteredEnv


def load_chain(path, adapter=None):
    """The chain of skills saved in the folder ``path`` (``<run>/chain`` of ``pbcs run`` or
    of :func:`pbcs.run` with ``out``). A folder without ``manifest.toml`` or ``run.toml``, a
    malformed manifest or bad weights raise ``OSError`` or ``ValueError`` naming the file.
    A chain of a user's Gymnasium environment (``pbcs.run(env=...)``): pass its
    :class:`pbcs.Adapter`, which the skills' lengths are checked against (its job says
    ``env = "gym"``, which nothing but the adapter builds); play it with
    :meth:`Chain.evaluate_in`."""
    if adapter is None:
        return Chain(_pbcs.ChainCore(str(path)))
    dims = (len(adapter.observation_names), len(adapter.action_high))
    return Chain(_pbcs.ChainCore(str(path), dims))


class Chain:
    """A chain π_0 … π_n with activation balls A_i = B_ε(τ_{K_i}), executed as the paper says:
    π_0 until the state enters A_1, then π_1, and so on. :meth:`act` remembers which skill
    acts, so call :meth:`reset` at the start of every episode."""

    def __init__(self, core):
        self._core = core

    def __len__(self):
        return len(self._core)

    @property
    def balls(self):
        """The activation balls as ``(x, y, radius)``, in execution order."""
        return self._core.balls

    @property
    def maze(self):
        """``(size, layout)`` of the maze the chain was built for (``ValueError`` for a chain
        of another environment)."""
        return self._core.maze

    @property
    def env(self):
        """The environment the chain was built for, by its registry name (``maze``,
        ``rooms``, ``pointmaze_medium``, ...)."""
        return self._core.env

    @property
    def pointmaze(self):
        """For a chain of PointMaze: ``(gym_id, start_cell, goal_cell, time_limit)`` of its
        task in gymnasium-robotics (cells as (row, column)); None otherwise. See
        :mod:`pbcs.pointmaze` to run it there."""
        return self._core.pointmaze

    @property
    def antmaze(self):
        """For a chain of AntMaze's fixed task: ``(gym_id, start_cell, goal_cell, time_limit)``
        of its task in gymnasium-robotics (cells as (row, column)); None otherwise. See
        :mod:`pbcs.antmaze` to run it there."""
        return self._core.antmaze

    @property
    def pointmaze_map(self):
        """For a chain on a map of one's own (``env`` ``"pointmaze"`` or ``"antmaze"``): the
        map as gymnasium-robotics' ``maze_map`` takes it (rows of 0 and 1); None otherwise."""
        return self._core.pointmaze_map

    @property
    def active_skill(self):
        """The skill that chose the last action."""
        return self._core.active_skill

    def reset(self):
        """Starts a new episode: π_0 acts next."""
        self._core.reset()

    def act(self, obs, goal=None, noise=None):
        """The action (float32, the environment's units) at observation ``obs`` (the
        environment's whole observation: (x, y) in the maze, (x, y, vx, vy) in PointMaze);
        ``goal``, the episode's goal (a goal-conditioned env's ``desired_goal``), needed by a
        chain whose last skill aims at each episode's own (:attr:`needs_goal`). With
        ``noise`` (standard normal draws, one per action component), a SAC chain's stochastic
        action b ⊙ tanh(μ + σ·noise), as its skills explored in training; greedy otherwise."""
        return self._core.act(obs, goal, noise)

    @property
    def needs_goal(self):
        """Whether :meth:`act` needs the episode's goal: a chain built with
        ``phase2.last_goal = "drawn"``, whose last skill aims at the goal each reset draws."""
        return self._core.needs_goal

    def make_env(self, **kwargs):
        """The chain's environment as a ``gymnasium.Env`` (``kwargs`` go to its constructor):
        a :class:`ContinuousMaze` of its maze, else the registry's (:func:`pbcs.make`), with
        episodes of the job's evaluation length."""
        kwargs.setdefault("max_episode_steps", self._core.eval_max_steps)
        if self.env == "maze":
            size, layout = self._core.maze
            return ContinuousMaze(size=size, layout=layout, **kwargs)
        return RegisteredEnv(self.env, **kwargs)

    def rollout(self, start=None, env=None, max_steps=None, seed=None):
        """One episode through the Gymnasium environment ``env`` (default: :meth:`make_env`)
        from ``start`` (a state the env's reset takes as ``options={"state": start}``, the
        maze's; default: the env's own reset, seeded with ``seed``), at most ``max_steps``
        steps (default: the job's evaluation length): a dict with the observations visited
        (``states``, start included), ``success`` and ``steps``. A dict observation (a
        goal-conditioned env, gymnasium-robotics') is acted on through its ``observation`` (and
        its ``desired_goal`` for a chain that :attr:`needs_goal`);
        success is the env's ``info["success"]`` where it says one, else a positive reward at
        the end of the episode."""
        env = env or self.make_env()
        limit = max_steps or self._core.eval_max_steps
        options = None if start is None else {"state": start}
        obs, info = env.reset(seed=seed, options=options)
        self.reset()
        see = (lambda o: o["observation"]) if isinstance(obs, dict) else (lambda o: o)
        if self.needs_goal and not isinstance(obs, dict):
            raise ValueError(
                "this chain's last skill aims at each episode's own goal (phase2.last_goal = "
                "\"drawn\"): its env must give dict observations with a desired_goal"
            )
        goal = (lambda o: o["desired_goal"]) if self.needs_goal else (lambda o: None)
        states, success = [see(obs)], False
        for _ in range(limit):
            obs, reward, terminated, truncated, info = env.step(self.act(see(obs), goal(obs)))
            states.append(see(obs))
            if terminated or truncated:
                success = bool(info["success"]) if "success" in info else terminated and reward > 0
                break
        return {"states": np.stack(states), "success": success, "steps": len(states) - 1}

    def eval_starts(self, episodes=100, seed=None):
        """The start states of ``pbcs eval --episodes episodes --seed seed`` (default seed:
        the run's), uniform in B_ε(s_0) (with ``phase2.first_starts = "drawn"``, drawn as the
        env's reset draws them), as observations: shape (episodes, observation length)."""
        return self._core.eval_starts(episodes, seed)

    def evaluate(self, episodes=100, seed=None):
        """``pbcs eval``'s protocol, stepped in Python: :meth:`rollout` from each of
        :meth:`eval_starts`. Returns ``successes``, ``episodes`` and each episode's ``success``
        and ``steps``; equal to :meth:`evaluate_in_core` for the same arguments. Needs the
        maze's reset-anywhere (:meth:`evaluate_in_core` evaluates a chain of any
        environment)."""
        if self.env != "maze":
            raise ValueError(
                f"a chain of env = {self.env!r}: its evaluation starts are set through the "
                "maze's reset-anywhere; use evaluate_in_core"
            )
        env = self.make_env()
        runs = [self.rollout(tuple(s), env=env) for s in self.eval_starts(episodes, seed)]
        success = np.array([r["success"] for r in runs])
        return {
            "successes": int(success.sum()),
            "episodes": episodes,
            "success": success,
            "steps": np.array([r["steps"] for r in runs]),
        }

    def evaluate_in(self, adapter, episodes=100, seed=0, max_steps=None):
        """The chain played in a user's Gymnasium environment through the :class:`Adapter` it
        was trained through (``pbcs.run(env=...)``): ``episodes`` episodes from the env's own
        resets (seeds ``seed``, ``seed + 1``, ...), each at most ``max_steps`` steps (default:
        the job's evaluation length), success as the adapter reads it. Returns ``successes``,
        ``episodes`` and each episode's ``success`` and ``steps``."""
        if not isinstance(episodes, int) or not 1 <= episodes <= 100_000:
            raise ValueError(f"invalid `episodes`: an integer in 1..100000, got {episodes!r}")
        if max_steps is not None and not (isinstance(max_steps, int) and 1 <= max_steps <= 10**7):
            raise ValueError(f"invalid `max_steps`: an integer in 1..10000000, got {max_steps!r}")
        limit = max_steps or self._core.eval_max_steps
        wins, steps = [], []
        for e in range(episodes):
            obs, _ = adapter.env.reset(seed=seed + e)
            obs = adapter._observation(obs)
            self.reset()
            won, t = False, 0
            while t < limit and not won:
                _, obs, reward, terminal = adapter.step(self.act(obs))
                t += 1
                if terminal:
                    won = reward > 0
                    break
            wins.append(won)
            steps.append(t)
        wins = np.array(wins)
        return {"successes": int(wins.sum()), "episodes": episodes, "success": wins,
                "steps": np.array(steps)}

    def evaluate_in_core(self, episodes=100, seed=None):
        """``pbcs eval``'s evaluation computed by the Rust core (the same function as the
        command): ``successes``, ``episodes``, the Wilson 95 % ``interval``, each episode's
        ``success`` and ``steps``."""
        return self._core.evaluate(episodes, seed)

    def core_rollout(self, start=None, max_steps=None):
        """One execution computed by the core from s_0 (or ``start``, a point of the maze):
        ``states`` (the points drawn), ``success``, ``steps`` and the ``skill_used`` for each
        action."""
        return self._core.rollout(start, max_steps)

    def render(self, paths=None, size=256):
        """An RGB image of the chain's environment with its activation balls and ``paths``
        (arrays of shape (len, 2): points as :meth:`core_rollout` gives them) in green."""
        paths = None if paths is None else [np.asarray(p, dtype=np.float32) for p in paths]
        return self._core.render(paths, size)
