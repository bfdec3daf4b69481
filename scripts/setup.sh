#!/usr/bin/env bash
# One-time, idempotent set-up on Debian/Ubuntu (docs/install.md says what it changes):
#  1. apt: the libraries for headless OpenGL (EGL on Mesa: moderngl, MuJoCo's renderer)
#     and python3-venv, if missing (as root, or through sudo);
#  2. a project virtualenv, .venv/ in the checkout, made with the first python3 on PATH
#     (>= 3.11; an active virtualenv's python is fine too);
#  3. nbst and its test tools into .venv, at the exact versions of requirements.lock;
#  4. numba's kernels compiled once into its cache, one process per core (later runs start at
#     once); it says each group's time as it finishes.
# Everything else (scripts/demo.sh, the tests) runs from .venv/bin. Run it again any
# time: it redoes only what is missing or out of date.
set -euo pipefail
cd "$(dirname "$0")/.."

PY="${PYTHON:-python3}"
VENV=".venv"
say() { echo "setup: $*"; }
die() { echo "setup: error: $*" >&2; exit 1; }

command -v "$PY" >/dev/null 2>&1 || die "no $PY on PATH; install Python >= 3.11 (apt-get install python3)"
ver=$("$PY" -c 'import sys; print("%d.%d" % sys.version_info[:2])')
"$PY" -c 'import sys; sys.exit(sys.version_info < (3, 11))' || die "$PY is Python $ver; nbst needs >= 3.11"

# --- 1. system packages -------------------------------------------------------
APT_PACKAGES=(libegl1 libgl1 libgl1-mesa-dri)
have_venv=1
[ -x "$VENV/bin/python" ] || "$PY" -c 'import ensurepip, venv' >/dev/null 2>&1 || have_venv=0
[ "$have_venv" = 1 ] || APT_PACKAGES+=("python$ver-venv")
missing=()
for p in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  command -v apt-get >/dev/null 2>&1 || die "missing ${missing[*]} and no apt-get: install their equivalents by hand (docs/install.md)"
  SUDO=()
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null 2>&1 || die "need root to install ${missing[*]}: run as root, or: apt-get install ${missing[*]}"
    SUDO=(sudo)
  fi
  say "installing ${missing[*]} (apt)"
  "${SUDO[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${SUDO[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# --- 2. the project virtualenv ------------------------------------------------
if ! "$VENV/bin/python" -c 'import sys' >/dev/null 2>&1; then
  rm -rf "$VENV"
  say "making $VENV with $("$PY" -c 'import sys; print(sys.executable)') (Python $ver)"
  # an active virtualenv's python makes a venv of its base interpreter
  "$PY" -m venv "$VENV"
fi

# --- 3. nbst at the locked versions ---------------------------------------------
stamp="$VENV/.nbst-install"
want=$(cat pyproject.toml requirements.lock | sha256sum | cut -d' ' -f1)
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ] || ! "$VENV/bin/python" -c 'import nbst' >/dev/null 2>&1; then
  say "installing nbst and its dependencies into $VENV (pinned by requirements.lock)"
  PIP_DISABLE_PIP_VERSION_CHECK=1 "$VENV/bin/python" -m pip install -q -c requirements.lock -e ".[test]"
  echo "$want" > "$stamp"
fi

# --- 4. numba kernels -----------------------------------------------------------
"$VENV/bin/python" -m nbst.warmup
say "done in ${SECONDS} s: $("$VENV/bin/nbst" --version); run tools as .venv/bin/nbst, tests as .venv/bin/python -m pytest -q -n auto -m \"not slow\""
