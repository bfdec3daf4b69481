#!/usr/bin/env bash
# The main job on a built-in problem (default diamond-s14): solve it, check the
# solution exactly and under MuJoCo, and film it. Everything goes to out/.
set -euo pipefail
cd "$(dirname "$0")/.."
PROBLEM="${1:-diamond-s14}"
OUT="out"
mkdir -p "$OUT"
set -x
nbst solve "$PROBLEM" -o "$OUT/$PROBLEM.json" --seed 1 --target-cost 1e-9
nbst simulate "$PROBLEM" "$OUT/$PROBLEM.json"
nbst validate "$PROBLEM" "$OUT/$PROBLEM.json" --report "$OUT/$PROBLEM-validation"
nbst render "$PROBLEM" "$OUT/$PROBLEM.json" -o "$OUT/$PROBLEM.mp4" --trails --labels
nbst plot trajectories "$PROBLEM" "$OUT/$PROBLEM.json" -o "$OUT/$PROBLEM-paths.png"
