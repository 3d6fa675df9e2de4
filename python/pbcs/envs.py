"""The paper's continuous maze as Gymnasium environments (one maze, and N mazes per call), and
every environment of pbcs-rs' registry by name (:func:`make`, :class:`RegisteredEnv`).

State and observation: the point mass's position in [0, N]² (float32). Action: its step,
in [−0.1, 0.1]² (the paper's action space; out-of-range components are clipped, NaN counts as
0). ``step(s, a) = s`` if the segment [s, s + a] crosses a wall, else ``s + a``. Reward: +1 on
entering the target disc (radius 0.2 around (N − 0.5, N − 0.5), or (0.5, 1.5) for N = 2), which
terminates the episode; −1 for a step into a wall; 0 otherwise. Episodes are truncated after
``max_episode_steps`` steps (1000 by default, our vanilla baselines' episode length). The step
is the Rust core's own (``pbcs::envs::maze::Maze::step``).
"""

import numpy as np
import gymnasium as gym
from gymnasium import spaces
from gymnasium.vector import VectorEnv
from gymnasium.vector.utils import batch_space

from . import _pbcs

try:  # gymnasium >= 1.1 names the autoreset modes
    from gymnasium.vector import AutoresetMode

    _NEXT_STEP = AutoresetMode.NEXT_STEP
except ImportError:  # pragma: no cover - gymnasium 1.0
    _NEXT_STEP = "NextStep"


def _spaces(size, max_action):
    observation = spaces.Box(0.0, float(size), shape=(2,), dtype=np.float32)
    action = spaces.Box(-max_action, max_action, shape=(2,), dtype=np.float32)
    return observation, action


