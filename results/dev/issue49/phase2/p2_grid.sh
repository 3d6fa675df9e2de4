#!/bin/bash
# Issue 49 phase-2 development grid: 4 settings x seeds 0-3 on antmaze_umaze, 16 at once, each
# cut at 520 s (its log says how far Backplay got).
export LD_LIBRARY_PATH=$PWD/.mujoco/lib
mkdir -p $OUT/logs /tmp/r
nproc > $OUT/logs/nproc.txt; lscpu | grep "Model name" >> $OUT/logs/nproc.txt
for c in ddpg64_e1 ddpg64_e05 td3256_e1 td3256_e05; do
  for s in 0 1 2 3; do
    timeout 520 .devbin/pbcs run --env antmaze_umaze --seed $s --out /tmp/r/$c-s$s \
      --config results/dev/issue49/phase2/$c.toml > $OUT/logs/$c-s$s.log 2>&1 &
  done
done
wait
for d in /tmp/r/*; do
  [ -f $d/record.csv ] && cp $d/record.csv $OUT/logs/$(basename $d).record.csv
done
cd $OUT && tar czf logs.tgz logs && rm -rf logs
