"""A fixed generated validation set, scored per crop kind."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from doctrpp import contract
from doctrpp.benchmarks.map_shape import nonprojective_recovery
from doctrpp.benchmarks.metrics import local_distortion, map_drift, ms_ssim, ms_ssim_masked
from doctrpp.contract import identity_map
from doctrpp.runtime.processing import flip_averaged_map, rectify_with_map
from doctrpp.udir.sample import generate, kind_for_index

from .data import VALIDATION_SEED_OFFSET, to_tensors


@dataclass
class ValidationItem:
    kind: str
    image: np.ndarray  # BGR uint8, 288x288 unless rendered larger
    backward_map: np.ndarray  # (288, 288, 2) normalised


def validation_set(
    count: int = 48, size: int = contract.INPUT_SIZE, start: int = 0
) -> list[ValidationItem]:
    """Crops `start` to `start + count - 1` of the fixed validation stream (the trainer's
    check uses the first 48); `size` renders them larger (their maps stay 288)."""
    if count < 1 or start < 0:
        raise ValueError(
            f"validation crops: count must be >= 1 and start >= 0, not {count}, {start}"
        )
    items = []
    for i in range(start, start + count):
        sample = generate(VALIDATION_SEED_OFFSET + i, kind_for_index(i), size=size)
        items.append(ValidationItem(sample.kind, sample.image, sample.backward_map))
    return items


def save_validation_set(items: list[ValidationItem], path: Path) -> None:
    """Freeze a validation set (kinds, crops, maps) in one .npz, written atomically, so that
    later generator changes do not move the yardstick old and new weights are paired on."""
    path = Path(path)
    partial = path.with_name(path.name + ".partial.npz")
    np.savez(
        partial,
        kinds=np.array([it.kind for it in items]),
        images=np.stack([it.image for it in items]),
        maps=np.stack([it.backward_map for it in items]),
    )
    partial.replace(path)


def load_validation_set(path: Path) -> list[ValidationItem]:
    """A set written by `save_validation_set`."""
    with np.load(Path(path)) as data:
        kinds, images, maps = data["kinds"], data["images"], data["maps"]
    return [ValidationItem(str(k), i, m) for k, i, m in zip(kinds, images, maps, strict=True)]


def crop_scores(items: list[ValidationItem], predicted: list[np.ndarray]) -> list[dict[str, float]]:
    """Each crop's map error (px of the 288 grid), MS-SSIM-M, unmasked MS-SSIM and local
    distortion, and the size of its map's non-projective part and of the error in it."""
    rows = []
    for item, bm in zip(items, predicted, strict=True):
        rectified = rectify_with_map(item.image, bm)
        reference = rectify_with_map(item.image, item.backward_map)
        shape = nonprojective_recovery(bm, item.backward_map)
        rows.append(
            {
                "map_error_px": map_drift(bm, item.backward_map).mean_px,
                "ms_ssim_m": ms_ssim_masked(rectified, reference),
                "ms_ssim": ms_ssim(rectified, reference),
                "local_distortion": local_distortion(rectified, reference),
                "nonprojective_error_px": shape.error_px,
                "nonprojective_truth_px": shape.truth_px,
            }
        )
    return rows


def summarise_crops(kinds: list[str], rows: list[dict[str, float]]) -> dict[str, float]:
    """Per kind and overall: the means of `crop_scores`, and how much of the maps'
    non-projective part (curls, folds) was recovered (1 - its error / its size, ratio of
    means; 0 = a model that only straightens perspective)."""
    scores: dict[str, float] = {}
    for kind in [*dict.fromkeys(kinds), "all"]:
        chosen = [r for r, k in zip(rows, kinds, strict=True) if kind in ("all", k)]
        mean = {key: float(np.mean([r[key] for r in chosen])) for key in chosen[0]}
        scores[f"map_error_px/{kind}"] = mean["map_error_px"]
        scores[f"ms_ssim_m/{kind}"] = mean["ms_ssim_m"]
        scores[f"nonprojective_recovered/{kind}"] = 1.0 - mean["nonprojective_error_px"] / max(
            mean["nonprojective_truth_px"], 1e-9
        )
        scores[f"ms_ssim/{kind}"] = mean["ms_ssim"]
        scores[f"local_distortion/{kind}"] = mean["local_distortion"]
    return scores


def score_maps(items: list[ValidationItem], predicted: list[np.ndarray]) -> dict[str, float]:
    """Per kind and overall: mean map error (px of the 288 grid), MS-SSIM-M, non-projective
    part recovered, and the unmasked MS-SSIM and local distortion that issue #10's held-out
    check uses (black counts against them)."""
    return summarise_crops([it.kind for it in items], crop_scores(items, predicted))


@torch.no_grad()
def batch_maps(
    model: torch.nn.Module,
    images: torch.Tensor,
    autocast_dtype: torch.dtype | None = None,
    flip_average: bool = False,
) -> list[np.ndarray]:
    """(N, 3, S, S) RGB inputs -> the model's normalised maps, (S, S, 2) each; with
    `flip_average` each averaged with the unmirrored map of the mirrored input, as the
    runtime's default pipeline (`runtime.processing.flip_averaged_map`)."""
    device = next(model.parameters()).device

    def run(inputs: torch.Tensor) -> list[np.ndarray]:
        with torch.autocast(
            device.type, dtype=autocast_dtype or torch.bfloat16, enabled=autocast_dtype is not None
        ):
            pixels = model(inputs.to(device)).float().cpu().numpy()
        return [contract.pixels_to_normalised(p).transpose(1, 2, 0) for p in pixels]

    maps = run(images)
    if flip_average:
        maps = list(map(flip_averaged_map, maps, run(torch.flip(images, dims=[-1]))))
    return maps


@torch.no_grad()
def predict_maps(
    model: torch.nn.Module,
    items: list[ValidationItem],
    batch: int = 8,
    autocast_dtype: torch.dtype | None = None,
    flip_average: bool = False,
) -> list[np.ndarray]:
    """The model's maps of the items (`batch_maps`)."""
    was_training = model.training
    model.eval()
    maps: list[np.ndarray] = []
    for start in range(0, len(items), batch):
        chunk = items[start : start + batch]
        images = torch.stack([to_tensors(it.image, it.backward_map)[0] for it in chunk])
        maps.extend(batch_maps(model, images, autocast_dtype, flip_average))
    model.train(was_training)
    return maps


def identity_scores(items: list[ValidationItem]) -> dict[str, float]:
    """The untouched input as a baseline: the identity backward map."""
    return score_maps(items, [identity_map()] * len(items))
