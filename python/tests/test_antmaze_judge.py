"""The judge for AntMaze chains (``pbcs.antmaze``, issue 49 point 3): a saved chain acts in
gymnasium-robotics' own ``AntMaze_UMaze-v5`` (``continuing_task=False``, the 27-number
observation) from the env's resets of the task's cells, seeing the torso's (x, y) and the env's
27 numbers, as in our env. The chain is the development run of
``results/dev/issue49/phase2/long/`` (AntMaze UMaze seed 2, stopped by its budget: some skills,
the task not solved), committed with its job.

Needs gymnasium-robotics and mujoco==3.17.0 beside this package, built with ``--features
mujoco`` (``pbcs.MUJOCO``); otherwise skipped."""

from pathlib import Path

import numpy as np
import pytest

import pbcs

ROOT = Path(__file__).resolve().parents[2]
CHAIN = ROOT / "results/dev/issue49/phase2/long/chain"


@pytest.fixture(scope="module")
def chain():
    if not pbcs.MUJOCO:
        pytest.skip("pbcs built without --features mujoco")
    pytest.importorskip("gymnasium_robotics")
    return pbcs.load_chain(CHAIN)


def test_the_chain_names_its_task_in_gymnasium_robotics(chain):
    assert chain.env == "antmaze_umaze"
    assert chain.antmaze == ("AntMaze_UMaze-v5", (1, 1), (3, 1), 700)
    assert chain.pointmaze is None and chain.pointmaze_map is None


def test_the_judges_env_resets_the_cells_and_shows_what_our_env_shows(chain):
    import pbcs.antmaze as am

    env = am.make_env(chain)
    assert env.spec.max_episode_steps == 700
    centres = {(1, 1): (-4.0, 4.0), (3, 1): (-4.0, -4.0)}
    for seed in range(5):
        obs, _ = env.reset(seed=seed)
        o = obs["observation"]
        assert o.shape == (29,) and env.observation_space["observation"].contains(o)
        assert np.array_equal(o[:2], obs["achieved_goal"])
        assert np.abs(o[:2] - centres[(1, 1)]).max() <= 1.0
        assert np.abs(obs["desired_goal"] - centres[(3, 1)]).max() <= 1.0
    env.close()


def test_the_chain_sees_the_state_as_our_env_observes_it(chain):
    """Our env observes a state as gymnasium-robotics' ant holds it, qpos then qvel (the
    torso's x, y first), and while the chain acts in the judge's env, that env shows it the
    same (that the two envs step alike, bit for bit, is test_antmaze.py's)."""
    import pbcs.antmaze as am

    # Our env's first observation (at rest at the start cell's centre) is the same state's
    # qpos ++ qvel in gymnasium-robotics' ant, in float32.
    mine, _ = pbcs.make("antmaze_umaze").reset(seed=0)
    env = am.make_env(chain)
    env.reset(seed=0)
    ant = env.unwrapped.ant_env
    qpos = ant.init_qpos.copy()
    qpos[:2] = (-4.0, 4.0)
    ant.set_state(qpos, np.zeros(ant.model.nv))
    assert np.array_equal(mine, np.concatenate([ant.data.qpos, ant.data.qvel]).astype(np.float32))
    obs, _ = env.reset(seed=3)
    data = env.unwrapped.ant_env.data
    chain.reset()
    for _ in range(50):
        assert np.array_equal(obs["observation"], np.concatenate([data.qpos, data.qvel]))
        obs, _, terminated, truncated, _ = env.step(chain.act(obs["observation"]))
        if terminated or truncated:
            break
    env.close()


def test_the_judge_plays_episodes_to_the_time_limit_or_success(chain):
    import pbcs.antmaze as am

    r = am.evaluate(chain, episodes=3, seed=1_000_002)
    assert r["episodes"] == 3 and len(r["success"]) == 3
    assert all((s and n <= 700) or (not s and n == 700) for s, n in zip(r["success"], r["steps"]))
    again = am.evaluate(chain, episodes=3, seed=1_000_002)
    assert np.array_equal(r["steps"], again["steps"])


def test_a_chain_aiming_at_each_episodes_goal_is_told_the_goal_the_judge_drew(chain, tmp_path):
    """A chain built with ``phase2.last_goal = "drawn"`` (here the committed chain with its last
    skill marked so in a copy of its manifest) is told each episode's ``desired_goal`` by the
    judge's rollout: its last skill acts on the torso's position from that goal, which for the
    task's own goal is what the chain as saved does."""
    import shutil
    import tomllib

    import pbcs.antmaze as am

    copy = tmp_path / "chain"
    shutil.copytree(CHAIN, copy)
    manifest = (copy / "manifest.toml").read_text()
    (copy / "manifest.toml").write_text(manifest.rstrip("\n") + "\nepisode_goal = true\n")
    drawn = pbcs.load_chain(copy)
    assert drawn.needs_goal and not chain.needs_goal
    origin = np.array(tomllib.loads(manifest)["skills"][-1]["origin"][:2])
    env = am.make_env(drawn)
    obs, _ = env.reset(seed=5)
    last = len(chain.balls) - 1
    # In the last skill's ball: the same action for the task's own goal, another for the drawn.
    o = obs["observation"].copy()
    o[:2] = chain.balls[last][:2]
    chain.reset()
    drawn.reset()
    assert drawn.act(o, origin).tolist() == chain.act(o).tolist()
    assert drawn.active_skill == last
    drawn.reset()
    assert drawn.act(o, obs["desired_goal"]).tolist() != chain.act(o).tolist()
    # A chain that needs the goal cannot act without it.
    with pytest.raises(ValueError, match="desired_goal"):
        drawn.act(o)
    env.close()
    # The judge's rollout passes the goal it drew: with the first skill marked too (it acts
    # from the start, where the last one never comes), an episode replayed by hand with each
    # step's desired_goal visits the states of the rollout the judge counts, and another goal
    # would act otherwise.
    first = tmp_path / "first"
    shutil.copytree(copy, first)
    text = (first / "manifest.toml").read_text()
    head = text.index("[[skills]]\n") + len("[[skills]]\n")
    (first / "manifest.toml").write_text(text[:head] + "episode_goal = true\n" + text[head:])
    told = pbcs.load_chain(first)
    env = am.make_env(told)
    obs, _ = env.reset(seed=1_000_002)
    told.reset()
    assert (told.act(obs["observation"], obs["desired_goal"]).tolist()
            != told.act(obs["observation"], obs["achieved_goal"]).tolist())
    told.reset()
    states = [obs["observation"]]
    for _ in range(100):
        obs, _, terminated, truncated, _ = env.step(
            told.act(obs["observation"], obs["desired_goal"]))
        states.append(obs["observation"])
        if terminated or truncated:
            break
    r = told.rollout(env=am.make_env(told), max_steps=100, seed=1_000_002)
    assert np.array_equal(r["states"], np.stack(states))
    env.close()
