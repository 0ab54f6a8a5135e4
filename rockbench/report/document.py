"""The report as a document: header, sections of paragraphs, tables and figures.

Rendered to Markdown here (``report.md``) and to HTML by :mod:`rockbench.report.html`,
so both files hold the same tables.
"""

from __future__ import annotations

import datetime as _dt
import os
import platform
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from rockbench import provenance
from rockbench.report.tables import STATUS_MARKS, STATUS_MEANING, Table, render_markdown

__all__ = ["FigureItem", "Bullets", "Section", "Document", "render_document_markdown",
           "cpu_model", "status_legend", "report_date", "run_header"]


@dataclass
class FigureItem:
    """A PNG with its caption (path relative to the report directory)."""

    path: str
    caption: str
    title: str = ""


@dataclass
class Bullets:
    """A titled list of points (e.g. the paper's published findings)."""

    title: str
    items: list[str]


@dataclass
class Section:
    """A report section: an anchor, a title, paragraphs, then tables/figures/bullets."""

    key: str
    title: str
    paragraphs: list[str] = field(default_factory=list)
    items: list[Table | FigureItem | Bullets] = field(default_factory=list)


@dataclass
class Document:
    """The whole report.

    Attributes
    ----------
    title : str
        Page title.
    header : list of (str, str)
        Metadata shown at the top (date, wall time, machine, versions, command).
    intro : list of str
        Paragraphs under the header.
    sections : list of Section
        The body.
    citation : str
        The paper reproduced.
    """

    title: str
    header: list[tuple[str, str]]
    intro: list[str]
    sections: list[Section]
    citation: str


def cpu_model() -> str:
    """CPU model name (from /proc/cpuinfo on Linux, else :mod:`platform`) and core count."""
    name = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                name = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    name = name or platform.processor() or platform.machine() or "unknown CPU"
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:
        cores = os.cpu_count() or 1
    return f"{name}, {cores} usable core{'s' if cores != 1 else ''}"


def python_version() -> str:
    """``3.11.7 (CPython)`` and the platform."""
    return f"{platform.python_version()} ({platform.python_implementation()}), " \
           f"{platform.system()} {platform.release()}"


def report_date() -> str:
    """Now, as the header's date (local time with its zone)."""
    return _dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M:%S %Z")


def run_header(wall_time: float, jobs: int, versions: Mapping[str, str],
               command: str) -> list[tuple[str, str]]:
    """The header rows that say how a study ran: wall time and workers, the code, Python,
    the machine, the engines' versions and the command (empty: the Python API)."""
    return [
        ("Wall time", f"{wall_time:.1f} s on {jobs} worker(s)"),
        ("rockbench", provenance.describe()),
        ("Python", python_version()),
        ("Machine (CPU)", cpu_model()),
        ("Engine versions", ", ".join(f"{e} {v}" for e, v in versions.items())),
        ("Command", command or "(Python API)"),
    ]


def status_legend() -> list[tuple[str, str, str]]:
    """(status, marker, meaning) for the legend."""
    out = [("ok", "number", STATUS_MEANING["ok"])]
    out += [(k, STATUS_MARKS[k], STATUS_MEANING[k]) for k in STATUS_MARKS]
    return out


def render_document_markdown(doc: Document) -> str:
    """The report as Markdown (figures linked relative to the report directory)."""
    lines = [f"# {doc.title}", ""]
    for k, v in doc.header:
        lines.append(f"- **{k}:** {v}")
    lines.append("")
    lines += [p + "\n" for p in doc.intro]
    lines.append("**Status legend.** " + "; ".join(
        f"{m} = {s}: {meaning}" for s, m, meaning in status_legend()) + ".")
    lines.append("")
    for sec in doc.sections:
        lines += [f"## {sec.title}", ""]
        lines += [p + "\n" for p in sec.paragraphs]
        for item in sec.items:
            if isinstance(item, Table):
                lines.append(render_markdown(item))
            elif isinstance(item, FigureItem):
                lines += [f"![{item.title or item.caption}]({item.path})", "",
                          f"*{item.title + '. ' if item.title else ''}{item.caption}*", ""]
            else:
                lines += [f"**{item.title}**", ""] + [f"- {x}" for x in item.items] + [""]
    lines += ["---", "", f"Reproduces and generalises: {doc.citation}.", ""]
    return "\n".join(lines)
