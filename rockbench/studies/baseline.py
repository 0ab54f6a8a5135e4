"""Matrix baselines: the typed metrics of an earlier matrix, to detect regressions.

A baseline is a JSON file (``rockbench matrix --write-baseline FILE``)::

    {"format": 2, "suite": "smoke", "rockbench_version": "...", "created": "...",
     "cells": {"mujoco/free-b2-0.5": {"status": "ok", "settings": {...},
                                      "metrics": {<RunMetrics.to_json()>}}}}

Reading validates every field's type against :class:`~rockbench.evaluation.RunMetrics`:
a string where a number belongs is an error naming the file and the field,
never coerced.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from rockbench import provenance
from rockbench.errors import RockbenchError
from rockbench.evaluation import RunMetrics
from rockbench.store import jsonable
from rockbench.trajectory import Status

__all__ = ["Baseline", "BaselineCell", "BaselineError", "load_baseline", "write_baseline",
           "baseline_data", "FORMAT"]

#: Format written (and the only one read) by this rockbench.
FORMAT = 2
_STATUSES = {s.value for s in Status}


class BaselineError(RockbenchError, ValueError):
    """A baseline file is unreadable or malformed."""


@dataclass(frozen=True)
class BaselineCell:
    """One cell of a baseline: how the run ended, its settings and its metrics."""

    status: Status
    settings: dict[str, Any]
    metrics: RunMetrics


@dataclass(frozen=True)
class Baseline:
    """A baseline file: ``engine/scenario`` → :class:`BaselineCell`."""

    source: str
    suite: str
    cells: dict[str, BaselineCell] = field(default_factory=dict)


def baseline_data(cells: Mapping[str, tuple[Status, Mapping[str, Any], RunMetrics]],
                  suite: str) -> dict[str, Any]:
    """The JSON document of a baseline (``key → (status, settings, metrics)``)."""
    return {
        "format": FORMAT,
        "suite": suite,
        "rockbench_version": provenance.code_version(),
        "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "cells": {k: {"status": s.value, "settings": jsonable(dict(st)),
                      "metrics": m.to_json()}
                  for k, (s, st, m) in sorted(cells.items())},
    }


def write_baseline(data: Mapping[str, Any], path: str | Path) -> Path:
    """Write a baseline document (:func:`baseline_data`) atomically (write, then rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, "w") as fh:
            fh.write(json.dumps(jsonable(data), indent=1) + "\n")
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


# ---------------------------------------------------------------------- reading
def _metrics(data: Any, where: str) -> RunMetrics:
    try:
        return RunMetrics.from_json(data, where=where)
    except ValueError as exc:
        raise BaselineError(str(exc)) from None


def load_baseline(path: str | Path) -> Baseline:
    """Read and validate a baseline written by :func:`write_baseline`.

    Raises
    ------
    BaselineError
        Unreadable, not UTF-8 JSON, not a rockbench baseline of this format, or
        a field of the wrong type (the message names the file and the field).
    """
    path = Path(path)
    try:
        data = json.loads(path.read_bytes().decode("utf-8"))
    except OSError as exc:
        raise BaselineError(f"{path}: cannot read baseline ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise BaselineError(f"{path}: not a baseline (not UTF-8 text)") from None
    except (json.JSONDecodeError, RecursionError) as exc:
        raise BaselineError(f"{path}: not JSON ({exc})") from None
    if not (isinstance(data, dict) and isinstance(data.get("cells"), dict)):
        raise BaselineError(f"{path}: not a rockbench baseline (needs format = {FORMAT} "
                            "and cells)")
    if data.get("format") != FORMAT:
        raise BaselineError(f"{path}: baseline format {data.get('format')!r} is not "
                            f"supported (this rockbench reads {FORMAT}); write a new one "
                            "with --write-baseline")
    suite = data.get("suite", "")
    if not isinstance(suite, str):
        raise BaselineError(f"{path}: suite must be a string, got {suite!r}")
    cells = {}
    for key, cell in data["cells"].items():
        where = f"{path}: cell {key!r}"
        if not isinstance(cell, dict) or cell.get("status") not in _STATUSES:
            raise BaselineError(f"{where} needs a valid status and metrics")
        settings = cell.get("settings", {})
        if not isinstance(settings, dict):
            raise BaselineError(f"{where}: settings must be a table")
        try:
            metrics = _metrics(cell.get("metrics"), f"{where}: metrics")
        except BaselineError:
            raise
        except ValueError as exc:
            raise BaselineError(f"{where}: metrics: {exc}") from None
        cells[key] = BaselineCell(Status(cell["status"]), settings, metrics)
    return Baseline(str(path), suite, cells)
