"""Bad input is a Python exception with the core's message; nothing panics across the
boundary."""

from pathlib import Path

import pytest

import pbcs


@pytest.mark.parametrize("size", [1, 0, -3, 101])
def test_bad_maze_size_names_the_field(size):
    with pytest.raises(ValueError, match="maze.size"):
        pbcs.ContinuousMaze(size=size)


def test_bad_arguments_name_what_is_wrong():
    with pytest.raises(ValueError, match="max_episode_steps"):
        pbcs.ContinuousMaze(size=2, max_episode_steps=0)
    with pytest.raises(ValueError, match="maze.seed"):
        pbcs.ContinuousMaze(size=3, layout=-1)
    with pytest.raises(ValueError, match="maze.wall_thickness"):
        pbcs.ContinuousMaze(size=3, wall_thickness=-1.0)
    env = pbcs.ContinuousMaze(size=2)
    env.reset()
    with pytest.raises(ValueError, match="action"):
        env.step([0.1, 0.1, 0.1])
    with pytest.raises(ValueError, match="action"):
        env.step("up")
    with pytest.raises(ValueError, match="state"):
        env.reset(options={"state": (5.0, 0.5)})
    with pytest.raises(ValueError, match="state"):
        env.reset(options={"state": (float("nan"), 0.5)})
    with pytest.raises(ValueError, match="render_mode"):
        pbcs.ContinuousMaze(size=2, render_mode="human")
    envs = pbcs.ContinuousMazeVec(4, size=2)
    envs.reset()
    with pytest.raises(ValueError, match="actions"):
        envs.step([[0.0, 0.0]])
    with pytest.raises(ValueError, match="num_envs"):
        pbcs.ContinuousMazeVec(0, size=2)
    with pytest.raises(ValueError, match="preset"):
        pbcs.run(2, preset="slow")
    with pytest.raises(ValueError, match="not an environment"):
        pbcs.run(env="hall")
    # A maze size for another environment: refused by the same rule as `pbcs run --maze`.
    with pytest.raises(ValueError, match="maze size or layout .* environment is `rooms`"):
        pbcs.run(2, env="rooms")


def test_a_missing_or_malformed_chain_folder_is_named(tmp_path):
    with pytest.raises(OSError, match="run.toml"):
        pbcs.load_chain(tmp_path)
    # A valid job (the `fast` preset), a manifest that is not one.
    root = Path(__file__).resolve().parents[2]
    (tmp_path / "run.toml").write_text((root / "experiments" / "pbcs_fast.toml").read_text())
    (tmp_path / "manifest.toml").write_text("skills = 3\n")
    with pytest.raises(ValueError, match="manifest.toml"):
        pbcs.load_chain(tmp_path)


def test_exploration_out_of_budget_is_a_runtime_error():
    with pytest.raises(RuntimeError, match="explore.budget"):
        pbcs.explore(5, budget=10)
