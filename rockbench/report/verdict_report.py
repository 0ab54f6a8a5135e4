"""The verdict in a report: which method to trust, against which reference, with the evidence.

:func:`verdict_section` is the section ``compare`` puts first and ``verify``
builds on; :func:`write_verify_report` writes the whole ``verify`` report
(``index.html``, ``report.md``, ``verdict.csv``, figures): the verdict, each
judgement, the convergence ladders, the consensus (and how far it lies from
the closed forms where both exist) and the cost of the verdict against the
runs it judges. Every table says how many scenarios stand behind its figures.
"""

from __future__ import annotations

import csv
import datetime as _dt
import math
import os
import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from rockbench import provenance
from rockbench.method import slug
from rockbench.report.document import (
    Document,
    FigureItem,
    Section,
    cpu_model,
)
from rockbench.report.html import write_document
from rockbench.report.options import ReportOptions
from rockbench.report.paper import citation
from rockbench.report.tables import Cell, Table
from rockbench.studies.convergence import Convergence
from rockbench.studies.verdict import Trust, Verdict
from rockbench.studies.verify import VerifyResult

__all__ = ["verdict_section", "write_verify_report", "convergence_figure"]

#: Cell style of each verdict (the report's status classes).
_KIND = {Trust.TRUSTED: "", Trust.UNVERIFIED: "unsupported", Trust.NOT_CONVERGED: "unstable",
         Trust.NOT_TRUSTED: "crashed"}
_MARK = {Trust.TRUSTED: "✓ trusted", Trust.UNVERIFIED: "? unverified",
         Trust.NOT_CONVERGED: "✗ not converged", Trust.NOT_TRUSTED: "✗ not trusted"}


def _plural(n: int, word: str) -> str:
    return f"{n} {word}{'s' if n != 1 else ''}"


def verdict_table(verdict: Verdict, number: int) -> Table:
    """Per method: the verdict, how many scenarios each reference judged, its CPU time,
    and the evidence of its worst judgement."""
    n = len(verdict.scenarios)
    t = Table("verdict", f"Table {number}. Verdict per method ({_plural(n, 'scenario')})",
              "Trusted: every scenario within the tolerances of its reference (closed form "
              "where one exists, else the consensus of converged engines); the evidence is "
              "that of the judgement that set the verdict. CPU time over all scenarios.",
              ["method", "verdict", "trusted / not / not converged / unverified",
               "references", "CPU (s)", "evidence"])
    for mv in verdict.methods:
        c = mv.counts
        worst = mv.worst()
        evidence = "" if worst is None else (
            worst.evidence if mv.trust is Trust.TRUSTED and n == 1 else
            f"{worst.scenario}: {worst.evidence}")
        t.add_row([Cell(mv.method.label, kind="head"), Cell(_MARK[mv.trust], _KIND[mv.trust]),
                   f"{c[Trust.TRUSTED]} / {c[Trust.NOT_TRUSTED]} / {c[Trust.NOT_CONVERGED]} / "
                   f"{c[Trust.UNVERIFIED]}",
                   ", ".join(f"{k} {v}" for k, v in sorted(mv.references.items())),
                   f"{mv.cpu_time:.3g}", evidence])
    return t


def verdict_section(verdict: Verdict, number: Callable[[], int]) -> Section:
    """The verdict section: the line that says what to use, and the table behind it."""
    sec = Section("verdict", "Verdict: which method to trust here")
    n = len(verdict.scenarios)
    tol = verdict.tolerances
    if verdict.cheapest is not None:
        sec.paragraphs.append(
            f"**Use {verdict.cheapest.method.label}**: the cheapest method trusted on all "
            f"{_plural(n, 'scenario')} ({verdict.cheapest.cpu_time:.3g} s CPU).")
    else:
        sec.paragraphs.append(f"**No method is trusted on all {_plural(n, 'scenario')}.**")
    sec.paragraphs.append(
        f"Tolerances: peaks within {100 * tol.peak:g} % (over max(peak, 0.02 λ)), the "
        f"overturning time within {100 * tol.overturn_time:g} %, max |Δθ| within "
        f"{tol.history:g} λ up to the predictability horizon t* (beyond it the reference "
        "is not predictable and is not used); a method judged against a consensus must "
        "itself converge.")
    sec.items.append(verdict_table(verdict, number()))
    return sec


