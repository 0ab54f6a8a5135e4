"""Wobbling: does an engine keep planar rocking planar?

Giordano et al. (2025) drove Single #2 (0.17 × 0.502 × 1.0 m) with the 5 Hz / 6 mm
sinusoid: Vortex and 3DEC rotated the block about a second axis ("wobbling"), Bullet
and the shake-table test did not. This study asks every engine the same question, free
in 3D: the scenario as the catalog has it (the base moves exactly along x, the block's
principal axis: the *symmetric* variant) and with a tiny out-of-plane perturbation, a y
component of the base motion ε times the x one (the *asymmetric* variant, an incidence
of atan ε: 0.06° at the default ε = 10⁻³).

The reference stays planar in both. A rectangular block rocking on a full edge rests on a
line of length d (its depth); rotating it about x (a roll) means lifting one end of that
line, which a y acceleration does only past g·(d/2)/h_c (h_c the centroid's height): 4.9
m/s² for Single #2, 830 times the ε = 10⁻³ component (5.9·10⁻³ m/s²). A twist about z
needs a torque about the vertical, which no base motion through a symmetric block's
contact line gives. So the analytic reference is planar, the y component only carries
the block along, and an engine that rolls or twists is adding its own out-of-plane
motion.

Each engine (at each preset) runs both variants, and again at its time step halved
(:meth:`rockbench.engines.Engine.refined`, level 1) to see whether its out-of-plane
response converges. The verdict of a method on a variant is :class:`Verdict`:
*stays planar* when max |roll| and max |twist| stay below :data:`THRESHOLD` λ,
*wobbles* above, *planar by construction* for 2D engines, the analytic reference and
engines holding blocks in the plane by a constraint (Blender's ``planar``), *unsupported*
where the engine does not apply a y base motion, *failed* where the run did not
complete.

This is the Python API behind ``rockbench wobbling``::

    from rockbench.studies.wobbling import WobblingOptions, run_wobbling
    result = run_wobbling(WobblingOptions(engines=["mujoco", "bullet"]))
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum
from pathlib import Path
from typing import Any

import numpy as np

from rockbench.analytic import critical_angle
from rockbench.campaign import CampaignOptions, PlannedRun, run_campaign
from rockbench.engines import SettingsError, engine_class
from rockbench.errors import RockbenchError
from rockbench.evaluation import PEAK_FLOOR, RunResult
from rockbench.method import Method
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Scenario, get_scenario
from rockbench.scenarios.excitation import AxialExcitation, Components
from rockbench.trajectory import Status, Trajectory

__all__ = ["KIND", "DEFAULT_SCENARIO", "THRESHOLD", "CONVERGENCE_TOLERANCE", "Variant",
           "Verdict", "Convergence", "PaperCase", "PAPER", "WobblingOptions", "WobblingRow",
           "WobblingSeries", "WobblingVerdict", "WobblingResult", "asymmetric_scenario",
           "out_of_plane_uplift", "run_wobbling"]

#: The store's ``kind`` of runs made by this study.
KIND = "wobbling"
#: The paper's wobbling case: Single #2 under the 5 Hz / 6 mm sinusoid.
DEFAULT_SCENARIO = "single-sine-5.0hz-6mm"
#: A method stays planar while max |roll| and max |twist| stay below this fraction of λ.
#: 10⁻³ λ is the in-plane accuracy of the best engines on free rocking (0.5–2·10⁻³ λ, the
#: README's table): an out-of-plane rotation below it is below what the benchmark resolves
#: in the plane (for Single #2, 1.7·10⁻⁴ rad, 0.17 mm at the top of the 1 m block), and
#: well above the engines' round-off (10⁻¹⁸ to 10⁻⁵ rad, float32 included).
THRESHOLD = 1e-3
#: The halved step converges when it gives the same max |roll| and max |twist| within this
#: relative difference (or both rungs stay below :data:`THRESHOLD`).
CONVERGENCE_TOLERANCE = 0.2


class Variant(str, Enum):
    """The base motion of a run: exactly along x, or with a tiny y component."""

    SYMMETRIC = "symmetric"
    ASYMMETRIC = "asymmetric"

    def __str__(self) -> str:
        return self.value


class Verdict(str, Enum):
    """What a method does out of the plane."""

    STAYS_PLANAR = "stays planar"
    WOBBLES = "wobbles"
    PLANAR_BY_CONSTRUCTION = "planar by construction"
    UNSUPPORTED = "unsupported"
    FAILED = "failed"

    def __str__(self) -> str:
        return self.value


class Convergence(str, Enum):
    """Whether the out-of-plane response holds when the time step is halved."""

    CONVERGED = "converged"
    NOT_CONVERGED = "not converged"
    NOT_MEASURED = "not measured"
    NOT_APPLICABLE = "–"

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class PaperCase:
    """What Giordano et al. (2025) report of one method on the wobbling case.

    Attributes
    ----------
    method : str
        The method as the paper names it.
    wobbled : bool or None
        Whether it rotated about a second axis (None: planar by construction).
    error : float or None
        Table 7: (θ_method − θ_experiment)/θ_experiment for max |θ| on the 5 Hz / 6 mm
        sinusoid, magnitude (None: not given).
    note : str
        What else the paper says.
    """

    method: str
    wobbled: bool | None
    error: float | None
    note: str = ""


#: The paper on Single #2 under the 5 Hz / 6 mm sinusoid (Section 5, Table 7).
PAPER = (
    PaperCase("experiment (Peña et al. 2008)", False, 0.0, "the measurement the errors are of"),
    PaperCase("analytical (Housner, ODE45)", None, 0.43,
              "planar by construction; underestimates"),
    PaperCase("Bullet (Blender)", False, 0.07, "did not wobble"),
    PaperCase("Vortex", True, 1.07, "wobbled"),
    PaperCase("DEM (3DEC)", True, None, "wobbled and collapsed"),
)


@dataclass
class WobblingOptions:
    """What the study runs and how.

    Attributes
    ----------
    scenario : Scenario
        A block or column excited along x only (default :data:`DEFAULT_SCENARIO`).
    engines : list of str
        Engines beside the analytic reference (always run).
    presets : list of str
        Each engine runs at each preset (an ``overrides`` entry ``preset`` runs that
        engine at that preset only).
    overrides : dict
        Per engine, knob overrides on top of every preset.
    asymmetry : float
        ε: the asymmetric variant's y base motion is ε times the x one (> 0).
    converge : bool
        Also run each engine at its time step halved.
    duration : float or None
        Simulated time (s; None: the scenario's).
    threshold : float
        Planar while max |roll| and |twist| stay below this fraction of λ.
    execution : ExecutionOptions
        Workers, executor, isolation, time limit.
    resume : bool
        Reuse the runs found in the store (their trajectories are archived there).
    db : Path or None
        The results store (None: record nothing).
    command : str
        The command line shown in the report.
    """

    scenario: Scenario = field(default_factory=lambda: get_scenario(DEFAULT_SCENARIO))
    engines: list[str] = field(default_factory=list)
    presets: list[str] = field(default_factory=lambda: ["accurate"])
    overrides: dict[str, dict[str, Any]] = field(default_factory=dict)
    asymmetry: float = 1e-3
    converge: bool = True
    duration: float | None = None
    threshold: float = THRESHOLD
    execution: ExecutionOptions = field(default_factory=ExecutionOptions)
    resume: bool = False
    db: Path | None = None
    command: str = ""


@dataclass(frozen=True)
class WobblingRow:
    """One run: a method on a variant at a rung of the time step.

    Attributes
    ----------
    method : str
        The method's label at rung 0 (``mujoco[accurate]``); a rung-1 run keeps it.
    engine, preset : str
        Engine and preset ("" for the analytic reference).
    variant : Variant
        The base motion.
    rung : int
        0: the preset's time step; 1: halved.
    timestep : float or None
        The run's time step (s; None where the engine has no such knob).
    status : Status
        How the run ended.
    message : str
        Why, when it did not end ``ok``.
    max_roll, max_twist, max_wobble : float or None
        Largest |rotation about +x|, |twist about the block's vertical axis| and angle
        between the block's y axis and the world's (rad, over the blocks).
    max_drift : float or None
        Largest |y − y(0) − u_gy(t)|: how far the centroid leaves the plane the base
        carries it in (m; lean and slip across the plane).
    peak : float or None
        max |θ|/λ.
    peak_error : float or None
        (peak − reference peak) / max(reference peak, PEAK_FLOOR), against the planar
        reference of the symmetric variant (which the asymmetric one keeps, see the
        module docstring).
    cpu_time : float
        CPU time of the run (s).
    lam : float
        λ of the scenario (rad).
    """

    method: str
    engine: str
    preset: str
    variant: Variant
    rung: int
    timestep: float | None
    status: Status
    message: str
    max_roll: float | None
    max_twist: float | None
    max_wobble: float | None
    max_drift: float | None
    peak: float | None
    peak_error: float | None
    cpu_time: float
    lam: float

    @property
    def out_of_plane(self) -> float | None:
        """max(max |roll|, max |twist|) / λ (None where not measured)."""
        if self.max_roll is None or self.max_twist is None:
            return None
        return max(self.max_roll, self.max_twist) / self.lam


@dataclass(frozen=True)
class WobblingSeries:
    """The time histories of a rung-0 run, for the figures (bottom block).

    Attributes
    ----------
    method : str
        The method's label.
    variant : Variant
        The base motion.
    t, roll, twist : ndarray
        Times (s), roll and twist (rad).
    x, y : ndarray
        The centroid seen from above (m): x − x(0), and y − y(0) − u_gy(t), its departure
        from the plane the base's y motion carries it in (the drift of
        :attr:`WobblingRow.max_drift`).
    """

    method: str
    variant: Variant
    t: np.ndarray
    roll: np.ndarray
    twist: np.ndarray
    x: np.ndarray
    y: np.ndarray


@dataclass(frozen=True)
class WobblingVerdict:
    """A method's verdict on one variant.

    Attributes
    ----------
    method, engine, preset : str
        Who.
    variant : Variant
        The base motion.
    verdict : Verdict
        What it does out of the plane at its preset (rung 0).
    convergence : Convergence
        Whether the halved step gives the same out-of-plane response.
    row : WobblingRow
        The rung-0 run.
    refined : WobblingRow or None
        The rung-1 run (None: not run).
    note : str
        Why the verdict or the convergence is what it is, where a reason is needed.
    """

    method: str
    engine: str
    preset: str
    variant: Variant
    verdict: Verdict
    convergence: Convergence
    row: WobblingRow
    refined: WobblingRow | None
    note: str = ""


@dataclass(frozen=True)
class WobblingResult:
    """What the study ran and found.

    Attributes
    ----------
    options : WobblingOptions
        What was asked.
    scenario : Scenario
        The symmetric variant as run (duration applied).
    asymmetric : Scenario
        The asymmetric variant.
    lam : float
        λ (rad).
    methods : tuple of Method
        The analytic reference first, then the engines at their presets (rung 0).
    rows : tuple of WobblingRow
        Every run.
    verdicts : tuple of WobblingVerdict
        Per method and variant.
    series : tuple of WobblingSeries
        Time histories of the rung-0 runs that have samples.
    reference_peak : float or None
        The planar reference's max |θ|/λ.
    uplift_ratio : float
        The y base acceleration that lifts one end of the rocking edge over the
        asymmetric variant's largest y acceleration (> 1: the reference stays planar).
    versions : dict
        Engine → library version.
    ran, reused : int
        Runs executed now and taken from the store.
    wall_time : float
        Wall time of the study (s).
    """

    options: WobblingOptions
    scenario: Scenario
    asymmetric: Scenario
    lam: float
    methods: tuple[Method, ...]
    rows: tuple[WobblingRow, ...]
    verdicts: tuple[WobblingVerdict, ...]
    series: tuple[WobblingSeries, ...]
    reference_peak: float | None
    uplift_ratio: float
    versions: dict[str, str]
    ran: int
    reused: int
    wall_time: float

    def verdict(self, method: str, variant: Variant | str) -> WobblingVerdict:
        """The verdict of one method (its rung-0 label) on one variant."""
        for v in self.verdicts:
            if v.method == method and v.variant == Variant(variant):
                return v
        raise KeyError((method, variant))

    def row(self, method: str, variant: Variant | str, rung: int = 0) -> WobblingRow:
        """The run of one method on one variant at one rung."""
        for r in self.rows:
            if (r.method, r.variant, r.rung) == (method, Variant(variant), rung):
                return r
        raise KeyError((method, variant, rung))

    def series_of(self, method: str, variant: Variant | str) -> WobblingSeries | None:
        """The time histories of one method on one variant (None: no samples)."""
        return next((s for s in self.series
                     if s.method == method and s.variant == Variant(variant)), None)


def _x_motion(sc: Scenario) -> AxialExcitation:
    """The scenario's x base motion, or RockbenchError when it moves along other axes."""
    ex = sc.excitation
    if isinstance(ex, Components):
        if not (ex.y.is_free and ex.z.is_free):
            raise RockbenchError(f"scenario {sc.name!r}: the wobbling study perturbs a base "
                                 "motion along x only; this one also moves along y or z")
        ex_x: Any = ex.x
    else:
        ex_x = ex
    if not isinstance(ex_x, AxialExcitation) or ex_x.is_free:
        raise RockbenchError(f"scenario {sc.name!r}: the wobbling study needs a base motion "
                             f"along x (e.g. {DEFAULT_SCENARIO})")
    return ex_x


