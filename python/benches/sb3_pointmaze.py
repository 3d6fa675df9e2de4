"""The practitioner's baseline of issue 35: Stable-Baselines3's SAC with HER on
gymnasium-robotics' own PointMaze_<map>-v3 (continuing_task=False), on the fixed task of our
experiment (start and goal cells: the two free cells farthest apart along the maze, found here
by a breadth-first search of the env's own map, 4-neighbour moves, ties to the first pair in
row-major order, start = the earlier cell; the same rule as src/envs/pointmaze/model.rs).

Protocol (the issue's point 4, the one PBCS's chains are judged by): every 10 000 env steps,
100 deterministic episodes in a separate PointMaze of the same cells, from the env's own
resets (start and goal drawn within ±0.25 of the cells' centres), within its time limit;
success = the env's ``info["success"]`` on the last step. Training stops at the first
evaluation with >= 95 successes, else after ``--steps`` (500 000) env steps.

Settings: SB3's SAC defaults (networks 256×256, lr 3e-4, batch 256, γ = 0.99, τ = 0.005,
buffer 1M, entropy auto) with HerReplayBuffer (4 sampled goals, strategy "future"), 1 000
random warm-up steps, one torch thread.

    python python/benches/sb3_pointmaze.py --map umaze --seeds 0-2 --out results/pointmaze/sb3

Each evaluation is appended to ``<out>/sac_her-pointmaze_<map>/s<seed>.evals.csv`` as it
happens, and the run saved right before it is appended (model, optimisers and HER replay buffer
under ``--checkpoints``, default ``~/.cache/pbcs-rs/sb3-checkpoints``, not committed; the
replay buffer holds only its rows written so far, about 166 bytes a step: 17 MB at 100 000
steps, so that a checkpoint can travel between machines). An interrupted run resumes from its
last checkpoint when the script is started again (``s<seed>.resumes.csv`` lists where);
evaluations already written are never rewritten. A resumed run is not the uninterrupted one:
the training episode in progress is cut, and SB3's random streams, the training env's and the
evaluation env's resets are seeded again from the run seed and the step it resumes at (so a
resume at the same step is repeatable; the transition of the checkpoint's own step, not yet
stored when it was taken, is lost). A run is repeatable on one machine and torch only: the same
seed on another gave other evaluations from the first one on. A run stopped before its first
evaluation starts afresh; a fresh start removes any checkpoint of its seed; a checkpoint that
does not continue the evaluations written (its step and successes, its budget) is refused, as
is a run with evaluations and no checkpoint (move its file away to start over); a refused seed
is reported and the next one runs (exit status 1). The finished run writes ``s<seed>.csv``
atomically (a finished seed is skipped on re-run) and its wall clock beside it in
``s<seed>.timing.toml``. Needs stable-baselines3 and torch; not part of CI.
"""

import argparse
import copy
import csv
import io
import json
import pickle
import shutil
import sys
import time
from collections import deque
from pathlib import Path

from common import write_atomic
import numpy as np
from pbcs.pointmaze import FixedCells
import gymnasium as gym
import gymnasium_robotics

gym.register_envs(gymnasium_robotics)

MAPS = {"umaze": "UMaze", "open": "Open", "medium": "Medium", "large": "Large"}
EVAL_EVERY = 10_000
EVAL_EPISODES = 100
SOLVED = 95


def farthest_cells(maze_map):
    """The pair of free cells farthest apart along the maze (see the module's docstring)."""
    rows, cols = len(maze_map), len(maze_map[0])
    free = [(i, j) for i in range(rows) for j in range(cols) if maze_map[i][j] != 1]
    best = (-1, None, None)
    for a in free:
        dist = {a: 0}
        queue = deque([a])
        while queue:
            i, j = queue.popleft()
            for di, dj in ((-1, 0), (1, 0), (0, -1), (0, 1)):
                n = (i + di, j + dj)
                if n in dist or not (0 <= n[0] < rows and 0 <= n[1] < cols):
                    continue
                if maze_map[n[0]][n[1]] == 1:
                    continue
                dist[n] = dist[(i, j)] + 1
                queue.append(n)
        for b in free:
            if b > a and dist.get(b, -1) > best[0]:
                best = (dist[b], a, b)
    return best


def make_env(name, start, goal):
    return FixedCells(gym.make(f"PointMaze_{name}-v3", continuing_task=False), start, goal)


def evaluate(model, env):
    """Successes of EVAL_EPISODES deterministic episodes in `env` (its own resets)."""
    wins = 0
    for _ in range(EVAL_EPISODES):
        obs, _ = env.reset()
        while True:
            action, _ = model.predict(obs, deterministic=True)
            obs, _, terminated, truncated, info = env.step(action)
            if terminated or truncated:
                wins += bool(info["success"])
                break
    return wins




class Refused(Exception):
    """A seed that cannot run: its message says why and what to do."""


