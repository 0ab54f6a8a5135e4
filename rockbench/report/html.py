"""Self-contained HTML rendering of a report: inline CSS, figures embedded as base64.

The page opens from the file system in any browser, with no server and no
JavaScript. Figures are also written beside it (``figures/*.png``).
"""

from __future__ import annotations

import base64
import html
from collections.abc import Sequence
from pathlib import Path

from rockbench.report.document import (
    Bullets,
    Document,
    FigureItem,
    render_document_markdown,
    status_legend,
)
from rockbench.report.tables import Table, render_html

__all__ = ["render_document_html", "CSS"]

CSS = """
:root { --ink:#1d2430; --muted:#5b6575; --rule:#d5dae1; --bg:#ffffff; --band:#f4f6f9;
        --accent:#1f4e79; }
* { box-sizing: border-box; }
body { margin:0; background:var(--bg); color:var(--ink);
       font: 15px/1.5 "Segoe UI", "Helvetica Neue", Arial, sans-serif; }
main { max-width: 1400px; margin: 0 auto; padding: 28px 32px 60px; }
h1 { font-size: 26px; margin: 0 0 4px; color: var(--accent); }
h2 { font-size: 20px; margin: 42px 0 10px; padding-bottom: 4px;
     border-bottom: 2px solid var(--accent); color: var(--accent); }
p { margin: 8px 0; max-width: 80ch; }
.subtitle { color: var(--muted); margin-bottom: 18px; }
dl.meta { display: grid; grid-template-columns: max-content 1fr; gap: 3px 18px;
          background: var(--band); border: 1px solid var(--rule); border-radius: 6px;
          padding: 12px 16px; font-size: 13.5px; }
dl.meta dt { font-weight: 600; color: var(--muted); }
dl.meta dd { margin: 0; word-break: break-word; }
dl.meta code { font-size: 12.5px; }
nav.toc { margin: 18px 0; font-size: 14px; }
nav.toc ol { margin: 4px 0; padding-left: 22px; columns: 2; }
figure { margin: 22px 0; }
figure.table figcaption, figure.plot figcaption { font-size: 13.5px; color: var(--ink);
          margin-bottom: 6px; max-width: 100ch; }
figure.plot figcaption { margin-top: 6px; }
figure.plot img { max-width: 100%; height: auto; border: 1px solid var(--rule); }
.scroll { overflow-x: auto; }
table { border-collapse: collapse; font-size: 13px; font-variant-numeric: tabular-nums; }
th, td { padding: 4px 9px; border-bottom: 1px solid var(--rule); text-align: right;
         white-space: nowrap; }
thead th { background: var(--band); border-bottom: 2px solid #9aa4b2; font-weight: 600;
           text-align: center; }
thead th.group { border-bottom: 1px solid #9aa4b2; }
tbody th, td.first { text-align: left; font-weight: 600; }
tbody tr:nth-child(even) { background: #fafbfc; }
td.ref { background: #eef2f7; }
td.paper { color: #4a5566; font-style: italic; background: #fbf8ef; }
td.overturned { background: #fff1d6; color: #8a5300; font-weight: 600; }
td.unstable, td.crashed, td.timeout { background: #fde2e1; color: #a11d1d; font-weight: 600; }
td.unsupported { background: #eceef1; color: #5b6575; }
sup a { color: inherit; text-decoration: none; font-size: 10px; }
ol.notes { font-size: 12.5px; color: var(--muted); margin: 6px 0 0; padding-left: 22px; }
table.legend td { text-align: left; white-space: normal; }
.bullets { background: #fbf8ef; border-left: 4px solid #d8c38a; padding: 8px 14px;
           font-size: 14px; }
.bullets ul { margin: 4px 0; }
footer { margin-top: 48px; font-size: 13px; color: var(--muted);
         border-top: 1px solid var(--rule); padding-top: 10px; }
"""


def _figure_html(item: FigureItem, root: Path, number: int, embed: bool) -> str:
    e = html.escape
    src = item.path
    if embed:
        data = (root / item.path).read_bytes()
        src = "data:image/png;base64," + base64.b64encode(data).decode("ascii")
    title = f"{item.title}. " if item.title else ""
    return (f'<figure class="plot"><img src="{src}" alt="{e(item.title or item.caption)}" '
            f'loading="lazy"><figcaption><b>Figure {number}.</b> {e(title)}{e(item.caption)} '
            f'<a href="{e(item.path)}">PNG</a></figcaption></figure>')


