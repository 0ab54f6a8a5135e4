"""The regression matrix: engines × scenarios, each cell checked against tolerances.

:func:`run_matrix` computes (or takes from the results store) the analytic
reference of each scenario once, runs every engine on every scenario in
isolated child processes, stores each run as it finishes, and judges each cell:

* **pass / fail** against the tolerance file (:mod:`rockbench.report.tolerances`);
* **regression** against a baseline (JSON of an earlier matrix, written with
  ``--write-baseline``) when a metric grew beyond ``base·(1 + rel) + abs`` or
  the run no longer ends as it did;
* **skip** when the engine cannot model the scenario (status ``unsupported``).

Outputs: a grid (engines as columns, coloured on a terminal, plain text
otherwise), JUnit XML (one ``testsuite`` per engine, one ``testcase`` per
scenario) and the exit status (0 all pass, 1 any fail or regression).
"""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import numpy as np

import rockbench
from rockbench import analytic, metrics
from rockbench.engines import engine_class
from rockbench.errors import RockbenchError
from rockbench.report.tolerances import DEFAULT_REGRESSION, Tolerances
from rockbench.runner import Job, run_jobs
from rockbench.scenarios import Scenario
from rockbench.store import Store, jsonable
from rockbench.trajectory import Status, Trajectory

__all__ = ["Cell", "MatrixResult", "run_metrics", "sliding", "rocking_impacts", "references",
           "run_matrix", "evaluate", "regressions", "load_baseline", "write_baseline",
           "write_junit", "format_grid",
           "grid_table", "BaselineError", "PASS", "FAIL", "REGRESSION", "SKIP"]

PASS, FAIL, REGRESSION, SKIP = "pass", "fail", "regression", "skip"
#: A zero crossing of θ is an impact only after |θ| reached this fraction of λ.
IMPACT_THRESHOLD = 0.01


class BaselineError(RockbenchError, ValueError):
    """A baseline file is unreadable or malformed."""


# ---------------------------------------------------------------------- metrics
def _f(x: Any) -> float | None:
    """A finite float or None."""
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def sliding(traj: Trajectory, scenario: Scenario) -> float | None:
    """Largest sliding of the bottom block on the base (m), None if positions are unknown.

    A block that rocks without sliding has its centroid where the rigid
    rotation about its active pivot puts it: ``x = u_g + s b' − s b' cos θ +
    h sin θ`` (``s = sgn θ``, ``b'`` the pivot half-width, ``h`` the half-height,
    ``u_g`` the base displacement). The largest departure from it measures
    sliding or drift of the contact (physical only with low friction). Only
    samples where the block is within its critical angle count (an overturning
    block slides when it lands).
    """
    if traj.t.size == 0 or not np.all(np.isfinite(traj.x[:, 0])):
        return None
    b = scenario.blocks[0]
    th = traj.theta[:, 0]
    sgn = np.sign(th)
    u = np.asarray(scenario.excitation.displacement(traj.t), float)
    x_kin = (u + scenario.stack.offsets[0] + sgn * b.pivot_half_width
             - sgn * b.pivot_half_width * np.cos(th) + b.h * np.sin(th))
    keep = np.abs(th) <= b.rocking(scenario.g).lam  # not falling over
    return float(np.max(np.abs(traj.x[keep, 0] - x_kin[keep]))) if keep.any() else None


def rocking_impacts(traj: Trajectory, lam: float, threshold: float = IMPACT_THRESHOLD,
                    block: int = 0) -> np.ndarray:
    """Impact times of a block: zero crossings of θ after it rocked beyond ``threshold`` λ.

    Crossings of contact noise (a block that barely lifts, or jitters before
    uplift) are ignored: a crossing counts only if |θ| reached ``threshold``·λ
    since the previous counted crossing (or the start). Times are linearly
    interpolated between samples, the same way for engines and references.
    """
    return metrics.zero_crossings(traj.t, traj.theta[:, block], threshold * lam)


