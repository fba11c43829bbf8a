#!/usr/bin/env bash
# Set up .venv (package + [export,dev,tflite,tflite-export]) and run the whole test suite,
# TFLite conversion included. The converter stack adds ~1 GB and ~2 minutes of install.
# usage: scripts/test.sh [PYTEST ARGS]
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh export,dev,tflite,tflite-export
.venv/bin/pytest -q "$@"