def asymmetric_scenario(scenario: Scenario, asymmetry: float) -> Scenario:
    """``scenario`` with a y base motion ``asymmetry`` times its x one.

    The y component is the x motion scaled (its ``amplitude``, or a record's ``scale``):
    the base moves along a line at atan(ε) from x.

    Raises
    ------
    RockbenchError
        ε not finite and > 0, a scenario whose base does not move along x only, or a
        motion that has neither an amplitude nor a scale.
    """
    if not (isinstance(asymmetry, (int, float)) and math.isfinite(asymmetry)
            and asymmetry > 0):
        raise RockbenchError(f"the asymmetry ε must be a finite number > 0, got {asymmetry!r}")
    ex: Any = _x_motion(scenario)  # a frozen dataclass, whichever kind
    names = {f.name for f in dataclasses.fields(ex)}
    knob = "amplitude" if "amplitude" in names else "scale" if "scale" in names else None
    if knob is None:
        raise RockbenchError(f"scenario {scenario.name!r}: its {ex.kind} base motion has no "
                             "amplitude or scale to make a y component of")
    y = dataclasses.replace(ex, **{knob: getattr(ex, knob) * asymmetry})
    return scenario.replace(name=f"{scenario.name}|y={asymmetry:g}x",
                            excitation=Components(x=ex, y=y))


