"""`python -m doctrpp.training.score`: fresh validation crops and the paired comparison."""

from __future__ import annotations

import json

import numpy as np
import pytest

from doctrpp.benchmarks.metrics import paired_difference
from doctrpp.training.validate import (
    load_validation_set,
    save_validation_set,
    validation_set,
)


def test_a_later_start_continues_the_same_validation_stream():
    first_three = validation_set(3)
    from_second = validation_set(2, start=1)
    for a, b in zip(first_three[1:], from_second, strict=True):
        assert a.kind == b.kind
        assert np.array_equal(a.image, b.image)
        assert np.array_equal(a.backward_map, b.backward_map)
    with pytest.raises(ValueError, match="validation crops"):
        validation_set(2, start=-1)


def test_a_frozen_validation_set_loads_back_unchanged(tmp_path):
    items = validation_set(3, start=5)
    path = tmp_path / "frozen.npz"
    save_validation_set(items, path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["frozen.npz"]  # no partial left
    for a, b in zip(items, load_validation_set(path), strict=True):
        assert a.kind == b.kind
        assert np.array_equal(a.image, b.image)
        assert np.array_equal(a.backward_map, b.backward_map)


def test_paired_difference_is_the_mean_per_crop_difference_with_its_standard_error():
    kinds = ["complete", "none", "complete", "none"]
    reference = [10.0, 20.0, 12.0, 22.0]
    candidate = [9.0, 21.0, 10.0, 22.0]  # complete: -1, -2; none: +1, 0
    pairs = paired_difference(kinds, reference, candidate)
    assert list(pairs) == ["complete", "none", "all"]
    assert pairs["complete"] == pytest.approx((-1.5, 0.5))
    assert pairs["none"] == pytest.approx((0.5, 0.5))
    mean, error = pairs["all"]
    assert mean == pytest.approx(-0.5)
    assert error == pytest.approx(np.std([-1, 1, -2, 0], ddof=1) / 2)


def test_score_compares_each_file_with_the_first_on_fresh_crops(tiny_checkpoint, capsys):
    from doctrpp.training.score import main as score

    args = [str(tiny_checkpoint), str(tiny_checkpoint), "--validation-start", "48"]
    assert score([*args, "--validation-size", "3"]) == 0
    lines = [json.loads(line) for line in capsys.readouterr().out.strip().splitlines()]
    assert [line["weights"] for line in lines[:3]] == ["identity", *args[:2]]
    paired = lines[3]
    assert paired["paired_against"] == str(tiny_checkpoint)
    for metric in ("map_error_px", "ms_ssim", "local_distortion"):  # a file against itself
        assert paired[f"paired_{metric}/all"] == [0.0, 0.0]
    assert len(lines) == 4


def test_score_freezes_its_crops_once_and_reuses_them(tiny_checkpoint, tmp_path, capsys):
    from doctrpp.training.score import main as score

    frozen = tmp_path / "v.npz"
    args = [str(tiny_checkpoint), "--validation-size", "2", "--frozen-validation", str(frozen)]
    assert score(args) == 0
    first = capsys.readouterr().out
    assert frozen.is_file()
    # A different start or size no longer matters: the frozen crops are the yardstick.
    assert score([*args, "--validation-start", "48"]) == 0
    assert capsys.readouterr().out == first


def test_score_refuses_bad_arguments_in_one_line(tmp_path, capsys):
    from doctrpp.training.score import main as score

    with pytest.raises(SystemExit) as exit_info:
        score([str(tmp_path / "missing.pt")])
    assert exit_info.value.code == 2
    assert "no such weights file" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        score([str(tmp_path / "missing.pt"), "--validation-start", "-1"])
    assert "--validation-start" in capsys.readouterr().err


def test_score_cache_reuses_a_files_results_only_for_the_same_setting(
    tiny_checkpoint, tmp_path, capsys, monkeypatch
):
    from doctrpp.training import score as score_module

    cache = tmp_path / "cache"
    args = [str(tiny_checkpoint), "--validation-size", "2", "--cache", str(cache)]
    assert score_module.main(args) == 0
    first = capsys.readouterr().out
    assert len(list(cache.glob("*.json"))) == 2  # the identity map and the file
    computed = []
    real_score_file = score_module.score_file
    monkeypatch.setattr(
        score_module,
        "score_file",
        lambda *a, **k: computed.append(a[0]) or real_score_file(*a, **k),
    )
    assert score_module.main(args) == 0
    assert capsys.readouterr().out == first and computed == []  # all from the cache
    assert score_module.main([*args, "--flip-average"]) == 0  # another setting: scored
    assert computed == [None, tiny_checkpoint]
    other = tmp_path / "other.pt"
    other.write_bytes(tiny_checkpoint.read_bytes())  # the same weights under another name
    assert score_module.main([str(other), *args[1:]]) == 0
    lines = [json.loads(line) for line in capsys.readouterr().out.strip().splitlines()]
    assert lines[-1]["weights"] == str(other) and len(computed) == 2
