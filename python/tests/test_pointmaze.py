"""The referee: gymnasium-robotics' own PointMaze_*-v3 (MuJoCo 3.17.0) and our Rust PointMaze
(``src/envs/pointmaze/``, driven through ``examples/pointmaze_step.rs``) are set to the same whole
states — position, velocity and the solver's warm start — and given the same actions; every
observation, warm start, reward, success flag and termination must be the same, bit for bit,
on every map: from random states anywhere in the free space with random actions (some outside
[-1, 1], some speeds beyond the ±5 clip), runs into walls and corners, and long episodes from
gymnasium-robotics' own resets, whose warm start our side carries step after step.

Needs gymnasium-robotics and mujoco==3.17.0 (pip) and the example built with the ``mujoco``
feature: ``$PBCS_POINTMAZE_STEP`` names it (CI sets it); without it the test is skipped."""

import os
import subprocess
import tomllib
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]

MAPS = ["UMaze", "Open", "Medium", "Large", "Own"]

# A map of one's own (10 × 10 cells, the grid experiments/pointmaze_own.toml runs): gymnasium-
# robotics builds it from `maze_map=` these rows, ours from the same rows.
OWN_MAP = ROOT / "experiments/maps/pointmaze_own.txt"


def own_rows():
    rows = [line.split("#")[0].replace(" ", "").strip() for line in OWN_MAP.read_text().splitlines()]
    return [r for r in rows if r]


@pytest.fixture(scope="module")
def ours():
    path = os.environ.get("PBCS_POINTMAZE_STEP")
    if not path:
        pytest.skip("set PBCS_POINTMAZE_STEP to examples/pointmaze_step built with --features mujoco")
    proc = subprocess.Popen(
        [path], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, bufsize=1
    )
    yield proc
    proc.stdin.close()
    assert proc.wait(timeout=30) == 0


def ask(proc, line):
    proc.stdin.write(line + "\n")
    proc.stdin.flush()


def task(proc, name):
    if name == "Own":
        ask(proc, "map own " + " ".join(own_rows()))
        assert proc.stdout.readline().strip() == ""
    ask(proc, f"task {name.lower()}")
    a, b, c, d = map(int, proc.stdout.readline().split())
    return (a, b), (c, d)


def run_ours(proc, name, state, actions, goal=None):
    """Our steps from `state` (x, y, vx, vy, w0, w1) under `actions` (float32 pairs), toward
    `goal` (the task's, the goal cell's centre, when None)."""
    numbers = [] if goal is None else ["goal", *(repr(float(g)) for g in goal)]
    numbers += [repr(float(v)) for v in state]
    numbers += [repr(float(v)) for a in actions for v in a]
    ask(proc, f"{name.lower()} " + " ".join(numbers))
    rows = []
    while (line := proc.stdout.readline().strip()) != "":
        w = line.split()
        rows.append(([float(v) for v in w[:6]], float(w[6]), w[7] == "true", w[8] == "true"))
    assert len(rows) == len(actions)
    return rows


def run_theirs(env, state, actions):
    """gymnasium-robotics' steps from the same whole state."""
    point = env.point_env
    point.set_state(np.array(state[:2]), np.array(state[2:4]))
    point.data.qacc_warmstart[:] = state[4:6]
    rows = []
    for a in actions:
        obs, reward, terminated, _, info = env.step(a)
        full = list(obs["observation"]) + list(point.data.qacc_warmstart)
        rows.append((full, float(reward), bool(info["success"]), bool(terminated)))
    return rows


def same(ours_rows, theirs_rows, what):
    for t, (o, g) in enumerate(zip(ours_rows, theirs_rows)):
        bits_o = np.array(o[0], dtype=np.float64).view(np.uint64)
        bits_g = np.array(g[0], dtype=np.float64).view(np.uint64)
        assert (bits_o == bits_g).all(), f"{what}, step {t}: ours {o[0]}, theirs {g[0]}"
        assert o[1:] == g[1:], f"{what}, step {t}: ours {o[1:]}, theirs {g[1:]}"


