"""The restitution report: η asked, η obtained, η measured, per engine, preset and block.

:func:`write_report` renders a :class:`~rockbench.studies.restitution.RestitutionResult`:
a table per block of each method's effective η (mean over the impacts, their range,
the ratio to Housner's η, the cost), the published measurements beside Housner's η for
the same slenderness, a figure of η over Housner's η against λ, and
``restitution.csv`` with the η of every impact.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from rockbench.analytic.overturning import housner_eta
from rockbench.report.document import (
    Document,
    FigureItem,
    Section,
    report_date,
    run_header,
)
from rockbench.report.figures import method_styles
from rockbench.report.html import write_document
from rockbench.report.tables import Cell, Table
from rockbench.studies.restitution import EXPERIMENTS, RestitutionResult, RestitutionRow

__all__ = ["write_report", "restitution_figure", "CITATION"]

_DPI = 110
#: The effective η's definition and the tests it is compared with.
CITATION = ("G. W. Housner, \u201cThe behavior of inverted pendulum structures during "
            "earthquakes\u201d, Bull. Seismol. Soc. Am. 53(2), 403\u2013417 (1963); "
            "M. A. ElGawady, Q. Ma, J. W. Butterworth, J. Ingham, Earthquake Engng Struct. "
            "Dyn. 40(4), 375\u2013392 (2011)")


def _f(v: float, fmt: str = "{:.4f}") -> str:
    return fmt.format(v) if math.isfinite(v) else "–"


def restitution_figure(path: Path, result: RestitutionResult) -> Path:
    """η obtained / η Housner against λ: one marker per method (e = 0 runs; bars: the range
    over the impacts) and the published measurements as stars; where several bounce
    coefficients ran, a second panel of the ratio against the e asked."""
    styles = method_styles(result.methods)
    bounces = sorted({r.restitution for r in result.rows})
    fig = Figure(figsize=(11.0 if len(bounces) > 1 else 8.5, 4.8))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 2 if len(bounces) > 1 else 1, 1)
    ax.axhline(1.0, color="0.3", linewidth=1.0, label="Housner: η = 1 − 1.5 sin²λ")
    n = len(result.methods)
    lams = sorted({r.lam for r in result.rows})
    span = (max(lams) - min(lams)) or 0.1
    for k, m in enumerate(result.methods):
        rows = [r for r in result.rows if r.method == m.label and r.restitution == 0.0]
        got = [(r, r.impacts) for r in rows if r.impacts is not None]
        if not got:
            continue
        st = styles[m.label]
        dx = (k - (n - 1) / 2) * 0.008 * span  # side by side: equal values stay visible
        x = np.array([r.lam for r, _ in got]) + dx
        y = np.array([r.ratio for r, _ in got])
        lo = y - np.array([min(i.eta) / r.housner for r, i in got])
        hi = np.array([max(i.eta) / r.housner for r, i in got]) - y
        ax.errorbar(x, y, yerr=[lo, hi], linestyle="none", marker=st.marker, color=st.color,
                    markerfacecolor="none" if m.is_reference else st.color, markersize=6,
                    capsize=2, label=m.label)
    for i, e in enumerate(EXPERIMENTS):
        ax.plot([e.lam], [e.ratio], linestyle="none", marker="*", markersize=12,
                color="#8c564b", label="measured (ElGawady et al. 2011)" if i == 0 else None)
        ax.annotate(f"{e.base}, h/b = {e.aspect:g}", (e.lam, e.ratio), fontsize=7,
                    xytext=(6, -3), textcoords="offset points")
    ax.set_xlabel("slenderness angle λ (rad)")
    ax.set_ylabel("η obtained / η Housner")
    ax.set_title("e = 0: mean and range over the impacts", fontsize=10)
    ax.grid(True, alpha=0.3)
    if len(bounces) > 1:
        bx = fig.add_subplot(1, 2, 2, sharey=ax)
        bx.axhline(1.0, color="0.3", linewidth=1.0)
        for m in result.methods[1:]:
            pts = [(e, float(np.mean(v))) for e in bounces
                   if (v := [r.ratio for r in result.rows if r.method == m.label
                             and r.restitution == e and r.impacts is not None])]
            if pts:
                st = styles[m.label]
                bx.plot(*zip(*pts, strict=True), marker=st.marker, color=st.color,
                        linestyle=st.linestyle)
        bx.set_xlabel("bounce coefficient e asked of the engine")
        bx.set_title("mean over the blocks, per e asked (missing: no impact measured)",
                     fontsize=10)
        bx.grid(True, alpha=0.3)
    fig.legend(*ax.get_legend_handles_labels(), fontsize=7, loc="center right")
    fig.tight_layout(rect=(0.0, 0.0, 0.8, 1.0))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=_DPI)
    return path


def _block_table(result: RestitutionResult, scenario: str, number: int) -> Table:
    rows = [r for r in result.rows if r.scenario == scenario]
    first = rows[0]
    aspect = 1.0 / math.tan(first.lam)
    t = Table(
        key=f"eta-{scenario}",
        title=f"Table {number}. {scenario}: λ = {first.lam:.4f} rad (h/b = {aspect:.2f}), "
              f"Housner's η = {first.housner:.4f}",
        caption=("Effective η of each method: the mean over the first impacts (η_k = "
                 "sqrt(V(θ_{k+1}) / V(θ_k)) from successive peaks, V(θ) = cos(λ − θ) − cos λ), "
                 "their range, the mean over Housner's η, and the run's CPU time. e: the bounce "
                 "coefficient the engine was given (contact.restitution)."),
        columns=["method", "e asked", "η obtained", "range over impacts", "η / η Housner",
                 "impacts", "CPU time (s)"])
    for r in rows:
        kind = "ref" if r.method == result.methods[0].label else ""
        head = Cell(r.method, kind="head")
        if r.impacts is None:
            t.add_row([head, f"{r.restitution:g}", Cell(r.note, kind="crashed"), "–", "–", "0",
                       f"{r.cpu_time:.2f}"])
            continue
        t.add_row([head, f"{r.restitution:g}", Cell(_f(r.mean), kind),
                   f"[{min(r.impacts.eta):.4f}, {max(r.impacts.eta):.4f}]",
                   Cell(_f(r.ratio), kind), str(len(r.impacts.eta)), f"{r.cpu_time:.2f}"])
    return t


def _experiments_table(number: int) -> Table:
    t = Table(key="experiments", title=f"Table {number}. η measured on shake tables",
              caption=("Published free-rocking tests: the measured coefficient over Housner's "
                       "prediction for the same block, as each source reports it, and the η "
                       "it implies at that slenderness."),
              columns=["source", "h/b", "λ (rad)", "base", "measured / Housner",
                       "η Housner", "η measured"])
    for e in EXPERIMENTS:
        h = housner_eta(e.lam)
        t.add_row([Cell(e.source, kind="head"), f"{e.aspect:g}", f"{e.lam:.4f}", e.base,
                   f"{e.ratio:.2f}", f"{h:.4f}", f"{e.ratio * h:.4f}"])
    return t


def _write_csv(result: RestitutionResult, path: Path) -> Path:
    with path.open("w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(["scenario", "lambda", "method", "preset", "restitution", "status",
                    "impact", "eta", "eta_housner", "cpu_time", "note"])
        for r in result.rows:
            etas: tuple[float | None, ...] = r.impacts.eta if r.impacts else (None,)
            for k, eta in enumerate(etas, 1):
                w.writerow([r.scenario, r.lam, r.method, r.preset, r.restitution,
                            r.status.value, k if eta is not None else "", eta, r.housner,
                            r.cpu_time, r.note])
    return path


def _summary(result: RestitutionResult) -> str:
    """The largest departure from Housner's η of each method at e = 0."""
    parts = []
    for m in result.methods[1:]:
        rows: list[RestitutionRow] = [r for r in result.rows if r.method == m.label
                                      and r.restitution == 0.0]
        got = [abs(r.ratio - 1.0) for r in rows if r.impacts is not None]
        failed = len(rows) - len(got)
        text = f"{m.label}: within {100 * max(got):.2g} %" if got else f"{m.label}: none"
        parts.append(text + (f" ({failed} run(s) without impacts)" if failed else ""))
    return ("Largest departure of the mean η from Housner's at e = 0, over the blocks: "
            + "; ".join(parts) + "." if parts else "Only the analytic reference ran.")


