#!/usr/bin/env bash
# The main job on a fresh machine: set up, export the model to ONNX, rectify sample photos.
# Everything goes to ./out/. Until trained weights ship, the model has RANDOM weights and
# its "rectifications" are meaningless: the commands print that plainly.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh export
.venv/bin/doctrpp export --random-weights 0 --out out/model
# Sample photos: generated UDIR-style crops (with their flat targets beside them).
.venv/bin/doctrpp crops --out out/samples --n 6 --seed 0 --size 576
.venv/bin/doctrpp rectify out/samples/0000?.png --model out/model/doctrpp_fp32.onnx \
    -o out/rectified --threads 2
echo "done: photos in out/samples, rectified in out/rectified"
