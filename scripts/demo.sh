#!/usr/bin/env bash
# The main job on a built-in problem (default diamond-s14): solve it, check the
# solution exactly and under MuJoCo, and film it. Everything goes to out/.
# Runs nbst from the project virtualenv that scripts/setup.sh makes.
set -euo pipefail
cd "$(dirname "$0")/.."
PROBLEM="${1:-diamond-s14}"
OUT="out"
NBST=".venv/bin/nbst"
[ -x "$NBST" ] || { echo "demo: no $NBST: run bash scripts/setup.sh first" >&2; exit 1; }
mkdir -p "$OUT"
set -x
"$NBST" solve "$PROBLEM" -o "$OUT/$PROBLEM.json" --seed 1
"$NBST" simulate "$PROBLEM" "$OUT/$PROBLEM.json"
"$NBST" validate "$PROBLEM" "$OUT/$PROBLEM.json" --out-dir "$OUT/$PROBLEM-validation"
"$NBST" render "$PROBLEM" "$OUT/$PROBLEM.json" -o "$OUT/$PROBLEM.mp4" --trails --labels
"$NBST" plot trajectories "$PROBLEM" "$OUT/$PROBLEM.json" -o "$OUT/$PROBLEM-paths.png"
{ set +x; } 2>/dev/null
echo "demo: done in ${SECONDS} s: $OUT/$PROBLEM.json, $OUT/$PROBLEM-validation/, $OUT/$PROBLEM.mp4, $OUT/$PROBLEM-paths.png"
