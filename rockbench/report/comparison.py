"""The comparison tables of a report, laid out like the paper's, built from result rows.

Per scenario group: normalised peak rocking angles side by side with the
paper's published columns (Tables 6, 9, 10), relative errors against our
analytic reference (Table 7/11/12 style), free-rocking errors against Housner,
and cost (wall time, real-time factor, the paper's reported times).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from rockbench.analytic import critical_angle, uplift_ratio
from rockbench.evaluation import N_IMPACTS, RunResult
from rockbench.method import REFERENCE, Method
from rockbench.report.groups import group_title
from rockbench.report.paper import paper_runtimes, paper_summary, paper_tables
from rockbench.report.tables import (
    Cell,
    Table,
    fmt_error,
    fmt_factor,
    fmt_percent,
    fmt_ratio,
    fmt_seconds,
)
from rockbench.scenarios import Scenario
from rockbench.trajectory import Status

__all__ = ["GROUP_TABLES", "group_table", "group_tables", "Context", "overview_table",
           "peak_tables", "error_table", "free_tables",
           "timing_table", "cost_table", "paper_experiment_table", "paper_findings",
           "input_label", "fmt_impact"]

Row = RunResult


def _at(values: tuple[Any, ...], i: int) -> Any:
    return values[i] if i < len(values) else None


def fmt_impact(v: Any) -> str:
    """An unsigned relative impact-time error as a percentage (three significant digits)."""
    return f"{100.0 * v:.3g} %" if isinstance(v, float) and math.isfinite(v) else "–"


class Context:
    """What every table builder needs: the scenarios, the methods and the rows.

    Parameters
    ----------
    scenarios : sequence of Scenario
        In report order.
    methods : sequence of Method
        In column order (the analytic reference first).
    rows : sequence of RunResult
        Results of the main comparison (variations are left out).
    """

    def __init__(self, scenarios: Sequence[Scenario], methods: Sequence[Method],
                 rows: Sequence[Row]) -> None:
        self.scenarios = list(scenarios)
        self.methods = [m.label for m in methods]
        self.rows = {r.key: r for r in rows if not r.method.variation}
        self.counter = 0

    @property
    def engines(self) -> list[str]:
        """The methods other than the analytic reference."""
        return [m for m in self.methods if m != REFERENCE]

    def row(self, scenario: str, method: str) -> Row | None:
        """The row of a scenario × method (None if it was not run)."""
        return self.rows.get((scenario, method))

    def next_number(self) -> int:
        """Running table number in the report."""
        self.counter += 1
        return self.counter


def input_label(s: Scenario) -> tuple[str, str]:
    """(frequency in Hz, amplitude in mm) of a periodic input, else a description."""
    d = s.excitation.to_table()
    if "frequency" in d and "amplitude" in d:
        return f"{float(d['frequency']):.1f}", f"{1000.0 * float(d['amplitude']):g}"
    return d.get("type", "?"), "–"


def _value(table: Table, row: Row | None, text: str, who: str) -> Cell:
    if row is None:
        return Cell("not run", kind="crashed")
    if row.status is not Status.OK:
        return table.status_cell(row.status.value, row.metrics.message, who)
    return Cell(text, kind="ref" if who == REFERENCE else "")


def _error_cell(table: Table, row: Row | None, text: str, who: str) -> Cell:
    if row is None:
        return Cell("not run", kind="crashed")
    if row.status is not Status.OK:
        return table.status_cell(row.status.value, row.metrics.message, who)
    note = row.metrics.error_note
    if text == "–":
        return Cell("–", note=table.note(note or "undefined"), title=note)
    if note:
        return Cell(text, note=table.note(note), title=note)
    return Cell(text)


def overview_table(ctx: Context, number: int) -> Table:
    """Per method: runs by status, median error against the reference, total cost."""
    t = Table(
        key="overview-table", title=f"Table {number}. Overview per method",
        caption=("Number of runs by outcome, median over scenarios of the largest "
                 "normalised deviation max |θ − θ_ref|/λ from the analytic reference, "
                 "total wall time and median real-time factor (simulated seconds per wall "
                 "second; > 1 is faster than real time)."),
        columns=["method", "runs", "ok", "overturned", "failed", "unsupported",
                 "median max |Δθ|/λ", "total wall (s)", "median real-time factor"])
    for m in ctx.methods:
        rows = [r for s in ctx.scenarios if (r := ctx.row(s.name, m)) is not None]
        st = [r.status.value for r in rows]
        errs = [r.metrics.max_error for r in rows if r.status is Status.OK
                and r.metrics.max_error is not None]
        rtf = [r.metrics.realtime_factor for r in rows if r.metrics.realtime_factor is not None]
        t.add_row([
            Cell(m, kind="head"), str(len(rows)), str(st.count("ok")),
            str(st.count("overturned")),
            str(sum(x in ("unstable", "crashed", "timeout") for x in st)),
            str(st.count("unsupported")),
            "reference" if m == REFERENCE else fmt_error(float(np.median(errs)) if errs
                                                         else math.nan),
            fmt_seconds(sum(r.metrics.wall_time for r in rows)),
            fmt_factor(float(np.median(rtf)) if rtf else math.nan),
        ])
    return t


def _case_columns(s: Scenario) -> list[Cell | str]:
    f, a = input_label(s)
    ratio = "–" if s.motion.is_free else f"{uplift_ratio(s):.2f}"
    return [Cell(s.name, kind="head"), f, a, ratio]


def peak_tables(ctx: Context, group: str, scenarios: Sequence[Scenario]) -> list[Table]:
    """Normalised peak rocking angle per method (one table per block, top block first).

    The paper's published columns (Tables 6, 9, 10) are appended where the
    scenarios are the paper's catalog cases.
    """
    nb = max(s.n_blocks for s in scenarios)
    published = [pt for pt in paper_tables().values() if pt.quantity == "peak_ratio"
                 and any(pt.values(s) is not None for s in scenarios)]
    out = []
    for block in range(nb, 0, -1):
        which = ("" if nb == 1 else " (top block)" if block == nb else
                 " (bottom block)" if block == 1 else f" (block {block})")
        pt = next((p for p in published if p.block == block), None)
        columns = ["scenario", "f (Hz)", "A (mm)", "ü_g/(g tan λ)", *ctx.methods]
        groups = [("input", 4), ("rockbench", len(ctx.methods))]
        if pt is not None:
            columns += list(pt.methods)
            groups.append((f"paper, Table {pt.number}", len(pt.methods)))
        number = ctx.next_number()
        cap = (f"{group_title(group)}{which}: maximum absolute rocking angle normalised by the "
               f"critical angle λ of the scenario, max |θ|/λ, for our analytic reference and "
               f"each engine run on the same input (three decimals).")
        if pt is not None:
            cap += (f" Right: the values published by the paper's Table {pt.number} "
                    f"(italics; its engines drove the base differently from its analytical "
                    f"model, see the paper).")
        t = Table(key=f"peaks-{group}-b{block}",
                  title=f"Table {number}. Peak rocking angle, {group_title(group).lower()}"
                        f"{which}", caption=cap, columns=columns, groups=groups)
        for s in scenarios:
            if block > s.n_blocks:
                continue
            cells: list[Cell | str] = _case_columns(s)
            for m in ctx.methods:
                r = ctx.row(s.name, m)
                text = fmt_ratio(r.metrics.peaks[block - 1]) if r else "–"
                cells.append(_value(t, r, text, m))
            if pt is not None:
                vals = pt.values(s)
                for i in range(len(pt.methods)):
                    v = vals[i] if vals else "–"
                    cells.append(Cell(fmt_ratio(v) if isinstance(v, (int, float)) else str(v),
                                      kind="paper"))
            t.add_row(cells)
        out.append(t)
    return out


def error_table(ctx: Context, group: str, scenarios: Sequence[Scenario]) -> Table:
    """Relative peak error of each engine against our analytic reference, per block."""
    nb = max(s.n_blocks for s in scenarios)
    sub = ([f"Δpeak/peak, block {i}" for i in range(1, nb + 1)] if nb > 1
           else ["Δpeak/peak"]) + ["max |Δθ|/λ"]
    if nb == 2:
        sub = ["Δpeak/peak, bottom", "Δpeak/peak, top", "max |Δθ|/λ"]
    columns = ["scenario", "f (Hz)", "A (mm)", "ü_g/(g tan λ)"]
    groups = [("input", 4)]
    for m in ctx.engines:
        columns += sub
        groups.append((m, len(sub)))
    number = ctx.next_number()
    t = Table(
        key=f"errors-{group}",
        title=f"Table {number}. Error against the analytic reference, "
              f"{group_title(group).lower()}",
        caption=("Signed relative error of the peak, (max|θ| − max|θ_ref|)/max|θ_ref| per block "
                 "(one decimal, %), and the largest deviation of the whole time history "
                 "max |θ − θ_ref|/λ (three significant digits), against our analytic reference "
                 "on identical input. The paper's Tables 7, 11 and 12 give errors against the "
                 "shake-table experiment instead (listed separately)."),
        columns=columns, groups=groups)
    for s in scenarios:
        cells: list[Cell | str] = _case_columns(s)
        for m in ctx.engines:
            r = ctx.row(s.name, m)
            for i in range(1, nb + 1):
                if i > s.n_blocks:
                    cells.append(Cell(""))
                    continue
                v = _at(r.metrics.peak_errors, i - 1) if r else None
                cells.append(_error_cell(t, r, fmt_percent(v), m))
            cells.append(_error_cell(t, r, fmt_error(r.metrics.max_error) if r else "–", m))
        t.add_row(cells)
    return t


def free_tables(ctx: Context, scenarios: Sequence[Scenario]) -> list[Table]:
    """Free rocking against Housner: time-history error, time to rest, first impact times."""
    n1 = ctx.next_number()
    cols = ["scenario", "λ (rad)", "θ0/λ", "Housner t_rest (s)"]
    groups: list[tuple[str, int]] = [("case", 4)]
    for m in ctx.engines:
        cols += ["max |Δθ|/λ", "t_rest (s)"]
        groups.append((m, 2))
    a = Table(
        key="free-errors", title=f"Table {n1}. Free rocking: error against Housner's solution",
        caption=("Largest deviation of the rocking angle from Housner's solution over the whole "
                 "record, max |θ − θ_Housner|/λ (three significant digits), and the time to "
                 "rest: the first time after which |θ| stays below 0.01 λ (– if the block is "
                 "still rocking at the end)."),
        columns=cols, groups=groups)
    for s in scenarios:
        ref = ctx.row(s.name, REFERENCE)
        cells: list[Cell | str] = [Cell(s.name, kind="head"), f"{critical_angle(s.geometry):.4f}",
                                   f"{s.initial_tilt:g}"]
        cells.append(_value(a, ref, fmt_seconds(ref.metrics.time_to_rest) if ref else "–",
                            REFERENCE))
        for m in ctx.engines:
            r = ctx.row(s.name, m)
            cells.append(_error_cell(a, r, fmt_error(r.metrics.max_error) if r else "–", m))
            cells.append(_value(a, r, fmt_seconds(r.metrics.time_to_rest) if r else "–", m))
        a.add_row(cells)
    n2 = ctx.next_number()
    cols = ["scenario"]
    groups = [("", 1)]
    for m in ctx.engines:
        cols += [f"Δt{k}/t{k}" for k in range(1, N_IMPACTS + 1)]
        groups.append((m, N_IMPACTS))
    b = Table(
        key="free-impacts",
        title=f"Table {n2}. Free rocking: error of the first impact times",
        caption=(f"Relative error |t_k − t_k,Housner|/t_k,Housner of the first {N_IMPACTS} "
                 "impacts (sign changes of θ; three significant digits, %). An impact that "
                 "an engine misses, or that does not occur, is –."),
        columns=cols, groups=groups)
    for s in scenarios:
        cells = [Cell(s.name, kind="head")]
        for m in ctx.engines:
            r = ctx.row(s.name, m)
            for k in range(1, N_IMPACTS + 1):
                v = _at(r.metrics.impact_time_errors, k - 1) if r else None
                cells.append(_error_cell(b, r, fmt_impact(v), m))
        b.add_row(cells)
    return [a, b]


def _paper_times(s: Scenario) -> tuple[str, str]:
    for rt in paper_runtimes():
        if rt.get("scenario") == s.name or (
                "scenario_prefix" in rt and s.name.startswith(rt["scenario_prefix"] + "-")):
            return rt["engines"], rt["dem"]
    return "", ""


def timing_table(ctx: Context) -> Table:
    """Wall time and real-time factor per scenario and method, with the paper's times."""
    cols = ["scenario", "simulated (s)"]
    groups: list[tuple[str, int]] = [("case", 2)]
    for m in ctx.methods:
        cols += ["wall (s)", "RTF"]
        groups.append((m, 2))
    cols += ["Bullet/Vortex", "DEM"]
    groups.append(("paper (other machines)", 2))
    number = ctx.next_number()
    t = Table(
        key="timing", title=f"Table {number}. Cost: wall time per case and method",
        caption=("Wall-clock time of each simulation (two decimals below 10 s) and real-time "
                 "factor RTF = simulated time / wall time (> 1: faster than real time), on the "
                 "machine in the header, one process per run. Right: run times reported by "
                 "the paper for the same case where it gives them (its engines on an "
                 "i7-13700K, DEM on an i9-12900K; its durations may differ from ours)."),
        columns=cols, groups=groups)
    for s in ctx.scenarios:
        cells: list[Cell | str] = [Cell(s.name, kind="head"), f"{s.duration:g}"]
        for m in ctx.methods:
            r = ctx.row(s.name, m)
            if r is None:
                cells += [Cell("not run", kind="crashed"), Cell("")]
                continue
            if r.metrics.completed:
                cells += [Cell(fmt_seconds(r.metrics.wall_time),
                               kind="" if r.status is Status.OK else "overturned"),
                          Cell(fmt_factor(r.metrics.realtime_factor))]
            else:
                cells += [t.status_cell(r.status.value, r.metrics.message, m), Cell("")]
        eng, dem = _paper_times(s)
        cells += [Cell(eng, kind="paper"), Cell(dem, kind="paper")]
        t.add_row(cells)
    return t