class ContinuousMaze(gym.Env):
    """The N × N continuous maze of PBCS (appendix "Experimental Setup").

    ``reset(options={"state": (x, y)})`` starts the episode at any state of [0, N]² (the
    reset-anywhere primitive PBCS relies on); without it the episode starts at s_0 = (0.5, 0.5).
    ``info["hit_wall"]`` says whether the step was blocked by a wall. ``render()`` (with
    ``render_mode="rgb_array"``) returns the maze with the episode's path as an RGB array.

    >>> env = ContinuousMaze(size=2)
    >>> obs, _ = env.reset(options={"state": (0.5, 1.25)})
    >>> obs, reward, terminated, truncated, info = env.step([0.0, 0.1])
    >>> reward, terminated
    (1.0, True)
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 30}

    def __init__(
        self,
        size=2,
        layout=0,
        max_episode_steps=1000,
        render_mode=None,
        render_size=256,
        wall_thickness=0.1,
        target_radius=0.2,
        max_action=0.1,
    ):
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"invalid `render_mode`: must be one of {self.metadata['render_modes']} or None, "
                f"got {render_mode!r}"
            )
        self._core = _pbcs.MazeEnv(
            size, layout, max_episode_steps, wall_thickness, target_radius, max_action
        )
        self.observation_space, self.action_space = _spaces(size, self._core.max_action)
        self.render_mode = render_mode
        self.render_size = render_size

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        state = None
        if options is not None and options.get("state") is not None:
            s = np.asarray(options["state"], dtype=np.float32).reshape(-1)
            if s.shape != (2,):
                raise ValueError(
                    f"invalid `options['state']`: must have 2 coordinates, got {s.shape[0]}"
                )
            state = (float(s[0]), float(s[1]))
        return self._core.reset(state), {}

    def step(self, action):
        obs, reward, terminated, truncated, hit = self._core.step(action)
        return obs, reward, terminated, truncated, {"hit_wall": hit}

    def render(self):
        if self.render_mode == "rgb_array":
            return self._core.render(self.render_size)
        return None

    @property
    def maze(self):
        """The compiled maze: ``size``, ``layout``, ``target``, ``walls``, ``fewest_steps``,
        ``state``, and the pure ``step_from(x, y, ax, ay)``."""
        return self._core


class ContinuousMazeVec(VectorEnv):
    """``num_envs`` mazes of one layout stepped in one call on numpy arrays.

    Follows Gymnasium's vector conventions: batched spaces, ``step(actions)`` with ``actions``
    of shape (num_envs, 2) returns ``(obs, rewards, terminations, truncations, infos)``, and the
    next-step autoreset: the call after an episode ends resets that maze to s_0 (its action is
    ignored, its reward is 0). ``reset(options={"states": array})`` starts each maze at its own
    state.

    >>> envs = ContinuousMazeVec(4, size=2)
    >>> obs, _ = envs.reset(seed=0)
    >>> obs.shape
    (4, 2)
    """

    metadata = {"autoreset_mode": _NEXT_STEP, "render_modes": []}

    def __init__(
        self,
        num_envs,
        size=2,
        layout=0,
        max_episode_steps=1000,
        wall_thickness=0.1,
        target_radius=0.2,
        max_action=0.1,
        render_mode=None,
    ):
        self._core = _pbcs.MazeVecEnv(
            num_envs, size, layout, max_episode_steps, wall_thickness, target_radius, max_action
        )
        self.num_envs = num_envs
        self.single_observation_space, self.single_action_space = _spaces(
            size, self._core.max_action
        )
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self.render_mode = None

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        states = None
        if options is not None and options.get("states") is not None:
            states = np.ascontiguousarray(options["states"], dtype=np.float32)
        return self._core.reset(states), {}

    def step(self, actions):
        obs, rewards, terminations, truncations = self._core.step(
            np.ascontiguousarray(actions, dtype=np.float32)
        )
        return obs, rewards, terminations, truncations, {}


class RegisteredEnv(gym.Env):
    """An environment of pbcs-rs' registry by name (``pbcs.ENV_NAMES``: ``maze``, ``rooms``,
    ``three_rooms``, ``pointmaze_<map>`` and ``antmaze_<map>`` in a build with MuJoCo), as a
    ``gymnasium.Env``: the observation is the environment's (float32, unbounded box), the
    action box its bounds (out-of-range components are clipped, NaN counts as 0), ``reset``
    starts from its start distribution (s_0 for the maze, the rooms and PointMaze's task),
    ``step`` is the Rust core's own, truncated after ``max_episode_steps``. ``size`` and
    ``layout`` are the maze's and refused for another environment; ``map`` (rows as strings
    of 0 and 1, or lists of 0 and 1) or ``map_file`` (a file of rows) is the map of one's
    own of ``pointmaze`` and ``antmaze``, and refused for another. ``render()`` (with
    ``render_mode="rgb_array"``) draws the environment with the episode's path.

    >>> env = RegisteredEnv("rooms")
    >>> obs, _ = env.reset(seed=0)
    >>> obs.tolist()
    [0.30000001192092896, 0.20000000298023224]
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 30}

    def __init__(self, name="maze", size=None, layout=None, max_episode_steps=1000,
                 render_mode=None, render_size=256, map=None, map_file=None):
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"invalid `render_mode`: must be one of {self.metadata['render_modes']} or None, "
                f"got {render_mode!r}"
            )
        self._core = _pbcs.NamedEnv(name, size, layout, max_episode_steps, map, map_file)
        self.name = self._core.name
        n = self._core.obs_dim
        self.observation_space = spaces.Box(-np.inf, np.inf, shape=(n,), dtype=np.float32)
        bounds = np.asarray(self._core.action_bounds, dtype=np.float32)
        self.action_space = spaces.Box(-bounds, bounds, dtype=np.float32)
        self.render_mode = render_mode
        self.render_size = render_size

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        if options is not None and options.get("state") is not None:
            raise ValueError(
                f"invalid `options['state']`: {self.name} starts from its own start "
                "distribution (reset-anywhere from Python is the maze's: pbcs.ContinuousMaze)"
            )
        return self._core.reset(seed), {}

    def step(self, action):
        a = np.asarray(action, dtype=np.float32).reshape(-1)
        obs, reward, terminated, truncated = self._core.step(a.tolist())
        return obs, reward, terminated, truncated, {}

    def render(self):
        if self.render_mode == "rgb_array":
            return self._core.render(self.render_size)
        return None


def make(name, **kwargs):
    """The environment of pbcs-rs' registry called ``name`` (:class:`RegisteredEnv`; the maze
    as :class:`ContinuousMaze`, which adds reset-anywhere); ``kwargs`` go to its constructor.
    Every name also has a Gymnasium id, ``pbcs/<name>-v0``."""
    if name == "maze":
        if "map" in kwargs or "map_file" in kwargs:
            raise ValueError(
                "invalid `pointmaze.map`: a map (map=, map_file=) is for env `pointmaze` or "
                "`antmaze`, but the environment is `maze`"
            )
        return ContinuousMaze(**kwargs)
    return RegisteredEnv(name, **kwargs)
