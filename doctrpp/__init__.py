"""doctrpp-edge: DocTr++ document-image rectification for phones and CPUs.

Importing this package (or `doctrpp.runtime`) never imports torch.
"""

from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

try:
    __version__ = version("doctrpp-edge")
except PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0.0.0+unknown"

# In a source checkout the stage folders (export/, runtime/, ...) sit beside this folder, not
# inside it as in an installed package; with the checkout's root on sys.path (python run
# from the repository root) `doctrpp.runtime` must still resolve, so look there too.
_checkout = Path(__file__).resolve().parent.parent
if (
    not (Path(__file__).resolve().parent / "runtime").is_dir()
    and (_checkout / "runtime" / "__init__.py").is_file()
):
    __path__.append(str(_checkout))  # noqa: F821 - the package's own search path

__all__ = ["__version__"]
