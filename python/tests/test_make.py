"""Every environment of the registry by name: ``pbcs.make(name)`` and the Gymnasium ids
``pbcs/<name>-v0`` pass Gymnasium's own checker, step as the Rust core does, and a name this
build cannot make (PointMaze without MuJoCo) is refused saying why."""

import re

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import pbcs

# Every name this build makes without arguments (PointMaze's and AntMaze's maps with MuJoCo;
# `pointmaze` and `antmaze` need a map: PointMaze's own test below).
RUNNABLE = [
    n for n in pbcs.ENV_NAMES
    if n not in ("pointmaze", "antmaze")
    and (pbcs.MUJOCO or not n.startswith(("pointmaze_", "antmaze_")))
]


def test_the_registry_lists_the_maze_the_rooms_and_pointmaze():
    assert pbcs.ENV_NAMES[:2] == ("maze", "rooms")
    assert {"pointmaze_umaze", "pointmaze_large", "pointmaze"} <= set(pbcs.ENV_NAMES)


def test_a_goal_drawing_name_is_refused_naming_gymnasium_robotics_own():
    # pointmaze_<map>_goals draws a goal per episode; this binding's observation would not show
    # it, so it is not in ENV_NAMES and making it says what to use instead.
    assert not [n for n in pbcs.ENV_NAMES if n.endswith("_goals")]
    with pytest.raises(ValueError, match=r"PointMaze_UMaze-v3.*pointmaze_umaze"):
        pbcs.make("pointmaze_umaze_goals")
    # So does AntMaze's: antmaze_<map>_goals is refused, antmaze_<map> is PBCS's fixed task.
    assert {"antmaze_umaze", "antmaze_large", "antmaze"} <= set(pbcs.ENV_NAMES)
    with pytest.raises(ValueError, match=r"AntMaze_Large-v5.*`antmaze_large` for PBCS's fixed"):
        pbcs.make("antmaze_large_goals")


@pytest.mark.parametrize("name", RUNNABLE)
def test_every_environment_passes_gymnasiums_checker(name):
    check_env(pbcs.make(name), skip_render_check=False)
    check_env(pbcs.RegisteredEnv(name, render_mode="rgb_array"), skip_render_check=False)
    env = gym.make(f"pbcs/{name}-v0")
    obs, _ = env.reset(seed=0)
    assert env.observation_space.contains(obs)


def test_the_registrys_maze_steps_as_the_python_maze():
    ours = pbcs.RegisteredEnv("maze", size=3, layout=1, max_episode_steps=50)
    theirs = pbcs.ContinuousMaze(size=3, layout=1, max_episode_steps=50)
    a, _ = ours.reset(seed=0)
    b, _ = theirs.reset(seed=0)
    rng = np.random.default_rng(0)
    for _ in range(60):
        action = rng.uniform(-0.2, 0.2, size=2).astype(np.float32)
        ra, rb = ours.step(action), theirs.step(action)
        assert ra[0].tobytes() == rb[0].tobytes() and ra[1:4] == rb[1:4]
        if ra[2] or ra[3]:
            break


def test_the_rooms_reward_their_target_and_render():
    env = pbcs.make("rooms", render_mode="rgb_array", max_episode_steps=300)
    obs, _ = env.reset(seed=0)
    assert obs.tolist() == pytest.approx([0.3, 0.2])
    assert env.action_space.high.tolist() == pytest.approx([0.1, 0.1])
    done = False
    for _ in range(300):
        # Up to the door's height, through it, then to the target in the right room.
        x, y = obs
        action = [0.0, 0.1] if x < 1 and y < 0.9 else [0.1, 0.0] if x < 1.65 else [0.0, -0.1]
        obs, reward, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            done = terminated
            break
    picture = env.render()
    assert picture.shape == (256, 256, 3)
    assert done, obs


def test_names_and_arguments_this_build_refuses_say_why():
    with pytest.raises(ValueError, match="not an environment"):
        pbcs.make("hall")
    with pytest.raises(ValueError, match="rooms"):
        pbcs.make("rooms", size=4)
    with pytest.raises(ValueError, match="max_episode_steps"):
        pbcs.make("rooms", max_episode_steps=0)
    env = pbcs.make("rooms")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="2 components"):
        env.step([0.1])
    # Reset-anywhere from Python is the maze's: a start state elsewhere is refused, not ignored.
    with pytest.raises(ValueError, match="options"):
        env.reset(options={"state": (0.5, 0.5)})
    if not pbcs.MUJOCO:
        with pytest.raises(ValueError, match="MuJoCo"):
            pbcs.make("pointmaze_umaze")