def out_of_plane_uplift(scenario: Scenario) -> float:
    """The y base acceleration (m/s²) that lifts one end of the bottom block's rocking edge,
    g·(d/2)/h_c, d the block's depth and h_c its centroid's height."""
    col = scenario.geometry.column
    if col is None:
        raise RockbenchError(f"scenario {scenario.name!r}: the wobbling study runs a block or "
                             "a column of blocks on the base")
    b = col.blocks[0]
    return scenario.g * 0.5 * b.depth / (0.5 * b.height)


def _by_construction(method: Method) -> str:
    """Why ``method`` cannot leave the plane ('' : it can)."""
    if method.is_reference:
        return "the analytic reference is planar"
    cls = engine_class(method.engine)
    if cls.capabilities.dimensions == 2:
        return f"{method.engine} is a 2D engine"
    if getattr(cls.resolve_settings(method.settings), "planar", False) is True:
        return f"{method.engine} holds each block in the x–z plane (planar = true)"
    return ""


def _timestep(method: Method) -> float | None:
    if method.is_reference:
        return None
    return engine_class(method.engine).resolve_settings(method.settings).physics_step


def _max(a: np.ndarray) -> float | None:
    if not a.size:
        return None
    v = float(np.max(np.abs(a)))
    return v if math.isfinite(v) else None


