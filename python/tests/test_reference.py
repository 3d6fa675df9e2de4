"""The compiled maze against an independent plain numpy implementation of the same rules
(`reference_maze.NumpyMaze`): the same transitions, bit for bit, from random states and
actions on every size of the results table."""

import numpy as np
import pytest

import pbcs
from reference_maze import NumpyMaze


@pytest.mark.parametrize("size", [2, 5, 15])
def test_compiled_transitions_equal_the_numpy_reference(size):
    env = pbcs.ContinuousMaze(size=size)
    ref = NumpyMaze(env.maze)
    rng = np.random.default_rng(size)
    n = 5000
    # States anywhere in [0, N]² (inside walls too), actions beyond the bound too (clipped),
    # and a quarter of the states next to the target so that both rewards occur.
    states = rng.uniform(0, size, size=(n, 2)).astype(np.float32)
    states[: n // 4] = (np.asarray(env.maze.target) + rng.uniform(-0.3, 0.3, size=(n // 4, 2))).astype(np.float32)
    actions = rng.uniform(-0.15, 0.15, size=(n, 2)).astype(np.float32)
    got = np.empty_like(states)
    rewards = np.empty(n, dtype=np.float32)
    ends = np.empty(n, dtype=bool)
    for i in range(n):
        env.reset(options={"state": tuple(states[i])})
        obs, rewards[i], ends[i], _, _ = env.step(actions[i])
        got[i] = obs
    want, want_rewards, want_ends = ref.step(states, actions)
    assert (rewards < 0).sum() > 100 and (rewards > 0).sum() > 100  # both events exercised
    bad = np.flatnonzero(~((got == want).all(1) & (rewards == want_rewards) & (ends == want_ends)))
    assert bad.size == 0, f"{bad.size} transitions differ, first from {states[bad[0]]} by {actions[bad[0]]}"
