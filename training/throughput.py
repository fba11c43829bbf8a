"""Training-step cost per config and variant, measured as ratios in one process.

usage: python -m doctrpp.training.throughput [--configs tiny mid FILE.pt] [--batch 8] [--rounds 5]
       [--variants fp32 bf16 bf16+channels-last bf16+compile] [--threads 1] [--out T.json]

A config is a preset's name or a weights file that records one (a grown model,
`training.grow`). Each variant is one forward + backward + AdamW step on random inputs (data
excluded: its cost is the generator's, measured by `doctrpp crops`), timed in CPU seconds of
this process (`time.process_time`, so other load on a shared machine matters less than wall
time), interleaved round by round, median over rounds. `compile` is torch.compile
(inductor); its one-off compile time is reported apart. `channels-last` and `compile` are
offered but not run by default: with torch 2.13.0 on this CPU our model's first training
step aborts the process with heap corruption in both ("double free or corruption", "free():
invalid next size"; each variant alone in a fresh process; a plain conv in channels-last is
fine).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import torch

from doctrpp.export.checkpoint import read_checkpoint
from doctrpp.export.config import ModelConfig, config_by_name
from doctrpp.export.model import DocTrPP
from doctrpp.files import write_bytes_atomically
from doctrpp.training.losses import map_l1

VARIANTS = ("fp32", "bf16", "bf16+channels-last", "bf16+compile")
DEFAULT_VARIANTS = ("fp32", "bf16")


def model_config(name: str) -> ModelConfig:
    """A preset by name, or the config a weights file records."""
    if Path(name).is_file():
        recorded = read_checkpoint(name)[1]
        if recorded is None:
            raise ValueError(f"{name} records no model config")
        return recorded
    return config_by_name(name)


def make_step(config: str, variant: str, batch: int, seed: int = 0):
    """A closure running one training step; returns (step, setup CPU seconds)."""
    torch.manual_seed(seed)
    model = DocTrPP(model_config(config)).train()
    images = torch.rand(batch, 3, 288, 288)
    targets = torch.rand(batch, 2, 288, 288) * 287
    if "channels-last" in variant:
        model = model.to(memory_format=torch.channels_last)
        images = images.contiguous(memory_format=torch.channels_last)
    net = torch.compile(model) if "compile" in variant else model
    optimiser = torch.optim.AdamW(model.parameters(), lr=1e-4)
    bf16 = "bf16" in variant

    def step() -> float:
        with torch.autocast("cpu", dtype=torch.bfloat16, enabled=bf16):
            predicted = net(images)
        loss = map_l1(predicted.float(), targets)
        optimiser.zero_grad(set_to_none=True)
        loss.backward()
        optimiser.step()
        return float(loss.detach())

    started = time.process_time()
    step()  # warm-up (and compilation)
    return step, time.process_time() - started


def measure(configs, variants, batch: int, rounds: int) -> list[dict]:
    steps = {}
    rows = []
    for config in configs:
        for variant in variants:
            try:
                steps[(config, variant)], setup = make_step(config, variant, batch)
            except Exception as exc:  # a variant this machine cannot run (no compiler...)
                rows.append({"config": config, "variant": variant, "error": str(exc)[:200]})
                continue
            print(f"{config} {variant}: warm-up {setup:.1f} CPU s", flush=True)
            rows.append({"config": config, "variant": variant, "warmup_cpu_s": setup})
    timings: dict = {key: [] for key in steps}
    for r in range(rounds):
        for key, step in steps.items():
            started = time.process_time()
            step()
            timings[key].append(time.process_time() - started)
        print(f"round {r + 1}/{rounds}", flush=True)
    for row in rows:
        key = (row["config"], row["variant"])
        if key in timings:
            row["cpu_s_per_step"] = float(np.median(timings[key]))
            row["samples_per_cpu_s"] = batch / row["cpu_s_per_step"]
    for config in configs:
        base = next((r for r in rows if r["config"] == config and "cpu_s_per_step" in r), None)
        for row in rows:
            if base and row["config"] == config and "cpu_s_per_step" in row:
                row["vs_first"] = row["cpu_s_per_step"] / base["cpu_s_per_step"]
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m doctrpp.training.throughput", description=__doc__
    )
    parser.add_argument("--configs", nargs="+", default=["tiny", "mid"])
    parser.add_argument("--variants", nargs="+", default=list(DEFAULT_VARIANTS), choices=VARIANTS)
    parser.add_argument("--batch", type=int, default=8)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--threads", type=int, default=1, help="torch threads (training uses 1)")
    parser.add_argument("--out", type=Path, help="write the rows as JSON here")
    args = parser.parse_args(argv)
    torch.set_num_threads(args.threads)
    rows = measure(args.configs, args.variants, args.batch, args.rounds)
    print("| config | variant | CPU s / step | samples / CPU s | vs first | warm-up CPU s |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        if "error" in r:
            print(f"| {r['config']} | {r['variant']} | failed: {r['error']} | | | |")
            continue
        print(
            f"| {r['config']} | {r['variant']} | {r['cpu_s_per_step']:.2f} | "
            f"{r['samples_per_cpu_s']:.1f} | {r['vs_first']:.2f}x | {r['warmup_cpu_s']:.0f} |"
        )
    if args.out:
        write_bytes_atomically(args.out, json.dumps(rows, indent=1).encode())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
