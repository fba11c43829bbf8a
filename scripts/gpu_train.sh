#!/usr/bin/env bash
# Continue the long run on a lent CUDA machine (the library's `device` tool) from the
# committed weights, and leave the final weights and the logs in $OUT to be fetched.
# The device image has torch (CUDA), OpenCV, numpy, pillow and matplotlib (our fonts), so
# the source tree runs as it is (run from the repository root). Its 16 cores generate the
# crops (the bottleneck there: about 100 samples/s in session 27), hence --sample-reuse 2.
#
# usage (repository root): [DEVICE=cuda] [STEPS=N] [LR=2e-4] [INIT=training/resume/bb24_c3_s40lo_end.pt]
#        [BACKBONE_WIDTHS="24 48 72"] [COARSE_LAYERS=3] [PHOTOMETRIC=60] bash scripts/gpu_train.sh [MINUTES]
# INIT: the weights to continue from (training/resume/README.md says which is the long run's end).
# BACKBONE_WIDTHS / COARSE_LAYERS: first widen INIT's feature encoder to these widths and/or
# deepen its 18/9-grid attention blocks to this many layers (`training.grow`; same output,
# more capacity); the run then trains the grown model (its config comes from INIT).
# Afterwards, here: score $OUT's end.pt against the default (training/resume/README.md), keep
# it under training/resume/ if it is better, and record the run in MODEL_CARD.md. STEPS is
# the lr cycle's length; unset, a one-minute probe measures samples/s and sizes it to end
# inside MINUTES. fp32 (the model is small; generation is the bottleneck there).
# PHOTOMETRIC: the weight of `--photometric-loss` (60, the shipped default's since session
# 29; 0 trains without it). On CUDA the data workers are spawned with one OpenCV thread each
# (`--worker-start auto`; not yet measured there).
set -euo pipefail
cd "$(dirname "$0")/.."
# numpy's OpenBLAS would give each of the 15 generating workers a thread per core (the
# generator's (N, 3) @ (3, 3) products); the trainer's own numpy work is small.
export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}"
minutes="${1:-8}"
out="${OUT:-runs/gpu_out}"
run=/tmp/gpu_run
rm -rf "$run" /tmp/gpu_probe  # scratch: a warm machine keeps the last call's
mkdir -p "$out"
init="${INIT:-training/resume/bb24_c3_s40lo_end.pt}"
grow_args=()
if [ -n "${BACKBONE_WIDTHS:-}" ]; then
    # shellcheck disable=SC2206  # three widths, split on purpose
    grow_args+=(--backbone-widths $BACKBONE_WIDTHS)
fi
if [ -n "${COARSE_LAYERS:-}" ]; then
    grow_args+=(--coarse-layers "$COARSE_LAYERS")
fi
if [ ${#grow_args[@]} -gt 0 ]; then
    rm -f /tmp/gpu_grown.pt
    python3 -m doctrpp.training.grow "$init" "${grow_args[@]}" --out /tmp/gpu_grown.pt \
        | tee "$out/grow.log"
    init=/tmp/gpu_grown.pt
fi
started=$SECONDS
steps="${STEPS:-}"
if [ -z "$steps" ]; then
    # Probe the samples/s for a minute at a tiny lr, so that the lr cycle (OneCycle over
    # STEPS) ends inside MINUTES: a run cut by --max-minutes would end at a high lr.
    python3 -m doctrpp train --out /tmp/gpu_probe --init "$init" --device "${DEVICE:-cuda}" \
        --batch 32 --lr 1e-6 --steps 100000 --sample-reuse 2 --no-bf16 --validate-every 100000 \
        --validation-size 4 --max-minutes 1 >"$out/probe.log" 2>&1 \
        || { tail -n 20 "$out/probe.log" >&2; echo "gpu_train: the probe run failed" >&2; exit 1; }
    rate=$(grep -o '[0-9.]* samples/s' "$out/probe.log" | tail -n 1 | cut -d' ' -f1)
    [ -n "$rate" ] || { echo "gpu_train: the probe logged no samples/s (set STEPS)" >&2; exit 1; }
    left=$((minutes * 60 - (SECONDS - started) - 60))  # 60 s: start-up, validation, saving
    steps=$(python3 -c "print(max(50, int(0.9 * float('$rate') * $left / 32)))")
    echo "gpu_train: probe ${rate} samples/s; ${left} s left -> STEPS=${steps}"
fi
left_minutes=$(python3 -c "print(($minutes * 60 - ($SECONDS - $started)) / 60)")
python3 -m doctrpp train --out "$run" --init "$init" \
    --device "${DEVICE:-cuda}" --batch 32 --lr "${LR:-2e-4}" --steps "$steps" --no-bf16 \
    --sample-reuse 2 --gradient-loss 2 --photometric-loss "${PHOTOMETRIC:-60}" \
    --validate-every 400 --max-minutes "$left_minutes" 2>&1 \
    | tee "$out/train.log"
cp "$run/validation.jsonl" "$out/"
last=$(ls "$run"/snapshots/step*.pt | tail -n 1)
cp "$last" "$out/end.pt"
echo "gpu_train: $(basename "$last") -> $out/end.pt"
