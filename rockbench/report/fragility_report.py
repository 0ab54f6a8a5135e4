"""The fragility report: curves, fits, median ratios, cost, records, and every run's result.

:func:`write_report` renders a :class:`~rockbench.studies.fragility.FragilityResult`
(nothing is computed here but the curves drawn from the fits): per limit state
a figure of every method's lognormal fragility over the reference's (analytic, or
the engines' consensus) with the observed fractions as points, and a table of
median, dispersion, their bootstrap intervals, the median's ratio to the
reference's with its paired interval, how often each method's outcome is the
reference's, and the cost (runs, CPU time) side by side; the safe islands found
(as they are, not smoothed); the records with their provenance; and
``runs.csv`` / ``runs.json`` with every run's result. ``report.md`` and
``index.html`` hold the same tables (:mod:`rockbench.report.document`).
"""

from __future__ import annotations

import csv
import datetime as _dt
import json
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from scipy.stats import norm

from rockbench import provenance
from rockbench.analytic import critical_angle
from rockbench.fragility import FitStatus, FragilityFit
from rockbench.method import CONSENSUS
from rockbench.report.document import (
    Document,
    FigureItem,
    Section,
    cpu_model,
    python_version,
)
from rockbench.report.figures import method_styles
from rockbench.report.html import write_document
from rockbench.report.tables import Cell, Table
from rockbench.scenarios.excitation import STANDARD_GRAVITY
from rockbench.store import jsonable
from rockbench.studies.code_comparison import CodeBeside
from rockbench.studies.fragility import (
    FragilityOptions,
    FragilityResult,
    FragilityRun,
    LimitState,
    LimitStateCurve,
)

__all__ = ["write_report", "fragility_figure", "ida_figure", "CITATION"]

#: The method of the fits.
CITATION = ("J. W. Baker, \u201cEfficient analytical fragility function fitting using dynamic "
            "structural analysis\u201d, Earthquake Spectra 31(1), 579\u2013599 (2015), "
            "doi:10.1193/021113EQS025M")
_DPI = 110
#: Records beyond which the IDA figure names none in a legend.
_IDA_LEGEND = 12


def _num(v: float, fmt: str = "{:.3g}") -> str:
    return fmt.format(v) if v is not None and math.isfinite(v) else "–"


def _interval(iv: tuple[float, float], fmt: str = "{:.3g}") -> str:
    return (f"[{_num(iv[0], fmt)}, {_num(iv[1], fmt)}]" if all(math.isfinite(v) for v in iv)
            else "–")


def _fit_text(fit: FragilityFit) -> str:
    """What a degenerate fit says instead of a median."""
    lo, hi = fit.median_range
    if fit.status is FitStatus.NONE_EXCEEDED:
        return f"none exceeded: θ > {_num(lo)}"
    if fit.status is FitStatus.ALL_EXCEEDED:
        return f"all exceeded: θ < {_num(hi)}"
    if fit.status is FitStatus.SEPARATED:
        return f"separated: {_num(lo)} < θ ≤ {_num(hi)}, β → 0"
    if fit.status is FitStatus.SINGLE_TRANSITION:
        return f"single transition at {_num(fit.median)}, β → 0"
    return "not increasing with intensity (β → ∞)"


