#!/bin/bash
# Issue 49 phase-2 development grid, second call: small balls (ε 0.1 and 0.25 m), DDPG 64 × 64,
# seeds 0-7 on antmaze_umaze, 16 at once, each cut at 250 s (its log says how far it got).
export LD_LIBRARY_PATH=$PWD/.mujoco/lib
mkdir -p $OUT/logs2 /tmp/r
for c in ddpg64_e01 ddpg64_e025; do
  for s in 0 1 2 3 4 5 6 7; do
    timeout 250 .devbin/pbcs run --env antmaze_umaze --seed $s --out /tmp/r/$c-s$s \
      --config results/dev/issue49/phase2/$c.toml > $OUT/logs2/$c-s$s.log 2>&1 &
  done
done
wait
cd $OUT && tar czf logs2.tgz logs2 && rm -rf logs2
