from __future__ import annotations

import importlib.util
import os
from pathlib import Path

import cv2
import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_REFERENCE = Path(
    os.environ.get("DOCTRPP_SHARED_REFERENCE", REPO.parent / "shared" / "reference")
)


@pytest.fixture(scope="session")
def shared_reference() -> Path:
    """../shared/reference beside the clone; CI must have it, elsewhere we skip."""
    if not (SHARED_REFERENCE / "official_seed0.npz").is_file():
        if os.environ.get("CI"):
            pytest.fail(f"shared reference files missing at {SHARED_REFERENCE}")
        pytest.skip(f"shared reference files not found at {SHARED_REFERENCE}")
    return SHARED_REFERENCE


@pytest.fixture(scope="session")
def make_ckpt(shared_reference):
    """The shared deterministic random-checkpoint writer, imported as a module."""
    spec = importlib.util.spec_from_file_location("make_ckpt", shared_reference / "make_ckpt.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def reference_state(make_ckpt):
    """Seed-0 reference checkpoint as saved by the authors' code (with `module.`)."""
    return make_ckpt.build(seed=0, prefix=True, drop_unused=False)


@pytest.fixture(scope="session")
def tiny_model():
    import torch

    from doctrpp.export.config import TINY
    from doctrpp.export.model import DocTrPP

    torch.manual_seed(0)
    return DocTrPP(TINY).eval()


@pytest.fixture(scope="session")
def tiny_checkpoint(tiny_model, tmp_path_factory) -> Path:
    """The tiny model saved as our trainer does: state dict + recorded config."""
    import dataclasses

    import torch

    path = tmp_path_factory.mktemp("ckpt") / "tiny.pt"
    torch.save(
        {"model": tiny_model.state_dict(), "config": dataclasses.asdict(tiny_model.config)}, path
    )
    return path


@pytest.fixture(scope="session")
def tiny_onnx(tiny_model, tmp_path_factory) -> Path:
    from doctrpp.export.onnx_export import export_onnx

    path = tmp_path_factory.mktemp("tiny") / "doctrpp_fp32.onnx"
    export_onnx(tiny_model, path, checkpoint_sha256="0" * 64, checkpoint_note="tiny test model")
    return path


@pytest.fixture
def document_photo() -> np.ndarray:
    """A small synthetic BGR 'photo': a page with text and lines on a darker table."""
    import cv2

    photo = np.full((300, 240, 3), (60, 80, 100), np.uint8)
    cv2.rectangle(photo, (30, 20), (210, 280), (235, 235, 230), -1)
    for row, y in enumerate(range(50, 260, 22)):
        cv2.putText(photo, f"line {row} text", (40, y), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (20, 20, 20))
    return photo


_PARITY_LINES: list[str] = []


@pytest.fixture
def report_difference(request):
    """Record a measured largest difference; all of them are printed at the end of the run."""

    def report(what: str, largest: float, tolerance: float, unit: str = "px") -> None:
        line = (
            f"{request.node.name}: {what}: largest difference {largest:.2e} {unit} "
            f"(tolerance {tolerance:g})"
        )
        print(line)
        _PARITY_LINES.append(line)

    return report


def pytest_terminal_summary(terminalreporter):
    if _PARITY_LINES:
        terminalreporter.section("measured differences")
        for line in _PARITY_LINES:
            terminalreporter.write_line(line)


# The photo kinds the runtime accepts, made from an 8-bit BGR photo.
PHOTO_KINDS = {
    "gray": lambda im: cv2.cvtColor(im, cv2.COLOR_BGR2GRAY),
    "bgra": lambda im: cv2.cvtColor(im, cv2.COLOR_BGR2BGRA),
    "uint16": lambda im: im.astype(np.uint16) * 257,
    "float": lambda im: im.astype(np.float32) / 255.0,
}


@pytest.fixture(params=list(PHOTO_KINDS.values()), ids=list(PHOTO_KINDS))
def convert_photo(request):
    """Each accepted photo kind in turn: a function of an 8-bit BGR photo."""
    return request.param