def read_evals(path):
    """The evaluations written so far: (env_steps, successes, wall_seconds) in order."""
    try:
        with path.open() as f:
            return [(int(r["env_steps"]), int(r["successes"]), float(r["wall_seconds"]))
                    for r in csv.DictReader(f)]
    except (KeyError, TypeError, ValueError) as e:
        raise Refused(f"{path}: unreadable ({e!r}; a line cut by a crash?): repair it or move "
                      "it away") from e


def _rows(buffer, size):
    """Names of the buffer's per-transition arrays (first axis `size`); ``observations.key``
    for those in the dict observations."""
    for name, value in vars(buffer).items():
        items = value.items() if isinstance(value, dict) else [(None, value)]
        for key, array in items:
            if isinstance(array, np.ndarray) and array.shape[:1] == (size,):
                yield name, key


def cut_buffer(buffer):
    """A shallow copy of the replay buffer holding only its rows written so far (SB3 allocates
    all 1M rows at once: a checkpoint at 100k steps then takes 17 MB instead of 166 MB);
    ``grow_buffer`` gives back the whole buffer, equal to the original array for array."""
    rows = buffer.buffer_size if buffer.full else buffer.pos
    cut = copy.copy(buffer)
    names = list(_rows(buffer, buffer.buffer_size))
    for name, key in names:
        if key is None:
            setattr(cut, name, getattr(buffer, name)[:rows])
        else:
            setattr(cut, name, {**getattr(cut, name), key: getattr(buffer, name)[key][:rows]})
    cut.pbcs_cut = {"rows": rows, "names": names}
    return cut


def grow_buffer(buffer):
    """The whole replay buffer from one saved by ``cut_buffer`` (a buffer saved whole, by an
    earlier version of this script, is returned as it is): the unwritten rows are zeros, and
    empty info dicts in HER's ``infos``, as SB3 allocates them."""
    cut = vars(buffer).pop("pbcs_cut", None)
    if cut is None:
        return buffer
    for name, key in cut["names"]:
        value = getattr(buffer, name)
        array = value if key is None else value[key]
        if array.shape[:1] != (cut["rows"],):
            raise Refused(f"replay buffer: {name} {key or ''} has {array.shape[0]} rows, not the "
                          f"{cut['rows']} saved: a damaged checkpoint")
        pad = np.zeros((buffer.buffer_size - cut["rows"], *array.shape[1:]), array.dtype)
        if array.dtype == object:
            for index in np.ndindex(pad.shape):
                pad[index] = {}
        whole = np.concatenate([array, pad])
        if key is None:
            setattr(buffer, name, whole)
        else:
            value[key] = whole
    return buffer


def save_checkpoint(model, ckpt, record, budget):
    """Saves `model` and its replay buffer as of `record` (env_steps, successes, wall_seconds),
    then names them in ``last.json`` (written atomically, with the run's budget), then removes
    older ones: a stopped process leaves ``last.json`` naming a whole checkpoint."""
    steps = record[0]
    ckpt.mkdir(parents=True, exist_ok=True)
    model.save(ckpt / f"model_{steps}.zip")
    with (ckpt / f"replay_{steps}.pkl").open("wb") as f:
        pickle.dump(cut_buffer(model.replay_buffer), f, protocol=pickle.HIGHEST_PROTOCOL)
    meta = dict(zip(("env_steps", "successes", "wall_seconds"), record), budget=budget)
    write_atomic(ckpt / "last.json", json.dumps(meta))
    for old in ckpt.glob("*_*.*"):
        if old.stem.rsplit("_", 1)[1] != str(steps):
            old.unlink()


def resume(evals, ckpt, env, seed, budget):
    """The model of an interrupted run and its evaluations so far (the checkpoint's own
    evaluation appended if the run stopped before writing it); None when the run stopped
    before its first evaluation (start afresh); refuses a checkpoint that is not this run's."""
    from stable_baselines3 import SAC

    done = read_evals(evals)
    last = ckpt / "last.json"
    saved = json.loads(last.read_text()) if last.exists() else None
    if saved is None and not done:
        return None
    prev = done[-1] if done else (0, None, 0.0)
    at = saved["env_steps"] if saved else None
    fits = saved is not None and (
        at == prev[0] + EVAL_EVERY or (at == prev[0] and saved["successes"] == prev[1])
    ) and saved.get("budget", budget) == budget
    if not fits:
        raise Refused(
            f"{evals}: evaluations up to {prev[0]} steps, checkpoint "
            f"{'none' if saved is None else saved} in {ckpt} (budget {budget}): not this run's "
            "state; the evaluations are kept, never overwritten: move them away to run the seed "
            "again"
        )
    if at > prev[0]:
        done.append((at, saved["successes"], saved["wall_seconds"]))
        with evals.open("a") as f:
            f.write(f"{at},{saved['successes']},{EVAL_EPISODES},{saved['wall_seconds']:.1f}\n")
    model = SAC.load(ckpt / f"model_{at}.zip", env=env, device="cpu")
    with (ckpt / f"replay_{at}.pkl").open("rb") as f:
        buffer = grow_buffer(pickle.load(f))
    model.load_replay_buffer(io.BytesIO(pickle.dumps(buffer, protocol=pickle.HIGHEST_PROTOCOL)))
    model.set_random_seed(seed + at)
    resumes = evals.with_name(evals.name.replace(".evals.", ".resumes."))
    if not resumes.exists():
        resumes.write_text("env_steps\n")
    with resumes.open("a") as f:
        f.write(f"{at}\n")
    return model, done