def fragility_figure(path: Path, result: FragilityResult, state: LimitState) -> Path:
    """P(exceed) against intensity: each method's fit (the reference in black) and its
    fractions.

    A method without a finite fit shows its fractions only (its legend entry says why).
    """
    opts = result.options
    styles = method_styles(result.methods)
    fig = Figure(figsize=(7.5, 4.8))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    levels = np.asarray(opts.levels, float)
    pos = levels[levels > 0]
    x = np.geomspace(pos.min() / 1.5, pos.max() * 1.2, 400) if pos.size else levels
    n_methods = len(result.methods)
    span = (levels.max() - levels.min()) or 1.0
    for k, meth in enumerate(result.methods):
        c = result.curve(meth.label, state)
        st = styles[meth.label]
        fit = c.bootstrap.fit if c.bootstrap is not None else None
        label = meth.label
        if fit is not None and fit.ok:
            ax.plot(x, norm.cdf(np.log(x / fit.median) / fit.dispersion), color=st.color,
                    linestyle=st.linestyle, linewidth=st.linewidth, zorder=st.zorder)
            label += f" (θ = {fit.median:.3g}, β = {fit.dispersion:.2f})"
        elif fit is not None:
            label += f" ({fit.status.value}: no fit)"
        f = np.asarray(c.fractions)
        have = ~np.isnan(f)
        # markers of the methods side by side at each level, so that equal fractions show
        dx = (k - (n_methods - 1) / 2) * 0.006 * span
        ax.plot(levels[have] + dx, f[have], linestyle="none", marker=st.marker,
                markerfacecolor="none" if meth.is_reference else st.color,
                markeredgecolor=st.color, markersize=7 if meth.is_reference else 5,
                zorder=st.zorder + 1, label=label)
    ax.set_xlabel(f"intensity: {result.measure.label}")
    ax.set_ylabel("fraction of records exceeding")
    ax.set_ylim(-0.04, 1.04)
    ax.set_title(f"{state.label(opts.theta_limit)}: {opts.scenario.name}, "
                 f"{len(result.records)} records ({opts.set_name or 'custom set'})",
                 fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=_DPI)
    return path


