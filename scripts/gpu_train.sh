#!/usr/bin/env bash
# Continue the long run on a lent CUDA machine (the library's `device` tool) from the
# committed weights, and leave the final weights and the logs in $OUT to be fetched.
# The device image has torch (CUDA), OpenCV, numpy, pillow and matplotlib (our fonts), so
# only this package is installed, offline. Its 16 cores generate the crops (the bottleneck
# there), hence --sample-reuse 2.
#
# usage (repository root): [DEVICE=cuda] [STEPS=1600] [INIT=training/resume/bb24_s26b_end.pt]
#        [BACKBONE_WIDTHS="24 48 72"] bash scripts/gpu_train.sh [MINUTES]
# INIT: the weights to continue from (training/resume/README.md says which is the long run's end).
# BACKBONE_WIDTHS: first widen INIT's feature encoder to these widths (`training.grow`; same
# output, more capacity); the run then trains the wider model (its config comes from INIT).
# Afterwards, here: score $OUT's end.pt against the default (training/resume/README.md), keep
# it under training/resume/ if it is better, and record the run in MODEL_CARD.md. STEPS is
# the lr cycle's length; size it so that it ends before MINUTES (the log's samples/s tells,
# for the next time).
set -euo pipefail
cd "$(dirname "$0")/.."
minutes="${1:-8}"
out="${OUT:-runs/gpu_out}"
run=/tmp/gpu_run
mkdir -p "$out"
if ! python3 -c "import doctrpp" 2>/dev/null; then
    python3 -m pip install -q --no-index --no-deps --no-build-isolation . >"$out/install.log" 2>&1 \
        || { echo "gpu_train: installing the package failed (see $out/install.log)" >&2; exit 1; }
fi
init="${INIT:-training/resume/bb24_s26b_end.pt}"
if [ -n "${BACKBONE_WIDTHS:-}" ]; then
    rm -f /tmp/gpu_grown.pt
    # shellcheck disable=SC2086  # three widths, split on purpose
    python3 -m doctrpp.training.grow "$init" --backbone-widths $BACKBONE_WIDTHS \
        --out /tmp/gpu_grown.pt | tee "$out/grow.log"
    init=/tmp/gpu_grown.pt
fi
python3 -m doctrpp train --out "$run" --init "$init" \
    --device "${DEVICE:-cuda}" --batch 32 --lr 3e-4 --steps "${STEPS:-1600}" \
    --sample-reuse 2 --gradient-loss 2 --validate-every 400 --max-minutes "$minutes" 2>&1 | tee "$out/train.log"
cp "$run/validation.jsonl" "$out/"
last=$(ls "$run"/snapshots/step*.pt | tail -n 1)
cp "$last" "$out/end.pt"
echo "gpu_train: $(basename "$last") -> $out/end.pt"