def _median(values: Sequence[float]) -> float:
    return float(np.median(values)) if values else math.nan


def _kind(scenarios: Sequence[Scenario]) -> str:
    if any(s.geometry.column is None for s in scenarios):
        return "assemblies"
    return "single blocks" if all(s.n_blocks == 1 for s in scenarios) else "stacks"


def cost_table(ctx: Context, group: str, scenarios: Sequence[Scenario]) -> Table:
    """Per engine and preset: CPU per simulated second next to the accuracy it buys.

    Over the group's scenarios (single blocks, stacks or assemblies): the median
    CPU seconds per simulated second of the completed runs, their total CPU
    time, and the median over the ``ok`` runs of max |Δθ|/λ and of |Δpeak|/peak
    (the largest magnitude over the blocks) against the analytic reference.
    """
    number = ctx.next_number()
    t = Table(
        key=f"cost-{group}",
        title=f"Table {number}. Cost and the accuracy it buys, {group_title(group).lower()}",
        caption=(f"Per engine and preset over the {len(scenarios)} "
                 f"scenario{'' if len(scenarios) == 1 else 's'} of this group "
                 f"({_kind(scenarios)}): median CPU seconds per simulated second of the "
                 "completed runs (CPU time of the run inside its worker, process start-up "
                 "excluded; < 1 is faster than real time on one core) and their total CPU "
                 "time, next to the median over the ok runs of the largest deviation "
                 "max |θ − θ_ref|/λ and of the peak error |Δpeak|/peak (largest over the "
                 "blocks; – in free rocking, whose peak is the initial tilt) against the "
                 "analytic reference. Read it before choosing a preset for a study of many "
                 "runs."),
        columns=["method", "ok runs", "CPU s / simulated s", "total CPU (s)",
                 "median max |Δθ|/λ", "median |Δpeak|/peak"])
    for m in ctx.engines:
        rows = [r for s in scenarios if (r := ctx.row(s.name, m)) is not None]
        done = [r.metrics for r in rows if r.metrics.completed]
        ok = [r.metrics for r in rows if r.status is Status.OK]
        cost = [c for x in done if (c := x.cpu_per_simulated_second) is not None]
        errs = [x.max_error for x in ok if x.max_error is not None]
        # in free rocking the peak is the initial tilt: no measure of accuracy
        peaks = [abs(r.metrics.peak_error) for r in rows if r.status is Status.OK
                 and r.metrics.peak_error is not None and not r.scenario.excitation.is_free]
        t.add_row([
            Cell(m, kind="head"), f"{len(ok)}/{len(rows)}",
            fmt_factor(_median(cost)) if cost else Cell("–", kind="crashed"),
            fmt_seconds(sum(x.cpu_time or 0.0 for x in done)),
            fmt_error(_median(errs)),
            fmt_impact(_median(peaks)) if peaks else "–",
        ])
    return t


