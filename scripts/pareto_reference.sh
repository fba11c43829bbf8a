#!/usr/bin/env bash
# Speed/accuracy Pareto at the reference size (23.45M parameters) with random weights: the
# shared reference checkpoint (make_ckpt.py --seed 0) exported to every format and int8
# recipe we ship, then one bench report with our eager PyTorch model for scale.
# Random weights: latency is real, accuracy columns only smoke-test the recipes.
#
# usage: bash scripts/pareto_reference.sh REPORT_DIR [WORK_DIR]   (about 20 minutes, 2 cores)
set -euo pipefail
report=${1:?usage: bash scripts/pareto_reference.sh REPORT_DIR [WORK_DIR]}
work=${2:-$(mktemp -d)}
here=$(cd "$(dirname "$0")/.." && pwd)
python=${PYTHON:-$here/.venv/bin/python}
reference=${REFERENCE_DIR:-$here/../shared/reference}
export MALLOC_MMAP_THRESHOLD_=17179869184 MALLOC_TRIM_THRESHOLD_=17179869184
mkdir -p "$work"
cd "$work"

"$python" "$reference/make_ckpt.py" seed0.pth --seed 0
run() { echo "+ doctrpp $*" >&2; "$python" -m doctrpp "$@"; }
run export --checkpoint seed0.pth --out . --format onnx
run quantize --model doctrpp_fp32.onnx --out int8_static_weights.onnx --calib-synthetic 48
run quantize --model doctrpp_fp32.onnx --out int8_dynamic_linear.onnx --preset dynamic-linear
run export --checkpoint seed0.pth --out tflite_head_backbone --format tflite --precision int8 \
    --calib-synthetic 48
run export --checkpoint seed0.pth --out tflite_head --format tflite --precision int8 \
    --calib-synthetic 48 --keep-float head
run export --checkpoint seed0.pth --out tflite_fp16 --format tflite --precision fp16
cp tflite_head_backbone/doctrpp_int8.tflite int8_keep_head_backbone.tflite
cp tflite_head/doctrpp_int8.tflite int8_keep_head.tflite
cp tflite_fp16/doctrpp_fp16.tflite fp16.tflite
run bench --models doctrpp_fp32.onnx int8_static_weights.onnx int8_dynamic_linear.onnx \
    fp16.tflite int8_keep_head_backbone.tflite int8_keep_head.tflite \
    --out "$report" --runs 10 --per-kind 4 --no-peers --torch-checkpoint seed0.pth \
    --note "RANDOM WEIGHTS (shared reference checkpoint, make_ckpt.py --seed 0): latency is \
real, accuracy only smoke-tests the recipes"
