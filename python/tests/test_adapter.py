"""PBCS on Gymnasium environments the package did not write (`pbcs.Adapter`): the same bytes
as the Rust core on our maze when the env is the maze written in numpy, and on our PointMaze
when it is gymnasium-robotics' own set to our task (pointmaze_task.py), a room with a door
written here solved, and bad input refused before any work."""

import csv
import re
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import pbcs
from pointmaze_task import OurPointMazeTask, pointmaze_job
from reference_maze import NumpyMaze

ROOT = Path(__file__).resolve().parents[2]
# Files whose bytes depend on the wall clock; the pictures are not drawn through the adapter.
CLOCKED = {"timing.toml", "trace.timing.csv", "run.png", "run.svg"}


def adapter_job(tmp_path, size):
    """The fast preset with the settings that need walls (shortening, failure stops,
    retargets, path limits) off: those need hooks a user's env need not have."""
    text = (ROOT / "experiments" / "pbcs_fast.toml").read_text()
    for key, value in [("shorten", "false"), ("stop_at_failure", "false"), ("retargets", "0"),
                       ("test_path_limit", "0.0"), ("size", str(size))]:
        text, n = re.subn(rf"(?m)^{key} = [^#\n]*", f"{key} = {value} ", text, count=1)
        assert n == 1, key
    path = tmp_path / f"adapter{size}.toml"
    path.write_text(text)
    return path


class PythonMaze(gym.Env):
    """The paper's maze as a plain Gymnasium env whose step is `NumpyMaze`'s (numpy, no code
    of the package), its layout taken from the compiled maze, and a state to get and set."""

    def __init__(self, size):
        maze = pbcs.ContinuousMaze(size=size).maze
        self.ref, self.target = NumpyMaze(maze), np.asarray(maze.target, np.float32)
        self.observation_space = gym.spaces.Box(0.0, float(size), (2,), np.float32)
        self.action_space = gym.spaces.Box(-0.1, 0.1, (2,), np.float32)
        self.s = np.array([0.5, 0.5], np.float32)

    def reset(self, seed=None, options=None):
        super().reset(seed=seed)
        self.s = np.array([0.5, 0.5], np.float32)
        return self.s.copy(), {}

    def step(self, action):
        s, reward, reached = self.ref.step(self.s[None], np.asarray(action, np.float32)[None])
        self.s = s[0]
        return self.s.copy(), float(reward[0]), bool(reached[0]), False, {}

    def get_state(self):
        return self.s.copy()

    def set_state(self, state):
        self.s = np.asarray(state, np.float32).copy()


def folder_bytes(out):
    return {
        str(p.relative_to(out)): p.read_bytes()
        for p in sorted(out.rglob("*"))
        if p.is_file() and p.name not in CLOCKED
    }


@pytest.mark.parametrize("size", [2, 3])
def test_pbcs_through_the_adapter_on_a_numpy_maze_writes_the_rust_mazes_bytes(tmp_path, size):
    job = adapter_job(tmp_path, size)
    env = PythonMaze(size)
    gym_run = pbcs.run(env=env, position=slice(0, 2), success="terminated",
                       success_region=(env.target, 0.2), observation_names=["x", "y"],
                       recorded_as="maze", config=job, seed=3,
                       out=tmp_path / "gym", progress=False)
    rust_run = pbcs.run(config=job, seed=3, out=tmp_path / "rust")
    assert gym_run["solved"] and rust_run["solved"]
    got, want = folder_bytes(tmp_path / "gym"), folder_bytes(tmp_path / "rust")
    assert sorted(got) == sorted(k for k in want if k != "picture.csv" or k in got)
    differ = [k for k in got if got[k] != want[k]]
    assert not differ, f"files that differ: {differ}"
    assert (gym_run["tau"] == rust_run["tau"]).all()


class DoorRoom(gym.Env):
    """A point in the room [0, 2] × [0, 1] cut by a wall at x = 1 with a door at y in
    [0.8, 1.0]: from (0.3, 0.2) to the disc of radius 0.15 around (1.7, 0.2). Written here,
    numpy only."""

    observation_space = gym.spaces.Box(np.array([0.0, 0.0], np.float32),
                                       np.array([2.0, 1.0], np.float32))
    action_space = gym.spaces.Box(-0.1, 0.1, (2,), np.float32)
    goal = np.array([1.7, 0.2], np.float32)

    def reset(self, seed=None, options=None):
        super().reset(seed=seed)
        self.p = np.array([0.3, 0.2], np.float32)
        return self.p.copy(), {}

    def step(self, action):
        a = np.clip(np.asarray(action, np.float32), -0.1, 0.1)
        q = np.clip(self.p + a, [0.0, 0.0], [2.0, 1.0]).astype(np.float32)
        crosses = (self.p[0] - 1.0) * (q[0] - 1.0) <= 0 and self.p[0] != q[0]
        if crosses and not (0.8 <= (self.p[1] + q[1]) / 2 <= 1.0):
            q = self.p
        self.p = q
        won = bool(np.hypot(*(q - self.goal)) < 0.15)
        return q.copy(), float(won), won, False, {"success": won}

    def get_state(self):
        return self.p.copy()

    def set_state(self, state):
        self.p = np.asarray(state, np.float32).copy()


