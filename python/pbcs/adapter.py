"""PBCS on a Gymnasium environment of one's own: the adapter the Rust core steps.

PBCS needs one thing more than a Gymnasium environment gives: to start anywhere (phase 1
returns to archived states, Backplay starts near τ_K). :class:`Adapter` asks the environment
for its whole state as a float array (``get_state()`` / ``set_state(state)``, the user's or
:class:`MujocoState` for any MuJoCo environment) and checks, before any work, that restoring a
state replays the same step. The core then calls :meth:`Adapter.step` once per environment
step, and :meth:`Adapter.set_state` only when the state it steps from is not the one the
environment is in.

What the core sees:

* the observation (a dict observation's ``observation_key`` entry) as float32, **the position
  first** — the components ``position`` names, in order, then the others in theirs: phase 1
  bins on the position, the ε-balls and the shaped reward Φ measure it;
* the action in ``[-high, high]`` of the env's ``Box`` (symmetric bounds; wrap the env in
  ``gymnasium.wrappers.RescaleAction`` otherwise);
* success as the env says it (``success="info"``: ``info["success"]``; ``"terminated"``:
  ``terminated`` with a positive reward), paid ``max(reward, 1)`` and ending the episode;
  another ``terminated`` ends it with the reward capped at 0; ``truncated`` is ignored (PBCS
  bounds its episodes itself).
"""

import numpy as np

from . import _pbcs

MAX_POSITION_DIMS = 8
MAX_OBSERVATION_DIMS = 4096
MAX_STATE_DIMS = 1 << 20


class MujocoState:
    """The whole state of a Gymnasium MuJoCo environment (``env.unwrapped`` has ``model`` and
    ``data``), through ``mujoco.mj_getState`` / ``mj_setState`` with ``mjSTATE_INTEGRATION``:
    time, positions, velocities, actuator activations, the solver's warm start, controls and
    applied forces. Restoring ``qpos`` and ``qvel`` alone does not replay the next step
    (the warm start changes the contact solve). ``position_in_state(i)`` is where ``qpos[i]``
    lies in the state vector."""

    def __init__(self, env):
        import mujoco

        # The env's model and data, made once by gymnasium's MujocoEnv (a reset keeps them): read
        # once here, since some envs reach them through properties (PointMaze's).
        self._model, self._data = env.unwrapped.model, env.unwrapped.data
        self._spec = mujoco.mjtState.mjSTATE_INTEGRATION
        self._size = mujoco.mj_stateSize(self._model, self._spec)
        self._get, self._set, self._forward = mujoco.mj_getState, mujoco.mj_setState, mujoco.mj_forward

    def get_state(self):
        state = np.empty(self._size, dtype=np.float64)
        self._get(self._model, self._data, state, self._spec)
        return state

    def set_state(self, state):
        state = np.ascontiguousarray(state, dtype=np.float64)
        self._set(self._model, self._data, state, self._spec)
        # Positions changed: recompute what depends on them (sites, contacts) as a reset does.
        self._forward(self._model, self._data)

    def position_in_state(self, qpos_index):
        """The index in :meth:`get_state`'s vector of ``qpos[qpos_index]`` (after the time)."""
        return 1 + qpos_index


def _state_protocol(env, state):
    """The object whose ``get_state`` / ``set_state`` PBCS calls: ``state`` when given, else
    ``env.unwrapped``'s own pair, else :class:`MujocoState` for a MuJoCo environment."""
    if state is not None:
        for name in ("get_state", "set_state"):
            if not callable(getattr(state, name, None)):
                raise ValueError(f"invalid `state`: {type(state).__name__} has no {name}() method")
        return state
    base = env.unwrapped
    if hasattr(base, "model") and hasattr(base, "data") and not callable(
        getattr(base, "get_state", None)
    ):
        return MujocoState(env)
    for name in ("get_state", "set_state"):
        if not callable(getattr(base, name, None)):
            raise ValueError(
                f"invalid `env`: {type(base).__name__} has no {name}() method; PBCS resets "
                "anywhere: write get_state() -> float array and set_state(state), or pass "
                "state= an object that has them (MuJoCo envs: pbcs.MujocoState(env))"
            )
    return base