def write_report(result: RestitutionResult, out: Path, *, embed_figures: bool = True
                 ) -> list[Path]:
    """Write ``index.html``, ``report.md``, ``restitution.csv`` and ``figures/``.

    Returns
    -------
    list of Path
        The files written (figures excluded).
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    csv_path = _write_csv(result, out / "restitution.csv")
    sec = Section("eta", "η obtained, per block")
    sec.paragraphs.append(_summary(result))
    fig = restitution_figure(out / "figures" / "restitution.png", result)
    sec.items.append(FigureItem(str(fig.relative_to(out)), (
        "η obtained over Housner's η against λ (e = 0 runs; bars: range over the impacts); "
        "stars: shake-table measurements."), "Restitution fidelity"))
    scenarios = list(dict.fromkeys(r.scenario for r in result.rows))
    for i, sc in enumerate(scenarios, 1):
        sec.items.append(_block_table(result, sc, i))
    xsec = Section("measured", "η measured")
    xsec.paragraphs.append(
        "Tests find that real blocks lose less energy per impact than Housner's model says "
        "on hard bases (their η is a few per cent closer to 1 than his) and much more on "
        "soft ones; the reason is the impact over a contact region, not a corner "
        "(Kalliontzis, Sritharan & Schultz 2016; Ther & Kollár 2017). An engine that "
        "reproduces Housner's η reproduces his model, not the test.")
    xsec.items.append(_experiments_table(len(scenarios) + 1))
    opts = result.options
    header = [
        ("Date", report_date()),
        ("Blocks", ", ".join(scenarios)),
        ("Runs", f"{result.ran + result.reused}: {result.ran} run now, {result.reused} reused; "
                 f"at most {opts.impacts} impacts measured per run"),
        *run_header(result.wall_time, opts.execution.jobs, result.versions, opts.command),
    ]
    doc = Document(
        title="rockbench restitution report", header=header,
        intro=["Free rocking of single blocks on every method: the effective coefficient of "
               "restitution of each impact, read from successive peaks of |θ| (energy is "
               "conserved between impacts), against Housner's η (a perfectly plastic impact "
               "about the new corner: what an engine asked for no bounce should give) and "
               "shake-table measurements."],
        sections=[sec, xsec], citation=CITATION)
    index, md = write_document(doc, out, embed=embed_figures, data=("restitution.csv",))
    return [index, md, csv_path]
