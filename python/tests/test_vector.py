"""The vectorised maze: the same steps as N single mazes, Gymnasium's next-step autoreset."""

import gymnasium as gym
import numpy as np

import pbcs


def test_vector_steps_equal_single_steps():
    n, size = 16, 5
    envs = pbcs.ContinuousMazeVec(n, size=size, max_episode_steps=50)
    singles = [pbcs.ContinuousMaze(size=size, max_episode_steps=50) for _ in range(n)]
    obs, _ = envs.reset(seed=0)
    single_obs = np.stack([e.reset()[0] for e in singles])
    assert obs.tobytes() == single_obs.tobytes()
    rng = np.random.default_rng(0)
    ended = np.zeros(n, dtype=bool)
    for _ in range(200):
        actions = rng.uniform(-0.1, 0.1, size=(n, 2)).astype(np.float32)
        obs, rew, term, trunc, _ = envs.step(actions)
        for i, e in enumerate(singles):
            if ended[i]:  # next-step autoreset: this call reset maze i
                o = e.reset()[0]
                r, t, tr = 0.0, False, False
            else:
                o, r, t, tr, _ = e.step(actions[i])
            assert o.tobytes() == obs[i].tobytes()
            assert (r, t, tr) == (rew[i], term[i], trunc[i])
        ended = term | trunc


def test_make_vec_and_spaces():
    envs = gym.make_vec("pbcs/ContinuousMaze-v0", num_envs=3, vectorization_mode="vector_entry_point", size=2)
    obs, _ = envs.reset(seed=1)
    assert obs.shape == (3, 2) and envs.single_action_space.shape == (2,)
    assert envs.action_space.shape == (3, 2)
    obs, rew, term, trunc, _ = envs.step(envs.action_space.sample())
    assert rew.dtype == np.float64 and term.dtype == np.bool_


def test_reset_to_given_states():
    envs = pbcs.ContinuousMazeVec(2, size=2)
    obs, _ = envs.reset(options={"states": [[0.5, 1.25], [1.5, 0.5]]})
    obs, rew, term, _, _ = envs.step(np.array([[0.0, 0.1], [0.0, 0.1]], dtype=np.float32))
    assert term.tolist() == [True, False] and rew[0] == 1.0
