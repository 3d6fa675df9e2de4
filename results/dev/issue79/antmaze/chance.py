"""How often chance alone wins a goal-conditioned AntMaze chain's training tries (a development
diagnostic, issue 79): from τ's state at each skill's start (τ_{start_index}, the whole qpos and
qvel of the run's `pbcs explore` trajectory.csv; the solver's warm start left at 0), uniform
random actions for `steps_per_goal` steps in gymnasium-robotics' AntMaze_UMaze-v5, a try won
when the torso comes within `radius` of the skill's goal (τ's point at its target_index, the
manifest's `goal`). Prints per skill the fraction of `tries` random tries won, and the mean: the
rate a learner's training tries reach by chance. The first try of each skill also holds still
(zero actions), what τ's velocities alone carry.

    pbcs explore --config <arm>.toml --env antmaze_umaze --seed 100 --out <explore>
    python results/dev/issue79/antmaze/chance.py <explore>/trajectory.csv <run>/chain/manifest.toml \
        [tries] [steps_per_goal] [radius] [--spacing S] [--rest]

``--spacing S``: the sub-goals cut from τ as `SubGoals::cut` cuts them (every S m of the torso's
position, the end replacing a last cut within S/2 of it) instead of the manifest's; ``--rest``:
each try starts with τ's velocities set to 0 (the ant at rest where τ was).
"""
import sys
import tomllib

import gymnasium as gym
import gymnasium_robotics
import numpy as np

gym.register_envs(gymnasium_robotics)
flags = sys.argv[1:]
spacing = float(flags[flags.index("--spacing") + 1]) if "--spacing" in flags else None
rest = "--rest" in flags
if spacing is not None:
    del flags[flags.index("--spacing"):flags.index("--spacing") + 2]
flags = [f for f in flags if f != "--rest"]
sys.argv = [sys.argv[0]] + flags
tau = np.loadtxt(sys.argv[1], delimiter=",", skiprows=1, usecols=range(30))
manifest = tomllib.load(open(sys.argv[2], "rb"))
tries = int(sys.argv[3]) if len(sys.argv) > 3 else 20
steps = int(sys.argv[4]) if len(sys.argv) > 4 else 100
radius = float(sys.argv[5]) if len(sys.argv) > 5 else 0.45
env = gym.make("AntMaze_UMaze-v5", continuing_task=False, include_cfrc_ext_in_observation=False)
env.reset(seed=0)
ant = env.unwrapped.ant_env
rng = np.random.default_rng(0)
rates, still = [], []
skills = manifest["skills"][:-1]  # the last aims at the episode's own goal
if spacing is not None:
    xy, at = tau[:, 1:3], []
    for i in range(1, len(tau) - 1):
        if np.linalg.norm(xy[i] - xy[at[-1] if at else 0]) >= spacing:
            at.append(i)
    if at and np.linalg.norm(xy[at[-1]] - xy[-1]) < spacing / 2:
        at.pop()
    starts = [0] + at
    skills = [{"start_index": a, "target_index": b, "goal": xy[b]} for a, b in zip(starts, at)]
for i, skill in enumerate(skills):
    row = tau[skill["start_index"], 1:30]  # t, then x … dankle_4 (qpos, qvel)
    qpos, qvel = row[:15], (0.0 * row[15:29] if rest else row[15:29])
    goal = np.asarray(skill["goal"])
    wins = 0
    for t in range(tries + 1):
        ant.set_state(qpos, qvel)
        won = False
        for _ in range(steps):
            a = np.zeros(8) if t == 0 else rng.uniform(-1, 1, 8)
            ant.do_simulation(a, ant.frame_skip)
            if np.linalg.norm(ant.data.qpos[:2] - goal) <= radius:
                won = True
                break
        if t == 0:
            still.append(won)
        else:
            wins += won
    rates.append(wins / tries)
    print(f"skill {i}: τ_{skill['start_index']} → τ_{skill['target_index']}, "
          f"{np.linalg.norm(qpos[:2] - goal):.2f} m; random {wins}/{tries}, still {still[-1]}")
print(f"mean over {len(rates)} skills: random {np.mean(rates):.2f}, still {np.mean(still):.2f}")
