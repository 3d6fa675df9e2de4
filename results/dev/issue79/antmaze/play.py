"""Where a goal-conditioned AntMaze chain's episodes go (a development diagnostic, issue 79):
the chain of a `pbcs run` folder played in gymnasium-robotics' AntMaze_UMaze-v5 (the judge's
env, `pbcs.antmaze.make_env`), printing per episode the furthest skill it handed over to, the
fraction of steps with the torso upside down, and the torso's path length.

    python results/dev/issue79/antmaze/play.py <run folder>/chain [episodes] [--sample | --random]

With ``--random``, the chain only says which skill would act (its activation balls) while the
ant takes uniform random actions: how far chance alone hands over. With ``--sample``, a SAC
chain acts as its skills explored in training, b ⊙ tanh(μ + σ·ε)
(``Chain.act(..., noise=ε)``, ε standard normal from numpy's generator seeded by the episode),
instead of greedily.
"""
import sys

import numpy as np

import pbcs
import pbcs.antmaze as am

sample, chance = "--sample" in sys.argv, "--random" in sys.argv
args = [a for a in sys.argv[1:] if a not in ("--sample", "--random")]
chain = pbcs.load_chain(args[0])
episodes = int(args[1]) if len(args) > 1 else 20
env = am.make_env(chain)
for e in range(episodes):
    obs, _ = env.reset(seed=e)
    chain.reset()
    furthest, flipped, path, success = 0, 0, 0.0, False
    xy = obs["observation"][:2].copy()
    noise = np.random.default_rng(e)
    for t in range(700):
        eps = noise.standard_normal(8).astype(np.float32) if sample else None
        action = chain.act(obs["observation"], obs["desired_goal"], noise=eps)
        if chance:
            action = noise.uniform(-1.0, 1.0, 8).astype(np.float32)
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
