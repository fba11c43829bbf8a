"""`python -m doctrpp.training.grow`: wider feed-forward layers or feature encoder, deeper
coarse attention blocks, same function."""

from __future__ import annotations

import dataclasses

import pytest
import torch

from doctrpp.errors import CliError
from doctrpp.export.checkpoint import CheckpointError, load_model
from doctrpp.export.model import DocTrPP
from doctrpp.training.cli import _model_config
from doctrpp.training.grow import (
    backbone_stages,
    deepen_coarse_blocks,
    grow_file,
    main,
    widen_backbone,
    widen_feed_forward,
)
from doctrpp.training.throughput import model_config

# fp32 sums in another order after the zero columns: rounding only (pixels of the 288 map).
GROWN_TOLERANCE_PX = 1e-3


def _as_model(state: dict, config) -> DocTrPP:
    model = DocTrPP(config).eval()
    model.load_state_dict(state)
    return model


def _grown(tiny_model, ffn_dim: int = 96) -> DocTrPP:
    return _as_model(*widen_feed_forward(tiny_model.state_dict(), tiny_model.config, ffn_dim))


def _wide_backbone(tiny_model, widths=(12, 24, 30)) -> DocTrPP:
    return _as_model(*widen_backbone(tiny_model.state_dict(), tiny_model.config, widths))


def _deep_coarse(tiny_model, layers: int = 3) -> DocTrPP:
    return _as_model(*deepen_coarse_blocks(tiny_model.state_dict(), tiny_model.config, layers))


@pytest.mark.parametrize(
    ("grow", "what", "grown_config"),
    [
        (_grown, "feed-forward 96", {"ffn_dim": 96}),
        (_wide_backbone, "feature encoder 12/24/30", {"backbone_widths": (12, 24, 30)}),
    ],
)
def test_the_grown_model_computes_the_same_map(
    tiny_model, report_difference, grow, what, grown_config
):
    grown = grow(tiny_model)
    assert grown.config == dataclasses.replace(tiny_model.config, **grown_config)
    image = torch.rand(1, 3, 288, 288, generator=torch.Generator().manual_seed(1)) * 255
    with torch.no_grad():
        largest = (grown(image) - tiny_model(image)).abs().max().item()
    report_difference(f"grown ({what}) vs source backward map", largest, GROWN_TOLERANCE_PX)
    assert largest <= GROWN_TOLERANCE_PX


def test_the_new_channels_learn_from_the_first_step(tiny_model):
    grown = _wide_backbone(tiny_model).train()
    grown(torch.rand(1, 3, 288, 288) * 255).abs().mean().backward()
    projection = grown.fnet.conv2.weight  # reads stage 3: 24 old channels, 6 new
    assert projection.grad[:, 24:].abs().sum() > 0  # the zero weights get gradients
    assert torch.count_nonzero(projection.detach()[:, 24:]) == 0
    first = grown.fnet.conv1.weight
    assert first.shape[0] == 12 and torch.count_nonzero(first.detach()[8:]) > 0


def test_every_feature_encoder_convolution_has_its_stages(tiny_model):
    stages = {
        key: backbone_stages(key)
        for key in tiny_model.state_dict()
        if key.startswith("fnet.") and key.endswith(".weight")
    }
    assert stages["fnet.conv1.weight"] == (None, 0)
    assert stages["fnet.layer1.0.conv1.weight"] == (0, 0)
    assert stages["fnet.layer2.0.conv1.weight"] == (0, 1)
    assert stages["fnet.layer2.0.conv2.weight"] == (1, 1)
    assert stages["fnet.layer3.0.downsample.0.weight"] == (1, 2)
    assert stages["fnet.layer3.1.conv1.weight"] == (2, 2)
    assert stages["fnet.conv2.weight"] == (2, None)
    with pytest.raises(ValueError, match="none below"):
        widen_backbone(tiny_model.state_dict(), tiny_model.config, (4, 16, 24))
    with pytest.raises(ValueError, match="at least one above"):
        widen_backbone(tiny_model.state_dict(), tiny_model.config, (8, 16, 24))


def test_the_new_units_learn_from_the_first_step(tiny_model):
    grown = _grown(tiny_model).train()
    grown(torch.rand(1, 3, 288, 288) * 255).abs().mean().backward()
    linear2 = grown.encoder_block0.layers[0].linear2.weight
    assert linear2.grad[:, 64:].abs().sum() > 0  # the zero columns get gradients
    assert torch.count_nonzero(linear2.detach()[:, 64:]) == 0


