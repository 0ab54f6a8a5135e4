"""How a report is rendered: its folder, the command shown in its header, figures embedded."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

__all__ = ["ReportOptions"]


@dataclass(frozen=True)
class ReportOptions:
    """Rendering options of a report (a study's options say what ran, these how it is shown).

    Attributes
    ----------
    out : Path
        The report folder (``index.html``, ``report.md``, ``results.csv``,
        ``figures/``, ``trajectories/``).
    command : str
        The command line shown in the header ('' for the Python API).
    embed_figures : bool
        Embed the PNGs in ``index.html`` (else link ``figures/``).
    """

    out: Path
    command: str = ""
    embed_figures: bool = True
