"""Tolerance files of ``rockbench matrix``: what each engine × scenario cell must achieve.

Format (TOML)::

    format = 1
    suite = "smoke"                # informational: the suite it was calibrated on

    [defaults]                     # every engine and scenario
    status = "reference"           # the run must end as the analytic reference does
    max_error = 0.05               # max |Δθ|/λ against the reference
    impact_time_error = 0.02       # relative error of the first three impact times
    peak_error = 0.05              # relative error of max |θ|/λ (worst block)

    [scenarios."stack-*"]          # one scenario or a glob, every engine
    max_error = 0.1

    [engines.mujoco]               # one engine, every scenario
    max_error = 0.02

    [engines.mujoco.scenarios."free-b2-0.5"]   # one cell
    max_error = 0.01

    [suites.paper.defaults]        # optional layer for one suite (same structure:
    max_error = 0.2                # defaults, scenarios, engines), applied last

    [regression]                   # checks against --baseline
    rel = 0.25                     # a metric regresses beyond base·(1 + rel) + abs
    abs = 0.002
    metrics = ["max_error", "impact_time_error", "peak_error"]

Layers apply in the order defaults → scenarios (globs, then exact names) →
engines → engine × scenario, first at top level and then under the suite's
section; later layers win. A metric limit is a non-negative number, or
``false`` to switch the check off. ``status`` is ``"reference"`` (ok or
overturned as the reference says; any completed run when there is no
analytic model), ``"completed"`` (ok or overturned), ``"any"``, or a list of
allowed statuses. A cell whose analytic reference did not complete (crashed,
timed out, ...) fails, since it cannot be checked, unless its limits check the
status only (a rule other than ``"reference"`` and every metric ``false``).
Metric names are those of :data:`METRICS`.
"""

from __future__ import annotations

import fnmatch
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rockbench.errors import RockbenchError
from rockbench.evaluation import NUMERIC_METRICS
from rockbench.tomlfile import read_toml
from rockbench.trajectory import Status

__all__ = ["Tolerances", "ToleranceError", "METRICS", "STATUS_RULES", "load_tolerances",
           "shipped_tolerances", "DEFAULT_REGRESSION"]

#: Metric limits a tolerance file may set (upper limits: lower is better), with their
#: meaning; each is a :data:`rockbench.evaluation.NUMERIC_METRICS` name, read with
#: :meth:`rockbench.evaluation.RunMetrics.value`.
METRICS: dict[str, str] = {
    "max_error": "max |Δθ|/λ against the analytic reference up to the predictability "
                 "horizon t* (the whole run when it is well posed)",
    "max_error_early": "max |Δθ|/λ up to the reference's third impact (and t*)",
    "impact_time_error": "largest relative error of the first three impact times before t*",
    "impacts_missing": "number of the reference's first impacts the run lacks",
    "peak_error": "largest |relative error| of max |θ|/λ over the blocks (peaks up to t*)",
    "time_to_rest": "time after which every |θ| stays below 0.01 λ (s)",
    "wall_time": "wall-clock time of the run in s",
    "cpu_time": "CPU time of the run in s",
    "slide": "largest sliding of the bottom block on the base (m)",
    "max_wobble": "largest out-of-plane rotation (rad)",
    "max_roll": "largest rotation about +x (rad)",
    "max_twist": "largest rotation about the block's vertical axis (rad)",
}
_NOT_LIMITS = NUMERIC_METRICS - set(METRICS)  # measured, but not an upper limit
#: Symbolic status rules.
STATUS_RULES = ("reference", "completed", "any")
#: Regression margins used when a file has no [regression] table.
DEFAULT_REGRESSION: dict[str, Any] = {
    "rel": 0.25, "abs": 0.002,
    "metrics": ["max_error", "max_error_early", "impact_time_error", "peak_error"],
}
_LAYER_KEYS = {"defaults", "scenarios", "engines"}
_TOP_KEYS = _LAYER_KEYS | {"format", "suite", "description", "suites", "regression"}


class ToleranceError(RockbenchError, ValueError):
    """A tolerance file is unreadable, malformed or holds an invalid value."""


