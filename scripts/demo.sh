#!/usr/bin/env bash
# The main job on a fresh machine: set up, export the embedded default weights to ONNX,
# generate sample photos and rectify them. Everything goes to ./out/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh export
.venv/bin/doctrpp export --out out/model   # no --checkpoint: the embedded default weights
# Sample photos: generated UDIR-style crops from seeds training never used (flat targets
# and ground-truth maps beside them).
.venv/bin/doctrpp crops --out out/samples --n 6 --seed 2100000000 --size 576
.venv/bin/doctrpp rectify out/samples/0000?.png --model out/model/doctrpp_fp32.onnx \
    -o out/rectified --threads 2
echo "done: photos in out/samples, rectified in out/rectified"
