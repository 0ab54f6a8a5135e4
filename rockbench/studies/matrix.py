"""The regression matrix: engines × scenarios, each cell checked against tolerances.

:func:`run_matrix` plans every engine on every scenario and runs them through the
campaign (:func:`rockbench.campaign.run_campaign`: references, isolated runs,
metrics, every run recorded as it finishes), then judges each cell:

* **pass / fail** against the tolerance file (:mod:`rockbench.studies.tolerances`);
  a cell whose analytic reference did not complete fails (it cannot be
  checked) unless its tolerance checks the status only;
* **regression** against a baseline (:mod:`rockbench.studies.baseline`) when a
  metric grew beyond ``base·(1 + rel) + abs`` or the run no longer ends as it did;
* **skip** when the engine cannot model the scenario (status ``unsupported``).

Time-history errors are measured up to each scenario's predictability horizon
t* (:mod:`rockbench.campaign.predictability`), as in the comparison report: a
cell's ``max_error`` is its largest deviation up to t*, and a divergence
after t* (where the reference itself is not predictable) fails no cell. t* is
measured only for the scenarios where a cell checks a metric that stops at it
(:data:`HORIZON_METRICS`, as a tolerance or a baseline regression): a matrix
that checks statuses only costs no ensemble. Where the ensemble's members end
differently (some overturn, others do not), how the run ends is not predictable
either: the status rule ``reference`` then accepts any completed run
(:func:`horizon_limits`).

Rendering lives in :mod:`rockbench.report.grid` (the grid) and
:mod:`rockbench.report.junit` (JUnit XML); the exit status is
:attr:`MatrixResult.exit_code` (0 all pass, 1 any fail or regression).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rockbench.campaign import CampaignOptions, PlannedRun, run_campaign
from rockbench.campaign.predictability import DEFAULT_MEMBERS, Predictability
from rockbench.errors import RockbenchError
from rockbench.evaluation import RunMetrics
from rockbench.method import REFERENCE, Method
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Scenario
from rockbench.studies.baseline import Baseline, BaselineCell
from rockbench.studies.tolerances import DEFAULT_REGRESSION, Tolerances
from rockbench.trajectory import Status

__all__ = ["Cell", "MatrixResult", "run_matrix", "evaluate", "regressions", "fmt_number",
           "KIND", "PASS", "FAIL", "REGRESSION", "SKIP"]

PASS, FAIL, REGRESSION, SKIP = "pass", "fail", "regression", "skip"
#: Metrics measured up to the predictability horizon t*.
HORIZON_METRICS = frozenset({"max_error", "max_error_early", "impact_time_error",
                             "impacts_missing", "peak_error"})
#: The store's ``kind`` of runs made by this study.
KIND = "matrix"


# ---------------------------------------------------------------------- cells
@dataclass
class Cell:
    """One engine × scenario cell of the matrix.

    Attributes
    ----------
    scenario : str
        Row (scenario name).
    method : Method
        Column: the engine and its requested settings.
    metrics : RunMetrics
        The run's metrics (status and message included).
    reused : bool
        Taken from the store by ``--resume``.
    outcome : str
        pass, fail, regression or skip.
    reasons : list of str
        Why it did not pass.
    """

    scenario: str
    method: Method
    metrics: RunMetrics
    reused: bool = False
    outcome: str = PASS
    reasons: list[str] = field(default_factory=list)

    @property
    def engine(self) -> str:
        """The engine (the column name)."""
        return self.method.engine

    @property
    def settings(self) -> dict[str, Any]:
        """The requested settings."""
        return self.method.settings

    @property
    def status(self) -> Status:
        """How the run ended."""
        return self.metrics.status

    @property
    def message(self) -> str:
        """Reason or note of the run."""
        return self.metrics.message

    @property
    def key(self) -> str:
        """``engine/scenario`` (the baseline key)."""
        return f"{self.engine}/{self.scenario}"


def fmt_number(x: float) -> str:
    """A metric value in reasons and tables (3 significant digits)."""
    return f"{x:.3g}" if abs(x) >= 1e-3 or x == 0 else f"{x:.2e}"


def _status_only(limits: Mapping[str, Any]) -> bool:
    """The tolerance checks how the run ends and nothing else."""
    return (limits.get("status", "reference") != "reference"
            and all(v is None for k, v in limits.items() if k != "status"))


def evaluate(cell: Cell, limits: Mapping[str, Any]) -> list[str]:
    """Tolerance failures of a cell (empty: it passes).

    Parameters
    ----------
    cell : Cell
        The run's metrics.
    limits : mapping
        From :meth:`Tolerances.for_cell`: the ``status`` rule and metric → limit
        (None: unchecked).
    """
    m = cell.metrics
    rule = limits.get("status", "reference")
    ref = m.reference_status
    if ref is not None and not ref.completed and not _status_only(limits):
        why = m.error_note or f"reference {ref.value}"
        return [f"{why}: the cell cannot be checked against it"]
    completed = (Status.OK.value, Status.OVERTURNED.value)
    if rule == "any":
        allowed: tuple[str, ...] = tuple(s.value for s in Status)
    elif rule == "completed" or (rule == "reference" and ref is None):
        allowed = completed
    elif rule == "reference":
        allowed = (ref.value,) if ref is not None else completed
    else:
        allowed = tuple(rule)
    if cell.status.value not in allowed:
        why = f": {cell.message}" if cell.message else ""
        return [f"status {cell.status.value}{why} (expected {' or '.join(allowed)})"]
    out = []
    for name, limit in limits.items():
        if name == "status" or limit is None:
            continue
        if name == "impact_time_error" and (m.impacts_missing or 0) > 0:
            out.append(f"missed {m.impacts_missing} of the reference's first impacts")
            continue
        value = m.value(name)
        if value is not None and value > limit:
            out.append(f"{name} {fmt_number(value)} > {fmt_number(limit)}")
    return out


def horizon_limits(limits: Mapping[str, Any], pred: Predictability | None) -> dict[str, Any]:
    """A cell's limits given its scenario's predictability: the ``reference`` status rule
    becomes ``completed`` when perturbed references end differently."""
    out = dict(limits)
    if pred is not None and pred.diverged_outcome and out.get("status", "reference") == "reference":
        out["status"] = "completed"
    return out


def regressions(cell: Cell, base: BaselineCell, reg: Mapping[str, Any]) -> list[str]:
    """Regressions of a cell against its baseline entry (empty: none).

    A completed baseline run that now ends differently, or a metric in
    ``reg["metrics"]`` that grew beyond ``base·(1 + rel) + abs``.
    """
    if base.status.completed and cell.status is not base.status:
        return [f"status {base.status.value} → {cell.status.value}"]
    out = []
    rel, ab = float(reg.get("rel", 0.25)), float(reg.get("abs", 0.002))
    for name in reg.get("metrics", DEFAULT_REGRESSION["metrics"]):
        b, c = base.metrics.value(name), cell.metrics.value(name)
        if b is None or c is None:
            continue
        if c > b * (1.0 + rel) + ab:
            grow = f" (+{100 * (c - b) / b:.0f}%)" if b > 0 else ""
            out.append(f"{name} {fmt_number(b)} → {fmt_number(c)}{grow}")
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
    no_model : frozenset of str
        The scenarios no analytic model covers (their cells check the status only).
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
    no_model: frozenset[str] = frozenset()
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
def run_matrix(
    scenarios: Sequence[Scenario],
    engines: Sequence[str],
    tolerances: Tolerances,
    *,
    settings: Mapping[str, Mapping[str, Any]] | None = None,
    suite: str = "",
    db: Path | None = None,
    baseline: Baseline | None = None,
    resume: bool = False,
    execution: ExecutionOptions | None = None,
    on_cell: Callable[[Cell], None] | None = None,
    horizon_members: int = DEFAULT_MEMBERS,
) -> MatrixResult:
    """Run the engines × scenarios matrix and judge every cell.

    Parameters
    ----------
    scenarios : sequence of Scenario
        Rows (names unique).
    engines : sequence of str
        Columns (canonical engine names; the analytic reference is not a column).
    tolerances : Tolerances
        Limits per cell.
    settings : mapping, optional
        Engine → requested settings.
    suite : str
        Suite name (selects the tolerance file's suite layer, labels outputs).
    db : Path, optional
        The results store: every run is appended as it finishes, references are cached.
    baseline : Baseline, optional
        From :func:`rockbench.studies.baseline.load_baseline`.
    resume : bool
        Reuse stored runs of the same identity instead of running them again.
    execution : ExecutionOptions, optional
        Workers, time limit, executor.
    on_cell : callable, optional
        Called with each finished (or reused) cell.
    horizon_members : int
        Perturbed reference runs per scenario that measure its horizon t*
        (0: errors over the whole run).
    """
    start = time.perf_counter()
    settings = settings or {}
    engines = [e for e in engines if e != REFERENCE]
    if not engines:
        raise RockbenchError("the matrix needs at least one engine besides 'analytic'")
    names = [sc.name for sc in scenarios]
    dup = next((n for n in names if names.count(n) > 1), None)
    if dup is not None:
        raise RockbenchError(f"scenario name {dup!r} appears twice in the matrix")
    checked = set(HORIZON_METRICS & set(tolerances.regression.get("metrics", ()))
                  if baseline is not None else ())
    # t* only where a cell checks a metric that stops at it: a status-only matrix costs no
    # ensemble
    timed = {sc.name for sc in scenarios
             if checked or any(tolerances.for_cell(e, sc.name, suite).get(m) is not None
                               for e in engines for m in HORIZON_METRICS)}
    methods = {e: Method.of(e, settings.get(e, {})) for e in engines}
    plan = [PlannedRun(sc, methods[e]) for sc in scenarios for e in engines]
    cells: dict[tuple[str, str], Cell] = {}

    def add(res: Any, _: Any) -> None:
        cell = Cell(res.scenario.name, res.method, res.metrics, reused=res.reused)
        cells[(cell.scenario, cell.engine)] = cell
        if on_cell is not None:
            on_cell(cell)

    campaign = run_campaign(plan, CampaignOptions(
        kind=KIND, suite=suite, db=db, resume=resume,
        execution=execution or ExecutionOptions(),
        timeout=(execution or ExecutionOptions()).timeout,
        horizon_members=horizon_members if timed else 0, horizon_for=timed), on_result=add)
    horizons = campaign.horizons
    base_cells = baseline.cells if baseline is not None else {}
    for (name, e), cell in cells.items():
        if cell.status is Status.UNSUPPORTED:
            cell.outcome, cell.reasons = SKIP, [cell.message or "unsupported"]
            continue
        fails = evaluate(cell, horizon_limits(tolerances.for_cell(e, name, suite),
                                              horizons.get(name)))
        regs = (regressions(cell, base_cells[cell.key], tolerances.regression)
                if cell.key in base_cells else [])
        cell.reasons = fails + [f"regression: {r}" for r in regs]
        cell.outcome = FAIL if fails else REGRESSION if regs else PASS
    ordered = {(sc.name, e): cells[(sc.name, e)] for sc in scenarios for e in engines}
    return MatrixResult(suite=suite, scenarios=names, engines=list(engines), cells=ordered,
                        reference_notes=campaign.reference_notes,
                        no_model=frozenset(n for n, r in campaign.references.items()
                                           if r is None),
                        tolerances=tolerances.source,
                        baseline=baseline.source if baseline is not None else "",
                        wall_time=time.perf_counter() - start)
