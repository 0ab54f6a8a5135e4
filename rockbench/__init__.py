"""rockbench: rigid-block rocking in physics engines, benchmarked against analytical solutions."""

from rockbench.provenance import RELEASE as __version__

__all__ = ["__version__"]