def _drift(traj: Trajectory | None, scenario: Scenario) -> float | None:
    if traj is None or not traj.t.size:
        return None
    u = np.asarray(scenario.motion.y.displacement(traj.t), float).reshape(-1, 1)
    return _max(traj.y - traj.y[:1] - u)


@dataclass(frozen=True)
class _Planned:
    run: PlannedRun
    label: str
    variant: Variant
    rung: int
    construction: str


def _plan(opts: WobblingOptions, sym: Scenario, asym: Scenario
          ) -> tuple[tuple[Method, ...], list[_Planned], dict[str, str]]:
    engines = list(dict.fromkeys(e for e in opts.engines if not Method(e).is_reference))
    methods: list[Method] = [Method.reference()]
    for e in engines:
        over = dict(opts.overrides.get(e, {}))
        presets = [over.pop("preset")] if "preset" in over else opts.presets
        methods += [Method.of(e, {"preset": p, **over}, qualified=True) for p in presets]
    plan = [_Planned(PlannedRun(sym, methods[0]), methods[0].label, Variant.SYMMETRIC, 0,
                     _by_construction(methods[0]))]
    notes: dict[str, str] = {}
    for m in methods[1:]:
        why = _by_construction(m)
        cls = engine_class(m.engine)
        for variant, sc in ((Variant.SYMMETRIC, sym), (Variant.ASYMMETRIC, asym)):
            plan.append(_Planned(PlannedRun(sc, m), m.label, variant, 0, why))
            applies = all(a in cls.capabilities.base_axes for a in sc.motion.axes)
            if not opts.converge or why or not applies:
                continue
            try:
                finer = cls.refined(m.settings, 1)
            except SettingsError as exc:
                notes[m.label] = str(exc)
                continue
            rung = Method.of(m.engine, finer, variation=f"{m.preset or 'defaults'}, rung 1")
            plan.append(_Planned(PlannedRun(sc, rung), m.label, variant, 1, why))
    return tuple(methods), plan, notes


