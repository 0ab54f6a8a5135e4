"""Pulse to collapse: the smallest one-sine pulse that collapses an assembly, per engine.

For each assembly, engine and pulse frequency f_p, the study finds by bisection
the smallest peak acceleration a_p of a one-sine base pulse
(:class:`~rockbench.scenarios.excitation.SinePulse`, ü_g = a_p sin ω_p t for one
period) that collapses the assembly. There is no analytic dynamic reference for
multi-block assemblies: the result shows the engines' spread, the DEM's
(``dem2d``), and the static factor α of limit analysis as the low-frequency
limit (a_p/g → α as ω_p → 0: a pulse that lasts long enough is a slow tilt).

Collapse criterion
------------------
A run ends in one of three outcomes (:func:`outcome`). It *collapses* if the
engine reports a block overturned (``Status.OVERTURNED``: a block turned past
half a turn from its rest orientation or thrown out of the scene), or if at the
end of the run, the pulse plus :data:`FREE_TIME` seconds of still base, some
block is

* turned from its rest orientation by more than :data:`RESIDUAL_ROTATION`
  times the assembly's critical angle λ = atan α (a block that rocked comes
  back to its seat; one that stays turned has lost it, e.g. a fallen
  voussoir or a drum lying on its neighbour), or
* lower than at rest by more than :data:`RESIDUAL_DROP` of its height (it
  fell off the assembly).

It *slid* if no block did either but some block is displaced relative to the
base by more than :data:`RESIDUAL_DISPLACEMENT` of its size: blocks that
translate without turning or falling (a squat block, or a whole wall, sliding
on the base, a course slipping on the one below) have not collapsed; the
smallest pulse that slid is reported (:attr:`CollapsePoint.sliding_factor`)
and the bisection goes on above it. Otherwise the run is at *rest*.

A run that failed (crash, instability, time-out) is none of these: its probe is
kept with ``failed`` and the bracket is not moved by it (the point is then
marked unresolved).

Bisection
---------
Amplitudes are in units of the static factor, k = a_p / (α g). Below k = 1 a
rigid assembly cannot move at all (the static equilibrium holds at every
instant), so k = 1 is the lower end of the bracket without a run. The upper
end starts at :data:`FIRST_FACTOR` and grows by :data:`GROWTH` until a run
collapses (at most ``max_factor``; beyond it the point is "no collapse"). The
bracket [lo, hi] (lo did not collapse, hi did) is then halved geometrically
until hi / lo − 1 ≤ ``rtol``. Collapse need not be monotonic in the
amplitude (an overturning spectrum has safe islands above its minimum): the
result is the first collapse boundary found from below, the analogue of a
spectrum's minimum overturning acceleration. Every round of probes, over all
assemblies, engines and frequencies at once, is one campaign
(:func:`rockbench.campaign.run_campaign`: parallel, isolated, Dask-capable jobs),
and every run is recorded in the store (kind ``collapse``).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from rockbench.analytic import critical_angle
from rockbench.campaign import CampaignOptions, PlannedRun, run_campaign
from rockbench.evaluation import RunResult
from rockbench.method import Method
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Scenario, SinePulse
from rockbench.studies.tilting import reference
from rockbench.trajectory import Status, Trajectory

__all__ = ["FREE_TIME", "RESIDUAL_ROTATION", "RESIDUAL_DROP", "RESIDUAL_DISPLACEMENT",
           "FIRST_FACTOR", "GROWTH", "KIND", "Outcome", "CollapseProbe", "CollapsePoint",
           "CollapseStudy", "static_factor", "outcome", "collapsed", "pulse_scenario",
           "pulse_to_collapse"]

#: How a pulse-to-collapse run ended (module docstring).
Outcome = Literal["rest", "collapse", "sliding"]

#: Seconds of still base after the pulse before the end state is judged.
FREE_TIME = 2.0
#: A block still turned by more than this many critical angles at the end has collapsed.
RESIDUAL_ROTATION = 1.0
#: A block lower than at rest by more than this fraction of its height has fallen.
RESIDUAL_DROP = 0.25
#: A block displaced relative to the base by more than this fraction of its size has
#: slid (collapse only if it also turned or fell).
RESIDUAL_DISPLACEMENT = 0.25
#: First upper probe, in units of the static factor.
FIRST_FACTOR = 1.5
#: Factor by which the upper probe grows until a run collapses.
GROWTH = 2.0
#: Store kind of the study's runs.
KIND = "collapse"
#: Output rate of the runs (Hz): the end state and overturning need no more.
_OUTPUT_RATE = 200.0


def static_factor(scenario: Scenario) -> float:
    """The limit-analysis factor α of the first mechanism, the smaller of both directions.

    The scenario's friction (:func:`rockbench.studies.tilting.reference`); inf if
    neither direction has a mechanism.
    """
    alphas = [r.load_factor for r in (reference(scenario, d) for d in (1, -1))
              if r.status == "collapse"]
    return min(alphas) if alphas else math.inf


def pulse_scenario(scenario: Scenario, frequency: float, factor: float, alpha: float,
                   free_time: float = FREE_TIME) -> Scenario:
    """``scenario`` under a one-sine pulse of f = ``frequency`` and a_p = factor · α · g."""
    omega = 2.0 * math.pi * frequency
    a_p = factor * alpha * scenario.g
    return scenario.replace(
        name=f"{scenario.name}-pulse{frequency:g}hz-{factor:.5g}alpha",
        excitation=SinePulse(frequency, a_p / omega ** 2),
        duration=1.0 / frequency + free_time, output_rate=_OUTPUT_RATE, initial_tilt=0.0)


def outcome(traj: Trajectory, scenario: Scenario) -> Outcome | None:
    """The outcome of a run by the criterion of the module docstring; None for a failed run."""
    if traj.status is Status.OVERTURNED:
        return "collapse"
    if not traj.status.completed or traj.t.size < 2:
        return None
    turn = np.abs(traj.theta[-1] - traj.theta[0])
    drop = traj.z[0] - traj.z[-1]
    heights = np.array([b.height for b in scenario.blocks])
    if np.any(turn > RESIDUAL_ROTATION * critical_angle(scenario.geometry)) or np.any(
            drop > RESIDUAL_DROP * heights):
        return "collapse"
    u = float(np.asarray(scenario.motion.x.displacement(traj.t[-1])))
    disp = np.hypot(traj.x[-1] - traj.x[0] - u, traj.z[-1] - traj.z[0])
    sizes = np.array([max(b.width, b.height) for b in scenario.blocks])
    return "sliding" if np.any(disp > RESIDUAL_DISPLACEMENT * sizes) else "rest"


def collapsed(traj: Trajectory, scenario: Scenario) -> bool | None:
    """True if the run collapsed (:func:`outcome`; sliding is not collapse), None if it failed."""
    result = outcome(traj, scenario)
    return None if result is None else result == "collapse"


@dataclass(frozen=True)
class CollapseProbe:
    """One run of the bisection.

    Attributes
    ----------
    factor : float
        a_p / (α g).
    collapsed : bool or None
        The criterion's verdict (None: the run failed).
    status : Status
        The run's status.
    cpu_time, wall_time : float
        Its cost (s).
    slid : bool
        The run slid (:func:`outcome`): blocks displaced, none turned or fallen.
    """

    factor: float
    collapsed: bool | None
    status: Status
    cpu_time: float
    wall_time: float
    slid: bool = False


@dataclass(frozen=True)
class CollapsePoint:
    """The collapse amplitude of one assembly in one engine at one pulse frequency.

    Attributes
    ----------
    engine : str
        Engine name.
    scenario : str
        Assembly (scenario) name.
    frequency : float
        f_p (Hz).
    static_factor : float
        α of limit analysis.
    lower, upper : float
        The final bracket in units of α: ``lower`` did not collapse (1: the
        static bound, not run), ``upper`` did (inf: nothing up to the largest
        factor tried collapsed).
    probes : tuple of CollapseProbe
        Every run, in the order run.
    """

    engine: str
    scenario: str
    frequency: float
    static_factor: float
    lower: float
    upper: float
    probes: tuple[CollapseProbe, ...]

    @property
    def factor(self) -> float:
        """a_p / (α g) of the collapse: the smallest amplitude seen to collapse."""
        return self.upper

    @property
    def sliding_factor(self) -> float:
        """a_p / (α g) of the smallest pulse that slid without collapsing (inf: none did)."""
        return min((p.factor for p in self.probes if p.slid), default=math.inf)

    @property
    def acceleration_ratio(self) -> float:
        """a_p / g of the collapse (``factor`` · α)."""
        return self.upper * self.static_factor

    @property
    def failed(self) -> int:
        """How many probes failed (crash, instability, time-out)."""
        return sum(p.collapsed is None for p in self.probes)

    @property
    def cpu_time(self) -> float:
        """CPU time of all the probes (s)."""
        return float(sum(p.cpu_time for p in self.probes if math.isfinite(p.cpu_time)))

    @property
    def wall_time(self) -> float:
        """Wall time of all the probes (s)."""
        return float(sum(p.wall_time for p in self.probes))


@dataclass(frozen=True)
class CollapseStudy:
    """All the points of a pulse-to-collapse study and its cost.

    Attributes
    ----------
    points : tuple of CollapsePoint
        Per scenario, engine and frequency (scenario-major).
    scenarios : tuple of Scenario
        The assemblies at rest.
    engines : tuple of str
        Engines, in order.
    frequencies : tuple of float
        f_p (Hz).
    settings : mapping
        Engine → settings used.
    rtol : float
        Bisection tolerance (hi / lo − 1).
    wall_time : float
        Wall time of the whole study (s).
    """

    points: tuple[CollapsePoint, ...]
    scenarios: tuple[Scenario, ...]
    engines: tuple[str, ...]
    frequencies: tuple[float, ...]
    settings: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    rtol: float = 0.02
    wall_time: float = 0.0

    def curve(self, scenario: str, engine: str) -> list[CollapsePoint]:
        """The points of one assembly and engine, by frequency."""
        return sorted((p for p in self.points if p.scenario == scenario and p.engine == engine),
                      key=lambda p: p.frequency)


@dataclass
class _Cell:
    """Bisection state of one (scenario, engine, frequency)."""

    scenario: Scenario
    engine: str
    frequency: float
    alpha: float
    lower: float = 1.0
    upper: float = math.inf
    next_up: float = FIRST_FACTOR
    probes: list[CollapseProbe] = field(default_factory=list)
    done: bool = False

    def probe(self, rtol: float, max_factor: float) -> float | None:
        """The next factor to run, or None when the bracket is closed."""
        if self.done:
            return None
        if math.isinf(self.upper):
            if self.next_up > max_factor * (1 + 1e-12):
                self.done = True
                return None
            return self.next_up
        if self.upper / self.lower - 1.0 <= rtol:
            self.done = True
            return None
        return math.sqrt(self.lower * self.upper)

    def update(self, factor: float, verdict: bool | None, growth: float) -> None:
        if verdict is None:  # a failed run decides nothing: stop rather than loop on it
            self.done = True
        elif verdict:
            self.upper = factor
        else:
            self.lower = factor
            if math.isinf(self.upper):
                self.next_up = factor * growth


def pulse_to_collapse(scenarios: Sequence[Scenario], engines: Sequence[str],
                      frequencies: Sequence[float], *,
                      settings: Mapping[str, Mapping[str, Any]] | None = None,
                      rtol: float = 0.02, max_factor: float = 16.0, growth: float = GROWTH,
                      free_time: float = FREE_TIME,
                      execution: ExecutionOptions | None = None, db: Path | None = None,
                      on_result: Callable[[RunResult, Trajectory | None], None] | None = None
                      ) -> CollapseStudy:
    """Bisect the collapse amplitude of every assembly × engine × frequency.

    Parameters
    ----------
    scenarios : sequence of Scenario
        Assemblies (or single blocks and stacks) at rest.
    engines : sequence of str
        Registered engine names.
    frequencies : sequence of float
        Pulse frequencies f_p (Hz).
    settings : mapping, optional
        Engine → knob overrides (``"preset"`` selects a preset).
    rtol : float
        Stop when upper / lower − 1 ≤ rtol.
    max_factor : float
        Largest amplitude tried, in units of α.
    growth : float
        Growth of the upper probe until a collapse (> 1).
    free_time : float
        Still base after the pulse before the end state is judged (s).
    execution : ExecutionOptions, optional
        How the runs are executed (default: one isolated worker).
    db : Path, optional
        The results store, where each run is recorded as it finishes (kind ``collapse``).
    on_result : callable, optional
        Called as ``on_result(result, trajectory)`` after each run (progress).

    Returns
    -------
    CollapseStudy

    Raises
    ------
    ValueError
        Bad tolerances, a non-positive frequency, or a scenario with no
        collapse mechanism.
    """
    start = time.perf_counter()
    if not (rtol > 0 and growth > 1 and max_factor > 1):
        raise ValueError(f"need rtol > 0, growth > 1, max_factor > 1; got {rtol}, {growth}, "
                         f"{max_factor}")
    if not frequencies or not all(math.isfinite(f) and f > 0 for f in frequencies):
        raise ValueError(f"pulse frequencies must be finite and > 0, got {list(frequencies)}")
    settings = {e: dict((settings or {}).get(e, {})) for e in engines}
    ex = execution or ExecutionOptions()
    cells = []
    for sc in scenarios:
        alpha = static_factor(sc)
        if not math.isfinite(alpha):
            raise ValueError(f"{sc.name}: limit analysis finds no collapse mechanism")
        cells += [_Cell(sc, e, float(f), alpha) for e in engines for f in frequencies]
    while True:
        batch = [(c, f) for c in cells if (f := c.probe(rtol, max_factor)) is not None]
        if not batch:
            break
        plan = [PlannedRun(pulse_scenario(c.scenario, c.frequency, f, c.alpha, free_time),
                           Method.of(c.engine, settings[c.engine])) for c, f in batch]
        campaign = run_campaign(plan, CampaignOptions(
            kind=KIND, db=db, keep=True, references=False, execution=ex, timeout=ex.timeout),
            on_result=on_result)
        for (c, f), run in zip(batch, plan, strict=True):
            traj = campaign.trajectories[run.key]
            result = outcome(traj, run.scenario)
            verdict = None if result is None else result == "collapse"
            c.probes.append(CollapseProbe(
                f, verdict, traj.status, float(traj.cpu_time),
                float(traj.wall_time), slid=result == "sliding"))
            c.update(f, verdict, growth)
    points = tuple(CollapsePoint(c.engine, c.scenario.name, c.frequency, c.alpha, c.lower,
                                 c.upper, tuple(c.probes)) for c in cells)
    return CollapseStudy(points, tuple(scenarios), tuple(engines),
                         tuple(float(f) for f in frequencies), settings, rtol,
                         time.perf_counter() - start)