def new_model(env, seed):
    from stable_baselines3 import SAC, HerReplayBuffer

    return SAC(
        "MultiInputPolicy",
        env,
        replay_buffer_class=HerReplayBuffer,
        replay_buffer_kwargs=dict(n_sampled_goal=4, goal_selection_strategy="future"),
        learning_starts=1_000,
        seed=seed,
        device="cpu",
        verbose=0,
    )


def run(map_key, seed, steps, out, checkpoints):
    import stable_baselines3
    import torch
    from stable_baselines3.common.callbacks import BaseCallback

    name = MAPS[map_key]
    folder = out / f"sac_her-pointmaze_{map_key}"
    row = folder / f"s{seed}.csv"
    if row.exists():
        return row.read_text()
    torch.set_num_threads(1)
    probe = gym.make(f"PointMaze_{name}-v3").unwrapped
    length, start, goal = farthest_cells(probe.maze.maze_map)
    env = make_env(name, start, goal)
    eval_env = make_env(name, start, goal)
    evals = folder / f"s{seed}.evals.csv"
    ckpt = checkpoints / folder.name / f"s{seed}"
    folder.mkdir(parents=True, exist_ok=True)
    resumed = resume(evals, ckpt, env, seed, steps) if evals.exists() else None
    if resumed:
        model, done = resumed
        at = done[-1][0]
    else:
        shutil.rmtree(ckpt, ignore_errors=True)  # another run's, if any: never adopted
        env.reset(seed=seed)
        model, done, at = new_model(env, seed), [], 0
        evals.write_text("env_steps,successes,episodes,wall_seconds\n")
    eval_env.reset(seed=1_000_000 + seed + at)
    clock = time.perf_counter() - (done[-1][2] if done else 0.0)
    # successes, env steps: the first evaluation with the most successes; (0, 0) while none has
    # succeeded, resumed or not (the convention `pbcs aggregate` checks the ended row against)
    succeeded = ((k, n) for n, k, _ in done if k > 0)
    best = list(max(succeeded, key=lambda b: (b[0], -b[1]), default=(0, 0)))

    class Evaluate(BaseCallback):
        def _on_step(self):
            if self.num_timesteps % EVAL_EVERY:
                return True
            wins = evaluate(self.model, eval_env)
            record = (self.num_timesteps, wins, time.perf_counter() - clock)
            save_checkpoint(self.model, ckpt, record, steps)
            with evals.open("a") as f:
                f.write(f"{record[0]},{wins},{EVAL_EPISODES},{record[2]:.1f}\n")
            if wins > best[0]:
                best[:] = [wins, self.num_timesteps]
            return wins < SOLVED

    if best[0] < SOLVED and at < steps:
        model.learn(total_timesteps=steps - at, callback=Evaluate(), reset_num_timesteps=at == 0)
    seconds = time.perf_counter() - clock
    solved = best[0] >= SOLVED
    text = (
        "library,algo,map,start_cell,goal_cell,cells_apart,seed,budget,solved,"
        "steps_to_solve,best_successes,best_at_steps,env_steps,episodes\n"
        f"sb3-{stable_baselines3.__version__},sac_her,pointmaze_{map_key},"
        f"{start[0]} {start[1]},{goal[0]} {goal[1]},{length},{seed},{steps},"
        f"{str(solved).lower()},{best[1] if solved else ''},{best[0]},{best[1]},"
        f"{model.num_timesteps},{EVAL_EPISODES}\n"
    )
    write_atomic(
        row.with_suffix(".timing.toml"),
        f"# wall clock of model.learn with its evaluations (not deterministic)\n"
        f"wall_seconds = {seconds:.1f}\nsteps_per_second = {model.num_timesteps / seconds:.0f}\n"
        f"torch = \"{torch.__version__}\"\ntorch_threads = {torch.get_num_threads()}\n",
    )
    write_atomic(row, text)
    return text


def seeds(text):
    if "-" in text:
        a, b = text.split("-")
        return range(int(a), int(b) + 1)
    return [int(s) for s in text.split(",")]


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--map", choices=sorted(MAPS), required=True)
    p.add_argument("--seeds", default="0-2", type=seeds)
    p.add_argument("--steps", default=500_000, type=int)
    p.add_argument("--out", default=Path("results/pointmaze/sb3"), type=Path)
    p.add_argument("--checkpoints", type=Path,
                   default=Path.home() / ".cache" / "pbcs-rs" / "sb3-checkpoints")
    args = p.parse_args()
    refused = 0
    for seed in args.seeds:
        try:
            print(run(args.map, seed, args.steps, args.out, args.checkpoints), end="", flush=True)
        except Refused as e:
            print(f"seed {seed} not run: {e}", file=sys.stderr, flush=True)
            refused += 1
    sys.exit(1 if refused else 0)


if __name__ == "__main__":
    main()
