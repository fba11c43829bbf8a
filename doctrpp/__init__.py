"""doctrpp-edge: DocTr++ document-image rectification for phones and CPUs.

Importing this package (or `doctrpp.runtime`) never imports torch.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("doctrpp-edge")
except PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0.0.0+unknown"

__all__ = ["__version__"]
