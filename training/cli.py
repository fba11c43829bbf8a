"""`doctrpp train`: train DocTr++ weights on generated UDIR-style crops."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from doctrpp.errors import CliError, require
from doctrpp.udir.scene import KINDS


def add_parser(commands: argparse._SubParsersAction) -> None:
    p = commands.add_parser(
        "train",
        help="train weights on generated crops (CPU or GPUs; torchrun for several)",
        description="Train the DocTr++ network with the paper's recipe (L1 on the backward map, "
        "AdamW, OneCycle max lr 1e-4 with 10% warm-up, HSV jitter) on UDIR-style crops "
        "generated on the fly. Checkpoints RUN_DIR/last.pth and best.pth; logs log.csv and "
        "validation.jsonl. Several GPUs/nodes: torchrun --nproc_per_node N -m doctrpp train ...",
    )
    p.add_argument("--out", type=Path, required=True, help="run folder (created)")
    p.add_argument(
        "--config",
        help="model config preset (default: the --init file's config, else reference)",
    )
    p.add_argument("--steps", type=int, default=100_000, help="length of the lr schedule")
    p.add_argument("--stop-at", type=int, help="stop after this step (schedule keeps --steps)")
    p.add_argument("--batch", type=int, default=12, help="batch per process (default 12)")
    p.add_argument("--lr", type=float, default=1e-4, help="OneCycle max learning rate")
    p.add_argument(
        "--resume", type=Path, help="checkpoint to continue from (e.g. RUN_DIR/last.pth)"
    )
    p.add_argument(
        "--restart-schedule",
        action="store_true",
        help="with --resume: keep weights and optimiser, run a new OneCycle of --steps",
    )
    p.add_argument(
        "--init",
        type=Path,
        help="start from these weights only (the embedded default .pt, a committed checkpoint "
        "or a run's .pth) with a fresh optimiser and lr cycle; step, hours and the generated "
        "stream continue from its record",
    )
    p.add_argument("--data", type=Path, help="train on a folder from `doctrpp crops` instead")
    p.add_argument(
        "--kind",
        default="mixed",
        choices=["mixed", *KINDS],
        help="crop kinds to generate (default: mixed thirds)",
    )
    p.add_argument(
        "--complete-first",
        type=int,
        default=0,
        metavar="STEPS",
        help="curriculum: train this many steps on complete-boundary crops, then on --kind "
        "(CPU runs here needed it to leave the mean-map plateau)",
    )
    p.add_argument(
        "--workers",
        type=int,
        help="data generator processes (default: 1 on CPU; beside a GPU, the cores left over)",
    )
    p.add_argument(
        "--device",
        choices=["auto", "cuda", "cpu"],
        default="auto",
        help="where to train (default auto: CUDA when torch sees a GPU)",
    )
    p.add_argument("--threads", type=int, help="torch threads per process")
    precision = p.add_mutually_exclusive_group()
    precision.add_argument(
        "--bf16",
        action="store_true",
        help="force bf16 autocast (default: on where the device computes bf16 natively)",
    )
    precision.add_argument("--no-bf16", action="store_true", help="train in fp32")
    p.add_argument(
        "--validate-every",
        type=int,
        default=200,
        help="steps between validations (and snapshots); default 200",
    )
    p.add_argument(
        "--checkpoint-every",
        type=int,
        default=50,
        help="steps between writes of RUN_DIR/last.pth; default 50",
    )
    p.add_argument("--validation-size", type=int, default=48, help="fixed validation crops")
    p.add_argument("--max-minutes", type=float, help="stop cleanly after this long")
    p.add_argument("--seed", type=int, default=0, help="seed of the weights and generated data")
    p.add_argument(
        "--real-photos",
        type=Path,
        metavar="FOLDER",
        help="real photos for a reference-free check at each validation (never trained on): "
        "text-line straightness, black and kept share per crop kind",
    )
    p.add_argument(
        "--page-reuse",
        type=int,
        default=4,
        help="generated crops share a page this many at a time (cheaper data)",
    )
    p.add_argument(
        "--sample-reuse",
        type=int,
        default=1,
        metavar="K",
        help="show each generated crop K times, each with its own colour jitter (data "
        "workers keep the last few hundred); pays when generation is slower than training",
    )
    p.add_argument(
        "--real-photos-count",
        type=int,
        default=16,
        metavar="N",
        help="photos of --real-photos used by the check, each cut into a complete, partial and "
        "no-boundary crop (default 16; more is less noisy and slower per validation)",
    )
    p.add_argument(
        "--cross-shot-pairs",
        type=int,
        default=0,
        metavar="N",
        help="also compare the two rectified shots of the first N documents of --real-photos "
        "(<doc>_1 and <doc>_2; `training.cross_shot`) at each validation (default 0: off)",
    )
    p.add_argument(
        "--gradient-loss",
        type=float,
        default=0.0,
        metavar="W",
        help="add W times the L1 of the maps' 8-pixel differences, which ignores where the "
        "page sits and weighs its local shape (default 0: the paper's plain L1)",
    )
    p.add_argument(
        "--worker-start",
        choices=("auto", "fork", "spawn"),
        default="auto",
        help="how data workers start: spawn gives each one OpenCV thread (for many workers on "
        "a GPU machine), fork starts quicker; auto (default) spawns on CUDA, forks elsewhere",
    )
    p.add_argument(
        "--photometric-loss",
        type=float,
        default=0.0,
        metavar="W",
        help="add W times the L1 between the crop rectified by the predicted map and by the "
        "true one (intensities 0-1, at a few blur widths), which weighs map errors by the "
        "print they move (default 0)",
    )
    p.add_argument(
        "--ms-ssim-loss",
        type=float,
        default=0.0,
        metavar="W",
        help="add W times 1 - MS-SSIM between those two rectified crops (unmasked, gray, the "
        "metric's 5-level weights), the held-out score's own measure (default 0)",
    )
    p.set_defaults(handler=run)


def _model_config(name: str | None, flag: str, start: Path | None):
    """The preset `name`; without one, the config the starting file (`--init` or
    `--resume`) records, e.g. a grown model's (`training.grow`), else the reference. A preset
    that differs from the starting file's is refused in one line."""
    from doctrpp.export.checkpoint import (
        CheckpointError,
        read_checkpoint_payload,
        split_checkpoint,
    )
    from doctrpp.export.config import REFERENCE, config_by_name

    recorded = None
    if start:
        if not start.is_file():
            raise CliError(f"{flag} {start}: no such file")
        try:
            payload = read_checkpoint_payload(start)
        except CheckpointError as exc:
            raise CliError(f"{flag} {start}: {exc}") from None
        if flag == "--resume":  # a weights-only snapshot has no optimiser to resume
            from .checkpoints import RESUME_KEYS, missing_keys

            problem = missing_keys(start, payload, RESUME_KEYS)
            if problem:
                raise CliError(f"--resume {problem} (a snapshot continues with --init)")
        recorded = split_checkpoint(payload)[1]
    if name is None:
        return recorded or REFERENCE
    try:
        config = config_by_name(name)
    except ValueError as exc:
        raise CliError(str(exc)) from None
    if recorded and recorded != config:
        raise CliError(
            f"{flag} {start} holds a model of another config ({recorded.to_json()}) than "
            f"--config {name}; leave --config out to train the file's own"
        )
    return config