def _row(p: _Planned, res: RunResult, traj: Trajectory | None, lam: float,
         ref_peak: float | None) -> WobblingRow:
    mt = res.metrics
    peaks = [v for v in mt.peaks if v is not None]
    peak = max(peaks) if peaks else None
    err = (None if peak is None or ref_peak is None or p.run.method.is_reference
           else (peak - ref_peak) / max(ref_peak, PEAK_FLOOR))
    drift = _drift(traj, p.run.scenario)
    return WobblingRow(
        method=p.label, engine=p.run.method.engine, preset=p.run.method.preset,
        variant=p.variant, rung=p.rung, timestep=_timestep(p.run.method), status=mt.status,
        message=mt.message, max_roll=mt.max_roll, max_twist=mt.max_twist,
        max_wobble=mt.max_wobble, max_drift=drift, peak=peak, peak_error=err,
        cpu_time=mt.cpu_time or 0.0, lam=lam)


def _verdict_of(row: WobblingRow, construction: str, threshold: float) -> Verdict:
    if construction:
        return Verdict.PLANAR_BY_CONSTRUCTION
    if row.status is Status.UNSUPPORTED:
        return Verdict.UNSUPPORTED
    oop = row.out_of_plane
    if not row.status.completed or oop is None:
        return Verdict.FAILED
    return Verdict.STAYS_PLANAR if oop <= threshold else Verdict.WOBBLES


