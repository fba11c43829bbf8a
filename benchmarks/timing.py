"""Latency and memory of model files: interleaved rounds in one process, medians."""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from doctrpp.runtime.backends import open_backend


@dataclass(frozen=True)
class Latency:
    median_ms: float
    p90_ms: float
    runs: int

    @property
    def fps(self) -> float:
        return 1000.0 / self.median_ms


def interleaved_latency(
    models: list[Path],
    threads: tuple[int, ...] = (1, 2),
    runs: int = 20,
    warmup: int = 3,
    progress=None,
) -> dict[tuple[str, int], Latency]:
    """Time every (model, threads) pair in rounds, one run each per round, so that load
    from elsewhere on a shared machine hits all of them alike."""
    sessions = {(str(m), t): open_backend(m, t) for m in models for t in threads}
    x = np.random.default_rng(0).random((1, 3, 288, 288), dtype=np.float32)
    for backend in sessions.values():
        for _ in range(warmup):
            backend.run(x)
    times: dict[tuple[str, int], list[float]] = {key: [] for key in sessions}
    for round_index in range(runs):
        for key, backend in sessions.items():
            start = time.perf_counter()
            backend.run(x)
            times[key].append((time.perf_counter() - start) * 1000)
        if progress:
            progress(round_index + 1, runs)
    return {
        key: Latency(float(np.median(v)), float(np.percentile(v, 90)), len(v))
        for key, v in times.items()
    }


# VmHWM of the child's own address space: ru_maxrss would carry over the parent's peak
# across fork + exec on Linux.
_RSS_PROBE = """
import json, sys
import numpy as np
from doctrpp.runtime.backends import open_backend
backend = open_backend(sys.argv[1], int(sys.argv[2]))
x = np.zeros((1, 3, 288, 288), np.float32)
for _ in range(3):
    backend.run(x)
with open("/proc/self/status") as f:
    peak_kb = next(int(line.split()[1]) for line in f if line.startswith("VmHWM:"))
print(json.dumps(peak_kb))
"""


def peak_rss_mb(model: Path, threads: int = 2) -> float:
    """Peak resident memory (MB) of a fresh process that loads the model and runs it."""
    # Run outside the current folder: a source checkout there would shadow the package.
    done = subprocess.run(
        [sys.executable, "-c", _RSS_PROBE, str(Path(model).resolve()), str(threads)],
        capture_output=True,
        text=True,
        check=True,
        timeout=600,
        cwd=tempfile.gettempdir(),
    )
    return json.loads(done.stdout.strip().splitlines()[-1]) / 1024.0
