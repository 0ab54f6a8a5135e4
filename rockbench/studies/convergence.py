"""Self-convergence of an engine on any scenario: a ladder of refinements and its estimate.

Rung 0 is the method as given (an engine at a preset, with overrides); rung k
refines the engine's refinement knob k times by a factor of 2
(:meth:`rockbench.engines.Engine.refined`: its time step, or the knob that sets
it). Rungs run through the campaign, so the preset's own run and every rung
are reused from the results store when they are there already, and each new
one is recorded. Refinement stops as soon as successive rungs agree, or after
``max_level`` rungs.

What is compared (the *response* of a run, :class:`Response`):

* the outcome (``ok``, ``overturned``, or a failure);
* each block's peak max |θ_i|/λ, up to the horizon when one is given;
* the overturning time, when it overturns;
* the time history up to the horizon: max |θ_k − θ_{k−1}|/λ between rungs.

Two successive rungs *agree* when their outcomes are the same and every
quantity differs by less than its tolerance (:class:`ConvergenceTolerances`;
peaks relative to max(peak, 0.02 λ) as the metrics do). The method
*converges* when its finest two rungs agree and the differences shrank with
the last refinement (or were already below a quarter of the tolerance).

Estimates (:class:`Estimate`): with three rungs or more, Richardson
extrapolation of each scalar with the observed order p = log₂(|d₁| / |d₂|)
(clamped to [0.5, 4]) and Roache's grid convergence index as the uncertainty,
1.25 · |d₂| / (2ᵖ − 1); with two, the finest value and |d| as uncertainty. The
preset's error is rung 0 against the estimate.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rockbench.analytic import critical_angle
from rockbench.campaign import CampaignOptions, PlannedRun, run_campaign
from rockbench.engines import engine_class
from rockbench.errors import RockbenchError
from rockbench.evaluation import PEAK_FLOOR, RunResult
from rockbench.method import Method
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Scenario
from rockbench.trajectory import Status, Trajectory

__all__ = ["Response", "Estimate", "Rung", "Convergence", "ConvergenceTolerances",
           "response", "converge", "converge_many", "KIND", "DEFAULT_MAX_LEVEL"]

#: The store's ``kind`` of the ladder's runs.
KIND = "convergence"
#: Rungs refined at most beyond the method itself.
DEFAULT_MAX_LEVEL = 3
#: Richardson's safety factor on the extrapolation (Roache's GCI with three grids).
SAFETY = 1.25


@dataclass(frozen=True)
class ConvergenceTolerances:
    """When two rungs agree.

    Attributes
    ----------
    peak : float
        Relative difference of each block's peak, over max(peak, 0.02 λ).
    overturn_time : float
        Relative difference of the overturning time.
    history : float
        max |θ_k − θ_{k−1}|/λ over the samples up to the horizon (and of the roll
        where a rung left the x–z plane).
    """

    peak: float = 0.02
    overturn_time: float = 0.01
    history: float = 0.02


@dataclass(frozen=True)
class Response:
    """What one run says about a scenario, in the terms rungs and methods are compared.

    Attributes
    ----------
    status : Status
        How it ended.
    peaks : tuple of float
        max |θ_i|/λ of each block up to the horizon (NaN where unknown); in a run that
        left the x–z plane, the largest tilt about any horizontal axis over λ.
    overturn_time : float or None
        When it overturned (the end of the run; None if it did not).
    """

    status: Status
    peaks: tuple[float, ...]
    overturn_time: float | None

    @property
    def completed(self) -> bool:
        """It ended ``ok`` or ``overturned``."""
        return self.status.completed


def response(traj: Trajectory, lam: float, horizon: float | None = None) -> Response:
    """The :class:`Response` of a run's trajectory, its peaks up to ``horizon``."""
    n = traj.t.size
    if horizon is not None:
        n = int(np.searchsorted(traj.t, horizon, side="right"))
    peaks = (tuple(float(p) for p in np.max(_lean(traj)[:n], axis=0) / lam) if n
             else (math.nan,) * traj.n_blocks)
    over = float(traj.t[-1]) if traj.status is Status.OVERTURNED and traj.t.size else None
    return Response(traj.status, peaks, over)


