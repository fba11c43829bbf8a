"""Turn a training checkpoint into the embedded default: fp16 weights + config + record.

usage: python -m doctrpp.training.publish RUN_DIR/best.pth [--note TEXT] [--out DIR]
       python -m doctrpp.training.publish RUN_DIR/snapshots/stepNNNNNNN.pt ...
       python -m doctrpp.training.publish --rescore [--out DIR]

Writes doctrpp_default.pt (state dict in fp16, config, training record) and
doctrpp_default.json (the same record plus the .pt file's sha256) into export/weights/.
`--rescore` keeps the weights and re-scores them on the generated validation set of the
current generator (after a change to udir/): the record's generated scores and their
identity baseline are replaced, the earlier ones kept under "validation_before_rescore".
"""

from __future__ import annotations

import argparse
import datetime
import io
import json
import sys
from pathlib import Path

import torch

from doctrpp.errors import CliError
from doctrpp.export.default_weights import DEFAULT_NAME, WEIGHTS_DIR
from doctrpp.files import sha256_of, write_bytes_atomically

from .checkpoints import read_training_checkpoint
from .runlog import read_validation


def validation_at(run_dir: Path, step: int) -> dict:
    """The run's validation scores at `step` and the identity baseline's."""
    identity, records = read_validation(run_dir)
    at_step = [r for r in records if r["step"] == step]
    if not at_step:
        raise CliError(f"{run_dir / 'validation.jsonl'} has no validation at step {step}")
    scores = lambda r: {k: v for k, v in r.items() if "/" in k}  # noqa: E731
    return {"validation": scores(at_step[-1]), "identity": scores(identity)}


def training_record(checkpoint: dict, run_dir: Path, note: str) -> dict:
    state = checkpoint["train_state"]
    return {
        "config": checkpoint["config"],
        "run": run_dir.name,
        "step": state["step"],
        "samples_seen": state["samples_seen"],
        "cpu_hours": round(state["cpu_seconds"] / 3600, 3),
        # Data workers' CPU time, counted from session 4 on (earlier runs did not record it).
        "data_cpu_hours": round(state.get("data_cpu_seconds", 0.0) / 3600, 3),
        "wall_hours": round(state["wall_seconds"] / 3600, 3),
        "date": datetime.date.today().isoformat(),
        "note": note,
        # weights averaged from these steps' checkpoints (`training.average`)
        **({"averaged_from": state["averaged_from"]} if "averaged_from" in state else {}),
        **validation_at(run_dir, state["step"]),
    }


def publish(checkpoint_path: Path, out_dir: Path, note: str) -> Path:
    checkpoint = read_training_checkpoint(checkpoint_path)
    run_dir = checkpoint_path.parent
    if run_dir.name == "snapshots":  # RUN_DIR/snapshots/stepNNNNNNN.pt
        run_dir = run_dir.parent
    record = training_record(checkpoint, run_dir, note)
    payload = {
        "model": {
            k: v.half() if v.is_floating_point() else v for k, v in checkpoint["model"].items()
        },
        "config": checkpoint["config"],
        "training_record": record,
    }
    buffer = io.BytesIO()
    torch.save(payload, buffer)
    weights = out_dir / DEFAULT_NAME
    write_bytes_atomically(weights, buffer.getvalue())
    record = {**record, "sha256": sha256_of(weights), "file": DEFAULT_NAME}
    write_record(weights.with_suffix(".json"), record)
    return weights


def write_record(path: Path, record: dict) -> None:
    text = json.dumps(record, indent=2, sort_keys=True) + "\n"
    write_bytes_atomically(path, text.encode())


GENERATED_SCORES = (
    "map_error_px/",
    "ms_ssim_m/",
    "nonprojective_recovered/",
    "ms_ssim/",
    "local_distortion/",
)


def rescore(out_dir: Path, validation_size: int = 48) -> dict:
    """Re-score the published weights on the current generator's validation set and
    rewrite their record's generated scores (real-photo scores do not depend on it)."""
    from doctrpp.export.checkpoint import load_model

    from .validate import identity_scores, predict_maps, score_maps, validation_set

    weights = out_dir / DEFAULT_NAME
    record_path = weights.with_suffix(".json")
    if not weights.is_file() or not record_path.is_file():
        raise CliError(f"{out_dir}: no published default to re-score")
    record = json.loads(record_path.read_text())
    if record.get("sha256") != sha256_of(weights):
        raise CliError(f"{record_path}: its sha256 does not match {weights.name}")
    items = validation_set(validation_size)
    fresh = {
        "validation": score_maps(items, predict_maps(load_model(weights), items)),
        "identity": identity_scores(items),
    }
    before = {}
    for part, scores in fresh.items():
        kept = {k: v for k, v in record[part].items() if not k.startswith(GENERATED_SCORES)}
        before[part] = {k: v for k, v in record[part].items() if k.startswith(GENERATED_SCORES)}
        record[part] = {**kept, **scores}
    record["validation_before_rescore"] = before
    record["rescored"] = datetime.date.today().isoformat()
    write_record(record_path, record)
    return record


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m doctrpp.training.publish", description=__doc__)
    parser.add_argument("checkpoint", type=Path, nargs="?", help="a checkpoint of `doctrpp train`")
    parser.add_argument(
        "--rescore",
        action="store_true",
        help="re-score the published default on the current generator's validation set",
    )
    parser.add_argument("--note", default="", help="free text for the record (e.g. the recipe)")
    parser.add_argument("--out", type=Path, default=WEIGHTS_DIR, help="folder (export/weights)")
    args = parser.parse_args(argv)
    try:
        if args.rescore:
            if args.checkpoint is not None:
                raise CliError("--rescore takes no checkpoint (it re-scores the published one)")
            record = rescore(args.out)
            print(
                f"re-scored {args.out / DEFAULT_NAME}: generated validation all "
                f"{record['validation']['map_error_px/all']:.2f} px "
                f"(identity {record['identity']['map_error_px/all']:.2f})"
            )
            return 0
        if args.checkpoint is None:
            raise CliError("give a checkpoint to publish, or --rescore")
        if not args.checkpoint.is_file():
            raise CliError(f"{args.checkpoint}: no such file")
        weights = publish(args.checkpoint, args.out, args.note)
    except CliError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    size = weights.stat().st_size / 1e6
    print(f"wrote {weights} ({size:.1f} MB) and {weights.with_suffix('.json').name}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
