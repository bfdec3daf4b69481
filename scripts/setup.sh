#!/usr/bin/env bash
# One-time (idempotent) set-up on a Debian/Ubuntu machine: the system libraries for
# headless OpenGL (EGL on Mesa's llvmpipe: moderngl rendering, MuJoCo's renderer),
# then nbst itself with its test dependencies, into the current Python (a venv if
# one is active). Safe to run again: it installs only what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

APT_PACKAGES=(libegl1 libgl1 libgl1-mesa-dri)
missing=()
for p in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  echo "setup: installing ${missing[*]} (apt)"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

PY="${PYTHON:-python3}"
echo "setup: pip install -e .[test] into $("$PY" -c 'import sys; print(sys.prefix)')"
"$PY" -m pip install -q --disable-pip-version-check --root-user-action=ignore -e ".[test]"
echo "setup: done ($("$PY" -m nbst.cli --version))"