@pytest.mark.parametrize("name", MAPS)
def test_our_pointmaze_steps_as_gymnasium_robotics_does(ours, name):
    gym = pytest.importorskip("gymnasium")
    gymnasium_robotics = pytest.importorskip("gymnasium_robotics")
    mujoco = pytest.importorskip("mujoco")
    assert mujoco.__version__ == "3.17.0"
    gym.register_envs(gymnasium_robotics)
    if name == "Own":
        rows = [[int(c) for c in r] for r in own_rows()]
        assert len(rows) >= 10 and len(rows[0]) >= 10
        env = gym.make("PointMaze_UMaze-v3", maze_map=rows, continuing_task=False).unwrapped
    else:
        env = gym.make(f"PointMaze_{name}-v3", continuing_task=False).unwrapped
    start, goal = task(ours, name)
    maze = env.maze
    env.reset(seed=0, options={"reset_cell": np.array(start), "goal_cell": np.array(goal)})
    # The task's goal is the goal cell's centre, by gymnasium-robotics' own conversion.
    env.goal = maze.cell_rowcol_to_xy(np.array(goal))
    rng = np.random.default_rng(sum(map(ord, name)))
    free = [
        (i, j)
        for i in range(maze.map_length)
        for j in range(maze.map_width)
        if maze.maze_map[i][j] != 1
    ]
    checked = 0
    # Random whole states anywhere in the free cells, random actions.
    for episode in range(40):
        cell = free[rng.integers(len(free))]
        xy = maze.cell_rowcol_to_xy(np.array(cell)) + rng.uniform(-0.5, 0.5, 2)
        v = rng.uniform(-6, 6, 2)
        w = rng.uniform(-50, 50, 2) if episode % 2 else np.zeros(2)
        state = [*xy, *v, *w]
        actions = rng.uniform(-1.2, 1.2, (40, 2)).astype(np.float32)
        same(run_ours(ours, name, state, actions), run_theirs(env, state, actions), f"{name} random {episode}")
        checked += len(actions)
    # Into walls and corners: full thrust along each diagonal and axis from the start, at rest.
    s0 = maze.cell_rowcol_to_xy(np.array(start))
    for direction in [(1, 1), (-1, 1), (1, -1), (-1, -1), (1, 0), (0, -1)]:
        state = [*s0, 0.0, 0.0, 0.0, 0.0]
        actions = np.tile(np.array(direction, dtype=np.float32), (150, 1))
        same(run_ours(ours, name, state, actions), run_theirs(env, state, actions), f"{name} push {direction}")
        checked += len(actions)
    # gymnasium-robotics' own resets (start and goal ±0.25), then a time limit of random
    # actions: the warm start is carried by each side from step to step.
    for seed in range(3):
        env.reset(seed=seed, options={"reset_cell": np.array(start), "goal_cell": np.array(goal)})
        point = env.point_env
        state = [*point.data.qpos, *point.data.qvel, *point.data.qacc_warmstart]
        env.goal = maze.cell_rowcol_to_xy(np.array(goal))
        n = {"UMaze": 300, "Open": 300, "Medium": 600, "Large": 800, "Own": 800}[name]
        actions = rng.uniform(-1, 1, (n, 2)).astype(np.float32)
        same(run_ours(ours, name, state, actions), run_theirs(env, state, actions), f"{name} reset {seed}")
        checked += len(actions)
    # The same resets toward the goal they drew (the `_goals` environments' episodes): reward,
    # success and termination for that goal, from a start within reach of it.
    for seed in range(3, 9):
        env.reset(seed=seed, options={"reset_cell": np.array(goal), "goal_cell": np.array(goal)})
        point = env.point_env
        state = [*point.data.qpos, *point.data.qvel, *point.data.qacc_warmstart]
        drawn = env.goal.copy()
        actions = rng.uniform(-1, 1, (60, 2)).astype(np.float32)
        same(
            run_ours(ours, name, state, actions, goal=drawn),
            run_theirs(env, state, actions),
            f"{name} drawn goal {seed}",
        )
        checked += len(actions)
    assert checked > 3000


def ks_distance(a, b):
    """The two-sample Kolmogorov-Smirnov statistic: the largest gap between the empirical
    distribution functions of `a` and `b`."""
    both = np.sort(np.concatenate([a, b]))
    fa = np.searchsorted(np.sort(a), both, side="right") / len(a)
    fb = np.searchsorted(np.sort(b), both, side="right") / len(b)
    return np.abs(fa - fb).max()


