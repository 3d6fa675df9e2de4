import numpy as np, pbcs, pbcs.pointmaze as pm
import gymnasium as gym, gymnasium_robotics
chain = pbcs.load_chain("chain")
env = pm.make_env(chain)
starts, goals, wins = [], [], []
for e in range(100):
    obs, info = env.reset(seed=1_000_017 if e == 0 else None)
    starts.append(obs["observation"][:2].copy()); goals.append(obs["desired_goal"].copy())
    chain.reset()
    while True:
        obs, _, term, trunc, info = env.step(chain.act(obs["observation"]))
        if term or trunc: break
    wins.append(bool(info["success"]))
starts, goals, wins = np.array(starts), np.array(goals), np.array(wins)
c = starts.mean(0)  # start cell centre approx
centre = np.round(starts.mean(0)*2)/2
d = np.linalg.norm(starts - centre, axis=1)
print("successes", wins.sum(), "centre", centre)
print("outside disc 0.25:", (d > 0.25).sum(), "of which failed", ((d > 0.25) & ~wins).sum())
print("inside disc:", (d <= 0.25).sum(), "of which failed", ((d <= 0.25) & ~wins).sum())
gc = np.round(goals.mean(0)*2)/2
print("goal offsets of failures:", np.round(goals[~wins]-gc, 2).tolist())
print("start offsets of failures:", np.round(starts[~wins]-centre, 2).tolist())