def paper_experiment_table(ctx: Context, scenarios: Sequence[Scenario]) -> Table | None:
    """The paper's Table 7 (errors against the experiment) for the scenarios present."""
    pt = paper_tables().get("table7")
    if pt is None or not any(pt.values(s) is not None for s in scenarios):
        return None
    number = ctx.next_number()
    t = Table(key="paper-table7",
              title=f"Table {number}. Published: paper's Table {pt.number}",
              caption=f"{pt.title}. {pt.note}",
              columns=["scenario", "f (Hz)", "A (mm)", *pt.methods],
              groups=[("input", 3), (f"paper, Table {pt.number}, vs experiment",
                                     len(pt.methods))])
    for s in scenarios:
        vals = pt.values(s)
        if vals is None:
            continue
        f, a = input_label(s)
        t.add_row([Cell(s.name, kind="head"), f, a, *[
            Cell(f"{v:g} %" if isinstance(v, (int, float)) else str(v), kind="paper")
            for v in vals]])
    return t


def paper_findings(group: str, scenarios: Sequence[Scenario]) -> tuple[str, list[str]] | None:
    """The paper's summary findings that apply to a group (title, bullet points)."""
    key = {"stack-sine": "tables11_12", "free": "free"}.get(group)
    if key is None:
        return None
    summ = paper_summary(key)
    from rockbench.report.paper import is_catalog_case

    if not any(is_catalog_case(s) for s in scenarios):
        return None
    title = f"Published ({summ['number']}): {summ['title']}"
    items = list(summ["findings"])
    if summ.get("note"):
        items.append(summ["note"])
    return title, items