def run_metrics(traj: Trajectory, ref: Trajectory | None, scenario: Scenario) -> dict[str, Any]:
    """JSON-able metrics of one run, against the analytic reference when there is one.

    Keys: ``peak_ratio`` (max|θ|/λ per block), ``max_error`` (max |Δθ|/λ; for an
    overturning reference only until the reference passes λ), ``max_error_early``
    (the same up to the reference's third impact), ``impact_time_errors`` and
    their maximum ``impact_time_error`` (first three impacts of the bottom
    block, relative, from :func:`rocking_impacts`), ``impacts_missing``
    (reference impacts the run lacks),
    ``peak_error`` (largest |relative error| of max|θ|/λ, when the reference
    uplifts and does not overturn), ``time_to_rest``, ``wall_time``,
    ``realtime_factor`` (simulated / wall seconds), ``slide`` (:func:`sliding`),
    ``max_wobble`` (rad), ``reference_status``.
    Values that cannot be computed are None.
    """
    lam = scenario.critical_angle
    m: dict[str, Any] = {
        "peak_ratio": metrics.peak_ratio(traj, lam).tolist(),
        "slide": sliding(traj, scenario),
        "max_wobble": float(np.max(np.abs(traj.wobble))) if traj.t.size else None,
        "wall_time": float(traj.wall_time),
        "realtime_factor": (scenario.duration / traj.wall_time
                            if traj.status.completed and traj.wall_time > 0 else None),
        "time_to_rest": metrics.time_to_rest(traj, lam) if traj.t.size else None,
        "n_samples": int(traj.t.size),
        "reference_status": ref.status.value if ref is not None else None,
        "max_error": None, "max_error_early": None, "impact_time_errors": None,
        "impact_time_error": None, "impacts_missing": None, "peak_error": None,
    }
    if ref is None or not ref.status.completed or not traj.status.completed or not traj.t.size:
        return jsonable(m)
    t_end: float | None = None
    if ref.status is Status.OVERTURNED:  # beyond λ the fall is not a rocking comparison
        past = np.nonzero(np.max(np.abs(ref.theta), axis=1) > lam)[0]
        t_end = float(ref.t[past[0]]) if past.size else None
    m["max_error"] = metrics.max_error(traj, ref, lam, t_end)
    ref_imp = rocking_impacts(ref, lam)
    if t_end is not None:
        ref_imp = ref_imp[ref_imp <= t_end]
    early = float(ref_imp[2]) if ref_imp.size >= 3 else t_end
    if early is not None and t_end is not None:
        early = min(early, t_end)
    m["max_error_early"] = metrics.max_error(traj, ref, lam, early)
    k = min(3, ref_imp.size)
    if k:
        eng_imp = rocking_impacts(traj, lam)[:k]
        errs = np.full(k, np.nan)
        errs[:eng_imp.size] = np.abs(eng_imp - ref_imp[:eng_imp.size]) / ref_imp[:eng_imp.size]
        m["impact_time_errors"] = errs.tolist()
        m["impacts_missing"] = int(np.sum(~np.isfinite(errs)))
        m["impact_time_error"] = float(np.nanmax(errs)) if np.any(np.isfinite(errs)) else None
    if ref.status is Status.OK:
        peaks = metrics.peak_ratio(ref, lam)
        if np.all(peaks > 0.01):
            m["peak_error"] = float(np.max(np.abs(metrics.peak_relative_error(traj, ref, lam))))
    return jsonable(m)


# ---------------------------------------------------------------------- cells
@dataclass
class Cell:
    """One engine × scenario cell of the matrix.

    Attributes
    ----------
    scenario, engine : str
        Coordinates.
    settings : dict
        Requested settings.
    status : Status
        How the run ended.
    message : str
        Reason or note.
    metrics : dict
        From :func:`run_metrics`.
    reused : bool
        Taken from the store by ``--resume``.
    outcome : str
        pass, fail, regression or skip.
    reasons : list of str
        Why it did not pass.
    """

    scenario: str
    engine: str
    settings: dict[str, Any]
    status: Status
    message: str
    metrics: dict[str, Any]
    reused: bool = False
    outcome: str = PASS
    reasons: list[str] = field(default_factory=list)

    @property
    def key(self) -> str:
        """``engine/scenario`` (the baseline key)."""
        return f"{self.engine}/{self.scenario}"


