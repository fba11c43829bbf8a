"""The training loop: L1 on the backward map (optionally on its local differences too), AdamW,
OneCycle; resumable; DDP-aware."""

from __future__ import annotations

import dataclasses
import json
import signal
import time
from dataclasses import dataclass
from pathlib import Path

import torch
from torch.utils.data import DataLoader

from doctrpp.benchmarks.cross_shot import shot_pairs
from doctrpp.export.config import ModelConfig
from doctrpp.export.model import DocTrPP

from .checkpoints import RESUME_KEYS, read_training_checkpoint, save_checkpoint
from .cross_shot import model_check as cross_shot_check
from .data import FolderCrops, GeneratedCrops, StreamSampler, reuse_window
from .losses import map_loss
from .processes import (
    Distributed,
    bf16_is_native,
    children_cpu_seconds,
    default_workers,
    leave_stopping_to_the_trainer,
    spawned_worker_setup,
    stop_workers,
    worker_start_method,
)
from .realcheck import real_photo_set, validation_scores
from .runlog import RunLog
from .validate import validation_set


@dataclass(frozen=True)
class TrainSettings:
    out: Path
    config: ModelConfig
    steps: int = 100_000  # length of the OneCycle schedule
    batch: int = 12  # per process
    max_lr: float = 1e-4
    warmup: float = 0.1
    weight_decay: float = 1e-4
    bf16: bool | None = None  # autocast; None: where the hardware computes bf16 natively
    workers: int | None = None  # data processes; None: 1 on CPU, the free cores beside a GPU
    device: str = "auto"  # auto (CUDA when available) | cuda | cpu
    threads: int | None = None
    validate_every: int = 200
    checkpoint_every: int = 50
    validation_size: int = 48
    data_folder: Path | None = None
    kind: str = "mixed"  # generated crops: mixed thirds, or only complete/partial/none
    complete_first: int = 0  # curriculum: this many steps of complete crops before `kind`
    max_minutes: float | None = None  # stop cleanly (with a checkpoint) after this long
    stop_at: int | None = None  # stop after this step (the schedule still spans `steps`)
    resume: Path | None = None
    restart_schedule: bool = False  # on resume: keep weights/optimiser, start a new lr cycle
    init: Path | None = None  # weights-only start (default .pt or committed checkpoint), new cycle
    seed: int = 0
    page_reuse: int = 4  # generated crops share a page this many at a time
    sample_reuse: int = 1  # each generated crop is shown this many times (fresh jitter)
    real_photos: Path | None = None  # real photos for the reference-free check at validation
    real_photos_count: int = 16  # photos used (each as a complete, partial and none crop)
    cross_shot_pairs: int = 0  # documents of real_photos whose two shots are compared
    gradient_loss: float = 0.0  # weight of L1 on the maps' 8-px differences (0: the paper's loss)
    photometric_loss: float = 0.0  # weight of L1 between crops rectified by predicted/true maps
    ms_ssim_loss: float = 0.0  # weight of 1 - MS-SSIM between those two rectified crops
    worker_start: str = "auto"  # fork | spawn | auto (spawn on CUDA, where workers are many)
    snapshots: bool = True  # keep a weights-only snapshot at each validation (to choose from)


def carried_state(weights: dict) -> dict:
    """Step, stream position and hours carried by a weights-only file, so totals accumulate
    and the generated stream continues where that training stopped (no repeated samples)."""
    if "train_state" in weights:
        source = weights["train_state"]
        keys = (
            "step",
            "samples_seen",
            "generated_samples",
            "wall_seconds",
            "cpu_seconds",
            "data_cpu_seconds",
        )
        return {k: source[k] for k in keys if k in source}
    record = weights.get("training_record", {})
    return {
        "step": int(record.get("step", 0)),
        "samples_seen": int(record.get("samples_seen", 0)),
        "wall_seconds": 3600.0 * record.get("wall_hours", 0.0),
        "cpu_seconds": 3600.0 * record.get("cpu_hours", 0.0),
        "data_cpu_seconds": 3600.0 * record.get("data_cpu_hours", 0.0),
    }


# Steps the pace is measured over before the run says whether its cycle fits --max-minutes
# (the first few steps include start-up and the data workers' warm-up).
PACE_FROM_STEP, PACE_TO_STEP = 10, 30


def time_limit_warning(
    seconds_per_step: float, elapsed_s: float, step: int, last_step: int, max_minutes: float
) -> str | None:
    """A warning when, at `seconds_per_step`, --max-minutes stops the run before `last_step`:
    such a run ends mid-cycle, its lr still above the cycle's end (a slower machine than the
    one a command was written on, e.g. one without native bf16, is the usual cause)."""
    steps_that_fit = int(max(60 * max_minutes - elapsed_s, 0) / max(seconds_per_step, 1e-9))
    if step + steps_that_fit >= last_step:
        return None
    return (
        f"warning: at {seconds_per_step:.1f} s a step --max-minutes {max_minutes:g} stops "
        f"this run near step {step + steps_that_fit} of {last_step}, its lr cycle unfinished "
        f"(validations not counted); lower --steps or raise --max-minutes"
    )