def test_pbcs_solves_a_room_with_a_door_written_in_the_test(tmp_path):
    env = DoorRoom()
    run = pbcs.run(env=env, position=[0, 1], success_region=(DoorRoom.goal, 0.15),
                   config=adapter_job(tmp_path, 2), seed=0, out=tmp_path / "run", progress=False)
    assert run["solved"] and run["success_rate"] >= 0.9, run
    # Recorded as an environment of one's own, which nothing but the adapter builds.
    assert run["env"] == "gym" and 'env = "gym"' in (tmp_path / "run/chain/run.toml").read_text()
    with open(tmp_path / "run" / "record.csv", newline="") as f:
        assert [row["env"] for row in csv.DictReader(f)] == ["gym"]
    with pytest.raises(ValueError, match="runs from Python only"):
        pbcs.run(env="gym")
    tau = run["tau"]
    assert np.hypot(*(tau[-1] - DoorRoom.goal)) < 0.15
    assert (tau[:, 1] >= 0.7).any()  # τ went through the door
    chain = pbcs.load_chain(tmp_path / "run" / "chain")
    assert len(chain) == run["skills"]
    played = chain.evaluate_in(pbcs.Adapter(DoorRoom(), [0, 1]), episodes=20)
    assert played["successes"] >= 18, played
    with pytest.raises(ValueError, match="invalid `episodes`"):
        chain.evaluate_in(pbcs.Adapter(DoorRoom(), [0, 1]), episodes=10**9)
    # Loaded against the adapter (the job's env is not the one it ran on): the same actions.
    adapter = pbcs.Adapter(DoorRoom(), [0, 1])
    mine = pbcs.load_chain(tmp_path / "run" / "chain", adapter=adapter)
    a, b = mine.evaluate_in(adapter, episodes=3), chain.evaluate_in(adapter, episodes=3)
    assert a["successes"] == b["successes"] and (a["steps"] == b["steps"]).all()
    assert np.array_equal(mine.act(tau[0]), chain.act(tau[0]))
    with pytest.raises(ValueError, match="the adapter's environment 3 and 2"):
        pbcs.load_chain(tmp_path / "run" / "chain", adapter=pbcs.Adapter(WithClock(), [0, 1]))
    # Phase 1 alone, same job and seed: the τ the run worked on (not shortened in this job).
    phase1 = pbcs.explore(env=DoorRoom(), position=[0, 1], config=adapter_job(tmp_path, 2))
    assert phase1["tau"].shape == tau.shape and (phase1["tau"] == tau).all()
    assert phase1["actions"].shape == (len(tau) - 1, 2) and phase1["env_steps"] >= len(tau) - 1


class WithClock(DoorRoom):
    """The room observing a third number, a step count."""

    observation_space = gym.spaces.Box(np.array([0.0, 0.0, 0.0], np.float32),
                                       np.array([2.0, 1.0, 1e6], np.float32))

    def reset(self, seed=None, options=None):
        obs, info = super().reset(seed=seed)
        self.t = 0.0
        return np.append(obs, self.t).astype(np.float32), info

    def step(self, action):
        obs, r, term, trunc, info = super().step(action)
        self.t += 1.0
        return np.append(obs, self.t).astype(np.float32), r, term, trunc, info

    def get_state(self):
        return np.append(self.p, self.t)

    def set_state(self, state):
        self.p, self.t = np.asarray(state[:2], np.float32).copy(), float(state[2])


class SwappedState(DoorRoom):
    """Its state is (y, x): as long as the observation, but not it."""

    def get_state(self):
        return self.p[::-1].copy()

    def set_state(self, state):
        self.p = np.asarray(state, np.float32)[::-1].copy()