def _fmt(x: float) -> str:
    return f"{x:.3g}" if abs(x) >= 1e-3 or x == 0 else f"{x:.2e}"


def evaluate(cell: Cell, limits: Mapping[str, Any]) -> list[str]:
    """Tolerance failures of a cell (empty: it passes).

    Parameters
    ----------
    cell : Cell
        The run's status and metrics.
    limits : mapping
        From :meth:`Tolerances.for_cell`.
    """
    rule = limits.get("status", "reference")
    ref_status = cell.metrics.get("reference_status")
    completed = (Status.OK.value, Status.OVERTURNED.value)
    if rule == "any":
        allowed: tuple[str, ...] = tuple(s.value for s in Status)
    elif rule == "completed" or (rule == "reference" and ref_status not in completed):
        allowed = completed
    elif rule == "reference":
        allowed = (ref_status,)
    else:
        allowed = tuple(rule)
    if cell.status.value not in allowed:
        why = f": {cell.message}" if cell.message else ""
        return [f"status {cell.status.value}{why} (expected {' or '.join(allowed)})"]
    out = []
    for name, limit in limits.items():
        if name == "status" or limit is None:
            continue
        if name == "impact_time_error" and (cell.metrics.get("impacts_missing") or 0) > 0:
            out.append(f"missed {cell.metrics['impacts_missing']} of the reference's first "
                       "impacts")
            continue
        value = _f(cell.metrics.get(name))
        if value is not None and value > limit:
            out.append(f"{name} {_fmt(value)} > {_fmt(limit)}")
    return out


def regressions(cell: Cell, base: Mapping[str, Any], reg: Mapping[str, Any]) -> list[str]:
    """Regressions of a cell against its baseline entry (empty: none).

    A completed baseline run that now ends differently, or a metric in
    ``reg["metrics"]`` that grew beyond ``base·(1 + rel) + abs``.
    """
    out = []
    b_status = base.get("status")
    if b_status in (Status.OK.value, Status.OVERTURNED.value) and cell.status.value != b_status:
        out.append(f"status {b_status} → {cell.status.value}")
        return out
    rel, ab = float(reg.get("rel", 0.25)), float(reg.get("abs", 0.002))
    b_metrics = base.get("metrics", {})
    for name in reg.get("metrics", DEFAULT_REGRESSION["metrics"]):
        b, c = _f(b_metrics.get(name)), _f(cell.metrics.get(name))
        if b is None or c is None:
            continue
        if c > b * (1.0 + rel) + ab:
            grow = f" (+{100 * (c - b) / b:.0f}%)" if b > 0 else ""
            out.append(f"{name} {_fmt(b)} → {_fmt(c)}{grow}")
    return out


@dataclass
class MatrixResult:
    """Everything a matrix run produced.

    Attributes
    ----------
    suite : str
        Suite (or scenario list) name.
    scenarios, engines : list of str
        Rows and columns, in order.
    cells : dict
        ``(scenario, engine)`` → :class:`Cell`.
    reference_notes : dict
        Scenario → why it has no usable reference.
    tolerances : str
        Source of the tolerances.
    baseline : str
        Source of the baseline ('' if none).
    wall_time : float
        Wall time of the whole matrix in s.
    """

    suite: str
    scenarios: list[str]
    engines: list[str]
    cells: dict[tuple[str, str], Cell]
    reference_notes: dict[str, str] = field(default_factory=dict)
    tolerances: str = ""
    baseline: str = ""
    wall_time: float = 0.0

    def count(self, outcome: str) -> int:
        """Number of cells with this outcome."""
        return sum(c.outcome == outcome for c in self.cells.values())

    @property
    def exit_code(self) -> int:
        """0 if no cell failed or regressed, else 1."""
        return 1 if self.count(FAIL) or self.count(REGRESSION) else 0

    def summary(self) -> str:
        """One line: counts per outcome."""
        return (f"{len(self.cells)} cells: {self.count(PASS)} passed, {self.count(FAIL)} "
                f"failed, {self.count(REGRESSION)} regressed, {self.count(SKIP)} skipped "
                f"({self.wall_time:.1f} s)")


