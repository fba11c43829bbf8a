"""Checkpoints saved by the authors' code load in every common layout; others fail clearly."""

from __future__ import annotations

import pytest
import torch

from doctrpp.export.checkpoint import (
    CheckpointError,
    load_model,
    read_checkpoint,
    unwrap_state_dict,
)
from doctrpp.export.config import REFERENCE, TINY
from doctrpp.export.model import DocTrPP


@pytest.mark.parametrize(
    ("prefix", "drop_unused", "wrapper"),
    [
        (True, False, None),
        (False, False, None),
        (True, True, None),
        (False, True, "state_dict"),
        (True, False, "model"),
    ],
)
def test_layouts_load(make_ckpt, prefix, drop_unused, wrapper, tmp_path):
    state = make_ckpt.build(seed=1, prefix=prefix, drop_unused=drop_unused)
    obj = {wrapper: state, "epoch": 3} if wrapper else state
    unwrapped = unwrap_state_dict(obj)
    model = DocTrPP(REFERENCE)
    model.load_state_dict(unwrapped)  # strict: every key used, none left over
    assert not any(k.startswith("module.") for k in unwrapped)


def test_file_round_trip_reference(make_ckpt, tmp_path):
    path = tmp_path / "official.pth"
    torch.save(make_ckpt.build(seed=2), path)
    model = load_model(path)
    assert model.config == REFERENCE
    assert not model.training


def test_tiny_round_trip_with_recorded_config(tiny_checkpoint):
    _, config = read_checkpoint(tiny_checkpoint)
    assert config == TINY
    assert load_model(tiny_checkpoint).config == TINY


def test_missing_and_mismatched_keys_named(tiny_model, tmp_path):
    state = dict(tiny_model.state_dict())
    state.pop("query_embed.weight")
    state["down_layer0.bias"] = torch.zeros(7)
    state["extra.weight"] = torch.zeros(1)
    path = tmp_path / "broken.pth"
    torch.save(state, path)
    with pytest.raises(CheckpointError) as info:
        load_model(path, TINY)
    message = str(info.value)
    print(message)
    assert "\n" not in message
    assert "missing keys: query_embed.weight" in message
    assert "unexpected keys: extra.weight" in message
    assert "down_layer0.bias (7,) vs (32,)" in message


def test_wrong_config_reports_shapes(tiny_model, tmp_path):
    path = tmp_path / "tiny.pth"
    torch.save(tiny_model.state_dict(), path)
    with pytest.raises(CheckpointError, match="shape mismatches"):
        load_model(path, REFERENCE)


class NotAllowed:
    pass


def test_pickled_objects_refused(tmp_path):
    path = tmp_path / "evil.pth"
    torch.save({"state_dict": {"a": torch.zeros(1)}, "obj": NotAllowed()}, path)
    with pytest.raises(CheckpointError, match="cannot read checkpoint"):
        read_checkpoint(path)


def test_not_a_checkpoint(tmp_path):
    path = tmp_path / "junk.pth"
    path.write_bytes(b"not a checkpoint")
    with pytest.raises(CheckpointError, match="is not a PyTorch checkpoint"):
        read_checkpoint(path)
    png = tmp_path / "text.png"  # the case: an image given as the checkpoint
    png.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(64))
    with pytest.raises(CheckpointError, match="text.png is not a PyTorch checkpoint"):
        read_checkpoint(png)
    with pytest.raises(CheckpointError, match="not found"):
        read_checkpoint(tmp_path / "absent.pth")
    torch.save({"epoch": 1}, path)
    with pytest.raises(CheckpointError, match="no state dict"):
        read_checkpoint(path)