def _history_change(a: Trajectory, b: Trajectory, lam: float, horizon: float | None) -> float:
    """max |θ_a − θ_b|/λ over their common samples up to ``horizon`` (NaN if none)."""
    n = min(a.t.size, b.t.size)
    if horizon is not None:
        n = min(n, int(np.searchsorted(a.t, horizon, side="right")))
    if n == 0:
        return math.nan
    change = np.abs(a.theta[:n] - b.theta[:n])
    if not (a.planar and b.planar):  # a rung that left the plane: its roll counts too
        change = np.maximum(change, np.abs(a.roll[:n] - b.roll[:n]))
    return float(np.max(change)) / lam


def _lean(traj: Trajectory) -> np.ndarray:
    """|θ| of each sample, or its tilt about any horizontal axis where the run left the
    x–z plane (a block rocking on a corner leans along its diagonal)."""
    return np.abs(traj.theta) if traj.planar else traj.tilt


@dataclass(frozen=True)
class Estimate:
    """A converged value with its uncertainty.

    Attributes
    ----------
    value : float
        The estimate (extrapolated with three rungs or more).
    uncertainty : float
        Its half-width (same unit).
    order : float or None
        The observed order of convergence (None with two rungs).
    """

    value: float
    uncertainty: float
    order: float | None = None

    def __str__(self) -> str:
        return f"{self.value:.4g} ± {self.uncertainty:.2g}"


def _estimate(values: Sequence[float]) -> Estimate | None:
    """Richardson's estimate of a rung sequence (refinement ratio 2), None if undefined."""
    v = [x for x in values if x is not None and math.isfinite(x)]
    if len(v) != len(values) or not v:
        return None
    if len(v) == 1:
        return Estimate(v[0], math.inf)
    d2 = v[-1] - v[-2]
    if len(v) == 2 or d2 == 0.0:
        return Estimate(v[-1], abs(d2))
    d1 = v[-2] - v[-3]
    if d1 == 0.0 or d1 * d2 < 0:  # oscillating or stalled: no order to speak of
        return Estimate(v[-1], abs(d2))
    p = min(4.0, max(0.5, math.log2(abs(d1 / d2))))
    corr = d2 / (2.0 ** p - 1.0)
    return Estimate(v[-1] + corr, SAFETY * abs(corr), p)


@dataclass(frozen=True)
class Rung:
    """One rung of a ladder.

    Attributes
    ----------
    level : int
        0 for the method as given, k for k refinements.
    method : Method
        The engine and the settings of this rung.
    result : RunResult
        Its run (metrics, cost, whether it was reused from the store).
    response : Response
        What it says.
    history_change : float or None
        max |θ − θ_previous rung|/λ up to the horizon (None for rung 0).
    """

    level: int
    method: Method
    result: RunResult
    response: Response
    history_change: float | None = None

    @property
    def cpu_time(self) -> float:
        """CPU time of its run (wall time if CPU was not measured), s."""
        m = self.result.metrics
        return float(m.cpu_time if m.cpu_time else m.wall_time)


@dataclass(frozen=True)
class Convergence:
    """The ladder of one method on one scenario, and what it establishes.

    Attributes
    ----------
    scenario : Scenario
        What was simulated.
    method : Method
        The method judged (rung 0).
    rungs : tuple of Rung
        Coarse to fine.
    converged : bool
        The finest rungs agree and the differences shrank.
    reason : str
        How it converged, or why not (with the numbers).
    outcome : Status or None
        The finest rungs' common outcome (None if they differ or failed).
    peaks : tuple of Estimate or None
        Per block, the converged peak max |θ_i|/λ.
    overturn_time : Estimate or None
        The converged overturning time (s), when it overturns.
    horizon : float or None
        The time histories were compared up to this time (s; None: the whole run).
    """

    scenario: Scenario
    method: Method
    rungs: tuple[Rung, ...]
    converged: bool
    reason: str
    outcome: Status | None
    peaks: tuple[Estimate | None, ...] = ()
    overturn_time: Estimate | None = None
    horizon: float | None = None

    @property
    def preset(self) -> Rung:
        """Rung 0: the method as judged."""
        return self.rungs[0]

    @property
    def cost(self) -> float:
        """CPU time of every rung (s), the reused ones included."""
        return sum(r.cpu_time for r in self.rungs)

    @property
    def new_cost(self) -> float:
        """CPU time of the rungs run now (s)."""
        return sum(r.cpu_time for r in self.rungs if not r.result.reused)

    def peak_errors(self) -> tuple[float | None, ...]:
        """Rung 0's peak per block against the estimate, relative to max(estimate, 0.02)."""
        out: list[float | None] = []
        for p, e in zip(self.preset.response.peaks, self.peaks, strict=False):
            out.append(None if e is None or not math.isfinite(p)
                       else (p - e.value) / max(e.value, PEAK_FLOOR))
        return tuple(out)


