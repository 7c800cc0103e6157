#!/bin/bash
# Issue 33's acceptance figure: 256 variants of the box drop (8 masses x 4 bounces x 8 heights, dt 4 ms) on a
# batching backend (default mujoco_warp, Warp's CPU device), once through `--batch` and once as 256 separate
# runs (-j 2), with the wall time of each and whether the per-variant verdicts are identical (sweep.csv without
# its trace column). Run from the repository root: bash bench/sweep_batch.sh [BACKEND] [OUT]
set -u
BACKEND=${1:-mujoco_warp}
OUT=${2:-traces/bench/sweep_batch}
SCENARIO=${SCENARIO:-.venv/bin/scenario}
GRID=(--param mass=0.1,0.2,0.5,1,2,4,7,10 --param bounce=0.1,0.3,0.5,0.7
      --param height=0.05,0.1,0.15,0.2,0.25,0.3,0.4,0.5 --set world.dt=0.004)
rm -rf "$OUT" && mkdir -p "$OUT"
start=$(date +%s.%N)
$SCENARIO sweep scenarios/sweeps/box_drop.yaml "${GRID[@]}" -b "$BACKEND" -q --force --batch --out "$OUT/batch"
echo "batched: exit $? in $(echo "$(date +%s.%N) - $start" | bc) s"
start=$(date +%s.%N)
$SCENARIO sweep scenarios/sweeps/box_drop.yaml "${GRID[@]}" -b "$BACKEND" -q --force -j 2 --out "$OUT/alone"
echo "separate (-j 2): exit $? in $(echo "$(date +%s.%N) - $start" | bc) s"
cut -d, -f1-13 "$OUT/alone/sweep.csv" > "$OUT/alone.csv"
cut -d, -f1-13 "$OUT/batch/sweep.csv" > "$OUT/batch.csv"
if cmp -s "$OUT/alone.csv" "$OUT/batch.csv"; then
    echo "verdicts identical: $(($(wc -l < "$OUT/alone.csv") - 1)) variants, $(grep -c ',passed,' "$OUT/alone.csv") passed"
else
    echo "verdicts DIFFER:"; diff "$OUT/alone.csv" "$OUT/batch.csv"; exit 1
fi