def _float_vector(value, what, limit):
    try:
        v = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{what} must be an array of numbers: {e}") from None
    if v.ndim != 1 or not 1 <= v.size <= limit:
        raise ValueError(f"{what} must be a 1-D array of 1 to {limit} numbers, got shape {v.shape}")
    if not np.isfinite(v).all():
        raise ValueError(f"{what} must be finite, got {v}")
    return v


class Adapter:
    """A ``gymnasium.Env`` as PBCS's core steps it (see the module's notes): built and checked
    by ``pbcs.run(env=...)`` and ``pbcs.explore(env=...)``.

    ``position``: the observation's components that are the position (a slice or indices, 1 to
    8 of them). ``state``: the get/set protocol (default: the env's own, else MuJoCo's).
    ``state_position``: where the position lies in the state vector, for starts drawn in a
    ball (default: MuJoCo's ``qpos`` at the same indices as ``position``; else the state's own
    indices when the state is the observation). ``success``: ``"info"`` or ``"terminated"``.
    ``observation_key``: the entry of a dict observation. ``reset_seed``: the seed of the one
    reset that gives s_0. ``success_region``: ``(centre, radius)`` around the position, what
    the last skill aims at (``phase2.last_goal = "success_region"``). ``ball_is_clear``: a
    callable ``(centre, radius) -> bool`` (``phase2.stop_at_failure``, ``phase2.retargets``).
    ``sample_ball``: how a start in B_ε(τ_K) is drawn, a callable ``(state, radius, draws) ->
    state`` given the centre's whole state (a copy), ε and ``draws``, the run's own random
    stream (:meth:`Draws.random`: what PBCS's core would draw next), returning the start's
    whole state; the observation the core sees of it is the centre's with the position read
    from the state at ``state_position`` (default: the position moved uniformly in the disc
    of radius ε, clamped to the observation space's bounds). ``observation_names``:
    the env's observation components' names, the CSV headers (default ``o<i>``, ``i`` the
    env's index, whatever the core's order). ``recorded_as``: what the run's record and its
    chain's job name as its environment: by default ``gym``, an environment of one's own; or the
    name of the registry environment (``pbcs.ENV_NAMES``) this env is a copy of, for a
    comparison with that environment's runs to the byte (python/tests/test_adapter.py).
    """

    def __init__(self, env, position, state=None, state_position=None, success="info",
                 observation_key=None, reset_seed=0, success_region=None, ball_is_clear=None,
                 observation_names=None, sample_ball=None, recorded_as=None):
        import gymnasium as gym

        if not isinstance(env, gym.Env):
            raise ValueError(f"invalid `env`: must be a gymnasium.Env, got {type(env).__name__}")
        space = env.action_space
        if not isinstance(space, gym.spaces.Box) or len(space.shape) != 1:
            raise ValueError(
                f"invalid `env`: its action space must be a 1-D gymnasium.spaces.Box, got {space}"
            )
        low, high = np.asarray(space.low, np.float64), np.asarray(space.high, np.float64)
        if not (np.isfinite(high).all() and (high > 0).all() and (low == -high).all()):
            raise ValueError(
                f"invalid `env`: its action bounds must be finite and symmetric, got {low} .. {high}"
                "; wrap it in gymnasium.wrappers.RescaleAction(env, -1.0, 1.0)"
            )
        if not isinstance(reset_seed, int) or not 0 <= reset_seed < 2**63:
            raise ValueError(f"invalid `reset_seed`: an integer in [0, 2^63), got {reset_seed!r}")
        if success not in ("info", "terminated"):
            raise ValueError(f"invalid `success`: must be \"info\" or \"terminated\", got {success!r}")
        self.env, self.success, self.observation_key = env, success, observation_key
        self.action_high = high.astype(np.float32)
        self._action_dtype = space.dtype
        self._protocol = _state_protocol(env, state)
        obs, _ = env.reset(seed=reset_seed)
        raw = self._raw_observation(obs)
        n = raw.size
        self.position = _indices(position, n, "position", MAX_POSITION_DIMS)
        rest = [i for i in range(n) if i not in set(self.position)]
        self._order = np.asarray(self.position + rest, dtype=np.intp)
        self._reorder = not (self._order == np.arange(n)).all()
        names = [f"o{i}" for i in range(n)] if observation_names is None else observation_names
        if not isinstance(names, (list, tuple)) or len(names) != n or not all(
            isinstance(x, str) and x.isidentifier() for x in names
        ):
            raise ValueError(
                f"invalid `observation_names`: {n} names (letters, digits, _), got {names!r}"
            )
        self.observation_names = [names[i] for i in self._order]
        self.start_state = _float_vector(self._protocol.get_state(), "get_state()", MAX_STATE_DIMS)
        self.start_observation = self._observation(obs)
        self.state_position = self._state_position(state_position, n)
        self.position_low, self.position_high = self._position_bounds()
        self.success_region = _region(success_region, len(self.position))
        if ball_is_clear is not None and not callable(ball_is_clear):
            raise ValueError("invalid `ball_is_clear`: must be a callable (centre, radius) -> bool")
        self.ball_is_clear = ball_is_clear
        if sample_ball is not None:
            if not callable(sample_ball):
                raise ValueError(
                    "invalid `sample_ball`: must be a callable (state, radius, draws) -> state"
                )
            if self.state_position is None:
                raise ValueError(
                    "invalid `sample_ball`: the observation of a drawn start is read from the state "
                    "at `state_position`, which is not known: give state_position="
                )
        self.sample_ball = sample_ball
        if recorded_as is not None:
            if recorded_as not in _pbcs.ENV_NAMES:
                raise ValueError(
                    f"invalid `recorded_as`: one of pbcs.ENV_NAMES "
                    f"{tuple(_pbcs.ENV_NAMES)}, got {recorded_as!r}"
                )
        self.recorded_as = recorded_as
        self._check_restores()

    # The calls the core makes.

    def step(self, action):
        """One step: ``(state, observation, reward, terminal)`` as the module says. The hot
        path: shapes are checked, not every value (the construction checked the first)."""
        obs, reward, terminated, _, info = self.env.step(np.asarray(action, self._action_dtype))
        if self.observation_key is not None:
            obs = obs[self.observation_key]
        obs = np.asarray(obs, dtype=np.float32)
        if self._reorder:
            obs = obs[self._order]
        if obs.shape != self._order.shape:
            raise ValueError(f"the env's observation has shape {obs.shape}, not {self._order.shape}")
        reward = float(reward)
        if self.success == "info":
            if "success" not in info:
                raise ValueError(
                    "success = \"info\" but the env's step gave no info[\"success\"]; "
                    "use success=\"terminated\""
                )
            won = bool(info["success"])
        else:
            won = bool(terminated) and reward > 0
        if won:
            reward = max(reward, 1.0)
        elif terminated:
            reward = min(reward, 0.0)
        state = np.asarray(self._protocol.get_state(), dtype=np.float64)
        return state, obs, reward, bool(won or terminated)

    def set_state(self, state):
        """Puts the environment in ``state`` (a vector :meth:`step` or the start gave)."""
        self._protocol.set_state(np.array(state, dtype=np.float64))

    def ball_start(self, state, observation, radius, draws):
        """A start in the ball of radius ``radius`` around the state ``state`` (whose observation
        as the core sees it is ``observation``), drawn by the user's ``sample_ball``:
        ``(state, observation)``, checked."""
        start = self.sample_ball(np.array(state, dtype=np.float64), float(radius), draws)
        try:
            start = np.asarray(start, dtype=np.float64)
        except (TypeError, ValueError):
            start = None
        if start is None or start.shape != self.start_state.shape or not np.isfinite(start).all():
            raise ValueError(
                f"sample_ball must return a state of {self.start_state.size} finite numbers, got "
                f"{getattr(start, 'shape', None)}"
            )
        obs = np.array(observation, dtype=np.float32)
        obs[: len(self.position)] = start[self.state_position].astype(np.float32)
        return start, obs

    # Construction's checks.

    def _raw_observation(self, obs):
        if isinstance(obs, dict):
            if self.observation_key is None or self.observation_key not in obs:
                raise ValueError(
                    f"invalid `observation_key`: the env's observation is a dict with keys "
                    f"{sorted(obs)}; name the one PBCS sees (e.g. observation_key=\"observation\")"
                )
            obs = obs[self.observation_key]
        return _float_vector(obs, "the env's observation", MAX_OBSERVATION_DIMS)

    def _observation(self, obs):
        return self._raw_observation(obs)[self._order].astype(np.float32)

    def _state_position(self, given, n):
        """Where the position lies in the state vector: ``given``, checked; else a guess (a
        MuJoCo env's ``qpos``, or the state's own indices when it is as long as the
        observation), kept only where s_0 confirms it (else no ball starts: the settings that
        need them are refused by the core, naming them)."""
        size, d = self.start_state.size, len(self.position)
        if given is None:
            if isinstance(self._protocol, MujocoState):
                guess = [self._protocol.position_in_state(i) for i in self.position]
            elif size == n:
                guess = self.position
            else:
                return None
            fits = max(guess) < size and (
                self.start_state[guess].astype(np.float32) == self.start_observation[:d]
            ).all()
            return guess if fits else None
        idx = _indices(given, size, "state_position", MAX_POSITION_DIMS)
        if len(idx) != d:
            raise ValueError(
                f"invalid `state_position`: {len(idx)} indices for {d} position components"
            )
        got = self.start_state[idx].astype(np.float32)
        if not (got == self.start_observation[:d]).all():
            raise ValueError(
                f"invalid `state_position`: the state's components {idx} are {got}, the "
                f"observation's position is {self.start_observation[:d]}"
            )
        return idx

    def _position_bounds(self):
        space = self.env.observation_space
        if self.observation_key is not None and hasattr(space, "spaces"):
            space = space.spaces[self.observation_key]
        low = np.full(len(self.position), -np.inf, np.float32)
        high = np.full(len(self.position), np.inf, np.float32)
        if hasattr(space, "low") and np.shape(space.low) == (self._order.size,):
            low = np.asarray(space.low, np.float32)[self.position]
            high = np.asarray(space.high, np.float32)[self.position]
        if np.isnan(low).any() or np.isnan(high).any() or (low > high).any():
            raise ValueError(f"invalid `env`: its observation space's bounds {low} .. {high}")
        return low, high

    def _check_restores(self):
        """Steps from s_0, restores s_0 and steps again: the same state, observation, reward
        and end, else ``set_state`` does not restore the whole state."""
        s0 = self.start_state
        probe = (0.5 * self.action_high).astype(np.float32)
        first = self.step(probe)
        self.set_state(s0)
        back = np.asarray(self._protocol.get_state(), dtype=np.float64)
        if back.shape != s0.shape or not (back == s0).all():
            raise ValueError(
                "invalid `env`: set_state(s) does not restore s (get_state() afterwards differs "
                "from s): PBCS starts from saved states"
            )
        second = self.step(probe)
        same = all(np.array_equal(a, b) for a, b in zip(first[:2], second[:2]))
        if not (same and first[2:] == second[2:]):
            raise ValueError(
                "invalid `env`: a step from a restored state differs from the first step from "
                "it: set_state does not restore the whole state (a MuJoCo env: "
                "pbcs.MujocoState(env) restores the solver's warm start too)"
            )
        self.set_state(s0)


def _indices(value, n, what, limit):
    if isinstance(value, slice):
        idx = list(range(n))[value]
        if value.stop is not None and value.stop > n:
            raise ValueError(f"invalid `{what}`: {value} reaches past the {n} components")
    else:
        try:
            idx = [int(i) for i in value]
        except (TypeError, ValueError):
            raise ValueError(f"invalid `{what}`: must be a slice or a sequence of indices") from None
        bad = [i for i in idx if not 0 <= i < n]
        if bad:
            raise ValueError(f"invalid `{what}`: indices {bad} out of range for {n} components")
    if not 1 <= len(idx) <= limit or len(set(idx)) != len(idx):
        raise ValueError(f"invalid `{what}`: must name 1 to {limit} distinct components, got {idx}")
    return idx


def _region(region, dims):
    if region is None:
        return None
    try:
        centre, radius = region
        centre = np.asarray(centre, np.float32)
        radius = float(radius)
    except (TypeError, ValueError):
        raise ValueError("invalid `success_region`: must be (centre, radius)") from None
    if centre.shape != (dims,) or not np.isfinite(centre).all() or not 0 < radius < np.inf:
        raise ValueError(
            f"invalid `success_region`: a centre of {dims} finite numbers and a positive radius"
        )
    return centre, radius