@dataclass
class _Ladder:
    scenario: Scenario
    method: Method
    lam: float
    horizon: float | None
    rungs: list[Rung] = field(default_factory=list)
    trajs: list[Trajectory] = field(default_factory=list)
    done: Convergence | None = None

    def planned(self, level: int) -> PlannedRun:
        cls = engine_class(self.method.engine)
        settings = cls.refined(self.method.settings, level) if level else self.method.settings
        if not level:
            return PlannedRun(self.scenario, self.method)
        rung = f"{self.method.preset or 'defaults'}, rung {level}"
        return PlannedRun(self.scenario, Method.of(self.method.engine, settings,
                                                   variation=rung))

    def add(self, level: int, result: RunResult, traj: Trajectory) -> None:
        prev = self.trajs[-1] if self.trajs else None
        change = None if prev is None else _history_change(prev, traj, self.lam, self.horizon)
        self.rungs.append(Rung(level, result.method, result,
                               response(traj, self.lam, self.horizon), change))
        self.trajs.append(traj)


def _differences(a: Response, b: Response) -> tuple[float, float | None]:
    """Largest relative peak difference and relative overturning-time difference."""
    peak = max((abs(x - y) / max(abs(y), PEAK_FLOOR) for x, y in zip(a.peaks, b.peaks,
                                                                      strict=True)),
               default=math.nan)
    over = None
    if a.overturn_time is not None and b.overturn_time is not None:
        over = abs(a.overturn_time - b.overturn_time) / b.overturn_time
    return peak, over


def _judge(ladder: _Ladder, tol: ConvergenceTolerances, max_level: int) -> Convergence | None:
    """The ladder's verdict, or None when another rung is needed."""
    rungs = ladder.rungs
    last = rungs[-1]
    if len(rungs) < 2:
        return None
    a, b = rungs[-2].response, last.response
    finest = last.level >= max_level
    if not (a.completed and b.completed):
        if finest:
            return _verdict(ladder, False, f"the finest rungs end {a.status.value} and "
                                          f"{b.status.value}")
        return None
    if a.status is not b.status:
        if finest:
            return _verdict(ladder, False, f"the outcome flips between the finest rungs "
                                          f"({a.status.value} at {rungs[-2].method.label}, "
                                          f"{b.status.value} at {last.method.label})")
        return None
    peak, over = _differences(a, b)
    hist = last.history_change
    worst = [("peaks", peak / tol.peak)]
    if over is not None:
        worst.append(("overturning time", over / tol.overturn_time))
    if hist is not None and math.isfinite(hist) and a.status is not Status.OVERTURNED:
        worst.append(("time history", hist / tol.history))
    what, ratio = max(worst, key=lambda w: w[1] if math.isfinite(w[1]) else math.inf)
    if ratio < 1.0:
        shrinking = True
        if len(rungs) >= 3:
            prev_peak, _ = _differences(rungs[-3].response, a)
            shrinking = peak <= prev_peak or ratio < 0.25
        elif ratio >= 0.25:
            return None  # two rungs agree, but only a third shows the trend
        if shrinking:
            return _verdict(ladder, True, f"{len(rungs)} rungs; the finest two agree "
                                         f"({_fmt_diff(peak, over, hist)})")
    if finest:
        return _verdict(ladder, False, f"no agreement after {len(rungs)} rungs: the finest "
                                      f"two differ by {_fmt_diff(peak, over, hist)} "
                                      f"({what} {ratio:.1f}× its tolerance)")
    return None


