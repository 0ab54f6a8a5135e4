"""Tilting table: an assembly's quasi-static collapse angle in an engine, against limit analysis.

The table is tilted slowly through the base-acceleration ramp of
:class:`~rockbench.scenarios.excitation.TiltTable`: α(t) = rate · t is the
tangent of the equivalent tilt angle (every block feels its weight plus α m g
horizontally, i.e. gravity turned by atan α). The run records when the assembly
starts to move relative to the base (the *onset*) and which blocks take part
once the motion is developed (a block turned by ten times :data:`ONSET_ROTATION`
or displaced by ten times :data:`ONSET_DISPLACEMENT` of its size relative to the
base: the blocks whose motion is then at least :data:`MOVED_FRACTION` of the
largest). α at the onset is compared with the limit-analysis factor of
:func:`rockbench.analytic.static_collapse.limit_analysis` (the scenario's
friction, real Coulomb joints, loads toward ``direction``) and the blocks with
its mechanism.

The onset is located on the developed motion, not on the first sample past the
thresholds: many small blocks on soft contacts creep before the mechanism
starts (MuJoCo's 6 × 3 wall turns single half bricks of its leeward edge by
2e-4 rad at 4–5 % below the factor, while its wedge turns at +0.8 %). With the
motion in units of the thresholds (the *level*), the onset is the α where the
developed motion's growth, fitted through its crossings of :data:`DEVELOPED`
and 10 · :data:`DEVELOPED` with the cubic law below, crosses level 1:
α₁ = α₁₀ − (α₁₀₀ − α₁₀) / ∛10. Where the first crossing of level 1 is the
mechanism's (pymunk, single blocks, the parapet, columns, arches) this onset is
0.1–0.4 % of α later than that crossing (the motion grows a little faster than
cubic), and the rate-0 extrapolations of both agree within 0.7 %.

The onset lags the true threshold: past it the mechanism accelerates from rest
under a load that grows with the ramp, and it takes a finite time to turn by
the onset angle. Linearised about the threshold, a rocking mechanism obeys
θ̈ − p²θ = c p² rate · τ (τ the time since the threshold, p its frequency
parameter, c = cos λ for one block), so θ = c · rate · (sinh(pτ)/p − τ) ≈
c · rate · p² τ³ / 6 while pτ is small: a level L is crossed τ_L ∝ L^(1/3)
rate^(−1/3) late, i.e. the onset factor (L = 1) overshoots by Δα ∝ rate^(2/3),
and τ₁₀₀ / τ₁₀ = ∛10 gives the back-extrapolation above. A rate is shown to be
quasi-static by halving it (:func:`quasi_static`): the onset factor changes by
the difference of the two lags, and the Richardson extrapolation
:attr:`TiltComparison.extrapolated_factor` with that exponent removes the lag.

Runs go through the campaign (:func:`rockbench.campaign.run_campaign`), so
their cost (CPU and wall time per run) is recorded next to the accuracy.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rockbench.analytic.static_collapse import LimitResult, limit_analysis
from rockbench.campaign import CampaignOptions, PlannedRun, run_campaign
from rockbench.method import Method
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Scenario
from rockbench.scenarios.excitation import TiltTable
from rockbench.trajectory import Status, Trajectory

__all__ = ["KIND", "ONSET_ROTATION", "ONSET_DISPLACEMENT", "DEVELOPED", "MOVED_FRACTION", "SETTLE",
           "TiltOutcome",
           "TiltComparison", "tilt_scenario", "tilt_outcome", "reference", "tilting_table",
           "quasi_static"]

#: The store's ``kind`` of runs made by this study.
KIND = "tilting"
#: Rotation relative to the rest pose (rad) that marks the onset of motion.
ONSET_ROTATION = 2e-4
#: Displacement relative to the base, as a fraction of the block's size, that marks it.
#: Engines lag a fast base by about one step's travel (pymunk at dt 0.1 ms: 2.5 mm at
#: α = 0.5 with rate 0.05/s, growing with the base speed as α²/rate), which is not
#: sliding: :func:`tilt_outcome` measures that lag, proportional to the base velocity,
#: while α is below half the reference factor, and removes it.
ONSET_DISPLACEMENT = 2e-3
#: Fraction of the reference factor below which the lag behind the base is measured.
_LAG_WINDOW = 0.5
#: A block takes part in the mechanism if its developed motion is at least this
#: fraction of the largest block's.
MOVED_FRACTION = 0.2
#: Time (s) the base stays still before tilting: contacts settle (a thin arch in pymunk
#: turns its voussoirs by 1.8e-4 rad in the first 0.25 s, then holds), and the rest pose
#: the onset is measured from is the one at the end of it.
SETTLE = 0.5
#: Level (multiple of the onset thresholds) at which the motion is "developed": its
#: blocks are the moving ones, and its crossings of this level and ten times it locate
#: the onset (module docstring).
DEVELOPED = 10.0


def tilt_scenario(scenario: Scenario, rate: float, *, direction: int = 1,
                  alpha_end: float, output_rate: float = 200.0,
                  settle: float = SETTLE) -> Scenario:
    """``scenario`` on a tilting table: ``settle`` s still, then up to α = ``alpha_end``."""
    return scenario.replace(
        name=f"{scenario.name}-tilt{'+' if direction > 0 else '-'}{rate:g}",
        excitation=TiltTable(rate, direction, gravity=scenario.g, delay=settle),
        duration=settle + alpha_end / rate, output_rate=output_rate)


@dataclass(frozen=True)
class TiltOutcome:
    """What one tilting-table run showed.

    Attributes
    ----------
    status : Status
        The run's status (``overturned`` is the usual end of a collapse).
    rate : float
        dα/dt (1/s).
    onset_factor : float
        α at which the developed motion relative to the base, extrapolated
        back, crossed the onset thresholds (module docstring; NaN: the motion
        never reached ten times :data:`DEVELOPED`).
    moved : tuple of int
        Blocks taking part in the developed motion (empty if it never developed).
    rotation_sign : tuple of int
        For each block in ``moved``, the sign of its rotation (+1: top toward +x),
        0 for a block that has not turned by the onset rotation (it translates).
    cpu_time, wall_time : float
        Cost of the run (s).
    message : str
        The run's message.
    """

    status: Status
    rate: float
    onset_factor: float
    moved: tuple[int, ...]
    rotation_sign: tuple[int, ...]
    cpu_time: float
    wall_time: float
    message: str = ""

    @property
    def onset_angle(self) -> float:
        """atan(onset factor) (rad): the tilt angle at which the assembly moved."""
        return math.atan(self.onset_factor)


def _sizes(scenario: Scenario) -> np.ndarray:
    return np.array([max(b.width, b.height) for b in scenario.blocks])


def tilt_outcome(traj: Trajectory, scenario: Scenario,
                 alpha_ref: float | None = None) -> TiltOutcome:
    """Onset and moving blocks of a tilting-table trajectory of ``scenario``.

    Parameters
    ----------
    traj : Trajectory
        The run.
    scenario : Scenario
        The scenario on its tilting table (:func:`tilt_scenario`).
    alpha_ref : float, optional
        The expected collapse factor: while α < α_ref / 2 each block's lag
        behind the base, c · u̇_g(t), is fitted and removed from its
        displacement (None: no correction).
    """
    exc = scenario.excitation
    if not isinstance(exc, TiltTable):
        raise ValueError(f"{scenario.name} is not on a tilting table ({exc.kind})")
    cost = (float(getattr(traj, "cpu_time", math.nan) or math.nan), float(traj.wall_time))
    if traj.t.size < 2 or not traj.status.completed:
        return TiltOutcome(traj.status, exc.rate, math.nan, (), (), *cost, traj.message)
    # the rest pose: the last sample before the ramp starts
    r = max(int(np.searchsorted(traj.t, exc.delay, side="right")) - 1, 0)
    turn = traj.theta - traj.theta[r]
    u = np.asarray(exc.displacement(traj.t), float)[:, None]
    slip = traj.x - traj.x[r] - u
    if alpha_ref is not None:
        v = np.asarray(exc.velocity(traj.t), float)
        early = exc.load_factor(traj.t) <= _LAG_WINDOW * alpha_ref
        vv = float(v[early] @ v[early])
        if vv > 0:
            slip = slip - np.outer(v, v[early] @ slip[early] / vv)
    disp = np.hypot(slip, traj.z - traj.z[r]) / _sizes(scenario)
    # motion in units of the onset thresholds, per sample and block
    level = np.maximum(np.abs(turn) / ONSET_ROTATION, disp / ONSET_DISPLACEMENT)
    level[:r] = 0.0  # settling on the contacts is not the onset
    peak = level.max(axis=1)
    alpha = np.asarray(exc.load_factor(traj.t), float)
    developed = np.nonzero(peak > DEVELOPED)[0]
    if developed.size == 0:
        return TiltOutcome(traj.status, exc.rate, math.nan, (), (), *cost, traj.message)
    j = developed[0]
    moved = tuple(int(i) for i in np.nonzero(level[j] >= MOVED_FRACTION * peak[j])[0])
    signs = tuple(int(np.sign(turn[j, i])) if abs(turn[j, i]) > ONSET_ROTATION else 0
                  for i in moved)
    a10, a100 = _crossing(alpha, peak, DEVELOPED), _crossing(alpha, peak, 10.0 * DEVELOPED)
    onset = a10 - (a100 - a10) / 10.0 ** (1.0 / 3.0)
    return TiltOutcome(traj.status, exc.rate, onset, moved, signs, *cost, traj.message)


def _crossing(alpha: np.ndarray, peak: np.ndarray, level: float) -> float:
    """α where ``peak`` first exceeds ``level``, interpolated in log level (NaN: never)."""
    above = np.nonzero(peak > level)[0]
    if above.size == 0:
        return math.nan
    k = int(above[0])
    if k == 0 or peak[k - 1] <= 0.0:
        return float(alpha[k])
    lo, hi = math.log(peak[k - 1]), math.log(peak[k])
    return float(alpha[k - 1] + (math.log(level) - lo) / (hi - lo) * (alpha[k] - alpha[k - 1]))


def reference(scenario: Scenario, direction: int = 1) -> LimitResult:
    """The limit-analysis collapse of ``scenario``'s blocks under loads toward ``direction``.

    The scenario's base friction at every joint, real (non-associative)
    Coulomb joints (:mod:`rockbench.analytic.static_collapse`): where no joint
    slides it is the associative factor; on a running-bond wall it is the
    stepped wedge that turns out of the wall with its head joints opening
    (6 × 3 wall: 11/19 = 0.579), where the associative LP leans on friction at
    head joints that nothing presses (0.992).
    """
    mu = scenario.contact.friction
    return limit_analysis(scenario.geometry, friction=mu, direction=direction,
                          g=scenario.g,
                          flow="non-associative" if math.isfinite(mu) else "associative")


@dataclass(frozen=True)
class TiltComparison:
    """A tilting-table run at a rate and at half of it, against limit analysis.

    Attributes
    ----------
    engine : str
        Engine name.
    scenario : str
        Scenario name (at rest).
    direction : int
        Sense of the horizontal loads (+1: toward +x).
    limit : LimitResult
        The reference factor and mechanism.
    run, half : TiltOutcome
        At ``rate`` and at ``rate / 2``.
    settings : mapping
        The engine settings used.
    """

    engine: str
    scenario: str
    direction: int
    limit: LimitResult
    run: TiltOutcome
    half: TiltOutcome
    settings: Mapping[str, Any] = field(default_factory=dict)

    @property
    def error(self) -> float:
        """Relative error of the onset factor at half the rate: α_engine / α_LP − 1."""
        return self.half.onset_factor / self.limit.load_factor - 1.0

    @property
    def angle_error(self) -> float:
        """Error of the onset angle at half the rate (rad): atan α_engine − atan α_LP."""
        return self.half.onset_angle - self.limit.tilt_angle

    @property
    def extrapolated_factor(self) -> float:
        """The onset factor extrapolated to rate 0 from the two rates, with Δα ∝ rate^(2/3)."""
        a, b = self.run.onset_factor, self.half.onset_factor
        return b - (a - b) / (2.0 ** (2.0 / 3.0) - 1.0)

    @property
    def extrapolated_error(self) -> float:
        """Relative error of :attr:`extrapolated_factor` against the LP factor."""
        return self.extrapolated_factor / self.limit.load_factor - 1.0

    @property
    def rate_change(self) -> float:
        """Relative change of the onset factor when the rate is halved (quasi-statics)."""
        return self.half.onset_factor / self.run.onset_factor - 1.0

    @property
    def mechanism_matches(self) -> bool:
        """True if the blocks that moved (at half the rate) are the mechanism's."""
        return self.half.moved == self.limit.moving_blocks


