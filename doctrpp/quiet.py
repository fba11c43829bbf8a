"""Keep a noisy library's output (C++ logs included) out of the way unless asked for."""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from collections.abc import Iterator


@contextlib.contextmanager
def quiet(enabled: bool = True, tail_lines: int = 20) -> Iterator[None]:
    """Send stdout/stderr (file descriptors 1 and 2) to a temporary file while inside;
    on an exception, print the last `tail_lines` of what was captured, then re-raise."""
    if not enabled:
        yield
        return
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    with tempfile.TemporaryFile(mode="w+b") as sink:
        os.dup2(sink.fileno(), 1)
        os.dup2(sink.fileno(), 2)
        try:
            yield
        except BaseException:
            _restore(saved)
            sink.seek(0)
            lines = sink.read().decode(errors="replace").splitlines()[-tail_lines:]
            print("\n".join(lines), file=sys.stderr)
            raise
        else:
            _restore(saved)


def _restore(saved: tuple[int, int]) -> None:
    sys.stdout.flush()
    sys.stderr.flush()
    os.dup2(saved[0], 1)
    os.dup2(saved[1], 2)
    os.close(saved[0])
    os.close(saved[1])
