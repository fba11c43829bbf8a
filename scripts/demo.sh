#!/usr/bin/env bash
# The main job on a fresh machine: set up, rectify photos with the shipped default model,
# and show that the exporter reproduces it from the embedded weights. Everything goes to
# ./out/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh export
# Sample photos: generated UDIR-style crops from seeds training never used (flat targets
# and ground-truth maps beside them), and real phone photos when ../shared has them.
.venv/bin/doctrpp crops --out out/samples --n 6 --seed 2100000000 --size 576
.venv/bin/doctrpp rectify out/samples/0000?.png -o out/rectified --threads 2 --jobs 2
real=../shared/realphotos/docunet_dev
if [ -d "$real" ]; then
    mkdir -p out/real
    cp "$real"/1[0-2]_1.jpg "$real"/2[0-2]_2.jpg out/real/ 2>/dev/null || true
    .venv/bin/doctrpp rectify out/real -o out/real_rectified --threads 2 --jobs 2
fi
.venv/bin/doctrpp export --out out/model   # no --checkpoint: the embedded default weights
echo "done: photos in out/samples (and out/real), rectified in out/rectified" \
    "(and out/real_rectified); the default exported to out/model"
