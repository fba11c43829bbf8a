"""Training smoke test: a tiny config, a few steps, the loss goes down; resume works."""

from __future__ import annotations

import csv
import dataclasses

import numpy as np
import pytest
import torch

from doctrpp.errors import CliError
from doctrpp.export.checkpoint import load_model
from doctrpp.export.config import TINY
from doctrpp.files import save_npy_atomically
from doctrpp.runtime.imageio import write_image
from doctrpp.training.data import GeneratedCrops, StreamSampler, hsv_jitter, to_tensors
from doctrpp.training.loop import TrainSettings, train
from doctrpp.udir.sample import generate


def _losses(run) -> list[float]:
    with open(run / "log.csv") as f:
        return [float(row["loss_px"]) for row in csv.DictReader(f)]


def test_tiny_training_loss_goes_down_and_resumes(tmp_path):
    data = tmp_path / "data"
    for i in range(2):  # two fixed samples: the net can only get better at them
        sample = generate(i, "complete")
        write_image(data / f"{i:05d}.png", sample.image)
        save_npy_atomically(data / f"{i:05d}_map.npy", sample.backward_map)
    run = tmp_path / "run"
    settings = TrainSettings(
        out=run,
        config=TINY,
        steps=40,
        batch=2,
        max_lr=3e-3,
        warmup=0.1,
        workers=0,
        threads=2,
        validate_every=40,
        checkpoint_every=10,
        validation_size=3,
        data_folder=data,
        stop_at=30,
    )
    state = train(settings)
    assert state["step"] == 30
    losses = _losses(run)
    print(f"first 5 steps {np.mean(losses[:5]):.2f} px, last 5 {np.mean(losses[-5:]):.2f} px")
    assert np.mean(losses[-5:]) < 0.8 * np.mean(losses[:5])

    resumed = train(dataclasses.replace(settings, resume=run / "last.pth", stop_at=None))
    assert resumed["step"] == 40 and resumed["samples_seen"] == 80
    assert len(_losses(run)) == 40
    assert (run / "best.pth").is_file()
    assert (run / "validation.jsonl").read_text().count("\n") >= 2
    model = load_model(run / "last.pth")  # our checkpoints load like the authors'
    assert model.config == TINY


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


def test_restart_schedule_runs_a_new_cycle(tmp_path):
    data = tmp_path / "data"
    sample = generate(0, "none")
    write_image(data / "00000.png", sample.image)
    save_npy_atomically(data / "00000_map.npy", sample.backward_map)
    run = tmp_path / "run"
    settings = TrainSettings(
        out=run,
        config=TINY,
        steps=4,
        batch=1,
        workers=0,
        threads=2,
        validate_every=100,
        validation_size=3,
        data_folder=data,
    )
    assert train(settings)["step"] == 4
    again = dataclasses.replace(settings, steps=3, resume=run / "last.pth", restart_schedule=True)
    state = train(again)
    assert state["step"] == 7 and state["schedule_start"] == 4


def test_torchrun_ddp_on_cpu(tmp_path):
    """Two processes with the gloo backend: the same code path as several GPUs/nodes."""
    import subprocess
    import sys

    run = tmp_path / "ddp"
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "torch.distributed.run",
            "--nproc_per_node",
            "2",
            "--master_port",
            "29533",
            "-m",
            "doctrpp",
            "train",
            "--out",
            str(run),
            "--config",
            "tiny",
            "--steps",
            "2",
            "--batch",
            "1",
            "--workers",
            "0",
            "--threads",
            "1",
            "--validation-size",
            "3",
            "--validate-every",
            "2",
        ],
        capture_output=True,
        text=True,
        timeout=600,
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    state = torch.load(run / "last.pth", weights_only=True)["train_state"]
    assert state["step"] == 2 and state["samples_seen"] == 4  # 2 steps x 1 x 2 processes
    assert done.stdout.count("stopped at step 2") == 1  # rank 0 reports


def test_generated_crops_of_one_kind_for_a_curriculum():
    """`--kind complete` trains on complete-boundary crops only (what broke session 1's plateau)."""
    complete = GeneratedCrops(kind="complete", augment=False)
    mixed = GeneratedCrops(kind="mixed", augment=False)
    expected = generate(1, "complete")
    image, target = complete[1]
    assert torch.equal(target, to_tensors(expected.image, expected.backward_map)[1])
    assert not torch.equal(target, mixed[1][1])  # mixed index 1 is a partial crop


