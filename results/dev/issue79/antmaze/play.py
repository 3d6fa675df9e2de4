"""Where a goal-conditioned AntMaze chain's episodes go (a development diagnostic, issue 79):
the chain of a `pbcs run` folder played in gymnasium-robotics' AntMaze_UMaze-v5 (the judge's
env, `pbcs.antmaze.make_env`), printing per episode the furthest skill it handed over to, the
fraction of steps with the torso upside down, and the torso's path length.

    python results/dev/issue79/antmaze/play.py <run folder>/chain [episodes]
"""
import sys

import numpy as np

import pbcs
import pbcs.antmaze as am

chain = pbcs.load_chain(sys.argv[1])
episodes = int(sys.argv[2]) if len(sys.argv) > 2 else 20
env = am.make_env(chain)
for e in range(episodes):
    obs, _ = env.reset(seed=e)
    chain.reset()
    furthest, flipped, path, success = 0, 0, 0.0, False
    xy = obs["observation"][:2].copy()
    for t in range(700):
        action = chain.act(obs["observation"], obs["desired_goal"])
        obs, _, terminated, truncated, info = env.step(action)
        furthest = max(furthest, chain.active_skill)
        w, x, y, z = obs["observation"][3:7]
        up = 1.0 - 2.0 * (x * x + y * y)  # the torso's z axis, world z component
        flipped += up < 0.0
        path += float(np.linalg.norm(obs["observation"][:2] - xy))
        xy = obs["observation"][:2].copy()
        success = bool(info.get("success", False))
        if terminated or truncated:
            break
    print(f"episode {e}: furthest skill {furthest} of {len(chain)}, upside down "
          f"{flipped / (t + 1):.0%} of {t + 1} steps, path {path:.1f} m, success {success}")
