"""Errors the command line reports as one line with a non-zero exit."""

from __future__ import annotations

import importlib


class CliError(Exception):
    """A user error: printed as one line, exit status 2."""


def require(*modules: str, extra: str) -> None:
    """Fail with an install hint when an optional dependency is missing."""
    for name in modules:
        try:
            importlib.import_module(name)
        except ImportError:
            raise CliError(
                f"this command needs the [{extra}] extra ({name} is missing): "
                f"pip install 'doctrpp-edge[{extra}]'"
            ) from None
