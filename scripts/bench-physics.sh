#!/usr/bin/env bash
# The physics figures of BENCHMARKS.md, alternating so that a noisy host
# treats every side alike:
#
#   scripts/bench-physics.sh QUADWALK [REFERENCE_QUADWALK]
#
# QUADWALK and the optional REFERENCE_QUADWALK are `quadwalk` binaries (e.g.
# target/release/quadwalk and a copy built at an older commit). Three rounds
# of the robot standing on the paper's 15 x 5 tile scene (steps/s on one
# core), each followed by MuJoCo on the same scene when the `mujoco` Python
# package is installed (../shared/peers/mujoco_bench.py beside the
# repository), then two rounds of crawl phases on that scene and on rigid
# ground (ms per phase on one core). Nothing else should run meanwhile.
set -euo pipefail
if [ $# -lt 1 ] || [ $# -gt 2 ]; then
  echo "usage: $0 QUADWALK [REFERENCE_QUADWALK]" >&2
  exit 2
fi
for binary in "$@"; do
  if [ ! -x "$binary" ]; then
    echo "$0: $binary is not an executable quadwalk binary" >&2
    exit 2
  fi
done
SCENE=elastic:5cm:length=3m:back=1.5m:width=1m
MUJOCO_BENCH="$(dirname "$0")/../../shared/peers/mujoco_bench.py"
field() { python3 -c "import json,sys; r=json.load(sys.stdin)['results'][0]; print(*[round(r[k], 2) for k in sys.argv[1:]])" "$@"; }
date -u; grep -m1 "model name" /proc/cpuinfo || true
for round in 1 2 3; do
  for binary in "$@"; do
    echo "stand $binary round $round: $("$binary" bench --terrain $SCENE --threads 1 --seconds 100 --repeat 1 --json | field steps_per_s) steps/s"
  done
  if [ -f "$MUJOCO_BENCH" ] && python3 -c "import mujoco" 2>/dev/null; then
    echo "stand mujoco round $round: $(python3 "$MUJOCO_BENCH" --scene tiles --dt 0.004166666666666667 --repeats 1 | grep "steps/s")"
  fi
done
for terrain in $SCENE rigid; do
  for round in 1 2; do
    for binary in "$@"; do
      echo "crawl on $terrain, $binary round $round: $("$binary" bench --terrain "$terrain" --threads 1 --seconds 60 --repeat 1 --phases 40 --json | field ms_per_phase_per_world) ms per phase"
    done
  done
done
date -u
