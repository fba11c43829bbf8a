"""The generated training stream: determinism, sharding, jitter, kinds, the curriculum,
sample reuse, and flip-averaged predictions as scoring makes them."""

from __future__ import annotations

import dataclasses

import numpy as np
import torch

from doctrpp.training.data import GeneratedCrops, StreamSampler, hsv_jitter, to_tensors
from doctrpp.udir.sample import generate


def test_generated_stream_is_deterministic_and_sharded():
    dataset = GeneratedCrops(augment=True)
    image, target = dataset[4]
    again, _ = dataset[4]
    assert image.shape == (3, 288, 288) and target.shape == (2, 288, 288)
    assert torch.equal(image, again)
    assert float(image.min()) >= 0 and float(image.max()) <= 1
    ranks = [list(zip(range(3), StreamSampler(10, rank, 2), strict=False)) for rank in (0, 1)]
    assert [i for _, i in ranks[0]] == [10, 12, 14] and [i for _, i in ranks[1]] == [11, 13, 15]


def test_hsv_jitter_keeps_shape():
    image = generate(1, "none").image
    out = hsv_jitter(image, np.random.default_rng(0))
    assert out.shape == image.shape and out.dtype == np.uint8
    assert not np.array_equal(out, image)


def test_generated_crops_of_one_kind_for_a_curriculum():
    """`--kind complete` trains on complete-boundary crops only (what broke session 1's plateau)."""
    complete = GeneratedCrops(kind="complete", augment=False)
    mixed = GeneratedCrops(kind="mixed", augment=False)
    expected = generate(1, "complete")
    image, target = complete[1]
    assert torch.equal(target, to_tensors(expected.image, expected.backward_map)[1])
    assert not torch.equal(target, mixed[1][1])  # mixed index 1 is a partial crop


def test_complete_first_curriculum_switches_to_mixed():
    data = GeneratedCrops(kind="mixed", complete_until=6)
    kinds = [data.kind_of(i) for i in range(4, 10)]
    assert kinds == ["complete", "complete", "complete", "partial", "none", "complete"]


def test_sample_reuse_shows_each_crop_k_times_from_the_cache(monkeypatch):
    """--sample-reuse K: windows of distinct crops, each shown K times (fresh jitter),
    generated once per data worker; K = 1 is the plain stream."""
    from doctrpp.training import data

    assert [data.generated_index(p, 2, 4) for p in range(12)] == [
        0, 1, 2, 3, 0, 1, 2, 3, 8, 9, 10, 11,
    ]  # fmt: skip
    assert [data.generated_index(p, 1, 4) for p in range(6)] == list(range(6))
    assert data.reuse_window(8, 1) == 256 and data.reuse_window(12, 15, 2) == 360
    calls = []
    real_generate = data.generate
    monkeypatch.setattr(data, "generate", lambda *a, **k: calls.append(a) or real_generate(*a, **k))
    reused = GeneratedCrops(sample_reuse=2, window=2, page_reuse=4)
    first, target = reused[0]
    repeat, repeat_target = reused[2]
    assert len(calls) == 1  # the repeat came from the cache
    assert torch.equal(target, repeat_target) and not torch.equal(first, repeat)
    plain_image, plain_target = GeneratedCrops(page_reuse=4)[0]
    assert torch.equal(plain_target, target) and torch.equal(plain_image, first)
    assert reused.kind_of(data.generated_index(2, 2, 2)) == "complete"


def test_flip_averaged_predictions_match_the_runtimes_definition(tiny_model):
    """Scoring and sheets flip-average as `rectify` does: mean of the map and the
    unmirrored map of the mirrored input."""
    from doctrpp.runtime.processing import flip_averaged_map
    from doctrpp.training.realcheck import RealItem, predict
    from doctrpp.training.validate import ValidationItem, predict_maps

    model = tiny_model
    images = [generate(i, "complete").image for i in range(2)]
    items = [ValidationItem("complete", im, np.zeros((288, 288, 2), np.float32)) for im in images]
    mirrored = [dataclasses.replace(it, image=_mirrored(it.image)) for it in items]
    averaged = predict_maps(model, items, flip_average=True)
    one_run = zip(predict_maps(model, items), predict_maps(model, mirrored), strict=True)
    for got, (one, other) in zip(averaged, one_run, strict=True):
        assert np.abs(got - flip_averaged_map(one, other)).max() < 1e-5
    real = [RealItem("p", "complete", im, {}) for im in images]
    real_mirrored = [dataclasses.replace(it, image=_mirrored(it.image)) for it in real]
    one_run = zip(predict(model, real), predict(model, real_mirrored), strict=True)
    for got, (one, other) in zip(predict(model, real, flip_average=True), one_run, strict=True):
        assert np.abs(got - flip_averaged_map(one, other)).max() < 1e-5


def _mirrored(image: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(image[:, ::-1])
