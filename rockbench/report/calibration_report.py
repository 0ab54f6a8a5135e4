"""A calibration in a report: the table of settings, its CSV and the error-against-cost chart.

:func:`calibration_table` is the table of every setting a calibration tried
(:class:`~rockbench.studies.calibration.Calibration`): its knob values, the
worst errors over the cases, how many cases end as the reference does, the cost
in CPU seconds per simulated second, whether it lies on the Pareto front and
whether it meets the tolerances (the cheapest that does is marked).
:func:`calibration_figure` draws error against cost (log axes): each knob's
ladder through the starting preset, the front, the named presets and the
cheapest setting meeting the tolerances. :func:`write_calibration_report`
writes ``report.md``, ``index.html``, ``calibration.csv`` and
``figures/calibration.png``; the same table renders in the documentation
(``.. calibration-table::``) and on the terminal (:func:`format_calibration`).
"""

from __future__ import annotations

import csv
import datetime as _dt
import math
import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter

from rockbench import provenance
from rockbench.report.document import (
    Document,
    FigureItem,
    Section,
    cpu_model,
)
from rockbench.report.html import write_document
from rockbench.report.options import ReportOptions
from rockbench.report.paper import citation
from rockbench.report.tables import Cell, Table, render_markdown
from rockbench.studies.calibration import Calibration, SettingResult
from rockbench.studies.calibration_plan import fmt_value

__all__ = ["calibration_table", "calibration_figure", "write_calibration_csv",
           "write_calibration_report", "format_calibration", "table_knobs", "METRIC_LABELS"]

#: How tables and axes name the error measures.
METRIC_LABELS = {"max_error": "worst max abs(θ − θ_ref)/λ",
                 "peak_error": "worst relative peak error",
                 "impact_time_error": "worst relative error of the first impact times"}
_CHEAPEST = "✓ cheapest"


def table_knobs(cal: Calibration) -> tuple[str, ...]:
    """The knobs shown as columns: those the search moved (or the explicit overrides set)."""
    return cal.plan.knobs or tuple(dict.fromkeys(k for s in cal.plan.settings
                                                 for k, _ in s.overrides))


def _name(r: SettingResult) -> str:
    s = r.setting
    also = [p for p in s.presets if p != s.label]
    return s.label + (f" (= {', '.join(also)})" if also else "")


def _percent(v: float | None) -> str:
    if v is None or not math.isfinite(v):
        return "–"
    return f"{100 * v:.2g} %" if abs(v) >= 1e-5 else "< 0.001 %"


def _number(v: float | None) -> str:
    return "–" if v is None or not math.isfinite(v) else f"{v:.3g}"


def calibration_table(cal: Calibration, number: int = 1) -> Table:
    """One row per setting, in plan order (see the module docstring).

    Parameters
    ----------
    cal : Calibration
        The calibration.
    number : int
        The table's number in its document.
    """
    knobs = table_knobs(cal)
    tol = cal.tolerances
    front = {id(r) for r in cal.front()}
    best = cal.cheapest()
    n = len(cal.cases)
    durations = ", ".join(f"{d:g}" for d in sorted({sc.duration for sc in cal.cases}))
    what = METRIC_LABELS[cal.metric].removeprefix("worst ")
    t = Table(
        "calibration",
        f"Table {number}. Calibration of {cal.engine}: {len(cal.results)} settings on "
        f"{n} case{'s' if n != 1 else ''}",
        f"Each setting is the preset {cal.plan.preset} with one knob moved by factors of 2 "
        "(rung +1: one step finer, −1: coarser), or another named preset. Errors are the "
        f"worst over the {n} cases ({durations} s) against the "
        "analytic reference; cost is CPU seconds per simulated second over all of them. "
        f"Pareto front: no other setting is both cheaper and has a smaller {what}. "
        f"Tolerances: max error ≤ {_tol(tol.max_error)} λ, peak error ≤ "
        f"{_tol(tol.peak_error, True)}, impact times ≤ {_tol(tol.impact_time_error, True)}, "
        "and every case ends as the reference does.",
        ["setting", *knobs, "rung", "worst max abs(θ − θ_ref)/λ", "worst peak error",
         "worst impact-time error", "ends as reference", "CPU s per simulated s",
         "Pareto front", "meets tolerances"])
    for r in cal.results:
        resolved = cal.plan.resolved(r.setting)
        impact = _percent(r.impact_time_error)
        if r.impacts_missing:
            impact = f"{impact}, {r.impacts_missing} missing"
        misses = r.misses(tol)
        if not misses:
            meets = Cell(_CHEAPEST if r is best else "✓")
        elif len(misses) == 1:
            meets = Cell(f"✗ {misses[0]}", "unstable")
        else:
            meets = Cell(f"✗ {misses[0]} …", "unstable",
                         t.note(f"{r.setting.label}: {'; '.join(misses)}"))
        t.add_row([Cell(_name(r), kind="head"), *[fmt_value(getattr(resolved, k)) for k in knobs],
                   r.setting.rung, _number(r.max_error), _percent(r.peak_error), impact,
                   f"{r.agreements}/{r.cases}", _number(r.cost),
                   "✓" if id(r) in front else "", meets])
    return t


