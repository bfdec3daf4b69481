#!/usr/bin/env bash
# Refresh requirements.lock: resolve nbst's dependencies afresh (newest versions
# allowed by pyproject.toml) in a throwaway virtualenv, run the test suite there,
# and only if it passes write the exact versions to requirements.lock.
set -euo pipefail
cd "$(dirname "$0")/.."
PY="${PYTHON:-python3}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$PY" -m venv "$tmp/venv"
"$tmp/venv/bin/python" -m pip install -q --disable-pip-version-check -e ".[test]"
"$tmp/venv/bin/python" -m pytest -q -n auto  # both tiers: everything
{
  echo "# Exact versions the test suite passed with ($("$tmp/venv/bin/python" -c 'import platform; print(platform.python_implementation(), platform.python_version() + ",", platform.system(), platform.machine())')), used as pip constraints"
  echo "# by scripts/setup.sh and so by CI. Refresh: bash scripts/lock.sh (docs/install.md)."
  "$tmp/venv/bin/python" -m pip freeze --all --exclude-editable | grep -v '^pip=='
} > requirements.lock
# the editable install of nbst points at this checkout: reinstall .venv on the next setup
echo "lock: wrote requirements.lock ($(grep -vc '^#' requirements.lock) packages); run bash scripts/setup.sh to use it"
