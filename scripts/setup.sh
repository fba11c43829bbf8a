#!/usr/bin/env bash
# Create ./.venv and install doctrpp-edge (non-editable) with the given extras.
# usage: scripts/setup.sh [EXTRAS]   (default: export,dev)
set -euo pipefail
cd "$(dirname "$0")/.."
extras="${1:-export,dev}"
python3 -m venv .venv
.venv/bin/python -m pip install -q --upgrade pip
# torch first and pinned: an open range pulls a multi-GB CUDA build.
.venv/bin/python -m pip install -q torch==2.13.0
.venv/bin/python -m pip install -q ".[${extras}]"