def test_a_state_position_s0_does_not_confirm_offers_no_ball_starts(tmp_path):
    assert pbcs.Adapter(SwappedState(), [0, 1]).state_position is None
    with pytest.raises(ValueError, match=r"phase2.start.*ball_starts"):
        pbcs.run(env=SwappedState(), position=[0, 1], config=adapter_job(tmp_path, 2),
                 success_region=(DoorRoom.goal, 0.15), progress=False)
    # Said explicitly, it is checked and refused naming it.
    with pytest.raises(ValueError, match="invalid `state_position`"):
        pbcs.Adapter(SwappedState(), [0, 1], state_position=[0, 1])
    assert pbcs.Adapter(SwappedState(), [0, 1], state_position=[1, 0]).state_position == [1, 0]


class NoState(DoorRoom):
    get_state = None


class ForgetfulState(DoorRoom):
    """`set_state` that keeps only x: a restore that does not restore."""

    def set_state(self, state):
        self.p = np.array([state[0], self.p[1]], np.float32)


class Discrete(DoorRoom):
    action_space = gym.spaces.Discrete(4)


class Broken(DoorRoom):
    """Its step raises after a few hundred steps, in the middle of phase 1."""

    calls = 0

    def step(self, action):
        Broken.calls += 1
        if Broken.calls > 300:
            raise ArithmeticError("the simulator diverged")
        return super().step(action)


@pytest.mark.parametrize(
    "env, kwargs, message",
    [
        (NoState(), {"position": [0, 1]}, "no get_state() method"),
        (ForgetfulState(), {"position": [0, 1]}, "does not restore"),
        (Discrete(), {"position": [0, 1]}, "1-D gymnasium.spaces.Box"),
        (DoorRoom(), {"position": slice(0, 3)}, "reaches past the 2 components"),
        (DoorRoom(), {"position": [2]}, "out of range"),
        (DoorRoom(), {}, "needs position="),
        (DoorRoom(), {"position": [0, 1], "success": "reward"}, "invalid `success`"),
        (DoorRoom(), {"position": [0, 1], "reset_seed": -1}, "invalid `reset_seed`"),
        (DoorRoom(), {"position": [0, 1], "success_region": ([1.7], 0.15)}, "invalid `success_region`"),
        (DoorRoom(), {"position": [0, 1], "success_region": ([1.7, 0.2], float("inf"))},
         "invalid `success_region`"),
        (DoorRoom(), {"position": [0, 1], "sample_ball": 3}, "invalid `sample_ball`"),
        (SwappedState(), {"position": [0, 1], "sample_ball": lambda s, r, d: s},
         "not known: give state_position="),
        (DoorRoom(), {"position": [0, 1], "recorded_as": "gym"}, "invalid `recorded_as`"),
    ],
)
def test_bad_environments_are_refused_before_any_work(tmp_path, env, kwargs, message):
    with pytest.raises(ValueError, match=re.escape(message)):
        pbcs.run(env=env, config=adapter_job(tmp_path, 2), out=tmp_path / "out", **kwargs)
    assert not (tmp_path / "out").exists()


def test_a_job_needing_a_hook_the_env_lacks_is_refused_naming_the_setting(tmp_path):
    with pytest.raises(ValueError, match=r"phase2.stop_at_failure.*clear_balls"):
        pbcs.run(env=DoorRoom(), position=[0, 1], success_region=(DoorRoom.goal, 0.15),
                 preset="fast", out=tmp_path / "out", progress=False)
    assert not (tmp_path / "out").exists()


def test_a_sample_ball_hook_draws_from_the_runs_stream_and_is_checked(tmp_path):
    seen = []

    def centre_itself(state, radius, draws):
        seen.append((draws.random(), draws.random_f32()))
        return state

    job = adapter_job(tmp_path, 2)
    first = pbcs.run(env=DoorRoom(), position=[0, 1], success_region=(DoorRoom.goal, 0.15),
                     sample_ball=centre_itself, config=job, progress=False)
    draws, seen[:] = list(seen), []
    again = pbcs.run(env=DoorRoom(), position=[0, 1], success_region=(DoorRoom.goal, 0.15),
                     sample_ball=centre_itself, config=job, progress=False)
    # Called for every start in a ball, the same numbers in the same order for the same seed,
    # each in [0, 1); and what the hook drew was taken from the stream, not drawn again.
    assert draws and seen == draws and first["total_steps"] == again["total_steps"]
    flat = np.array(draws).ravel()
    assert ((0 <= flat) & (flat < 1)).all() and len(set(flat.tolist())) == flat.size
    with pytest.raises(RuntimeError, match="sample_ball hook raised ValueError") as e:
        pbcs.run(env=DoorRoom(), position=[0, 1], success_region=(DoorRoom.goal, 0.15),
                 sample_ball=lambda s, r, d: s[:1], config=job, out=tmp_path / "out",
                 progress=False)
    assert "a state of 2 finite numbers" in str(e.value.__cause__)
    assert not (tmp_path / "out").exists()


