"""``results.csv`` of a comparison: one row per run, written as runs finish.

The columns are laid out from :class:`~rockbench.evaluation.RunResult` here and
nowhere else; :func:`read_results` reads a file back (text columns as str,
numbers as float, NaN where empty).
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from rockbench.analytic import uplift_ratio
from rockbench.evaluation import N_IMPACTS, RunResult
from rockbench.report.groups import scenario_group

__all__ = ["result_columns", "result_row", "ResultsWriter", "read_results"]


def result_columns(max_blocks: int) -> list[str]:
    """Column names of ``results.csv`` for stacks of up to ``max_blocks`` blocks."""
    blocks = range(1, max_blocks + 1)
    return [
        "scenario", "group", "method", "engine", "preset", "variation", "reference",
        "status", "message", "n_blocks", "critical_angle", "uplift_ratio", "duration",
        "simulated_time",
        *[f"peak_ratio_{i}" for i in blocks],
        "max_error", "max_error_early",
        *[f"peak_error_{i}" for i in blocks],
        *[f"impact_error_{k}" for k in range(1, N_IMPACTS + 1)],
        "horizon", "time_to_rest", "reference_time_to_rest", "error_note",
        "wall_time", "cpu_time", "time_per_simulated_second", "realtime_factor",
        "slide", "max_wobble", "max_roll", "max_twist",
        "settings_hash", "scenario_hash", "engine_version", "trajectory",
    ]


def _at(values: tuple[Any, ...], i: int) -> Any:
    return values[i] if i < len(values) else None


def result_row(r: RunResult) -> dict[str, Any]:
    """The CSV row of one run (None where undefined)."""
    m, s = r.metrics, r.scenario
    row: dict[str, Any] = {
        "scenario": s.name, "group": scenario_group(s), "method": r.method.label,
        "engine": r.method.engine, "preset": r.method.preset, "variation": r.method.variation,
        "reference": int(r.method.is_reference), "status": m.status.value,
        "message": m.message, "n_blocks": m.n_blocks, "critical_angle": m.critical_angle,
        "uplift_ratio": None if s.motion.is_free else uplift_ratio(s),
        "duration": m.duration, "simulated_time": m.simulated_time,
        "max_error": m.max_error, "max_error_early": m.max_error_early, "horizon": m.horizon,
        "time_to_rest": m.time_to_rest, "reference_time_to_rest": m.reference_time_to_rest,
        "error_note": m.error_note, "wall_time": m.wall_time, "cpu_time": m.cpu_time,
        "time_per_simulated_second": m.time_per_simulated_second,
        "realtime_factor": m.realtime_factor, "slide": m.slide, "max_wobble": m.max_wobble,
        "max_roll": m.max_roll, "max_twist": m.max_twist,
        "settings_hash": m.settings_hash, "scenario_hash": m.scenario_hash,
        "engine_version": m.engine_version, "trajectory": r.trajectory,
    }
    for i in range(m.n_blocks):
        row[f"peak_ratio_{i + 1}"] = _at(m.peaks, i)
        row[f"peak_error_{i + 1}"] = _at(m.peak_errors, i)
    for k in range(N_IMPACTS):
        row[f"impact_error_{k + 1}"] = _at(m.impact_time_errors, k)
    return row


def _cell(v: Any) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return ""
    return repr(v) if isinstance(v, float) else str(v)


class ResultsWriter:
    """Writes ``results.csv`` one row at a time (flushed), then rewrites it in order.

    Parameters
    ----------
    path : Path
        The CSV file (truncated when opened).
    max_blocks : int
        Largest number of blocks among the scenarios (fixes the columns).
    """

    def __init__(self, path: Path, max_blocks: int) -> None:
        self.path = Path(path)
        self.columns = result_columns(max_blocks)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._fh = self.path.open("w", newline="", encoding="utf-8")
        self._writer = csv.writer(self._fh)
        self._writer.writerow(self.columns)
        self._fh.flush()

    def append(self, result: RunResult) -> None:
        """Append one run's row and flush it to disk."""
        row = result_row(result)
        self._writer.writerow([_cell(row.get(c)) for c in self.columns])
        self._fh.flush()

    def close(self) -> None:
        """Close the file."""
        if not self._fh.closed:
            self._fh.close()

    def rewrite(self, results: Iterable[RunResult]) -> None:
        """Replace the file by these runs in the given order (atomically)."""
        self.close()
        tmp = self.path.with_suffix(".csv.tmp")
        with tmp.open("w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh)
            w.writerow(self.columns)
            for r in results:
                row = result_row(r)
                w.writerow([_cell(row.get(c)) for c in self.columns])
        os.replace(tmp, self.path)


_TEXT = {"scenario", "group", "method", "engine", "preset", "variation", "status", "message",
         "error_note", "settings_hash", "scenario_hash", "engine_version", "trajectory"}


def read_results(path: str | Path) -> list[dict[str, Any]]:
    """Read ``results.csv`` back: text columns as str, the others as float (NaN if empty)."""
    with Path(path).open(newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    return [{k: (v if k in _TEXT else float(v) if v != "" else math.nan)
             for k, v in r.items()} for r in rows]
