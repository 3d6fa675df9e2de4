"""A chain saved by `pbcs run`, loaded in Python: stepped through the Gymnasium environment it
succeeds exactly where `pbcs eval` does."""

import subprocess
from pathlib import Path

import numpy as np
import pytest

import pbcs

ROOT = Path(__file__).resolve().parents[2]

@pytest.fixture(scope="module")
def chain_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("run")
    record = pbcs.run(2, seed=0, out=str(out))
    assert record["solved"] and record["chain"] is not None
    return out


def test_run_returns_the_record_and_saves_the_chain(chain_dir):
    assert (chain_dir / "chain" / "manifest.toml").exists()
    assert (chain_dir / "record.csv").exists()


def test_python_rollouts_equal_pbcs_eval(chain_dir, tmp_path, pbcs_bin):
    chain = pbcs.load_chain(chain_dir / "chain")
    ours = chain.evaluate(episodes=40, seed=7)
    core = chain.evaluate_in_core(episodes=40, seed=7)
    assert ours["success"].tolist() == core["success"].tolist()
    assert ours["steps"].tolist() == core["steps"].tolist()
    subprocess.run(
        [pbcs_bin, "eval", "--chain", str(chain_dir / "chain"), "--episodes", "40", "--seed", "7",
         "--out", str(tmp_path)],
        check=True, capture_output=True,
    )
    lines = (tmp_path / "eval-s7.csv").read_text().split()
    assert lines[0] == "success,steps"
    rows = [line.split(",") for line in lines[1:]]
    assert [s == "true" for s, _ in rows] == ours["success"].tolist()
    assert [int(n) for _, n in rows] == ours["steps"].tolist()


def assert_acts_like_the_core(chain):
    """``chain.act`` stepped through its Gymnasium env chooses the core rollout's skills and
    ends in its last state, to the byte."""
    core = chain.core_rollout()
    env = chain.make_env()
    obs, _ = env.reset()
    chain.reset()
    used = []
    for _ in range(core["steps"]):
        a = chain.act(obs)
        used.append(chain.active_skill)
        obs, *_ = env.step(a)
    assert used == core["skill_used"].tolist()
    assert obs.tobytes() == core["states"][-1].tobytes()


def test_act_switches_skills_like_the_core(chain_dir):
    chain = pbcs.load_chain(chain_dir / "chain")
    assert_acts_like_the_core(chain)
    assert len(chain) == len(chain.balls) >= 1


def test_render_draws_the_chain(chain_dir):
    chain = pbcs.load_chain(chain_dir / "chain")
    r = chain.rollout()
    img = chain.render([r["states"]], size=96)
    assert img.shape == (96, 96, 3)


def test_the_protocols_starts_are_the_chains(chain_dir):
    chain = pbcs.load_chain(chain_dir / "chain")
    starts = pbcs.evaluation_starts(2, seed=5, episodes=30, epsilon=chain._core.epsilon)
    assert starts.tobytes() == chain.eval_starts(30, seed=5).tobytes()
    assert (np.linalg.norm(starts - np.array([0.5, 0.5]), axis=1) <= chain._core.epsilon + 1e-6).all()


def test_a_chain_whose_files_do_not_match_its_manifest_is_refused(chain_dir, tmp_path, pbcs_bin):
    """The manifest records the skills' count and the SHA-256 of each policy file and of
    run.toml: ``pbcs.load_chain`` and ``pbcs eval`` refuse another run's job or a policy file
    edited, naming the manifest's field; the chain as saved loads."""
    import shutil

    manifest = (chain_dir / "chain" / "manifest.toml").read_text()
    assert manifest.startswith("skill_count = ") and "sha256 = " in manifest
    bad = tmp_path / "chain"
    shutil.copytree(chain_dir / "chain", bad)
    (bad / "run.toml").write_text((bad / "run.toml").read_text().replace("seed = 0", "seed = 1"))
    with pytest.raises(ValueError, match="job_sha256"):
        pbcs.load_chain(bad)
    done = subprocess.run([pbcs_bin, "eval", "--chain", str(bad), "--out", str(tmp_path / "e")],
                          capture_output=True, text=True)
    assert done.returncode != 0 and "job_sha256" in done.stderr
    shutil.copy(chain_dir / "chain" / "run.toml", bad / "run.toml")
    policy = bad / "skill0.safetensors"
    data = policy.read_bytes()
    policy.write_bytes(data[:-1] + bytes([data[-1] ^ 1]))
    with pytest.raises(ValueError, match=r"skills\[0\]\.sha256"):
        pbcs.load_chain(bad)


