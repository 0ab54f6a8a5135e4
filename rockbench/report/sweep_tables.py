"""Tables of a settings sweep: the CSV of every point and the plain-text table per engine."""

from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import Any

from rockbench.studies.sweep import ERROR_METRICS, SweepResult

__all__ = ["write_table", "format_table"]


def _none(v: float | None) -> Any:
    return "" if v is None else v


def _value(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def write_table(result: SweepResult, path: str | Path) -> Path:
    """Write every point as CSV (engine, knobs, status, errors, cost, times, drift, message).

    ``cost`` is the point's cost (CPU time if measured, else wall time), in s.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    knobs = list(dict.fromkeys(k for g in result.grid.values() for k in g))
    cols = ["engine", *knobs, "status", *ERROR_METRICS, "cost", "wall_time", "cpu_time",
            "realtime_factor", "slide", "drift", "message"]
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(cols)
        for p in result.points:
            m = p.metrics
            w.writerow([p.engine, *[p.knobs.get(k, "") for k in knobs], p.status.value,
                        *[_none(m.value(name)) for name in ERROR_METRICS],
                        "" if math.isnan(p.cost) else p.cost, m.wall_time, _none(m.cpu_time),
                        _none(m.realtime_factor), _none(m.slide), int(p.drift), p.message])
    return path


def format_table(result: SweepResult, target: float | None = None) -> str:
    """Plain-text table of the points per engine, cheapest first."""
    lines = []
    m = result.metric
    for engine in result.engines:
        pts = sorted(result.engine_points(engine), key=lambda p: p.cost)
        knobs = list(result.grid[engine])
        head = [*knobs, "status", m, "cost (s)", "note"]
        rows = []
        for p in pts:
            note = "drift" if p.drift else ("unlike reference" if p.kind() == "mismatch"
                                            else "")
            if target is not None and p.meets(target, m):
                note = "meets target"
            if not p.status.completed:
                note = p.message[:60]
            err = p.error(m)
            rows.append([*[_value(p.knobs[k]) for k in knobs], p.status.value,
                         "-" if not math.isfinite(err) else f"{err:.4g}",
                         f"{p.cost:.3f}", note])
        widths = [max(len(str(r[i])) for r in [head, *rows]) for i in range(len(head))]
        lines.append(f"{engine} on {result.scenario.name}:")
        for r in [head, ["-" * w for w in widths], *rows]:
            lines.append("  " + "  ".join(str(x).ljust(w) for x, w in
                                          zip(r, widths, strict=True)).rstrip())
        lines.append("")
    return "\n".join(lines)