def test_publish_writes_fp16_default_with_record(tmp_path):
    import json

    from doctrpp.export.model import DocTrPP
    from doctrpp.files import sha256_of
    from doctrpp.training.publish import publish

    run = tmp_path / "run"
    run.mkdir()
    model = DocTrPP(TINY)
    state = {"step": 5, "samples_seen": 40, "cpu_seconds": 36.0, "wall_seconds": 20.0}
    ckpt = {"model": model.state_dict(), "config": dataclasses.asdict(TINY), "train_state": state}
    torch.save(ckpt, run / "best.pth")
    lines = [
        {"step": 0, "identity": True, "map_error_px/all": 48.0},
        {"step": 5, "samples_seen": 40, "map_error_px/all": 30.0},
    ]
    (run / "validation.jsonl").write_text("".join(json.dumps(r) + "\n" for r in lines))
    (run / "snapshots").mkdir()
    torch.save(ckpt, run / "snapshots" / "step0000005.pt")  # a snapshot publishes alike
    snapshot = publish(run / "snapshots" / "step0000005.pt", tmp_path / "from_snapshot", "test")
    assert json.loads(snapshot.with_suffix(".json").read_text())["run"] == "run"
    weights = publish(run / "best.pth", tmp_path / "weights", note="test")
    record = json.loads(weights.with_suffix(".json").read_text())
    assert record["sha256"] == sha256_of(weights)
    assert record["validation"] == {"map_error_px/all": 30.0}
    assert record["identity"] == {"map_error_px/all": 48.0}
    assert record["samples_seen"] == 40 and record["cpu_hours"] == 0.01
    stored = torch.load(weights, weights_only=True)["model"]
    assert all(v.dtype == torch.float16 for v in stored.values() if v.is_floating_point())
    loaded = load_model(weights)
    assert loaded.config == TINY
    x = torch.rand(1, 3, 288, 288)
    with torch.no_grad():
        worst = float((loaded(x) - model.eval()(x)).abs().max())
    print(f"fp16 storage vs fp32 weights (tiny, random): largest difference {worst:.3g} px")
    assert worst < 0.5


def test_publish_rescore_replaces_generated_scores_only(tmp_path):
    """After a generator change the published record is re-scored on the new validation set:
    generated scores replaced (the old ones kept), real-photo scores and weights untouched."""
    import json

    from doctrpp.export.model import DocTrPP
    from doctrpp.files import sha256_of
    from doctrpp.training.publish import publish, rescore

    run = tmp_path / "run"
    run.mkdir()
    state = {"step": 5, "samples_seen": 40, "cpu_seconds": 36.0, "wall_seconds": 20.0}
    ckpt = {"model": DocTrPP(TINY).state_dict(), "config": dataclasses.asdict(TINY)}
    torch.save({**ckpt, "train_state": state}, run / "best.pth")
    lines = [
        {"step": 0, "identity": True, "map_error_px/all": 48.0, "real/kept_share/none": 1.0},
        {"step": 5, "map_error_px/all": 1.0, "real/kept_share/none": 0.9},
    ]
    (run / "validation.jsonl").write_text("".join(json.dumps(r) + "\n" for r in lines))
    weights = publish(run / "best.pth", tmp_path / "weights", note="test")
    digest = sha256_of(weights)
    record = rescore(tmp_path / "weights", validation_size=3)
    assert json.loads(weights.with_suffix(".json").read_text()) == record
    assert sha256_of(weights) == digest == record["sha256"]
    assert record["validation"]["real/kept_share/none"] == 0.9
    assert record["validation"]["map_error_px/all"] > 1.0  # random weights, really scored
    assert set(record["identity"]) > {"map_error_px/complete", "map_error_px/all"}
    assert record["validation_before_rescore"]["validation"] == {"map_error_px/all": 1.0}
    with pytest.raises(CliError, match="no published default"):
        rescore(tmp_path / "nothing")


def test_complete_first_curriculum_switches_to_mixed():
    data = GeneratedCrops(kind="mixed", complete_until=6)
    kinds = [data.kind_of(i) for i in range(4, 10)]
    assert kinds == ["complete", "complete", "complete", "partial", "none", "complete"]


