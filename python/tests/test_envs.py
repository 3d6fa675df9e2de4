"""Environments by name from Python: ``pbcs.run(env="rooms")`` runs PBCS on the registry's
two rooms, the same run as the committed row of ``experiments/rooms.toml`` for that seed."""

import csv
from pathlib import Path

import numpy as np

import pbcs

ROOT = Path(__file__).resolve().parents[2]


def test_a_run_on_the_rooms_is_the_committed_rows_run():
    record = pbcs.run(env="rooms", seed=0)
    assert record["env"] == "rooms"
    assert record["maze"] is None
    assert record["solved"]
    tau = record["tau"]
    assert tau.ndim == 2 and tau.shape[1] == 2 and len(tau) > 2
    # The rooms are 2 × 1: τ stays in that frame.
    assert (tau[:, 0] >= 0).all() and (tau[:, 0] <= 2).all()
    assert (tau[:, 1] >= 0).all() and (tau[:, 1] <= 1).all()
    row_path = ROOT / "results/raw/rooms/pbcs_fast-rooms/s0.csv"
    with open(row_path, newline="") as f:
        row = next(csv.DictReader(f))
    assert row["maze"] == "rooms"
    assert record["total_steps"] == int(row["env_steps"])
    assert record["skills"] == int(row["skills"])


def test_a_rooms_run_writes_its_folder_and_its_chain_acts_on_rooms_observations(tmp_path):
    out = tmp_path / "run"
    record = pbcs.run(env="rooms", seed=1, out=str(out))
    assert (out / "record.csv").exists() and (out / "chain" / "manifest.toml").exists()
    assert 'env = "rooms"' in (out / "chain" / "run.toml").read_text()
    assert record["chain"] == out / "chain"
    # The chain acts on any environment's observations, and rolls out, evaluates and draws on
    # its own environment (the registry's); only the maze's own questions are refused.
    chain = pbcs.load_chain(out / "chain")
    assert chain.env == "rooms" and chain.pointmaze is None
    chain.reset()
    action = chain.act([0.5, 0.5])
    assert action.shape == (2,) and np.all(np.isfinite(action))
    for call in (lambda: chain.maze, lambda: chain.core_rollout(start=(0.3, 0.2))):
        try:
            call()
        except ValueError as e:
            assert "rooms" in str(e) and "not of the maze" in str(e)
        else:
            raise AssertionError("a rooms chain answered as a maze chain")
    core = chain.core_rollout()
    assert core["success"] == record["solved"]
    assert (core["states"][:, 0] <= 2).all() and (core["states"][:, 1] <= 1).all()
    # Stepped in Python through the registry's environment: the same episode.
    ours = chain.rollout()
    assert (ours["success"], ours["steps"]) == (core["success"], core["steps"])
    assert ours["states"][-1].tobytes() == core["states"][-1].tobytes()
    picture = chain.render([core["states"]])
    assert picture.shape == (256, 256, 3) and picture.dtype == np.uint8
    starts = chain.eval_starts(episodes=5)
    assert starts.shape == (5, 2)
    # The run's own evaluation, re-run by the core from the chain folder.
    again = chain.evaluate_in_core(episodes=len(record["evaluation_success"]))
    assert again["success"].tolist() == record["evaluation_success"].tolist()
    assert again["steps"].tolist() == record["evaluation_steps"].tolist()
    try:
        chain.evaluate()
    except ValueError as e:
        assert "evaluate_in_core" in str(e)
    else:
        raise AssertionError("a rooms chain's evaluation was stepped through the maze")
    for bad in ([0.5], [0.5, float("nan")], "xy"):
        try:
            chain.act(bad)
        except ValueError as e:
            assert "obs" in str(e)
        else:
            raise AssertionError(f"act({bad!r}) was accepted")


def test_a_configs_maze_is_kept_unless_size_or_layout_is_given(tmp_path):
    text = (ROOT / "experiments/pbcs_fast.toml").read_text()
    text = text.replace("size = 5\nseed = 0\n", "size = 2\nseed = 3\n", 1)
    assert "size = 2\nseed = 3\n" in text
    config = tmp_path / "mine.toml"
    config.write_text(text)
    record = pbcs.run(config=str(config), max_env_steps=30_000)
    assert (record["maze"], record["maze_seed"]) == (2, 3)
