"""Report tables: a small neutral model rendered to Markdown and to HTML.

Non-ok runs are never blank: their cells carry a status marker (see
:data:`STATUS_MARKS`) and a numbered note with the reason under the table.
"""

from __future__ import annotations

import html
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

__all__ = ["Cell", "Table", "STATUS_MARKS", "STATUS_MEANING", "render_markdown",
           "render_html", "fmt_ratio", "fmt_error", "fmt_percent", "fmt_seconds", "fmt_factor"]

#: Marker shown in a table cell (and on charts) for every non-ok status.
STATUS_MARKS: dict[str, str] = {
    "overturned": "▲ overturned",
    "unstable": "✗ unstable",
    "crashed": "✗ crashed",
    "timeout": "✗ timeout",
    "unsupported": "⊘ unsupported",
}
#: What each status means (legend of the report).
STATUS_MEANING: dict[str, str] = {
    "ok": "the run finished; the number is its result",
    "overturned": "a block overturned (|θ| ≥ 90°): a physical outcome, shown instead of a number",
    "unstable": "NaN, explosion or energy gain in free motion: the simulation diverged",
    "crashed": "the engine raised an error or its process died",
    "timeout": "the run exceeded its wall-time limit and was killed",
    "unsupported": "the method cannot model this scenario (e.g. no analytic model for 3 blocks)",
}


def _finite(v: Any) -> bool:
    return isinstance(v, (int, float)) and math.isfinite(v)


def fmt_ratio(v: Any) -> str:
    """max |θ|/λ: three decimals, like the paper's tables."""
    return f"{v:.3f}" if _finite(v) else "–"


def fmt_error(v: Any) -> str:
    """A normalised error (max |Δθ|/λ): three significant digits."""
    return f"{v:.3g}" if _finite(v) else "–"


def fmt_percent(v: Any) -> str:
    """A signed relative error as a percentage with one decimal."""
    return f"{100.0 * v:+.1f} %" if _finite(v) else "–"


def fmt_seconds(v: Any) -> str:
    """A time in seconds: three significant digits (at least two decimals below 10 s)."""
    if not _finite(v):
        return "–"
    return f"{v:.2f}" if abs(v) < 10 else f"{v:.1f}"


def fmt_factor(v: Any) -> str:
    """A dimensionless factor (real-time factor): three significant digits."""
    return f"{v:.3g}" if _finite(v) else "–"


@dataclass
class Cell:
    """One table cell.

    Attributes
    ----------
    text : str
        What is shown.
    kind : str
        Style class: ``""`` (a number), a status (``overturned``, ``crashed``, ...),
        ``paper`` (a published value), ``ref`` (the analytic reference), ``head``
        (a row header).
    note : int
        Number of the footnote that explains the cell (0: none).
    title : str
        Tooltip in HTML (e.g. the exact value or the reason).
    """

    text: str
    kind: str = ""
    note: int = 0
    title: str = ""


@dataclass
class Table:
    """A table with an optional row of column groups, footnotes and a caption.

    Attributes
    ----------
    key : str
        Anchor id (unique in the report).
    title : str
        Title (with its number, e.g. "Table 3. ...").
    caption : str
        What the table shows and how to read it.
    columns : list of str
        Column headers.
    groups : list of (str, int)
        Spans over the columns (label, number of columns); empty for none.
    rows : list of list of Cell
        The body.
    notes : list of str
        Footnotes, referenced by ``Cell.note`` (1-based).
    """

    key: str
    title: str
    caption: str
    columns: list[str]
    groups: list[tuple[str, int]] = field(default_factory=list)
    rows: list[list[Cell]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def note(self, text: str) -> int:
        """Register a footnote (deduplicated) and return its number."""
        if text in self.notes:
            return self.notes.index(text) + 1
        self.notes.append(text)
        return len(self.notes)

    def add_row(self, cells: Sequence[Cell | str]) -> None:
        """Append a row (strings become plain cells)."""
        row = [c if isinstance(c, Cell) else Cell(str(c)) for c in cells]
        if len(row) != len(self.columns):
            raise ValueError(f"row has {len(row)} cells, table {self.key} has "
                             f"{len(self.columns)} columns")
        self.rows.append(row)

    def status_cell(self, status: str, reason: str, who: str = "") -> Cell:
        """The marked cell of a non-ok run, with its reason as a footnote."""
        mark = STATUS_MARKS.get(status, f"✗ {status}")
        text = f"{who}: {reason}" if who else reason
        return Cell(mark, kind=status, note=self.note(text or status), title=text)


def _md_escape(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _cell_md(c: Cell) -> str:
    text = _md_escape(c.text)
    if c.kind == "head" and text:
        text = f"**{text}**"
    elif c.kind == "paper" and text not in ("", "–"):
        text = f"*{text}*"
    if c.note:
        text += f" [{c.note}]"
    return text


def render_markdown(table: Table) -> str:
    """The table as GitHub-flavoured Markdown (title, caption, table, notes)."""
    cols = list(table.columns)
    if table.groups:
        labels = [g for g, n in table.groups for _ in range(n)]
        cols = [f"{g}: {c}" if g and c else (g or c) for g, c in zip(labels, cols, strict=True)]
    lines = [f"### {table.title}", "", table.caption, ""]
    lines.append("| " + " | ".join(_md_escape(c) for c in cols) + " |")
    lines.append("|" + "|".join(":---" if i == 0 else "---:" for i in range(len(cols))) + "|")
    for row in table.rows:
        lines.append("| " + " | ".join(_cell_md(c) for c in row) + " |")
    if table.notes:
        lines.append("")
        lines += [f"[{i}] {_md_escape(n)}  " for i, n in enumerate(table.notes, 1)]
    lines.append("")
    return "\n".join(lines)


def render_html(table: Table) -> str:
    """The table as an HTML ``<figure>`` with caption, table and notes."""
    e = html.escape
    out = [f'<figure class="table" id="{e(table.key)}">',
           f"<figcaption><b>{e(table.title)}.</b> {e(table.caption)}</figcaption>",
           '<div class="scroll"><table>', "<thead>"]
    if table.groups:
        out.append("<tr>" + "".join(
            f'<th colspan="{n}" class="group">{e(g)}</th>' if n > 1 else f"<th>{e(g)}</th>"
            for g, n in table.groups) + "</tr>")
    out.append("<tr>" + "".join(f"<th>{e(c)}</th>" for c in table.columns) + "</tr>")
    out.append("</thead><tbody>")
    for row in table.rows:
        cells = []
        for i, c in enumerate(row):
            cls = [c.kind] if c.kind else []
            if i == 0:
                cls.append("first")
            attrs = f' class="{" ".join(cls)}"' if cls else ""
            if c.title:
                attrs += f' title="{e(c.title)}"'
            note = f'<sup><a href="#{e(table.key)}-n{c.note}">{c.note}</a></sup>' if c.note else ""
            tag = "th" if c.kind == "head" else "td"
            cells.append(f"<{tag}{attrs}>{e(c.text)}{note}</{tag}>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</tbody></table></div>")
    if table.notes:
        out.append('<ol class="notes">' + "".join(
            f'<li id="{e(table.key)}-n{i}">{e(n)}</li>' for i, n in enumerate(table.notes, 1))
            + "</ol>")
    out.append("</figure>")
    return "\n".join(out)
