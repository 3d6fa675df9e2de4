"""PBCS (Plan, Backplay, Chain Skills; Matheron, Perrin, Sigaud 2020) from Python.

Everything is computed by the Rust package pbcs-rs (the compiled module ``pbcs._pbcs``):

* :class:`ContinuousMaze` — the paper's continuous maze as a ``gymnasium.Env``, registered as
  ``pbcs/ContinuousMaze-v0``; :class:`ContinuousMazeVec` steps N mazes in one call.
* :func:`make` — any environment of the registry by name (``ENV_NAMES``: ``maze``, ``rooms``,
  ``three_rooms``; in a build with MuJoCo, ``MUJOCO``, PointMaze's and AntMaze's maps and
  ``pointmaze`` and ``antmaze`` on a map of one's own), registered as ``pbcs/<name>-v0``.
* :func:`explore` — phase 1: the trajectory τ from s_0 to the target.
* :func:`run` — a whole PBCS run with a preset (``fast`` or ``paper``).
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
from .chain import Chain, load_chain
from .envs import ContinuousMaze, ContinuousMazeVec, RegisteredEnv, make

__all__ = [
    "ContinuousMaze",
    "ContinuousMazeVec",
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
ENV_NAMES = tuple(_pbcs.ENV_NAMES)
#: Whether this build runs PointMaze and AntMaze (built with the ``mujoco`` feature:
#: ``MATURIN_PEP517_ARGS="--features mujoco" pip install ./python`` after ``make mujoco``).
MUJOCO = bool(_pbcs.MUJOCO)


def explore(size, layout=0, seed=0, bin_side=None, budget=None):
    """Phase 1 on the maze of ``size`` × ``size`` cells and layout seed ``layout``, run seed
    ``seed``: a dict with ``tau`` (float32 array of shape (len, 2), from s_0 to the first state
    in the target disc), ``actions`` ((len − 1, 2), the action from each state of τ to the
    next), ``env_steps`` and ``archive_states``. The same τ as ``pbcs explore``.
    """
    return _pbcs.explore(size, layout, seed, bin_side, budget)


def run(size=None, layout=None, seed=0, preset="fast", config=None, out=None,
        max_env_steps=None, env=None, map=None, map_file=None):
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
    """
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