def _schedule(optimiser, s: TrainSettings):
    return torch.optim.lr_scheduler.OneCycleLR(
        # +1: the scheduler counts its construction as a step; s.steps updates follow.
        optimiser,
        max_lr=s.max_lr,
        total_steps=s.steps + 1,
        pct_start=s.warmup,
        anneal_strategy="linear",
    )


def train(s: TrainSettings) -> dict:
    env = Distributed(s.device)
    if s.workers is None:
        s = dataclasses.replace(s, workers=default_workers(env.device.type, env.world))
    if s.threads:
        torch.set_num_threads(s.threads)
    if s.bf16 is None:
        s = dataclasses.replace(s, bf16=bf16_is_native(env.device))
        if env.main:
            print(
                "precision: bf16 autocast (native here)"
                if s.bf16
                else "precision: fp32 (this device has no native bf16; --bf16 forces it)",
                flush=True,
            )
    torch.manual_seed(s.seed)
    s.out.mkdir(parents=True, exist_ok=True)
    model = DocTrPP(s.config).to(env.device).train()
    optimiser = torch.optim.AdamW(model.parameters(), lr=s.max_lr, weight_decay=s.weight_decay)
    schedule = _schedule(optimiser, s)
    state = {
        "step": 0,
        "samples_seen": 0,
        "wall_seconds": 0.0,
        "cpu_seconds": 0.0,
        "best_map_error_px": float("inf"),
    }
    if s.resume:
        ckpt = read_training_checkpoint(s.resume, RESUME_KEYS)
        model.load_state_dict(ckpt["model"])
        optimiser.load_state_dict(ckpt["optimizer"])
        state.update(ckpt["train_state"])
        if s.restart_schedule:  # a fresh cycle (and --lr) from the current step
            state["schedule_start"] = state["step"]
            schedule = _schedule(optimiser, s)
        else:
            schedule.load_state_dict(ckpt["scheduler"])
    elif s.init:
        weights = read_training_checkpoint(s.init, ("model",))
        model.load_state_dict({k: v.float() for k, v in weights["model"].items()})
        state.update(carried_state(weights))
        state["schedule_start"] = state["step"]  # a fresh optimiser and lr cycle from here
    # Distinct crops trained on (runs before sample reuse existed showed each once).
    state.setdefault("generated_samples", state["samples_seen"])
    net = model
    if env.world > 1:
        net = torch.nn.parallel.DistributedDataParallel(
            model, device_ids=[env.local_rank] if env.device.type == "cuda" else None
        )

    if s.data_folder:
        dataset = FolderCrops(s.data_folder)
    else:
        complete_until = s.complete_first * s.batch * env.world  # sample index
        dataset = GeneratedCrops(
            s.seed * 10**9,
            kind=s.kind,
            complete_until=complete_until,
            page_reuse=s.page_reuse,
            sample_reuse=s.sample_reuse,
            window=reuse_window(s.batch, s.workers, env.world),
        )
    per_step = s.batch * env.world
    # With sample reuse the workers run a window ahead: while the trainer takes the cheap
    # repeats, they generate the next fresh window (with 2 batches ahead they sat idle).
    ahead = 2 if s.sample_reuse <= 1 or s.data_folder else max(2, dataset.window // s.batch)
    start = worker_start_method(s.worker_start, env.device.type)
    loader = DataLoader(
        dataset,
        batch_size=s.batch,
        sampler=StreamSampler(state["samples_seen"], env.rank, env.world),
        num_workers=s.workers,
        worker_init_fn=(spawned_worker_setup if start == "spawn" else leave_stopping_to_the_trainer)
        if s.workers
        else None,
        multiprocessing_context=start if s.workers else None,
        persistent_workers=s.workers > 0,
        prefetch_factor=ahead if s.workers else None,
    )
    validation = validation_set(s.validation_size) if env.main else []
    real_items = []
    if env.main and s.real_photos:
        real_items = real_photo_set(s.real_photos, s.real_photos_count)
    shot_pairs_checked = []
    if env.main and s.real_photos and s.cross_shot_pairs:
        shot_pairs_checked = shot_pairs(s.real_photos)[: s.cross_shot_pairs]
    log = RunLog(s.out) if env.main else None
    if env.main and not (s.out / "validation.jsonl").exists():
        baseline = validation_scores(None, validation, real_items)
        if shot_pairs_checked:
            baseline.update(cross_shot_check(None, shot_pairs_checked))
        log.validation({"step": 0, "identity": True, **baseline})
        print("identity baseline:", json.dumps({k: round(v, 3) for k, v in baseline.items()}))

    stop = {"now": False}

    def request_stop(*_) -> None:  # SIGTERM/Ctrl-C: finish the step, checkpoint, exit
        if env.main and not stop["now"]:
            print(
                "stop requested: finishing this step, then last.pth and (unless this step "
                "validated) a last validation",
                flush=True,
            )
        stop["now"] = True

    previous_handlers = {
        sig: signal.signal(sig, request_stop) for sig in (signal.SIGTERM, signal.SIGINT)
    }
    autocast_dtype = torch.bfloat16 if s.bf16 else None
    started, cpu_started = time.time(), time.process_time()
    data_started = children_cpu_seconds()
    wall_before, cpu_before = state["wall_seconds"], state["cpu_seconds"]
    data_before = state.get("data_cpu_seconds", 0.0)

    def payload() -> dict:
        state["wall_seconds"] = wall_before + time.time() - started
        state["cpu_seconds"] = cpu_before + time.process_time() - cpu_started
        # Data workers' time; with --workers 0 generation is already in cpu_seconds.
        state["data_cpu_seconds"] = data_before + children_cpu_seconds() - data_started
        return {
            "model": model.state_dict(),
            "config": dataclasses.asdict(s.config),
            "optimizer": optimiser.state_dict(),
            "scheduler": schedule.state_dict(),
            "train_state": dict(state),
        }

    def weights_only() -> dict:
        """What `--init` and publishing need: weights, config and the training state."""
        full = payload()
        return {
            "model": full["model"],
            "config": full["config"],
            "train_state": full["train_state"],
        }

    def run_validation() -> None:
        scores = validation_scores(model, validation, real_items, autocast_dtype=autocast_dtype)
        if shot_pairs_checked:
            scores.update(cross_shot_check(model, shot_pairs_checked))
        record = {
            "step": state["step"],
            "samples_seen": state["samples_seen"],
            "generated_samples": int(state["generated_samples"]),
            "cpu_hours": state["cpu_seconds"] / 3600,
            "data_cpu_hours": state.get("data_cpu_seconds", 0.0) / 3600,
            **scores,
        }
        log.validation(record)
        print(
            f"step {state['step']}: validation",
            json.dumps({k: round(v, 3) for k, v in scores.items()}),
            flush=True,
        )
        if s.snapshots:
            save_checkpoint(s.out / "snapshots" / f"step{state['step']:07d}.pt", weights_only())
        if scores["map_error_px/all"] < state["best_map_error_px"]:
            state["best_map_error_px"] = scores["map_error_px/all"]
            save_checkpoint(s.out / "best.pth", payload())

    last_time = pace_started = time.time()
    first_step = state["step"]
    batches = iter(loader)
    try:
        schedule_end = state.get("schedule_start", 0) + s.steps
        last_step = min(schedule_end, s.stop_at or schedule_end)
        while state["step"] < last_step and not stop["now"]:
            images, targets = next(batches)
            images, targets = images.to(env.device), targets.to(env.device)
            with torch.autocast(env.device.type, dtype=torch.bfloat16, enabled=s.bf16):
                predicted = net(images)
            loss = map_loss(
                predicted.float(),
                targets,
                s.gradient_loss,
                images.float(),
                s.photometric_loss,
                s.ms_ssim_loss,
            )
            optimiser.zero_grad(set_to_none=True)
            loss.backward()
            optimiser.step()
            schedule.step()
            state["step"] += 1
            state["samples_seen"] += per_step
            state["generated_samples"] += per_step / (1 if s.data_folder else s.sample_reuse)
            if env.main:
                now = time.time()
                log.step(
                    state["step"],
                    loss.item(),
                    schedule.get_last_lr()[0],
                    per_step / max(now - last_time, 1e-9),
                    now - started,
                )
                last_time = now
                done = state["step"] - first_step
                if done == PACE_FROM_STEP:
                    pace_started = now
                if done == PACE_TO_STEP and s.max_minutes:
                    warning = time_limit_warning(
                        (now - pace_started) / (PACE_TO_STEP - PACE_FROM_STEP),
                        now - started,
                        state["step"],
                        last_step,
                        s.max_minutes,
                    )
                    if warning:
                        print(warning, flush=True)
                if state["step"] % 10 == 0 or state["step"] == 1:
                    elapsed = now - started
                    eta = elapsed / max(done, 1) * (last_step - state["step"])
                    print(
                        f"step {state['step']}/{last_step} loss {loss.item():.3f} px "
                        f"lr {schedule.get_last_lr()[0]:.2e} {done * per_step / elapsed:.2f} "
                        f"samples/s eta {eta / 60:.0f} min",
                        flush=True,
                    )
                if state["step"] % s.checkpoint_every == 0:
                    save_checkpoint(s.out / "last.pth", payload())
                if state["step"] % s.validate_every == 0:
                    run_validation()
            if s.max_minutes and time.time() - started > 60 * s.max_minutes:
                stop["now"] = True
        if env.main:
            save_checkpoint(s.out / "last.pth", payload())
            if state["step"] % s.validate_every:
                run_validation()
    finally:  # also on an error: a worker left running would keep the process alive
        stop_workers(batches)
        for sig, handler in previous_handlers.items():
            signal.signal(sig, handler)
    env.close()
    return dict(state)