# ---------------------------------------------------------------------- running
def references(
    scenarios: Sequence[Scenario],
    store: Store | None = None,
    *,
    n_jobs: int | None = 1,
    timeout: float | None = None,
    executor: str = "process",
    scheduler: Any = None,
) -> tuple[dict[str, Trajectory | None], dict[str, str]]:
    """Analytic references of the scenarios, computed once and cached in the store.

    Returns
    -------
    refs : dict
        Scenario name → reference trajectory (None where there is none).
    notes : dict
        Scenario name → why there is no (usable) reference.
    """
    refs: dict[str, Trajectory | None] = {}
    notes: dict[str, str] = {}
    todo = []
    for sc in scenarios:
        if not analytic.has_reference(sc):
            refs[sc.name] = None
            notes[sc.name] = "no analytic model (more than two or off-centre blocks)"
            continue
        cached = store.reference(sc) if store is not None else None
        if cached is not None:
            refs[sc.name] = cached
        else:
            todo.append(Job(sc, "analytic", {}))
    for job, traj in zip(todo, run_jobs(todo, n_jobs=n_jobs, timeout=timeout, executor=executor,
                                        scheduler=scheduler), strict=True):
        if traj.status.completed:
            refs[job.scenario.name] = traj
            if store is not None:
                store.save_reference(job.scenario, traj)
        else:
            refs[job.scenario.name] = None
            notes[job.scenario.name] = f"reference {traj.status.value}: {traj.message}"
    return refs, notes


