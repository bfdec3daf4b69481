#!/usr/bin/env bash
# The system packages that only the slow tier's tests use (a user of nbst needs none of them):
# Debian's chromium, to open the HTML reports headless. Installed if missing (as root, with
# apt-get); elsewhere the tests that need it are skipped, and this says so.
set -euo pipefail
if command -v chromium >/dev/null 2>&1; then
  exit 0
fi
if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" -eq 0 ]; then
  echo "test-packages: installing chromium (apt) for the HTML report tests"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends chromium >/dev/null
else
  echo "test-packages: no chromium and no root apt-get: the headless-browser tests will be skipped"
fi