def test_deeper_coarse_blocks_compute_the_same_map(tiny_model, report_difference):
    # Norms as training leaves them (not 1 and 0), so moving the last scale and shift counts.
    generator = torch.Generator().manual_seed(2)
    state = tiny_model.state_dict()
    for key, value in state.items():
        if ".norm" in key:  # weights in [0.8, 1.2], biases in [-0.1, 0.1]
            low, spread = (0.8, 0.4) if key.endswith("weight") else (-0.1, 0.2)
            state[key] = torch.rand(value.shape, generator=generator) * spread + low
    source = _as_model(state, tiny_model.config)
    grown = _as_model(*deepen_coarse_blocks(state, tiny_model.config, 3))
    assert grown.config == dataclasses.replace(tiny_model.config, coarse_layers_per_block=3)
    image = torch.rand(1, 3, 288, 288, generator=generator) * 255
    with torch.no_grad():
        largest = (grown(image) - source(image)).abs().max().item()
    report_difference("grown (coarse blocks 3 layers) vs source", largest, GROWN_TOLERANCE_PX)
    assert largest <= GROWN_TOLERANCE_PX


def test_the_new_layers_sit_in_the_coarse_blocks_and_learn(tiny_model):
    grown = _deep_coarse(tiny_model).train()
    assert [
        len(grown.get_submodule(f"{kind}_block{i}").layers)
        for kind in ("encoder", "decoder")
        for i in range(3)
    ] == [1, 3, 3, 3, 3, 1]
    grown(torch.rand(1, 3, 288, 288) * 255).abs().mean().backward()
    new_layer = grown.decoder_block0.layers[2]
    assert new_layer.linear2.weight.grad.abs().sum() > 0  # zero matrices get gradients
    assert new_layer.self_attn.out_proj.weight.grad.abs().sum() > 0
    assert torch.count_nonzero(new_layer.linear2.weight.detach()) == 0
    old_last = tiny_model.encoder_block1.layers[0].norm3
    assert torch.equal(grown.encoder_block1.layers[2].norm3.weight.detach(), old_last.weight)
    with pytest.raises(ValueError, match="must exceed"):
        deepen_coarse_blocks(tiny_model.state_dict(), tiny_model.config, 1)


def test_grow_file_keeps_the_record_and_never_overwrites(tiny_model, tmp_path, capsys):
    source = tmp_path / "source.pt"
    record = {"step": 1234, "samples_seen": 9872, "cpu_seconds": 5.0}
    torch.save(
        {
            "model": tiny_model.state_dict(),
            "config": dataclasses.asdict(tiny_model.config),
            "train_state": record,
        },
        source,
    )
    out = tmp_path / "grown.pt"
    assert main([str(source), "--ffn-dim", "128", "--out", str(out)]) == 0
    assert "feed-forward width 128" in capsys.readouterr().out
    both = tmp_path / "both.pt"
    assert (
        main(
            [
                str(source),
                "--ffn-dim",
                "96",
                "--backbone-widths",
                "8",
                "24",
                "32",
                "--out",
                str(both),
            ]
        )
        == 0
    )
    assert load_model(both).config.backbone_widths == (8, 24, 32)
    assert load_model(both).config.ffn_dim == 96
    deep = tmp_path / "deep.pt"
    assert main([str(source), "--coarse-layers", "2", "--out", str(deep)]) == 0
    assert "coarse-block layers 2" in capsys.readouterr().out
    assert load_model(deep).config.coarse_depth == 2
    assert main([str(source), "--out", str(tmp_path / "none.pt")]) == 2
    assert "nothing to grow" in capsys.readouterr().err
    written = torch.load(out, weights_only=True)
    assert written["train_state"] == record and written["config"]["ffn_dim"] == 128
    assert load_model(out).config.ffn_dim == 128
    before = out.read_bytes()
    assert main([str(source), "--ffn-dim", "256", "--out", str(out)]) == 2
    assert "exists" in capsys.readouterr().err and out.read_bytes() == before
    assert main([str(source), "--ffn-dim", "32", "--out", str(tmp_path / "x.pt")]) == 2
    assert "must exceed" in capsys.readouterr().err
    with pytest.raises(CheckpointError, match="not found"):
        grow_file(tmp_path / "missing.pt", tmp_path / "y.pt", 128)


def test_the_trainer_takes_the_config_of_the_file_it_starts_from(tiny_model, tmp_path):
    grown = tmp_path / "grown.pt"
    state, config = widen_feed_forward(tiny_model.state_dict(), tiny_model.config, 96)
    torch.save({"model": state, "config": dataclasses.asdict(config)}, grown)
    assert _model_config(None, "--init", grown) == config
    assert model_config(str(grown)) == config  # the throughput tool's --configs take files too
    assert _model_config("tiny", "--init", None).ffn_dim == 64
    with pytest.raises(CliError, match="another config"):
        _model_config("tiny", "--init", grown)
    with pytest.raises(CliError, match="no such file"):
        _model_config(None, "--resume", tmp_path / "missing.pth")