def judgement_table(verdict: Verdict, number: int) -> Table:
    """Every method on every scenario."""
    t = Table("judgements", f"Table {number}. Each method on each scenario "
                            f"({_plural(len(verdict.scenarios), 'scenario')})",
              "The reference each scenario was judged against and the numbers.",
              ["scenario", "method", "reference", "verdict", "evidence"])
    for mv in verdict.methods:
        for j in mv.judgements:
            t.add_row([Cell(j.scenario, kind="head"), j.method.label, j.reference,
                       Cell(_MARK[j.trust], _KIND[j.trust]), j.evidence])
    return t


def ladder_table(ladders: Sequence[Convergence], number: int) -> Table:
    """The rungs of every ladder."""
    t = Table("ladders", f"Table {number}. Convergence ladders ({_plural(len(ladders), 'ladder')}"
                         f" on {_plural(len({c.scenario.name for c in ladders}), 'scenario')})",
              "Rung 0 is the method as judged; each further rung refines the engine's time "
              "step (or the knob that sets it) by 2. Peaks max |θ_i|/λ (up to t*); Δhistory "
              "= max |θ − θ_previous rung|/λ. The estimate is Richardson's with its "
              "uncertainty (Roache's GCI).",
              ["scenario", "method", "rungs", "peaks per rung", "Δhistory per rung",
               "estimate", "converged", "CPU (s)"])
    for c in ladders:
        peaks = " → ".join("/".join(f"{p:.4g}" for p in r.response.peaks) for r in c.rungs)
        hist = " → ".join(f"{r.history_change:.2g}" for r in c.rungs[1:]
                          if r.history_change is not None)
        est = "/".join(str(e) for e in c.peaks if e is not None) or "–"
        t.add_row([Cell(c.scenario.name, kind="head"), c.method.label, str(len(c.rungs)),
                   peaks, hist or "–", est,
                   Cell("yes" if c.converged else f"no: {c.reason}",
                        "" if c.converged else "unstable"), f"{c.cost:.3g}"])
    return t


def consensus_table(result: VerifyResult, number: int) -> Table:
    """Each scenario's consensus, with its members and outliers, and the closed form."""
    checks = {c.scenario: c for c in result.consensus_check}
    cons = result.verdict.consensus
    t = Table("consensus", f"Table {number}. Consensus of converged engines "
                           f"({_plural(len(cons), 'scenario')})",
              "One value per contact-model family (the median of its engines), then the "
              "median over the families; ± the largest distance of a family plus its "
              "uncertainty. Where a closed form exists the consensus is compared with it: "
              "what a consensus is worth where none does.",
              ["scenario", "formed", "outcome", "peaks", "overturning time (s)", "families",
               "outside", "closed form − consensus"])
    for name, c in cons.items():
        ck = checks.get(name)
        vs = "–" if ck is None else (
            ", ".join(f"{100 * e:+.2g} %" for e in ck.peak_errors)
            + (" (inside its ±)" if ck.within else " (outside its ±)"))
        t.add_row([Cell(name, kind="head"), "yes" if c.formed else f"no: {c.note}",
                   c.outcome.value if c.outcome else "–",
                   "/".join(str(p) for p in c.peaks) or "–",
                   str(c.overturn_time) if c.overturn_time else "–",
                   ", ".join(f"{m} ({f})" for m, f in c.members) or "–",
                   "; ".join(f"{m}: {why}" for m, why in c.outliers) or "–", vs])
    return t


