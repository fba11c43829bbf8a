"""A run's logs: log.csv (every step) and validation.jsonl (every validation)."""

from __future__ import annotations

import csv
import json
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

try:
    import fcntl
except ImportError:  # Windows: no advisory locks; runs go unguarded
    fcntl = None


class RunFolderBusy(RuntimeError):
    """Another process is training into this run folder."""


@contextmanager
def run_folder_lock(out: Path) -> Iterator[None]:
    """Hold RUN_DIR/.lock while a run trains into RUN_DIR.

    Two trainers in one folder would interleave their checkpoints and logs; a stopped run
    is not gone at once (on SIGTERM it finishes the step, saves last.pth, validates).
    The lock dies with the process, even a killed one.
    """
    out.mkdir(parents=True, exist_ok=True)
    fd = os.open(out / ".lock", os.O_RDWR | os.O_CREAT, 0o644)
    try:
        if fcntl is not None:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = os.pread(fd, 32, 0).decode(errors="replace").strip() or "unknown"
                raise RunFolderBusy(
                    f"{out} is in use by another training process (pid {holder}); wait for "
                    "it to stop (it saves last.pth and validates first) or stop it"
                ) from None
            os.ftruncate(fd, 0)
            os.pwrite(fd, str(os.getpid()).encode(), 0)
        yield
    finally:
        os.close(fd)


class RunLog:
    """log.csv (every step) and validation.jsonl (every validation), appended."""

    def __init__(self, out: Path) -> None:
        self.csv_path = out / "log.csv"
        self.val_path = out / "validation.jsonl"
        fresh = not self.csv_path.exists()
        self.csv_file = open(self.csv_path, "a", newline="")  # noqa: SIM115 - kept open for the run
        self.writer = csv.writer(self.csv_file)
        if fresh:
            self.writer.writerow(["step", "loss_px", "lr", "samples_per_s", "wall_s"])

    def step(self, step: int, loss: float, lr: float, rate: float, wall: float) -> None:
        self.writer.writerow([step, f"{loss:.4f}", f"{lr:.3e}", f"{rate:.3f}", f"{wall:.1f}"])
        self.csv_file.flush()

    def validation(self, record: dict) -> None:
        with open(self.val_path, "a") as f:
            f.write(json.dumps(record) + "\n")


def read_validation(run_dir: Path) -> tuple[dict, list[dict]]:
    """(identity baseline, validation records in step order) of one run."""
    path = run_dir / "validation.jsonl"
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file (not a `doctrpp train` run folder?)")
    records = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    identity = next((r for r in records if r.get("identity")), {})
    scored = sorted((r for r in records if not r.get("identity")), key=lambda r: r["step"])
    return identity, scored
