"""Where training runs: the device and DDP ranks, bf16 support, and the data worker
processes (how they start, stop and are counted in CPU time)."""

from __future__ import annotations

import os
import signal
from pathlib import Path

import torch
import torch.distributed as dist


class Distributed:
    """torchrun sets WORLD_SIZE/RANK/LOCAL_RANK; without them this is one plain process."""

    def __init__(self, device: str = "auto") -> None:
        self.world = int(os.environ.get("WORLD_SIZE", "1"))
        self.rank = int(os.environ.get("RANK", "0"))
        self.local_rank = int(os.environ.get("LOCAL_RANK", "0"))
        if device == "cuda" and not torch.cuda.is_available():
            raise RuntimeError("--device cuda: no CUDA GPU is visible to torch")
        if device != "cpu" and torch.cuda.is_available():
            self.device = torch.device("cuda", self.local_rank)
            torch.cuda.set_device(self.device)
        else:
            self.device = torch.device("cpu")
        if self.world > 1:
            dist.init_process_group("nccl" if self.device.type == "cuda" else "gloo")

    @property
    def main(self) -> bool:
        return self.rank == 0

    def close(self) -> None:
        if self.world > 1:
            dist.destroy_process_group()


def leave_stopping_to_the_trainer(_worker_id: int) -> None:
    """Data workers ignore SIGTERM/SIGINT: a signal sent to the whole process group (Ctrl-C,
    `kill -- -PGID`, a job scheduler) must reach only the trainer, which checkpoints and
    then shuts the workers down, instead of killing a worker and crashing the trainer.
    (`cv2.setNumThreads(1)` here would deadlock: a forked worker inherits the parent's
    OpenCV thread pool, session 27.)"""
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def spawned_worker_setup(worker_id: int) -> None:
    """A spawned worker is a fresh process with no OpenCV thread pool inherited, so one
    OpenCV thread each is safe there: many workers otherwise each spread over every core
    (0.35 CPU s per crop on 16 cores against 0.16 on 2, session 27)."""
    import cv2

    leave_stopping_to_the_trainer(worker_id)
    cv2.setNumThreads(1)


def worker_start_method(setting: str, device_type: str) -> str:
    """How data workers start: `auto` spawns them on CUDA, forks them elsewhere (a fork is
    quicker to start and the CPU runs use one or two workers)."""
    if setting not in ("auto", "fork", "spawn"):
        raise ValueError(f"worker start must be auto, fork or spawn, not {setting!r}")
    if setting == "auto":
        return "spawn" if device_type == "cuda" else "fork"
    return setting


def stop_workers(batches) -> None:
    """Shut the loader's workers down now. Left to garbage collection after an error (the
    traceback keeps the iterator alive), multiprocessing's exit handler would `terminate`
    them, which they ignore (`leave_stopping_to_the_trainer`), and wait for them forever."""
    shutdown = getattr(batches, "_shutdown_workers", None)  # torch's own orderly shutdown
    if shutdown is not None:
        shutdown()
    for worker in getattr(batches, "_workers", []):
        if worker.is_alive():
            worker.kill()
            worker.join(timeout=10)


def children_cpu_seconds() -> float:
    """CPU time of this process's children (the data workers), live and finished.

    Linux /proc; elsewhere only finished children count."""
    finished = os.times()
    total = finished.children_user + finished.children_system
    ticks = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100
    me = os.getpid()
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue  # the process ended meanwhile
        if int(fields[1]) == me:  # fields after the name: state, ppid, ..., utime, stime
            total += (int(fields[11]) + int(fields[12])) / ticks
    return total


def bf16_is_native(device: torch.device) -> bool:
    """Whether bf16 autocast pays on this device. CPUs without AVX-512 (AVX2 only) emulate
    bf16: a `mid` step took 6.6x as long as fp32 there (session 20), against 0.87x on
    AVX-512 CPUs (session 4)."""
    if device.type == "cuda":
        return torch.cuda.is_bf16_supported()
    try:
        return bool(torch.ops.mkldnn._is_mkldnn_bf16_supported())
    except (AttributeError, RuntimeError):
        return False


def default_workers(device_type: str, world: int = 1) -> int:
    """On CPU one data process (the trainer needs the other core); beside a GPU, the cores
    left after one per training process, so generation keeps up with the GPU."""
    if device_type != "cuda":
        return 1
    return max(1, (os.cpu_count() or 2) // max(world, 1) - 1)
