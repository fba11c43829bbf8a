"""Weight averaging of cycle ends: the mean weights, CPU hours counted once, a run folder
that publishing accepts."""

from __future__ import annotations

import dataclasses
import json

import pytest
import torch

from doctrpp.errors import CliError
from doctrpp.export.config import TINY
from doctrpp.export.model import DocTrPP
from doctrpp.training.average import average, main
from doctrpp.training.publish import publish


def _checkpoint(path, seed: int, step: int, start: int, cpu: float) -> None:
    torch.manual_seed(seed)
    state = {"step": step, "schedule_start": start, "cpu_seconds": cpu, "samples_seen": 8 * step}
    payload = {
        "model": DocTrPP(TINY).state_dict(),
        "config": dataclasses.asdict(TINY),
        "train_state": {**state, "wall_seconds": cpu, "data_cpu_seconds": cpu / 2},
    }
    torch.save(payload, path)


@pytest.fixture
def lineage(tmp_path):
    """An ancestor at step 100 and two cycles grown from it (siblings)."""
    paths = {name: tmp_path / f"{name}.pt" for name in ("ancestor", "first", "second")}
    _checkpoint(paths["ancestor"], 0, 100, 0, 1000.0)
    _checkpoint(paths["first"], 1, 150, 100, 1500.0)
    _checkpoint(paths["second"], 2, 130, 100, 1300.0)
    return paths


def test_mean_weights_and_cpu_counted_once(lineage):
    averaged = average([lineage["first"], lineage["second"]], [lineage["ancestor"]])
    first = torch.load(lineage["first"], weights_only=True)["model"]
    second = torch.load(lineage["second"], weights_only=True)["model"]
    for key, value in averaged["model"].items():
        if value.is_floating_point():
            torch.testing.assert_close(value, (first[key] + second[key]) / 2)
    state = averaged["train_state"]
    # the longer cycle's lineage (1500 s) plus the sibling's own 300 s, not its ancestor's
    assert state["cpu_seconds"] == 1800.0 and state["data_cpu_seconds"] == 900.0
    assert state["step"] == 150 and state["samples_seen"] == 8 * 150 + 8 * 30
    assert state["averaged_from"] == [130, 150]


def test_a_cycle_and_its_start_add_nothing(lineage):
    state = average([lineage["ancestor"], lineage["first"]], [])["train_state"]
    assert state["cpu_seconds"] == 1500.0 and state["averaged_from"] == [100, 150]


def test_a_grandparent_is_counted_in_its_grandchild(lineage, tmp_path):
    # a cycle continued from "first": averaging it with "ancestor" needs "first" named
    _checkpoint(tmp_path / "third.pt", 3, 200, 150, 2000.0)
    with pytest.raises(CliError, match="--ancestor"):
        average([lineage["ancestor"], tmp_path / "third.pt"], [])
    state = average([lineage["ancestor"], tmp_path / "third.pt"], [lineage["first"]])
    assert state["train_state"]["cpu_seconds"] == 2000.0
    assert state["train_state"]["averaged_from"] == [100, 200]


def test_missing_ancestor_and_bad_input_are_clear(lineage, tmp_path):
    with pytest.raises(CliError, match="--ancestor"):
        average([lineage["first"], lineage["second"]], [])
    with pytest.raises(CliError, match="at least two"):
        average([lineage["first"]], [])
    with pytest.raises(CliError, match="checkpoint not found"):
        average([lineage["first"], tmp_path / "missing.pt"], [])
    (tmp_path / "notes.pt").write_text("not a checkpoint")
    with pytest.raises(CliError, match="not a PyTorch checkpoint"):
        average([lineage["first"], tmp_path / "notes.pt"], [])
    torch.save({"model": {}}, tmp_path / "weights_only.pt")
    with pytest.raises(CliError, match="not a training checkpoint"):
        average([lineage["first"], tmp_path / "weights_only.pt"], [])
    with pytest.raises(CliError, match="not a training checkpoint"):
        publish(tmp_path / "weights_only.pt", tmp_path / "published", note="test")


def test_run_folder_publishes(lineage, tmp_path, capsys):
    out = tmp_path / "averaged"
    args = [str(lineage["first"]), str(lineage["second"]), "--out", str(out)]
    args += ["--ancestor", str(lineage["ancestor"]), "--validation-size", "3"]
    assert main(args) == 0
    snapshot = out / "snapshots" / "step0000150.pt"
    assert snapshot.is_file()
    records = [json.loads(line) for line in (out / "validation.jsonl").read_text().splitlines()]
    assert records[0]["identity"] and records[1]["averaged_from"] == [130, 150]
    weights = publish(snapshot, tmp_path / "published", note="test")
    record = json.loads(weights.with_suffix(".json").read_text())
    assert record["averaged_from"] == [130, 150] and record["cpu_hours"] == 0.5
    assert main(args) == 2  # the run folder exists: nothing overwritten
    assert "already holds a run" in capsys.readouterr().err
