"""The matrix grid: engines as columns, one cell per scenario, then failures and a summary."""

from __future__ import annotations

from typing import Any

from rockbench.studies.matrix import FAIL, PASS, REGRESSION, SKIP, Cell, MatrixResult
from rockbench.trajectory import Status

__all__ = ["format_grid", "grid_table"]

_MARK = {PASS: "PASS", FAIL: "FAIL", REGRESSION: "REGR", SKIP: "skip"}
_STYLE = {PASS: "green", FAIL: "bold red", REGRESSION: "bold magenta", SKIP: "dim"}


def _cell_text(c: Cell | None) -> str:
    if c is None:
        return "-"
    if c.outcome == SKIP:
        return "skip"
    if not c.status.completed:
        return f"{_MARK[c.outcome]} {c.status.value}"
    err = c.metrics.max_error
    val = f"{err:.4f}" if err is not None else c.status.value
    if c.status is Status.OVERTURNED and err is not None:
        val += " ovt"
    return f"{_MARK[c.outcome]} {val}" + ("*" if c.reused else "")


def _legend(result: MatrixResult) -> list[str]:
    lines = ["cells: outcome and max |Δθ|/λ against the analytic reference"
             + (" (* = reused from the store)" if any(c.reused for c in result.cells.values())
                else "")]
    for name, note in result.reference_notes.items():
        lines.append(f"note: {name}: {note}; " + (
            "only the status is checked" if name in result.no_model
            else "its cells fail unless their tolerance checks the status only"))
    bad = [c for c in result.cells.values() if c.outcome in (FAIL, REGRESSION)]
    for c in sorted(bad, key=lambda c: (c.engine, c.scenario)):
        lines.append(f"{_MARK[c.outcome]} {c.engine} × {c.scenario}: {'; '.join(c.reasons)}")
    lines.append(result.summary())
    return lines


def format_grid(result: MatrixResult) -> str:
    """The grid as plain text (engines as columns), then failures and a summary."""
    head = ["scenario", *result.engines]
    rows = [[s, *[_cell_text(result.cells.get((s, e))) for e in result.engines]]
            for s in result.scenarios]
    widths = [max(len(r[i]) for r in [head, *rows]) for i in range(len(head))]
    lines = [f"rockbench matrix {result.suite}  (tolerances: {result.tolerances}"
             + (f", baseline: {result.baseline})" if result.baseline else ")")]
    for r in [head, ["-" * w for w in widths], *rows]:
        lines.append("  ".join(x.ljust(w) for x, w in zip(r, widths, strict=True)).rstrip())
    return "\n".join(lines + [""] + _legend(result)) + "\n"


def grid_table(result: MatrixResult) -> tuple[Any, list[str]]:
    """The grid as a coloured :class:`rich.table.Table`, plus the legend lines."""
    from rich.table import Table
    from rich.text import Text

    table = Table(title=f"rockbench matrix {result.suite}",
                  caption=f"tolerances: {result.tolerances}"
                  + (f"; baseline: {result.baseline}" if result.baseline else ""))
    table.add_column("scenario")
    for e in result.engines:
        table.add_column(e, justify="center")
    for s in result.scenarios:
        row = [Text(s)]
        for e in result.engines:
            c = result.cells.get((s, e))
            row.append(Text(_cell_text(c), style=_STYLE[c.outcome] if c else "dim"))
        table.add_row(*row)
    return table, _legend(result)
