"""Our DocTr++ implementation computes the reference function."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from doctrpp.export.checkpoint import unwrap_state_dict
from doctrpp.export.config import REFERENCE, TINY, ModelConfig
from doctrpp.export.model import DocTrPP
from doctrpp.export.upsample import ConvexUpsample, convex_upsample_raft

REFERENCE_TOLERANCE_PX = 1e-3


def test_reference_outputs_reproduced(reference_state, shared_reference, report_difference):
    model = DocTrPP(REFERENCE).eval()
    model.load_state_dict(unwrap_state_dict(reference_state))
    expected = np.load(shared_reference / "official_seed0.npz")
    with torch.no_grad():
        got = model(torch.from_numpy(expected["input"])).numpy()
    worst = float(np.abs(got - expected["bm_pixels"]).max())
    report_difference("PyTorch vs official_seed0 bm_pixels", worst, REFERENCE_TOLERANCE_PX)
    assert worst <= REFERENCE_TOLERANCE_PX


def test_state_dict_matches_reference_layout(shared_reference):
    listing = json.loads((shared_reference / "official_state_dict.json").read_text())
    unused = (".multihead_attn_list.1.", ".norm2_list.1.")
    used = {k: tuple(v) for k, v in listing.items() if not any(u in k for u in unused)}
    ours = {k: tuple(v.shape) for k, v in DocTrPP(REFERENCE).state_dict().items()}
    assert ours == used
    n_used = sum(int(np.prod(s)) for s in used.values())
    assert n_used == sum(p.numel() for p in DocTrPP(REFERENCE).parameters())


def test_convex_upsample_equals_raft(report_difference):
    torch.manual_seed(0)
    flow = torch.randn(2, 2, 36, 36) * 3
    mask = torch.randn(2, 576, 36, 36) * 2
    ours = ConvexUpsample()(flow, mask)
    raft = convex_upsample_raft(flow, mask)
    worst = float((ours - raft).abs().max())
    report_difference("convex upsampling vs RAFT Unfold/7-D", worst, 1e-5)
    assert ours.shape == (2, 2, 288, 288)
    assert worst <= 1e-5


def test_no_tensor_above_4d_in_forward(tiny_model):
    ranks = []

    def record(_module, _inputs, output):
        outputs = output if isinstance(output, tuple) else (output,)
        ranks.extend(t.dim() for t in outputs if isinstance(t, torch.Tensor))

    handles = [m.register_forward_hook(record) for m in tiny_model.modules()]
    try:
        with torch.no_grad():
            tiny_model(torch.rand(1, 3, 288, 288))
    finally:
        for h in handles:
            h.remove()
    assert max(ranks) <= 4


def test_positional_encodings_are_not_state(tiny_model):
    keys = tiny_model.state_dict().keys()
    assert not any(k.endswith(".pos") or k.endswith("grid") or "kernel" in k for k in keys)


def test_batch_items_independent(tiny_model):
    x = torch.rand(2, 3, 288, 288)
    with torch.no_grad():
        both = tiny_model(x)
        first = tiny_model(x[:1])
    assert torch.allclose(both[:1], first, atol=1e-4)


def test_config_validation():
    with pytest.raises(ValueError, match="divisible"):
        ModelConfig(hidden_dim=30, num_heads=4)
    with pytest.raises(ValueError, match="unknown model config keys"):
        ModelConfig.from_dict({"width": 3})
    assert ModelConfig.from_dict(json.loads(TINY.to_json())) == TINY
    with pytest.raises(ValueError, match="at least 1"):
        ModelConfig(coarse_layers_per_block=0)
    deep = ModelConfig.from_dict({**json.loads(TINY.to_json()), "coarse_layers_per_block": 2})
    assert (deep.coarse_depth, TINY.coarse_depth) == (2, TINY.layers_per_block)
    # Configs saved before the field existed still load, as the reference's layout.
    saved = {k: v for k, v in json.loads(TINY.to_json()).items() if k != "coarse_layers_per_block"}
    assert ModelConfig.from_dict(saved) == TINY
