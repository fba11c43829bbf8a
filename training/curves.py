"""Validation curves of training runs (map error per crop kind vs samples seen), as one PNG.

usage: python -m doctrpp.training.curves RUN_DIR [RUN_DIR ...] -o curves.png
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from doctrpp.files import write_bytes_atomically

from .runlog import read_validation

KINDS = ("complete", "partial", "none", "all")


def plot_runs(run_dirs: list[Path], out: Path) -> None:
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(KINDS), figsize=(4 * len(KINDS), 3.4), sharex=True)
    identity = {}
    for run_dir in run_dirs:
        identity, records = read_validation(run_dir)
        samples = [r["samples_seen"] for r in records]
        for ax, kind in zip(axes, KINDS, strict=True):
            ax.plot(
                samples,
                [r[f"map_error_px/{kind}"] for r in records],
                marker=".",
                label=run_dir.name,
            )
    for ax, kind in zip(axes, KINDS, strict=True):
        if f"map_error_px/{kind}" in identity:
            ax.axhline(identity[f"map_error_px/{kind}"], color="grey", ls="--", label="identity")
        ax.set_title(f"{kind}")
        ax.set_xlabel("samples seen")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("validation map error (px, 288 grid)")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    plt.close(fig)
    write_bytes_atomically(out, buffer.getvalue())


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m doctrpp.training.curves", description=__doc__)
    parser.add_argument("runs", type=Path, nargs="+", help="run folders of `doctrpp train`")
    parser.add_argument("-o", "--out", type=Path, required=True, help="PNG to write")
    args = parser.parse_args(argv)
    try:
        plot_runs(args.runs, args.out)
    except (FileNotFoundError, KeyError, json.JSONDecodeError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