def test_a_pointmaze_map_of_ones_own_is_checked_before_mujoco_is_needed(tmp_path):
    """``pbcs.make("pointmaze", map=...)``: a bad or misplaced map is a ValueError naming its
    field in any build; a good one (rows as strings, as lists, or a file) is the registry's
    PointMaze on that map where this build has MuJoCo, else refused saying why."""
    bad = [
        (dict(), "pointmaze.map"),
        (dict(map=["111", "121", "111"]), "0 (free) or 1"),
        (dict(map=[[1, 1, 1], [1, 2, 1], [1, 1, 1]]), "0 (free) or 1"),
        (dict(map=["111", "101", "111"]), "one free cell"),
        (dict(map=["1111", "1001", "111"]), "row 2 has 3"),
        (dict(map=["1111", "1001", "1111"], map_file="m.txt"), "not both"),
        (dict(map=3), "rows as strings"),
        (dict(map_file=str(tmp_path / "none.txt")), "none.txt"),
    ]
    for kwargs, says in bad:
        with pytest.raises(ValueError, match=re.escape(says)):
            pbcs.make("pointmaze", **kwargs)
    for other in ["rooms", "maze"]:
        with pytest.raises(ValueError, match="is for env `pointmaze`"):
            pbcs.make(other, map=["1111", "1001", "1111"])
    file = tmp_path / "map.txt"
    file.write_text("# mine\n1 1 1 1\n1 0 0 1\n1 1 1 1\n")
    for kwargs in [dict(map=["1111", "1001", "1111"]), dict(map=[[1, 1, 1, 1], [1, 0, 0, 1], [1, 1, 1, 1]]),
                   dict(map_file=str(file))]:
        if not pbcs.MUJOCO:
            with pytest.raises(ValueError, match="MuJoCo"):
                pbcs.make("pointmaze", **kwargs)
            continue
        env = pbcs.make("pointmaze", **kwargs)
        check_env(env)
        obs, _ = env.reset(seed=0)
        # The task's start: the first free cell's centre, at rest (x = (j + 0.5) − W/2).
        assert obs.tolist()[:4] == [-0.5, 0.0, 0.0, 0.0]


def test_a_three_rooms_chain_rolls_out_in_python_as_in_the_core(tmp_path):
    # The environment issue 47 added through the registry alone: a run, its chain, and that
    # chain stepped through pbcs.make's environment, the same episode as the core's.
    record = pbcs.run(env="three_rooms", seed=0, out=str(tmp_path / "run"))
    assert record["env"] == "three_rooms" and record["solved"]
    chain = pbcs.load_chain(record["chain"])
    core = chain.core_rollout()
    ours = chain.rollout()
    assert (ours["success"], ours["steps"]) == (core["success"], core["steps"])
    assert ours["states"][-1].tobytes() == core["states"][-1].tobytes()
    assert chain.render([core["states"]]).shape == (256, 256, 3)


@pytest.mark.skipif(not pbcs.MUJOCO, reason="a build of the package without MuJoCo")
def test_a_run_on_a_pointmaze_map_of_ones_own_from_python_is_its_committed_row(tmp_path):
    """``pbcs.run(env="pointmaze", map=...)`` on the committed grid's job (seed 7 of
    experiments/pointmaze_own.toml, with its map given from Python instead of the job): the same
    env steps and verdict as the committed row, and the saved chain evaluated by the core from
    Python as in the row."""
    import csv
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    cell = root / "results/raw/pointmaze_own/pbcs_pm-pointmaze"
    row = next(csv.DictReader((cell / "s7.csv").open()))
    grid = root / "results/raw/pointmaze/pbcs_pm-pointmaze_large/s0.toml"
    rows = [r for r in (root / "experiments/maps/pointmaze_own.txt").read_text().splitlines()
            if r and not r.startswith("#")]
    r = pbcs.run(config=str(grid), env="pointmaze", map=rows, seed=7, out=str(tmp_path / "run"))
    assert (r["env"], r["total_steps"], r["solved"]) == ("pointmaze", int(row["env_steps"]), True)
    chain = pbcs.load_chain(r["chain"])
    assert chain.pointmaze_map == [[int(c) for c in line] for line in rows]
    judged = chain.evaluate_in_core(episodes=100)
    assert judged["successes"] == round(float(row["success_rate"]) * 100)
    roll = chain.core_rollout()
    assert roll["success"] and roll["steps"] > 0