def _convergence(row: WobblingRow, finer: WobblingRow | None, verdict: Verdict,
                 threshold: float) -> tuple[Convergence, str]:
    if verdict in (Verdict.PLANAR_BY_CONSTRUCTION, Verdict.UNSUPPORTED, Verdict.FAILED):
        return Convergence.NOT_APPLICABLE, ""
    if finer is None:
        return Convergence.NOT_MEASURED, ""
    if finer.out_of_plane is None or not finer.status.completed:
        return Convergence.NOT_CONVERGED, f"the halved step ended {finer.status.value}"
    a, b = row.out_of_plane, finer.out_of_plane
    assert a is not None
    if a <= threshold and b <= threshold:
        return Convergence.CONVERGED, "planar at both steps"
    pairs = ((row.max_roll, finer.max_roll), (row.max_twist, finer.max_twist))
    change = max(abs(x - y) / max(abs(x), abs(y)) for x, y in pairs
                 if x is not None and y is not None and max(abs(x), abs(y)) > 0)
    text = f"halving the step changes the max roll/twist by {100 * change:.0f} %"
    if change <= CONVERGENCE_TOLERANCE:
        return Convergence.CONVERGED, text
    return Convergence.NOT_CONVERGED, text


def run_wobbling(opts: WobblingOptions,
                 progress: Callable[[int, str], Any] | None = None) -> WobblingResult:
    """Run (or resume) both variants on every method and judge who stays planar.

    Raises
    ------
    RockbenchError
        A bad asymmetry, threshold or duration, a scenario that is not a column excited
        along x only, an unknown engine or bad settings.
    """
    start = time.perf_counter()
    if not (math.isfinite(opts.threshold) and opts.threshold > 0):
        raise RockbenchError(f"the planar threshold must be > 0 (a fraction of λ), got "
                             f"{opts.threshold!r}")
    if not opts.presets:
        raise RockbenchError("no preset to run")
    sym = opts.scenario
    if opts.duration is not None:
        if not (math.isfinite(opts.duration) and opts.duration > 0):
            raise RockbenchError(f"duration must be > 0 s, got {opts.duration!r}")
        sym = sym.replace(name=f"{sym.name}|{opts.duration:g}s", duration=opts.duration)
    asym = asymmetric_scenario(sym, opts.asymmetry)
    lam = critical_angle(sym.geometry)
    y_peak = asym.motion.y.peak_acceleration(sym.duration)
    uplift = out_of_plane_uplift(sym) / y_peak if y_peak > 0 else math.inf
    methods, plan, notes = _plan(opts, sym, asym)
    campaign = run_campaign([p.run for p in plan], CampaignOptions(
        kind=KIND, suite="wobbling", db=opts.db, resume=opts.resume,
        archive=opts.db is not None, keep=True, execution=opts.execution),
        progress=progress)
    ref_res = campaign.results[0]
    ref_peaks = [v for v in ref_res.metrics.peaks if v is not None]
    ref_peak = (max(ref_peaks) if ref_peaks and ref_res.metrics.status.completed else None)
    rows: list[WobblingRow] = []
    series: list[WobblingSeries] = []
    for p, res in zip(plan, campaign.results, strict=True):
        traj = campaign.trajectories.get(p.run.key)
        rows.append(_row(p, res, traj, lam, ref_peak))
        if p.rung == 0 and traj is not None and traj.t.size:
            u_y = np.asarray(p.run.scenario.motion.y.displacement(traj.t), float)
            series.append(WobblingSeries(p.label, p.variant, traj.t, traj.roll[:, 0],
                                         traj.twist[:, 0], traj.x[:, 0] - traj.x[0, 0],
                                         traj.y[:, 0] - traj.y[0, 0] - u_y))
    verdicts = []
    for p, row in zip(plan, rows, strict=True):
        if p.rung:
            continue
        finer = next((r for r in rows if (r.method, r.variant, r.rung)
                      == (row.method, row.variant, 1)), None)
        verdict = _verdict_of(row, p.construction, opts.threshold)
        conv, why = _convergence(row, finer, verdict, opts.threshold)
        note = p.construction or (row.message if verdict in (Verdict.UNSUPPORTED,
                                                             Verdict.FAILED) else why)
        if conv is Convergence.NOT_MEASURED:
            note = notes.get(row.method, "--no-converge")
        verdicts.append(WobblingVerdict(row.method, row.engine, row.preset, row.variant,
                                        verdict, conv, row, finer, note))
    return WobblingResult(opts, sym, asym, lam, methods, tuple(rows), tuple(verdicts),
                          tuple(series), ref_peak, uplift, campaign.versions, campaign.ran,
                          campaign.reused, time.perf_counter() - start)