def test_an_exception_in_the_users_step_stops_the_run_naming_the_call(tmp_path):
    Broken.calls = 0
    with pytest.raises(RuntimeError, match="environment's step raised ArithmeticError") as e:
        pbcs.run(env=Broken(), position=[0, 1], success_region=(DoorRoom.goal, 0.15),
                 config=adapter_job(tmp_path, 2), out=tmp_path / "out", progress=False)
    assert isinstance(e.value.__cause__, ArithmeticError)
    assert not (tmp_path / "out").exists()


def test_mujoco_state_replays_an_ants_step_where_qpos_and_qvel_do_not():
    robotics = pytest.importorskip("gymnasium_robotics")
    gym.register_envs(robotics)
    env = gym.make("AntMaze_UMaze-v5", continuing_task=False)
    env.reset(seed=0)
    ant, whole = env.unwrapped.ant_env, pbcs.MujocoState(env)
    rng = np.random.default_rng(0)
    for _ in range(200):  # into contacts with the floor, where the warm start matters
        env.step(rng.uniform(-1, 1, 8).astype(np.float32))
    state, qpos, qvel = whole.get_state(), ant.data.qpos.copy(), ant.data.qvel.copy()
    action = rng.uniform(-1, 1, 8).astype(np.float32)
    first = env.step(action)[0]["observation"]
    whole.set_state(state)
    assert np.array_equal(env.step(action)[0]["observation"], first)
    ant.set_state(qpos, qvel)
    assert not np.array_equal(env.step(action)[0]["observation"], first)


def test_phase_1_on_gymnasium_roboticss_own_pointmaze_reaches_its_goal():
    robotics = pytest.importorskip("gymnasium_robotics")
    gym.register_envs(robotics)
    env = gym.make("PointMaze_UMaze-v3", continuing_task=False)
    found = pbcs.explore(env=env, position=slice(0, 2), observation_key="observation", seed=0)
    tau, goal = found["tau"], env.unwrapped.goal
    assert tau.shape[1] == 4 and found["env_steps"] >= len(tau) - 1
    assert np.hypot(*(tau[-1, :2] - goal)) <= 0.45 < np.hypot(*(tau[0, :2] - goal))
    # A dict observation needs its key, named in the refusal.
    with pytest.raises(ValueError, match="observation_key"):
        pbcs.explore(env=gym.make("PointMaze_UMaze-v3"), position=slice(0, 2))


def test_an_adapter_used_twice_gives_the_same_phase_1(tmp_path):
    adapter = pbcs.Adapter(DoorRoom(), [0, 1])
    job = adapter_job(tmp_path, 2)
    first = pbcs.explore(env=adapter, config=job, seed=1)
    # The env is left where phase 1 ended; the second run must still start from s_0.
    second = pbcs.explore(env=adapter, config=job, seed=1)
    assert (first["tau"] == second["tau"]).all() and first["env_steps"] == second["env_steps"]


@pytest.mark.skipif(not pbcs.MUJOCO, reason="a build without MuJoCo has no PointMaze of ours")
@pytest.mark.parametrize("seed", [1, 2])
def test_pbcs_through_the_adapter_on_gymnasium_roboticss_pointmaze_writes_our_pointmazes_bytes(
        tmp_path, seed):
    pytest.importorskip("gymnasium_robotics")
    env = OurPointMazeTask()
    job = pointmaze_job(tmp_path)
    gym_run = pbcs.run(env=env, **env.adapter_settings(), config=job, seed=seed,
                       out=tmp_path / "gym", progress=False)
    rust_run = pbcs.run(config=job, seed=seed, out=tmp_path / "rust")
    assert rust_run["env"] == "pointmaze_umaze" and gym_run["solved"] and rust_run["solved"]
    got, want = folder_bytes(tmp_path / "gym"), folder_bytes(tmp_path / "rust")
    assert sorted(got) == sorted(want)
    differ = [k for k in got if got[k] != want[k]]
    # picture.csv holds the picture's points, which our PointMaze draws with the map in
    # [0, 5] × [0, 5]: the adapter, which knows no map, writes them unshifted.
    assert differ == ["picture.csv"], f"files that differ: {differ}"
    rows = [np.loadtxt(tmp_path / f / "picture.csv", delimiter=",", skiprows=1,
                       usecols=(1, 2, 3, 4)) for f in ("gym", "rust")]
    shift = np.array([0.0, 2.5, 2.5, 0.0])
    assert rows[0].shape == rows[1].shape and np.allclose(rows[0] + shift, rows[1], atol=1e-6)
