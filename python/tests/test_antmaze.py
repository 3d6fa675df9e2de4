"""The referee for AntMaze: gymnasium-robotics' own AntMaze_*-v5 (continuing_task=False,
include_cfrc_ext_in_observation=False; MuJoCo 3.17.0) and our Rust AntMaze
(``src/envs/antmaze/``, driven through ``examples/antmaze_step.rs``) are set to the same whole
states — the ant's 15 positions, 14 velocities and the solver's warm start — and given the same
actions; every position, velocity, warm start, reward, success flag and termination must be the
same, bit for bit, on every map and one of one's own: episodes from gymnasium-robotics' own
resets whose state each side carries for a whole time limit, random whole states (the torso
anywhere in the free space at any height and orientation, joints and velocities random, some
actions outside [-1, 1]), runs into walls, and an ant upside down.

Needs gymnasium-robotics and mujoco==3.17.0 (pip) and the example built with the ``mujoco``
feature: ``$PBCS_ANTMAZE_STEP`` names it (CI sets it); without it the test is skipped."""

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]

MAPS = ["UMaze", "Open", "Medium", "Large", "Own"]

# A map of one's own: the grid experiments/pointmaze_own.toml runs, in cells of 4 m.
OWN_MAP = ROOT / "experiments/maps/pointmaze_own.txt"

LIMITS = {"UMaze": 700, "Open": 700, "Medium": 1000, "Large": 1000, "Own": 1000}


def own_rows():
    rows = [line.split("#")[0].replace(" ", "").strip() for line in OWN_MAP.read_text().splitlines()]
    return [r for r in rows if r]


@pytest.fixture(scope="module")
def ours():
    path = os.environ.get("PBCS_ANTMAZE_STEP")
    if not path:
        pytest.skip("set PBCS_ANTMAZE_STEP to examples/antmaze_step built with --features mujoco")
    proc = subprocess.Popen([path], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, bufsize=1)
    yield proc
    proc.stdin.close()
    assert proc.wait(timeout=30) == 0


def ask(proc, line):
    proc.stdin.write(line + "\n")
    proc.stdin.flush()


def theirs_env(name):
    gym = pytest.importorskip("gymnasium")
    gymnasium_robotics = pytest.importorskip("gymnasium_robotics")
    mujoco = pytest.importorskip("mujoco")
    assert mujoco.__version__ == "3.17.0"
    gym.register_envs(gymnasium_robotics)
    kwargs = dict(continuing_task=False, include_cfrc_ext_in_observation=False)
    if name == "Own":
        kwargs["maze_map"] = [[int(c) for c in r] for r in own_rows()]
        return gym.make("AntMaze_UMaze-v5", **kwargs).unwrapped
    return gym.make(f"AntMaze_{name}-v5", **kwargs).unwrapped


def task(proc, name):
    if name == "Own":
        ask(proc, "map own " + " ".join(own_rows()))
        assert proc.stdout.readline().strip() == ""
    ask(proc, f"task {name.lower()}")
    a, b, c, d = map(int, proc.stdout.readline().split())
    return (a, b), (c, d)


def whole(env):
    d = env.ant_env.data
    return [float(v) for v in [*d.qpos, *d.qvel, *d.qacc_warmstart]]


def run_ours(proc, name, goal, state, actions):
    numbers = [repr(float(v)) for v in [*goal, *state]]
    numbers += [repr(float(v)) for a in actions for v in a]
    ask(proc, f"{name.lower()} goal " + " ".join(numbers))
    rows = []
    while (line := proc.stdout.readline().strip()) != "":
        w = line.split()
        rows.append(([float(v) for v in w[:43]], float(w[43]), w[44] == "true", w[45] == "true"))
    assert len(rows) == len(actions)
    return rows


WALLS = set()