def _tol(v: float | None, percent: bool = False) -> str:
    if v is None:
        return "(not judged)"
    return f"{100 * v:g} %" if percent else f"{v:g}"


def format_calibration(cal: Calibration) -> str:
    """The table as Markdown, with a line naming the cheapest setting meeting the tolerances."""
    best = cal.cheapest()
    line = ("No setting meets the tolerances." if best is None else
            f"Cheapest setting meeting the tolerances: {_name(best)} "
            f"({best.cost:.3g} CPU s per simulated s).")
    return render_markdown(calibration_table(cal)) + "\n" + line + "\n"


def _atomic(path: Path, write: Callable[[Any], None]) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        with os.fdopen(fd, "w", newline="", encoding="utf-8") as f:
            write(f)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def write_calibration_csv(cal: Calibration, path: Path) -> Path:
    """Every setting as a CSV row: the setting, every searched knob's value, the errors,
    agreement, cost, front and tolerance verdict (written atomically)."""
    knobs = table_knobs(cal)
    front = {id(r) for r in cal.front()}
    best = cal.cheapest()

    def write(f: Any) -> None:
        w = csv.writer(f)
        w.writerow(["engine", "setting", "preset", "knob", "level", "presets", *knobs,
                    "max_error", "peak_error", "impact_time_error", "impacts_missing",
                    "agreements", "cases", "cpu_time", "cost", "pareto_front",
                    "meets_tolerances", "cheapest", "misses"])
        for r in cal.results:
            s, resolved = r.setting, cal.plan.resolved(r.setting)
            w.writerow([cal.engine, s.label, s.preset, s.knob, s.rung, " ".join(s.presets),
                        *[getattr(resolved, k) for k in knobs],
                        *["" if v is None else f"{v:.6g}" for v in
                          (r.max_error, r.peak_error, r.impact_time_error)],
                        r.impacts_missing, r.agreements, r.cases, f"{r.cpu_time:.6g}",
                        "" if math.isnan(r.cost) else f"{r.cost:.6g}", int(id(r) in front),
                        int(r.meets(cal.tolerances)), int(r is best),
                        "; ".join(r.misses(cal.tolerances))])

    return _atomic(Path(path), write)


