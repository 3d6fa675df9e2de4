"""A second implementation of the maze's rules in plain numpy (its own slab test against every
wall, no grid and no parry2d): the reference the compiled maze is tested against
(`test_reference.py`) and the step bench compares speeds with."""

import numpy as np


class NumpyMaze:
    """The maze of `pbcs.ContinuousMaze` written in plain numpy for the comparison: N agents
    stepped at once; an action clipped to [-0.1, 0.1] per axis; a move whose closed segment
    touches a wall (the slab test against every wall rectangle, plus the end point inside a
    wall) stays put with reward -1; reaching the target disc (strictly inside) gives +1. No
    time limit and no reset: the bench steps, the comparison takes single transitions."""

    def __init__(self, maze, max_action=0.1, target_radius=0.2):
        w = np.asarray(maze.walls, dtype=np.float32)  # (W, 4): x0, y0, x1, y1
        self.lo, self.hi = w[:, :2][None], w[:, 2:][None]  # (1, W, 2)
        self.target = np.asarray(maze.target, dtype=np.float32)
        self.max_action, self.r2 = np.float32(max_action), np.float32(target_radius) ** 2

    def step(self, states, actions):
        a = np.nan_to_num(actions.astype(np.float32), nan=0.0)
        nxt = states + np.clip(a, -self.max_action, self.max_action)
        p, d = states[:, None, :], (nxt - states)[:, None, :]  # (N, 1, 2)
        with np.errstate(divide="ignore", invalid="ignore"):
            t1, t2 = (self.lo - p) / d, (self.hi - p) / d  # (N, W, 2)
        moving = d != 0
        inside = (p >= self.lo) & (p <= self.hi)  # an axis without motion: inside its slab
        tmin = np.where(moving, np.minimum(t1, t2), np.where(inside, -np.inf, np.inf)).max(-1)
        tmax = np.where(moving, np.maximum(t1, t2), np.where(inside, np.inf, -np.inf)).min(-1)
        ray = (tmin <= tmax) & (tmax >= 0) & (tmin <= 1)
        q = nxt[:, None, :]
        end = ((q >= self.lo) & (q <= self.hi)).all(-1)
        hit = (ray | end).any(-1)
        states = np.where(hit[:, None], states, nxt)
        reached = ((states - self.target) ** 2).sum(-1) < self.r2
        return states, reached.astype(np.float32) - hit.astype(np.float32), reached