def run_matrix(
    scenarios: Sequence[Scenario],
    engines: Sequence[str],
    tolerances: Tolerances,
    *,
    settings: Mapping[str, Mapping[str, Any]] | None = None,
    suite: str = "",
    store: Store | None = None,
    baseline: Mapping[str, Any] | None = None,
    resume: bool = False,
    n_jobs: int | None = 1,
    timeout: float | None = None,
    executor: str = "process",
    scheduler: Any = None,
    on_cell: Callable[[Cell], None] | None = None,
) -> MatrixResult:
    """Run the engines × scenarios matrix and judge every cell.

    Parameters
    ----------
    scenarios : sequence of Scenario
        Rows.
    engines : sequence of str
        Columns (canonical engine names; the analytic reference is not a column).
    tolerances : Tolerances
        Limits per cell.
    settings : mapping, optional
        Engine → requested settings.
    suite : str
        Suite name (selects the tolerance file's suite layer, labels outputs).
    store : Store, optional
        Results store: every run is appended as it finishes, references are cached.
    baseline : mapping, optional
        From :func:`load_baseline`.
    resume : bool
        Reuse stored runs of the same cell (scenario content, engine and its
        version, settings, rockbench version) instead of running them again.
    n_jobs, timeout, executor, scheduler
        Passed to :func:`rockbench.runner.run_jobs`.
    on_cell : callable, optional
        Called with each finished (or reused) cell.
    """
    import time

    start = time.perf_counter()
    settings = settings or {}
    engines = [e for e in engines if e != "analytic"]
    if not engines:
        raise RockbenchError("the matrix needs at least one engine besides 'analytic'")
    refs, notes = references(scenarios, store, n_jobs=n_jobs, timeout=timeout,
                             executor=executor, scheduler=scheduler)
    versions = {e: engine_class(e).version() for e in engines}
    by_name = {sc.name: sc for sc in scenarios}
    cells: dict[tuple[str, str], Cell] = {}
    jobs = []
    for sc in scenarios:
        for e in engines:
            s = dict(settings.get(e, {}))
            old = (store.find(sc, e, s, engine_version=versions[e],
                              rockbench_version=rockbench.__version__)
                   if resume and store is not None else None)
            if old is not None:
                cell = Cell(sc.name, e, s, old.status, old.message, old.metrics, reused=True)
                cells[(sc.name, e)] = cell
                if on_cell is not None:
                    on_cell(cell)
            else:
                jobs.append(Job(sc, e, s))

    def finished(job: Job, traj: Trajectory) -> None:
        sc = by_name[job.scenario.name]
        m = run_metrics(traj, refs.get(sc.name), sc)
        if store is not None:
            store.record(sc, job.engine, job.settings, traj, m, kind="matrix", suite=suite,
                         engine_version=versions[job.engine])
        cell = Cell(sc.name, job.engine, dict(job.settings), traj.status, traj.message, m)
        cells[(sc.name, job.engine)] = cell
        if on_cell is not None:
            on_cell(cell)

    run_jobs(jobs, n_jobs=n_jobs, timeout=timeout, on_result=finished, executor=executor,
             scheduler=scheduler)
    base_cells = (baseline or {}).get("cells", {})
    for (name, e), cell in cells.items():
        if cell.status is Status.UNSUPPORTED:
            cell.outcome, cell.reasons = SKIP, [cell.message or "unsupported"]
            continue
        fails = evaluate(cell, tolerances.for_cell(e, name, suite))
        regs = (regressions(cell, base_cells[cell.key], tolerances.regression)
                if cell.key in base_cells else [])
        cell.reasons = fails + [f"regression: {r}" for r in regs]
        cell.outcome = FAIL if fails else REGRESSION if regs else PASS
    return MatrixResult(suite=suite, scenarios=[sc.name for sc in scenarios],
                        engines=list(engines), cells=cells, reference_notes=notes,
                        tolerances=tolerances.source,
                        baseline=str((baseline or {}).get("source", "")),
                        wall_time=time.perf_counter() - start)


# ---------------------------------------------------------------------- baseline
def write_baseline(result: MatrixResult, path: str | Path) -> Path:
    """Write the matrix's statuses and metrics as a baseline JSON file."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    data = {
        "format": 1,
        "suite": result.suite,
        "rockbench_version": rockbench.__version__,
        "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "cells": {c.key: {"status": c.status.value, "settings": c.settings,
                          "metrics": c.metrics}
                  for c in sorted(result.cells.values(), key=lambda c: c.key)},
    }
    path.write_text(json.dumps(jsonable(data), indent=1, sort_keys=False) + "\n")
    return path


def load_baseline(path: str | Path) -> dict[str, Any]:
    """Read a baseline written by :func:`write_baseline`.

    Raises
    ------
    BaselineError
        Unreadable, not JSON, or not a rockbench baseline.
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except OSError as exc:
        raise BaselineError(f"{path}: cannot read baseline ({exc.strerror})") from None
    except json.JSONDecodeError as exc:
        raise BaselineError(f"{path}: not JSON ({exc})") from None
    if not (isinstance(data, dict) and data.get("format") == 1
            and isinstance(data.get("cells"), dict)):
        raise BaselineError(f"{path}: not a rockbench baseline (needs format = 1 and cells)")
    for key, cell in data["cells"].items():
        if not (isinstance(cell, dict) and isinstance(cell.get("metrics", {}), dict)
                and cell.get("status") in {s.value for s in Status}):
            raise BaselineError(f"{path}: cell {key!r} needs a valid status and metrics")
    data["source"] = str(path)
    return data


