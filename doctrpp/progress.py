"""A dependency-free progress bar on stderr (a line per step when not a terminal)."""

from __future__ import annotations

import sys
import time
from collections.abc import Iterable, Iterator
from typing import TypeVar

T = TypeVar("T")


def progress(items: Iterable[T], total: int, label: str, enabled: bool = True) -> Iterator[T]:
    stream = sys.stderr
    interactive = stream.isatty()
    start = time.perf_counter()
    for done, item in enumerate(items):
        yield item
        if not enabled:
            continue
        elapsed = time.perf_counter() - start
        count = done + 1
        rate = count / elapsed if elapsed > 0 else 0.0
        eta = (total - count) / rate if rate > 0 else 0.0
        filled = int(30 * count / max(total, 1))
        line = (
            f"{label} [{'#' * filled}{'.' * (30 - filled)}] {count}/{total} "
            f"{rate:.2f}/s eta {eta:.0f}s"
        )
        if interactive:
            stream.write("\r" + line + ("\n" if count == total else ""))
        else:
            stream.write(line + "\n")
        stream.flush()