def ida_figure(path: Path, result: FragilityResult) -> Path:
    """Incremental dynamic analysis curves: peak |θ|/λ against intensity, one line per record.

    One panel per method that ran (the analytic reference first; a consensus has no runs
    of its own); a run that overturned is drawn at |θ|/λ = 1 with a triangle, one without
    an outcome is left out (a peak above 1 with no overturning is a block the ground
    pushed back).
    """
    methods = [m for m in result.methods if m.engine != CONSENSUS]
    cols = min(3, len(methods))
    rows = -(-len(methods) // cols)
    fig = Figure(figsize=(3.6 * cols, 3.0 * rows + 0.4))
    FigureCanvasAgg(fig)
    names = [r.name for r in result.records]
    colors = [f"C{i % 10}" for i in range(len(names))]
    first = None
    for k, meth in enumerate(methods):
        ax = fig.add_subplot(rows, cols, k + 1, sharex=first, sharey=first)
        first = first or ax
        for rec, color in zip(names, colors, strict=True):
            runs = sorted((r for r in result.runs if r.method == meth.label and r.record == rec),
                          key=lambda r: r.level)
            pts = [(r.level, 1.0 if r.overturned else _peak(r)) for r in runs
                   if r.overturned is not None and (r.overturned or _peak(r) is not None)]
            if not pts:
                continue
            x, y = zip(*pts, strict=True)
            ax.plot(x, y, color=color, linewidth=1.0, alpha=0.8, label=rec)
            over = [(r.level, 1.0) for r in runs if r.overturned]
            if over:
                ax.plot(*zip(*over, strict=True), linestyle="none", marker="^", color=color,
                        markersize=5)
        ax.axhline(1.0, color="0.5", linewidth=0.6, linestyle=":")
        ax.set_title(meth.label, fontsize=9)
        ax.set_ylim(bottom=0.0)
        ax.grid(True, alpha=0.3)
        if k % cols == 0:
            ax.set_ylabel("peak |θ| / λ")
        if k >= len(methods) - cols:
            ax.set_xlabel(result.measure.label, fontsize=8)
    handles, labels = first.get_legend_handles_labels() if first is not None else ([], [])
    if handles and len(labels) <= _IDA_LEGEND:
        fig.legend(handles, labels, fontsize=7, loc="lower center",
                   ncol=min(4, len(labels)), frameon=False)
        fig.tight_layout(rect=(0.0, 0.06 + 0.02 * (len(labels) // 4), 1.0, 1.0))
    else:  # a legend of dozens of records would cover the panels: runs.csv names them
        fig.suptitle(f"one line per record ({len(names)}; colours repeat every 10)",
                     fontsize=9)
        fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=_DPI)
    return path


def _peak(run: FragilityRun) -> float | None:
    """The largest peak |θ|/λ over the blocks of a run (None without one)."""
    return max((p for p in run.metrics.peaks if p is not None), default=None)


def _fit_table(result: FragilityResult, state: LimitState, number: int) -> Table:
    opts = result.options
    conf = f"{100 * opts.confidence:g} %"
    ref = result.reference.label
    t = Table(
        key=f"fit-{state.value}", title=f"Table {number}. {state.label(opts.theta_limit)}: "
                                        "lognormal fragility per method",
        caption=(f"Maximum-likelihood median θ (in {result.measure.label}) and dispersion β "
                 f"(Baker 2015) over the levels with runs, with {conf} bootstrap intervals "
                 f"({opts.n_resamples} resamples of the runs within each level); the ratio "
                 f"θ/θ_{ref} with its {conf} paired bootstrap interval (the records "
                 "resampled jointly for both methods); the runs whose outcome is the "
                 f"{ref} reference's, of those where both have one; the cost of the method "
                 "over the whole study. 'extrapolated': the median lies outside the tested "
                 "levels."),
        columns=["method", "θ", "θ in units", f"θ {conf}", f"θ {conf} in units", "β",
                 f"β {conf}",
                 f"θ / θ_{ref}", f"ratio {conf}", f"agrees with {ref}", "runs",
                 "no outcome", "CPU time (s)"])
    costs = {c.method: c for c in result.costs}
    for meth in result.methods:
        c = result.curve(meth.label, state)
        cost = costs[meth.label]
        kind = "ref" if meth.is_reference else ""
        cells: list[Cell | str] = [Cell(meth.label, kind="head")]
        boot = c.bootstrap
        if boot is None:
            cells += [Cell("no completed run", kind="crashed")] + ["–"] * 7
        elif boot.fit.ok:
            med = _num(boot.fit.median) + (" (extrapolated)" if boot.fit.extrapolated else "")
            cells += [Cell(med, kind), Cell(result.in_units(boot.fit.median) or "–", kind),
                      Cell(_interval(boot.median_interval), kind),
                      Cell(result.interval_in_units(*boot.median_interval) or "–", kind),
                      Cell(_num(boot.fit.dispersion), kind),
                      Cell(_interval(boot.dispersion_interval), kind)]
            cmp = c.comparison
            if meth.is_reference:
                cells += [Cell("1", kind), Cell("–", kind)]
            elif cmp is not None and math.isfinite(cmp.ratio):
                cells += [_num(cmp.ratio, "{:.3f}"), _interval(cmp.ratio_interval, "{:.3f}")]
            else:
                cells += ["–", "–"]
        else:
            cells += [Cell(_fit_text(boot.fit), kind)] + ["–"] * 7
        cells.append(Cell("–", kind) if meth.is_reference else
                     f"{c.agreed}/{c.compared}" if c.compared else "–")
        if meth.engine == CONSENSUS:  # not a method that runs: it has no runs of its own
            cells += [Cell("–", kind)] * 3
        else:
            cells += [str(cost.runs), str(cost.failed), f"{cost.cpu_time:.2f}"]
        t.add_row(cells)
    return t


def _design_table(result: FragilityResult, state: LimitState, number: int,
                  level: float) -> Table:
    opts = result.options
    conf = f"{100 * opts.confidence:g} %"
    phys = result.in_units(level)
    t = Table(
        key=f"design-{state.value}",
        title=f"Table {number}. {state.label(opts.theta_limit)}: probability at the design "
              f"level {level:g}{f' = {phys}' if phys else ''}",
        caption=(f"P(exceeded | {result.measure.label} = {level:g}) = Φ(ln(level/θ)/β) of "
                 f"each method's fit, with its {conf} bootstrap interval (the same probability "
                 "over the resamples); no value where the fit is degenerate."),
        columns=["method", "P", f"P {conf}"])
    for meth in result.methods:
        boot = result.curve(meth.label, state).bootstrap
        kind = "ref" if meth.is_reference else ""
        if boot is None or not boot.fit.ok:
            t.add_row([Cell(meth.label, kind="head"), "–", "–"])
            continue
        at = boot.probability_at(level)
        t.add_row([Cell(meth.label, kind="head"), Cell(f"{at.probability:.3f}", kind),
                   Cell(_interval(at.interval, "{:.3f}"), kind)])
    return t


def _fractions_table(result: FragilityResult, state: LimitState, number: int) -> Table:
    opts = result.options
    t = Table(key=f"fractions-{state.value}",
              title=f"Table {number}. {state.label(opts.theta_limit)}: fraction of records "
                    "exceeding, per level",
              caption=("Exceeded / completed runs at each intensity level (the points of the "
                       "figure). Runs without an outcome (crashed, unstable, timed out) are "
                       "left out of their level's count."),
              columns=["method"] + [f"{v:g}" for v in opts.levels])
    for meth in result.methods:
        c = result.curve(meth.label, state)
        kind = "ref" if meth.is_reference else ""
        t.add_row([Cell(meth.label, kind="head")] + [
            Cell(f"{z}/{n}" if n else "–", kind) for n, z in zip(c.runs, c.exceeded,
                                                                 strict=True)])
    return t


def _span(first: float, last: float) -> str:
    return f"at {first:g}" if first == last else f"over {first:g}–{last:g}"


def _islands_paragraph(curves: Sequence[LimitStateCurve], theta_limit: float) -> str:
    parts = []
    for c in curves:
        for isl in c.islands:
            parts.append(f"{c.method}, {c.state.label(theta_limit)}: the fraction falls from "
                         f"{isl.peak_fraction:.2f} (at {isl.peak_level:g}) to "
                         f"{isl.fraction:.2f} {_span(isl.first_level, isl.last_level)}")
        for ri in c.record_islands:
            i = ri.island
            parts.append(f"{c.method}, {c.state.label(theta_limit)}: {ri.record} exceeds at "
                         f"{i.peak_level:g} but not {_span(i.first_level, i.last_level)}")
    if not parts:
        return ("Monotone: for every method, neither the fraction exceeded nor any record's "
                "outcome falls as the intensity grows.")
    return ("Not monotone (safe islands, shown as measured, not smoothed; the lognormal fit "
            "describes the trend only): " + "; ".join(parts) + ".")


def _records_table(result: FragilityResult, number: int) -> Table:
    t = Table(key="records", title=f"Table {number}. Records used",
              caption=("Each record at scale 1 (baseline-corrected once), with its provenance; "
                       "for a motion of several components, PGA and PGV are its x "
                       "component's (the one the levels measure)."),
              columns=["record", "event", "station", "duration (s)", "PGA (g)",
                       "PGV (m/s)", "provenance"])
    for r in result.records:
        rec = r.horizontal
        t.add_row([Cell(r.name, kind="head"), r.event or "–", r.station or "–",
                   f"{rec.end_time:.2f}", f"{rec.peak_acceleration() / STANDARD_GRAVITY:.3g}",
                   f"{rec.peak_velocity():.3g}", r.provenance or "–"])
    return t


def _write_runs(result: FragilityResult, out: Path) -> list[Path]:
    rows = []
    for r in result.runs:
        m = r.metrics
        rows.append({"record": r.record, "level": r.level, "scale": r.scale,
                     "method": r.method, "preset": r.preset, "status": m.status.value,
                     "overturned": r.overturned,
                     "rocking_exceeded": r.rocking,
                     "peak": _peak(r),
                     "wall_time": m.wall_time, "cpu_time": m.cpu_time,
                     "reused": r.reused, "message": m.message})
    csv_path = out / "runs.csv"
    with csv_path.open("w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]) if rows else ["record"])
        w.writeheader()
        w.writerows(rows)
    json_path = out / "runs.json"
    json_path.write_text(json.dumps(jsonable({
        "measure": result.measure.value, "levels": list(result.options.levels),
        "theta_limit": result.options.theta_limit,
        "runs": [{**row, "metrics": r.metrics.to_json()}
                 for row, r in zip(rows, result.runs, strict=True)]}), indent=1),
        encoding="utf-8")
    return [csv_path, json_path]


def _pga(v: float, g: float) -> str:
    return f"{v:.3g} m/s² ({v / g:.3g} g)" if math.isfinite(v) else "–"


def _code_section(result: FragilityResult, code: CodeBeside, number: int) -> Section:
    """The code's verdict beside each method's P(overturn) at the design PGA and margins."""
    check, g = code.check, result.options.scenario.g
    site = check.site
    where = ("on the ground" if site.building is None else
             f"at z = {site.building.element_height:g} m of a {site.building.storeys}-storey "
             f"building (H = {site.building.height:g} m, T₁ = {site.building.period:g} s)")
    sec = Section("code", "The code check beside the dynamics")
    parts = []
    for name, done in (("linear", check.checks("linear")),
                       ("non-linear", check.checks("nonlinear"))):
        if not done:
            parts.append(f"the {name} check is not done (no mechanism, or no finite "
                         f"kinematics)")
            continue
        worst = min(done, key=lambda dc: dc[1].ratio)
        parts.append(f"the {name} check {'passes' if all(c.passed for _, c in done) else 'fails'} "
                     f"(weaker direction {worst[0].label}: ratio {worst[1].ratio:.3f}, capacity "
                     f"PGA {_pga(worst[1].capacity_pga, g)})")
    sec.paragraphs.append(
        f"NTC 2018 kinematic analysis (Circolare 2019 §C8.7.1.2.1) at a_g = {site.ag:g} g, soil "
        f"{site.soil}, F₀ = {site.F0:g}, T_C* = {site.TC_star:g} s, q = {site.q:g}, FC = "
        f"{site.confidence_factor:g}, {where}: design PGA at the element's base "
        f"{_pga(check.design_pga, g)} (level {code.design_level:.4g} of "
        f"{result.measure.label}). The " + "; ".join(parts)[4:] + ". Overall the element "
        + ("passes." if check.passed else "fails.") + " `rockbench check` gives the whole check."
        + ("" if check.ec8 is None else
           f" Eurocode 8's element check (EN 1998-1 §4.3.5.2, S_a = {check.ec8.coefficient:.3g} g, "
           f"γ_a = {check.ec8.importance:g}, q_a = {check.ec8.qa:g}) "
           f"{'passes' if check.ec8.passed else 'fails'} (ratio {check.ec8.ratio:.3f}, capacity "
           f"PGA {_pga(check.ec8.capacity_pga, g)})."))
    ref = code.methods[0]
    if ref.probability is not None and math.isfinite(ref.nonlinear_margin):
        verdict = ("conservative" if ref.nonlinear_margin > 1 else "not conservative")
        sec.paragraphs.append(
            f"Against the {ref.method} reference the code's non-linear check is {verdict} here: "
            f"the element overturns, in the median, at {ref.nonlinear_margin:.2f} times the "
            f"acceleration the check accepts; at the design PGA it overturns with probability "
            f"{ref.probability.probability:.3f}.")
    conf = f"{100 * result.options.confidence:g} %"
    t = Table(key="code", title=f"Table {number}. Overturning against the code",
              caption=(f"P(overturning | PGA = the code's design PGA) with its {conf} "
                       "interval; the median overturning PGA at the element's base; the "
                       "margins: that median over each check's capacity PGA (above 1 the code "
                       "is conservative by that factor)."),
              columns=["method", "P(overturn | design)", f"P {conf}", "median overturning PGA",
                       "median / linear capacity", "median / non-linear capacity",
                       "median / EC8 capacity"])
    for m in code.methods:
        p = m.probability
        kind = "ref" if m is ref else ""
        t.add_row([Cell(m.method, kind="head"),
                   Cell(f"{p.probability:.3f}", kind) if p else "–",
                   _interval(p.interval, "{:.3f}") if p else "–",
                   Cell(_pga(m.median_pga, g), kind), _num(m.linear_margin, "{:.2f}"),
                   _num(m.nonlinear_margin, "{:.2f}"), _num(m.ec8_margin, "{:.2f}")])
    sec.items.append(t)
    return sec


def _oscillator(opts: FragilityOptions) -> str:
    """The period and damping of a spectral measure, for the report's header."""
    o = opts.oscillator
    return "" if o is None else f", T = {o.period:g} s, ζ = {o.damping:g}"


def write_report(result: FragilityResult, out: Path, *, embed_figures: bool = True,
                 code: CodeBeside | None = None) -> list[Path]:
    """Write ``index.html``, ``report.md``, ``runs.csv``, ``runs.json`` and ``figures/``.

    ``code``: the code check of the element beside the study
    (:func:`rockbench.studies.code_comparison.code_beside`), a section of its own.

    Returns
    -------
    list of Path
        The files written (figures excluded).
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    opts = result.options
    ref = result.reference.label
    files = _write_runs(result, out)
    number = 0
    sections = []
    for state in LimitState:
        sec = Section(f"state-{state.value}", f"Limit state: {state.label(opts.theta_limit)}")
        sec.paragraphs.append(
            "Overturning: the run ended overturned." if state is LimitState.OVERTURNING else
            f"Rocking: the largest |θ|/λ over the blocks reached {opts.theta_limit:g} "
            "(an overturned run counts as exceeding).")
        path = fragility_figure(out / "figures" / f"fragility-{state.value}.png", result, state)
        sec.items.append(FigureItem(str(path.relative_to(out)), (
            f"Fraction of records exceeding against intensity (markers; the {ref} reference "
            f"hollow black, methods side by side at each level) and each method's lognormal "
            f"fit (curves; {ref} in black)."), f"Fragility curves: {state.value}"))
        number += 1
        sec.items.append(_fit_table(result, state, number))
        number += 1
        sec.items.append(_fractions_table(result, state, number))
        if opts.design_level is not None:
            number += 1
            sec.items.append(_design_table(result, state, number, opts.design_level))
        sec.paragraphs.append(_islands_paragraph(
            [c for c in result.curves if c.state is state], opts.theta_limit))
        sections.append(sec)
    if code is not None:
        number += 1
        sections.append(_code_section(result, code, number))
    isec = Section("ida", "Incremental dynamic analysis curves")
    path = ida_figure(out / "figures" / "ida.png", result)
    isec.items.append(FigureItem(str(path.relative_to(out)), (
        "Peak |θ|/λ of each record against intensity, one panel per method; a triangle at 1: "
        "the run overturned."), "IDA curves"))
    sections.append(isec)
    number += 1
    rsec = Section("records", "Records")
    rsec.items.append(_records_table(result, number))
    sections.append(rsec)
    fsec = Section("files", "Files")
    fsec.paragraphs.append("runs.csv and runs.json: every run's record, level, scale, method, "
                           "status, outcomes, peak |θ|/λ and cost (runs.json with the full "
                           "metrics); the same runs are in the results store (kind "
                           "'fragility').")
    sections.append(fsec)
    overhead = result.overhead
    header = [
        ("Date", _dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M:%S %Z")),
        ("Scenario", f"{opts.scenario.name} ({opts.scenario.n_blocks} block(s), λ = "
                     f"{critical_angle(opts.scenario.geometry):.4f} rad)"),
        ("Record set", f"{opts.set_name or 'custom'} ({len(result.records)} records)"),
        ("Intensity", f"{result.measure.label}{_oscillator(opts)} at "
                      f"{', '.join(f'{v:g}' for v in opts.levels)}"),
        ("Runs", f"{len(result.runs)}: {result.ran} run now, {result.reused} reused (--resume); "
                 f"each the record plus {opts.settle:g} s, sampled at {opts.output_rate:g}/s"),
        ("Wall time", f"{result.wall_time:.1f} s on {opts.execution.jobs} worker(s); overhead "
                      "(wall × workers)/(Σ CPU of the runs) − 1 = "
                      + (f"{100 * overhead:.0f} %" if math.isfinite(overhead) else "–")
                      + "; over the runs' own wall time "
                      + (f"{100 * result.overhead_on_run_wall:.0f} %"
                         if math.isfinite(result.overhead_on_run_wall) else "–")),
        ("rockbench", provenance.describe()),
        ("Python", python_version()),
        ("Machine (CPU)", cpu_model()),
        ("Engine versions", ", ".join(f"{e} {v}" for e, v in result.versions.items())),
        ("Command", opts.command or "(Python API)"),
    ]
    doc = Document(
        title=f"rockbench fragility report — {opts.scenario.name}",
        header=header,
        intro=[("Incremental dynamic analysis: every record scaled to every intensity level, "
                "run on every method, the analytic reference (Housner's equation; the "
                "two-block model for stacks) among them."
                if ref != CONSENSUS else
                "Incremental dynamic analysis: every record scaled to every intensity level, "
                "run on every engine. No closed form covers this structure: the reference is "
                "the consensus of the engines' contact-model families, run by run (each "
                "family's majority outcome; the outcome at least two families give, and more "
                "families than the other; no consensus otherwise). It is only as good as the "
                "engines at these presets: check them first with `rockbench verify` on the "
                "structure.")
               + " Fragilities are lognormal, fitted by maximum likelihood (Baker 2015) with "
               f"bootstrap intervals; each engine's median is compared with the {ref} one by "
               "a paired bootstrap over the records."],
        sections=sections, citation=CITATION)
    index, md = write_document(doc, out, embed=embed_figures,
                               data=("runs.csv", "runs.json"))
    return [index, md, *files]