@pytest.mark.parametrize("name", ["UMaze", "Medium"])
def test_our_goal_resets_draw_as_gymnasium_robotics_does(ours, name):
    """The `_goals` environments' resets (Resets::Gym) against gymnasium-robotics' own with
    the task's cells: both inside the squares of half-side 0.25 around the cells' centres, and
    each coordinate of start and goal of 2 000 resets from the same law (two-sample
    Kolmogorov-Smirnov at the 0.1 % level: D below 1.95·sqrt(2/n)). The draws are not the
    same numbers (numpy's stream against ours), only the same law."""
    gym = pytest.importorskip("gymnasium")
    gymnasium_robotics = pytest.importorskip("gymnasium_robotics")
    gym.register_envs(gymnasium_robotics)
    env = gym.make(f"PointMaze_{name}-v3", continuing_task=False).unwrapped
    start, goal = task(ours, name)
    n = 2000
    theirs = []
    for seed in range(n):
        obs, _ = env.reset(seed=seed, options={"reset_cell": np.array(start), "goal_cell": np.array(goal)})
        assert (obs["observation"][2:] == 0).all() and (env.point_env.data.qacc_warmstart == 0).all()
        theirs.append([*obs["observation"][:2], *obs["desired_goal"]])
    ask(ours, f"resets {name.lower()} {n} 7")
    mine = [[float(v) for v in ours.stdout.readline().split()] for _ in range(n)]
    theirs, mine = np.array(theirs), np.array(mine)
    centres = np.array([*env.maze.cell_rowcol_to_xy(np.array(start)), *env.maze.cell_rowcol_to_xy(np.array(goal))])
    for drawn in (theirs, mine):
        offsets = drawn - centres
        assert (np.abs(offsets) <= 0.25).all(), offsets[np.abs(offsets) > 0.25]
    for k, what in enumerate(["start x", "start y", "goal x", "goal y"]):
        d = ks_distance(theirs[:, k], mine[:, k])
        assert d < 1.95 * np.sqrt(2 / n), f"{name} {what}: D = {d}"


@pytest.mark.parametrize(
    "cell, seed, weights",
    [
        ("pointmaze/pbcs_pm-pointmaze_umaze", 1, None),
        ("pointmaze_velocity/pbcs_pm_velocity-pointmaze_umaze", 21, [1.0, 1.0, 0.1, 0.1]),
        ("pointmaze_own/pbcs_pm-pointmaze", 7, None),
        ("pointmaze_gc/gc_pm-pointmaze_umaze", 7, None),
    ],
)
def test_a_committed_pointmaze_chain_scores_its_committed_gymnasium_number(
    tmp_path, cell, seed, weights
):
    """The table's number, re-made: UMaze seed 1 of experiments/pointmaze.toml (balls in
    position), seed 21 of experiments/pointmaze_velocity.toml's velocity arm (balls in
    position and velocity, whose weights the manifest keeps) and seed 7 on the map of one's
    own (experiments/pointmaze_own.toml, judged with `maze_map=` its rows), and seed 7 of the
    goal-conditioned chain (experiments/pointmaze_gc.toml: skills sharing one policy, each
    told its sub-goal) run again from their job files
    (the same env steps as their rows), each chain loaded in Python and judged by
    gymnasium-robotics (python/benches/pointmaze_gym.py's protocol): the same successes as the
    committed s<seed>.gym.csv. Needs `pbcs` built with --features mujoco:
    ``$PBCS_POINTMAZE_BIN`` (CI sets it); without it the test is skipped."""
    import csv

    import pbcs
    import pbcs.pointmaze as pm

    binary = os.environ.get("PBCS_POINTMAZE_BIN")
    if not binary:
        pytest.skip("set PBCS_POINTMAZE_BIN to `pbcs` built with --features mujoco")
    cell = ROOT / "results/raw" / cell
    row = next(csv.DictReader((cell / f"s{seed}.csv").open()))
    judged = next(csv.DictReader((cell / f"s{seed}.gym.csv").open()))
    out = tmp_path / "run"
    subprocess.run(
        [binary, "run", "--config", str(cell / f"s{seed}.toml"), "--out", str(out), "--quiet"],
        check=True,
    )
    again = next(csv.DictReader((out / "record.csv").open()))
    assert again["total_steps"] == row["env_steps"]
    manifest = tomllib.loads((out / "chain" / "manifest.toml").read_text())
    assert all(s.get("weights") == weights for s in manifest["skills"])
    chain = pbcs.load_chain(out / "chain")
    gym_id, start, goal, limit = chain.pointmaze
    assert (gym_id, start, goal) == ("PointMaze_UMaze-v3", *{
        "pbcs_pm-pointmaze_umaze": ((1, 1), (3, 1)),
        "pbcs_pm_velocity-pointmaze_umaze": ((1, 1), (3, 1)),
        "pbcs_pm-pointmaze": ((1, 3), (8, 7)),
        "gc_pm-pointmaze_umaze": ((1, 1), (3, 1)),
    }[row["cell"]])
    assert str(limit) == judged["time_limit"]
    # A map of one's own is judged on its rows (`maze_map=`), the named maps on their own.
    own = chain.pointmaze_map
    assert (own is not None) == ("maze_map=" in judged["gym_id"])
    if own is not None:
        assert ["".join(map(str, r)) for r in own] == own_rows()
    r = pm.evaluate(chain, episodes=100, seed=1_000_000 + seed)
    assert r["successes"] == int(judged["gym_successes"]) >= 95