# ---------------------------------------------------------------------- tables per group
GroupTable = Callable[[Context, str, Sequence[Scenario]], list[Table]]
#: The tables of a scenario group's section, in order (see :func:`group_table`).
GROUP_TABLES: list[GroupTable] = []


def group_table(make: GroupTable) -> GroupTable:
    """Register a table of the group sections: ``make(ctx, group, scenarios)`` returns the
    tables it draws for that group (none where it does not apply). Adding a table to the
    report is writing one such function here."""
    GROUP_TABLES.append(make)
    return make


def group_tables(ctx: Context, group: str, scenarios: Sequence[Scenario]) -> list[Table]:
    """Every registered table of one group, in registration order."""
    return [t for make in GROUP_TABLES for t in make(ctx, group, scenarios)]


@group_table
def _free(ctx: Context, group: str, scenarios: Sequence[Scenario]) -> list[Table]:
    return free_tables(ctx, scenarios) if group == "free" else []


@group_table
def _peaks(ctx: Context, group: str, scenarios: Sequence[Scenario]) -> list[Table]:
    return peak_tables(ctx, group, scenarios) if group != "free" else []


@group_table
def _errors(ctx: Context, group: str, scenarios: Sequence[Scenario]) -> list[Table]:
    return [error_table(ctx, group, scenarios)] if group != "free" and ctx.engines else []


