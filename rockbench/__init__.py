"""rockbench: rigid-block rocking in physics engines, benchmarked against analytical solutions."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("rockbench")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0.0.0"

__all__ = ["__version__"]
