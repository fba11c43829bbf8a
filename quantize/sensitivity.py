"""Which int8 nodes cost accuracy: quantise one group of nodes at a time, measure drift.

Groups are the module paths in the node names (e.g. `/model/fnet/layer1`,
`/model/layers.0_5/self_attn`): one quantisation per group, so the ranking of a large
network costs tens of quantisations, not hundreds.
"""

from __future__ import annotations

import dataclasses
import tempfile
from collections import defaultdict
from pathlib import Path

import numpy as np
import onnx

from doctrpp.benchmarks.accuracy import drift, predict

from .presets import QuantPreset
from .quantize import _preprocess, eligible_nodes, quantise


def group_of(node_name: str, depth: int = 3) -> str:
    parts = [p for p in node_name.split("/") if p]
    return "/" + "/".join(parts[: depth - 1]) if len(parts) >= depth else node_name


def node_groups(fp32_path: Path, preset: QuantPreset) -> dict[str, list[str]]:
    with tempfile.TemporaryDirectory() as folder:
        prepared = Path(folder) / "prepared.onnx"
        _preprocess(fp32_path, prepared)
        names = eligible_nodes(onnx.load(str(prepared)), preset)
    groups: dict[str, list[str]] = defaultdict(list)
    for name in names:
        groups[group_of(name)].append(name)
    return dict(groups)


def rank_groups(
    fp32_path: Path,
    preset: QuantPreset,
    calibration: list[np.ndarray] | None,
    held_out: list[np.ndarray],
    progress=None,
) -> list[dict]:
    """Mean/max drift (px) caused by quantising each group alone, worst first."""
    reference = predict(fp32_path, held_out)
    groups = node_groups(fp32_path, preset)
    ranking = []
    with tempfile.TemporaryDirectory() as folder:
        for index, (group, names) in enumerate(sorted(groups.items())):
            only = dataclasses.replace(preset, name=f"{preset.name}:{group}")
            out = Path(folder) / "one.onnx"
            quantise(fp32_path, out, only, calibration, only_nodes=names)
            summary = drift(reference, predict(out, held_out))
            ranking.append(
                {
                    "group": group,
                    "nodes": len(names),
                    "drift_mean_px": summary.mean_px,
                    "drift_max_px": summary.max_px,
                }
            )
            if progress:
                progress(index + 1, len(groups), group)
    return sorted(ranking, key=lambda r: r["drift_mean_px"], reverse=True)