@group_table
def _experiment(ctx: Context, group: str, scenarios: Sequence[Scenario]) -> list[Table]:
    t = paper_experiment_table(ctx, scenarios) if group == "single-sine" else None
    return [t] if t is not None else []


def horizon_table(ctx: Context, group: str, scenarios: Sequence[Scenario]) -> Table | None:
    """Predictability horizon t* per case and each engine's error up to it (None: not measured).

    t* is read from the runs' metrics (``RunMetrics.horizon``, the same for every
    method of a scenario); past it the case is chaotic and only distributions compare.
    """
    def horizon(s: Scenario) -> float | None:
        rows = [ctx.row(s.name, m) for m in ctx.methods]
        return next((r.metrics.horizon for r in rows
                     if r is not None and r.metrics.horizon is not None), None)

    if all(horizon(s) is None for s in scenarios):
        return None
    columns = ["scenario", "f (Hz)", "A (mm)", "ü_g/(g tan λ)", "t* (s)", "duration (s)",
               "beyond t*", *ctx.engines]
    groups = [("input", 4), ("predictability", 3)]
    if ctx.engines:
        groups.append(("max |Δθ|/λ up to t*", len(ctx.engines)))
    t = Table(
        key=f"horizon-{group}",
        title=f"Table {ctx.next_number()}. Predictability horizon, "
              f"{group_title(group).lower()}",
        caption=("t*: the first time at which an ensemble of analytic reference runs with "
                 "tiny perturbations of the input amplitude and the initial tilt (see the "
                 "predictability section) spreads by more than the stated fraction of λ; the "
                 "duration when it never does (well posed). Every time-history, impact and "
                 "peak error of this report is measured up to t*; past it the reference is not "
                 "predictable and engines are compared by distributions instead."),
        columns=columns, groups=groups)
    for s in scenarios:
        h = horizon(s)
        cells: list[Cell | str] = _case_columns(s)
        if h is None:
            cells += ["–", fmt_seconds(s.duration), Cell("not measured")]
        else:
            chaotic = h < s.duration
            cells += [fmt_seconds(h), fmt_seconds(s.duration),
                      Cell("chaotic: see the distributions" if chaotic else "well posed",
                           title=f"spread > λ fraction after {h:.2f} s" if chaotic else "")]
        for m in ctx.engines:
            r = ctx.row(s.name, m)
            cells.append(_error_cell(t, r, fmt_error(r.metrics.max_error) if r else "–", m))
        t.add_row(cells)
    return t


@group_table
def _horizon(ctx: Context, group: str, scenarios: Sequence[Scenario]) -> list[Table]:
    t = horizon_table(ctx, group, scenarios) if group != "free" else None
    return [t] if t is not None else []


@group_table
def _cost(ctx: Context, group: str, scenarios: Sequence[Scenario]) -> list[Table]:
    return [cost_table(ctx, group, scenarios)] if ctx.engines else []
