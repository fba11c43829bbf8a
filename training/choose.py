"""Shortlist the snapshots that may ship, by the selection rule of MODEL_CARD.md.

usage: python -m doctrpp.training.choose RUN_DIR [RUN_DIR ...] [--margin 0.3] [--max-black 0.05]

The rule: among validations whose real-photo black share is at most --max-black on every
kind, keep those within --margin px of the lowest generated map error (all kinds), then
order them by the real photos' cross-shot agreement where the run logged it
(`--cross-shot-pairs`), else by mean real coherence. The in-loop real scores are noisy and
the map error was the ground the shortlist was chosen on, so the shortlist is re-scored
with `python -m doctrpp.training.score` on 48 photos and on 192 fresh generated crops
(48-239 of the validation stream) and with `python -m doctrpp.training.cross_shot`, against
the shipped default photo by photo and crop by crop, before anything is published; this
prints those commands (raw maps, and as `rectify` runs them).
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path

from doctrpp.export.default_weights import DEFAULT_NAME
from doctrpp.udir.scene import KINDS

from .runlog import read_validation

# Validation crops no snapshot was chosen on: the trainer's check uses the first 48.
FRESH_START, FRESH_COUNT = 48, 192


@dataclass(frozen=True)
class Candidate:
    run_dir: Path
    record: dict

    @property
    def step(self) -> int:
        return int(self.record["step"])

    @property
    def map_error(self) -> float:
        return float(self.record["map_error_px/all"])

    @property
    def snapshot(self) -> Path:
        return self.run_dir / "snapshots" / f"step{self.step:07d}.pt"

    def real(self, metric: str) -> list[float]:
        return [float(self.record.get(f"real/{metric}/{kind}", float("nan"))) for kind in KINDS]

    @property
    def mean_coherence(self) -> float:
        values = self.real("coherence_ratio")
        return sum(values) / len(values)

    @property
    def cross_shot(self) -> float | None:
        value = self.record.get("real/cross_shot_ms_ssim")
        return None if value is None else float(value)


def shortlist(candidates: list[Candidate], margin: float, max_black: float) -> list[Candidate]:
    """Candidates within `margin` px of the lowest map error among those with little black,
    best cross-shot agreement first where every one has it, else best mean real coherence."""
    allowed = [c for c in candidates if max(c.real("black_share")) <= max_black]
    if not allowed:
        return []
    lowest = min(c.map_error for c in allowed)
    near = [c for c in allowed if c.map_error <= lowest + margin]
    if all(c.cross_shot is not None for c in near):
        return sorted(near, key=lambda c: -c.cross_shot)
    return sorted(near, key=lambda c: -c.mean_coherence)


def markdown_table(candidates: list[Candidate], untouched: list[float]) -> str:
    lines = [
        "| run | step | map error all px | real coherence c / p / n | cross-shot MS-SSIM "
        "| black max | snapshot |",
        "|---|---|---|---|---|---|---|",
    ]
    for c in candidates:
        coherence = " / ".join(f"{v:.3f}" for v in c.real("coherence_ratio"))
        below = any(v < u for v, u in zip(c.real("coherence_ratio"), untouched, strict=True))
        cross_shot = "—" if c.cross_shot is None else f"{c.cross_shot:.4f}"
        lines.append(
            f"| {c.run_dir.name} | {c.step:,} | {c.map_error:.2f} | {coherence}"
            f"{' (below untouched)' if below else ''} | {cross_shot} | "
            f"{max(c.real('black_share')):.3f} | "
            f"{c.snapshot if c.snapshot.is_file() else '(no snapshot)'} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m doctrpp.training.choose", description=__doc__.split("\n")[0]
    )
    parser.add_argument("run_dirs", nargs="+", type=Path, metavar="RUN_DIR")
    parser.add_argument(
        "--margin", type=float, default=0.3, help="px above the lowest map error (default 0.3)"
    )
    parser.add_argument(
        "--max-black", type=float, default=0.05, help="largest real black share (default 0.05)"
    )
    args = parser.parse_args(argv)
    candidates: list[Candidate] = []
    untouched = [0.0] * len(KINDS)
    try:
        for run_dir in args.run_dirs:
            identity, records = read_validation(run_dir)
            candidates += [Candidate(run_dir, r) for r in records if "map_error_px/all" in r]
            if identity:
                untouched = Candidate(run_dir, identity).real("coherence_ratio")
    except (FileNotFoundError, ValueError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    chosen = shortlist(candidates, args.margin, args.max_black)
    if not chosen:
        print("error: no validation with real black share within --max-black", file=sys.stderr)
        return 1
    print(markdown_table(chosen, untouched))
    snapshots = [str(c.snapshot) for c in chosen if c.snapshot.is_file()]
    if snapshots:
        print("\n" + rescore_commands(snapshots))
    return 0


def rescore_commands(snapshots: list[str]) -> str:
    """The re-scorings the rule asks for, the shipped default first so that each snapshot
    is compared with it crop by crop (a snapshot ships only if it beats it): raw maps (the
    rule's coherence) and as `rectify` runs them, on fresh generated crops, and the two
    shots of each real document (`training.cross_shot`)."""
    weights = " ".join([f"export/weights/{DEFAULT_NAME}", *snapshots])
    command = (
        f"python -m doctrpp.training.score {weights} "
        "--real-photos ../shared/realphotos/docunet_dev --photos 48 "
        f"--validation-start {FRESH_START} --validation-size {FRESH_COUNT}"
    )
    pipeline = f"{command} --flip-average --line-alignment"
    cross_shot = (
        f"python -m doctrpp.training.cross_shot {weights} --photos ../shared/realphotos/docunet_dev"
    )
    return (
        f"re-score, raw: {command}\nas rectify runs them: {pipeline}\n"
        f"real photos, two shots each: {cross_shot}"
    )


if __name__ == "__main__":
    raise SystemExit(main())
