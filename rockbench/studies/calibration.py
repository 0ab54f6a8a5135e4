"""Calibration: an engine's declared knobs searched on the calibration cases.

The study behind ``rockbench calibrate ENGINE``. The settings come from
:func:`~rockbench.studies.calibration_plan.plan_search`
(each declared knob moved a factor of 2 at a time from a preset, plus the other
presets). :func:`calibrate` runs every setting on the calibration cases, by
default the catalog's ten free-rocking cases of 20 s (:data:`FREE`) and the six
Single #2 one-sine pulses (:data:`PULSES`), through the campaign
(:func:`rockbench.campaign.run_campaign`): the public engine interface, each run
measured once against the analytic reference
(:func:`rockbench.evaluation.evaluate_run`) and recorded in the results store;
a run whose identity is stored is reused, so a second calibration on the same
store runs nothing. :func:`stored_calibration` builds the same result from the
store alone (whatever code made the runs): how tables are made again without
running an engine.

Per setting (:class:`SettingResult`), worst over its cases: max |θ − θ_ref|/λ,
the relative peak error, the relative error of the first impact times (a
missing impact counts as infinite), how many cases end as the reference does
(rocking or overturned), and the cost in CPU seconds per simulated second. Per
calibration (:class:`Calibration`): the Pareto front of one error against the
cost (:func:`rockbench.studies.pareto.pareto_front`) and the cheapest setting
that meets the :class:`Tolerances` (by default the project's acceptance bounds
of an ``accurate`` preset). Rendering is :mod:`rockbench.report.calibration_report`.

Example::

    from rockbench.studies.calibration import calibrate
    cal = calibrate("pymunk", cases="free", levels=1, db=Path("rockbench.db"))
    best = cal.cheapest()
    print(best.setting.label if best else "none", [r.setting.label for r in cal.front()])
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rockbench.campaign import CampaignOptions, PlannedRun, run_campaign
from rockbench.errors import UnknownScenario
from rockbench.evaluation import RunResult
from rockbench.method import Method
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Scenario, get_scenario, get_suite
from rockbench.scenarios.catalog import FREE_BLOCKS, FREE_TILTS, SINGLE_CASES, STACK_CASES
from rockbench.store import RunRecord, Store, scenario_hash, settings_key
from rockbench.studies.calibration_plan import (
    DEFAULT_LEVELS,
    CalibrationError,
    SearchPlan,
    Setting,
    plan_search,
)
from rockbench.studies.pareto import pareto_front

__all__ = ["CalibrationError", "Tolerances", "SettingResult", "Calibration",
           "calibration_cases", "max_timestep", "calibrate", "run_plan", "stored_calibration",
           "KIND", "FREE", "PULSES", "STACK", "CASE_GROUPS", "ERROR_METRICS"]

#: The store's ``kind`` of the runs made by this study.
KIND = "calibration"
#: Catalog names of the free-rocking calibration cases (B0 at 0.5 λ; B1–B3 at 0.2, 0.5,
#: 0.99 λ; 20 s, 1 kHz output, friction 1, restitution 0).
FREE: tuple[str, ...] = tuple(f"free-{b}" if b == "b0" else f"free-{b}-{t}"
                              for b in FREE_BLOCKS for t in ((0.5,) if b == "b0" else FREE_TILTS))
#: Catalog names of the six Single #2 one-sine pulses (4 s).
PULSES: tuple[str, ...] = tuple(f"single-pulse-{f:.1f}hz-{a}mm" for f, a in SINGLE_CASES)
#: The paper's two-block stack: its eight one-sine pulses (4 s) and the two sinusoids
#: (10 s) whose response is well-posed over the whole record (the six others are chaotic:
#: a perturbation of the input at rounding level changes their peaks by more than 5 %).
STACK: tuple[str, ...] = (tuple(f"stack-pulse-{f:.1f}hz-{a}mm" for f, a in STACK_CASES)
                          + ("stack-sine-5.0hz-2mm", "stack-sine-5.0hz-4mm"))
#: Named groups of calibration cases (``--cases``).
CASE_GROUPS: dict[str, tuple[str, ...]] = {"free": FREE, "pulses": PULSES, "stack": STACK,
                                           "all": FREE + PULSES}
#: The error measures of a setting (lower is better), worst over its cases.
ERROR_METRICS = ("max_error", "peak_error", "impact_time_error")


def calibration_cases(spec: str | Sequence[str] = "all",
                      duration: float | None = None) -> list[Scenario]:
    """The scenarios of ``spec``: ``free``, ``pulses``, ``stack``, ``all``, suites or catalog names.

    Parameters
    ----------
    spec : str or sequence of str
        A group of :data:`CASE_GROUPS`, or a comma list (or sequence) of groups,
        suite names and catalog scenario names; duplicates are dropped.
    duration : float, optional
        Every case shortened (or lengthened) to this many seconds: a quick look
        (other scenarios, with other references and store identities).

    Raises
    ------
    CalibrationError
        An unknown name, no case, or a duration that is not positive.
    """
    items = ([x.strip() for x in spec.split(",")] if isinstance(spec, str)
             else [str(x).strip() for x in spec])
    items = [x for x in items if x]
    if not items:
        raise CalibrationError("--cases expects free, pulses, stack, all or a comma list of "
                               "scenario names, got nothing")
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        raise CalibrationError(f"--duration expects a positive number of seconds, got "
                               f"{duration:g}")
    names: list[str] = []
    for item in items:
        if item in CASE_GROUPS:
            names += CASE_GROUPS[item]
            continue
        try:
            names += get_suite(item)
        except UnknownScenario:
            names.append(item)
    out: list[Scenario] = []
    for name in dict.fromkeys(names):
        try:
            sc = get_scenario(name)
        except UnknownScenario:
            raise CalibrationError(
                f"--cases expects free, pulses, stack, all or catalog scenario and suite "
                f"names, got {name!r} (see `rockbench scenarios`)") from None
        out.append(sc if duration is None else sc.replace(duration=float(duration)))
    return out


# ---------------------------------------------------------------------- results
@dataclass(frozen=True)
class Tolerances:
    """What a setting must meet on every case (None: not judged). Every case must also
    complete, be measured against a reference and end as the reference does.

    The defaults are the project's acceptance bounds of an ``accurate`` preset
    (docs/engines/index.md): 0.005 λ, impact times within 0.5 %, peaks within 2 %; the
    project states the first two for free rocking and the third for the pulses, a
    calibration applies all three to every case.

    Attributes
    ----------
    max_error : float or None
        Worst max |θ − θ_ref|/λ.
    peak_error : float or None
        Worst relative peak error (of the cases whose reference ends rocking).
    impact_time_error : float or None
        Worst relative error of the first impact times; a missing impact fails.
    """

    max_error: float | None = 0.005
    peak_error: float | None = 0.02
    impact_time_error: float | None = 0.005

    def __post_init__(self) -> None:
        for name in ERROR_METRICS:
            v = getattr(self, name)
            if v is not None and not (isinstance(v, (int, float)) and math.isfinite(v)
                                      and v > 0):
                raise CalibrationError(f"--tolerance {name} must be a number > 0, got {v!r}")


def _agrees(r: RunResult) -> bool:
    """The run completed and ends as its reference (both rocking, or both overturned)."""
    ref = r.metrics.reference_status
    return r.metrics.completed and (ref is None or r.status is ref)


def _cpu(r: RunResult) -> float:
    m = r.metrics
    return float(m.cpu_time if m.cpu_time else m.wall_time)


@dataclass(frozen=True)
class SettingResult:
    """One setting on every case.

    Attributes
    ----------
    setting : Setting
        What was tried.
    method : Method
        Its engine and requested settings.
    runs : tuple of RunResult
        One per case that has a result, in case order.
    missing : tuple of str
        Cases without a result (from :func:`stored_calibration` only).
    """

    setting: Setting
    method: Method
    runs: tuple[RunResult, ...]
    missing: tuple[str, ...] = ()

    def _worst(self, name: str) -> float | None:
        vals = [abs(v) for r in self.runs if r.metrics.completed
                and (v := r.metrics.value(name)) is not None]
        return max(vals) if vals else None

    @property
    def max_error(self) -> float | None:
        """Worst max |θ − θ_ref|/λ over the completed runs (None if none has one)."""
        return self._worst("max_error")

    @property
    def peak_error(self) -> float | None:
        """Worst |relative peak error| over the completed runs."""
        return self._worst("peak_error")

    @property
    def impact_time_error(self) -> float | None:
        """Worst relative error of the first impact times that both have."""
        return self._worst("impact_time_error")

    @property
    def impacts_missing(self) -> int:
        """Reference impacts (of the first three per case) the runs lack."""
        return sum(r.metrics.impacts_missing or 0 for r in self.runs)

    @property
    def agreements(self) -> int:
        """Runs that complete and end as their reference does."""
        return sum(_agrees(r) for r in self.runs)

    @property
    def cases(self) -> int:
        """Cases planned (run or missing)."""
        return len(self.runs) + len(self.missing)

    @property
    def cpu_time(self) -> float:
        """CPU time of every run (s; wall time where CPU was not measured)."""
        return sum(_cpu(r) for r in self.runs)

    @property
    def cost(self) -> float:
        """CPU seconds per simulated second over the runs (NaN if nothing was simulated)."""
        sim = sum(r.metrics.simulated_time for r in self.runs)
        return self.cpu_time / sim if sim > 0 else math.nan

    @property
    def complete(self) -> bool:
        """Every case ran, completed, was measured and ended as its reference."""
        return (not self.missing and bool(self.runs)
                and all(_agrees(r) and r.metrics.max_error is not None for r in self.runs))

    def error(self, metric: str = "max_error") -> float:
        """The worst ``metric`` (one of :data:`ERROR_METRICS`) as a number: NaN where
        undefined, infinite for ``impact_time_error`` when an impact is missing.

        Raises
        ------
        CalibrationError
            An unknown metric.
        """
        if metric not in ERROR_METRICS:
            raise CalibrationError(f"--metric expects one of {', '.join(ERROR_METRICS)}, "
                                   f"got {metric!r}")
        if metric == "impact_time_error" and self.impacts_missing:
            return math.inf
        v = getattr(self, metric)
        return math.nan if v is None else float(v)

    def misses(self, tolerances: Tolerances) -> tuple[str, ...]:
        """What keeps it from meeting ``tolerances``, one phrase each (empty: it meets them)."""
        out: list[str] = []
        if self.missing:
            out.append(f"{len(self.missing)} case(s) without a run")
        if not self.runs:
            return (*out, "no run")
        for r in self.runs:
            m, name = r.metrics, r.scenario.name
            if not m.completed:
                out.append(f"{name}: {r.status.value}")
            elif not _agrees(r):
                ref = m.reference_status.value if m.reference_status else "-"
                out.append(f"{name} ends {r.status.value}, the reference {ref}")
            elif m.max_error is None:
                out.append(f"{name}: not measured ({m.error_note or 'no reference'})")
        for name in ERROR_METRICS:
            tol = getattr(tolerances, name)
            if tol is None:
                continue
            e = self.error(name)
            if math.isinf(e):
                out.append(f"{self.impacts_missing} impact(s) missing")
            elif e > tol:
                out.append(f"{name} {e:.3g} > {tol:g}")
        return tuple(out)

    def meets(self, tolerances: Tolerances) -> bool:
        """Every case ran, completed as its reference did, within every tolerance."""
        return not self.misses(tolerances)


@dataclass(frozen=True)
class Calibration:
    """A calibration of one engine: every setting on every case, and what it shows.

    Attributes
    ----------
    plan : SearchPlan
        What was tried.
    cases : tuple of Scenario
        The cases, in table order.
    results : tuple of SettingResult
        One per setting of the plan, in plan order.
    tolerances : Tolerances
        What :meth:`cheapest` asks for.
    metric : str
        The error of :meth:`front` (one of :data:`ERROR_METRICS`).
    engine_version : str
        The engine's library version (several joined by ", " from the store).
    ran, reused : int
        Runs executed now and runs taken from the store.
    wall_time : float
        Wall time of the study (s).
    made_by : tuple of str
        The code versions that made the runs (from the store; empty when run now).
    """

    plan: SearchPlan
    cases: tuple[Scenario, ...]
    results: tuple[SettingResult, ...]
    tolerances: Tolerances = field(default_factory=Tolerances)
    metric: str = "max_error"
    engine_version: str = ""
    ran: int = 0
    reused: int = 0
    wall_time: float = 0.0
    made_by: tuple[str, ...] = ()

    @property
    def engine(self) -> str:
        """The engine calibrated."""
        return self.plan.engine

    @property
    def start(self) -> SettingResult:
        """The result of the preset the search started from."""
        return next((r for r in self.results if r.setting.is_preset
                     and r.setting.preset == self.plan.preset), self.results[0])

    def front(self, metric: str | None = None) -> tuple[SettingResult, ...]:
        """The Pareto front of cost against ``metric`` (default :attr:`metric`), cheapest
        first: the settings no other beats in both. Only :attr:`SettingResult.complete`
        settings take part."""
        m = metric or self.metric
        return tuple(pareto_front([r for r in self.results if r.complete],
                                  cost=lambda r: r.cost, error=lambda r: r.error(m)))

    def meeting(self, tolerances: Tolerances | None = None) -> tuple[SettingResult, ...]:
        """The settings that meet ``tolerances`` (default :attr:`tolerances`), cheapest first."""
        tol = tolerances or self.tolerances
        ok = [r for r in self.results if r.meets(tol) and math.isfinite(r.cost)]
        return tuple(sorted(ok, key=lambda r: r.cost))

    def cheapest(self, tolerances: Tolerances | None = None) -> SettingResult | None:
        """The least costly setting that meets ``tolerances`` (None if none does)."""
        ok = self.meeting(tolerances)
        return ok[0] if ok else None


# ---------------------------------------------------------------------- running
def calibrate(
    engine: str,
    *,
    cases: str | Sequence[str] = "all",
    preset: str = "accurate",
    knobs: Sequence[str] | None = None,
    levels: int = DEFAULT_LEVELS,
    presets: bool = True,
    duration: float | None = None,
    tolerances: Tolerances | None = None,
    metric: str = "max_error",
    db: Path | None = None,
    execution: ExecutionOptions | None = None,
    timeout: float | None = None,
    progress: Callable[[int, str], Any] | None = None,
    on_result: Callable[[RunResult], None] | None = None,
) -> Calibration:
    """Search ``engine``'s declared knobs on the calibration cases (module docstring).

    Parameters
    ----------
    engine : str
        The engine.
    cases : str or sequence of str
        ``free``, ``pulses``, ``all`` or names (:func:`calibration_cases`).
    preset, knobs, levels, presets
        The search (:func:`~rockbench.studies.calibration_plan.plan_search`).
    duration : float, optional
        Every case run for this many seconds instead (a quick look).
    tolerances : Tolerances, optional
        What :meth:`Calibration.cheapest` asks for (default :class:`Tolerances`).
    metric : str
        The error of the Pareto front (:data:`ERROR_METRICS`).
    db : Path, optional
        The results store: every run is recorded, and runs already there are reused.
    execution : ExecutionOptions, optional
        Workers, isolation, executor.
    timeout : float, optional
        Per-run wall-time limit (s; default: the campaign's, by duration).
    progress : callable, optional
        ``progress(total, description)`` → a context manager with ``advance(text)``.
    on_result : callable, optional
        Called with each run's result as it finishes (or is reused).

    Raises
    ------
    CalibrationError, UnknownEngine, EngineUnavailable
        Bad input, before anything runs.
    """
    scenarios = calibration_cases(cases, duration)
    plan = plan_search(engine, preset=preset, knobs=knobs, levels=levels, presets=presets,
                       max_timestep=max_timestep(scenarios))
    return run_plan(plan, scenarios, tolerances=tolerances, metric=metric, db=db,
                    execution=execution, timeout=timeout, progress=progress,
                    on_result=on_result)


def max_timestep(scenarios: Sequence[Scenario]) -> float | None:
    """The longest physics step every scenario accepts: its shortest output interval (s)."""
    return min((1.0 / sc.output_rate for sc in scenarios), default=None)


def _check_metric(metric: str) -> None:
    if metric not in ERROR_METRICS:
        raise CalibrationError(f"--metric expects one of {', '.join(ERROR_METRICS)}, "
                               f"got {metric!r}")


def run_plan(
    plan: SearchPlan,
    scenarios: Sequence[Scenario],
    *,
    tolerances: Tolerances | None = None,
    metric: str = "max_error",
    db: Path | None = None,
    execution: ExecutionOptions | None = None,
    timeout: float | None = None,
    progress: Callable[[int, str], Any] | None = None,
    on_result: Callable[[RunResult], None] | None = None,
) -> Calibration:
    """Run every setting of ``plan`` on every scenario through the campaign.

    With a store, runs whose identity is stored are reused and the others are
    recorded as :data:`KIND` (the suite names the engine and the starting preset).
    Parameters as in :func:`calibrate`.
    """
    _check_metric(metric)
    if not scenarios:
        raise CalibrationError("--cases selects no case")
    start = time.perf_counter()
    methods = [s.method(plan.engine) for s in plan.settings]
    runs = [PlannedRun(sc, m) for m in methods for sc in scenarios]
    campaign = run_campaign(runs, CampaignOptions(
        kind=KIND, suite=f"calibrate {plan.engine} from {plan.preset}", db=db,
        resume=db is not None, execution=execution or ExecutionOptions(), timeout=timeout),
        progress=progress,
        on_result=None if on_result is None else (lambda res, _traj: on_result(res)))
    n = len(scenarios)
    results = tuple(SettingResult(s, m, tuple(campaign.results[i * n:(i + 1) * n]))
                    for i, (s, m) in enumerate(zip(plan.settings, methods, strict=True)))
    return Calibration(plan, tuple(scenarios), results, tolerances or Tolerances(), metric,
                       campaign.versions.get(plan.engine, ""), campaign.ran, campaign.reused,
                       time.perf_counter() - start)


def _pick(records: Sequence[RunRecord]) -> RunRecord:
    """Of stored runs of one identity: the latest compared over the whole run (no
    predictability horizon), else the latest."""
    whole = [r for r in records if r.metrics is not None and r.metrics.horizon is None]
    return (whole or list(records))[-1]


def stored_calibration(
    plan: SearchPlan,
    scenarios: Sequence[Scenario],
    db: Path,
    *,
    tolerances: Tolerances | None = None,
    metric: str = "max_error",
) -> Calibration:
    """The calibration of ``plan`` built from the runs in the store only (nothing runs).

    A stored run counts when its engine, scenario content and *resolved* settings
    match, whatever study or code version made it (the latest such run is taken,
    preferring one compared over the whole run); :attr:`Calibration.made_by`
    lists the code versions. Cases without a stored run are listed in
    :attr:`SettingResult.missing`.

    Raises
    ------
    StoreError
        ``db`` does not exist or is not a rockbench store.
    """
    _check_metric(metric)
    if not scenarios:
        raise CalibrationError("--cases selects no case")
    start = time.perf_counter()
    found: dict[tuple[str, str], list[RunRecord]] = {}
    with Store(db, create=False) as store:
        for rec in store.runs(engine=plan.engine):
            if rec.metrics is not None:
                found.setdefault((rec.scenario_hash, rec.metrics.settings_hash), []).append(rec)
    hashes = [scenario_hash(sc) for sc in scenarios]
    results: list[SettingResult] = []
    made_by: set[str] = set()
    versions: set[str] = set()
    count = 0
    for s in plan.settings:
        m = s.method(plan.engine)
        key = settings_key(plan.resolved(s).to_dict())
        runs: list[RunResult] = []
        missing: list[str] = []
        for sc, h in zip(scenarios, hashes, strict=True):
            recs = found.get((h, key))
            if not recs:
                missing.append(sc.name)
                continue
            rec = _pick(recs)
            assert rec.metrics is not None
            runs.append(RunResult(sc, m, rec.metrics, rec.trajectory, reused=True))
            made_by.add(rec.made_by)
            versions.add(rec.engine_version)
            count += 1
        results.append(SettingResult(s, m, tuple(runs), tuple(missing)))
    return Calibration(plan, tuple(scenarios), tuple(results), tolerances or Tolerances(),
                       metric, ", ".join(sorted(versions)), 0, count,
                       time.perf_counter() - start, tuple(sorted(made_by)))