def run_theirs(env, goal, state, actions):
    """gymnasium-robotics' steps from the same whole state toward `goal`; its observation dict
    must be the state's positions and velocities, and MuJoCo must not have warned (a warning
    on bad values resets its data, and both sides would then agree on a reset state). Records
    in WALLS whether a wall block was touched."""
    d, m = env.ant_env.data, env.ant_env.model
    warned = [w.number for w in d.warning]
    d.qpos[:], d.qvel[:], d.qacc_warmstart[:] = state[:15], state[15:29], state[29:]
    env.goal = np.array(goal, dtype=np.float64)
    rows = []
    WALLS.discard("touched")
    for a in actions:
        obs, reward, terminated, _, info = env.step(a)
        assert (obs["achieved_goal"] == d.qpos[:2]).all()
        assert (obs["observation"] == np.concatenate([d.qpos[2:], d.qvel])).all()
        assert (obs["desired_goal"] == env.goal).all()
        rows.append((whole(env), float(reward), bool(info["success"]), bool(terminated)))
        for c in d.contact[: d.ncon]:
            if any(m.geom(g).name.startswith("block_") for g in (c.geom1, c.geom2)):
                WALLS.add("touched")
    assert [w.number for w in d.warning] == warned, "MuJoCo warned: the data was reset"
    return rows


def same(ours_rows, theirs_rows, what):
    assert len(ours_rows) == len(theirs_rows)
    for t, (o, g) in enumerate(zip(ours_rows, theirs_rows)):
        bits_o = np.array(o[0], dtype=np.float64).view(np.uint64)
        bits_g = np.array(g[0], dtype=np.float64).view(np.uint64)
        assert (bits_o == bits_g).all(), f"{what}, step {t}: ours {o[0]}, theirs {g[0]}"
        assert o[1:] == g[1:], f"{what}, step {t}: ours {o[1:]}, theirs {g[1:]}"


def random_quaternion(rng):
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


