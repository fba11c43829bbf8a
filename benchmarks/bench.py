"""`doctrpp bench`: per model file, size, latency, memory and accuracy; one JSON record."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from doctrpp import contract
from doctrpp.benchmarks.accuracy import predict
from doctrpp.benchmarks.metrics import (
    local_distortion_masked,
    map_drift,
    ms_ssim_masked,
)
from doctrpp.benchmarks.reference_free import line_scores, rectification_scores, summarise
from doctrpp.runtime.backends import open_backend
from doctrpp.runtime.processing import model_input, rectify_with_map

BENCH_SEED_OFFSET = 3_000_000_000


@dataclass
class Probe:
    """One input of the accuracy set: a generated crop (with ground truth) or a real photo."""

    name: str
    kind: str  # complete | partial | none | photo
    image: np.ndarray
    backward_map: np.ndarray | None = None


def generated_probes(per_kind: int) -> list[Probe]:
    from doctrpp.udir.sample import generate, kind_for_index

    probes = []
    for i in range(3 * per_kind):
        sample = generate(BENCH_SEED_OFFSET + i, kind_for_index(i))
        probes.append(Probe(f"crop{i:03d}", sample.kind, sample.image, sample.backward_map))
    return probes


def photo_probes(folder: Path | None, limit: int = 12) -> list[Probe]:
    """Crops of the three kinds cut from real photos (the user's `folder`, at most `limit`
    spread over it; else the two document photos scikit-image ships, if installed)."""
    from doctrpp.runtime.imageio import image_files, read_image
    from doctrpp.udir.photos import crops_of_each_kind, spread

    if folder is not None:
        paths = spread(image_files(folder), limit)
    else:
        try:
            import skimage
        except ImportError:
            return []
        data = Path(skimage.__file__).parent / "data"
        paths = [data / "page.png", data / "text.png"]
    probes = []
    for index, path in enumerate(p for p in paths if p.is_file()):
        for kind, crop in crops_of_each_kind(read_image(path), BENCH_SEED_OFFSET, index).items():
            probes.append(Probe(f"{path.stem}-{kind}", f"real {kind}", crop))
    return probes


def untouched_accuracy(probes: list[Probe]) -> dict:
    """The untouched input (identity map) against ground truth: the bar a model must clear."""
    rows: dict[str, dict[str, list[float]]] = {}
    for probe in probes:
        if probe.backward_map is None:
            continue
        image = _as_uint8_bgr(probe.image)
        truth = rectify_with_map(image, probe.backward_map)
        identity = contract.identity_map(probe.backward_map.shape[0])
        row = rows.setdefault(probe.kind, {"gt_map_error_px": [], "gt_ms_ssim_m": []})
        row["gt_map_error_px"].append(map_drift(identity, probe.backward_map).mean_px)
        row["gt_ms_ssim_m"].append(ms_ssim_masked(image, truth))
    return {k: {m: float(np.mean(v)) for m, v in row.items()} for k, row in rows.items()}


def _as_uint8_bgr(image: np.ndarray) -> np.ndarray:
    if image.dtype == np.uint16:
        image = (image // 257).astype(np.uint8)
    return image


def accuracy(model: Path, probes: list[Probe], reference_maps: list[np.ndarray] | None) -> dict:
    """Drift and image metrics against the reference model's maps and against ground truth."""
    inputs = [model_input(p.image, contract.INPUT_SIZE) for p in probes]
    maps = predict(model, inputs)
    return {"per_kind": accuracy_of_maps(probes, maps, reference_maps), "maps": maps}


def accuracy_of_maps(
    probes: list[Probe], maps: list[np.ndarray], reference_maps: list[np.ndarray] | None
) -> dict:
    """Per kind: drift against reference maps (if given), accuracy against ground truth
    (generated crops) and reference-free scores (real-photo crops)."""
    rows: dict[str, dict[str, list[float]]] = {}
    real_rows: dict[str, list[dict[str, float]]] = {}

    def add(group: str, metric: str, value: float) -> None:
        rows.setdefault(group, {}).setdefault(metric, []).append(value)

    for probe, bm, ref in zip(probes, maps, reference_maps or [None] * len(maps), strict=True):
        image = _as_uint8_bgr(probe.image)
        rectified = rectify_with_map(image, bm)
        if ref is not None:
            d = map_drift(bm, ref)
            add(probe.kind, "drift_mean_px", d.mean_px)
            add(probe.kind, "drift_max_px", d.max_px)
            theirs = rectify_with_map(image, ref)
            add(probe.kind, "ms_ssim_m_vs_ref", ms_ssim_masked(rectified, theirs))
            add(probe.kind, "ld_m_vs_ref", local_distortion_masked(rectified, theirs))
        if probe.backward_map is not None:
            add(probe.kind, "gt_map_error_px", map_drift(bm, probe.backward_map).mean_px)
            truth = rectify_with_map(image, probe.backward_map)
            add(probe.kind, "gt_ms_ssim_m", ms_ssim_masked(rectified, truth))
        else:
            real_rows.setdefault(probe.kind, []).append(
                rectification_scores(rectified, bm, line_scores(image))
            )
    summary: dict[str, dict[str, float]] = {}
    for group, metrics in rows.items():
        summary[group] = {
            k: float(np.max(v)) if k.endswith("max_px") else float(np.mean(v))
            for k, v in metrics.items()
        }
    for group, group_rows in real_rows.items():
        summary.setdefault(group, {}).update(summarise(group_rows))
    return summary


def describe(model: Path) -> dict:
    backend = open_backend(model, 1)
    meta = backend.metadata
    return {
        "name": model.name,
        "path": str(model),
        "format": model.suffix.lstrip(".").lower(),
        "precision": meta.get(contract.META_PRECISION, "unknown"),
        "file_mb": model.stat().st_size / 1e6,
        "checkpoint_note": meta.get(contract.META_CHECKPOINT_NOTE, ""),
        "checkpoint_sha256": meta.get(contract.META_CHECKPOINT_SHA256, ""),
    }


def cross_shot_section(
    models: list[Path],
    reference: Path,
    photos: Path,
    pairs: int | None,
    threads: int,
    peers: bool,
    status=print,
) -> dict | None:
    """Cross-shot agreement of the untouched photos, each model file (run as `doctrpp
    rectify` runs it) and UVDoc (when installed and `peers`) on the first `pairs` documents
    with two shots in `photos` (None: all); None where the folder holds fewer than two."""
    from doctrpp.runtime.rectifier import Rectifier

    from .cross_shot import UNTOUCHED, report_entries, shot_pairs
    from .peers import UVDocPeer, uvdoc_model_path

    documents = shot_pairs(photos)[:pairs]
    if len(documents) < 2:
        return None
    entries = [(UNTOUCHED, lambda image: image)]
    entries += [(m.name, Rectifier(m, threads=threads).rectify) for m in models]
    uvdoc = uvdoc_model_path() if peers else None
    if uvdoc is not None:
        entries.append(("UVDoc (peer)", UVDocPeer(uvdoc, threads).rectify))
    rows = report_entries(entries, documents, reference.name, status)
    return {"photos": str(Path(photos).resolve()), "documents": len(documents), "rows": rows}
