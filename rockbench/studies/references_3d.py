"""The engines against the 3D references: a drum in the plane, a corner release, a precession.

The three scenes of :mod:`rockbench.analytic.cases_3d`, each with an answer
known in closed form that a planar case cannot reveal: a drum released in the
plane (its first impact), a pillar released on its corner (its landing time,
and it stays on its diagonal), a slender cylinder in steady precession (its
tilt and rate).

:func:`run_references_3d` runs them on every method, at its preset's time
step and at half of it, and measures the errors (:class:`Errors3D`);
``rockbench references-3d`` writes the report
(:mod:`rockbench.report.references_3d_report`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from rockbench.analytic import SteadyPrecession, reference
from rockbench.analytic.cases_3d import (
    DRUM,
    PILLAR,
    PRECESSION_TILT,
    SLENDER_CYLINDER,
    corner_landing_time,
    corner_release,
    drum_release,
    precession,
)
from rockbench.campaign import CampaignOptions, PlannedRun, run_campaign
from rockbench.engines import engine_class
from rockbench.errors import RockbenchError
from rockbench.geometry import Cylinder
from rockbench.method import Method
from rockbench.metrics import first_zero
from rockbench.runner import ExecutionOptions
from rockbench.trajectory import Status, Trajectory

__all__ = ["DRUM", "SLENDER_CYLINDER", "PILLAR", "PRECESSION_TILT", "drum_release",
           "corner_release", "precession", "corner_landing_time", "first_zero", "Errors3D",
           "Failure", "Targets", "targets", "errors", "rim_contact", "References3DOptions",
           "References3DResult", "run_references_3d", "KIND", "TIMING_TOLERANCE",
           "DRIFT_TOLERANCE", "BOUNDS"]


class Failure(NamedTuple):
    """A run of the study that did not end ``ok``: its scene, status and the reason."""

    scene: str
    status: Status
    message: str

    def __str__(self) -> str:
        return f"{self.scene}: {self.status} ({self.message})"


@dataclass(frozen=True)
class Errors3D:
    """One method's errors against the three references (NaN where a run failed).

    Attributes
    ----------
    method : Method
        The engine and its settings.
    label : str
        The method's label in the study (a halved step keeps its preset's).
    rung : int
        0 at the preset's time step, 1 at half of it.
    drum_impact : float
        Relative error of the drum's first impact time.
    corner_landing : float
        Relative error of the corner release's landing time.
    off_diagonal : float
        Largest |θ + roll| before the landing (rad): how far it left the diagonal plane.
    tilt_drift : float
        Largest |tilt − 0.2| of the precession (rad).
    rate_error : float
        Relative error of the mean precession rate.
    cpu_per_s : float
        CPU seconds per simulated second of the precession.
    failures : tuple of Failure
        The runs whose status was not ``ok``.
    precession : Trajectory or None
        The precession run (for the figures).
    """

    method: Method
    label: str
    rung: int
    drum_impact: float
    corner_landing: float
    off_diagonal: float
    tilt_drift: float
    rate_error: float
    cpu_per_s: float
    failures: tuple[Failure, ...]
    precession: Trajectory | None = None

    def converged(self, finer: Errors3D) -> bool | None:
        """Whether the half-step rung ``finer`` gives the same answers (None: unknown).

        The same within :data:`TIMING_TOLERANCE` on the two landing times, and within
        the larger of half the drift and :data:`DRIFT_TOLERANCE` on the precession's tilt.
        """
        pairs = ((self.drum_impact, finer.drum_impact, TIMING_TOLERANCE),
                 (self.corner_landing, finer.corner_landing, TIMING_TOLERANCE),
                 (self.tilt_drift, finer.tilt_drift,
                  max(DRIFT_TOLERANCE, 0.5 * finer.tilt_drift)))
        if any(not (math.isfinite(a) and math.isfinite(b)) for a, b, _ in pairs):
            return None
        return all(abs(a - b) <= tol for a, b, tol in pairs)


    def within_bounds(self) -> bool | None:
        """Whether every error is within :data:`BOUNDS` (None: a run failed)."""
        values = (abs(self.drum_impact), abs(self.corner_landing), self.off_diagonal,
                  self.tilt_drift, abs(self.rate_error))
        if not all(math.isfinite(v) for v in values):
            return None
        return all(v <= b for v, b in zip(values, BOUNDS, strict=True))


#: The bounds of :meth:`Errors3D.within_bounds`: 1 % on the two landing times, 1e-3 rad
#: off the diagonal, 0.01 rad (5 % of the tilt) of tilt drift and 1 % on the precession
#: rate.
BOUNDS = (0.01, 0.01, 1e-3, 0.01, 0.01)
#: Largest change of a landing time's relative error at half the step that counts as
#: converged.
TIMING_TOLERANCE = 1e-3
#: Floor of the change of the precession's tilt drift (rad) that counts as converged.
DRIFT_TOLERANCE = 2e-4


class Targets(NamedTuple):
    """What the three scenes should give: the drum's first impact and the pillar's landing
    (s), and the steady precession."""

    drum_impact: float
    landing: float
    precession: SteadyPrecession


def targets() -> Targets:
    """The closed forms of the three scenes (the drum's impact from Housner's reference)."""
    ref = reference(drum_release())
    corner = corner_release()
    return Targets(first_zero(ref.t, ref.theta[:, 0]),
                   corner_landing_time(PILLAR, corner.theta0, corner.g), precession()[1])


def errors(method: Method, label: str, rung: int, drum: Trajectory | None,
           corner: Trajectory | None, spinning: Trajectory | None,
           failures: tuple[Failure, ...] = (), goal: Targets | None = None) -> Errors3D:
    """The errors of one method's three runs (None: a run that failed) against ``goal``
    (default: :func:`targets`)."""
    goal = goal or targets()
    nan = math.nan
    drum_err = (nan if drum is None else
                first_zero(drum.t, drum.theta[:, 0]) / goal.drum_impact - 1)
    land_err = off = nan
    if corner is not None:
        land_err = first_zero(corner.t, corner.theta[:, 0]) / goal.landing - 1.0
        before = corner.t < 0.95 * goal.landing
        off = float(np.max(np.abs(corner.theta[before, 0] + corner.roll[before, 0])))
    drift = rate = cost = nan
    if spinning is not None:
        sp = goal.precession
        drift = float(np.max(np.abs(spinning.tilt[:, 0] - sp.theta)))
        az = np.unwrap(spinning.azimuth[:, 0])
        rate = float((az[-1] - az[0]) / (spinning.t[-1] - spinning.t[0]) / sp.psi_dot - 1.0)
        cost = spinning.cpu_time / float(spinning.t[-1])
    return Errors3D(method, label, rung, drum_err, land_err, off, drift, rate, cost, failures,
                    spinning)


def rim_contact(traj: Trajectory, cylinder: Cylinder) -> np.ndarray:
    """The path of a cylinder's lowest rim point (x, y), shape (n, 2), from its trajectory.

    The point of the bottom rim on the lean side: G − h e₃ + R (cos θ u − sin θ ẑ), with θ
    the tilt, u the lean's horizontal direction and e₃ = cos θ ẑ + sin θ u the axis.
    """
    tilt, az = traj.tilt[:, 0], traj.azimuth[:, 0]
    # horizontal part of −h e₃ + R (cos θ u − sin θ ẑ), along u
    lever = -cylinder.h * np.sin(tilt) + cylinder.radius * np.cos(tilt)
    return np.column_stack([traj.x[:, 0] + lever * np.cos(az),
                            traj.y[:, 0] + lever * np.sin(az)])


@dataclass(frozen=True)
class References3DOptions:
    """What ``rockbench references-3d`` runs.

    Attributes
    ----------
    engines : sequence of str
        The engines (the analytic reference is always run).
    presets : sequence of str
        Each engine's presets (an engine's ``preset`` override picks one).
    overrides : mapping
        Engine → knob overrides.
    converge : bool
        Run each method again at half its time step.
    duration : float
        Simulated time of the precession (s).
    execution : ExecutionOptions
        Workers, time limits.
    resume : bool
        Reuse runs (and their trajectories) from the store.
    db : Path or None
        The results store.
    command : str
        The command line, for the report.
    """

    engines: Sequence[str]
    presets: Sequence[str] = ("accurate", "fast")
    overrides: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    converge: bool = True
    duration: float = 5.0
    execution: ExecutionOptions = field(default_factory=ExecutionOptions)
    resume: bool = False
    db: Path | None = None
    command: str = ""


@dataclass(frozen=True)
class References3DResult:
    """The study's rows (each method, rung 0 then its half step) and the reference.

    Attributes
    ----------
    options : References3DOptions
        What was run.
    rows : tuple of Errors3D
        One per method and rung, the reference first.
    versions : dict
        Engine → library version.
    ran, reused : int
        Runs executed now and taken from the store.
    wall_time : float
        Seconds.
    """

    options: References3DOptions
    rows: tuple[Errors3D, ...]
    versions: dict[str, str]
    ran: int
    reused: int
    wall_time: float

    def finer(self, row: Errors3D) -> Errors3D | None:
        """The half-step rung of a rung-0 row, if it ran."""
        return next((r for r in self.rows if r.label == row.label and r.rung == 1), None)


#: The store's ``kind`` of runs made by this study.
KIND = "references-3d"


def run_references_3d(opts: References3DOptions,
                      progress: Callable[[int, str], Any] | None = None) -> References3DResult:
    """Run (or resume) the three scenes on the reference and every method.

    Raises
    ------
    RockbenchError
        No preset, a duration that is not positive, an unknown engine or bad settings.
    """
    start = time.perf_counter()
    if not opts.presets:
        raise RockbenchError("no preset to run")
    if not (math.isfinite(opts.duration) and opts.duration > 0):
        raise RockbenchError(f"duration must be > 0 s, got {opts.duration!r}")
    scenes = (drum_release(), corner_release(), precession(opts.duration)[0])
    planned: list[tuple[Method, str, int]] = [(Method.reference(), Method.reference().label,
                                              0)]
    for e in dict.fromkeys(e for e in opts.engines if not Method(e).is_reference):
        over = dict(opts.overrides.get(e, {}))
        presets = [over.pop("preset")] if "preset" in over else list(opts.presets)
        for p in presets:
            m = Method.of(e, {"preset": p, **over}, qualified=True)
            planned.append((m, m.label, 0))
            if opts.converge:
                finer = engine_class(e).refined(m.settings, 1)
                planned.append((Method.of(e, finer, variation=f"{p}, half step"), m.label, 1))
    runs = [PlannedRun(sc, m) for m, _, _ in planned for sc in scenes]
    campaign = run_campaign(runs, CampaignOptions(
        kind=KIND, suite=KIND, db=opts.db, resume=opts.resume, archive=opts.db is not None,
        keep=True, execution=opts.execution, references=False), progress=progress)
    goal = targets()
    rows = []
    for k, (m, label, rung) in enumerate(planned):
        got: list[Trajectory | None] = []
        failures: list[Failure] = []
        for run, res in zip(runs[3 * k:3 * k + 3], campaign.results[3 * k:3 * k + 3],
                            strict=True):
            traj = campaign.trajectories.get(run.key)
            ok = res.metrics.status is Status.OK and traj is not None
            got.append(traj if ok else None)
            if not ok:
                failures.append(Failure(run.scenario.name, res.metrics.status,
                                        res.metrics.message))
        rows.append(errors(m, label, rung, got[0], got[1], got[2], tuple(failures), goal))
    return References3DResult(opts, tuple(rows), campaign.versions, campaign.ran,
                              campaign.reused, time.perf_counter() - start)