def _legend_html() -> str:
    rows = "".join(
        f'<tr><td class="{s if s != "ok" else ""}">{html.escape(m)}</td>'
        f"<td><b>{s}</b></td><td>{html.escape(meaning)}</td></tr>"
        for s, m, meaning in status_legend())
    return ('<figure class="table" id="legend"><figcaption><b>Status legend.</b> How runs '
            "that did not finish normally appear in every table (hover a marked cell for its "
            "reason; numbered notes under each table give it too) and on every chart "
            "(crosses).</figcaption><table class=\"legend\"><thead><tr><th>cell</th>"
            f"<th>status</th><th>meaning</th></tr></thead><tbody>{rows}</tbody></table>"
            "</figure>")


def render_document_html(doc: Document, root: Path, *, embed: bool = True,
                         data: Sequence[str] = ()) -> str:
    """The report as one HTML page.

    Parameters
    ----------
    doc : Document
        The report.
    root : Path
        The report directory (figure paths are relative to it).
    embed : bool
        Embed the PNGs as base64 data (default) rather than linking them.

    Returns
    -------
    str
        The HTML text.
    """
    e = html.escape
    out = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
           '<meta name="viewport" content="width=device-width, initial-scale=1">',
           f"<title>{e(doc.title)}</title><style>{CSS}</style></head><body><main>",
           f"<h1>{e(doc.title)}</h1>",
           f'<div class="subtitle">Reproducing and generalising {e(doc.citation)}</div>',
           '<dl class="meta">']
    for k, v in doc.header:
        val = f"<code>{e(v)}</code>" if k.lower() in ("command", "output") else e(v)
        out.append(f"<dt>{e(k)}</dt><dd>{val}</dd>")
    out.append("</dl>")
    out += [f"<p>{e(p)}</p>" for p in doc.intro]
    out.append('<nav class="toc"><b>Contents</b><ol>' + "".join(
        f'<li><a href="#{e(s.key)}">{e(s.title)}</a></li>' for s in doc.sections)
        + "</ol></nav>")
    out.append(_legend_html())
    fig_no = 0
    for sec in doc.sections:
        out.append(f'<section id="{e(sec.key)}"><h2>{e(sec.title)}</h2>')
        out += [f"<p>{e(p)}</p>" for p in sec.paragraphs]
        for item in sec.items:
            if isinstance(item, Table):
                out.append(render_html(item))
            elif isinstance(item, FigureItem):
                fig_no += 1
                out.append(_figure_html(item, root, fig_no, embed))
            elif isinstance(item, Bullets):
                out.append(f'<div class="bullets"><b>{e(item.title)}</b><ul>'
                           + "".join(f"<li>{e(x)}</li>" for x in item.items) + "</ul></div>")
        out.append("</section>")
    raw = ", ".join(f'<a href="{e(name)}">{e(name)}</a>' for name in data)
    out.append(f"<footer>Generated by rockbench. Reproduces and generalises: "
               f"{e(doc.citation)}. {f'Raw data: {raw}; t' if raw else 'T'}ables also in "
               f"<a href=\"report.md\">report.md</a>.</footer>")
    out.append("</main></body></html>")
    return "\n".join(out)


def write_document(doc: Document, out: Path, *, embed: bool = True,
                   data: Sequence[str] = ()) -> tuple[Path, Path]:
    """Write the report as ``out/index.html`` and ``out/report.md``.

    Parameters
    ----------
    doc : Document
        The report.
    out : Path
        Its directory (created); figure paths in ``doc`` are relative to it.
    embed : bool
        Embed the figures in the HTML page (else link them).
    data : sequence of str
        The report's raw-data files and folders (relative to ``out``), linked from the
        page's footer.

    Returns
    -------
    tuple of Path
        The HTML page and the Markdown file.
    """
    out.mkdir(parents=True, exist_ok=True)
    md = out / "report.md"
    md.write_text(render_document_markdown(doc), encoding="utf-8")
    index = out / "index.html"
    index.write_text(render_document_html(doc, out, embed=embed, data=data), encoding="utf-8")
    return index, md
