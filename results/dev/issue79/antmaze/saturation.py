"""How often a goal-conditioned AntMaze chain's greedy actions sit at the bounds (a development
diagnostic, issue 79): the chain's one TD3 actor (read from its safetensors with numpy: two
ReLU layers, a tanh head scaled by `head.tanh_scale`) played greedily in gymnasium-robotics'
AntMaze_UMaze-v5 from its resets to PBCS's cells (start (1, 1), goal (3, 1)), toward the
chain's sub-goals in turn (the next once the torso is within its radius), printing per
episode the share of action components with |a| > 0.95 of the bound, the mean |a| over the
bound, the share of steps upside down, the torso's path and the sub-goals reached. A chain
trained with `normalise` is given its observations shifted and scaled as its manifest says.

    python results/dev/issue79/antmaze/saturation.py <run folder>/chain [episodes]
"""
import json, struct, sys, tomllib
import numpy as np
import gymnasium as gym
import gymnasium_robotics  # noqa: F401

def load(path):
    b = open(path, 'rb').read(); n = struct.unpack('<Q', b[:8])[0]
    h = json.loads(b[8:8 + n]); data = b[8 + n:]
    return {k: np.frombuffer(data[v['data_offsets'][0]:v['data_offsets'][1]], dtype=np.float32).reshape(v['shape'])
            for k, v in h.items() if k != '__metadata__'}

chain = sys.argv[1]; episodes = int(sys.argv[2]) if len(sys.argv) > 2 else 10
m = tomllib.load(open(f'{chain}/manifest.toml', 'rb'))
w = load(f"{chain}/{m['skills'][0]['file']}")
goals = [s['goal'] for s in m['skills'] if s.get('goal')]
# The observation as the networks see it: minus `origin`, divided by `scale` and clipped to ±10
# where the chain was trained with `normalise` (Inputs::observation).
origin = np.array(m['skills'][0]['origin'], dtype=np.float32)
scale = m['skills'][0].get('scale')
def seen(x):
    return x - origin if scale is None else np.clip((x - origin) / np.array(scale, dtype=np.float32), -10, 10)
def act(x):
    h = np.maximum(x @ w['l0.weight'] + w['l0.bias'], 0)
    h = np.maximum(h @ w['l1.weight'] + w['l1.bias'], 0)
    return np.tanh(h @ w['l2.weight'] + w['l2.bias']) * w['head.tanh_scale']
env = gym.make('AntMaze_UMaze-v5', continuing_task=False, max_episode_steps=700)
sat_all, flip_all, size_all, path_all = [], [], [], []
for e in range(episodes):
    obs, _ = env.reset(seed=e, options={'reset_cell': np.array([1, 1]), 'goal_cell': np.array([3, 1])})
    d = env.unwrapped.ant_env.data
    aim, sat, flips, size, path = 0, [], 0, [], 0.0
    xy = d.qpos[:2].copy()
    for t in range(700):
        x = np.concatenate([d.qpos, d.qvel]).astype(np.float32)
        g = np.array(goals[min(aim, len(goals) - 1)], dtype=np.float32) if aim < len(goals) else obs['desired_goal']
        a = act(np.concatenate([seen(x), g - x[:2]]).astype(np.float32))
        sat.append(np.mean(np.abs(a) > 0.95 * w['head.tanh_scale']))
        size.append(np.mean(np.abs(a) / w['head.tanh_scale']))
        obs, _, term, trunc, info = env.step(a)
        qw, qx, qy, qz = d.qpos[3:7]
        flips += (1 - 2 * (qx * qx + qy * qy)) < 0
        path += float(np.linalg.norm(d.qpos[:2] - xy)); xy = d.qpos[:2].copy()
        if aim < len(goals) and np.linalg.norm(d.qpos[:2] - g) <= m['skills'][min(aim + 1, len(goals) - 1)]['radius']:
            aim += 1
        if term or trunc:
            break
    sat_all.append(np.mean(sat)); flip_all.append(flips / (t + 1)); size_all.append(np.mean(size)); path_all.append(path)
    print(f'episode {e}: {np.mean(sat):.0%} of action components saturated (|a| > 0.95), mean |a| {np.mean(size):.2f}, upside down {flips / (t + 1):.0%}, path {path:.1f} m, reached {aim} sub-goals')
print(f'mean: saturated {np.mean(sat_all):.0%}, upside down {np.mean(flip_all):.0%}, mean |a| {np.mean(size_all):.2f}, median path {np.median(path_all):.1f} m')