def _fmt_diff(peak: float, over: float | None, hist: float | None) -> str:
    parts = [f"peaks {100 * peak:.2g} %"]
    if over is not None:
        parts.append(f"overturning time {100 * over:.2g} %")
    if hist is not None and math.isfinite(hist):
        parts.append(f"history {hist:.2g} λ")
    return ", ".join(parts)


def _verdict(ladder: _Ladder, converged: bool, reason: str) -> Convergence:
    rungs = tuple(ladder.rungs)
    last = rungs[-1].response
    outcome = last.status if converged else None
    peaks: tuple[Estimate | None, ...] = ()
    over = None
    if converged:
        n = len(last.peaks)
        peaks = tuple(_estimate([r.response.peaks[i] for r in rungs]) for i in range(n))
        if last.overturn_time is not None:
            over = _estimate([r.response.overturn_time for r in rungs
                              if r.response.overturn_time is not None])
    return Convergence(ladder.scenario, ladder.method, rungs, converged, reason, outcome,
                       peaks, over, ladder.horizon)


def converge_many(runs: Sequence[tuple[Scenario, Method]], *,
                  tolerances: ConvergenceTolerances = ConvergenceTolerances(),
                  max_level: int = DEFAULT_MAX_LEVEL,
                  horizons: dict[str, float] | None = None,
                  db: Path | None = None, execution: ExecutionOptions | None = None,
                  timeout: float | None = None,
                  progress: Callable[[int, str], Any] | None = None) -> list[Convergence]:
    """The ladders of several (scenario, method) pairs, rung by rung in parallel.

    Every round runs the next rung of each ladder not yet settled, through one
    campaign (so rungs of different ladders share the workers).

    Parameters
    ----------
    runs : sequence of (Scenario, Method)
        What to judge; the methods' engines must declare a refinement knob.
    tolerances : ConvergenceTolerances
        When two rungs agree.
    max_level : int
        The finest rung (refinements beyond rung 0), at least 1.
    horizons : dict, optional
        Scenario name → time (s) up to which histories and peaks are compared.
    db, execution, timeout, progress
        As for :func:`rockbench.campaign.run_campaign` (the store is read with
        resume: rungs already run are reused).

    Raises
    ------
    RockbenchError
        ``max_level`` below 1, or an engine without a refinement knob.
    """
    if max_level < 1:
        raise RockbenchError(f"a convergence ladder needs at least one refinement, got "
                             f"max_level {max_level}")
    horizons = horizons or {}
    ladders = [_Ladder(sc, m, critical_angle(sc.geometry), horizons.get(sc.name))
               for sc, m in runs]
    for lad in ladders:  # a method whose engine cannot be refined fails before any run
        lad.planned(1)
    level = 0
    ex = execution or ExecutionOptions()
    while any(lad.done is None for lad in ladders):
        todo = [lad for lad in ladders if lad.done is None]
        # the first round runs rungs 0 and 1 together (a ladder needs two at least)
        levels = (0, 1) if level == 0 else (level,)
        plan = [lad.planned(k) for lad in todo for k in levels]
        # rungs are archived with the store, so that a later ladder reuses them whole
        campaign = run_campaign(plan, CampaignOptions(
            kind=KIND, db=db, resume=db is not None, archive=db is not None, keep=True,
            references=False, execution=ex, timeout=timeout), progress=progress)
        results = iter(campaign.results)
        for lad in todo:
            for k in levels:
                res = next(results)
                lad.add(k, res, campaign.trajectories[(res.scenario.name, res.method.label)])
            lad.done = _judge(lad, tolerances, max_level)
        level = levels[-1] + 1
    return [lad.done for lad in ladders if lad.done is not None]


def converge(scenario: Scenario, method: Method, **kwargs: Any) -> Convergence:
    """The ladder of one method on one scenario (see :func:`converge_many`)."""
    return converge_many([(scenario, method)], **kwargs)[0]
