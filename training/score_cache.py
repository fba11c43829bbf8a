"""A cache of `training.score`'s per-file results, so that the default (scored in every
comparison, several minutes per set of crops) is scored once per setting.

An entry is keyed by the weights file's sha256 and by everything else its numbers depend
on: the generated crops and real-photo crops (their pixels and maps), the flip-average and
line-alignment switches, and the scoring code itself (every source file of the core,
benchmarks, export, runtime, training and udir packages; the metrics live in benchmarks):
a code change, a regenerated set or retrained weights miss the cache, never read stale
numbers.
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
from collections.abc import Callable, Sequence
from pathlib import Path

from doctrpp.files import sha256_of, write_bytes_atomically

Result = tuple[dict, list[dict[str, float]]]


# The sub-packages whose code the scores depend on (the core's own files included).
SCORED_PACKAGES = (
    "doctrpp",
    "doctrpp.benchmarks",  # MS-SSIM, local distortion, map shape, the reference-free scores
    "doctrpp.export",
    "doctrpp.runtime",
    "doctrpp.training",
    "doctrpp.udir",
)


def _package_digest() -> str:
    """sha256 over the scoring packages' Python sources (names and bytes), sorted; in a
    source checkout and in an installed package alike."""
    digest = hashlib.sha256()
    for name in SCORED_PACKAGES:
        folder = Path(importlib.util.find_spec(name).origin).parent
        # the core's own modules only: in an installed package its folder also holds the
        # stage folders, hashed as packages of their own
        sources = folder.glob("*.py") if name == "doctrpp" else folder.rglob("*.py")
        for source in sorted(sources):
            digest.update(f"{name}/{source.relative_to(folder)}".encode())
            digest.update(source.read_bytes())
    return digest.hexdigest()


def setting_key(
    validation: Sequence, real_items: Sequence, flip_average: bool, line_alignment: bool
) -> str:
    """One hex digest for the crops, the real-photo crops, the switches and the code."""
    digest = hashlib.sha256()
    digest.update(json.dumps([flip_average, line_alignment]).encode())
    for item in validation:
        digest.update(item.kind.encode())
        digest.update(item.image.tobytes())
        digest.update(item.backward_map.tobytes())
    for item in real_items:
        digest.update(f"{item.name}/{item.kind}".encode())
        digest.update(item.image.tobytes())
    digest.update(_package_digest().encode())
    return digest.hexdigest()


def cached_score(
    cache: Path | None, path: Path | None, key: str, compute: Callable[[], Result]
) -> Result:
    """`compute()`'s result for weights `path` (None: the identity map) under setting `key`,
    read from `cache` when an entry exists and written there (atomically) when not."""
    if cache is None:
        return compute()
    weights = sha256_of(path) if path else "identity"
    entry = cache / f"{hashlib.sha256((weights + key).encode()).hexdigest()[:32]}.json"
    if entry.is_file():
        stored = json.loads(entry.read_text())
        scores = {**stored["scores"], "weights": str(path) if path else "identity"}
        return scores, stored["rows"]
    scores, rows = compute()
    write_bytes_atomically(entry, json.dumps({"scores": scores, "rows": rows}).encode())
    return scores, rows