def test_sigterm_to_the_process_group_checkpoints_cleanly(tmp_path):
    """Ctrl-C or `kill -- -PGID` reaches the data workers too: they must leave stopping
    to the trainer, which writes last.pth and exits 0."""
    import os
    import signal
    import subprocess
    import sys
    import time

    run = tmp_path / "run"
    args = ["--out", str(run), "--config", "tiny", "--steps", "100000", "--batch", "1"]
    args += ["--workers", "1", "--threads", "1", "--validation-size", "3"]
    process = subprocess.Popen(
        [sys.executable, "-m", "doctrpp", "train", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=tmp_path,
        start_new_session=True,  # its own process group, like a shell job
    )
    deadline = time.time() + 300
    while time.time() < deadline and not (run / "log.csv").is_file():
        time.sleep(0.5)
    time.sleep(3)  # a few steps, workers running
    os.killpg(process.pid, signal.SIGTERM)
    out, err = process.communicate(timeout=300)
    assert process.returncode == 0, err[-2000:]
    assert "stopped at step" in out
    state = torch.load(run / "last.pth", weights_only=True)["train_state"]
    assert state["step"] >= 1


def test_an_error_in_the_trainer_exits_instead_of_hanging_on_its_workers(tmp_path):
    """Data workers ignore SIGTERM (above), so the trainer must stop them itself also when
    it fails: left to the interpreter's exit, they kept a crashed run alive for good."""
    import subprocess
    import sys

    script = (
        "import sys\n"
        "from pathlib import Path\n"
        "from doctrpp.export.config import TINY\n"
        "from doctrpp.training import runlog\n"
        "from doctrpp.training.loop import TrainSettings, train\n"
        "def fail(self, record):\n"
        "    if not record.get('identity'):\n"
        "        raise OSError('disk gone')\n"
        "runlog.RunLog.validation = fail\n"
        "train(TrainSettings(out=Path(sys.argv[1]), config=TINY, steps=4, batch=1, workers=1,\n"
        "                    threads=1, validate_every=2, validation_size=3))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script, str(tmp_path / "run")],
        capture_output=True,
        text=True,
        timeout=300,  # the hang this guards against lasted forever
    )
    assert done.returncode != 0
    assert "disk gone" in done.stderr


def quick_settings(out, **changes) -> TrainSettings:
    """A few steps of the tiny config on generated crops, validating at the end."""
    base = dict(
        out=out,
        config=TINY,
        steps=2,
        batch=2,
        workers=0,
        threads=2,
        validate_every=2,
        validation_size=3,
    )
    return TrainSettings(**{**base, **changes})


def test_spawned_workers_train_like_forked_ones(tmp_path):
    """Spawned workers (one OpenCV thread each; the default on CUDA) give the same batches:
    the parent has used OpenCV before they start, which is what deadlocked forked ones."""
    from doctrpp.training.processes import worker_start_method

    assert worker_start_method("auto", "cuda") == "spawn"
    assert worker_start_method("auto", "cpu") == "fork"
    with pytest.raises(ValueError, match="auto, fork or spawn"):
        worker_start_method("thread", "cpu")
    finals = []
    for start in ("fork", "spawn"):
        out = tmp_path / start
        state = train(quick_settings(out, workers=1, kind="complete", worker_start=start))
        assert state["step"] == 2
        finals.append(load_model(out / "last.pth").state_dict())
    for name, value in finals[0].items():
        assert torch.equal(value, finals[1][name]), name


def test_init_continues_from_weights_only_file(tmp_path):
    """--init: weights from a weights-only file, step/stream/hours carried on, a new cycle."""
    from doctrpp.training.loop import carried_state

    settings = quick_settings(
        tmp_path / "a", steps=4, validate_every=4, checkpoint_every=2, kind="complete"
    )
    train(settings)
    snapshot = tmp_path / "a" / "snapshots" / "step0000004.pt"
    assert snapshot.is_file()
    weights = torch.load(snapshot, weights_only=True)
    assert set(weights) == {"model", "config", "train_state"}
    carried = carried_state(weights)
    assert carried["step"] == 4 and carried["samples_seen"] == 8
    state = train(dataclasses.replace(settings, out=tmp_path / "b", init=snapshot, steps=2))
    assert state["step"] == 6 and state["samples_seen"] == 12
    assert state["cpu_seconds"] > carried["cpu_seconds"]
    assert state["data_cpu_seconds"] >= carried["data_cpu_seconds"] >= 0.0
    # the embedded default's record works as a starting point too
    record = {"training_record": {"step": 7, "samples_seen": 56, "cpu_hours": 1.0}}
    assert carried_state(record)["cpu_seconds"] == 3600.0


def test_real_photo_check_is_logged_with_validation(tmp_path):
    """--real-photos: reference-free scores per kind at each validation, identity first."""
    import json

    photos = tmp_path / "photos"
    for i in range(2):
        write_image(photos / f"p{i}.jpg", generate(i, "complete", size=400).image)
    train(quick_settings(tmp_path / "run", real_photos=photos, real_photos_count=2))
    records = [
        json.loads(x) for x in (tmp_path / "run" / "validation.jsonl").read_text().splitlines()
    ]
    assert records[0]["identity"] and records[0]["real/black_share/none"] == 0.0
    for kind in ("complete", "partial", "none"):
        assert 0 <= records[-1][f"real/black_share/{kind}"] <= 1
        assert f"real/straightness_ratio/{kind}" in records[-1]


def test_device_choice(tmp_path, capsys):
    """--device cpu trains on the CPU (CI's path); --device cuda without a GPU is a clear error."""
    from doctrpp.cli import main
    from doctrpp.training.processes import default_workers

    assert default_workers("cpu") == 1 and default_workers("cuda", world=1) >= 1
    state = train(quick_settings(tmp_path / "cpu", device="cpu", steps=1, validate_every=1))
    assert state["step"] == 1
    if not torch.cuda.is_available():
        code = main(
            ["train", "--out", str(tmp_path / "gpu"), "--config", "tiny", "--device", "cuda"]
        )
        assert code == 2 and "no CUDA GPU" in capsys.readouterr().err


def test_bf16_autocast_only_where_native_unless_asked(tmp_path, capsys):
    """Emulated bf16 made a CPU step 6.6x slower: the default follows the hardware, and the
    run says which precision it chose; --bf16 / --no-bf16 override it."""
    from doctrpp.training.processes import bf16_is_native

    native = bf16_is_native(torch.device("cpu"))
    assert isinstance(native, bool)
    train(quick_settings(tmp_path / "auto", device="cpu", steps=1, validate_every=1))
    expected = "bf16 autocast" if native else "fp32"
    assert f"precision: {expected}" in capsys.readouterr().out
    train(quick_settings(tmp_path / "forced", device="cpu", steps=1, validate_every=1, bf16=True))
    assert "precision:" not in capsys.readouterr().out


def test_data_workers_cpu_time_is_counted():
    """Generation runs in worker processes: their CPU time is what children_cpu_seconds adds."""
    import subprocess
    import sys

    from doctrpp.training.processes import children_cpu_seconds

    before = children_cpu_seconds()
    busy = "import time\nt = time.process_time()\nwhile time.process_time() - t < 0.3: pass"
    subprocess.run([sys.executable, "-c", busy], check=True)
    assert children_cpu_seconds() - before >= 0.25


def test_throughput_tool_measures_a_step():
    """`python -m doctrpp.training.throughput`: CPU seconds per step, ratios to the first."""
    from doctrpp.training.throughput import measure

    rows = measure(["tiny"], ["fp32", "bf16"], batch=1, rounds=1)
    assert [r["variant"] for r in rows] == ["fp32", "bf16"]
    assert all(r["cpu_s_per_step"] > 0 for r in rows) and rows[0]["vs_first"] == 1.0


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


def test_sample_reuse_counts_generated_crops(tmp_path):
    state = train(
        quick_settings(tmp_path / "r", steps=4, validate_every=4, kind="complete", sample_reuse=2)
    )
    assert state["samples_seen"] == 8 and state["generated_samples"] == 4


def test_gradient_loss_ignores_placement_and_weighs_local_shape():
    from doctrpp.training.losses import map_gradient_l1, map_l1, map_loss

    target = torch.randn(2, 2, 32, 32)
    shifted = target + 3.0  # the whole page moved: plain L1 sees it, the gradient term not
    assert float(map_gradient_l1(shifted, target)) == pytest.approx(0.0, abs=1e-6)
    assert float(map_l1(shifted, target)) == pytest.approx(3.0)
    bent = target.clone()
    bent[:, :, 16:, :] += 1.0  # a fold: a step across the map
    assert float(map_gradient_l1(bent, target)) > 0
    assert torch.equal(map_loss(bent, target, 0.0), map_l1(bent, target))
    both = map_loss(bent, target, 2.0)
    expected = map_l1(bent, target) + 2.0 * map_gradient_l1(bent, target)
    assert torch.allclose(both, expected)


def test_photometric_loss_is_zero_on_the_true_map_and_pulls_a_shifted_one_back():
    from doctrpp.training.losses import map_l1, map_loss, rectified_image_l1

    sample = generate(3, "complete")
    images, target = (t[None] for t in to_tensors(sample.image, sample.backward_map))
    assert float(rectified_image_l1(images, target, target)) == pytest.approx(0.0, abs=1e-7)
    shifted = (target + torch.tensor([2.0, 0.0]).view(1, 2, 1, 1)).requires_grad_(True)
    loss = rectified_image_l1(images, shifted, target)
    assert float(loss.detach()) > 1e-3
    (gradient,) = torch.autograd.grad(loss, shifted)
    # descending the gradient moves x back toward the true map
    assert float(gradient[:, 0].sum()) > 0 and abs(float(gradient[:, 1].sum())) < float(
        gradient[:, 0].sum()
    )
    both = map_loss(shifted, target, 0.0, images, 5.0)
    assert torch.allclose(both, map_l1(shifted, target) + 5.0 * loss)
    with pytest.raises(ValueError, match="need the input images"):
        map_loss(shifted, target, 0.0, None, 5.0)


def test_ms_ssim_loss_is_zero_on_the_true_map_and_grows_with_a_shift():
    from doctrpp.training.losses import map_l1, map_loss, rectified_image_ms_ssim

    sample = generate(3, "complete")
    images, target = (t[None] for t in to_tensors(sample.image, sample.backward_map))
    assert float(rectified_image_ms_ssim(images, target, target)) == pytest.approx(0.0, abs=1e-5)
    losses = []
    for shift in (1.0, 3.0):
        shifted = (target + torch.tensor([shift, 0.0]).view(1, 2, 1, 1)).requires_grad_(True)
        loss = rectified_image_ms_ssim(images, shifted, target)
        (gradient,) = torch.autograd.grad(loss, shifted)
        assert torch.isfinite(gradient).all() and float(gradient.abs().sum()) > 0
        losses.append(float(loss.detach()))
    print(f"1 - MS-SSIM at 1 px / 3 px shift: {losses[0]:.4f} / {losses[1]:.4f}")
    assert 1e-3 < losses[0] < losses[1] < 1.0
    both = map_loss(shifted, target, 0.0, images, 0.0, 2.0)
    assert torch.allclose(both, map_l1(shifted, target) + 2.0 * loss)
    with pytest.raises(ValueError, match="need the input images"):
        map_loss(shifted, target, 0.0, None, 0.0, 2.0)


def test_loss_terms_train_and_the_cli_rejects_negative_weights(tmp_path, capsys):
    from doctrpp.cli import main

    settings = quick_settings(
        tmp_path / "g", kind="complete", gradient_loss=1.0, photometric_loss=10.0, ms_ssim_loss=2.0
    )
    state = train(settings)
    assert state["step"] == 2
    for flag in ("--gradient-loss", "--photometric-loss", "--ms-ssim-loss"):
        code = main(["train", "--out", str(tmp_path / "r"), "--config", "tiny", flag, "-1"])
        assert code == 2
        assert f"{flag} must be >= 0" in capsys.readouterr().err
    code = main(["train", "--out", str(tmp_path / "r"), "--real-photos-count", "0"])
    assert code == 2
    assert "--real-photos-count must be >= 1" in capsys.readouterr().err
    snapshot = sorted((tmp_path / "g" / "snapshots").glob("step*.pt"))[-1]
    code = main(["train", "--out", str(tmp_path / "s"), "--resume", str(snapshot)])
    assert code == 2  # a weights-only snapshot has no optimiser: one line naming --init
    err = capsys.readouterr().err.strip()
    assert "no optimizer, scheduler" in err and "--init" in err and len(err.splitlines()) == 1


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
