"""gymnasium-robotics' own PointMaze_UMaze-v3 set to our `pointmaze_umaze` task, with our
PointMaze's hooks written in Python, and the PointMaze grid's job: what the adapter's
byte-equality test (test_adapter.py) and python/benches/adapter_pointmaze.py run."""

import math
import re
from pathlib import Path

import gymnasium as gym
import numpy as np

ROOT = Path(__file__).resolve().parents[2]


def pointmaze_job(folder):
    """The PointMaze grid's job (experiments/pointmaze.toml, method pbcs_pm: the fast preset
    for momentum), on `pointmaze_umaze`."""
    text = (ROOT / "experiments" / "pbcs_fast.toml").read_text()
    for key, value in [("seed", '0\nenv = "pointmaze_umaze"'), ("shorten", "false"),
                       ("test_path_limit", "0.0"), ("max_steps", "150"), ("epsilon", "0.25"),
                       ("stop_at_failure", "false")]:
        text, n = re.subn(rf"(?m)^{key} = [^#\n]*", f"{key} = {value} ", text, count=1)
        assert n == 1, key
    path = Path(folder) / "pointmaze.toml"
    path.write_text(text)
    return path


class OurPointMazeTask(gym.Wrapper):
    """gymnasium-robotics' own PointMaze_UMaze-v3 (continuing_task=False) set to our
    `pointmaze_umaze` task (src/envs/pointmaze/sim.rs): every reset at rest at the centre of
    cell (1, 1), the goal the centre of cell (3, 1) (the env's reset of those cells with its
    noise off), and success (reward 1, the end) within 0.45 of every goal its noisy reset may
    draw: ‖(|Δx| + 0.25, |Δy| + 0.25)‖ ≤ 0.45. The step is the env's own."""

    NOISE = 0.25

    def __init__(self):
        import gymnasium_robotics

        gym.register_envs(gymnasium_robotics)
        super().__init__(gym.make("PointMaze_UMaze-v3", continuing_task=False))
        self.unwrapped.add_xy_position_noise = lambda xy: xy
        maze = self.unwrapped.maze
        # The wall cells' centres, for the distance to the nearest wall (PointMap::clearance).
        self.walls = [maze.cell_rowcol_to_xy(np.array([i, j]))
                      for i, row in enumerate(maze.maze_map) for j, c in enumerate(row) if c == 1]

    def reset(self, *, seed=None, options=None):
        cells = {"reset_cell": np.array([1, 1]), "goal_cell": np.array([3, 1])}
        return self.env.reset(seed=seed, options=cells)

    def step(self, action):
        obs, _, _, truncated, info = self.env.step(action)
        d = obs["achieved_goal"] - self.unwrapped.goal
        won = bool(np.hypot(abs(d[0]) + self.NOISE, abs(d[1]) + self.NOISE) <= 0.45)
        return obs, float(won), won, truncated, dict(info, success=won)

    def clearance(self, x, y):
        return min(np.hypot(max(abs(x - cx) - 0.5, 0.0), max(abs(y - cy) - 0.5, 0.0))
                   for cx, cy in self.walls)

    def sample_ball(self, state, radius, draws):
        """Our PointMaze's ball start: a point uniform in the disc (r = ε√u, angle uniform),
        redrawn while it would overlap a wall (16 draws, then the centre); the centre's
        velocity and warm start. qpos lies at 1, 2 of MuJoCo's state (after the time)."""
        for _ in range(16):
            r = radius * math.sqrt(draws.random())
            phi = math.tau * draws.random()
            x, y = state[1] + r * math.cos(phi), state[2] + r * math.sin(phi)
            if self.clearance(x, y) >= 0.1:
                state[1], state[2] = x, y
                return state
        return state

    def ball_is_clear(self, centre, radius):
        return self.clearance(float(centre[0]), float(centre[1])) >= radius + 0.1

    def adapter_settings(self):
        """What `pbcs.run(env=self, **...)` is given: our PointMaze's position, observation
        names, success region (the disc inside the region every goal agrees on) and hooks,
        recorded as `pointmaze_umaze`."""
        self.reset(seed=0)
        sure = 0.45 - self.NOISE * math.sqrt(2)
        return dict(position=slice(0, 2), observation_key="observation",
                    success_region=(self.unwrapped.goal.copy(), sure),
                    sample_ball=self.sample_ball, ball_is_clear=self.ball_is_clear,
                    observation_names=["x", "y", "vx", "vy"], recorded_as="pointmaze_umaze")