def convergence_figure(path: Path, ladders: Sequence[Convergence], title: str) -> Path:
    """Peak max |θ|/λ (largest block) against refinement, one line per method."""
    fig = Figure(figsize=(7.0, 4.2))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for c in ladders:
        levels = [r.level for r in c.rungs]
        peaks = [max(r.response.peaks) if r.response.peaks else math.nan for r in c.rungs]
        ax.plot(levels, peaks, marker="o" if c.converged else "x",
                ls="-" if c.converged else "--", label=c.method.label)
    ax.set_xlabel("rung (each refines the step by 2)")
    ax.set_ylabel("peak max |θ|/λ")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8, ncol=2)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    return path


def _write_csv(result: VerifyResult, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    with os.fdopen(fd, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(["scenario", "method", "engine", "preset", "reference", "verdict",
                    "cpu_time", "evidence"])
        for mv in result.verdict.methods:
            for j in mv.judgements:
                w.writerow([j.scenario, j.method.label, j.method.engine, j.method.preset,
                            j.reference, j.trust.value, f"{j.cpu_time:.6g}", j.evidence])
    os.replace(tmp, path)
    return path


def write_verify_report(result: VerifyResult, options: ReportOptions) -> list[Path]:
    """``index.html``, ``report.md``, ``verdict.csv`` and ``figures/`` of a verification."""
    out = Path(options.out)
    counter = iter(range(1, 1000))

    def number() -> int:
        return next(counter)

    def fig(path: Path, caption: str, title: str = "") -> FigureItem:
        return FigureItem(path.relative_to(out).as_posix(), caption, title)

    sections = [verdict_section(result.verdict, number)]
    detail = Section("evidence", "The evidence")
    detail.items.append(judgement_table(result.verdict, number()))
    sections.append(detail)
    if result.ladders:
        lad = Section("convergence", "Self-convergence of each method")
        lad.paragraphs.append(
            "A method that does not converge is reported as such and never trusted against "
            "a consensus.")
        lad.items.append(ladder_table(result.ladders, number()))
        for name in dict.fromkeys(c.scenario.name for c in result.ladders):
            mine = [c for c in result.ladders if c.scenario.name == name]
            p = convergence_figure(out / "figures" / f"convergence-{slug(name)}.png", mine,
                                   f"{name}: peak against refinement")
            lad.items.append(fig(p, "Peak of the largest block at each rung; crosses and "
                                    "dashes: a ladder that did not converge.",
                                 f"Convergence, {name}"))
        sections.append(lad)
        cons = Section("consensus", "Consensus where no closed form exists")
        cons.items.append(consensus_table(result, number()))
        sections.append(cons)
    cost = Section("cost", "Cost of the verdict")
    ratio = result.verdict_cpu / result.run_cpu if result.run_cpu > 0 else math.nan
    cost.paragraphs.append(
        f"The methods' own runs took {result.run_cpu:.3g} s CPU; the ladders' further rungs "
        f"{result.verdict_cpu:.3g} s ({ratio:.3g}× the runs they judge). Every run is in "
        "the results store: a repeated verification reuses them.")
    sections.append(cost)
    doc = Document(
        title="rockbench verification",
        header=[("Date", _dt.datetime.now().isoformat(timespec="seconds")),
                ("Wall time", f"{result.wall_time:.1f} s"), ("Machine", cpu_model()),
                ("rockbench", provenance.describe()),
                ("Scenarios", ", ".join(s.name for s in result.options.scenarios)),
                ("Command", options.command or "(Python API)")],
        intro=["For each method (an engine at a preset): can it be trusted on these "
               "scenarios, against which reference, and which is the cheapest that is right?"],
        sections=sections, citation=citation())
    index, md = write_document(doc, out, embed=options.embed_figures, data=("verdict.csv",))
    return [index, md, _write_csv(result, out / "verdict.csv")]
