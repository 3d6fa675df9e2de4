#!/usr/bin/env bash
# Issue 49's phase-1 development grid, second part: an action held for 5 and 10 env steps.
set -u
export LD_LIBRARY_PATH="$PWD/.mujoco/lib"
out="${OUT:-/tmp}/phase1_hold_dev.csv"
.devbin/antmaze_explore --header > "$out"
for m in large medium open umaze; do
  for h in 5 10; do for s in 0 1 2 3 4; do echo "$m $s refuse 0.5 $h"; done; done
done > /tmp/jobs.txt
xargs -P "$(nproc)" -L 1 sh -c 'timeout 230 .devbin/antmaze_explore "$0" "$1" "$2" "$3" 1500000 "$4" || echo "$0,$1,$2,$3,1500000,timeout,,,,,,230,$4"' < /tmp/jobs.txt >> "$out"
wc -l "$out"
