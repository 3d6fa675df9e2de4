"""PBCS (Plan, Backplay, Chain Skills; Matheron, Perrin, Sigaud 2020) from Python.

Everything is computed by the Rust package pbcs-rs (the compiled module ``pbcs._pbcs``):

* :class:`ContinuousMaze` — the paper's continuous maze as a ``gymnasium.Env``, registered as
  ``pbcs/ContinuousMaze-v0``; :class:`ContinuousMazeVec` steps N mazes in one call.
* :func:`make` — any environment of the registry by name (``ENV_NAMES``: ``maze``, ``rooms``,
  ``three_rooms``; in a build with MuJoCo, ``MUJOCO``, PointMaze's and AntMaze's maps and
  ``pointmaze`` and ``antmaze`` on a map of one's own), registered as ``pbcs/<name>-v0``.
* :func:`explore` — phase 1: the trajectory τ from s_0 to the target.
* :func:`run` — a whole PBCS run with a preset (``fast`` or ``paper``), on our environments
  or on a ``gymnasium.Env`` of one's own that can save and restore its state
  (:class:`Adapter`; any MuJoCo env through :class:`MujocoState`).
* :func:`load_chain` — a chain of skills saved by ``pbcs run`` as a policy (:class:`Chain`).

Errors of the core are Python exceptions carrying its message: ``ValueError`` for bad
arguments or malformed files, ``OSError`` for files that cannot be read, ``RuntimeError`` for
work that failed (phase 1 out of budget).

>>> import pbcs
>>> env = pbcs.ContinuousMaze(size=2)
>>> obs, info = env.reset(seed=0)
>>> obs.tolist()
[0.5, 0.5]
"""

from gymnasium.envs.registration import register

from . import _pbcs
from .adapter import Adapter, MujocoState
from .chain import Chain, load_chain
from .envs import ContinuousMaze, ContinuousMazeVec, RegisteredEnv, make

__all__ = [
    "Adapter",
    "MujocoState",
    "ContinuousMaze",
    "ContinuousMazeVec",
    "Draws",
    "Chain",
    "ENV_NAMES",
    "evaluation_starts",
    "explore",
    "load_chain",
    "make",
    "RegisteredEnv",
    "run",
    "MAX_MAZE_SIZE",
    "MUJOCO",
]

MAX_MAZE_SIZE = _pbcs.MAX_MAZE_SIZE
#: The run's random stream as an :class:`Adapter`'s ``sample_ball`` hook draws from it.
Draws = _pbcs.Draws
ENV_NAMES = tuple(_pbcs.ENV_NAMES)
#: Whether this build runs PointMaze and AntMaze (built with the ``mujoco`` feature:
#: ``MATURIN_PEP517_ARGS="--features mujoco" pip install ./python`` after ``make mujoco``).
MUJOCO = bool(_pbcs.MUJOCO)


def _adapter(env, position, options):
    if isinstance(env, Adapter):
        if position is not None or options:
            raise ValueError("an Adapter is already built: give position and its options to it")
        return env
    if position is None:
        raise ValueError(
            "invalid `position`: a gymnasium.Env needs position= (a slice or the indices of "
            "the observation's components that are the position, e.g. slice(0, 2))"
        )
    return Adapter(env, position, **options)


def explore(size=None, layout=0, seed=0, bin_side=None, budget=None, env=None, position=None,
            preset="fast", config=None, progress=True, **adapter):
    """Phase 1 on the maze of ``size`` × ``size`` cells and layout seed ``layout``, run seed
    ``seed``: a dict with ``tau`` (float32 array of shape (len, 2), from s_0 to the first state
    in the target disc), ``actions`` ((len − 1, 2), the action from each state of τ to the
    next), ``env_steps`` and ``archive_states``. The same τ as ``pbcs explore``.

    With ``env`` a ``gymnasium.Env`` (and ``position``, and any other :class:`Adapter`
    argument), phase 1 of the preset's or config's job on it: ``tau`` as the observations
    the core sees (position first); ``progress``: a spinner on standard error (env steps,
    archived states, steps per second).
    """
    if env is not None:
        return _pbcs.explore_gym(_adapter(env, position, adapter), seed, preset, config, progress)
    if size is None:
        raise ValueError("invalid `size`: give the maze's size, or env= a gymnasium.Env")
    return _pbcs.explore(size, layout, seed, bin_side, budget)


def run(size=None, layout=None, seed=0, preset="fast", config=None, out=None,
        max_env_steps=None, env=None, map=None, map_file=None, position=None, progress=True,
        **adapter):
    """A whole PBCS run (phase 1, phase 2, the chain's evaluation from B_ε(s_0)), run seed
    ``seed``, with the preset ``fast`` or ``paper``, or the job in the TOML file ``config``, on
    the environment ``env`` names (a registry name, ``ENV_NAMES``; default: the config's, else
    the maze), the maze of ``size`` and layout ``layout`` (default: the config's, else 5 and 0),
    the map of one's own of ``env="pointmaze"`` or ``"antmaze"`` (``map``: rows as strings of 0 and 1
    or as lists of 0 and 1; or ``map_file``: a file of rows; default: the config's). With
    ``out`` (a folder), the run's files are written there as ``pbcs run --out`` writes them,
    the chain in ``out/chain`` (load it with :func:`load_chain`). Returns the run's record as a
    dict (``env``, ``solved``, ``success_rate``, ``skills``, step counts, ``tau`` as points of
    the plane, each evaluation episode's success and steps, ``chain``). The same bytes as
    ``pbcs run`` for the same job and seed.

    With ``env`` a ``gymnasium.Env`` of one's own (or an :class:`Adapter`): PBCS on it, the
    observation components ``position`` names being the position (any other keyword goes to
    :class:`Adapter`: ``success``, ``state``, ``observation_key``, ``success_region``, ...).
    Settings that need a hook it was not given are refused before any work (the ``fast``
    preset needs more than ball starts: ``config=`` a job with ``shorten``,
    ``stop_at_failure`` and the path limits off, as docs/python.md shows). ``progress``:
    phase 2's spinner on standard error. The chain is loaded with :func:`load_chain` and
    played in the env with :meth:`Chain.evaluate_in` and the same adapter.
    """
    if env is not None and not isinstance(env, str):
        if size is not None or layout is not None or map is not None or map_file is not None:
            raise ValueError("size, layout, map and map_file describe our environments, not env=")
        return _pbcs.run_gym(
            _adapter(env, position, adapter), seed, preset, config, out, max_env_steps, progress
        )
    if position is not None or adapter:
        raise ValueError(f"position and {sorted(adapter)} are for env= a gymnasium.Env")
    return _pbcs.run(size, layout, seed, preset, config, out, max_env_steps, env, map, map_file)


def evaluation_starts(size, layout=0, seed=0, episodes=100, epsilon=0.1):
    """The start states of PBCS's evaluation protocol: ``episodes`` states uniform in
    B_ε(s_0), drawn from run seed ``seed``'s evaluation stream (float32, shape (episodes, 2)).
    A chain of that seed is evaluated from exactly these (``Chain.eval_starts``), and so is a
    vanilla run with ``train.final_eval_episodes``; judge any other policy from them too."""
    return _pbcs.evaluation_starts(size, layout, seed, episodes, epsilon)


for _name in ENV_NAMES:
    register(id=f"pbcs/{_name}-v0", entry_point="pbcs.envs:make", kwargs={"name": _name})

register(
    id="pbcs/ContinuousMaze-v0",
    entry_point="pbcs.envs:ContinuousMaze",
    vector_entry_point="pbcs.envs:ContinuousMazeVec",
    kwargs={"size": 2},
)
