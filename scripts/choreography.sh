#!/usr/bin/env bash
# The animator's job at scale: N disks (default 1,000) start on a grid and end spelling a
# text (default "nbst"); solve it exactly, check it under MuJoCo, and film it. Everything
# goes to out/. Runs nbst from the project virtualenv that scripts/setup.sh makes.
#   bash scripts/choreography.sh "hello" 500
set -euo pipefail
cd "$(dirname "$0")/.."
TEXT="${1:-nbst}"
N="${2:-1000}"
OUT="out"
NAME="text-$N"
NBST=".venv/bin/nbst"
[ -x "$NBST" ] || { echo "choreography: no $NBST: run bash scripts/setup.sh first" >&2; exit 1; }
mkdir -p "$OUT"
set -x
"$NBST" generate --targets-from "$TEXT" --disks "$N" --seed 1 --name "$NAME" -o "$OUT/$NAME.problem.json"
"$NBST" solve "$OUT/$NAME.problem.json" -o "$OUT/$NAME.json" --seed 1
"$NBST" validate "$OUT/$NAME.problem.json" "$OUT/$NAME.json" --out-dir "$OUT/$NAME-validation"
"$NBST" render "$OUT/$NAME.problem.json" "$OUT/$NAME.json" -o "$OUT/$NAME.mp4"
