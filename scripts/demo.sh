#!/usr/bin/env bash
# The main job on a built-in problem (default diamond-s14); results go to out/.
set -euo pipefail
cd "$(dirname "$0")/.."
PROBLEM="${1:-diamond-s14}"
OUT="out"
mkdir -p "$OUT"
# straight-line shots (the paper's directed randomize for every disk), simulated exactly
python3 - "$PROBLEM" "$OUT/$PROBLEM-straight.json" <<'PY'
import sys
from nbst import load_problem
from nbst.solution import make_solution, save_solution
p = load_problem(sys.argv[1])
save_solution(sys.argv[2], make_solution(p, p.straight_velocities(), note="straight-line shots"))
PY
nbst simulate "$PROBLEM" "$OUT/$PROBLEM-straight.json"