def _limits(table: Any, where: str) -> dict[str, Any]:
    """Validate one table of metric limits (and the status rule)."""
    if not isinstance(table, Mapping):
        raise ToleranceError(f"{where} must be a table of metric limits")
    out: dict[str, Any] = {}
    for key, value in table.items():
        if key == "status":
            out[key] = _status_rule(value, f"{where}.status")
        elif key in METRICS:
            if value is False:
                out[key] = None
            elif (isinstance(value, (int, float)) and not isinstance(value, bool)
                  and math.isfinite(value) and value >= 0):
                out[key] = float(value)
            else:
                raise ToleranceError(f"{where}.{key} must be a number >= 0 or false, "
                                     f"got {value!r}")
        elif key in _NOT_LIMITS:
            raise ToleranceError(f"{where}.{key}: {key!r} is measured but is not a limit "
                                 f"(higher is not worse); limits: {', '.join(METRICS)}")
        else:
            raise ToleranceError(f"{where}: unknown metric {key!r}; known: status, "
                                 f"{', '.join(METRICS)}")
    return out


def _status_rule(value: Any, where: str) -> str | tuple[str, ...]:
    if isinstance(value, str):
        if value in STATUS_RULES:
            return value
        value = [value]
    if isinstance(value, list) and value:
        odd = next((v for v in value if not isinstance(v, str)), None)
        if odd is not None:
            raise ToleranceError(f"{where} must list status names (strings), got "
                                 f"{type(odd).__name__} {odd!r}")
        valid = {s.value for s in Status}
        bad = [v for v in value if v not in valid]
        if not bad:
            return tuple(value)
        raise ToleranceError(f"{where}: unknown status {bad[0]!r}; use "
                             f"{', '.join(STATUS_RULES)} or a list of {', '.join(sorted(valid))}")
    raise ToleranceError(f"{where} must be one of {', '.join(STATUS_RULES)} or a list of "
                         f"statuses, got {value!r}")


def _layer(data: Any, where: str) -> dict[str, Any]:
    """Validate a layer: defaults, scenarios.<glob>, engines.<e>[.scenarios.<glob>]."""
    if not isinstance(data, Mapping):
        raise ToleranceError(f"{where} must be a table")
    out: dict[str, Any] = {"defaults": _limits(data.get("defaults", {}), f"{where}defaults"),
                           "scenarios": {}, "engines": {}}
    scen = data.get("scenarios", {})
    if not isinstance(scen, Mapping):
        raise ToleranceError(f"{where}scenarios must be a table of scenario tables")
    for name, lim in scen.items():
        out["scenarios"][name] = _limits(lim, f"{where}scenarios.{name!r}")
    engines = data.get("engines", {})
    if not isinstance(engines, Mapping):
        raise ToleranceError(f"{where}engines must be a table of engine tables")
    for eng, table in engines.items():
        if not isinstance(table, Mapping):
            raise ToleranceError(f"{where}engines.{eng} must be a table")
        table = dict(table)
        cells = table.pop("scenarios", {})
        if not isinstance(cells, Mapping):
            raise ToleranceError(f"{where}engines.{eng}.scenarios must be a table")
        out["engines"][eng] = {
            "limits": _limits(table, f"{where}engines.{eng}"),
            "scenarios": {n: _limits(lim, f"{where}engines.{eng}.scenarios.{n!r}")
                          for n, lim in cells.items()},
        }
    return out


def _matching(tables: Mapping[str, dict[str, Any]], scenario: str) -> list[dict[str, Any]]:
    """Tables whose key matches ``scenario``: globs first, then the exact name."""
    globs = [v for k, v in tables.items() if k != scenario and fnmatch.fnmatchcase(scenario, k)]
    exact = [tables[scenario]] if scenario in tables else []
    return globs + exact