def _plan(scenarios: Sequence[Scenario], method: Method, rate: float, direction: int,
          limits: Sequence[LimitResult], overshoot: float) -> list[PlannedRun]:
    plan = []
    for sc, lim in zip(scenarios, limits, strict=True):
        alpha_end = overshoot * lim.load_factor + 0.02
        for r in (rate, 0.5 * rate):
            plan.append(PlannedRun(tilt_scenario(sc, r, direction=direction,
                                                 alpha_end=alpha_end), method))
    return plan


def tilting_table(scenarios: Sequence[Scenario], engine: str, *, rate: float = 0.05,
                  direction: int = 1, settings: Mapping[str, Any] | None = None,
                  execution: ExecutionOptions | None = None,
                  overshoot: float = 1.3, db: Path | None = None) -> list[TiltComparison]:
    """Tilt each scenario at ``rate`` and ``rate / 2`` in ``engine``; compare with the LP.

    Parameters
    ----------
    scenarios : sequence of Scenario
        Assemblies (or single blocks and stacks) at rest.
    engine : str
        Registered engine name.
    rate : float
        dα/dt (1/s) of the first run; the second runs at half of it.
    direction : {+1, -1}
        Sense of the horizontal loads.
    settings : mapping, optional
        Engine knob overrides (``"preset"`` selects a preset).
    execution : ExecutionOptions, optional
        How the runs are executed (default: one isolated worker).
    overshoot : float
        Each run lasts until α = overshoot · α_LP + 0.02.
    db : Path, optional
        The results store, where each run is recorded as it finishes (kind
        ``tilting``; limit analysis is the reference of the onset, not of a
        trajectory).

    Returns
    -------
    list of TiltComparison
        One per scenario, in order.

    Raises
    ------
    ValueError
        A scenario without a collapse mechanism under these loads.
    """
    limits = [reference(sc, direction) for sc in scenarios]
    for sc, lim in zip(scenarios, limits, strict=True):
        if lim.status != "collapse":
            raise ValueError(f"{sc.name}: limit analysis finds no collapse ({lim.status})")
    s = dict(settings or {})
    plan = _plan(scenarios, Method.of(engine, s), rate, direction, limits, overshoot)
    ex = execution or ExecutionOptions()
    campaign = run_campaign(plan, CampaignOptions(
        kind=KIND, db=db, keep=True, references=False, execution=ex, timeout=ex.timeout))
    outcomes = [tilt_outcome(campaign.trajectories[run.key], run.scenario, lim.load_factor)
                for run, lim in zip(plan, [x for x in limits for _ in (0, 1)], strict=True)]
    return [TiltComparison(engine, sc.name, direction, lim, outcomes[2 * k], outcomes[2 * k + 1], s)
            for k, (sc, lim) in enumerate(zip(scenarios, limits, strict=True))]


def quasi_static(comparison: TiltComparison, tol: float) -> bool:
    """True if halving the rate moved the onset factor by less than ``tol`` (relative)."""
    return math.isfinite(comparison.rate_change) and abs(comparison.rate_change) < tol
