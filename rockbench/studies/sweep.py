"""Settings sweeps: the grid of engine knobs on one scenario, accuracy versus cost.

:func:`run_sweep` runs the cartesian grid of engine knobs given as
``engine.knob=v1,v2,...`` on one scenario through the campaign
(:func:`rockbench.campaign.run_campaign`: each point measured against the
analytic reference and recorded as it finishes) and returns typed
:class:`SweepPoint` s. :func:`cheapest` picks the cheapest
point that meets a target error, :func:`efficient_points` is each engine's
Pareto front (:func:`rockbench.studies.pareto.pareto_front`), and
:mod:`rockbench.studies.tune` searches knob ladders automatically. The
stability maps, the Pareto plot and the tables are drawn by
:mod:`rockbench.report.sweep_figures` and :mod:`rockbench.report.sweep_tables`.

A point's cost is the CPU time of its run when it was measured (wall time
otherwise): CPU time does not grow when ``--jobs`` runs share the cores.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rockbench.campaign import CampaignOptions, PlannedRun, run_campaign
from rockbench.errors import RockbenchError
from rockbench.evaluation import RunMetrics
from rockbench.method import Method
from rockbench.presets import typed_settings
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Scenario
from rockbench.studies.pareto import pareto_front
from rockbench.trajectory import Status

__all__ = ["SweepError", "SweepPoint", "SweepResult", "parse_grid", "run_sweep", "run_points",
           "grid_points", "cheapest", "efficient_points", "ERROR_METRICS",
           "DRIFT_WIDTH", "DRIFT_WOBBLE", "KIND"]

#: The store's ``kind`` of runs made by this study.
KIND = "sweep"

#: Metrics a sweep may rank by (lower is better).
ERROR_METRICS = ("max_error", "max_error_early", "impact_time_error", "peak_error")
#: Sliding of the bottom block beyond this fraction of its width is non-physical drift.
DRIFT_WIDTH = 0.05
#: Out-of-plane wobble beyond this (rad) is non-physical drift in a planar problem.
DRIFT_WOBBLE = 0.05


class SweepError(RockbenchError, ValueError):
    """A bad ``--grid`` option or sweep request."""


def parse_grid(options: Sequence[str], engines: Sequence[str]) -> dict[str, dict[str, list[Any]]]:
    """Parse ``engine.knob=v1,v2,...`` options into typed value lists per engine.

    Values are converted to the knob's type (and checked) now. Engines without
    a grid option run a single point (their settings as given).

    Raises
    ------
    SweepError
        Malformed option, an engine that is not selected, or a repeated knob.
    SettingsError
        Unknown knob or a value of the wrong type.
    """
    from rockbench.engines.registry import ALIASES

    grid: dict[str, dict[str, list[Any]]] = {e: {} for e in engines}
    for opt in options:
        key, sep, values = opt.partition("=")
        engine, dot, knob = key.strip().partition(".")
        engine = ALIASES.get(engine.strip().lower(), engine.strip().lower())
        knob = knob.strip()
        items = [v.strip() for v in values.split(",") if v.strip()]
        if not (sep and dot and engine and knob and items):
            raise SweepError(f"--grid expects engine.knob=v1,v2,..., got {opt!r}")
        if engine not in grid:
            raise SweepError(f"--grid names engine {engine!r}, which is not selected "
                             f"(--engine {','.join(engines)})")
        if knob in grid[engine]:
            raise SweepError(f"--grid gives {engine}.{knob} twice")
        typed = [typed_settings(engine, {knob: v})[knob] for v in items]
        grid[engine][knob] = list(dict.fromkeys(typed))  # drop repeats, keep order
    return grid


@dataclass(frozen=True)
class SweepPoint:
    """One point of a sweep.

    Attributes
    ----------
    method : Method
        Engine and full requested settings (base settings plus ``knobs``).
    knobs : dict
        The grid knobs' values at this point.
    metrics : RunMetrics
        The run's metrics against the analytic reference.
    drift : bool
        Non-physical sliding (beyond :data:`DRIFT_WIDTH` of the block's width)
        or out-of-plane wobble (beyond :data:`DRIFT_WOBBLE` rad).
    """

    method: Method
    knobs: dict[str, Any]
    metrics: RunMetrics
    drift: bool = False

    @property
    def engine(self) -> str:
        """Engine name."""
        return self.method.engine

    @property
    def settings(self) -> dict[str, Any]:
        """The full requested settings."""
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
    def cost(self) -> float:
        """CPU time of the run in s if measured, else its wall time (NaN if neither)."""
        m = self.metrics
        if m.cpu_time is not None and m.cpu_time > 0:
            return m.cpu_time
        return m.wall_time if m.wall_time > 0 else math.nan

    def error(self, metric: str = "max_error") -> float:
        """The error metric (NaN if it could not be computed)."""
        v = self.metrics.value(metric)
        return math.nan if v is None else v

    @property
    def as_reference(self) -> bool:
        """The run ends as the reference does (ok/overturned; any completion without one)."""
        ref = self.metrics.reference_status
        return self.status.completed and (ref is None or self.status is ref)

    def meets(self, target: float, metric: str = "max_error") -> bool:
        """Ends as the reference, without drift, with the metric ≤ ``target``."""
        e = self.error(metric)
        return self.as_reference and not self.drift and math.isfinite(e) and e <= target

    def kind(self) -> str:
        """Marker class: ok, mismatch (ends unlike the reference), drift, or the status."""
        if not self.status.completed:
            return self.status.value
        if not self.as_reference:
            return "mismatch"
        return "drift" if self.drift else "ok"


@dataclass
class SweepResult:
    """Points of a sweep on one scenario."""

    scenario: Scenario
    grid: dict[str, dict[str, Sequence[Any]]]
    points: list[SweepPoint] = field(default_factory=list)
    metric: str = "max_error"
    reference_note: str = ""

    def engine_points(self, engine: str) -> list[SweepPoint]:
        """The points of one engine, in grid order."""
        return [p for p in self.points if p.engine == engine]

    @property
    def engines(self) -> list[str]:
        """Engines in the sweep, in order."""
        return list(self.grid)


def _drift(m: RunMetrics, scenario: Scenario) -> bool:
    return bool((m.slide is not None and m.slide > DRIFT_WIDTH * scenario.blocks[0].width)
                or (m.max_wobble is not None and m.max_wobble > DRIFT_WOBBLE))


def grid_points(grid: Mapping[str, Sequence[Any]]) -> list[dict[str, Any]]:
    """The cartesian product of knob → values, in grid order (first knob slowest)."""
    knobs = list(grid)
    return [dict(zip(knobs, combo, strict=True))
            for combo in itertools.product(*(grid[k] for k in knobs))]


def run_points(
    scenario: Scenario,
    points: Sequence[tuple[str, Mapping[str, Any], Mapping[str, Any]]],
    *,
    db: Path | None = None,
    resume: bool = False,
    kind: str = KIND,
    execution: ExecutionOptions | None = None,
    on_point: Callable[[SweepPoint], None] | None = None,
) -> tuple[list[SweepPoint], str]:
    """Run explicit points ``(engine, knobs, full settings)`` of one scenario.

    Each run is measured against the analytic reference and recorded as it
    finishes (:func:`rockbench.campaign.run_campaign`); with ``resume`` a point
    already in the store (the same identity) is taken from it.

    Returns
    -------
    points : list of SweepPoint
        In the order given.
    reference_note : str
        Why there is no usable reference ('' if there is one).
    """
    plan = [PlannedRun(scenario, Method.of(engine, settings)) for engine, _, settings in points]
    knobs = {p.method: dict(k) for p, (_, k, _) in zip(plan, points, strict=True)}

    def point(res: Any) -> SweepPoint:
        return SweepPoint(res.method, knobs[res.method], res.metrics,
                          _drift(res.metrics, scenario))

    def finished(res: Any, _: Any) -> None:
        if on_point is not None:
            on_point(point(res))

    campaign = run_campaign(plan, CampaignOptions(
        kind=kind, db=db, resume=resume, execution=execution or ExecutionOptions(),
        timeout=(execution or ExecutionOptions()).timeout), on_result=finished)
    return ([point(r) for r in campaign.results],
            campaign.reference_notes.get(scenario.name, ""))


def run_sweep(
    scenario: Scenario,
    grid: Mapping[str, Mapping[str, Sequence[Any]]],
    *,
    base: Mapping[str, Mapping[str, Any]] | None = None,
    metric: str = "max_error",
    db: Path | None = None,
    resume: bool = False,
    kind: str = KIND,
    execution: ExecutionOptions | None = None,
    on_point: Callable[[SweepPoint], None] | None = None,
) -> SweepResult:
    """Run every grid point of every engine on ``scenario``.

    Parameters
    ----------
    scenario : Scenario
        The problem.
    grid : mapping
        Engine → knob → values (from :func:`parse_grid`); an engine with an
        empty mapping runs once.
    base : mapping, optional
        Engine → settings applied under the grid knobs (preset, ``--set``).
    metric : str
        Error metric of :data:`ERROR_METRICS` used for ranking.
    db : Path, optional
        The results store: every run is appended as it finishes, the reference cached.
    resume : bool
        Reuse stored runs of identical points.
    kind : str
        Label of the runs in the store.
    execution : ExecutionOptions, optional
        Workers, time limit, executor.
    on_point : callable, optional
        Called with each finished point.
    """
    if metric not in ERROR_METRICS:
        raise SweepError(f"unknown metric {metric!r}; choose one of {', '.join(ERROR_METRICS)}")
    base = base or {}
    points = [(engine, knobs, {**base.get(engine, {}), **knobs})
              for engine, g in grid.items() for knobs in grid_points(g)]
    result = SweepResult(scenario, {e: dict(g) for e, g in grid.items()}, metric=metric)
    result.points, result.reference_note = run_points(
        scenario, points, db=db, resume=resume, kind=kind, execution=execution,
        on_point=on_point)
    return result


def cheapest(points: Sequence[SweepPoint], target: float,
             metric: str = "max_error") -> SweepPoint | None:
    """The lowest-cost point that meets ``target`` (None if none does)."""
    ok = [p for p in points if p.meets(target, metric) and math.isfinite(p.cost)]
    return min(ok, key=lambda p: (p.cost, p.error(metric))) if ok else None


def efficient_points(points: Sequence[SweepPoint], metric: str = "max_error") -> list[SweepPoint]:
    """The Pareto front of cost and error, cheapest first.

    Only runs that end as the reference does, without drift, take part.
    """
    return pareto_front([p for p in points if p.as_reference and not p.drift],
                        cost=lambda p: p.cost, error=lambda p: p.error(metric))
