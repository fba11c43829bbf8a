#!/usr/bin/env bash
# The runtime install alone: `pip install .` (no extras) in a fresh venv must rectify a photo
# with the shipped default model, from any folder (the repository root included), with no
# torch installed. CI runs this after the test suite.
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
python3 -m venv "$work/venv"
"$work/venv/bin/python" -m pip install -q --upgrade pip
"$work/venv/bin/python" -m pip install -q "$repo"
if "$work/venv/bin/python" -c "import torch" 2>/dev/null; then
    echo "runtime check: torch was installed by the runtime-only install" >&2
    exit 1
fi
"$work/venv/bin/python" - "$work/photo.png" <<'PY'
import sys
import cv2
import numpy as np
page = np.full((900, 700, 3), 235, np.uint8)
for y in range(80, 820, 24):
    cv2.putText(page, "a plain line of text on a page", (60, y), 0, 0.6, (30, 30, 30), 1)
tilt = cv2.getPerspectiveTransform(
    np.float32([[0, 0], [700, 0], [700, 900], [0, 900]]),
    np.float32([[40, 30], [660, 60], [690, 880], [10, 860]]),
)
cv2.imwrite(sys.argv[1], cv2.warpPerspective(page, tilt, (700, 900), borderValue=(60, 90, 120)))
PY
(cd "$work" && "$work/venv/bin/doctrpp" rectify photo.png -o out)
test -s "$work/out/photo_rectified.png"
(cd "$repo" && "$work/venv/bin/python" -m doctrpp rectify "$work/photo.png" -o "$work/from_repo")
test -s "$work/from_repo/photo_rectified.png"
echo "runtime check: runtime-only install rectified a photo with the shipped default, no torch"
