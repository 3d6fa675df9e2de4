#!/usr/bin/env bash
# Issue 49's phase-1 development grid on AntMaze's fixed task, run on a lent 16-core machine.
set -u
export LD_LIBRARY_PATH="$PWD/.mujoco/lib"
out="${OUT:-/tmp}/phase1_dev.csv"
.devbin/antmaze_explore --header > "$out"
{
  for m in large medium open umaze; do
    for f in keep refuse; do for s in 0 1 2 3 4; do echo "$m $s $f 0.5"; done; done
    for s in 0 1 2 3 4; do echo "$m $s refuse 1.0"; echo "$m $s refuse 0.25"; done
  done
} > /tmp/jobs.txt
nproc
xargs -P "$(nproc)" -L 1 sh -c 'timeout 330 .devbin/antmaze_explore "$0" "$1" "$2" "$3" 1500000 || echo "$0,$1,$2,$3,1500000,timeout,,,,,,330"' < /tmp/jobs.txt >> "$out"
wc -l "$out"
