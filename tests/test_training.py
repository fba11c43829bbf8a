"""Training smoke tests: a tiny config, a few steps, the loss goes down; resume, restart,
--init, DDP, signals, devices, precision and the trainer's options work."""

from __future__ import annotations

import csv
import dataclasses
import os

import numpy as np
import pytest
import torch

from doctrpp.export.checkpoint import load_model
from doctrpp.export.config import TINY
from doctrpp.files import save_npy_atomically
from doctrpp.runtime.imageio import write_image
from doctrpp.training.loop import TrainSettings, time_limit_warning, train
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


def test_sigterm_to_the_process_group_checkpoints_cleanly(tmp_path):
    """Ctrl-C or `kill -- -PGID` reaches the data workers too: they must leave stopping
    to the trainer, which writes last.pth and exits 0."""
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
    assert "stop requested" in out and "stopped at step" in out
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
    """--real-photos: reference-free scores per kind at each validation, identity first;
    --cross-shot-pairs adds the two shots' agreement."""
    import json

    photos = tmp_path / "photos"
    for i in range(2):
        for shot in (1, 2):
            page = generate(2 * i + shot, "complete", size=400).image
            write_image(photos / f"{i}_{shot}.jpg", page)
    settings = quick_settings(tmp_path / "run", real_photos=photos, real_photos_count=2)
    train(dataclasses.replace(settings, cross_shot_pairs=2))
    records = [
        json.loads(x) for x in (tmp_path / "run" / "validation.jsonl").read_text().splitlines()
    ]
    assert records[0]["identity"] and records[0]["real/black_share/none"] == 0.0
    for kind in ("complete", "partial", "none"):
        assert 0 <= records[-1][f"real/black_share/{kind}"] <= 1
        assert f"real/straightness_ratio/{kind}" in records[-1]
    for record in (records[0], records[-1]):
        assert 0 < record["real/cross_shot_ms_ssim"] < 1
        assert record["real/cross_shot_local_distortion"] >= 0


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


def test_sample_reuse_counts_generated_crops(tmp_path):
    state = train(
        quick_settings(tmp_path / "r", steps=4, validate_every=4, kind="complete", sample_reuse=2)
    )
    assert state["samples_seen"] == 8 and state["generated_samples"] == 4


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
    code = main(["train", "--out", str(tmp_path / "r"), "--cross-shot-pairs", "4"])
    assert code == 2
    assert "--cross-shot-pairs needs --real-photos" in capsys.readouterr().err
    photos = tmp_path / "single_shots"
    photos.mkdir()
    write_image(photos / "a.png", np.zeros((8, 8, 3), np.uint8))
    args = ["--real-photos", str(photos), "--cross-shot-pairs", "4"]
    assert main(["train", "--out", str(tmp_path / "r"), *args]) == 2
    assert "has no <doc>_1/<doc>_2 photos" in capsys.readouterr().err
    snapshot = sorted((tmp_path / "g" / "snapshots").glob("step*.pt"))[-1]
    code = main(["train", "--out", str(tmp_path / "s"), "--resume", str(snapshot)])
    assert code == 2  # a weights-only snapshot has no optimiser: one line naming --init
    err = capsys.readouterr().err.strip()
    assert "no optimizer, scheduler" in err and "--init" in err and len(err.splitlines()) == 1


def test_a_second_trainer_on_a_busy_run_folder_gets_one_line(tmp_path, capsys):
    from doctrpp.cli import main
    from doctrpp.training.runlog import run_folder_lock

    out = tmp_path / "busy"
    with run_folder_lock(out):  # as a running (or still stopping) trainer holds it
        code = main(["train", "--out", str(out), "--config", "tiny", "--steps", "1"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "in use by another training process" in err
    assert f"pid {os.getpid()}" in err and len(err.splitlines()) == 1
    with run_folder_lock(out):  # released on exit: the folder is free again
        pass


def test_a_cycle_longer_than_max_minutes_is_warned_about():
    # 7.7 s a step, 3 minutes gone, at step 30 of 1100: the 109 minutes left fit 849 steps.
    warning = time_limit_warning(7.7, 180.0, 30, 1100, 112)
    assert warning and "near step 879 of 1100" in warning and "lower --steps" in warning
    assert time_limit_warning(5.0, 180.0, 30, 1100, 112) is None  # 1070 steps in 5,540 s
