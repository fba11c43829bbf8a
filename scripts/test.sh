#!/usr/bin/env bash
# Set up ./.venv (if needed, and reinstall the package) and run the test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh export,dev
.venv/bin/pytest -q "$@"