def run(args: argparse.Namespace) -> int:
    require("torch", extra="export")

    from .loop import TrainSettings, train
    from .runlog import RunFolderBusy, run_folder_lock

    if args.init and args.resume:
        raise CliError("--init and --resume exclude each other (--resume keeps the optimiser)")
    flag, start = ("--init", args.init) if args.init else ("--resume", args.resume)
    config = _model_config(args.config, flag, start)
    if args.device == "cuda":
        import torch

        if not torch.cuda.is_available():
            raise CliError("--device cuda: torch sees no CUDA GPU on this machine")
    if args.complete_first < 0:
        raise CliError("--complete-first must be >= 0")
    if args.data and (args.kind != "mixed" or args.complete_first):
        raise CliError(
            "--kind and --complete-first choose generated crops; they do not apply to --data"
        )
    if args.real_photos and not args.real_photos.is_dir():
        raise CliError(f"--real-photos {args.real_photos}: no such folder")
    if args.real_photos_count < 1:
        raise CliError("--real-photos-count must be >= 1")
    if args.cross_shot_pairs < 0:
        raise CliError("--cross-shot-pairs must be >= 0")
    if args.cross_shot_pairs and not args.real_photos:
        raise CliError("--cross-shot-pairs needs --real-photos (the folder of <doc>_1/_2 shots)")
    if args.cross_shot_pairs and not _has_shot_pairs(args.real_photos):
        raise CliError(f"--cross-shot-pairs: {args.real_photos} has no <doc>_1/<doc>_2 photos")
    if args.gradient_loss < 0:
        raise CliError("--gradient-loss must be >= 0")
    if args.photometric_loss < 0:
        raise CliError("--photometric-loss must be >= 0")
    if args.ms_ssim_loss < 0:
        raise CliError("--ms-ssim-loss must be >= 0")
    if args.page_reuse < 1:
        raise CliError("--page-reuse must be >= 1")
    if args.sample_reuse < 1:
        raise CliError("--sample-reuse must be >= 1")
    if args.data and args.sample_reuse > 1:
        raise CliError("--sample-reuse applies to generated crops, not to --data")
    if args.data and not args.data.is_dir():
        raise CliError(f"--data {args.data}: no such folder")
    if args.out.exists() and not args.out.is_dir():
        raise CliError(f"--out {args.out} exists and is not a folder")
    if not args.resume and (args.out / "last.pth").exists():
        raise CliError(f"{args.out} already holds a run; pass --resume {args.out / 'last.pth'}")
    settings = TrainSettings(
        out=args.out,
        config=config,
        steps=args.steps,
        batch=args.batch,
        max_lr=args.lr,
        bf16=True if args.bf16 else False if args.no_bf16 else None,
        workers=args.workers,
        device=args.device,
        threads=args.threads,
        validate_every=args.validate_every,
        checkpoint_every=args.checkpoint_every,
        validation_size=args.validation_size,
        data_folder=args.data,
        kind=args.kind,
        complete_first=args.complete_first,
        max_minutes=args.max_minutes,
        stop_at=args.stop_at,
        resume=args.resume,
        restart_schedule=args.restart_schedule,
        init=args.init,
        real_photos=args.real_photos,
        real_photos_count=args.real_photos_count,
        cross_shot_pairs=args.cross_shot_pairs,
        page_reuse=args.page_reuse,
        sample_reuse=args.sample_reuse,
        gradient_loss=args.gradient_loss,
        photometric_loss=args.photometric_loss,
        ms_ssim_loss=args.ms_ssim_loss,
        worker_start=args.worker_start,
        seed=args.seed,
    )
    if os.environ.get("RANK", "0") != "0":  # rank 0 holds the folder for all ranks
        train(settings)
        return 0
    try:
        with run_folder_lock(args.out):
            state = train(settings)
    except RunFolderBusy as exc:
        raise CliError(str(exc)) from None
    print(
        f"stopped at step {state['step']} ({state['samples_seen']} samples, "
        f"{state['cpu_seconds'] / 3600:.2f} CPU hours training, "
        f"{state.get('data_cpu_seconds', 0.0) / 3600:.2f} generating data); "
        f"checkpoint {args.out / 'last.pth'}"
    )
    return 0


def _has_shot_pairs(folder: Path) -> bool:
    from doctrpp.benchmarks.cross_shot import shot_pairs  # imported here: numpy and OpenCV

    return bool(shot_pairs(folder))
