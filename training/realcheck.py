"""The real-photo check in the training loop: reference-free scores on real phone photos.

Photos (never trained on) and crops of the three kinds cut from them
(`udir.photos.photo_crop_box`), rectified by the model being trained and scored with
`benchmarks.reference_free`: text-line straightness and coherence against the untouched
crop's, black share and kept share, per kind.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import torch

from doctrpp import contract
from doctrpp.benchmarks.reference_free import (
    SCORE_SIZE,
    line_scores,
    rectification_scores,
    summarise,
)
from doctrpp.runtime.processing import applied_map, model_input, rectify_with_map
from doctrpp.udir.photos import chosen_photos, crops_of_photos

from .validate import batch_maps, identity_map, predict_maps, score_maps


@dataclass
class RealItem:
    name: str
    kind: str
    image: np.ndarray  # BGR uint8 crop at SCORE_SIZE x SCORE_SIZE (squashed like the input)
    lines: dict[str, float]  # line scores of the untouched crop


def real_photo_set(folder: Path, photos: int = 32, seed: int = 0) -> list[RealItem]:
    """`photos` photos spread over the folder, each as a complete, partial and none crop."""
    items = []
    for path, crops in crops_of_photos(chosen_photos(folder, photos), seed):
        for kind, crop in crops.items():
            crop = cv2.resize(crop, (SCORE_SIZE, SCORE_SIZE), cv2.INTER_AREA)
            items.append(RealItem(path.stem, kind, crop, line_scores(crop)))
    return items


@torch.no_grad()
def predict(
    model: torch.nn.Module, items: list[RealItem], batch: int = 8, flip_average: bool = False
) -> list[np.ndarray]:
    """The model's maps of the items (`validate.batch_maps`), from the runtime's input."""
    was_training = model.training
    model.eval()
    maps = []
    for start in range(0, len(items), batch):
        chunk = items[start : start + batch]
        inputs = np.concatenate([model_input(it.image, contract.INPUT_SIZE) for it in chunk])
        maps.extend(batch_maps(model, torch.from_numpy(inputs), flip_average=flip_average))
    model.train(was_training)
    return maps


def score_real(items: list[RealItem], maps: list[np.ndarray]) -> dict[str, float]:
    """Per kind: straightness and coherence of the results / of the untouched crops, black
    and kept share."""
    rows: dict[str, list[dict[str, float]]] = {}
    for item, backward_map in zip(items, maps, strict=True):
        rectified = rectify_with_map(item.image, backward_map)
        rows.setdefault(item.kind, []).append(
            rectification_scores(rectified, backward_map, item.lines)
        )
    return {
        f"real/{metric}/{kind}": value
        for kind, kind_rows in rows.items()
        for metric, value in summarise(kind_rows).items()
    }


def validation_maps(
    model: torch.nn.Module | None,
    validation: list,
    real_items: list[RealItem],
    autocast_dtype: torch.dtype | None = None,
    flip_average: bool = False,
    line_alignment: bool = False,
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The model's maps (None: the identity map) of the generated set and the real items.
    Raw maps, as a training validation logs them, unless `flip_average` and
    `line_alignment` ask for the runtime's steps (the latter also smooths, as `rectify`
    does)."""
    if model is None:
        return [identity_map()] * len(validation), [identity_map()] * len(real_items)
    maps = predict_maps(model, validation, autocast_dtype=autocast_dtype, flip_average=flip_average)
    real_maps = predict(model, real_items, flip_average=flip_average) if real_items else []
    if line_alignment:
        maps, real_maps = _as_applied(validation, maps), _as_applied(real_items, real_maps)
    return maps, real_maps


def scores_of_maps(
    validation: list,
    maps: list[np.ndarray],
    real_items: list[RealItem],
    real_maps: list[np.ndarray],
) -> dict[str, float]:
    """The generated set's scores and, with real items, the real-photo check's."""
    scores = score_maps(validation, maps)
    if real_items:
        scores.update(score_real(real_items, real_maps))
    return scores


def validation_scores(
    model: torch.nn.Module | None, validation: list, real_items: list[RealItem], **options
) -> dict[str, float]:
    """`scores_of_maps` of `validation_maps` (`options`: its autocast_dtype, flip_average
    and line_alignment)."""
    maps, real_maps = validation_maps(model, validation, real_items, **options)
    return scores_of_maps(validation, maps, real_items, real_maps)


def _as_applied(items: list, maps: list[np.ndarray]) -> list[np.ndarray]:
    """The maps as `rectify` post-processes them: smoothed, text lines aligned."""
    return [applied_map(it.image, m) for it, m in zip(items, maps, strict=True)]