# ---------------------------------------------------------------------- JUnit XML
def write_junit(result: MatrixResult, path: str | Path) -> Path:
    """Write JUnit XML: one ``testsuite`` per engine, one ``testcase`` per scenario.

    Failed and regressed cells carry a ``failure`` element (type ``tolerance``
    or ``regression``), unsupported ones a ``skipped`` element; metrics go to
    ``properties`` and the run's wall time to ``time``.
    """
    path = Path(path)
    root = ET.Element("testsuites", name=f"rockbench matrix {result.suite}".strip())
    totals = {"tests": 0, "failures": 0, "errors": 0, "skipped": 0}
    stamp = datetime.now(timezone.utc).isoformat(timespec="seconds")
    total_time = 0.0
    for engine in result.engines:
        cells = [result.cells[(s, engine)] for s in result.scenarios
                 if (s, engine) in result.cells]
        n_fail = sum(c.outcome in (FAIL, REGRESSION) for c in cells)
        n_skip = sum(c.outcome == SKIP for c in cells)
        t_suite = sum(_f(c.metrics.get("wall_time")) or 0.0 for c in cells)
        suite_el = ET.SubElement(
            root, "testsuite", name=f"rockbench.{result.suite or 'matrix'}.{engine}",
            tests=str(len(cells)), failures=str(n_fail), errors="0", skipped=str(n_skip),
            time=f"{t_suite:.3f}", timestamp=stamp,
        )
        for c in cells:
            case = ET.SubElement(suite_el, "testcase", name=c.scenario,
                                 classname=f"rockbench.{result.suite or 'matrix'}.{engine}",
                                 time=f"{_f(c.metrics.get('wall_time')) or 0.0:.3f}")
            props = ET.SubElement(case, "properties")
            ET.SubElement(props, "property", name="status", value=c.status.value)
            for k, v in sorted(c.metrics.items()):
                if v is not None and not isinstance(v, (list, dict)):
                    ET.SubElement(props, "property", name=k, value=str(v))
            if c.outcome in (FAIL, REGRESSION):
                kind = "tolerance" if c.outcome == FAIL else "regression"
                fail = ET.SubElement(case, "failure", type=kind,
                                     message="; ".join(c.reasons))
                fail.text = "\n".join(c.reasons + ([f"message: {c.message}"]
                                                   if c.message else []))
            elif c.outcome == SKIP:
                ET.SubElement(case, "skipped", message="; ".join(c.reasons))
            if c.message and c.outcome == PASS:
                ET.SubElement(case, "system-out").text = c.message
        totals["tests"] += len(cells)
        totals["failures"] += n_fail
        totals["skipped"] += n_skip
        total_time += t_suite
    for k, v in totals.items():
        root.set(k, str(v))
    root.set("time", f"{total_time:.3f}")
    ET.indent(root)
    path.parent.mkdir(parents=True, exist_ok=True)
    ET.ElementTree(root).write(path, encoding="utf-8", xml_declaration=True)
    return path


# ---------------------------------------------------------------------- the grid
_MARK = {PASS: "PASS", FAIL: "FAIL", REGRESSION: "REGR", SKIP: "skip"}
_STYLE = {PASS: "green", FAIL: "bold red", REGRESSION: "bold magenta", SKIP: "dim"}


def _cell_text(c: Cell | None) -> str:
    if c is None:
        return "-"
    if c.outcome == SKIP:
        return "skip"
    if not c.status.completed:
        return f"{_MARK[c.outcome]} {c.status.value}"
    err = _f(c.metrics.get("max_error"))
    val = f"{err:.4f}" if err is not None else c.status.value
    if c.status is Status.OVERTURNED and err is not None:
        val += " ovt"
    return f"{_MARK[c.outcome]} {val}" + ("*" if c.reused else "")


def _legend(result: MatrixResult) -> list[str]:
    lines = ["cells: outcome and max |Δθ|/λ against the analytic reference"
             + (" (* = reused from the store)" if any(c.reused for c in result.cells.values())
                else "")]
    for name, note in result.reference_notes.items():
        lines.append(f"note: {name}: {note}; only the status is checked")
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

    title = f"rockbench matrix {result.suite}"
    table = Table(title=title, caption=f"tolerances: {result.tolerances}"
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
