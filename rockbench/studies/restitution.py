"""Restitution fidelity: the coefficient of restitution each engine and preset produces.

Users of game and robotics engines ask which η their engine gives a rocking block. This
study answers it impact by impact: every method (each engine at each preset, and the
analytic reference) runs free rocking of blocks of several slendernesses (by default
the paper's four, released from half their λ), and
:func:`rockbench.analytic.effective_restitution` reads the effective η of each impact
off the trajectory. Beside it stand Housner's η = 1 − 1.5 sin²λ, the value of a
perfectly plastic impact about the new corner (what an engine asked for no bounce,
``restitution = 0``, should give), and published shake-table measurements
(:data:`EXPERIMENTS`): η asked, η obtained, η measured. The engines' own restitution
knob (the scenario's ``contact.restitution``, a bounce coefficient e) can be swept too,
to show the η a user gets for the e they set.

This is the Python API behind ``rockbench restitution``::

    from rockbench.studies.restitution import RestitutionOptions, run_restitution
    result = run_restitution(RestitutionOptions(engines=["mujoco", "pymunk"]))
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rockbench.analytic import critical_angle
from rockbench.analytic.overturning import housner_eta
from rockbench.analytic.restitution import ImpactRestitution, effective_restitution
from rockbench.campaign import CampaignOptions, PlannedRun, run_campaign
from rockbench.engines import engine_class
from rockbench.errors import RockbenchError
from rockbench.method import Method
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Scenario, get_scenario
from rockbench.trajectory import Status, Trajectory

__all__ = ["KIND", "DEFAULT_SCENARIOS", "Experiment", "EXPERIMENTS", "RestitutionOptions",
           "RestitutionRow", "RestitutionResult", "run_restitution", "sampled_for"]

#: The store's ``kind`` of runs made by this study.
KIND = "restitution"
#: The paper's four blocks (λ from 0.20 to 0.59 rad), released from 0.5 λ.
DEFAULT_SCENARIOS = ("free-b0", "free-b3-0.5", "free-b2-0.5", "free-b1-0.5")


@dataclass(frozen=True)
class Experiment:
    """A published measurement of the coefficient of restitution of free-rocking blocks.

    Attributes
    ----------
    source : str
        Who measured it, and where it is published.
    aspect : float
        Height over width of the blocks, h/b (λ = atan(b/h)).
    base : str
        What the blocks rocked on.
    ratio : float
        The measured coefficient over Housner's prediction for the same block, as the
        source reports it.
    """

    source: str
    aspect: float
    base: str
    ratio: float

    @property
    def lam(self) -> float:
        """λ = atan(1 / aspect) (rad)."""
        return math.atan(1.0 / self.aspect)


_ELGAWADY = ("ElGawady, Ma, Butterworth & Ingham (2011), Effects of interface material "
             "on the performance of free rocking blocks, Earthquake Engng Struct. Dyn. "
             "40(4), 375–392")

#: Shake-table measurements against Housner's η (the ratio as each source reports it).
EXPERIMENTS = (
    Experiment(_ELGAWADY, 3.0, "concrete", 0.97),
    Experiment(_ELGAWADY, 5.0, "concrete", 0.95),
    Experiment(_ELGAWADY, 5.0, "rubber", 0.67),
)


@dataclass
class RestitutionOptions:
    """What the study runs and how.

    Attributes
    ----------
    scenarios : sequence of Scenario
        Free-rocking single blocks (default :data:`DEFAULT_SCENARIOS`).
    engines : list of str
        Engines beside the analytic reference (always run).
    presets : list of str
        Each engine runs once per preset.
    overrides : dict
        Per engine, knob overrides on top of every preset.
    restitution : sequence of float
        The engines' bounce coefficients e to run (``contact.restitution``, in [0, 1]);
        the analytic reference runs once per block (it takes Housner's η).
    impacts : int
        At most this many impacts per run are measured (≥ 1).
    execution : ExecutionOptions
        Workers, executor, isolation, time limit.
    resume : bool
        Reuse the runs found in the store (their trajectories are archived there).
    db : Path or None
        The results store (None: record nothing).
    command : str
        The command line shown in the report.
    """

    scenarios: Sequence[Scenario] = field(
        default_factory=lambda: [get_scenario(n) for n in DEFAULT_SCENARIOS])
    engines: list[str] = field(default_factory=list)
    presets: list[str] = field(default_factory=lambda: ["accurate", "fast"])
    overrides: dict[str, dict[str, Any]] = field(default_factory=dict)
    restitution: Sequence[float] = (0.0,)
    impacts: int = 5
    execution: ExecutionOptions = field(default_factory=ExecutionOptions)
    resume: bool = False
    db: Path | None = None
    command: str = ""


@dataclass(frozen=True)
class RestitutionRow:
    """One method on one block.

    Attributes
    ----------
    method : str
        Method label.
    preset : str
        The engine's preset ("" for the analytic reference).
    scenario : str
        Scenario name (the block's, without the bounce coefficient).
    restitution : float
        The bounce coefficient e the engine was given (0 for the analytic reference).
    lam : float
        The block's λ (rad).
    housner : float
        Housner's η for it.
    status : Status
        How the run ended.
    impacts : ImpactRestitution or None
        η of each impact (None: the run has none to measure, ``note`` says why).
    cpu_time : float
        The run's CPU time (s).
    note : str
        Why no η was measured.
    """

    method: str
    preset: str
    scenario: str
    restitution: float
    lam: float
    housner: float
    status: Status
    impacts: ImpactRestitution | None
    cpu_time: float
    note: str = ""

    @property
    def mean(self) -> float:
        """Mean η over the measured impacts (NaN without one)."""
        return self.impacts.mean if self.impacts is not None else math.nan

    @property
    def ratio(self) -> float:
        """Mean η over Housner's (NaN without one)."""
        return self.mean / self.housner


@dataclass(frozen=True)
class RestitutionResult:
    """What the study ran and found.

    Attributes
    ----------
    options : RestitutionOptions
        What was asked.
    methods : tuple of Method
        The analytic reference first, then the engines at their presets.
    rows : tuple of RestitutionRow
        Per scenario and method.
    versions : dict
        Engine → library version.
    ran, reused : int
        Runs executed now and taken from the store.
    wall_time : float
        Wall time of the study (s).
    """

    options: RestitutionOptions
    methods: tuple[Method, ...]
    rows: tuple[RestitutionRow, ...]
    versions: dict[str, str]
    ran: int
    reused: int
    wall_time: float

    def row(self, method: str, scenario: str, restitution: float = 0.0) -> RestitutionRow:
        """The row of one method on one scenario at one bounce coefficient."""
        for r in self.rows:
            if (r.method, r.scenario, r.restitution) == (method, scenario, restitution):
                return r
        raise KeyError((method, scenario, restitution))


def _free_block(sc: Scenario) -> float:
    """λ of a free-rocking single block, or RockbenchError saying what it is not."""
    col = sc.geometry.column
    if col is None or len(col) != 1 or not sc.excitation.is_free or sc.theta0 == 0.0:
        raise RockbenchError(f"scenario {sc.name!r}: the restitution study measures free "
                             f"rocking of one block released from a tilt (e.g. free-b2-0.5)")
    return critical_angle(sc.geometry)


def _measure(traj: Trajectory | None, lam: float, impacts: int
             ) -> tuple[ImpactRestitution | None, str]:
    if traj is None:
        return None, "no trajectory kept (rerun without --resume, or with a store)"
    if traj.status is not Status.OK:
        return None, f"the run ended {traj.status.value}"
    try:
        found = effective_restitution(traj.t, traj.theta[:, 0], lam, impacts=impacts)
    except RockbenchError as exc:
        return None, str(exc)
    if not found.eta:
        return None, "no impact above the contact's jitter"
    return found, ""


def sampled_for(scenario: Scenario, method: Method) -> Scenario:
    """``scenario`` at an output rate ``method``'s time step allows.

    A method whose step is longer than the scenario's output interval (a ``game`` preset
    at 60 Hz against the paper's 1 kHz) runs the scenario sampled once per step, so that
    each sample is a state the engine computed (the peaks between impacts are then read
    to within about (π f Δt)²/2 of their height, 0.5 % for a 1 Hz swing at 60 Hz).
    """
    step = engine_class(method.engine).resolve_settings(method.settings).physics_step
    if step is None or step * scenario.output_rate <= 1.0 + 1e-9:
        return scenario
    rate = 1.0 / step
    return scenario.replace(name=f"{scenario.name}|{rate:.4g}Hz", output_rate=rate)


def run_restitution(opts: RestitutionOptions,
                    progress: Callable[[int, str], Any] | None = None) -> RestitutionResult:
    """Run (or resume) the free-rocking runs and measure each impact's η.

    Raises
    ------
    RockbenchError
        A scenario that is not a free-rocking block, fewer than one impact asked, an
        unknown engine or bad settings.
    """
    start = time.perf_counter()
    if opts.impacts < 1:
        raise RockbenchError(f"impacts must be at least 1, got {opts.impacts!r}")
    if not opts.restitution or not all(0.0 <= e <= 1.0 for e in opts.restitution):
        raise RockbenchError(f"restitution coefficients must be in [0, 1], got "
                             f"{list(opts.restitution)}")
    lams = {sc.name: _free_block(sc) for sc in opts.scenarios}
    engines = list(dict.fromkeys(e for e in opts.engines if not Method(e).is_reference))
    methods = (Method.reference(),) + tuple(
        Method.of(e, {"preset": p, **opts.overrides.get(e, {})}, qualified=True)
        for e in engines for p in opts.presets)
    plan, asked = [], []
    for sc in opts.scenarios:
        plan.append(PlannedRun(sc, methods[0]))
        asked.append((sc.name, 0.0))
        for e in dict.fromkeys(float(v) for v in opts.restitution):
            bounced = sc if e == sc.contact.restitution else sc.replace(
                name=f"{sc.name}|e={e:g}",
                contact=dataclasses.replace(sc.contact, restitution=e))
            plan += [PlannedRun(sampled_for(bounced, m), m) for m in methods[1:]]
            asked += [(sc.name, e)] * (len(methods) - 1)
    campaign = run_campaign(plan, CampaignOptions(
        kind=KIND, suite="restitution", db=opts.db, resume=opts.resume,
        archive=opts.db is not None, keep=True, execution=opts.execution),
        progress=progress)
    rows = []
    for run, res, (name, e) in zip(plan, campaign.results, asked, strict=True):
        lam = lams[name]
        found, note = _measure(campaign.trajectories.get(run.key), lam, opts.impacts)
        rows.append(RestitutionRow(run.method.label, run.method.preset, name, e, lam,
                                   housner_eta(lam), res.metrics.status, found,
                                   res.metrics.cpu_time or 0.0, note))
    return RestitutionResult(opts, methods, tuple(rows), campaign.versions, campaign.ran,
                             campaign.reused, time.perf_counter() - start)