def test_a_chain_of_sac_skills_runs_and_loads_like_any_other(tmp_path):
    """A learner of another family through the same door: the `fast` job with one [learner]
    table of SAC's (experiments/sac_skills.toml's setting); its chain names its skills' kind
    (`sac`), loads, and steps through the Gymnasium environment exactly as in the core."""
    fast = (Path(__file__).parents[2] / "experiments" / "pbcs_fast.toml").read_text()
    head, _, rest = fast.partition("[learner]")
    _, _, tail = rest.partition("\n[")
    job = tmp_path / "sac.toml"
    job.write_text(
        head + "[learner]\nalgo = \"sac\"\nhidden = [64, 64]\nbatch_size = 64\ngamma = 0.9\n"
        "learning_rate = 0.001\nent_coef = \"auto_0.01\"\n\n[" + tail)
    record = pbcs.run(2, seed=0, config=str(job), out=str(tmp_path / "run"))
    assert record["solved"]
    manifest = (tmp_path / "run" / "chain" / "manifest.toml").read_text()
    assert 'policy = "sac"' in manifest and 'policy = "mlp"' not in manifest
    chain = pbcs.load_chain(tmp_path / "run" / "chain")
    ours = chain.evaluate(episodes=20, seed=3)
    core = chain.evaluate_in_core(episodes=20, seed=3)
    assert ours["success"].tolist() == core["success"].tolist()
    assert ours["steps"].tolist() == core["steps"].tolist()
    # Sampled as training explored: with ε = 0 the greedy action, else b ⊙ tanh(μ + σ·ε),
    # within the bound; ε of the wrong length refused, and a DDPG chain does not sample.
    obs = np.array([0.5, 0.5], np.float32)
    chain.reset()
    greedy = chain.act(obs)
    assert np.array_equal(chain.act(obs, noise=np.zeros(2, np.float32)), greedy)
    pushed = chain.act(obs, noise=np.full(2, 3.0, np.float32))
    assert not np.array_equal(pushed, greedy) and (np.abs(pushed) <= 0.1).all()
    with pytest.raises(ValueError, match="noise"):
        chain.act(obs, noise=np.zeros(3, np.float32))


def test_a_deterministic_chain_refuses_to_sample(chain_dir):
    chain = pbcs.load_chain(chain_dir / "chain")
    chain.reset()
    with pytest.raises(ValueError, match="only SAC's skills sample"):
        chain.act(np.array([0.5, 0.5], np.float32), noise=np.zeros(2, np.float32))


def test_a_chain_aiming_at_each_episodes_goal_needs_the_goal_to_act(chain_dir, tmp_path):
    """A chain whose last skill aims at each episode's own goal (``phase2.last_goal =
    "drawn"``; here the saved chain with its last skill marked so in the manifest) needs the
    goal to act: without it, an error naming ``desired_goal``; given the task's own goal (the
    skill's origin), the actions of the chain as saved; given another, other actions."""
    import shutil
    import tomllib

    plain = pbcs.load_chain(chain_dir / "chain")
    assert not plain.needs_goal
    copy = tmp_path / "chain"
    shutil.copytree(chain_dir / "chain", copy)
    manifest = (copy / "manifest.toml").read_text()
    # The last [[skills]] table ends the file.
    (copy / "manifest.toml").write_text(manifest.rstrip("\n") + "\nepisode_goal = true\n")
    drawn = pbcs.load_chain(copy)
    assert drawn.needs_goal
    origin = tomllib.loads(manifest)["skills"][-1]["origin"][:2]
    obs = plain.eval_starts(episodes=5, seed=3)
    with pytest.raises(ValueError, match="desired_goal"):
        drawn.act(obs[0])
    for o in obs:
        plain.reset()
        drawn.reset()
        assert drawn.act(o, np.array(origin)).tolist() == plain.act(o).tolist()
    # Only the last skill sees the goal: from a state where it acts, another goal moves it.
    last = len(plain.balls) - 1
    centre = np.array(plain.balls[last][:2], dtype=np.float32)
    plain.reset()
    drawn.reset()
    assert plain.act(centre).tolist() == drawn.act(centre, np.array(origin)).tolist()
    assert drawn.active_skill == last
    # Seen from the goal reflected through the ball's centre, the skill stands where the goal
    # was: its policy heads the other way.
    moved = 2 * centre - np.array(origin, dtype=np.float32)
    drawn.reset()
    assert drawn.act(centre, moved).tolist() != plain.act(centre).tolist()


def test_a_goal_conditioned_chain_acts_in_python_as_in_the_core(tmp_path):
    """A chain of the goal-conditioned strategy (phase2.chain = "goal_conditioned": one policy
    whose skills each see their sub-goal) re-made from its committed job file (maze 2, seed 0
    of experiments/goal_conditioned.toml: the row's env steps), loaded in Python: its skills
    take the maze's observation (the sub-goal appended by the chain), and its rollouts and
    evaluation equal the core's."""
    import csv

    cell = ROOT / "results/raw/goal_conditioned/gc-maze2"
    row = next(csv.DictReader((cell / "s0.csv").open()))
    record = pbcs.run(config=str(cell / "s0.toml"), seed=0, out=str(tmp_path))
    assert record["total_steps"] == int(row["env_steps"])
    chain = pbcs.load_chain(tmp_path / "chain")
    assert len(chain) == int(row["skills"])
    ours = chain.evaluate(episodes=20, seed=3)
    core = chain.evaluate_in_core(episodes=20, seed=3)
    assert ours["success"].tolist() == core["success"].tolist()
    assert ours["steps"].tolist() == core["steps"].tolist()
    assert_acts_like_the_core(chain)