@pytest.mark.parametrize("name", MAPS)
def test_our_antmaze_steps_as_gymnasium_robotics_does(ours, name):
    env = theirs_env(name)
    maze = env.maze
    start, goal = task(ours, name)
    rng = np.random.default_rng(sum(map(ord, name)))
    cells = {"reset_cell": np.array(start), "goal_cell": np.array(goal)}
    checked = 0
    # gymnasium-robotics' own resets of the task's cells (start and goal ±1 m), then a whole
    # time limit of random actions: each side carries its own state from step to step.
    for seed in range(2):
        env.reset(seed=seed, options=cells)
        state, drawn = whole(env), env.goal.copy()
        ask(ours, f"reset {name.lower()} " + " ".join(repr(float(v)) for v in [*state[:2], *drawn]))
        mine = [float(v) for v in ours.stdout.readline().split()]
        assert np.array_equal(np.array(mine).view(np.uint64), np.array(state).view(np.uint64))
        actions = rng.uniform(-1, 1, (LIMITS[name], 8)).astype(np.float32)
        same(run_ours(ours, name, drawn, state, actions), run_theirs(env, drawn, state, actions), f"{name} reset {seed}")
        checked += len(actions)
    # Random whole states: the torso over any free cell at any height and orientation (upside
    # down among them), joints anywhere in or past their ranges, velocities and warm starts
    # random; some actions past the control range (MuJoCo clamps them).
    free = [(i, j) for i in range(maze.map_length) for j in range(maze.map_width) if maze.maze_map[i][j] != 1]
    flipped = 0
    for episode in range(30):
        cell = free[rng.integers(len(free))]
        xy = maze.cell_rowcol_to_xy(np.array(cell)) + rng.uniform(-1.5, 1.5, 2)
        q = random_quaternion(rng)
        flipped += 1 - 2 * (q[1] ** 2 + q[2] ** 2) < 0
        qpos = [*xy, rng.uniform(0.2, 1.5), *q, *rng.uniform(-1.3, 1.3, 8)]
        qvel = [*rng.normal(0, 2, 6), *rng.normal(0, 5, 8)]
        warm = rng.normal(0, 20, 14) if episode % 2 else np.zeros(14)
        state = [*qpos, *qvel, *warm]
        goal_xy = maze.cell_rowcol_to_xy(np.array(goal)) + rng.uniform(-1, 1, 2)
        actions = rng.uniform(-1.3, 1.3, (40, 8)).astype(np.float32)
        same(run_ours(ours, name, goal_xy, state, actions), run_theirs(env, goal_xy, state, actions), f"{name} random {episode}")
        checked += len(actions)
    assert flipped >= 5
    # Near the goal, 0.3 to 0.6 m from it (success within 0.45): reward 1, success and the end
    # of the episode, on both sides of the edge.
    ends = set()
    for episode in range(12):
        env.reset(seed=episode, options=cells)
        state, drawn = whole(env), env.goal.copy()
        angle, r = rng.uniform(0, 2 * np.pi), rng.uniform(0.3, 0.6)
        state[0], state[1] = drawn[0] + r * np.cos(angle), drawn[1] + r * np.sin(angle)
        actions = rng.uniform(-1, 1, (25, 8)).astype(np.float32)
        rows = run_theirs(env, drawn, state, actions)
        same(run_ours(ours, name, drawn, state, actions), rows, f"{name} near the goal {episode}")
        ends |= {r[1:] for r in rows}
        checked += len(actions)
    assert (1.0, True, True) in ends and (0.0, False, False) in ends, ends
    # Into the walls: from the start cell, thrown at 4 m/s along each axis and diagonal, legs
    # kicking at random; some throw reaches a wall.
    s0 = maze.cell_rowcol_to_xy(np.array(start))
    walls = 0
    for direction in [(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (-1, -1)]:
        env.reset(seed=0, options=cells)
        state = whole(env)
        state[0], state[1] = s0
        state[15], state[16] = 4 * np.array(direction) / np.hypot(*direction)
        actions = rng.uniform(-1, 1, (120, 8)).astype(np.float32)
        g = maze.cell_rowcol_to_xy(np.array(goal))
        rows = run_theirs(env, g, state, actions)
        walls += "touched" in WALLS
        same(run_ours(ours, name, g, state, actions), rows, f"{name} wall {direction}")
        checked += len(actions)
    print(name, "throws that touched a wall:", walls)
    assert walls >= 3
    # An ant upside down (rotated π about x), dropped from 1 m, legs kicking: it stays on its back.
    env.reset(seed=1, options=cells)
    state = whole(env)
    state[2:7] = [1.0, 0.0, 1.0, 0.0, 0.0]
    actions = rng.uniform(-1, 1, (200, 8)).astype(np.float32)
    g = maze.cell_rowcol_to_xy(np.array(goal))
    rows = run_theirs(env, g, state, actions)
    same(run_ours(ours, name, g, state, actions), rows, f"{name} upside down")
    up = [1 - 2 * (r[0][4] ** 2 + r[0][5] ** 2) for r in rows]
    assert min(up) < 0, "the ant was never upside down"
    checked += len(actions)
    assert checked > 2500


def ks_distance(a, b):
    """The two-sample Kolmogorov-Smirnov statistic."""
    both = np.sort(np.concatenate([a, b]))
    fa = np.searchsorted(np.sort(a), both, side="right") / len(a)
    fb = np.searchsorted(np.sort(b), both, side="right") / len(b)
    return np.abs(fa - fb).max()


@pytest.mark.parametrize("name", ["UMaze", "Large"])
def test_our_antmaze_resets_draw_as_gymnasium_robotics_does(ours, name):
    """Our resets (Resets::Gym) against gymnasium-robotics' own with the task's cells: both
    inside the squares of half-side 1 m around the cells' centres, and each coordinate of start
    and goal of 2 000 resets from the same law (two-sample Kolmogorov-Smirnov at the 0.1 %
    level: D below 1.95·sqrt(2/n)); the ant at rest, level, its joints at 0."""
    env = theirs_env(name)
    start, goal = task(ours, name)
    n = 2000
    theirs = []
    for seed in range(n):
        obs, _ = env.reset(seed=seed, options={"reset_cell": np.array(start), "goal_cell": np.array(goal)})
        d = env.ant_env.data
        assert (d.qvel == 0).all() and (d.qacc_warmstart == 0).all()
        assert (d.qpos[2:] == [0.75, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]).all()
        theirs.append([*obs["achieved_goal"], *obs["desired_goal"]])
    ask(ours, f"resets {name.lower()} {n} 7")
    mine = np.array([[float(v) for v in ours.stdout.readline().split()] for _ in range(n)])
    theirs = np.array(theirs)
    centres = np.array([*env.maze.cell_rowcol_to_xy(np.array(start)), *env.maze.cell_rowcol_to_xy(np.array(goal))])
    for drawn in (theirs, mine):
        assert (np.abs(drawn - centres) <= 1.0).all()
    for k, what in enumerate(["start x", "start y", "goal x", "goal y"]):
        d = ks_distance(theirs[:, k], mine[:, k])
        assert d < 1.95 * np.sqrt(2 / n), f"{name} {what}: D = {d}"
