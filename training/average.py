"""Average the weights of training checkpoints (ends of annealed cycles) into one.

usage: python -m doctrpp.training.average CHECKPOINT... --out RUN_DIR
       [--ancestor CHECKPOINT]... [--real-photos DIR] [--real-photos-count 32]

Cycle ends that grew from one start (two cycles from the same weights, or a cycle and its
continuation) lie in one basin of the loss, where the mean of their weights can predict
better than either alone (measured on ours: a gain within the noise, MODEL_CARD.md,
"Weight averaging"). Writes RUN_DIR/snapshots/stepN.pt
(weights, config, training state; N = the step of the source trained longest) and
RUN_DIR/validation.jsonl (the identity baseline and the average's scores, as the trainer
logs them), so `training.choose`, `training.score` and `training.publish` take it like a
run folder.

The training state counts CPU hours and samples once: the source with the most CPU time
is the base, and each other source adds only what it trained after its own start (its
`schedule_start`), which must be the step of the base's lineage or of an `--ancestor`
checkpoint given here (the weights it started from). A source that another grew from,
directly or through the given checkpoints' starts, is counted in that one.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import torch

from doctrpp.errors import CliError
from doctrpp.export.config import ModelConfig
from doctrpp.export.model import DocTrPP

from .checkpoints import read_training_checkpoint, save_checkpoint
from .realcheck import real_photo_set, validation_scores
from .runlog import RunLog
from .validate import validation_set


def check(condition: bool, message: str) -> None:
    if not condition:
        raise CliError(message)


COUNTED = ("samples_seen", "generated_samples", "cpu_seconds", "data_cpu_seconds", "wall_seconds")


def mean_state_dict(states: list[dict]) -> dict:
    """Element-wise mean of float tensors; integer buffers (counters) from the first."""
    keys = set(states[0])
    for state in states[1:]:
        check(set(state) == keys, "the checkpoints have different parameters")
    return {
        key: torch.stack([s[key].float() for s in states]).mean(0)
        if states[0][key].is_floating_point()
        else states[0][key]
        for key in states[0]
    }


def lineage_steps(state: dict, known: dict[int, dict]) -> set[int]:
    """Steps of the checkpoints `state` grew from, followed back through `known`."""
    steps: set[int] = set()
    start = state.get("schedule_start")
    while start is not None and start not in steps:
        steps.add(start)
        start = known.get(start, {}).get("schedule_start")
    return steps


def combined_state(states: list[dict], ancestors: list[dict]) -> dict:
    """The averaged weights' training state: the base's (most CPU time) plus, for each
    other source that no other source grew from, what it trained after its ancestor."""
    base = max(states, key=lambda s: s["cpu_seconds"])
    known = {s["step"]: s for s in [*ancestors, *states]}
    combined = dict(base)
    grown_from = set().union(*(lineage_steps(s, known) for s in states))
    for state in states:
        if state is base or state["step"] in grown_from:
            continue  # the base, or a checkpoint another source grew from: counted there
        start = state.get("schedule_start")
        check(
            start in known and known[start]["cpu_seconds"] <= state["cpu_seconds"],
            f"a checkpoint at step {state['step']} started at step {start}: give that "
            "checkpoint with --ancestor so the record counts its training once",
        )
        for field in COUNTED:
            combined[field] = combined.get(field, 0.0) + state.get(field, 0.0)
            combined[field] -= known[start].get(field, 0.0)
    combined["averaged_from"] = sorted(s["step"] for s in states)
    return combined


def average(paths: list[Path], ancestors: list[Path]) -> dict:
    """The averaged checkpoint (model, config, train_state) of `paths`."""
    check(len(paths) >= 2, "give at least two checkpoints to average")
    checkpoints = [read_training_checkpoint(p) for p in paths]
    config = checkpoints[0]["config"]
    model_config = ModelConfig.from_dict(dict(config))  # files from before a new field match
    for path, checkpoint in zip(paths, checkpoints, strict=True):
        same = ModelConfig.from_dict(dict(checkpoint["config"])) == model_config
        check(same, f"{path}: another model configuration")
    return {
        "model": mean_state_dict([c["model"] for c in checkpoints]),
        "config": config,
        "train_state": combined_state(
            [c["train_state"] for c in checkpoints],
            [read_training_checkpoint(p)["train_state"] for p in ancestors],
        ),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m doctrpp.training.average", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("checkpoints", type=Path, nargs="+", help="checkpoints to average")
    parser.add_argument("--out", type=Path, required=True, help="run folder to write (new)")
    parser.add_argument(
        "--ancestor", type=Path, action="append", default=[], help="weights a source began from"
    )
    parser.add_argument("--real-photos", type=Path, help="folder of real photos to score on")
    parser.add_argument("--real-photos-count", type=int, default=32)
    parser.add_argument("--validation-size", type=int, default=48)
    args = parser.parse_args(argv)
    try:
        check(not (args.out / "validation.jsonl").exists(), f"{args.out} already holds a run")
        averaged = average(args.checkpoints, args.ancestor)
        model = DocTrPP(ModelConfig.from_dict(dict(averaged["config"])))
        model.load_state_dict(averaged["model"])
        validation = validation_set(args.validation_size)
        real = real_photo_set(args.real_photos, args.real_photos_count) if args.real_photos else []
        identity = validation_scores(None, validation, real)
        scores = validation_scores(model, validation, real)
    except CliError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    state = averaged["train_state"]
    step = state["step"]
    save_checkpoint(args.out / "snapshots" / f"step{step:07d}.pt", averaged)
    log = RunLog(args.out)
    log.validation({"step": 0, "identity": True, **identity})
    log.validation(
        {
            "step": step,
            "samples_seen": state["samples_seen"],
            "cpu_hours": state["cpu_seconds"] / 3600,
            "data_cpu_hours": state.get("data_cpu_seconds", 0.0) / 3600,
            "averaged_from": state["averaged_from"],
            **scores,
        }
    )
    print(f"averaged steps {state['averaged_from']}: map error {scores['map_error_px/all']:.3f} px")
    print(f"wrote {args.out / 'snapshots' / f'step{step:07d}.pt'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