def calibration_figure(cal: Calibration, path: Path, metric: str | None = None) -> Path:
    """Error (``metric``, default the calibration's) against cost, both on log axes.

    Each searched knob's rungs are joined through the starting preset; the named
    presets are stars with their names; the Pareto front is a black step line;
    the cheapest setting meeting the tolerances is ringed and the metric's
    tolerance is a dashed line. Settings without a finite error (a failed or
    unmeasured case) are left out and counted in the title.
    """
    m = metric or cal.metric
    fig = Figure(figsize=(7.5, 4.8))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()

    def xy(r: SettingResult) -> tuple[float, float] | None:
        e, c = r.error(m), r.cost
        ok = math.isfinite(e) and e > 0 and math.isfinite(c) and c > 0
        return (c, e) if ok else None

    start = cal.start
    cycle = ["tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown",
             "tab:pink", "tab:olive", "tab:cyan"]
    for i, knob in enumerate(cal.plan.knobs):
        rungs = [r for r in cal.results if r.setting.knob == knob]
        ladder = sorted([*rungs, start], key=lambda r: r.setting.level if r is not start else 0)
        pts = [p for r in ladder if (p := xy(r)) is not None]
        if pts:
            colour = cycle[i % len(cycle)]
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "-o", color=colour, ms=5,
                    lw=1.2, alpha=0.85, label=knob, zorder=2)
    for r in cal.results:
        p = xy(r)
        if p is None or not r.setting.presets:
            continue
        ax.plot(*p, marker="*", ms=14, color="black", mfc="gold", ls="", zorder=4)
        ax.annotate(", ".join(r.setting.presets), p, textcoords="offset points",
                    xytext=(7, 5), fontsize=9)
    front = [p for r in cal.front(m) if (p := xy(r)) is not None]
    if front:
        ax.step([p[0] for p in front], [p[1] for p in front], where="post", color="black",
                lw=1.0, ls="-", alpha=0.6, zorder=1, label="Pareto front")
    best = cal.cheapest()
    if best is not None and (p := xy(best)) is not None:
        ax.plot(*p, marker="o", ms=20, mfc="none", mec="green", mew=2, ls="", zorder=5,
                label="cheapest meeting the tolerances")
    tol = getattr(cal.tolerances, m)
    if tol is not None:
        ax.axhline(tol, color="green", ls="--", lw=1, label=f"tolerance {tol:g}")
    ax.plot([], [], marker="*", ms=12, color="black", mfc="gold", ls="", label="named preset")
    left = sum(xy(r) is None for r in cal.results)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("cost: CPU s per simulated s")
    ax.set_ylabel(METRIC_LABELS[m].replace("abs(θ − θ_ref)", "|θ − θ_ref|"))
    ax.set_title(f"{cal.engine}: error against cost on {len(cal.cases)} cases"
                 + (f" ({left} setting{'s' if left != 1 else ''} without a finite error "
                    "left out)" if left else ""), fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    return path


def write_calibration_report(cal: Calibration, options: ReportOptions) -> list[Path]:
    """``index.html``, ``report.md``, ``calibration.csv`` and ``figures/calibration.png``."""
    out = Path(options.out)
    fig = calibration_figure(cal, out / "figures" / "calibration.png")
    best = cal.cheapest()
    settings = Section("settings", "Settings against the analytic reference")
    settings.paragraphs.append(
        f"**Use {_name(best)}**: the cheapest setting meeting the tolerances "
        f"({best.cost:.3g} CPU s per simulated s)." if best is not None else
        "**No setting meets the tolerances.**")
    settings.items.append(calibration_table(cal))
    settings.items.append(FigureItem(
        fig.relative_to(out).as_posix(),
        "Error against cost: each knob's rungs joined through the starting preset, the named "
        "presets (stars), the Pareto front (black steps) and the cheapest setting meeting "
        "the tolerances (green ring).", f"{cal.engine}: error against cost"))
    search = Section("search", "The search")
    search.paragraphs.append(
        f"From preset {cal.plan.preset}, {cal.plan.levels} rung(s) either side of each knob "
        f"the engine declares ({', '.join(cal.plan.knobs) or 'none moved'}); cases: "
        + ", ".join(f"{sc.name} ({sc.duration:g} s)" for sc in cal.cases) + ".")
    if cal.plan.skipped:
        search.paragraphs.append("Left out: " + "; ".join(
            f"{s.knob}: {s.reason}" for s in cal.plan.skipped) + ".")
    runs = (f"{cal.ran} run now, {cal.reused} taken from the results store"
            if not cal.made_by else
            f"{cal.reused} taken from the results store, made by {', '.join(cal.made_by)}")
    doc = Document(
        title=f"rockbench calibration: {cal.engine}",
        header=[("Date", _dt.datetime.now().isoformat(timespec="seconds")),
                ("Wall time", f"{cal.wall_time:.1f} s"), ("Machine", cpu_model()),
                ("rockbench", provenance.describe()),
                ("Engine", f"{cal.engine} {cal.engine_version}".strip()), ("Runs", runs),
                ("Command", options.command or "(Python API)")],
        intro=["Which settings of this engine reproduce the analytic reference, and at "
               "what cost? Every setting the search tried, on every calibration case."],
        sections=[settings, search], citation=citation())
    index, md = write_document(doc, out, embed=options.embed_figures,
                               data=("calibration.csv",))
    return [index, md, write_calibration_csv(cal, out / "calibration.csv"), fig]
