"""The identity of a method in a study: which engine, at which settings.

Every study, table, figure, stored run and file name refers to a method through
one :class:`Method`; its display label and its file-name slug are derived here
and nowhere else.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

__all__ = ["Method", "REFERENCE", "CONSENSUS", "slug"]

#: Engine name of the analytic reference.
REFERENCE = "analytic"
#: Name of a study's reference where no closed form exists: the consensus of its engines'
#: contact-model families (:mod:`rockbench.studies.consensus`); never run itself.
CONSENSUS = "consensus"


def slug(text: str) -> str:
    """A file-name-safe form of a label (``mujoco[fast]`` → ``mujoco-fast``)."""
    out = re.sub(r"[^A-Za-z0-9_.=+-]+", "-", text).strip("-.")
    return out or "method"


@dataclass(frozen=True)
class Method:
    """One method of a study: an engine, its preset, knob overrides and a variation.

    Attributes
    ----------
    engine : str
        Registered engine name (``analytic`` for the reference).
    preset : str
        Settings preset (empty: the engine's defaults).
    overrides : tuple of (str, value)
        Knob overrides applied on top of the preset (``--settings``, ``--set``,
        a sweep point), sorted by knob name.
    variation : str
        A named variation of a study (the sensitivity study's ``iterations=10``);
        empty for the main runs.
    qualified : bool
        Whether the label names the preset (a study that runs several presets
        of one engine needs it; one that runs one preset does not).
    """

    engine: str
    preset: str = ""
    overrides: tuple[tuple[str, Any], ...] = field(default=())
    variation: str = ""
    qualified: bool = False

    @classmethod
    def of(cls, engine: str, settings: Mapping[str, Any] | None = None, *,
           variation: str = "", qualified: bool = False) -> Method:
        """A method from a requested-settings mapping (``{"preset": ..., knob: value}``)."""
        s = dict(settings or {})
        preset = str(s.pop("preset", "") or "")
        return cls(engine, preset, tuple(sorted(s.items())), variation, qualified)

    @classmethod
    def reference(cls) -> Method:
        """The analytic reference."""
        return cls(REFERENCE)

    @classmethod
    def consensus(cls) -> Method:
        """The consensus of a study's engines, its reference where no closed form exists."""
        return cls(CONSENSUS)

    @property
    def is_reference(self) -> bool:
        """True for a study's reference, analytic or consensus (not a variation of it)."""
        return self.engine in (REFERENCE, CONSENSUS) and not self.variation

    @property
    def settings(self) -> dict[str, Any]:
        """The requested settings: ``preset`` (if any) then the overrides."""
        out: dict[str, Any] = {"preset": self.preset} if self.preset else {}
        out.update(self.overrides)
        return out

    @property
    def label(self) -> str:
        """How tables and figures name it: ``mujoco``, ``mujoco[fast]``,
        ``bullet[iterations=10]``."""
        if self.variation:
            return f"{self.engine}[{self.variation}]"
        if self.qualified and self.preset and not self.is_reference:
            return f"{self.engine}[{self.preset}]"
        return self.engine

    @property
    def slug(self) -> str:
        """File stem of its runs; names the preset even when the label does not, so that
        a run is found again whatever presets a later study shows."""
        if self.variation or self.is_reference or not self.preset:
            return slug(self.label)
        return slug(f"{self.engine}[{self.preset}]")

    def __str__(self) -> str:
        return self.label
