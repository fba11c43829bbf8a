#!/usr/bin/env bash
# Speed/accuracy Pareto at the reference size (23.45M parameters) with random weights: the
# shared reference checkpoint (make_ckpt.py --seed 0) exported to every format and int8
# recipe we ship, then one bench report with our eager PyTorch model for scale.
# Random weights: latency is real, accuracy columns only smoke-test the recipes.
#
# usage: bash scripts/pareto_reference.sh REPORT_DIR [WORK_DIR]   (about 20 minutes, 2 cores)
# Files already in WORK_DIR are kept, so a rerun with the same WORK_DIR only re-benchmarks
# (e.g. after the exports ran while the machine was busy). EXPORT_ONLY=1 stops before the bench.
set -euo pipefail
report=$(realpath -m "${1:?usage: bash scripts/pareto_reference.sh REPORT_DIR [WORK_DIR]}")
work=${2:-$(mktemp -d)}
here=$(cd "$(dirname "$0")/.." && pwd)
python=${PYTHON:-$here/.venv/bin/python}
reference=${REFERENCE_DIR:-$here/../shared/reference}
export MALLOC_MMAP_THRESHOLD_=17179869184 MALLOC_TRIM_THRESHOLD_=17179869184
mkdir -p "$work"
cd "$work"

[ -f seed0.pth ] || "$python" "$reference/make_ckpt.py" seed0.pth --seed 0
run() { echo "+ doctrpp $*" >&2; "$python" -m doctrpp "$@"; }
[ -f doctrpp_fp32.onnx ] || run export --checkpoint seed0.pth --out . --format onnx
for preset in static-weights static-encoder-float dynamic-linear; do
    [ -f "int8_$preset.onnx" ] || run quantize --model doctrpp_fp32.onnx \
        --out "int8_$preset.onnx" --preset "$preset" --calib-synthetic 48
done
tflite() {  # NAME ARGS...: export once, keep the file as NAME
    local name=$1
    shift
    if [ ! -f "$name" ]; then
        run export --checkpoint seed0.pth --out "tflite_$name" --format tflite "$@"
        cp "tflite_$name"/doctrpp_*.tflite "$name"
    fi
}
tflite fp16.tflite --precision fp16
tflite int8_keep_head_backbone.tflite --precision int8 --calib-synthetic 48
tflite int8_keep_head.tflite --precision int8 --calib-synthetic 48 --keep-float head
[ -z "${EXPORT_ONLY:-}" ] || exit 0
run bench --models doctrpp_fp32.onnx int8_static-weights.onnx int8_static-encoder-float.onnx \
    int8_dynamic-linear.onnx fp16.tflite int8_keep_head_backbone.tflite int8_keep_head.tflite \
    --out "$report" --runs 10 --per-kind 4 --no-peers --torch-checkpoint seed0.pth \
    --note "RANDOM WEIGHTS (shared reference checkpoint, make_ckpt.py --seed 0): latency is \
real, accuracy only smoke-tests the recipes"