@dataclass
class Tolerances:
    """Parsed tolerance file.

    Attributes
    ----------
    source : str
        Where it came from (file name).
    suite : str
        The suite it declares (informational).
    layers : dict
        Top-level layer and suite layers (``{"": top, "paper": ...}``).
    regression : dict
        ``rel``, ``abs`` and ``metrics`` for baseline comparisons.
    """

    source: str = "<defaults>"
    suite: str = ""
    layers: dict[str, dict[str, Any]] = field(default_factory=dict)
    regression: dict[str, Any] = field(default_factory=lambda: dict(DEFAULT_REGRESSION))

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "<dict>") -> Tolerances:
        """Validate a parsed TOML document.

        Raises
        ------
        ToleranceError
            Unknown keys, wrong types or values (message starts with ``source``).
        """
        try:
            return cls._from_dict(data, source)
        except ToleranceError as exc:
            raise ToleranceError(f"{source}: {exc}") from None

    @classmethod
    def _from_dict(cls, data: Mapping[str, Any], source: str) -> Tolerances:
        unknown = set(data) - _TOP_KEYS
        if unknown:
            raise ToleranceError(f"unknown key {sorted(unknown)[0]!r}; allowed: "
                                 f"{', '.join(sorted(_TOP_KEYS))}")
        fmt = data.get("format", 1)
        if fmt != 1:
            raise ToleranceError(f"format {fmt!r} is not supported (this rockbench reads 1)")
        suite = data.get("suite", "")
        if not isinstance(suite, str):
            raise ToleranceError("suite must be a string")
        layers = {"": _layer({k: v for k, v in data.items() if k in _LAYER_KEYS}, "")}
        suites = data.get("suites", {})
        if not isinstance(suites, Mapping):
            raise ToleranceError("suites must be a table of suite tables")
        for name, table in suites.items():
            if not isinstance(table, Mapping) or set(table) - _LAYER_KEYS:
                raise ToleranceError(f"suites.{name} may only hold "
                                     f"{', '.join(sorted(_LAYER_KEYS))}")
            layers[name] = _layer(table, f"suites.{name}.")
        reg = dict(DEFAULT_REGRESSION)
        raw = data.get("regression", {})
        if not isinstance(raw, Mapping):
            raise ToleranceError("regression must be a table")
        for key, value in raw.items():
            if key in ("rel", "abs"):
                if not (isinstance(value, (int, float)) and not isinstance(value, bool)
                        and math.isfinite(value) and value >= 0):
                    raise ToleranceError(f"regression.{key} must be a number >= 0, "
                                         f"got {value!r}")
                reg[key] = float(value)
            elif key == "metrics":
                if not (isinstance(value, list)
                        and all(isinstance(v, str) and v in METRICS for v in value)):
                    raise ToleranceError(f"regression.metrics must be a list of "
                                         f"{', '.join(METRICS)}")
                reg[key] = list(value)
            else:
                raise ToleranceError(f"regression: unknown key {key!r}; allowed: rel, abs, "
                                     "metrics")
        return cls(source=source, suite=suite, layers=layers, regression=reg)

    def for_cell(self, engine: str, scenario: str, suite: str = "") -> dict[str, Any]:
        """The limits for one cell: ``status`` rule plus metric → limit (None: unchecked)."""
        out: dict[str, Any] = {"status": "reference"}
        for key in ("", suite) if suite and suite in self.layers else ("",):
            layer = self.layers.get(key)
            if layer is None:
                continue
            out.update(layer["defaults"])
            for t in _matching(layer["scenarios"], scenario):
                out.update(t)
            eng = layer["engines"].get(engine)
            if eng is not None:
                out.update(eng["limits"])
                for t in _matching(eng["scenarios"], scenario):
                    out.update(t)
        return out

    def engines(self) -> set[str]:
        """Engines named anywhere in the file."""
        return {e for layer in self.layers.values() for e in layer["engines"]}


def shipped_tolerances(name: str) -> Path | None:
    """The tolerance file shipped with rockbench for suite ``name`` (None if there is none)."""
    path = Path(__file__).resolve().parent.parent / "data" / f"tolerances-{name}.toml"
    return path if path.is_file() else None


def load_tolerances(path: str | Path) -> Tolerances:
    """Read and validate a tolerance file.

    ``path`` may also be the name of a shipped file's suite (``smoke``,
    ``paper``) when no such file exists in the current directory.

    Raises
    ------
    ToleranceError
        Unreadable file, malformed TOML, unknown keys or invalid values; the
        message starts with the file name.
    """
    path = Path(path)
    if not path.exists() and path.suffix != ".toml":
        path = shipped_tolerances(str(path)) or path
    data = read_toml(path, ToleranceError, "tolerance file")
    return Tolerances.from_dict(data, str(path))
