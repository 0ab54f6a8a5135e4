"""Exception hierarchy of rockbench.

Every error raised on purpose by rockbench derives from :class:`RockbenchError`,
so callers (and the CLI) can catch one type; errors about bad values also derive
from :class:`ValueError` so that generic code keeps working.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable

__all__ = [
    "RockbenchError",
    "ScenarioError",
    "UnknownEngine",
    "UnknownScenario",
    "UnsupportedScenario",
    "EngineUnavailable",
    "PlausibilityWarning",
]


class RockbenchError(Exception):
    """Base class of all rockbench errors."""


class ScenarioError(RockbenchError, ValueError):
    """A scenario, block, excitation or scenario file is invalid."""


def _did_you_mean(name: str, choices: Iterable[str], listing: str = "") -> str:
    choices = sorted(choices)
    close = difflib.get_close_matches(name, choices, n=1)
    hint = f"; did you mean {close[0]!r}?" if close else "."
    names = listing or f"valid names: {', '.join(choices)}"
    return f"{hint} {names[0].upper()}{names[1:]}"


class UnknownEngine(RockbenchError, ValueError):
    """No engine plugin is registered under this name."""

    def __init__(self, name: str, choices: Iterable[str]) -> None:
        super().__init__(f"unknown engine {name!r}{_did_you_mean(name, choices)}")
        self.name = name


class UnknownScenario(ScenarioError):
    """No catalog scenario or suite has this name (and it is not a file)."""

    def __init__(self, name: str, choices: Iterable[str], kind: str = "scenario") -> None:
        listing = f"run `rockbench scenarios` for the list of {kind}s" if kind == "scenario" else ""
        super().__init__(f"unknown {kind} {name!r}{_did_you_mean(name, choices, listing)}")
        self.name = name


class UnsupportedScenario(RockbenchError):
    """An engine cannot model this scenario (e.g. a 3D feature in a 2D engine)."""


class EngineUnavailable(RockbenchError, ImportError):
    """The engine's library is not installed or failed to import."""


class PlausibilityWarning(UserWarning):
    """A value physics can use but that is probably a slip (of units, most often)."""
